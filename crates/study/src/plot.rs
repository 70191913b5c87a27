//! Plots of a study (plotters): log-log relative error against samples and against time per
//! estimate, and an efficiency bar chart; each as PNG (drawn into an RGB buffer, encoded by
//! `image`) and SVG. Text uses DejaVu Sans, shipped in `assets/` with its licence.

use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::groups::{Group, groups, short_brdf, short_light};
use crate::ranking::{ESTIMATOR_BRDF, Ranking};
use crate::{CellResult, Mode, StudyError, StudyResults};

/// Plot size in pixels (the plot area, and a legend panel on its right).
pub const PLOT_SIZE: (u32, u32) = (1040, 600);

/// Width of the legend panel, right of the plot area (pixels).
const LEGEND_WIDTH: u32 = 270;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the compiled-in font once (plots and sheets).
pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled in and valid; failing here would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// A point marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled disc.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Diagonal cross.
    Cross,
}

/// How a sampler is drawn in every plot: one colour and one marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SamplerStyle {
    /// Line, marker and bar colour.
    pub colour: RGBColor,
    /// Point marker.
    pub marker: Marker,
}

/// The fixed sampler styles, indexed by the registry entry's study index
/// (`samplers::SamplerEntry::study`, the order of [`crate::PREFERRED_SAMPLERS`]): every
/// preferred sampler has its own colour (Okabe–Ito's colour-blind-friendly eight, then darker
/// or lighter variants) and, so that no two samplers look alike even in grey, a marker;
/// families share a hue family (greens for the lobes, blues for the CDFs, reds/oranges for the
/// adaptive ones). The comments name today's holders.
const STYLES: [(RGBColor, Marker); 15] = [
    (RGBColor(120, 120, 120), Marker::Circle),  // uniform
    (RGBColor(0, 0, 0), Marker::Square),        // cosine
    (RGBColor(0, 158, 115), Marker::Triangle),  // lobe-sphere
    (RGBColor(0, 90, 60), Marker::Diamond),     // lobe-hemisphere
    (RGBColor(86, 180, 233), Marker::Cross),    // analytic
    (RGBColor(0, 114, 178), Marker::Square),    // tabulated-cdf
    (RGBColor(0, 50, 110), Marker::Triangle),   // cascade-cdf
    (RGBColor(204, 121, 167), Marker::Diamond), // factored
    (RGBColor(120, 40, 140), Marker::Circle),   // srbf
    (RGBColor(160, 140, 0), Marker::Cross),     // rgl-native
    (RGBColor(213, 94, 0), Marker::Circle),     // adaptive
    (RGBColor(230, 159, 0), Marker::Square),    // adaptive-mixture
    (RGBColor(150, 30, 30), Marker::Triangle),  // adaptive-exact
    (RGBColor(240, 80, 140), Marker::Diamond),  // adaptive-paper
    (RGBColor(130, 80, 30), Marker::Cross),     // adaptive-paper-mixture
];

/// Colours and markers of samplers outside [`STYLES`] (picked by a hash of the name, so
/// stable across plots and runs).
const SPARE: [RGBColor; 4] = [
    RGBColor(60, 60, 160),
    RGBColor(100, 160, 60),
    RGBColor(190, 120, 90),
    RGBColor(90, 150, 150),
];

/// The style of a sampler, or of a cell's label (`adaptive-paper (batch)` is drawn like
/// `adaptive-paper`, with a dashed line): the same in every plot of every study.
pub fn sampler_style(label: &str) -> SamplerStyle {
    let name = label.strip_suffix(" (batch)").unwrap_or(label);
    let slot = samplers::find(name).ok().and_then(|e| e.study);
    if let Some((colour, marker)) = slot.and_then(|i| STYLES.get(usize::from(i))) {
        return SamplerStyle {
            colour: *colour,
            marker: *marker,
        };
    }
    // FNV-1a: stable across platforms and runs (std's hasher is not).
    let h = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    });
    let markers = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::Cross,
    ];
    SamplerStyle {
        colour: SPARE[(h % SPARE.len() as u64) as usize],
        marker: markers[((h / 7) % markers.len() as u64) as usize],
    }
}

