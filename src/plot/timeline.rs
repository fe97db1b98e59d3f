//! The fault timeline of any plant: the outputs the scenario sets a point for (each over its set point, dashed),
//! then the inputs (each command dashed over the position it moves, where the plant reports one), one panel per
//! unit, against time, with a marker and a label at every event, each fault's window from its start to its end
//! shaded red, and the rows whose outputs the plant held shaded grey.

use std::path::Path;

use super::columns::{Columns, zip};
use super::drawn::Drawn;
use super::figure::{Figure, Panel, Series, palette};
use super::plant_series::{InputLines, held_spans, input_lines, measured_outputs, shading_note, time_span, unit_label};
use super::render::write_figure;
use super::{PlotError, TimelineEvent};
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;

/// Height of the figure's title and time axis, and of each panel, px.
const FRAME_HEIGHT_PX: u32 = 160;
const PANEL_HEIGHT_PX: u32 = 260;

/// Draw `<stem>.{png,svg}` in `out_dir` for `plant`'s trace: the outputs with a set point (`setpoint` gives it by
/// name; every measured output where none has one) above, the inputs below, each group one panel per unit, with a
/// dashed vertical line at every event (every panel) and its label above the top panel. Events outside the trace's
/// time span are left out. Returns the files written.
pub fn plot_timeline(
    trace: &Trace,
    plant: &PlantSignals,
    setpoint: &dyn Fn(&str) -> Option<f64>,
    events: &[TimelineEvent],
    out_dir: &Path,
    stem: &str,
    title: &str,
) -> Result<Drawn, PlotError> {
    let file = out_dir.join(format!("{stem}.png"));
    let data = Columns::new(trace, &file, "the trace")?;
    let t = data.get("t_s")?;
    let mut panels = output_panels(&data, &t, plant, setpoint)?;
    panels.extend(input_panels(&data, &t, &input_lines(plant))?);
    if panels.is_empty() {
        return Err(PlotError::NoData { file, problem: format!("plant {} has no traced signal", plant.plant) });
    }
    let finite: Vec<&TimelineEvent> = events.iter().filter(|e| e.t_s.is_finite()).collect();
    let marks: Vec<(f64, String)> = finite.iter().map(|e| (e.t_s, e.label.clone())).collect();
    let t_end = t.last().copied().unwrap_or(0.0);
    let windows: Vec<(f64, f64)> =
        finite.iter().filter_map(|e| e.end_s.map(|end| (e.t_s, if end.is_finite() { end } else { t_end }))).collect();
    let held = held_spans(trace);
    for panel in &mut panels {
        panel.events = marks.clone();
        panel.windows = windows.clone();
        panel.shaded = held.clone();
        panel.x_span = time_span(&t);
    }
    panels[0].event_labels = true;
    let size = (1200, FRAME_HEIGHT_PX + PANEL_HEIGHT_PX * panels.len() as u32);
    let windows_note = if windows.is_empty() { "" } else { "; red bands: each fault from start to end" };
    let fig = Figure::stacked(&format!("{title}{windows_note}{}", shading_note(&held)), size, panels);
    write_figure(&fig, out_dir, stem)
}

/// The outputs with a set point (all measured outputs where none has one), each solid over its set point dashed in
/// its colour, one panel per unit in the order the units first come.
fn output_panels(
    data: &Columns,
    t: &[f64],
    plant: &PlantSignals,
    setpoint: &dyn Fn(&str) -> Option<f64>,
) -> Result<Vec<Panel>, PlotError> {
    let measured = measured_outputs(plant);
    let with_setpoint: Vec<_> = measured.iter().filter(|(name, _)| setpoint(name).is_some()).cloned().collect();
    let (shown, caption) = match with_setpoint.is_empty() {
        true => (measured, "outputs"),
        false => (with_setpoint, "outputs (solid) and their set points (dashed)"),
    };
    let span = time_span(t).unwrap_or((0.0, 0.0));
    let mut panels: Vec<(String, Panel)> = Vec::new();
    for (k, (name, unit)) in shown.iter().enumerate() {
        let mut series = vec![Series::solid(name, zip(t, &data.get(name)?), palette(k))];
        if let Some(sp) = setpoint(name) {
            series.push(Series::level(&format!("{name} set point"), sp, span, palette(k)));
        }
        add_to_unit_panel(&mut panels, unit_label(unit), caption, series);
    }
    Ok(panels.into_iter().map(|(_, p)| p).collect())
}

