//! silrig-recording: what the logger writes, and reading it back.
//!
//! - Here: the sinks a logged row goes to ([`RowSink`], [`LoggedRow`]), the recording's topics, metadata keys and
//!   files, `timing.csv`'s columns, and the [`RecordingTap`], a second reader handed what the MCAP sink writes as it
//!   writes it (the logger's live Foxglove server).
//! - [`csv`]: `trace.csv` and `timing.csv`; [`mcap_file`]: the MCAP recording (channels, messages, the run's
//!   metadata), written by [`mcap_writer`], our MCAP file format chunk by chunk.
//! - [`cdr`]: the binary form of wire samples and rows with their ROS 2 message definitions (what the recording
//!   holds); [`foxglove`]: the aircraft in 3-D for Foxglove (a frame transform and a scene, protobuf); [`json`]: the
//!   samples' JSON form, what the first recordings held (replay still reads them).
//! - [`reader`]: a recording read back, what replay and the run's report use.
//!
//! The logger decides what a row is (pairing, gaps, restarts); a sink only writes it, so a new format is a new sink,
//! not a second copy of that logic.
//!
//! Layers: uses `silrig-wire` (the samples it records) and `silrig-flight` (a plant's signals, the trace's columns);
//! used by `silrig-rig` (the logger), `silrig-launch` (the run's report) and `silrig-tools` (replay).

pub mod cdr;
pub mod csv;
pub mod foxglove;
pub mod foxglove_layout;
pub mod json;
pub mod mcap_file;
pub mod mcap_writer;
pub mod reader;

use silrig_wire::ipc::Received;
use silrig_wire::wire::{CommandSample, PlantInfo, PlantSample};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One row the logger writes: a plant sample as received, the command that answered it (if one did), and the
/// trace's values for the tick (the same columns as `silrig sim`).
#[derive(Debug, Clone, Copy)]
pub struct LoggedRow<'a> {
    /// The plant sample, with the logger's receive stamp.
    pub plant: &'a Received<PlantSample>,
    /// The command answering it, with the logger's receive stamp.
    pub command: Option<&'a Received<CommandSample>>,
    /// The plant's step execution time of this tick, ns: reported in the next sample, like the deflections.
    pub step_exec_ns: Option<u64>,
    /// The plant's end-of-run sample when it closes this row (the last tick's actuator positions, which no row's
    /// sample carries), with the logger's receive stamp.
    pub end_of_run: Option<&'a Received<PlantSample>>,
    /// The trace row, in the order of the columns given to [`RowSink::start`].
    pub trace: &'a [f64],
}

/// Where the logger's rows go. Rows come in tick order; `flush` is called every few rows and at the end, and what a
/// sink has flushed must survive the logger being killed right after.
pub trait RowSink {
    /// The plant's announcement, once, before the first row.
    fn plant(&mut self, _info: &PlantInfo) -> std::io::Result<()> {
        Ok(())
    }
    /// The trace's columns, before the first row.
    fn start(&mut self, trace_columns: &[String]) -> std::io::Result<()>;
    /// One row.
    fn row(&mut self, row: &LoggedRow) -> std::io::Result<()>;
    /// Make every row so far durable in the file.
    fn flush(&mut self) -> std::io::Result<()>;
    /// The logger is done: flush and close the file properly.
    fn finish(&mut self) -> std::io::Result<()> {
        self.flush()
    }
}

/// A recording channel, as the MCAP sink adds it: what a [`RecordingTap`] needs to advertise it.
#[derive(Debug, Clone, Copy)]
pub struct TapChannel<'a> {
    /// The recording's channel id.
    pub id: u16,
    /// The topic, one of [`topics`].
    pub topic: &'a str,
    /// How each message is encoded (`cdr`, `protobuf`, `json`).
    pub message_encoding: &'a str,
    /// The schema's name.
    pub schema_name: &'a str,
    /// How the schema is written (`ros2msg`, `protobuf`, `jsonschema`).
    pub schema_encoding: &'a str,
    /// The schema itself (text, or a binary protobuf descriptor set).
    pub schema_data: &'a [u8],
    /// The channel's metadata (the trace's column names).
    pub metadata: &'a BTreeMap<String, String>,
}

/// A second reader of the recording, handed each channel and each message as the MCAP sink writes them (the
/// logger's live server, `silrig run --live foxglove`). Called from the logger's loop, after the file has the
/// message: an implementation queues and returns, and never blocks on a reader of its own.
pub trait RecordingTap: Send {
    /// A new channel, before its first message.
    fn channel(&mut self, channel: &TapChannel);
    /// A message of channel `id`, stamped with its log time as the recording has it (wall clock, ns since the Unix
    /// epoch).
    fn message(&mut self, id: u16, log_time_ns: u64, data: &[u8]);
    /// The recording is complete: nothing more comes.
    fn finish(&mut self) {}
}

