"""Controllers that misbehave on purpose, for tests/clients.rs: each mode breaks one rule of the contract.

    python3 misbehaving.py MODE     (the SILRIG_* variables and SILRIG_CLIENT_LIB come from the test)

layout       opens with another layout version                  -> ERR_LAYOUT, exit 2
size         opens with a plant sample size off by 8 bytes      -> ERR_LAYOUT, exit 2
open         only opens a session (a second controller)          -> exit 2 with the error
nan          sends a NaN aileron for ticks 100..=149, else holds every input where it is
never        takes samples and never answers (no rig: ERR_NO_RIG, exit 2)
missing      asks for an output the F-16 does not have, `theta`  -> ERR_PLANT naming its outputs, exit 2
"""

import ctypes
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))

import silrig_client  # noqa: E402
from silrig_contract import WIRE_LAYOUT_VERSION, CommandSample, PlantSample  # noqa: E402


def raw_open(layout_version, plant_size):
    lib = silrig_client.library()
    handle = ctypes.c_void_p()
    code = lib.silrig_session_open(layout_version, plant_size, ctypes.sizeof(CommandSample), None, 0,
                                   ctypes.byref(handle))
    print(f"status {code}: {lib.silrig_last_error().decode()}", file=sys.stderr)
    return 2 if code < 0 else 0


def main(mode):
    if mode == "layout":
        return raw_open(WIRE_LAYOUT_VERSION + 7, ctypes.sizeof(PlantSample))
    if mode == "size":
        return raw_open(WIRE_LAYOUT_VERSION, ctypes.sizeof(PlantSample) - 8)
    try:
        with silrig_client.Session() as session:
            if mode == "open":
                return 0
            if mode == "missing":
                session.output("theta")
            hold = None
            while (sample := session.next_sample()) is not None:
                if mode == "never":
                    continue
                hold = hold or session.held_command()
                command = list(hold)
                if 100 <= sample.header.tick <= 149:
                    command[session.input("aileron")] = math.nan
                session.send(command)
    except silrig_client.SilrigError as e:
        print(f"status {e.code}: {e}", file=sys.stderr)
        return 2
    return 0

if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
