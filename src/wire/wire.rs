//! The wire format: the one definition of every sample type that crosses a process boundary over iceoryx2, with
//! its layout version and its validity check.
//!
//! iceoryx2 matches a service's payload by type *name*, size and alignment only; field order and meaning are not
//! checked. The type names therefore carry [`WIRE_LAYOUT_VERSION`] (each is built from it by the `wire_type!` macro):
//! whenever a field is added, removed, reordered or changes meaning, bump the version, so that a peer built from the
//! old layout gets `IncompatibleTypes` on open (turned into [`crate::ipc::IpcError::OtherWireLayout`]) instead of
//! misreading bytes.

use iceoryx2::prelude::ZeroCopySend;

/// The layout version as a literal, so that the type names can be built from it with `concat!`.
macro_rules! layout_version {
    () => {
        4
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

/// `PlantSample::flags`/`CommandSample::flags`: the command the plant applied is older than the staleness limit.
pub const FLAG_COMMAND_STALE: u32 = 1 << 0;
/// At least one surface or the throttle sits on its position limit.
pub const FLAG_SATURATED: u32 = 1 << 1;
/// The failsafe output is active (the producer of the input is gone or stale for too long).
pub const FLAG_FAILSAFE: u32 = 1 << 2;
/// At least one surface moved at its rate limit during this tick.
pub const FLAG_RATE_LIMITED: u32 = 1 << 3;
/// `PlantSample::flags`: the plant's last sample of the run, after its last tick (the end of the scenario, or a
/// state that left the model's envelope). It repeats that tick's state with the surfaces the actuators took under
/// that tick's command, which no later sample would carry; a controller does not answer it.
pub const FLAG_END_OF_RUN: u32 = 1 << 5;

/// `CommandSample::flags`: the controller's command for this tick was refused (NaN, infinity or out of range) and
/// not sent; the plant holds its last valid command, as for a missing one.
pub const FLAG_COMMAND_REFUSED: u32 = 1 << 4;

pub use silrig_model::actuator::SURFACE_CMD_LIMIT_DEG;

/// Names of the three surfaces, in the order of every `[f64; 3]` surface array on the wire.
pub const SURFACE_NAMES: [&str; 3] = ["aileron", "elevator", "rudder"];

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
/// What the plant publishes every tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantSample with header {
    /// Bookkeeping.
    pub header: SampleHeader,
    /// The 13 states in `F16State` order and book units: vt_fps, alpha_rad, beta_rad, phi_rad, theta_rad, psi_rad,
    /// p_radps, q_radps, r_radps, north_ft, east_ft, alt_ft, power_pct.
    pub state: [f64; 13],
    /// Surface positions the actuators hold now, deg: aileron, elevator, rudder. Sampled when the tick begins,
    /// before this tick's command acts: the deflections held over the step from the previous tick to this one
    /// (the trace's row of the previous tick shows them). In the end-of-run sample: those the last tick's command
    /// set.
    pub surfaces_deg: [f64; 3],
    /// Throttle after its limits, 0..1 (sampled as the surfaces).
    pub throttle: f64,
    /// Normal load factor, g: the accelerometer 15 ft ahead of the CG along body -z (specific force: 1 g in level
    /// flight, cos(theta) when trimmed).
    pub nz_g: f64,
    /// Lateral load factor, g: the same accelerometer along body +y (out the right wing).
    pub ny_g: f64,
    /// Simulated time of this state, s.
    pub t_sim_s: f64,
    /// How late the plant woke for this tick (actual minus ideal start, the cyclictest figure), ns; 0 in lockstep
    /// (no sleeping) and in the end-of-run sample.
    pub wake_lateness_ns: i64,
    /// Execution time of the previous tick's step (actuators and RK4), ns: a tick's step runs after its sample is
    /// published, so the next sample carries it (the end-of-run sample carries the last tick's); 0 in the first
    /// sample of a plant life.
    pub previous_step_exec_ns: u64,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
}
}