/// Columns of `timing.csv` (and fields of the recording's `/timing` messages).
pub const TIMING_COLUMNS: [&str; 14] = [
    "tick",
    "plant_seq",
    "plant_epoch",
    "t_plant_send_ns",
    "t_plant_recv_ns",
    "plant_flags",
    "command_seq",
    "command_epoch",
    "t_command_send_ns",
    "t_command_recv_ns",
    "compute_ns",
    "command_missing",
    "wake_lateness_ns",
    "step_exec_ns",
];

/// A row's values under [`TIMING_COLUMNS`]; the command's are `None` when no command answered the tick, the step
/// time when the next sample has not come. Stamps are monotonic nanoseconds since boot, far inside i64; the wake-up
/// lateness may be negative.
pub fn timing_values(row: &LoggedRow) -> [Option<i64>; TIMING_COLUMNS.len()] {
    let p = &row.plant.sample.header;
    let c = row.command.map(|c| (&c.sample.header, c.t_recv_ns, c.sample.compute_ns));
    let n = |v: u64| v as i64;
    [
        Some(n(p.tick)),
        Some(n(p.seq)),
        Some(n(p.epoch)),
        Some(n(p.t_send_ns)),
        Some(n(row.plant.t_recv_ns)),
        Some(i64::from(row.plant.sample.flags)),
        c.map(|(h, _, _)| n(h.seq)),
        c.map(|(h, _, _)| n(h.epoch)),
        c.map(|(h, _, _)| n(h.t_send_ns)),
        c.map(|(_, recv, _)| n(recv)),
        c.map(|(_, _, compute)| n(compute)),
        Some(i64::from(c.is_none())),
        Some(row.plant.sample.wake_lateness_ns),
        row.step_exec_ns.map(n),
    ]
}

/// File name of the run's first recording; a restarted logger writes `recording-2.mcap`, then `-3`, and so on.
pub const RECORDING_FILE: &str = "recording.mcap";

/// The recording files of the run in `dir`, in the order their loggers wrote them.
pub fn recording_files(dir: &Path) -> Vec<PathBuf> {
    let mut found: Vec<(u32, PathBuf)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|entry| {
            let name = entry.file_name().into_string().ok()?;
            let life = if name == RECORDING_FILE {
                1
            } else {
                name.strip_prefix("recording-")?.strip_suffix(".mcap")?.parse().ok().filter(|n| *n >= 2)?
            };
            Some((life, entry.path()))
        })
        .collect();
    found.sort();
    found.into_iter().map(|(_, p)| p).collect()
}

/// The name of the `life`-th logger's recording file.
pub fn recording_file_name(life: u32) -> String {
    if life <= 1 { RECORDING_FILE.to_string() } else { format!("recording-{life}.mcap") }
}

/// What a recording says about its run, beside the samples (MCAP metadata `silrig`, and `scenario`).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingMeta {
    /// The run id.
    pub run_id: String,
    /// The scenario's name.
    pub scenario_name: String,
    /// The scenario as the processes flew it (TOML), so a recording is enough to replay.
    pub scenario_toml: String,
    /// realtime or lockstep.
    pub mode: String,
    /// Ticks the scenario flies.
    pub ticks: u64,
}

/// MCAP metadata keys.
pub mod meta_keys {
    /// The record with the run's identity.
    pub const RUN: &str = "silrig";
    /// The record holding the scenario's TOML under [`TOML`].
    pub const SCENARIO: &str = "scenario";
    /// Key of the scenario's TOML.
    pub const TOML: &str = "toml";
    /// Wire layout version of every sample in the file.
    pub const LAYOUT_VERSION: &str = "layout_version";
    /// The record of a recording without `/trace` (lockstep) holding trace.csv's columns under
    /// [`super::TRACE_COLUMNS_KEY`], as the `/trace` channel's metadata does in the others.
    pub const TRACE: &str = "trace";
}

/// Metadata key of the `/trace` channel (and of the `trace` metadata record): trace.csv's columns, comma-separated,
/// in order.
pub const TRACE_COLUMNS_KEY: &str = "columns";

/// The recording's topics.
pub mod topics {
    /// Plant samples as received.
    pub const PLANT: &str = "/plant";
    /// The command answering each row's plant sample, as received.
    pub const COMMAND: &str = "/command";
    /// The plant's announcement of its signals, once.
    pub const PLANT_INFO: &str = "/plant_info";
    /// The trace row (`trace.csv`'s columns); realtime recordings only: a lockstep recording leaves it out, since
    /// every value of it is in `/plant` and `/command` ([`super::mcap_file`]).
    pub const TRACE: &str = "/trace";
    /// Per-tick stamps (`timing.csv`'s columns); realtime recordings only, as [`TRACE`].
    pub const TIMING: &str = "/timing";
    /// The run's events (`events.jsonl`).
    pub const EVENTS: &str = "/events";
    /// The aircraft's position and attitude, `foxglove.FrameTransform` world -> body, a message a row (plants that
    /// announce both, [`foxglove`]).
    pub const BODY_TRANSFORM: &str = "/body_transform";
    /// The aircraft's model with its surfaces deflected, `foxglove.SceneUpdate` in `body`, a message a row.
    pub const AIRCRAFT: &str = "/aircraft";
}
