//! Reading a run's recording back: every `recording*.mcap` of a run folder, in the order their loggers wrote them,
//! as wire samples again (bit for bit, see [`super::cdr`]), with the run's metadata and the trace's columns. Each
//! channel's message encoding says how its messages are read: `cdr` (what the logger writes) or `json` (what the
//! first recordings held), so recordings of older runs of the same wire layout still replay. A folder without a
//! recording, a file that is not MCAP, one cut short (its logger was killed), one of another wire layout, or a
//! message that does not fit its type is an error naming the file.

use crate::cdr::{self, CdrCodec, CdrReader};
use crate::json::sample_from_json;
use crate::{TRACE_COLUMNS_KEY, meta_keys, recording_files, topics};
use silrig_flight::signals::PlantSignals;
use silrig_wire::wire::{CommandSample, FLAG_END_OF_RUN, PlantInfo, PlantSample, WIRE_LAYOUT_VERSION, WireType};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Why a recording cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// No `recording.mcap` in the folder.
    #[error(
        "no recording in {}: a run's logger writes recording.mcap beside trace.csv (is this a run folder of \
         `silrig run`?)",
        .0.display()
    )]
    NoRecording(PathBuf),
    /// The file cannot be read at all.
    #[error("{}: {why}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What failed.
        why: String,
    },
    /// The file ends before its MCAP footer: the logger that wrote it was killed (or the copy is partial).
    #[error(
        "{} is cut short ({why}): {messages} messages can be read up to its last flushed chunk, but the flight \
         after that is missing; replay needs whole recordings",
        path.display()
    )]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Messages readable before the cut.
        messages: u64,
        /// What the reader found where the file ends.
        why: String,
    },
    /// A record inside the file cannot be read although the file ends with its footer: it was changed after it was
    /// written (a disk or copy error), not cut short.
    #[error(
        "{} is damaged ({why}): {messages} messages can be read before the damaged record, although the file ends \
         with its footer (so it was not cut short: its bytes were changed after they were written); replay needs \
         whole recordings",
        path.display()
    )]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Messages readable before the damage.
        messages: u64,
        /// What the reader found.
        why: String,
    },
    /// Samples of another wire layout.
    #[error(
        "{}: recorded with wire layout version {found}, this silrig reads version {WIRE_LAYOUT_VERSION}: use the \
         silrig that recorded it",
        path.display()
    )]
    OtherLayout {
        /// The file.
        path: PathBuf,
        /// Its layout version (or what stood in its place).
        found: String,
    },
    /// A message that is not what its topic holds.
    #[error("{}: message {index} on {topic}: {why}", path.display())]
    BadMessage {
        /// The file.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// Its position among the topic's messages, from 1.
        index: u64,
        /// What is wrong with it.
        why: String,
    },
}

/// A run's recording, read whole.
#[derive(Debug, Clone, Default)]
pub struct RecordedRun {
    /// The files read, in order.
    pub files: Vec<PathBuf>,
    /// The `silrig` metadata of the first file (run id, scenario, mode, ticks, versions).
    pub run: BTreeMap<String, String>,
    /// The scenario the run flew, as TOML.
    pub scenario_toml: String,
    /// trace.csv's columns (from the `/trace` channel, or a lockstep recording's `trace` metadata record).
    pub trace_columns: Vec<String>,
    /// The plant's announcement of its signals (the first, if a restarted logger recorded it again).
    pub plant_info: Option<PlantInfo>,
    /// The plant sample of every row, in tick order.
    pub plant: Vec<PlantSample>,
    /// The command of every row that had one, by the tick it answers.
    pub commands: BTreeMap<u64, CommandSample>,
    /// Messages per topic, over all files.
    pub counts: BTreeMap<String, u64>,
}

/// The codecs of the recorded wire types, made once per file.
struct Codecs {
    plant: CdrCodec,
    command: CdrCodec,
    plant_info: CdrCodec,
}

