//! Wire samples and the logger's rows as CDR (the encoding of ROS 2 messages: a 4-byte encapsulation header
//! `00 01 00 00` for little-endian, then every field in order, each aligned to its own size counted from the end of
//! that header) with their ROS 2 message definitions (`ros2msg`), which Foxglove, PlotJuggler and `ros2 bag` decode
//! without a plug-in. Definitions and codecs are built from each type's field table
//! ([`silrig_wire::wire::WireField`]), so a field added to the wire appears in the recording without an edit here.
//!
//! Every field is written as received: numbers in their own binary form (so every f64, NaN and -0.0 included,
//! reads back bit for bit), `SampleHeader` as a nested message, byte arrays (names and units) as strings. A number
//! array with a count beside it (`outputs` and `outputs_len`, `inputs` and `inputs_len`, `diagnostics` and
//! `diagnostics_len`) is a ROS bounded sequence of the entries in use (`float64[<=64] diagnostics`): the wire has the
//! rest 0, and writing them was most of a `/command` message (4 inputs and 21 diagnostics of the F-16 in 80 slots).
//! Other arrays are ROS fixed arrays. `_pad` fields are left out. [`CdrCodec::decode`] is the inverse, which replay
//! uses to send the recorded samples again bit for bit; [`CdrCodec::fixed`] reads the recordings written before the
//! sequences, whose arrays were all fixed ([`ARRAYS_KEY`] tells them apart).

use crate::json::{Element, bytes_of, fields_shown, shape};
use silrig_wire::wire::{SampleHeader, WireField, WireType};

/// MCAP schema encoding of the definitions.
pub const SCHEMA_ENCODING: &str = "ros2msg";
/// MCAP message encoding of the messages.
pub const MESSAGE_ENCODING: &str = "cdr";
/// The ROS 2 package the definitions belong to (`silrig/msg/PlantSample`).
pub const PACKAGE: &str = "silrig";
/// CDR encapsulation header: plain CDR, little-endian.
const ENCAPSULATION_LE: [u8; 4] = [0, 1, 0, 0];
/// The recording's run metadata key that says its counted arrays are bounded sequences ([`ARRAYS_BOUNDED`]);
/// recordings without it wrote every array fixed.
pub const ARRAYS_KEY: &str = "cdr_arrays";
/// [`ARRAYS_KEY`]'s value in recordings whose counted arrays are bounded sequences.
pub const ARRAYS_BOUNDED: &str = "bounded";
/// Separates a definition from the definitions it uses, as `ros2 bag` writes them.
const DEFINITION_SEPARATOR: &str = "================================================================================\n";

/// A CDR message being built; reused from message to message, so writing one allocates nothing.
#[derive(Debug, Default, Clone)]
pub struct CdrBuffer {
    bytes: Vec<u8>,
}

impl CdrBuffer {
    /// Start a new message: the encapsulation header and nothing else.
    pub fn start(&mut self) {
        self.bytes.clear();
        self.bytes.extend_from_slice(&ENCAPSULATION_LE);
    }

    /// The message so far.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    fn align(&mut self, size: usize) {
        let position = self.bytes.len() - ENCAPSULATION_LE.len();
        let pad = (size - position % size) % size;
        self.bytes.resize(self.bytes.len() + pad, 0);
    }

    /// A float64.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// An int64.
    pub fn i64(&mut self, v: i64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// A uint64.
    pub fn u64(&mut self, v: u64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// A uint32.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// A string: its length with the terminating NUL, its bytes, the NUL.
    pub fn string(&mut self, text: &[u8]) {
        self.u32(text.len() as u32 + 1);
        self.bytes.extend_from_slice(text);
        self.bytes.push(0);
    }
}

/// A CDR message that does not fit what it should hold.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{type_name}: CDR byte {at}: {why}")]
pub struct CdrError {
    type_name: String,
    at: usize,
    why: String,
}

/// Reads a CDR message field by field.
pub struct CdrReader<'a> {
    type_name: &'a str,
    data: &'a [u8],
    /// Position in `data`, counting the encapsulation header.
    at: usize,
}

