//! Opening a stream: the pub/sub service and the event service of one stream name, with the settings every peer of
//! the stream must use ([`StreamSettings`]; iceoryx2 refuses a peer that asks for other ones), and the ports made
//! from them. Which streams exist and with which settings is the rig's topology ([`crate::topology`]), not this
//! module's.

use super::half_made::{self, Mend};
use super::publisher::StreamPublisher;
use super::subscriber::StreamSubscriber;
use super::{IpcError, StreamEvent};
use crate::clock;
use crate::wire::WireSample;
use iceoryx2::node::NodeView;
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeCreateError, PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::port_factory::{event as event_factory, publish_subscribe as pubsub_factory};
use std::time::Duration;

/// Attempts of `open_or_create` on the transient errors iceoryx2 reports while another process creates, removes or
/// cleans up the same service (#1578).
pub const OPEN_ATTEMPTS: u32 = 5;
/// Pause between those attempts.
pub const OPEN_RETRY_PAUSE: Duration = Duration::from_millis(20);

/// The iceoryx2 settings of a stream's two services. A peer must ask for exactly these: they are part of the wire
/// contract, as the sample layout is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct StreamSettings {
    /// Publishers allowed at once.
    pub max_publishers: usize,
    /// Subscribers allowed at once (also the listeners of the event service).
    pub max_subscribers: usize,
    /// Nodes that may hold the services at once, live or dead but not yet cleaned up.
    pub max_nodes: usize,
    /// Deepest queue a subscriber may ask for; the memory is preallocated per subscriber.
    pub subscriber_max_buffer: usize,
    /// Samples a subscriber may hold at once.
    pub subscriber_max_borrowed: usize,
    /// Samples the service keeps for a late subscriber (delivered on the publisher's next send).
    pub history_size: usize,
    /// Notifiers allowed on the event service.
    pub max_notifiers: usize,
}

/// One stream as the transport needs to know it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamSpec {
    /// Short name for messages (`plant`, `command`).
    pub label: &'static str,
    /// iceoryx2 service name; the pub/sub and the event service share it (iceoryx2 keys services by name and
    /// messaging pattern).
    pub service_name: &'static str,
    /// The settings of its services.
    pub settings: StreamSettings,
}

/// The two services of one stream, opened by [`open_stream`]; ports are made from here.
pub struct StreamService<T: WireSample> {
    spec: StreamSpec,
    run: String,
    pubsub: pubsub_factory::PortFactory<ipc::Service, T, ()>,
    event: event_factory::PortFactory<ipc::Service>,
}

impl<T: WireSample> std::fmt::Debug for StreamService<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamService").field("stream", &self.spec.label).field("run", &self.run).finish()
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
/// in a bad state are cleaned up, and so are service files a dead creator left half-made ([`super::half_made`]).
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
                mend_half_made(node);
                std::thread::sleep(OPEN_RETRY_PAUSE);
            }
            Err(e) => return Err(e),
        }
    }
}

/// [`super::half_made::mend`] in the node's run, each mend said on stderr (the run's messages keep it).
fn mend_half_made(node: &Node<ipc::Service>) {
    let dir = node.config().global.service_dir().to_string();
    for (mend, service) in half_made::mend(std::path::Path::new(&dir)) {
        let done = match mend {
            Mend::Finished => "finished it, as its creator would have",
            Mend::Removed => "removed it (its description was cut short)",
        };
        eprintln!(
            "silrig: the service file of `{service}` was left half-made by a process that died while creating it: \
             {done}; opening again"
        );
    }
}

