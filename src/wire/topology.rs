//! The rig's shape: its three processes ([`Role`]) and the sample streams between them ([`Stream`]): who publishes
//! each stream, who reads it with how deep a queue, its payload, and the iceoryx2 settings every peer of the
//! stream must use. The transport ([`crate::ipc`]) opens whatever stream it is given; adding a stream is an edit
//! here, not there. This is also the part of the wire contract that is not a sample layout.

use crate::ipc::{StreamSettings, StreamSpec};
use crate::wire;
pub use silrig_flight::role::Role;

/// Queue depth of a reader that only wants the freshest sample (the controller, the plant): after a stall it sees
/// the 4 newest samples, not 128 stale ones.
pub const CONSUMER_BUFFER: usize = 4;

/// Queue depth of the logger on the plant and command streams: 4.1 s at 1 kHz (the quadrotor, Betaflight), 41 s at
/// 100 Hz (the F-16), so a logger stopped or not scheduled for a few seconds loses no row. The logger is the one
/// reader that must see every sample, and nothing can make it run on time everywhere: it takes a real-time priority
/// below the plant's and the controller's where that is allowed (`Role::fifo_priority`), not for an unprivileged
/// user, and no priority helps against a SIGSTOP or a write the kernel holds back. The cost is shared memory the
/// publisher preallocates for every subscriber it may have ([`Stream::settings`]): about 18 MB a run
/// (docs/src/explanations/architecture.md, "The logger's queue").
pub const LOGGER_BUFFER: usize = 4096;

/// The settings every stream of the rig shares but its subscribers' deepest queue, which is
/// [`Stream::settings`]'s (a stream with no deep reader would otherwise preallocate the logger's depth for nothing).
pub const STREAM_SETTINGS: StreamSettings = StreamSettings {
    // One producer per stream and run, so a second plant or controller is refused.
    max_publishers: 1,
    // The consumer, the logger, and two spare (a monitor, a restarted consumer whose dead predecessor is not
    // cleaned up yet).
    max_subscribers: 4,
    // Plant, controller, logger, supervisor, plus restarts waiting for cleanup.
    max_nodes: 8,
    // Per stream: its deepest reader's queue (`Stream::settings`), preallocated per subscriber.
    subscriber_max_buffer: CONSUMER_BUFFER,
    // Readers copy each sample out and release it at once.
    subscriber_max_borrowed: 2,
    // A late subscriber gets the newest sample (on the publisher's next send).
    history_size: 1,
    // The publisher's notifier, plus one for a restarted publisher before cleanup.
    max_notifiers: 2,
};

/// A sample stream of the rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// Plant -> controller, logger: [`wire::PlantSample`].
    Plant,
    /// Controller -> plant, logger: [`wire::CommandSample`].
    Command,
    /// Logger -> plant: [`wire::LogAckSample`], rows written (lockstep flow control).
    LogAck,
    /// Controller -> logger: [`wire::ControllerInfo`], the names of its diagnostics, once per epoch.
    ControllerInfo,
    /// Plant -> controller, logger: [`wire::PlantInfo`], its name and signals, once per epoch.
    PlantInfo,
}

impl Stream {
    /// Every stream.
    pub const ALL: [Stream; 5] =
        [Stream::Plant, Stream::Command, Stream::LogAck, Stream::ControllerInfo, Stream::PlantInfo];

