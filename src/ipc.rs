//! The iceoryx2 transport of the rig: per-run namespaces ([`RunId`], [`rig_config`]), the one function that builds
//! every stream's services ([`open_stream`]) with the rig's QoS, typed ports that stamp and check sample headers
//! ([`StreamPublisher`], [`StreamSubscriber`]), the WaitSet loop with the rig's signal rules ([`run_waitset`]), a
//! timerfd tick source that a WaitSet can wait on ([`TickTimer`]), and end-of-run cleanup ([`cleanup_run`]).
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

use crate::clock;
use crate::wire::{WireError, WireSample};
use iceoryx2::node::NodeView;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeCreateError, PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::port_factory::{event as event_factory, publish_subscribe as pubsub_factory};
use iceoryx2::waitset::WaitSetRunResult;
use std::cell::Cell;
use std::path::PathBuf;
use std::time::Duration;

/// Longest run id; keeps the prefix, and every shm name built from it, short.
pub const RUN_ID_MAX_LEN: usize = 24;
/// Publishers per stream: one producer per stream and run, so a second plant or controller is refused.
pub const MAX_PUBLISHERS: usize = 1;
/// Subscribers per stream: the consumer, the logger, and two spare (monitor, a restarted consumer whose dead
/// predecessor is not cleaned up yet).
pub const MAX_SUBSCRIBERS: usize = 4;
/// Nodes per service: plant, controller, logger, supervisor, plus restarts waiting for cleanup.
pub const MAX_NODES: usize = 8;
/// Deepest subscriber queue the service allows: 1.28 s at 100 Hz, so the logger rides out a 1 s stall without
/// losing a sample. The memory is preallocated per subscriber (4 x 128 x 192 B, about 100 KB per stream).
pub const SUBSCRIBER_MAX_BUFFER: usize = 128;
/// Queue depth of a consumer that only wants the freshest sample (the controller): after a stall it sees the 4
/// newest samples, not 128 stale ones.
pub const CONSUMER_BUFFER: usize = 4;
/// Queue depth of the logger: the whole service maximum.
pub const LOGGER_BUFFER: usize = SUBSCRIBER_MAX_BUFFER;
/// History the service keeps for a late subscriber (delivered on the publisher's next send).
pub const HISTORY_SIZE: usize = 1;
/// Samples a subscriber may hold at once; the typed subscriber copies each sample out and releases it at once.
pub const SUBSCRIBER_MAX_BORROWED: usize = 2;
/// Notifiers per event service: the publisher's, plus one for a restarted publisher before cleanup.
pub const MAX_NOTIFIERS: usize = 2;
/// Listeners per event service: one per subscriber.
pub const MAX_LISTENERS: usize = MAX_SUBSCRIBERS;
/// Event id iceoryx2 emits on a stream's event service when it cleans up the node of a dead publisher.
pub const NOTIFIER_DEAD_EVENT_ID: usize = 254;
/// Event id of "a sample was sent".
pub const SAMPLE_EVENT_ID: usize = 0;
/// Attempts of `open_or_create` on the transient errors iceoryx2 reports while another process creates, removes or
/// cleans up the same service (#1578).
pub const OPEN_ATTEMPTS: u32 = 5;
/// Pause between those attempts.
pub const OPEN_RETRY_PAUSE: Duration = Duration::from_millis(20);

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
        /// Stream.
        stream: Stream,
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
        /// Stream.
        stream: Stream,
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
        /// Stream.
        stream: Stream,
        /// Node name and pid of the holder, when known.
        holder: String,
    },
    /// A port could not be created.
    #[error("stream `{stream}`: cannot create {port}: {detail}")]
    Port {
        /// Stream.
        stream: Stream,
        /// Which port.
        port: &'static str,
        /// iceoryx2's reason.
        detail: String,
    },
    /// A sample to be sent failed validation.
    #[error("stream `{stream}`: refusing to send an invalid sample: {source}")]
    InvalidSample {
        /// Stream.
        stream: Stream,
        /// What is wrong.
        source: WireError,
    },
    /// Loan, send, notify or receive failed.
    #[error("stream `{stream}`: {op} failed: {detail}")]
    Transfer {
        /// Stream.
        stream: Stream,
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

/// The name of one rig run: its processes share an iceoryx2 namespace that no other run sees.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunId(String);

impl RunId {
    /// Validate: 1..=24 characters of `[a-z0-9-]`. No `_`, so one run's prefix `sr_<run>_` can never be the start of
    /// another run's prefix, and cleanup of one run cannot touch another run's files.
    pub fn new(id: &str) -> Result<Self, IpcError> {
        let bad = |reason| Err(IpcError::InvalidRunId { given: id.to_string(), reason });
        if id.is_empty() {
            return bad("it is empty");
        }
        if id.len() > RUN_ID_MAX_LEN {
            return bad("it is too long");
        }
        if !id.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-') {
            return bad("it contains a character outside [a-z0-9-]");
        }
        Ok(Self(id.to_string()))
    }

    /// The id.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Prefix of every iceoryx2 file of the run, in `/dev/shm` and under the root dir: `sr_<run>_`.
    pub fn prefix(&self) -> String {
        format!("sr_{}_", self.0)
    }

    /// Root directory of the run's iceoryx2 files: `/tmp/silrig_<run>/`.
    pub fn root_dir(&self) -> PathBuf {
        PathBuf::from(format!("/tmp/silrig_{}/", self.0))
    }
}

