//! FMUs in one process (`silrig sim`, `silrig sweep` with `[plant] fmu`, `[controller] fmu` or `--plant-fmu`,
//! `--controller-fmu`): the generic in-process loop gives the three-process lockstep rig's `trace.csv` byte for byte,
//! with the rig's actuators, sensor noise and actuator faults around an FMU plant, for the airframe FMU under the
//! PID FMU and for the built-in F-16 under the PID FMU. A sweep disperses FMU parameters by variable name and each
//! of its cases is the case `silrig sim --sample` flies alone; planned in shards from another folder, its shards give
//! the same cases. A case whose FMU fails is a failed case naming the FMU's error, a case with NaN outputs fails
//! saying they were refused, and a sampled parameter outside the FMU's declared range is an infeasible case saying so:
//! never a crashed sweep. A plant FMU with no controller named flies under the built-in controller that fits it (the
//! quadrotor's FMU under ours for the quadrotor, hovering, in `sim` and the lockstep rig alike); one that fits none is
//! refused by `sim`, `sweep` and `run`, naming its signals and the flags that name a controller. The FMUs are built
//! from C by `examples/fmu/build.sh`, the quadrotor's by `silrig export-fmu`.

mod common;

use common::Run;
use std::path::Path;
use std::process::{Command, Output};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "fmu-in-process";

fn fmu(name: &str) -> String {
    common::fmu::cached_fmu(SUITE, name)
}

fn silrig(args: &[&str], cwd: &Path) -> Output {
    Command::new(SILRIG).args(args).current_dir(cwd).output().unwrap()
}