impl<'a> CdrReader<'a> {
    /// A reader of `data` for a message of `type_name` (named in errors); refuses anything but little-endian plain
    /// CDR.
    pub fn new(type_name: &'a str, data: &'a [u8]) -> Result<Self, CdrError> {
        let reader = Self { type_name, data, at: 0 };
        if !data.starts_with(&ENCAPSULATION_LE) {
            let found = &data[..data.len().min(4)];
            return Err(reader.error(format!("encapsulation {found:02x?}, expected little-endian CDR 00 01 00 00")));
        }
        Ok(Self { at: ENCAPSULATION_LE.len(), ..reader })
    }

    fn error(&self, why: String) -> CdrError {
        CdrError { type_name: self.type_name.to_string(), at: self.at, why }
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], CdrError> {
        let position = self.at - ENCAPSULATION_LE.len();
        let start = self.at + (N - position % N) % N;
        let bytes = self
            .data
            .get(start..start + N)
            .ok_or_else(|| self.error(format!("the message ends ({N} bytes more expected)")))?;
        self.at = start + N;
        Ok(bytes.try_into().expect("N bytes"))
    }

    /// A float64.
    pub fn f64(&mut self) -> Result<f64, CdrError> {
        self.take().map(f64::from_le_bytes)
    }

    /// An int64.
    pub fn i64(&mut self) -> Result<i64, CdrError> {
        self.take().map(i64::from_le_bytes)
    }

    /// A uint64.
    pub fn u64(&mut self) -> Result<u64, CdrError> {
        self.take().map(u64::from_le_bytes)
    }

    /// A uint32.
    pub fn u32(&mut self) -> Result<u32, CdrError> {
        self.take().map(u32::from_le_bytes)
    }

    /// A string's bytes, without its NUL.
    pub fn string(&mut self) -> Result<&'a [u8], CdrError> {
        let len = self.u32()? as usize;
        let bytes = self
            .data
            .get(self.at..self.at + len)
            .ok_or_else(|| self.error(format!("a string of {len} bytes runs past the end")))?;
        if len == 0 || bytes[len - 1] != 0 {
            return Err(self.error("a string without its terminating NUL".into()));
        }
        self.at += len;
        Ok(&bytes[..len - 1])
    }

    /// Every byte has been read (trailing alignment padding aside).
    pub fn finish(&self) -> Result<(), CdrError> {
        match self.data.len() - self.at {
            0..=7 => Ok(()),
            n => Err(self.error(format!("{n} bytes left after the last field"))),
        }
    }
}

/// One element of a flattened field table: where it sits in the wire type and how CDR writes it.
#[derive(Debug, Clone, Copy)]
struct Step {
    offset: usize,
    element: Element,
    /// Elements in a row (1 for a scalar).
    count: usize,
    /// Bytes per element (the NUL-padded text's length for text).
    size: usize,
    /// A bounded sequence: where its count (a `u32`) sits in the wire type.
    len_offset: Option<usize>,
}

