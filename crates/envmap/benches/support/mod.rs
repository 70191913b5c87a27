//! Helpers shared by envmap's benches, examples and tests (included with `mod support;` from
//! `benches/` and `#[path = "../benches/support/mod.rs"] mod support;` elsewhere).

use std::path::{Path, PathBuf};

use envmap::MapFormat;

/// The real environment maps of the project's test data (1024 × 512 HDR files, not in the
/// repository): every file of `../../../shared/data/envmaps` (from this crate's manifest) whose
/// extension `EnvMap::load` reads, sorted by path; `Err(dir)` when that directory is absent.
pub(crate) fn real_map_paths() -> Result<Vec<PathBuf>, PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/envmaps");
    let entries = std::fs::read_dir(&dir).map_err(|_| dir.clone())?;
    let mut paths: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| MapFormat::from_path(p).is_some())
        .collect();
    paths.sort();
    Ok(paths)
}
