//! A direction sampler's declaration of where its pdf is piecewise constant, so that a
//! validation can integrate it exactly instead of refining quadrature at every jump.

use std::f64::consts::TAU;

use brdf::Vec3;

/// The coordinates `y` of an incident direction `ωi` in which a [`PdfCells`] declaration's
/// cells are boxes of `(cos θ_y, φ_y)` (local frame, normal `+z`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CellCoords {
    /// `y = ωi`.
    Incident,
    /// The half vector `y = ωh = normalize(ωi + ωo)`, flipped to the upper hemisphere. The map
    /// `ωh ↦ ωi = 2(ωo·ωh)ωh − ωo` is one-to-one from the upper hemisphere onto the sphere
    /// (up to null sets), with `dωi = 4 |ωo·ωh| dωh`; so the density of `ωh` is
    /// `q(ωh) = p(ωi) · 4 |ωo·ωh|`.
    HalfVector {
        /// The outgoing direction `ωo` (unit, local frame).
        wo: Vec3,
    },
}

/// One row of cells: `cos θ_y ∈ [z₀, z₁)`, cut along `φ_y` at `phi_edges` (strictly
/// increasing from 0 to 2π).
#[derive(Debug, Clone, PartialEq)]
pub struct PdfCellRow {
    /// `[z₀, z₁]` with `z₀ < z₁`.
    pub z: [f64; 2],
    /// Azimuth edges, `0 = φ₀ < φ₁ < … < φ_k = 2π`.
    pub phi_edges: Vec<f64>,
}

impl PdfCellRow {
    /// The row `z` whose cells, given by `edges` (increasing, spanning one turn
    /// `[e₀, e₀ + 2π]`) in a frame turned by `turn` about the normal, are expressed in the local
    /// frame: every edge moves to `(e + turn) mod 2π`, and the cell that wraps through `φ = 0`
    /// is split there (so the edges run from 0 to 2π).
    pub fn turned(z: [f64; 2], edges: &[f64], turn: f64) -> Self {
        let mut phi_edges: Vec<f64> = edges[..edges.len().saturating_sub(1)]
            .iter()
            .map(|e| (e + turn).rem_euclid(TAU))
            .filter(|e| *e > 0.0 && *e < TAU)
            .collect();
        phi_edges.sort_by(f64::total_cmp);
        phi_edges.dedup();
        phi_edges.insert(0, 0.0);
        phi_edges.push(TAU);
        Self { z, phi_edges }
    }
}

/// Where the pdf of a direction sampler at one `ωo` is piecewise constant.
///
/// Declares that `q(y) − w · c(y)` is constant on each cell `[z₀, z₁) × [φ_k, φ_{k+1})` of
/// `(cos θ_y, φ_y)`, where `q` is the sampler's pdf expressed as a density w.r.t. the solid angle
/// of `y` ([`CellCoords`]), `w` = [`PdfCells::cosine_weight`] and `c(y)` the density of the
/// cosine-weighted hemisphere `max(0, cos θi)/π` (w.r.t. the solid angle of `ωi`) expressed in
/// `y`. The rows tile the `y` domain (the upper hemisphere `cos θ_y ∈ [0, 1]` for both
/// coordinate kinds of a hemisphere sampler or of the half vector).
///
/// A validation reads only the cell geometry from here: it takes the constants from the
/// sampler's own `pdf` and checks that they are constant, so a wrong declaration is reported,
/// not trusted.
#[derive(Debug, Clone, PartialEq)]
pub struct PdfCells {
    /// The coordinates of the cells.
    pub coords: CellCoords,
    /// The rows, in increasing `z`.
    pub rows: Vec<PdfCellRow>,
    /// Weight `w ∈ [0, 1]` of a smooth cosine-weighted component (a defensive mixture), 0 if none.
    pub cosine_weight: f64,
}

impl PdfCells {
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.rows.iter().map(|r| r.phi_edges.len() - 1).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turned_rows_wrap_and_split_at_zero() {
        let edges = [0.0, 1.0, 3.0, TAU];
        let r = PdfCellRow::turned([0.0, 1.0], &edges, 0.0);
        assert_eq!(r.phi_edges, vec![0.0, 1.0, 3.0, TAU]);
        let r = PdfCellRow::turned([0.0, 1.0], &edges, -2.0);
        let expected = [0.0, 1.0, TAU - 2.0, TAU - 1.0, TAU];
        assert_eq!(r.phi_edges.len(), expected.len());
        for (a, b) in r.phi_edges.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{:?}", r.phi_edges);
        }
    }
}