impl Codecs {
    /// As a file's run metadata says its arrays are written: bounded sequences ([`cdr::ARRAYS_KEY`]), or all fixed
    /// (the recordings before them).
    fn new(run: &BTreeMap<String, String>) -> Self {
        match run.get(cdr::ARRAYS_KEY).map(String::as_str) {
            Some(cdr::ARRAYS_BOUNDED) => Self {
                plant: CdrCodec::of::<PlantSample>(),
                command: CdrCodec::of::<CommandSample>(),
                plant_info: CdrCodec::of::<PlantInfo>(),
            },
            _ => Self {
                plant: CdrCodec::fixed::<PlantSample>(),
                command: CdrCodec::fixed::<CommandSample>(),
                plant_info: CdrCodec::fixed::<PlantInfo>(),
            },
        }
    }
}

/// The sample a message of `encoding` holds, bit for bit; a `stamped` message (`/plant`, `/command`) carries the
/// logger's receive stamp after the sample's own fields.
/// The first top-level record of an MCAP file (after its magic) whose length, or whose chunk's uncompressed size,
/// no file of this size can hold (a record cut off by the end of a file cut short, or a damaged length field):
/// its byte offset and why. None when every record fits.
fn first_impossible_record(bytes: &[u8]) -> Option<(usize, String)> {
    const OP_FOOTER: u8 = 0x02;
    const OP_CHUNK: u8 = 0x06;
    // LZ4 expands at most about 255 times; zstd in principle by far more (a run of zeros), so its chunks are held
    // only to what a chunk of ours could not reach (the logger closes one every 0.1 s). Anything beyond is a
    // damaged size field.
    const MAX_EXPANSION_LZ4: u64 = 256;
    const MAX_EXPANSION_OTHER: u64 = 1 << 16;
    let u64_at = |at: usize| bytes.get(at..at + 8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")));
    let mut at = mcap::MAGIC.len();
    while at + 9 <= bytes.len() {
        let opcode = bytes[at];
        let len = u64_at(at + 1)?;
        let left = (bytes.len() - at - 9) as u64;
        if len > left {
            let why = format!(
                "the record at byte {at} (opcode {opcode:#04x}) claims {len} bytes, more than the {left} left in the file"
            );
            return Some((at, why));
        }
        if opcode == OP_CHUNK {
            // message_start_time, message_end_time, uncompressed_size: the third u64 of the chunk; then its CRC
            // (u32) and its compression (a u32-prefixed string).
            let uncompressed = u64_at(at + 9 + 16).unwrap_or(0);
            let lz4 = bytes.get(at + 9 + 32..at + 9 + 35) == Some(b"lz4".as_slice());
            let expansion = if lz4 { MAX_EXPANSION_LZ4 } else { MAX_EXPANSION_OTHER };
            if uncompressed > len.saturating_mul(expansion) + (1 << 20) {
                return Some((
                    at,
                    format!("the chunk at byte {at} claims {uncompressed} bytes uncompressed from {len} bytes"),
                ));
            }
        }
        if opcode == OP_FOOTER {
            return None;
        }
        at += 9 + len as usize;
    }
    None
}

/// The records of an MCAP file, chunks unpacked, each chunk's CRC checked before any of its records is read: bytes
/// changed inside a compressed chunk would otherwise be read as records (with any length, which the reader would
/// reserve), or as samples.
fn checked_records(mut bytes: &[u8]) -> impl Iterator<Item = mcap::McapResult<mcap::records::Record<'static>>> + '_ {
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    // Lengths are bounded by `first_impossible_record` before this reads them.
    let options = LinearReaderOptions::default().with_skip_end_magic(true).with_prevalidate_chunk_crcs(true);
    let mut reader = LinearReader::new_with_options(options);
    std::iter::from_fn(move || {
        while let Some(event) = reader.next_event() {
            match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let n = need.min(bytes.len());
                    reader.insert(n).copy_from_slice(&bytes[..n]);
                    reader.notify_read(n);
                    bytes = &bytes[n..];
                }
                Ok(LinearReadEvent::Record { data, opcode }) => {
                    return Some(mcap::parse_record(opcode, data).map(mcap::records::Record::into_owned));
                }
                Err(e) => return Some(Err(e)),
            }
        }
        None
    })
}