fn said(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// `silrig sim ARGS --out DIR/sim` must succeed; its trace.csv.
fn sim_trace(dir: &Path, args: &[&str]) -> Vec<u8> {
    let out = dir.join("sim");
    let o = silrig(&[&["sim"], args, &["--out", out.to_str().unwrap()]].concat(), dir);
    assert!(o.status.success(), "{}", said(&o));
    std::fs::read(out.join("trace.csv")).unwrap()
}

/// `silrig run --mode lockstep ARGS` must succeed; its trace.csv.
fn rig_trace(test: &str, args: &[&str]) -> Vec<u8> {
    let r = Run::start(SILRIG, SUITE, "i", test, &[&["--mode", "lockstep"], args].concat());
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let trace = std::fs::read(r.out.join("trace.csv")).unwrap();
    r.finish();
    trace
}

fn same_bytes(a: &[u8], b: &[u8], what: &str) {
    if a != b {
        let (a, b) = (String::from_utf8_lossy(a), String::from_utf8_lossy(b));
        let first = a.lines().zip(b.lines()).position(|(x, y)| x != y);
        panic!(
            "{what}: the traces differ (first at line {first:?}; {} and {} lines)",
            a.lines().count(),
            b.lines().count()
        );
    }
}

#[test]
fn an_fmu_plant_and_controller_fly_in_one_process_as_in_the_lockstep_rig_with_actuators_and_faults() {
    let dir = common::temp_dir(SUITE, "both");
    let (plant, pid) = (fmu("airframe"), fmu("pid"));
    let airframe = std::fs::read_to_string(format!("{ROOT}/examples/fmu/airframe.toml")).unwrap();
    // The rig's own servo on the rudder, sensor noise on the roll rate and a stuck aileron: the chain around the FMU.
    let path = dir.join("chain.toml");
    std::fs::write(
        &path,
        format!(
            "{airframe}\n[actuators.rudder]\nmin = -20.0\nmax = 20.0\nrate_limit_per_s = 60.0\nlag_time_constant_s = 0.05\n\
             [[faults]]\nat_s = 2.0\ntarget = \"plant\"\naction = \"sensor-noise\"\nchannel = \"p_dps\"\nstd = 0.5\nduration_s = 3.0\n\
             [[faults]]\nat_s = 4.0\ntarget = \"plant\"\naction = \"actuator-stuck\"\nsurface = \"aileron\"\nduration_s = 1.0\n"
        ),
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let flags = ["--plant-fmu", &plant, "--controller-fmu", &pid, path];
    let in_process = sim_trace(&dir, &flags);
    same_bytes(&in_process, &rig_trace("both-rig", &flags), "airframe FMU under the PID FMU");
    let text = String::from_utf8_lossy(&in_process);
    assert_eq!(text.lines().count(), 1002, "a header and 1001 rows");
    assert!(text.lines().next().unwrap().starts_with("t_s,phi_deg"), "{}", &text[..200]);
    // A plant of the user's own gets the figure of all its signals.
    assert!(dir.join("sim/signals.png").is_file());
    // Its summary.json names its signals alone: the rudder is its one input under the rig's `[actuators]`, judged
    // from the position the FMU reports; it has an alpha but no altitude or airspeed of the F-16's names.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sim/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["plant"], "airframe");
    let actuators: Vec<(&str, &str)> = summary["actuators"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a["name"].as_str().unwrap(), a["position"].as_str().unwrap_or("-")))
        .collect();
    assert_eq!(actuators, [("rudder", "rudder_deg")], "{summary}");
    assert!(summary["alpha"].is_object() && summary.get("flight_path").is_none(), "{summary}");
    let text = summary.to_string();
    assert!(!text.contains("aileron") && !text.contains("elevator"), "{text}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn the_f16_under_a_controller_fmu_flies_in_one_process_as_in_the_lockstep_rig() {
    let dir = common::temp_dir(SUITE, "f16");
    let pid = fmu("pid");
    let robust = format!("{ROOT}/configs/robust.toml");
    let flags = ["--controller-fmu", &pid, &robust];
    same_bytes(&sim_trace(&dir, &flags), &rig_trace("f16-rig", &flags), "the F-16 under the PID FMU");
    // The F-16's own figures, not the generic one.
    assert!(dir.join("sim/fig1_states.png").is_file() && !dir.join("sim/signals.png").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// examples/fmu/airframe_sweep.toml in `dir`, naming the FMUs beside it (relative paths, as a user writes them).
fn sweep_config(dir: &Path) -> String {
    std::fs::copy(fmu("airframe"), dir.join("airframe.fmu")).unwrap();
    std::fs::copy(fmu("pid"), dir.join("pid.fmu")).unwrap();
    std::fs::copy(format!("{ROOT}/examples/fmu/airframe_sweep.toml"), dir.join("airframe_sweep.toml")).unwrap();
    dir.join("airframe_sweep.toml").display().to_string()
}

/// cases.csv's rows, split into fields (a reason is quoted and may hold commas).
fn cases(csv: &Path) -> Vec<Vec<String>> {
    let split = |line: &str| {
        let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
        for ch in line.chars() {
            match ch {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut field)),
                _ => field.push(ch),
            }
        }
        fields.push(field);
        fields
    };
    std::fs::read_to_string(csv).unwrap().lines().map(split).collect()
}

#[test]
fn a_sweep_disperses_fmu_parameters_and_each_case_is_the_case_flown_alone_and_in_shards() {
    let dir = common::temp_dir(SUITE, "sweep");
    let config = sweep_config(&dir);
    let out = dir.join("local");
    let o = silrig(&["sweep", &config, "--runs", "120", "--jobs", "2", "--out", out.to_str().unwrap()], Path::new("/"));
    assert!(o.status.success(), "{}", said(&o));
    let text = said(&o);
    assert!(text.contains("flew 120 cases"), "{text}");
    let local = cases(&out.join("cases.csv"));
    let header = &local[0];
    let col = |name: &str| header.iter().position(|c| c == name).unwrap_or_else(|| panic!("no {name} in {header:?}"));
    // The summary's columns name the airframe's signals: its attitude, alpha and rates; no actuator is the rig's.
    for name in ["phi_settle_s", "theta_final_error_deg", "psi_max_error_deg", "alpha_peak_deg", "r_max_late_dps"] {
        col(name);
    }
    assert!(!header.iter().any(|c| c.contains("limit_fraction")), "{header:?}");
    assert!(local[1..].iter().all(|r| !r[col("phi_final_error_deg")].is_empty()), "every flown case has its figures");
    // The FMU's parameters were dispersed: every case flew other values, and the outcomes follow from them.
    let (mass, servo, outcome) = (col("plant.parameters.mass_kg"), col("plant.parameters.servo_tau_s"), col("outcome"));
    let masses: std::collections::BTreeSet<&str> = local[1..].iter().map(|r| r[mass].as_str()).collect();
    assert_eq!(masses.len(), 120);
    let servos: std::collections::BTreeSet<&str> = local[1..].iter().map(|r| r[servo].as_str()).collect();
    assert_eq!(servos.len(), 4, "{servos:?}");
    let passed = local[1..].iter().filter(|r| r[outcome] == "pass").count();
    assert!(
        passed > 0 && passed < 120,
        "{passed} of 120 passed: the example's criteria should split the cases\n{text}"
    );
    // A failed case flown alone gives the figures it had inside the sweep.
    let failed = local[1..].iter().find(|r| r[outcome] == "fail").unwrap();
    let index = failed[0].clone();
    let alone = dir.join("alone");
    let o = silrig(&["sim", &config, "--sample", &index, "--out", alone.to_str().unwrap()], Path::new("/"));
    assert!(o.status.success(), "{}", said(&o));
    let case: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(alone.join("case.json")).unwrap()).unwrap();
    assert_eq!(case["outcome"], "fail");
    let settle = col("outputs.phi_deg.settled");
    let figure =
        case["judgements"].as_array().unwrap().iter().find(|j| j["criterion"] == "outputs.phi_deg.settled").unwrap();
    assert_eq!(figure["value"].as_f64().unwrap().to_string(), failed[settle], "{case}");
    // Planned from the repository, flown from another folder: the plan carries the FMUs' absolute paths.
    let plan = dir.join("plan");
    let o = silrig(
        &["sweep", "plan", &config, "--runs", "120", "--shards", "2", "--out", plan.to_str().unwrap()],
        Path::new(ROOT),
    );
    assert!(o.status.success(), "{}", said(&o));
    for k in ["0", "1"] {
        let o = silrig(&["sweep", "run", plan.to_str().unwrap(), "--index", k], Path::new("/"));
        assert!(o.status.success(), "shard {k}: {}", said(&o));
    }
    let o = silrig(&["sweep", "merge", plan.to_str().unwrap()], Path::new("/"));
    assert!(o.status.success(), "{}", said(&o));
    assert_eq!(cases(&plan.join("cases.csv")), local, "the shards' cases differ from the local sweep's");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_failing_fmu_fails_its_case_and_a_parameter_it_rejects_makes_it_infeasible_never_a_crashed_sweep() {
    let dir = common::temp_dir(SUITE, "misbehave");
    let misbehave = fmu("misbehave");
    // misbehave is a lag y' = u - y; as its own controller (mapped u <- y, y -> u) it closes a loop with itself.
    // `fault` 1: doStep fails at 0.5 s; 5: y reads NaN from 0.5 s on; 7: outside the variable's declared range.
    let path = dir.join("misbehave.toml");
    std::fs::write(
        &path,
        format!(
            "name = \"misbehave\"\nseed = 3\n[timing]\ndt_s = 0.01\nduration_s = 1.0\ncommand_timing = \"same-tick\"\n\
             [plant]\nfmu = \"{misbehave}\"\n[plant.parameters]\nfault = 0.0\nfault_time_s = 0.5\n\
             [controller]\nfmu = \"{misbehave}\"\n[controller.map]\nu = \"y\"\ny = \"u\"\n\
             [dispersions]\n\"plant.parameters.fault\" = {{ dist = \"choice\", values = [0.0, 1.0, 5.0, 7.0] }}\n\
             [criteria.outputs.y]\nabs_max = {{ after_s = 0.0, max = 1000.0 }}\n"
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = silrig(&["sweep", path.to_str().unwrap(), "--runs", "24", "--out", out.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", said(&o));
    let all = cases(&out.join("cases.csv"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    let fault = all[0].iter().position(|c| c == "plant.parameters.fault").unwrap();
    let outcome = all[0].iter().position(|c| c == "outcome").unwrap();
    let rows = |f: &str| all[1..].iter().filter(move |r| r[fault] == f).collect::<Vec<_>>();
    for f in ["0", "1", "5", "7"] {
        assert!(!rows(f).is_empty(), "no case drew fault {f}: {text}");
    }
    assert!(rows("0").iter().all(|r| r[outcome] == "pass"), "{text}");
    assert!(rows("1").iter().all(|r| r[outcome] == "fail"), "{text}");
    assert!(rows("5").iter().all(|r| r[outcome] == "fail"), "{text}");
    assert!(rows("7").iter().all(|r| r[outcome] == "infeasible"), "{text}");
    let reason = all[0].iter().position(|c| c == "reason").unwrap();
    let first = |f: &str| rows(f)[0][reason].clone();
    assert!(first("1").contains("fault 1 at t = 0.5 s: fmi2DoStep returns fmi2Error"), "{}", first("1"));
    assert!(first("5").contains("outputs refused") && first("5").contains("output y is NaN"), "{}", first("5"));
    assert!(first("7").contains("`plant.parameters.fault` = 7 is outside the variable's range 0..6"), "{}", first("7"));
    assert_eq!(json["infeasible"].as_u64().unwrap() as usize, rows("7").len(), "{json}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_fmu_that_cannot_be_opened_or_a_key_it_does_not_read_is_a_clear_error_of_sim_and_sweep() {
    let dir = common::temp_dir(SUITE, "missing");
    let o = silrig(&["sim", "--plant-fmu", "nowhere.fmu", "--out", "x"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("nowhere.fmu") && said(&o).contains("cannot be read"), "{}", said(&o));
    let config = format!("{ROOT}/examples/fmu/airframe_sweep.toml");
    let o = silrig(&["sweep", &config, "--runs", "3", "--plant-fmu", "nowhere.fmu"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("nowhere.fmu"), "{}", said(&o));
    // The F-16's keys do not reach an FMU plant: dispersing them would fly one plant in every case.
    let airframe = fmu("airframe");
    let robust = format!("{ROOT}/configs/sweep-robust.toml");
    let o = silrig(&["sweep", &robust, "--runs", "3", "--plant-fmu", &airframe], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("does not read `") && said(&o).contains("plant.parameters.<variable>"), "{}", said(&o));
    assert!(!dir.join("out").exists(), "nothing is written");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_check_suites_sweep_case_flies_a_controller_fmu_in_one_process() {
    let dir = common::temp_dir(SUITE, "check-sweep");
    let pid = fmu("pid");
    let out = dir.join("out");
    let o = silrig(
        &["check", "configs/check-dispersed.toml", "--controller-fmu", &pid, "--out", out.to_str().unwrap()],
        Path::new(ROOT),
    );
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap()).unwrap();
    assert_eq!(verdict["controller"].as_str().unwrap(), format!("the FMU {pid} in silrig-controller"));
    let measured = verdict["cases"][0]["judgements"][0]["measured"].as_str().unwrap();
    assert!(measured.contains("of 200 passed"), "{measured}");
    // The cases flew the FMU, not our controller: the same dispersions give other figures.
    let csv = std::fs::read_to_string(out.join("dispersed-robust/cases.csv")).unwrap();
    assert_eq!(csv.lines().count(), 201);
    let ours = dir.join("ours");
    let o = silrig(&["check", "configs/check-dispersed.toml", "--out", ours.to_str().unwrap()], Path::new(ROOT));
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    let ours = std::fs::read_to_string(ours.join("dispersed-robust/cases.csv")).unwrap();
    assert_ne!(csv, ours, "the FMU's figures are not our controller's");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A check's `judgements` of one case: (criterion, measured, passed).
fn judgements(out: &Path, case: &str) -> Vec<(String, String, bool)> {
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap()).unwrap();
    let case = verdict["cases"].as_array().unwrap().iter().find(|c| c["name"] == case).unwrap().clone();
    case["judgements"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| (j["criterion"].as_str().unwrap().into(), j["measured"].as_str().unwrap().into(), j["passed"] == true))
        .collect()
}

#[test]
fn check_in_process_flies_a_lockstep_case_of_two_fmus_as_the_rig_does_and_refuses_what_needs_the_rig() {
    let dir = common::temp_dir(SUITE, "check-in-process");
    let (plant, pid) = (fmu("airframe"), fmu("pid"));
    let suite = format!("{ROOT}/examples/fmu/airframe_check.toml");
    let flags = ["--case", "lockstep-steps", "--plant-fmu", &plant, "--controller-fmu", &pid];
    let (one, rig) = (dir.join("one"), dir.join("rig"));
    let o = silrig(&[&["check", &suite, "--in-process"], &flags[..], &["--out", one.to_str().unwrap()]].concat(), &dir);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    assert!(said(&o).contains("lockstep, in one process"), "{}", said(&o));
    let o = silrig(&[&["check", &suite], &flags[..], &["--out", rig.to_str().unwrap()]].concat(), &dir);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    // Both flights of the determinism pair, byte for byte the rig's.
    for run in ["run-1", "run-2"] {
        let trace = |out: &Path| std::fs::read(out.join("lockstep-steps").join(run).join("trace.csv")).unwrap();
        same_bytes(&trace(&one), &trace(&rig), &format!("check --in-process {run}"));
    }
    // The same criteria, the same figures (run_completed says where it flew).
    let (a, b) = (judgements(&one, "lockstep-steps"), judgements(&rig, "lockstep-steps"));
    assert_eq!(a.len(), b.len(), "{a:?}\n{b:?}");
    for (x, y) in a.iter().zip(&b).filter(|(x, _)| x.0 != "run_completed") {
        assert_eq!(x, y);
    }
    assert!(a.iter().all(|j| j.2), "{a:?}");
    assert!(a.iter().any(|j| j.0 == "deterministic" && j.1 == "identical over 1001 ticks"), "{a:?}");
    // The reproduce command keeps the flag.
    let verdict = std::fs::read_to_string(one.join("check.json")).unwrap();
    assert!(verdict.contains("--in-process"), "{verdict}");

    // A lockstep case with a criterion only the rig's processes measure is refused before anything flies.
    let rig_only = dir.join("rig-only.toml");
    std::fs::write(
        &rig_only,
        format!(
            "name = \"rig-only\"\nscenario = \"{ROOT}/examples/fmu/airframe.toml\"\n[[cases]]\nname = \"timed\"\n\
             why = \"compute time\"\nmode = \"lockstep\"\n[cases.criteria]\ncompute_p99 = {{ max_us = 1000.0 }}\n"
        ),
    )
    .unwrap();
    let refused = dir.join("refused");
    let o = silrig(
        &["check", rig_only.to_str().unwrap(), "--in-process", "--plant-fmu", &plant, "--controller-fmu", &pid]
            .iter()
            .copied()
            .chain(["--out", refused.to_str().unwrap()])
            .collect::<Vec<_>>(),
        &dir,
    );
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("case `timed`: `criteria.compute_p99`"), "{}", said(&o));
    assert!(!refused.join("timed").exists(), "nothing flew");
    // A controller of your own is a process: not with --in-process.
    let o = silrig(&["check", "--in-process", "--controller-cmd", "python3 x.py"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("--in-process") && said(&o).contains("--controller-cmd"), "{}", said(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

/// The quadrotor exported as an FMU, under a scenario that gives set points and timing but does not say it is the
/// quadrotor: `sim` and the lockstep rig choose our quadrotor controller by its signals (not the F-16's), give the
/// same bytes, and take it off to a hover at its set point.
#[test]
fn the_quadrotors_fmu_gets_our_quadrotor_controller_and_hovers() {
    let dir = common::temp_dir(SUITE, "quad-fmu");
    let hover = format!("{ROOT}/configs/quad-hover.toml");
    let (quad, _) = common::fmu::export_builtin(SILRIG, &dir, "quad.fmu", Some(&hover));
    let scenario = dir.join("hover.toml");
    std::fs::write(
        &scenario,
        "name = \"quad-fmu-hover\"\n[setpoint]\nalt_m = 2.0\n\
         [timing]\ndt_s = 0.001\nduration_s = 6.0\ncommand_timing = \"next-tick\"\n",
    )
    .unwrap();
    let args = ["--plant-fmu", quad.to_str().unwrap(), scenario.to_str().unwrap()];
    let sim = sim_trace(&dir, &args);
    same_bytes(&sim, &rig_trace("quad-fmu-rig", &args), "the quadrotor's FMU in sim and the lockstep rig");
    let text = String::from_utf8(sim).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"motor1_cmd") && !header.iter().any(|c| c.starts_with("aileron")), "{header:?}");
    let last: Vec<f64> = text.lines().last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    let at = |name: &str| last[header.iter().position(|c| *c == name).unwrap()];
    assert!((at("alt_m") - 2.0).abs() < 0.05, "hovering at {} m", at("alt_m"));
    assert!(at("phi_deg").abs() < 1.0 && at("theta_deg").abs() < 1.0 && at("on_ground") == 0.0);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A plant FMU that neither built-in controller fits (the foreign attitude vehicle: no `vt_fps`, no `alt_m`, no
/// motors), with no controller named, is refused before it flies by `sim`, `sweep` and `run`, naming what each
/// controller missed, the plant's signals and the flags that name one; nothing is written.
#[test]
fn a_plant_fmu_no_built_in_controller_fits_is_refused_naming_its_signals_and_what_to_do() {
    let dir = common::temp_dir(SUITE, "unfit");
    let attitude = fmu("attitude");
    let any_plant = format!("{ROOT}/configs/any-plant.toml");
    let sweep = dir.join("sweep.toml");
    let dispersed = "[dispersions]\n\"setpoint.theta_deg\" = { dist = \"uniform\", min = 5.0, max = 10.0 }\n\
                     [criteria.outputs.theta_deg]\nsettled = { within_s = 5.0, band = 0.5 }\n";
    std::fs::write(&sweep, std::fs::read_to_string(&any_plant).unwrap() + dispersed).unwrap();
    let refusals = [
        silrig(&["sim", "--plant-fmu", &attitude, &any_plant, "--out", "out"], &dir),
        silrig(&["sweep", sweep.to_str().unwrap(), "--runs", "2", "--plant-fmu", &attitude, "--out", "out"], &dir),
    ];
    let run =
        Run::start(SILRIG, SUITE, "i", "unfit-run", &["--mode", "lockstep", "--plant-fmu", &attitude, &any_plant]);
    let said_by_run = format!("{}{}", run.stdout, run.stderr);
    for (what, code, text) in [
        ("sim", refusals[0].status.code(), said(&refusals[0])),
        ("sweep", refusals[1].status.code(), said(&refusals[1])),
        ("run", run.code, said_by_run),
    ] {
        assert_ne!(code, Some(0), "{what}: {text}");
        for part in [
            "fits no built-in controller (ours for the F-16: plant ",
            "has no output `vt_fps`; ours for the quadrotor: plant ",
            "its outputs: phi_deg, theta_deg",
            "its inputs: ",
            "`--controller-fmu FILE`",
            "`--controller-cmd CMD`",
        ] {
            assert!(text.contains(part), "{what} does not say {part:?}: {text}");
        }
    }
    assert!(!run.out.join("trace.csv").exists(), "the run flew");
    assert!(!dir.join("out").exists(), "sim or sweep wrote {}", dir.join("out").display());
    run.finish();
    std::fs::remove_dir_all(dir).unwrap();
}
