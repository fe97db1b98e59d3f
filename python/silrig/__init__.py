"""silrig: fly your controller or your plant in the silrig software-in-the-loop rig, and run its simulator and
sweeps, from Python. Natively: the rig's own sessions and tools, compiled in (`pip install ./python` from a silrig
checkout); no ctypes, no library path to set.

Your controller: a `Controller` with one method, `step(sample, dt_s)`, handed to `serve()`. Read an output by name
(`sample["theta_deg"]`), command inputs with a dict; an input you leave out stays where its actuator is. For the
F-16 (Stevens & Lewis), a positive elevator pitches the nose down:

    import silrig

    class Hold(silrig.Controller):
        def start(self, session):
            self.theta_deg = session.setpoint("theta_deg")

        def step(self, sample, dt_s):
            error_deg = sample["theta_deg"] - self.theta_deg
            return {"elevator": -2.0 + 2.0 * error_deg + 1.0 * sample["q_dps"]}

    if __name__ == "__main__":
        raise SystemExit(silrig.serve(Hold()))

flown with `silrig run --controller-cmd "python3 my_controller.py"`, or in this process with
`silrig.sim(scenario, controller=Hold())`. Your plant: a `PlantModel` handed to `serve_plant()`, flown with
`silrig run --plant-cmd "python3 my_plant.py"`. In a notebook: `silrig.sim()` flies a scenario's closed loop in this
process and returns its trace as columns; `silrig.sweep(scenario, runs=...)` flies a Monte Carlo campaign and
returns its case table.

The API is that of the ctypes module examples/python/silrig_client.py (for those who cannot build this package): a
controller or model written for one runs with the other by changing its import.
"""

from typing import Any, Dict, Optional, Sequence, Tuple, Union

from ._native import (
    ERR_COMMAND_REFUSED,
    ERR_INTERNAL,
    ERR_LAYOUT,
    ERR_NO_RIG,
    ERR_PLANT,
    ERR_SECOND_CONTROLLER,
    ERR_SETUP,
    ERR_TRANSPORT,
    ERR_USAGE,
    MAX_INPUTS,
    MAX_OUTPUTS,
    NOT_GIVEN,
    OK,
    RUN_ENDED,
    STOPPED,
    WIRE_LAYOUT_VERSION,
    ControllerSession,
    InProcessSession,
    Plant,
    PlantSession,
    Sample,
    SilrigError,
    plant_parameter,
    serve,
    serve_plant,
    sim,
    sweep,
)

#: The ctypes module's name for the controller session.
Session = ControllerSession

__all__ = [
    "Controller",
    "ControllerSession",
    "InProcessSession",
    "Plant",
    "PlantModel",
    "PlantSession",
    "Sample",
    "Session",
    "SilrigError",
    "plant_parameter",
    "serve",
    "serve_plant",
    "sim",
    "sweep",
    "OK",
    "STOPPED",
    "RUN_ENDED",
    "NOT_GIVEN",
    "ERR_USAGE",
    "ERR_LAYOUT",
    "ERR_SETUP",
    "ERR_NO_RIG",
    "ERR_SECOND_CONTROLLER",
    "ERR_COMMAND_REFUSED",
    "ERR_TRANSPORT",
    "ERR_INTERNAL",
    "ERR_PLANT",
    "WIRE_LAYOUT_VERSION",
    "MAX_INPUTS",
    "MAX_OUTPUTS",
]

Commands = Dict[str, float]


class Controller:
    """A controller for `serve()`: override `step`; the rest is optional."""

    #: Names of the diagnostics `step` returns (logged and plotted by the rig), 1..31 of [A-Za-z0-9_] each.
    diagnostic_names: Sequence[str] = ()

    def start(self, session: ControllerSession) -> None:
        """Called once the session is open (read `session.setpoint(name)`, `session.dt_s`, `session.plant` here;
        `session.output(name)` fails early, naming the plant's outputs, when a signal you need is missing). The
        session is a `ControllerSession` under the rig, an `InProcessSession` under `sim` and `sweep`."""

    def step(self, sample: Sample, dt_s: float) -> Union[Commands, Tuple[Commands, Sequence[float]]]:
        """One plant sample in (read it by name: `sample["theta_deg"]`); out, a dict of commands by input name
        (inputs left out stay where they are), or `(commands, diagnostics)`."""
        raise NotImplementedError

    def checkpoint(self) -> Optional[str]:
        """The state a restarted controller should resume from, as text (None: nothing to save)."""
        return None

    def restore(self, text: str) -> bool:
        """Resume from what `checkpoint` saved; return False if it does not fit."""
        return False


class PlantModel:
    """A vehicle model for `serve_plant()`. Set `name`, `outputs` and `inputs`; implement `outputs_now` and `step`.

    outputs: [(name, unit)] or [(name, unit, in_trace)], in the order `outputs_now` returns them.
    inputs: [(name, unit, min, max, hold)] or with a sixth item, the name of the output that reports the
      actuator's position (the controller's session blends from it after a restart; the trace shows it after the
      commands); `hold` is what the rig's failsafe commands while no controller answers.
    """

    name: str = "plant"
    outputs: Sequence[Tuple[Any, ...]] = ()
    inputs: Sequence[Tuple[Any, ...]] = ()

    def start(self, dt_s: float) -> None:
        """Called once the session is open, with the run's step, s."""

    def outputs_now(self) -> Sequence[float]:
        """The outputs at this tick, one float per entry of `outputs`."""
        raise NotImplementedError

    def step(self, inputs: Sequence[float], dt_s: float) -> None:
        """Advance the model by one period with these inputs (one float per entry of `inputs`)."""
        raise NotImplementedError

    def save(self) -> Optional[str]:
        """The model's state as text, for a plant the launcher restarts (realtime); None: keep no checkpoint (a
        restarted plant then flies again from tick 0)."""
        return None

    def restore(self, text: str) -> None:
        """Take back the state `save` returned; raise to refuse it (the flight then starts again from tick 0)."""
        raise NotImplementedError("this model keeps no checkpoint")
