"""Issue 6 verification (slow): CJ pressure of the programmed burn, 1 kg TNT free-air blast vs
Kingery-Bulmash at three resolutions, cube-root scaling. Figures in docs/verification.md."""
import numpy as np
import pytest

import blastfsi

pytestmark = pytest.mark.slow
Z = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0)


def cj_ratio(geometry, cells):
    d = {"method": "lagrangian1d", "name": "cj", "charge": {"radius": 0.05},
         "domain": {"geometry": geometry, "length": 0.2}, "grid": {"cells": cells, "first_ratio": 1.0},
         "time": {"end": 0.05 / 6930.0 * 1.02}, "output": {"history_samples": 2, "fields": 0, "plots": False}}
    return blastfsi.run(d).summary["burn_front_pressure_ratio"]


def test_planar_burn_reaches_the_cj_pressure():
    # planar: the Taylor wave behind the front is linear, the front state converges to CJ
    # (measured 0.906, 0.945, 0.983, 1.048 at 100..800 zones); target 5 % at the finer grids
    ratios = [cj_ratio("planar", n) for n in (100, 200, 400, 800)]
    assert abs(ratios[2] - 1) < 0.05 and abs(ratios[3] - 1) < 0.05
    assert ratios[0] < ratios[1] < ratios[2]


def test_spherical_burn_front_converges_to_cj_like_sqrt_h():
    # spherical: the Taylor wave's gradient is singular at the CJ point, so a front smeared over a
    # few zones sits below p_CJ by ~ (h/R)^(1/2): measured 0.830, 0.869, 0.903, 0.933 at 200..1600
    ratios = np.array([cj_ratio("spherical", n) for n in (200, 400, 800, 1600)])
    err = 1 - ratios
    assert np.all(np.diff(err) < 0)
    order = np.log2(err[:-1] / err[1:])
    assert np.all((order > 0.3) & (order < 0.8))
    assert err[-1] < 0.08  # the 5 % target is not reached at 1600 zones (6.7 %)


@pytest.fixture(scope="module")
def runs():
    return {n: blastfsi.run("tnt-free-air", set={"grid.cells": n, "output.fields": 0, "output.plots": False})
            for n in (200, 400, 800)}


def ratios(res, key):
    return np.array([g["ratio"][key] for g in res.summary["gauges"]])


def test_arrival_times_match_kb(runs):
    r = ratios(runs[800], "arrival_time")
    assert np.all(np.abs(r[2:] - 1) < 0.05)  # Z >= 2: within 0.2 % (measured)
    assert abs(r[1] - 1) < 0.08  # Z = 1: 6.5 % early (ideal-gas air too fast near the fireball)


def test_peak_overpressure_within_ten_percent_of_kb_for_z_at_least_one(runs):
    r = ratios(runs[800], "peak_overpressure")
    ok = [z for z, v in zip(Z, r) if z >= 1 and abs(v - 1) < 0.10]
    assert ok == [1.0, 3.0, 5.0, 10.0]  # Z = 2 is 11.6 % low (see docs/verification.md)
    # converging from below with resolution at every Z >= 1
    coarse, mid = ratios(runs[200], "peak_overpressure"), ratios(runs[400], "peak_overpressure")
    assert np.all((coarse[1:] < mid[1:]) & (mid[1:] < r[1:]))


@pytest.mark.xfail(reason="JWL products without afterburning: positive impulse 18-29 % below KB at Z >= 1 "
                          "(measured 0.71, 0.79, 0.82, 0.82, 0.79 at 800 zones)", strict=True)
def test_positive_impulse_within_ten_percent_of_kb(runs):
    r = ratios(runs[800], "impulse")
    assert np.all(np.abs(r[1:] - 1) < 0.10)


def test_cube_root_scaling_1_kg_to_100_kg(runs):
    k = 100 ** (1 / 3)
    big = blastfsi.run("tnt-free-air", set={"grid.cells": 400, "charge.mass": 100.0, "domain.length": 14.0 * k,
                                            "time.end": 0.03 * k, "output.gauges": [z * k for z in Z],
                                            "output.fields": 0, "output.plots": False})
    for a, b in zip(runs[400].summary["gauges"], big.summary["gauges"]):
        assert b["peak_overpressure"] == pytest.approx(a["peak_overpressure"], rel=1e-2)
        assert b["impulse"] == pytest.approx(k * a["impulse"], rel=1e-2)
        assert b["arrival_time"] == pytest.approx(k * a["arrival_time"], rel=1e-2)
