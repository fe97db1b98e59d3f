//! The MCAP sink: the run as Foxglove, PlotJuggler and `ros2 bag` open it. Binary messages (CDR, with ROS 2 message
//! definitions generated from the wire's field tables, [`super::cdr`]) on [`super::topics`]: `/plant` and
//! `/command` (every field as received, the arrays' entries in use as bounded sequences, with header stamps, flags and
//! the logger's receive stamp), `/plant_info`
//! (the plant's announcement), `/trace` (the trace row, one float64 field per column) and `/timing` (the per-tick
//! stamps). `/trace` and `/timing` are in realtime recordings only: every value of theirs is in `/plant` and
//! `/command` (an output, a command, a diagnostic, a stamp; an actuator's position and a step's time in the next
//! `/plant`, the last row's in the plant's end-of-run sample, which ends a lockstep recording's `/plant`), and in
//! lockstep, where the logger's CPU a tick matters, they were half of what LZ4 compressed; a lockstep recording
//! keeps the trace's columns (which name the diagnostics) in the `trace` metadata record instead. `/events` holds the run's `events.jsonl` lines as they appear, as JSON. A plant that announces its
//! position and attitude also gets the aircraft in 3-D for Foxglove's 3D panel ([`super::foxglove`]): `/body_transform`
//! (`foxglove.FrameTransform`, world -> body, every row) and `/aircraft` (`foxglove.SceneUpdate`, the model with its
//! surfaces deflected, written again when a surface has turned [`SCENE_SURFACE_STEP_RAD`] or a second has passed),
//! protobuf, stamped with the plant's send time. The run's identity and scenario
//! are MCAP metadata.
//!
//! The file is written by [`super::mcap_writer`]: chunks (zstd in realtime, LZ4 in lockstep) closed at every flush
//! (the logger flushes every 0.1 s) or at 1 MiB, so a killed logger leaves a file a reader can read up to its last
//! flush; a restarted logger writes the next `recording-<n>.mcap`, never over
//! an earlier one. Message log times are wall-clock (the monotonic stamps shifted by the offset between the clocks
//! when the file was opened), so a viewer shows when the run flew; the monotonic stamps themselves are in the
//! messages. Each message is encoded into one reused buffer: writing a row allocates nothing. A [`RecordingTap`]
//! given at creation sees every channel and message after the file has it.

use crate::cdr::{self, CdrBuffer, CdrCodec, MESSAGE_ENCODING, SCHEMA_ENCODING};
use crate::foxglove::{self as fox, BodySignals, ProtoBuffer};
use crate::foxglove_layout::{SignalSource, layout};
use crate::mcap_writer::{ChunkCompression, McapWriter};
use crate::{
    LoggedRow, RecordingMeta, RecordingTap, RowSink, TIMING_COLUMNS, TRACE_COLUMNS_KEY, TapChannel, meta_keys,
    recording_file_name, timing_values, topics,
};
use serde_json::{Value, json};
use silrig_wire::ipc::Received;
use silrig_wire::wire::{CommandSample, PlantInfo, PlantSample, WIRE_LAYOUT_VERSION};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// A new `/aircraft` scene is written when a surface has turned this far since the last one (0.5 deg: under 2 cm
/// at the trailing edge of the model's largest surface), ...
pub const SCENE_SURFACE_STEP_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// ... or this much simulated time has passed, so a viewer that seeks finds one near. The scene is frame-locked to
/// `body`, whose transform is written every tick, so the model moves with every tick regardless; a scene each tick
/// was half the recording's bytes and most of the logger's compression work.
pub const SCENE_AT_LEAST_EVERY_S: f64 = 1.0;

/// Channel ids of the topics.
struct Channels {
    plant: u16,
    plant_info: u16,
    command: u16,
    /// `/timing`: realtime recordings only (a lockstep one leaves out what repeats the samples).
    timing: Option<u16>,
    events: u16,
    /// Added with the trace's columns.
    trace: Option<u16>,
    /// `/body_transform` and `/aircraft`, added with the first announcement of a position and an attitude.
    body: Option<(u16, u16)>,
}

