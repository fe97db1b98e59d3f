"""toy_plant.py's model flown through the `silrig` package (`pip install ./python`): the template for a plant of your
own in Python, natively. The model is the same class, written against the ctypes module's `PlantModel`; here the
package reads its `[plant.parameters]` (`silrig.plant_parameter`) and flies it (`silrig.serve_plant`), with no
library path to set.

    silrig run --mode lockstep --plant-cmd "venv/bin/python3 examples/python/toy_plant_native.py" \\
        --controller-cmd "venv/bin/python3 examples/python/pid_attitude_native.py" tests/scenarios/toy.toml
"""

import sys

import silrig
import toy_plant

if __name__ == "__main__":
    # The parameters through the package rather than the ctypes module's library.
    toy_plant.plant_parameter = silrig.plant_parameter
    sys.exit(silrig.serve_plant(toy_plant.Toy()))
