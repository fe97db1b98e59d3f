//! What a figure was drawn as: its files and, for each panel, what the layout decided (the axes' ranges and tick
//! labels, the axis names shown, the title's size) beside the extent of the panel's data, so that a test can hold a
//! figure's axes to its data without reading pixels.

use std::path::PathBuf;

use super::figure::{Figure, Panel};
use super::layout::{Layout, show_x_desc, text_size};

/// The files of one or more figures and what each was drawn as. Reads as the list of files (PNG before SVG,
/// figure by figure), which is what most callers want.
#[derive(Debug, Clone, Default)]
pub struct Drawn {
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// Every figure drawn, in order.
    pub figures: Vec<FigureAxes>,
}

impl Drawn {
    /// The figure written as `<stem>.png` and `.svg`, if it was drawn.
    pub fn figure(&self, stem: &str) -> Option<&FigureAxes> {
        self.figures.iter().find(|f| f.stem == stem)
    }

    pub(super) fn extend(&mut self, other: Drawn) {
        self.files.extend(other.files);
        self.figures.extend(other.figures);
    }
}

impl std::ops::Deref for Drawn {
    type Target = [PathBuf];
    fn deref(&self) -> &[PathBuf] {
        &self.files
    }
}

impl IntoIterator for Drawn {
    type Item = PathBuf;
    type IntoIter = std::vec::IntoIter<PathBuf>;
    fn into_iter(self) -> Self::IntoIter {
        self.files.into_iter()
    }
}

impl<'a> IntoIterator for &'a Drawn {
    type Item = &'a PathBuf;
    type IntoIter = std::slice::Iter<'a, PathBuf>;
    fn into_iter(self) -> Self::IntoIter {
        self.files.iter()
    }
}

/// One figure as drawn.
#[derive(Debug, Clone)]
pub struct FigureAxes {
    /// The files' stem.
    pub stem: String,
    /// The title.
    pub title: String,
    /// The figure's width, px.
    pub width_px: u32,
    /// The title's width at the size it was drawn, px (it fits when at most `width_px`).
    pub title_width_px: u32,
    /// Every panel, row by row.
    pub panels: Vec<PanelAxes>,
}

/// One axis as drawn: its range in the data's units (a log axis' decades turned back into values) and its tick
/// labels.
#[derive(Debug, Clone)]
pub struct AxisRange {
    /// The lowest value the axis shows.
    pub lo: f64,
    /// The highest.
    pub hi: f64,
    /// The tick labels, in order.
    pub ticks: Vec<String>,
}

/// One panel as drawn.
#[derive(Debug, Clone)]
pub struct PanelAxes {
    /// The caption above it.
    pub caption: String,
    /// The x axis' name where it is written under this panel (a column of panels sharing time names it once).
    pub x_label: Option<String>,
    /// The y axis' name: the unit, blank for a dimensionless one.
    pub y_label: String,
    /// The x axis.
    pub x: AxisRange,
    /// The y axis.
    pub y: AxisRange,
    /// Whether the y axis is logarithmic.
    pub y_log: bool,
    /// The lowest and highest finite x of the data drawn (None: no data).
    pub x_data: Option<(f64, f64)>,
    /// The lowest and highest finite y of the series that set the range (None: no data).
    pub y_data: Option<(f64, f64)>,
    /// The series' labels, in order.
    pub series: Vec<String>,
    /// The windows shaded in the event colour (a fault from start to end).
    pub windows: Vec<(f64, f64)>,
    /// The instants marked.
    pub events: Vec<(f64, String)>,
}

/// What `fig`, laid out as `lay`, was drawn as.
pub(super) fn describe(fig: &Figure, lay: &Layout, stem: &str, files: Vec<PathBuf>) -> Drawn {
    let mut panels = Vec::new();
    for (i, (panel, axes)) in fig.cells.iter().zip(&lay.axes).enumerate() {
        let (Some(panel), Some((x, y))) = (panel, axes) else { continue };
        let (r, c) = (i / fig.cols, i % fig.cols);
        let value = |v: f64| if panel.y_log { 10f64.powf(v) } else { v };
        panels.push(PanelAxes {
            caption: panel.caption.clone(),
            x_label: show_x_desc(fig, r, c).then(|| panel.x_desc.clone()),
            y_label: panel.y_desc.clone(),
            x: AxisRange { lo: x.lo, hi: x.hi, ticks: x.tick_labels().to_vec() },
            y: AxisRange { lo: value(y.lo), hi: value(y.hi), ticks: y.tick_labels().to_vec() },
            y_log: panel.y_log,
            x_data: extent(panel, |p| p.0, false),
            y_data: extent(panel, |p| p.1, true),
            series: panel.series.iter().map(|s| s.label.clone()).collect(),
            windows: panel.windows.clone(),
            events: panel.events.clone(),
        });
    }
    let figure = FigureAxes {
        stem: stem.to_string(),
        title: fig.title.clone(),
        width_px: fig.size.0,
        title_width_px: text_size(&fig.title, lay.title_size).0,
        panels,
    };
    Drawn { files, figures: vec![figure] }
}

/// The finite extent of `pick` over the panel's points (of the series that set the y range, for y; a bar reaches
/// its right edge in x).
fn extent(panel: &Panel, pick: impl Fn(&(f64, f64)) -> f64, ranging: bool) -> Option<(f64, f64)> {
    let any = panel.series.iter().any(|s| s.sets_y_range);
    let values = panel
        .series
        .iter()
        .filter(|s| !ranging || s.sets_y_range || !any)
        .flat_map(|s| s.points.iter().flat_map(move |p| [*p, (p.0 + s.bar_width.unwrap_or(0.0), p.1)]))
        // A log axis shows positive values only; zero sits on its edge.
        .filter(|(x, y)| x.is_finite() && y.is_finite() && (!panel.y_log || *y > 0.0))
        .map(|p| pick(&p));
    values.fold(None, |acc, v| Some(acc.map_or((v, v), |(lo, hi): (f64, f64)| (lo.min(v), hi.max(v)))))
}