/// The file side of the recording: the writer, who else sees each message, and the clock messages are stamped
/// with; apart from the sink's reused message buffers, so a message is written straight from them.
struct RecordingFile {
    path: PathBuf,
    writer: McapWriter<BufWriter<File>>,
    /// Wall clock minus monotonic clock, ns.
    wall_minus_monotonic_ns: i128,
    /// Who else sees the channels and messages (the live server), if anyone.
    tap: Option<Box<dyn RecordingTap>>,
}

impl RecordingFile {
    fn wall_ns(&self, monotonic_ns: u64) -> u64 {
        (i128::from(monotonic_ns) + self.wall_minus_monotonic_ns).clamp(0, i128::from(u64::MAX)) as u64
    }

    fn named(&self, e: std::io::Error) -> std::io::Error {
        named_error(&self.path, e)
    }

    fn write(&mut self, channel: u16, t_log_ns: u64, t_publish_ns: u64, data: &[u8]) -> std::io::Result<()> {
        let (log_time, publish_time) = (self.wall_ns(t_log_ns), self.wall_ns(t_publish_ns));
        self.writer.write_message(channel, log_time, publish_time, data).map_err(|e| named_error(&self.path, e))?;
        if let Some(tap) = &mut self.tap {
            tap.message(channel, log_time, data);
        }
        Ok(())
    }

    /// Add a channel with its schema, announced to the tap.
    fn add_channel(&mut self, c: NewChannel) -> u16 {
        add_channel(&mut self.writer, &mut self.tap, c)
    }
}

/// The run's MCAP recording, being written.
pub struct McapSink {
    file: RecordingFile,
    channels: Channels,
    plant_codec: CdrCodec,
    command_codec: CdrCodec,
    /// The message being written, reused.
    buffer: CdrBuffer,
    /// Where the current plant announces its position, attitude and surfaces (`None`: it does not, no 3-D).
    body_signals: Option<BodySignals>,
    /// The 3-D messages being written, reused.
    proto: ProtoBuffer,
    /// The arm a quadrotor is drawn with, m (the scenario's `arm_m`).
    rotor_arm_m: f64,
    /// The surfaces (rad) and simulated time (s) of the last `/aircraft` scene written; `None`: none yet for the
    /// current plant life.
    last_scene: Option<([f64; 3], f64)>,
    events_path: PathBuf,
    events_file: Option<File>,
    /// Bytes of `events.jsonl` already recorded.
    events_read: u64,
    /// The recording has `/trace` and `/timing`, which repeat what the samples hold (realtime); a lockstep one
    /// leaves them out and keeps the trace's columns in a metadata record.
    derived: bool,
    /// The trace's columns have come ([`RowSink::start`]).
    started: bool,
    finished: bool,
}

const RECEIVE_STAMP: (&str, &str) = ("t_recv_ns", "CLOCK_MONOTONIC when the logger took the sample from its queue, ns");

/// An I/O error naming the file.
fn named_error(path: &Path, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("writing {}: {e}", path.display()))
}

/// A channel of `topic` with its schema in the file, announced to the tap.
struct NewChannel<'a> {
    topic: &'a str,
    message_encoding: &'a str,
    schema_name: &'a str,
    schema_encoding: &'a str,
    schema_data: &'a [u8],
    metadata: &'a BTreeMap<String, String>,
}

fn add_channel(
    writer: &mut McapWriter<BufWriter<File>>,
    tap: &mut Option<Box<dyn RecordingTap>>,
    c: NewChannel,
) -> u16 {
    let schema_id = writer.add_schema(c.schema_name, c.schema_encoding, c.schema_data);
    let id = writer.add_channel(schema_id, c.topic, c.message_encoding, c.metadata);
    if let Some(tap) = tap {
        tap.channel(&TapChannel {
            id,
            topic: c.topic,
            message_encoding: c.message_encoding,
            schema_name: c.schema_name,
            schema_encoding: c.schema_encoding,
            schema_data: c.schema_data,
            metadata: c.metadata,
        });
    }
    id
}

// `empty_columns` has a bit per timing column.
const _: () = assert!(TIMING_COLUMNS.len() <= 32);

/// The schema name of the `/timing` messages.
const TIMING_MSG: &str = "silrig/msg/Timing";
/// The schema name of the `/trace` messages.
const TRACE_MSG: &str = "silrig/msg/Trace";

