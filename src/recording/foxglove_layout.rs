//! The Foxglove (and Lichtblick) layout of a run, `foxglove-layout.json` beside its recording, generated from what
//! the plant announced, so it fits any plant: a 3D panel following the body when the plant has a position and an
//! attitude ([`BodySignals`]); a plot for each unit of the traced outputs (a few signals a plot); a plot for each
//! unit of the commands, each command beside the position of the actuator it moves; the events on a timeline and
//! the latest in full. Message paths are `/trace.<column>` (the columns of `trace.csv`) in a recording with `/trace`
//! (realtime); in one without (lockstep) the same signals from the samples, `/plant.outputs[k]` and
//! `/command.inputs[k]`, labelled with the same column names; and `/events.kind`.

use crate::foxglove::BodySignals;
use crate::topics;
use serde_json::{Value, json};
use silrig_flight::signals::PlantSignals;

/// The file's name in the run's folder.
pub const FILE: &str = "foxglove-layout.json";

/// Signals a plot shows at most: more are split into plots of their own.
const PER_PLOT: usize = 6;

/// Where the plots read a plant's signals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignalSource {
    /// The `/trace` row, by column (realtime recordings).
    Trace,
    /// The samples (lockstep recordings, which have no `/trace`): an output in `/plant`, a command in `/command`.
    Samples,
}

/// A signal a plot shows: its label (the trace's column name) and the message path it is read from.
struct Plotted {
    label: String,
    path: String,
}

impl SignalSource {
    /// Output `k` of `plant`, labelled with its trace column.
    fn output(self, plant: &PlantSignals, k: usize) -> Plotted {
        let label = plant.outputs[k].name.clone();
        let path = match self {
            SignalSource::Trace => format!("{}.{label}", topics::TRACE),
            SignalSource::Samples => format!("{}.outputs[{k}]", topics::PLANT),
        };
        Plotted { label, path }
    }

    /// The command of input `k` of `plant`, labelled with its trace column.
    fn command(self, plant: &PlantSignals, k: usize) -> Plotted {
        let label = plant.command_column(k);
        let path = match self {
            SignalSource::Trace => format!("{}.{label}", topics::TRACE),
            SignalSource::Samples => format!("{}.inputs[{k}]", topics::COMMAND),
        };
        Plotted { label, path }
    }
}

/// A plot panel of these signals.
fn plot(title: &str, signals: &[Plotted]) -> Value {
    let paths: Vec<Value> = signals
        .iter()
        .map(|s| json!({"value": s.path, "enabled": true, "timestampMethod": "receiveTime", "label": s.label}))
        .collect();
    json!({"title": title, "paths": paths, "showLegend": true, "isSynced": true, "xAxisVal": "timestamp"})
}

/// Add `signals` to the group of `unit` in `groups`, or start one.
fn group_by_unit(groups: &mut Vec<(String, Vec<Plotted>)>, unit: &str, signals: impl IntoIterator<Item = Plotted>) {
    match groups.iter_mut().find(|(u, _)| u == unit) {
        Some((_, group)) => group.extend(signals),
        None => groups.push((unit.to_string(), signals.into_iter().collect())),
    }
}

/// Traced outputs that are no actuator's position, grouped by unit in the order announced.
fn output_groups(plant: &PlantSignals, source: SignalSource) -> Vec<(String, Vec<Plotted>)> {
    let held: Vec<usize> = plant.inputs.iter().filter_map(|i| i.held_output).collect();
    let mut groups = Vec::new();
    for (k, o) in plant.outputs.iter().enumerate().filter(|(k, o)| o.in_trace && !held.contains(k)) {
        group_by_unit(&mut groups, &o.unit, [source.output(plant, k)]);
    }
    groups
}

/// Traced commands, each followed by its actuator's position when traced, grouped by the input's unit.
fn command_groups(plant: &PlantSignals, source: SignalSource) -> Vec<(String, Vec<Plotted>)> {
    let mut groups = Vec::new();
    for (k, input) in plant.inputs.iter().enumerate().filter(|(_, i)| i.command_in_trace) {
        let position = input.held_output.filter(|o| plant.outputs[*o].in_trace).map(|o| source.output(plant, o));
        group_by_unit(&mut groups, &input.unit, std::iter::once(source.command(plant, k)).chain(position));
    }
    groups
}

/// A unit as a plot's title says it: none for a dimensionless signal.
fn in_unit(what: &str, unit: &str) -> String {
    if unit.is_empty() || unit == "1" { what.to_string() } else { format!("{what}, {unit}") }
}

