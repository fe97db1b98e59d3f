//! The wire format: the one definition of every sample type that crosses a process boundary over iceoryx2, with
//! its layout version and its validity check.
//!
//! iceoryx2 matches a service's payload by type *name*, size and alignment only; field order and meaning are not
//! checked. The type names therefore carry [`WIRE_LAYOUT_VERSION`] (each is built from it by the `wire_type!` macro):
//! whenever a field is added, removed, reordered or changes meaning, bump the version, so that a peer built from the
//! old layout gets `IncompatibleTypes` on open (turned into [`crate::ipc::IpcError::OtherWireLayout`]) instead of
//! misreading bytes.

use iceoryx2::prelude::ZeroCopySend;
use silrig_flight::signals::{self, InputSignal, OutputSignal, PlantSignals};

/// The layout version as a literal, so that the type names can be built from it with `concat!`.
macro_rules! layout_version {
    () => {
        5
    };
}

/// Version of the wire layout; every sample carries it in [`SampleHeader::layout_version`], and every type name
/// ends in `::v<version>`.
pub const WIRE_LAYOUT_VERSION: u32 = layout_version!();

/// Declares a type that crosses a process boundary: `#[repr(C)]`, with the iceoryx2 identity
/// `silrig::<Name>::v<WIRE_LAYOUT_VERSION>` (its `TYPE_NAME`). `ZeroCopySend` is implemented here rather than
/// derived because the derive takes a type name only as a literal; the check the derive makes (every field is itself
/// `ZeroCopySend`) is kept. `with header` also makes it a [`WireSample`] whose `validate` checks the layout version
/// and then calls the type's own `check`.
macro_rules! wire_type {
    (
        $(#[$meta:meta])*
        pub struct $name:ident { $($(#[doc = $doc:literal])* pub $field:ident: $ty:ty,)* }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        pub struct $name { $($(#[doc = $doc])* pub $field: $ty,)* }

        impl $name {
            /// The iceoryx2 type name.
            pub const TYPE_NAME: &'static str = concat!("silrig::", stringify!($name), "::v", layout_version!());
            /// Every field in memory order, with its offset and size taken from this very type.
            pub const FIELDS: &'static [WireField] = &[$(WireField {
                name: stringify!($field),
                rust_type: stringify!($ty),
                offset: core::mem::offset_of!($name, $field),
                size: core::mem::size_of::<$ty>(),
                doc: concat!($($doc, "\n",)*),
            },)*];
        }

        impl WireType for $name {
            const NAME: &'static str = stringify!($name);
            const TYPE_NAME: &'static str = $name::TYPE_NAME;
            const FIELDS: &'static [WireField] = $name::FIELDS;
        }

        // SAFETY: `#[repr(C)]` and every field is ZeroCopySend (checked below, as the derive does): numbers and
        // arrays of numbers, no pointers, no Drop, the same layout in every process built from this definition.
        unsafe impl ZeroCopySend for $name {
            unsafe fn type_name() -> &'static str {
                Self::TYPE_NAME
            }

            fn __is_zero_copy_send(&self) {
                $(ZeroCopySend::__is_zero_copy_send(&self.$field);)*
            }
        }
    };
    (
        $(#[$meta:meta])*
        pub struct $name:ident with header { $($body:tt)* }
    ) => {
        wire_type! { $(#[$meta])* pub struct $name { $($body)* } }

        impl WireSample for $name {
            const TYPE_NAME: &'static str = $name::TYPE_NAME;

            fn header(&self) -> &SampleHeader {
                &self.header
            }

            fn header_mut(&mut self) -> &mut SampleHeader {
                &mut self.header
            }

            fn validate(&self) -> Result<(), WireError> {
                check_layout(Self::TYPE_NAME, &self.header)?;
                self.check()
            }
        }
    };
}

/// One field of a wire type, as the contract describes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WireField {
    /// Field name.
    pub name: &'static str,
    /// Its Rust type as written in the definition (`u64`, `[f64; 3]`, `SampleHeader`).
    pub rust_type: &'static str,
    /// Byte offset in the type (`core::mem::offset_of!`).
    pub offset: usize,
    /// Size in bytes.
    pub size: usize,
    /// Its doc comment, one line per source line: what it is, in which unit.
    pub doc: &'static str,
}

/// What the contract needs to know of every type that crosses a process boundary.
pub trait WireType {
    /// The Rust name.
    const NAME: &'static str;
    /// The iceoryx2 type name.
    const TYPE_NAME: &'static str;
    /// Every field in memory order.
    const FIELDS: &'static [WireField];
}

/// Diagnostics a command sample carries at most (the paper's controller with 5 RBF nodes per channel reports 21;
/// with 19, 63).
pub const MAX_DIAGNOSTICS: usize = 64;
/// Outputs a plant sample carries at most (the F-16 announces 28).
pub const MAX_OUTPUTS: usize = 32;
/// Inputs a command carries at most (the F-16 takes 4).
pub const MAX_INPUTS: usize = 16;
/// Bytes of a name on the wire (plant, signal, diagnostic), NUL-padded: at most 31 characters.
pub const NAME_BYTES: usize = signals::MAX_NAME_LEN + 1;
/// Bytes of a unit on the wire, NUL-padded: at most 15 characters.
pub const UNIT_BYTES: usize = signals::MAX_UNIT_LEN + 1;
/// `PlantInfo::output_flags`: the logger writes this output to `trace.csv`.
pub const OUTPUT_IN_TRACE: u32 = 1 << 0;
/// `PlantInfo::input_flags`: the logger writes this input's command to `trace.csv`.
pub const INPUT_COMMAND_IN_TRACE: u32 = 1 << 0;
/// `PlantInfo::input_held_output`: the input has no output that reports its actuator's position.
pub const NO_OUTPUT: u32 = u32::MAX;

/// `PlantSample::flags`/`CommandSample::flags`: the command the plant applied is older than the staleness limit.
pub const FLAG_COMMAND_STALE: u32 = 1 << 0;
/// At least one input's actuator sits on its position limit.
pub const FLAG_SATURATED: u32 = 1 << 1;
/// The failsafe output is active (the producer of the input is gone or stale for too long).
pub const FLAG_FAILSAFE: u32 = 1 << 2;
/// At least one actuator moved at its rate limit during this tick.
pub const FLAG_RATE_LIMITED: u32 = 1 << 3;
/// `PlantSample::flags`: the plant's last sample of the run, after its last tick (the end of the scenario, or a
/// state that left the model's envelope). It repeats that tick's outputs with the actuator positions that tick's
/// command set, which no later sample would carry; a controller does not answer it.
pub const FLAG_END_OF_RUN: u32 = 1 << 5;
/// `PlantSample::flags`: the model's outputs for this tick were refused (NaN or infinity) and the sample carries
/// the last valid ones, held: the row is not the model's flight data (`trace.csv`'s `outputs_held`).
pub const FLAG_OUTPUTS_HELD: u32 = 1 << 6;

/// `CommandSample::flags`: the controller's command for this tick was refused (NaN, infinity or out of range) and
/// not sent; the plant holds its last valid command, as for a missing one.
pub const FLAG_COMMAND_REFUSED: u32 = 1 << 4;

wire_type! {
/// Bookkeeping that precedes every sample: loss detection, timing and restart detection.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SampleHeader {
    /// Per-publisher counter, starting at 0 for each epoch; a jump means samples were lost.
    pub seq: u64,
    /// Plant tick the sample belongs to; sim time = tick * dt.
    pub tick: u64,
    /// CLOCK_MONOTONIC at publish, ns (the same clock in every process of the machine).
    pub t_send_ns: u64,
    /// Identity of the publishing process's life: changes whenever that process (re)starts.
    pub epoch: u64,
    /// [`WIRE_LAYOUT_VERSION`] of the sender.
    pub layout_version: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
}
}

wire_type! {
/// What the plant publishes every tick: its announced outputs, in the order of its [`PlantInfo`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantSample with header {
    /// Bookkeeping.
    pub header: SampleHeader,
    /// Simulated time of these outputs, s.
    pub t_sim_s: f64,
    /// How late the plant woke for this tick (actual minus ideal start, the cyclictest figure), ns; 0 in lockstep
    /// (no sleeping) and in the end-of-run sample.
    pub wake_lateness_ns: i64,
    /// Execution time of the previous tick's step (actuators and model), ns: a tick's step runs after its sample
    /// is published, so the next sample carries it (the end-of-run sample carries the last tick's); 0 in the first
    /// sample of a plant life.
    pub previous_step_exec_ns: u64,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Entries of `outputs` in use: as many as the plant announced, always.
    pub outputs_len: u32,
    /// The outputs in the order the plant announced them; entries past `outputs_len` are 0. An output that reports
    /// an input's actuator position (`PlantInfo::input_held_output`) is sampled when the tick begins, before this
    /// tick's command acts: the position held over the step from the previous tick to this one (the trace's row
    /// of the previous tick shows it). In the end-of-run sample: the position the last tick's command set.
    pub outputs: [f64; MAX_OUTPUTS],
}
}