wire_type! {
/// What a controller publishes in answer to a plant sample: what every controller has (the tick it answers, its
/// commands, its compute time, flags), then its own diagnostics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandSample with header {
    /// Bookkeeping; `tick` is the tick this command answers.
    pub header: SampleHeader,
    /// Tick of the plant sample this command was computed from.
    pub answers_tick: u64,
    /// Commanded surfaces, deg: aileron, elevator, rudder.
    pub surface_cmd_deg: [f64; 3],
    /// Commanded throttle, 0..1.
    pub throttle_cmd: f64,
    /// Time the controller spent computing this command, ns.
    pub compute_ns: u64,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Entries of `diagnostics` in use, at most MAX_DIAGNOSTICS.
    pub diagnostics_len: u32,
    /// The controller's own values for this tick, whatever it wants logged and plotted (the paper's controller:
    /// S and f_hat per channel, then its RBF weights, channel by channel); entries past `diagnostics_len` are 0.
    pub diagnostics: [f64; MAX_DIAGNOSTICS],
}
}

/// Bytes of one diagnostic name in [`ControllerInfo`], NUL-padded (so at most 31 characters).
pub const DIAGNOSTIC_NAME_BYTES: usize = 32;

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
    pub diagnostic_names: [[u8; DIAGNOSTIC_NAME_BYTES]; MAX_DIAGNOSTICS],
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
const _: () = assert!(core::mem::size_of::<PlantSample>() == 224);
const _: () = assert!(core::mem::align_of::<PlantSample>() == 8);
const _: () = assert!(core::mem::size_of::<CommandSample>() == 608);
const _: () = assert!(core::mem::size_of::<LogAckSample>() == 48);
const _: () = assert!(core::mem::align_of::<CommandSample>() == 8);

/// A sample that must not be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum WireError {
    /// A float field is NaN or infinite.
    #[error("{type_name}: field `{field}` is not finite ({value})")]
    NotFinite {
        /// Type name of the sample.
        type_name: &'static str,
        /// Field (with its element name, e.g. `state[3] phi_rad`).
        field: &'static str,
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
    /// A count beyond what the layout holds, or a command no actuator could mean.
    #[error("{type_name}: field `{field}` is out of range ({value})")]
    OutOfRange {
        /// Type name of the sample.
        type_name: &'static str,
        /// Field.
        field: &'static str,
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

const STATE_FIELDS: [&str; 13] = [
    "state[0] vt_fps",
    "state[1] alpha_rad",
    "state[2] beta_rad",
    "state[3] phi_rad",
    "state[4] theta_rad",
    "state[5] psi_rad",
    "state[6] p_radps",
    "state[7] q_radps",
    "state[8] r_radps",
    "state[9] north_ft",
    "state[10] east_ft",
    "state[11] alt_ft",
    "state[12] power_pct",
];

fn check_layout(type_name: &'static str, header: &SampleHeader) -> Result<(), WireError> {
    if header.layout_version != WIRE_LAYOUT_VERSION {
        return Err(WireError::LayoutVersion { type_name, got: header.layout_version, expected: WIRE_LAYOUT_VERSION });
    }
    Ok(())
}

fn check_finite(type_name: &'static str, fields: &[&'static str], values: &[f64]) -> Result<(), WireError> {
    for (field, value) in fields.iter().zip(values) {
        if !value.is_finite() {
            return Err(WireError::NotFinite { type_name, field, value: *value });
        }
    }
    Ok(())
}

impl PlantSample {
    /// A sample with everything zero and the current layout version.
    pub fn zeroed() -> Self {
        Self {
            header: SampleHeader { layout_version: WIRE_LAYOUT_VERSION, ..SampleHeader::default() },
            state: [0.0; 13],
            surfaces_deg: [0.0; 3],
            throttle: 0.0,
            nz_g: 0.0,
            ny_g: 0.0,
            t_sim_s: 0.0,
            wake_lateness_ns: 0,
            previous_step_exec_ns: 0,
            flags: 0,
            _pad: 0,
        }
    }
}

impl PlantSample {
    /// Rejects NaN/inf in any float field, naming it.
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        check_finite(t, &STATE_FIELDS, &self.state)?;
        check_finite(
            t,
            &["surfaces_deg[0] aileron", "surfaces_deg[1] elevator", "surfaces_deg[2] rudder"],
            &self.surfaces_deg,
        )?;
        check_finite(t, &["throttle", "nz_g", "ny_g", "t_sim_s"], &[self.throttle, self.nz_g, self.ny_g, self.t_sim_s])
    }
}

