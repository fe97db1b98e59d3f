"""A plant of our own for tests/plants.rs: three decoupled rotational axes (roll, pitch, yaw), each a damped
double integrator driven by its surface, with the F-16's sign convention (a positive deflection makes a negative
moment) and the F-16's signal names, so the example PID flies it unchanged.

    python3 toy_plant.py [MODE]     MODE: ok (default), nan (output phi_deg is NaN at ticks 300..=309),
                                    degraded (phi_deg is NaN from tick 334 on: two thirds of a 10 s run),
                                    twice (announces phi_deg twice), none (announces no outputs)

It keeps checkpoints (`save`, `restore`), so a restarted toy goes on with the flight. The scenario's
`[plant.parameters]` may set its gain and damping (`gain_dps2_per_deg`, `damping_per_s`, as examples/c/toy_plant.c)
and its start values by signal name (`phi_deg`, `theta_deg`, `psi_deg`; default 0), so a sweep disperses them as
`plant.parameters.<name>`.
"""

import json
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

from silrig_client import PlantModel, plant_parameter, serve_plant  # noqa: E402

GAIN = 4.0  # deg/s^2 of angular acceleration per deg of surface
DAMPING = 1.0  # 1/s
ANGLES = ["phi_deg", "theta_deg", "psi_deg"]


class Toy(PlantModel):
    name = "toy"
    outputs = [("phi_deg", "deg"), ("theta_deg", "deg"), ("psi_deg", "deg"), ("p_dps", "deg/s"),
               ("q_dps", "deg/s"), ("r_dps", "deg/s"), ("aileron_deg", "deg"), ("elevator_deg", "deg"),
               ("rudder_deg", "deg")]
    inputs = [("aileron", "deg", -30.0, 30.0, 0.0, "aileron_deg"), ("elevator", "deg", -30.0, 30.0, 0.0,
              "elevator_deg"), ("rudder", "deg", -30.0, 30.0, 0.0, "rudder_deg")]

    def __init__(self, mode):
        self.mode = mode
        self.gain = plant_parameter("gain_dps2_per_deg", GAIN)
        self.damping = plant_parameter("damping_per_s", DAMPING)
        self.angle = [plant_parameter(name, 0.0) for name in ANGLES]
        self.rate = [0.0, 0.0, 0.0]
        self.surface = [0.0, 0.0, 0.0]
        self.tick = 0
        if mode == "twice":
            self.outputs = self.outputs + [("phi_deg", "deg")]
        if mode == "none":
            self.outputs = []
            self.inputs = [entry[:5] for entry in self.inputs]

    def outputs_now(self):
        out = self.angle + self.rate + self.surface
        if (self.mode == "nan" and 300 <= self.tick <= 309) or (self.mode == "degraded" and self.tick >= 334):
            out[0] = math.nan
        return out

    def step(self, inputs, dt_s):
        self.surface = list(inputs)
        for c in range(3):
            accel = -self.gain * inputs[c] - self.damping * self.rate[c]
            self.rate[c] += accel * dt_s
            self.angle[c] += self.rate[c] * dt_s
        self.tick += 1

    def save(self):
        return json.dumps({"angle": self.angle, "rate": self.rate, "surface": self.surface, "tick": self.tick})

    def restore(self, text):
        state = json.loads(text)
        self.angle, self.rate, self.surface, self.tick = state["angle"], state["rate"], state["surface"], state["tick"]


if __name__ == "__main__":
    sys.exit(serve_plant(Toy(sys.argv[1] if len(sys.argv) > 1 else "ok")))
