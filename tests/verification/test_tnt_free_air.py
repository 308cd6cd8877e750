"""Issue 6 verification (slow): CJ pressure of the programmed burn, 1 kg TNT free-air blast vs
Kingery-Bulmash at three resolutions, cube-root scaling. Figures in docs/verification.md.

Resolution of the free-air runs: the gauges are governed by the widest air zone, max_ratio h
(h = R / cells), not by the zones across the charge (docs/verification.md). The three runs keep
cells = 100 (h = 0.527 mm for 1 kg) and uniform air zones (first_ratio = max_ratio) of 10.5, 5.3
(the shipped ``tnt-free-air``) and 2.6 mm."""
import numpy as np
import pytest

import blastfsi

pytestmark = pytest.mark.slow
Z = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0)


def cj_run(geometry, cells):
    d = {"method": "lagrangian1d", "name": "cj", "charge": {"radius": 0.05},
         "domain": {"geometry": geometry, "length": 0.2}, "grid": {"cells": cells, "first_ratio": 1.0},
         "time": {"end": 0.05 / 6930.0 * 1.02}, "output": {"history_samples": 2, "fields": 0, "plots": False}}
    return blastfsi.run(d)


def cj_ratio(geometry, cells):
    return cj_run(geometry, cells).summary["burn_front_pressure_ratio"]


def test_planar_burn_reaches_the_cj_pressure():
    # planar: the Taylor wave behind the front is linear, the front state converges to CJ
    # (measured 0.906, 0.945, 0.983, 1.048 at 100..800 zones); target 5 % at the finer grids
    ratios = [cj_ratio("planar", n) for n in (100, 200, 400, 800)]
    assert abs(ratios[2] - 1) < 0.05 and abs(ratios[3] - 1) < 0.05
    assert ratios[0] < ratios[1] < ratios[2]


def test_spherical_burn_front_converges_to_cj_like_sqrt_h():
    # spherical: the Taylor wave's gradient is singular at the CJ point, so a front smeared over a
    # few zones sits below p_CJ by ~ (h/R)^(1/2): measured 0.830, 0.869, 0.903, 0.933, 0.959 at
    # 200..3200 zones (pairwise orders of 1 - ratio 0.38, 0.43, 0.53, 0.71, rising: the limit of the
    # programmed burn at D = 6930 m/s, 2 m/s above D_CJ, is the strong point 1.034 p_CJ, not p_CJ).
    # The 5 % target is met at 3200 zones (4.1 %), not at 1600 (6.7 %).
    ratios = np.array([cj_ratio("spherical", n) for n in (200, 400, 800, 1600, 3200)])
    err = 1 - ratios
    assert np.all(np.diff(err) < 0)
    order = np.log2(err[:-1] / err[1:])
    assert np.all((order > 0.3) & (order < 0.8))
    assert err[-2] > 0.05 and err[-1] < 0.05


@pytest.mark.xfail(strict=True, reason="lagrangian1d at 6400 zones across R: the state turns NaN near the "
                   "burn front at ~0.9 R (t ~ 6.5 us) and the run is not stopped (stable_dt's jnp.min drops NaN "
                   "on large arrays, so no fault is raised); the summary's energy error is NaN")
def test_spherical_burn_front_at_6400_zones_stays_finite_and_within_five_percent():
    summary = cj_run("spherical", 6400).summary
    assert np.isfinite(summary["energy_error_relative"])
    assert abs(summary["burn_front_pressure_ratio"] - 1) < 0.05


COARSE, FINE = 20.0, 5.0  # max_ratio = first_ratio: 10.5 mm and 2.6 mm air zones; shipped: 10 (5.3 mm)


def free_air(**over):
    return blastfsi.run("tnt-free-air", set={"output.fields": 0, "output.plots": False, **over})


@pytest.fixture(scope="module")
def runs():
    out = {ratio: free_air(**{"grid.max_ratio": ratio, "grid.first_ratio": ratio}) for ratio in (COARSE, FINE)}
    out["shipped"] = free_air()
    return out


def values(res, key):
    return np.array([g[key] for g in res.summary["gauges"]])


def ratios(res, key):
    return np.array([g["ratio"][key] for g in res.summary["gauges"]])


