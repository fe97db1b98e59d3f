//! `silrig run --live foxglove=ADDR` (feature `live`): the logger serves the recording's channels over the Foxglove
//! WebSocket protocol while the run flies. Four clients written in Python (`foxglove/live_client.py`, PyPI
//! `websockets`, in the virtual environment `.ci/run` creates) connect to a realtime run: one that reads
//! everything, one too slow to keep up, one that leaves mid-run, one that joins late (it must still get the plant's
//! announcement, `/plant_info`, sent once when the plant started: it connects once the first client has a `/trace`
//! message). The first must have been advertised every channel
//! of the recording, with the recording's encodings and schemas, and must receive each channel's messages exactly as
//! the recording holds them from its first message on: same bytes, same log times, in order, none missing (for
//! `/trace` one a tick, by the trace's time). Whatever the clients do, the run must succeed and keep every row:
//! `trace.csv` one a tick of the scenario, and the recording one `/trace` message a row. No timing figure is
//! asserted (the lateness with and without a client is a benchmark, in docs/src/guides/foxglove.md).
//! Without the feature, `--live` is refused before anything starts (tests/live.rs).

mod common;

use common::{Run, temp_dir, venv_python, wait_with_watchdog};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// A port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// `live_client.py ADDR OUT ARGS`, started.
fn client(python: &Path, addr: &str, out: &Path, args: &[&str]) -> Child {
    Command::new(python)
        .arg(Path::new(ROOT).join("tests/foxglove/live_client.py"))
        .args([addr, out.to_str().unwrap()])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// What a client wrote: the channels advertised (topic to the advertisement) and the messages per topic, as (log
/// time, bytes), in arrival order.
struct Received {
    advertised: BTreeMap<String, Value>,
    messages: BTreeMap<String, Vec<(u64, Vec<u8>)>>,
}

fn hex(text: &str) -> Vec<u8> {
    (0..text.len()).step_by(2).map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap()).collect()
}

fn received(child: Child, out: &Path, who: &str) -> Received {
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    assert!(o.status.success(), "{who} client: {}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out).unwrap();
    let mut r = Received { advertised: BTreeMap::new(), messages: BTreeMap::new() };
    for line in text.lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        if let Some(a) = v.get("advertised") {
            r.advertised.insert(a["topic"].as_str().unwrap().to_string(), a.clone());
        } else {
            let topic = v["topic"].as_str().unwrap().to_string();
            let message = (v["log_time_ns"].as_u64().unwrap(), hex(v["data"].as_str().unwrap()));
            r.messages.entry(topic).or_default().push(message);
        }
    }
    r
}

/// The recording's channels (topic to message encoding and schema name) and messages per topic, as (log time,
/// bytes), in file order.
type Recorded = (BTreeMap<String, (String, String)>, BTreeMap<String, Vec<(u64, Vec<u8>)>>);

fn recorded(file: &Path) -> Recorded {
    let bytes = std::fs::read(file).unwrap();
    let (mut channels, mut messages) = (BTreeMap::new(), BTreeMap::<String, Vec<_>>::new());
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default();
        channels.insert(m.channel.topic.clone(), (m.channel.message_encoding.clone(), schema));
        messages.entry(m.channel.topic.clone()).or_default().push((m.log_time, m.data.into_owned()));
    }
    (channels, messages)
}

/// `live` is a contiguous stretch of `file`: the same messages in the same order, none missing between the first
/// and the last; returns where it starts in `file`.
fn contiguous(topic: &str, live: &[(u64, Vec<u8>)], file: &[(u64, Vec<u8>)], who: &str) -> usize {
    let start = file
        .iter()
        .position(|m| *m == live[0])
        .unwrap_or_else(|| panic!("{who}: the first {topic} message received is not in the recording"));
    assert!(start + live.len() <= file.len(), "{who}: more {topic} messages than the recording has after the first");
    for (k, (got, want)) in live.iter().zip(&file[start..]).enumerate() {
        assert!(
            got == want,
            "{who}: {topic} message {k} received (log time {}) is not the recording's {} (log time {})",
            got.0,
            start + k,
            want.0
        );
    }
    start
}

/// The trace's time of a `/trace` message (CDR: a 4-byte encapsulation header, then a float64 per column).
fn trace_time_s(data: &[u8], t_column: usize) -> f64 {
    let at = 4 + 8 * t_column;
    f64::from_le_bytes(data[at..at + 8].try_into().unwrap())
}

