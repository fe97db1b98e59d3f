//! Golden traces: the `trace.csv` of every shipped scenario (and of the embedded default), as `silrig sim` writes
//! it, is fingerprinted and compared with the fingerprint recorded when the trace last changed on purpose. A
//! refactoring that claims to change no behaviour must leave every fingerprint as it is; a change that moves the
//! traces must update this table in the same commit, saying why. (The rig's lockstep traces equal these bit for
//! bit: `tests/rig.rs`.)
//!
//! The fingerprints are FNV-1a 64 of the CSV bytes, recorded on x86_64 Linux with glibc's libm; another libm may
//! round `exp`/`sin` differently in the last bit, which shows here first.

use silrig::scenario::Scenario;
use std::path::Path;

/// (scenario, FNV-1a 64 of trace.csv, rows, theta_deg in the last row).
const GOLDEN: [(&str, u64, usize, f64); 9] = [
    ("embedded default", 0x1d00_bb7d_2760_37ee, 1001, 9.947743275854997),
    ("faults-demo", 0xdb90_c6ec_4956_2b96, 1001, 9.948573807122512),
    ("paper", 0x1b6f_6ee5_0eb0_569c, 1001, 10.54604740751627),
    ("paper-ideal", 0xe125_bd67_4b09_5049, 1001, 9.971834435552738),
    ("paper-ideal-sign", 0x65bb_b396_7a88_6a71, 1001, 9.98677969302759),
    ("paper-next-tick", 0xfb85_9a2d_a374_eff0, 1001, 13.227882796507306),
    ("robust", 0x1d00_bb7d_2760_37ee, 1001, 9.947743275854997),
    // The robust scenario with 0.01 deg/s of gyro noise on q (and dispersions and criteria, which sim ignores).
    ("sweep-robust", 0xe21d_6e73_08b6_165a, 1001, 9.947334720841178),
    // The robust scenario flown 140 s with the elevator hard-over at 60 s for 0.3 s.
    ("sweep-hard-over", 0x95b7_db40_a84e_4af4, 14001, 10.068518443977899),
];

/// The quadrotor's scenarios (`[plant] model = "quad"`), flown as `silrig sim` flies them (the rig's loop in one
/// process, `silrig::adapters::in_process`, which the lockstep rig equals bit for bit: `tests/quad.rs`): (scenario, FNV-1a
/// 64 of trace.csv, rows, alt_m in the last row). Recorded again when the model gained RotorPy's axial inflow and
/// frame drag (every climb, descent and tilted flight moves; the hover point does not).
const QUAD_GOLDEN: [(&str, u64, usize, f64); 4] = [
    ("quad-hover", 0xa223_0f86_7e37_8b1c, 10001, 2.0004743887764787),
    // quad-hover with dispersions and criteria, which sim ignores.
    ("quad-sweep", 0xa223_0f86_7e37_8b1c, 10001, 2.0004743887764787),
    ("quad-steps", 0x681f_0725_be09_5cc0, 6001, 1.9523565235296716),
    // A roll step at 2 s and back at 4 s (`[[setpoint_steps]]`), recorded when the schedule came.
    ("quad-roll-step", 0xf717_d211_9cf1_565c, 6001, 2.0061456520570338),
];

fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
}

fn scenario(name: &str) -> Scenario {
    if name == "embedded default" {
        return Scenario::embedded_default();
    }
    Scenario::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("configs").join(format!("{name}.toml"))).unwrap()
}

#[test]
fn every_shipped_scenario_flies_its_golden_trace() {
    let mut moved = Vec::new();
    for (name, fingerprint, rows, final_theta_deg) in GOLDEN {
        let trace = silrig::sim::run(&scenario(name)).unwrap();
        let mut csv = Vec::new();
        trace.write_csv(&mut csv).unwrap();
        let theta = trace.column("theta_deg").unwrap();
        let got = (fnv1a64(&csv), trace.rows.len(), *theta.last().unwrap());
        if got != (fingerprint, rows, final_theta_deg) {
            moved.push(format!(
                "{name}: fingerprint {:#018x}, {} rows, final theta {} deg (golden {fingerprint:#018x}, {rows}, {final_theta_deg})",
                got.0, got.1, got.2
            ));
        }
    }
    assert!(moved.is_empty(), "traces moved:\n{}", moved.join("\n"));
}

#[test]
fn every_quadrotor_scenario_flies_its_golden_trace() {
    let mut moved = Vec::new();
    for (name, fingerprint, rows, final_alt_m) in QUAD_GOLDEN {
        let s = scenario(name);
        let trace = silrig::adapters::in_process::Models::open(&s).unwrap().fly(&s).unwrap().trace;
        let mut csv = Vec::new();
        trace.write_csv(&mut csv).unwrap();
        let got = (fnv1a64(&csv), trace.rows.len(), *trace.column("alt_m").unwrap().last().unwrap());
        if got != (fingerprint, rows, final_alt_m) {
            moved.push(format!(
                "{name}: fingerprint {:#018x}, {} rows, final alt {} m (golden {fingerprint:#018x}, {rows}, {final_alt_m})",
                got.0, got.1, got.2
            ));
        }
    }
    assert!(moved.is_empty(), "traces moved:\n{}", moved.join("\n"));
}

#[test]
fn every_shipped_scenario_has_a_golden_trace() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let Ok(scenario) = Scenario::load(&path) else { continue };
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        // The any-plant scenario is for plants of the user's own (set points and timing, nothing of the F-16): no
        // F-16 trace to hold; tests/check.rs and tests/plants.rs fly it with the toy plants.
        if name == "any-plant" {
            continue;
        }
        // A device's scenario (Betaflight's SITL) flies another program in realtime: no trace to hold byte for byte;
        // tests/betaflight.rs flies it.
        if scenario.controller.device.is_some() {
            continue;
        }
        let mut golden = GOLDEN.iter().map(|g| g.0).chain(QUAD_GOLDEN.iter().map(|g| g.0));
        assert!(golden.any(|g| g == name), "{} has no golden trace ({})", path.display(), scenario.name);
    }
}
