//! A device over UDP as the rig's controller (`[controller] device`), against a fake device
//! (`udp_device/fake_device.py`, a real UDP peer the layout's `[process]` starts): the F-16 flown in lockstep with
//! the device's commands, the link's round trip in the report; packets with NaN or of the wrong size refused,
//! counted and the command held; a device that dies restarted; and every refusal named: a device that never
//! answers (its address and ports), a port in use, an unknown type, a signal the plant lacks.

mod common;

use common::Run;
use std::net::UdpSocket;
use std::path::Path;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const SUITE: &str = "udp_device";

/// Two free UDP ports: the device's and the rig's.
fn free_ports() -> (u16, u16) {
    let a = UdpSocket::bind("127.0.0.1:0").unwrap();
    let b = UdpSocket::bind("127.0.0.1:0").unwrap();
    (a.local_addr().unwrap().port(), b.local_addr().unwrap().port())
}

/// The fake device's layout: the F-16's time, roll, pitch and pitch rate out, three f32 surface commands back.
fn layout(device_port: u16, rig_port: u16, mode: &str, send_type: &str, sent_signal: &str) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/udp_device/fake_device.py");
    format!(
        r#"name = "fake"
byte_order = "little"
silent_after_s = 3.0

[process]
command = ["python3", "{script}", "{device_port}", "{rig_port}", "{mode}", "-1.5"]
working_dir = "."

[[to_device]]
name = "state"
port = {device_port}
fields = [
  {{ type = "f64", from = "time_s" }},
  {{ type = "{send_type}", from = ["phi_deg", "{sent_signal}", "q_radps"] }},
]

[[from_device]]
name = "surfaces"
port = {rig_port}
fields = [{{ type = "f32", to = ["aileron", "elevator", "rudder"] }}]
"#,
        script = script.display()
    )
}

/// A 2 s lockstep flight of the F-16 with the fake device in `mode` as its controller.
fn fly(test: &str, mode: &str, layout_text: impl FnOnce(u16, u16) -> String) -> Run {
    let _ = mode;
    fly_scenario(test, "", layout_text)
}

/// [`fly`] with `extra` at the top of the scenario (set points and their steps).
fn fly_scenario(test: &str, extra: &str, layout_text: impl FnOnce(u16, u16) -> String) -> Run {
    let dir = common::temp_dir(SUITE, &format!("{test}-files"));
    let (device_port, rig_port) = free_ports();
    std::fs::write(dir.join("device.toml"), layout_text(device_port, rig_port)).unwrap();
    let scenario = dir.join("scenario.toml");
    std::fs::write(
        &scenario,
        format!(
            "name = \"udp-fake\"\n{extra}\n[controller]\ndevice = \"device.toml\"\n[timing]\ndt_s = 0.01\n\
             duration_s = 2.0\ncommand_timing = \"same-tick\"\n"
        ),
    )
    .unwrap();
    let run = Run::start(SILRIG, SUITE, "ud", test, &[scenario.to_str().unwrap(), "--mode", "lockstep"]);
    std::fs::remove_dir_all(&dir).unwrap();
    run
}

fn fly_mode(test: &str, mode: &str) -> Run {
    fly(test, mode, |d, r| layout(d, r, mode, "f64", "theta_deg"))
}

/// The elevator command column of the trace.
fn elevator_commands(run: &Run) -> Vec<f64> {
    let (header, rows) = run.trace();
    let k = Run::column(&header, "elevator_cmd_deg");
    rows.iter().map(|r| r[k]).collect()
}

fn latency<'a>(run: &'a Run, name: &str) -> &'a serde_json::Value {
    let latencies = run.process("controller")["latencies"].as_array().unwrap();
    latencies.iter().find(|l| l["name"] == name).unwrap_or_else(|| panic!("no {name} in {latencies:?}"))
}

#[test]
fn the_device_commands_the_plant_and_its_round_trip_is_reported() {
    let run = fly_mode("good", "good");
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    let elevator = elevator_commands(&run);
    assert_eq!(elevator.len(), 201);
    // Every tick's command is the device's reply to that tick's packet (same-tick, lockstep).
    assert!(elevator.iter().all(|e| *e == -1.5), "{elevator:?}");
    let round_trip = latency(&run, "controller.device_round_trip");
    assert_eq!(round_trip["summary"]["count"], 201, "{round_trip}");
    assert!(round_trip["summary"]["p50_us"].as_f64().unwrap() > 0.0, "{round_trip}");
    // One packet a tick, and the first again every budget while the device's program starts.
    assert!(run.counter("controller", "device_packets_sent") >= 201);
    assert!(run.counter("controller", "device_packets_received") >= 201);
    assert_eq!(run.counter("controller", "device_replies_missing"), 0);
    // The printed report shows the link beside iceoryx2's figures.
    assert!(run.stdout.contains("controller.device_round_trip"), "{}", run.stdout);
    run.finish();
}

#[test]
fn a_set_point_the_device_is_sent_takes_each_step_at_its_tick() {
    // The device echoes the pitch set point it is sent as its elevator command: -1.5 until the step at 1 s, then 2.
    let extra = "[setpoint]\ntheta_deg = -1.5\n[[setpoint_steps]]\nat_s = 1.0\ntheta_deg = 2.0\n";
    let run = fly_scenario("steps", extra, |d, r| layout(d, r, "echo", "f64", "setpoint.theta_deg"));
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    let elevator = elevator_commands(&run);
    assert_eq!(elevator.len(), 201);
    assert!(elevator[..100].iter().all(|e| *e == -1.5), "{elevator:?}");
    assert!(elevator[100..].iter().all(|e| *e == 2.0), "{elevator:?}");
    run.finish();
}

