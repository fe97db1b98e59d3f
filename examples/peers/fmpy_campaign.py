"""Peers, part 3: a sweep's campaign flown by a Python loop over FMPy, the way one couples two FMUs by hand: the
example PID as an FMU (examples/fmu/pid) on the F-16 exported from the campaign's scenario (`silrig export-fmu`),
each case in fresh instances of both, tick by tick under the rig's lockstep rules.

    fmpy_campaign.py F16.fmu PID.fmu CASES.csv OUT.csv [N]

CASES.csv is a `silrig sweep` of the same scenario (its `cases.csv`): each case's dispersed values, which this loop
sets as the F-16 FMU's parameters by name (`initial.phi_deg` is `initial_phi_deg`, `plant.xcg` is `xcg`,
`plant.aero_scale.cl` is `aero_scale_cl`, `actuators.elevator_deg.rate_limit_per_s` is
`elevator_rate_limit_per_s`); N: fly only the first N cases. OUT.csv gets, per case, the figures of `cases.csv`
this loop computes the same way (each output's final value minus its set point, the peak alpha), repr() of each.

The rules, those of the rig (src/adapters/in_process.rs): at tick k the PID reads the F-16's outputs and its set
points and steps from k dt; its surface commands, with the throttle held where it is, act over step k + 1
(`next-tick`), the actuators' positions at t = 0 over step 0. The campaign's scenario has no transport delay,
disturbance or sensor errors, which this loop would have to add.

Needs `pip install fmpy` (in target/test-venv).
"""

import csv
import sys
from collections import deque

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

SURFACES = ["aileron", "elevator", "rudder"]
# What the PID reads, by its input names: the F-16's outputs of the same names, then the set points.
PID_READS = ["phi_deg", "theta_deg", "psi_deg", "p_dps", "q_dps", "r_dps", "aileron_deg", "elevator_deg",
             "rudder_deg"]
SETPOINTS_DEG = {"phi_deg_sp": 0.0, "theta_deg_sp": 10.0, "psi_deg_sp": 0.0}  # the scenario's [setpoint]
FIGURES = ["phi_final_error_deg", "theta_final_error_deg", "psi_final_error_deg", "alpha_peak_deg"]
DELAY_TICKS = 1  # next-tick


class Model:
    """An FMU unpacked once, instantiated afresh for each case."""

    def __init__(self, path, name):
        self.md = read_model_description(path)
        self.dir = extract(path)
        self.name = name
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.kind = {v.name: v.type for v in self.md.modelVariables}
        self.dt_s = float(self.md.defaultExperiment.stepSize)

    def instance(self, parameters):
        slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                          modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=self.name)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        for name, value in parameters.items():
            if self.kind[name] == "Boolean":
                slave.setBoolean([self.vr[name]], [value != 0.0])
            else:
                slave.setReal([self.vr[name]], [value])
        slave.exitInitializationMode()
        return slave

    def refs(self, names):
        return [self.vr[n] for n in names]


def parameter_name(key):
    """The F-16 FMU's parameter for a dispersed key of the scenario."""
    parts = key.split(".")
    if parts[0] == "initial" and len(parts) == 2:
        return "initial_" + parts[1]
    if parts[0] == "plant":
        return "_".join(parts[1:])
    if parts[0] == "actuators" and len(parts) == 3:
        return parts[1].removesuffix("_deg") + "_" + parts[2]
    return None


def case_parameters(f16, row):
    parameters = {}
    for key, value in row.items():
        if "." not in key:
            continue  # index, outcome and the figures
        name = parameter_name(key)
        if name not in f16.vr:
            sys.exit(f"the F-16 FMU has no parameter for the dispersed key `{key}`: disperse only what "
                     f"`silrig export-fmu` writes as a parameter (the initial condition, plant and actuators)")
        parameters[name] = float(value)
    return parameters


def fly(f16, pid, parameters, ticks):
    """One case; its figures."""
    plant, law = f16.instance(parameters), pid.instance({})
    outputs = [v.name for v in f16.md.modelVariables if v.causality == "output"]
    out_vrs = f16.refs(outputs)
    at = {n: i for i, n in enumerate(outputs)}
    reads = [at[n] for n in PID_READS]
    pid_in = pid.refs(PID_READS + list(SETPOINTS_DEG))
    pid_out = pid.refs(SURFACES)
    f16_in = f16.refs(SURFACES + ["throttle_cmd"])
    setpoints = list(SETPOINTS_DEG.values())
    y = plant.getReal(out_vrs)
    applied = [y[at[n]] for n in ("aileron_deg", "elevator_deg", "rudder_deg", "throttle")]
    pending = deque()
    rows = []
    dt_s = f16.dt_s
    for k in range(ticks + 1):
        rows.append(y)
        law.setReal(pid_in, [y[i] for i in reads] + setpoints)
        law.doStep(currentCommunicationPoint=k * dt_s, communicationStepSize=dt_s)
        pending.append(law.getReal(pid_out) + [y[at["throttle"]]])
        if len(pending) > DELAY_TICKS:
            applied = pending.popleft()
        if k == ticks:
            break  # the last sample is taken: a further step changes no figure
        plant.setReal(f16_in, applied)
        plant.doStep(currentCommunicationPoint=k * dt_s, communicationStepSize=dt_s)
        y = plant.getReal(out_vrs)
    for slave in (plant, law):
        slave.terminate()
        slave.freeInstance()
    final = rows[-1]
    return [final[at["phi_deg"]] - setpoints[0], final[at["theta_deg"]] - setpoints[1],
            final[at["psi_deg"]] - setpoints[2], max(r[at["alpha_deg"]] for r in rows)]


def main():
    if len(sys.argv) not in (5, 6):
        sys.exit("usage: fmpy_campaign.py F16.fmu PID.fmu CASES.csv OUT.csv [N]")
    f16, pid = Model(sys.argv[1], "f16"), Model(sys.argv[2], "pid")
    with open(sys.argv[3]) as f:
        cases = list(csv.DictReader(f))
    if len(sys.argv) == 6:
        cases = cases[: int(sys.argv[5])]
    ticks = round(float(f16.md.defaultExperiment.stopTime) / f16.dt_s)
    with open(sys.argv[4], "w") as f:
        f.write(",".join(["index"] + FIGURES) + "\n")
        for case in cases:
            figures = fly(f16, pid, case_parameters(f16, case), ticks)
            f.write(",".join([case["index"]] + [repr(v) for v in figures]) + "\n")
    print(f"flew {len(cases)} cases of {ticks} ticks")


if __name__ == "__main__":
    main()
