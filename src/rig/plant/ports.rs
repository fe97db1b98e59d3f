//! The plant's side of the run's streams: [`PlantPorts`] opens them (the announcement, plant samples out,
//! commands and the logger's acknowledgements in) and waits for the controller and the logger to connect.

use crate::{ProcessArgs, signals};
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_wire::clock::{join_look_pause, monotonic_ns};
use silrig_wire::ipc::{self, StreamPublisher, StreamService, StreamSubscriber};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{CommandSample, LogAckSample, PlantInfo, PlantSample};
use std::time::Duration;

/// The plant's side of the run's streams.
pub struct PlantPorts {
    pub(super) plant_stream: StreamService<PlantSample>,
    pub(super) command_stream: StreamService<CommandSample>,
    pub(super) publisher: StreamPublisher<PlantSample>,
    /// Held for the run, so a second plant is refused before it could announce other signals.
    pub(super) announcer: StreamPublisher<PlantInfo>,
    pub(super) commands: StreamSubscriber<CommandSample>,
    pub(super) acks: StreamSubscriber<LogAckSample>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl PlantPorts {
    /// Open the plant's streams: announce `info`, publish plant samples, read commands and the logger's
    /// acknowledgements. The announcement goes out now and again with the first sample (a reader that subscribed
    /// in between gets it then), and any reader that joins later gets it from the stream's history
    /// ([`StreamPublisher::deliver_history`], every tick).
    pub fn connect(args: &ProcessArgs, info: &PlantInfo) -> anyhow::Result<Self> {
        let node = ipc::create_node(&args.run_id, Role::Plant.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let ack_stream = ipc::open_stream::<LogAckSample>(&node, Stream::LogAck)?;
        let info_stream = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?;
        let mut announcer = info_stream.publisher().context("the plant-info stream")?;
        announcer.send(0, info)?;
        let publisher = plant_stream.publisher().context("the plant stream")?;
        let commands = command_stream.subscriber(Stream::Command.queue_depth(Role::Plant))?;
        let acks = ack_stream.subscriber(Stream::LogAck.queue_depth(Role::Plant))?;
        Ok(Self { plant_stream, command_stream, publisher, announcer, commands, acks, _node: node })
    }

    /// Tell readers that did not start with the run (`--controller external`) that it is over.
    pub fn announce_finished(&self) -> anyhow::Result<()> {
        Ok(self.publisher.announce_finished()?)
    }

    /// Wait until the controller and the logger are connected, or time out; SIGTERM ends the wait early (false).
    pub fn wait_for_peers(&self, timeout_s: f64) -> anyhow::Result<bool> {
        // Every port the peers read with, the logger's command subscriber too (it subscribes to commands after
        // plant samples): otherwise the first commands of a fast lockstep run can go out before it listens.
        let ready = || {
            self.plant_stream.number_of_subscribers() >= 2
                && self.command_stream.number_of_publishers() >= 1
                && self.command_stream.number_of_subscribers() >= 2
        };
        let started_ns = monotonic_ns();
        let deadline = started_ns + (timeout_s * 1e9) as u64;
        while !ready() {
            if signals::termination_requested() {
                return Ok(false);
            }
            anyhow::ensure!(
                monotonic_ns() < deadline,
                "no controller and logger connected within {timeout_s} s (start silrig-controller and silrig-logger \
                 with the same --run-id)"
            );
            std::thread::sleep(join_look_pause(monotonic_ns() - started_ns, Duration::from_millis(5)));
        }
        Ok(true)
    }
}
