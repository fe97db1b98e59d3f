//! What every figure of a plant draws from its announcement rather than from the F-16's column names: the axis
//! label of a unit (a dimensionless one left blank), each input's command beside the position it moves (where the
//! plant reports one), the outputs that are measurements rather than positions, and the time spans of the rows
//! whose outputs the plant held (the trace's `outputs_held`), which the figures shade.

use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::{OUTPUTS_HELD_COLUMN, Trace};

/// A set point's history by an output's name, `None` for an output without one (what the figures draw dashed).
pub type SetpointOf<'a> = dyn Fn(&str) -> Option<SetpointTrack> + 'a;

/// A set point's line over `span` (the trace's first and last time): flat, or a staircase rising or falling at each
/// step inside the span (two points at a step's time, the value before and after).
pub(super) fn setpoint_line(track: &SetpointTrack, span: [f64; 2]) -> Vec<(f64, f64)> {
    let mut points = vec![(span[0], track.at(span[0]))];
    for s in track.segments().iter().filter(|s| s.from_s > span[0] && s.from_s <= span[1]) {
        let before = points.last().expect("starts with one").1;
        points.extend([(s.from_s, before), (s.from_s, s.value)]);
    }
    points.push((span[1], track.at(span[1])));
    points
}

/// A set point as a panel's caption says it: `4` held, `0, 10 from 2 s` with its steps.
pub(super) fn setpoint_words(track: &SetpointTrack) -> String {
    let steps = track.segments()[1..].iter().map(|s| format!(", {} from {} s", s.value, s.from_s));
    std::iter::once(track.segments()[0].value.to_string()).chain(steps).collect()
}

/// The y axis label of `unit`: blank for a dimensionless one (`1`, or none), the unit otherwise.
pub(super) fn unit_label(unit: &str) -> &str {
    if unit == "1" { "" } else { unit }
}

/// One input as a figure draws it: its command (dashed) over the position it moves (solid), each a trace column
/// where the trace has it.
pub(super) struct InputLines {
    pub(super) name: String,
    pub(super) unit: String,
    pub(super) command: Option<String>,
    pub(super) position: Option<String>,
}

/// Every input whose command or position the trace holds, in the announced order.
pub(super) fn input_lines(plant: &PlantSignals) -> Vec<InputLines> {
    (0..plant.inputs.len())
        .map(|k| {
            let input = &plant.inputs[k];
            let position = input.held_output.map(|o| &plant.outputs[o]).filter(|o| o.in_trace);
            InputLines {
                name: input.name.clone(),
                unit: input.unit.clone(),
                command: input.command_in_trace.then(|| plant.command_column(k)),
                position: position.map(|o| o.name.clone()),
            }
        })
        .filter(|i| i.command.is_some() || i.position.is_some())
        .collect()
}

/// The traced outputs that are measurements, not an input's position: (name, unit), in the announced order.
pub(super) fn measured_outputs(plant: &PlantSignals) -> Vec<(String, String)> {
    let position = |k: usize| plant.inputs.iter().any(|i| i.held_output == Some(k));
    (0..plant.outputs.len())
        .filter(|k| plant.outputs[*k].in_trace && !position(*k))
        .map(|k| (plant.outputs[k].name.clone(), plant.outputs[k].unit.clone()))
        .collect()
}

/// The time spans of the rows whose outputs were held: each run of consecutive flagged rows, from its first row's
/// time to the next row's (one period past the last row at the trace's end). None without the column.
pub(super) fn held_spans(trace: &Trace) -> Vec<(f64, f64)> {
    let (Some(t), Some(held)) = (trace.column("t_s"), trace.column(OUTPUTS_HELD_COLUMN)) else { return Vec::new() };
    let period = |k: usize| if k > 0 { t[k] - t[k - 1] } else { 0.0 };
    let end_of = |k: usize| t.get(k + 1).copied().unwrap_or_else(|| t[k] + period(k));
    let mut spans: Vec<(f64, f64)> = Vec::new();
    for k in (0..t.len()).filter(|k| held[*k] == 1.0) {
        match spans.last_mut() {
            Some(last) if last.1 == t[k] => last.1 = end_of(k),
            _ => spans.push((t[k], end_of(k))),
        }
    }
    spans
}

