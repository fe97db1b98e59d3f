"""A controller for the FMU tests: commands each named input to a constant from the command line
(`hold_inputs.py u=1.0`) every tick, so a plant's open-loop response can be checked against its equations."""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python"))
from silrig_client import Controller, serve  # noqa: E402


class HoldInputs(Controller):
    def __init__(self, commands):
        self.commands = commands

    def start(self, session):
        for name in self.commands:
            session.input(name)  # fails now, naming the plant's inputs, if one is missing

    def step(self, sample, dt_s):
        return dict(self.commands)


if __name__ == "__main__":
    pairs = [arg.split("=", 1) for arg in sys.argv[1:]]
    sys.exit(serve(HoldInputs({name: float(value) for name, value in pairs})))
