//! Versioned binary persistence of a [`QuadTree`] (postcard payload behind an 8-byte header).
//!
//! Layout: `b"PSQT"`, [`FORMAT_VERSION`] as little-endian `u32`, then the postcard encoding of
//! the tree. The density is not stored: re-attach it with
//! [`crate::QuadTreeSampler::from_parts`], which checks its shape and fingerprint.

use crate::error::PersistError;
use crate::tree::QuadTree;

/// Version of the stored tree format; bumped on any incompatible change.
///
/// Version 2: leaves store root-normalised `f32` rectangles and bounds (with a per-tree
/// power-of-two bound scale); descent CDFs are a separate array, empty for
/// [`crate::LeafChoice::Alias`].
pub const FORMAT_VERSION: u32 = 2;

const MAGIC: &[u8; 4] = b"PSQT";

impl QuadTree {
    /// Encodes the tree: header (magic, version) + postcard payload.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(8 + self.bytes_used());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        // Serialising plain data into a Vec cannot fail.
        if let Ok(payload) = postcard::to_allocvec(self) {
            out.extend_from_slice(&payload);
        }
        out
    }

    /// Decodes and structurally validates a tree written by [`QuadTree::to_bytes`].
    ///
    /// Errors: [`PersistError::Truncated`], [`PersistError::BadMagic`],
    /// [`PersistError::UnsupportedVersion`], [`PersistError::Decode`],
    /// [`PersistError::Corrupt`] (indices out of range, non-finite bounds, …).
    pub fn from_bytes(bytes: &[u8]) -> Result<QuadTree, PersistError> {
        let (Some(magic), Some(version)) = (bytes.get(0..4), bytes.get(4..8)) else {
            return Err(PersistError::Truncated);
        };
        if magic != MAGIC {
            return Err(PersistError::BadMagic);
        }
        let mut v = [0u8; 4];
        v.copy_from_slice(version);
        let found = u32::from_le_bytes(v);
        if found != FORMAT_VERSION {
            return Err(PersistError::UnsupportedVersion {
                found,
                expected: FORMAT_VERSION,
            });
        }
        let tree: QuadTree = postcard::from_bytes(&bytes[8..]).map_err(|e| match e {
            postcard::Error::DeserializeUnexpectedEnd => PersistError::Truncated,
            other => PersistError::Decode(other.to_string()),
        })?;
        tree.validate().map_err(PersistError::Corrupt)?;
        Ok(tree)
    }
}
