//! Arguments shared by the BRDF commands (`sample`, `eval`, `build`) and building samplers.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, DiscMapPolicy, QuadTreeSet, SetOptions};
use clap::Args;
use partition_sampler::TreeParams;

use crate::baseline_args::{BaselineArgs, ProductBaselineArgs, applies_to};
use crate::error::{CliError, CliResult};
use crate::progress;
use crate::values::{self, End, display_path};

/// The BRDF and the outgoing direction.
#[derive(Debug, Args)]
pub(crate) struct BrdfArgs {
    /// BRDF: `name` or `name:key=value,...` (e.g. `phong:n=50,ks=0.7,kd=0.3`) or `merl:PATH`.
    /// Optional with --set (the set stores it; when given, it must match).
    #[arg(long = "brdf", required_unless_present = "set_file")]
    pub(crate) spec: Option<String>,
    /// Outgoing polar angle θo in degrees, in [0, 90).
    #[arg(long = "theta-o", value_parser = values::theta_o, allow_hyphen_values = true)]
    pub(crate) theta_o: f64,
    /// Outgoing azimuth φo in degrees, in [−360, 360].
    #[arg(long = "phi-o", default_value_t = 0.0, value_parser = values::azimuth, allow_hyphen_values = true)]
    pub(crate) phi_o: f64,
}

/// Options of the adaptive quadtree sets (and `adaptive-exact`).
#[derive(Debug, Args, Clone)]
#[command(next_help_heading = "Options of the adaptive samplers")]
pub(crate) struct AdaptiveArgs {
    /// Outgoing-angle slices of an isotropic BRDF's set.
    #[arg(long, default_value_t = SetOptions::DEFAULT_SLICES,
          value_parser = values::int(1, SetOptions::MAX_SLICES), allow_negative_numbers = true)]
    pub(crate) slices: usize,
    /// Split threshold n_max ≥ 1 (mean trials per sample ≤ n_max). `adaptive-exact` on an RGL
    /// file splits its envelope trees further, to n_max ≤ 1.2 (fewer costly evaluations).
    #[arg(long, default_value_t = SetOptions::DEFAULT_N_MAX,
          value_parser = values::real(End::Closed(1.0), End::None), allow_hyphen_values = true)]
    pub(crate) n_max: f64,
    /// Maximum quadtree depth; the image map must be finer than the deepest leaf:
    /// 2^(max_depth+1) ≤ grid, so at most 7 at the default --grid 256 (8 needs --grid 512).
    #[arg(long, default_value_t = SetOptions::DEFAULT_MAX_DEPTH,
          value_parser = values::int(0u32, partition_sampler::MAX_DEPTH_LIMIT), allow_negative_numbers = true)]
    pub(crate) max_depth: u32,
    /// Cells per axis of each slice's sampled image map over [-1, 1]²: a power of two; the
    /// slices refined for grazing lobes use up to 4 times as many.
    #[arg(long, default_value_t = SetOptions::DEFAULT_GRID,
          value_parser = values::int(4, SetOptions::MAX_GRID), allow_negative_numbers = true)]
    pub(crate) grid: usize,
    /// Hemisphere-to-disc map of the slices: `auto` (projected disc; equal-area from
    /// --equal-area-from degrees and for BRDFs unbounded at the horizon), `projected`
    /// (the papers') or `equal-area`.
    #[arg(long, default_value = "auto", value_parser = parse_disc_map)]
    pub(crate) disc_map: DiscMapPolicy,
    /// Outgoing polar angle (degrees, in [0, 90]) from which `--disc-map auto` uses the
    /// equal-area map.
    #[arg(long, default_value_t = SetOptions::DEFAULT_EQUAL_AREA_FROM_DEG,
          value_parser = values::real(End::Closed(0.0), End::Closed(90.0)), allow_hyphen_values = true)]
    pub(crate) equal_area_from: f64,
}

/// A command's sampler options: the adaptive sets' and the baseline samplers' (`B`). Each
/// applies to some samplers only ([`applies_to`]).
#[derive(Debug, Args, Clone)]
pub(crate) struct SamplerOptionArgs<B: Args> {
    #[command(flatten)]
    pub(crate) adaptive: AdaptiveArgs,
    #[command(flatten)]
    pub(crate) baselines: B,
}

/// The sampler options of `sample`, `eval` and `build`.
pub(crate) type SamplerArgs = SamplerOptionArgs<BaselineArgs>;