impl std::fmt::Display for RunId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::str::FromStr for RunId {
    type Err = IpcError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::new(s)
    }
}

/// The iceoryx2 config of a run: its own root dir and file prefix, defaults otherwise. Every process of the run must
/// use exactly this config (passed explicitly, so no `./config/iceoryx2.toml` in the working directory can change
/// it).
pub fn rig_config(run: &RunId) -> Config {
    let mut cfg = Config::default();
    // A validated RunId gives an absolute path and a file name of [a-z0-9_-], both far below iceoryx2's length
    // limits, so these conversions cannot fail.
    let root = run.root_dir();
    let root = root.to_string_lossy();
    let root = Path::new(root.as_bytes()).expect("a validated run id gives a valid iceoryx2 path");
    cfg.global.set_root_path(&root);
    cfg.global.prefix = FileName::new(run.prefix().as_bytes()).expect("a validated run id gives a valid prefix");
    cfg
}

/// Create a node of the run with the run's config.
pub fn create_node(run: &RunId, name: &str) -> Result<Node<ipc::Service>, IpcError> {
    let node_name = NodeName::new(name).map_err(|e| IpcError::Name { name: name.into(), detail: format!("{e:?}") })?;
    NodeBuilder::new().name(&node_name).config(&rig_config(run)).create::<ipc::Service>().map_err(|e| IpcError::Node {
        run: run.to_string(),
        node: name.into(),
        detail: e.to_string(),
    })
}

/// The rig's sample streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// Plant -> controller, logger: [`crate::wire::PlantSample`].
    Plant,
    /// Controller -> plant, logger: [`crate::wire::CommandSample`].
    Command,
    /// Logger -> plant: [`crate::wire::LogAckSample`], rows written (lockstep flow control).
    LogAck,
}

impl Stream {
    /// Every stream.
    pub const ALL: [Stream; 3] = [Stream::Plant, Stream::Command, Stream::LogAck];

    /// Short name, as in messages.
    pub fn label(self) -> &'static str {
        match self {
            Stream::Plant => "plant",
            Stream::Command => "command",
            Stream::LogAck => "log-ack",
        }
    }

    /// iceoryx2 service name (the pub/sub and the event service share it; iceoryx2 keys services by name and
    /// messaging pattern).
    pub fn service_name(self) -> &'static str {
        match self {
            Stream::Plant => "silrig/plant",
            Stream::Command => "silrig/command",
            Stream::LogAck => "silrig/log-ack",
        }
    }
}

impl std::fmt::Display for Stream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// The two services of one stream, opened by [`open_stream`]; ports are made from here.
pub struct StreamService<T: WireSample> {
    stream: Stream,
    run: String,
    pubsub: pubsub_factory::PortFactory<ipc::Service, T, ()>,
    event: event_factory::PortFactory<ipc::Service>,
}

impl<T: WireSample> std::fmt::Debug for StreamService<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamService").field("stream", &self.stream).field("run", &self.run).finish()
    }
}

fn transient_pubsub(e: &PublishSubscribeOpenOrCreateError) -> bool {
    use PublishSubscribeCreateError as C;
    use PublishSubscribeOpenError as O;
    use PublishSubscribeOpenOrCreateError as E;
    matches!(
        e,
        E::SystemInFlux
            | E::PublishSubscribeOpenError(
                O::ServiceInCorruptedState
                    | O::IsMarkedForDestruction
                    | O::HangsInCreation
                    | O::Interrupt
                    | O::ExceedsMaxNumberOfNodes
            )
            | E::PublishSubscribeCreateError(
                C::IsBeingCreatedByAnotherInstance | C::ServiceInCorruptedState | C::Interrupt | C::AlreadyExists
            )
    )
}