/// What the service of a stream actually carries, for the "other wire layout" message.
fn describe_existing_payload(config: &Config, service_name: &str) -> String {
    let Ok(name) = ServiceName::new(service_name) else {
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

/// Open (or create) both services of the stream `spec` describes, for the payload `T`, with `spec.settings`. Every
/// process must open its streams through this one function with the same settings: iceoryx2 checks the settings
/// asked for on open against the existing service, and a mismatch fails.
///
/// Safe overflow is always on (a full queue drops its oldest sample, the publisher never blocks: iceoryx2's
/// blocking strategy deadlocks on a dead subscriber, #314); the event service of the same name wakes subscribers
/// and announces a dead publisher with [`StreamEvent::PublisherDead`] once it is cleaned up.
pub fn open_stream<T: WireSample>(
    node: &Node<ipc::Service>,
    spec: impl Into<StreamSpec>,
) -> Result<StreamService<T>, IpcError> {
    let spec = spec.into();
    let q = spec.settings;
    let stream = spec.label;
    let run = node.config().global.prefix.as_str().trim_start_matches("sr_").trim_end_matches('_').to_string();
    let name = ServiceName::new(spec.service_name)
        .map_err(|e| IpcError::Name { name: spec.service_name.into(), detail: super::in_words(&e) })?;

    let pubsub = open_with_retry(
        node,
        || {
            node.service_builder(&name)
                .publish_subscribe::<T>()
                .enable_safe_overflow(true)
                .max_publishers(q.max_publishers)
                .max_subscribers(q.max_subscribers)
                .max_nodes(q.max_nodes)
                .subscriber_max_buffer_size(q.subscriber_max_buffer)
                .subscriber_max_borrowed_samples(q.subscriber_max_borrowed)
                .history_size(q.history_size)
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
                found: describe_existing_payload(node.config(), spec.service_name),
            }
        }
        other => IpcError::OpenStream {
            run: run.clone(),
            stream,
            pattern: "publish-subscribe",
            detail: super::in_words(&other),
        },
    })?;

    let event = open_with_retry(
        node,
        || {
            node.service_builder(&name)
                .event()
                .max_notifiers(q.max_notifiers)
                .max_listeners(q.max_subscribers)
                .max_nodes(q.max_nodes)
                .notifier_dead_event(EventId::new(StreamEvent::PublisherDead.id()))
                .open_or_create()
        },
        transient_event,
    )
    .map_err(|e| IpcError::OpenStream {
        run: run.clone(),
        stream,
        pattern: "event",
        detail: super::in_words(&e),
    })?;
    super::namespace::restrict_root_path(std::path::Path::new(&node.config().global.root_path().to_string()));

    Ok(StreamService { spec, run, pubsub, event })
}

/// A fresh publisher epoch: CLOCK_MONOTONIC at creation with the pid folded into the top bits, so a restarted
/// process (or a re-created publisher) gets another value. Unique, not ordered.
pub fn new_epoch() -> u64 {
    let pid = u64::from(std::process::id());
    (clock::monotonic_ns() ^ (pid << 48)).max(1)
}

impl<T: WireSample> StreamService<T> {
    /// Publishers connected now.
    pub fn number_of_publishers(&self) -> usize {
        self.pubsub.dynamic_config().number_of_publishers()
    }

    /// Subscribers connected now.
    pub fn number_of_subscribers(&self) -> usize {
        self.pubsub.dynamic_config().number_of_subscribers()
    }

    /// Remove the resources of dead nodes attached to this stream (e.g. after a missed deadline); returns how many
    /// were cleaned up. This is also what makes the listener see [`StreamEvent::PublisherDead`] for a dead publisher.
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
                stream: self.spec.label,
                holder: self.publisher_holder(),
            },
            other => IpcError::Port { stream: self.spec.label, port: "publisher", detail: super::in_words(&other) },
        })?;
        let notifier = self
            .event
            .notifier_builder()
            .default_event_id(EventId::new(StreamEvent::SampleSent.id()))
            .create()
            .map_err(|e| IpcError::Port { stream: self.spec.label, port: "notifier", detail: super::in_words(&e) })?;
        Ok(StreamPublisher::new(self.spec.label, publisher, notifier, epoch))
    }

    /// A subscriber with a queue of `buffer_size` samples (clamped to 1..=`subscriber_max_buffer` of the stream's
    /// settings) and its listener.
    pub fn subscriber(&self, buffer_size: usize) -> Result<StreamSubscriber<T>, IpcError> {
        let subscriber = self
            .pubsub
            .subscriber_builder()
            .buffer_size(buffer_size.clamp(1, self.spec.settings.subscriber_max_buffer))
            .create()
            .map_err(|e| IpcError::Port { stream: self.spec.label, port: "subscriber", detail: super::in_words(&e) })?;
        let listener = self.event.listener_builder().create().map_err(|e| IpcError::Port {
            stream: self.spec.label,
            port: "listener",
            detail: super::in_words(&e),
        })?;
        Ok(StreamSubscriber::new(self.spec.label, subscriber, listener))
    }
}