/// The count field beside a number array (`outputs_len` beside `outputs`), which makes it a bounded sequence.
fn count_field(fields: &'static [WireField], array: &WireField) -> Option<&'static WireField> {
    let s = shape(array);
    if !s.array || matches!(s.element, Element::Text | Element::Header) {
        return None;
    }
    let name = format!("{}_len", array.name);
    fields.iter().find(|f| f.name == name && f.rust_type.trim() == "u32")
}

/// A wire type's CDR codec: its field table flattened once (nested headers expanded, padding left out), so
/// writing a sample is one pass over numbers.
#[derive(Debug, Clone)]
pub struct CdrCodec {
    type_name: &'static str,
    steps: Vec<Step>,
    size: usize,
}

fn flatten(fields: &'static [WireField], base: usize, bounded: bool, steps: &mut Vec<Step>) {
    for field in fields_shown(fields) {
        let s = shape(field);
        let offset = base + field.offset;
        if s.element == Element::Header {
            let n = if s.array { field.size / size_of::<SampleHeader>() } else { 1 };
            for k in 0..n {
                flatten(SampleHeader::FIELDS, offset + k * size_of::<SampleHeader>(), bounded, steps);
            }
            continue;
        }
        let size = s.element.size(s.text_len);
        let len_offset = count_field(fields, field).filter(|_| bounded).map(|len| base + len.offset);
        steps.push(Step { offset, element: s.element, count: field.size / size, size, len_offset });
    }
}

impl CdrCodec {
    /// The codec of `T` as the logger writes it: counted arrays as bounded sequences.
    pub fn of<T: WireType + Copy>() -> Self {
        Self::with::<T>(true)
    }

    /// The codec of `T` as recordings without [`ARRAYS_KEY`] hold it: every array fixed.
    pub fn fixed<T: WireType + Copy>() -> Self {
        Self::with::<T>(false)
    }

    fn with<T: WireType + Copy>(bounded: bool) -> Self {
        let mut steps = Vec::new();
        flatten(T::FIELDS, 0, bounded, &mut steps);
        Self { type_name: T::TYPE_NAME, steps, size: size_of::<T>() }
    }

    /// The elements of `step` to write: all of a fixed array, the ones in use of a sequence (its count, bounded by
    /// the array, written first).
    fn in_use(step: &Step, bytes: &[u8], out: &mut CdrBuffer) -> usize {
        let Some(at) = step.len_offset else { return step.count };
        let n = (u32::from_ne_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize).min(step.count);
        out.u32(n as u32);
        n
    }

    /// Append `sample`'s fields to `out` (after [`CdrBuffer::start`]; the caller adds any fields after them).
    pub fn encode<T: WireType + Copy>(&self, sample: &T, out: &mut CdrBuffer) {
        debug_assert_eq!(size_of::<T>(), self.size, "the codec of {}", self.type_name);
        let bytes = bytes_of(sample);
        for step in &self.steps {
            let count = Self::in_use(step, bytes, out);
            if count == 0 {
                // CDR aligns an element, not a sequence: an empty one has no padding after its count.
                continue;
            }
            let data = &bytes[step.offset..step.offset + count * step.size];
            match step.element {
                Element::Text => {
                    for text in data.chunks_exact(step.size) {
                        out.string(&text[..text.iter().position(|&b| b == 0).unwrap_or(text.len())]);
                    }
                }
                Element::U32 => {
                    out.align(4);
                    for chunk in data.chunks_exact(4) {
                        let v = u32::from_ne_bytes(chunk.try_into().expect("4 bytes"));
                        out.bytes.extend_from_slice(&v.to_le_bytes());
                    }
                }
                // f64, u64, i64: 8 bytes each, already in a row in the sample.
                _ if cfg!(target_endian = "little") => {
                    out.align(8);
                    out.bytes.extend_from_slice(data);
                }
                _ => {
                    out.align(8);
                    for chunk in data.chunks_exact(8) {
                        let v = u64::from_ne_bytes(chunk.try_into().expect("8 bytes"));
                        out.bytes.extend_from_slice(&v.to_le_bytes());
                    }
                }
            }
        }
    }

    /// The sample `reader` holds next, bit for bit (padding 0; a text longer than its field is an error). The
    /// caller reads any fields after it and calls [`CdrReader::finish`].
    pub fn decode<T: WireType + Copy>(&self, reader: &mut CdrReader) -> Result<T, CdrError> {
        assert_eq!(size_of::<T>(), self.size, "the codec of {}", self.type_name);
        // SAFETY: every wire type is numbers and arrays of numbers, for which all-zero bytes are a valid value.
        let mut sample: T = unsafe { std::mem::zeroed() };
        // SAFETY: as in `bytes_of`; the slice covers exactly the sample, which outlives it, and any bytes are valid.
        let bytes = unsafe { std::slice::from_raw_parts_mut((&mut sample as *mut T).cast::<u8>(), size_of::<T>()) };
        for step in &self.steps {
            let count = match step.len_offset {
                Some(_) => Self::sequence_len(step, reader)?,
                None => step.count,
            };
            // A sequence's entries past its count stay 0, as the wire has them.
            let data = &mut bytes[step.offset..step.offset + count * step.size];
            for chunk in data.chunks_exact_mut(step.size) {
                match step.element {
                    Element::Text => {
                        let text = reader.string()?;
                        if text.len() >= chunk.len() {
                            let why = format!("a name of {} bytes where at most {} fit", text.len(), chunk.len() - 1);
                            return Err(reader.error(why));
                        }
                        chunk[..text.len()].copy_from_slice(text);
                    }
                    Element::U32 => chunk.copy_from_slice(&reader.u32()?.to_ne_bytes()),
                    _ => chunk.copy_from_slice(&reader.u64()?.to_ne_bytes()),
                }
            }
        }
        Ok(sample)
    }

    /// A bounded sequence's count, refused past the array's length.
    fn sequence_len(step: &Step, reader: &mut CdrReader) -> Result<usize, CdrError> {
        let n = reader.u32()? as usize;
        if n > step.count {
            return Err(reader.error(format!("a sequence of {n} entries where at most {} fit", step.count)));
        }
        Ok(n)
    }
}

fn ros_type(element: Element) -> String {
    match element {
        Element::F64 => "float64".into(),
        Element::U64 => "uint64".into(),
        Element::I64 => "int64".into(),
        Element::U32 => "uint32".into(),
        Element::Text => "string".into(),
        Element::Header => format!("{PACKAGE}/{}", SampleHeader::NAME),
    }
}

/// `doc` as `#` comment lines.
fn comment(doc: &str) -> String {
    let text = doc.split_whitespace().collect::<Vec<_>>().join(" ");
    if text.is_empty() { String::new() } else { format!("# {text}\n") }
}

fn fields_msg(fields: &'static [WireField]) -> String {
    let mut out = String::new();
    for field in fields_shown(fields) {
        let s = shape(field);
        let n = field.size / s.element.size(s.text_len);
        let array = match (s.array, count_field(fields, field)) {
            (true, Some(_)) => format!("[<={n}]"),
            (true, None) => format!("[{n}]"),
            (false, _) => String::new(),
        };
        out += &comment(field.doc);
        out += &format!("{}{array} {}\n", ros_type(s.element), field.name);
    }
    out
}

/// The schema name of `T`'s message (`silrig/msg/PlantSample`).
pub fn msg_name<T: WireType>() -> String {
    format!("{PACKAGE}/msg/{}", T::NAME)
}

/// The ROS 2 message definition of `T` with `extra` uint64 fields after its own (name, description), followed by
/// the definitions it uses, as `ros2 bag` stores them.
pub fn sample_msg<T: WireType>(extra: &[(&str, &str)]) -> String {
    let mut out = fields_msg(T::FIELDS);
    for (name, doc) in extra {
        out += &comment(doc);
        out += &format!("uint64 {name}\n");
    }
    if fields_shown(T::FIELDS).any(|f| shape(f).element == Element::Header) {
        out += DEFINITION_SEPARATOR;
        out += &format!("MSG: {PACKAGE}/{}\n", SampleHeader::NAME);
        out += &fields_msg(SampleHeader::FIELDS);
    }
    out
}

/// Whether `name` is a valid ROS 2 field name: a lowercase letter, then lowercase letters, digits and single
/// underscores, not ending in one.
pub fn valid_field_name(name: &str) -> bool {
    let bytes = name.as_bytes();
    bytes.first().is_some_and(u8::is_ascii_lowercase)
        && bytes.iter().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || *b == b'_')
        && !name.contains("__")
        && !name.ends_with('_')
}

