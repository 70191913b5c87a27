//! Typed errors of the crate.

use crate::options::OptionsError;

/// A quadtree set could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SetError {
    /// The options are invalid.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// The image map of a slice could not be evaluated (the BRDF returned NaN, a negative or
    /// infinite value, or is zero for this outgoing direction).
    #[error("slice {slice} (θo = {theta_deg:.3}°, φo = {phi_deg:.3}°): {source}")]
    Density {
        /// Slice index.
        slice: usize,
        /// θ of the slice (degrees).
        theta_deg: f64,
        /// φ of the slice (degrees).
        phi_deg: f64,
        /// The cause.
        source: partition_sampler::DensityError,
    },
    /// The quadtree of a slice could not be built.
    #[error("slice {slice} (θo = {theta_deg:.3}°, φo = {phi_deg:.3}°): {source}")]
    Tree {
        /// Slice index.
        slice: usize,
        /// θ of the slice (degrees).
        theta_deg: f64,
        /// φ of the slice (degrees).
        phi_deg: f64,
        /// The cause.
        source: partition_sampler::BuildError,
    },
    /// The BRDF declares [`brdf::Brdf::is_mirror_symmetric`] but a probe found
    /// `f(x, y) ≠ f(x, −y)` on a slice's disc.
    #[error(
        "slice {slice} (θo = {theta_deg:.3}°): the BRDF declares mirror symmetry but f({x:.4}, {y:.4}) = {a} ≠ f({x:.4}, {neg_y:.4}) = {b}",
        neg_y = -y
    )]
    MirrorAsymmetry {
        /// Slice index.
        slice: usize,
        /// θ of the slice (degrees).
        theta_deg: f64,
        /// x of the probe point on the disc.
        x: f64,
        /// y of the probe point on the disc.
        y: f64,
        /// Density at `(x, y)`.
        a: f64,
        /// Density at `(x, −y)`.
        b: f64,
    },
    /// A built tree could not be attached to its density.
    #[error("slice {slice}: {source}")]
    Attach {
        /// Slice index.
        slice: usize,
        /// The cause.
        source: partition_sampler::AttachError,
    },
}

/// A set file could not be written, or its bytes read back into a set.
#[derive(Debug, thiserror::Error)]
pub enum SetFileError {
    /// Fewer bytes than the header or the payload needs.
    #[error("truncated input")]
    Truncated,
    /// The bytes do not start with the set format's magic `BRQS`.
    #[error("not a brdf-sampling quadtree set (bad magic)")]
    BadMagic,
    /// The stored format version is not the one this build reads.
    #[error("set format version {found} is not supported (expected {expected})")]
    UnsupportedVersion {
        /// Version in the bytes.
        found: u32,
        /// Version this build reads ([`crate::SET_FORMAT_VERSION`]).
        expected: u32,
    },
    /// The payload could not be decoded.
    #[error("decode error: {0}")]
    Decode(String),
    /// The payload decoded but is inconsistent (slice count, options, …).
    #[error("corrupt set: {0}")]
    Corrupt(String),
    /// A stored tree could not be decoded.
    #[error("slice {slice}: {source}")]
    Tree {
        /// Slice index.
        slice: usize,
        /// The cause (includes the tree format version check).
        source: partition_sampler::PersistError,
    },
    /// A stored tree could not be re-attached.
    #[error("slice {slice}: {source}")]
    Attach {
        /// Slice index.
        slice: usize,
        /// The cause.
        source: partition_sampler::AttachError,
    },
    /// The set was built for another BRDF spec.
    #[error("the set was built for BRDF spec `{stored}`, not `{given}`")]
    SpecMismatch {
        /// Spec stored in the set.
        stored: String,
        /// Spec given when loading.
        given: String,
    },
    /// The BRDF given when loading does not evaluate like the one the set was built for.
    #[error(
        "the BRDF `{name}` does not match the stored one: probe {probe} gives {found}, stored {stored}"
    )]
    BrdfMismatch {
        /// Name of the given BRDF.
        name: String,
        /// Index of the first mismatching probe.
        probe: usize,
        /// Stored value.
        stored: f64,
        /// Value of the given BRDF.
        found: f64,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}
