//! The MCAP recording and `silrig replay`, with the real processes. Recordings are read back with Foxglove's own
//! Python packages, `mcap` and `mcap-ros2-support` (the CDR decoder: `recording/read_mcap.py`, in the virtual
//! environment `.ci/run` creates, or this test creates when it is missing) and compared value by value, bit for bit,
//! with `trace.csv` and `timing.csv`. Replay is checked
//! bit for bit against our controller and a user's, for a changed controller's divergence, and for every recording
//! it must refuse.

mod common;

use common::{no_shared_memory_left, temp_dir, wait_with_watchdog};
use serde_json::Value;
use silrig::trace::Trace;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The Python of the test virtual environment, with `mcap` and `mcap_ros2` installed (created here if `.ci/run` has
/// not).
fn python_with_mcap() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = Path::new(ROOT).join("target/test-venv");
        let python = venv.join("bin/python3");
        let has_mcap =
            || Command::new(&python).args(["-c", "import mcap, mcap_ros2"]).status().is_ok_and(|s| s.success());
        if !has_mcap() {
            let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 runs");
            assert!(made.success(), "python3 -m venv {} failed (Debian: apt-get install python3-venv)", venv.display());
            let pip = venv.join("bin/pip");
            let installed =
                Command::new(&pip).args(["install", "-q", "mcap", "mcap-ros2-support"]).status().expect("pip runs");
            assert!(installed.success(), "pip install mcap mcap-ros2-support failed");
        }
        python
    })
}

/// What `read_mcap.py` reads from each file.
fn read_with_python(files: &[PathBuf]) -> Vec<Value> {
    let out = Command::new(python_with_mcap())
        .arg(Path::new(ROOT).join("tests/recording/read_mcap.py"))
        .args(files)
        .output()
        .expect("python runs");
    assert!(out.status.success(), "read_mcap.py: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice::<Vec<Value>>(&out.stdout).expect("JSON")
}

/// `silrig run` with its own run id and folder; (exit code, stdout + stderr).
fn run(out: &Path, id: &str, args: &[&str]) -> (Option<i32>, String) {
    let child = Command::new(SILRIG)
        .current_dir(ROOT)
        .args(["run", "--no-baseline", "--run-id", id, "--out", out.to_str().unwrap()])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = wait_with_watchdog(child, Duration::from_secs(120));
    no_shared_memory_left(id);
    (o.status.code(), String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr))
}

/// `silrig replay` of `run_dir` with `args`; (exit code, stdout + stderr).
fn replay(run_dir: &Path, args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String) {
    let child = Command::new(SILRIG)
        .current_dir(ROOT)
        .arg("replay")
        .arg(run_dir)
        .args(args)
        .envs(env.iter().copied())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = wait_with_watchdog(child, Duration::from_secs(120));
    (o.status.code(), String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr))
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// A float `read_mcap.py` printed as its bit pattern.
fn float_bits(v: &Value) -> f64 {
    f64::from_bits(v.as_u64().unwrap_or_else(|| panic!("{v} is not a float's bit pattern")))
}

/// Every `/trace` message of `file` equals `trace.csv`'s row of its tick, bit for bit; returns the rows' indexes in
/// `trace.csv` (a tick the logger never saw has no row, so index and tick may differ).
fn assert_trace_rows_match(file: &Value, trace: &Trace) -> Vec<usize> {
    let columns: Vec<String> =
        file["trace_columns"].as_array().unwrap().iter().map(|c| c.as_str().unwrap().into()).collect();
    assert_eq!(columns, trace.columns, "the recording's trace columns are trace.csv's");
    let t = trace.index("t_s").unwrap();
    let row_of: std::collections::HashMap<u64, usize> =
        trace.rows.iter().enumerate().map(|(i, r)| (r[t].to_bits(), i)).collect();
    let mut rows = Vec::new();
    for message in file["trace"].as_array().unwrap() {
        let values: Vec<f64> = message.as_array().unwrap().iter().map(float_bits).collect();
        assert_eq!(values.len(), columns.len(), "a field per column");
        let row = *row_of.get(&values[t].to_bits()).unwrap_or_else(|| panic!("t = {} is not in trace.csv", values[t]));
        let csv = &trace.rows[row];
        for (i, (a, b)) in values.iter().zip(csv).enumerate() {
            assert!(same(*a, *b), "tick {row}, {}: recording {a}, trace.csv {b}", columns[i]);
        }
        rows.push(row);
    }
    rows
}

