//! How a bridge fails: [`BridgeError`], each variant phrased for the person running it, and the one way a Zenoh
//! error becomes one. A file of its own that imports nothing of the folder: `net.rs` returns it and `options.rs`
//! checks endpoints with `net.rs`, so next to the options it would close a circle.

use silrig_wire::ipc::IpcError;

/// Failures of a bridge, each phrased for the person running it.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// A flag out of range or malformed.
    #[error("{0}")]
    Usage(String),
    /// Zenoh refused to start or to declare something.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The iceoryx2 side.
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// Nobody answered at the endpoint.
    #[error(
        "no plant-side bridge answered at {endpoint} within {waited_s} s: is `silrig run --bridge-listen` running \
         on that host, is the address right, is the port open in its firewall, and do both bridges give the same \
         bridge key (or neither)?"
    )]
    Unreachable {
        /// Where we connected.
        endpoint: String,
        /// How long we waited.
        waited_s: f64,
    },
    /// The bridge at the endpoint serves another run.
    #[error("the plant-side bridge at {endpoint} serves run `{theirs}`, not `{ours}`: use --run-id {theirs}")]
    OtherRun {
        /// Where we connected.
        endpoint: String,
        /// Its run.
        theirs: String,
        /// Ours.
        ours: String,
    },
    /// The other bridge speaks another layout version.
    #[error(
        "the plant-side bridge at {endpoint} speaks wire layout version {theirs}, this build speaks {ours}: build \
         silrig on both hosts from the same commit"
    )]
    OtherLayout {
        /// Where we connected.
        endpoint: String,
        /// Its version.
        theirs: u32,
        /// Ours.
        ours: u32,
    },
    /// The plant side serves another controller-side bridge of this run.
    #[error(
        "run `{run}` already has a controller-side bridge (epoch {serving:x}) that the plant side serves; stop it \
         first: one controller per run"
    )]
    Refused {
        /// The run.
        run: String,
        /// The epoch of the one served.
        serving: u64,
    },
    /// A file could not be written or read.
    #[error("{0}")]
    Io(String),
    /// The bridge key: missing, unreadable, readable by others, not a key, or its absence where one is needed.
    #[error("{0}")]
    Key(String),
    /// The TLS handshake with the plant-side bridge failed over a certificate: the hosts hold different keys.
    #[error(
        "the plant-side bridge at {endpoint} holds another bridge key, or refused this one (TLS: {detail}): give \
         both hosts the same key file; this one's fingerprint is {fingerprint}, and each bridge prints its own when \
         it starts"
    )]
    WrongKey {
        /// Where we connected.
        endpoint: String,
        /// What TLS said.
        detail: String,
        /// This side's key.
        fingerprint: String,
    },
}

/// Zenoh's errors do not say which of our declarations failed: `what` names it.
pub(super) fn zenoh_err(what: &str) -> impl Fn(zenoh::Error) -> BridgeError + '_ {
    move |e| BridgeError::Zenoh(format!("{what}: {e}"))
}