wire_type! {
/// What a controller publishes in answer to a plant sample: the tick it answers, the plant's inputs, its compute
/// time, flags, then its own diagnostics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandSample with header {
    /// Bookkeeping; `tick` is the tick this command answers.
    pub header: SampleHeader,
    /// Tick of the plant sample this command was computed from.
    pub answers_tick: u64,
    /// Time the controller spent computing this command, ns.
    pub compute_ns: u64,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Entries of `inputs` in use: as many as the plant announced, always.
    pub inputs_len: u32,
    /// Entries of `diagnostics` in use, at most MAX_DIAGNOSTICS.
    pub diagnostics_len: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
    /// The command of each input, in the order the plant announced them, each within the input's range;
    /// entries past `inputs_len` are 0.
    pub inputs: [f64; MAX_INPUTS],
    /// The controller's own values for this tick, whatever it wants logged and plotted (the paper's controller:
    /// S and f_hat per channel, then its RBF weights, channel by channel); entries past `diagnostics_len` are 0.
    pub diagnostics: [f64; MAX_DIAGNOSTICS],
}
}

wire_type! {
/// What a plant announces once per epoch, before its first sample: its name and its signals. Controllers find the
/// outputs they read and the inputs they command by name here; the logger makes the trace's columns from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantInfo with header {
    /// Bookkeeping; `epoch` is the plant's, as in its samples.
    pub header: SampleHeader,
    /// The plant's name (`f16`): ASCII letters, digits and '_', NUL-padded.
    pub plant_name: [u8; NAME_BYTES],
    /// Outputs announced, 1..=MAX_OUTPUTS.
    pub outputs_len: u32,
    /// Inputs announced, 0..=MAX_INPUTS.
    pub inputs_len: u32,
    /// Per output: `OUTPUT_IN_TRACE` or 0.
    pub output_flags: [u32; MAX_OUTPUTS],
    /// Per input: `INPUT_COMMAND_IN_TRACE` or 0.
    pub input_flags: [u32; MAX_INPUTS],
    /// Per input: the index of the output that reports its actuator's position, or `NO_OUTPUT`.
    pub input_held_output: [u32; MAX_INPUTS],
    /// Per input: a command below this is refused.
    pub input_min: [f64; MAX_INPUTS],
    /// Per input: a command above this is refused.
    pub input_max: [f64; MAX_INPUTS],
    /// Per input: what the plant's failsafe commands while no controller answers, within min..max.
    pub input_hold: [f64; MAX_INPUTS],
    /// Per output: its name, unique among the outputs (ASCII letters, digits and '_', NUL-padded).
    pub output_names: [[u8; NAME_BYTES]; MAX_OUTPUTS],
    /// Per output: its unit, printable ASCII without comma or quote, NUL-padded (may be empty).
    pub output_units: [[u8; UNIT_BYTES]; MAX_OUTPUTS],
    /// Per input: its name, unique among the inputs.
    pub input_names: [[u8; NAME_BYTES]; MAX_INPUTS],
    /// Per input: its unit.
    pub input_units: [[u8; UNIT_BYTES]; MAX_INPUTS],
}
}