    /// Short name, as in messages.
    pub fn label(self) -> &'static str {
        match self {
            Stream::Plant => "plant",
            Stream::Command => "command",
            Stream::LogAck => "log-ack",
            Stream::ControllerInfo => "controller-info",
            Stream::PlantInfo => "plant-info",
        }
    }

    /// iceoryx2 service name of its pub/sub and event services.
    pub fn service_name(self) -> &'static str {
        match self {
            Stream::Plant => "silrig/plant",
            Stream::Command => "silrig/command",
            Stream::LogAck => "silrig/log-ack",
            Stream::ControllerInfo => "silrig/controller-info",
            Stream::PlantInfo => "silrig/plant-info",
        }
    }

    /// The iceoryx2 type name of its payload.
    pub fn payload_type_name(self) -> &'static str {
        match self {
            Stream::Plant => wire::PlantSample::TYPE_NAME,
            Stream::Command => wire::CommandSample::TYPE_NAME,
            Stream::LogAck => wire::LogAckSample::TYPE_NAME,
            Stream::ControllerInfo => wire::ControllerInfo::TYPE_NAME,
            Stream::PlantInfo => wire::PlantInfo::TYPE_NAME,
        }
    }

    /// Who publishes it.
    pub fn publisher(self) -> Role {
        match self {
            Stream::Plant => Role::Plant,
            Stream::Command => Role::Controller,
            Stream::LogAck => Role::Logger,
            Stream::ControllerInfo => Role::Controller,
            Stream::PlantInfo => Role::Plant,
        }
    }

    /// Who reads it, and with how deep a queue.
    pub fn readers(self) -> &'static [(Role, usize)] {
        match self {
            Stream::Plant => &[(Role::Controller, CONSUMER_BUFFER), (Role::Logger, LOGGER_BUFFER)],
            Stream::Command => &[(Role::Plant, CONSUMER_BUFFER), (Role::Logger, LOGGER_BUFFER)],
            Stream::LogAck => &[(Role::Plant, CONSUMER_BUFFER)],
            Stream::ControllerInfo => &[(Role::Logger, CONSUMER_BUFFER)],
            Stream::PlantInfo => &[(Role::Controller, CONSUMER_BUFFER), (Role::Logger, CONSUMER_BUFFER)],
        }
    }

    /// The iceoryx2 settings every peer of this stream must ask for: [`STREAM_SETTINGS`] with its deepest reader's
    /// queue as the subscribers' largest. The publisher preallocates that depth for each of `max_subscribers`, so
    /// the plant and command streams cost 4 x (4096 + 2) samples each, the announcements 4 x (4 + 2).
    pub fn settings(self) -> StreamSettings {
        let deepest = self.readers().iter().map(|(_, depth)| *depth).max().unwrap_or(CONSUMER_BUFFER);
        StreamSettings { subscriber_max_buffer: deepest, ..STREAM_SETTINGS }
    }

    /// Queue depth `reader` asks for on this stream (the consumer depth for a role the topology does not list).
    pub fn queue_depth(self, reader: Role) -> usize {
        self.readers().iter().find(|(r, _)| *r == reader).map_or(CONSUMER_BUFFER, |(_, depth)| *depth)
    }
}

impl std::fmt::Display for Stream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

impl From<Stream> for StreamSpec {
    fn from(stream: Stream) -> Self {
        StreamSpec { label: stream.label(), service_name: stream.service_name(), settings: stream.settings() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_stream_has_one_publisher_and_its_readers_fit_the_settings() {
        for s in Stream::ALL {
            let readers = s.readers();
            assert!(!readers.is_empty() && readers.len() < STREAM_SETTINGS.max_subscribers, "{s}");
            assert!(readers.iter().all(|(r, depth)| *r != s.publisher() && *depth <= LOGGER_BUFFER), "{s}");
            assert!(s.payload_type_name().starts_with("silrig::"));
        }
        assert_eq!(Stream::Plant.queue_depth(Role::Logger), LOGGER_BUFFER);
        assert_eq!(Stream::Command.queue_depth(Role::Plant), CONSUMER_BUFFER);
    }

    #[test]
    fn only_the_streams_the_logger_reads_preallocate_its_depth() {
        for s in [Stream::Plant, Stream::Command] {
            assert_eq!(s.settings().subscriber_max_buffer, LOGGER_BUFFER, "{s}");
        }
        for s in [Stream::LogAck, Stream::ControllerInfo, Stream::PlantInfo] {
            assert_eq!(s.settings().subscriber_max_buffer, CONSUMER_BUFFER, "{s}");
        }
        // Everything else is the same for every stream.
        let rest = |s: Stream| StreamSettings { subscriber_max_buffer: 0, ..s.settings() };
        assert!(Stream::ALL.iter().all(|s| rest(*s) == rest(Stream::Plant)));
    }
}
