//! Rendering: draws a laid-out figure with one backend-generic routine on the bitmap and the SVG backend, registers
//! the embedded font, and writes the PNG and SVG files.

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

use super::PlotError;
use super::axis::Axis;
use super::drawn::{Drawn, describe};
use super::figure::{Dash, Figure, FigureLegend, LegendEntry, Panel, clip_to_y, segments, y_axis_value};
use super::layout::{
    CAPTION_SIZE, DESC_SIZE, EVENT_ROW, EVENT_SIZE, FLAG_GAP, LEGEND_ROW, LEGEND_SAMPLE, LEGEND_SIZE, Layout,
    LegendGrid, PAD, TICK_MARK, TICK_SIZE, font, in_range, layout, place_event_labels, show_x_desc, show_x_ticks,
    text_size,
};

/// Event markers and their labels.
const EVENT_COLOR: RGBColor = RGBColor(190, 30, 30);
/// Shaded spans: a light warm grey that every palette colour stays readable on.
const SHADE_COLOR: RGBColor = RGBColor(236, 226, 214);
/// Event windows (a fault from start to end): the event colour, light enough to read every line over it.
const WINDOW_COLOR: RGBColor = RGBColor(250, 218, 218);

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<Axis, Axis>>;

/// A plot's edges (left, top, right, bottom) in the pixels of its cell.
type PlotRect = (i32, i32, i32, i32);

fn draw_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure, lay: &Layout) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let title_style = font(lay.title_size).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
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
    let (x, y) = lay.axes[r * fig.cols + c].clone().expect("axes of a panel");
    let legend_w = lay.col_legend[c].width();
    let mut chart = ChartBuilder::on(area)
        .margin_top(lay.row_top[r])
        .margin_right(legend_w + 2 * PAD)
        .margin_left(PAD)
        .x_label_area_size(lay.row_bottom[r])
        .y_label_area_size(lay.col_left[c])
        .build_cartesian_2d(x.clone(), y.clone())?;
    draw_mesh(&mut chart, fig, panel, r, c, (&x, &y))?;
    let events = in_range(&panel.events, &x);
    draw_data(&mut chart, panel, &events, (&x, &y))?;

    // Frame the plot, then caption, event labels and legend, in this area's pixels.
    let (px, py) = chart.plotting_area().get_pixel_range();
    let (bx, by) = area.get_base_pixel();
    let plot = (px.start - bx, py.start - by, px.end - bx, py.end - by);
    let (left, top, right, bottom) = plot;
    area.draw(&Rectangle::new([(left, top), (right - 1, bottom - 1)], BLACK.mix(0.85).stroke_width(1)))?;

    if !panel.caption.is_empty() {
        let style = font(CAPTION_SIZE).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
        let y = if r > 0 { 2 * PAD } else { PAD };
        area.draw_text(&panel.caption, &style, ((left + right) / 2, y as i32))?;
    }
    if panel.event_labels {
        draw_event_labels(area, &events, &x, plot)?;
    }
    if legend_w > 0 && panel.legend {
        let entries = panel.legend_entries();
        let grid = LegendGrid::fitting_height(&entries, lay.row_plot_h);
        let (aw, _) = area.dim_in_pixel();
        let x0 = (aw as i32 - legend_w as i32 - PAD as i32).max(right + PAD as i32);
        draw_legend(area, &entries, &grid, (x0, top))?;
    }
    Ok(())
}

/// Grid, ticks and axis names. The ticks are the axes' own; x tick labels only where the layout shows them.
fn draw_mesh<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    fig: &Figure,
    panel: &Panel,
    r: usize,
    c: usize,
    (x, y): (&Axis, &Axis),
) -> DrawResult<DB> {
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
    mesh.draw()
}

