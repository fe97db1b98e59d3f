//! Layout: the pixel size of every part of a figure (title, legends, the bands around each plot, the axes' ticks,
//! event-label rows), computed once from the figure so that both backends draw the same picture.

use plotters::prelude::*;
use plotters::style::FontStyle;

use super::axis::Axis;
use super::figure::{Figure, FigureLegend, LegendEntry, Panel, XScale};

pub(super) const TITLE_SIZE: f64 = 30.0;
pub(super) const CAPTION_SIZE: f64 = 21.0;
pub(super) const TICK_SIZE: f64 = 18.0;
pub(super) const DESC_SIZE: f64 = 19.0;
pub(super) const LEGEND_SIZE: f64 = 18.0;
pub(super) const EVENT_SIZE: f64 = 17.0;
/// Height of one legend line.
pub(super) const LEGEND_ROW: u32 = 21;
/// Length of the line sample in a legend entry.
pub(super) const LEGEND_SAMPLE: u32 = 30;
/// Height of one row of event labels.
pub(super) const EVENT_ROW: u32 = 20;
/// Space around panels and between their parts.
pub(super) const PAD: u32 = 8;
pub(super) const TICK_MARK: u32 = 5;
/// Gap between a marker line and its label.
pub(super) const FLAG_GAP: u32 = 4;

pub(super) fn font(size: f64) -> FontDesc<'static> {
    FontDesc::new(FontFamily::SansSerif, size, FontStyle::Normal)
}

pub(super) fn text_size(text: &str, size: f64) -> (u32, u32) {
    // The font is registered before any layout runs; the fallback only keeps layout total.
    font(size).box_size(text).unwrap_or(((text.chars().count() as f64 * size * 0.5) as u32, size as u32))
}

/// A legend as a grid of entries, filled row by row.
#[derive(Clone, Copy, Default)]
pub(super) struct LegendGrid {
    pub(super) cols: usize,
    rows: usize,
    pub(super) col_w: u32,
}

impl LegendGrid {
    fn col_width(entries: &[LegendEntry]) -> u32 {
        let widest = entries.iter().map(|e| text_size(&e.label, LEGEND_SIZE).0).max().unwrap_or(0);
        LEGEND_SAMPLE + 6 + widest + 16
    }