/// A file that stops making sense after `messages` messages: damaged if it still ends with MCAP's magic (a record
/// broken inside it), truncated if not (a logger killed mid-write).
fn cut_short(path: &Path, bytes: &[u8], messages: u64, why: String) -> RecordingError {
    let path = path.to_path_buf();
    if bytes.ends_with(mcap::MAGIC) {
        RecordingError::Damaged { path, messages, why }
    } else {
        RecordingError::Truncated { path, messages, why }
    }
}

/// trace.csv's columns, as the `/trace` channel's metadata or a lockstep recording's `trace` record holds them.
fn trace_columns_in(metadata: &BTreeMap<String, String>) -> Vec<String> {
    let columns = metadata.get(TRACE_COLUMNS_KEY).map(String::as_str).unwrap_or("");
    columns.split(',').map(str::to_string).collect()
}

fn decode<T: WireType + Copy>(encoding: &str, codec: &CdrCodec, data: &[u8], stamped: bool) -> Result<T, String> {
    match encoding {
        cdr::MESSAGE_ENCODING => {
            let mut reader = CdrReader::new(T::TYPE_NAME, data).map_err(|e| e.to_string())?;
            let sample = codec.decode(&mut reader).map_err(|e| e.to_string())?;
            if stamped {
                reader.u64().map_err(|e| e.to_string())?;
            }
            reader.finish().map_err(|e| e.to_string())?;
            Ok(sample)
        }
        "json" => {
            let value = serde_json::from_slice(data).map_err(|e| e.to_string())?;
            sample_from_json(&value).map_err(|e| e.to_string())
        }
        other => Err(format!("message encoding `{other}`: this silrig reads cdr (and json, of older recordings)")),
    }
}

impl RecordedRun {
    /// Read every recording file of the run in `run_dir`.
    pub fn read(run_dir: &Path) -> Result<Self, RecordingError> {
        let files = recording_files(run_dir);
        if files.is_empty() {
            return Err(RecordingError::NoRecording(run_dir.to_path_buf()));
        }
        let mut run = RecordedRun { files: files.clone(), ..Self::default() };
        for path in &files {
            run.read_file(path)?;
        }
        Ok(run)
    }

    fn read_file(&mut self, path: &Path) -> Result<(), RecordingError> {
        let unreadable = |why: String| RecordingError::Unreadable { path: path.to_path_buf(), why };
        let bytes = std::fs::read(path).map_err(|e| unreadable(e.to_string()))?;
        if !bytes.starts_with(mcap::MAGIC) {
            return Err(unreadable("not an MCAP file (no MCAP magic at its start)".into()));
        }
        let mut topics_by_id: HashMap<u16, (String, String, BTreeMap<String, String>)> = HashMap::new();
        // Set by the file's run metadata, which comes before its first message.
        let mut codecs = Codecs::new(&BTreeMap::new());
        let mut messages = 0u64;
        let mut layout_checked = false;
        // A record whose length field was damaged would have the reader reserve that many bytes (an abort, not an
        // error): read up to the first record that claims more than the file holds, then say so.
        let bad_record = first_impossible_record(&bytes);
        let readable = bad_record.as_ref().map_or(&bytes[..], |(offset, _)| &bytes[..*offset]);
        for record in checked_records(readable) {
            let record = record.map_err(|e| cut_short(path, &bytes, messages, e.to_string()))?;
            match record {
                mcap::records::Record::Metadata(m) if m.name == meta_keys::RUN => {
                    codecs = Codecs::new(&m.metadata);
                    self.add_run_metadata(path, m.metadata)?;
                    layout_checked = true;
                }
                mcap::records::Record::Metadata(m)
                    if m.name == meta_keys::SCENARIO && self.scenario_toml.is_empty() =>
                {
                    self.scenario_toml = m.metadata.get(meta_keys::TOML).cloned().unwrap_or_default();
                }
                // A lockstep recording's trace columns (it has no `/trace` channel to carry them).
                mcap::records::Record::Metadata(m) if m.name == meta_keys::TRACE && self.trace_columns.is_empty() => {
                    self.trace_columns = trace_columns_in(&m.metadata);
                }
                mcap::records::Record::Channel(c) => {
                    topics_by_id.insert(c.id, (c.topic, c.message_encoding, c.metadata));
                }
                mcap::records::Record::Message { header, data } => {
                    messages += 1;
                    if !layout_checked {
                        let found = "no silrig metadata before the first message".to_string();
                        return Err(RecordingError::OtherLayout { path: path.to_path_buf(), found });
                    }
                    let Some(channel) = topics_by_id.get(&header.channel_id) else {
                        return Err(unreadable(format!("a message on unknown channel {}", header.channel_id)));
                    };
                    self.add_message(path, channel, &codecs, &data)?;
                }
                _ => {}
            }
        }
        if let Some((_, why)) = bad_record {
            return Err(cut_short(path, &bytes, messages, why));
        }
        if !bytes.ends_with(mcap::MAGIC) {
            let why = "no MCAP footer at its end".to_string();
            return Err(RecordingError::Truncated { path: path.to_path_buf(), messages, why });
        }
        Ok(())
    }

