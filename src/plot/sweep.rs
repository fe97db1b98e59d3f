//! The sweep figures: histograms of each criterion's figure over the cases, scatter plots of the most influential
//! dispersed parameters against a criterion, and the envelope of each output with a set point over all cases with the failures
//! drawn one by one. Plain data in (the campaign module computes it), figures out.

use std::path::Path;

use super::PlotError;
use super::drawn::Drawn;
use super::figure::{Figure, FigureLegend, LegendEntry, Panel, Series, palette};
use super::render::write_figure;

const PASS: usize = 0;
const FAIL: usize = 3;
const BAND: usize = 7;

/// One histogram panel.
pub struct Histogram {
    /// Panel caption (the criterion).
    pub caption: String,
    /// Unit of the values.
    pub unit: String,
    /// The values (non-finite ones are left out).
    pub values: Vec<f64>,
    /// The criterion's limit, drawn as a marker.
    pub limit: Option<f64>,
}

/// One scatter panel: a parameter against a figure, passed and failed cases in two colours.
pub struct Scatter {
    /// Panel caption.
    pub caption: String,
    /// The parameter (x axis).
    pub x_desc: String,
    /// The figure (y axis).
    pub y_desc: String,
    /// (parameter, figure) of passed cases.
    pub passed: Vec<(f64, f64)>,
    /// ... of failed cases.
    pub failed: Vec<(f64, f64)>,
}

/// One envelope panel: an output with a set point over time.
pub struct Envelope {
    /// Panel caption.
    pub caption: String,
    /// The output's unit.
    pub unit: String,
    /// (t, lowest, highest) over the passed cases.
    pub band: Vec<(f64, f64, f64)>,
    /// The failed cases drawn one by one (at most a few dozen).
    pub failed: Vec<Vec<(f64, f64)>>,
    /// The set point.
    pub setpoint: f64,
}

fn grid_for(n: usize) -> (usize, usize) {
    let cols = if n <= 1 { 1 } else { 2 };
    (n.div_ceil(cols).max(1), cols)
}

/// The cells of a grid, the last ones left empty.
fn padded(mut cells: Vec<Option<Panel>>, n: usize) -> Vec<Option<Panel>> {
    cells.resize_with(n, || None);
    cells
}

/// A histogram as a step line, `bins` bins over the values' range.
fn steps(values: &[f64], bins: usize) -> Vec<(f64, f64)> {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
    if finite.is_empty() {
        return Vec::new();
    }
    let width = if hi > lo { (hi - lo) / bins as f64 } else { 1.0 };
    let mut counts = vec![0u64; bins];
    for v in &finite {
        counts[(((v - lo) / width) as usize).min(bins - 1)] += 1;
    }
    let mut points = vec![(lo, 0.0)];
    for (i, c) in counts.iter().enumerate() {
        let (x0, x1) = (lo + i as f64 * width, lo + (i + 1) as f64 * width);
        points.extend([(x0, *c as f64), (x1, *c as f64)]);
    }
    points.push((lo + bins as f64 * width, 0.0));
    points
}

/// Scatter points: each point its own segment (separated by NaN), which the renderer draws as a dot.
fn dots(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points.iter().flat_map(|p| [*p, (f64::NAN, f64::NAN)]).collect()
}

/// `<stem>.{png,svg}`: one histogram per criterion, the limit marked.
pub fn plot_histograms(panels: &[Histogram], out_dir: &Path, stem: &str, title: &str) -> Result<Drawn, PlotError> {
    if panels.is_empty() {
        return Err(PlotError::NoData { file: out_dir.join(format!("{stem}.png")), problem: "no criteria".into() });
    }
    let cells: Vec<Option<Panel>> = panels
        .iter()
        .map(|h| {
            let mut p =
                Panel::new(&h.caption, "cases", vec![Series::solid("cases", steps(&h.values, 30), palette(PASS))]);
            p.x_desc = h.unit.clone();
            p.legend = false;
            p.y_from_zero = true;
            if let Some(limit) = h.limit {
                p.events = vec![(limit, "limit".into())];
                p.event_labels = true;
            }
            Some(p)
        })
        .collect();
    let (rows, cols) = grid_for(panels.len());
    let fig =
        Figure::grid(title, (1200, 330 * rows as u32 + 80), rows, cols, padded(cells, rows * cols), FigureLegend::None);
    write_figure(&fig, out_dir, stem)
}

/// `<stem>.{png,svg}`: one scatter panel per parameter, passed and failed cases in two colours.
pub fn plot_scatter(panels: &[Scatter], out_dir: &Path, stem: &str, title: &str) -> Result<Drawn, PlotError> {
    if panels.is_empty() {
        return Err(PlotError::NoData { file: out_dir.join(format!("{stem}.png")), problem: "no parameters".into() });
    }
    let cells: Vec<Option<Panel>> = panels
        .iter()
        .map(|s| {
            let mut p = Panel::new(
                &s.caption,
                &s.y_desc,
                vec![
                    Series::solid("passed", dots(&s.passed), palette(PASS)),
                    Series::solid("failed", dots(&s.failed), palette(FAIL)),
                ],
            );
            p.x_desc = s.x_desc.clone();
            p.legend = false;
            Some(p)
        })
        .collect();
    let (rows, cols) = grid_for(panels.len());
    let legend = vec![LegendEntry::solid("passed", palette(PASS)), LegendEntry::solid("failed", palette(FAIL))];
    let fig = Figure::grid(
        title,
        (1200, 330 * rows as u32 + 110),
        rows,
        cols,
        padded(cells, rows * cols),
        FigureLegend::Top(legend),
    );
    write_figure(&fig, out_dir, stem)
}

/// `<stem>.{png,svg}`: per output with a set point, the band the passed cases stay in, the set point, and each failed case.
pub fn plot_envelope(panels: &[Envelope], out_dir: &Path, stem: &str, title: &str) -> Result<Drawn, PlotError> {
    let panels: Vec<Panel> = panels
        .iter()
        .map(|e| {
            let mut series: Vec<Series> = e
                .failed
                .iter()
                .map(|f| {
                    let mut s = Series::solid("failed", f.clone(), palette(FAIL));
                    s.stroke.width = 1;
                    s
                })
                .collect();
            // The band last, so the failures do not hide it.
            let t_end = e.band.last().map_or(0.0, |b| b.0);
            series.push(Series::level("set point", e.setpoint, (0.0, t_end), palette(PASS)));
            for (label, pick) in [("passed: lowest", 0), ("passed: highest", 1)] {
                let line = e.band.iter().map(|(t, lo, hi)| (*t, if pick == 0 { *lo } else { *hi })).collect();
                let mut s = Series::solid(label, line, palette(BAND));
                s.stroke.width = 3;
                series.push(s);
            }
            let mut p = Panel::new(&e.caption, &e.unit, series);
            p.legend = false;
            p
        })
        .collect();
    let legend = vec![
        LegendEntry::solid("range of the passed cases", palette(BAND)),
        LegendEntry::solid("a failed case", palette(FAIL)),
    ];
    let mut fig = Figure::stacked(title, (1200, 1000), panels);
    fig.legend = FigureLegend::Top(legend);
    write_figure(&fig, out_dir, stem)
}
