"""The plant role: a toy model flown as the run's plant through the package, with the example PID through the
package as its controller, every tick; a broken announcement refused naming the rule."""

import sys

from conftest import ROOT, counter, process, read_csv_columns, silrig_run

# The template (examples/) flies; the test's own toy breaks the rules on purpose.
TOY = f"{sys.executable} {ROOT}/examples/python/toy_plant_native.py"
BROKEN_TOY = f"{sys.executable} {ROOT}/python/tests/native_toy_plant.py"
PID = f"{sys.executable} {ROOT}/examples/python/pid_attitude_native.py"
SCENARIO = str(ROOT / "tests" / "scenarios" / "toy.toml")


def test_a_toy_plant_flies_lockstep_through_the_package(tmp_path):
    out = tmp_path / "run"
    r, report = silrig_run("toy", out, ["--mode", "lockstep", "--plant-cmd", TOY, "--controller-cmd", PID,
                                        SCENARIO])
    assert r.returncode == 0, r.stdout + r.stderr
    assert counter(report, "plant", "ticks") == 1001
    assert counter(report, "plant", "command_misses") == 0
    assert counter(report, "controller", "commands_sent") == 1001
    assert counter(report, "controller", "commands_refused") == 0
    assert counter(report, "logger", "rows_written") == 1001
    assert process(report, "plant")["ended"] == "completed"
    trace = read_csv_columns(out / "trace.csv")
    # The columns the toy announced, commands before positions, then the PID's diagnostics.
    assert ",".join(trace) == ("t_s,phi_deg,theta_deg,psi_deg,p_dps,q_dps,r_dps,aileron_cmd_deg,elevator_cmd_deg,"
                               "rudder_cmd_deg,aileron_deg,elevator_deg,rudder_deg,flight_segment,err_phi_deg,"
                               "err_theta_deg,err_psi_deg")
    assert len(trace["t_s"]) == 1001
    assert abs(trace["theta_deg"][-1] - 10.0) < 1.0, trace["theta_deg"][-1]

def test_a_broken_announcement_is_refused_naming_the_rule(tmp_path):
    out = tmp_path / "run"
    r, report = silrig_run("twice", out, ["--duration-s", "1", "--startup-timeout-s", "2", "--plant-cmd",
                                          BROKEN_TOY + " twice", SCENARIO])
    assert r.returncode == 1, r.stdout + r.stderr
    assert "plant toy: output `phi_deg` named twice" in str(report["failures"])
