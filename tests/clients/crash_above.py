"""The Python PID example, crashing in some cases of a sweep, for tests/sweep_rig.rs: a sweep must fail those cases
with the rig's reason and fly the others.

    python3 crash_above.py THETA_DEG    exits with status 3 at tick 50 when the theta set point is above THETA_DEG
"""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

from pid_attitude import PidAttitude  # noqa: E402
from silrig_client import serve  # noqa: E402


class CrashAbove(PidAttitude):
    def __init__(self, threshold_deg):
        super().__init__()
        self.threshold_deg = threshold_deg

    def step(self, sample, dt_s):
        theta_sp = self.setpoint_deg[1]
        if sample.tick == 50 and theta_sp > self.threshold_deg:
            print(f"crash_above: theta set point {theta_sp:.2f} deg is above {self.threshold_deg} deg", file=sys.stderr)
            sys.exit(3)
        return super().step(sample, dt_s)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(serve(CrashAbove(float(sys.argv[1]))))