fn transient_event(e: &EventOpenOrCreateError) -> bool {
    use EventCreateError as C;
    use EventOpenError as O;
    use EventOpenOrCreateError as E;
    matches!(
        e,
        E::SystemInFlux
            | E::EventOpenError(
                O::ServiceInCorruptedState
                    | O::IsMarkedForDestruction
                    | O::HangsInCreation
                    | O::Interrupt
                    | O::ExceedsMaxNumberOfNodes
            )
            | E::EventCreateError(
                C::IsBeingCreatedByAnotherInstance | C::ServiceInCorruptedState | C::Interrupt | C::AlreadyExists
            )
    )
}

/// `open_or_create` with retries on the transient errors; between attempts, dead nodes that may hold the service
/// in a bad state are cleaned up.
fn open_with_retry<F, E>(
    node: &Node<ipc::Service>,
    mut attempt: impl FnMut() -> Result<F, E>,
    transient: impl Fn(&E) -> bool,
) -> Result<F, E> {
    let mut tries = 1;
    loop {
        match attempt() {
            Ok(f) => return Ok(f),
            Err(e) if tries < OPEN_ATTEMPTS && transient(&e) => {
                tries += 1;
                let _ = node.try_cleanup_dead_nodes();
                std::thread::sleep(OPEN_RETRY_PAUSE);
            }
            Err(e) => return Err(e),
        }
    }
}

/// What the service of a stream actually carries, for the "other wire layout" message.
fn describe_existing_payload(config: &Config, stream: Stream) -> String {
    let Ok(name) = ServiceName::new(stream.service_name()) else {
        return "an unreadable type".into();
    };
    match ipc::Service::details(&name, config, MessagingPattern::PublishSubscribe) {
        Ok(Some(details)) => {
            let payload = &details.static_details.publish_subscribe().message_type_details().payload;
            format!("{} ({} B, align {})", payload.type_name(), payload.size(), payload.alignment())
        }
        _ => "a type that could not be read back".into(),
    }
}

/// Open (or create) both services of `stream` for the payload `T` with the rig's QoS. Every process must open its
/// streams through this one function: iceoryx2 checks the QoS asked for on open against the existing service, and
/// a mismatch fails.
///
/// QoS: safe overflow (a full queue drops its oldest sample, the publisher never blocks), one publisher,
/// [`MAX_SUBSCRIBERS`], queues up to [`SUBSCRIBER_MAX_BUFFER`], history [`HISTORY_SIZE`]; an event service of the
/// same name for wake-ups, which announces a dead publisher with [`NOTIFIER_DEAD_EVENT_ID`] once it is cleaned up.
pub fn open_stream<T: WireSample>(node: &Node<ipc::Service>, stream: Stream) -> Result<StreamService<T>, IpcError> {
    let run = node.config().global.prefix.as_str().trim_start_matches("sr_").trim_end_matches('_').to_string();
    let name = ServiceName::new(stream.service_name())
        .map_err(|e| IpcError::Name { name: stream.service_name().into(), detail: format!("{e:?}") })?;

    let pubsub = open_with_retry(
        node,
        || {
            node.service_builder(&name)
                .publish_subscribe::<T>()
                .enable_safe_overflow(true)
                .max_publishers(MAX_PUBLISHERS)
                .max_subscribers(MAX_SUBSCRIBERS)
                .max_nodes(MAX_NODES)
                .subscriber_max_buffer_size(SUBSCRIBER_MAX_BUFFER)
                .subscriber_max_borrowed_samples(SUBSCRIBER_MAX_BORROWED)
                .history_size(HISTORY_SIZE)
                .open_or_create()
        },
        transient_pubsub,
    )
    .map_err(|e| match e {
        PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(PublishSubscribeOpenError::IncompatibleTypes) => {
            IpcError::OtherWireLayout {
                stream,
                expected: T::TYPE_NAME,
                expected_size: size_of::<T>(),
                expected_align: align_of::<T>(),
                found: describe_existing_payload(node.config(), stream),
            }
        }
        other => IpcError::OpenStream {
            run: run.clone(),
            stream,
            pattern: "publish-subscribe",
            detail: format!("{other:?}"),
        },
    })?;

    let event = open_with_retry(
        node,
        || {
            node.service_builder(&name)
                .event()
                .max_notifiers(MAX_NOTIFIERS)
                .max_listeners(MAX_LISTENERS)
                .max_nodes(MAX_NODES)
                .notifier_dead_event(EventId::new(NOTIFIER_DEAD_EVENT_ID))
                .open_or_create()
        },
        transient_event,
    )
    .map_err(|e| IpcError::OpenStream { run: run.clone(), stream, pattern: "event", detail: format!("{e:?}") })?;

    Ok(StreamService { stream, run, pubsub, event })
}