/// Draws `m` centred on backend pixel `at`.
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    m: Marker,
    colour: RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x, y) = at;
    let r = 5;
    match m {
        Marker::Circle => area.draw(&Circle::new((x, y), r, colour.filled())),
        Marker::Square => area.draw(&Rectangle::new(
            [(x - r + 1, y - r + 1), (x + r - 1, y + r - 1)],
            colour.filled(),
        )),
        Marker::Triangle => area.draw(&Polygon::new(
            vec![(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)],
            colour.filled(),
        )),
        Marker::Diamond => area.draw(&Polygon::new(
            vec![
                (x, y - r - 1),
                (x + r + 1, y),
                (x, y + r + 1),
                (x - r - 1, y),
            ],
            colour.filled(),
        )),
        Marker::Cross => {
            area.draw(&PathElement::new(
                vec![(x - r, y - r), (x + r, y + r)],
                colour.stroke_width(3),
            ))?;
            area.draw(&PathElement::new(
                vec![(x - r, y + r), (x + r, y - r)],
                colour.stroke_width(3),
            ))
        }
    }
}

/// One line of a line plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label (a cell's label: its colour and marker come from [`sampler_style`]).
    pub label: String,
    /// `(x, y)` points, both > 0 on log axes.
    pub points: Vec<(f64, f64)>,
    /// The 95 % interval `(lo, hi)` of each point's `y` (empty: none drawn).
    pub intervals: Vec<(f64, f64)>,
    /// Dashed (e.g. batch mode).
    pub dashed: bool,
}

/// One bar: `(label shown, sampler label for the style, value > 0, 95 % interval)`.
pub type Bar = (String, String, f64, Option<(f64, f64)>);

/// What a figure shows.
#[derive(Debug, Clone)]
pub enum Figure {
    /// Lines with markers (log-log; linear x when `x_linear`), intervals as bands (or as
    /// error bars when `x_linear`), the legend beside the plot.
    Lines {
        /// Title.
        title: String,
        /// x-axis label.
        x_label: String,
        /// y-axis label.
        y_label: String,
        /// Linear x axis (e.g. θo) instead of logarithmic.
        x_linear: bool,
        /// The lines.
        series: Vec<Series>,
    },
    /// Horizontal bars on a logarithmic axis, with 95 % interval whiskers.
    Bars {
        /// Title.
        title: String,
        /// x-axis label.
        y_label: String,
        /// The bars, top to bottom.
        bars: Vec<Bar>,
    },
}

/// A rendered plot.
#[derive(Debug, Clone)]
pub struct PlotFile {
    /// Group slug (empty for summary plots).
    pub slug: String,
    /// Caption for the report.
    pub caption: String,
    /// File stem (`plots/<stem>.png`, `.svg`).
    pub stem: String,
    /// PNG bytes.
    pub png: Vec<u8>,
    /// SVG text.
    pub svg: String,
}