wire_type! {
/// What a controller announces once per epoch, before its first command: the names of its diagnostics, which the
/// logger makes the trace's columns and the plots label.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerInfo with header {
    /// Bookkeeping; `epoch` is the controller's, as in its commands.
    pub header: SampleHeader,
    /// Names in use, at most MAX_DIAGNOSTICS.
    pub diagnostics_len: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
    /// The name of each diagnostic, in the order of `CommandSample::diagnostics`: ASCII letters, digits and '_',
    /// NUL-padded.
    pub diagnostic_names: [[u8; NAME_BYTES]; MAX_DIAGNOSTICS],
}
}

wire_type! {
/// What the logger publishes after writing rows, so a lockstep plant never runs further ahead of it than the
/// logger's queue holds (lockstep must lose nothing, however slow the disk).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogAckSample with header {
    /// Bookkeeping (`tick` is the last tick written).
    pub header: SampleHeader,
    /// Rows written to `trace.csv` so far.
    pub rows_written: u64,
}
}

// The sizes are part of the wire contract: iceoryx2 compares them on open, and a change here without a version bump
// would only be caught at run time.
const _: () = assert!(core::mem::size_of::<SampleHeader>() == 40);
const _: () = assert!(core::mem::align_of::<SampleHeader>() == 8);
const _: () = assert!(core::mem::size_of::<PlantSample>() == 328);
const _: () = assert!(core::mem::align_of::<PlantSample>() == 8);
const _: () = assert!(core::mem::size_of::<CommandSample>() == 712);
const _: () = assert!(core::mem::size_of::<PlantInfo>() == 3024);
const _: () = assert!(core::mem::align_of::<PlantInfo>() == 8);
const _: () = assert!(core::mem::size_of::<LogAckSample>() == 48);
const _: () = assert!(core::mem::align_of::<CommandSample>() == 8);