#[test]
fn a_realtime_run_records_what_the_csv_files_hold() {
    let out = temp_dir("recording", "realtime");
    let id = format!("m{}-rt", std::process::id());
    // A stopped controller leaves rows without a command: empty cells in timing.csv.
    let (code, text) = run(&out, &id, &["--duration-s", "2", "--fault", "controller:stop@1s,for=0.2s"]);
    assert_eq!(code, Some(0), "{text}");
    let files = silrig::recording::recording_files(&out);
    assert_eq!(files, vec![out.join("recording.mcap")]);
    let file = &read_with_python(&files)[0];
    assert_eq!(file["complete"], true, "{}", file["error"]);
    let run_meta = &file["metadata"]["silrig"];
    assert_eq!(run_meta["run_id"], id.as_str());
    assert_eq!(run_meta["layout_version"], silrig::wire::WIRE_LAYOUT_VERSION.to_string());
    assert_eq!(run_meta["mode"], "realtime");
    assert!(file["metadata"]["scenario"]["toml"].as_str().unwrap().contains("[timing]"));
    for topic in ["/plant", "/command", "/plant_info", "/trace", "/timing"] {
        assert_eq!(file["schemas"][topic], "ros2msg", "{topic}");
        assert_eq!(file["channels"][topic], "cdr", "{topic}");
    }
    assert_eq!(file["schema_names"]["/plant"], "silrig/msg/PlantSample");
    assert_eq!((&file["schemas"]["/events"], &file["channels"]["/events"]), (&"jsonschema".into(), &"json".into()));

    let trace = Trace::load(&out.join("trace.csv")).unwrap();
    let rows = assert_trace_rows_match(file, &trace);
    assert_eq!(rows, (0..trace.rows.len()).collect::<Vec<_>>(), "one /trace message per row, in order");
    let counts = &file["counts"];
    assert_eq!(counts["/plant"], trace.rows.len());
    assert_eq!(counts["/timing"], trace.rows.len());
    let aileron_cmd = trace.index("aileron_cmd_deg").unwrap();
    let commanded = trace.rows.iter().filter(|r| !r[aileron_cmd].is_nan()).count();
    assert_eq!(counts["/command"], commanded, "one /command per row that had a command");
    let total: u64 = counts.as_object().unwrap().values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(file["summary_message_count"], total, "the summary counts what the file holds");

    // The plant's announcement names the outputs and inputs; samples carry them in that order.
    let info = &file["plant_info"];
    assert_eq!(info["plant_name"], "f16");
    let position = |list: &str, name: &str| {
        info[list].as_array().unwrap().iter().position(|n| n == name).unwrap_or_else(|| panic!("{name} in {info}"))
    };
    let (theta_out, aileron_in) = (position("output_names", "theta_deg"), position("input_names", "aileron"));
    // Plant samples: the outputs the trace shows, as received.
    let theta = trace.index("theta_deg").unwrap();
    let t_s = trace.index("t_s").unwrap();
    for (i, p) in file["plant"].as_array().unwrap().iter().enumerate() {
        assert_eq!(p["tick"], i as u64);
        assert!(same(float_bits(&p["t_sim_s"]), trace.rows[i][t_s]), "tick {i}: t_sim_s");
        assert!(same(float_bits(&p["outputs"][theta_out]), trace.rows[i][theta]), "tick {i}: theta");
    }
    // Commands: the surfaces the trace shows as commanded.
    for c in file["command"].as_array().unwrap() {
        let tick = c["answers_tick"].as_u64().unwrap() as usize;
        assert!(same(float_bits(&c["inputs"][aileron_in]), trace.rows[tick][aileron_cmd]), "tick {tick}: aileron");
    }
    // Timing: timing.csv's rows; an empty cell is a 0 with its bit set in `empty_columns`.
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let mut lines = timing.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut empty_cells = 0;
    for (line, message) in lines.zip(file["timing"].as_array().unwrap()) {
        let empty = message["empty_columns"].as_u64().unwrap();
        for (k, (column, cell)) in header.iter().zip(line.split(',')).enumerate() {
            let recorded = message[*column].as_i64().unwrap();
            assert_eq!(empty >> k & 1 == 1, cell.is_empty(), "timing column {column}: {line}");
            let expected = if cell.is_empty() { 0 } else { cell.parse::<i64>().unwrap() };
            assert_eq!(recorded, expected, "timing column {column}");
            empty_cells += usize::from(cell.is_empty());
        }
        assert_eq!(empty >> header.len(), 0, "no bits past the columns");
    }
    assert!(empty_cells > 0, "the rows without a command have empty cells");
    assert_eq!(file["timing"].as_array().unwrap().len(), timing.lines().count() - 1);
    // Events: the run's events.jsonl lines up to the logger's end, in order.
    let events: Vec<Value> = std::fs::read_to_string(out.join("events.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let recorded = file["events"].as_array().unwrap();
    assert!(!recorded.is_empty());
    assert_eq!(recorded[..], events[..recorded.len()], "the recorded events are the log's first lines");
    let _ = std::fs::remove_dir_all(&out);
}

/// timing.csv's row of tick `i` from the samples as `read_mcap.py` decoded them: the row's plant sample, the command
/// answering it (none: empty cells) and the sample after it (its step time, when the same plant life flew it).
fn timing_from_samples(i: usize, sample: &Value, command: Option<&Value>, next: &Value) -> String {
    let n = |v: &Value, key: &str| v[key].as_i64().unwrap_or_else(|| panic!("{key} in {v}")).to_string();
    let mut cells = vec![i.to_string(), n(sample, "seq"), n(sample, "epoch"), n(sample, "t_send_ns")];
    cells.extend([n(sample, "t_recv_ns"), n(sample, "flags")]);
    match command {
        Some(c) => cells.extend(["seq", "epoch", "t_send_ns", "t_recv_ns", "compute_ns"].map(|k| n(c, k))),
        None => cells.extend(["", "", "", "", ""].map(String::from)),
    }
    cells.extend([u8::from(command.is_none()).to_string(), n(sample, "wake_lateness_ns")]);
    let same_life = next["epoch"] == sample["epoch"];
    cells.push(if same_life { n(next, "previous_step_exec_ns") } else { String::new() });
    cells.join(",")
}

#[test]
fn a_lockstep_recording_has_every_value_of_the_csv_files_in_its_samples_without_trace_and_timing() {
    let out = temp_dir("recording", "lockstep");
    let id = format!("m{}-ls", std::process::id());
    let (code, text) = run(&out, &id, &["--mode", "lockstep", "--duration-s", "2"]);
    assert_eq!(code, Some(0), "{text}");
    let file = &read_with_python(&[out.join("recording.mcap")])[0];
    assert_eq!(file["complete"], true, "{}", file["error"]);
    for topic in ["/trace", "/timing"] {
        assert!(file["channels"].get(topic).is_none(), "a lockstep recording has no {topic}");
    }
    let trace = Trace::load(&out.join("trace.csv")).unwrap();
    let columns = file["metadata"]["trace"]["columns"].as_str().expect("the trace's columns in metadata");
    assert_eq!(columns.split(',').collect::<Vec<_>>(), trace.columns, "the recording's trace columns");
    // Each row again from the samples as Foxglove's reader decodes them: the row's /plant sample, the /command
    // answering it, and the next /plant sample (the last one the plant's end-of-run sample) for the positions.
    let plant = silrig::recording::reader::RecordedRun::read(&out).unwrap().plant_signals().unwrap();
    let diagnostics = trace.columns.len() - plant.trace_columns(&[]).len();
    let samples = file["plant"].as_array().unwrap();
    assert_eq!(samples.len(), trace.rows.len() + 1, "a sample a row, then the end-of-run sample");
    let end_flags = samples[trace.rows.len()]["flags"].as_u64().unwrap() as u32;
    assert_ne!(end_flags & silrig::wire::FLAG_END_OF_RUN, 0, "the last /plant message is the end-of-run sample");
    let floats = |v: &Value| v.as_array().unwrap().iter().map(float_bits).collect::<Vec<f64>>();
    let commands: std::collections::HashMap<u64, &Value> =
        file["command"].as_array().unwrap().iter().map(|c| (c["answers_tick"].as_u64().unwrap(), c)).collect();
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let timing: Vec<&str> = timing.lines().skip(1).collect();
    assert_eq!(timing.len(), trace.rows.len());
    let mut row = Vec::new();
    for (i, csv) in trace.rows.iter().enumerate() {
        let (sample, next) = (&samples[i], &samples[i + 1]);
        let command = commands.get(&(i as u64)).expect("lockstep answers every tick");
        assert_eq!(timing_from_samples(i, sample, Some(command), next), timing[i], "timing.csv row {i}");
        let mut diag = floats(&command["diagnostics"]);
        diag.resize(diagnostics, f64::NAN);
        let (inputs, next) = (floats(&command["inputs"]), floats(&next["outputs"]));
        let t_s = float_bits(&sample["t_sim_s"]);
        plant.trace_row(&mut row, t_s, &floats(&sample["outputs"]), Some(&inputs), Some(&next), 0, &diag);
        for (k, (a, b)) in row.iter().zip(csv).enumerate() {
            assert!(same(*a, *b), "row {i}, {}: from the samples {a}, trace.csv {b}", trace.columns[k]);
        }
    }
    // Replay of such a recording (the diagnostics named from the columns, the rows' samples sent, not the end-of-run
    // one): replaying_our_controller_gives_the_recorded_commands_bit_for_bit.
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_killed_logger_leaves_a_readable_recording_and_its_successor_writes_the_next_file() {
    let out = temp_dir("recording", "killed");
    let id = format!("m{}-kill", std::process::id());
    let (code, text) = run(&out, &id, &["--duration-s", "3", "--fault", "logger:kill@1.5s,restart_after=0.3s"]);
    assert_eq!(code, Some(0), "{text}");
    let files = silrig::recording::recording_files(&out);
    assert_eq!(files, vec![out.join("recording.mcap"), out.join("recording-2.mcap")], "a new file, none overwritten");
    let read = read_with_python(&files);
    let (first, second) = (&read[0], &read[1]);
    assert_eq!(first["complete"], false, "SIGKILL leaves no footer");
    assert!(first["error"].is_string());
    assert_eq!(second["complete"], true, "{}", second["error"]);
    assert_eq!(second["metadata"]["silrig"]["file"], "recording-2.mcap");

    let trace = Trace::load(&out.join("trace.csv")).unwrap();
    let before = assert_trace_rows_match(first, &trace);
    let after = assert_trace_rows_match(second, &trace);
    // The killed logger's file holds its rows up to its last flush (0.1 s of rows at most are only in the CSV),
    // contiguous from the first row; the restarted logger's rows come after them, each row once.
    assert!(before.len() >= 100, "rows readable from the killed logger's file: {}", before.len());
    assert_eq!(before, (0..before.len()).collect::<Vec<_>>());
    assert!(after.first().is_some_and(|t| *t > *before.last().unwrap()), "{:?}", &after[..3.min(after.len())]);
    assert_eq!(*after.last().unwrap(), trace.rows.len() - 1, "the second file runs to the last row");

    // Replay needs whole recordings, and says which file is not.
    let (code, text) = replay(&out, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("recording.mcap is cut short") && text.contains("messages can be read"), "{text}");
    let _ = std::fs::remove_dir_all(&out);
}

/// A replay's `replay.json`, after checking it removed its run's shared memory.
fn replay_json(out: &Path) -> Value {
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("replay.json")).unwrap()).unwrap();
    no_shared_memory_left(report["run_id"].as_str().unwrap());
    report
}

#[test]
fn replaying_our_controller_gives_the_recorded_commands_bit_for_bit() {
    let out = temp_dir("recording", "ours");
    let id = format!("m{}-ours", std::process::id());
    let (code, text) = run(&out, &id, &["--mode", "lockstep", "--duration-s", "2"]);
    assert_eq!(code, Some(0), "{text}");
    let (code, text) = replay(&out, &[], &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("every compared command is bit-identical to the recording"), "{text}");
    let report = replay_json(&out.join("replay"));
    assert_eq!(report["samples_sent"], 201);
    assert_eq!(report["ticks_compared"], 201);
    assert_eq!(report["ticks_bit_identical"], 201);
    assert_eq!(report["recorded_controller_lives"], 1);
    assert!(report["fields"].as_array().unwrap().iter().any(|f| f["field"] == "w_theta_3"), "diagnostics compared");
    assert!(out.join("replay/controller.report.json").exists(), "the replayed controller's report is kept");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn replay_finds_where_a_changed_controller_diverges() {
    let out = temp_dir("recording", "changed");
    let id = format!("m{}-py", std::process::id());
    let pid = "python3 examples/python/pid_attitude.py";
    let (code, text) =
        run(&out, &id, &["--mode", "lockstep", "--duration-s", "2", "--controller-cmd", pid, "configs/robust.toml"]);
    assert_eq!(code, Some(0), "{text}");

    // The user's controller, unchanged: the same commands, bit for bit.
    let (code, text) = replay(&out, &["--controller-cmd", pid], &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("bit-identical"), "{text}");

    // The same controller with more pitch damping: elevator commands move from tick 1 on (tick 0 has no rate).
    let changed_dir = out.join("changed");
    std::fs::create_dir_all(&changed_dir).unwrap();
    let source = std::fs::read_to_string(Path::new(ROOT).join("examples/python/pid_attitude.py")).unwrap();
    // The F-16's gains: KP, then KD.
    let old = "F16 = ((2.0, 4.0, 8.0), (0.6, 1.5, 3.0)";
    assert!(source.contains(old));
    let new = "F16 = ((2.0, 4.0, 8.0), (0.6, 1.8, 3.0)";
    std::fs::write(changed_dir.join("pid_changed.py"), source.replace(old, new)).unwrap();
    let cmd = format!("python3 {}", changed_dir.join("pid_changed.py").display());
    let pythonpath = Path::new(ROOT).join("examples/python");
    let env = [("PYTHONPATH", pythonpath.to_str().unwrap())];
    let (code, text) = replay(&out, &["--controller-cmd", &cmd], &env);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("first divergence: tick 1 (t = 0.01 s), elevator_cmd_deg: recorded"), "{text}");
    let report = replay_json(&out.join("replay-2"));
    let field = |name: &str| report["fields"].as_array().unwrap().iter().find(|f| f["field"] == name).unwrap().clone();
    assert_eq!(field("aileron_cmd_deg")["max_abs_difference"], 0.0, "roll and yaw are unchanged");
    let elevator = number(&field("elevator_cmd_deg")["max_abs_difference"]);
    assert!(elevator > 0.0 && elevator < 25.0, "{elevator}");

    // Within a tolerance above the largest difference, it passes.
    let tolerance = format!("{}", elevator * 1.01);
    let (code, text) = replay(&out, &["--controller-cmd", &cmd, "--tolerance", &tolerance], &env);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("within the tolerance"), "{text}");
    let _ = std::fs::remove_dir_all(&out);
}

