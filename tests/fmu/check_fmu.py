"""Checks of the example and fixture FMUs through FMPy, for tests/fmu_examples.rs. Each prints one JSON object (the
Rust test judges it) and exits 0, unless the FMU takes the process down (misbehave's fault 4).

    python3 check_fmu.py validate FMU            FMPy's validate_fmu: {"problems": [...]}
    python3 check_fmu.py open-loop AIRFRAME.fmu  surface steps through fmpy.simulate_fmu, parameters read back
    python3 check_fmu.py roundtrip AIRFRAME.fmu  FMU state got, serialized, restored: does the flight go on the same?
    python3 check_fmu.py misbehave MISBEHAVE.fmu FAULT   fault from 0.5 s, stepping 0.01 s to 1 s
    python3 check_fmu.py instantiate FMU         instantiate as the model description says: failure and log

It unpacks the FMU into folders beside it (unzipped-*), which it leaves there.
"""

import json
import math
import os
import struct
import sys
import tempfile
import time
from ctypes import byref

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException, calloc, free
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2LastSuccessfulTime,
    fmi2Terminated,
)
from fmpy.logging import addLoggerProxy
from fmpy.validation import validate_fmu

DT_S = 0.01
STATUS = ["ok", "warning", "discard", "error", "fatal", "pending"]


class Logged:
    """Callbacks that keep what the FMU logs: [(status, category, message)]."""

    def __init__(self):
        self.messages = []

        def log(_env, _name, status, category, message):
            self.messages.append((STATUS[status] if 0 <= status < 6 else str(status),
                                  category.decode() if category else "", message.decode() if message else ""))

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))  # formats the FMU's printf-style message before log() sees it


def unzipped(fmu):
    """The FMU unpacked beside it (the test's own folder, which the test removes: a segfault leaves nothing
    behind elsewhere)."""
    folder = tempfile.mkdtemp(prefix="unzipped-", dir=os.path.dirname(os.path.abspath(fmu)))
    return extract(fmu, unzipdir=folder)


def open_slave(fmu, logged=None, name="check"):
    md = read_model_description(fmu)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped(fmu), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
    slave.instantiate(callbacks=logged.callbacks if logged else None)
    return md, slave, {v.name: v.valueReference for v in md.modelVariables}


def validate(fmu):
    """FMPy's validation, and which functions of the FMI 2.0 API (every fmi2...TYPE of fmpy's fmi2FunctionTypes.h)
    the binary does not export."""
    import ctypes
    import re

    import fmpy

    md = read_model_description(fmu)
    header = os.path.join(os.path.dirname(fmpy.__file__), "c-code", "fmi2FunctionTypes.h")
    api = sorted(set(re.findall(r"\b(fmi2\w+)TYPE\b", open(header).read())))
    binary = os.path.join(unzipped(fmu), "binaries", "linux64", md.coSimulation.modelIdentifier + ".so")
    lib = ctypes.CDLL(binary)
    return {"problems": validate_fmu(fmu), "api_functions": len(api),
            "missing_functions": [f for f in api if not hasattr(lib, f)]}


