"""The controller role: the example PID flown through the package in lockstep, every tick answered, to the set
points; and a session opened without a rig is refused with the contract's status code."""

import os
import subprocess
import sys

import pytest
import silrig

from conftest import ROOT, counter, process, read_csv_columns, silrig_run


def test_the_example_pid_flies_lockstep_through_the_package_every_tick_answered(tmp_path):
    out = tmp_path / "run"
    controller = f"{sys.executable} {ROOT}/examples/python/pid_attitude_native.py"
    r, report = silrig_run("pid", out, ["--mode", "lockstep", "--controller-cmd", controller,
                                        str(ROOT / "configs" / "robust.toml")])
    assert r.returncode == 0, r.stdout + r.stderr
    assert counter(report, "plant", "ticks") == 1001
    assert counter(report, "plant", "command_misses") == 0
    assert counter(report, "controller", "commands_sent") == 1001
    assert counter(report, "controller", "commands_refused") == 0
    assert process(report, "controller")["ended"] == "completed"
    trace = read_csv_columns(out / "trace.csv")
    assert len(trace["t_s"]) == 1001
    assert list(trace)[-3:] == ["err_phi_deg", "err_theta_deg", "err_psi_deg"]
    for angle, setpoint in [("phi_deg", 0.0), ("theta_deg", 10.0), ("psi_deg", 0.0)]:
        assert abs(trace[angle][-1] - setpoint) < 1.0, (angle, trace[angle][-1])


def test_a_session_without_a_rig_is_refused_with_the_contracts_code(monkeypatch):
    for name in [n for n in os.environ if n.startswith("SILRIG_")]:
        monkeypatch.delenv(name)
    with pytest.raises(silrig.SilrigError) as refused:
        silrig.ControllerSession(["err_deg"])
    assert refused.value.code == silrig.ERR_SETUP
    assert "SILRIG_" in str(refused.value)


def test_serve_without_a_rig_says_why_and_returns_2():
    env = {k: v for k, v in os.environ.items() if not k.startswith("SILRIG_")}
    script = "import silrig\nclass C(silrig.Controller):\n    def step(self, s, dt): return {}\nraise SystemExit(silrig.serve(C()))"
    r = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("silrig: "), r.stderr


def test_the_status_codes_are_the_contracts():
    assert (silrig.OK, silrig.STOPPED, silrig.RUN_ENDED, silrig.NOT_GIVEN) == (0, 1, 2, 3)
    assert silrig.ERR_COMMAND_REFUSED == -6 and silrig.ERR_PLANT == -9
    assert issubclass(silrig.SilrigError, RuntimeError)
