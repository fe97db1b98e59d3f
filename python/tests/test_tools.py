"""The in-process tools: `silrig.sim` gives what `silrig sim` writes (trace.csv column by column, summary.json), from
a file, from TOML text and for the embedded default; `silrig.sweep` gives what `silrig sweep` writes (cases.csv,
sweep.json); bad input is refused naming the problem."""

import csv
import json
import math
import subprocess

import pytest
import silrig

from conftest import ROOT, SILRIG, assert_same_columns, read_csv_columns, same


def cli_sim(out, *args):
    r = subprocess.run([SILRIG, "sim", *args, "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return read_csv_columns(out / "trace.csv"), json.loads((out / "summary.json").read_text())


def test_sim_of_the_default_scenario_is_silrig_sims_trace_and_summary(tmp_path):
    trace, summary = cli_sim(tmp_path / "cli")
    flown = silrig.sim()
    assert_same_columns(flown["trace"], trace)
    assert flown["summary"] == summary
    assert flown["ended_early"] is None
    assert flown["refusals"] == []
    assert len(trace["t_s"]) > 1000


def test_sim_takes_a_file_or_its_text(tmp_path):
    path = ROOT / "configs" / "robust.toml"
    trace, summary = cli_sim(tmp_path / "cli", str(path))
    from_file = silrig.sim(path)
    assert_same_columns(from_file["trace"], trace)
    assert from_file["summary"] == summary
    from_text = silrig.sim(path.read_text())
    assert_same_columns(from_text["trace"], trace)


def test_sim_refuses_a_bad_scenario_naming_the_key_or_file(tmp_path):
    with pytest.raises(silrig.SilrigError) as bad:
        silrig.sim((ROOT / "configs" / "robust.toml").read_text().replace("duration_s = 10.0", "duration_s = -1.0"))
    assert "timing.duration_s" in str(bad.value) and bad.value.code == silrig.ERR_SETUP
    missing = tmp_path / "no-such.toml"
    with pytest.raises(silrig.SilrigError, match="no-such.toml"):
        silrig.sim(str(missing))


def test_sweep_is_silrig_sweeps_case_table_and_summary(tmp_path):
    config = str(ROOT / "configs" / "sweep-robust.toml")
    out = tmp_path / "cli"
    r = subprocess.run([SILRIG, "sweep", config, "--runs", "6", "--jobs", "1", "--out", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    swept = silrig.sweep(config, runs=6, jobs=2)
    assert swept["jobs"] == 2 and swept["fly_s"] > 0
    assert swept["summary"] == json.loads((out / "sweep.json").read_text())
    cases = swept["cases"]
    with open(out / "cases.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert list(cases) == rows[0]
    assert cases["index"] == list(range(6))
    for k, row in enumerate(rows[1:]):
        for name, cell in zip(rows[0], row):
            if name == "index":
                assert cases[name][k] == int(cell)
            elif name in ("outcome", "reason"):
                assert cases[name][k] == cell, (k, name)
            else:
                assert same(cases[name][k], float(cell) if cell else math.nan), (k, name, cases[name][k], cell)
    assert set(cases["outcome"]) <= {"pass", "fail", "infeasible"}

def test_sweep_refuses_a_scenario_without_dispersions():
    with pytest.raises(silrig.SilrigError, match=r"no \[dispersions\]"):
        silrig.sweep(str(ROOT / "configs" / "robust.toml"), runs=2)
    with pytest.raises(silrig.SilrigError, match="runs must be within"):
        silrig.sweep(str(ROOT / "configs" / "sweep-robust.toml"), runs=0)


def test_numpy_columns_when_asked():
    np = pytest.importorskip("numpy")
    flown = silrig.sim(numpy=True)
    plain = silrig.sim()
    assert isinstance(flown["trace"]["t_s"], np.ndarray)
    assert flown["trace"]["t_s"].dtype == np.float64
    assert np.array_equal(flown["trace"]["theta_deg"], np.array(plain["trace"]["theta_deg"]))