impl CommandSample {
    /// A sample with everything zero and the current layout version.
    pub fn zeroed() -> Self {
        Self {
            header: SampleHeader { layout_version: WIRE_LAYOUT_VERSION, ..SampleHeader::default() },
            answers_tick: 0,
            surface_cmd_deg: [0.0; 3],
            throttle_cmd: 0.0,
            compute_ns: 0,
            flags: 0,
            diagnostics_len: 0,
            diagnostics: [0.0; MAX_DIAGNOSTICS],
        }
    }

    /// The diagnostics in use.
    pub fn diagnostics(&self) -> &[f64] {
        &self.diagnostics[..(self.diagnostics_len as usize).min(MAX_DIAGNOSTICS)]
    }

    /// Rejects NaN/inf in a command or a diagnostic in use, a surface beyond [`SURFACE_CMD_LIMIT_DEG`], a throttle
    /// outside 0..1 and a diagnostics count beyond the layout, naming the field.
    fn check(&self) -> Result<(), WireError> {
        let t = Self::TYPE_NAME;
        let surfaces = ["surface_cmd_deg[0] aileron", "surface_cmd_deg[1] elevator", "surface_cmd_deg[2] rudder"];
        check_finite(t, &surfaces, &self.surface_cmd_deg)?;
        check_finite(t, &["throttle_cmd"], &[self.throttle_cmd])?;
        for (value, field) in self.surface_cmd_deg.iter().zip(surfaces) {
            if value.abs() > SURFACE_CMD_LIMIT_DEG {
                return Err(WireError::OutOfRange { type_name: t, field, value: *value });
            }
        }
        if !(0.0..=1.0).contains(&self.throttle_cmd) {
            return Err(WireError::OutOfRange { type_name: t, field: "throttle_cmd", value: self.throttle_cmd });
        }
        if self.diagnostics_len as usize > MAX_DIAGNOSTICS {
            let value = f64::from(self.diagnostics_len);
            return Err(WireError::OutOfRange { type_name: t, field: "diagnostics_len", value });
        }
        if let Some(value) = self.diagnostics().iter().find(|w| !w.is_finite()) {
            return Err(WireError::NotFinite { type_name: t, field: "diagnostics", value: *value });
        }
        Ok(())
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
            header: SampleHeader { layout_version: WIRE_LAYOUT_VERSION, ..SampleHeader::default() },
            diagnostics_len: names.len() as u32,
            _pad: 0,
            diagnostic_names: [[0; DIAGNOSTIC_NAME_BYTES]; MAX_DIAGNOSTICS],
        };
        for (slot, name) in info.diagnostic_names.iter_mut().zip(names) {
            if !valid_diagnostic_name(name.as_bytes()) {
                return Err(format!(
                    "diagnostic name {name:?}: use 1..={} of ASCII letters, digits and '_'",
                    DIAGNOSTIC_NAME_BYTES - 1
                ));
            }
            slot[..name.len()].copy_from_slice(name.as_bytes());
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
        if self.diagnostics_len as usize > MAX_DIAGNOSTICS {
            let value = f64::from(self.diagnostics_len);
            return Err(WireError::OutOfRange { type_name: t, field: "diagnostics_len", value });
        }
        for (k, raw) in self.diagnostic_names[..self.diagnostics_len as usize].iter().enumerate() {
            let len = raw.iter().position(|b| *b == 0).unwrap_or(raw.len());
            if len == raw.len() || !valid_diagnostic_name(&raw[..len]) {
                return Err(WireError::OutOfRange { type_name: t, field: "diagnostic_names", value: k as f64 });
            }
        }
        Ok(())
    }
}

