"""A PID attitude controller for silrig, in plain Python: the "bring your own controller" example.

Each channel is a PID on the Euler angle error with the body rate as the derivative: roll (phi) on the
aileron, pitch (theta) on the elevator, yaw (psi) on the rudder. The integrators start from the surfaces' positions
when the controller connects, so taking over is bumpless, and they carry the trim. It reads and commands the
plant's signals by name (a surface as `aileron` or `aileron_deg`); the throttle, which it does not command, stays
where it is.

The gains are tuned per plant (the announced plant name picks them): for the F-16 in deg of surface per deg of
error (per deg/s of rate, per deg*s of integral), with the Stevens & Lewis sign convention (a positive deflection
of any surface makes a negative moment, hence the minus signs); for JSBSim's Cessna 172 (c172x, through
examples/python/jsbsim_plant.py) in JSBSim's normalized commands per deg, whose aileron rolls right when positive.

    silrig run --controller-cmd "python3 examples/python/pid_attitude.py" configs/robust.toml
"""

import json
import math
import sys

from silrig_client import Controller, serve

# Per plant: KP (per deg), KD (per deg/s), KI (per deg*s) and the travel each command is kept within, each for
# (aileron, elevator, rudder).
F16 = ((2.0, 4.0, 8.0), (0.6, 1.5, 3.0), (1.5, 3.0, 8.0), (21.5, 25.0, 30.0))  # deg of surface
C172 = ((-0.04, 0.15, 0.3), (-0.02, 0.05, 0.15), (-0.02, 0.08, 0.1), (1.0, 1.0, 1.0))  # normalized command
GAINS = {"f16": F16, "c172x": C172}
ANGLES = ("phi_deg", "theta_deg", "psi_deg")
RATES = ("p_dps", "q_dps", "r_dps")
INPUTS = ("aileron", "elevator", "rudder")


class PidAttitude(Controller):
    diagnostic_names = ("err_phi_deg", "err_theta_deg", "err_psi_deg")

    def __init__(self):
        self.setpoint_deg = (0.0, 0.0, 0.0)
        self.integral = None  # the command carried by the integrators, per channel
        self.gains = F16
        self.names = INPUTS  # the plant's names of the three surfaces
        self.session = None

    def start(self, session):
        self.setpoint_deg = tuple(session.setpoint(name) for name in ANGLES)
        self.session = session
        plant = session.plant
        # Each surface by its name, or by its name and unit (`aileron_deg`), as tools outside silrig name them.
        have = [name for name, *_ in plant.inputs]
        self.names = [name + "_deg" if name not in have and name + "_deg" in have else name for name in INPUTS]
        # A plant of the F-16's kind (surfaces in deg) flies with its gains; any other needs a tuning of its own.
        degrees = all(unit == "deg" for name, unit, *_ in plant.inputs if name in self.names)
        if plant.name not in GAINS and not degrees:
            raise SystemExit(f"pid_attitude: no gains for plant {plant.name}; tuned for: {', '.join(GAINS)}")
        self.gains = GAINS.get(plant.name, F16)
        # Fail now, naming what the plant has, if it lacks a signal this law needs.
        for name in ANGLES + RATES:
            session.output(name)
        self.inputs = [session.input(name) for name in self.names]

    def step(self, sample, dt_s):
        KP, KD, KI, TRAVEL = self.gains
        if self.integral is None:
            held = self.session.held_command()
            self.integral = [held[k] for k in self.inputs]
        surfaces = [0.0, 0.0, 0.0]
        errors = [0.0, 0.0, 0.0]
        # The set points in force at this sample (a scenario's [[setpoint_steps]] change them during the run).
        self.setpoint_deg = tuple(self.session.setpoint(name, t_s=sample.t_s) for name in ANGLES)
        for c in range(3):
            error = self.setpoint_deg[c] - sample[ANGLES[c]]
            rate = sample[RATES[c]]
            integral = self.integral[c] - KI[c] * error * dt_s
            command = integral - KP[c] * error + KD[c] * rate
            # Anti-windup: an integrator pushing a surface past its travel stops integrating, and the command
            # stays within the travel.
            if abs(command) <= TRAVEL[c] or abs(integral) < abs(self.integral[c]):
                self.integral[c] = integral
            surfaces[c] = max(-TRAVEL[c], min(TRAVEL[c], self.integral[c] - KP[c] * error + KD[c] * rate))
            errors[c] = error
        return dict(zip(self.names, surfaces)), errors

    def checkpoint(self):
        return json.dumps(self.integral)

    def restore(self, text):
        # Three finite integrators within the widest travel of any tuning (the plant is not known yet), or the text
        # is not a checkpoint of ours.
        try:
            integral = [float(x) for x in json.loads(text)]
        except (ValueError, TypeError):
            return False
        widest = [max(g[3][c] for g in GAINS.values()) for c in range(3)]
        if len(integral) != 3 or not all(math.isfinite(x) and abs(x) <= t for x, t in zip(integral, widest)):
            return False
        self.integral = integral
        return True


if __name__ == "__main__":
    sys.exit(serve(PidAttitude()))
