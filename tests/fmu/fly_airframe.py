"""Fly examples/fmu/airframe's FMU closed loop with the example PID of examples/python/pid_attitude.py, outside the
rig: FMPy's FMU2Slave stepped at the rig's 100 Hz, and the PidAttitude class itself (the gains its start() picks
for a plant named `airframe` with surfaces in deg) answering each sample. As in a rig of separate processes, the
command computed from the outputs at tick k is applied over the step after it (one tick of transport delay;
--delay-ticks changes that).

    python3 fly_airframe.py AIRFRAME.fmu [--phi 10] [--theta 5] [--psi 0] [--duration-s 20] [--delay-ticks 1]
                                         [--set NAME=VALUE ...] [--trace FILE.csv]

Prints one JSON object: per angle its set point, final value, peak, overshoot beyond the set point (deg, in the
direction of the step), the 2 % settling time (the last time it was outside 2 % of the step, or 0.1 deg when the
set point is 0) and its peak-to-peak in the last 3 s; per surface its peak |position| and peak-to-peak in the last
3 s; the gain set the PID chose.
"""

import argparse
import json
import math
import pathlib
import shutil
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from pid_attitude import ANGLES, GAINS, INPUTS, RATES, PidAttitude  # noqa: E402

DT_S = 0.01  # the rig's period


class Plant:
    """What PidAttitude.start reads of silrig_client's Plant: the name and the inputs (name, unit, ...)."""

    def __init__(self, name, inputs):
        self.name = name
        self.inputs = inputs


class Sample(dict):
    """A sample as the session library hands it: outputs by name, and its time `t_s`."""

    def __init__(self, t_s, values):
        super().__init__(values)
        self.t_s = t_s


class Session:
    """The part of silrig_client's Session that PidAttitude uses, answered from the FMU's model description."""

    def __init__(self, md, setpoints, held):
        self.plant = Plant(md.coSimulation.modelIdentifier,
                           [(v.name, v.unit, float(v.min), float(v.max), float(v.start)) for v in md.modelVariables
                            if v.causality == "input"])
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        self.input_names = [p[0] for p in self.plant.inputs]
        self.setpoints = setpoints
        self.held = held

    def setpoint(self, name, default=None, t_s=None):
        # The set points here are constant: the same at every sample's time.
        return self.setpoints.get(name, 0.0)

    def output(self, name):
        if name not in self.outputs:
            raise SystemExit(f"plant {self.plant.name} has no output {name}; its outputs: {', '.join(self.outputs)}")
        return self.outputs.index(name)

    def input(self, name):
        if name not in self.input_names:
            raise SystemExit(f"plant {self.plant.name} has no input {name}")
        return self.input_names.index(name)

    def held_command(self):
        return list(self.held)


def fly(fmu, setpoints, duration_s, delay_ticks, parameters, trace=None):
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(fmu)  # a temporary folder, removed at the end
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="airframe")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    if parameters:
        slave.setReal([vr[n] for n in parameters], list(parameters.values()))
    slave.exitInitializationMode()

    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    out_vr = [vr[n] for n in outputs]
    in_vr = [vr[n] for n in INPUTS]
    session = Session(md, setpoints, [float(v.start) for v in md.modelVariables if v.causality == "input"])
    pid = PidAttitude()
    pid.start(session)

    pending = [list(session.held)] * delay_ticks  # commands on their way to the plant
    rows = []
    t = 0.0
    ticks = int(round(duration_s / DT_S))
    for k in range(ticks + 1):
        sample = Sample(t, zip(outputs, slave.getReal(out_vr)))
        rows.append((t, sample))
        if k == ticks:
            break
        command, _errors = pid.step(sample, DT_S)
        pending.append([command[n] for n in INPUTS])
        slave.setReal(in_vr, pending.pop(0))
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=DT_S)
        t = (k + 1) * DT_S
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)

    if trace:
        with open(trace, "w") as f:
            f.write("t_s," + ",".join(outputs) + "\n")
            for t, s in rows:
                f.write(f"{t:.2f}," + ",".join(repr(s[n]) for n in outputs) + "\n")

    last = [s for t, s in rows if t >= duration_s - 3.0 - 1e-9]
    result = {"plant": session.plant.name, "gains": next(n for n, g in GAINS.items() if g is pid.gains), "angles": {},
              "surfaces": {}, "finite": all(math.isfinite(v) for _, s in rows for v in s.values())}
    for name in ANGLES:
        sp = setpoints.get(name, 0.0)
        values = [s[name] for _, s in rows]
        step = sp - values[0]
        band = 0.02 * abs(step) if abs(step) > 5.0 else 0.1
        outside = [t for t, s in rows if abs(s[name] - sp) > band]
        direction = 1.0 if step >= 0 else -1.0
        result["angles"][name] = {
            "setpoint": sp,
            "final": values[-1],
            "peak": max(values, key=abs),
            "overshoot": max(0.0, max(direction * (v - sp) for v in values)) if step != 0 else max(map(abs, values)),
            "band": band,
            "settling_s": (outside[-1] + DT_S) if outside else 0.0,
            "last3s_p2p": max(s[name] for s in last) - min(s[name] for s in last),
        }
    for name in INPUTS:
        values = [s[name + "_deg"] for _, s in rows]
        result["surfaces"][name] = {
            "peak_abs": max(map(abs, values)),
            "last3s_p2p": max(s[name + "_deg"] for s in last) - min(s[name + "_deg"] for s in last),
        }
    for name in RATES:
        result.setdefault("rates_peak_abs", {})[name] = max(abs(s[name]) for _, s in rows)
    result["beta_peak_abs"] = max(abs(s["beta_deg"]) for _, s in rows) if "beta_deg" in outputs else None
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fmu")
    ap.add_argument("--phi", type=float, default=10.0)
    ap.add_argument("--theta", type=float, default=5.0)
    ap.add_argument("--psi", type=float, default=0.0)
    ap.add_argument("--duration-s", type=float, default=20.0)
    ap.add_argument("--delay-ticks", type=int, default=1)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a parameter of the FMU")
    ap.add_argument("--trace")
    a = ap.parse_args()
    parameters = {}
    for item in a.set:
        name, _, value = item.partition("=")
        parameters[name] = float(value)
    setpoints = {"phi_deg": a.phi, "theta_deg": a.theta, "psi_deg": a.psi}
    print(json.dumps(fly(a.fmu, setpoints, a.duration_s, a.delay_ticks, parameters, a.trace)))


if __name__ == "__main__":
    main()
