//! Analytic reflectance models (one module per model; each documents its formula, parameters,
//! defaults and reference).

pub mod abc;
pub mod ashikhmin_shirley;
pub mod beard_maxwell;
pub mod blinn;
pub mod cook_torrance;
pub mod coupled;
mod half_vector_lobe;
pub mod htsg;
pub mod lafortune;
pub mod lambert;
pub mod lewis;
mod merl_fits;
pub mod microfacet;
pub mod minnaert;
pub mod oren_nayar;
pub mod phong;
pub mod poulin_fournier;
mod properties;
pub mod schlick;
pub mod sgd;
pub mod strauss;
pub mod ward;

pub use abc::{Abc, AbcParams};
pub use ashikhmin_shirley::{AshikhminShirley, AshikhminShirleyParams};
pub use beard_maxwell::{BeardMaxwell, BeardMaxwellParams};
pub use blinn::{Blinn, BlinnParams, blinn_defaults};
pub use cook_torrance::{CookTorrance, CookTorranceParams};
pub use coupled::{Coupled, CoupledParams};
pub use htsg::{Htsg, HtsgParams};
pub use lafortune::{Lafortune, LafortuneLobe, LafortuneParams};
pub use lambert::{Lambert, LambertParams};
pub use lewis::{Lewis, LewisParams, lewis_defaults};
pub use microfacet::{Microfacet, MicrofacetParams, NormalDistribution};
pub use minnaert::{Minnaert, MinnaertParams};
pub use oren_nayar::{OrenNayar, OrenNayarParams};
pub use phong::{Phong, PhongParams};
pub use poulin_fournier::{PoulinFournier, PoulinFournierParams};
pub use schlick::{Schlick, SchlickParams};
pub use sgd::{Sgd, SgdChannel};
pub use strauss::{Strauss, StraussParams};
pub use ward::{Ward, WardNormalisation, WardParams};

pub(crate) use crate::params::{model_common, model_params};
pub(crate) use crate::registry::model;
pub use properties::Properties;
pub(crate) use properties::brdf_properties;
