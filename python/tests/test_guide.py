"""docs/src/guides/python.md's examples, run as the page says: its controller flown by the lockstep rig against the
F-16 (every tick answered, no command refused, the pitch held near its set point, no departure), and its Python
lines executed in order in one namespace, as a notebook would (the controller in process, a small sweep, the plot
drawn)."""

import re
import sys

import matplotlib

from conftest import ROOT, counter, read_csv_columns, silrig_run

GUIDE = ROOT / "docs" / "src" / "guides" / "python.md"


def python_blocks():
    return re.findall(r"```python\n(.*?)```", GUIDE.read_text(), re.S)


def test_the_guides_controller_holds_the_f16s_pitch_in_the_rig(tmp_path):
    served = [block for block in python_blocks() if "silrig.serve(" in block]
    assert len(served) == 1, "one controller served on the page"
    script = tmp_path / "hold.py"
    script.write_text(served[0])
    out = tmp_path / "run"
    r, report = silrig_run("hold", out, ["--mode", "lockstep", "--controller-cmd", f"{sys.executable} {script}",
                                         str(ROOT / "configs" / "robust.toml")])
    assert r.returncode == 0, r.stdout + r.stderr
    assert counter(report, "controller", "commands_sent") == 1001
    assert counter(report, "controller", "commands_refused") == 0
    trace = read_csv_columns(out / "trace.csv")
    assert abs(trace["theta_deg"][-1] - 10.0) < 2.0, trace["theta_deg"][-1]
    assert max(trace["alpha_deg"]) < 15.0, max(trace["alpha_deg"])


def test_the_guides_notebook_lines_run_and_draw_the_plot(monkeypatch):
    monkeypatch.chdir(ROOT)
    matplotlib.use("Agg")
    namespace = {"__name__": "notebook"}
    blocks = python_blocks()
    assert len(blocks) >= 3, "the controller, the notebook lines and the plot"
    for block in blocks:
        exec(compile(block, str(GUIDE), "exec"), namespace)
    assert namespace["flown"]["ended_early"] is None
    assert len(namespace["swept"]["cases"]["outcome"]) == 20
    (line,) = namespace["plt"].gca().lines
    assert list(line.get_xdata()) == list(namespace["flown"]["trace"]["t_s"])
    assert len(line.get_ydata()) == 1001