    /// A file's run metadata: its wire layout must be this build's (replay sends the samples as they were); the
    /// first file's is the run's.
    fn add_run_metadata(&mut self, path: &Path, metadata: BTreeMap<String, String>) -> Result<(), RecordingError> {
        let found = metadata.get(meta_keys::LAYOUT_VERSION).cloned().unwrap_or_else(|| "none".into());
        if found != WIRE_LAYOUT_VERSION.to_string() {
            return Err(RecordingError::OtherLayout { path: path.to_path_buf(), found });
        }
        if self.run.is_empty() {
            self.run = metadata;
        }
        Ok(())
    }

    /// One message on `channel` (its topic, encoding and metadata): counted on its topic, and the wire samples and
    /// the trace's columns kept; an error names the topic and the message's number on it.
    fn add_message(
        &mut self,
        path: &Path,
        (topic, encoding, channel_meta): &(String, String, BTreeMap<String, String>),
        codecs: &Codecs,
        data: &[u8],
    ) -> Result<(), RecordingError> {
        let index = {
            let n = self.counts.entry(topic.clone()).or_insert(0);
            *n += 1;
            *n
        };
        let bad =
            |why: String| RecordingError::BadMessage { path: path.to_path_buf(), topic: topic.clone(), index, why };
        match topic.as_str() {
            topics::PLANT => {
                let sample: PlantSample = decode(encoding, &codecs.plant, data, true).map_err(bad)?;
                // A lockstep recording ends `/plant` with the plant's end-of-run sample (its last actuator
                // positions): no row's sample, so not one replay sends.
                if sample.flags & FLAG_END_OF_RUN == 0 {
                    self.plant.push(sample);
                }
            }
            topics::COMMAND => {
                let command: CommandSample = decode(encoding, &codecs.command, data, true).map_err(bad)?;
                self.commands.insert(command.answers_tick, command);
            }
            topics::PLANT_INFO if self.plant_info.is_none() => {
                self.plant_info = Some(decode(encoding, &codecs.plant_info, data, false).map_err(bad)?);
            }
            topics::TRACE if self.trace_columns.is_empty() => self.trace_columns = trace_columns_in(channel_meta),
            _ => {}
        }
        Ok(())
    }

    /// The plant's signals as it announced them; an error names the file when the recording lacks them or they
    /// break the rules.
    pub fn plant_signals(&self) -> Result<PlantSignals, RecordingError> {
        let path = self.files.first().cloned().unwrap_or_default();
        let info = self.plant_info.as_ref().ok_or_else(|| RecordingError::Unreadable {
            path: path.clone(),
            why: format!("no message on {}: the plant's announcement of its signals is missing", topics::PLANT_INFO),
        })?;
        info.signals().map_err(|why| RecordingError::Unreadable { path, why })
    }

