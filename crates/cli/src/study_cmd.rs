//! `brdf-lab study`: variance-versus-cost studies of the direction samplers (crate `study`),
//! and `brdf-lab study merge` of shards.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use study::{StudyConfig, StudyPlan, StudyResults};

use crate::error::{CliError, CliResult};
use crate::output::write_atomically;
use crate::progress;
use crate::values::{self, counted, display_path};

/// Arguments of `brdf-lab study`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct StudyArgs {
    #[command(subcommand)]
    merge: Option<StudySub>,
    /// BRDF spec (repeatable); default: every analytic model, every shared measured file and
    /// four MERL-100 fits (the quick study's with --quick).
    #[arg(long = "brdf")]
    brdfs: Vec<String>,
    /// Registered direction sampler (repeatable); default: every registered sampler of the
    /// preferred list (uniform, cosine, the lobe/CDF/factored baselines, the adaptive ones).
    #[arg(long = "sampler")]
    samplers: Vec<String>,
    /// Outgoing polar angle θo in degrees, in [0, 90) (repeatable); default 0, 30, 60, 80, 88
    /// (30 and 60 with --quick).
    #[arg(long = "theta-o", allow_hyphen_values = true)]
    theta_o: Vec<f64>,
    /// Light (repeatable): `sky` (built in; the default when no map is found), `envmap:PATH`,
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
    /// Without a preset: study every MERL-100 fit (SGD and ABC, 200 BRDFs) instead of the four
    /// default ones (long: shard it).
    #[arg(long, conflicts_with_all = ["quick", "paper"])]
    all_merl_fits: bool,
    /// Sample counts N of the error curves, comma-separated, strictly increasing
    /// (default 1,25,100,225,400,900,1600,2500).
    #[arg(long, value_delimiter = ',', value_parser = values::at_least(1usize), allow_hyphen_values = true)]
    n_grid: Option<Vec<usize>>,
    /// Independent estimates per N (≥ 2).
    #[arg(long, value_parser = values::at_least(2usize), allow_negative_numbers = true)]
    repetitions: Option<usize>,
    /// Seed of the study; cell i uses a stream seeded from (seed, i).
    #[arg(long, default_value_t = 1, value_parser = values::seed, allow_negative_numbers = true)]
    seed: u64,
    /// Run only the cells of every N-th BRDF, starting at the K-th (K/N, 1 ≤ K ≤ N), so that
    /// a shard builds only its own BRDFs' samplers; merge the shards' directories with
    /// `brdf-lab study merge`.
    #[arg(long)]
    shard: Option<String>,
    /// Skip the sphere images (always skipped for a shard; `study merge` renders them).
    #[arg(long)]
    no_images: bool,
    /// Samples per pixel of the equal-samples sphere images, in 1 ..= 65536.
    #[arg(long, default_value_t = 64, value_parser = values::int(1usize, MAX_SPP), allow_negative_numbers = true)]
    spp: usize,
    /// Pixels per sphere side in the sphere sheets, in 16 ..= 512; default 128 (80 with --quick,
    /// to keep it within its three minutes).
    #[arg(long, value_parser = values::int(MIN_SPHERE_PX, MAX_SPHERE_PX), allow_negative_numbers = true)]
    sphere_px: Option<usize>,
    /// Output directory (checked before any work; the outputs are written to a temporary
    /// directory beside it and moved in at the end, so a failed run leaves nothing).
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
    /// Output directory of the merged study (written as `study --out` is).
    #[arg(long)]
    out: PathBuf,
    /// Skip the sphere images.
    #[arg(long)]
    no_images: bool,
    /// Samples per pixel of the equal-samples sphere images, in 1 ..= 65536.
    #[arg(long, default_value_t = 64, value_parser = values::int(1usize, MAX_SPP), allow_negative_numbers = true)]
    spp: usize,
    /// Pixels per sphere side in the sphere sheets, in 16 ..= 512.
    #[arg(long, default_value_t = SPHERE_PX, value_parser = values::int(MIN_SPHERE_PX, MAX_SPHERE_PX), allow_negative_numbers = true)]
    sphere_px: usize,
}

/// Largest `--spp` (the equal-samples images take `spp` samples per pixel and sampler).
const MAX_SPP: usize = 65_536;

/// Default pixels per sphere side of the sphere sheets (issue 28: ≥ 128 px per sphere).
const SPHERE_PX: usize = 128;
/// Pixels per sphere side of `--quick`'s sheets (its three-minute budget).
const QUICK_SPHERE_PX: usize = 80;
/// Smallest `--sphere-px`.
const MIN_SPHERE_PX: usize = 16;
/// Largest `--sphere-px`.
const MAX_SPHERE_PX: usize = 512;

