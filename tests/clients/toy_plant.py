"""examples/python/toy_plant.py for tests/plants.rs, with ways to break the rules on purpose:

    python3 toy_plant.py [MODE]     MODE: ok (default), nan (output phi_deg is NaN at ticks 300..=309),
                                    degraded (phi_deg is NaN from tick 334 on: two thirds of a 10 s run),
                                    twice (announces phi_deg twice), none (announces no outputs)
"""

import importlib.util
import math
import pathlib
import sys

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"
sys.path.insert(0, str(EXAMPLES))

from silrig_client import serve_plant  # noqa: E402

# The example is loaded by its path under a name of its own: this file is `toy_plant` too, for whoever imports it
# (python/tests/native_toy_plant.py), so `import toy_plant` here would find this file again.
_spec = importlib.util.spec_from_file_location("example_toy_plant", EXAMPLES / "toy_plant.py")
_example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_example)
Toy = _example.Toy


class TestToy(Toy):
    def __init__(self, mode):
        super().__init__()
        self.mode = mode
        if mode == "twice":
            self.outputs = self.outputs + [("phi_deg", "deg")]
        if mode == "none":
            self.outputs = []
            self.inputs = [entry[:5] for entry in self.inputs]

    def outputs_now(self):
        out = super().outputs_now()
        if (self.mode == "nan" and 300 <= self.tick <= 309) or (self.mode == "degraded" and self.tick >= 334):
            out[0] = math.nan
        return out


if __name__ == "__main__":
    sys.exit(serve_plant(TestToy(sys.argv[1] if len(sys.argv) > 1 else "ok")))
