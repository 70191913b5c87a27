//! The RGL format's error type, shared by the container reader ([`tensor`](super::tensor))
//! and the material ([`rgl`](super::rgl)): a leaf module, so neither imports the other for it.

use std::path::PathBuf;

use thiserror::Error;

/// Why an RGL `.bsdf` file could not be read.
#[derive(Debug, Error)]
pub enum RglError {
    /// Filesystem error.
    #[error("RGL file {path}: {source}")]
    Io {
        /// File involved.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The file does not start with `tensor_file\0`.
    #[error("not an RGL tensor file (the magic `tensor_file\\0` is missing)")]
    BadMagic,
    /// A container version other than 1.0.
    #[error("unsupported tensor file version {major}.{minor} (expected 1.0)")]
    UnsupportedVersion {
        /// Major version.
        major: u8,
        /// Minor version.
        minor: u8,
    },
    /// The file ends inside the header or a field's data.
    #[error("truncated tensor file: {what} needs {needed} bytes, the file has {len}")]
    Truncated {
        /// What was being read.
        what: String,
        /// Bytes needed.
        needed: usize,
        /// Bytes present.
        len: usize,
    },
    /// Two fields have the same name.
    #[error("field `{name}` appears twice")]
    DuplicateField {
        /// The name.
        name: String,
    },
    /// An element type code outside the format's list.
    #[error("field `{field}` has unknown element type {dtype}")]
    UnknownType {
        /// The field.
        field: String,
        /// Its code.
        dtype: u8,
    },
    /// A field the format requires is absent.
    #[error("field `{name}` is missing")]
    MissingField {
        /// The name.
        name: String,
    },
    /// A field has the wrong element type.
    #[error("field `{field}` has element type {dtype}, expected {expected}")]
    WrongType {
        /// The field.
        field: String,
        /// Its code.
        dtype: u8,
        /// The expected type.
        expected: &'static str,
    },
    /// A field's shape is inconsistent with the format or with the other fields.
    #[error("field `{field}` has shape {shape:?}, expected {expected}")]
    WrongShape {
        /// The field.
        field: String,
        /// Its shape.
        shape: Vec<usize>,
        /// What was expected.
        expected: String,
    },
    /// A NaN or infinite value.
    #[error("field `{field}` holds a non-finite value at index {index}")]
    NonFinite {
        /// The field.
        field: String,
        /// Flat index.
        index: usize,
    },
    /// A value out of its range (negative density, non-positive `sigma`, angle out of range).
    #[error("field `{field}`: value {value} at index {index} is out of range ({rule})")]
    OutOfRange {
        /// The field.
        field: String,
        /// Flat index.
        index: usize,
        /// The value.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// More than one `phi_i` value: anisotropic files are not supported.
    #[error("anisotropic RGL files ({n_phi} values of phi_i) are not supported; expected 1")]
    Anisotropic {
        /// Number of `phi_i` values.
        n_phi: usize,
    },
    /// A table breaks a physical rule of the format that no single value breaks: the NDF's
    /// normalisation, the bounds of `sigma` implied by the NDF, an albedo far above 1, or a
    /// product or sum that overflows the format's `f32` (see [`RglBrdf::from_bytes`]).
    #[error("field `{field}`: {detail}")]
    Implausible {
        /// The field.
        field: String,
        /// The rule broken and the offending value.
        detail: String,
    },
    /// A sampling table slice integrates to zero.
    #[error("field `{field}`: slice {slice} integrates to zero")]
    ZeroSlice {
        /// The field.
        field: String,
        /// The slice.
        slice: usize,
    },
}
