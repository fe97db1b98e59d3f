"""Your controller in process: `silrig.sim(..., controller=...)` flies the example PID, the class `serve()` flies, and
gives the trace the lockstep rig gives for it served with `--controller-cmd`, value for value; `silrig.sweep(...,
controller=...)` flies a fresh copy per case, the same cases on one thread or two; a controller's unknown signal
names and its exceptions are raised to the caller, naming what the plant has."""

import sys

import pytest
import silrig

from conftest import ROOT, assert_same_columns, read_csv_columns, silrig_run

sys.path.insert(0, str(ROOT / "examples" / "python"))
from pid_attitude import PidAttitude  # noqa: E402

SCENARIO = ROOT / "configs" / "robust.toml"
SWEEP = str(ROOT / "configs" / "sweep-robust.toml")


def test_sim_with_your_controller_is_the_lockstep_rigs_trace_value_for_value(tmp_path):
    out = tmp_path / "run"
    controller = f"{sys.executable} {ROOT}/examples/python/pid_attitude_native.py"
    r, _ = silrig_run("inproc", out, ["--mode", "lockstep", "--controller-cmd", controller, str(SCENARIO)])
    assert r.returncode == 0, r.stdout + r.stderr
    rig = read_csv_columns(out / "trace.csv")
    pid = PidAttitude()
    flown = silrig.sim(SCENARIO, controller=pid)
    assert flown["ended_early"] is None and flown["refusals"] == []
    assert list(flown["trace"])[-3:] == ["err_phi_deg", "err_theta_deg", "err_psi_deg"]
    assert_same_columns(flown["trace"], rig)
    # The object handed over is the one that flew: its integrators moved from where the surfaces started.
    assert pid.integral is not None
    # And it is not the scenario's own controller that flew.
    assert flown["trace"]["elevator_cmd_deg"] != silrig.sim(SCENARIO)["trace"]["elevator_cmd_deg"]


def test_the_example_pid_follows_set_point_steps_in_process_and_served_alike(tmp_path):
    # robust.toml (theta 10 deg) with a step of theta to 4 deg at 2 s: both ways of flying read the set point in
    # force at each sample, so each error after 2 s is against 4 deg, and the two traces are equal.
    scenario = tmp_path / "steps.toml"
    scenario.write_text(SCENARIO.read_text() + "\n[[setpoint_steps]]\nat_s = 2.0\ntheta_deg = 4.0\n")
    out = tmp_path / "run"
    controller = f"{sys.executable} {ROOT}/examples/python/pid_attitude_native.py"
    args = ["--mode", "lockstep", "--controller-cmd", controller, str(scenario)]
    r, _ = silrig_run("inproc-steps", out, args)
    assert r.returncode == 0, r.stdout + r.stderr
    rig = read_csv_columns(out / "trace.csv")
    flown = silrig.sim(scenario, controller=PidAttitude())
    assert_same_columns(flown["trace"], rig)
    trace = flown["trace"]
    for t, theta, error in zip(trace["t_s"], trace["theta_deg"], trace["err_theta_deg"]):
        assert error == pytest.approx((10.0 if t < 2.0 - 1e-9 else 4.0) - theta, abs=1e-9), t


def test_sweep_flies_a_fresh_copy_of_your_controller_per_case():
    pid = PidAttitude()
    one = silrig.sweep(SWEEP, runs=3, jobs=1, controller=pid)
    two = silrig.sweep(SWEEP, runs=3, jobs=2, controller=pid)
    # repr: every value to its last digit, and NaN (a figure a case does not have) equal to NaN.
    assert repr(one["cases"]) == repr(two["cases"])
    assert pid.integral is None, "each case flies a copy; the object given stays as it was"
    ours = silrig.sweep(SWEEP, runs=3, jobs=1)
    assert one["cases"]["theta_max_error_deg"] != ours["cases"]["theta_max_error_deg"]
    assert len(one["cases"]["index"]) == 3


class Misspelled(silrig.Controller):
    def step(self, sample, dt_s):
        return {"elevator": -sample["theta_dg"]}


class WrongInput(silrig.Controller):
    def step(self, sample, dt_s):
        return {"elevater": 0.0}


class Raises(silrig.Controller):
    def step(self, sample, dt_s):
        if sample.t_s > 0.5:
            raise ZeroDivisionError("the controller's own bug")
        return {}


def test_an_unknown_output_name_raises_naming_the_plants_outputs():
    with pytest.raises(KeyError) as missing:
        silrig.sim(SCENARIO, controller=Misspelled())
    said = str(missing.value)
    assert "theta_dg" in said and "theta_deg" in said and "q_dps" in said, said


def test_an_unknown_input_name_raises_naming_the_plants_inputs():
    with pytest.raises(silrig.SilrigError) as missing:
        silrig.sim(SCENARIO, controller=WrongInput())
    said = str(missing.value)
    assert missing.value.code == silrig.ERR_PLANT
    assert "elevater" in said and "elevator" in said and "throttle" in said, said


def test_your_controllers_exception_is_raised_to_you():
    with pytest.raises(ZeroDivisionError, match="the controller's own bug"):
        silrig.sim(SCENARIO, controller=Raises())
    with pytest.raises(ZeroDivisionError, match="the controller's own bug"):
        silrig.sweep(SWEEP, runs=2, jobs=2, controller=Raises())


def test_a_controller_without_step_is_refused():
    with pytest.raises(TypeError, match="step"):
        silrig.sim(SCENARIO, controller=object())


def test_start_is_handed_the_runs_set_up():
    seen = {}

    class Looks(silrig.Controller):
        diagnostic_names = ("held_elevator_deg",)

        def start(self, session):
            seen["dt_s"] = session.dt_s
            seen["theta"] = session.setpoint("theta_deg")
            seen["alt"] = session.setpoint("no_such_output", 7.0)
            seen["plant"] = session.plant.name
            seen["elevator"] = session.input("elevator")
            self.session = session
            with pytest.raises(silrig.SilrigError, match="its outputs: "):
                session.output("theta_dg")

        def step(self, sample, dt_s):
            held = self.session.held_command()[seen["elevator"]]
            return {}, [held]

    flown = silrig.sim(SCENARIO, controller=Looks())
    assert seen == {"dt_s": 0.01, "theta": 10.0, "alt": 7.0, "plant": "f16", "elevator": seen["elevator"]}
    # An input left alone stays where its actuator is: the held command is the trace's elevator position.
    assert flown["trace"]["held_elevator_deg"][1:] == flown["trace"]["elevator_deg"][:-1]


def test_the_ctypes_modules_sample_names_the_plants_outputs_too():
    import silrig_client

    sample = silrig_client.Sample(silrig_client.PlantSample(), {"theta_deg": 0, "q_dps": 1})
    assert sample["q_dps"] == 0.0
    with pytest.raises(KeyError) as missing:
        sample["theta_dg"]
    assert "no output `theta_dg`; its outputs: theta_deg, q_dps" in str(missing.value)
