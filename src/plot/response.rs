//! The response figure of any plant: every output the scenario sets a point for, each in a panel of its own over
//! its set point (dashed), in the order the plant announced them, a dimensionless unit left blank and the rows
//! whose outputs the plant held shaded. It is the first figure of a run's page: wide and one row high for up to
//! three outputs, so that it shows beside the verdict on the first screen.

use std::path::Path;

use super::PlotError;
use super::columns::{Columns, zip};
use super::drawn::Drawn;
use super::figure::{Figure, FigureLegend, Panel, Series, palette};
use super::plant_series::{held_spans, measured_outputs, shading_note, time_span, unit_label};
use super::render::write_figure;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;

/// Panels side by side.
const COLUMNS: usize = 3;
/// Width of the figure and height of one row of panels (and of the title and time axis), px.
const WIDTH_PX: u32 = 1500;
const ROW_HEIGHT_PX: u32 = 250;
const FRAME_HEIGHT_PX: u32 = 70;

/// The outputs with a set point, (name, unit), in the announced order; without the announcement (a run with no
/// recording), the trace's columns with a set point, unit-less.
fn with_setpoints(
    trace: &Trace,
    plant: Option<&PlantSignals>,
    setpoint: &dyn Fn(&str) -> Option<f64>,
) -> Vec<(String, String)> {
    let all = match plant {
        Some(p) => measured_outputs(p),
        None => trace.columns.iter().map(|c| (c.clone(), String::new())).collect(),
    };
    all.into_iter().filter(|(name, _)| setpoint(name).is_some()).collect()
}

/// Draw `<stem>.{png,svg}` in `out_dir`: one panel per output with a set point (`setpoint` gives it by name), the
/// output solid over its set point dashed, time on every x axis. A scenario that sets no point for any output has
/// no response to draw (an error naming the plant). Returns the files written and what they were drawn as.
pub fn plot_response(
    trace: &Trace,
    plant: Option<&PlantSignals>,
    setpoint: &dyn Fn(&str) -> Option<f64>,
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Drawn, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let outputs = with_setpoints(trace, plant, setpoint);
    if outputs.is_empty() {
        let plant = plant.map_or("the trace's".to_string(), |p| format!("plant {}'s", p.plant));
        let problem = format!("the scenario sets no point for any of {plant} outputs, so there is no response to draw");
        return Err(PlotError::NoData { file, problem });
    }
    let span = time_span(&t).unwrap_or((0.0, 0.0));
    let held = held_spans(trace);
    let mut cells = Vec::with_capacity(outputs.len());
    for (name, unit) in &outputs {
        let sp = setpoint(name).unwrap_or(f64::NAN);
        let series = vec![
            Series::solid(name, zip(&t, &data.get(name)?), palette(0)),
            Series::level("set point", sp, span, palette(3)),
        ];
        let mut panel = Panel::new(&format!("{name}: set point {sp} (dashed)"), unit_label(unit), series);
        panel.legend = false;
        panel.shaded = held.clone();
        panel.x_span = Some(span);
        cells.push(Some(panel));
    }
    // Up to four outputs in one row (the quadrotor's attitude and altitude), then rows of three.
    let cols = if cells.len() <= 4 { cells.len() } else { COLUMNS };
    let rows = cells.len().div_ceil(cols);
    cells.resize_with(rows * cols, || None);
    let size = (WIDTH_PX, FRAME_HEIGHT_PX + ROW_HEIGHT_PX * rows as u32);
    let title = format!("{title}{}", shading_note(&held));
    let mut fig = Figure::grid(&title, size, rows, cols, cells, FigureLegend::None);
    fig.shared_x = false;
    write_figure(&fig, out_dir, stem)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant_series::tests::cart;

    #[test]
    fn one_panel_per_output_with_a_set_point_over_it_and_none_without_one() {
        let p = cart();
        let names = ["t_s", "x_m", "v_mps", "steer_cmd_deg", "throttle_cmd", "steer_deg"];
        let mut trace = Trace::new(names.map(String::from).to_vec());
        trace.rows = (0..100).map(|k| vec![k as f64 * 0.01, 0.02 * k as f64, 1.0, 0.0, 0.5, 0.0]).collect();
        let dir = std::env::temp_dir().join(format!("silrig-plot-response-{}", std::process::id()));
        let setpoint = |n: &str| match n {
            "x_m" => Some(2.0),
            "v_mps" => Some(1.0),
            // A position is not a response: the steering wheel's set point is ignored.
            "steer_deg" => Some(3.0),
            _ => None,
        };
        let drawn = plot_response(&trace, Some(&p), &setpoint, &dir, "response", "cart").unwrap();
        let fig = drawn.figure("response").unwrap();
        let captions: Vec<&str> = fig.panels.iter().map(|p| p.caption.as_str()).collect();
        assert_eq!(captions, ["x_m: set point 2 (dashed)", "v_mps: set point 1 (dashed)"]);
        assert_eq!((fig.panels[0].y_label.as_str(), fig.panels[1].y_label.as_str()), ("m", "m/s"));
        assert!(fig.panels.iter().all(|p| p.series == ["x_m", "set point"] || p.series == ["v_mps", "set point"]));
        let err = plot_response(&trace, Some(&p), &|_: &str| None, &dir, "none", "cart").unwrap_err().to_string();
        assert!(err.contains("sets no point for any of plant cart's outputs"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