/// Inside the plot: the zero line, the event markers, then the series over them.
fn draw_data<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    panel: &Panel,
    events: &[(f64, String)],
    (x, y): (&Axis, &Axis),
) -> DrawResult<DB> {
    // Shading first, under everything, cut to the time axis.
    for (from, to) in &panel.shaded {
        let (from, to) = (from.max(x.lo), to.min(x.hi));
        if from < to {
            chart.draw_series(std::iter::once(Rectangle::new([(from, y.lo), (to, y.hi)], SHADE_COLOR.filled())))?;
        }
    }
    for (from, to) in &panel.windows {
        let (from, to) = (from.max(x.lo), to.min(x.hi));
        if from < to {
            chart.draw_series(std::iter::once(Rectangle::new([(from, y.lo), (to, y.hi)], WINDOW_COLOR.filled())))?;
        }
    }
    // Zero line, when zero is inside a range that is not all positive (a log axis has no zero).
    if !panel.y_log && y.lo < 0.0 && y.hi > 0.0 {
        chart.draw_series(std::iter::once(PathElement::new(vec![(x.lo, 0.0), (x.hi, 0.0)], BLACK.mix(0.35))))?;
    }

    for (t, _) in events {
        chart.draw_series(DashedLineSeries::new(vec![(*t, y.lo), (*t, y.hi)], 6, 4, EVENT_COLOR.stroke_width(2)))?;
    }

    for series in &panel.series {
        let style = series.stroke.style();
        let on_axis: Vec<(f64, f64)> =
            series.points.iter().map(|&(px, py)| (px, y_axis_value(panel.y_log, py, y.lo))).collect();
        if let Some(width) = series.bar_width {
            // From the axis' bottom on a log axis (no zero there), from zero on a linear one.
            let base = if panel.y_log { y.lo } else { 0.0f64.clamp(y.lo, y.hi) };
            draw_bars(chart, &on_axis, width, series.stroke.color, base)?;
            continue;
        }
        let points = if series.sets_y_range { on_axis } else { clip_to_y(&on_axis, y.lo, y.hi) };
        for seg in segments(&points) {
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
    Ok(())
}

/// Bars from `base` to each point's height, `width` wide from its x, filled half-transparent so that the bars of
/// several series over the same x stay visible, outlined in their colour.
fn draw_bars<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    points: &[(f64, f64)],
    width: f64,
    color: RGBColor,
    base: f64,
) -> DrawResult<DB> {
    let bars = points.iter().filter(|(x, y)| x.is_finite() && y.is_finite()).map(|&(x, y)| [(x, base), (x + width, y)]);
    chart.draw_series(bars.clone().map(|corners| Rectangle::new(corners, color.mix(0.45).filled())))?;
    chart.draw_series(bars.map(|corners| Rectangle::new(corners, color.stroke_width(1))))?;
    Ok(())
}

/// Event labels above the plot, each a flag on a line down to the plot, in the rows `place_event_labels` chooses.
fn draw_event_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    events: &[(f64, String)],
    x: &Axis,
    (left, top, right, _): PlotRect,
) -> DrawResult<DB> {
    let color = EVENT_COLOR;
    let placed = place_event_labels(events, x, (right - left).max(1) as u32);
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

static DEJAVU_SANS: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

/// Register the embedded font as plotters' "sans-serif", once per process.
fn ensure_font(file: &Path) -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS).is_ok());
    if ok { Ok(()) } else { Err(PlotError::Font { file: file.to_path_buf() }) }
}

/// Encode an 8-bit RGB buffer as a PNG file. (The `png` crate directly, rather than plotters' `bitmap_encoder`
/// feature, which pulls in the whole `image` crate: the largest single crate of a clean build.)
fn write_png(file: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<(), PlotError> {
    let out = std::fs::File::create(file).map_err(|cause| PlotError::Write { file: file.to_path_buf(), cause })?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(out), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let encoded = encoder.write_header().and_then(|mut writer| {
        writer.write_image_data(rgb)?;
        writer.finish()
    });
    encoded.map_err(|e| match e {
        png::EncodingError::IoError(cause) => PlotError::Write { file: file.to_path_buf(), cause },
        other => PlotError::Draw { file: file.to_path_buf(), message: format!("PNG encoding: {other}") },
    })
}

/// Draw `fig` as `<stem>.png` and `<stem>.svg` in `out_dir`; returns both paths and what the figure was drawn as.
pub(super) fn write_figure(fig: &Figure, out_dir: &Path, stem: &str) -> Result<Drawn, PlotError> {
    let png = out_dir.join(format!("{stem}.png"));
    let svg = out_dir.join(format!("{stem}.svg"));
    ensure_font(&png)?;
    std::fs::create_dir_all(out_dir).map_err(|cause| PlotError::CreateDir { dir: out_dir.to_path_buf(), cause })?;
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
    std::fs::write(&svg, text).map_err(|cause| PlotError::Write { file: svg.clone(), cause })?;
    Ok(describe(fig, &lay, stem, vec![png, svg]))
}
