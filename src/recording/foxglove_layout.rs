//! The Foxglove (and Lichtblick) layout of a run, `foxglove-layout.json` beside its recording, generated from what
//! the plant announced, so it fits any plant: a 3D panel following the body when the plant has a position and an
//! attitude ([`BodySignals`]); a plot for each unit of the traced outputs (a few signals a plot); a plot for each
//! unit of the commands, each command beside the position of the actuator it moves; the events on a timeline and
//! the latest in full. Message paths are `/trace.<column>` (the columns of `trace.csv`) and `/events.kind`.

use crate::foxglove::BodySignals;
use crate::topics;
use serde_json::{Value, json};
use silrig_flight::signals::PlantSignals;

/// The file's name in the run's folder.
pub const FILE: &str = "foxglove-layout.json";

/// Signals a plot shows at most: more are split into plots of their own.
const PER_PLOT: usize = 6;

/// A plot panel of `/trace` columns.
fn plot(title: &str, columns: &[String]) -> Value {
    let paths: Vec<Value> = columns
        .iter()
        .map(|c| {
            json!({"value": format!("{}.{c}", topics::TRACE), "enabled": true, "timestampMethod": "receiveTime", "label": c})
        })
        .collect();
    json!({"title": title, "paths": paths, "showLegend": true, "isSynced": true, "xAxisVal": "timestamp"})
}

/// Traced outputs that are no actuator's position, grouped by unit in the order announced.
fn output_groups(plant: &PlantSignals) -> Vec<(String, Vec<String>)> {
    let held: Vec<usize> = plant.inputs.iter().filter_map(|i| i.held_output).collect();
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    let traced = plant.outputs.iter().enumerate().filter(|(k, o)| o.in_trace && !held.contains(k)).map(|(_, o)| o);
    for o in traced {
        match groups.iter_mut().find(|(unit, _)| *unit == o.unit) {
            Some((_, names)) => names.push(o.name.clone()),
            None => groups.push((o.unit.clone(), vec![o.name.clone()])),
        }
    }
    groups
}

/// Traced commands, each followed by its actuator's position when traced, grouped by the input's unit.
fn command_groups(plant: &PlantSignals) -> Vec<(String, Vec<String>)> {
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    for (k, input) in plant.inputs.iter().enumerate().filter(|(_, i)| i.command_in_trace) {
        let mut columns = vec![plant.command_column(k)];
        columns.extend(input.held_output.map(|o| &plant.outputs[o]).filter(|o| o.in_trace).map(|o| o.name.clone()));
        match groups.iter_mut().find(|(unit, _)| *unit == input.unit) {
            Some((_, names)) => names.extend(columns),
            None => groups.push((input.unit.clone(), columns)),
        }
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

/// The layout for `plant`'s recording.
pub fn layout(plant: &PlantSignals) -> Value {
    let mut configs = serde_json::Map::new();
    let mut plots = Vec::new();
    let mut add_plots =
        |what: &str, groups: Vec<(String, Vec<String>)>, configs: &mut serde_json::Map<String, Value>| {
            for (unit, names) in groups {
                for chunk in names.chunks(PER_PLOT) {
                    let id = format!("Plot!{}", plots.len());
                    configs.insert(id.clone(), plot(&in_unit(what, &unit), chunk));
                    plots.push(id);
                }
            }
        };
    add_plots("outputs", output_groups(plant), &mut configs);
    add_plots("commands and positions", command_groups(plant), &mut configs);
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

    #[test]
    fn every_panel_is_placed_and_names_the_plants_own_columns() {
        let plant = quadrotor_like();
        let l = layout(&plant);
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
        let columns = plant.trace_columns(&[]);
        let mut titles: Vec<&str> = configs.values().filter_map(|c| c["title"].as_str()).collect();
        titles.sort();
        assert_eq!(titles, ["commands and positions", "outputs", "outputs, deg", "outputs, m", "outputs, rad/s"]);
        for c in configs.values() {
            for p in c["paths"].as_array().into_iter().flatten() {
                let path = p["value"].as_str().unwrap();
                if let Some(column) = path.strip_prefix("/trace.") {
                    assert!(columns.iter().any(|c| c == column), "{path} is no trace column of {columns:?}");
                }
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
        let l = layout(&PlantSignals { plant: "p".into(), outputs, inputs: Vec::new() });
        let configs = l["configById"].as_object().unwrap();
        assert!(!configs.contains_key("3D!silrig"));
        let sizes: Vec<usize> =
            configs.values().filter_map(|c| c["paths"].as_array()).filter(|p| p.len() > 1).map(Vec::len).collect();
        assert_eq!(sizes, [6, 2]);
    }
}