/// The options of `product`: every sampler option (its `--brdf-sampler`s may be any direction
/// sampler) and the SRBF product estimator's.
pub(crate) type ProductSamplerArgs = SamplerOptionArgs<ProductBaselineArgs>;

/// The name `product_cmd` knows `product`'s sampler options by.
pub(crate) type SetArgs = ProductSamplerArgs;

impl<B: Args> SamplerOptionArgs<B> {
    /// The adaptive sets' options.
    pub(crate) fn options(&self) -> SetOptions {
        self.adaptive.options()
    }

    /// [`AdaptiveArgs::check`].
    pub(crate) fn check(&self) -> CliResult<()> {
        self.adaptive.check()
    }
}

fn parse_disc_map(s: &str) -> Result<DiscMapPolicy, String> {
    DiscMapPolicy::parse(s).ok_or_else(|| format!("`{s}`: expected auto, projected or equal-area"))
}

impl AdaptiveArgs {
    /// The adaptive sets' options these flags select.
    pub(crate) fn options(&self) -> SetOptions {
        let defaults = SetOptions::default();
        SetOptions {
            slices: self.slices,
            tree: TreeParams {
                n_max: self.n_max,
                max_depth: self.max_depth,
                ..defaults.tree
            },
            grid: self.grid,
            disc_map: self.disc_map,
            equal_area_from_deg: self.equal_area_from,
            ..defaults
        }
    }
}

impl AdaptiveArgs {
    /// Checks `--grid` and `--max-depth` with messages in terms of the options (exit 2), e.g.
    /// which `--grid` a `--max-depth` needs.
    pub(crate) fn check(&self) -> CliResult<()> {
        let levels = SetOptions::DEFAULT_REFINE_LEVELS;
        let largest = SetOptions::MAX_GRID >> levels;
        if !(self.grid.is_power_of_two() && (4..=largest).contains(&self.grid)) {
            return Err(CliError::input(format!(
                "--grid {}: must be a power of two in 4 ..= {largest} (refined slices double it up to {levels} times, at most {})",
                self.grid,
                SetOptions::MAX_GRID
            )));
        }
        let deepest = largest.trailing_zeros() - 1;
        if self.max_depth > deepest {
            return Err(CliError::input(format!(
                "--max-depth {}: at most {deepest} (2^(max_depth+1) ≤ grid ≤ {largest})",
                self.max_depth
            )));
        }
        let needed = 1usize << (self.max_depth + 1);
        if needed > self.grid {
            return Err(CliError::input(format!(
                "--max-depth {} needs --grid {needed} or more (2^(max_depth+1) ≤ grid; the grid is {})",
                self.max_depth, self.grid
            )));
        }
        Ok(())
    }
}

pub(crate) use crate::baseline_args::SET_OPTION_IDS;

/// `--brdf` when no `--set` is given (clap requires it then).
pub(crate) fn required_spec(args: &BrdfArgs) -> CliResult<&str> {
    args.spec
        .as_deref()
        .ok_or_else(|| CliError::input("--brdf SPEC is required without --set"))
}

/// A set loaded from `--set FILE` (written by `build --out`): its stored spec, the BRDF parsed
/// from it and the set. `--brdf` (`given_spec`) must be the stored spec when given, `--sampler`
/// (`given_sampler`) the set's sampler name (returned last: the registry entry it was built as).
pub(crate) fn load_set(
    path: &Path,
    given_spec: Option<&str>,
    given_sampler: Option<&str>,
) -> CliResult<(String, Arc<dyn Brdf>, Built, &'static str)> {
    let fail = |why: String| CliError::input(format!("--set {}: {why}", display_path(path)));
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let stored = if brdf_sampling::ExactSet::is_stored(&bytes) {
        brdf_sampling::ExactSet::stored_spec(&bytes)
    } else {
        QuadTreeSet::stored_spec(&bytes)
    };
    let spec = stored.map_err(|e| fail(e.to_string()))?;
    if let Some(given) = given_spec
        && given.trim() != spec
    {
        return Err(fail(format!(
            "the set was built for --brdf {spec}, not {given} (omit --brdf or give that spec)"
        )));
    }
    let brdf = parse_brdf(&spec)?;
    let (entry, built) = samplers::load_set(&bytes, Some((brdf.clone(), spec.as_str())))
        .map_err(|e| fail(e.to_string()))?;
    if let Some(name) = given_sampler
        && name.trim() != entry.name
    {
        return Err(fail(format!(
            "the set is an `{}` sampler, not `{name}` (omit --sampler)",
            entry.name
        )));
    }
    Ok((spec, brdf, Built::from(built), entry.name))
}

