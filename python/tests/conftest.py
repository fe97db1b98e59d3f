"""What the package's tests share: the checkout they run in, the `silrig` binary they compare with (SILRIG_BIN, as
tests/python_package.rs passes it; otherwise target/release/silrig), and a run-id prefix of their own
(SILRIG_TEST_RUN_PREFIX) so that the Rust test can check each run left no shared memory behind."""

import json
import math
import os
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
SILRIG = os.environ.get("SILRIG_BIN") or str(ROOT / "target" / "release" / "silrig")
RUN_PREFIX = os.environ.get("SILRIG_TEST_RUN_PREFIX", f"py{os.getpid()}")


def silrig_run(test, out, args):
    """`silrig run ARGS` with its own run id and folder; the completed process and its report (None when none)."""
    run_id = f"{RUN_PREFIX}-{test}"
    r = subprocess.run(
        [SILRIG, "run", *args, "--run-id", run_id, "--out", str(out), "--no-baseline"],
        capture_output=True, text=True, timeout=300,
    )
    report_path = out / "report.json"
    report = json.loads(report_path.read_text()) if report_path.exists() else None
    return r, report


def process(report, name):
    return next(p for p in report["processes"] if p["process"] == name)


def counter(report, name, key):
    return process(report, name)["counters"].get(key, 0)


def read_csv_columns(path):
    """A CSV of numbers as {column: [float]} (an empty cell is NaN)."""
    lines = pathlib.Path(path).read_text().splitlines()
    header = lines[0].split(",")
    columns = {name: [] for name in header}
    for line in lines[1:]:
        for name, cell in zip(header, line.split(",")):
            columns[name].append(float(cell) if cell else float("nan"))
    return columns


def same(a, b):
    return a == b or (math.isnan(a) and math.isnan(b))


def assert_same_columns(ours, theirs):
    """Two traces as {column: values}: the same columns in the same order, equal value for value (NaN with NaN)."""
    assert list(ours) == list(theirs)
    for name in theirs:
        assert len(ours[name]) == len(theirs[name]), name
        bad = [k for k, (x, y) in enumerate(zip(ours[name], theirs[name])) if not same(float(x), y)]
        assert not bad, f"column {name} differs first at row {bad[0]}: {ours[name][bad[0]]} != {theirs[name][bad[0]]}"
