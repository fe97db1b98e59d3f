"""A plant of your own in Python: the "bring your own plant" example. Three decoupled rotational axes (roll, pitch,
yaw), each a damped double integrator driven by its surface, with the F-16's sign convention (a positive deflection
makes a negative moment) and the F-16's signal names, so the example PID flies it unchanged. It reports each
surface's position (the output named in the sixth field of its input), so a controller joining a flying plant
starts from where the surfaces are, and it keeps checkpoints (`save`, `restore`), so a restarted plant goes on with
the flight. The scenario's `[plant.parameters]` may set its gain and damping (`gain_dps2_per_deg`, `damping_per_s`,
as examples/c/toy_plant.c) and its start values by signal name (`phi_deg`, `theta_deg`, `psi_deg`; default 0), so a
sweep disperses them as `plant.parameters.<name>`.

    silrig run --plant-cmd "python3 examples/python/toy_plant.py" \\
        --controller-cmd "python3 examples/python/pid_attitude.py" tests/scenarios/toy.toml
"""

import json
import sys

from silrig_client import PlantModel, plant_parameter, serve_plant

GAIN = 4.0  # deg/s^2 of angular acceleration per deg of surface
DAMPING = 1.0  # 1/s
ANGLES = ["phi_deg", "theta_deg", "psi_deg"]


class Toy(PlantModel):
    name = "toy"
    # (name, unit)
    outputs = [("phi_deg", "deg"), ("theta_deg", "deg"), ("psi_deg", "deg"), ("p_dps", "deg/s"),
               ("q_dps", "deg/s"), ("r_dps", "deg/s"), ("aileron_deg", "deg"), ("elevator_deg", "deg"),
               ("rudder_deg", "deg")]
    # (name, unit, min, max, what the failsafe holds, the output reporting its position)
    inputs = [("aileron", "deg", -30.0, 30.0, 0.0, "aileron_deg"), ("elevator", "deg", -30.0, 30.0, 0.0,
              "elevator_deg"), ("rudder", "deg", -30.0, 30.0, 0.0, "rudder_deg")]

    def __init__(self):
        self.gain = plant_parameter("gain_dps2_per_deg", GAIN)
        self.damping = plant_parameter("damping_per_s", DAMPING)
        self.angle = [plant_parameter(name, 0.0) for name in ANGLES]
        self.rate = [0.0, 0.0, 0.0]
        self.surface = [0.0, 0.0, 0.0]
        self.tick = 0

    def outputs_now(self):
        return self.angle + self.rate + self.surface

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
    sys.exit(serve_plant(Toy()))
