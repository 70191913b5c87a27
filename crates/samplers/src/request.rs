//! What a direction sampler is built from, and what building it gives.

use std::sync::Arc;

use baselines::BaselineOptions;
use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, Progress, QuadTreeSet, SetOptions};

/// Everything a direction sampler may need to be built for one BRDF.
#[derive(Clone)]
pub struct DirectionRequest<'a> {
    /// The BRDF.
    pub brdf: Arc<dyn Brdf>,
    /// The BRDF's spec string (recorded in saved sets); the BRDF's name when `None`.
    pub spec: Option<&'a str>,
    /// Options of the adaptive quadtree sets.
    pub options: &'a SetOptions,
    /// Options of the BRDF baselines (defaults unless set with [`DirectionRequest::with_baselines`]).
    pub baselines: BaselineOptions,
    /// Called with `(steps done, total)` while a sampler with a long build is built.
    pub progress: Option<Progress<'a>>,
}

impl<'a> DirectionRequest<'a> {
    /// A request for `brdf` with `options`, no spec and no progress callback.
    pub fn new(brdf: Arc<dyn Brdf>, options: &'a SetOptions) -> Self {
        Self {
            brdf,
            spec: None,
            options,
            baselines: BaselineOptions::default(),
            progress: None,
        }
    }

    /// The same request with these baseline options.
    pub fn with_baselines(mut self, baselines: BaselineOptions) -> Self {
        self.baselines = baselines;
        self
    }

    /// The same request recording `spec`.
    pub fn with_spec(mut self, spec: &'a str) -> Self {
        self.spec = Some(spec);
        self
    }

    /// The same request reporting build progress to `progress`.
    pub fn with_progress(mut self, progress: Progress<'a>) -> Self {
        self.progress = Some(progress);
        self
    }

    pub(crate) fn spec_or_name(&self) -> String {
        self.spec
            .map_or_else(|| self.brdf.name().to_string(), str::to_string)
    }
}

impl std::fmt::Debug for DirectionRequest<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DirectionRequest")
            .field("brdf", &self.brdf.name())
            .field("spec", &self.spec)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// A built direction sampler, shareable across threads.
#[derive(Clone)]
pub struct BuiltDirection {
    /// The sampler (pdf w.r.t. solid angle).
    pub sampler: Arc<dyn DirectionSampler>,
    /// The same sampler as an adaptive quadtree set, when it is one (for its report and for
    /// saving it).
    pub set: Option<Arc<QuadTreeSet>>,
    /// The same sampler as an `adaptive-exact` set, when it is one (for saving it).
    pub exact: Option<Arc<brdf_sampling::ExactSet>>,
}

impl BuiltDirection {
    /// A sampler that is not an adaptive set.
    pub fn plain(sampler: Arc<dyn DirectionSampler>) -> Self {
        Self {
            sampler,
            set: None,
            exact: None,
        }
    }

    /// An adaptive set.
    pub fn from_set(set: QuadTreeSet) -> Self {
        let set = Arc::new(set);
        Self {
            sampler: Arc::clone(&set) as Arc<dyn DirectionSampler>,
            set: Some(set),
            exact: None,
        }
    }

    /// An `adaptive-exact` set.
    pub fn from_exact(set: brdf_sampling::ExactSet) -> Self {
        let set = Arc::new(set);
        Self {
            sampler: Arc::clone(&set) as Arc<dyn DirectionSampler>,
            set: None,
            exact: Some(set),
        }
    }

    /// The bytes that save this sampler (`spec`: the BRDF spec it was built from), for the
    /// samplers that can be saved: adaptive quadtree sets and `adaptive-exact`.
    pub fn to_bytes(&self, spec: &str) -> Option<Vec<u8>> {
        match (&self.set, &self.exact) {
            (Some(set), _) => Some(set.to_bytes()),
            (None, Some(exact)) => Some(exact.to_bytes(spec)),
            (None, None) => None,
        }
    }

    /// `sampler.pdf(wo, wi)` (convenience).
    pub fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.sampler.pdf(wo, wi)
    }
}

impl std::fmt::Debug for BuiltDirection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BuiltDirection")
            .field("bytes_used", &self.sampler.bytes_used())
            .field("set", &self.set)
            .finish()
    }
}