/// A sample that must not be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum WireError {
    /// A float field is NaN or infinite.
    #[error("{type_name}: field `{field}{}` is not finite ({value})", element(*.index))]
    NotFinite {
        /// Type name of the sample.
        type_name: &'static str,
        /// Field.
        field: &'static str,
        /// Element of an array field.
        index: Option<usize>,
        /// The offending value.
        value: f64,
    },
    /// The sender used another layout version (should be unreachable: the type name already differs).
    #[error("{type_name}: layout_version {got}, this build speaks {expected}")]
    LayoutVersion {
        /// Type name of the sample.
        type_name: &'static str,
        /// Version in the sample.
        got: u32,
        /// [`WIRE_LAYOUT_VERSION`].
        expected: u32,
    },
    /// A count beyond what the layout holds, or a command outside its input's range.
    #[error("{type_name}: field `{field}{}` is out of range ({value})", element(*.index))]
    OutOfRange {
        /// Type name of the sample.
        type_name: &'static str,
        /// Field.
        field: &'static str,
        /// Element of an array field.
        index: Option<usize>,
        /// The offending value.
        value: f64,
    },
}

/// What every sample type on the wire offers to the transport.
pub trait WireSample: ZeroCopySend + Copy + core::fmt::Debug + 'static {
    /// The iceoryx2 type name (also in `#[type_name]`).
    const TYPE_NAME: &'static str;
    /// The header.
    fn header(&self) -> &SampleHeader;
    /// The header, to stamp before sending.
    fn header_mut(&mut self) -> &mut SampleHeader;
    /// Rejects NaN/inf in any float field and a foreign layout version, naming the field.
    fn validate(&self) -> Result<(), WireError>;
}

/// `[k]` for an element of an array field.
fn element(index: Option<usize>) -> String {
    index.map(|k| format!("[{k}]")).unwrap_or_default()
}

fn check_layout(type_name: &'static str, header: &SampleHeader) -> Result<(), WireError> {
    if header.layout_version != WIRE_LAYOUT_VERSION {
        return Err(WireError::LayoutVersion { type_name, got: header.layout_version, expected: WIRE_LAYOUT_VERSION });
    }
    Ok(())
}

/// A count field within `0..=max`.
fn check_count(type_name: &'static str, field: &'static str, count: u32, max: usize) -> Result<usize, WireError> {
    match count as usize {
        n if n <= max => Ok(n),
        _ => Err(WireError::OutOfRange { type_name, field, index: None, value: f64::from(count) }),
    }
}

/// The first NaN or infinity among `values`, as an error naming its element.
fn check_finite(type_name: &'static str, field: &'static str, values: &[f64]) -> Result<(), WireError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(WireError::NotFinite { type_name, field, index: Some(k), value: values[k] }),
        None => Ok(()),
    }
}

fn header() -> SampleHeader {
    SampleHeader { layout_version: WIRE_LAYOUT_VERSION, ..SampleHeader::default() }
}

