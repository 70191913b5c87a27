//! One flags value for a model's properties (symmetries, reciprocity, energy, horizon), as
//! pbrt-v4 and Mitsuba give a BxDF one flags value. A model computes its [`Properties`] once in
//! an inherent `properties()` and [`brdf_properties!`](crate::models) derives the matching
//! [`Brdf`](crate::Brdf) predicates from it, so no model spells them out again.

use std::fmt;
use std::ops::{BitOr, BitOrAssign};

/// A set of model properties (a small bit set; `|` is union).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Properties(u8);

impl Properties {
    /// No property.
    pub const NONE: Self = Self(0);
    /// Invariant under a common rotation of `ωo` and `ωi` about the normal
    /// ([`Brdf::is_isotropic`](crate::Brdf::is_isotropic)).
    pub const ISOTROPIC: Self = Self(1);
    /// Isotropic and even under `(x, y, z) ↦ (x, −y, z)`
    /// ([`Brdf::is_mirror_symmetric`](crate::Brdf::is_mirror_symmetric)).
    pub const MIRROR_SYMMETRIC: Self = Self(1 << 1);
    /// Invariant under the half-turn `(x, y, z) ↦ (−x, −y, z)`
    /// ([`Brdf::is_half_turn_symmetric`](crate::Brdf::is_half_turn_symmetric)).
    pub const HALF_TURN_SYMMETRIC: Self = Self(1 << 2);
    /// Helmholtz reciprocity ([`Brdf::is_reciprocal`](crate::Brdf::is_reciprocal)).
    pub const RECIPROCAL: Self = Self(1 << 3);
    /// Directional albedo `≤ 1` everywhere
    /// ([`Brdf::conserves_energy`](crate::Brdf::conserves_energy)).
    pub const CONSERVES_ENERGY: Self = Self(1 << 4);
    /// `f_r` may grow without bound as `θi → 90°` (the negation of
    /// [`Brdf::bounded_at_horizon`](crate::Brdf::bounded_at_horizon), whose default is `true`).
    pub const UNBOUNDED_AT_HORIZON: Self = Self(1 << 5);
    /// The three symmetries an isotropic model whose value depends on `cos(φi − φo)` has:
    /// isotropic, mirror-symmetric and half-turn symmetric.
    pub const ISOTROPIC_SYMMETRIC: Self =
        Self(Self::ISOTROPIC.0 | Self::MIRROR_SYMMETRIC.0 | Self::HALF_TURN_SYMMETRIC.0);

    const NAMES: [(Self, &'static str); 6] = [
        (Self::ISOTROPIC, "isotropic"),
        (Self::MIRROR_SYMMETRIC, "mirror-symmetric"),
        (Self::HALF_TURN_SYMMETRIC, "half-turn-symmetric"),
        (Self::RECIPROCAL, "reciprocal"),
        (Self::CONSERVES_ENERGY, "conserves-energy"),
        (Self::UNBOUNDED_AT_HORIZON, "unbounded-at-horizon"),
    ];

    /// True when every flag of `other` is set in `self`.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// `self` when `condition` holds, else [`Properties::NONE`] (for properties that depend on
    /// the parameters).
    pub const fn when(self, condition: bool) -> Self {
        if condition { self } else { Self::NONE }
    }

    /// The symmetries of an elliptically anisotropic model (terms in `x²`, `y²`, `x x'`, `y y'`
    /// of the directions or of the half vector only): half-turn symmetric always, isotropic and
    /// mirror-symmetric when its two axes are equal (`isotropic`).
    pub const fn elliptical(isotropic: bool) -> Self {
        if isotropic {
            Self::ISOTROPIC_SYMMETRIC
        } else {
            Self::HALF_TURN_SYMMETRIC
        }
    }

    /// The properties a [`Brdf`](crate::Brdf) reports through its predicates (for any
    /// implementation, so tests can compare a model's declared flags with its trait answers).
    pub fn of(brdf: &dyn crate::Brdf) -> Self {
        Self::ISOTROPIC.when(brdf.is_isotropic())
            | Self::MIRROR_SYMMETRIC.when(brdf.is_mirror_symmetric())
            | Self::HALF_TURN_SYMMETRIC.when(brdf.is_half_turn_symmetric())
            | Self::RECIPROCAL.when(brdf.is_reciprocal())
            | Self::CONSERVES_ENERGY.when(brdf.conserves_energy())
            | Self::UNBOUNDED_AT_HORIZON.when(!brdf.bounded_at_horizon())
    }
}

impl BitOr for Properties {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

impl BitOrAssign for Properties {
    fn bitor_assign(&mut self, rhs: Self) {
        self.0 |= rhs.0;
    }
}

impl fmt::Debug for Properties {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = Self::NAMES
            .iter()
            .filter(|(p, _)| self.contains(*p))
            .map(|(_, n)| *n)
            .collect();
        write!(f, "Properties({})", names.join(" | "))
    }
}

/// The [`Brdf`](crate::Brdf) predicates of a model, from its inherent
/// `fn properties(&self) -> Properties` (used inside `impl Brdf for …`), and with a name
/// (`brdf_properties!(NAME)`) its [`Brdf::name`](crate::Brdf::name) too.
macro_rules! brdf_properties {
    (@has $($predicate:ident: $FLAG:ident),+) => {
        $(
            fn $predicate(&self) -> bool {
                self.properties().contains($crate::models::Properties::$FLAG)
            }
        )+
    };
    ($name:expr) => {
        $crate::models::brdf_properties!();
        fn name(&self) -> &str {
            $name
        }
    };
    () => {
        $crate::models::brdf_properties!(@has
            is_isotropic: ISOTROPIC,
            is_mirror_symmetric: MIRROR_SYMMETRIC,
            is_half_turn_symmetric: HALF_TURN_SYMMETRIC,
            is_reciprocal: RECIPROCAL,
            conserves_energy: CONSERVES_ENERGY);
        fn bounded_at_horizon(&self) -> bool {
            !self
                .properties()
                .contains($crate::models::Properties::UNBOUNDED_AT_HORIZON)
        }
    };
}
pub(crate) use brdf_properties;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_contains_when_and_debug() {
        let p = Properties::ISOTROPIC_SYMMETRIC | Properties::RECIPROCAL.when(false);
        assert!(p.contains(Properties::ISOTROPIC | Properties::HALF_TURN_SYMMETRIC));
        assert!(!p.contains(Properties::RECIPROCAL));
        assert!(p.contains(Properties::NONE));
        assert_eq!(
            Properties::elliptical(true),
            Properties::ISOTROPIC_SYMMETRIC
        );
        assert_eq!(
            Properties::elliptical(false),
            Properties::HALF_TURN_SYMMETRIC
        );
        assert_eq!(
            format!("{p:?}"),
            "Properties(isotropic | mirror-symmetric | half-turn-symmetric)"
        );
    }
}