/// A recording file with the `silrig` metadata saying `layout_version`, and nothing else.
fn write_recording_of_layout(path: &Path, layout_version: &str) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut writer = mcap::Writer::new(file).unwrap();
    let metadata = std::collections::BTreeMap::from([("layout_version".to_string(), layout_version.to_string())]);
    writer.write_metadata(&mcap::records::Metadata { name: "silrig".into(), metadata }).unwrap();
    writer.finish().unwrap();
}

#[test]
fn replay_refuses_what_is_not_a_whole_recording_of_this_layout() {
    let dir = temp_dir("recording", "bad");
    let (code, text) = replay(&dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("no recording in") && text.contains("recording.mcap beside trace.csv"), "{text}");

    std::fs::write(dir.join("recording.mcap"), "t_s,phi_deg\n0,0\n").unwrap();
    let (code, text) = replay(&dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("recording.mcap: not an MCAP file"), "{text}");

    write_recording_of_layout(&dir.join("recording.mcap"), "2");
    let (code, text) = replay(&dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    let expected =
        format!("recorded with wire layout version 2, this silrig reads version {}", silrig::wire::WIRE_LAYOUT_VERSION);
    assert!(text.contains(&expected), "{text}");

    // A whole recording cut in half, as a copy interrupted.
    let run_dir = temp_dir("recording", "cut");
    let id = format!("m{}-cut", std::process::id());
    let (code, text) = run(&run_dir, &id, &["--mode", "lockstep", "--duration-s", "1"]);
    assert_eq!(code, Some(0), "{text}");
    let bytes = std::fs::read(run_dir.join("recording.mcap")).unwrap();
    std::fs::write(dir.join("recording.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let (code, text) = replay(&dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("is cut short"), "{text}");
    assert!(!dir.join("replay").exists(), "nothing is started for a recording that cannot be replayed");

    // A whole recording with bytes changed in its middle (its footer intact): damaged, not cut short.
    let mut damaged = bytes.clone();
    let middle = damaged.len() / 2;
    damaged[middle..middle + 64].fill(0xa5);
    std::fs::write(dir.join("recording.mcap"), &damaged).unwrap();
    let (code, text) = replay(&dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("recording.mcap is damaged") && !text.contains("is cut short"), "{text}");
    assert!(text.contains("ends with its footer"), "{text}");

    // A whole recording copied into the folder of another run.
    let other_dir = temp_dir("recording", "other");
    let (code, text) =
        run(&other_dir, &format!("m{}-other", std::process::id()), &["--mode", "lockstep", "--duration-s", "1"]);
    assert_eq!(code, Some(0), "{text}");
    std::fs::copy(run_dir.join("recording.mcap"), other_dir.join("recording.mcap")).unwrap();
    let (code, text) = replay(&other_dir, &[], &[]);
    assert_eq!(code, Some(2), "{text}");
    let expected = format!(
        "the recording is of run `{id}`, but this folder's report.json is of run `m{}-other`",
        std::process::id()
    );
    assert!(text.contains(&expected), "{text}");
    assert!(!other_dir.join("replay").exists() && !other_dir.join("replay.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&run_dir);
    let _ = std::fs::remove_dir_all(&other_dir);
}
