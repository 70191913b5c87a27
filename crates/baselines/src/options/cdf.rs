//! Options of the cdf baselines (`tabulated-cdf`, `cascade-cdf`; baselines.md §B).

/// Options of the tabulated and Douglas–Peucker-compressed cascade CDFs (baselines.md §B).
///
/// Each outgoing slice holds a fine `n_z × n_φ` grid over `(z = cos θi, φi) ∈ [0,1] × [0, 2π)`
/// of `g = f_r · cos θi`, each cell the mean of `supersampling²` evaluations plus a defensive
/// floor (see [`CdfOptions::floor`]); the cascade simplifies every 1D CDF of that grid with
/// tolerance [`CdfOptions::epsilon`].
#[derive(Debug, Clone, PartialEq)]
pub struct CdfOptions {
    /// θ slices for isotropic BRDFs (φ rotation serves every azimuth; default
    /// [`CdfOptions::DEFAULT_SLICES`]).
    pub slices: usize,
    /// `[θ, φ]` slices for anisotropic BRDFs (default
    /// [`CdfOptions::DEFAULT_ANISOTROPIC_SLICES`]; the φ slices cover `[0, π)` instead of
    /// `[0, 2π)` for half-turn-symmetric BRDFs when the count is even, which halves it).
    pub anisotropic_slices: [usize; 2],
    /// Fine cells along `z = cos θi` (default [`CdfOptions::DEFAULT_N_Z`]).
    pub n_z: usize,
    /// Fine cells along `φi` (default [`CdfOptions::DEFAULT_N_PHI`]).
    pub n_phi: usize,
    /// Evaluations per cell and axis: a cell's value is the mean of `supersampling²`
    /// evaluations at the centres of a regular sub-grid (default
    /// [`CdfOptions::DEFAULT_SUPERSAMPLING`]).
    pub supersampling: usize,
    /// Douglas–Peucker tolerance of the cascade in CDF units (vertical L∞ distance, default
    /// [`CdfOptions::DEFAULT_EPSILON`]); ignored by the uncompressed `tabulated-cdf`.
    pub epsilon: f64,
    /// Defensive floor: every cell's value gets `floor ·` (the slice's mean cell value) added,
    /// so every cell has positive mass and no region where `g > 0` can have pdf 0, even if the
    /// sub-grid missed a narrow peak (default [`CdfOptions::DEFAULT_FLOOR`]). It moves a
    /// fraction `floor / (1 + floor)` of the samples to a uniform density.
    pub floor: f64,
}

impl CdfOptions {
    /// Default θ slices of an isotropic BRDF (baselines.md §B.2).
    pub const DEFAULT_SLICES: usize = 32;
    /// Default `[θ, φ]` slices of an anisotropic BRDF. baselines.md §B.2 suggests 32 × 16;
    /// 16 × 8 keeps the build of the default grid to a few seconds and the table under
    /// 150 MB (a coarser outgoing grid costs variance only: the nearest slice is used in
    /// both `sample` and `pdf`).
    pub const DEFAULT_ANISOTROPIC_SLICES: [usize; 2] = [16, 8];
    /// Default fine cells along `z` (baselines.md §B.2).
    pub const DEFAULT_N_Z: usize = 256;
    /// Default fine cells along `φ` (baselines.md §B.2).
    pub const DEFAULT_N_PHI: usize = 512;
    /// Default evaluations per cell and axis.
    pub const DEFAULT_SUPERSAMPLING: usize = 3;
    /// Default Douglas–Peucker tolerance (baselines.md §B.3).
    pub const DEFAULT_EPSILON: f64 = 1e-3;
    /// Default defensive floor, relative to the slice's mean cell value.
    pub const DEFAULT_FLOOR: f64 = 1e-4;
    /// Largest slice count per axis.
    pub const MAX_SLICES: usize = 1024;
    /// Largest cell count per axis of the fine grid (grid indices are stored as `u32`).
    pub const MAX_CELLS_PER_AXIS: usize = 16_384;
    /// Largest evaluations per cell and axis.
    pub const MAX_SUPERSAMPLING: usize = 16;
    /// Largest total number of fine cells over all slices (`slices · n_z · n_φ`): 8 bytes
    /// each in the uncompressed table, so at most 1 GiB.
    pub const MAX_TOTAL_CELLS: usize = 1 << 27;
}

impl Default for CdfOptions {
    fn default() -> Self {
        Self {
            slices: Self::DEFAULT_SLICES,
            anisotropic_slices: Self::DEFAULT_ANISOTROPIC_SLICES,
            n_z: Self::DEFAULT_N_Z,
            n_phi: Self::DEFAULT_N_PHI,
            supersampling: Self::DEFAULT_SUPERSAMPLING,
            epsilon: Self::DEFAULT_EPSILON,
            floor: Self::DEFAULT_FLOOR,
        }
    }
}