/// The panels in a column, each split off the rest in turn so that each gets an equal share.
fn column(ids: &[String]) -> Value {
    match ids {
        [] => Value::Null,
        [one] => json!(one),
        [first, rest @ ..] => json!({
            "direction": "column",
            "splitPercentage": 100.0 / ids.len() as f64,
            "first": first,
            "second": column(rest),
        }),
    }
}

/// The layout for `plant`'s recording, its plots reading the signals from `source`.
pub fn layout(plant: &PlantSignals, source: SignalSource) -> Value {
    let mut configs = serde_json::Map::new();
    let mut plots = Vec::new();
    let mut add_plots =
        |what: &str, groups: Vec<(String, Vec<Plotted>)>, configs: &mut serde_json::Map<String, Value>| {
            for (unit, signals) in groups {
                for chunk in signals.chunks(PER_PLOT) {
                    let id = format!("Plot!{}", plots.len());
                    configs.insert(id.clone(), plot(&in_unit(what, &unit), chunk));
                    plots.push(id);
                }
            }
        };
    add_plots("outputs", output_groups(plant, source), &mut configs);
    add_plots("commands and positions", command_groups(plant, source), &mut configs);
    configs.insert(
        "StateTransitions!events".into(),
        json!({"paths": [{"value": format!("{}.kind", topics::EVENTS), "timestampMethod": "receiveTime", "label": "event"}],
               "isSynced": true}),
    );
    configs.insert(
        "RawMessages!events".into(),
        json!({"topicPath": topics::EVENTS, "diffEnabled": false, "diffMethod": "custom", "diffTopicPath": "",
               "showFullMessageForDiff": false}),
    );
    let events = json!({"direction": "column", "splitPercentage": 40, "first": "StateTransitions!events",
                        "second": "RawMessages!events"});
    let side = if plots.is_empty() {
        events
    } else {
        json!({"direction": "column", "splitPercentage": 70, "first": column(&plots), "second": events})
    };
    let tree = match BodySignals::resolve(plant) {
        Some(body) => {
            // The camera's distance, m: a few lengths of the vehicle drawn (an F-16, or a quadrotor of about 0.5 m).
            let distance_m = if body.rotorcraft() { 2.0 } else { 32.0 };
            configs.insert("3D!silrig".into(), three_d(distance_m));
            json!({"direction": "row", "splitPercentage": 55, "first": "3D!silrig", "second": side})
        }
        None => side,
    };
    json!({"configById": configs, "globalVariables": {}, "userNodes": {}, "playbackConfig": {"speed": 1},
           "layout": tree})
}

