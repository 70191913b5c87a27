//! Lighting of the shading point: environment maps, the procedural sky, a small area light and
//! constant white.
//!
//! The shading frame is the world frame: the normal is `+z`, the zenith of a lat-long map
//! (`v = 0`), so a map's `(u, v)` gives the incident direction `ωi` directly
//! ([`envmap::latlong`]). Radiance is linear RGB; the study's estimates are luminances
//! (`colour::luminance`) of `f_r ⊙ L`.

use std::path::Path;

use brdf::Vec3;
use envmap::EnvMap;

use crate::StudyError;

/// Width of the procedural sky (`sky`); its height is half of it.
pub const SKY_WIDTH: usize = 1024;

/// Default polar angle (degrees) of the area light's centre.
pub const AREA_THETA_DEG: f64 = 35.0;
/// Default azimuth (degrees) of the area light's centre: opposite the outgoing azimuth
/// φo = 0, near the mirror direction of the study's outgoing angles.
pub const AREA_PHI_DEG: f64 = 180.0;
/// Default angular radius (degrees) of the area light.
pub const AREA_RADIUS_DEG: f64 = 5.0;
/// Default radiance of the area light.
pub const AREA_RADIANCE: f64 = 50.0;

/// The radiance arriving at the shading point from every direction.
#[derive(Debug, Clone)]
pub enum Light {
    /// A lat-long environment map (a file, or the procedural sky), pixels piecewise constant.
    Map {
        /// The map.
        map: EnvMap,
        /// `sky` or the file's name.
        label: String,
    },
    /// A disc light seen under the angular radius `radius` around `axis`, constant radiance;
    /// wholly above the horizon.
    Area {
        /// Unit direction of the disc's centre.
        axis: Vec3,
        /// Angular radius (radians).
        radius: f64,
        /// Radiance (grey).
        radiance: f64,
    },
    /// The same radiance from every direction: `L_r(ωo)` is the directional albedo times it.
    Constant {
        /// Radiance (grey).
        radiance: f64,
    },
}

impl Light {
    /// Parses a light spec: `sky` (procedural sky with a sun), `envmap:PATH` (`.hdr`, `.exr`,
    /// `.pfm`), `area[:theta=DEG,phi=DEG,radius=DEG,radiance=L]`, `constant[:radiance=L]`.
    ///
    /// Errors: [`StudyError::Light`] naming the problem (unknown kind or key, a bad number, an
    /// unreadable map, an area light reaching below the horizon).
    pub fn parse(spec: &str) -> Result<Self, StudyError> {
        let fail = |reason: String| StudyError::Light {
            spec: spec.to_string(),
            reason,
        };
        let (kind, rest) = match spec.trim().split_once(':') {
            Some((k, r)) => (k.trim(), Some(r)),
            None => (spec.trim(), None),
        };
        match kind {
            "sky" if rest.is_none() => Ok(Light::Map {
                map: envmap::procedural_sky(SKY_WIDTH, SKY_WIDTH / 2)
                    .map_err(|e| fail(e.to_string()))?,
                label: "sky".to_string(),
            }),
            "envmap" => {
                let path = rest.filter(|p| !p.is_empty()).ok_or_else(|| {
                    fail("expected envmap:PATH to a .hdr, .exr or .pfm file".into())
                })?;
                let map = EnvMap::load(path).map_err(|e| fail(e.to_string()))?;
                let label = Path::new(path)
                    .file_stem()
                    .map_or_else(|| path.to_string(), |s| s.to_string_lossy().into_owned());
                Ok(Light::Map { map, label })
            }
            "area" => {
                let mut theta = AREA_THETA_DEG;
                let mut phi = AREA_PHI_DEG;
                let mut radius = AREA_RADIUS_DEG;
                let mut radiance = AREA_RADIANCE;
                for (key, value) in key_values(rest).map_err(fail)? {
                    match key {
                        "theta" => theta = value,
                        "phi" => phi = value,
                        "radius" => radius = value,
                        "radiance" => radiance = value,
                        other => {
                            return Err(fail(format!(
                                "unknown key `{other}` (keys: theta, phi, radius, radiance)"
                            )));
                        }
                    }
                }
                if !(radius > 0.0 && theta >= 0.0 && theta + radius < 90.0) {
                    return Err(fail(format!(
                        "the light must lie above the horizon: need radius > 0, theta >= 0 and theta + radius < 90, got theta={theta}, radius={radius}"
                    )));
                }
                if !(radiance > 0.0 && radiance.is_finite() && phi.is_finite()) {
                    return Err(fail("radiance must be positive and finite".into()));
                }
                Ok(Light::Area {
                    axis: brdf::direction_from_angles(theta, phi),
                    radius: radius.to_radians(),
                    radiance,
                })
            }
            "constant" => {
                let mut radiance = 1.0;
                for (key, value) in key_values(rest).map_err(fail)? {
                    match key {
                        "radiance" => radiance = value,
                        other => {
                            return Err(fail(format!("unknown key `{other}` (keys: radiance)")));
                        }
                    }
                }
                if !(radiance > 0.0 && radiance.is_finite()) {
                    return Err(fail("radiance must be positive and finite".into()));
                }
                Ok(Light::Constant { radiance })
            }
            other => Err(fail(format!(
                "unknown light `{other}` (lights: sky, envmap:PATH, area[:theta=,phi=,radius=,radiance=], constant[:radiance=])"
            ))),
        }
    }

