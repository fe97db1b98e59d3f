//! The iceoryx2 transport of the rig, a thin layer that knows nothing of which streams the rig has (that is
//! [`crate::topology`]): per-run namespaces and their cleanup ([`namespace`]), opening a stream's services with the
//! settings every peer must use ([`stream`]) and the mending of service files a dead creator left half-made
//! ([`half_made`]), typed ports that stamp and check sample headers ([`publisher`],
//! [`subscriber`]), and the WaitSet loop with the rig's signal rules and a timerfd tick source ([`waitset`]).
//!
//! Everything here uses `ipc::Service`, whose ports are `!Send`: create them on the thread that uses them.
//!
//! # Signals
//!
//! Nodes and WaitSets are built with iceoryx2's default `SignalHandlingMode::HandleTerminationRequests`: from the
//! first WaitSet wait on, iceoryx2 owns SIGINT, SIGTERM, SIGCONT and a dozen more. A SIGSTOP/SIGCONT pair (fault
//! injection) makes the blocked wait return `WaitSetRunResult::Interrupt`; that is *not* a request to stop, and
//! [`run_waitset`] loops over it. SIGTERM or SIGINT also interrupt the wait first; the *next* wait then reports
//! `TerminationRequest`, which ends [`run_waitset`] with [`LoopEnd::TerminationRequest`]. A process that never
//! waits on a WaitSet keeps the default SIGTERM action and leaves a dead node behind when killed.

pub mod half_made;
pub mod namespace;
pub mod publisher;
pub mod stream;
pub mod subscriber;
pub mod waitset;

pub use namespace::{
    CleanupReport, DEAD_RUN_GRACE, NodeOfRun, NodeSummary, RUN_ID_MAX_LEN, RunId, SHM_DIR, cleanup_dead_nodes,
    cleanup_dead_runs, cleanup_run, create_node, nodes_of_run, rig_config,
};
pub use publisher::{SendReceipt, StreamPublisher};
pub use stream::{StreamService, StreamSettings, StreamSpec, new_epoch, open_stream};
pub use subscriber::{Received, SeqObservation, SeqTracker, StreamSubscriber, SubscriberStats, WaitOutcome};
pub use waitset::{LoopEnd, LoopExit, TickTimer, rig_waitset, run_waitset};

use crate::wire::WireError;

/// An iceoryx2 error in words: its variant's name split into lower-case words, its type's name and any payload's
/// brackets left out (iceoryx2 prints its errors as `PublisherCreateError::ExceedsMaxSupportedPublishers`, Display
/// and Debug alike), so a message a person reads never holds an internal type name.
pub fn in_words(error: &impl std::fmt::Debug) -> String {
    let debug = format!("{error:?}");
    // `Outer(Inner::Variant)` says most in its innermost name; `Type::Variant` in its variant.
    let name = debug.rsplit("::").next().unwrap_or(&debug);
    let mut words = String::new();
    let mut previous_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && previous_lower {
            words.push(' ');
        }
        if c.is_ascii_alphanumeric() {
            words.push(c.to_ascii_lowercase());
        } else if !words.ends_with(' ') && !words.is_empty() {
            words.push(' ');
        }
        previous_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
    }
    words.trim().to_string()
}

/// The event ids on a stream's event service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamEvent {
    /// The publisher sent a sample (after every send).
    SampleSent,
    /// The publisher has sent its last sample: the plant flew the whole scenario.
    Finished,
    /// iceoryx2 cleaned up the node of a dead publisher (emitted by whoever ran the cleanup).
    PublisherDead,
}

impl StreamEvent {
    /// The iceoryx2 event id.
    pub const fn id(self) -> usize {
        match self {
            StreamEvent::SampleSent => 0,
            StreamEvent::Finished => 253,
            StreamEvent::PublisherDead => 254,
        }
    }
}