/// A fresh publisher epoch: CLOCK_MONOTONIC at creation with the pid folded into the top bits, so a restarted
/// process (or a re-created publisher) gets another value. Unique, not ordered.
pub fn new_epoch() -> u64 {
    let pid = u64::from(std::process::id());
    (clock::monotonic_ns() ^ (pid << 48)).max(1)
}

impl<T: WireSample> StreamService<T> {
    /// The stream.
    pub fn stream(&self) -> Stream {
        self.stream
    }

    /// Publishers connected now.
    pub fn number_of_publishers(&self) -> usize {
        self.pubsub.dynamic_config().number_of_publishers()
    }

    /// Subscribers connected now.
    pub fn number_of_subscribers(&self) -> usize {
        self.pubsub.dynamic_config().number_of_subscribers()
    }

    /// Remove the resources of dead nodes attached to this stream (e.g. after a missed deadline); returns how many
    /// were cleaned up. This is also what makes the listener see [`NOTIFIER_DEAD_EVENT_ID`] for a dead publisher.
    pub fn try_cleanup_dead_nodes(&self) -> u64 {
        self.pubsub.try_cleanup_dead_nodes().cleanups + self.event.try_cleanup_dead_nodes().cleanups
    }

    fn publisher_holder(&self) -> String {
        let mut holder_ids = Vec::new();
        self.pubsub.dynamic_config().list_publishers(|p| {
            holder_ids.push(p.node_id);
            CallbackProgression::Continue
        });
        let mut holders = Vec::new();
        let _ = self.pubsub.nodes(|state| {
            if let NodeState::Alive(view) = &state
                && holder_ids.contains(view.id())
            {
                match view.details() {
                    Some(d) => holders.push(format!("node `{}`, pid {}", d.name(), d.process_id())),
                    None => holders.push("a node without details".into()),
                }
            }
            CallbackProgression::Continue
        });
        if holders.is_empty() { "holder unknown".into() } else { holders.join("; ") }
    }

    /// The stream's publisher with a fresh [`new_epoch`]. With another publisher present, dead nodes are cleaned
    /// up first (the other one may have crashed) and creation is retried once; a live one gives
    /// [`IpcError::PublisherAlreadyActive`].
    pub fn publisher(&self) -> Result<StreamPublisher<T>, IpcError> {
        self.publisher_with_epoch(new_epoch())
    }

    /// The stream's publisher with a given epoch (tests, replays).
    pub fn publisher_with_epoch(&self, epoch: u64) -> Result<StreamPublisher<T>, IpcError> {
        let create =
            || self.pubsub.publisher_builder().backpressure_strategy(BackpressureStrategy::DiscardData).create();
        let publisher = match create() {
            Err(PublisherCreateError::ExceedsMaxSupportedPublishers) => {
                let _ = self.pubsub.try_cleanup_dead_nodes();
                create()
            }
            other => other,
        }
        .map_err(|e| match e {
            PublisherCreateError::ExceedsMaxSupportedPublishers => IpcError::PublisherAlreadyActive {
                run: self.run.clone(),
                stream: self.stream,
                holder: self.publisher_holder(),
            },
            other => IpcError::Port { stream: self.stream, port: "publisher", detail: format!("{other:?}") },
        })?;
        let notifier = self
            .event
            .notifier_builder()
            .default_event_id(EventId::new(SAMPLE_EVENT_ID))
            .create()
            .map_err(|e| IpcError::Port { stream: self.stream, port: "notifier", detail: format!("{e:?}") })?;
        Ok(StreamPublisher { stream: self.stream, publisher, notifier, epoch, next_seq: 0 })
    }

    /// A subscriber with a queue of `buffer_size` samples (at most [`SUBSCRIBER_MAX_BUFFER`]; use
    /// [`CONSUMER_BUFFER`] for a controller-like consumer, [`LOGGER_BUFFER`] for the logger) and its listener.
    pub fn subscriber(&self, buffer_size: usize) -> Result<StreamSubscriber<T>, IpcError> {
        let subscriber = self
            .pubsub
            .subscriber_builder()
            .buffer_size(buffer_size.clamp(1, SUBSCRIBER_MAX_BUFFER))
            .create()
            .map_err(|e| IpcError::Port { stream: self.stream, port: "subscriber", detail: format!("{e:?}") })?;
        let listener = self.event.listener_builder().create().map_err(|e| IpcError::Port {
            stream: self.stream,
            port: "listener",
            detail: format!("{e:?}"),
        })?;
        Ok(StreamSubscriber {
            stream: self.stream,
            subscriber,
            listener,
            tracker: Cell::new(SeqTracker::default()),
            stats: Cell::new(SubscriberStats::default()),
        })
    }
}

/// The sending side of a stream: stamps the header, sends, then wakes the listeners.
pub struct StreamPublisher<T: WireSample> {
    stream: Stream,
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    epoch: u64,
    next_seq: u64,
}