impl Figure {
    /// The figure as PNG bytes.
    pub fn png(&self, name: &str) -> Result<Vec<u8>, StudyError> {
        register_font();
        let (w, h) = PLOT_SIZE;
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            self.draw(root, name)?;
        }
        let img =
            image::RgbImage::from_raw(w, h, buf).ok_or_else(|| plot_err(name, "buffer size"))?;
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| plot_err(name, e))?;
        Ok(out.into_inner())
    }

    /// The figure as SVG text.
    pub fn svg(&self, name: &str) -> Result<String, StudyError> {
        register_font();
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, PLOT_SIZE).into_drawing_area();
            self.draw(root, name)?;
        }
        Ok(s)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
        name: &str,
    ) -> Result<(), StudyError> {
        let e = |x: &dyn std::fmt::Debug| plot_err(name, format!("{x:?}"));
        root.fill(&WHITE).map_err(|x| e(&x))?;
        match self {
            Figure::Lines {
                title,
                x_label,
                y_label,
                x_linear,
                series,
            } => {
                let body = root.titled(title, ("sans-serif", 20)).map_err(|x| e(&x))?;
                let (plot, legend) = body.split_horizontally(PLOT_SIZE.0 - LEGEND_WIDTH);
                let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                for s in series {
                    for (i, p) in s.points.iter().enumerate() {
                        if !(p.0 > 0.0 || *x_linear) || !(p.1 > 0.0) {
                            continue;
                        }
                        let (lo, hi) = s.intervals.get(i).copied().unwrap_or((p.1, p.1));
                        x0 = x0.min(p.0);
                        x1 = x1.max(p.0);
                        y0 = y0.min(if lo > 0.0 { lo } else { p.1 });
                        y1 = y1.max(hi.max(p.1));
                    }
                }
                if x0 > x1 {
                    (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
                }
                let (y0, y1) = (y0 / 1.3, y1 * 1.3);
                if *x_linear {
                    let pad = ((x1 - x0) * 0.05).max(1.0);
                    let mut chart = lines_chart(&plot)
                        .build_cartesian_2d(x0 - pad..x1 + pad, (y0..y1).log_scale())
                        .map_err(|x| e(&x))?;
                    lines_mesh(&mut chart, x_label, y_label).map_err(|x| e(&x))?;
                    let n = series.len().max(1) as f64;
                    for (k, s) in series.iter().enumerate() {
                        // Spread the series a little along x so that whiskers do not overlap.
                        let dx = (k as f64 - (n - 1.0) / 2.0) * (pad * 0.12);
                        let moved: Vec<(f64, f64)> =
                            s.points.iter().map(|p| (p.0 + dx, p.1)).collect();
                        let moved_s = Series {
                            points: moved,
                            ..s.clone()
                        };
                        draw_series(&root, &mut chart, &moved_s, y0, true).map_err(|x| e(&x))?;
                    }
                } else {
                    let mut chart = lines_chart(&plot)
                        .build_cartesian_2d((x0 / 1.3..x1 * 1.3).log_scale(), (y0..y1).log_scale())
                        .map_err(|x| e(&x))?;
                    lines_mesh(&mut chart, x_label, y_label).map_err(|x| e(&x))?;
                    for s in series {
                        draw_series(&root, &mut chart, s, y0, false).map_err(|x| e(&x))?;
                    }
                }
                draw_legend(
                    &legend,
                    series.iter().map(|s| (s.label.as_str(), s.dashed)),
                    series
                        .iter()
                        .any(|s| !s.intervals.is_empty())
                        .then_some(if *x_linear {
                            "whiskers: the ranking's intervals"
                        } else {
                            "bands: 95 % intervals"
                        }),
                )
                .map_err(|x| e(&x))?;
            }
            Figure::Bars {
                title,
                y_label,
                bars,
            } => {
                let vals = bars.iter().flat_map(|b| {
                    let (lo, hi) = b.3.unwrap_or((b.2, b.2));
                    [b.2, lo, hi]
                });
                let (lo, hi) = vals
                    .filter(|v| *v > 0.0)
                    .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
                let (lo, hi) = if lo > hi {
                    (1.0, 10.0)
                } else {
                    (lo / 2.0, hi * 2.0)
                };
                let n = bars.len().max(1);
                let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
                // Horizontal bars: sampler names on the vertical axis, top to bottom.
                let mut chart = ChartBuilder::on(&root)
                    .caption(title, ("sans-serif", 20))
                    .margin(12)
                    .x_label_area_size(45)
                    .y_label_area_size(290)
                    .build_cartesian_2d((lo..hi).log_scale(), 0f64..n as f64)
                    .map_err(|x| e(&x))?;
                chart
                    .configure_mesh()
                    .disable_y_mesh()
                    .y_labels(n * 4)
                    .y_label_formatter(&|y| {
                        let k = y.floor();
                        let i = n.saturating_sub(1 + k as usize);
                        if (y - k - 0.5).abs() < 0.13 && k >= 0.0 && i < labels.len() {
                            labels[i].clone()
                        } else {
                            String::new()
                        }
                    })
                    .x_labels(6)
                    .x_label_formatter(&|v| tick(*v))
                    .x_desc(y_label.as_str())
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 16))
                    .draw()
                    .map_err(|x| e(&x))?;
                for (i, b) in bars.iter().enumerate().filter(|(_, b)| b.2 > 0.0) {
                    let k = (n - 1 - i) as f64;
                    let st = sampler_style(&b.1);
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(lo, k + 0.2), (b.2, k + 0.8)],
                            st.colour.mix(0.75).filled(),
                        )))
                        .map_err(|x| e(&x))?;
                    if let Some((l, h)) = b.3 {
                        let (l, h) = (l.max(lo), h.min(hi));
                        chart
                            .draw_series([
                                PathElement::new(
                                    vec![(l, k + 0.5), (h, k + 0.5)],
                                    BLACK.stroke_width(2),
                                ),
                                PathElement::new(
                                    vec![(l, k + 0.3), (l, k + 0.7)],
                                    BLACK.stroke_width(2),
                                ),
                                PathElement::new(
                                    vec![(h, k + 0.3), (h, k + 0.7)],
                                    BLACK.stroke_width(2),
                                ),
                            ])
                            .map_err(|x| e(&x))?;
                    }
                    let at = chart.backend_coord(&(b.2, k + 0.5));
                    draw_marker(&root, at, st.marker, st.colour).map_err(|x| e(&x))?;
                }
            }
        }
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
}