impl PlantSample {
    /// A sample with everything zero and the current layout version.
    pub fn zeroed() -> Self {
        Self {
            header: header(),
            t_sim_s: 0.0,
            wake_lateness_ns: 0,
            previous_step_exec_ns: 0,
            flags: 0,
            outputs_len: 0,
            outputs: [0.0; MAX_OUTPUTS],
        }
    }

    /// A sample carrying `outputs` (at most [`MAX_OUTPUTS`]).
    pub fn with_outputs(outputs: &[f64]) -> Self {
        let mut sample = Self::zeroed();
        sample.outputs[..outputs.len()].copy_from_slice(outputs);
        sample.outputs_len = outputs.len() as u32;
        sample
    }

    /// The outputs in use.
    pub fn outputs(&self) -> &[f64] {
        &self.outputs[..(self.outputs_len as usize).min(MAX_OUTPUTS)]
    }

    /// Rejects an output count beyond the layout and NaN/inf in an output in use or the time, naming it.
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        check_count(t, "outputs_len", self.outputs_len, MAX_OUTPUTS)?;
        check_finite(t, "outputs", self.outputs())?;
        if !self.t_sim_s.is_finite() {
            return Err(WireError::NotFinite { type_name: t, field: "t_sim_s", index: None, value: self.t_sim_s });
        }
        Ok(())
    }
}

impl CommandSample {
    /// A sample with everything zero and the current layout version.
    pub fn zeroed() -> Self {
        Self {
            header: header(),
            answers_tick: 0,
            compute_ns: 0,
            flags: 0,
            inputs_len: 0,
            diagnostics_len: 0,
            _pad: 0,
            inputs: [0.0; MAX_INPUTS],
            diagnostics: [0.0; MAX_DIAGNOSTICS],
        }
    }

    /// The inputs in use.
    pub fn inputs(&self) -> &[f64] {
        &self.inputs[..(self.inputs_len as usize).min(MAX_INPUTS)]
    }

    /// The diagnostics in use.
    pub fn diagnostics(&self) -> &[f64] {
        &self.diagnostics[..(self.diagnostics_len as usize).min(MAX_DIAGNOSTICS)]
    }

    /// Rejects counts beyond the layout and NaN/inf in an input or a diagnostic in use, naming the field. Whether
    /// each input lies within its range is the plant's to say ([`PlantSignals`], `check_command`).
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        check_count(t, "inputs_len", self.inputs_len, MAX_INPUTS)?;
        check_count(t, "diagnostics_len", self.diagnostics_len, MAX_DIAGNOSTICS)?;
        check_finite(t, "inputs", self.inputs())?;
        check_finite(t, "diagnostics", self.diagnostics())
    }
}

/// `text` NUL-padded into a name or unit field (the caller has checked that it fits).
fn padded<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0; N];
    out[..text.len()].copy_from_slice(text.as_bytes());
    out
}

/// The text of a NUL-padded field: `None` when it is unterminated or not ASCII.
fn unpadded(raw: &[u8]) -> Option<String> {
    let len = raw.iter().position(|b| *b == 0)?;
    raw[..len].is_ascii().then(|| String::from_utf8_lossy(&raw[..len]).into_owned())
}

/// Whether a command fits a plant: as many inputs as it announced, each within its range. The error names the
/// input by index and name.
pub fn check_command(plant: &PlantSignals, command: &CommandSample) -> Result<(), String> {
    let t = CommandSample::TYPE_NAME;
    if command.inputs_len as usize != plant.inputs.len() {
        return Err(format!(
            "{t}: {} inputs; plant {} takes {} ({})",
            command.inputs_len,
            plant.plant,
            plant.inputs.len(),
            plant.inputs.iter().map(|i| i.name.as_str()).collect::<Vec<_>>().join(", ")
        ));
    }
    for (k, (value, input)) in command.inputs().iter().zip(&plant.inputs).enumerate() {
        if !(*value >= input.min && *value <= input.max) {
            return Err(format!(
                "{t}: field `inputs[{k}]` ({} {}) is out of range ({value}): plant {} takes {}..{}",
                input.name, input.unit, plant.plant, input.min, input.max
            ));
        }
    }
    Ok(())
}

