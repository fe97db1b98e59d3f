//! The figure of any plant: one small panel per measured output (its set point dashed where the scenario gives
//! one) and one per input (its command dashed over the position it moves, where the plant reports one), in the
//! order the plant announced them, a dimensionless unit left blank and the rows whose outputs the plant held
//! shaded. The closed-loop figures show the F-16's states; this one shows whatever a plant of your own calls its
//! signals.

use std::path::Path;

use super::PlotError;
use super::columns::{Columns, zip};
use super::drawn::Drawn;
use super::figure::{Figure, FigureLegend, Panel, Series, palette};
use super::plant_series::{held_spans, input_lines, measured_outputs, shading_note, time_span, unit_label};
use super::render::write_figure;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::{OUTPUTS_HELD_COLUMN, Trace};

/// Panels side by side: three, four past 24 panels, so up to 48 stay readable on one page.
fn columns_for(panels: usize) -> usize {
    if panels > 24 { 4 } else { 3 }.min(panels.max(1))
}

/// Height of one row of panels, px.
const ROW_HEIGHT_PX: u32 = 230;

/// One line of a panel: a trace column, drawn solid (a measurement, a position) or dashed (a command).
struct Line {
    column: String,
    label: String,
    command: bool,
}

/// One panel: its caption, the axis label of its unit, its lines and the set point it is held to.
struct Signal {
    caption: String,
    unit: String,
    lines: Vec<Line>,
    setpoint: Option<f64>,
}

/// What to draw: with the plant's announcement, its measured outputs then its inputs (position and command
/// together); without it (a run with no recording), every trace column but time, the flight segment and the held
/// flag, unit-less.
fn signals(trace: &Trace, plant: Option<&PlantSignals>, setpoint: &dyn Fn(&str) -> Option<f64>) -> Vec<Signal> {
    let line = |column: &str, label: &str, command| Line { column: column.into(), label: label.into(), command };
    let Some(p) = plant else {
        return trace
            .columns
            .iter()
            .filter(|c| !["t_s", "flight_segment", OUTPUTS_HELD_COLUMN].contains(&c.as_str()))
            .map(|c| Signal {
                caption: c.clone(),
                unit: String::new(),
                lines: vec![line(c, c, false)],
                setpoint: setpoint(c),
            })
            .collect();
    };
    let outputs = measured_outputs(p).into_iter().map(|(name, unit)| Signal {
        caption: name.clone(),
        unit: unit_label(&unit).into(),
        setpoint: setpoint(&name),
        lines: vec![line(&name, &name, false)],
    });
    let inputs = input_lines(p).into_iter().map(|i| {
        let caption = match i.position {
            Some(_) => format!("{}: position, command dashed", i.name),
            None => format!("{} command", i.name),
        };
        let mut lines: Vec<Line> = i.position.iter().map(|c| line(c, &i.name, false)).collect();
        lines.extend(i.command.iter().map(|c| line(c, &format!("{} command", i.name), true)));
        Signal { caption, unit: unit_label(&i.unit).into(), lines, setpoint: None }
    });
    outputs.chain(inputs).collect()
}