def test_shipped_zoning_is_converged(runs):
    grid = runs["shipped"].scenario.grid  # the shipped zoning is the middle resolution
    assert (grid.cells, grid.first_ratio, grid.max_ratio) == (100, 10.0, 10.0)
    # "converged to ~3 %": the change from the shipped to the 2.6 mm grid, measured <= 2.9 % for every
    # quantity at Z >= 1 (peak at Z = 1) and 3.2 % at Z = 0.5 (arrival), must stay below 4 % (5 %).
    # A 1.3 mm grid differs from the shipped one by <= 2.8 % at Z >= 1; the arrival, first order, would
    # be ~3 % off at Z = 1 by Richardson extrapolation (docs/verification.md)
    for key in ("peak_overpressure", "impulse", "arrival_time"):
        change = np.abs(values(runs["shipped"], key) / values(runs[FINE], key) - 1)
        assert np.all(change[1:] < 0.04) and change[0] < 0.05, key
    # arrival converges monotonically: every step of refinement changes it less than the one before
    coarse, mid, fine = (values(runs[k], "arrival_time") for k in (COARSE, "shipped", FINE))
    assert np.all(np.abs(fine - mid) < np.abs(mid - coarse))


def test_arrival_times_match_kb(runs):
    r = ratios(runs[FINE], "arrival_time")
    assert np.all(np.abs(r[1:] - 1) < 0.05)  # Z >= 1: measured 0.958 .. 1.023
    # Z = 0.5: 6 % early (measured 0.940, converging from 0.868 / 0.910 at the coarser grids): with
    # gamma = 1.4 air (no dissociation) the near-field shock is compressed less and runs faster
    assert 0.90 < r[0] < 1.0
    shipped = ratios(runs["shipped"], "arrival_time")
    assert np.all(np.abs(shipped[2:] - 1) < 0.05) and abs(shipped[1] - 1) < 0.07  # Z = 1: 5.9 % early


def test_peak_overpressure_within_ten_percent_of_kb_for_z_at_least_one(runs):
    r = ratios(runs[FINE], "peak_overpressure")
    ok = [z for z, v in zip(Z, r) if z >= 1 and abs(v - 1) < 0.10]
    assert ok == [1.0, 3.0, 5.0, 10.0]
    assert abs(r[2] - 1) < 0.12  # Z = 2 is 10.2 % low (measured 0.898), still converging from below:
    coarse, mid = ratios(runs[COARSE], "peak_overpressure"), ratios(runs["shipped"], "peak_overpressure")
    assert coarse[2] < mid[2] < r[2]  # 0.878, 0.889, 0.898
    assert np.all(np.abs(ratios(runs["shipped"], "peak_overpressure")[1:] - 1) < 0.12)


def test_positive_impulse_is_below_kb_by_the_missing_afterburning(runs):
    # JWL products release only E0 (no afterburning with the air, which KB's measured impulses include):
    # 18-30 % below KB at Z >= 1 (measured 0.705 .. 0.816), and the deficit is not numerical -- the
    # impulse changes by < 1.3 % from the 5.3 mm to the 2.6 mm grid
    r = ratios(runs[FINE], "impulse")
    assert np.all((r[1:] > 0.65) & (r[1:] < 0.85))
    assert np.all(np.abs(values(runs["shipped"], "impulse") / values(runs[FINE], "impulse") - 1) < 0.02)
    assert abs(r[0] - 1) < 0.05  # Z = 0.5 (before the afterburning would matter): measured 0.983


@pytest.mark.xfail(reason="JWL products without afterburning: positive impulse 18-30 % below KB at Z >= 1 "
                          "(measured 0.705, 0.787, 0.816, 0.808, 0.786 at 2.6 mm air zones)", strict=True)
def test_positive_impulse_within_ten_percent_of_kb(runs):
    r = ratios(runs[FINE], "impulse")
    assert np.all(np.abs(r[1:] - 1) < 0.10)


def test_cube_root_scaling_1_kg_to_100_kg(runs):
    k = 100 ** (1 / 3)
    big = free_air(**{"charge.mass": 100.0, "domain.length": 14.0 * k, "time.end": 0.03 * k,
                      "output.gauges": [z * k for z in Z]})
    for a, b in zip(runs["shipped"].summary["gauges"], big.summary["gauges"]):
        assert b["peak_overpressure"] == pytest.approx(a["peak_overpressure"], rel=1e-2)
        assert b["impulse"] == pytest.approx(k * a["impulse"], rel=1e-2)
        assert b["arrival_time"] == pytest.approx(k * a["arrival_time"], rel=1e-2)
