//! `brdf-lab study`: variance-versus-cost studies of the direction samplers (crate `study`),
//! and `brdf-lab study merge` of shards.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use study::{Shard, StudyConfig, StudyPlan, StudyResults};

use crate::error::{CliError, CliResult};
use crate::output::write_atomically;
use crate::progress;

/// Arguments of `brdf-lab study`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct StudyArgs {
    #[command(subcommand)]
    merge: Option<StudySub>,
    /// BRDF spec (repeatable); default: the quick study's BRDFs.
    #[arg(long = "brdf")]
    brdfs: Vec<String>,
    /// Registered direction sampler (repeatable); default: every registered sampler of the
    /// preferred list (uniform, cosine, the lobe/CDF/factored baselines, the adaptive ones).
    #[arg(long = "sampler")]
    samplers: Vec<String>,
    /// Outgoing polar angle θo in degrees (repeatable); default 30 and 60.
    #[arg(long = "theta-o")]
    theta_o: Vec<f64>,
    /// Light (repeatable): `sky` (default, built in), `envmap:PATH`,
    /// `area[:theta=DEG,phi=DEG,radius=DEG,radiance=L]`, `constant[:radiance=L]`.
    #[arg(long = "light")]
    lights: Vec<String>,
    /// The one-minute study: every registered preferred sampler on 4+ BRDFs under a real map
    /// from ../shared/data/envmaps (the procedural sky when it is missing, said in the report).
    #[arg(long, conflicts_with = "paper")]
    quick: bool,
    /// The papers' study (reduced size, stated in the report): sphere scene lights and BRDFs.
    #[arg(long)]
    paper: bool,
    /// Sample counts N of the error curves, comma-separated, strictly increasing
    /// (default 1,25,100,225,400,900,1600,2500).
    #[arg(long, value_delimiter = ',')]
    n_grid: Option<Vec<usize>>,
    /// Independent estimates per N (≥ 2).
    #[arg(long)]
    repetitions: Option<usize>,
    /// Seed of the study; cell i uses a stream seeded from (seed, i).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run only every N-th cell, starting at the K-th (K/N, 1 ≤ K ≤ N); merge the shards'
    /// directories with `brdf-lab study merge`.
    #[arg(long)]
    shard: Option<String>,
    /// Skip the sphere images (always skipped for a shard; `study merge` renders them).
    #[arg(long)]
    no_images: bool,
    /// Samples per pixel of the equal-samples sphere images.
    #[arg(long, default_value_t = 64)]
    spp: usize,
    /// Output directory (created if missing; checked before any work).
    #[arg(long, default_value = "study-out")]
    out: PathBuf,
}

/// `brdf-lab study merge`.
#[derive(Debug, Subcommand)]
enum StudySub {
    /// Combine the output directories of shards (`study --shard K/N`) into one report.
    Merge(MergeArgs),
}

/// Arguments of `brdf-lab study merge`.
#[derive(Debug, Args)]
struct MergeArgs {
    /// Shard output directories (each with a results.json).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output directory of the merged study.
    #[arg(long)]
    out: PathBuf,
    /// Skip the sphere images.
    #[arg(long)]
    no_images: bool,
    /// Samples per pixel of the equal-samples sphere images.
    #[arg(long, default_value_t = 64)]
    spp: usize,
}