/// Draws one series on `chart`: its interval (a translucent band, or whiskers when
/// `whiskers`), its line (dashed for batch modes) and its markers (drawn on `root` in pixels).
/// The chart builder of a lines figure (either x axis): margins and label areas.
fn lines_chart<'a, 'b, DB: DrawingBackend>(
    plot: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(plot);
    builder
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70);
    builder
}

/// The mesh of a lines figure (either x axis): axis descriptions, tick labels, fonts.
fn lines_mesh<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x_label: &str,
    y_label: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
}

fn draw_series<DB: DrawingBackend, X, Y>(
    root: &DrawingArea<DB, Shift>,
    chart: &mut ChartContext<'_, DB, plotters::coord::cartesian::Cartesian2d<X, Y>>,
    s: &Series,
    y_floor: f64,
    whiskers: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
{
    let st = sampler_style(&s.label);
    let keep = |p: &(f64, f64)| p.1 > 0.0 && p.1.is_finite() && p.0.is_finite();
    let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
    let iv: Vec<((f64, f64), (f64, f64))> = s
        .points
        .iter()
        .zip(&s.intervals)
        .filter(|(p, _)| keep(p))
        .map(|(p, (lo, hi))| (*p, (lo.max(y_floor), hi.max(y_floor))))
        .collect();
    if whiskers {
        for ((x, _), (lo, hi)) in &iv {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(*x, *lo), (*x, *hi)],
                st.colour.mix(0.8).stroke_width(2),
            )))?;
        }
    } else if iv.len() >= 2 {
        let band: Vec<(f64, f64)> = iv
            .iter()
            .map(|(p, (_, hi))| (p.0, *hi))
            .chain(iv.iter().rev().map(|(p, (lo, _))| (p.0, *lo)))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(
            band,
            st.colour.mix(0.12).filled(),
        )))?;
    }
    let style = st.colour.stroke_width(2);
    if s.dashed {
        chart.draw_series(DashedLineSeries::new(pts.clone(), 8, 5, style))?;
    } else {
        chart.draw_series(LineSeries::new(pts.clone(), style))?;
    }
    for p in &pts {
        draw_marker(root, chart.backend_coord(p), st.marker, st.colour)?;
    }
    Ok(())
}

