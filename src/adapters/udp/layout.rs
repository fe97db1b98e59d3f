//! A device's packet layouts as a layout file declares them, and their binding to one plant's signals: what each
//! field of each packet carries (a plant output, a set point, the simulated time, a constant; or, coming back, a
//! plant input), its type, byte order, scale, offset and frame. Binding checks every name and number before
//! anything flies and turns the file into [`BoundLayout`], which the codec ([`super::codec`]) runs each tick.
//!
//! Sending, a field's value is `(frame applied to its sources) * scale + offset`, cast to its type (integers
//! rounded to nearest and held to the type's range). Receiving, the inverse: `raw * scale + offset`, then the
//! frame's inverse, into the named inputs.

use super::frames::Frame;
use serde::Deserialize;
use std::path::Path;

/// A layout file: the device's name, its byte order and its packets each way.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceLayout {
    /// The device's name, for messages and reports.
    pub name: String,
    /// What it is, with where its layouts come from.
    #[serde(default)]
    pub description: String,
    /// Byte order of every multi-byte field.
    pub byte_order: ByteOrder,
    /// What the rig sends the device.
    #[serde(default)]
    pub to_device: Vec<PacketLayout>,
    /// What the device sends the rig.
    #[serde(default)]
    pub from_device: Vec<PacketLayout>,
    /// The device's IP address: where packets to it go (the rig listens on every address).
    #[serde(default = "loopback")]
    pub address: std::net::IpAddr,
    /// How long the device may send no valid packet (from the first packet sent to it, or from its last valid
    /// one) before the run fails naming it, s.
    #[serde(default = "silent_after_s")]
    pub silent_after_s: f64,
    /// The device's program, when the rig starts, watches and restarts it (a SITL).
    #[serde(default)]
    pub process: Option<super::supervise::DeviceProcess>,
    /// How the device is armed, when it must be (Betaflight's arm switch, its flags read over MSP).
    #[serde(default)]
    pub arming: Option<super::arming::ArmingOptions>,
}

fn loopback() -> std::net::IpAddr {
    std::net::Ipv4Addr::LOCALHOST.into()
}

fn silent_after_s() -> f64 {
    5.0
}

/// Byte order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ByteOrder {
    /// Least significant byte first (x86, ARM as usually run).
    Little,
    /// Most significant byte first (network order).
    Big,
}

/// One packet: its name, its port and its fields in order, with no padding between them.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PacketLayout {
    /// The packet's name, for messages and counters.
    pub name: String,
    /// To the device: the device's UDP port; from it: the port the rig listens on.
    pub port: u16,
    /// To the device: sent every this many plant ticks (1: every tick).
    #[serde(default = "every_tick")]
    pub every_ticks: u32,
    /// The fields, in the packet's order.
    pub fields: Vec<FieldLayout>,
}

fn every_tick() -> u32 {
    1
}

/// One field or a group of fields of the same type.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldLayout {
    /// `u8`, `i8`, `u16`, `i16`, `u32`, `i32`, `u64`, `i64`, `f32` or `f64`.
    #[serde(rename = "type")]
    pub ty: String,
    /// To the device: the plant outputs, `setpoint.<name>`s or `time_s` it carries, one per field.
    #[serde(default)]
    pub from: Option<OneOrMany<String>>,
    /// From the device: the plant inputs it carries, one per field.
    #[serde(default)]
    pub to: Option<OneOrMany<String>>,
    /// A constant sent in every field of the group.
    #[serde(default)]
    pub value: Option<f64>,
    /// How many fields of a constant or skipped group.
    #[serde(default)]
    pub count: Option<usize>,
    /// From the device: fields read and ignored.
    #[serde(default)]
    pub skip: bool,
    /// Multiplies each value (one for all, or one per field).
    #[serde(default)]
    pub scale: Option<OneOrMany<f64>>,
    /// Added to each value after the scale (one for all, or one per field).
    #[serde(default)]
    pub offset: Option<OneOrMany<f64>>,
    /// A frame conversion of the group (3 values for vectors, 4 for quaternions).
    #[serde(default)]
    pub frame: Option<Frame>,
}

/// One value, or a list.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum OneOrMany<T> {
    /// One.
    One(T),
    /// A list.
    Many(Vec<T>),
}

impl<T: Clone> OneOrMany<T> {
    /// The values, one or many, as a list.
    pub fn values(&self) -> Vec<T> {
        match self {
            OneOrMany::One(x) => vec![x.clone()],
            OneOrMany::Many(v) => v.clone(),
        }
    }
}