    /// As few columns as fit `height`.
    pub(super) fn fitting_height(entries: &[LegendEntry], height: u32) -> Self {
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

    pub(super) fn width(&self) -> u32 {
        self.cols as u32 * self.col_w
    }

    pub(super) fn height(&self) -> u32 {
        self.rows as u32 * LEGEND_ROW
    }
}

/// Pixel sizes of every part of a figure, computed once and used by both backends.
pub(super) struct Layout {
    /// The title's font size: [`TITLE_SIZE`], or smaller so that the title fits the figure's width.
    pub(super) title_size: f64,
    pub(super) title_h: u32,
    pub(super) top_legend: LegendGrid,
    pub(super) top_legend_h: u32,
    /// Per row: band above the plot (caption, event labels), x label area under it.
    pub(super) row_top: Vec<u32>,
    pub(super) row_bottom: Vec<u32>,
    pub(super) row_plot_h: u32,
    /// Per column: y label area, legend width.
    pub(super) col_left: Vec<u32>,
    pub(super) col_legend: Vec<LegendGrid>,
    /// Per cell (row-major): axes.
    pub(super) axes: Vec<Option<(Axis, Axis)>>,
}

pub(super) fn show_x_ticks(fig: &Figure, r: usize, c: usize) -> bool {
    !fig.shared_x || (r + 1..fig.rows).all(|below| fig.cell(below, c).is_none())
}

pub(super) fn show_x_desc(fig: &Figure, r: usize, c: usize) -> bool {
    if fig.shared_x {
        return show_x_ticks(fig, r, c);
    }
    // In a grid: on the lowest row that has panels, and on any panel whose x axis is not the one under it (each
    // criterion of a sweep's histograms has its own unit).
    let last = (0..fig.rows).rev().find(|&row| (0..fig.cols).any(|col| fig.cell(row, col).is_some()));
    let own = fig.cell(r, c).map(|p| p.x_desc.as_str());
    let below = (r + 1..fig.rows).find_map(|row| fig.cell(row, c)).map(|p| p.x_desc.as_str());
    Some(r) == last || below.is_none() || below != own
}

/// The largest font size, at most [`TITLE_SIZE`] and at least 12 pt, at which `title` fits `width` pixels less the
/// margins: a long scenario description shrinks the title rather than running past the figure's edges.
pub(super) fn title_size(title: &str, width: u32) -> f64 {
    let room = width.saturating_sub(4 * PAD);
    let mut size = TITLE_SIZE;
    while size > 12.0 && text_size(title, size).0 > room {
        size -= 1.0;
    }
    size
}

/// Where an event label goes above the plot: a flag on its marker line, starting at the line, or ending there
/// (`flip`) where it would run past the right edge.
#[derive(Clone, Copy, Default)]
pub(super) struct EventLabel {
    pub(super) row: usize,
    pub(super) flip: bool,
}

/// Place event labels in rows above a plot `plot_w` pixels wide. Labels are placed from the latest event back, each
/// on the lowest row where it clears the labels already there; as those start further right, the line that joins a
/// higher label to the plot never crosses a lower label.
pub(super) fn place_event_labels(events: &[(f64, String)], x: &Axis, plot_w: u32) -> Vec<EventLabel> {
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

pub(super) fn in_range(events: &[(f64, String)], x: &Axis) -> Vec<(f64, String)> {
    events.iter().filter(|(t, _)| *t >= x.lo && *t <= x.hi).cloned().collect()
}

pub(super) fn layout(fig: &Figure) -> Layout {
    let (w, h) = fig.size;
    let title_size = title_size(&fig.title, w);
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

    let x_ranges: Vec<Option<(f64, f64)>> = fig.cells.iter().map(|p| p.as_ref().map(Panel::x_range)).collect();
    let (row_top, row_bottom) = row_bands(fig, &x_ranges, cell_w);
    let fixed: u32 = row_top.iter().sum::<u32>() + row_bottom.iter().sum::<u32>();
    let row_plot_h = (body_h.saturating_sub(fixed) / fig.rows as u32).max(40);

    let y_target = ((row_plot_h / 55) as usize).clamp(3, 8);
    let y_axes: Vec<Option<Axis>> = fig
        .cells
        .iter()
        .map(|p| {
            p.as_ref().map(|p| {
                let (lo, hi) = p.y_range();
                match (p.y_log, p.series.iter().any(|s| s.bar_width.is_some())) {
                    // Bars on a log axis count things: no tick at a fraction of one.
                    (true, true) => Axis::decades(lo, hi).without_ticks_below(1.0),
                    (true, false) => Axis::decades(lo, hi),
                    (false, _) => Axis::linear(lo, hi, y_target),
                }
            })
        })
        .collect();
    let (col_left, col_legend) = column_bands(fig, &y_axes, row_plot_h);
    let axes = cell_axes(fig, &x_ranges, y_axes, cell_w, &col_left, &col_legend);
    Layout {
        title_size,
        title_h,
        top_legend,
        top_legend_h,
        row_top,
        row_bottom,
        row_plot_h,
        col_left,
        col_legend,
        axes,
    }
}

/// Per row, the bands above the plots (captions, event labels) and below them (x ticks, x axis name): the most any
/// panel of the row needs, so that the plots of a row line up.
fn row_bands(fig: &Figure, x_ranges: &[Option<(f64, f64)>], cell_w: u32) -> (Vec<u32>, Vec<u32>) {
    let tick_h = text_size("0123456789", TICK_SIZE).1;
    let desc_h = text_size("t (s)", DESC_SIZE).1;
    // Rows for event labels are reserved for a plot narrower than the real one (its width depends on the y labels,
    // which depend on the plot height), so the labels, placed again at drawing time, need at most as many.
    let guess_w = cell_w.saturating_sub(300).max(100);
    let mut row_top = vec![PAD; fig.rows];
    let mut row_bottom = vec![PAD; fig.rows];
    for r in 0..fig.rows {
        for c in 0..fig.cols {
            let Some(panel) = fig.cell(r, c) else { continue };
            let x_range = x_ranges[r * fig.cols + c];
            row_top[r] = row_top[r].max(band_above(panel, r, x_range, guess_w));
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
    (row_top, row_bottom)
}

/// The band one panel in row `r` needs above its plot: caption, then the rows of event labels.
fn band_above(panel: &Panel, r: usize, x_range: Option<(f64, f64)>, guess_w: u32) -> u32 {
    let caption_h = text_size("(a) Ag", CAPTION_SIZE).1;
    let mut top = PAD;
    if !panel.caption.is_empty() {
        top += caption_h + PAD;
    }
    if r > 0 {
        top += PAD;
    }
    if panel.event_labels {
        let (lo, hi) = x_range.unwrap_or((0.0, 1.0));
        let x = Axis::linear(lo, hi, 5);
        let placed = place_event_labels(&in_range(&panel.events, &x), &x, guess_w);
        top += placed.iter().map(|p| p.row).max().map_or(0, |m| (m as u32 + 1) * EVENT_ROW + PAD / 2);
    }
    top
}

/// Per column, the y label area (widest tick label, axis name) and the widest legend: the most any panel of the
/// column needs, so that the plots of a column line up.
fn column_bands(fig: &Figure, y_axes: &[Option<Axis>], row_plot_h: u32) -> (Vec<u32>, Vec<LegendGrid>) {
    let desc_h = text_size("t (s)", DESC_SIZE).1;
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
    (col_left, col_legend)
}

/// Per cell, its axes. Linear x ticks are spaced for the plot's width, known only once the columns are.
fn cell_axes(
    fig: &Figure,
    x_ranges: &[Option<(f64, f64)>],
    y_axes: Vec<Option<Axis>>,
    cell_w: u32,
    col_left: &[u32],
    col_legend: &[LegendGrid],
) -> Vec<Option<(Axis, Axis)>> {
    let mut axes = Vec::with_capacity(fig.cells.len());
    for (i, (cell, y)) in fig.cells.iter().zip(y_axes).enumerate() {
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
        axes.push(Some((x, y.expect("axis of a panel"))));
    }
    axes
}
