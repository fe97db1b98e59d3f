//! What crosses the network between the two bridges: each sample as the contract's bytes, header included
//! ([`to_bytes`]), checked on arrival for the layout version, the size and the contract's rules ([`from_bytes`]);
//! and the bridges' own messages ([`Hello`], [`RunInfo`], [`CommandTrailer`]). Pure, so the checks are
//! unit-tested without a network.

use serde::{Deserialize, Serialize};
use silrig_wire::wire::{SampleHeader, WIRE_LAYOUT_VERSION, WireError, WireSample};

/// Why bytes from the network are not a sample this build can use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// Fewer bytes than a header.
    #[error("{type_name}: {len} B is not a sample (a header alone is {header} B)")]
    TooShort {
        /// The type expected.
        type_name: &'static str,
        /// Bytes received.
        len: usize,
        /// Bytes of a header.
        header: usize,
    },
    /// The sender speaks another layout version.
    #[error(
        "{type_name}: the peer sends layout version {got}, this build speaks {expected}; rebuild silrig on both \
         hosts from the same commit"
    )]
    LayoutVersion {
        /// The type expected.
        type_name: &'static str,
        /// Version in the sample.
        got: u32,
        /// [`WIRE_LAYOUT_VERSION`].
        expected: u32,
    },
    /// Right version, wrong size (a corrupted or foreign message).
    #[error("{type_name}: {got} B received, the layout is {expected} B")]
    Size {
        /// The type expected.
        type_name: &'static str,
        /// Bytes received.
        got: usize,
        /// Size of the type.
        expected: usize,
    },
    /// The sample breaks the contract (NaN, out of range).
    #[error(transparent)]
    Invalid(#[from] WireError),
}

/// The sample's bytes as the contract lays them out (native byte order, as on the rig's own host).
pub fn to_bytes<T: WireSample>(sample: &T) -> Vec<u8> {
    // SAFETY: wire types are `#[repr(C)]` plain data whose fields leave no implicit padding (their sizes are
    // asserted in `wire`, and every gap is an explicit `_pad` field), so all `size_of::<T>()` bytes are initialised.
    unsafe { std::slice::from_raw_parts((sample as *const T).cast::<u8>(), size_of::<T>()) }.to_vec()
}

/// A sample from bytes of the network: the layout version first (a peer of another version gets a message naming
/// both versions, whatever the size its layout has), then the size, then the contract's rules.
pub fn from_bytes<T: WireSample>(bytes: &[u8]) -> Result<T, FrameError> {
    let type_name = T::TYPE_NAME;
    let header = size_of::<SampleHeader>();
    if bytes.len() < header {
        return Err(FrameError::TooShort { type_name, len: bytes.len(), header });
    }
    let at = core::mem::offset_of!(SampleHeader, layout_version);
    let got = u32::from_ne_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    if got != WIRE_LAYOUT_VERSION {
        return Err(FrameError::LayoutVersion { type_name, got, expected: WIRE_LAYOUT_VERSION });
    }
    if bytes.len() != size_of::<T>() {
        return Err(FrameError::Size { type_name, got: bytes.len(), expected: size_of::<T>() });
    }
    // SAFETY: exactly size_of::<T>() bytes, read unaligned; every field of a wire type is an integer, a float or an
    // array of them, for which any bit pattern is a value.
    let sample = unsafe { std::ptr::read_unaligned(bytes.as_ptr().cast::<T>()) };
    sample.validate()?;
    Ok(sample)
}

/// Which end of the link a bridge is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// On the plant's host: listens, forwards plant samples out and commands in.
    Plant,
    /// On the controller's host: connects, forwards plant samples in and commands out.
    Controller,
}

impl Side {
    /// Name in keys and messages.
    pub fn label(self) -> &'static str {
        match self {
            Side::Plant => "plant",
            Side::Controller => "controller",
        }
    }
}

/// What each bridge says every heartbeat period: who it is, and what it serves. A bridge that stops hearing it
/// has lost its peer.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Hello {
    /// Which end.
    pub side: Side,
    /// The run it serves.
    pub run_id: String,
    /// [`WIRE_LAYOUT_VERSION`] of its build.
    pub layout_version: u32,
    /// This bridge's life: a new value when it (re)starts.
    pub epoch: u64,
    /// Plant side: the epoch of the controller-side bridge whose commands it passes to the plant.
    pub serving: Option<u64>,
    /// Controller side: a controller is connected to the run on its host.
    pub controller_connected: bool,
}

impl Hello {
    /// The hello as it goes out.
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("a hello serialises")
    }

    /// A hello from the network.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        serde_json::from_slice(bytes).map_err(|e| format!("not a silrig bridge hello: {e}"))
    }
}

