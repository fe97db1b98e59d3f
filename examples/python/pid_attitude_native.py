"""pid_attitude.py's PID controller flown through the `silrig` package (`pip install ./python`): natively, with no
ctypes and no library path. The controller class is the same; only what flies it changed, which for a controller
of your own is one line: `from silrig import Controller, serve` in place of `from silrig_client import ...`.

    python3 -m venv venv && venv/bin/pip install ./python
    silrig run --controller-cmd "venv/bin/python3 examples/python/pid_attitude_native.py" configs/robust.toml
"""

import sys

import silrig
from pid_attitude import PidAttitude

if __name__ == "__main__":
    sys.exit(silrig.serve(PidAttitude()))
