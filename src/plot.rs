//! Plotting: owns every figure the rig draws (closed-loop states, sliding surfaces, RBF weights, run overlays, fault
//! timelines, latency percentile distributions), each written as PNG and SVG.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`data/fonts/`, Bitstream Vera licence), so plotting needs
//! no system font libraries. Every figure is first described as plain data (a figure: a grid of panels, each with
//! its series), then laid out once and drawn twice, by the same code, on the bitmap and the SVG backend.
//!
//! Data rules shared by all figures: NaN and infinite samples are skipped (the line breaks there); y ranges are the
//! data range padded by 5 %, and a constant or all-zero series gets a small symmetric range around its value.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

use crate::trace::{CHANNELS, Trace};

/// A figure that could not be drawn. Each variant names the file it was drawing (or the directory it wanted).
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A column the figure needs is not in the trace.
    #[error("cannot draw {file}: {trace} has no column `{column}`")]
    MissingColumn {
        /// The figure's first output file.
        file: PathBuf,
        /// Which trace: "the trace", or "run `name`" in an overlay.
        trace: String,
        /// The missing column.
        column: String,
    },
    /// There is nothing to draw (no rows, no runs, no series).
    #[error("cannot draw {file}: {problem}")]
    NoData {
        /// The figure's first output file.
        file: PathBuf,
        /// What is missing.
        problem: String,
    },
    /// The output directory cannot be created.
    #[error("cannot create the output directory {dir}: {source}")]
    CreateDir {
        /// The directory.
        dir: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Writing a file failed.
    #[error("cannot write {file}: {source}")]
    Write {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The plotting backend failed (drawing or PNG encoding).
    #[error("cannot draw {file}: {message}")]
    Draw {
        /// The file.
        file: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// The embedded font is not a font (a build problem, not a data problem).
    #[error("cannot draw {file}: the embedded font data/fonts/DejaVuSans.ttf does not load")]
    Font {
        /// The file.
        file: PathBuf,
    },
}

/// A marked instant on a timeline (an injected fault, a mode change).
#[derive(Debug, Clone)]
pub struct TimelineEvent {
    /// When, in the trace's time `t_s` (seconds).
    pub t_s: f64,
    /// The text written at the top of the figure next to the marker.
    pub label: String,
}

// ---------------------------------------------------------------------------------------------------------------
// Public figures
// ---------------------------------------------------------------------------------------------------------------

/// Draw the closed-loop figures of `trace` into `out_dir` (created if missing), each as PNG and SVG:
/// `fig1_states` (alpha; Euler angles; body rates; surfaces and their commands), `fig2_sliding` (sliding surfaces and
/// RBF estimates, 3x2) and `fig3_weights` (the RBF weights `w_<channel>_<k>` of each channel). `title` goes on top
/// of every figure. Every column is checked before any file is written. Returns the files written, PNG before SVG,
/// figure by figure.
pub fn plot_closed_loop(trace: &Trace, out_dir: &Path, title: &str) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join("fig1_states.png");
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let panel = |caption: &str, y_desc: &str, specs: &[(&str, &str)]| -> Result<Panel, PlotError> {
        let mut series = Vec::new();
        for (k, (column, label)) in specs.iter().enumerate() {
            series.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
        }
        Ok(Panel::new(caption, y_desc, series))
    };
    let mut surfaces = Vec::new();
    for (k, name) in ["aileron", "elevator", "rudder"].into_iter().enumerate() {
        let actual = data.get(&format!("{name}_deg"))?;
        let command = data.get(&format!("{name}_cmd_deg"))?;
        surfaces.push(Series::solid(name, zip(&t, &actual), palette(k)));
        surfaces.push(Series::command(&format!("{name} cmd"), zip(&t, &command), palette(k)));
    }
    let fig1 = Figure::stacked(
        title,
        (1200, 900),
        vec![
            panel("(a) angle of attack", "deg", &[("alpha_deg", "α")])?,
            panel("(b) Euler angles", "deg", &[("phi_deg", "φ roll"), ("theta_deg", "θ pitch"), ("psi_deg", "ψ yaw")])?,
            panel("(c) body rates", "deg/s", &[("p_dps", "p roll"), ("q_dps", "q pitch"), ("r_dps", "r yaw")])?,
            Panel::new("(d) control surfaces: actual (solid) and command (dashed)", "deg", surfaces),
        ],
    );

    let file = out_dir.join("fig2_sliding.png");
    let data = Columns::new(trace, &file, "the trace")?;
    let mut cells = Vec::new();
    for (k, ch) in CHANNELS.iter().enumerate() {
        let greek = greek(ch);
        let s_col = format!("s_{ch}");
        let f_col = format!("fhat_{ch}");
        let s = Series::solid(&s_col, zip(&t, &data.get(&s_col)?), palette(k));
        let f = Series::solid(&f_col, zip(&t, &data.get(&f_col)?), palette(k));
        let mut left = Panel::new(&format!("sliding surface, {greek} channel"), &s_col, vec![s]);
        let mut right = Panel::new(&format!("RBF estimate, {greek} channel"), &f_col, vec![f]);
        left.legend = false;
        right.legend = false;
        cells.push(Some(left));
        cells.push(Some(right));
    }
    let fig2 = Figure::grid(title, (1200, 850), 3, 2, cells, FigureLegend::None);

    let file = out_dir.join("fig3_weights.png");
    let data = Columns::new(trace, &file, "the trace")?;
    // One colour per node number, the same in every channel and in the shared legend.
    let mut all_nodes: Vec<usize> = CHANNELS.iter().flat_map(|ch| weight_nodes(trace, ch)).collect();
    all_nodes.sort_unstable();
    all_nodes.dedup();
    let colour_of = |k: usize| all_nodes.iter().position(|&n| n == k).unwrap_or(0);
    let mut panels = Vec::new();
    for ch in CHANNELS {
        let nodes = weight_nodes(trace, ch);
        if nodes.is_empty() {
            return Err(PlotError::MissingColumn { file, trace: "the trace".into(), column: format!("w_{ch}_1") });
        }
        let mut series = Vec::new();
        for &k in &nodes {
            series.push(Series::cycled(&format!("W{k}"), zip(&t, &data.get(&format!("w_{ch}_{k}"))?), colour_of(k)));
        }
        let mut panel = Panel::new(&format!("RBF weights, {} channel", greek(ch)), "weight", series);
        panel.legend = false;
        panels.push(panel);
    }
    let entries = all_nodes.iter().enumerate().map(|(i, k)| LegendEntry::cycled(&format!("W{k}"), i)).collect();
    let mut fig3 = Figure::stacked(title, (1200, 900), panels);
    fig3.legend = FigureLegend::Top(entries);

    let mut written = write_figure(&fig1, out_dir, "fig1_states")?;
    written.extend(write_figure(&fig2, out_dir, "fig2_sliding")?);
    written.extend(write_figure(&fig3, out_dir, "fig3_weights")?);
    Ok(written)
}

/// Draw one figure `<stem>.{png,svg}` in `out_dir` comparing several runs (name, trace): panels for theta, phi,
/// psi, alpha, elevator, aileron and rudder (deg) against `t_s`, in a 4x2 grid, one colour per run, the legend of run
/// names in the eighth cell. Returns the files written.
pub fn plot_overlay(runs: &[(String, Trace)], out_dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if runs.is_empty() {
        return Err(PlotError::NoData { file, problem: "no runs to compare".into() });
    }
    let specs = [
        ("theta_deg", "pitch angle θ"),
        ("phi_deg", "roll angle φ"),
        ("psi_deg", "yaw angle ψ"),
        ("alpha_deg", "angle of attack α"),
        ("elevator_deg", "elevator"),
        ("aileron_deg", "aileron"),
        ("rudder_deg", "rudder"),
    ];
    let mut panels: Vec<Panel> = specs
        .iter()
        .map(|(_, caption)| {
            let mut panel = Panel::new(caption, "deg", Vec::new());
            panel.legend = false; // one legend for all panels, in the empty cell
            panel
        })
        .collect();
    for (r, (name, trace)) in runs.iter().enumerate() {
        let data = Columns::new(trace, &file, &format!("run `{name}`"))?;
        let t = data.get("t_s")?;
        for (panel, (column, _)) in panels.iter_mut().zip(specs) {
            panel.series.push(Series::cycled(name, zip(&t, &data.get(column)?), r));
        }
    }
    let entries = runs.iter().enumerate().map(|(r, (name, _))| LegendEntry::cycled(name, r)).collect();
    let mut cells: Vec<Option<Panel>> = panels.into_iter().map(Some).collect();
    cells.push(None);
    let fig = Figure::grid(stem, (1400, 1050), 4, 2, cells, FigureLegend::Cell(7, entries));
    write_figure(&fig, out_dir, stem)
}

/// Draw latency percentile distributions, as HdrHistogram's plotter does, into `<stem>.{png,svg}` in `out_dir`.
/// Each series is (name, points) with points (percentile in 0..100, latency in µs). The x axis is the "number of
/// nines", log10(1 / (1 - p/100)), labelled 0%, 90%, 99%, 99.9%, 99.99% (and further if the data go further); the
/// y axis is linear from 0. Points at or above the 100th percentile, below the 0th, or not finite are skipped.
pub fn plot_percentile_distributions(
    series: &[(String, Vec<(f64, f64)>)],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    if series.is_empty() {
        return Err(PlotError::NoData { file, problem: "no latency series".into() });
    }
    let lines = series
        .iter()
        .enumerate()
        .map(|(k, (name, points))| {
            let pts = points
                .iter()
                .filter(|(p, v)| (0.0..100.0).contains(p) && v.is_finite())
                .map(|&(p, v)| (nines(p), v))
                .collect();
            Series::cycled(name, pts, k)
        })
        .collect();
    let mut panel = Panel::new("", "latency (µs)", lines);
    panel.x_scale = XScale::Nines;
    panel.x_desc = "percentile".into();
    panel.y_from_zero = true;
    let fig = Figure::stacked(title, (1200, 700), vec![panel]);
    write_figure(&fig, out_dir, stem)
}

/// Draw `<stem>.{png,svg}` in `out_dir`: Euler angles above, actual surface deflections below, against `t_s`, with a
/// dashed vertical line at every event (both panels) and its label above the upper panel. Events outside the trace's
/// time span are left out. Returns the files written.
pub fn plot_timeline(
    trace: &Trace,
    events: &[TimelineEvent],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let mut euler = Vec::new();
    for (k, (column, label)) in
        [("phi_deg", "φ roll"), ("theta_deg", "θ pitch"), ("psi_deg", "ψ yaw")].iter().enumerate()
    {
        euler.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
    }
    let mut surfaces = Vec::new();
    for (k, (column, label)) in
        [("aileron_deg", "aileron"), ("elevator_deg", "elevator"), ("rudder_deg", "rudder")].iter().enumerate()
    {
        surfaces.push(Series::solid(label, zip(&t, &data.get(column)?), palette(k)));
    }
    let events: Vec<(f64, String)> =
        events.iter().filter(|e| e.t_s.is_finite()).map(|e| (e.t_s, e.label.clone())).collect();
    let mut upper = Panel::new("Euler angles", "deg", euler);
    upper.events = events.clone();
    upper.event_labels = true;
    let mut lower = Panel::new("control surfaces", "deg", surfaces);
    lower.events = events;
    let fig = Figure::stacked(title, (1200, 800), vec![upper, lower]);
    write_figure(&fig, out_dir, stem)
}

// ---------------------------------------------------------------------------------------------------------------
// Data: columns, series, panels, figures
// ---------------------------------------------------------------------------------------------------------------

/// Column access that turns a missing column into an error naming it.
struct Columns<'a> {
    trace: &'a Trace,
    file: PathBuf,
    who: String,
}