def open_loop(fmu):
    md = read_model_description(fmu)
    result = {}
    # The FMU's own parameter values before initialization against the model description's start values.
    md2, slave, vr = open_slave(fmu)
    params = [v for v in md.modelVariables if v.causality == "parameter"]
    own = slave.getReal([v.valueReference for v in params])
    result["parameter_start_mismatch"] = [v.name for v, x in zip(params, own) if float(v.start) != x]
    result["parameters"] = len(params)
    slave.freeInstance()

    # A parameter is fixed once initialized: setting it then is an error, and it keeps its value.
    logged = Logged()
    md2, slave, vr = open_slave(fmu, logged)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    try:
        slave.setReal([vr["Cl_da"]], [0.0])
        result["fixed_parameter_set_after_initialization"] = "accepted"
    except FMICallException as e:
        result["fixed_parameter_set_after_initialization"] = STATUS[e.status]
    result["Cl_da_after"] = slave.getReal([vr["Cl_da"]])[0]
    result["fixed_log"] = logged.messages
    slave.freeInstance()

    def step(surface, parameters=None):
        """FMPy's own co-simulation master: `surface` steps to +5 deg at 0.5 s, the others stay at 0."""
        columns = ("aileron", "elevator", "rudder")
        signal = np.array([(t,) + tuple(v if c == surface else 0.0 for c in columns)
                           for t, v in ((0.0, 0.0), (0.5, 0.0), (0.5, 5.0), (3.0, 5.0))],
                          dtype=[("time", np.float64)] + [(c, np.float64) for c in columns])
        return simulate_fmu(fmu, stop_time=3.0, step_size=DT_S, output_interval=DT_S, input=signal,
                            start_values=parameters or {})

    # Parameters reach the model: no aileron effectiveness, no roll or yaw from the aileron at all; the airspeed.
    r = step("aileron", {"Cl_da": 0.0, "Cn_da": 0.0, "trim_airspeed_mps": 30.0})
    result["ineffective_aileron"] = {n: float(abs(r[n]).max()) for n in ("phi_deg", "psi_deg", "p_dps", "r_dps",
                                                                        "beta_deg", "aileron_deg", "airspeed_mps")}

    result["steps"] = {}
    for surface in ("aileron", "elevator", "rudder"):
        r = step(surface)
        names = r.dtype.names
        before = r[r["time"] <= 0.5 + 1e-9]
        at = lambda t: r[np.argmin(abs(r["time"] - t))]  # noqa: E731
        result["steps"][surface] = {
            "quiet_before": bool(all(abs(before[n]).max() == 0.0 for n in names
                                     if n not in ("time", "airspeed_mps"))),
            "position_at_1s": float(at(1.0)[surface + "_deg"]),
            "at_0.7s": {n: float(at(0.7)[n]) for n in names if n != "time"},
            "at_1.5s": {n: float(at(1.5)[n]) for n in names if n != "time"},
            "finite": bool(all(np.isfinite(r[n]).all() for n in names)),
        }
    return result


def roundtrip(fmu):
    """Fly 1 s closed loop (a hand-made PD on all three axes so the state is busy), take and serialize the state,
    fly 1.5 s more with recorded commands; then go back to the state in the same instance, and in a new instance
    from the serialized bytes, and replay the same commands: the outputs must be the same bits."""
    logged = Logged()
    md, slave, vr = open_slave(fmu, logged, name="first")
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    out_vr = [vr[n] for n in outputs]
    in_vr = [vr[n] for n in ("aileron", "elevator", "rudder")]
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()

    def command(y, t):
        s = dict(zip(outputs, y))
        target = (20.0 * math.sin(2.0 * t), 8.0 * math.sin(1.3 * t), 0.0)
        return [1.5 * (s["phi_deg"] - target[0]) + 0.5 * s["p_dps"],
                3.0 * (s["theta_deg"] - target[1]) + 1.0 * s["q_dps"],
                4.0 * s["psi_deg"] + 2.0 * s["r_dps"]]

    t = 0.0
    for k in range(100):
        slave.setReal(in_vr, command(slave.getReal(out_vr), t))
        slave.doStep(t, DT_S)
        t = (k + 1) * DT_S
    t0 = t
    state = slave.getFMUstate()
    data = slave.serializeFMUstate(state)
    data_again = slave.serializeFMUstate(slave.getFMUstate())

    def pack(values):
        return struct.pack(f"<{len(values)}d", *values).hex()

    commands, first = [], []
    for k in range(150):
        c = command(slave.getReal(out_vr), t)
        commands.append(c)
        slave.setReal(in_vr, c)
        slave.doStep(t, DT_S)
        t = t0 + (k + 1) * DT_S
        first.append(pack(slave.getReal(out_vr)))

    def replay(s):
        got = []
        t = t0
        for k, c in enumerate(commands):
            s.setReal(in_vr, c)
            s.doStep(t, DT_S)
            t = t0 + (k + 1) * DT_S
            got.append(pack(s.getReal(out_vr)))
        return got

    slave.setFMUstate(state)
    same = replay(slave)

    md2, fresh, _ = open_slave(fmu, logged, name="second")
    fresh.setupExperiment(startTime=0.0)
    fresh.enterInitializationMode()
    fresh.exitInitializationMode()
    restored = fresh.deSerializeFMUstate(data)
    reserialized = fresh.serializeFMUstate(restored)
    fresh.setFMUstate(restored)
    other = replay(fresh)

    refused = {}
    for what, bad in (("truncated", data[:-8]), ("foreign", b"\x00" * len(data))):
        try:
            fresh.deSerializeFMUstate(bad)
            refused[what] = False
        except FMICallException:
            refused[what] = True

    moved = len(set(first)) == len(first)  # every output vector differs from the others: a busy flight
    return {
        "state_bytes": len(data),
        "serialized_twice_identical": data == data_again,
        "reserialized_identical": reserialized == data,
        "steps": len(first),
        "moved": moved,
        "same_instance_identical": same == first,
        "same_instance_first_difference": next((k for k, (a, b) in enumerate(zip(same, first)) if a != b), None),
        "new_instance_identical": other == first,
        "new_instance_first_difference": next((k for k, (a, b) in enumerate(zip(other, first)) if a != b), None),
        "refused": refused,
        "log": logged.messages,
    }


