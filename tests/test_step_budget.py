"""benchmarks/step_budget.py (issue 34): the three stable steps it records are those of the coupled step's
rule, dt = min(dt_E, dt_M) (:meth:`blastfsi.cfdmp.method.Cfdmp.advance`), so what it names as setting the step
is what the run used."""
import importlib.util
from pathlib import Path

import pytest

from blastfsi.timeloop import step_to

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "step_budget.py"


def load_script(monkeypatch):
    monkeypatch.syspath_prepend(str(SCRIPT.parent))  # (its helper module benchmarks/machine.py)
    spec = importlib.util.spec_from_file_location("step_budget", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow  # (a benchmark's own check; ~20 s of compile and one-step calls)
def test_recorded_limits_give_the_step_the_run_took(monkeypatch):
    budget = load_script(monkeypatch)
    end = 2.0e-4
    result = budget.measure("cfdmp-shock-tube", end, 1, {"grid.cells": 200, "output.plots": False})
    rows = result["rows"]
    assert len(rows) == result["coupled_steps"] >= result["steps"] - 1 > 50  # (activation may take one step)
    for row in rows:  # the time left to time.end in equal steps no longer than the stable one
        stable = min(row["dt_euler"], row["dt_structure"], row["dt_gas"])
        assert row["dt"] == pytest.approx(float(step_to(row["t"], end, stable)[0]), rel=1e-12)
    assert result["end_time"] == pytest.approx(end, rel=1e-12)
    assert sum(result["set_by"].values()) == len(rows)
    assert result["set_by"]["structure"] == 0  # (no structure in the tube)
