"""Peers, part 1: the exported F-16 FMU flown by FMPy's own co-simulation master, `fmpy.simulate_fmu`, with the
commands of a `silrig sim --plant-fmu` trace of the same FMU as its input table, for the trace's whole flight.

    fmpy_f16.py simulate F16.fmu TRACE.csv OUT.csv   simulate_fmu over the trace's duration at the FMU's step; the
                                                     input over step k is the command the trace sent at tick k - 1
                                                     (`next-tick`; before the first, the actuators'
                                                     positions at t = 0, as the rig holds them);
                                                     writes every output at each communication point, repr() of
                                                     each double
    fmpy_f16.py compare TRACE.csv OUT.csv            the two flights output by output: the attitude, rates, air
                                                     data and load factors of row k against FMPy's point k, the
                                                     surfaces' and throttle's positions (which the trace's row k
                                                     takes from after the step) against point k + 1; prints how
                                                     many values are bit-identical and the largest difference

Needs `pip install fmpy numpy` (both in target/test-venv). The part the timing compares is `simulate`: reading the
trace, FMPy's simulation and writing its result, as a whole process beside `silrig sim`'s.
"""

import csv
import struct
import sys

import numpy as np
from fmpy import read_model_description, simulate_fmu

# The trace's command columns and the FMU input each drives; the throttle is not commanded by our controller, so
# its command is the position it holds (the rig's rule for an input the controller leaves alone).
COMMANDS = {"aileron": "aileron_cmd_deg", "elevator": "elevator_cmd_deg", "rudder": "rudder_cmd_deg",
            "throttle_cmd": "throttle"}
# Over step 0, before the first command acts, the rig holds each input where its actuator is: these positions at
# t = 0 (the trace's row 0, since a command equal to the position leaves it where it is over that step).
POSITIONS = {"aileron": "aileron_deg", "elevator": "elevator_deg", "rudder": "rudder_deg", "throttle_cmd": "throttle"}
# Outputs the trace's row k takes from after the step (the actuators' positions), not from the sample at tick k.
AFTER_STEP = {"aileron_deg", "elevator_deg", "rudder_deg", "throttle"}


def read_trace(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def input_table(rows, dt_s):
    """The input signal FMPy interpolates: at t = k dt the command acting over step k. Every communication point
    is a breakpoint, where FMPy's linear interpolation returns the breakpoint's value exactly."""
    names = list(COMMANDS)
    table = np.zeros(len(rows), dtype=[("time", np.float64)] + [(n, np.float64) for n in names])
    for k in range(len(rows)):
        table["time"][k] = k * dt_s
        for n in names:
            table[n][k] = float(rows[0][POSITIONS[n]] if k == 0 else rows[k - 1][COMMANDS[n]])
    return table


def simulate(fmu, trace, out):
    md = read_model_description(fmu)
    dt_s = float(md.defaultExperiment.stepSize)
    rows = read_trace(trace)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    result = simulate_fmu(fmu, stop_time=(len(rows) - 1) * dt_s, step_size=dt_s, output_interval=dt_s,
                          input=input_table(rows, dt_s), output=outputs)
    with open(out, "w") as f:
        f.write(",".join(["time"] + outputs) + "\n")
        for r in result:
            f.write(",".join(repr(float(x)) for x in r) + "\n")
    print(f"{len(result)} points over {result['time'][-1]:.2f} s")


def compare(trace, out):
    rows = read_trace(trace)
    flown = read_trace(out)
    names = [n for n in flown[0] if n != "time" and n in rows[0]]
    values = identical = 0
    largest = (0.0, "")
    for k, row in enumerate(rows):
        for n in names:
            j = k + 1 if n in AFTER_STEP else k
            if j >= len(flown):
                continue
            want, got = float(row[n]), float(flown[j][n])
            values += 1
            if struct.pack("<d", want) == struct.pack("<d", got):
                identical += 1
            elif not abs(got - want) <= largest[0]:
                largest = (abs(got - want), f"{n} at t = {float(row['t_s']):.2f} s")
    print(f"{len(rows)} rows, {len(names)} outputs: {values} values, {identical} bit-identical; "
          f"largest difference {largest[0]!r} {largest[1]}".rstrip())


def main():
    usage = "usage: fmpy_f16.py simulate F16.fmu TRACE.csv OUT.csv | compare TRACE.csv OUT.csv"
    if len(sys.argv) == 5 and sys.argv[1] == "simulate":
        simulate(*sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(*sys.argv[2:])
    else:
        sys.exit(usage)


if __name__ == "__main__":
    main()
