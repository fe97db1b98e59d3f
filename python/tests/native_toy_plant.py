"""tests/clients/toy_plant.py's model, written against the ctypes module, flown through the package's
`serve_plant`, in the modes that break the rules on purpose (the template that flies is
examples/python/toy_plant_native.py).

    python3 native_toy_plant.py [MODE]     MODE as toy_plant.py's: ok, nan, twice, none
"""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tests" / "clients"))

import silrig  # noqa: E402
from toy_plant import TestToy  # noqa: E402

if __name__ == "__main__":
    sys.exit(silrig.serve_plant(TestToy(sys.argv[1] if len(sys.argv) > 1 else "ok")))