/// The type of one field on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarType {
    /// Unsigned 8 bits.
    U8,
    /// Signed 8 bits.
    I8,
    /// Unsigned 16 bits.
    U16,
    /// Signed 16 bits.
    I16,
    /// Unsigned 32 bits.
    U32,
    /// Signed 32 bits.
    I32,
    /// Unsigned 64 bits.
    U64,
    /// Signed 64 bits.
    I64,
    /// IEEE 754 single.
    F32,
    /// IEEE 754 double.
    F64,
}

/// The type names a layout file may use.
pub const TYPE_NAMES: &str = "u8, i8, u16, i16, u32, i32, u64, i64, f32, f64";

impl ScalarType {
    /// The type of a name in a layout file.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "u8" => Self::U8,
            "i8" => Self::I8,
            "u16" => Self::U16,
            "i16" => Self::I16,
            "u32" => Self::U32,
            "i32" => Self::I32,
            "u64" => Self::U64,
            "i64" => Self::I64,
            "f32" => Self::F32,
            "f64" => Self::F64,
            _ => return None,
        })
    }

    /// Bytes on the wire.
    pub fn size(self) -> usize {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::U64 | Self::I64 | Self::F64 => 8,
        }
    }
}

/// What a sent value is made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// The plant output at this index of its announcement.
    Output(usize),
    /// The scenario set point at this index of the set-point list bound against.
    Setpoint(usize),
    /// Simulated time, s.
    Time,
    /// A constant.
    Constant(f64),
}

/// One field sent: its type and `sum(coefficient * source) * scale + offset`.
#[derive(Debug, Clone, PartialEq)]
pub struct SendField {
    /// Its type.
    pub ty: ScalarType,
    /// The linear combination of sources (one term without a frame).
    pub terms: Vec<(Source, f64)>,
    /// Scale.
    pub scale: f64,
    /// Offset.
    pub offset: f64,
}

/// A group of fields received: each decoded as `raw * scale + offset`, then the frame's inverse, into inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct ReceiveGroup {
    /// Type, scale and offset of each field.
    pub fields: Vec<(ScalarType, f64, f64)>,
    /// The inverse frame map (row `i` gives target `i`), `None` for none.
    pub inverse_frame: Option<Vec<Vec<f64>>>,
    /// The plant input each value lands in (`None`: skipped).
    pub targets: Vec<Option<usize>>,
}

/// A packet to the device, bound.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundSend {
    /// Its name.
    pub name: String,
    /// The device's port.
    pub port: u16,
    /// Sent every this many ticks.
    pub every_ticks: u32,
    /// Its fields in order.
    pub fields: Vec<SendField>,
    /// Its size, bytes.
    pub size: usize,
}

/// A packet from the device, bound.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundReceive {
    /// Its name.
    pub name: String,
    /// The port the rig listens on.
    pub port: u16,
    /// Its field groups in order.
    pub groups: Vec<ReceiveGroup>,
    /// Its size, bytes.
    pub size: usize,
}

/// A layout bound to one plant's signals.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundLayout {
    /// The device's name.
    pub name: String,
    /// Byte order.
    pub byte_order: ByteOrder,
    /// Packets to the device.
    pub to_device: Vec<BoundSend>,
    /// Packets from the device.
    pub from_device: Vec<BoundReceive>,
}

/// The names a layout is bound against.
#[derive(Debug, Clone, Copy)]
pub struct SignalNames<'a> {
    /// The plant's outputs, in announced order.
    pub outputs: &'a [String],
    /// The plant's inputs, in announced order.
    pub inputs: &'a [String],
    /// The scenario's set points by name.
    pub setpoints: &'a [String],
}

/// A layout that cannot be flown, in words: the file, packet and field, the problem and the fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct LayoutError(pub String);

impl DeviceLayout {
    /// Reads a layout file.
    pub fn load(path: &Path) -> Result<Self, LayoutError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| LayoutError(format!("cannot read the device layout {}: {e}", path.display())))?;
        Self::parse(&text).map_err(|LayoutError(e)| LayoutError(format!("device layout {}: {e}", path.display())))
    }

    /// Parses a layout from TOML text.
    pub fn parse(text: &str) -> Result<Self, LayoutError> {
        toml::from_str(text).map_err(|e| LayoutError(e.to_string().trim().to_string()))
    }
}

#[cfg(test)]
#[path = "layout_tests.rs"]
mod tests;
