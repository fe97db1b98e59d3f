//! The shipped Betaflight layout against Betaflight's own struct sizes and the quadrotor's signals, the codec both
//! ways, and every refusal.

use super::*;
use crate::udp::codec::{DecodeError, SendValues};
use silrig_model::quad::outputs::{INPUTS, OUTPUTS};

const BETAFLIGHT: &str = include_str!("../../../configs/devices/betaflight-sitl.toml");

fn names(list: &[(&str, &str)]) -> Vec<String> {
    list.iter().map(|(n, _)| n.to_string()).collect()
}

fn rc_setpoints() -> Vec<String> {
    ["rc_roll", "rc_pitch", "rc_throttle", "rc_yaw", "rc_arm", "rc_angle_mode", "rc_althold"].map(String::from).to_vec()
}

fn bind(text: &str) -> Result<BoundLayout, LayoutError> {
    let (outputs, inputs, setpoints) = (names(&OUTPUTS), names(&INPUTS), rc_setpoints());
    DeviceLayout::parse(text)?.bind(&SignalNames { outputs: &outputs, inputs: &inputs, setpoints: &setpoints })
}

fn f64_at(bytes: &[u8], k: usize) -> f64 {
    f64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap())
}

#[test]
fn the_betaflight_layout_has_betaflights_struct_sizes() {
    let layout = bind(BETAFLIGHT).unwrap();
    // sizeof(fdm_packet), sizeof(rc_packet), sizeof(servo_packet) in target.h: 18 doubles; a double and 16
    // uint16s; 4 floats. sitl.c drops a packet of any other size.
    assert_eq!(
        layout.to_device.iter().map(|p| (p.name.as_str(), p.size)).collect::<Vec<_>>(),
        [("fdm", 144), ("rc", 40)]
    );
    assert_eq!(layout.from_device[0].size, 16);
    assert_eq!([layout.to_device[0].port, layout.to_device[1].port, layout.from_device[0].port], [9003, 9004, 9002]);
}

#[test]
fn the_fdm_packet_carries_the_quadrotor_in_betaflights_frames() {
    let layout = bind(BETAFLIGHT).unwrap();
    let mut outputs = vec![0.0; OUTPUTS.len()];
    let set =
        |outputs: &mut Vec<f64>, name: &str, v: f64| outputs[OUTPUTS.iter().position(|(n, _)| *n == name).unwrap()] = v;
    for (name, v) in [("p_dps", 90.0), ("q_dps", -45.0), ("r_dps", 180.0), ("fx_mps2", 1.0), ("fy_mps2", 2.0)] {
        set(&mut outputs, name, v);
    }
    for (name, v) in [("fz_mps2", -9.8), ("qw", 0.5), ("qx", 0.5), ("qy", -0.5), ("qz", 0.5), ("vn_mps", 3.0)] {
        set(&mut outputs, name, v);
    }
    for (name, v) in [("ve_mps", 4.0), ("vd_mps", -1.0), ("baro_alt_m", 120.0), ("pressure_pa", 99_900.0)] {
        set(&mut outputs, name, v);
    }
    let mut out = Vec::new();
    let values = SendValues { t_s: 1.25, outputs: &outputs, setpoints: &[0.0; 7] };
    layout.to_device[0].encode(layout.byte_order, &values, &mut out);
    let got: Vec<f64> = (0..18).map(|k| f64_at(&out, k)).collect();
    let d = std::f64::consts::PI / 180.0;
    let want = [
        1.25,
        90.0 * d,
        -45.0 * d,
        180.0 * d,
        -1.0,
        2.0,
        -9.8,
        0.5,
        0.5,
        -0.5,
        0.5,
        4.0,
        3.0,
        1.0,
        0.0,
        0.0,
        120.0,
        99_900.0,
    ];
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() < 1e-12, "double {k}: {g} against {w}");
    }
}

#[test]
fn the_rc_packet_turns_set_points_into_pulse_widths() {
    let layout = bind(BETAFLIGHT).unwrap();
    let rc = &layout.to_device[1];
    let mut out = Vec::new();
    // roll, pitch, throttle, yaw, arm, angle, altitude hold
    let setpoints = [0.2, -1.0, 0.5, 0.0, 1.0, 1.0, 1.0];
    rc.encode(
        layout.byte_order,
        &SendValues { t_s: 2.0, outputs: &[0.0; OUTPUTS.len()], setpoints: &setpoints },
        &mut out,
    );
    assert_eq!(f64_at(&out, 0), 2.0);
    let channels: Vec<u16> = (0..16).map(|k| u16::from_le_bytes([out[8 + 2 * k], out[9 + 2 * k]])).collect();
    assert_eq!(channels[..7], [1600, 1000, 1500, 1500, 2000, 2000, 2000]);
    assert!(channels[7..].iter().all(|c| *c == 1000));
    assert!(rc.due(0) && !rc.due(5) && rc.due(20) && layout.to_device[0].due(7));
}

