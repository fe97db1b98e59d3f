//! The figure model: a figure is plain data (a grid of panels, each with its series, strokes and legend entries),
//! built by the figure families and read by layout and rendering. Also the data ranges a panel's axes start from.

use plotters::prelude::*;

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

pub(super) fn palette(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// How a line is stroked.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Dash {
    Solid,
    Dashed,
}

/// A line's look, shared by the series and its legend entry.
#[derive(Clone, Copy)]
pub(super) struct Stroke {
    pub(super) color: RGBColor,
    pub(super) width: u32,
    pub(super) dash: Dash,
}

impl Stroke {
    /// The k-th of many lines: the palette, then the palette dashed, and so on.
    fn cycled(k: usize) -> Self {
        let dash = if (k / PALETTE.len()).is_multiple_of(2) { Dash::Solid } else { Dash::Dashed };
        Self { color: palette(k), width: 2, dash }
    }

    pub(super) fn style(&self) -> ShapeStyle {
        let width = self.width;
        match self.dash {
            Dash::Solid => self.color.stroke_width(width),
            // A dashed line drawn over a solid one of the same colour stays visible if it is lighter.
            Dash::Dashed => self.color.mix(0.9).stroke_width(width),
        }
    }
}

pub(super) struct Series {
    pub(super) label: String,
    pub(super) points: Vec<(f64, f64)>,
    pub(super) stroke: Stroke,
    /// Whether its values set the panel's y range; a series that does not is drawn cut at the range's edges
    /// ([`clip_to_y`]), so one far-off series cannot flatten the others.
    pub(super) sets_y_range: bool,
    /// Drawn as bars this wide (x units), each point its left edge and its height, rather than as a line.
    pub(super) bar_width: Option<f64>,
}

impl Series {
    pub(super) fn solid(label: &str, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self::new(label, points, Stroke { color, width: 2, dash: Dash::Solid })
    }

    /// A thin solid line: a reference drawn under the data it is compared with.
    pub(super) fn thin(label: &str, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self::new(label, points, Stroke { color, width: 1, dash: Dash::Solid })
    }

    pub(super) fn command(label: &str, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self::new(label, points, Stroke { color, width: 1, dash: Dash::Dashed })
    }

    /// A set point: a dashed level line at `value` over `span` (the trace's time span).
    pub(super) fn level(label: &str, value: f64, span: (f64, f64), color: RGBColor) -> Self {
        Self::command(label, vec![(span.0, value), (span.1, value)], color)
    }

    pub(super) fn cycled(label: &str, points: Vec<(f64, f64)>, k: usize) -> Self {
        Self::new(label, points, Stroke::cycled(k))
    }

    /// Bars `width` wide: each point is a bar's left edge and height.
    pub(super) fn bars(label: &str, points: Vec<(f64, f64)>, width: f64, k: usize) -> Self {
        Self { bar_width: Some(width), ..Self::cycled(label, points, k) }
    }

    fn new(label: &str, points: Vec<(f64, f64)>, stroke: Stroke) -> Self {
        Self { label: label.to_string(), points, stroke, sets_y_range: true, bar_width: None }
    }

    /// The same series, drawn within the y range the panel's other series set and cut at its edges.
    pub(super) fn within_others_range(self) -> Self {
        Self { sets_y_range: false, ..self }
    }
}