/// What the plant side tells a controller side on request: the scenario the run flies and the run's process
/// arguments as `SILRIG_*` variables, so a controller on the other host runs with the same ones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// The scenario file's text.
    pub scenario_toml: String,
    /// The run's arguments as environment variables ([`silrig_rig::ProcessArgs::to_env`]).
    pub env: Vec<(String, String)>,
}

/// The controller side's bookkeeping sent beside each command (as a Zenoh attachment, so the command itself stays
/// the contract's bytes): which bridge sent it, and how long the command's tick spent on the controller's host.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommandTrailer {
    /// Epoch of the controller-side bridge.
    pub bridge_epoch: u64,
    /// From that bridge publishing the plant sample the command answers to receiving the command, ns (0: not
    /// known, e.g. the sample came before a restart of the bridge).
    pub residence_ns: u64,
}

impl CommandTrailer {
    /// 16 bytes, little-endian.
    pub fn to_bytes(self) -> [u8; 16] {
        let mut out = [0; 16];
        out[..8].copy_from_slice(&self.bridge_epoch.to_le_bytes());
        out[8..].copy_from_slice(&self.residence_ns.to_le_bytes());
        out
    }

    /// The trailer, if the bytes are one.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let bytes: &[u8; 16] = bytes.try_into().ok()?;
        Some(Self {
            bridge_epoch: u64::from_le_bytes(bytes[..8].try_into().ok()?),
            residence_ns: u64::from_le_bytes(bytes[8..].try_into().ok()?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_wire::wire::{CommandSample, ControllerInfo, PlantSample};

    #[test]
    fn samples_cross_as_their_contract_bytes() {
        let mut p = PlantSample::zeroed();
        p.header.seq = 7;
        p.header.tick = 42;
        p.outputs[3] = 0.25;
        p.outputs_len = 4;
        let bytes = to_bytes(&p);
        assert_eq!(bytes.len(), size_of::<PlantSample>());
        assert_eq!(&bytes[8..16], &42u64.to_ne_bytes());
        assert_eq!(from_bytes::<PlantSample>(&bytes), Ok(p));
        let info = ControllerInfo::new(&["s_roll".to_string()]).unwrap();
        assert_eq!(from_bytes::<ControllerInfo>(&to_bytes(&info)), Ok(info));
    }

    #[test]
    fn another_version_a_wrong_size_and_a_broken_sample_are_refused_by_name() {
        let mut c = CommandSample::zeroed();
        c.header.layout_version = WIRE_LAYOUT_VERSION + 1;
        let mut bytes = to_bytes(&c);
        bytes.truncate(300);
        let e = from_bytes::<CommandSample>(&bytes).unwrap_err();
        let (got, expected) = (WIRE_LAYOUT_VERSION + 1, WIRE_LAYOUT_VERSION);
        assert_eq!(e, FrameError::LayoutVersion { type_name: CommandSample::TYPE_NAME, got, expected });
        assert!(e.to_string().contains(&format!("layout version {got}, this build speaks {expected}")), "{e}");
        let e = from_bytes::<CommandSample>(&to_bytes(&PlantSample::zeroed())).unwrap_err();
        let (plant, command) = (size_of::<PlantSample>(), size_of::<CommandSample>());
        assert!(matches!(e, FrameError::Size { got, expected, .. } if got == plant && expected == command), "{e}");
        assert!(matches!(from_bytes::<PlantSample>(&[0; 12]), Err(FrameError::TooShort { len: 12, .. })));
        let mut c = CommandSample::zeroed();
        c.inputs_len = 2;
        c.inputs[1] = f64::NAN;
        let e = from_bytes::<CommandSample>(&to_bytes(&c)).unwrap_err();
        assert!(e.to_string().contains("inputs[1]"), "{e}");
    }

    #[test]
    fn hellos_and_trailers_round_trip() {
        let h = Hello {
            side: Side::Plant,
            run_id: "r1".into(),
            layout_version: WIRE_LAYOUT_VERSION,
            epoch: 9,
            serving: Some(4),
            controller_connected: false,
        };
        assert_eq!(Hello::from_bytes(&h.to_bytes()), Ok(h));
        assert!(Hello::from_bytes(b"{}").unwrap_err().contains("not a silrig bridge hello"));
        let t = CommandTrailer { bridge_epoch: u64::MAX - 3, residence_ns: 1_234_567 };
        assert_eq!(CommandTrailer::from_bytes(&t.to_bytes()), Some(t));
        assert_eq!(CommandTrailer::from_bytes(&[1, 2, 3]), None);
    }
}