/// Parses a SPEC into a shareable BRDF (exit 2 with the parser's reason on failure); warns on
/// stderr when its parameters are physically implausible ([`warn_if_implausible`]).
pub(crate) fn parse_brdf(spec: &str) -> CliResult<Arc<dyn Brdf>> {
    let brdf: Arc<dyn Brdf> = brdf::parse_spec(spec)
        .map(Arc::from)
        .map_err(|e| CliError::input(format!("--brdf {spec}: {e}")))?;
    warn_if_implausible(spec, brdf.as_ref());
    Ok(brdf)
}

/// Prints `brdf-lab: warning: --brdf SPEC: …` for each of [`brdf::energy_warnings`] (albedo
/// above 1 at some outgoing angle): accepted, but the user should know.
pub(crate) fn warn_if_implausible(spec: &str, brdf: &dyn Brdf) {
    for w in brdf::energy_warnings(brdf) {
        eprintln!("brdf-lab: warning: --brdf {spec}: {w}");
    }
}

/// The outgoing direction of `--theta-o/--phi-o`, validated.
pub(crate) fn outgoing(args: &BrdfArgs) -> CliResult<Vec3> {
    if !(args.theta_o >= 0.0 && args.theta_o < 90.0) {
        return Err(CliError::input(format!(
            "--theta-o must be in [0, 90) degrees, got {}",
            args.theta_o
        )));
    }
    if !args.phi_o.is_finite() {
        return Err(CliError::input(format!(
            "--phi-o must be finite, got {}",
            args.phi_o
        )));
    }
    Ok(brdf::direction_from_angles(args.theta_o, args.phi_o))
}

/// A built direction sampler; adaptive sets are kept concrete for their reports.
pub(crate) enum Built {
    /// An adaptive quadtree set.
    Set(Arc<QuadTreeSet>),
    /// An `adaptive-exact` set.
    Exact(Arc<brdf_sampling::ExactSet>),
    /// Any other sampler.
    Other(Arc<dyn DirectionSampler>),
}

impl Built {
    pub(crate) fn sampler(&self) -> &dyn DirectionSampler {
        match self {
            Built::Set(s) => s.as_ref(),
            Built::Exact(s) => s.as_ref(),
            Built::Other(s) => s.as_ref(),
        }
    }

    /// The bytes that save the sampler (`spec`: its BRDF spec), for the samplers that can be
    /// saved (adaptive quadtree sets, `adaptive-exact`).
    pub(crate) fn to_bytes(&self, spec: &str) -> Option<Vec<u8>> {
        match self {
            Built::Set(s) => Some(s.to_bytes()),
            Built::Exact(s) => Some(s.to_bytes(spec)),
            Built::Other(_) => None,
        }
    }

    /// The sampler as a shared direction sampler.
    pub(crate) fn shared(&self) -> Arc<dyn DirectionSampler> {
        match self {
            Built::Set(s) => Arc::clone(s) as Arc<dyn DirectionSampler>,
            Built::Exact(s) => Arc::clone(s) as Arc<dyn DirectionSampler>,
            Built::Other(s) => Arc::clone(s),
        }
    }
}

impl From<samplers::BuiltDirection> for Built {
    fn from(b: samplers::BuiltDirection) -> Self {
        match (b.set, b.exact) {
            (Some(set), _) => Built::Set(set),
            (None, Some(exact)) => Built::Exact(exact),
            (None, None) => Built::Other(b.sampler),
        }
    }
}

/// Builds sampler `name` for `brdf` (spec recorded), with a progress bar over the slices;
/// returns it with the wall time of the build. Prints the build's warnings
/// ([`print_build_warnings`]).
pub(crate) fn build(
    name: &str,
    spec: &str,
    brdf: Arc<dyn Brdf>,
    set: &SamplerArgs,
) -> CliResult<(Built, Duration)> {
    let options = set.options();
    let baselines = set.baselines.options()?;
    let pb = progress::bar(0, "building");
    let tick = |done: usize, total: usize| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let request = samplers::DirectionRequest::new(brdf, &options)
        .with_baselines(baselines)
        .with_spec(spec);
    let request = request.with_progress(&tick);
    let started = Instant::now();
    let built = samplers::build_direction(name, &request)
        .map(Built::from)
        .map_err(CliError::input);
    let elapsed = started.elapsed();
    pb.finish_and_clear();
    let built = built?;
    print_build_warnings(name, built.sampler());
    Ok((built, elapsed))
}

