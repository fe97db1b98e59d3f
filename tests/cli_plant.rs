//! The `silrig trim` and `silrig plant derivative` commands as a user runs them.

use std::io::Write;
use std::process::{Command, Stdio};

const HEADER: &str = "vt_fps,alpha_rad,beta_rad,phi_rad,theta_rad,psi_rad,p_radps,q_radps,r_radps,north_ft,east_ft,alt_ft,power_pct,throttle,elevator_deg,aileron_deg,rudder_deg,xcg";

fn derivative(input: &str) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_silrig"))
        .args(["plant", "derivative"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(input.as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    (out.status.code().unwrap(), String::from_utf8(out.stdout).unwrap(), String::from_utf8(out.stderr).unwrap())
}

#[test]
fn derivative_csv_reproduces_the_check_case_and_round_trips() {
    // Columns in another order plus an extra one: both allowed.
    let input = format!("note,{HEADER}\nx,500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,0.4\n");
    let (code, out, err) = derivative(&input);
    assert_eq!(code, 0, "{err}");
    let mut lines = out.lines();
    assert_eq!(
        lines.next().unwrap(),
        "vt_dot,alpha_dot,beta_dot,phi_dot,theta_dot,psi_dot,p_dot,q_dot,r_dot,north_dot,east_dot,alt_dot,power_dot"
    );
    let values: Vec<f64> = lines.next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!(values.len(), 13);
    // Printing round-trips exactly: the text reparses to the library's own f64s.
    let (x, u) = (
        silrig::plant::F16State::from_array(&[
            500.0, 0.5, -0.2, -1.0, 1.0, -1.0, 0.7, -0.8, 0.9, 1000.0, 900.0, 10000.0, 90.0,
        ]),
        silrig::plant::ControlInputs { throttle: 0.9, elevator_deg: 20.0, aileron_deg: -15.0, rudder_deg: -20.0 },
    );
    let want = silrig::plant::F16Model::new(0.4).derivative(&x, &u, &Default::default());
    assert_eq!(values, want.to_vec());
    assert!((values[7] - 0.9649671).abs() < 1e-6);
}

#[test]
fn xcg_column_is_optional_and_defaults_to_0_35() {
    let header = HEADER.trim_end_matches(",xcg");
    let (code, out, _) =
        derivative(&format!("{header}\n500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20\n"));
    assert_eq!(code, 0);
    let q_dot: f64 = out.lines().nth(1).unwrap().split(',').nth(7).unwrap().parse().unwrap();
    assert!((q_dot - -0.1457558572).abs() < 1e-9, "{q_dot}");
}

#[test]
fn bad_rows_name_the_line_and_column_and_exit_2_keeping_earlier_rows() {
    let good = "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,0.4";
    for (bad_row, needle) in [
        (
            "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,abc",
            "line 3, column `xcg`: not a number",
        ),
        ("500,NaN,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,0.4", "line 3, column `alpha_rad`: NaN"),
        ("500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20", "line 3, column `aileron_deg`: missing value"),
    ] {
        let (code, out, err) = derivative(&format!("{HEADER}\n{good}\n{bad_row}\n{good}\n"));
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(needle), "stderr {err:?} lacks {needle:?}");
        assert_eq!(out.lines().count(), 2, "the header and the good row stay written: {out}");
    }
    let (code, _, err) = derivative("vt_fps,alpha_rad\n1,2\n");
    assert_eq!(code, 2);
    assert!(err.contains("line 1: the header has no column `beta_rad`"), "{err}");
}

#[test]
fn states_outside_the_models_envelope_stop_naming_the_line_and_column_never_printing_nan() {
    // VT = 0 divides by zero; 150,000 ft is above the atmosphere's 142,248 ft, where its density formula gives NaN.
    let good = "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,0.4";
    for (bad_row, needle) in [
        (
            "0,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90,0.9,20,-15,-20,0.4",
            "line 3, column `vt_fps`: outside the model's envelope: vt_fps = 0: the airspeed must be above 0",
        ),
        (
            "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,150000,90,0.9,20,-15,-20,0.4",
            "line 3, column `alt_ft`: outside the model's envelope: alt_ft = 150000: above the atmosphere model's ceiling",
        ),
    ] {
        let (code, out, err) = derivative(&format!("{HEADER}\n{good}\n{bad_row}\n{good}\n"));
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(needle), "stderr {err:?} lacks {needle:?}");
        assert_eq!(out.lines().count(), 2, "the header and the good row stay written: {out}");
        assert!(!out.to_lowercase().contains("nan"), "{out}");
    }
}

#[test]
fn trim_command_prints_text_and_json() {
    let out = Command::new(env!("CARGO_BIN_EXE_silrig"))
        .args(["trim", "--airspeed-mps", "150", "--altitude-ft", "25000", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["alpha_deg"].as_f64().unwrap() - 6.789).abs() < 0.001);
    assert!(v["throttle"].as_f64().unwrap() > 0.0);

    let out = Command::new(env!("CARGO_BIN_EXE_silrig"))
        .args(["trim", "--airspeed-mps", "40", "--altitude-ft", "25000"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("too low"));
}
