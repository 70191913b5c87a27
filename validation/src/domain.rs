//! The domains samplers are tested on, and how each is binned.

use serde::{Deserialize, Serialize};
use stats::{Binning, DiscBinning, Point2, RectBinning, SphereBinning, StatsError};

/// The set a sampler draws from, with the measure its pdf refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Domain {
    /// Upper hemisphere `z ≥ 0`, pdf w.r.t. solid angle (total measure 2π); binned in
    /// `(cos θ, φ)` with equal-solid-angle bins.
    Hemisphere,
    /// Whole sphere, pdf w.r.t. solid angle (4π): for direction samplers whose support reaches
    /// below the horizon (e.g. lobes around the mirror direction). Below-horizon samples are
    /// legitimate and contribute zero to the estimators.
    Sphere,
    /// Unit disc `x² + y² ≤ 1`, pdf w.r.t. area (π): the projected hemisphere.
    Disc,
    /// Image square `[0, 1]²`, pdf w.r.t. area (1): e.g. lat-long environment maps in `(u, v)`.
    UnitSquare,
}

impl Domain {
    /// Short name used in reports (`hemisphere`, `sphere`, `disc`, `unit-square`).
    pub fn name(&self) -> &'static str {
        match self {
            Domain::Hemisphere => "hemisphere",
            Domain::Sphere => "sphere",
            Domain::Disc => "disc",
            Domain::UnitSquare => "unit-square",
        }
    }

    /// Whether points are directions (`[f64; 3]`) rather than planar points (`[f64; 2]`).
    pub fn is_directional(&self) -> bool {
        matches!(self, Domain::Hemisphere | Domain::Sphere)
    }

    /// Names of the two parameter axes the KS tests project onto.
    pub fn axis_names(&self) -> [&'static str; 2] {
        if self.is_directional() {
            ["ks-cos-theta", "ks-phi"]
        } else {
            ["ks-x", "ks-y"]
        }
    }
}

/// Bin counts per domain for one tier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Resolution {
    /// `(cos θ, φ)` bins of the hemisphere; the sphere uses twice as many `cos θ` bins.
    pub directions: [usize; 2],
    /// Cells per axis of the grid over `[−1, 1]²` clipped to the disc.
    pub disc: usize,
    /// `(x, y)` cells of the unit square.
    pub square: [usize; 2],
}

impl Resolution {
    /// This resolution coarsened for `samples` draws: each domain's bin counts are halved
    /// (both axes, rounding up, at least 1) until its cells (the sphere's, for the direction bins) number at most
    /// `samples / DEFAULT_MIN_EXPECTED`, so a density spread evenly over the domain expects at
    /// least [`stats::DEFAULT_MIN_EXPECTED`] samples per cell. Without it a small `--samples`
    /// on the full tier's 24 × 48 hemisphere bins left every cell of a uniform sampler below
    /// the χ² pooling threshold: one pooled cell, no statistic. The tiers' own sample counts
    /// keep their resolutions.
    pub fn for_samples(self, samples: usize) -> Self {
        let max_cells = ((samples as f64 / stats::DEFAULT_MIN_EXPECTED) as usize).max(1);
        let halve = |n: usize| n.div_ceil(2).max(1);
        // `cells(d)`: the domain's cell count for bins `d` (the sphere doubles the cos θ bins).
        let fit2 = |mut d: [usize; 2], cells: fn([usize; 2]) -> usize| {
            while cells(d) > max_cells && (d[0] > 1 || d[1] > 1) {
                d = [halve(d[0]), halve(d[1])];
            }
            d
        };
        let mut disc = self.disc;
        while disc * disc > max_cells && disc > 1 {
            disc = halve(disc);
        }
        Self {
            directions: fit2(self.directions, |d| 2 * d[0] * d[1]),
            disc,
            square: fit2(self.square, |d| d[0] * d[1]),
        }
    }

    /// The direction binning of `domain` (`None` for planar domains).
    ///
    /// # Errors
    /// A zero bin count.
    pub fn sphere_binning(&self, domain: Domain) -> Result<Option<SphereBinning>, StatsError> {
        let [nc, np] = self.directions;
        Ok(match domain {
            Domain::Hemisphere => Some(SphereBinning::hemisphere(nc, np)?),
            Domain::Sphere => Some(SphereBinning::sphere(2 * nc, np)?),
            Domain::Disc | Domain::UnitSquare => None,
        })
    }

    /// The planar binning of `domain` (`None` for direction domains).
    ///
    /// # Errors
    /// A zero bin count.
    pub fn planar_binning(
        &self,
        domain: Domain,
    ) -> Result<Option<Box<dyn Binning<Point = Point2>>>, StatsError> {
        Ok(match domain {
            Domain::Disc => Some(Box::new(DiscBinning::new(self.disc, self.disc)?)),
            Domain::UnitSquare => Some(Box::new(RectBinning::unit_square(
                self.square[0],
                self.square[1],
            )?)),
            Domain::Hemisphere | Domain::Sphere => None,
        })
    }
}