impl<T: WireSample> std::fmt::Debug for StreamPublisher<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamPublisher")
            .field("stream", &self.stream)
            .field("epoch", &self.epoch)
            .field("next_seq", &self.next_seq)
            .finish()
    }
}

impl<T: WireSample> StreamPublisher<T> {
    /// Send `sample` as belonging to plant `tick`: stamps `seq`, `tick`, `epoch`, `layout_version` and `t_send_ns`
    /// (overwriting what the caller put there), validates, loans, writes, sends, notifies. Returns the number of
    /// subscriber queues it went into (0 is not an error: nobody is listening) and the send stamp. An invalid
    /// sample is refused and not counted.
    pub fn send(&mut self, tick: u64, sample: &T) -> Result<SendReceipt, IpcError> {
        let mut out = *sample;
        {
            let h = out.header_mut();
            h.seq = self.next_seq;
            h.tick = tick;
            h.epoch = self.epoch;
            h.layout_version = crate::wire::WIRE_LAYOUT_VERSION;
            h._pad = 0;
        }
        out.validate().map_err(|source| IpcError::InvalidSample { stream: self.stream, source })?;
        let loan = self.publisher.loan_uninit().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "loan",
            detail: format!("{e:?}"),
        })?;
        // Stamped as late as possible, so that data age measured by the receiver excludes our own loan.
        let t_send_ns = clock::monotonic_ns();
        out.header_mut().t_send_ns = t_send_ns;
        let delivered = loan.write_payload(out).send().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "send",
            detail: format!("{e:?}"),
        })?;
        self.next_seq += 1;
        self.notifier.notify().map_err(|e| IpcError::Transfer {
            stream: self.stream,
            op: "notify",
            detail: format!("{e:?}"),
        })?;
        Ok(SendReceipt { delivered, t_send_ns })
    }

    /// Epoch stamped into every sample.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// `seq` the next sample will carry (= samples sent so far).
    pub fn next_seq(&self) -> u64 {
        self.next_seq
    }
}

/// What [`StreamPublisher::send`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SendReceipt {
    /// Subscriber queues the sample went into.
    pub delivered: usize,
    /// The `t_send_ns` stamped into the sample, CLOCK_MONOTONIC ns.
    pub t_send_ns: u64,
}

/// Loss and restart detection from `(epoch, seq)`. Pure, so the rules are unit-tested without iceoryx2.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SeqTracker {
    last: Option<(u64, u64)>,
}

/// What one sample's header says about the stream.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SeqObservation {
    /// Samples of this epoch missing just before this one.
    pub lost_before: u64,
    /// First sample of a new publisher epoch (a restart), or the very first sample seen.
    pub new_epoch: bool,
    /// `seq` did not advance within the epoch (duplicate or reordered); not counted as loss.
    pub out_of_order: bool,
}

impl SeqTracker {
    /// Account for a sample with this header.
    pub fn observe(&mut self, epoch: u64, seq: u64) -> SeqObservation {
        let obs = match self.last {
            // The first sample ever: whatever the publisher sent before we subscribed is not loss.
            None => SeqObservation { new_epoch: true, ..Default::default() },
            // A restarted publisher counts from 0 again, and we were connected when it started, so a first seq
            // above 0 means samples were lost.
            Some((last_epoch, _)) if last_epoch != epoch => {
                SeqObservation { lost_before: seq, new_epoch: true, out_of_order: false }
            }
            Some((_, last_seq)) if seq <= last_seq => SeqObservation { out_of_order: true, ..Default::default() },
            Some((_, last_seq)) => SeqObservation { lost_before: seq - last_seq - 1, ..Default::default() },
        };
        if !obs.out_of_order {
            self.last = Some((epoch, seq));
        }
        obs
    }
}

/// Running totals of a subscriber.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SubscriberStats {
    /// Samples received.
    pub received: u64,
    /// Samples missing by `seq` (overwritten by safe overflow or never delivered).
    pub lost: u64,
    /// Publisher epochs seen after the first (restarts).
    pub publisher_restarts: u64,
    /// Samples whose `seq` did not advance.
    pub out_of_order: u64,
    /// Samples that failed [`WireSample::validate`].
    pub invalid: u64,
    /// Dead-publisher events seen (after someone cleaned up its node).
    pub publisher_deaths: u64,
}

/// One received sample with what the transport knows about it.
#[derive(Debug, Clone, Copy)]
pub struct Received<T> {
    /// The sample, copied out of shared memory.
    pub sample: T,
    /// CLOCK_MONOTONIC when it was taken from the queue, ns.
    pub t_recv_ns: u64,
    /// Header bookkeeping.
    pub seq: SeqObservation,
    /// Why the sample must not be used, if so (NaN/inf, foreign layout).
    pub invalid: Option<WireError>,
}

