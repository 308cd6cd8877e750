"""Stand-off against full domain on one grid (issue 37, item 1), in 1D spherical euler: the incident wave
at the far end of the domain, where a structure would stand.

The full-domain run holds the charge and is remapped when its blast reaches the stand-off run's blast
face; from there both runs carry the same wave over the same cells, the one from the remapped cell
averages, the other from the 1D solution fed through the face (blastfsi.euler.boundaries.blast_layer).
Their difference is a property of the feed: it must stay below the grid's own error, measured by either
run's distance from the 1D detonation (lagrangian1d, zones several times finer than the euler cells)
at the same point. A feed that steepened, delayed or weakened the wave would show as a pair difference
of the size of that error or larger.
"""
import numpy as np
import pytest

import blastfsi
from blastfsi.detonation.charge import one_d_scenario
from blastfsi.materials.gases import GASES

AIR = GASES["air"]
GAS = {"gamma": AIR.gamma, "pressure": AIR.pressure, "density": AIR.density}
MASS, CELLS_1D, AIR_RATIO = 0.1, 30, 2.0  # kg TNT (radius 24.5 mm); 1D zones across its radius; air zones 1.6 mm
D, L, DX = 0.464, 0.2, 0.005  # Z = 1 m/kg^1/3; the stand-off run's depth; the euler cell (3 x the 1D air zone)
T_END = 6e-4  # after the positive phase at D (arrival about 0.23 ms)


def spherical(lower, initial):
    return {"method": "euler", "name": "t-standoff-pair",
            "domain": {"geometry": "spherical", "lower": [lower], "upper": [D]},
            "boundaries": {"x": ["blast" if lower > 0.0 else "axis", "outflow"]},
            "grid": {"cells": round((D - lower) / DX)}, "initial": initial, "time": {"end": T_END},
            "output": {"history_samples": 2, "fields": 0, "plots": False, "gauges": [D - 0.5 * DX]}}


@pytest.mark.slow  # (~20-40 s: two euler runs and a 1D detonation; the feed itself is tested in test_standoff.py)
def test_standoff_and_full_domain_carry_the_same_incident_wave():
    charge = {"kind": "charge", "mass": MASS, "cells": CELLS_1D, "air_ratio": AIR_RATIO, "center": [0.0]}
    so = blastfsi.run(spherical(D - L, charge))
    radius = so.setups[0].charge.charge_radius
    one = blastfsi.run(one_d_scenario("tnt", radius, CELLS_1D, AIR_RATIO, 1.5, T_END, GAS, [D - L, D - 0.5 * DX]))
    at_face, at_gauge = one.summary["gauges"]
    full = blastfsi.run(spherical(0.0, charge | {"remap_time": at_face["arrival_time"]}))
    gauges = (so.summary["gauges"][0], full.summary["gauges"][0], at_gauge)
    p_so, p_full, p_1d = (r["peak_overpressure"] for r in gauges)
    i_so, i_full, i_1d = (r["impulse"] for r in gauges)
    grid_error = max(abs(p_so - p_1d), abs(p_full - p_1d))
    assert grid_error > 0.0
    assert abs(p_so - p_full) <= grid_error
    # the positive impulse: the pair within the larger of the grid's impulse error and the smeared fraction
    # 2 DX / (S t+) of the positive phase (S the shock speed, as in test_standoff)
    c0 = np.sqrt(AIR.gamma * AIR.pressure / AIR.density)
    S = c0 * np.sqrt(1.0 + (AIR.gamma + 1.0) / (2.0 * AIR.gamma) * p_1d / AIR.pressure)
    smear = 2.0 * DX / (S * at_gauge["positive_phase_duration"]) * i_1d
    assert abs(i_so - i_full) <= max(abs(i_so - i_1d), abs(i_full - i_1d), smear)
    assert full.summary["remap_time"] == pytest.approx(at_face["arrival_time"], rel=1e-12)