/// Failures of the transport, each phrased for the person running the rig.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// A run id that is not 1..=24 characters of `[a-z0-9-]`.
    #[error("invalid run id {given:?}: {reason} (use 1..={RUN_ID_MAX_LEN} characters of a-z, 0-9 and '-')")]
    InvalidRunId {
        /// What was given.
        given: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// iceoryx2 rejected a name built from valid parts (should not happen).
    #[error("iceoryx2 rejected the name {name:?}: {detail}")]
    Name {
        /// The name.
        name: String,
        /// iceoryx2's reason.
        detail: String,
    },
    /// The node could not be created.
    #[error("run `{run}`: cannot create iceoryx2 node `{node}`: {detail}")]
    Node {
        /// Run id.
        run: String,
        /// Node name.
        node: String,
        /// iceoryx2's reason.
        detail: String,
    },
    /// The existing service carries a payload type of another name, size or alignment.
    #[error(
        "peer built with another wire layout: expected {expected} ({expected_size} B, align {expected_align}) on \
         stream `{stream}`, but the service carries {found}; rebuild every rig process from the same commit"
    )]
    OtherWireLayout {
        /// Stream label.
        stream: &'static str,
        /// Type name this build speaks.
        expected: &'static str,
        /// Its size.
        expected_size: usize,
        /// Its alignment.
        expected_align: usize,
        /// What the service holds, as far as it could be read.
        found: String,
    },
    /// The stream's services could not be opened or created.
    #[error("run `{run}`: cannot open stream `{stream}` ({pattern}): {detail}")]
    OpenStream {
        /// Run id.
        run: String,
        /// Stream label.
        stream: &'static str,
        /// `publish-subscribe` or `event`.
        pattern: &'static str,
        /// iceoryx2's reason.
        detail: String,
    },
    /// Another live publisher holds the stream.
    #[error(
        "stream `{stream}` of run `{run}` already has a live publisher ({holder}); only one is allowed: is another \
         {stream} process running for this run?"
    )]
    PublisherAlreadyActive {
        /// Run id.
        run: String,
        /// Stream label.
        stream: &'static str,
        /// Node name and pid of the holder, when known.
        holder: String,
    },
    /// A port could not be created.
    #[error("stream `{stream}`: cannot create {port}: {detail}")]
    Port {
        /// Stream label.
        stream: &'static str,
        /// Which port.
        port: &'static str,
        /// iceoryx2's reason.
        detail: String,
    },
    /// A sample to be sent failed validation.
    #[error("stream `{stream}`: refusing to send an invalid sample: {cause}")]
    InvalidSample {
        /// Stream label.
        stream: &'static str,
        /// What is wrong.
        cause: WireError,
    },
    /// Loan, send, notify or receive failed.
    #[error("stream `{stream}`: {op} failed: {detail}")]
    Transfer {
        /// Stream label.
        stream: &'static str,
        /// `loan`, `send`, `notify`, `receive`, `listener wait`.
        op: &'static str,
        /// iceoryx2's reason.
        detail: String,
    },
    /// WaitSet failure.
    #[error("waitset: {0}")]
    WaitSet(String),
    /// timerfd failure.
    #[error("timerfd: {0}")]
    Timer(std::io::Error),
    /// End-of-run cleanup failed.
    #[error("cleanup of run `{run}`: {detail}")]
    Cleanup {
        /// Run id.
        run: String,
        /// What failed.
        detail: String,
    },
}

#[cfg(test)]
mod tests {
    #[derive(Debug)]
    #[allow(dead_code)]
    enum Inner {
        ServiceInCorruptedState,
    }
    #[derive(Debug)]
    #[allow(dead_code)]
    enum Outer {
        Open(Inner),
        ExceedsMaxSupportedPublishers,
    }

    #[test]
    fn an_iceoryx2_error_reads_as_words_without_its_type_or_brackets() {
        assert_eq!(super::in_words(&Outer::ExceedsMaxSupportedPublishers), "exceeds max supported publishers");
        assert_eq!(super::in_words(&Outer::Open(Inner::ServiceInCorruptedState)), "open service in corrupted state");
    }
}