#[test]
fn packets_with_nan_or_of_the_wrong_size_are_refused_counted_and_the_command_held() {
    for mode in ["nan", "short"] {
        let run = fly_mode(mode, mode);
        assert_eq!(run.code, Some(0), "{mode}: {}\n{}", run.stdout, run.stderr);
        // Every 10th reply of about 201 is bad (a packet resent while the device starts up adds one or two): about
        // 20 refused, each leaving its tick without a fresh command, so the last one stays.
        let counter = if mode == "nan" { "device_packets_refused_nan" } else { "device_packets_refused_size" };
        let refused = run.counter("controller", counter);
        assert!((19..=21).contains(&refused), "{mode}: {refused} refused");
        assert!(run.counter("controller", "device_replies_missing") >= refused - 1, "{mode}");
        assert!(elevator_commands(&run).iter().all(|e| *e == -1.5), "{mode}");
        // Said once, in words.
        let said = std::fs::read_to_string(run.out.join("controller.stderr.log")).unwrap();
        let want =
            if mode == "nan" { "field 2 is NaN, not a finite number" } else { "of 8 bytes refused: its layout has 12" };
        assert_eq!(said.matches(want).count(), 1, "{said}");
        run.finish();
    }
}

#[test]
fn a_device_that_dies_is_started_again() {
    let run = fly_mode("dies", "die-after");
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    // 50 replies a life, 201 ticks (and a few without a device before each restart): at least 2 restarts, the
    // last command held between lives.
    assert!(run.counter("controller", "device_restarts") >= 2, "{}", run.process("controller"));
    assert!(elevator_commands(&run).iter().all(|e| *e == -1.5));
    run.finish();
}

#[test]
fn in_realtime_the_devices_program_runs_at_the_controllers_scheduling_in_every_life() {
    // A program left on the normal scheduler beside a real-time controller answered under half of a 1 kHz loop's
    // packets on a busy machine: each life of it (the first and the restarted ones) says what it runs at.
    let dir = common::temp_dir(SUITE, "scheduling-files");
    let (device_port, rig_port) = free_ports();
    let text = layout(device_port, rig_port, "die-after", "f64", "theta_deg")
        .replace(r#""-1.5"]"#, r#""-1.5", "scheduling.txt"]"#);
    std::fs::write(dir.join("device.toml"), text).unwrap();
    let scenario = dir.join("scenario.toml");
    let timing = "[timing]\ndt_s = 0.01\nduration_s = 2.0\ncommand_timing = \"same-tick\"\n";
    std::fs::write(&scenario, format!("name = \"udp-fake\"\n[controller]\ndevice = \"device.toml\"\n{timing}"))
        .unwrap();
    let run = Run::start(SILRIG, SUITE, "ud", "scheduling", &[scenario.to_str().unwrap(), "--mode", "realtime"]);
    assert_eq!(run.code, Some(0), "{}\n{}", run.stdout, run.stderr);
    let lives = std::fs::read_to_string(dir.join("scheduling.txt")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    // 50 replies a life, 201 ticks: a first life and restarted ones.
    assert!(lives.lines().count() >= 2, "{lives}");
    // "SCHED_FIFO 79, memory locked" as root; "SCHED_OTHER, ..." where real-time priority is refused.
    let controller = run.process("controller")["scheduling"].as_str().unwrap().to_string();
    let policy = controller.split(',').next().unwrap();
    let want = if policy == "SCHED_OTHER" { "SCHED_OTHER 0".to_string() } else { policy.to_string() };
    assert!(
        lives.lines().all(|life| life == want),
        "the controller runs at {controller}; the device's lives:\n{lives}"
    );
    run.finish();
}

#[test]
fn a_device_that_never_answers_fails_the_run_naming_its_address_and_ports() {
    let (mut device_port, mut rig_port) = (0, 0);
    let run = fly("silent", "silent", |d, r| {
        (device_port, rig_port) = (d, r);
        layout(d, r, "silent", "f64", "theta_deg")
    });
    assert_ne!(run.code, Some(0), "{}", run.stdout);
    let said = format!("{}{}", run.stdout, run.stderr);
    let want = format!("device `fake` at 127.0.0.1 sent no valid packet to UDP port {rig_port} for 3 s");
    assert!(said.contains(&want), "{said}");
    assert!(said.contains(&format!("packets to it went to port {device_port}")), "{said}");
    run.finish();
}

#[test]
fn a_port_in_use_an_unknown_type_and_a_missing_signal_are_refused_by_name() {
    let mut taken = None;
    let run = fly("port", "good", |d, r| {
        taken = Some(UdpSocket::bind(("0.0.0.0", r)).unwrap());
        layout(d, r, "good", "f64", "theta_deg")
    });
    let port = taken.as_ref().unwrap().local_addr().unwrap().port();
    let said = format!("{}{}", run.stdout, run.stderr);
    assert_ne!(run.code, Some(0));
    assert!(
        said.contains(&format!(
            "device `fake`: cannot listen on UDP port {port} for packet `surfaces`: the port is in use"
        )),
        "{said}"
    );
    run.finish();
    drop(taken);

    let run = fly("type", "good", |d, r| layout(d, r, "good", "f24", "theta_deg"));
    let said = format!("{}{}", run.stdout, run.stderr);
    assert_ne!(run.code, Some(0));
    assert!(said.contains("packet `state`, field 2: unknown type `f24`; the types are u8, i8"), "{said}");
    run.finish();

    let run = fly("signal", "good", |d, r| layout(d, r, "good", "f64", "alt_m"));
    let said = format!("{}{}", run.stdout, run.stderr);
    assert_ne!(run.code, Some(0));
    assert!(
        said.contains("packet `state`, field 2: the plant has no output `alt_m`; its outputs are: phi_deg"),
        "{said}"
    );
    run.finish();
}
