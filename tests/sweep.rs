//! `silrig sweep`: a sweep is a pure function of (scenario, seed, index): the same bytes with 1 or 2 threads and as
//! a prefix of a longer sweep; a worst case flown alone (`silrig sim --sample I --seed S`, the command the sweep
//! prints) gives the numbers the sweep gave; infeasible cases are counted with their reason; every figure is drawn;
//! bad dispersions and criteria are refused naming the key, with nothing written; a long sweep's peak memory grows by
//! far less than a case's results per case (they are streamed to cases.csv); SIGINT stops a sweep keeping every case
//! it flew; shards are checked at merge.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const CONFIG: &str = "configs/sweep-robust.toml";

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("silrig-sweep-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `silrig ARGS` from the repository root: (exit code, stdout, stderr).
fn silrig(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(SILRIG).args(args).current_dir(ROOT).output().unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into(), String::from_utf8_lossy(&o.stderr).into())
}

fn sweep(out: &Path, extra: &[&str]) -> (String, String) {
    let mut args = vec!["sweep", CONFIG, "--out", out.to_str().unwrap()];
    args.extend(extra);
    let (code, stdout, stderr) = silrig(&args);
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    (std::fs::read_to_string(out.join("cases.csv")).unwrap(), std::fs::read_to_string(out.join("sweep.json")).unwrap())
}