/// The legend, in its own panel beside the plot: a line sample (dashed for batch modes) with
/// the sampler's marker, and its label.
fn draw_legend<'a, DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: impl Iterator<Item = (&'a str, bool)>,
    note: Option<&str>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x0, y0) = area.get_base_pixel();
    let text = ("sans-serif", 14).into_font().color(&BLACK);
    let mut y = y0 + 24;
    for (label, dashed) in entries {
        let st = sampler_style(label);
        let seg = if dashed {
            vec![
                vec![(x0 + 4, y), (x0 + 14, y)],
                vec![(x0 + 20, y), (x0 + 30, y)],
            ]
        } else {
            vec![vec![(x0 + 4, y), (x0 + 30, y)]]
        };
        for s in seg {
            area.draw(&PathElement::new(
                s.into_iter()
                    .map(|(x, y)| (x - x0, y - y0))
                    .collect::<Vec<_>>(),
                st.colour.stroke_width(2),
            ))?;
        }
        draw_marker(area, (17, y - y0), st.marker, st.colour)?;
        area.draw(&Text::new(
            label.to_string(),
            (38, y - y0 - 8),
            text.clone(),
        ))?;
        y += 22;
    }
    if let Some(note) = note {
        area.draw(&Text::new(
            note.to_string(),
            (4, y - y0 + 4),
            ("sans-serif", 13).into_font().color(&RGBColor(90, 90, 90)),
        ))?;
    }
    Ok(())
}

/// A tick label: plain with at most 3 significant digits between 0.01 and 10⁵, else
/// scientific.
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (0.01..1e5).contains(&a) {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.1e}")
    }
}

fn plot_err(name: &str, reason: impl std::fmt::Display) -> StudyError {
    StudyError::Plot {
        name: name.to_string(),
        reason: reason.to_string(),
    }
}

/// The figures of one group: error vs N, error vs time per estimate (both with the 95 %
/// interval of the mean relative error as a band), and efficiency with its 95 % interval
/// (from `ranking`, whose verdict is appended to each label).
pub fn group_figures(g: &Group<'_>, ranking: Option<&Ranking>) -> Vec<(String, String, Figure)> {
    let title = format!(
        "{} · θo = {}° · {}",
        short_brdf(g.brdf),
        g.theta_o_deg,
        short_light(g.light)
    );
    let ok: Vec<_> = g.cells.iter().filter(|c| c.ok()).collect();
    let band = |c: &CellResult| -> Vec<(f64, f64)> {
        c.errors
            .iter()
            .map(|e| (e.mean_rel_err - e.ci95, e.mean_rel_err + e.ci95))
            .collect()
    };
    let err_n = ok
        .iter()
        .map(|c| Series {
            label: c.label(),
            points: c
                .errors
                .iter()
                .map(|e| (e.n as f64, e.mean_rel_err))
                .collect(),
            intervals: band(c),
            dashed: c.mode == Mode::Batch,
        })
        .collect();
    let err_t = ok
        .iter()
        .filter_map(|c| {
            let t = c.timing?;
            Some(Series {
                label: c.label(),
                points: c
                    .errors
                    .iter()
                    .map(|e| (e.n as f64 * t.estimator_ns * 1e-3, e.mean_rel_err))
                    .collect(),
                intervals: band(c),
                dashed: c.mode == Mode::Batch,
            })
        })
        .collect();
    let mut bars: Vec<Bar> = ok
        .iter()
        .filter_map(|c| {
            let eff = c.timing?.efficiency?;
            let entry = ranking.and_then(|r| r.entry(&c.label()));
            let interval = entry
                .and_then(|e| e.se_log_efficiency)
                .map(|se| (eff * (-1.96 * se).exp(), eff * (1.96 * se).exp()));
            let shown = match entry {
                Some(e) => format!(
                    "{} — {}{}",
                    c.label(),
                    e.verdict.as_str(),
                    if e.unreliable { " ⚠" } else { "" }
                ),
                None => c.label(),
            };
            Some((shown, c.label(), eff, interval))
        })
        .collect();
    bars.sort_by(|a, b| b.2.total_cmp(&a.2));
    vec![
        (
            format!("{}-error-vs-samples", g.slug),
            format!("Relative error vs samples — {}", g.title()),
            Figure::Lines {
                title: title.clone(),
                x_label: "samples N".into(),
                y_label: "mean relative error".into(),
                x_linear: false,
                series: err_n,
            },
        ),
        (
            format!("{}-error-vs-time", g.slug),
            format!(
                "Relative error vs time per estimate (timing) — {}",
                g.title()
            ),
            Figure::Lines {
                title: title.clone(),
                x_label: "time per estimate (µs, one thread)".into(),
                y_label: "mean relative error".into(),
                x_linear: false,
                series: err_t,
            },
        ),
        (
            format!("{}-efficiency", g.slug),
            format!(
                "Efficiency 1/(MSE × time) with its 95 % interval and verdict (timing) — {}",
                g.title()
            ),
            Figure::Bars {
                title,
                y_label: "efficiency 1/(MSE·s), whiskers: 95 % interval".into(),
                bars,
            },
        ),
    ]
}