impl<T: WireSample> Received<T> {
    /// Receive time minus send stamp, ns (0 if the clocks disagree, which CLOCK_MONOTONIC on one machine
    /// cannot).
    pub fn age_ns(&self) -> u64 {
        self.t_recv_ns.saturating_sub(self.sample.header().t_send_ns)
    }
}

/// The receiving side of a stream: a subscriber plus the listener that wakes a WaitSet.
pub struct StreamSubscriber<T: WireSample> {
    stream: Stream,
    subscriber: Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
    // Cells, because a WaitSet guard keeps `listener` borrowed while the callback drains: draining must work
    // through `&self`.
    tracker: Cell<SeqTracker>,
    stats: Cell<SubscriberStats>,
}

impl<T: WireSample> std::fmt::Debug for StreamSubscriber<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamSubscriber").field("stream", &self.stream).field("stats", &self.stats.get()).finish()
    }
}

impl<T: WireSample> StreamSubscriber<T> {
    /// The listener to attach to a WaitSet (`attach_notification` or `attach_deadline`).
    pub fn listener(&self) -> &Listener<ipc::Service> {
        &self.listener
    }

    /// Running totals.
    pub fn stats(&self) -> SubscriberStats {
        self.stats.get()
    }

    /// Take every pending sample, oldest first, and hand each to `on_sample`; returns how many. Also consumes the
    /// pending wake-ups, which a WaitSet callback must do or the WaitSet spins. Invalid samples are handed over too,
    /// marked in [`Received::invalid`] (the logger records them; a consumer must skip them).
    pub fn drain(&self, mut on_sample: impl FnMut(&Received<T>)) -> Result<usize, IpcError> {
        let stream = self.stream;
        let mut deaths = 0;
        self.listener
            .try_wait(|activation| {
                if activation.id.as_value() == NOTIFIER_DEAD_EVENT_ID {
                    deaths += 1;
                }
            })
            .map_err(|e| IpcError::Transfer { stream, op: "listener wait", detail: format!("{e:?}") })?;
        let mut stats = self.stats.get();
        let mut tracker = self.tracker.get();
        stats.publisher_deaths += deaths;
        let mut n = 0;
        loop {
            let sample = match self.subscriber.receive() {
                Ok(Some(s)) => *s.payload(),
                Ok(None) => break,
                Err(e) => {
                    self.stats.set(stats);
                    self.tracker.set(tracker);
                    return Err(IpcError::Transfer { stream, op: "receive", detail: format!("{e:?}") });
                }
            };
            let t_recv_ns = clock::monotonic_ns();
            let h = *sample.header();
            let seq = tracker.observe(h.epoch, h.seq);
            let invalid = sample.validate().err();
            stats.received += 1;
            stats.lost += seq.lost_before;
            stats.publisher_restarts += u64::from(seq.new_epoch && stats.received > 1);
            stats.out_of_order += u64::from(seq.out_of_order);
            stats.invalid += u64::from(invalid.is_some());
            on_sample(&Received { sample, t_recv_ns, seq, invalid });
            n += 1;
        }
        self.stats.set(stats);
        self.tracker.set(tracker);
        Ok(n)
    }

    /// Drain and keep only the newest valid sample (what a controller acts on).
    pub fn latest(&self) -> Result<Option<Received<T>>, IpcError> {
        let mut newest = None;
        self.drain(|r| {
            if r.invalid.is_none() {
                newest = Some(*r);
            }
        })?;
        Ok(newest)
    }
}

/// A WaitSet for a rig process (iceoryx2's default signal handling; see the module doc).
pub fn rig_waitset() -> Result<WaitSet<ipc::Service>, IpcError> {
    WaitSetBuilder::new().create::<ipc::Service>().map_err(|e| IpcError::WaitSet(format!("{e:?}")))
}

/// Why [`run_waitset`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopEnd {
    /// SIGTERM or SIGINT.
    TerminationRequest,
    /// The callback returned `CallbackProgression::Stop`.
    Stopped,
}

/// How a [`run_waitset`] loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopExit {
    /// Why.
    pub end: LoopEnd,
    /// Interrupted waits that were resumed (SIGSTOP/SIGCONT and the like).
    pub interrupts: u64,
}