/// Runs of consecutive finite points.
pub(super) fn segments(points: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> {
    points.split(|(x, y)| !(x.is_finite() && y.is_finite())).filter(|s| !s.is_empty())
}

pub(super) struct LegendEntry {
    pub(super) label: String,
    pub(super) stroke: Stroke,
}

impl LegendEntry {
    pub(super) fn cycled(label: &str, k: usize) -> Self {
        Self { label: label.to_string(), stroke: Stroke::cycled(k) }
    }

    pub(super) fn solid(label: &str, color: RGBColor) -> Self {
        Self { label: label.to_string(), stroke: Stroke { color, width: 2, dash: Dash::Solid } }
    }
}

#[derive(Clone, Copy, PartialEq)]
pub(super) enum XScale {
    /// Time in seconds.
    Linear,
    /// Percentiles on the number-of-nines scale.
    Nines,
}

pub(super) struct Panel {
    pub(super) caption: String,
    pub(super) y_desc: String,
    pub(super) x_desc: String,
    pub(super) x_scale: XScale,
    pub(super) series: Vec<Series>,
    /// Draw a legend of the series to the right of the plot.
    pub(super) legend: bool,
    /// Start the y axis at zero (if no value is negative).
    pub(super) y_from_zero: bool,
    /// Vertical markers (time, label).
    pub(super) events: Vec<(f64, String)>,
    /// Write the markers' labels above this panel.
    pub(super) event_labels: bool,
    /// Time spans shaded behind the data (rows whose outputs the plant held).
    pub(super) shaded: Vec<(f64, f64)>,
    /// The x range to show whatever the data spans (the whole flight for a command that stops coming early).
    pub(super) x_span: Option<(f64, f64)>,
    /// A logarithmic y axis (decades), for values spanning several orders of magnitude (latencies, counts): values
    /// at or below zero sit on the axis' bottom edge.
    pub(super) y_log: bool,
    /// Time windows shaded in the event colour behind the data (a fault from its injection to its end).
    pub(super) windows: Vec<(f64, f64)>,
}

impl Panel {
    pub(super) fn new(caption: &str, y_desc: &str, series: Vec<Series>) -> Self {
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
            shaded: Vec::new(),
            x_span: None,
            y_log: false,
            windows: Vec::new(),
        }
    }

    pub(super) fn legend_entries(&self) -> Vec<LegendEntry> {
        if !self.legend {
            return Vec::new();
        }
        self.series.iter().map(|s| LegendEntry { label: s.label.clone(), stroke: s.stroke }).collect()
    }

    fn finite(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.series.iter().flat_map(|s| s.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    /// The finite points of the series that set the y range (all of them if none does).
    fn finite_ranging(&self) -> impl Iterator<Item = &(f64, f64)> {
        let any = self.series.iter().any(|s| s.sets_y_range);
        self.series
            .iter()
            .filter(move |s| s.sets_y_range || !any)
            .flat_map(|s| s.points.iter())
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    pub(super) fn x_range(&self) -> (f64, f64) {
        let span = self.x_span.iter().flat_map(|(lo, hi)| [*lo, *hi]);
        let (lo, hi) = min_max(self.finite().map(|p| p.0).chain(span));
        match self.x_scale {
            XScale::Linear => match (lo, hi) {
                (Some(lo), Some(hi)) if hi - lo > 1e-9 * lo.abs().max(hi.abs()) => (lo, hi),
                (Some(lo), Some(hi)) => symmetric(0.5 * (lo + hi)),
                _ => (0.0, 1.0),
            },
            // Ending where the data end: a few hundred samples reach 99.7 %, and an axis to 99.99 % would leave
            // most of the plot empty.
            XScale::Nines => (0.0, hi.filter(|hi| *hi > 0.0).unwrap_or(1.0)),
        }
    }

    /// The y range in the axis' own space: data units, or decades (log10 of them) on a log axis.
    pub(super) fn y_range(&self) -> (f64, f64) {
        if self.y_log {
            return log_range(self.finite_ranging().map(|p| p.1));
        }
        let (lo, hi) = min_max(self.finite_ranging().map(|p| p.1));
        let (Some(lo), Some(hi)) = (lo, hi) else { return (-1.0, 1.0) };
        if self.y_from_zero && lo >= 0.0 && hi > 0.0 {
            return (0.0, hi * 1.05);
        }
        padded(lo, hi)
    }
}

/// A value on this panel's y axis: log10 of it on a log axis (at most `floor` below, so zero and negative values sit
/// on the bottom edge), the value itself otherwise.
pub(super) fn y_axis_value(y_log: bool, v: f64, floor: f64) -> f64 {
    if !y_log || !v.is_finite() {
        return v;
    }
    if v > 0.0 { v.log10().max(floor) } else { floor }
}

/// The decades a log axis spans: from the whole decade below the smallest positive value (at least 0.3 decade
/// below it, so the smallest bar of a count histogram, 1, stands a decade tall) to 5 % of the span above the largest.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = min_max(values.filter(|v| *v > 0.0).map(f64::log10));
    let (Some(lo), Some(hi)) = (lo, hi) else { return (0.0, 1.0) };
    let lo = (lo - 0.3).floor();
    let hi = if hi - lo < 1.0 { lo + 1.0 } else { hi };
    (lo, hi + 0.05 * (hi - lo))
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

/// `points` cut at y = lo and y = hi: a line that leaves the band ends on its edge (at the interpolated crossing)
/// and resumes where it comes back; the points outside become NaN breaks.
pub(super) fn clip_to_y(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<(f64, f64)> {
    let inside = |y: f64| (lo..=hi).contains(&y);
    // Where the line from a to b crosses the edge on the side of `outside` (a y beyond the band).
    let edge = |(x0, y0): (f64, f64), (x1, y1): (f64, f64), outside: f64| {
        let y = if outside > hi { hi } else { lo };
        (x0 + (x1 - x0) * (y - y0) / (y1 - y0), y)
    };
    let gap = (f64::NAN, f64::NAN);
    let mut out = Vec::with_capacity(points.len());
    for (k, &p) in points.iter().enumerate() {
        let prev = k.checked_sub(1).map(|j| points[j]).filter(|q| q.0.is_finite() && q.1.is_finite());
        let finite = p.0.is_finite() && p.1.is_finite();
        match (prev, finite) {
            (Some(q), true) if inside(q.1) && !inside(p.1) => out.extend([edge(q, p, p.1), gap]),
            (Some(q), true) if !inside(q.1) && inside(p.1) => out.extend([edge(q, p, q.1), p]),
            // From one side of the band to the other in one step: the piece across it.
            (Some(q), true) if !inside(q.1) && !inside(p.1) && (q.1 > hi) != (p.1 > hi) => {
                out.extend([edge(q, p, q.1), edge(q, p, p.1), gap])
            }
            (_, true) if inside(p.1) => out.push(p),
            _ => out.push(gap),
        }
    }
    out
}

/// Where the legend of the whole figure goes.
pub(super) enum FigureLegend {
    None,
    /// A strip under the title, entries left to right.
    Top(Vec<LegendEntry>),
    /// An empty grid cell (row-major index).
    Cell(usize, Vec<LegendEntry>),
}

pub(super) struct Figure {
    pub(super) title: String,
    pub(super) size: (u32, u32),
    pub(super) rows: usize,
    pub(super) cols: usize,
    /// Row-major; `None` leaves the cell empty.
    pub(super) cells: Vec<Option<Panel>>,
    pub(super) legend: FigureLegend,
    /// Panels in one column share the time axis: tick labels and the axis name only on the lowest.
    pub(super) shared_x: bool,
}

impl Figure {
    pub(super) fn stacked(title: &str, size: (u32, u32), panels: Vec<Panel>) -> Self {
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

    pub(super) fn grid(
        title: &str,
        size: (u32, u32),
        rows: usize,
        cols: usize,
        cells: Vec<Option<Panel>>,
        legend: FigureLegend,
    ) -> Self {
        Self { title: title.to_string(), size, rows, cols, cells, legend, shared_x: false }
    }

    pub(super) fn cell(&self, r: usize, c: usize) -> Option<&Panel> {
        self.cells.get(r * self.cols + c).and_then(Option::as_ref)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let segs: Vec<_> = segments(&s.points).collect();
        assert_eq!(segs.len(), 2);
        assert_eq!(segs[1].len(), 2);
    }

    #[test]
    fn a_series_off_the_range_is_left_out_of_it_and_cut_at_its_edges() {
        let inside = Series::solid("deflection", vec![(0.0, -10.0), (1.0, 10.0)], BLACK);
        let far = Series::command("command", vec![(0.0, 0.0), (1.0, 62.8)], BLACK).within_others_range();
        assert_eq!(Panel::new("", "", vec![inside, far]).y_range(), (-11.0, 11.0));
        // Out at y = 10 (x = 0.5), back in at y = 10 (x = 2.5); a jump across the band keeps the piece across it.
        let cut =
            clip_to_y(&[(0.0, 0.0), (1.0, 20.0), (2.0, 30.0), (3.0, 0.0), (4.0, -20.0), (5.0, 20.0)], -10.0, 10.0);
        let text: Vec<String> = cut.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
        assert_eq!(
            text,
            [
                "0.00,0.00",
                "0.50,10.00",
                "NaN,NaN",
                "NaN,NaN",
                "2.67,10.00",
                "3.00,0.00",
                "3.50,-10.00",
                "NaN,NaN",
                "4.25,-10.00",
                "4.75,10.00",
                "NaN,NaN"
            ]
        );
    }
}
