//! The device layouts silrig ships (`configs/devices/`): every one parses and binds against the quadrotor (an
//! excerpt, `*.excerpt.toml`, declares only what the format can say of a link, and is refused whole for lacking a
//! direction, naming it), and the binary parts the reference page (`docs/src/reference/device-layout.md`) claims
//! the format expresses are checked against the links' own definitions through
//! `tests/udp_device/reference_packets.py`: ArduPilot's servo packet packed by Python's struct as SIM_JSON.h declares
//! it and decoded by our codec; HIL_ACTUATOR_CONTROLS's payload packed by pymavlink and decoded by our codec; and our
//! HIL_SENSOR, HIL_STATE_QUATERNION and HIL_GPS payloads, framed, parsed by pymavlink into the values sent.

mod common;

use serde_json::Value;
use silrig::adapters::udp::codec::SendValues;
use silrig::adapters::udp::layout::{BoundLayout, DeviceLayout, FieldLayout, OneOrMany, PacketLayout, SignalNames};
use silrig::quad::outputs::{INPUTS, OUTPUTS, output_index};
use std::path::{Path, PathBuf};
use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Every layout file under configs/devices.
fn layout_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(format!("{ROOT}/configs/devices"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

fn is_excerpt(path: &Path) -> bool {
    path.to_string_lossy().ends_with(".excerpt.toml")
}

/// The set points the shipped quadrotor scenarios give (`configs/quad-*.toml`), by name.
fn setpoints() -> Vec<String> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(format!("{ROOT}/configs")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !(name.starts_with("quad-") && name.ends_with(".toml")) {
            continue;
        }
        let doc: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
        if let Some(sp) = doc.get("setpoint").and_then(|v| v.as_table()) {
            names.extend(sp.keys().cloned());
        }
    }
    names.sort();
    names.dedup();
    names
}

fn bind(layout: &DeviceLayout) -> Result<BoundLayout, String> {
    let outputs: Vec<String> = OUTPUTS.iter().map(|o| o.0.to_string()).collect();
    let inputs: Vec<String> = INPUTS.iter().map(|i| i.0.to_string()).collect();
    let setpoints = setpoints();
    layout.bind(&SignalNames { outputs: &outputs, inputs: &inputs, setpoints: &setpoints }).map_err(|e| e.to_string())
}

fn load(name: &str) -> DeviceLayout {
    DeviceLayout::load(Path::new(&format!("{ROOT}/configs/devices/{name}"))).unwrap()
}

/// An excerpt with a one-field packet to the device added, so its declared packets bind (test only: what the
/// excerpt leaves out is what the format cannot express).
fn completed(mut excerpt: DeviceLayout) -> DeviceLayout {
    assert!(excerpt.to_device.is_empty(), "an excerpt declares no packet to the device");
    let time = FieldLayout {
        ty: "f64".into(),
        from: Some(OneOrMany::One("time_s".into())),
        to: None,
        value: None,
        count: None,
        skip: false,
        scale: None,
        offset: None,
        frame: None,
    };
    excerpt.to_device.push(PacketLayout { name: "test-only".into(), port: 1, every_ticks: 1, fields: vec![time] });
    excerpt
}

fn reference(args: &[&str]) -> String {
    let python = common::venv_python("pymavlink", "pymavlink");
    let o = Command::new(python).arg(format!("{ROOT}/tests/udp_device/reference_packets.py")).args(args).output();
    let o = o.unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "reference_packets.py {args:?}: {stdout}{stderr}");
    stdout.trim().to_string()
}

fn hex(text: &str) -> Vec<u8> {
    (0..text.len()).step_by(2).map(|k| u8::from_str_radix(&text[k..k + 2], 16).unwrap()).collect()
}