/// Runs `brdf-lab study`.
pub(crate) fn run(args: &StudyArgs) -> CliResult<()> {
    let started = std::time::Instant::now();
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
        StudyConfig::full(shared_root().as_deref(), args.all_merl_fits)
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
    let shard = values::shard(args.shard.as_deref())?;
    let plan = StudyPlan::new(config, notes).map_err(CliError::input)?;
    let staging = Staging::new(&args.out)?;
    let images = !args.no_images && shard.is_none();
    let render_steps = if images {
        1 + study::IMAGE_KINDS.len() as u64 * plan.config().samplers.len() as u64
    } else {
        0
    };
    let table_steps = if args.paper && shard.is_none() { 4 } else { 0 };
    let bar = progress::bar(plan.steps(shard) + render_steps + table_steps, "study");
    let mut results = plan.run(shard, &|n| bar.inc(n));
    let cpu_before_images = study::process_cpu_seconds();
    let render = images
        .then(|| {
            let default_px = if args.quick {
                QUICK_SPHERE_PX
            } else {
                SPHERE_PX
            };
            let cfg = study::RenderConfig {
                spp: args.spp,
                seed: args.seed,
                sphere_px: args.sphere_px.unwrap_or(default_px),
                ..study::RenderConfig::default()
            };
            render_sheet(&plan, &cfg, &|n| bar.inc(n))
        })
        .transpose()?;
    let tables = if args.paper && shard.is_none() {
        Some(study::paper_tables(&|n| bar.inc(n)).map_err(CliError::input)?)
    } else {
        None
    };
    bar.finish_and_clear();
    let cpu_before_outputs = study::process_cpu_seconds();
    if let (Some(run), Some(a), Some(b), true) = (
        results.runs.first_mut(),
        cpu_before_images,
        cpu_before_outputs,
        images || tables.is_some(),
    ) {
        run.phases.push(study::PhaseCpu {
            phase: "images".into(),
            cpu_seconds: b - a,
        });
    }
    write_outputs(staging.path(), &results, render.as_ref(), tables.as_deref())?;
    staging.commit()?;
    summary(&args.out, &results);
    if let (Some(run), Some(a), Some(b)) = (
        results.runs.first(),
        cpu_before_outputs,
        study::process_cpu_seconds(),
    ) {
        phase_summary(run, Some(b - a), started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// The one-line phase summary on stderr: CPU seconds per phase of the run (all threads),
/// then the plots and report (`outputs`), and the total.
fn phase_summary(run: &study::RunInfo, outputs: Option<f64>, wall: f64) {
    let Some(phases) = run.phase_summary() else {
        return;
    };
    let total: f64 = run.phases.iter().map(|p| p.cpu_seconds).sum::<f64>() + outputs.unwrap_or(0.0);
    eprintln!(
        "study: CPU time by phase: {phases}{}; total {total:.0} CPU s, {:.0} s wall",
        outputs.map_or(String::new(), |o| format!(", outputs {o:.0} s")),
        wall
    );
}

/// `brdf-lab study merge DIR… --out DIR`.
fn merge(args: &MergeArgs) -> CliResult<()> {
    // The inputs are read and merged before the output is touched: bad input leaves nothing.
    let parts = args
        .dirs
        .iter()
        .map(|d| {
            let path = d.join("results.json");
            let text = std::fs::read_to_string(&path).map_err(|e| {
                CliError::input(format!("cannot read {}: {e}", display_path(&path)))
            })?;
            StudyResults::from_json(&text, &display_path(&path)).map_err(CliError::input)
        })
        .collect::<CliResult<Vec<_>>>()?;
    let merged = StudyResults::merge(parts).map_err(CliError::input)?;
    let staging = Staging::new(&args.out)?;
    let render = if args.no_images {
        None
    } else {
        let plan =
            StudyPlan::new(merged.config.clone(), merged.notes.clone()).map_err(CliError::input)?;
        let cfg = study::RenderConfig {
            spp: args.spp,
            seed: merged.config.seed,
            sphere_px: args.sphere_px,
            ..study::RenderConfig::default()
        };
        let bar = progress::bar(
            1 + study::IMAGE_KINDS.len() as u64 * plan.config().samplers.len() as u64,
            "images",
        );
        let r = render_sheet(&plan, &cfg, &|n| bar.inc(n))?;
        bar.finish_and_clear();
        Some(r)
    };
    // A `--paper` study's tables are not made by its shards: the merge makes them.
    let tables = if merged.config.preset == "paper" {
        let bar = progress::bar(4, "paper tables");
        let t = study::paper_tables(&|n| bar.inc(n)).map_err(CliError::input)?;
        bar.finish_and_clear();
        Some(t)
    } else {
        None
    };
    write_outputs(staging.path(), &merged, render.as_ref(), tables.as_deref())?;
    staging.commit()?;
    summary(&args.out, &merged);
    Ok(())
}

/// The sphere images of `plan`: of every BRDF when there are at most
/// [`study::SHEET_MAX_BRDFS`], else of [`study::sheet_brdfs`] (one per material family first),
/// said in the returned render's notes. Returns the render and the sentence to print above it.
fn render_sheet(
    plan: &StudyPlan,
    cfg: &study::RenderConfig,
    progress: study::ProgressFn<'_>,
) -> CliResult<(study::Render, Option<String>)> {
    let all = &plan.config().brdfs;
    let chosen = study::sheet_brdfs(all, study::SHEET_MAX_BRDFS);
    if chosen.len() == all.len() {
        let r = plan.render(cfg, progress).map_err(CliError::input)?;
        let note = missing_samplers(plan, &r);
        return Ok((r, note));
    }
    // The plan's own samplers for the chosen BRDFs (built once for the statistics).
    let r = plan
        .render_subset(cfg, &chosen, progress)
        .map_err(CliError::input)?;
    let note = format!(
        "The sphere images show {} of the study's {} materials (the first of each material family, then in order; `study::SHEET_MAX_BRDFS`), left to right: {}.\n\n",
        chosen.len(),
        all.len(),
        chosen
            .iter()
            .map(|b| format!("`{}`", study::short_brdf(b)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let note = note + &missing_samplers(plan, &r).unwrap_or_default();
    Ok((r, Some(note)))
}

/// The study's samplers that have no sphere image, and why: one sphere row holds several
/// materials, and a sampler is drawn only when it can be built for every one of them
/// (`analytic` applies to analytic models only, `rgl-native` to RGL files only).
fn missing_samplers(plan: &StudyPlan, r: &study::Render) -> Option<String> {
    let missing: Vec<String> = plan
        .config()
        .samplers
        .iter()
        .filter(|s| !r.images.iter().any(|i| &i.sampler == *s))
        .map(|s| format!("`{s}`"))
        .collect();
    (!missing.is_empty()).then(|| {
        format!(
            "Not in the sphere images: {} — a sampler is drawn only when it can be built for every material of the row (`analytic` applies to analytic models only, `rgl-native` to RGL files only); their numbers are in the tables above.\n\n",
            missing.join(", ")
        )
    })
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
        .map(|d| std::fs::canonicalize(&d).unwrap_or(d))
}

/// The output directory of a study, written atomically: checked before any work, filled in a
/// temporary directory (inside it when it exists, else in its nearest existing ancestor: on
/// the same file system either way), and moved in by [`Staging::commit`] only when every file
/// is written. A run that
/// fails (or bad input) leaves neither the output directory nor the temporary one.
struct Staging {
    dir: tempfile::TempDir,
    out: PathBuf,
}

impl Staging {
    /// Checks `out` (a directory or nothing yet, writable) and creates the temporary
    /// directory with `plots/` and `images/` (exit 2, one line, otherwise).
    fn new(out: &Path) -> CliResult<Self> {
        let fail = |why: String| CliError::input(format!("--out {}: {why}", display_path(out)));
        if out.exists() && !out.is_dir() {
            return Err(fail("exists and is not a directory".into()));
        }
        if out.is_dir() {
            tempfile::NamedTempFile::new_in(out)
                .map(drop)
                .map_err(|e| fail(format!("cannot create files: {e}")))?;
        }
        // An existing output directory holds its own temporary one (so `--out .` needs no
        // writable parent); a new one is staged in its nearest existing ancestor.
        let absolute = std::path::absolute(out).map_err(|e| fail(e.to_string()))?;
        let ancestor = absolute
            .ancestors()
            .find(|a| a.is_dir())
            .ok_or_else(|| fail("no existing parent directory".into()))?;
        let dir = tempfile::Builder::new()
            .prefix(".brdf-lab-study-")
            .tempdir_in(ancestor)
            .map_err(|e| {
                fail(format!(
                    "cannot create files in {}: {e}",
                    display_path(ancestor)
                ))
            })?;
        for sub in ["plots", "images"] {
            std::fs::create_dir(dir.path().join(sub))
                .map_err(|e| fail(format!("cannot create {sub}/: {e}")))?;
        }
        Ok(Self {
            dir,
            out: out.to_path_buf(),
        })
    }

    /// Where the outputs are written until [`Self::commit`].
    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Moves every written file into the output directory (created if missing; files of
    /// the same names are replaced, others kept), each by an atomic rename.
    fn commit(self) -> CliResult<()> {
        let fail =
            |why: String| CliError::input(format!("--out {}: {why}", display_path(&self.out)));
        let mut stack = vec![PathBuf::new()];
        while let Some(rel) = stack.pop() {
            let target = self.out.join(&rel);
            std::fs::create_dir_all(&target)
                .map_err(|e| fail(format!("cannot create {}: {e}", display_path(&target))))?;
            let entries =
                std::fs::read_dir(self.dir.path().join(&rel)).map_err(|e| fail(e.to_string()))?;
            for entry in entries {
                let entry = entry.map_err(|e| fail(e.to_string()))?;
                let name = rel.join(entry.file_name());
                if entry.path().is_dir() {
                    stack.push(name);
                } else {
                    std::fs::rename(entry.path(), self.out.join(&name))
                        .map_err(|e| fail(format!("cannot move {} in: {e}", name.display())))?;
                }
            }
        }
        Ok(())
    }
}

/// Writes `results.json`, `results.csv`, the plots (`plots/*.png`, `plots/*.svg`) and
/// `report.md` into `dir` (atomically each).
fn write_outputs(
    dir: &Path,
    results: &StudyResults,
    render: Option<&(study::Render, Option<String>)>,
    tables: Option<&[study::PaperTable]>,
) -> CliResult<()> {
    let mut assets = study::ReportAssets::default();
    if let Some((r, note)) = render {
        // Measured files by their short names: full paths are for results.json only.
        let section = results
            .config
            .brdfs
            .iter()
            .fold(write_images(dir, r)?, |sec, b| {
                sec.replace(&format!("`{b}`"), &format!("`{}`", study::short_brdf(b)))
            });
        assets.sections.push(match note {
            // After the section's heading line.
            Some(n) => match section.split_once('\n') {
                Some((head, rest)) => format!("{head}\n\n{n}{rest}"),
                None => format!("{n}{section}"),
            },
            None => section,
        });
    }
    if let Some(t) = tables {
        assets.sections.push(study::paper_markdown(t));
    }
    for p in study::study_plots(results).map_err(CliError::input)? {
        let png = format!("plots/{}.png", p.stem);
        write_atomically(&dir.join(&png), |w| w.write_all(&p.png))?;
        write_text(&dir.join(format!("plots/{}.svg", p.stem)), &p.svg)?;
        if p.slug.is_empty() {
            assets.summary_plots.push((p.caption, png));
        } else {
            assets.plots.push((p.slug, p.caption, png));
        }
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
    for kind in study::IMAGE_KINDS {
        if !r.images.iter().any(|i| i.kind == kind) {
            continue;
        }
        let rows: Vec<(String, image::RgbImage)> = std::iter::once(&r.reference)
            .chain(r.images.iter().filter(|i| i.kind == kind))
            .map(|i| {
                let label = if i.kind == "reference" {
                    format!("reference ({} spp)", i.spp)
                } else {
                    format!("{} ({} spp)", i.sampler, i.spp)
                };
                (label, i.to_rgb8(exposure))
            })
            .collect();
        let columns: Vec<String> = r.brdfs.iter().map(|b| study::short_brdf(b)).collect();
        let order: Vec<String> = r
            .images
            .iter()
            .filter(|i| i.kind == kind)
            .map(|i| format!("{} ({} spp)", i.sampler, i.spp))
            .collect();
        let file = format!("images/spheres-{}.png", kind.replace(' ', "-"));
        let sheet = study::labelled_sheet(&rows, &columns).map_err(CliError::input)?;
        let bytes = study::encode_png(&sheet, &file).map_err(CliError::input)?;
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
        "study: {}{}{} → {}",
        counted(results.cells.len(), "cell"),
        results.shard.map_or(String::new(), |s| format!(
            " (shard {}/{})",
            s.index, s.count
        )),
        if failed > 0 {
            format!(", {failed} could not run (see the report)")
        } else {
            String::new()
        },
        display_path(&dir.join("report.md"))
    );
}