def misbehave(fmu, fault):
    logged = Logged()
    md, slave, vr = open_slave(fmu, logged)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["fault"], vr["fault_time_s"]], [float(fault), 0.5])
    slave.exitInitializationMode()
    slave.setReal([vr["u"]], [1.0])
    result = {"fault": fault, "failed_at": None, "status": None, "ys": [], "step_s": []}
    t = 0.0
    for k in range(100):
        if fault == 4 and t >= 0.5 - 1e-9:
            print(json.dumps({"fault": 4, "stepping_into_fault_at": t}), flush=True)
        start = time.perf_counter()
        try:
            slave.doStep(t, DT_S)
        except FMICallException as e:
            result["failed_at"] = round(t, 6)
            result["status"] = STATUS[e.status]
            break
        result["step_s"].append((round(t, 6), time.perf_counter() - start))
        t = (k + 1) * DT_S
        result["ys"].append((round(t, 6), slave.getReal([vr["y"]])[0]))
    result["last_successful_time"] = slave.getRealStatus(fmi2LastSuccessfulTime)
    result["terminated"] = bool(slave.getBooleanStatus(fmi2Terminated))
    result["log"] = logged.messages
    result["ys"] = [(t, y if math.isfinite(y) else repr(y)) for t, y in result["ys"]]
    return result


def instantiate(fmu):
    logged = Logged()
    try:
        md, slave, vr = open_slave(fmu, logged)
        instantiated = True
        slave.freeInstance()
    except Exception as e:  # FMPy raises a plain Exception when fmi2Instantiate returns NULL
        instantiated = False
        error = str(e)
    return {"instantiated": instantiated, "error": None if instantiated else error, "log": logged.messages}


def main():
    what, fmu = sys.argv[1], sys.argv[2]
    if what == "validate":
        out = validate(fmu)
    elif what == "open-loop":
        out = open_loop(fmu)
    elif what == "roundtrip":
        out = roundtrip(fmu)
    elif what == "misbehave":
        out = misbehave(fmu, int(sys.argv[3]))
    elif what == "instantiate":
        out = instantiate(fmu)
    else:
        sys.exit(f"unknown check {what}")
    print(json.dumps(out))


if __name__ == "__main__":
    main()