/// The per-material summary figures: for each light and BRDF with rankings (estimator
/// `brdf`), the efficiency of the best over each sampler's (1 = best) against θo, with the
/// ranking's interval (Šidák level) as whiskers. Returns `(stem, caption, figure)`.
pub fn summary_figures(results: &StudyResults) -> Vec<(String, String, Figure)> {
    let cfg = &results.config;
    let mut out = Vec::new();
    for (li, light) in cfg.lights.iter().enumerate() {
        for (bi, brdf) in cfg.brdfs.iter().enumerate() {
            let rs: Vec<&Ranking> = results
                .rankings
                .iter()
                .filter(|r| &r.light == light && &r.brdf == brdf && r.estimator == ESTIMATOR_BRDF)
                .collect();
            if rs.is_empty() {
                continue;
            }
            // One series per sampler label, in first-seen order of the grid.
            let mut labels: Vec<String> = Vec::new();
            for c in results
                .cells
                .iter()
                .filter(|c| &c.light == light && &c.brdf == brdf && c.ok())
            {
                if !labels.contains(&c.label()) {
                    labels.push(c.label());
                }
            }
            let series: Vec<Series> = labels
                .iter()
                .filter_map(|label| {
                    let mut points = Vec::new();
                    let mut intervals = Vec::new();
                    for r in &rs {
                        if let Some(e) = r.entry(label)
                            && let (Some(x), Some(lo), Some(hi)) = (e.ratio, e.ratio_lo, e.ratio_hi)
                        {
                            points.push((r.theta_o, x));
                            intervals.push((lo, hi));
                        }
                    }
                    (!points.is_empty()).then(|| Series {
                        label: label.clone(),
                        points,
                        intervals,
                        dashed: label.ends_with(" (batch)"),
                    })
                })
                .collect();
            if series.is_empty() {
                continue;
            }
            let name = short_brdf(brdf);
            out.push((
                format!("summary-l{li}-b{bi}"),
                format!(
                    "{name} under {}: efficiency of the best sampler over each sampler's against θo (1 = best; whiskers: the ranking's Šidák interval)",
                    short_light(light)
                ),
                Figure::Lines {
                    title: format!("{name} · {} · best / this, by θo", short_light(light)),
                    x_label: "outgoing angle θo (degrees)".into(),
                    y_label: "efficiency of the best / this (1 = best)".into(),
                    x_linear: true,
                    series,
                },
            ));
        }
    }
    out
}