impl<'a> Columns<'a> {
    fn new(trace: &'a Trace, file: &Path, who: &str) -> Result<Self, PlotError> {
        if trace.rows.is_empty() {
            return Err(PlotError::NoData { file: file.to_path_buf(), problem: format!("{who} has no rows") });
        }
        Ok(Self { trace, file: file.to_path_buf(), who: who.to_string() })
    }

    fn get(&self, column: &str) -> Result<Vec<f64>, PlotError> {
        self.trace.column(column).ok_or_else(|| PlotError::MissingColumn {
            file: self.file.clone(),
            trace: self.who.clone(),
            column: column.to_string(),
        })
    }
}

/// Node numbers k of the columns `w_<ch>_<k>`, ascending.
fn weight_nodes(trace: &Trace, ch: &str) -> Vec<usize> {
    let prefix = format!("w_{ch}_");
    let mut nodes: Vec<usize> =
        trace.columns.iter().filter_map(|c| c.strip_prefix(&prefix).and_then(|k| k.parse().ok())).collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

fn greek(ch: &str) -> &'static str {
    match ch {
        "phi" => "φ",
        "theta" => "θ",
        "psi" => "ψ",
        _ => "?",
    }
}

fn zip(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter().copied().zip(y.iter().copied()).collect()
}