/// An invalid [`CdfOptions`] field, or a table too large to build.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CdfOptionsError {
    /// A slice count is 0 or above [`CdfOptions::MAX_SLICES`].
    #[error("{what} = {value} must be in 1 ..= {max}", max = CdfOptions::MAX_SLICES)]
    Slices {
        /// Which count.
        what: &'static str,
        /// The value.
        value: usize,
    },
    /// A fine-grid dimension is 0 or above [`CdfOptions::MAX_CELLS_PER_AXIS`].
    #[error("{what} = {value} must be in 1 ..= {max}", max = CdfOptions::MAX_CELLS_PER_AXIS)]
    Grid {
        /// Which axis.
        what: &'static str,
        /// The value.
        value: usize,
    },
    /// The supersampling is 0 or above [`CdfOptions::MAX_SUPERSAMPLING`].
    #[error("supersampling = {0} must be in 1 ..= {max}", max = CdfOptions::MAX_SUPERSAMPLING)]
    Supersampling(usize),
    /// The Douglas–Peucker tolerance must be in `(0, 1)` (CDF units).
    #[error("epsilon = {0} must be in (0, 1) (CDF units)")]
    Epsilon(f64),
    /// The defensive floor must be in `(0, 1]` (a fraction of the mean cell value).
    #[error("floor = {0} must be in (0, 1] (relative to the mean cell value)")]
    Floor(f64),
    /// `slices · n_z · n_φ` exceeds [`CdfOptions::MAX_TOTAL_CELLS`].
    #[error(
        "{slices} slices of {n_z} × {n_phi} cells exceed {max} cells in all",
        max = CdfOptions::MAX_TOTAL_CELLS
    )]
    TooLarge {
        /// Slices of the layout.
        slices: usize,
        /// Cells along z.
        n_z: usize,
        /// Cells along φ.
        n_phi: usize,
    },
}

impl CdfOptions {
    /// Checks every field (see [`CdfOptionsError`]); the total size is checked by
    /// [`CdfOptions::validate_size`] once the slice count is known.
    pub fn validate(&self) -> Result<(), CdfOptionsError> {
        if let Some((what, value)) =
            brdf_sampling::bad_slice_count(self.slices, self.anisotropic_slices, Self::MAX_SLICES)
        {
            return Err(CdfOptionsError::Slices { what, value });
        }
        for (what, value) in [("n_z", self.n_z), ("n_phi", self.n_phi)] {
            if !(1..=Self::MAX_CELLS_PER_AXIS).contains(&value) {
                return Err(CdfOptionsError::Grid { what, value });
            }
        }
        if !(1..=Self::MAX_SUPERSAMPLING).contains(&self.supersampling) {
            return Err(CdfOptionsError::Supersampling(self.supersampling));
        }
        if !(self.epsilon > 0.0 && self.epsilon < 1.0) {
            return Err(CdfOptionsError::Epsilon(self.epsilon));
        }
        if !(self.floor > 0.0 && self.floor <= 1.0) {
            return Err(CdfOptionsError::Floor(self.floor));
        }
        Ok(())
    }

    /// Checks that `slices` slices of the fine grid stay within
    /// [`CdfOptions::MAX_TOTAL_CELLS`].
    pub fn validate_size(&self, slices: usize) -> Result<(), CdfOptionsError> {
        let total = slices
            .checked_mul(self.n_z)
            .and_then(|c| c.checked_mul(self.n_phi));
        match total {
            Some(t) if t <= Self::MAX_TOTAL_CELLS => Ok(()),
            _ => Err(CdfOptionsError::TooLarge {
                slices,
                n_z: self.n_z,
                n_phi: self.n_phi,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_every_bad_field_is_named() {
        let d = CdfOptions::default();
        assert_eq!(d.validate(), Ok(()));
        assert_eq!(d.validate_size(CdfOptions::DEFAULT_SLICES), Ok(()));
        let bad = [
            CdfOptions {
                slices: 0,
                ..d.clone()
            },
            CdfOptions {
                anisotropic_slices: [4, 0],
                ..d.clone()
            },
            CdfOptions {
                n_z: 0,
                ..d.clone()
            },
            CdfOptions {
                n_phi: CdfOptions::MAX_CELLS_PER_AXIS + 1,
                ..d.clone()
            },
            CdfOptions {
                supersampling: 0,
                ..d.clone()
            },
            CdfOptions {
                epsilon: 0.0,
                ..d.clone()
            },
            CdfOptions {
                epsilon: f64::NAN,
                ..d.clone()
            },
            CdfOptions {
                floor: 0.0,
                ..d.clone()
            },
        ];
        for o in bad {
            let e = o.validate().expect_err("invalid options must be refused");
            assert!(e.to_string().contains("must be in"), "{e}");
        }
        assert!(matches!(
            d.validate_size(10_000),
            Err(CdfOptionsError::TooLarge { .. })
        ));
    }
}