impl PlantInfo {
    /// The announcement of `plant`; the error names the first rule it breaks ([`PlantSignals::check`]).
    pub fn new(plant: &PlantSignals) -> Result<Self, String> {
        plant.check(MAX_OUTPUTS, MAX_INPUTS)?;
        let mut info = Self {
            header: header(),
            plant_name: padded(&plant.plant),
            outputs_len: plant.outputs.len() as u32,
            inputs_len: plant.inputs.len() as u32,
            output_flags: [0; MAX_OUTPUTS],
            input_flags: [0; MAX_INPUTS],
            input_held_output: [NO_OUTPUT; MAX_INPUTS],
            input_min: [0.0; MAX_INPUTS],
            input_max: [0.0; MAX_INPUTS],
            input_hold: [0.0; MAX_INPUTS],
            output_names: [[0; NAME_BYTES]; MAX_OUTPUTS],
            output_units: [[0; UNIT_BYTES]; MAX_OUTPUTS],
            input_names: [[0; NAME_BYTES]; MAX_INPUTS],
            input_units: [[0; UNIT_BYTES]; MAX_INPUTS],
        };
        for (k, o) in plant.outputs.iter().enumerate() {
            info.output_names[k] = padded(&o.name);
            info.output_units[k] = padded(&o.unit);
            info.output_flags[k] = if o.in_trace { OUTPUT_IN_TRACE } else { 0 };
        }
        for (k, i) in plant.inputs.iter().enumerate() {
            info.input_names[k] = padded(&i.name);
            info.input_units[k] = padded(&i.unit);
            info.input_flags[k] = if i.command_in_trace { INPUT_COMMAND_IN_TRACE } else { 0 };
            info.input_held_output[k] = i.held_output.map_or(NO_OUTPUT, |o| o as u32);
            (info.input_min[k], info.input_max[k], info.input_hold[k]) = (i.min, i.max, i.hold);
        }
        Ok(info)
    }

    /// What the plant announced; the error names what breaks the rules ([`PlantSignals::check`]).
    pub fn signals(&self) -> Result<PlantSignals, String> {
        let t = Self::TYPE_NAME;
        let n_out = check_count(t, "outputs_len", self.outputs_len, MAX_OUTPUTS).map_err(|e| e.to_string())?;
        let n_in = check_count(t, "inputs_len", self.inputs_len, MAX_INPUTS).map_err(|e| e.to_string())?;
        let text = |field: &str, k: usize, raw: &[u8]| {
            unpadded(raw).ok_or_else(|| format!("{t}: field `{field}[{k}]` is not NUL-terminated ASCII"))
        };
        let plant = text("plant_name", 0, &self.plant_name)?;
        let mut outputs = Vec::with_capacity(n_out);
        for k in 0..n_out {
            outputs.push(OutputSignal {
                name: text("output_names", k, &self.output_names[k])?,
                unit: text("output_units", k, &self.output_units[k])?,
                in_trace: self.output_flags[k] & OUTPUT_IN_TRACE != 0,
            });
        }
        let mut inputs = Vec::with_capacity(n_in);
        for k in 0..n_in {
            inputs.push(InputSignal {
                name: text("input_names", k, &self.input_names[k])?,
                unit: text("input_units", k, &self.input_units[k])?,
                min: self.input_min[k],
                max: self.input_max[k],
                hold: self.input_hold[k],
                held_output: (self.input_held_output[k] != NO_OUTPUT).then_some(self.input_held_output[k] as usize),
                command_in_trace: self.input_flags[k] & INPUT_COMMAND_IN_TRACE != 0,
            });
        }
        let signals = PlantSignals { plant, outputs, inputs };
        signals.check(MAX_OUTPUTS, MAX_INPUTS)?;
        Ok(signals)
    }

    /// Rejects an announcement that breaks the rules; [`Self::signals`] says which rule.
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        check_count(t, "outputs_len", self.outputs_len, MAX_OUTPUTS)?;
        check_count(t, "inputs_len", self.inputs_len, MAX_INPUTS)?;
        match self.signals() {
            Ok(_) => Ok(()),
            Err(_) => Err(WireError::OutOfRange { type_name: t, field: "signals", index: None, value: 0.0 }),
        }
    }
}

