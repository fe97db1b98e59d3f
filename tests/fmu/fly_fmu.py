"""The exported F-16 FMU seen by an independent importer, FMPy (tests/fmu_export.rs runs it in target/test-venv).

    fly_fmu.py validate FMU                     FMPy's validation problems, one a line ("no problems" if none)
    fly_fmu.py fly FMU PARAMS PROGRAM OUT.csv
                                                instantiate, set the parameters by name (PARAMS: "none", or another
                                                FMU whose parameters' start values are copied by name), initialise, then 1000 doSteps of 0.01 s: the inputs held at
                                                the trim command (the actuators' positions the FMU reports at t = 0),
                                                or PROGRAM "doublet" (elevator +-2 deg, then an aileron step); write
                                                every output at t = 0 and after each step, repr() of each double
    fly_fmu.py state FMU                        fmi2GetFMUstate / Serialize / DeSerialize / SetFMUstate: a flight
                                                continued from a saved state, in this instance and in a second one,
                                                must give the same bits as flown on
    fly_fmu.py wrong-guid FMU                   instantiate under another GUID: must be refused
    fly_fmu.py simulate FMU                     fmpy.simulate_fmu over the default experiment; prints the final
                                                theta_deg and alt_ft
"""

import struct
import sys

from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

STEPS = 1000
DT = 0.01
INPUTS = ["aileron", "elevator", "rudder", "throttle_cmd"]


def open_fmu(path, guid=None):
    md = read_model_description(path)
    slave = FMU2Slave(
        guid=guid or md.guid,
        unzipDirectory=extract(path),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="f16",
    )
    return md, slave


def variables(md):
    return {v.name: v for v in md.modelVariables}


def initialise(md, slave, params):
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    by_name = variables(md)
    for name, value in params.items():
        v = by_name[name]
        if v.type == "Boolean":
            slave.setBoolean([v.valueReference], [bool(value)])
        else:
            slave.setReal([v.valueReference], [float(value)])
    slave.exitInitializationMode()


def command(program, trim, k):
    """The inputs over step k (from t = k * DT): the same numbers as tests/fmu_export.rs computes."""
    c = list(trim)
    if program == "doublet":
        if 100 <= k < 200:
            c[1] = trim[1] + 2.0
        elif 200 <= k < 300:
            c[1] = trim[1] - 2.0
        if k >= 400:
            c[0] = trim[0] + 5.0
    return c


def fly(md, slave, program, steps, start=0, trim=None):
    """Outputs at the current point, then after each of `steps` doSteps; the trim command is read at t = 0."""
    by_name = variables(md)
    out_vrs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    in_vrs = [by_name[n].valueReference for n in INPUTS]
    if trim is None:
        trim = slave.getReal([by_name[n].valueReference for n in ["aileron_deg", "elevator_deg", "rudder_deg", "throttle"]])
    rows = [slave.getReal(out_vrs)]
    for k in range(start, start + steps):
        slave.setReal(in_vrs, command(program, trim, k))
        slave.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
        rows.append(slave.getReal(out_vrs))
    return rows, trim


def bits(rows):
    return [struct.pack("<%dd" % len(r), *r) for r in rows]


def main():
    what, path = sys.argv[1], sys.argv[2]
    if what == "validate":
        problems = validate_fmu(path)
        print("\n".join(problems) if problems else "no problems")
    elif what == "fly":
        params, program, out = {}, sys.argv[4], sys.argv[5]
        if sys.argv[3] != "none":
            for v in read_model_description(sys.argv[3]).modelVariables:
                if v.causality == "parameter":
                    params[v.name] = v.start in ("true", "1", True) if v.type == "Boolean" else float(v.start)
        md, slave = open_fmu(path)
        initialise(md, slave, params)
        rows, _ = fly(md, slave, program, STEPS)
        slave.terminate()
        slave.freeInstance()
        names = [v.name for v in md.modelVariables if v.causality == "output"]
        with open(out, "w") as f:
            f.write(",".join(names) + "\n")
            for r in rows:
                f.write(",".join(repr(x) for x in r) + "\n")
        print(f"{len(rows)} rows")
    elif what == "state":
        md, a = open_fmu(path)
        initialise(md, a, {})
        _, trim = fly(md, a, "doublet", 150)
        saved = a.getFMUstate()
        data = a.serializeFMUstate(saved)
        flown_on, _ = fly(md, a, "doublet", 300, start=150, trim=trim)
        # The same instance, back to the saved state.
        a.setFMUstate(saved)
        again, _ = fly(md, a, "doublet", 300, start=150, trim=trim)
        # The same instance, from the serialised bytes.
        read = a.deSerializeFMUstate(data)
        a.setFMUstate(read)
        from_bytes, _ = fly(md, a, "doublet", 300, start=150, trim=trim)
        # A second instance (a restarted plant) from the bytes.
        md2, b = open_fmu(path)
        initialise(md2, b, {})
        b.setFMUstate(b.deSerializeFMUstate(data))
        restarted, _ = fly(md2, b, "doublet", 300, start=150, trim=trim)
        for state in (saved, read):
            a.freeFMUstate(state)
        moved = sum(1 for x, y in zip(flown_on[0], flown_on[-1]) if x != y)
        for name, rows in [("setFMUstate", again), ("deserialised", from_bytes), ("second instance", restarted)]:
            same = bits(rows) == bits(flown_on)
            print(f"{name}: {'bit-identical' if same else 'DIFFERENT'} over {len(rows)} samples")
        print(f"serialised state: {len(data)} bytes; outputs that moved over the 3 s: {moved}")
    elif what == "wrong-guid":
        md, slave = open_fmu(path, guid="{00000000-0000-0000-0000-000000000000}")
        try:
            slave.instantiate()
            print("instantiated")
        except Exception as e:
            print(f"refused: {e}")
    elif what == "simulate":
        result = simulate_fmu(path, output=["theta_deg", "alt_ft"])
        print(f"{len(result)} samples; final theta_deg {result['theta_deg'][-1]!r} alt_ft {result['alt_ft'][-1]!r}")


if __name__ == "__main__":
    main()