/// The "number of nines" of a percentile: 90% -> 1, 99% -> 2, 99.9% -> 3.
fn nines(percentile: f64) -> f64 {
    (1.0 / (1.0 - percentile / 100.0)).log10()
}

/// Colours of matplotlib's "tab10" cycle: distinct, print and colour-blind friendly enough.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn palette(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// How a line is stroked.
#[derive(Clone, Copy, PartialEq)]
enum Dash {
    Solid,
    Dashed,
}

/// A line's look, shared by the series and its legend entry.
#[derive(Clone, Copy)]
struct Stroke {
    color: RGBColor,
    width: u32,
    dash: Dash,
}

impl Stroke {
    /// The k-th of many lines: the palette, then the palette dashed, and so on.
    fn cycled(k: usize) -> Self {
        let dash = if (k / PALETTE.len()).is_multiple_of(2) { Dash::Solid } else { Dash::Dashed };
        Self { color: palette(k), width: 2, dash }
    }

    fn style(&self) -> ShapeStyle {
        let width = self.width;
        match self.dash {
            Dash::Solid => self.color.stroke_width(width),
            // A dashed line drawn over a solid one of the same colour stays visible if it is lighter.
            Dash::Dashed => self.color.mix(0.9).stroke_width(width),
        }
    }
}

struct Series {
    label: String,
    points: Vec<(f64, f64)>,
    stroke: Stroke,
}

impl Series {
    fn solid(label: &str, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.to_string(), points, stroke: Stroke { color, width: 2, dash: Dash::Solid } }
    }

    fn command(label: &str, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.to_string(), points, stroke: Stroke { color, width: 1, dash: Dash::Dashed } }
    }

    fn cycled(label: &str, points: Vec<(f64, f64)>, k: usize) -> Self {
        Self { label: label.to_string(), points, stroke: Stroke::cycled(k) }
    }

    /// Runs of consecutive finite points.
    fn segments(&self) -> impl Iterator<Item = &[(f64, f64)]> {
        self.points.split(|(x, y)| !(x.is_finite() && y.is_finite())).filter(|s| !s.is_empty())
    }
}

struct LegendEntry {
    label: String,
    stroke: Stroke,
}