/// Run the WaitSet until a termination signal or until `on_event` returns `Stop`. `Interrupt` (EINTR, e.g. after
/// SIGSTOP/SIGCONT) resumes waiting; a SIGTERM/SIGINT that caused it shows up as `TerminationRequest` on the next
/// wait, which ends the loop.
pub fn run_waitset<F>(waitset: &WaitSet<ipc::Service>, mut on_event: F) -> Result<LoopExit, IpcError>
where
    F: FnMut(WaitSetAttachmentId<ipc::Service>) -> CallbackProgression,
{
    let mut interrupts = 0;
    loop {
        match waitset.wait_and_process(&mut on_event) {
            Ok(WaitSetRunResult::Interrupt) => interrupts += 1,
            Ok(WaitSetRunResult::AllEventsHandled) => {}
            Ok(WaitSetRunResult::TerminationRequest) => {
                return Ok(LoopExit { end: LoopEnd::TerminationRequest, interrupts });
            }
            Ok(WaitSetRunResult::StopRequest) => return Ok(LoopExit { end: LoopEnd::Stopped, interrupts }),
            Err(e) => return Err(IpcError::WaitSet(format!("{e:?}"))),
        }
    }
}

/// A periodic tick source a WaitSet can wait on alongside listeners: a `timerfd` on CLOCK_MONOTONIC with absolute
/// expirations on the [`clock::TickSchedule`] grid (not `WaitSet::attach_interval`, whose epoll timeout is rounded
/// up to whole milliseconds, so its ticks land 0-1 ms late). Attach with `waitset.attach_notification(&timer)`;
/// in the callback, [`TickTimer::read_expirations`] re-arms readiness and says how many periods passed.
#[derive(Debug)]
pub struct TickTimer {
    fd: FileDescriptor,
    schedule: clock::TickSchedule,
}

impl TickTimer {
    /// Arm a timer whose expirations fall at `schedule.deadline_ns(k)` for k = 0, 1, 2, ...
    pub fn new(schedule: clock::TickSchedule) -> Result<Self, IpcError> {
        // Safety: plain syscalls with valid arguments; the fd is owned by `FileDescriptor` from here on.
        let raw = unsafe { libc::timerfd_create(libc::CLOCK_MONOTONIC, libc::TFD_NONBLOCK | libc::TFD_CLOEXEC) };
        if raw < 0 {
            return Err(IpcError::Timer(std::io::Error::last_os_error()));
        }
        let fd = FileDescriptor::new(raw)
            .ok_or_else(|| IpcError::Timer(std::io::Error::other("timerfd is not a valid descriptor")))?;
        let spec = libc::itimerspec {
            it_interval: clock::timespec_from_ns(schedule.period_ns),
            // An all-zero it_value would disarm the timer; tick 0 at t=0 cannot happen with CLOCK_MONOTONIC.
            it_value: clock::timespec_from_ns(schedule.t0_ns.max(1)),
        };
        let rc =
            unsafe { libc::timerfd_settime(fd.native_handle(), libc::TFD_TIMER_ABSTIME, &spec, std::ptr::null_mut()) };
        if rc != 0 {
            return Err(IpcError::Timer(std::io::Error::last_os_error()));
        }
        Ok(Self { fd, schedule })
    }

    /// The grid the timer fires on.
    pub fn schedule(&self) -> clock::TickSchedule {
        self.schedule
    }

    /// Periods expired since the last read (0 if none: the fd is non-blocking). More than 1 means ticks were missed.
    pub fn read_expirations(&self) -> Result<u64, IpcError> {
        let mut count: u64 = 0;
        loop {
            // Safety: reads at most 8 bytes into a u64 we own.
            let n = unsafe { libc::read(self.fd.native_handle(), (&mut count as *mut u64).cast(), size_of::<u64>()) };
            if n == size_of::<u64>() as isize {
                return Ok(count);
            }
            let err = std::io::Error::last_os_error();
            match err.kind() {
                std::io::ErrorKind::WouldBlock => return Ok(0),
                std::io::ErrorKind::Interrupted => continue,
                _ => return Err(IpcError::Timer(err)),
            }
        }
    }
}

impl FileDescriptorBased for TickTimer {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.fd
    }
}

impl SynchronousMultiplexing for TickTimer {}

/// A node found during cleanup.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct NodeSummary {
    /// Node name ("?" if its details are gone).
    pub name: String,
    /// Process id (0 if unknown).
    pub pid: i64,
}

/// What [`cleanup_run`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct CleanupReport {
    /// Run id.
    pub run: String,
    /// Nodes still alive: when not empty, nothing was removed.
    pub alive: Vec<NodeSummary>,
    /// Dead nodes whose resources were removed.
    pub dead_cleaned: Vec<NodeSummary>,
    /// Dead nodes whose cleanup failed (or that another process was cleaning).
    pub dead_failed: Vec<NodeSummary>,
    /// Nodes that could not be inspected (permissions, half-written state).
    pub unknown: usize,
    /// The run's root dir was removed.
    pub removed_root_dir: bool,
    /// Files removed from `/dev/shm`.
    pub removed_shm_files: Vec<String>,
}

