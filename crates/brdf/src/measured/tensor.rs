//! The tensor file container of the RGL material database (Mitsuba's `TensorFile`).
//!
//! Layout (little-endian): the 12 bytes `tensor_file\0`, a version `u8 major, u8 minor` (1.0),
//! a `u32` field count, then per field a `u16` name length and the name (UTF-8), a `u16` rank,
//! a `u8` element type, a `u64` byte offset of the data from the start of the file, and `rank`
//! `u64` extents (row-major, last extent contiguous). Element types used here: 1 = `u8`,
//! 10 = `f32` (Mitsuba's `Struct::Type` numbering: 0 invalid, 1 u8, 2 i8, 3 u16, 4 i16, 5 u32,
//! 6 i32, 7 u64, 8 i64, 9 f16, 10 f32, 11 f64).

use super::rgl_error::RglError;

/// The magic bytes at the start of a tensor file.
pub const MAGIC: &[u8; 12] = b"tensor_file\0";

/// Element type code of `u8`.
pub const DTYPE_U8: u8 = 1;
/// Element type code of `f32`.
pub const DTYPE_F32: u8 = 10;

/// One named field of a tensor file (its data not yet decoded).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Element type code.
    pub dtype: u8,
    /// Extents, slowest first.
    pub shape: Vec<usize>,
    /// Byte offset of the data in the file.
    pub offset: usize,
}

impl Field {
    /// Number of elements (`None` on overflow).
    pub fn len(&self) -> Option<usize> {
        self.shape.iter().try_fold(1usize, |a, &b| a.checked_mul(b))
    }

    /// Whether the field has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == Some(0)
    }
}

fn dtype_size(dtype: u8) -> Option<usize> {
    match dtype {
        1 | 2 => Some(1),
        3 | 4 | 9 => Some(2),
        5 | 6 | 10 => Some(4),
        7 | 8 | 11 => Some(8),
        _ => None,
    }
}

/// A parsed tensor file: the field table over the file's bytes.
#[derive(Debug)]
pub struct TensorFile<'a> {
    bytes: &'a [u8],
    fields: Vec<Field>,
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], RglError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(RglError::Truncated {
                what: what.to_string(),
                needed: self.pos.saturating_add(n),
                len: self.bytes.len(),
            });
        };
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u8(&mut self, what: &str) -> Result<u8, RglError> {
        Ok(self.take(1, what)?[0])
    }
    fn u16(&mut self, what: &str) -> Result<u16, RglError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self, what: &str) -> Result<u32, RglError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self, what: &str) -> Result<u64, RglError> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
}

impl<'a> TensorFile<'a> {
    /// Parses the header and field table of `bytes`; every field's data range is checked to lie
    /// inside the file.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, RglError> {
        let mut c = Cursor { bytes, pos: 0 };
        let magic = c.take(MAGIC.len(), "magic")?;
        if magic != MAGIC {
            return Err(RglError::BadMagic);
        }
        let (major, minor) = (c.u8("version")?, c.u8("version")?);
        if (major, minor) != (1, 0) {
            return Err(RglError::UnsupportedVersion { major, minor });
        }
        let count = c.u32("field count")?;
        let mut fields: Vec<Field> = Vec::new();
        // Names seen so far: a hash set keeps the duplicate check linear (a file of 65,536
        // short distinct names is 1 MB and would cost 2·10⁹ comparisons pairwise).
        let mut names = std::collections::HashSet::new();
        for _ in 0..count {
            let len = usize::from(c.u16("field name length")?);
            let name = String::from_utf8_lossy(c.take(len, "field name")?).into_owned();
            let rank = usize::from(c.u16("field rank")?);
            let dtype = c.u8("field type")?;
            let offset = c.u64("field offset")?;
            let mut shape = Vec::with_capacity(rank.min(16));
            for _ in 0..rank {
                let e = c.u64("field shape")?;
                shape.push(usize::try_from(e).unwrap_or(usize::MAX));
            }
            if !names.insert(name.clone()) {
                return Err(RglError::DuplicateField { name });
            }
            let Some(size) = dtype_size(dtype) else {
                return Err(RglError::UnknownType { field: name, dtype });
            };
            let offset = usize::try_from(offset).unwrap_or(usize::MAX);
            let field = Field {
                name,
                dtype,
                shape,
                offset,
            };
            let end = field
                .len()
                .and_then(|n| n.checked_mul(size))
                .and_then(|b| b.checked_add(offset));
            match end {
                Some(end) if end <= bytes.len() => {}
                _ => {
                    return Err(RglError::Truncated {
                        what: format!("data of field `{}`", field.name),
                        needed: end.unwrap_or(usize::MAX),
                        len: bytes.len(),
                    });
                }
            }
            fields.push(field);
        }
        Ok(Self { bytes, fields })
    }

    /// The fields, in file order.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    /// The field called `name`.
    pub fn field(&self, name: &str) -> Result<&Field, RglError> {
        self.fields
            .iter()
            .find(|f| f.name == name)
            .ok_or_else(|| RglError::MissingField {
                name: name.to_string(),
            })
    }

    /// The `u8` data of field `name`, checked to have type `u8`.
    pub fn u8_data(&self, name: &str) -> Result<&'a [u8], RglError> {
        let f = self.field(name)?;
        expect_type(f, DTYPE_U8, "u8")?;
        let n = f.len().unwrap_or(0);
        Ok(&self.bytes[f.offset..f.offset + n])
    }

    /// The `f32` data of field `name` as `f64`, checked to have type `f32` and every value
    /// finite.
    pub fn f32_data(&self, name: &str) -> Result<Vec<f64>, RglError> {
        let f = self.field(name)?;
        expect_type(f, DTYPE_F32, "f32")?;
        let n = f.len().unwrap_or(0);
        let raw = &self.bytes[f.offset..f.offset + 4 * n];
        let mut out = Vec::with_capacity(n);
        for (index, b) in raw.chunks_exact(4).enumerate() {
            let v = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            if !v.is_finite() {
                return Err(RglError::NonFinite {
                    field: name.to_string(),
                    index,
                });
            }
            out.push(v);
        }
        Ok(out)
    }
}

fn expect_type(f: &Field, dtype: u8, expected: &'static str) -> Result<(), RglError> {
    if f.dtype == dtype {
        Ok(())
    } else {
        Err(RglError::WrongType {
            field: f.name.clone(),
            dtype: f.dtype,
            expected,
        })
    }
}