impl LegendEntry {
    fn cycled(label: &str, k: usize) -> Self {
        Self { label: label.to_string(), stroke: Stroke::cycled(k) }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum XScale {
    /// Time in seconds.
    Linear,
    /// Percentiles on the number-of-nines scale.
    Nines,
}

struct Panel {
    caption: String,
    y_desc: String,
    x_desc: String,
    x_scale: XScale,
    series: Vec<Series>,
    /// Draw a legend of the series to the right of the plot.
    legend: bool,
    /// Start the y axis at zero (if no value is negative).
    y_from_zero: bool,
    /// Vertical markers (time, label).
    events: Vec<(f64, String)>,
    /// Write the markers' labels above this panel.
    event_labels: bool,
}

impl Panel {
    fn new(caption: &str, y_desc: &str, series: Vec<Series>) -> Self {
        Self {
            caption: caption.to_string(),
            y_desc: y_desc.to_string(),
            x_desc: "t (s)".into(),
            x_scale: XScale::Linear,
            series,
            legend: true,
            y_from_zero: false,
            events: Vec::new(),
            event_labels: false,
        }
    }

    fn legend_entries(&self) -> Vec<LegendEntry> {
        if !self.legend {
            return Vec::new();
        }
        self.series.iter().map(|s| LegendEntry { label: s.label.clone(), stroke: s.stroke }).collect()
    }

    fn finite(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.series.iter().flat_map(|s| s.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    fn x_range(&self) -> (f64, f64) {
        let (lo, hi) = min_max(self.finite().map(|p| p.0));
        match self.x_scale {
            XScale::Linear => match (lo, hi) {
                (Some(lo), Some(hi)) if hi - lo > 1e-9 * lo.abs().max(hi.abs()) => (lo, hi),
                (Some(lo), Some(hi)) => symmetric(0.5 * (lo + hi)),
                _ => (0.0, 1.0),
            },
            XScale::Nines => (0.0, hi.map_or(4.0, |hi| hi.ceil().max(4.0))),
        }
    }

    fn y_range(&self) -> (f64, f64) {
        let (lo, hi) = min_max(self.finite().map(|p| p.1));
        let (Some(lo), Some(hi)) = (lo, hi) else { return (-1.0, 1.0) };
        if self.y_from_zero && lo >= 0.0 && hi > 0.0 {
            return (0.0, hi * 1.05);
        }
        padded(lo, hi)
    }
}

fn min_max(values: impl Iterator<Item = f64>) -> (Option<f64>, Option<f64>) {
    values.fold((None, None), |(lo, hi), v| {
        (Some(lo.map_or(v, |l: f64| l.min(v))), Some(hi.map_or(v, |h: f64| h.max(v))))
    })
}

/// A small symmetric range around a constant: ±1 around zero, ±10 % around anything else.
fn symmetric(v: f64) -> (f64, f64) {
    let half = if v == 0.0 { 1.0 } else { 0.1 * v.abs() };
    (v - half, v + half)
}

/// The data range padded by 5 % each side; a (numerically) constant range gets [`symmetric`].
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let scale = lo.abs().max(hi.abs());
    if hi - lo <= 1e-9 * scale || hi - lo < 1e-300 {
        return symmetric(0.5 * (lo + hi));
    }
    let pad = 0.05 * hi - 0.05 * lo;
    ((lo - pad).max(-f64::MAX), (hi + pad).min(f64::MAX))
}

/// Where the legend of the whole figure goes.
enum FigureLegend {
    None,
    /// A strip under the title, entries left to right.
    Top(Vec<LegendEntry>),
    /// An empty grid cell (row-major index).
    Cell(usize, Vec<LegendEntry>),
}

struct Figure {
    title: String,
    size: (u32, u32),
    rows: usize,
    cols: usize,
    /// Row-major; `None` leaves the cell empty.
    cells: Vec<Option<Panel>>,
    legend: FigureLegend,
    /// Panels in one column share the time axis: tick labels and the axis name only on the lowest.
    shared_x: bool,
}

impl Figure {
    fn stacked(title: &str, size: (u32, u32), panels: Vec<Panel>) -> Self {
        let rows = panels.len();
        Self {
            title: title.to_string(),
            size,
            rows,
            cols: 1,
            cells: panels.into_iter().map(Some).collect(),
            legend: FigureLegend::None,
            shared_x: true,
        }
    }

    fn grid(
        title: &str,
        size: (u32, u32),
        rows: usize,
        cols: usize,
        cells: Vec<Option<Panel>>,
        legend: FigureLegend,
    ) -> Self {
        Self { title: title.to_string(), size, rows, cols, cells, legend, shared_x: false }
    }

    fn cell(&self, r: usize, c: usize) -> Option<&Panel> {
        self.cells.get(r * self.cols + c).and_then(Option::as_ref)
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Axes: our own tick positions and labels
// ---------------------------------------------------------------------------------------------------------------

/// A linear axis with precomputed ticks and their labels (plotters' own key points are not tunable enough).
#[derive(Clone)]
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
    labels: Vec<String>,
}

impl Axis {
    /// "Nice" ticks (1, 2 or 5 times a power of ten), about `target` of them.
    fn linear(lo: f64, hi: f64, target: usize) -> Self {
        let raw = (hi - lo) / target.max(1) as f64;
        let magnitude = 10f64.powf(raw.log10().floor());
        let norm = raw / magnitude;
        let mantissa = if norm < 1.5 {
            1.0
        } else if norm < 3.0 {
            2.0
        } else if norm < 7.5 {
            5.0
        } else {
            10.0
        };
        let step = mantissa * magnitude;
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        if !(step.is_finite() && step > 0.0) || last.saturating_sub(first) > 100 {
            // Spans no f64 arithmetic handles (near f64::MAX): just the ends.
            return Self { lo, hi, ticks: vec![lo, hi], labels: vec![format!("{lo:.3e}"), format!("{hi:.3e}")] };
        }
        let ticks: Vec<f64> = (first..=last).map(|n| n as f64 * step).collect();
        let biggest = lo.abs().max(hi.abs());
        let labels = if step < 1e-3 || biggest >= 1e6 {
            let digits = (biggest.log10().floor() - step.log10().floor()).max(0.0) as usize;
            ticks
                .iter()
                .map(|&v| if v.abs() < step * 1e-6 { "0".to_string() } else { format!("{v:.digits$e}") })
                .collect()
        } else {
            let decimals = (-step.log10().floor()).max(0.0) as usize;
            ticks.iter().map(|&v| format!("{:.decimals$}", if v.abs() < step * 1e-6 { 0.0 } else { v })).collect()
        };
        Self { lo, hi, ticks, labels }
    }

    /// Percentile ticks at whole numbers of nines: 0%, 90%, 99%, 99.9%, ...
    fn nines(hi: f64) -> Self {
        let ticks: Vec<f64> = (0..=hi as i64).map(|n| n as f64).collect();
        let labels = ticks
            .iter()
            .map(|&n| match n as i64 {
                0 => "0%".to_string(),
                n => format!("{:.*}%", (n - 2).max(0) as usize, 100.0 - 10f64.powi(2 - n as i32)),
            })
            .collect();
        Self { lo: 0.0, hi, ticks, labels }
    }

    fn label(&self, v: f64) -> String {
        let tol = 1e-9 * (self.hi / 2.0 - self.lo / 2.0).abs();
        self.ticks.iter().position(|t| (t - v).abs() <= tol).map_or_else(String::new, |i| self.labels[i].clone())
    }
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let span = self.hi - self.lo;
        let actual = limit.1 - limit.0;
        if span == 0.0 || actual == 0 {
            return limit.0;
        }
        // Halves keep spans near f64::MAX finite.
        let logic = ((*v / 2.0 - self.lo / 2.0) / (self.hi / 2.0 - self.lo / 2.0)).clamp(-10.0, 11.0);
        if actual > 0 {
            limit.0 + (actual as f64 * logic + 1e-3).floor() as i32
        } else {
            limit.0 + (actual as f64 * logic - 1e-3).ceil() as i32
        }
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // Bold points are the ticks; no light (minor) grid.
        if hint.weight().allow_light_points() { Vec::new() } else { self.ticks.clone() }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Layout
// ---------------------------------------------------------------------------------------------------------------

const TITLE_SIZE: f64 = 30.0;
const CAPTION_SIZE: f64 = 21.0;
const TICK_SIZE: f64 = 18.0;
const DESC_SIZE: f64 = 19.0;
const LEGEND_SIZE: f64 = 18.0;
const EVENT_SIZE: f64 = 17.0;
/// Height of one legend line.
const LEGEND_ROW: u32 = 21;
/// Length of the line sample in a legend entry.
const LEGEND_SAMPLE: u32 = 30;
/// Height of one row of event labels.
const EVENT_ROW: u32 = 20;
/// Space around panels and between their parts.
const PAD: u32 = 8;
const TICK_MARK: u32 = 5;
/// Event markers and their labels.
const EVENT_COLOR: RGBColor = RGBColor(190, 30, 30);

fn font(size: f64) -> FontDesc<'static> {
    FontDesc::new(FontFamily::SansSerif, size, FontStyle::Normal)
}

fn text_size(text: &str, size: f64) -> (u32, u32) {
    // The font is registered before any layout runs; the fallback only keeps layout total.
    font(size).box_size(text).unwrap_or(((text.chars().count() as f64 * size * 0.5) as u32, size as u32))
}

/// A legend as a grid of entries, filled row by row.
#[derive(Clone, Copy, Default)]
struct LegendGrid {
    cols: usize,
    rows: usize,
    col_w: u32,
}

impl LegendGrid {
    fn col_width(entries: &[LegendEntry]) -> u32 {
        let widest = entries.iter().map(|e| text_size(&e.label, LEGEND_SIZE).0).max().unwrap_or(0);
        LEGEND_SAMPLE + 6 + widest + 16
    }

    /// As few columns as fit `height`.
    fn fitting_height(entries: &[LegendEntry], height: u32) -> Self {
        if entries.is_empty() {
            return Self::default();
        }
        let per_col = ((height / LEGEND_ROW) as usize).max(1);
        let cols = entries.len().div_ceil(per_col);
        Self { cols, rows: entries.len().div_ceil(cols), col_w: Self::col_width(entries) }
    }

    /// As many columns as fit `width`.
    fn fitting_width(entries: &[LegendEntry], width: u32) -> Self {
        if entries.is_empty() {
            return Self::default();
        }
        let col_w = Self::col_width(entries);
        let cols = ((width / col_w) as usize).clamp(1, entries.len());
        Self { cols, rows: entries.len().div_ceil(cols), col_w }
    }

    fn width(&self) -> u32 {
        self.cols as u32 * self.col_w
    }

    fn height(&self) -> u32 {
        self.rows as u32 * LEGEND_ROW
    }
}

/// Pixel sizes of every part of a figure, computed once and used by both backends.
struct Layout {
    title_h: u32,
    top_legend: LegendGrid,
    top_legend_h: u32,
    /// Per row: band above the plot (caption, event labels), x label area under it.
    row_top: Vec<u32>,
    row_bottom: Vec<u32>,
    row_plot_h: u32,
    /// Per column: y label area, legend width.
    col_left: Vec<u32>,
    col_legend: Vec<LegendGrid>,
    /// Per cell (row-major): axes.
    axes: Vec<Option<(Axis, Axis)>>,
}

fn show_x_ticks(fig: &Figure, r: usize, c: usize) -> bool {
    !fig.shared_x || (r + 1..fig.rows).all(|below| fig.cell(below, c).is_none())
}

fn show_x_desc(fig: &Figure, r: usize, c: usize) -> bool {
    if fig.shared_x {
        return show_x_ticks(fig, r, c);
    }
    // In a grid: only on the lowest row that has panels.
    let last = (0..fig.rows).rev().find(|&row| (0..fig.cols).any(|col| fig.cell(row, col).is_some()));
    Some(r) == last || (r + 1..fig.rows).all(|below| fig.cell(below, c).is_none())
}

/// Where an event label goes above the plot: a flag on its marker line, starting at the line, or ending there
/// (`flip`) where it would run past the right edge.
#[derive(Clone, Copy, Default)]
struct EventLabel {
    row: usize,
    flip: bool,
}

/// Gap between a marker line and its label.
const FLAG_GAP: u32 = 4;

/// Place event labels in rows above a plot `plot_w` pixels wide. Labels are placed from the latest event back, each
/// on the lowest row where it clears the labels already there; as those start further right, the line that joins a
/// higher label to the plot never crosses a lower label.
fn place_event_labels(events: &[(f64, String)], x: &Axis, plot_w: u32) -> Vec<EventLabel> {
    let mut order: Vec<usize> = (0..events.len()).collect();
    order.sort_by(|&a, &b| events[b].0.total_cmp(&events[a].0));
    let mut row_left: Vec<f64> = Vec::new(); // leftmost label edge on each row
    let mut placed = vec![EventLabel::default(); events.len()];
    for i in order {
        let (t, label) = &events[i];
        let px = x.map(t, (0, plot_w as i32)) as f64;
        let w = (text_size(label, EVENT_SIZE).0 + FLAG_GAP) as f64;
        let flip = px + w > plot_w as f64 && px - w >= 0.0;
        let (left, right) = if flip { (px - w, px) } else { (px, px + w) };
        let row = row_left.iter().position(|&edge| right + 8.0 <= edge).unwrap_or(row_left.len());
        if row == row_left.len() {
            row_left.push(f64::INFINITY);
        }
        row_left[row] = row_left[row].min(left);
        placed[i] = EventLabel { row, flip };
    }
    placed
}

fn in_range(events: &[(f64, String)], x: &Axis) -> Vec<(f64, String)> {
    events.iter().filter(|(t, _)| *t >= x.lo && *t <= x.hi).cloned().collect()
}

fn layout(fig: &Figure) -> Layout {
    let (w, h) = fig.size;
    let title_h = text_size(&fig.title, TITLE_SIZE).1 + 2 * PAD;
    let (top_legend, top_legend_h) = match &fig.legend {
        FigureLegend::Top(entries) => {
            let grid = LegendGrid::fitting_width(entries, w - 4 * PAD);
            (grid, grid.height() + PAD)
        }
        _ => (LegendGrid::default(), 0),
    };
    let body_h = h.saturating_sub(title_h + top_legend_h);
    let cell_w = w / fig.cols as u32;

    let tick_h = text_size("0123456789", TICK_SIZE).1;
    let desc_h = text_size("t (s)", DESC_SIZE).1;
    let caption_h = text_size("(a) Ag", CAPTION_SIZE).1;

    // Rows for event labels are reserved for a plot narrower than the real one (its width depends on the y labels,
    // which depend on the plot height), so the labels, placed again at drawing time, need at most as many.
    let x_ranges: Vec<Option<(f64, f64)>> = fig.cells.iter().map(|p| p.as_ref().map(Panel::x_range)).collect();
    let guess_w = cell_w.saturating_sub(300).max(100);
    let mut row_top = vec![PAD; fig.rows];
    let mut row_bottom = vec![PAD; fig.rows];
    for r in 0..fig.rows {
        for c in 0..fig.cols {
            let Some(panel) = fig.cell(r, c) else { continue };
            let i = r * fig.cols + c;
            let mut top = PAD;
            if !panel.caption.is_empty() {
                top += caption_h + PAD;
            }
            if r > 0 {
                top += PAD;
            }
            if panel.event_labels {
                let (lo, hi) = x_ranges[i].unwrap_or((0.0, 1.0));
                let x = Axis::linear(lo, hi, 5);
                let placed = place_event_labels(&in_range(&panel.events, &x), &x, guess_w);
                top += placed.iter().map(|p| p.row).max().map_or(0, |m| (m as u32 + 1) * EVENT_ROW + PAD / 2);
            }
            row_top[r] = row_top[r].max(top);
            let mut bottom = TICK_MARK + 2;
            if show_x_ticks(fig, r, c) {
                bottom += tick_h + PAD;
            }
            if show_x_desc(fig, r, c) {
                bottom += desc_h + PAD;
            }
            row_bottom[r] = row_bottom[r].max(bottom);
        }
    }
    let fixed: u32 = row_top.iter().sum::<u32>() + row_bottom.iter().sum::<u32>();
    let row_plot_h = (body_h.saturating_sub(fixed) / fig.rows as u32).max(40);

    let y_target = ((row_plot_h / 55) as usize).clamp(3, 8);
    let mut y_axes: Vec<Option<Axis>> = fig
        .cells
        .iter()
        .map(|p| {
            p.as_ref().map(|p| {
                let (lo, hi) = p.y_range();
                Axis::linear(lo, hi, y_target)
            })
        })
        .collect();
    let mut col_left = vec![0; fig.cols];
    let mut col_legend = vec![LegendGrid::default(); fig.cols];
    for c in 0..fig.cols {
        for r in 0..fig.rows {
            let i = r * fig.cols + c;
            let Some(panel) = fig.cell(r, c) else { continue };
            let y = y_axes[i].as_ref().expect("axis of a panel");
            let widest = y.labels.iter().map(|l| text_size(l, TICK_SIZE).0).max().unwrap_or(0);
            let desc = if panel.y_desc.is_empty() { 0 } else { desc_h + PAD };
            col_left[c] = col_left[c].max(widest + TICK_MARK + PAD + desc + PAD);
            let grid = LegendGrid::fitting_height(&panel.legend_entries(), row_plot_h);
            if grid.width() > col_legend[c].width() {
                col_legend[c] = grid;
            }
        }
    }
    let mut axes = Vec::with_capacity(fig.cells.len());
    for (i, cell) in fig.cells.iter().enumerate() {
        let c = i % fig.cols;
        let Some(panel) = cell else {
            axes.push(None);
            continue;
        };
        let legend_w = col_legend[c].width();
        let plot_w = cell_w.saturating_sub(col_left[c] + legend_w + 3 * PAD).max(40);
        let (lo, hi) = x_ranges[i].expect("range of a panel");
        let x = match panel.x_scale {
            XScale::Linear => Axis::linear(lo, hi, ((plot_w / 110) as usize).clamp(3, 12)),
            XScale::Nines => Axis::nines(hi),
        };
        axes.push(Some((x, y_axes[i].take().expect("axis of a panel"))));
    }
    Layout { title_h, top_legend, top_legend_h, row_top, row_bottom, row_plot_h, col_left, col_legend, axes }
}

// ---------------------------------------------------------------------------------------------------------------
// Drawing (backend-generic)
// ---------------------------------------------------------------------------------------------------------------

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure, lay: &Layout) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let title_style = font(TITLE_SIZE).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
    root.draw_text(&fig.title, &title_style, (w as i32 / 2, PAD as i32))?;
    let (_, body) = root.split_vertically(lay.title_h);
    let body = if let FigureLegend::Top(entries) = &fig.legend {
        let (strip, rest) = body.split_vertically(lay.top_legend_h);
        let x0 = (w as i32 - lay.top_legend.width() as i32) / 2;
        draw_legend(&strip, entries, &lay.top_legend, (x0.max(0), 0))?;
        rest
    } else {
        body
    };

    let cell_w = w / fig.cols as u32;
    let xs: Vec<u32> = (1..fig.cols as u32).map(|c| c * cell_w).collect();
    let mut ys = Vec::new();
    let mut y = 0;
    for r in 0..fig.rows - 1 {
        y += lay.row_top[r] + lay.row_plot_h + lay.row_bottom[r];
        ys.push(y);
    }
    let cells = body.split_by_breakpoints(&xs, &ys);
    for (i, area) in cells.iter().enumerate() {
        let (r, c) = (i / fig.cols, i % fig.cols);
        match &fig.cells[i] {
            Some(panel) => draw_panel(area, fig, lay, panel, r, c)?,
            None => {
                if let FigureLegend::Cell(at, entries) = &fig.legend
                    && *at == i
                {
                    let (aw, ah) = area.dim_in_pixel();
                    let grid = LegendGrid::fitting_height(entries, ah.saturating_sub(2 * PAD));
                    let x0 = (aw as i32 - grid.width() as i32) / 2;
                    let y0 = (lay.row_top[r] as i32).min((ah as i32 - grid.height() as i32) / 2).max(0);
                    draw_legend(area, entries, &grid, (x0.max(0), y0))?;
                }
            }
        }
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
    lay: &Layout,
    panel: &Panel,
    r: usize,
    c: usize,
) -> DrawResult<DB> {
    let i = r * fig.cols + c;
    let (x, y) = lay.axes[i].clone().expect("axes of a panel");
    let (aw, _) = area.dim_in_pixel();
    let legend = lay.col_legend[c];
    let legend_w = legend.width();
    let right = legend_w + 2 * PAD;
    let mut chart = ChartBuilder::on(area)
        .margin_top(lay.row_top[r])
        .margin_right(right)
        .margin_left(PAD)
        .x_label_area_size(lay.row_bottom[r])
        .y_label_area_size(lay.col_left[c])
        .build_cartesian_2d(x.clone(), y.clone())?;

    let x_ticks = show_x_ticks(fig, r, c);
    let x_fmt = |v: &f64| if x_ticks { x.label(*v) } else { String::new() };
    let y_fmt = |v: &f64| y.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(64)
        .y_labels(64)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(font(TICK_SIZE).color(&BLACK))
        .axis_desc_style(font(DESC_SIZE).color(&BLACK))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK.mix(0.85))
        .set_all_tick_mark_size(TICK_MARK);
    if show_x_desc(fig, r, c) {
        mesh.x_desc(panel.x_desc.as_str());
    }
    if !panel.y_desc.is_empty() {
        mesh.y_desc(panel.y_desc.as_str());
    }
    mesh.draw()?;

    // Zero line, when zero is inside a range that is not all positive.
    if y.lo < 0.0 && y.hi > 0.0 {
        chart.draw_series(std::iter::once(PathElement::new(vec![(x.lo, 0.0), (x.hi, 0.0)], BLACK.mix(0.35))))?;
    }

    let events = in_range(&panel.events, &x);
    for (t, _) in &events {
        chart.draw_series(DashedLineSeries::new(vec![(*t, y.lo), (*t, y.hi)], 6, 4, EVENT_COLOR.stroke_width(2)))?;
    }

    for series in &panel.series {
        let style = series.stroke.style();
        for seg in series.segments() {
            if let [point] = seg {
                // A lone point (one row, or between NaNs) has no line: mark it.
                chart.draw_series(std::iter::once(Circle::new(*point, 2, series.stroke.color.filled())))?;
                continue;
            }
            match series.stroke.dash {
                Dash::Solid => {
                    chart.draw_series(LineSeries::new(seg.iter().copied(), style))?;
                }
                Dash::Dashed => {
                    chart.draw_series(DashedLineSeries::new(seg.iter().copied(), 7, 5, style))?;
                }
            }
        }
    }

    // Frame the plot, then caption, event labels and legend, in this area's pixels.
    let (px, py) = chart.plotting_area().get_pixel_range();
    let (bx, by) = area.get_base_pixel();
    let (left, top, right, bottom) = (px.start - bx, py.start - by, px.end - bx, py.end - by);
    area.draw(&Rectangle::new([(left, top), (right - 1, bottom - 1)], BLACK.mix(0.85).stroke_width(1)))?;

    if !panel.caption.is_empty() {
        let style = font(CAPTION_SIZE).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
        let y = if r > 0 { 2 * PAD } else { PAD };
        area.draw_text(&panel.caption, &style, ((left + right) / 2, y as i32))?;
    }

    if panel.event_labels {
        let color = EVENT_COLOR;
        let placed = place_event_labels(&events, &x, (right - left).max(1) as u32);
        for ((t, label), place) in events.iter().zip(placed) {
            let px = x.map(t, (left, right));
            let bottom = top - (PAD as i32) / 2 - place.row as i32 * EVENT_ROW as i32;
            let text_h = text_size(label, EVENT_SIZE).1 as i32;
            area.draw(&PathElement::new(vec![(px, top), (px, bottom - text_h)], color.stroke_width(1)))?;
            let (h_pos, tx) =
                if place.flip { (HPos::Right, px - FLAG_GAP as i32) } else { (HPos::Left, px + FLAG_GAP as i32) };
            let style = font(EVENT_SIZE).color(&color).pos(Pos::new(h_pos, VPos::Bottom));
            area.draw_text(label, &style, (tx, bottom))?;
        }
    }

    if legend_w > 0 && panel.legend {
        let entries = panel.legend_entries();
        let grid = LegendGrid::fitting_height(&entries, lay.row_plot_h);
        let x0 = (aw as i32 - legend_w as i32 - PAD as i32).max(right + PAD as i32);
        draw_legend(area, &entries, &grid, (x0, top))?;
    }
    Ok(())
}

/// Draw legend entries in a grid whose top-left corner is `origin` (pixels of `area`).
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    grid: &LegendGrid,
    origin: (i32, i32),
) -> DrawResult<DB> {
    let style = font(LEGEND_SIZE).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, entry) in entries.iter().enumerate() {
        let (row, col) = (k / grid.cols.max(1), k % grid.cols.max(1));
        let x = origin.0 + (col as u32 * grid.col_w) as i32;
        let y = origin.1 + (row as u32 * LEGEND_ROW + LEGEND_ROW / 2) as i32;
        let sample = vec![(x, y), (x + LEGEND_SAMPLE as i32, y)];
        let stroke = entry.stroke;
        match stroke.dash {
            Dash::Solid => area.draw(&PathElement::new(sample, stroke.style()))?,
            Dash::Dashed => area.draw(&DashedPathElement::new(sample, 7, 5, stroke.style()))?,
        }
        area.draw_text(&entry.label, &style, (x + LEGEND_SAMPLE as i32 + 6, y))?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------------------------------------

static DEJAVU_SANS: &[u8] = include_bytes!("../data/fonts/DejaVuSans.ttf");

/// Register the embedded font as plotters' "sans-serif", once per process.
fn ensure_font(file: &Path) -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS).is_ok());
    if ok { Ok(()) } else { Err(PlotError::Font { file: file.to_path_buf() }) }
}