/// Runs `brdf-lab study`.
pub(crate) fn run(args: &StudyArgs) -> CliResult<()> {
    if let Some(StudySub::Merge(m)) = &args.merge {
        return merge(m);
    }
    let (mut config, notes) = if args.quick {
        StudyConfig::quick(shared_root().as_deref())
    } else if args.paper {
        (StudyConfig::paper(), vec![
            "--paper runs the sphere-scene estimator study at reduced size (2 BRDFs, 3 angles, the area light and the sky); the paper tables that need the factored baseline or MERL data are produced only for the samplers and data present".to_string(),
        ])
    } else {
        let (q, _) = StudyConfig::quick(None);
        let mut c = StudyConfig::new(q.samplers, q.brdfs, q.theta_o_deg, vec!["sky".into()]);
        c.preset = "custom".into();
        (c, Vec::new())
    };
    if !args.brdfs.is_empty() {
        config.brdfs.clone_from(&args.brdfs);
    }
    if !args.samplers.is_empty() {
        config.samplers.clone_from(&args.samplers);
    }
    if !args.theta_o.is_empty() {
        config.theta_o_deg.clone_from(&args.theta_o);
    }
    if !args.lights.is_empty() {
        config.lights.clone_from(&args.lights);
    }
    if let Some(g) = &args.n_grid {
        config.n_grid.clone_from(g);
    }
    if let Some(r) = args.repetitions {
        config.repetitions = r;
    }
    config.seed = args.seed;
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(CliError::input)?;
    let plan = StudyPlan::new(config, notes).map_err(CliError::input)?;
    prepare_dir(&args.out)?;
    let images = !args.no_images && shard.is_none();
    let render_steps = if images {
        1 + 2 * plan.config().samplers.len() as u64
    } else {
        0
    };
    let table_steps = if args.paper && shard.is_none() { 4 } else { 0 };
    let bar = progress::bar(plan.steps(shard) + render_steps + table_steps, "study");
    let results = plan.run(shard, &|n| bar.inc(n));
    let render = images
        .then(|| {
            let cfg = study::RenderConfig {
                spp: args.spp.max(1),
                seed: args.seed,
                ..study::RenderConfig::default()
            };
            plan.render(&cfg, &|n| bar.inc(n))
        })
        .transpose()
        .map_err(CliError::input)?;
    let tables = if args.paper && shard.is_none() {
        Some(study::paper_tables(&|n| bar.inc(n)).map_err(CliError::input)?)
    } else {
        None
    };
    bar.finish_and_clear();
    write_outputs(&args.out, &results, render.as_ref(), tables.as_deref())?;
    summary(&args.out, &results);
    Ok(())
}

/// `brdf-lab study merge DIR… --out DIR`.
fn merge(args: &MergeArgs) -> CliResult<()> {
    prepare_dir(&args.out)?;
    let parts = args
        .dirs
        .iter()
        .map(|d| {
            let path = d.join("results.json");
            let text = std::fs::read_to_string(&path)
                .map_err(|e| CliError::input(format!("cannot read {}: {e}", path.display())))?;
            StudyResults::from_json(&text, &path.display().to_string()).map_err(CliError::input)
        })
        .collect::<CliResult<Vec<_>>>()?;
    let merged = StudyResults::merge(parts).map_err(CliError::input)?;
    let render = if args.no_images {
        None
    } else {
        let plan =
            StudyPlan::new(merged.config.clone(), merged.notes.clone()).map_err(CliError::input)?;
        let cfg = study::RenderConfig {
            spp: args.spp.max(1),
            seed: merged.config.seed,
            ..study::RenderConfig::default()
        };
        let bar = progress::bar(1 + 2 * plan.config().samplers.len() as u64, "images");
        let r = plan
            .render(&cfg, &|n| bar.inc(n))
            .map_err(CliError::input)?;
        bar.finish_and_clear();
        Some(r)
    };
    write_outputs(&args.out, &merged, render.as_ref(), None)?;
    summary(&args.out, &merged);
    Ok(())
}

/// The directory holding `../shared` for the quick study's data: the current directory when
/// `../shared` is beside it, else the repository this binary was built from.
fn shared_root() -> Option<PathBuf> {
    let candidates = [
        std::env::current_dir().ok(),
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|d| d.join("../shared").is_dir())
}

/// Creates the output directory if needed and checks that files can be created in it, before
/// any work (exit 2, one line, otherwise).
fn prepare_dir(dir: &Path) -> CliResult<()> {
    let fail = |why: String| CliError::input(format!("--out {}: {why}", dir.display()));
    if dir.exists() && !dir.is_dir() {
        return Err(fail("exists and is not a directory".into()));
    }
    for sub in [dir.to_path_buf(), dir.join("plots"), dir.join("images")] {
        std::fs::create_dir_all(&sub)
            .map_err(|e| fail(format!("cannot create {}: {e}", sub.display())))?;
    }
    tempfile::NamedTempFile::new_in(dir)
        .map(drop)
        .map_err(|e| fail(format!("cannot create files: {e}")))
}