/// The run's next recording file in `out_dir`, created so that no other life's file is overwritten: the first free
/// name of `recording.mcap`, `recording-2.mcap`, ... (a restarted logger starts a file of its own).
fn create_next_file(out_dir: &Path) -> std::io::Result<(PathBuf, File)> {
    let (path, file) = (1..)
        .map(|life| out_dir.join(recording_file_name(life)))
        .find_map(|path| match OpenOptions::new().write(true).create_new(true).open(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => None,
            opened => Some((path.clone(), opened)),
        })
        .expect("some recording file name is free");
    let file = file.map_err(|e| std::io::Error::new(e.kind(), format!("creating {}: {e}", path.display())))?;
    Ok((path, file))
}

/// The channels every recording has from its start, whatever the controller: the wire's samples (CDR), `/timing`
/// (with `derived`) and `/events`. `/trace` waits for the trace's columns, the 3-D channels for the plant's
/// announcement.
fn add_first_channels(
    writer: &mut McapWriter<BufWriter<File>>,
    tap: &mut Option<Box<dyn RecordingTap>>,
    derived: bool,
) -> Channels {
    let no_metadata = BTreeMap::new();
    let mut add = |topic: &str, name: &str, msg: String| -> u16 {
        let channel = NewChannel {
            topic,
            message_encoding: MESSAGE_ENCODING,
            schema_name: name,
            schema_encoding: SCHEMA_ENCODING,
            schema_data: msg.as_bytes(),
            metadata: &no_metadata,
        };
        add_channel(writer, tap, channel)
    };
    let plant = add(topics::PLANT, &cdr::msg_name::<PlantSample>(), cdr::sample_msg::<PlantSample>(&[RECEIVE_STAMP]));
    let plant_info = add(topics::PLANT_INFO, &cdr::msg_name::<PlantInfo>(), cdr::sample_msg::<PlantInfo>(&[]));
    let command =
        add(topics::COMMAND, &cdr::msg_name::<CommandSample>(), cdr::sample_msg::<CommandSample>(&[RECEIVE_STAMP]));
    let timing = derived.then(|| add(topics::TIMING, TIMING_MSG, timing_msg()));
    let event_schema = serde_json::to_vec(&event_schema()).expect("JSON");
    let events = NewChannel {
        topic: topics::EVENTS,
        message_encoding: "json",
        schema_name: "silrig.Event",
        schema_encoding: "jsonschema",
        schema_data: &event_schema,
        metadata: &no_metadata,
    };
    let events = add_channel(writer, tap, events);
    Channels { plant, plant_info, command, timing, events, trace: None, body: None }
}