#[test]
fn clients_receive_every_channel_in_order_and_the_run_loses_nothing() {
    let python = venv_python("websockets", "websockets");
    let addr = format!("127.0.0.1:{}", free_port());
    let clients_dir: PathBuf = temp_dir("foxglove_live_clients", "all");
    let (full_out, slow_out, leaver_out) =
        (clients_dir.join("full.jsonl"), clients_dir.join("slow.jsonl"), clients_dir.join("leaver.jsonl"));
    let full = client(&python, &addr, &full_out, &[]);
    let slow = client(&python, &addr, &slow_out, &["--slow-ms", "20"]);
    let leaver = client(&python, &addr, &leaver_out, &["--disconnect-after-s", "2.5"]);
    let late_out = clients_dir.join("late.jsonl");
    let late = client(&python, &addr, &late_out, &["--connect-after-trace-in", full_out.to_str().unwrap()]);
    // A fault mid-run puts events on /events while the clients listen.
    let live = format!("foxglove={addr}");
    let run_args = ["--duration-s", "4", "--quiet", "--live", &live, "--fault", "controller:delay@2s,delay=1ms"];
    let run = Run::start(SILRIG, "foxglove_live", "fl", "all", &run_args);
    let (full, slow, leaver) =
        (received(full, &full_out, "full"), received(slow, &slow_out, "slow"), received(leaver, &leaver_out, "leaver"));
    let late = received(late, &late_out, "late");
    assert_eq!(run.code, Some(0), "{}\n{}\n{}", run.stdout, run.stderr, run.failures());
    assert!(run.stderr.contains(&format!("ws://{addr}")), "the launcher does not say where: {}", run.stderr);
    assert!(run.stderr.contains("on the loopback only"), "the launcher does not say who can reach it: {}", run.stderr);
    assert!(run.event("logger", "live-serving").is_some(), "no live-serving event");

    // Nothing lost: a row a tick in trace.csv, a /trace message a row in the recording.
    let (header, rows) = run.trace();
    let ticks = run.counter("plant", "ticks");
    assert_eq!(rows.len() as u64, ticks, "trace.csv has {} rows for {ticks} plant ticks", rows.len());
    assert_eq!(run.counter("logger", "plant_samples_lost"), 0);
    let (channels, messages) = recorded(&run.out.join("recording.mcap"));
    assert_eq!(messages["/trace"].len(), rows.len(), "the recording's /trace against trace.csv");

    // Every channel advertised, as the recording has it.
    for topic in ["/trace", "/events", "/body_transform", "/aircraft", "/plant", "/command", "/timing"] {
        assert!(channels.contains_key(topic), "the recording has no {topic}");
    }
    for (topic, (encoding, schema)) in &channels {
        let a = full.advertised.get(topic).unwrap_or_else(|| panic!("{topic} not advertised: {:?}", full.advertised));
        assert_eq!(
            (a["encoding"].as_str(), a["schemaName"].as_str()),
            (Some(encoding.as_str()), Some(schema.as_str()))
        );
    }
    // Each channel's messages, as recorded, from the first received on; /plant_info, published once when the plant
    // announces itself, is sent again to a client that subscribes after it.
    for (topic, file) in &messages {
        let live = full.messages.get(topic).map(Vec::as_slice).unwrap_or_default();
        assert!(!live.is_empty(), "full: no {topic} message received ({} recorded)", file.len());
        contiguous(topic, live, file, "full");
        assert!(live.windows(2).all(|w| w[0].0 <= w[1].0), "full: {topic} log times go back");
    }
    // The fault's events, mid-run, came live.
    let events: Vec<Value> =
        full.messages["/events"].iter().map(|(_, data)| serde_json::from_slice(data).unwrap()).collect();
    assert!(events.iter().any(|e| e["kind"] == "fault-injected"), "no fault event received live: {events:?}");
    // /trace: one a tick from the first received, by the trace's own time.
    let t = Run::column(&header, "t_s");
    let dt_s = rows[1][t] - rows[0][t];
    let times: Vec<f64> = full.messages["/trace"].iter().map(|(_, d)| trace_time_s(d, t)).collect();
    for w in times.windows(2) {
        assert!(((w[1] - w[0]) / dt_s - 1.0).abs() < 1e-6, "full: /trace jumps from t = {} s to {} s", w[0], w[1]);
    }
    // Most of the run came live (the clients connect while the processes start).
    assert!(times.len() * 2 > rows.len(), "full: only {} of {} /trace rows", times.len(), rows.len());

    // The slow client and the one that left saw part of it, in order; the run did not notice them.
    for (who, r) in [("slow", &slow), ("leaver", &leaver)] {
        let live = r.messages.get("/trace").unwrap_or_else(|| panic!("{who}: no /trace message"));
        contiguous("/trace", live, &messages["/trace"], who);
    }
    // The client that joined once the run was flying got the plant's announcement, as recorded, before anything else of it.
    let announced =
        late.messages.get("/plant_info").unwrap_or_else(|| panic!("late: no /plant_info: {:?}", late.messages.keys()));
    assert_eq!(announced[0], *messages["/plant_info"].last().unwrap(), "late: /plant_info is not the recording's");
    let late_trace = late.messages.get("/trace").expect("late: no /trace");
    let first_trace = contiguous("/trace", late_trace, &messages["/trace"], "late");
    assert!(first_trace > 0, "the late client was not late: it got /trace from the first row");
    let left_at = leaver.messages["/trace"].len();
    assert!(left_at < full.messages["/trace"].len(), "the leaver did not leave early: {left_at} /trace messages");
    let _ = std::fs::remove_dir_all(&clients_dir);
    run.finish();
}

/// A port already taken is refused before anything starts, naming the address.
#[test]
fn a_live_address_in_use_is_refused_before_the_run_starts() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap();
    let live = format!("foxglove={addr}");
    let stderr = Run::refused(SILRIG, "foxglove_live", "fl", "taken", &["--live", &live, "--duration-s", "1"]);
    assert!(stderr.contains(&format!("--live foxglove={addr}: cannot listen there")), "{stderr}");
}
