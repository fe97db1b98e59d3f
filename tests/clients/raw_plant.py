"""A plant that speaks iceoryx2 itself, written from `silrig contract` alone (PyPI `iceoryx2` 0.10 and the generated
`examples/python/silrig_contract.py`; no libsilrig_client): the plant's side of a raw peer. It is the toy of
examples/python/toy_plant.py (three damped rotational axes with the F-16's names) and keeps the clock itself: one tick every
SILRIG_* period on the wall clock (realtime), the command answering each tick applied when it is in, the last one
held when not. It announces PlantInfo, waits for a command publisher, flies the run's ticks, sends the last tick
again with FLAG_END_OF_RUN and notifies EVENT_FINISHED. It writes no report.

    SILRIG_RUN_ID=<id> SILRIG_SCENARIO=<toml> python3 raw_plant.py     (silrig run --plant-cmd starts it)
"""

import os
import pathlib
import sys
import time
import tomllib

import iceoryx2 as iox2

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

import silrig_contract as c  # noqa: E402
from raw_controller import Sender, open_stream  # noqa: E402
from toy_plant import Toy  # noqa: E402


def announcement(model):
    info = c.PlantInfo()
    info.plant_name[:3] = b"raw"
    info.outputs_len, info.inputs_len = len(model.outputs), len(model.inputs)
    names = [name for name, _ in model.outputs]
    for k, (name, unit) in enumerate(model.outputs):
        info.output_names[k][:len(name)] = name.encode()
        info.output_units[k][:len(unit)] = unit.encode()
        info.output_flags[k] = c.OUTPUT_IN_TRACE
    for k, (name, unit, low, high, hold, held) in enumerate(model.inputs):
        info.input_names[k][:len(name)] = name.encode()
        info.input_units[k][:len(unit)] = unit.encode()
        info.input_min[k], info.input_max[k], info.input_hold[k] = low, high, hold
        info.input_held_output[k] = names.index(held)
        info.input_flags[k] = c.INPUT_COMMAND_IN_TRACE
    return info


def main():
    run = os.environ["SILRIG_RUN_ID"]
    with open(os.environ["SILRIG_SCENARIO"], "rb") as f:
        timing = tomllib.load(f).get("timing", {})
    dt_s = timing.get("dt_s", 0.01)
    ticks = round(float(os.environ.get("SILRIG_DURATION_S") or timing.get("duration_s", 10.0)) / dt_s)
    config = iox2.config.default()
    config.global_cfg.root_path = iox2.Path.new(f"/dev/shm/silrig_{run}/")
    config.global_cfg.prefix = iox2.FileName.new(f"sr_{run}_")
    node = iox2.NodeBuilder.new().config(config).name(iox2.NodeName.new("raw-plant")).create(iox2.ServiceType.Ipc)

    model = Toy()
    info = announcement(model)
    announcer = Sender(*open_stream(node, "plant-info", c.PlantInfo))
    announcer.send(info, 0)
    plant_pubsub, plant_event = open_stream(node, "plant", c.PlantSample)
    samples = Sender(plant_pubsub, plant_event)
    command_pubsub, _ = open_stream(node, "command", c.CommandSample)
    commands = command_pubsub.subscriber_builder().buffer_size(4).create()
    while command_pubsub.dynamic_config.number_of_publishers == 0:
        time.sleep(0.005)

    applied = [hold for *_, hold, _ in model.inputs]
    t0 = time.monotonic() + 2 * dt_s
    for tick in range(ticks + 1):
        time.sleep(max(0.0, t0 + tick * dt_s - time.monotonic()))
        sample = c.PlantSample()
        sample.t_sim_s = tick * dt_s
        outputs = model.outputs_now()
        sample.outputs_len = len(outputs)
        for k, v in enumerate(outputs):
            sample.outputs[k] = v
        announcer.publisher.update_connections()
        samples.send(sample, tick)
        # Same-tick: wait up to half a period for the answer to this tick, else hold the last command.
        deadline = time.monotonic() + dt_s / 2
        while time.monotonic() < deadline:
            received = commands.receive()
            if received is None:
                time.sleep(0.0002)
                continue
            command = received.payload().contents
            if command.answers_tick == tick and not command.flags & c.FLAG_COMMAND_REFUSED:
                applied = list(command.inputs[:command.inputs_len])
                break
        if tick < ticks:
            model.step(applied, dt_s)
    end = c.PlantSample()
    end.t_sim_s = ticks * dt_s
    end.flags = c.FLAG_END_OF_RUN
    outputs = model.outputs_now()
    end.outputs_len = len(outputs)
    for k, v in enumerate(outputs):
        end.outputs[k] = v
    samples.send(end, ticks)
    samples.notifier.notify_with_custom_event_id(iox2.EventId.new(c.EVENT_FINISHED))
    print(f"raw_plant: flew {ticks + 1} ticks", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