#[test]
fn a_sweep_is_the_same_bytes_on_any_number_of_threads_and_a_prefix_of_a_longer_one() {
    let dir = temp_dir("pure");
    let (csv1, json1) = sweep(&dir.join("one"), &["--runs", "40", "--jobs", "1"]);
    let (csv2, json2) = sweep(&dir.join("two"), &["--runs", "40", "--jobs", "2"]);
    assert_eq!(csv1, csv2);
    assert_eq!(json1, json2);
    let (csv_short, _) = sweep(&dir.join("short"), &["--runs", "25", "--jobs", "2"]);
    let long: Vec<&str> = csv1.lines().take(26).collect();
    assert_eq!(csv_short.lines().collect::<Vec<_>>(), long, "case i does not depend on how many cases there are");
    let (csv_other, _) = sweep(&dir.join("other-seed"), &["--runs", "40", "--seed", "2"]);
    assert_ne!(csv_other, csv1);
    for stem in ["histograms", "scatter", "envelope"] {
        for ext in ["png", "svg"] {
            let f = dir.join("one").join(format!("{stem}.{ext}"));
            assert!(std::fs::metadata(&f).map(|m| m.len() > 1000).unwrap_or(false), "{} drawn", f.display());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_worst_cases_fly_alone_with_the_numbers_the_sweep_gave() {
    let dir = temp_dir("worst");
    let (csv, json) = sweep(&dir.join("sweep"), &["--runs", "60"]);
    let summary: Value = serde_json::from_str(&json).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let mut checked = 0;
    for entry in summary["worst"].as_array().unwrap() {
        let criterion = entry[0].as_str().unwrap();
        let worst = &entry[1][0];
        let index = worst["index"].as_u64().unwrap();
        let command = worst["reproduce"].as_str().unwrap();
        assert_eq!(command, format!("silrig sim {CONFIG} --sample {index} --seed 1"));
        let out = dir.join(format!("case-{criterion}"));
        let mut args: Vec<&str> = command.split(' ').skip(1).collect();
        args.extend(["--out", out.to_str().unwrap()]);
        let (code, stdout, stderr) = silrig(&args);
        assert_eq!(code, Some(0), "{stdout}{stderr}");
        assert!(stdout.contains(worst["measured"].as_str().unwrap()), "{criterion}: {stdout}");
        let alone: Value = serde_json::from_str(&std::fs::read_to_string(out.join("case.json")).unwrap()).unwrap();
        // The row of the sweep: the same figure for every criterion, bit for bit.
        let row: Vec<&str> = csv.lines().nth(index as usize + 1).unwrap().split(',').collect();
        let row = &row[row.len() - header.len()..];
        for j in alone["judgements"].as_array().unwrap() {
            let column = header.iter().position(|h| *h == j["criterion"].as_str().unwrap()).unwrap();
            let in_sweep: Option<f64> = row[column].parse().ok();
            assert_eq!(in_sweep, j["value"].as_f64(), "case {index}, {}", j["criterion"]);
        }
        checked += 1;
    }
    assert_eq!(checked, 5, "one worst case per criterion of the scenario");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn infeasible_cases_are_counted_with_their_reason_never_dropped() {
    let dir = temp_dir("infeasible");
    // The shipped sweep draws no descent (none infeasible); descents at idle up high have no trim.
    let shipped = std::fs::read_to_string(CONFIG).unwrap();
    let theta = shipped.lines().find(|l| l.starts_with("\"initial.theta_deg\"")).unwrap();
    let descents = "\"initial.theta_deg\" = { dist = \"normal\", mean = 5.0, std = 2.0, min = -5.0, max = 15.0 }";
    let config = dir.join("descents.toml");
    std::fs::write(&config, shipped.replace(theta, descents)).unwrap();
    let out = dir.join("sweep");
    let (code, stdout, stderr) =
        silrig(&["sweep", config.to_str().unwrap(), "--runs", "30", "--out", out.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    let csv = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    let json = std::fs::read_to_string(out.join("sweep.json")).unwrap();
    let summary: Value = serde_json::from_str(&json).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 30);
    let infeasible: Vec<&&str> = rows.iter().filter(|r| r.split(',').nth(1) == Some("infeasible")).collect();
    assert!(!infeasible.is_empty(), "seed 1 has infeasible cases among its first 30 (case 0 is one)");
    assert!(rows[0].starts_with("0,infeasible,\"initial condition: no throttle in 0..1 holds the airspeed"));
    assert_eq!(summary["infeasible"].as_u64().unwrap() as usize, infeasible.len());
    assert_eq!(summary["infeasible_cases"].as_array().unwrap().len(), infeasible.len());
    let flown = summary["passed"].as_u64().unwrap() + summary["failed"].as_u64().unwrap();
    assert_eq!(flown as usize + infeasible.len(), 30);
    let (lo, hi) = (summary["pass_rate_95"][0].as_f64().unwrap(), summary["pass_rate_95"][1].as_f64().unwrap());
    let rate = summary["pass_rate"].as_f64().unwrap();
    assert!(lo <= rate && rate <= hi && 0.0 <= lo && hi <= 1.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_sweeps_are_refused_naming_the_key_with_nothing_written() {
    let dir = temp_dir("bad");
    let base = std::fs::read_to_string(Path::new(ROOT).join(CONFIG)).unwrap();
    let (head, _) = base.split_once("\n[dispersions]\n").unwrap();
    let cases = [
        ("\"initial.phi_dge\" = { dist = \"uniform\", min = 0.0, max = 1.0 }", "", "dispersions.\"initial.phi_dge\""),
        ("\"initial.phi_deg\" = { dist = \"lognormal\", mean = 0.0 }", "", "unknown variant `lognormal`"),
        ("\"initial.phi_deg\" = { dist = \"normal\", mean = 0.0, std = -1.0 }", "", "`std` must be >= 0"),
        (
            "\"initial.phi_deg\" = { dist = \"normal\", mean = 0.0, std = 1.0, min = 8.0, max = 9.0 }",
            "",
            "of the distribution's mass (mean 0, std 1); it must keep at least 1e-4",
        ),
        ("\"initial.phi_deg\" = { dist = \"uniform\", min = 0.0, max = 1.0, mode = 2.0 }", "", "unknown field `mode`"),
        ("\"name\" = { dist = \"uniform\", min = 0.0, max = 1.0 }", "", "is a string, not a number"),
        (
            "\"initial.phi_deg\" = { dist = \"uniform\", min = 0.0, max = 1.0 }",
            "compute_p99 = { max_us = 100.0 }",
            "`criteria.compute_p99`: is judged by `silrig check`",
        ),
        ("\"initial.phi_deg\" = { dist = \"uniform\", min = 0.0, max = 1.0 }", "NONE", "no [criteria]"),
    ];
    for (i, (dispersion, criteria, message)) in cases.iter().enumerate() {
        let criteria = match *criteria {
            "NONE" => String::new(),
            "" => "[criteria]\nalpha_max_deg = 20.0\n".to_string(),
            c => format!("[criteria]\n{c}\n"),
        };
        let config = dir.join(format!("bad-{i}.toml"));
        std::fs::write(&config, format!("{head}\n[dispersions]\n{dispersion}\n\n{criteria}")).unwrap();
        let out = dir.join(format!("out-{i}"));
        let (code, stdout, stderr) =
            silrig(&["sweep", config.to_str().unwrap(), "--runs", "5", "--out", out.to_str().unwrap()]);
        assert_eq!(code, Some(2), "{i}: {stdout}{stderr}");
        assert!(stderr.contains(message), "{i}: expected {message:?} in {stderr}");
        assert!(!out.exists(), "{i}: nothing written");
    }
    let (code, _, stderr) = silrig(&["sweep", CONFIG, "--runs", "0", "--out", dir.join("zero").to_str().unwrap()]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--runs must be within 1..="), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_sweep_split_in_shards_merges_into_the_same_bytes_and_refuses_what_does_not_belong() {
    let dir = temp_dir("shards");
    let (plan, other) = (dir.join("plan"), dir.join("other"));
    let (p, o) = (plan.to_str().unwrap(), other.to_str().unwrap());
    let ok = |args: &[&str]| {
        let (code, stdout, stderr) = silrig(args);
        assert_eq!(code, Some(0), "{args:?}: {stdout}{stderr}");
        stdout
    };
    let refused = |args: &[&str], message: &str| {
        let (code, stdout, stderr) = silrig(args);
        assert_eq!(code, Some(2), "{args:?}: {stdout}{stderr}");
        assert!(stderr.contains(message), "{args:?}: expected {message:?} in {stderr}");
    };
    ok(&["sweep", "plan", CONFIG, "--runs", "30", "--shards", "3", "--out", p]);
    refused(&["sweep", "plan", CONFIG, "--runs", "30", "--shards", "3", "--out", p], "already holds a sweep plan");
    refused(&["sweep", "plan", CONFIG, "--runs", "3", "--shards", "4", "--out", o], "--shards must be within 1..=3");
    refused(
        &["sweep", "plan", CONFIG, "--runs", "10000000", "--shards", "10", "--out", o],
        "--shards must be at least 100 for 10000000 cases",
    );
    assert!(!other.join("manifest.json").exists());
    ok(&["sweep", "plan", CONFIG, "--runs", "30", "--shards", "3", "--seed", "9", "--out", o]);
    // Each way of naming a shard: --index, --shard K/N, the batch system's variable.
    ok(&["sweep", "run", p, "--index", "0"]);
    ok(&["sweep", "run", p, "--shard", "1/3"]);
    refused(&["sweep", "merge", p], "1 of 3 shards have no results yet (shard 2)");
    let o2 = Command::new(SILRIG)
        .args(["sweep", "run", p])
        .env("JOB_COMPLETION_INDEX", "2")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .current_dir(ROOT)
        .output()
        .unwrap();
    assert!(o2.status.success(), "{}", String::from_utf8_lossy(&o2.stderr));
    refused(&["sweep", "run", p, "--index", "3"], "shard 3 is out of range: the plan has shards 0..=2");
    refused(&["sweep", "run", p, "--shard", "1/4"], "the plan has 3 shards, not 4");
    // A shard of another plan (another seed) in this plan's folder.
    ok(&["sweep", "run", o, "--index", "1"]);
    let mine = plan.join("shards/shard-1-of-3.json");
    let saved = std::fs::read(&mine).unwrap();
    std::fs::copy(other.join("shards/shard-1-of-3.json"), &mine).unwrap();
    refused(&["sweep", "merge", p], "belongs to another plan");
    assert!(!plan.join("sweep.json").exists(), "nothing written half");
    // A shard renamed into another's place, and one whose values were edited after it was flown.
    std::fs::copy(plan.join("shards/shard-0-of-3.json"), &mine).unwrap();
    refused(&["sweep", "merge", p], "holds shard 0's results, not shard 1's");
    let text = String::from_utf8(saved.clone()).unwrap();
    let value = text.split("\"values\":[").nth(1).unwrap().split([',', ']']).next().unwrap();
    std::fs::write(&mine, text.replacen(&format!("\"values\":[{value}"), "\"values\":[1e300", 1)).unwrap();
    refused(&["sweep", "merge", p], "its cases were changed after it was flown");
    assert!(!plan.join("sweep.json").exists(), "nothing written half");
    std::fs::write(&mine, saved).unwrap();
    ok(&["sweep", "merge", p]);
    refused(&["sweep", "merge", p], "already holds merged results");
    let (csv, json) = sweep(&dir.join("local"), &["--runs", "30"]);
    assert_eq!(std::fs::read_to_string(plan.join("cases.csv")).unwrap(), csv);
    assert_eq!(std::fs::read_to_string(plan.join("sweep.json")).unwrap(), json);
    assert!(plan.join("report.html").is_file(), "a merged sweep has its page as a local one does");
    ok(&["sweep", "slurm", p]);
    let script = std::fs::read_to_string(plan.join("sweep.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=0-2") && script.contains("sweep run"), "{script}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `silrig ARGS` from the repository root, its output thrown away: (exit code, its peak resident memory in KiB, as
/// the kernel accounts it for this child alone).
fn silrig_peak_kib(args: &[&str]) -> (Option<i32>, i64) {
    use std::os::unix::process::ExitStatusExt;
    // Reaped by wait4 below, which gives its resource usage with it.
    #[allow(clippy::zombie_processes)]
    let child = Command::new(SILRIG)
        .args(args)
        .current_dir(ROOT)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    // SAFETY: waits for this test's own child, whose pid it holds, with valid pointers.
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t, "{}", std::io::Error::last_os_error());
    (std::process::ExitStatus::from_raw(status).code(), usage.ru_maxrss)
}

#[test]
fn a_long_sweep_streams_its_cases_in_memory_bounded_per_case() {
    // Today's results held in memory took about 3.3 KB a case (10 million cases: 33 GB). Both sweeps are longer
    // than the figures' sample, so what grows with the cases is what is held per case.
    let dir = temp_dir("memory");
    let (few, many) = (6_000_u64, 18_000_u64);
    let peak = |runs: u64| {
        let out = dir.join(format!("runs-{runs}"));
        let runs = runs.to_string();
        let (code, kib) =
            silrig_peak_kib(&["sweep", CONFIG, "--runs", &runs, "--jobs", "2", "--out", out.to_str().unwrap()]);
        assert_eq!(code, Some(0), "sweep of {runs} cases");
        let csv = std::fs::read_to_string(out.join("cases.csv")).unwrap();
        assert_eq!(csv.lines().count().to_string(), (runs.parse::<usize>().unwrap() + 1).to_string());
        let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
        assert_eq!(json["runs"].to_string(), runs);
        assert!(json.get("interrupted").is_none(), "{json}");
        kib
    };
    let (small, large) = (peak(few), peak(many));
    let per_case_bytes = (large - small) as f64 * 1024.0 / (many - few) as f64;
    eprintln!("peak memory {small} KiB for {few} cases, {large} KiB for {many}: {per_case_bytes:.0} B a case");
    assert!(per_case_bytes < 600.0, "{per_case_bytes:.0} B a case ({small} KiB -> {large} KiB)");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigint_stops_a_sweep_keeping_every_case_it_flew_and_sweep_json_says_so() {
    let dir = temp_dir("sigint");
    let out = dir.join("stopped");
    let mut child = Command::new(SILRIG)
        .args(["sweep", CONFIG, "--runs", "10000000", "--jobs", "2", "--out", out.to_str().unwrap()])
        .current_dir(ROOT)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Rows reach cases.csv as they are flown.
    let started = std::time::Instant::now();
    while std::fs::read_to_string(out.join("cases.csv")).map_or(0, |t| t.lines().count()) < 500 {
        assert!(started.elapsed().as_secs() < 120, "no rows in cases.csv after 120 s");
        assert!(child.try_wait().unwrap().is_none(), "the sweep ended before it was stopped");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // SAFETY: signals this test's own child by its pid.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) }, 0);
    let o = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(130), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let why = json["interrupted"].as_str().unwrap_or_default();
    assert!(why.contains("stopped by SIGINT") && why.contains("of the 10000000 cases asked"), "{json}");
    assert!(stdout.contains("interrupted: stopped by SIGINT"), "{stdout}");
    // Whole: every case from 0 on, each row complete, the counts those of the rows.
    let csv = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    assert!(csv.ends_with('\n'));
    let runs = json["runs"].as_u64().unwrap();
    assert!(runs >= 499, "{runs}");
    let indices: Vec<u64> = csv.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert_eq!(indices, (0..runs).collect::<Vec<_>>());
    let counted = ["passed", "failed", "infeasible"].iter().map(|k| json[k].as_u64().unwrap()).sum::<u64>();
    assert_eq!(counted, runs);
    // The same rows as a sweep of that many cases.
    let (whole, _) = sweep(&dir.join("whole"), &["--runs", "300"]);
    assert_eq!(csv.lines().take(301).collect::<Vec<_>>(), whole.lines().collect::<Vec<_>>());
    assert!(out.join("envelope.png").exists(), "the figures of the cases flown are drawn");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_shipped_sweep_draws_no_infeasible_case_and_its_failure_counts_agree_with_its_tables() {
    let dir = temp_dir("agree");
    let out = dir.join("sweep");
    let (code, text, stderr) = silrig(&["sweep", CONFIG, "--runs", "1000", "--out", out.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{text}{stderr}");
    let summary: Value = serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(summary["infeasible"], 0, "{text}");
    let csv = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|r| r.split(',').collect()).collect();
    let cell = |row: &Vec<&str>, name: &str| -> String {
        row[row.len() - header.len() + header.iter().position(|h| *h == name).unwrap()].to_string()
    };
    for (k, entry) in summary["failures_by_criterion"].as_array().unwrap().iter().enumerate() {
        let name = entry[0].as_str().unwrap();
        let failing: Vec<&Vec<&str>> = rows.iter().filter(|r| cell(r, &format!("{name}_passed")) == "0").collect();
        let departed = failing.iter().filter(|r| !cell(r, "departed_at_s").is_empty()).count();
        assert_eq!(entry[1].as_u64().unwrap() as usize, failing.len(), "{name}");
        assert_eq!(summary["departed_failures_by_criterion"][k].as_u64().unwrap() as usize, departed, "{name}");
        // A criterion some case within the data failed lists that failure first among its worst cases.
        let worst = &summary["worst"][k][1];
        assert_eq!(worst[0]["passed"].as_bool().unwrap(), failing.len() == departed, "{name}: {worst}");
        if departed > 0 {
            assert!(
                text.contains(&format!("  {name}: failed in {} of 1000, {departed} of them departed", failing.len()))
            );
        }
    }
    // Every row of a table starts its verdict in the same column.
    let columns: Vec<usize> = text
        .lines()
        .filter(|l| l.starts_with("    case "))
        .filter_map(|l| l.find(" FAIL ").or(l.find(" pass ")))
        .collect();
    assert!(columns.len() >= 10 && columns.iter().all(|c| *c == columns[0]), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}