/// The 3D panel: the body's model and transform, the camera following the body's position from `distance_m`.
fn three_d(distance_m: f64) -> Value {
    json!({
        "followTf": crate::foxglove::BODY_FRAME,
        "followMode": "follow-position",
        "cameraState": {"distance": distance_m, "perspective": true, "phi": 65, "thetaOffset": -150,
                        "target": [0, 0, 0], "targetOffset": [0, 0, 0], "targetOrientation": [0, 0, 0, 1],
                        "fovy": 45, "near": distance_m / 64.0, "far": 20000},
        "scene": {}, "transforms": {},
        "topics": {topics::AIRCRAFT: {"visible": true}, topics::BODY_TRANSFORM: {"visible": true}},
        "layers": {}
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::signals::{InputSignal, OutputSignal};

    fn output(name: &str, unit: &str) -> OutputSignal {
        OutputSignal { name: name.into(), unit: unit.into(), in_trace: true }
    }

    fn quadrotor_like() -> PlantSignals {
        let mut outputs = vec![
            output("phi_deg", "deg"),
            output("theta_deg", "deg"),
            output("psi_deg", "deg"),
            output("north_m", "m"),
            output("east_m", "m"),
            output("alt_m", "m"),
        ];
        outputs.extend((1..=4).map(|k| output(&format!("omega{k}_radps"), "rad/s")));
        outputs.push(output("valve_pos", "1"));
        outputs.push(output("on_ground", "1"));
        let inputs = (1..=4)
            .map(|k| InputSignal {
                name: format!("motor{k}"),
                unit: "1".into(),
                min: 0.0,
                max: 1.0,
                hold: 0.0,
                held_output: (k == 1).then_some(10),
                command_in_trace: true,
            })
            .collect();
        PlantSignals { plant: "quad".into(), outputs, inputs }
    }

    /// Where a plotted path points: the trace column, output or command its label names.
    fn assert_path_is_its_label(plant: &PlantSignals, path: &str, label: &str) {
        let index = |prefix: &str| path.strip_prefix(prefix)?.strip_suffix(']')?.parse::<usize>().ok();
        if let Some(column) = path.strip_prefix("/trace.") {
            assert_eq!(column, label, "{path}");
            assert!(plant.trace_columns(&[]).iter().any(|c| c == column), "{path} is no trace column");
        } else if let Some(k) = index("/plant.outputs[") {
            assert_eq!(plant.outputs[k].name, label, "{path}");
        } else if let Some(k) = index("/command.inputs[") {
            assert_eq!(plant.command_column(k), label, "{path}");
        } else {
            panic!("{path} reads no signal");
        }
    }

    #[test]
    fn both_sources_plot_the_same_signals_each_from_where_the_recording_has_it() {
        let plant = quadrotor_like();
        let labels = |l: &Value| -> Vec<(String, String)> {
            let mut found = Vec::new();
            for c in l["configById"].as_object().unwrap().values().filter(|c| c["title"].is_string()) {
                for p in c["paths"].as_array().unwrap() {
                    let (path, label) = (p["value"].as_str().unwrap(), p["label"].as_str().unwrap());
                    assert_path_is_its_label(&plant, path, label);
                    found.push((c["title"].as_str().unwrap().to_string(), label.to_string()));
                }
            }
            found.sort();
            found
        };
        let (trace, samples) = (layout(&plant, SignalSource::Trace), layout(&plant, SignalSource::Samples));
        assert_eq!(labels(&trace), labels(&samples));
        assert!(samples.to_string().contains("/plant.outputs[10]"), "valve_pos from the samples");
        assert!(!samples.to_string().contains("/trace."), "no /trace path without /trace");
    }

    #[test]
    fn every_panel_is_placed_and_names_the_plants_own_columns() {
        let plant = quadrotor_like();
        let l = layout(&plant, SignalSource::Trace);
        let configs = l["configById"].as_object().unwrap();
        fn placed(node: &Value, into: &mut Vec<String>) {
            match node {
                Value::String(id) => into.push(id.clone()),
                Value::Object(split) => {
                    placed(&split["first"], into);
                    placed(&split["second"], into);
                }
                other => panic!("a layout node: {other}"),
            }
        }
        let mut panels = Vec::new();
        placed(&l["layout"], &mut panels);
        panels.sort();
        let mut ids: Vec<String> = configs.keys().cloned().collect();
        ids.sort();
        assert_eq!(panels, ids);
        assert_eq!(configs["3D!silrig"]["cameraState"]["distance"], 2.0, "a quadrotor's camera is near");
        let mut titles: Vec<&str> = configs.values().filter_map(|c| c["title"].as_str()).collect();
        titles.sort();
        assert_eq!(titles, ["commands and positions", "outputs", "outputs, deg", "outputs, m", "outputs, rad/s"]);
        for c in configs.values().filter(|c| c["title"].is_string()) {
            for p in c["paths"].as_array().unwrap() {
                assert_path_is_its_label(&plant, p["value"].as_str().unwrap(), p["label"].as_str().unwrap());
            }
        }
        // The position of the actuator a command moves is beside it, not among the outputs.
        let commands = configs.values().find(|c| c["title"] == "commands and positions").unwrap();
        let labels: Vec<&str> =
            commands["paths"].as_array().unwrap().iter().map(|p| p["label"].as_str().unwrap()).collect();
        assert_eq!(labels, ["motor1_cmd", "valve_pos", "motor2_cmd", "motor3_cmd", "motor4_cmd"]);
    }

    #[test]
    fn a_plant_without_position_or_attitude_gets_no_3d_panel_and_long_groups_are_split() {
        let outputs = (0..8).map(|k| output(&format!("x{k}_m"), "m")).collect();
        let l = layout(&PlantSignals { plant: "p".into(), outputs, inputs: Vec::new() }, SignalSource::Samples);
        let configs = l["configById"].as_object().unwrap();
        assert!(!configs.contains_key("3D!silrig"));
        let sizes: Vec<usize> =
            configs.values().filter_map(|c| c["paths"].as_array()).filter(|p| p.len() > 1).map(Vec::len).collect();
        assert_eq!(sizes, [6, 2]);
    }
}