/// Encode an 8-bit RGB buffer as a PNG file. (The `png` crate directly, rather than plotters' `bitmap_encoder`
/// feature, which pulls in the whole `image` crate: the largest single crate of a clean build.)
fn write_png(file: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<(), PlotError> {
    let out = std::fs::File::create(file).map_err(|source| PlotError::Write { file: file.to_path_buf(), source })?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(out), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let encoded = encoder.write_header().and_then(|mut writer| {
        writer.write_image_data(rgb)?;
        writer.finish()
    });
    encoded.map_err(|e| match e {
        png::EncodingError::IoError(source) => PlotError::Write { file: file.to_path_buf(), source },
        other => PlotError::Draw { file: file.to_path_buf(), message: format!("PNG encoding: {other}") },
    })
}

/// Draw `fig` as `<stem>.png` and `<stem>.svg` in `out_dir`; returns both paths.
fn write_figure(fig: &Figure, out_dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    let png = out_dir.join(format!("{stem}.png"));
    let svg = out_dir.join(format!("{stem}.svg"));
    ensure_font(&png)?;
    std::fs::create_dir_all(out_dir).map_err(|source| PlotError::CreateDir { dir: out_dir.to_path_buf(), source })?;
    let lay = layout(fig);
    let draw_error = |file: &Path, message: String| PlotError::Draw { file: file.to_path_buf(), message };

    let (w, h) = fig.size;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, fig.size).into_drawing_area();
        draw_figure(&root, fig, &lay).map_err(|e| draw_error(&png, e.to_string()))?;
        root.present().map_err(|e| draw_error(&png, e.to_string()))?;
    }
    write_png(&png, &rgb, fig.size)?;

    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fig.size).into_drawing_area();
        draw_figure(&root, fig, &lay).map_err(|e| draw_error(&svg, e.to_string()))?;
        root.present().map_err(|e| draw_error(&svg, e.to_string()))?;
    }
    std::fs::write(&svg, text).map_err(|source| PlotError::Write { file: svg.clone(), source })?;
    Ok(vec![png, svg])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_and_labels() {
        let a = Axis::linear(-1.05, 10.5, 5);
        assert_eq!(a.labels, ["0", "2", "4", "6", "8", "10"]);
        let a = Axis::linear(0.0, 1.0, 4);
        assert_eq!(a.labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let a = Axis::linear(-0.3, 0.3, 3);
        assert!(a.labels.contains(&"0.0".to_string()), "{:?}", a.labels);
        let a = Axis::linear(0.0, 3e-5, 3);
        assert!(a.labels.iter().all(|l| l == "0" || l.contains('e')), "{:?}", a.labels);
    }

    #[test]
    fn nines_axis_labels() {
        let a = Axis::nines(5.0);
        assert_eq!(a.labels, ["0%", "90%", "99%", "99.9%", "99.99%", "99.999%"]);
        assert!((nines(99.9) - 3.0).abs() < 1e-9);
        assert_eq!(nines(0.0), 0.0);
    }

    #[test]
    fn ranges_are_padded_and_constant_series_get_a_symmetric_range() {
        assert_eq!(padded(0.0, 10.0), (-0.5, 10.5));
        assert_eq!(padded(0.0, 0.0), (-1.0, 1.0));
        assert_eq!(padded(5.0, 5.0), (4.5, 5.5));
        assert_eq!(padded(-2.0, -2.0), (-2.2, -1.8));
        let p = Panel::new("", "", vec![Series::solid("x", vec![(0.0, f64::NAN), (1.0, f64::NAN)], BLACK)]);
        assert_eq!(p.y_range(), (-1.0, 1.0));
    }

    #[test]
    fn nan_splits_a_series_into_segments() {
        let s = Series::solid("x", vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0), (3.0, 4.0)], BLACK);
        let segs: Vec<_> = s.segments().collect();
        assert_eq!(segs.len(), 2);
        assert_eq!(segs[1].len(), 2);
    }
}
