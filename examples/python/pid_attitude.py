"""A PID attitude controller for silrig, in plain Python: the "bring your own controller" example.

Each channel is a PID on the Euler angle error with the body rate as the derivative: roll (phi) on the
aileron, pitch (theta) on the elevator, yaw (psi) on the rudder. The integrators start from the surfaces' positions
when the controller connects, so taking over is bumpless, and they carry the trim. Gains are in deg of surface per
deg of error (per deg/s of rate, per deg*s of integral). The Stevens & Lewis sign convention: a positive
deflection of any surface makes a negative moment, hence the minus signs. It reads and commands the plant's
signals by name; the throttle, which it does not command, stays where it is.

    silrig run --controller-cmd "python3 examples/python/pid_attitude.py" configs/robust.toml
"""

import json
import math
import sys

from silrig_client import Controller, serve

KP = (2.0, 4.0, 8.0)  # deg per deg: aileron, elevator, rudder
KD = (0.6, 1.5, 3.0)  # deg per deg/s
KI = (1.5, 3.0, 8.0)  # deg per deg*s
TRAVEL = (21.5, 25.0, 30.0)  # the F-16's surface travel, deg: aileron, elevator, rudder
ANGLES = ("phi_deg", "theta_deg", "psi_deg")
RATES = ("p_dps", "q_dps", "r_dps")
SURFACES = ("aileron_deg", "elevator_deg", "rudder_deg")  # where the surfaces are now
INPUTS = ("aileron", "elevator", "rudder")


class PidAttitude(Controller):
    diagnostic_names = ("err_phi_deg", "err_theta_deg", "err_psi_deg")

    def __init__(self):
        self.setpoint_deg = (0.0, 0.0, 0.0)
        self.integral = None  # surface deg carried by the integrators, per channel

    def start(self, session):
        self.setpoint_deg = session.setpoint_deg
        # Fail now, naming what the plant has, if it lacks a signal this law needs.
        for name in ANGLES + RATES + SURFACES:
            session.output(name)
        for name in INPUTS:
            session.input(name)

    def step(self, sample, dt_s):
        if self.integral is None:
            self.integral = [sample[s] for s in SURFACES]
        surfaces = [0.0, 0.0, 0.0]
        errors = [0.0, 0.0, 0.0]
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
        return dict(zip(INPUTS, surfaces)), errors

    def checkpoint(self):
        return json.dumps(self.integral)

    def restore(self, text):
        # Three finite integrators within the surfaces' travel, or the text is not a checkpoint of ours.
        try:
            integral = [float(x) for x in json.loads(text)]
        except (ValueError, TypeError):
            return False
        if len(integral) != 3 or not all(math.isfinite(x) and abs(x) <= t for x, t in zip(integral, TRAVEL)):
            return False
        self.integral = integral
        return True


if __name__ == "__main__":
    sys.exit(serve(PidAttitude()))