/// Draw `<stem>.{png,svg}` in `out_dir`: a grid of panels, one per signal (see [`signals`]), time on every x axis.
/// `setpoint` gives an output's set point by name. Returns the files written.
pub fn plot_signals(
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
    let wanted = signals(trace, plant, setpoint);
    if wanted.is_empty() {
        return Err(PlotError::NoData { file, problem: "the trace has no signal columns".into() });
    }
    let held = held_spans(trace);
    let mut cells = Vec::with_capacity(wanted.len());
    for s in &wanted {
        let mut series = Vec::with_capacity(s.lines.len() + 1);
        for l in &s.lines {
            let points = zip(&t, &data.get(&l.column)?);
            series.push(match l.command {
                true => Series::command(&l.label, points, palette(1)),
                false => Series::solid(&l.label, points, palette(0)),
            });
        }
        if let Some(sp) = s.setpoint {
            series.push(Series::level("set point", sp, time_span(&t).unwrap_or((0.0, 0.0)), palette(3)));
        }
        let caption = match s.setpoint {
            Some(sp) => format!("{} (set point {sp}, dashed)", s.caption),
            None => s.caption.clone(),
        };
        let mut panel = Panel::new(&caption, &s.unit, series);
        panel.legend = false;
        panel.shaded = held.clone();
        panel.x_span = time_span(&t);
        cells.push(Some(panel));
    }
    let cols = columns_for(cells.len());
    let rows = cells.len().div_ceil(cols);
    cells.resize_with(rows * cols, || None);
    let size = (1500, 90 + ROW_HEIGHT_PX * rows as u32);
    let mut fig = Figure::grid(&format!("{title}{}", shading_note(&held)), size, rows, cols, cells, FigureLegend::None);
    // Every panel keeps its own time labels: a grid this dense is read panel by panel.
    fig.shared_x = false;
    write_figure(&fig, out_dir, stem)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant_series::tests::cart;

    #[test]
    fn a_panel_per_measured_output_and_per_input_with_its_position_set_points_and_blank_dimensionless_units() {
        let p = cart();
        let setpoint = |name: &str| (name == "x_m").then_some(4.0);
        let trace = Trace::new(vec![]);
        let s = signals(&trace, Some(&p), &setpoint);
        let columns: Vec<Vec<&str>> = s.iter().map(|s| s.lines.iter().map(|l| l.column.as_str()).collect()).collect();
        assert_eq!(columns, [vec!["x_m"], vec!["v_mps"], vec!["steer_deg", "steer_cmd_deg"], vec!["throttle_cmd"]]);
        assert_eq!((s[0].setpoint, s[0].unit.as_str(), s[1].setpoint), (Some(4.0), "m", None));
        assert_eq!((s[2].unit.as_str(), s[3].unit.as_str()), ("deg", ""), "a dimensionless unit is left blank");
        assert!(!s[2].lines[0].command && s[2].lines[1].command && s[3].lines[0].command);
        assert_eq!(s[2].caption, "steer: position, command dashed");
        // Without the announcement: every column but time, the segment and the held flag.
        let bare = Trace::new(
            ["t_s", "x_m", "steer_cmd_deg", "flight_segment", OUTPUTS_HELD_COLUMN].map(String::from).to_vec(),
        );
        let columns: Vec<String> = signals(&bare, None, &setpoint).into_iter().map(|s| s.caption).collect();
        assert_eq!(columns, ["x_m", "steer_cmd_deg"]);
    }

    #[test]
    fn the_figure_is_drawn_with_nan_rows_as_breaks_and_held_rows_shaded() {
        let p = cart();
        let names = [
            "t_s",
            "x_m",
            "v_mps",
            "steer_cmd_deg",
            "throttle_cmd",
            "steer_deg",
            "flight_segment",
            OUTPUTS_HELD_COLUMN,
        ];
        let mut trace = Trace::new(names.map(String::from).to_vec());
        trace.rows = (0..200)
            .map(|k| {
                let t = k as f64 * 0.01;
                let cmd = if (50..60).contains(&k) { f64::NAN } else { (t * 3.0).sin() };
                let held = if (120..150).contains(&k) { 1.0 } else { 0.0 };
                vec![t, 4.0 * t, 4.0, cmd, 0.5, 0.9 * cmd, 0.0, held]
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("silrig-plot-signals-{}", std::process::id()));
        let files =
            plot_signals(&trace, Some(&p), &|n: &str| (n == "x_m").then_some(4.0), &dir, "signals", "t").unwrap();
        assert_eq!(files.len(), 2);
        let png = std::fs::read(&files[0]).unwrap();
        assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000, "{} bytes", png.len());
        let svg = std::fs::read_to_string(&files[1]).unwrap();
        assert!(svg.contains("shaded: outputs held"), "the title does not say what the shading is");
        assert!(svg.contains("rgb(236,226,214)") || svg.contains("#ECE2D6"), "no shaded span in the SVG");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