/// The warnings of a built sampler: the lines `warning: …` of its
/// [`brdf_sampling::SamplerDiagnostics::build_report`] (e.g. `srbf` fits that hit the L-BFGS iteration cap),
/// without that prefix.
pub(crate) fn build_warnings(sampler: &dyn DirectionSampler) -> Vec<String> {
    sampler
        .build_report()
        .map(|r| {
            r.lines()
                .filter_map(|l| l.strip_prefix("warning: ").map(str::to_string))
                .collect()
        })
        .unwrap_or_default()
}

/// Prints `brdf-lab: warning: --sampler NAME: …` on stderr for each of [`build_warnings`].
pub(crate) fn print_build_warnings(name: &str, sampler: &dyn DirectionSampler) {
    for w in build_warnings(sampler) {
        eprintln!("brdf-lab: warning: --sampler {name}: {w}");
    }
}

/// The lines of a built sampler's report without its warnings (printed apart).
pub(crate) fn report_lines(sampler: &dyn DirectionSampler) -> Vec<String> {
    sampler
        .build_report()
        .map(|r| {
            r.lines()
                .filter(|l| !l.starts_with("warning: "))
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default()
}

/// The ids of the options given on the command line (clap ids: the field names).
#[derive(Debug, Default)]
pub(crate) struct Given(pub(crate) Vec<String>);

impl Given {
    /// The options given on the command line among `matches`' (not their defaults).
    pub(crate) fn of(matches: &clap::ArgMatches) -> Self {
        Self(
            matches
                .ids()
                .filter(|id| {
                    matches.value_source(id.as_str())
                        == Some(clap::parser::ValueSource::CommandLine)
                })
                .map(|id| id.as_str().to_string())
                .collect(),
        )
    }
}

/// Refuses sampler options given for a sampler they do not configure ([`applies_to`]): exit
/// 2 with `--epsilon applies to sampler cascade-cdf, not adaptive`. `sampler` is the sampler
/// in use; `None` when the command builds none (`eval` without `--sampler`).
pub(crate) fn check_options_apply(given: &Given, sampler: Option<&str>) -> CliResult<()> {
    for (ids, names) in applies_to() {
        if sampler.is_some_and(|s| names.contains(&s.trim())) {
            continue;
        }
        if let Some(id) = ids.iter().find(|id| given.0.iter().any(|g| g == *id)) {
            let flag = format!("--{}", id.replace('_', "-"));
            let list = if names.len() == 1 {
                format!("sampler {}", names[0])
            } else {
                format!("samplers {}", names.join(", "))
            };
            let used = match sampler {
                Some(s) => s.trim().to_string(),
                None => "none (no --sampler given)".to_string(),
            };
            return Err(CliError::input(format!(
                "{flag} applies to {list}, not {used}"
            )));
        }
    }
    Ok(())
}

/// Prints the build report of an adaptive set to stdout (nothing for other samplers).
pub(crate) fn print_set_report(built: &Built) {
    for line in set_report_lines(built) {
        println!("{line}");
    }
}

/// The lines of the build report of an adaptive set (none for other samplers).
pub(crate) fn set_report_lines(built: &Built) -> Vec<String> {
    let Built::Set(set) = built else {
        return Vec::new();
    };
    let r = set.report();
    let structure = format!(
        "set        {} slices ({} θ × {} φ{}), {}, {:.1} KiB, {} nodes, {} leaves, depth ≤ {}",
        r.trees,
        r.layout.theta,
        r.layout.phi,
        if r.layout.half_turn {
            " over [0°, 180°), half-turn symmetry"
        } else {
            ""
        },
        if r.build_time.is_zero() {
            "loaded from a file".to_string()
        } else {
            format!("built in {:.3} s", r.build_time.as_secs_f64())
        },
        r.memory_bytes as f64 / 1024.0,
        r.nodes,
        r.leaves,
        r.max_depth
    );
    let measured = r
        .measured_mean_trials
        .map_or("n/a".into(), |t| format!("{t:.4}"));
    let trials = format!(
        "trials     expected {:.4} (worst slice {:.4}), measured {measured}; bound violations {}; grid evaluations {}",
        r.expected_mean_trials,
        r.worst_expected_mean_trials,
        r.bound_violations,
        r.grid_evaluations
    );
    vec![structure, trials]
}
