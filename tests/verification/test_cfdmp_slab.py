"""Issue 8 verification of ``he-slab-2d`` (seed 000 Sec. 5.2, Fig. 10): the two gauges stand symmetric about
the charge, gauge 1 in the Eulerian region and gauge 2 in the MPM gas past the bridge, so over the incident
pulse they must read the same blast. Targets of the issue (5 % peak, 5 % impulse, 2 % arrival); the figures
for w = 2, 5, 8 and their commands in docs/verification.md. Slow (``-m slow``): the run from the remap
(9.6 us after the detonation) to 24.6 us takes ~2-3 min.
"""
import numpy as np
import pytest

import blastfsi
from blastfsi.diagnostics.profiles import incident_pulse


@pytest.mark.slow
def test_symmetric_gauges_agree_over_the_incident_pulse(tmp_path):
    """Gauge 2 (MPM gas) against gauge 1 (Eulerian) over the incident pulse (to gauge 1's first minimum
    after its peak; gauge 2, 9 mm in front of the slab, records the slab's reflection after it). Without the
    pressure relaxation of the gas materials (blastfsi.mpm.relaxation) gauge 2's peak was +12.8 %: the air
    over-compressed at the products contact."""
    res = blastfsi.run("he-slab-2d", set={"time.end": 2.46e-5, "output.history_samples": 301, "output.fields": 0},
                       out=tmp_path / "run")
    g = res.gauges
    pulse = incident_pulse(g["time"], g["overpressure"])
    one, two = pulse["gauges"]
    assert pulse["window_end"] > 19.6e-6  # the pulse, not a wiggle: gauge 1's peak passes at ~19.3 us
    assert two["peak_overpressure"] == pytest.approx(one["peak_overpressure"], rel=0.05)
    assert two["impulse"] == pytest.approx(one["impulse"], rel=0.05)
    assert two["arrival_time"] == pytest.approx(one["arrival_time"], rel=0.02)  # (from the detonation)
    assert np.all(np.abs(res.history["mass_budget_residual"]) < 1e-13)
