"""The benchmark's quick run: a well-formed work-precision CSV, its plots and its report."""
import csv
import math

import pytest

from prandtl_fmu import STEPPERS
from prandtl_fmu.cli import main

# the quick benchmark run (minutes of compiling and timing): run by .ci/run after the quick suite
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def quick_bench(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bench")
    assert main(["bench", "--quick", "--out", str(folder)]) == 0
    return folder


def test_quick_bench_writes_a_well_formed_csv(quick_bench):
    with open(quick_bench / "work_precision.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert set(rows[0]) >= {"stepper", "n", "h", "error", "seconds"}
    methods = {row["stepper"] for row in rows}
    assert set(STEPPERS) | {"fmu-verlet", "fmu-projected", "scipy-LSODA", "scipy-Radau"} <= methods
    assert {row["n"] for row in rows} == {"10", "100"}
    for row in rows:
        error, seconds = float(row["error"]), float(row["seconds"])
        assert seconds >= 0 and math.isfinite(seconds)
        if row["stepper"] == "exact":
            assert error == 0.0  # the reference
        else:
            assert math.isfinite(error) and error > 0
    # more work buys more accuracy for every stepper, at its order
    verlet = sorted((float(r["h"]), float(r["error"])) for r in rows if r["stepper"] == "verlet" and r["n"] == "100")
    projected = sorted((float(r["h"]), float(r["error"])) for r in rows
                       if r["stepper"] == "projected" and r["n"] == "100")
    assert verlet[0][1] < verlet[-1][1] and projected[0][1] < projected[-1][1]
    assert verlet[0][1] < projected[0][1]


def test_quick_bench_writes_plots_and_report(quick_bench):
    for name in ("work_precision.png", "error_vs_h.png"):
        assert (quick_bench / name).read_bytes()[:4] == b"\x89PNG"
    report = (quick_bench / "report.md").read_text()
    assert "| verlet |" in report and "| projected |" in report and "Table 1" in report
    with open(quick_bench / "table1.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert {(row["q"], row["n"]) for row in table} == {(q, n) for q in ("inf", "2") for n in ("3", "10", "100")}
    for row in table:
        assert abs(float(row["alpha"]) - 1) < 0.05  # the paper's scheme is of order 1