impl ControllerInfo {
    /// The announcement of `names`; an error names the first name that does not fit the layout.
    pub fn new(names: &[String]) -> Result<Self, String> {
        if names.len() > MAX_DIAGNOSTICS {
            return Err(format!(
                "a command carries at most {MAX_DIAGNOSTICS} diagnostics; the controller reports {}",
                names.len()
            ));
        }
        let mut info = Self {
            header: header(),
            diagnostics_len: names.len() as u32,
            _pad: 0,
            diagnostic_names: [[0; NAME_BYTES]; MAX_DIAGNOSTICS],
        };
        for (slot, name) in info.diagnostic_names.iter_mut().zip(names) {
            if !signals::valid_name(name) {
                return Err(format!(
                    "diagnostic name {name:?}: use 1..={} of ASCII letters, digits and '_'",
                    signals::MAX_NAME_LEN
                ));
            }
            *slot = padded(name);
        }
        Ok(info)
    }

    /// The names in use.
    pub fn names(&self) -> Vec<String> {
        let n = (self.diagnostics_len as usize).min(MAX_DIAGNOSTICS);
        self.diagnostic_names[..n]
            .iter()
            .map(|raw| String::from_utf8_lossy(&raw[..raw.iter().position(|b| *b == 0).unwrap_or(raw.len())]).into())
            .collect()
    }

    /// Rejects a count beyond the layout and a name that is empty, unterminated or not ASCII letters, digits and
    /// '_'.
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        let n = check_count(t, "diagnostics_len", self.diagnostics_len, MAX_DIAGNOSTICS)?;
        for (k, raw) in self.diagnostic_names[..n].iter().enumerate() {
            if !unpadded(raw).is_some_and(|name| signals::valid_name(&name)) {
                return Err(WireError::OutOfRange {
                    type_name: t,
                    field: "diagnostic_names",
                    index: Some(k),
                    value: k as f64,
                });
            }
        }
        Ok(())
    }
}

impl LogAckSample {
    /// An acknowledgement of `rows_written` rows.
    pub fn new(rows_written: u64) -> Self {
        Self { header: header(), rows_written }
    }
}

impl LogAckSample {
    /// Nothing beyond the header to check.
    fn check(&self) -> Result<(), WireError> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::f16_signals::f16_signals;

    #[test]
    fn sizes_alignment_and_type_names_are_the_contract() {
        assert_eq!(core::mem::size_of::<SampleHeader>(), 40);
        assert_eq!(core::mem::size_of::<PlantSample>(), 328);
        assert_eq!(core::mem::size_of::<CommandSample>(), 712);
        assert_eq!(core::mem::size_of::<PlantInfo>(), 3024);
        assert_eq!(core::mem::align_of::<PlantSample>(), 8);
        assert_eq!(core::mem::align_of::<CommandSample>(), 8);
        // Safety of `type_name`: only reads the string the derive generated.
        unsafe {
            assert_eq!(<PlantSample as ZeroCopySend>::type_name(), "silrig::PlantSample::v5");
            assert_eq!(<CommandSample as ZeroCopySend>::type_name(), "silrig::CommandSample::v5");
            assert_eq!(<PlantInfo as ZeroCopySend>::type_name(), "silrig::PlantInfo::v5");
            assert_eq!(<SampleHeader as ZeroCopySend>::type_name(), "silrig::SampleHeader::v5");
            assert_eq!(<LogAckSample as ZeroCopySend>::type_name(), "silrig::LogAckSample::v5");
        }
        for name in [PlantSample::TYPE_NAME, CommandSample::TYPE_NAME, SampleHeader::TYPE_NAME, LogAckSample::TYPE_NAME]
        {
            assert!(name.ends_with(&format!("::v{WIRE_LAYOUT_VERSION}")), "{name}");
        }
    }

    #[test]
    fn diagnostic_names_round_trip_and_bad_ones_are_refused() {
        let names: Vec<String> = silrig_flight::trace::attitude_diagnostic_names(5);
        let info = ControllerInfo::new(&names).unwrap();
        assert_eq!(info.names(), names);
        assert_eq!(info.validate(), Ok(()));
        assert!(ControllerInfo::new(&["bad name".to_string()]).unwrap_err().contains("\"bad name\""));
        assert!(ControllerInfo::new(&["x".repeat(32)]).is_err());
        assert!(ControllerInfo::new(&vec!["x".to_string(); MAX_DIAGNOSTICS + 1]).unwrap_err().contains("at most"));
        let mut bad = info;
        bad.diagnostic_names[3][0] = b'-';
        assert!(matches!(bad.validate(), Err(WireError::OutOfRange { field: "diagnostic_names", index: Some(3), .. })));
    }

