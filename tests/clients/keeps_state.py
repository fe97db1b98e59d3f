"""The Python PID example, keeping state from one flight to the next against the contract, for tests/sweep_warm.rs:
each flight its process starts adds 0.01 deg to its aileron command, counted in the file FILE (a fork starts every
warm flight afresh in memory, so a program that keeps state across flights keeps it outside, as this one does). A
warm sweep must see its rig's first case flown a second time differently, say so and fly the rest cold.

    python3 keeps_state.py FILE
"""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

from pid_attitude import PidAttitude  # noqa: E402
from silrig_client import serve  # noqa: E402


class KeepsState(PidAttitude):
    def __init__(self, path):
        super().__init__()
        self.path = pathlib.Path(path)
        self.flights = None

    def start(self, session):
        super().start(session)
        self.flights = int(self.path.read_text()) if self.path.exists() else 0
        self.path.write_text(str(self.flights + 1))

    def step(self, sample, dt_s):
        surfaces, errors = super().step(sample, dt_s)
        surfaces[self.names[0]] += 0.01 * self.flights
        return surfaces, errors


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(serve(KeepsState(sys.argv[1])))