    /// The names of the command's diagnostics: the trace's columns after the plant's.
    pub fn diagnostic_names(&self) -> Result<Vec<String>, RecordingError> {
        let plant_columns = self.plant_signals()?.trace_columns(&[]).len();
        Ok(self.trace_columns.iter().skip(plant_columns).cloned().collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::json::sample_json;
    use silrig_wire::wire::SampleHeader;

    /// A recording as the first loggers wrote it (JSON messages with JSON Schemas), with `plant` and `command`.
    fn write_json_recording(path: &Path, info: &PlantInfo, plant: &PlantSample, command: &CommandSample) {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let mut writer = mcap::Writer::new(file).unwrap();
        let run = BTreeMap::from([
            ("run_id".to_string(), "old".to_string()),
            (meta_keys::LAYOUT_VERSION.to_string(), WIRE_LAYOUT_VERSION.to_string()),
        ]);
        writer.write_metadata(&mcap::records::Metadata { name: meta_keys::RUN.into(), metadata: run }).unwrap();
        let mut add = |topic: &str, metadata: BTreeMap<String, String>| {
            let schema = writer.add_schema(topic, "jsonschema", b"{}").unwrap();
            writer.add_channel(schema, topic, "json", &metadata).unwrap()
        };
        let columns = BTreeMap::from([(TRACE_COLUMNS_KEY.to_string(), "t_s,phi_deg".to_string())]);
        let channels = [
            (add(topics::PLANT_INFO, BTreeMap::new()), sample_json(info, &[])),
            (add(topics::PLANT, BTreeMap::new()), sample_json(plant, &[("t_recv_ns", 5)])),
            (add(topics::COMMAND, BTreeMap::new()), sample_json(command, &[("t_recv_ns", 6)])),
            (add(topics::TRACE, columns), r#"{"t_s":0.0,"phi_deg":1.5}"#.to_string()),
        ];
        for (channel_id, json) in channels {
            let header = mcap::records::MessageHeader { channel_id, sequence: 1, log_time: 1, publish_time: 1 };
            writer.write_to_known_channel(&header, json.as_bytes()).unwrap();
        }
        writer.finish().unwrap();
    }

    #[test]
    fn a_recording_of_json_messages_is_still_read_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("silrig-reader-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let info = PlantInfo::new(&silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2])).unwrap();
        let mut plant = PlantSample::zeroed();
        plant.header = SampleHeader { seq: 3, tick: 3, t_send_ns: 1 << 60, epoch: 9, ..plant.header };
        plant.outputs[..3].copy_from_slice(&[0.1 + 0.2, -0.0, 1e-310]);
        plant.outputs_len = 28;
        let mut command = CommandSample::zeroed();
        command.answers_tick = 3;
        command.diagnostics[2] = std::f64::consts::PI;
        write_json_recording(&dir.join(crate::RECORDING_FILE), &info, &plant, &command);
        let run = RecordedRun::read(&dir).unwrap();
        assert_eq!(run.plant_info, Some(info));
        assert_eq!(run.plant.len(), 1);
        assert_eq!(run.plant[0].outputs.map(f64::to_bits), plant.outputs.map(f64::to_bits));
        assert_eq!(run.plant[0].header, plant.header);
        assert_eq!(run.commands[&3].diagnostics[2].to_bits(), std::f64::consts::PI.to_bits());
        assert_eq!(run.trace_columns, ["t_s", "phi_deg"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A CDR recording of one command, its arrays fixed or bounded as `run` (the run metadata) says.
    fn write_cdr_command(path: &Path, run: &BTreeMap<String, String>, codec: &CdrCodec, command: &CommandSample) {
        let mut writer = mcap::Writer::new(std::io::BufWriter::new(std::fs::File::create(path).unwrap())).unwrap();
        let metadata = mcap::records::Metadata { name: meta_keys::RUN.into(), metadata: run.clone() };
        writer.write_metadata(&metadata).unwrap();
        let schema = writer.add_schema("silrig/msg/CommandSample", cdr::SCHEMA_ENCODING, b"").unwrap();
        let channel_id = writer.add_channel(schema, topics::COMMAND, cdr::MESSAGE_ENCODING, &BTreeMap::new()).unwrap();
        let mut data = cdr::CdrBuffer::default();
        data.start();
        codec.encode(command, &mut data);
        data.u64(6);
        let header = mcap::records::MessageHeader { channel_id, sequence: 1, log_time: 1, publish_time: 1 };
        writer.write_to_known_channel(&header, data.bytes()).unwrap();
        writer.finish().unwrap();
    }

    #[test]
    fn a_recording_reads_its_arrays_as_its_metadata_says_they_were_written() {
        let dir = std::env::temp_dir().join(format!("silrig-reader-arrays-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut command = CommandSample::zeroed();
        command.answers_tick = 4;
        (command.inputs_len, command.diagnostics_len) = (2, 3);
        command.inputs[..2].copy_from_slice(&[1.5, -0.0]);
        command.diagnostics[..3].copy_from_slice(&[0.25, f64::NAN, 7.0]);
        let old = BTreeMap::from([(meta_keys::LAYOUT_VERSION.to_string(), WIRE_LAYOUT_VERSION.to_string())]);
        let mut new = old.clone();
        new.insert(cdr::ARRAYS_KEY.to_string(), cdr::ARRAYS_BOUNDED.to_string());
        for (run, codec) in [(&old, CdrCodec::fixed::<CommandSample>()), (&new, CdrCodec::of::<CommandSample>())] {
            write_cdr_command(&dir.join(crate::RECORDING_FILE), run, &codec, &command);
            let read = RecordedRun::read(&dir).unwrap();
            let back = &read.commands[&4];
            assert_eq!(crate::json::bytes_of(back), crate::json::bytes_of(&command), "{run:?}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_damaged_length_or_chunk_size_is_a_damaged_recording_not_an_abort() {
        let dir = std::env::temp_dir().join(format!("silrig-reader-damaged-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let info = PlantInfo::new(&silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2])).unwrap();
        let path = dir.join(crate::RECORDING_FILE);
        write_json_recording(&path, &info, &PlantSample::zeroed(), &CommandSample::zeroed());
        let whole = std::fs::read(&path).unwrap();
        // The first chunk among the top-level records.
        let mut at = mcap::MAGIC.len();
        while whole[at] != 0x06 {
            at += 9 + u64::from_le_bytes(whole[at + 1..at + 9].try_into().unwrap()) as usize;
        }
        // Its length, then its uncompressed size, filled with the bytes a damaged disk might leave.
        for (field, said) in [(at + 1, "claims"), (at + 9 + 16, "uncompressed")] {
            let mut damaged = whole.clone();
            damaged[field..field + 8].fill(0xa5);
            std::fs::write(&path, &damaged).unwrap();
            match RecordedRun::read(&dir) {
                Err(e @ RecordingError::Damaged { .. }) => assert!(e.to_string().contains(said), "{e}"),
                other => panic!("{other:?}"),
            }
        }
        // Bytes changed inside the chunk's records: its CRC says so before any of them is read.
        let chunk_len = u64::from_le_bytes(whole[at + 1..at + 9].try_into().unwrap()) as usize;
        assert!(chunk_len > 200, "a chunk with records to damage ({chunk_len} bytes)");
        let mut damaged = whole.clone();
        damaged[at + 9 + chunk_len / 2..][..8].fill(0xa5);
        std::fs::write(&path, &damaged).unwrap();
        match RecordedRun::read(&dir) {
            Err(e @ RecordingError::Damaged { messages: 0, .. }) => assert!(e.to_string().contains("CRC"), "{e}"),
            other => panic!("{other:?}"),
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
