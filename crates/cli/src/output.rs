//! Atomic output files: written to a temporary file beside the target, then renamed over it,
//! so a failed or interrupted run never leaves a half-written file (or destroys an old one).

use crate::error::{CliError, CliResult};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes a file atomically: `fill` writes the content into a buffered writer; the file appears
/// at `path` only if `fill` and the flush succeed.
pub(crate) fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> CliResult<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let fail = |e: &dyn std::fmt::Display| {
        CliError::input(format!("cannot write {}: {e}", path.display()))
    };
    let tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| fail(&e))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(|e| fail(&e))?;
        w.flush().map_err(|e| fail(&e))?;
    }
    tmp.as_file().sync_all().map_err(|e| fail(&e))?;
    tmp.persist(path).map_err(|e| fail(&e.error))?;
    Ok(())
}

/// Formats an f64 for CSV output with full round-trip precision.
pub(crate) fn num(x: f64) -> String {
    format!("{x:?}")
}
