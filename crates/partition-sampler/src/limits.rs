//! Limits of the tree shared by the builder, the leaf encoding, the tree checks and the
//! errors (a leaf module: it imports nothing).

/// Largest accepted `max_depth` (cells of `2^-24` of the domain). Leaves store their
/// rectangles as `f32` (root-normalised, or domain coordinates for dyadic roots), in which
/// every cell edge down to this depth is exact; a deeper limit would need another encoding.
pub const MAX_DEPTH_LIMIT: u32 = 24;