/// Field names for `columns` in a message definition: each column's own name where it is a valid ROS 2 field name
/// and not taken; otherwise a valid name made from it and its position (`c7_s_phi` for column 7, `S_phi`). The
/// columns' real names travel beside the definition (the channel's metadata), in order.
pub fn field_names(columns: &[String]) -> Vec<String> {
    let mut taken = std::collections::HashSet::new();
    let mut names: Vec<Option<String>> =
        columns.iter().map(|c| (valid_field_name(c) && taken.insert(c.clone())).then(|| c.clone())).collect();
    for (k, (slot, column)) in names.iter_mut().zip(columns).enumerate() {
        if slot.is_none() {
            let lowered: String =
                column.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
            let words: Vec<&str> = lowered.split('_').filter(|w| !w.is_empty()).collect();
            let mut name = if words.is_empty() { format!("c{k}") } else { format!("c{k}_{}", words.join("_")) };
            while !taken.insert(name.clone()) {
                name += "_x";
            }
            *slot = Some(name);
        }
    }
    names.into_iter().map(|n| n.expect("every column named")).collect()
}

/// The definition of a message of float64 fields named `names`, each with its column's description.
pub fn float_row_msg(header: &str, names: &[String], columns: &[String]) -> String {
    let mut out = comment(header);
    for (name, column) in names.iter().zip(columns) {
        if name != column {
            out += &format!("# column {column}\n");
        }
        out += &format!("float64 {name}\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_wire::wire::{CommandSample, ControllerInfo, LogAckSample, PlantInfo, PlantSample};

    fn plant() -> PlantSample {
        let mut s = PlantSample::zeroed();
        s.header = SampleHeader { seq: 7, tick: 41, t_send_ns: u64::MAX - 3, epoch: 2, layout_version: 3, _pad: 0 };
        // Entries past the count are 0, as the wire has them.
        s.outputs_len = 20;
        s.outputs = std::array::from_fn(|i| if i < 20 { 0.1 * i as f64 + 1.0 / 3.0 } else { 0.0 });
        s.outputs[4] = -0.0;
        s.outputs[5..9].copy_from_slice(&[-1e-300, f64::NAN, f64::NEG_INFINITY, f64::MIN_POSITIVE]);
        s.t_sim_s = 0.41;
        s.flags = 0b101;
        s.wake_lateness_ns = -12;
        s.previous_step_exec_ns = 4321;
        s
    }

    #[test]
    fn a_plant_sample_reads_back_bit_for_bit_in_the_layout_ros_expects() {
        let s = plant();
        let codec = CdrCodec::of::<PlantSample>();
        let mut out = CdrBuffer::default();
        out.start();
        codec.encode(&s, &mut out);
        out.u64(99);
        let data = out.bytes();
        assert_eq!(&data[..4], &[0, 1, 0, 0]);
        // header: seq, tick, t_send_ns, epoch (8 each), layout_version (4); t_sim_s aligned to 8 after 4 bytes of
        // padding.
        assert_eq!(u64::from_le_bytes(data[12..20].try_into().unwrap()), 41);
        assert_eq!(u32::from_le_bytes(data[36..40].try_into().unwrap()), 3);
        assert_eq!(f64::from_le_bytes(data[44..52].try_into().unwrap()), 0.41);
        // outputs as a sequence: its count (20) after outputs_len, 4 bytes of padding, the 20 entries in use.
        assert_eq!(u32::from_le_bytes(data[76..80].try_into().unwrap()), 20);
        assert_eq!(f64::from_le_bytes(data[84..92].try_into().unwrap()), 1.0 / 3.0);
        assert_eq!(data.len(), 4 + 40 + 8 + 8 + 8 + 4 + 4 + 4 + 4 + 20 * 8 + 8);
        let mut reader = CdrReader::new(PlantSample::TYPE_NAME, data).unwrap();
        let back: PlantSample = codec.decode(&mut reader).unwrap();
        assert_eq!(reader.u64().unwrap(), 99);
        reader.finish().unwrap();
        assert_eq!(bytes_of(&back), bytes_of(&s));
    }

    #[test]
    fn every_wire_type_round_trips_and_has_a_definition_naming_every_field() {
        fn check<T: WireType + Copy>(sample: T) {
            let codec = CdrCodec::of::<T>();
            let mut out = CdrBuffer::default();
            out.start();
            codec.encode(&sample, &mut out);
            let mut reader = CdrReader::new(T::TYPE_NAME, out.bytes()).unwrap();
            let back: T = codec.decode(&mut reader).unwrap();
            reader.finish().unwrap();
            assert_eq!(bytes_of(&back), bytes_of(&sample), "{}", T::NAME);
            let msg = sample_msg::<T>(&[]);
            for f in fields_shown(T::FIELDS) {
                assert!(msg.lines().any(|l| l.ends_with(&format!(" {}", f.name))), "{} missing from {msg}", f.name);
            }
            assert!(!msg.contains("_pad"), "{msg}");
        }
        let f16 = silrig_flight::f16_signals::f16_signals([0.0, -1.9, 0.0, 0.2]);
        check(plant());
        let mut c = CommandSample::zeroed();
        c.inputs_len = 3;
        c.inputs[..3].copy_from_slice(&[f64::NAN, f64::INFINITY, 1.5]);
        c.diagnostics_len = 64;
        c.diagnostics[63] = -2.25;
        check(c);
        check(CommandSample::zeroed());
        check(PlantInfo::new(&f16).unwrap());
        check(ControllerInfo::new(&["s_phi".to_string(), "w_phi_0".to_string()]).unwrap());
        check(LogAckSample::new(12));
        let msg = sample_msg::<PlantInfo>(&[]);
        assert!(msg.contains("string[32] output_names\n") && msg.contains("silrig/SampleHeader header\n"), "{msg}");
        assert!(msg.contains("\nMSG: silrig/SampleHeader\n") && msg.contains("uint32 layout_version\n"), "{msg}");
        assert!(sample_msg::<PlantSample>(&[]).contains("float64[<=32] outputs\n"));
        let msg = sample_msg::<CommandSample>(&[]);
        assert!(msg.contains("float64[<=16] inputs\n") && msg.contains("float64[<=64] diagnostics\n"), "{msg}");
    }

    #[test]
    fn only_the_entries_in_use_are_written_and_an_empty_sequence_has_no_padding() {
        let mut c = CommandSample::zeroed();
        c.diagnostics_len = 2;
        c.diagnostics[..2].copy_from_slice(&[0.5, -0.25]);
        // Past the count: not the wire's contract, and not recorded.
        c.diagnostics[9] = 7.0;
        let codec = CdrCodec::of::<CommandSample>();
        let mut out = CdrBuffer::default();
        out.start();
        codec.encode(&c, &mut out);
        let data = out.bytes();
        // header 40, answers_tick 8, compute_ns 8, flags, inputs_len, diagnostics_len 12: then the inputs' count
        // (0) at 68 and, with no padding, the diagnostics' count (2) at 72, 4 bytes of padding, two entries.
        assert_eq!(u32::from_le_bytes(data[4 + 68..4 + 72].try_into().unwrap()), 0);
        assert_eq!(u32::from_le_bytes(data[4 + 72..4 + 76].try_into().unwrap()), 2);
        assert_eq!(f64::from_le_bytes(data[4 + 80..4 + 88].try_into().unwrap()), 0.5);
        assert_eq!(data.len(), 4 + 80 + 2 * 8);
        let back: CommandSample = codec.decode(&mut CdrReader::new("c", data).unwrap()).unwrap();
        assert_eq!((back.diagnostics(), back.diagnostics[9]), (&[0.5, -0.25][..], 0.0));
        assert_eq!(back.inputs.map(f64::to_bits), c.inputs.map(f64::to_bits));
    }

    #[test]
    fn a_recording_of_fixed_arrays_still_reads_and_a_sequence_too_long_is_refused() {
        let mut c = CommandSample::zeroed();
        c.inputs_len = 1;
        c.diagnostics[63] = -2.25;
        let fixed = CdrCodec::fixed::<CommandSample>();
        let mut out = CdrBuffer::default();
        out.start();
        fixed.encode(&c, &mut out);
        assert_eq!(out.bytes().len(), 4 + 72 + 80 * 8);
        let back: CommandSample = fixed.decode(&mut CdrReader::new("c", out.bytes()).unwrap()).unwrap();
        assert_eq!(bytes_of(&back), bytes_of(&c));
        let mut long = CdrBuffer::default();
        long.start();
        CdrCodec::of::<PlantSample>().encode(&plant(), &mut long);
        let mut data = long.bytes().to_vec();
        data[76..80].copy_from_slice(&33u32.to_le_bytes());
        let err = CdrCodec::of::<PlantSample>().decode::<PlantSample>(&mut CdrReader::new("p", &data).unwrap());
        assert!(err.unwrap_err().to_string().contains("a sequence of 33 entries where at most 32 fit"));
    }

    #[test]
    fn a_short_or_foreign_message_is_refused() {
        let codec = CdrCodec::of::<PlantSample>();
        let mut out = CdrBuffer::default();
        out.start();
        codec.encode(&plant(), &mut out);
        let data = out.bytes();
        let err = codec.decode::<PlantSample>(&mut CdrReader::new("p", &data[..100]).unwrap()).unwrap_err();
        assert!(err.to_string().contains("the message ends"), "{err}");
        let mut big_endian = data.to_vec();
        big_endian[1] = 0;
        assert!(CdrReader::new("p", &big_endian).is_err());
        let mut long = data.to_vec();
        long.extend([0; 16]);
        let mut reader = CdrReader::new("p", &long).unwrap();
        codec.decode::<PlantSample>(&mut reader).unwrap();
        assert!(reader.finish().unwrap_err().to_string().contains("16 bytes left"));
    }

    #[test]
    fn column_names_become_valid_unique_field_names() {
        let columns: Vec<String> =
            ["t_s", "phi_deg", "S_phi", "s_phi", "x__y", "9lives", "t_s"].map(String::from).into();
        let names = field_names(&columns);
        assert_eq!(names, ["t_s", "phi_deg", "c2_s_phi", "s_phi", "c4_x_y", "c5_9lives", "c6_t_s"]);
        assert!(names.iter().all(|n| valid_field_name(n)));
    }
}