#[test]
fn motor_packets_land_in_the_inputs_and_bad_ones_change_nothing() {
    let layout = bind(BETAFLIGHT).unwrap();
    let motors = &layout.from_device[0];
    let packet: Vec<u8> = [0.1f32, 0.2, 0.3, 0.4].iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut inputs = [0.0; 4];
    motors.decode(layout.byte_order, &packet, &mut inputs).unwrap();
    // sitl.c sends its motors 2, 3, 4, 1 in that order: the quadrotor's motor1 (rear right) is the packet's last.
    let in_motor_order = [0.4f32, 0.1, 0.2, 0.3].map(f64::from);
    assert_eq!(inputs, in_motor_order);
    let short = motors.decode(layout.byte_order, &packet[..12], &mut inputs).unwrap_err();
    assert_eq!(short, DecodeError::WrongSize { packet: "motors".into(), got: 12, want: 16 });
    assert_eq!(short.to_string(), "packet `motors` of 12 bytes refused: its layout has 16");
    let nan: Vec<u8> = [0.9f32, f32::NAN, 0.9, 0.9].iter().flat_map(|v| v.to_le_bytes()).collect();
    let e = motors.decode(layout.byte_order, &nan, &mut inputs).unwrap_err().to_string();
    assert_eq!(e, "packet `motors` refused: field 2 is NaN, not a finite number");
    assert_eq!(inputs, in_motor_order, "a refused packet changes no input");
}

const SMALL: &str = r#"
name = "probe"
byte_order = "big"
[[to_device]]
name = "state"
port = 7000
fields = [{ type = "i16", from = ["vn_mps", "ve_mps", "vd_mps"], frame = "ned_to_enu", scale = 100.0 }]
[[from_device]]
name = "reply"
port = 7001
fields = [
  { type = "u8", skip = true, count = 2 },
  { type = "f32", to = ["motor1", "motor2", "motor3"], frame = "ned_to_enu" },
]
"#;

#[test]
fn big_endian_integers_and_frames_both_ways() {
    let layout = bind(SMALL).unwrap();
    let mut outputs = vec![0.0; OUTPUTS.len()];
    for (name, v) in [("vn_mps", 1.5), ("ve_mps", -2.0), ("vd_mps", 400.0)] {
        outputs[OUTPUTS.iter().position(|(n, _)| *n == name).unwrap()] = v;
    }
    let mut out = Vec::new();
    layout.to_device[0].encode(
        layout.byte_order,
        &SendValues { t_s: 0.0, outputs: &outputs, setpoints: &[] },
        &mut out,
    );
    // (east, north, up) * 100, big-endian, the up component held to i16's range.
    assert_eq!(out, [(-200i16).to_be_bytes(), 150i16.to_be_bytes(), i16::MIN.to_be_bytes()].concat());
    let reply: Vec<u8> = [vec![9, 9], [2.0f32, 1.0, -3.0].iter().flat_map(|v| v.to_be_bytes()).collect()].concat();
    let mut inputs = [0.0; 4];
    layout.from_device[0].decode(layout.byte_order, &reply, &mut inputs).unwrap();
    assert_eq!(inputs, [1.0, 2.0, 3.0, 0.0], "ENU (2, 1, -3) is NED (1, 2, 3)");
}

fn refusal(edit: (&str, &str)) -> String {
    let text = SMALL.replacen(edit.0, edit.1, 1);
    assert_ne!(text, SMALL, "the edit {edit:?} must change the layout");
    bind(&text).unwrap_err().to_string()
}

#[test]
fn every_refusal_names_the_packet_field_and_fix() {
    let cases = [
        (("type = \"i16\"", "type = \"i17\""), "packet `state`, field 1: unknown type `i17`; the types are u8, i8,"),
        (
            ("\"vd_mps\"]", "\"vz_mps\"]"),
            "packet `state`, field 1: the plant has no output `vz_mps`; its outputs are: phi_deg,",
        ),
        (("\"vd_mps\"]", "\"setpoint.climb\"]"), "the scenario has no set point `climb`; add it under [setpoint]"),
        (
            ("\"motor3\"]", "\"motor9\"]"),
            "packet `reply`, field 2: the plant has no input `motor9`; its inputs are: motor1,",
        ),
        (("scale = 100.0", "scale = [1.0, 2.0]"), "packet `state`, field 1: scale has 2 values for 3 fields"),
        (
            ("\"motor3\"], frame", "\"motor3\", \"motor4\"], frame"),
            "frame `ned_to_enu` converts 3 values, but the field group has 4",
        ),
        (("port = 7001", "port = 0"), "packet `reply`: port 0 is not a port"),
        (("frame = \"ned_to_enu\", scale", "value = 3.0, scale"), "give either `from` (what it carries) or `value`"),
        (("skip = true", "skip = false"), "give either `to` (the plant inputs it carries) or `skip = true`"),
        (("byte_order = \"big\"", "byte_order = \"middle\""), "unknown variant `middle`"),
        (("frame = \"ned_to_enu\" }", "frame = \"ned_to_xyz\" }"), "unknown variant `ned_to_xyz`"),
    ];
    for (edit, want) in cases {
        let got = refusal(edit);
        assert!(got.contains(want), "{edit:?}: {got}");
    }
    let two = format!(
        "{SMALL}\n[[from_device]]\nname = \"again\"\nport = 7001\nfields = [{{ type = \"u8\", skip = true }}]\n"
    );
    let e = bind(&two).unwrap_err().to_string();
    assert!(e.contains("packet `again`: the rig already listens on port 7001"), "{e}");
}
