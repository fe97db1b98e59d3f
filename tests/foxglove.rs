//! The aircraft in 3-D in the recording (`/body_transform`, `/aircraft`) and the Foxglove layout that shows it. A
//! short lockstep run's recording is decoded with Foxglove's own Python schemas (`foxglove/read_3d.py`, in the
//! virtual environment `.ci/run` creates) and every transform is compared with `trace.csv` (attitude, altitude) and
//! the plant's samples (the north/east position the trace does not show): one a tick, in order, the rotation built
//! here independently from the direction cosine matrix of the Euler angles. The scene's moving surfaces must turn
//! by the surfaces' positions. A quadrotor's scene is an X quadrotor, its rotors in Betaflight's motor order. The
//! layout each run writes beside its recording (`foxglove-layout.json`, generated from the plant's signals) must
//! name only panels it places and topics and fields the recording has.

mod common;

use common::{Run, venv_python};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const M_PER_FT: f64 = 0.3048;

/// What `read_3d.py` reads from `file`.
fn read_3d(file: &Path) -> Value {
    venv_python("mcap", "mcap");
    venv_python("mcap_ros2", "mcap-ros2-support");
    let python = venv_python("foxglove_schemas_protobuf", "foxglove-schemas-protobuf");
    let out = Command::new(python).arg(Path::new(ROOT).join("tests/foxglove/read_3d.py")).arg(file).output().unwrap();
    assert!(out.status.success(), "read_3d.py: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("JSON")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

/// The rotation matrix of a unit quaternion (x, y, z, w).
fn matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [x, y, z, w] = q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
        [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
        [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// east-north-up <- forward-left-up from the aerospace direction cosine matrix north-east-down <- forward-right-down
/// of Euler angles phi, theta, psi (Stevens & Lewis): the axes swapped on both sides.
fn expected_rotation(phi: f64, theta: f64, psi: f64) -> [[f64; 3]; 3] {
    let (sf, cf) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    let ned_frd = [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ];
    // ENU row i is NED row enu_from_ned[i] times a sign; FLU column j is FRD column j times a sign.
    let (rows, row_sign) = ([1, 0, 2], [1.0, 1.0, -1.0]);
    let column_sign = [1.0, -1.0, -1.0];
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = row_sign[i] * ned_frd[rows[i]][j] * column_sign[j];
        }
    }
    m
}

#[test]
fn the_recording_carries_the_aircraft_in_3d_as_the_trace_flew_it() {
    let run = Run::start(SILRIG, "foxglove", "fx", "flight", &["--mode", "lockstep", "--duration-s", "3"]);
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    let file = read_3d(&run.out.join("recording.mcap"));
    let topics = &file["topics"];
    assert_eq!(topics["/body_transform"], serde_json::json!(["foxglove.FrameTransform", "protobuf", "protobuf"]));
    assert_eq!(topics["/aircraft"], serde_json::json!(["foxglove.SceneUpdate", "protobuf", "protobuf"]));

    let (header, rows) = run.trace();
    let col = |name: &str| Run::column(&header, name);
    let names: Vec<&str> = file["output_names"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    let out = |name: &str| names.iter().position(|n| *n == name).unwrap_or_else(|| panic!("{name} in {names:?}"));
    let plant = file["plant"].as_array().unwrap();
    let transforms = file["transforms"].as_array().unwrap();
    let scenes = file["scenes"].as_array().unwrap();
    assert!(rows.len() >= 300, "a 3 s flight: {} rows", rows.len());
    // A lockstep recording's /plant ends with the plant's end-of-run sample (the last row's positions).
    assert_eq!((plant.len(), transforms.len()), (rows.len() + 1, rows.len()), "one a tick");

    let deg = std::f64::consts::PI / 180.0;
    let mut last_stamp = 0;
    for (i, ((row, p), t)) in rows.iter().zip(plant).zip(transforms).enumerate() {
        // Tick i's transform: stamped with its sample's send time, after the previous tick's.
        assert_eq!(p["tick"], i as u64);
        assert_eq!(t["publish_time"], p["publish_time"], "tick {i}");
        let stamp = t["stamp_ns"].as_u64().unwrap();
        assert_eq!(stamp, p["publish_time"].as_u64().unwrap(), "tick {i}: the stamp is the sample's time");
        assert!(stamp > last_stamp, "tick {i}: in order");
        last_stamp = stamp;
        assert_eq!((&t["parent"], &t["child"]), (&"world".into(), &"body".into()));

        let outputs = p["outputs"].as_array().unwrap();
        let (north, east) = (f(&outputs[out("north_ft")]), f(&outputs[out("east_ft")]));
        let alt = row[col("alt_ft")];
        assert_eq!(alt, f(&outputs[out("alt_ft")]), "tick {i}: the trace shows the sample");
        let expected = [east * M_PER_FT, north * M_PER_FT, alt * M_PER_FT];
        for (k, e) in expected.iter().enumerate() {
            let got = f(&t["translation"][k]);
            assert!((got - e).abs() <= 1e-9 * e.abs().max(1.0), "tick {i}: translation[{k}] {got} against {e}");
        }
        let q: Vec<f64> = t["rotation"].as_array().unwrap().iter().map(f).collect();
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12, "tick {i}: a unit quaternion ({norm})");
        let (phi, theta, psi) = (row[col("phi_deg")] * deg, row[col("theta_deg")] * deg, row[col("psi_deg")] * deg);
        let (got, want) = (matrix([q[0], q[1], q[2], q[3]]), expected_rotation(phi, theta, psi));
        for r in 0..3 {
            for c in 0..3 {
                assert!((got[r][c] - want[r][c]).abs() < 1e-9, "tick {i}: rotation {got:?} against {want:?}");
            }
        }
    }
    // The flight moves and turns, so the checks above compared more than a constant.
    let first = &transforms[0]["translation"];
    let last = &transforms[transforms.len() - 1]["translation"];
    assert!((f(&first[1]) - f(&last[1])).abs() > 100.0, "it flew north: {first} to {last}");

    // The scene: the aircraft in `body`, its surfaces turned by their positions, written again when a surface has
    // turned 0.5 deg or a second has passed: at every tick the newest scene shows each surface within 0.5 deg.
    let surfaces = [out("aileron_deg"), out("elevator_deg"), out("rudder_deg")];
    assert!(scenes.len() < rows.len() / 2, "not one a tick: {} scenes, {} rows", scenes.len(), rows.len());
    let by_time: std::collections::HashMap<u64, usize> =
        plant.iter().enumerate().map(|(i, p)| (p["publish_time"].as_u64().unwrap(), i)).collect();
    let scene_ticks: Vec<usize> = scenes
        .iter()
        .map(|s| *by_time.get(&s["publish_time"].as_u64().unwrap()).expect("a scene at a plant sample's time"))
        .collect();
    assert_eq!(scene_ticks[0], 0, "the first tick has a scene");
    let surfaces_deg = |p: &Value| surfaces.map(|k| f(&p["outputs"][k]));
    for (i, p) in plant.iter().enumerate() {
        let shown = scene_ticks[scene_ticks.partition_point(|&t| t <= i) - 1];
        assert!(i - shown < 100, "tick {i}: the newest scene is from tick {shown}");
        for (now, then) in surfaces_deg(p).iter().zip(surfaces_deg(&plant[shown])) {
            assert!((now - then).abs() < 0.5, "tick {i}: surfaces {:?}, shown {then}", surfaces_deg(p));
        }
    }
    let mut deflected = 0;
    for (i, (s, p)) in scenes.iter().zip(scene_ticks.iter().map(|&t| &plant[t])).enumerate() {
        assert_eq!(s["deletions"], 0, "scene {i}");
        let entities = s["entities"].as_array().unwrap();
        assert_eq!(entities.len(), 1, "scene {i}");
        let e = &entities[0];
        assert_eq!((&e["frame_id"], &e["id"], &e["frame_locked"]), (&"body".into(), &"aircraft".into(), &true.into()));
        assert_eq!(e["stamp_ns"], p["publish_time"], "scene {i}");
        assert!(e["cylinders"].as_u64().unwrap() >= 1, "a fuselage");
        let [aileron, elevator, rudder] = surfaces.map(|k| f(&p["outputs"][k]) * deg);
        // A surface turned by angle a about the body's y (or z) axis has the orientation (0, sin a/2, 0, cos a/2)
        // (or (0, 0, sin a/2, cos a/2)); Stevens & Lewis' positive deflections: right aileron and elevator trailing
        // edge down (a turn about +y by minus the angle), left aileron up, rudder trailing edge left (about +z by
        // minus the angle).
        let turned = |axis: usize, angle: f64| {
            e["cubes"].as_array().unwrap().iter().filter(move |c| {
                let o: Vec<f64> = c["orientation"].as_array().unwrap().iter().map(f).collect();
                let mut want = [0.0, 0.0, 0.0, (angle / 2.0).cos()];
                want[axis] = (angle / 2.0).sin();
                o.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12)
            })
        };
        // A surface at 0 is one of the unturned boxes; a deflected one must be found turned.
        if aileron.abs() > 1e-9 {
            let (right, left) = (turned(1, -aileron).count(), turned(1, aileron).count());
            assert_eq!((right, left), (1, 1), "scene {i}: ailerons at {aileron} rad");
        }
        if elevator.abs() > 1e-9 {
            assert_eq!(turned(1, -elevator).count(), 2, "scene {i}: both tail halves at the elevator's {elevator} rad");
        }
        if rudder.abs() > 1e-9 {
            assert_eq!(turned(2, -rudder).count(), 1, "scene {i}: the rudder at {rudder} rad");
        }
        deflected += usize::from(elevator.abs() > 1e-3);
    }
    assert!(deflected > 0, "the elevator moved during the flight");

    check_layout(&run.out, &file, &header, 32.0);
    run.finish();
}

#[test]
fn a_quadrotor_is_drawn_with_its_rotors_in_betaflights_order_and_gets_a_layout_of_its_own() {
    let config = format!("{ROOT}/configs/quad-hover.toml");
    let args = ["--mode", "lockstep", "--duration-s", "1", &config];
    let run = Run::start(SILRIG, "foxglove", "fq", "quad", &args);
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    let file = read_3d(&run.out.join("recording.mcap"));
    let scenes = file["scenes"].as_array().unwrap();
    assert!(!scenes.is_empty(), "no /aircraft scene");
    // Quad X, props in, seen from above: 1 rear right, 2 front right, 3 rear left, 4 front left; body x forward,
    // y left (forward-left-up), the arm's 0.17 m at 45 degrees.
    let a = 0.17 / std::f64::consts::SQRT_2;
    let expected = [[-a, -a], [a, -a], [-a, a], [a, a]];
    for s in scenes {
        let e = &s["entities"][0];
        assert_eq!(e["cubes"].as_array().unwrap().len(), 4, "a hub, a nose and two arms: {e}");
        let rotors = e["cylinder_positions"].as_array().unwrap();
        assert_eq!(rotors.len(), 4, "four rotors: {e}");
        for (k, (r, want)) in rotors.iter().zip(expected).enumerate() {
            assert!((f(&r[0]) - want[0]).abs() < 1e-9 && (f(&r[1]) - want[1]).abs() < 1e-9, "rotor {}: {r}", k + 1);
        }
    }
    let (header, _) = run.trace();
    check_layout(&run.out, &file, &header, 2.0);
    run.finish();
}

/// The run's layout places every panel it configures, follows `body` from `distance_m`, and names only topics and
/// trace fields the recording has.
fn check_layout(run_dir: &Path, recording: &Value, trace_columns: &[String], distance_m: f64) {
    let path = run_dir.join("foxglove-layout.json");
    let layout: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).expect("the layout is JSON");
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
    placed(&layout["layout"], &mut panels);
    let configs = layout["configById"].as_object().unwrap();
    let mut configured: Vec<&String> = configs.keys().collect();
    configured.sort();
    panels.sort();
    assert_eq!(panels.iter().collect::<Vec<_>>(), configured, "every panel placed is configured and no other");
    let three_d = &configs["3D!silrig"];
    assert_eq!(three_d["followTf"], "body");
    assert_eq!(three_d["cameraState"]["distance"], distance_m);
    let has_topic = |topic: &str| recording["topics"].get(topic).is_some();
    for topic in three_d["topics"].as_object().unwrap().keys() {
        assert!(has_topic(topic), "the 3D panel's {topic}");
    }
    // Message paths: /topic.field.
    let mut paths = Vec::new();
    for config in configs.values() {
        for p in config["paths"].as_array().into_iter().flatten() {
            paths.push(p["value"].as_str().unwrap().to_string());
        }
        if let Some(topic) = config["topicPath"].as_str() {
            paths.push(topic.to_string());
        }
    }
    assert!(paths.len() >= 10, "{paths:?}");
    for p in paths {
        let (topic, field) = p.split_once('.').unwrap_or((&p, ""));
        assert!(has_topic(topic), "{p}: no topic {topic}");
        let indexed = |array: &str| field.strip_prefix(array)?.strip_suffix(']')?.parse::<usize>().ok();
        if topic == "/trace" {
            assert!(trace_columns.iter().any(|c| c == field), "{p}: no trace column {field}");
        } else if topic == "/plant" || topic == "/command" {
            // A lockstep recording has no /trace: its plots read the samples (which entry is which signal:
            // src/recording/foxglove_layout.rs's tests).
            let k = indexed("outputs[").or_else(|| indexed("inputs[")).unwrap_or_else(|| panic!("{p}: no signal"));
            assert!(k < trace_columns.len(), "{p}");
        } else if topic == "/events" && !field.is_empty() {
            assert!(["kind", "process", "detail", "tick", "t_ns"].contains(&field), "{p}");
        }
    }
}
