"""A controller that speaks iceoryx2 itself, written from `silrig contract` alone (PyPI `iceoryx2` 0.10 and the
generated `examples/python/silrig_contract.py`; no libsilrig_client): what a user of another language does without
the session library. It reads the plant's announcement, finds `theta_deg`, `q_dps` and `elevator` by name, holds
every input at the plant's hold value but the elevator, which a proportional-derivative law moves towards the
scenario's pitch set point, and leaves when the plant says the run is over. It writes no report.

    SILRIG_RUN_ID=<id> python3 raw_controller.py THETA_SETPOINT_DEG     (tests/clients.rs starts it)
"""

import ctypes
import os
import pathlib
import sys
import time

import iceoryx2 as iox2

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

import silrig_contract as c  # noqa: E402

KP, KD = 2.0, 1.0  # deg of elevator per deg of pitch error, per deg/s of pitch rate (Stevens & Lewis signs)


def open_stream(node, label, payload):
    """The stream's publish-subscribe and event services, with the settings the contract requires."""
    name = iox2.ServiceName.new(c.SERVICES[label])
    pubsub = (node.service_builder(name).publish_subscribe(payload).enable_safe_overflow(True).max_publishers(1)
              .max_subscribers(4).max_nodes(8)
              .subscriber_max_buffer_size(c.SUBSCRIBER_MAX_BUFFER[label]).subscriber_max_borrowed_samples(2)
              .history_size(1).open_or_create())
    event = (node.service_builder(name).event().max_notifiers(2).max_listeners(4).max_nodes(8)
             .notifier_dead_event(iox2.EventId.new(c.EVENT_PUBLISHER_DEAD)).open_or_create())
    return pubsub, event


class Sender:
    """A publisher that stamps the header as the contract says and notifies after every send."""

    def __init__(self, pubsub, event):
        self.publisher = pubsub.publisher_builder().create()
        self.notifier = event.notifier_builder().create()
        self.seq = 0
        self.epoch = time.monotonic_ns() | 1

    def send(self, sample, tick):
        h = sample.header
        h.seq, h.tick, h.epoch, h.layout_version = self.seq, tick, self.epoch, c.WIRE_LAYOUT_VERSION
        h.t_send_ns = time.monotonic_ns()
        self.publisher.loan_uninit().write_payload(sample).send()
        self.notifier.notify_with_custom_event_id(iox2.EventId.new(c.EVENT_SAMPLE_SENT))
        self.seq += 1


def text(raw):
    return bytes(raw).split(b"\0", 1)[0].decode()


def main():
    run = os.environ["SILRIG_RUN_ID"]
    theta_setpoint = float(sys.argv[1])
    config = iox2.config.default()
    config.global_cfg.root_path = iox2.Path.new(f"/dev/shm/silrig_{run}/")
    config.global_cfg.prefix = iox2.FileName.new(f"sr_{run}_")
    node = iox2.NodeBuilder.new().config(config).name(iox2.NodeName.new("raw-controller")).create(iox2.ServiceType.Ipc)

    plant_pubsub, plant_event = open_stream(node, "plant", c.PlantSample)
    info_pubsub, _ = open_stream(node, "plant-info", c.PlantInfo)
    samples = plant_pubsub.subscriber_builder().buffer_size(4).create()
    announcements = info_pubsub.subscriber_builder().buffer_size(4).create()
    finished = plant_event.listener_builder().create()
    # Announce no diagnostics before the command publisher exists (the plant starts once it sees that one).
    controller_info = Sender(*open_stream(node, "controller-info", c.ControllerInfo))
    controller_info.send(c.ControllerInfo(), 0)
    commands = Sender(*open_stream(node, "command", c.CommandSample))

    plant = None
    answered = 0
    while True:
        while plant is None and (received := announcements.receive()) is not None:
            plant = received.payload().contents
            outputs = [text(plant.output_names[k]) for k in range(plant.outputs_len)]
            inputs = [text(plant.input_names[k]) for k in range(plant.inputs_len)]
            theta, q, elevator = outputs.index("theta_deg"), outputs.index("q_dps"), inputs.index("elevator")
        if any(e.id.as_value == c.EVENT_FINISHED for e in finished.try_wait()):
            break
        received = samples.receive() if plant is not None else None
        if received is None:
            time.sleep(0.0001)
            continue
        sample = received.payload().contents
        if sample.flags & c.FLAG_END_OF_RUN:
            break
        command = c.CommandSample()
        command.answers_tick = sample.header.tick
        command.inputs_len = plant.inputs_len
        for k in range(plant.inputs_len):
            command.inputs[k] = plant.input_hold[k]
        error = theta_setpoint - sample.outputs[theta]
        command.inputs[elevator] = plant.input_hold[elevator] - KP * error + KD * sample.outputs[q]
        if answered == 0:
            controller_info.send(c.ControllerInfo(), sample.header.tick)
        commands.send(command, sample.header.tick)
        answered += 1
    print(f"raw_controller: answered {answered} samples", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