#[test]
fn every_shipped_layout_parses_and_binds_against_the_quadrotor() {
    let files = layout_files();
    let names: Vec<String> = files.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert!(names.len() >= 3, "{names:?}");
    for path in &files {
        let layout = DeviceLayout::load(path).unwrap_or_else(|e| panic!("{e}"));
        if is_excerpt(path) {
            let e = bind(&layout).unwrap_err();
            assert!(e.contains("needs at least one packet each way"), "{}: {e}", path.display());
            bind(&completed(layout)).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        } else {
            bind(&layout).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}

#[test]
fn ardupilots_servo_packet_packed_by_struct_decodes_into_the_quadrotors_motors() {
    let layout = completed(load("ardupilot-sitl-json.excerpt.toml"));
    let bound = bind(&layout).unwrap();
    let servos = &bound.from_device[0];
    assert_eq!((servos.name.as_str(), servos.port, servos.size), ("servos", 9002, 40));
    let packet = hex(&reference(&["servo", "1100", "1250", "1500", "1975", "1500", "1500"]));
    assert_eq!(packet.len(), 40);
    let mut inputs = vec![f64::NAN; 4];
    servos.decode(bound.byte_order, &packet, &mut inputs).unwrap();
    // ArduCopter's motors 1..4 (front right, rear left, front left, rear right) are the quadrotor's 2, 3, 4, 1.
    let want = [1975.0, 1100.0, 1250.0, 1500.0].map(|us: f64| us * 0.001 - 1.0);
    assert_eq!(inputs, want);
}

#[test]
fn hil_actuator_controls_packed_by_pymavlink_decodes_into_the_quadrotors_motors() {
    let bound = bind(&load("px4-hil-mavlink.toml")).unwrap();
    let controls = &bound.from_device[0];
    let payload = hex(&reference(&["actuators", "0.125", "0.5", "0.75", "0.875"]));
    assert_eq!((payload.len(), controls.size), (81, 81), "HIL_ACTUATOR_CONTROLS's payload, untruncated");
    let mut inputs = vec![f64::NAN; 4];
    controls.decode(bound.byte_order, &payload, &mut inputs).unwrap();
    // PX4's motors 1..4 (front right, rear left, front left, rear right) are the quadrotor's 2, 3, 4, 1.
    assert_eq!(inputs, [0.875, 0.125, 0.5, 0.75]);
    let mut cut = payload.clone();
    cut.pop();
    assert!(controls.decode(bound.byte_order, &cut, &mut inputs).unwrap_err().to_string().contains("of 80 bytes"));
}

/// The quadrotor's outputs with distinct values, by name.
fn outputs() -> Vec<f64> {
    let mut o = vec![0.0; OUTPUTS.len()];
    let set = [
        ("p_dps", 30.0),
        ("q_dps", -12.5),
        ("r_dps", 90.0),
        ("fx_mps2", 0.5),
        ("fy_mps2", -0.25),
        ("fz_mps2", -9.80665),
        ("pressure_pa", 101_200.0),
        ("baro_alt_m", 10.5),
        ("qw", 0.5),
        ("qx", -0.5),
        ("qy", 0.5),
        ("qz", 0.5),
        ("north_m", 12.0),
        ("east_m", -7.0),
        ("vn_mps", 1.5),
        ("ve_mps", -2.25),
        ("vd_mps", 0.75),
    ];
    for (name, v) in set {
        o[output_index(name).unwrap()] = v;
    }
    o
}

/// Our payload of packet `k` to PX4, framed and parsed by pymavlink as message `name`.
fn parsed(k: usize, name: &str) -> Value {
    let bound = bind(&load("px4-hil-mavlink.toml")).unwrap();
    let (outputs, setpoints) = (outputs(), vec![0.0; setpoints().len()]);
    let mut payload = Vec::new();
    bound.to_device[k].encode(
        bound.byte_order,
        &SendValues { t_s: 2.5, outputs: &outputs, setpoints: &setpoints },
        &mut payload,
    );
    let text: String = payload.iter().map(|b| format!("{b:02x}")).collect();
    serde_json::from_str(&reference(&["decode", name, &text])).unwrap()
}

fn f32_of(x: f64) -> f64 {
    x as f32 as f64
}

#[test]
fn our_hil_sensor_payload_is_what_pymavlink_reads() {
    let m = parsed(0, "HIL_SENSOR");
    let d = std::f64::consts::PI / 180.0;
    assert_eq!(m["time_usec"], 2_500_000);
    let got = |k: &str| m[k].as_f64().unwrap();
    assert_eq!([got("xacc"), got("yacc"), got("zacc")], [0.5, -0.25, f32_of(-9.80665)]);
    assert_eq!([got("xgyro"), got("ygyro"), got("zgyro")], [f32_of(30.0 * d), f32_of(-12.5 * d), f32_of(90.0 * d)]);
    assert_eq!(got("abs_pressure"), f32_of(1012.0), "hPa");
    assert_eq!((got("pressure_alt"), got("temperature")), (10.5, 15.0));
    assert_eq!(m["fields_updated"], 0b111 | 0b111000 | 0b1101000000000, "accelerometer, gyro, barometer");
    assert_eq!(m["id"], 0);
}

#[test]
fn our_hil_state_quaternion_and_hil_gps_payloads_are_what_pymavlink_reads() {
    let m = parsed(1, "HIL_STATE_QUATERNION");
    let q: Vec<f64> = m["attitude_quaternion"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(q, [0.5, -0.5, 0.5, 0.5]);
    // PX4's default home moved 12 m north and 7 m west on a flat earth, degE7; altitude in mm; velocity in cm/s.
    assert_eq!((m["lat"].as_i64(), m["lon"].as_i64()), (Some(473_978_498), Some(85_455_011)));
    assert_eq!(
        (m["alt"].as_i64(), m["vx"].as_i64(), m["vy"].as_i64(), m["vz"].as_i64()),
        (Some(10_500), Some(150), Some(-225), Some(75))
    );
    assert_eq!((m["xacc"].as_i64(), m["zacc"].as_i64()), (Some(51), Some(-1000)), "mG");
    let g = parsed(2, "HIL_GPS");
    assert_eq!(
        (g["lat"].as_i64(), g["lon"].as_i64(), g["alt"].as_i64()),
        (Some(473_978_498), Some(85_455_011), Some(10_500))
    );
    assert_eq!((g["vn"].as_i64(), g["ve"].as_i64(), g["vd"].as_i64()), (Some(150), Some(-225), Some(75)));
    assert_eq!(
        (g["fix_type"].as_i64(), g["satellites_visible"].as_i64(), g["cog"].as_i64()),
        (Some(3), Some(10), Some(65535))
    );
}
