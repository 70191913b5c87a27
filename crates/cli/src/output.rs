//! Output files: checked up front, written atomically.
//!
//! Every command calls [`check_writable`] on each of its output paths before any work, so a long
//! run never ends with "cannot write". Files are written to a temporary file beside the target,
//! then renamed over it, so a failed or interrupted run never leaves a half-written file (or
//! destroys an old one). A new file gets the mode a plainly created file would get (0666 minus
//! the umask, e.g. 0644), an existing one keeps its mode.

use crate::error::{CliError, CliResult};
use std::io::{BufWriter, Write};
use std::path::Path;

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

/// Why `path` cannot be an output file, judged without writing: it is a directory, or its
/// directory does not exist or is not a directory.
fn target_problem(path: &Path) -> Option<String> {
    if path.as_os_str().is_empty() {
        return Some("empty file name".to_string());
    }
    if path.is_dir() || path.to_string_lossy().ends_with(std::path::MAIN_SEPARATOR) {
        return Some("is a directory (give a file name)".to_string());
    }
    let dir = parent_dir(path);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => None,
        Ok(_) => Some(format!("{} is not a directory", dir.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Some(format!("directory {} does not exist", dir.display()))
        }
        Err(e) => Some(format!("directory {}: {}", dir.display(), reason(&e))),
    }
}

/// Checks, before any work, that `path` (given with `flag`, e.g. `--out`) can be written:
/// not a directory, its directory exists, and a file can be created there (probed with a
/// temporary file that is removed at once). Exit 2 with a one-line reason otherwise.
pub(crate) fn check_writable(flag: &str, path: &Path) -> CliResult<()> {
    let fail = |why: String| CliError::input(format!("{flag} {}: {why}", path.display()));
    if let Some(why) = target_problem(path) {
        return Err(fail(why));
    }
    let dir = parent_dir(path);
    tempfile::NamedTempFile::new_in(dir).map(drop).map_err(|e| {
        fail(format!(
            "cannot create files in {}: {}",
            dir.display(),
            reason(&e)
        ))
    })
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
    let fail = |why: String| CliError::input(format!("cannot write {}: {why}", path.display()));
    if let Some(why) = target_problem(path) {
        return Err(fail(why));
    }
    let tmp = temporary_in(parent_dir(path)).map_err(|e| fail(reason(&e)))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(|e| fail(reason(&e)))?;
        w.flush().map_err(|e| fail(reason(&e)))?;
    }
    // Replacing an existing file keeps its mode, as writing into it would.
    if let Ok(old) = std::fs::metadata(path) {
        tmp.as_file()
            .set_permissions(old.permissions())
            .map_err(|e| fail(reason(&e)))?;
    }
    tmp.as_file().sync_all().map_err(|e| fail(reason(&e)))?;
    tmp.persist(path).map_err(|e| fail(reason(&e.error)))?;
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
