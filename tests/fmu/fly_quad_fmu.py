"""The exported quadrotor FMU seen by an independent importer, FMPy (tests/fmu_export_quad.rs runs it in
target/test-venv). Validation and the wrong GUID are fly_fmu.py's, shared with the F-16.

    fly_quad_fmu.py replay FMU TRACE DELAY    instantiate at the export's start values, initialise, then one doStep
                                              of the trace's step per row: over step k the inputs are the trace's
                                              motor commands of row k - DELAY (the scenario's command timing: 1 for
                                              next-tick), the start values before; every output at t = 0 and after
                                              each step is compared with the trace's column of the same name, bit
                                              for bit. Prints rows, values and how many are bit-identical, and the
                                              first difference if any
    fly_quad_fmu.py state FMU                 fmi2GetFMUstate / Serialize / DeSerialize / SetFMUstate over a
                                              flight with the motors apart (it climbs, rolls and yaws): continued
                                              from a saved state, in this instance and in a second one, it must give
                                              the same bits as flown on
    fly_quad_fmu.py describe FMU              the model identifier, then each variable as FMPy reads it: causality,
                                              name, unit, start, one a line
    fly_quad_fmu.py simulate FMU              fmpy.simulate_fmu over the default experiment, an output each step;
                                              prints the samples and the final alt_m
"""

import csv
import struct
import sys

from fly_fmu import bits, initialise, open_fmu
from fmpy import read_model_description, simulate_fmu

MOTORS = ["motor1", "motor2", "motor3", "motor4"]


def vrs(md, causality):
    return [v.valueReference for v in md.modelVariables if v.causality == causality]


def replay(path, trace, delay):
    md, slave = open_fmu(path)
    names = [v.name for v in md.modelVariables if v.causality == "output"]
    by_name = {v.name: v for v in md.modelVariables}
    in_vrs = [by_name[m].valueReference for m in MOTORS]
    with open(trace) as f:
        rows = list(csv.DictReader(f))
    dt = float(md.defaultExperiment.stepSize)
    initialise(md, slave, {})
    flown = [slave.getReal(vrs(md, "output"))]
    for k in range(len(rows) - 1):
        if k >= delay:
            slave.setReal(in_vrs, [float(rows[k - delay][f"{m}_cmd"]) for m in MOTORS])
        slave.doStep(currentCommunicationPoint=k * dt, communicationStepSize=dt)
        flown.append(slave.getReal(vrs(md, "output")))
    slave.terminate()
    slave.freeInstance()
    values = identical = 0
    first = None
    for k, (row, got) in enumerate(zip(rows, flown)):
        for name, x in zip(names, got):
            want = float(row[name])
            values += 1
            if struct.pack("<d", x) == struct.pack("<d", want):
                identical += 1
            elif first is None:
                first = f"row {k} {name}: trace {want!r}, FMU {x!r}"
    print(f"{len(flown)} rows; {values} values; {identical} bit-identical")
    if first:
        print(f"first difference: {first}")


def state(path):
    def fly(slave, md, start, steps):
        in_vrs = [{v.name: v for v in md.modelVariables}[m].valueReference for m in MOTORS]
        rows = []
        for k in range(start, start + steps):
            # Full climb, then the motors apart: roll, pitch and yaw all move.
            slave.setReal(in_vrs, [0.8] * 4 if k < 200 else [0.62, 0.55, 0.58, 0.52])
            slave.doStep(currentCommunicationPoint=k * 0.001, communicationStepSize=0.001)
            rows.append(slave.getReal(vrs(md, "output")))
        return rows

    md, a = open_fmu(path)
    initialise(md, a, {})
    fly(a, md, 0, 300)
    saved = a.getFMUstate()
    data = a.serializeFMUstate(saved)
    flown_on = fly(a, md, 300, 400)
    a.setFMUstate(saved)
    again = fly(a, md, 300, 400)
    read = a.deSerializeFMUstate(data)
    a.setFMUstate(read)
    from_bytes = fly(a, md, 300, 400)
    md2, b = open_fmu(path)
    initialise(md2, b, {})
    b.setFMUstate(b.deSerializeFMUstate(data))
    restarted = fly(b, md2, 300, 400)
    for s in (saved, read):
        a.freeFMUstate(s)
    moved = sum(1 for x, y in zip(flown_on[0], flown_on[-1]) if x != y)
    for name, rows in [("setFMUstate", again), ("deserialised", from_bytes), ("second instance", restarted)]:
        same = bits(rows) == bits(flown_on)
        print(f"{name}: {'bit-identical' if same else 'DIFFERENT'} over {len(rows)} samples")
    print(f"serialised state: {len(data)} bytes; outputs that moved over the 0.4 s: {moved}")


def main():
    what, path = sys.argv[1], sys.argv[2]
    if what == "replay":
        replay(path, sys.argv[3], int(sys.argv[4]))
    elif what == "state":
        state(path)
    elif what == "describe":
        md = read_model_description(path)
        print(md.coSimulation.modelIdentifier)
        for v in md.modelVariables:
            print(f"{v.causality} {v.name} {v.unit} {v.start}")
    elif what == "simulate":
        step_s = float(read_model_description(path).defaultExperiment.stepSize)
        result = simulate_fmu(path, output=["alt_m", "on_ground"], step_size=step_s, output_interval=step_s)
        print(f"{len(result)} samples; final alt_m {float(result['alt_m'][-1])!r}")
    else:
        sys.exit(f"unknown check {what}")


if __name__ == "__main__":
    main()
