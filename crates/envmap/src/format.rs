//! The supported file formats of environment maps (a leaf module: the loaders and the error
//! type both name it).

use std::fmt;
use std::path::Path;

/// A supported file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MapFormat {
    /// Radiance RGBE (`.hdr`): `#?RADIANCE` or `#?RGBE` signature, flat or RLE scanlines.
    Hdr,
    /// OpenEXR (`.exr`): the first RGB(A) layer.
    Exr,
    /// Portable float map (`.pfm`): `PF` (RGB) or `Pf` (grey), either endianness.
    Pfm,
}

impl MapFormat {
    /// The format named by a file's extension (`hdr`, `exr`, `pfm`, any case), if supported.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "hdr" => Some(Self::Hdr),
            "exr" => Some(Self::Exr),
            "pfm" => Some(Self::Pfm),
            _ => None,
        }
    }
}

impl fmt::Display for MapFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Hdr => "Radiance HDR",
            Self::Exr => "OpenEXR",
            Self::Pfm => "PFM",
        })
    }
}
