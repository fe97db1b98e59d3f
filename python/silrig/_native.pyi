"""Type hints of silrig._native, the compiled half of the package (python/src/*.rs); `silrig` re-exports it."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, TypedDict, Union

OK: int
STOPPED: int
RUN_ENDED: int
NOT_GIVEN: int
ERR_USAGE: int
ERR_LAYOUT: int
ERR_SETUP: int
ERR_NO_RIG: int
ERR_SECOND_CONTROLLER: int
ERR_COMMAND_REFUSED: int
ERR_TRANSPORT: int
ERR_INTERNAL: int
ERR_PLANT: int
WIRE_LAYOUT_VERSION: int
MAX_INPUTS: int
MAX_OUTPUTS: int

class SilrigError(RuntimeError):
    """The rig refused a call or failed; `code` is one of the contract's status codes (silrig.ERR_*)."""

    code: int

class Plant:
    """What the plant announced: its name and signals, and where each is by name."""

    @property
    def name(self) -> str: ...
    @property
    def outputs(self) -> List[Tuple[str, str]]:
        """(name, unit) per output, in the order of every sample's outputs."""
    @property
    def inputs(self) -> List[Tuple[str, str, float, float, float]]:
        """(name, unit, min, max, hold) per input, in the order a command gives them."""
    @property
    def output_index(self) -> Dict[str, int]: ...
    @property
    def input_index(self) -> Dict[str, int]: ...

class Sample:
    """One plant sample: `sample["theta_deg"]` or `sample[3]`; `tick`, `t_s`, `outputs` beside."""

    @property
    def tick(self) -> int: ...
    @property
    def t_s(self) -> float: ...
    @property
    def outputs(self) -> List[float]: ...
    def __getitem__(self, key: Union[str, int]) -> float: ...
    def __len__(self) -> int: ...

class ControllerSession:
    """The controller's side of one run, opened from the SILRIG_* variables the launcher sets."""

    stop_reason: Optional[int]
    def __init__(self, diagnostic_names: Sequence[str] = ...) -> None: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def setpoint_deg(self) -> Tuple[float, float, float]: ...
    def setpoint(self, name: str, default: Optional[float] = None) -> Optional[float]: ...
    @property
    def plant(self) -> Plant: ...
    def output(self, name: str) -> int: ...
    def input(self, name: str) -> int: ...
    def held_command(self) -> List[float]: ...
    @property
    def restored_checkpoint(self) -> Optional[str]: ...
    def next_sample(self) -> Optional[Sample]: ...
    def send(self, inputs: Sequence[float], diagnostics: Sequence[float] = ...) -> bool: ...
    def checkpoint_used(self, used: bool, reason: Optional[str] = None) -> None: ...
    def checkpoint_due(self) -> bool: ...
    def save_checkpoint(self, text: str) -> None: ...
    def close(self, error: Optional[object] = None) -> None: ...
    def __enter__(self) -> "ControllerSession": ...
    def __exit__(self, kind: Any = None, value: Any = None, traceback: Any = None) -> bool: ...

class InProcessSession:
    """What a controller's `start` is handed when `sim` or `sweep` flies it in this process."""

    @property
    def dt_s(self) -> float: ...
    @property
    def setpoint_deg(self) -> Tuple[float, float, float]: ...
    def setpoint(self, name: str, default: Optional[float] = None) -> Optional[float]: ...
    @property
    def plant(self) -> Plant: ...
    def output(self, name: str) -> int: ...
    def input(self, name: str) -> int: ...
    def held_command(self) -> List[float]: ...

def serve(controller: Any) -> int:
    """Fly `controller` until the run ends or SIGTERM; 0 at the end, 2 when the session could not open."""

class PlantSession:
    """The plant's side of one run, announcing a PlantModel's signals."""

    stop_reason: Optional[int]
    def __init__(self, model: Any) -> None: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def restored_checkpoint(self) -> Optional[str]: ...
    def checkpoint_used(self, used: bool, reason: Optional[str] = None) -> None: ...
    @property
    def checkpoint_due(self) -> bool: ...
    def save_checkpoint(self, text: str) -> None: ...
    def tick(self, outputs: Sequence[float]) -> Optional[List[float]]: ...
    def close(self, error: Optional[object] = None) -> None: ...
    def __enter__(self) -> "PlantSession": ...
    def __exit__(self, kind: Any = None, value: Any = None, traceback: Any = None) -> bool: ...

def plant_parameter(name: str, default: Optional[float] = None) -> Optional[float]:
    """The run's [plant.parameters] value of `name`, or `default`."""

def serve_plant(model: Any) -> int:
    """Fly `model` as the run's plant until the run ends or SIGTERM; 0 at the end, 2 when it could not open."""

# A column: a list of floats, or a NumPy float64 array with numpy=True.
Column = Any
Scenario = Union[str, "os.PathLike[str]", None]

class EndedEarly(TypedDict):
    t_s: float
    reason: str

class SimResult(TypedDict):
    trace: Dict[str, Column]
    summary: Dict[str, Any]
    ended_early: Optional[EndedEarly]
    refusals: List[str]

class SweepResult(TypedDict):
    cases: Dict[str, Column]
    summary: Dict[str, Any]
    fly_s: float
    jobs: int

def sim(scenario: Scenario = None, *, controller: Any = None, numpy: bool = False) -> SimResult:
    """Fly a scenario's closed loop in this process, as `silrig sim` does (with `controller`, that controller in
    place of the scenario's, as the lockstep rig flies it); trace and summary."""

def sweep(
    scenario: Scenario,
    runs: int,
    *,
    seed: Optional[int] = None,
    jobs: Optional[int] = None,
    controller: Any = None,
    numpy: bool = False,
) -> SweepResult:
    """Fly a Monte Carlo campaign in this process, as `silrig sweep` does (with `controller`, a copy of it per
    case); case table and summary."""