    #[test]
    fn a_plant_announcement_round_trips_and_a_broken_one_is_named() {
        let f16 = f16_signals([0.0, -1.9, 0.0, 0.2]);
        let info = PlantInfo::new(&f16).unwrap();
        assert_eq!(info.validate(), Ok(()));
        assert_eq!(info.signals().unwrap(), f16);

        let mut twice = info;
        twice.output_names[1] = twice.output_names[0];
        assert_eq!(twice.signals().unwrap_err(), "plant f16: output `phi_deg` named twice");
        assert!(twice.validate().is_err());
        let mut none = info;
        none.outputs_len = 0;
        assert!(none.signals().unwrap_err().contains("announces no outputs"));
        let mut unterminated = info;
        unterminated.input_units[2] = [b'x'; UNIT_BYTES];
        assert!(unterminated.signals().unwrap_err().contains("`input_units[2]` is not NUL-terminated"));
        let mut many = info;
        many.outputs_len = MAX_OUTPUTS as u32 + 1;
        assert!(many.signals().unwrap_err().contains("`outputs_len` is out of range (33)"));
    }

    #[test]
    fn a_command_is_checked_against_the_plants_inputs() {
        let f16 = f16_signals([0.0, -1.9, 0.0, 0.2]);
        let mut c = CommandSample::zeroed();
        c.inputs_len = 4;
        c.inputs[..4].copy_from_slice(&[1.0, -2.0, 0.5, 0.3]);
        assert_eq!(check_command(&f16, &c), Ok(()));
        c.inputs[3] = 1.5;
        let e = check_command(&f16, &c).unwrap_err();
        assert!(e.contains("`inputs[3]` (throttle 1) is out of range (1.5): plant f16 takes 0..1"), "{e}");
        c.inputs[3] = 0.3;
        c.inputs[0] = -91.0;
        assert!(check_command(&f16, &c).unwrap_err().contains("(aileron deg) is out of range (-91)"));
        c.inputs_len = 3;
        let e = check_command(&f16, &c).unwrap_err();
        assert!(e.contains("3 inputs; plant f16 takes 4 (aileron, elevator, rudder, throttle)"), "{e}");
    }

    #[test]
    fn validate_names_the_non_finite_field() {
        assert_eq!(PlantSample::zeroed().validate(), Ok(()));
        assert_eq!(CommandSample::zeroed().validate(), Ok(()));

        let mut p = PlantSample::with_outputs(&[0.0; 5]);
        p.outputs[3] = f64::NAN;
        let msg = p.validate().unwrap_err().to_string();
        assert!(msg.contains("silrig::PlantSample::v5") && msg.contains("`outputs[3]`"), "{msg}");
        assert!(msg.contains("NaN"), "{msg}");
        // Only the outputs in use count.
        p.outputs_len = 3;
        assert_eq!(p.validate(), Ok(()));

        let mut p = PlantSample::zeroed();
        p.t_sim_s = f64::INFINITY;
        assert!(p.validate().unwrap_err().to_string().contains("`t_sim_s`"));

        let mut c = CommandSample::zeroed();
        c.diagnostics_len = 3;
        c.diagnostics[2] = f64::NEG_INFINITY;
        let msg = c.validate().unwrap_err().to_string();
        assert!(msg.contains("`diagnostics[2]`") && msg.contains("-inf"), "{msg}");
        c.diagnostics_len = 2;
        assert_eq!(c.validate(), Ok(()));
        c.diagnostics_len = MAX_DIAGNOSTICS as u32 + 1;
        assert!(matches!(c.validate(), Err(WireError::OutOfRange { field: "diagnostics_len", .. })));

        let mut c = CommandSample::zeroed();
        c.inputs_len = 2;
        c.inputs[1] = f64::NAN;
        assert!(c.validate().unwrap_err().to_string().contains("`inputs[1]`"));

        let mut c = CommandSample::zeroed();
        c.header.layout_version = 0;
        assert!(matches!(c.validate(), Err(WireError::LayoutVersion { got: 0, .. })));
    }
}
