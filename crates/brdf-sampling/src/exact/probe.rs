//! Where a normaliser's error comes from (issue 27): the node rule evaluated at any `ωo`.
//!
//! [`ExactSet::node_rule_at`] runs the quadrature an interval's normaliser nodes use (the leaf
//! quadrature of the interval's tree, or the table integral of `tabulated.rs`) at the query
//! itself, with no θo interpolation: against an independent reference, `Â − node rule` is the
//! interpolation's part of the gap and `node rule − A` the quadrature's.

use brdf::{Vec3, direction_from_radians};

use super::grid::TableVar;
use super::set::ExactSet;
use super::tabulated;

impl ExactSet {
    /// `(A, relative error estimate)` at `wo` by the rule the set's normaliser nodes use, at
    /// `wo` itself (no interpolation in θo); `None` at or below the horizon. A diagnostic for
    /// `examples/norm_gap.rs`.
    #[doc(hidden)]
    pub fn node_rule_at(&self, wo: &Vec3) -> Option<(f64, f64)> {
        let q = self.locate(wo)?;
        let theta = match self.var {
            TableVar::Cos => q.cos.clamp(-1.0, 1.0).acos(),
            TableVar::Theta => q.var,
        };
        if let Some(r) = tabulated::table_normaliser(self.brdf.as_ref(), theta) {
            return Some(r);
        }
        let iv = self.interval(&q);
        let phi_k = self.cells[q.cell].phi;
        let d = q.delta;
        let density = super::density::QueryDensity::new(
            self.brdf.as_ref(),
            direction_from_radians(theta, phi_k + d),
            d,
            iv.map,
        );
        let tree = iv.tree.tree();
        let mirror_y =
            self.options.set.symmetries && self.brdf.is_mirror_symmetric() && self.isotropic;
        let r = tabulated::node_quadrature(
            self.brdf.as_ref(),
            &density,
            tree.leaves(),
            tree.integral(),
            mirror_y,
        );
        Some((r.total, r.rel_err))
    }
}