impl CleanupReport {
    /// Nothing of the run is left on disk.
    pub fn is_clean(&self) -> bool {
        self.alive.is_empty()
    }
}

fn summary_of(details: &Option<iceoryx2::node::NodeDetails>) -> NodeSummary {
    match details {
        Some(d) => NodeSummary { name: d.name().to_string(), pid: i64::from(d.process_id().value()) },
        None => NodeSummary { name: "?".into(), pid: 0 },
    }
}

/// Directory where iceoryx2 puts shared memory on Linux.
pub const SHM_DIR: &str = "/dev/shm";

/// End-of-run cleanup: remove the resources of the run's dead nodes through iceoryx2, then, only if no node of the
/// run is alive, delete the run's root dir and its `/dev/shm/<prefix>*` files (both, never only one: iceoryx2 #601).
/// With live nodes, reports them and removes nothing. Reap child processes first: a zombie still holds its node's
/// liveness lock.
pub fn cleanup_run(run: &RunId) -> Result<CleanupReport, IpcError> {
    let cfg = rig_config(run);
    let mut report = CleanupReport { run: run.to_string(), ..Default::default() };
    let root = run.root_dir();
    if root.exists() {
        Node::<ipc::Service>::list(&cfg, |state| {
            match state {
                NodeState::Alive(view) => report.alive.push(summary_of(view.details())),
                NodeState::Dead(view) => {
                    let who = summary_of(view.details());
                    match view.try_remove_stale_resources() {
                        Ok(()) => report.dead_cleaned.push(who),
                        Err(_) => report.dead_failed.push(who),
                    }
                }
                NodeState::Inaccessible(_) | NodeState::Undefined(_) => report.unknown += 1,
            }
            CallbackProgression::Continue
        })
        .map_err(|e| IpcError::Cleanup { run: run.to_string(), detail: format!("listing nodes: {e:?}") })?;
    }
    if !report.alive.is_empty() {
        return Ok(report);
    }
    if root.exists() {
        std::fs::remove_dir_all(&root).map_err(|e| IpcError::Cleanup {
            run: run.to_string(),
            detail: format!("removing {}: {e}", root.display()),
        })?;
        report.removed_root_dir = true;
    }
    let prefix = run.prefix();
    let entries = std::fs::read_dir(SHM_DIR)
        .map_err(|e| IpcError::Cleanup { run: run.to_string(), detail: format!("reading {SHM_DIR}: {e}") })?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(&prefix) {
            match std::fs::remove_file(entry.path()) {
                Ok(()) => report.removed_shm_files.push(name),
                // Another cleaner got there first.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => {
                    return Err(IpcError::Cleanup {
                        run: run.to_string(),
                        detail: format!("removing {SHM_DIR}/{name}: {e}"),
                    });
                }
            }
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_id_is_validated() {
        assert!(RunId::new("r42").is_ok());
        assert!(RunId::new("a-b-0").is_ok());
        assert!(RunId::new(&"x".repeat(24)).is_ok());
        for bad in ["", "Run1", "a_b", "a/b", "a b", "ü"] {
            let e = RunId::new(bad).unwrap_err().to_string();
            assert!(e.contains("invalid run id") && e.contains("a-z, 0-9 and '-'"), "{e}");
        }
        assert!(RunId::new(&"x".repeat(25)).unwrap_err().to_string().contains("too long"));
        let r = RunId::new("r42").unwrap();
        assert_eq!(r.prefix(), "sr_r42_");
        assert_eq!(r.root_dir(), PathBuf::from("/tmp/silrig_r42/"));
        let cfg = rig_config(&r);
        assert_eq!(cfg.global.prefix.as_str(), "sr_r42_");
        assert_eq!(cfg.global.root_path().to_string(), "/tmp/silrig_r42/");
    }

    #[test]
    fn seq_tracker_counts_gaps_restarts_and_reorders() {
        let mut t = SeqTracker::default();
        assert_eq!(t.observe(7, 100), SeqObservation { lost_before: 0, new_epoch: true, out_of_order: false });
        assert_eq!(t.observe(7, 101).lost_before, 0);
        assert_eq!(t.observe(7, 105).lost_before, 3);
        assert!(t.observe(7, 104).out_of_order);
        assert_eq!(t.observe(7, 106).lost_before, 0);
        assert_eq!(t.observe(9, 2), SeqObservation { lost_before: 2, new_epoch: true, out_of_order: false });
        assert_eq!(t.observe(9, 3).lost_before, 0);
    }
}
