"""The Python PID example with one fault injected, for tests/check.rs: `silrig check` must fail the criteria the
fault breaks, and only those.

    python3 faulty_pid.py nan      every 100th tick (100, 200, ...) the aileron command is NaN
    python3 faulty_pid.py slow     every tick takes 15 ms of compute (1.5 periods at 100 Hz)
"""

import math
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

from pid_attitude import PidAttitude  # noqa: E402
from silrig_client import serve  # noqa: E402


class FaultyPid(PidAttitude):
    def __init__(self, fault):
        super().__init__()
        self.fault = fault

    def step(self, sample, dt_s):
        commands, diagnostics = super().step(sample, dt_s)
        tick = sample.tick
        if self.fault == "nan" and tick > 0 and tick % 100 == 0:
            commands["aileron"] = math.nan
        if self.fault == "slow":
            time.sleep(0.015)
        return commands, diagnostics


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ("nan", "slow"):
        sys.exit(__doc__)
    sys.exit(serve(FaultyPid(sys.argv[1])))
