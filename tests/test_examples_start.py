"""Every shipped example compiles and takes its first steps (slow: one time-loop compilation per example,
~15-30 s each on a 2-core CPU). Written after a change to the cfdmp transport broke the compilation of
``he-slab-2d-mpm`` (MPM everywhere) while every test of the default suite still passed."""
import pytest

import blastfsi
from blastfsi.api import example_names
from blastfsi.simulation import SimulationError

STEPS = 25


@pytest.mark.slow
@pytest.mark.parametrize("name", example_names())
def test_example_compiles_and_takes_its_first_steps(name):
    brief = {"time.max_steps": STEPS, "output.fields": 0, "output.plots": False, "output.history_samples": 3}
    try:
        summary = blastfsi.run(name, set=brief).summary
    except SimulationError as stop:  # the step budget spent before the end: the expected stop
        assert str(stop).startswith(f"time.max_steps = {STEPS} reached"), str(stop)
    else:
        assert 0 < summary["steps"] <= STEPS
