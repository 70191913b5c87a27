//! The environment map of an experiment: a file or the built-in procedural sky.

use std::path::Path;

use envmap::EnvMap;

use crate::EstimatorError;

/// Width and height of the built-in procedural sky of [`load_map`].
pub const SKY_SIZE: (usize, usize) = (1024, 512);

/// Name [`load_map`] gives the procedural sky.
pub const SKY_NAME: &str = "procedural-sky";

/// The map at `path` (`.hdr`, `.exr`, `.pfm`) with its path as its name, or without a path
/// the built-in procedural sky ([`SKY_SIZE`], named [`SKY_NAME`]).
///
/// Errors: [`EstimatorError::Map`] with the path and the reader's reason.
pub fn load_map(path: Option<&Path>) -> Result<(EnvMap, String), EstimatorError> {
    match path {
        Some(path) => {
            let map = EnvMap::load(path)
                .map_err(|e| EstimatorError::Map(format!("{}: {e}", path.display())))?;
            Ok((map, path.display().to_string()))
        }
        None => Ok((
            envmap::procedural_sky(SKY_SIZE.0, SKY_SIZE.1)
                .map_err(|e| EstimatorError::Map(e.to_string()))?,
            SKY_NAME.to_string(),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sky_is_built_in_and_a_missing_file_is_a_typed_error() {
        let (sky, name) = load_map(None).unwrap();
        assert_eq!((sky.width(), sky.height()), SKY_SIZE);
        assert_eq!(name, SKY_NAME);
        let e = load_map(Some(Path::new("/nonexistent/map.hdr"))).unwrap_err();
        assert!(matches!(e, EstimatorError::Map(ref m) if m.starts_with("/nonexistent/map.hdr: ")));
    }
}