/// Every plot of a study, rendered (PNG and SVG): the per-material summaries (slug empty)
/// first, then each group's.
pub fn study_plots(results: &StudyResults) -> Result<Vec<PlotFile>, StudyError> {
    let mut out = Vec::new();
    for (stem, caption, fig) in summary_figures(results) {
        out.push(PlotFile {
            slug: String::new(),
            caption,
            png: fig.png(&stem)?,
            svg: fig.svg(&stem)?,
            stem,
        });
    }
    for g in groups(results) {
        let ranking = results.rankings.iter().find(|r| {
            r.brdf == g.brdf
                && r.theta_o == g.theta_o_deg
                && r.light == g.light
                && r.estimator == ESTIMATOR_BRDF
        });
        for (stem, caption, fig) in group_figures(&g, ranking) {
            out.push(PlotFile {
                slug: g.slug.clone(),
                caption,
                png: fig.png(&stem)?,
                svg: fig.svg(&stem)?,
                stem,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every preferred sampler has its own colour and its own (colour, marker) pair, the same
    /// for its batch mode and in every call; unknown samplers get a stable style too.
    #[test]
    fn each_sampler_has_its_own_stable_colour_and_marker() {
        let styles: Vec<SamplerStyle> = crate::PREFERRED_SAMPLERS
            .iter()
            .map(|n| sampler_style(n))
            .collect();
        for (i, a) in styles.iter().enumerate() {
            for (j, b) in styles.iter().enumerate().skip(i + 1) {
                let (p, q) = (crate::PREFERRED_SAMPLERS[i], crate::PREFERRED_SAMPLERS[j]);
                assert_ne!(a.colour, b.colour, "{p} and {q} share a colour");
                // Colours far enough apart to tell (sum of absolute RGB differences).
                let d = (a.colour.0 as i32 - b.colour.0 as i32).abs()
                    + (a.colour.1 as i32 - b.colour.1 as i32).abs()
                    + (a.colour.2 as i32 - b.colour.2 as i32).abs();
                assert!(d >= 60 || a.marker != b.marker, "{p} and {q} look alike");
            }
        }
        assert_eq!(
            sampler_style("adaptive-paper (batch)"),
            sampler_style("adaptive-paper")
        );
        assert_eq!(
            sampler_style("my-new-sampler"),
            sampler_style("my-new-sampler")
        );
    }

    #[test]
    fn figures_render_with_intervals_and_an_outside_legend() {
        let series = |label: &str, k: f64| Series {
            label: label.into(),
            points: vec![(1.0, k), (10.0, k / 3.0), (100.0, k / 10.0)],
            intervals: vec![(k * 0.8, k * 1.2), (k / 4.0, k / 2.0), (k / 12.0, k / 8.0)],
            dashed: label.ends_with("(batch)"),
        };
        let fig = Figure::Lines {
            title: "ggx · θo = 30° · sky".into(),
            x_label: "samples N".into(),
            y_label: "mean relative error".into(),
            x_linear: false,
            series: vec![
                series("uniform", 1.0),
                series("adaptive-paper (batch)", 0.5),
            ],
        };
        let png = fig.png("t").unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), PLOT_SIZE);
        // The legend panel (right of the plot area) holds the samplers' colours.
        let legend_has = |c: RGBColor| {
            (PLOT_SIZE.0 - LEGEND_WIDTH..PLOT_SIZE.0)
                .any(|x| (0..PLOT_SIZE.1).any(|y| img.get_pixel(x, y).0 == [c.0, c.1, c.2]))
        };
        assert!(legend_has(sampler_style("uniform").colour));
        assert!(legend_has(sampler_style("adaptive-paper").colour));
        assert!(fig.svg("t").unwrap().contains("adaptive-paper (batch)"));
        let bars = Figure::Bars {
            title: "t".into(),
            y_label: "efficiency".into(),
            bars: vec![
                (
                    "cosine — best".into(),
                    "cosine".into(),
                    10.0,
                    Some((8.0, 12.0)),
                ),
                ("uniform — worse".into(), "uniform".into(), 1.0, None),
            ],
        };
        assert!(!bars.png("b").unwrap().is_empty());
    }
}
