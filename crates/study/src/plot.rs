//! Plots of a study (plotters): log-log relative error against samples and against time per
//! estimate, and an efficiency bar chart; each as PNG (drawn into an RGB buffer, encoded by
//! `image`) and SVG. Text uses DejaVu Sans, shipped in `assets/` with its licence.

use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::groups::{Group, groups, short_light};
use crate::{Mode, StudyError, StudyResults};

/// Plot size in pixels.
pub const PLOT_SIZE: (u32, u32) = (800, 560);

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled in and valid; failing here would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Series colours (colour-blind-friendly Okabe–Ito palette, then greys).
const COLOURS: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
    RGBColor(120, 120, 120),
    RGBColor(170, 60, 60),
];

/// One line of a line plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// `(x, y)` points, both > 0 (log-log axes).
    pub points: Vec<(f64, f64)>,
    /// Dashed (e.g. batch mode).
    pub dashed: bool,
}

/// What a figure shows.
#[derive(Debug, Clone)]
pub enum Figure {
    /// Log-log lines.
    Lines {
        /// Title.
        title: String,
        /// x-axis label.
        x_label: String,
        /// y-axis label.
        y_label: String,
        /// The lines.
        series: Vec<Series>,
    },
    /// Bars on a logarithmic axis.
    Bars {
        /// Title.
        title: String,
        /// y-axis label.
        y_label: String,
        /// `(label, value > 0)`.
        bars: Vec<(String, f64)>,
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
                series,
            } => {
                let pts = series
                    .iter()
                    .flat_map(|s| s.points.iter())
                    .filter(|p| p.0 > 0.0 && p.1 > 0.0);
                let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                for p in pts {
                    x0 = x0.min(p.0);
                    x1 = x1.max(p.0);
                    y0 = y0.min(p.1);
                    y1 = y1.max(p.1);
                }
                if x0 > x1 {
                    (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
                }
                let mut chart = ChartBuilder::on(&root)
                    .caption(title, ("sans-serif", 20))
                    .margin(12)
                    .x_label_area_size(45)
                    .y_label_area_size(70)
                    .build_cartesian_2d(
                        (x0 / 1.5..x1 * 1.5).log_scale(),
                        (y0 / 1.5..y1 * 1.5).log_scale(),
                    )
                    .map_err(|x| e(&x))?;
                chart
                    .configure_mesh()
                    .x_desc(x_label.as_str())
                    .y_desc(y_label.as_str())
                    .x_label_formatter(&|v| tick(*v))
                    .y_label_formatter(&|v| tick(*v))
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 16))
                    .draw()
                    .map_err(|x| e(&x))?;
                for (i, s) in series.iter().enumerate() {
                    let colour = COLOURS[i % COLOURS.len()];
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                        .collect();
                    let style = colour.stroke_width(2);
                    let anno = if s.dashed {
                        chart
                            .draw_series(DashedLineSeries::new(pts.clone(), 8, 5, style))
                            .map_err(|x| e(&x))?
                    } else {
                        chart
                            .draw_series(LineSeries::new(pts.clone(), style))
                            .map_err(|x| e(&x))?
                    };
                    anno.label(s.label.as_str()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                    });
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                        .map_err(|x| e(&x))?;
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::LowerLeft)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .draw()
                    .map_err(|x| e(&x))?;
            }
            Figure::Bars {
                title,
                y_label,
                bars,
            } => {
                let vals: Vec<f64> = bars.iter().map(|b| b.1).filter(|v| *v > 0.0).collect();
                let (lo, hi) = vals
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
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
                    .y_label_area_size(190)
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
                chart
                    .draw_series(bars.iter().enumerate().filter(|(_, b)| b.1 > 0.0).map(
                        |(i, b)| {
                            let k = (n - 1 - i) as f64;
                            Rectangle::new(
                                [(lo, k + 0.15), (b.1, k + 0.85)],
                                COLOURS[i % COLOURS.len()].filled(),
                            )
                        },
                    ))
                    .map_err(|x| e(&x))?;
            }
        }
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
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

/// The figures of one group: error vs N, error vs time per estimate, efficiency.
pub fn group_figures(g: &Group<'_>) -> Vec<(String, String, Figure)> {
    let title = format!("{} θo={}° {}", g.brdf, g.theta_o_deg, short_light(g.light));
    let ok: Vec<_> = g.cells.iter().filter(|c| c.ok()).collect();
    let err_n = ok
        .iter()
        .map(|c| Series {
            label: c.label(),
            points: c
                .errors
                .iter()
                .map(|e| (e.n as f64, e.mean_rel_err))
                .collect(),
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
                dashed: c.mode == Mode::Batch,
            })
        })
        .collect();
    let bars = ok
        .iter()
        .filter_map(|c| Some((c.label(), c.timing?.efficiency?)))
        .collect();
    vec![
        (
            format!("{}-error-vs-samples", g.slug),
            format!("Relative error vs samples — {}", g.title()),
            Figure::Lines {
                title: title.clone(),
                x_label: "samples N".into(),
                y_label: "mean relative error".into(),
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
                series: err_t,
            },
        ),
        (
            format!("{}-efficiency", g.slug),
            format!("Efficiency 1/(MSE × time) (timing) — {}", g.title()),
            Figure::Bars {
                title,
                y_label: "efficiency (1/(MSE·s))".into(),
                bars,
            },
        ),
    ]
}

/// Every plot of a study, rendered (PNG and SVG).
pub fn study_plots(results: &StudyResults) -> Result<Vec<PlotFile>, StudyError> {
    let mut out = Vec::new();
    for g in groups(results) {
        for (stem, caption, fig) in group_figures(&g) {
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