fn valid_diagnostic_name(name: &[u8]) -> bool {
    (1..DIAGNOSTIC_NAME_BYTES).contains(&name.len()) && name.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_')
}

impl LogAckSample {
    /// An acknowledgement of `rows_written` rows.
    pub fn new(rows_written: u64) -> Self {
        Self { header: SampleHeader { layout_version: WIRE_LAYOUT_VERSION, ..SampleHeader::default() }, rows_written }
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
    use silrig_model::plant::STATE_NAMES;

    #[test]
    fn sizes_alignment_and_type_names_are_the_contract() {
        assert_eq!(core::mem::size_of::<SampleHeader>(), 40);
        assert_eq!(core::mem::size_of::<PlantSample>(), 224);
        assert_eq!(core::mem::size_of::<CommandSample>(), 608);
        assert_eq!(core::mem::align_of::<PlantSample>(), 8);
        assert_eq!(core::mem::align_of::<CommandSample>(), 8);
        // Safety of `type_name`: only reads the string the derive generated.
        unsafe {
            assert_eq!(<PlantSample as ZeroCopySend>::type_name(), "silrig::PlantSample::v4");
            assert_eq!(<CommandSample as ZeroCopySend>::type_name(), "silrig::CommandSample::v4");
            assert_eq!(<SampleHeader as ZeroCopySend>::type_name(), "silrig::SampleHeader::v4");
            assert_eq!(<LogAckSample as ZeroCopySend>::type_name(), "silrig::LogAckSample::v4");
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
        assert!(
            matches!(bad.validate(), Err(WireError::OutOfRange { field: "diagnostic_names", value, .. }) if value == 3.0)
        );
    }

    #[test]
    fn state_field_names_follow_the_f16_state_order() {
        for (k, (field, state)) in STATE_FIELDS.iter().zip(STATE_NAMES).enumerate() {
            assert_eq!(*field, format!("state[{k}] {state}"));
        }
    }

    #[test]
    fn validate_names_the_non_finite_field() {
        assert_eq!(PlantSample::zeroed().validate(), Ok(()));
        assert_eq!(CommandSample::zeroed().validate(), Ok(()));

        let mut p = PlantSample::zeroed();
        p.state[3] = f64::NAN;
        let msg = p.validate().unwrap_err().to_string();
        assert!(msg.contains("silrig::PlantSample::v4") && msg.contains("state[3] phi_rad"), "{msg}");
        assert!(msg.contains("NaN"), "{msg}");

        let mut p = PlantSample::zeroed();
        p.t_sim_s = f64::INFINITY;
        assert!(p.validate().unwrap_err().to_string().contains("`t_sim_s`"));

        let mut c = CommandSample::zeroed();
        c.diagnostics_len = 3;
        c.diagnostics[2] = f64::NEG_INFINITY;
        let msg = c.validate().unwrap_err().to_string();
        assert!(msg.contains("`diagnostics`") && msg.contains("-inf"), "{msg}");
        // Only the diagnostics in use count; too many is out of range.
        c.diagnostics_len = 2;
        assert_eq!(c.validate(), Ok(()));
        c.diagnostics_len = MAX_DIAGNOSTICS as u32 + 1;
        assert!(matches!(c.validate(), Err(WireError::OutOfRange { field: "diagnostics_len", .. })));

        let mut c = CommandSample::zeroed();
        c.surface_cmd_deg[1] = f64::NAN;
        assert!(c.validate().unwrap_err().to_string().contains("surface_cmd_deg[1] elevator"));

        let mut c = CommandSample::zeroed();
        c.header.layout_version = 0;
        assert!(matches!(c.validate(), Err(WireError::LayoutVersion { got: 0, .. })));
    }
}