/// The inputs, each position solid and its command dashed in one colour (the command kept within the positions'
/// range where there are positions, as fig1 does, so a command far past the stops does not flatten them), one
/// panel per unit.
fn input_panels(data: &Columns, t: &[f64], inputs: &[InputLines]) -> Result<Vec<Panel>, PlotError> {
    let mut panels: Vec<(String, Panel)> = Vec::new();
    for unit in inputs.iter().map(|i| unit_label(&i.unit)) {
        if panels.iter().any(|(u, _)| u == unit) {
            continue;
        }
        let group: Vec<&InputLines> = inputs.iter().filter(|i| unit_label(&i.unit) == unit).collect();
        let positions = group.iter().any(|i| i.position.is_some());
        let mut series = Vec::new();
        for (k, i) in group.iter().enumerate() {
            if let Some(column) = &i.position {
                series.push(Series::solid(&i.name, zip(t, &data.get(column)?), palette(k)));
            }
            if let Some(column) = &i.command {
                let command = Series::command(&format!("{} cmd", i.name), zip(t, &data.get(column)?), palette(k));
                series.push(if positions { command.within_others_range() } else { command });
            }
        }
        let commands = group.iter().any(|i| i.command.is_some());
        let caption = match (positions, commands) {
            (true, true) => "inputs: position (solid), command (dashed, cut at the edges)",
            (true, false) => "inputs: position",
            _ => "inputs: command (dashed)",
        };
        add_to_unit_panel(&mut panels, unit, caption, series);
    }
    Ok(panels.into_iter().map(|(_, p)| p).collect())
}

/// Add `series` to the panel of `unit`, or start one with `caption`.
fn add_to_unit_panel(panels: &mut Vec<(String, Panel)>, unit: &str, caption: &str, series: Vec<Series>) {
    match panels.iter_mut().find(|(u, _)| u == unit) {
        Some((_, panel)) => panel.series.extend(series),
        None => panels.push((unit.to_string(), Panel::new(caption, unit, series))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant_series::tests::cart;
    use silrig_flight::trace::OUTPUTS_HELD_COLUMN;

    fn cart_trace() -> Trace {
        let names = ["t_s", "x_m", "v_mps", "steer_cmd_deg", "throttle_cmd", "steer_deg", "flight_segment"];
        let mut trace = Trace::new(names.iter().map(|s| s.to_string()).chain([OUTPUTS_HELD_COLUMN.into()]).collect());
        trace.rows = (0..300)
            .map(|k| {
                let t = k as f64 * 0.01;
                let held = if (100..130).contains(&k) { 1.0 } else { 0.0 };
                let steer_cmd_deg = 40.0 * (t * 2.0).sin();
                vec![t, t.min(2.0), 1.0, steer_cmd_deg, 0.5, steer_cmd_deg.clamp(-15.0, 15.0), 0.0, held]
            })
            .collect();
        trace
    }

    #[test]
    fn set_point_outputs_above_and_inputs_by_unit_below_with_commands_beside_positions() {
        let (p, trace) = (cart(), cart_trace());
        let data = Columns::new(&trace, Path::new("/nonexistent/f.png"), "the trace").unwrap();
        let t = data.get("t_s").unwrap();
        let outputs = output_panels(&data, &t, &p, &|n: &str| (n == "x_m").then_some(2.0)).unwrap();
        assert_eq!(outputs.len(), 1, "only the output with a set point");
        let labels: Vec<&str> = outputs[0].series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["x_m", "x_m set point"]);
        // No set point at all: every measured output, one panel per unit.
        let all = output_panels(&data, &t, &p, &|_: &str| None).unwrap();
        assert_eq!(all.iter().map(|p| p.y_desc.as_str()).collect::<Vec<_>>(), ["m", "m/s"]);
        let inputs = input_panels(&data, &t, &input_lines(&p)).unwrap();
        assert_eq!(inputs.iter().map(|p| p.y_desc.as_str()).collect::<Vec<_>>(), ["deg", ""], "dimensionless blank");
        let steer: Vec<(&str, bool)> = inputs[0].series.iter().map(|s| (s.label.as_str(), s.sets_y_range)).collect();
        assert_eq!(steer, [("steer", true), ("steer cmd", false)], "the command is kept within the position's range");
        let (lo, hi) = inputs[0].y_range();
        assert!(lo > -20.0 && hi < 20.0, "the 40 deg command widened the panel: {lo}..{hi}");
    }

    #[test]
    fn the_timeline_of_a_plant_that_is_not_the_f16_is_drawn_with_its_events_and_held_rows() {
        let dir = std::env::temp_dir().join(format!("silrig-plot-timeline-{}", std::process::id()));
        let events = [TimelineEvent { t_s: 1.0, label: "controller kill".into(), end_s: Some(1.4) }];
        let files =
            plot_timeline(&cart_trace(), &cart(), &|n: &str| (n == "x_m").then_some(2.0), &events, &dir, "faults", "t")
                .unwrap();
        let svg = std::fs::read_to_string(&files[1]).unwrap();
        for needle in ["controller kill", "x_m set point", "steer cmd", "throttle cmd", "shaded: outputs held"] {
            assert!(svg.contains(needle), "faults.svg lacks {needle:?}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
