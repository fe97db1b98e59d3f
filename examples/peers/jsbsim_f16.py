"""Peers, part 2: JSBSim's F-16 (aircraft/f16 of the `jsbsim` PyPI package) trimmed at the flight condition of
`silrig bench` (150 m/s, 25,000 ft, wings level) and stepped open loop from that trim at the rig's step, 0.01 s,
timed as `silrig bench` times our model: batches of steps after one warm-up batch, the median of the batches'
per-step means.

    jsbsim_f16.py trim                trim and print what it trimmed to, and how far the trimmed flight drifts in
                                      the 10 s after (JSON): what the test checks
    jsbsim_f16.py bench [BATCHES]     trim, then time BATCHES (default 200) batches of 1,000 steps (`FGFDMExec::Run`,
                                      one call a step) and print the figure as `silrig bench` prints its own

Needs `pip install jsbsim` (in target/test-venv). Each `Run` is JSBSim's whole step: the atmosphere, the flight
control system's channels, the F100 engine, the aerodynamic tables, the ground reactions and one integration step
(its default integrators), plus the Python call into the library (about a tenth of a microsecond).
"""

import json
import sys
import time

import jsbsim

DT_S = 0.01
AIRSPEED_MPS = 150.0
ALTITUDE_FT = 25000.0
FT_PER_M = 1.0 / 0.3048
BATCH = 1000


def trimmed():
    """JSBSim's F-16 at the condition, trimmed for steady wings-level flight (JSBSim's own trim, mode 1: full)."""
    jsbsim.FGJSBBase().debug_lvl = 0  # no start-up banner on stdout, which carries the JSON
    fdm = jsbsim.FGFDMExec(None)
    if not fdm.load_model("f16"):
        sys.exit("JSBSim could not load aircraft/f16: is the `jsbsim` package complete?")
    fdm.set_dt(DT_S)
    fdm["ic/h-sl-ft"] = ALTITUDE_FT
    fdm["ic/vt-fps"] = AIRSPEED_MPS * FT_PER_M
    fdm["ic/gamma-deg"] = 0.0
    fdm["ic/phi-deg"] = 0.0
    fdm["ic/psi-true-deg"] = 0.0
    fdm["propulsion/set-running"] = -1
    if not fdm.run_ic():
        sys.exit("JSBSim refused the initial condition")
    fdm["simulation/do_simple_trim"] = 1
    return fdm


def state(fdm):
    return {
        "alpha_deg": fdm["aero/alpha-deg"],
        "theta_deg": fdm["attitude/theta-deg"],
        "elevator_deg": fdm["fcs/elevator-pos-deg"],
        "throttle": fdm["fcs/throttle-cmd-norm"],
        "vt_mps": fdm["velocities/vt-fps"] / FT_PER_M,
        "alt_ft": fdm["position/h-sl-ft"],
    }


# JSBSim's integrators by number (FGPropagate): 1 rectangular Euler, 2 trapezoidal, 3 to 5 Adams-Bashforth of
# order 2 to 4; each takes one derivative evaluation a step, where our RK4 takes four.
INTEGRATORS = {0: "none", 1: "rectangular Euler", 2: "trapezoidal", 3: "Adams-Bashforth 2", 4: "Adams-Bashforth 3",
               5: "Adams-Bashforth 4", 6: "Buss 1", 7: "local linearization", 8: "Buss 2"}


def trim_report():
    fdm = trimmed()
    at_trim = state(fdm)
    model = {"weight_lbs": fdm["inertia/weight-lbs"], "ixx_slugft2": fdm["inertia/ixx-slugs_ft2"],
             "iyy_slugft2": fdm["inertia/iyy-slugs_ft2"], "izz_slugft2": fdm["inertia/izz-slugs_ft2"]}
    for what in ("rate/rotational", "rate/translational", "position/rotational", "position/translational"):
        model["integrator " + what] = INTEGRATORS.get(int(fdm["simulation/integrator/" + what]), "other")
    for _ in range(round(10.0 / DT_S)):
        fdm.run()
    after = state(fdm)
    print(json.dumps({"jsbsim_version": jsbsim.__version__, "dt_s": fdm.get_delta_t(), "model": model,
                      "trim": at_trim, "after_10_s": after}, indent=2))


def bench(batches):
    fdm = trimmed()
    run = fdm.run
    per_step_ns = []
    for b in range(batches + 1):
        start = time.perf_counter_ns()
        for _ in range(BATCH):
            run()
        if b > 0:  # the first batch warms caches up: not counted
            per_step_ns.append((time.perf_counter_ns() - start) / BATCH)
    per_step_ns.sort()
    q = lambda p: per_step_ns[round((len(per_step_ns) - 1) * p)]  # noqa: E731
    # The format of `silrig bench`'s lines, so the two are read side by side.
    print(f"{'JSBSim f16 step (dt 0.01 s)':<28} median {q(0.5):>9.1f} ns   p10 {q(0.1):>9.1f} ns   "
          f"p90 {q(0.9):>9.1f} ns   ({batches} batches of {BATCH})")
    print(f"JSBSim f16: {1e9 / q(0.5):.0f} steps/s median; {fdm['simulation/sim-time-sec']:.1f} s flown")


def main():
    if len(sys.argv) == 2 and sys.argv[1] == "trim":
        trim_report()
    elif len(sys.argv) in (2, 3) and sys.argv[1] == "bench":
        batches = int(sys.argv[2]) if len(sys.argv) == 3 else 200
        if batches < 1:
            sys.exit("BATCHES must be at least 1")
        bench(batches)
    else:
        sys.exit("usage: jsbsim_f16.py trim | bench [BATCHES]")


if __name__ == "__main__":
    main()
