"""JSBSim's aircraft as silrig's plant: the "bring your own plant" example.

JSBSim (PyPI `jsbsim`, which ships some sixty aircraft) flies one of them, trimmed for steady level flight, at the
rig's rate: each tick the rig hands in the controller's commands, JSBSim integrates one period (4 steps of
2.5 ms), and its outputs go back out by name. The rig keeps the clock, the watchdog and failsafe (the trimmed
commands below), the faults, the logger and the timing report.

    pip install jsbsim
    silrig run --plant-cmd "python3 examples/python/jsbsim_plant.py" \\
        --controller-cmd "python3 examples/python/pid_attitude.py" examples/python/jsbsim_c172.toml

Outputs use the F-16's names where the meaning is the same (phi_deg ... ny_g), then the surfaces' positions as
JSBSim reports them, deg (the aileron: the left one). Inputs are JSBSim's own normalized commands: aileron,
elevator, rudder (-1..1; the elevator's trim stays in JSBSim's pitch trim, so 0 holds the trim) and throttle
(0..1). JSBSim's signs: a positive aileron command rolls right, a positive elevator command pitches the nose down,
a positive rudder command yaws left.

    python3 jsbsim_plant.py [AIRCRAFT]     default: c172x

The trim point comes from the scenario's `[plant.parameters]`: `altitude_ft` (default 4000) and `speed_kt`
(calibrated airspeed, default 100), so a sweep can disperse them as `plant.parameters.altitude_ft`.
"""

import math
import os
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

# JSBSim prints its banner when the first FDM is built, before any debug level can be set on it.
os.environ.setdefault("JSBSIM_DEBUG", "0")

import jsbsim  # noqa: E402

from silrig_client import PlantModel, plant_parameter, serve_plant  # noqa: E402

SUBSTEPS = 4  # JSBSim steps per rig tick: 2.5 ms at 100 Hz, finer than JSBSim's own 1/120 s default
M_PER_FT = 0.3048

# (output name, unit, JSBSim property, scale)
OUTPUTS = [
    ("phi_deg", "deg", "attitude/phi-deg", 1.0),
    ("theta_deg", "deg", "attitude/theta-deg", 1.0),
    ("psi_deg", "deg", "attitude/psi-deg", 1.0),
    ("alpha_deg", "deg", "aero/alpha-deg", 1.0),
    ("beta_deg", "deg", "aero/beta-deg", 1.0),
    ("p_dps", "deg/s", "velocities/p-rad_sec", 180.0 / math.pi),
    ("q_dps", "deg/s", "velocities/q-rad_sec", 180.0 / math.pi),
    ("r_dps", "deg/s", "velocities/r-rad_sec", 180.0 / math.pi),
    ("vt_mps", "m/s", "velocities/vt-fps", M_PER_FT),
    ("alt_ft", "ft", "position/h-sl-ft", 1.0),
    ("nz_g", "g", "accelerations/Nz", 1.0),
    ("ny_g", "g", "accelerations/Ny", 1.0),
    ("aileron_deg", "deg", "fcs/left-aileron-pos-deg", 1.0),
    ("elevator_deg", "deg", "fcs/elevator-pos-deg", 1.0),
    ("rudder_deg", "deg", "fcs/rudder-pos-deg", 1.0),
    ("throttle", "1", "fcs/throttle-pos-norm", 1.0),
]

PSI = [name for name, _, _, _ in OUTPUTS].index("psi_deg")

# (input name, JSBSim command property, min, max)
INPUTS = [
    ("aileron", "fcs/aileron-cmd-norm", -1.0, 1.0),
    ("elevator", "fcs/elevator-cmd-norm", -1.0, 1.0),
    ("rudder", "fcs/rudder-cmd-norm", -1.0, 1.0),
    ("throttle", "fcs/throttle-cmd-norm", 0.0, 1.0),
]


class JsbsimPlant(PlantModel):
    """One JSBSim aircraft, trimmed for steady level flight at the given altitude and calibrated airspeed."""

    def __init__(self, aircraft="c172x", altitude_ft=4000.0, speed_kt=100.0):
        jsbsim.FGJSBBase().debug_lvl = 0  # no banner or chatter on the rig's log
        fdm = jsbsim.FGFDMExec(None)
        fdm.set_debug_level(0)
        if not fdm.load_model(aircraft):
            raise SystemExit(f"jsbsim_plant: JSBSim cannot load aircraft {aircraft!r}")
        # The aircraft may declare file outputs of its own (c172x: JSBout172B.csv in the working folder at 10 Hz),
        # which disable_output() alone does not stop being created: the rig records everything already.
        n = 0
        while n < 64 and fdm.get_output_filename(n):
            fdm.set_output_filename(n, os.devnull)
            n += 1
        fdm.disable_output()
        fdm["ic/h-sl-ft"] = altitude_ft
        fdm["ic/vc-kts"] = speed_kt
        fdm["ic/psi-true-deg"] = 0.0
        fdm["ic/gamma-deg"] = 0.0
        fdm.run_ic()
        fdm["propulsion/set-running"] = -1
        fdm["fcs/mixture-cmd-norm"] = 1.0
        fdm["fcs/throttle-cmd-norm"] = 0.7
        try:
            fdm["simulation/do_simple_trim"] = 1
        except RuntimeError as e:
            raise SystemExit(f"jsbsim_plant: {aircraft} does not trim at {altitude_ft} ft, {speed_kt} kt: {e}")
        self.fdm = fdm
        self.name = aircraft.replace("-", "_")
        self.outputs = [(name, unit) for name, unit, _, _ in OUTPUTS]
        # The failsafe holds the trimmed commands.
        self.inputs = [(name, "1", low, high, fdm[prop]) for name, prop, low, high in INPUTS]

    def start(self, dt_s):
        self.fdm.set_dt(dt_s / SUBSTEPS)

    def outputs_now(self):
        fdm = self.fdm
        out = [fdm[prop] * scale for _, _, prop, scale in OUTPUTS]
        # JSBSim's heading runs 0..360; the rig's angles, as the F-16's, run -180..180.
        out[PSI] = (out[PSI] + 180.0) % 360.0 - 180.0
        return out

    def step(self, inputs, dt_s):
        fdm = self.fdm
        for (_, prop, _, _), value in zip(INPUTS, inputs):
            fdm[prop] = value
        for _ in range(SUBSTEPS):
            fdm.run()


if __name__ == "__main__":
    aircraft = sys.argv[1] if len(sys.argv) > 1 else "c172x"
    altitude_ft = plant_parameter("altitude_ft", 4000.0)
    speed_kt = plant_parameter("speed_kt", 100.0)
    sys.exit(serve_plant(JsbsimPlant(aircraft, altitude_ft, speed_kt)))
