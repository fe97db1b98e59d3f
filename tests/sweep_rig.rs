//! `silrig sweep --controller-cmd`: a sweep of a user's controller, each case flown through the three-process
//! lockstep rig. The same bytes with one rig or two side by side and through a plan's shards; a case flown alone
//! (`silrig sim --sample I --controller-cmd`) is the sweep's case, and its trace is a lone `silrig run --mode
//! lockstep` of its scenario byte for byte; a controller that crashes in some cases fails those cases with the
//! rig's reason and the sweep goes on, as does one that never answers; a command that cannot run, or one beside a
//! controller FMU, is refused, while a plant FMU sweeps under it. Every sweep leaves no run folder, scratch folder
//! or shared memory behind.

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "sweep_rig";

/// The Python PID example (with libsilrig_client.so built for it).
fn python_pid() -> String {
    common::client_lib(SILRIG);
    format!("python3 {ROOT}/examples/python/pid_attitude.py")
}

/// configs/sweep-robust.toml shortened to 2 s (its criteria's windows with it), the theta set point dispersed too,
/// written into `dir`.
fn short_config(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(Path::new(ROOT).join("configs/sweep-robust.toml")).unwrap();
    let text = text
        .replace("duration_s = 10.0", "duration_s = 2.0")
        .replace("within_s = 8.0", "within_s = 1.5")
        .replace("after_s = 8.0", "after_s = 1.5")
        .replace(
            "[dispersions]\n",
            "[dispersions]\n\"setpoint.theta_deg\" = { dist = \"uniform\", min = 5.0, max = 15.0 }\n",
        )
        // Descents too (the shipped sweep draws none), so that some case cannot be trimmed.
        .replace(
            "\"initial.theta_deg\" = { dist = \"normal\", mean = 7.0, std = 2.0, min = 5.0, max = 15.0 }",
            "\"initial.theta_deg\" = { dist = \"normal\", mean = 5.0, std = 2.0, min = -5.0, max = 15.0 }",
        );
    assert!(text.contains("min = -5.0, max = 15.0"), "the shipped sweep's initial.theta_deg changed");
    let path = dir.join("short.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `silrig ARGS` from the repository root, to its end (5 minutes at most), leaving nothing behind.
fn silrig(args: &[&str]) -> (Option<i32>, String, String) {
    common::run_leaving_nothing(SILRIG, args)
}

/// `silrig ARGS`, which must succeed.
fn ok(args: &[&str]) -> String {
    let (code, stdout, stderr) = silrig(args);
    assert_eq!(code, Some(0), "silrig {args:?}:\n{stdout}{stderr}");
    stdout
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn a_sweep_of_the_python_pid_is_the_same_on_one_rig_two_and_shards_and_a_case_is_a_lone_lockstep_run() {
    let dir = common::temp_dir(SUITE, "same");
    let config = short_config(&dir);
    let config = config.to_str().unwrap();
    let pid = python_pid();
    let out = |name: &str| dir.join(name).display().to_string();
    ok(&["sweep", config, "--runs", "8", "--jobs", "1", "--controller-cmd", &pid, "--out", &out("one")]);
    let stdout = ok(&["sweep", config, "--runs", "8", "--jobs", "2", "--controller-cmd", &pid, "--out", &out("two")]);
    let csv = read(&dir.join("one/cases.csv"));
    assert_eq!(csv, read(&dir.join("two/cases.csv")), "one rig or two side by side: the same cases");
    assert_eq!(read(&dir.join("one/sweep.json")), read(&dir.join("two/sweep.json")));
    assert_eq!(csv.lines().count(), 9, "{csv}");
    // Every case of this sweep is flown (the first one cannot be trimmed) and the worst cases are printed with the
    // command that flies them alone, the controller's command quoted for a shell.
    assert!(csv.lines().any(|l| l.contains(",pass,")), "{csv}");
    assert!(csv.lines().any(|l| l.contains(",fail,")), "{csv}");
    assert!(csv.lines().nth(1).unwrap().starts_with("0,infeasible,\"initial condition:"), "{csv}");
    assert!(stdout.contains(&format!("--controller-cmd '{pid}' --sample ")), "{stdout}");
    for stem in ["histograms", "scatter", "envelope"] {
        assert!(dir.join("two").join(format!("{stem}.png")).exists(), "{stem} drawn");
    }

    // A plan carries the command to the workers; its merged shards are the same sweep.
    ok(&["sweep", "plan", config, "--runs", "8", "--shards", "3", "--controller-cmd", &pid, "--out", &out("plan")]);
    let manifest: Value = serde_json::from_str(&read(&dir.join("plan/manifest.json"))).unwrap();
    assert_eq!(manifest["controller_cmd"], pid.as_str());
    for k in ["0", "1", "2"] {
        ok(&["sweep", "run", &out("plan"), "--index", k, "--jobs", "2"]);
    }
    ok(&["sweep", "merge", &out("plan")]);
    assert_eq!(read(&dir.join("plan/cases.csv")), csv);
    assert_eq!(read(&dir.join("plan/sweep.json")), read(&dir.join("one/sweep.json")));
    let script = ok(&["sweep", "slurm", &out("plan")]);
    assert!(read(&dir.join("plan/sweep.sbatch")).contains(&format!("#SBATCH --chdir={ROOT}\n")), "{script}");

    // Case 3 flown alone is the sweep's case 3 (its shard holds it in full) ...
    let shard: Value = serde_json::from_str(&read(&dir.join("plan/shards/shard-1-of-3.json"))).unwrap();
    let in_sweep = shard["cases"].as_array().unwrap().iter().find(|c| c["index"] == 3).unwrap().clone();
    let sim = ok(&["sim", config, "--sample", "3", "--controller-cmd", &pid, "--out", &out("case-3")]);
    let alone: Value = serde_json::from_str(&read(&dir.join("case-3/case.json"))).unwrap();
    assert_eq!(alone, in_sweep, "{sim}");
    assert_ne!(alone["outcome"], "infeasible");
    // ... and its trace is a lone `silrig run --mode lockstep` of its scenario, byte for byte.
    let run_id = format!("sr{}-lone", std::process::id());
    let scenario = out("case-3/case-scenario.toml");
    let lone = out("lone");
    ok(&[
        "run",
        "--mode",
        "lockstep",
        "--quiet",
        "--no-figures",
        "--controller-cmd",
        &pid,
        "--run-id",
        &run_id,
        "--out",
        &lone,
        &scenario,
    ]);
    common::no_shared_memory_left(&run_id);
    assert!(read(&dir.join("lone/trace.csv")) == read(&dir.join("case-3/trace.csv")), "the traces differ");
    // The case alone draws its figures; a run asked for none (as a sweep's runs are) has the same trace.
    assert!(dir.join("case-3/fig1_states.png").exists());
    assert!(!dir.join("lone/fig1_states.png").exists() && dir.join("lone/report.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_controller_that_crashes_fails_its_cases_with_the_reason_and_the_sweep_goes_on() {
    let dir = common::temp_dir(SUITE, "crash");
    let config = short_config(&dir);
    common::client_lib(SILRIG);
    let crashing = format!("python3 {ROOT}/tests/clients/crash_above.py 10");
    let out = dir.join("sweep").display().to_string();
    ok(&[
        "sweep",
        config.to_str().unwrap(),
        "--runs",
        "8",
        "--jobs",
        "2",
        "--controller-cmd",
        &crashing,
        "--out",
        &out,
    ]);
    let csv = read(&dir.join("sweep/cases.csv"));
    let crashed: Vec<&str> = csv.lines().filter(|l| l.contains("crash_above: theta set point")).collect();
    assert!(!crashed.is_empty() && crashed.len() < 7, "some cases crash, not all:\n{csv}");
    for line in &crashed {
        assert!(line.contains(",fail,\"departed at 0.50 s: controller: exit status 3"), "{line}");
    }
    let summary: Value = serde_json::from_str(&read(&dir.join("sweep/sweep.json"))).unwrap();
    assert_eq!(summary["runs"], 8);
    assert!(csv.lines().any(|l| l.contains(",pass,")), "the cases below the threshold fly: {csv}");

    // A controller that takes samples and never answers: the plant gives up on it, and the case fails saying so.
    let silent = format!("python3 {ROOT}/tests/clients/misbehaving.py never");
    let out = dir.join("silent").display().to_string();
    ok(&["sweep", config.to_str().unwrap(), "--runs", "3", "--jobs", "2", "--controller-cmd", &silent, "--out", &out]);
    let csv = read(&dir.join("silent/cases.csv"));
    for line in csv.lines().skip(2) {
        assert!(line.contains(",fail,\"departed at ") && line.contains("no command for tick 0"), "{line}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_controller_command_that_cannot_run_or_flies_beside_a_controller_fmu_is_refused_with_nothing_written() {
    let dir = common::temp_dir(SUITE, "refused");
    let config = short_config(&dir);
    let config = config.to_str().unwrap();
    let out = dir.join("out").display().to_string();
    let missing = "surely-no-such-controller --gain 2";
    for args in [
        vec!["sweep", config, "--runs", "4", "--controller-cmd", missing, "--out", &out],
        vec!["sweep", "plan", config, "--runs", "4", "--shards", "2", "--controller-cmd", missing, "--out", &out],
        vec!["sim", config, "--sample", "1", "--controller-cmd", missing, "--out", &out],
    ] {
        let (code, stdout, stderr) = silrig(&args);
        assert_eq!(code, Some(2), "{args:?}: {stdout}{stderr}");
        assert!(stderr.contains("--controller-cmd: cannot find `surely-no-such-controller`"), "{stderr}");
        assert!(!Path::new(&out).exists(), "{args:?} wrote {out}");
    }
    let fmu = dir.join("controller.fmu").display().to_string();
    let (code, _, stderr) =
        silrig(&["sweep", config, "--runs", "4", "--controller-cmd", "python3 x.py", "--controller-fmu", &fmu]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("flies the controller FMU") && stderr.contains("sweep one controller at a time"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_plant_fmu_sweeps_under_a_controller_command() {
    let dir = common::temp_dir(SUITE, "plant-fmu");
    let fmu = common::fmu::cached_fmu(SUITE, "airframe");
    std::fs::copy(&fmu, dir.join("airframe.fmu")).unwrap();
    // examples/fmu/airframe_sweep.toml without its controller FMU (and the gain dispersed on it), shortened to 4 s.
    let text = std::fs::read_to_string(Path::new(ROOT).join("examples/fmu/airframe_sweep.toml")).unwrap();
    let (head, rest) = text.split_once("[controller]").unwrap();
    let (_, tail) = rest.split_once("[dispersions]").unwrap();
    let tail = tail.lines().filter(|l| !l.starts_with("\"controller.")).collect::<Vec<_>>().join("\n");
    let config = dir.join("airframe_sweep.toml");
    std::fs::write(&config, format!("{}[dispersions]{tail}\n", head.replace("duration_s = 10.0", "duration_s = 4.0")))
        .unwrap();
    let pid = python_pid();
    let out = dir.join("sweep").display().to_string();
    let stdout =
        ok(&["sweep", config.to_str().unwrap(), "--runs", "4", "--jobs", "2", "--controller-cmd", &pid, "--out", &out]);
    let csv = read(&dir.join("sweep/cases.csv"));
    assert_eq!(csv.lines().count(), 5, "{stdout}");
    assert!(csv.lines().skip(1).all(|l| l.contains(",pass,") || l.contains(",fail,")), "every case flown: {csv}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The Python toy plant (tests/clients/toy_plant.py, with libsilrig_client.so built for it).
fn toy_plant() -> String {
    common::client_lib(SILRIG);
    format!("python3 {ROOT}/tests/clients/toy_plant.py")
}

/// A 3 s scenario for the toy plant written into `dir`: its gain and its start roll (a start value by signal name)
/// dispersed as `plant.parameters.*`, the pitch set point as `setpoint.theta_deg`, criteria on its outputs by name.
fn toy_config(dir: &Path) -> PathBuf {
    let text = "name = \"toy-sweep\"\nseed = 3\n\
                [setpoint]\ntheta_deg = 10.0\n\
                [plant.parameters]\ngain_dps2_per_deg = 4.0\nphi_deg = 0.0\n\
                [timing]\ndt_s = 0.01\nduration_s = 3.0\ncommand_timing = \"next-tick\"\n\
                [dispersions]\n\
                \"plant.parameters.gain_dps2_per_deg\" = { dist = \"uniform\", min = 0.5, max = 8.0 }\n\
                \"plant.parameters.phi_deg\" = { dist = \"uniform\", min = -10.0, max = 10.0 }\n\
                \"setpoint.theta_deg\" = { dist = \"uniform\", min = 5.0, max = 15.0 }\n\
                [criteria.outputs.theta_deg]\nsettled = { within_s = 2.8, band = 0.5 }\n\
                [criteria.outputs.phi_deg]\nabs_max = { after_s = 2.0, max = 1.0 }\n";
    let path = dir.join("toy_sweep.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A column of a CSV's text by its header name: (header index, the rows' cells).
fn csv_column(csv: &str, name: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let at = lines.next().unwrap().split(',').position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    lines.map(|l| l.split(',').nth(at).unwrap().to_string()).collect()
}

/// `silrig sweep` with these commands flown on one rig, on two, and as a 2-shard plan merged: the same bytes each
/// time; returns the first sweep's stdout and `cases.csv`.
fn same_sweep_three_ways(dir: &Path, config: &str, runs: &str, commands: &[&str]) -> (String, String) {
    let out = |name: &str| dir.join(name).display().to_string();
    let sweep = |jobs: &str, name: &str| {
        let out = out(name);
        ok(&[&["sweep", config, "--runs", runs, "--jobs", jobs, "--out", &out], commands].concat())
    };
    let stdout = sweep("1", "one");
    sweep("2", "two");
    let csv = read(&dir.join("one/cases.csv"));
    assert_eq!(csv, read(&dir.join("two/cases.csv")), "one rig or two side by side: the same cases");
    assert_eq!(read(&dir.join("one/sweep.json")), read(&dir.join("two/sweep.json")));
    ok(&[&["sweep", "plan", config, "--runs", runs, "--shards", "2", "--out", &out("plan")], commands].concat());
    for k in ["0", "1"] {
        ok(&["sweep", "run", &out("plan"), "--index", k, "--jobs", "2"]);
    }
    ok(&["sweep", "merge", &out("plan")]);
    assert_eq!(read(&dir.join("plan/cases.csv")), csv, "the merged shards: the same cases");
    assert_eq!(read(&dir.join("plan/sweep.json")), read(&dir.join("one/sweep.json")));
    (stdout, csv)
}

#[test]
fn a_sweep_of_a_python_plant_is_the_same_on_one_rig_two_and_shards_and_its_dispersions_reach_the_plant() {
    let dir = common::temp_dir(SUITE, "toy");
    let config = toy_config(&dir);
    let config = config.to_str().unwrap();
    let (toy, pid) = (toy_plant(), python_pid());
    let commands = ["--plant-cmd", toy.as_str(), "--controller-cmd", pid.as_str()];
    let (stdout, csv) = same_sweep_three_ways(&dir, config, "6", &commands);
    assert_eq!(csv.lines().count(), 7, "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.contains(",pass,") || l.contains(",fail,")), "every case flown: {csv}");
    assert!(csv.lines().any(|l| l.contains(",pass,")) && csv.lines().any(|l| l.contains(",fail,")), "{csv}");
    assert!(stdout.contains(&format!("--plant-cmd '{toy}' --sample ")), "{stdout}");
    let manifest: Value = serde_json::from_str(&read(&dir.join("plan/manifest.json"))).unwrap();
    assert_eq!((manifest["plant_cmd"].as_str(), manifest["controller_cmd"].as_str()), (Some(&*toy), Some(&*pid)));

    // Case 4 flown alone is the sweep's case, and its dispersions reached the processes: the toy starts at the
    // sampled roll (a start value by signal name), and the PID's pitch error at tick 0 is the sampled set point.
    let case_dir = dir.join("case-4");
    ok(&[&["sim", config, "--sample", "4", "--out", case_dir.to_str().unwrap()], &commands[..]].concat());
    let alone: Value = serde_json::from_str(&read(&case_dir.join("case.json"))).unwrap();
    assert_eq!(alone["outcome"].as_str(), csv_column(&csv, "outcome").get(4).map(String::as_str));
    let trace = read(&case_dir.join("trace.csv"));
    let first = |column: &str| csv_column(&trace, column)[0].parse::<f64>().unwrap();
    let sampled = |column: &str| csv_column(&csv, column)[4].parse::<f64>().unwrap();
    assert_eq!(first("phi_deg"), sampled("plant.parameters.phi_deg"));
    assert_ne!(first("phi_deg"), 0.0);
    assert_eq!(first("err_theta_deg"), sampled("setpoint.theta_deg"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_sweep_of_jsbsims_cessna_is_the_same_on_one_rig_two_and_shards_trimmed_where_each_case_says() {
    let dir = common::temp_dir(SUITE, "jsbsim");
    common::client_lib(SILRIG);
    let python = common::venv_python("jsbsim", "jsbsim");
    let jsbsim = format!("{} {ROOT}/examples/python/jsbsim_plant.py", python.display());
    // examples/python/jsbsim_sweep.toml shortened to 3 s, its settling window with it.
    let text = read(&Path::new(ROOT).join("examples/python/jsbsim_sweep.toml"))
        .replace("duration_s = 10.0", "duration_s = 3.0")
        .replace("within_s = 8.0", "within_s = 2.5");
    let config = dir.join("jsbsim_sweep.toml");
    std::fs::write(&config, text).unwrap();
    let pid = python_pid();
    let commands = ["--plant-cmd", jsbsim.as_str(), "--controller-cmd", pid.as_str()];
    let (_, csv) = same_sweep_three_ways(&dir, config.to_str().unwrap(), "4", &commands);
    assert!(csv.lines().skip(1).all(|l| l.contains(",pass,") || l.contains(",fail,")), "every case flown: {csv}");
    // Each case trimmed at its own altitude: the outputs' criterion sees the airspeed of its own trim.
    let altitudes: Vec<f64> =
        csv_column(&csv, "plant.parameters.altitude_ft").iter().map(|v| v.parse().unwrap()).collect();
    assert!(altitudes.iter().all(|a| (2000.0..=8000.0).contains(a)) && altitudes[0] != altitudes[1], "{altitudes:?}");
    let case_dir = dir.join("case-1");
    ok(&[&["sim", config.to_str().unwrap(), "--sample", "1", "--out", case_dir.to_str().unwrap()], &commands[..]]
        .concat());
    let alt_ft = csv_column(&read(&case_dir.join("trace.csv")), "alt_ft")[0].parse::<f64>().unwrap();
    assert!((alt_ft - altitudes[1]).abs() < 1.0, "trimmed at {alt_ft} ft, the case says {}", altitudes[1]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_plant_command_sweeps_under_a_controller_fmu_and_under_ours_which_fails_naming_what_the_plant_lacks() {
    let dir = common::temp_dir(SUITE, "plant-under");
    let config = toy_config(&dir);
    let config = config.to_str().unwrap();
    let pid_fmu = common::fmu::cached_fmu(SUITE, "pid");
    let toy = toy_plant();
    let out = |name: &str| dir.join(name).display().to_string();
    ok(&[
        "sweep",
        config,
        "--runs",
        "2",
        "--jobs",
        "2",
        "--plant-cmd",
        &toy,
        "--controller-fmu",
        &pid_fmu,
        "--out",
        &out("fmu"),
    ]);
    let csv = read(&dir.join("fmu/cases.csv"));
    assert!(csv.lines().skip(1).all(|l| l.contains(",pass,") || l.contains(",fail,\"outputs.")), "{csv}");
    // Our controller flies the F-16's states, which the toy does not announce: the case fails saying so.
    ok(&["sweep", config, "--runs", "1", "--plant-cmd", &toy, "--out", &out("ours")]);
    let csv = read(&dir.join("ours/cases.csv"));
    assert!(csv.contains(",fail,") && csv.contains("plant toy has no output `vt_fps`"), "{csv}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_plant_command_is_refused_before_any_case_flies_beside_a_plant_fmu_or_an_f16_only_dispersion() {
    let dir = common::temp_dir(SUITE, "plant-refused");
    let config = toy_config(&dir);
    let text = read(&config).replace("\"setpoint.theta_deg\"", "\"initial.phi_deg\"");
    let f16_only = dir.join("f16_only.toml");
    std::fs::write(&f16_only, text).unwrap();
    let (config, f16_only) = (config.to_str().unwrap(), f16_only.to_str().unwrap());
    let out = dir.join("out").display().to_string();
    let toy = toy_plant();
    for args in [
        vec!["sweep", f16_only, "--runs", "4", "--plant-cmd", &toy, "--out", &out],
        vec!["sweep", "plan", f16_only, "--runs", "4", "--shards", "2", "--plant-cmd", &toy, "--out", &out],
        vec!["sim", f16_only, "--sample", "1", "--plant-cmd", &toy, "--out", &out],
    ] {
        let (code, stdout, stderr) = silrig(&args);
        assert_eq!(code, Some(2), "{args:?}: {stdout}{stderr}");
        assert!(
            stderr.contains(
                "dispersions.\"initial.phi_deg\": the plant is your process (--plant-cmd), which does not \
                             read `initial.phi_deg`"
            ) && stderr.contains("`plant.parameters.<name>`"),
            "{stderr}"
        );
        assert!(!Path::new(&out).exists(), "{args:?} wrote {out}");
    }
    let (code, _, stderr) =
        silrig(&["sweep", config, "--runs", "4", "--plant-cmd", "surely-no-such-plant", "--out", &out]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("--plant-cmd: cannot find `surely-no-such-plant`"), "{stderr}");
    let fmu = dir.join("plant.fmu").display().to_string();
    let (code, _, stderr) = silrig(&["sweep", config, "--runs", "4", "--plant-cmd", &toy, "--plant-fmu", &fmu]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("flies the plant FMU") && stderr.contains("sweep one plant at a time"), "{stderr}");
    assert!(!Path::new(&out).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