/// The run's metadata records: who wrote the file for which run and mode (with the wire layout replay checks), and
/// the scenario as it was loaded.
fn write_run_metadata(
    writer: &mut McapWriter<BufWriter<File>>,
    meta: &RecordingMeta,
    path: &Path,
) -> std::io::Result<()> {
    let run = BTreeMap::from([
        ("run_id".to_string(), meta.run_id.clone()),
        ("scenario".to_string(), meta.scenario_name.clone()),
        ("mode".to_string(), meta.mode.clone()),
        ("ticks".to_string(), meta.ticks.to_string()),
        ("silrig_version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
        (meta_keys::LAYOUT_VERSION.to_string(), WIRE_LAYOUT_VERSION.to_string()),
        (cdr::ARRAYS_KEY.to_string(), cdr::ARRAYS_BOUNDED.to_string()),
        ("file".to_string(), path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()),
    ]);
    writer.write_metadata(meta_keys::RUN, &run)?;
    let scenario = BTreeMap::from([(meta_keys::TOML.to_string(), meta.scenario_toml.clone())]);
    writer.write_metadata(meta_keys::SCENARIO, &scenario)
}

impl McapSink {
    /// Create the run's next recording file in `out_dir` (`recording.mcap`, or `recording-<n>.mcap` after a
    /// logger restart), with the run's metadata and the channels that do not depend on the controller; `tap`, if
    /// given, sees every channel and message after the file.
    pub fn create(
        out_dir: &Path,
        meta: &RecordingMeta,
        mut tap: Option<Box<dyn RecordingTap>>,
    ) -> std::io::Result<Self> {
        let (path, file) = create_next_file(out_dir)?;
        let named = |e: std::io::Error| named_error(&path, e);
        // Realtime: the smaller file, zstd at level 1 (Foxglove's own recorder writes zstd): the default run's
        // recording 0.75 MB against 0.86 MB with lz4, for about the same CPU. Lockstep: lz4, the cheaper per byte,
        // since the logger's CPU there bounds the loop. Message indexes are written (16 bytes a message, about 0.11
        // MB of a 10 s run's 0.86 MB): Foxglove's indexed reader refuses a chunk without them.
        let compression = if meta.mode == "lockstep" { ChunkCompression::Lz4 } else { ChunkCompression::Zstd(1) };
        let library = format!("silrig {}", env!("CARGO_PKG_VERSION"));
        let mut writer = McapWriter::new(BufWriter::new(file), "", &library, compression).map_err(named)?;
        let derived = meta.mode != "lockstep";
        let channels = add_first_channels(&mut writer, &mut tap, derived);
        write_run_metadata(&mut writer, meta, &path).map_err(named)?;
        let wall_ns = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let wall_minus_monotonic_ns = wall_ns as i128 - i128::from(silrig_wire::clock::monotonic_ns());
        Ok(Self {
            events_path: out_dir.join("events.jsonl"),
            events_file: None,
            file: RecordingFile { path, writer, wall_minus_monotonic_ns, tap },
            channels,
            plant_codec: CdrCodec::of::<PlantSample>(),
            command_codec: CdrCodec::of::<CommandSample>(),
            buffer: CdrBuffer::default(),
            body_signals: None,
            proto: ProtoBuffer::default(),
            rotor_arm_m: fox::rotor_arm_m(&meta.scenario_toml),
            last_scene: None,
            events_read: 0,
            derived,
            started: false,
            finished: false,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.file.path
    }

    /// A plant sample on `/plant`, with the logger's receive stamp after its fields.
    fn write_plant(&mut self, r: &Received<PlantSample>) -> std::io::Result<()> {
        self.buffer.start();
        self.plant_codec.encode(&r.sample, &mut self.buffer);
        self.buffer.u64(r.t_recv_ns);
        self.file.write(self.channels.plant, r.t_recv_ns, r.sample.header.t_send_ns, self.buffer.bytes())
    }

    /// Add `/body_transform` and `/aircraft`, with Foxglove's schemas.
    fn add_body_channels(&mut self) -> (u16, u16) {
        let mut add = |topic: &str, schema: &str| -> u16 {
            let channel = NewChannel {
                topic,
                message_encoding: fox::MESSAGE_ENCODING,
                schema_name: schema,
                schema_encoding: fox::SCHEMA_ENCODING,
                schema_data: &fox::descriptor_set(schema),
                metadata: &BTreeMap::new(),
            };
            self.file.add_channel(channel)
        };
        (add(topics::BODY_TRANSFORM, fox::FRAME_TRANSFORM), add(topics::AIRCRAFT, fox::SCENE_UPDATE))
    }

    /// Record the lines other processes appended to `events.jsonl` since the last call (whole lines only).
    fn record_new_events(&mut self) -> std::io::Result<()> {
        // Opened once it exists and kept: a lockstep logger flushes thousands of times a second.
        if self.events_file.is_none() {
            self.events_file = File::open(&self.events_path).ok();
        }
        let Some(file) = self.events_file.as_mut() else { return Ok(()) };
        let mut text = Vec::new();
        // From the end of the last whole line read: a line being written (or cut back on a full disk) is read
        // again whole next time.
        file.seek(SeekFrom::Start(self.events_read))?;
        file.read_to_end(&mut text)?;
        let Some(end) = text.iter().rposition(|&b| b == b'\n') else { return Ok(()) };
        self.events_read += end as u64 + 1;
        for line in text[..end].split(|&b| b == b'\n') {
            // A line that is not an event (torn by a full disk, foreign) is left out, as the fault report does.
            let Some(t_ns) = serde_json::from_slice::<Value>(line).ok().and_then(|v| v["t_ns"].as_u64()) else {
                continue;
            };
            self.file.write(self.channels.events, t_ns, t_ns, line)?;
        }
        Ok(())
    }
}

/// The definition of `/timing`: timing.csv's columns, then which of them are empty.
fn timing_msg() -> String {
    let mut msg = "# timing.csv's columns (a row per tick), in order\n".to_string();
    for column in TIMING_COLUMNS {
        msg += &format!("int64 {column}\n");
    }
    msg += "# Bit k set: column k above is empty in timing.csv (no command answered the tick, or the step time is \
            unknown), and its field is 0\nuint32 empty_columns\n";
    msg
}

fn event_schema() -> Value {
    json!({"title": "silrig event", "type": "object", "properties": {
        "t_ns": {"type": "integer", "description": "CLOCK_MONOTONIC, ns"},
        "tick": {"type": "integer", "description": "plant tick, when the process knew it"},
        "process": {"type": "string"},
        "kind": {"type": "string"},
        "detail": {"type": "string"}}})
}

impl RowSink for McapSink {
    fn plant(&mut self, info: &PlantInfo) -> std::io::Result<()> {
        // Each plant life announces itself: the 3-D follows what the current one has.
        self.body_signals = info.signals().ok().and_then(|signals| BodySignals::resolve(&signals));
        self.proto.draw(self.body_signals.as_ref().is_some_and(BodySignals::rotorcraft).then_some(self.rotor_arm_m));
        // The layout that fits this plant's recording, beside it; the recording goes on without it.
        if let Ok(signals) = info.signals() {
            let source = if self.derived { SignalSource::Trace } else { SignalSource::Samples };
            let layout = serde_json::to_string_pretty(&layout(&signals, source)).unwrap_or_default();
            let path = self.events_path.with_file_name(crate::foxglove_layout::FILE);
            if let Err(e) = silrig_flight::files::write_atomically(&path, &layout) {
                eprintln!("logger: the Foxglove layout {} could not be written: {e}", path.display());
            }
        }
        self.last_scene = None;
        if self.body_signals.is_some() && self.channels.body.is_none() {
            self.channels.body = Some(self.add_body_channels());
        }
        let t_send = info.header.t_send_ns;
        self.buffer.start();
        CdrCodec::of::<PlantInfo>().encode(info, &mut self.buffer);
        self.file.write(self.channels.plant_info, t_send, t_send, self.buffer.bytes())
    }

    fn start(&mut self, trace_columns: &[String]) -> std::io::Result<()> {
        if self.started {
            return Ok(());
        }
        self.started = true;
        if !self.derived {
            // Lockstep: no `/trace` (a third of what LZ4 compressed a tick, and every value of it is in `/plant` and
            // `/command`), but its columns, which name the command's diagnostics for replay.
            let columns = BTreeMap::from([(TRACE_COLUMNS_KEY.to_string(), trace_columns.join(","))]);
            return self.file.writer.write_metadata(meta_keys::TRACE, &columns).map_err(|e| self.file.named(e));
        }
        if self.channels.trace.is_none() {
            let names = cdr::field_names(trace_columns);
            let header = "trace.csv's columns (the same as silrig sim), in order; an empty value is NaN";
            let msg = cdr::float_row_msg(header, &names, trace_columns);
            // A column whose name is no ROS field name has another field name; the channel keeps the real ones.
            let columns = BTreeMap::from([(TRACE_COLUMNS_KEY.to_string(), trace_columns.join(","))]);
            let channel = NewChannel {
                topic: topics::TRACE,
                message_encoding: MESSAGE_ENCODING,
                schema_name: TRACE_MSG,
                schema_encoding: SCHEMA_ENCODING,
                schema_data: msg.as_bytes(),
                metadata: &columns,
            };
            self.channels.trace = Some(self.file.add_channel(channel));
        }
        Ok(())
    }

    fn row(&mut self, row: &LoggedRow) -> std::io::Result<()> {
        let plant = row.plant;
        let (t_recv, t_send) = (plant.t_recv_ns, plant.sample.header.t_send_ns);
        self.write_plant(plant)?;
        if let Some(c) = row.command {
            self.buffer.start();
            self.command_codec.encode(&c.sample, &mut self.buffer);
            self.buffer.u64(c.t_recv_ns);
            self.file.write(self.channels.command, c.t_recv_ns, c.sample.header.t_send_ns, self.buffer.bytes())?;
        }
        if !self.started {
            return Err(std::io::Error::other("recording: a row before its columns"));
        }
        if let Some(trace) = self.channels.trace {
            self.buffer.start();
            for v in row.trace {
                self.buffer.f64(*v);
            }
            self.file.write(trace, t_recv, t_send, self.buffer.bytes())?;
        }
        if let Some(timing) = self.channels.timing {
            self.buffer.start();
            let mut empty = 0u32;
            for (k, v) in timing_values(row).into_iter().enumerate() {
                self.buffer.i64(v.unwrap_or(0));
                empty |= u32::from(v.is_none()) << k;
            }
            self.buffer.u32(empty);
            self.file.write(timing, t_recv, t_send, self.buffer.bytes())?;
        }
        if let (Some(body), Some((transform, aircraft))) = (&self.body_signals, self.channels.body) {
            let outputs = plant.sample.outputs();
            let (translation, rotation, surfaces) =
                (body.translation_m(outputs), body.rotation(outputs), body.surfaces_rad(outputs));
            // Stamped with the sample's time, so the panel draws the model at the transform of the same tick.
            let stamp = self.file.wall_ns(t_send);
            fox::frame_transform(&mut self.proto, stamp, translation, rotation);
            self.file.write(transform, t_recv, t_send, self.proto.bytes())?;
            let t_sim_s = plant.sample.t_sim_s;
            let due = self.last_scene.is_none_or(|(last, at_s)| {
                surfaces.iter().zip(last).any(|(now, then)| (now - then).abs() >= SCENE_SURFACE_STEP_RAD)
                    || (t_sim_s - at_s).abs() >= SCENE_AT_LEAST_EVERY_S
            });
            if due {
                fox::aircraft_scene(&mut self.proto, stamp, surfaces);
                self.file.write(aircraft, t_recv, t_send, self.proto.bytes())?;
                self.last_scene = Some((surfaces, t_sim_s));
            }
        }
        match row.end_of_run {
            // Without `/trace` and `/timing`, the last row's actuator positions and step time are only in the plant's
            // end-of-run sample.
            Some(end) if !self.derived => self.write_plant(end),
            _ => Ok(()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.record_new_events()?;
        // Closes the chunk: a reader can read everything up to here even if the logger dies next.
        self.file.writer.flush().map_err(|e| self.file.named(e))
    }

    fn finish(&mut self) -> std::io::Result<()> {
        if !self.finished {
            self.record_new_events()?;
            self.finished = true;
            self.file.writer.finish().map_err(|e| self.file.named(e))?;
            if let Some(tap) = &mut self.file.tap {
                tap.finish();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::signals::{OutputSignal, PlantSignals};

    /// An empty folder of this test's own and the metadata of a one-tick lockstep run.
    fn fresh_recording(test: &str) -> (std::path::PathBuf, RecordingMeta) {
        let dir = std::env::temp_dir().join(format!("silrig-mcap-sink-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let meta = RecordingMeta {
            run_id: "r".into(),
            scenario_name: "s".into(),
            scenario_toml: String::new(),
            mode: "lockstep".into(),
            ticks: 1,
        };
        (dir, meta)
    }

    /// The topics of the recording a sink writes for a plant announcing `plant`.
    fn topics_for(plant: &PlantSignals, test: &str) -> Vec<String> {
        let (dir, meta) = fresh_recording(test);
        let mut sink = McapSink::create(&dir, &meta, None).unwrap();
        sink.plant(&PlantInfo::new(plant).unwrap()).unwrap();
        sink.finish().unwrap();
        let bytes = std::fs::read(sink.path()).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
        let _ = std::fs::remove_dir_all(&dir);
        let mut topics: Vec<String> = summary.channels.values().map(|c| c.topic.clone()).collect();
        topics.sort();
        topics
    }

    /// What a tap was handed: channels (id, topic, message encoding, schema name, schema) and messages (id, log
    /// time, bytes), in order.
    #[derive(Default)]
    struct Seen {
        channels: Vec<(u16, String, String, String, Vec<u8>)>,
        messages: Vec<(u16, u64, Vec<u8>)>,
        finished: bool,
    }

    struct Tap(std::sync::Arc<std::sync::Mutex<Seen>>);

    impl RecordingTap for Tap {
        fn channel(&mut self, c: &TapChannel) {
            let channel = (c.id, c.topic.into(), c.message_encoding.into(), c.schema_name.into(), c.schema_data.into());
            self.0.lock().unwrap().channels.push(channel);
        }
        fn message(&mut self, id: u16, log_time_ns: u64, data: &[u8]) {
            self.0.lock().unwrap().messages.push((id, log_time_ns, data.to_vec()));
        }
        fn finish(&mut self) {
            self.0.lock().unwrap().finished = true;
        }
    }

    #[test]
    fn a_tap_is_handed_every_channel_and_message_the_file_gets() {
        let (dir, meta) = fresh_recording("tap");
        let seen = std::sync::Arc::new(std::sync::Mutex::new(Seen::default()));
        let mut sink = McapSink::create(&dir, &meta, Some(Box::new(Tap(seen.clone())))).unwrap();
        let f16 = silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2]);
        sink.plant(&PlantInfo::new(&f16).unwrap()).unwrap();
        sink.start(&["t_s".to_string(), "alpha_deg".to_string()]).unwrap();
        std::fs::write(dir.join("events.jsonl"), "{\"t_ns\":5,\"kind\":\"a\"}\nnot an event\n").unwrap();
        sink.finish().unwrap();
        let bytes = std::fs::read(sink.path()).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let seen = seen.lock().unwrap();
        assert!(seen.finished);
        let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
        assert_eq!(seen.channels.len(), summary.channels.len());
        for (id, topic, encoding, schema_name, schema) in &seen.channels {
            let c = &summary.channels[id];
            let s = c.schema.as_ref().unwrap();
            assert_eq!((&c.topic, &c.message_encoding, &s.name), (topic, encoding, schema_name));
            assert_eq!(&s.data[..], &schema[..], "{topic}");
        }
        let file: Vec<(u16, u64, Vec<u8>)> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| m.map(|m| (m.channel.id, m.log_time, m.data.into_owned())).unwrap())
            .collect();
        // The announcement and the one whole event line.
        assert_eq!(file.len(), 2);
        assert_eq!(seen.messages, file);
    }

    #[test]
    fn a_lockstep_recording_keeps_the_trace_columns_without_trace_and_timing_and_a_realtime_one_has_them() {
        let columns = ["t_s".to_string(), "phi_deg".to_string(), "s_phi".to_string()];
        let f16 = silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2]);
        for mode in ["lockstep", "realtime"] {
            let (dir, mut meta) = fresh_recording(&format!("trace-{mode}"));
            meta.mode = mode.into();
            let mut sink = McapSink::create(&dir, &meta, None).unwrap();
            sink.plant(&PlantInfo::new(&f16).unwrap()).unwrap();
            sink.start(&columns).unwrap();
            sink.finish().unwrap();
            let bytes = std::fs::read(sink.path()).unwrap();
            let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
            let has = |topic: &str| summary.channels.values().any(|c| c.topic == topic);
            let has_trace = has(topics::TRACE);
            assert_eq!((has_trace, has(topics::TIMING)), (mode == "realtime", mode == "realtime"), "{mode}");
            if mode == "lockstep" {
                // Replay's reader finds the columns (which name the diagnostics) in the metadata record.
                let run = crate::reader::RecordedRun::read(&dir).unwrap();
                assert_eq!(run.trace_columns, columns);
            }
            let layout = std::fs::read_to_string(dir.join(crate::foxglove_layout::FILE)).unwrap();
            assert_eq!(layout.contains("\"/trace."), has_trace, "{mode}: the layout reads /trace only if it is there");
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    #[test]
    fn only_a_plant_with_a_position_and_an_attitude_gets_the_3d_channels() {
        let f16 = silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2]);
        let with = topics_for(&f16, "f16");
        assert!(with.contains(&topics::BODY_TRANSFORM.to_string()) && with.contains(&topics::AIRCRAFT.to_string()));
        // Attitude and altitude but no north/east position, as the JSBSim example plant announces.
        let outputs = ["phi_deg", "theta_deg", "psi_deg", "alt_ft"].map(|name| OutputSignal {
            name: name.into(),
            unit: name.rsplit('_').next().unwrap().into(),
            in_trace: true,
        });
        let level = PlantSignals { plant: "level".into(), outputs: outputs.into(), inputs: Vec::new() };
        let without = topics_for(&level, "level");
        assert_eq!(with.len(), without.len() + 2, "{with:?} against {without:?}");
        assert!(!without.iter().any(|t| t == topics::BODY_TRANSFORM || t == topics::AIRCRAFT), "{without:?}");
    }
}