    /// Linear RGB radiance arriving from the unit direction `wi` (world = shading frame).
    #[inline]
    pub fn radiance(&self, wi: &Vec3) -> [f64; 3] {
        match self {
            Light::Map { map, .. } => {
                let (u, v) = envmap::latlong::direction_to_uv([wi.x, wi.y, wi.z]);
                let c = map.radiance_uv(u, v);
                [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])]
            }
            Light::Area {
                axis,
                radius,
                radiance,
            } => {
                if wi.dot(axis) >= radius.cos() {
                    [*radiance; 3]
                } else {
                    [0.0; 3]
                }
            }
            Light::Constant { radiance } => [*radiance; 3],
        }
    }

    /// A one-line description for reports.
    pub fn describe(&self) -> String {
        match self {
            Light::Map { map, label } if label == "sky" => format!(
                "procedural sky with a sun ({}×{} lat-long, built in)",
                map.width(),
                map.height()
            ),
            Light::Map { map, label } => {
                format!(
                    "environment map {label} ({}×{} lat-long)",
                    map.width(),
                    map.height()
                )
            }
            Light::Area {
                axis,
                radius,
                radiance,
            } => {
                let (t, p) = brdf::angles_of(axis);
                let (t, p) = (t.to_degrees(), p.to_degrees());
                format!(
                    "disc light of angular radius {:.1}° centred at θ = {:.1}°, φ = {:.1}°, radiance {radiance}",
                    radius.to_degrees(),
                    t,
                    p
                )
            }
            Light::Constant { radiance } => format!(
                "constant white, radiance {radiance} (L_r = radiance × albedo: an exact f·cos sampler has zero variance — a correctness check, not a race)"
            ),
        }
    }

    /// Whether this is constant white (zero variance for exact f·cos samplers).
    pub fn is_constant(&self) -> bool {
        matches!(self, Light::Constant { .. })
    }
}

/// `key=value` pairs of a spec's tail, values parsed as numbers.
fn key_values(rest: Option<&str>) -> Result<Vec<(&str, f64)>, String> {
    let Some(rest) = rest.filter(|r| !r.trim().is_empty()) else {
        return Ok(Vec::new());
    };
    rest.split(',')
        .map(|kv| {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| format!("expected key=value, got `{kv}`"))?;
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("`{}` is not a number", v.trim()))?;
            if !x.is_finite() {
                return Err(format!("`{}` is not finite", v.trim()));
            }
            Ok((k.trim(), x))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_kind_and_refuses_bad_specs() {
        assert!(matches!(Light::parse("sky").unwrap(), Light::Map { .. }));
        assert!(matches!(
            Light::parse("constant:radiance=2").unwrap(),
            Light::Constant { radiance } if radiance == 2.0
        ));
        let area = Light::parse("area:theta=20,radius=3").unwrap();
        let Light::Area { radius, .. } = area else {
            panic!("not an area light")
        };
        assert!((radius - 3f64.to_radians()).abs() < 1e-15);
        for bad in [
            "moon",
            "area:theta=88,radius=5",
            "area:colour=1",
            "constant:radiance=-1",
            "constant:radiance=nan",
            "envmap:",
            "envmap:/nonexistent/map.hdr",
            "sky:x=1",
        ] {
            assert!(Light::parse(bad).is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn area_light_is_lit_inside_its_cone_only() {
        let light = Light::parse("area:theta=30,phi=0,radius=5,radiance=7").unwrap();
        let inside = brdf::direction_from_angles(33.0, 0.0);
        let outside = brdf::direction_from_angles(36.0, 0.0);
        assert_eq!(light.radiance(&inside), [7.0; 3]);
        assert_eq!(light.radiance(&outside), [0.0; 3]);
    }
}
