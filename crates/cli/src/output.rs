//! Output files: checked up front, written atomically.
//!
//! Every command calls [`check_writable`] on each of its output paths before any work, so a long
//! run never ends with "cannot write". Files are written to a temporary file beside the target,
//! then renamed over it, so a failed or interrupted run never leaves a half-written file (or
//! destroys an old one); a symbolic link is followed (the link stays), and special files
//! (`/dev/null`, `/dev/stdout`, FIFOs) are written in place, never replaced. A new file gets the mode a plainly created file would get (0666 minus
//! the umask, e.g. 0644), an existing one keeps its mode.

use crate::error::{CliError, CliResult};
use crate::values::display_path;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The reason of an I/O error without the paths some wrappers add (tempfile's own names).
fn reason(e: &std::io::Error) -> String {
    match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code).to_string(),
        None => e.kind().to_string(),
    }
}

/// The directory an output file is created in.
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Where an output goes.
enum Target {
    /// A regular file (new or existing), written atomically: a temporary file beside it,
    /// renamed over it. A symbolic link is followed, so the link stays and its target is
    /// replaced.
    File(PathBuf),
    /// An existing special file (`/dev/null`, `/dev/stdout`, a FIFO, a process substitution),
    /// written in place: renaming over it would replace the device or pipe.
    Stream,
}

/// Resolves `path` as an output, judged without writing; `Err` says why it cannot be one (a
/// directory, a missing or non-directory parent).
fn target(path: &Path) -> Result<Target, String> {
    if path.as_os_str().is_empty() {
        return Err("empty file name".to_string());
    }
    if path.to_string_lossy().ends_with(std::path::MAIN_SEPARATOR) {
        return Err("is a directory (give a file name)".to_string());
    }
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err("is a directory (give a file name)".to_string()),
        Ok(m) if !m.is_file() => return Ok(Target::Stream),
        _ => {}
    }
    let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    let file = if is_link {
        // The link's target, also when it does not exist yet (it is created then).
        std::fs::canonicalize(path)
            .or_else(|_| {
                std::fs::read_link(path).map(|t| {
                    if t.is_absolute() {
                        t
                    } else {
                        parent_dir(path).join(t)
                    }
                })
            })
            .map_err(|e| format!("symbolic link: {}", reason(&e)))?
    } else {
        path.to_path_buf()
    };
    let dir = parent_dir(&file);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(Target::File(file)),
        Ok(_) => Err(format!("{} is not a directory", display_path(dir))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(format!("directory {} does not exist", display_path(dir)))
        }
        Err(e) => Err(format!("directory {}: {}", display_path(dir), reason(&e))),
    }
}

/// Checks, before any work, that `path` (given with `flag`, e.g. `--out`) can be written:
/// not a directory, its directory exists, and a file can be created there (probed with a
/// temporary file that is removed at once). Exit 2 with a one-line reason otherwise.
pub(crate) fn check_writable(flag: &str, path: &Path) -> CliResult<()> {
    let fail = |why: String| CliError::input(format!("{flag} {}: {why}", display_path(path)));
    match target(path).map_err(fail)? {
        // Opening a FIFO here would block or signal end of file to its reader.
        Target::Stream => Ok(()),
        Target::File(file) => {
            let dir = parent_dir(&file);
            tempfile::NamedTempFile::new_in(dir).map(drop).map_err(|e| {
                fail(format!(
                    "cannot create files in {}: {}",
                    display_path(dir),
                    reason(&e)
                ))
            })
        }
    }
}

/// [`check_writable`] for every `(flag, path)` given.
pub(crate) fn check_all<'a>(
    outputs: impl IntoIterator<Item = (&'a str, Option<&'a Path>)>,
) -> CliResult<()> {
    outputs
        .into_iter()
        .filter_map(|(flag, path)| path.map(|p| (flag, p)))
        .try_for_each(|(flag, path)| check_writable(flag, path))
}

/// A temporary file in `dir` with the mode of a plainly created file (0666 minus the umask:
/// `open(2)` applies the umask to the mode given at creation).
fn temporary_in(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir)
}

/// Writes a file atomically: `fill` writes the content into a buffered writer; the file appears
/// at `path` only if `fill` and the flush succeed.
pub(crate) fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> CliResult<()> {
    let fail = |why: String| CliError::input(format!("cannot write {}: {why}", display_path(path)));
    let file = match target(path).map_err(fail)? {
        Target::Stream => {
            let out = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| fail(reason(&e)))?;
            let mut w = BufWriter::new(out);
            fill(&mut w).map_err(|e| fail(reason(&e)))?;
            return w.flush().map_err(|e| fail(reason(&e)));
        }
        Target::File(file) => file,
    };
    let tmp = temporary_in(parent_dir(&file)).map_err(|e| fail(reason(&e)))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(|e| fail(reason(&e)))?;
        w.flush().map_err(|e| fail(reason(&e)))?;
    }
    // Replacing an existing file keeps its mode, as writing into it would.
    if let Ok(old) = std::fs::metadata(&file) {
        tmp.as_file()
            .set_permissions(old.permissions())
            .map_err(|e| fail(reason(&e)))?;
    }
    tmp.as_file().sync_all().map_err(|e| fail(reason(&e)))?;
    tmp.persist(&file).map_err(|e| fail(reason(&e.error)))?;
    Ok(())
}

/// Writes data to standard output (buffered). A closed pipe (`brdf-lab sample … | head`) ends
/// the output quietly; other errors are reported.
pub(crate) fn write_stdout(
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> CliResult<()> {
    let mut out = BufWriter::new(std::io::stdout().lock());
    match fill(&mut out).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(CliError::input(format!(
            "cannot write to standard output: {}",
            reason(&e)
        ))),
        _ => Ok(()),
    }
}

/// Formats an f64 for CSV output with full round-trip precision.
pub(crate) fn num(x: f64) -> String {
    format!("{x:?}")
}