/// Writes `results.json`, `results.csv`, the plots (`plots/*.png`, `plots/*.svg`) and
/// `report.md` into `dir` (atomically each).
fn write_outputs(
    dir: &Path,
    results: &StudyResults,
    render: Option<&study::Render>,
    tables: Option<&[study::PaperTable]>,
) -> CliResult<()> {
    let mut assets = study::ReportAssets::default();
    if let Some(r) = render {
        assets.sections.push(write_images(dir, r)?);
    }
    if let Some(t) = tables {
        assets.sections.push(study::paper_markdown(t));
    }
    for p in study::study_plots(results).map_err(CliError::input)? {
        let png = format!("plots/{}.png", p.stem);
        write_atomically(&dir.join(&png), |w| w.write_all(&p.png))?;
        write_text(&dir.join(format!("plots/{}.svg", p.stem)), &p.svg)?;
        assets.plots.push((p.slug, p.caption, png));
    }
    write_text(&dir.join("results.json"), &results.to_json())?;
    write_text(&dir.join("results.csv"), &results.to_csv())?;
    write_text(
        &dir.join("report.md"),
        &study::report_markdown(results, &assets),
    )
}

/// Writes every sphere image (PNG tone-mapped with the reference's exposure, PFM raw) and the
/// two contact sheets; returns the report's section.
fn write_images(dir: &Path, r: &study::Render) -> CliResult<String> {
    let exposure = study::Image::exposure_of(&r.reference);
    let png = |img: &study::Image| img.png(exposure).map_err(CliError::input);
    let stem = |img: &study::Image| format!("{}-{}", img.sampler, img.kind.replace(' ', "-"));
    for img in std::iter::once(&r.reference).chain(&r.images) {
        let name = if img.kind == "reference" {
            "reference".to_string()
        } else {
            stem(img)
        };
        let bytes = png(img)?;
        write_atomically(&dir.join(format!("images/{name}.png")), |w| {
            w.write_all(&bytes)
        })?;
        let raw = img.pfm();
        write_atomically(&dir.join(format!("images/{name}.pfm")), |w| {
            w.write_all(&raw)
        })?;
    }
    let mut sheets = Vec::new();
    for kind in ["equal samples", "equal time"] {
        let rows: Vec<image::RgbImage> = std::iter::once(&r.reference)
            .chain(r.images.iter().filter(|i| i.kind == kind))
            .map(|i| i.to_rgb8(exposure))
            .collect();
        let order: Vec<String> = r
            .images
            .iter()
            .filter(|i| i.kind == kind)
            .map(|i| format!("{} ({} spp)", i.sampler, i.spp))
            .collect();
        let file = format!("images/spheres-{}.png", kind.replace(' ', "-"));
        let bytes = study::encode_png(&study::stack(&rows), &file).map_err(CliError::input)?;
        write_atomically(&dir.join(&file), |w| w.write_all(&bytes))?;
        sheets.push((
            format!("{kind}, top to bottom: reference, {}", order.join(", ")),
            file,
        ));
    }
    Ok(r.markdown(&sheets))
}

fn write_text(path: &Path, text: &str) -> CliResult<()> {
    write_atomically(path, |w| w.write_all(text.as_bytes()))
}

/// The one-line summary on stderr.
fn summary(dir: &Path, results: &StudyResults) {
    let failed = results.cells.iter().filter(|c| !c.ok()).count();
    eprintln!(
        "study: {} cells{}{} → {}",
        results.cells.len(),
        results.shard.map_or(String::new(), |s| format!(
            " (shard {}/{})",
            s.index, s.count
        )),
        if failed > 0 {
            format!(", {failed} could not run (see the report)")
        } else {
            String::new()
        },
        dir.join("report.md").display()
    );
}