/// The trace's time span, which every panel of a plant's figure shows (a command that stops coming early, from a
/// killed controller, leaves its panel's data shorter than the flight).
pub(super) fn time_span(t: &[f64]) -> Option<(f64, f64)> {
    Some((*t.first()?, *t.last()?))
}

/// The text a caption adds when rows are shaded.
pub(super) fn shading_note(spans: &[(f64, f64)]) -> &'static str {
    if spans.is_empty() { "" } else { "; shaded: outputs held (refused NaN or infinity)" }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use silrig_flight::scenario::Scenario;
    use silrig_flight::signals::{InputSignal, OutputSignal};

    #[test]
    fn a_set_point_is_drawn_flat_or_as_steps_inside_the_span_and_captioned_with_them() {
        assert_eq!(setpoint_line(&SetpointTrack::constant(4.0), [0.0, 6.0]), [(0.0, 4.0), (6.0, 4.0)]);
        let text = "name = \"s\"\n[setpoint]\nx_m = 1.0\n[[setpoint_steps]]\nat_s = 2.0\nx_m = 3.0\n\
                    [[setpoint_steps]]\nat_s = 5.0\nx_m = -1.0\n[timing]\ndt_s = 0.01\nduration_s = 8.0\n\
                    command_timing = \"next-tick\"\n";
        let track = Scenario::from_toml(text, "test").unwrap().setpoint_track("x_m").unwrap();
        let line = setpoint_line(&track, [0.0, 6.0]);
        assert_eq!(line, [(0.0, 1.0), (2.0, 1.0), (2.0, 3.0), (5.0, 3.0), (5.0, -1.0), (6.0, -1.0)]);
        // A span the first step does not reach (a run cut short) draws what was in force.
        assert_eq!(setpoint_line(&track, [0.0, 1.5]), [(0.0, 1.0), (1.5, 1.0)]);
        assert_eq!(setpoint_words(&track), "1, 3 from 2 s, -1 from 5 s");
        assert_eq!(setpoint_words(&SetpointTrack::constant(4.0)), "4");
    }

    /// A plant that is not the F-16: a cart with a steered, reported wheel and an unreported dimensionless throttle.
    pub(crate) fn cart() -> PlantSignals {
        let output = |name: &str, unit: &str| OutputSignal { name: name.into(), unit: unit.into(), in_trace: true };
        let input = |name: &str, unit: &str, held_output| InputSignal {
            name: name.into(),
            unit: unit.into(),
            min: -1.0,
            max: 1.0,
            hold: 0.0,
            held_output,
            command_in_trace: true,
        };
        PlantSignals {
            plant: "cart".into(),
            outputs: vec![output("x_m", "m"), output("v_mps", "m/s"), output("steer_deg", "deg")],
            inputs: vec![input("steer", "deg", Some(2)), input("throttle", "1", None)],
        }
    }

    #[test]
    fn commands_sit_beside_the_positions_they_move_and_positions_are_not_measurements() {
        let p = cart();
        let lines = input_lines(&p);
        assert_eq!(lines.len(), 2);
        assert_eq!(
            (lines[0].command.as_deref(), lines[0].position.as_deref()),
            (Some("steer_cmd_deg"), Some("steer_deg"))
        );
        assert_eq!((lines[1].command.as_deref(), lines[1].position.as_deref()), (Some("throttle_cmd"), None));
        let measured: Vec<String> = measured_outputs(&p).into_iter().map(|(n, _)| n).collect();
        assert_eq!(measured, ["x_m", "v_mps"]);
        assert_eq!((unit_label("1"), unit_label(""), unit_label("deg")), ("", "", "deg"));
    }

    #[test]
    fn held_rows_become_spans_to_the_next_row() {
        let mut trace = Trace::new(vec!["t_s".into(), "x".into(), OUTPUTS_HELD_COLUMN.into()]);
        let held = [0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0];
        trace.rows = held.iter().enumerate().map(|(k, h)| vec![k as f64 * 0.5, 0.0, *h]).collect();
        assert_eq!(held_spans(&trace), [(0.5, 1.5), (2.0, 2.5), (3.0, 3.5)]);
        trace.rows.iter_mut().for_each(|r| r[2] = 0.0);
        assert!(held_spans(&trace).is_empty());
        assert!(held_spans(&Trace::new(vec!["t_s".into()])).is_empty(), "no column, no spans");
    }
}
