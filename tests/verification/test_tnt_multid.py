"""Issue 6 verification of the multi-D TNT examples (the 1D detonation remapped onto the euler grid,
:mod:`blastfsi.detonation.charge`). Figures and the commands behind them in docs/verification.md.

Fast (default suite): the remapped initial state of ``tnt-free-air-axisym`` on a tiny grid holds the
1D solution's mass and puts the detonation products only inside the fireball.

Slow (``-m slow``):

* ``tnt-free-air-axisym`` (r-z, dx = 2 cm) against the 1D spherical euler run with the same dx and the
  same remap (isolates the 2D discretisation; target 3 %), against the converged ``lagrangian1d`` run,
  and just after the remap against the 1D profile it came from;
* ``tnt-surface-burst`` on rigid ground against the 1D spherical euler run of the whole sphere (twice
  the mass: the ground is a mirror plane) and against Kingery-Bulmash hemispherical surface burst.
"""
import numpy as np
import pytest

import blastfsi
from blastfsi.api import load
from blastfsi.detonation import charge
from blastfsi.materials import lookup
from blastfsi.euler.problem import cell_volumes
from blastfsi.scenario import parse

AIR = lookup("air")


def euler_setup(name: str, overrides: dict):
    """(scenario, euler Setup) of an example with dotted-key overrides: the initial data, nothing run."""
    sc = parse(load(name, set=overrides))
    return sc, blastfsi.method.get("euler").build(sc)


def one_d_state(sc, info):
    """The 1D spherical lagrangian1d solution at the remap time, rerun with the arguments
    :func:`blastfsi.detonation.charge.charge_initial` uses (deterministic: the same state)."""
    gas = {"gamma": AIR.gamma, "pressure": AIR.pressure, "density": AIR.density}
    length = 1.5 * info.limit_radius + 10.0 * info.charge_radius
    return blastfsi.run(charge.one_d_scenario(sc.initial.explosive, info.charge_radius, sc.initial.cells,
                                              sc.initial.air_ratio, length, info.remap_time, gas))


def cell_distance_bounds(g, centre):
    """Nearest and farthest distance of every cell of an r-z grid from the charge centre."""
    lo = [l + np.arange(n) * g.dx for l, n in zip(g.lower, g.shape)]
    near = [np.maximum(np.maximum(a - c, c - (a + g.dx)), 0.0) for a, c in zip(lo, centre)]
    far = [np.maximum(np.abs(a - c), np.abs(a + g.dx - c)) for a, c in zip(lo, centre)]
    return np.hypot(near[0][:, None], near[1][None, :]), np.hypot(far[0][:, None], far[1][None, :])


def test_axisym_remap_conserves_mass_and_keeps_products_in_the_fireball():
    # tiny grid (60 x 30 cells, dx = 10 cm), a coarse 1D run (40 zones across the charge) remapped at 0.2 ms
    sc, setup = euler_setup("tnt-free-air-axisym", {"grid.cells": 60, "initial.cells": 40, "initial.remap_time": 2e-4})
    info, g = setup.charge, setup.grid
    share = info.remap_share
    assert share == 0.5  # the symmetry plane z = 0 through the centre
    vol = cell_volumes(g)
    alpha = setup.alpha[0]  # products volume fraction
    products = alpha * setup.rho_k[0] * vol
    mass = products + (1.0 - alpha) * setup.rho_k[1] * vol
    # every kg of products of the 1D run (the whole charge) is on the grid, halved by the symmetry plane
    assert products.sum() == pytest.approx(share * info.charge_mass, rel=1e-12)
    # mass: the ambient air of the domain plus the 1D mass inside the remapped ball, less the ambient
    # air the ball displaces -- what the 1D solution holds, summed from its own zones
    f = one_d_state(sc, info).fields()
    edges, rho_1d = np.asarray(f["node_x"]), np.asarray(f["density"])
    inside = edges[1:] <= info.remap_radius * (1 + 1e-12)
    m_ball = np.sum(rho_1d[inside] * 4.0 / 3.0 * np.pi * np.diff(edges**3)[inside])
    v_ball = 4.0 / 3.0 * np.pi * edges[1:][inside][-1] ** 3
    assert mass.sum() == pytest.approx(AIR.density * (vol.sum() - share * v_ball) + share * m_ball, rel=1e-12)
    # products only inside the fireball (the 1D products/air interface r_c), to within one cell; cells
    # wholly inside it are pure products
    r_c = edges[np.count_nonzero(f["products_fraction"])]
    near, far = cell_distance_bounds(g, info.charge_center)
    assert np.all(products[near > r_c + g.dx] == 0.0)
    assert np.all(alpha[far < r_c - g.dx] == 1.0)
    assert np.count_nonzero(alpha) < 0.05 * alpha.size  # the bug filled the whole grid with products


# ---------------------------------------------------------------- slow: the shipped multi-D examples

def gauge_values(res, key):
    return np.array([g[key] for g in res.summary["gauges"]])


def euler_1d(mass: float, dx: float, sc):
    """The 1D spherical euler run of a free-air sphere of ``mass`` with cell size ``dx`` and the remap,
    gauge distances (1, 2, 5 m) and end time of the multi-D scenario ``sc``."""
    gauges = [float(np.hypot(*np.subtract(p, sc.initial.center))) for p in sc.output.gauges]
    data = {"method": "euler", "name": "tnt-1d", "domain": {"geometry": "spherical", "lower": [0.0],
                                                             "upper": [round(6.0 / dx) * dx]},
            "boundaries": {"x": ["axis", "outflow"]}, "grid": {"cells": round(6.0 / dx)},
            "initial": {"kind": "charge", "explosive": "tnt", "mass": mass, "cells": sc.initial.cells,
                        "air_ratio": sc.initial.air_ratio, "margin_cells": sc.initial.margin_cells},
            "time": {"end": sc.time.end},
            "output": {"history_samples": sc.output.history_samples, "fields": 0, "plots": False,
                       "gauges": gauges}}
    return blastfsi.run(data)


def run_example(name: str):
    return blastfsi.run(name, set={"output.fields": 0, "output.plots": False})


@pytest.fixture(scope="module")
def axisym():
    return run_example("tnt-free-air-axisym")


@pytest.fixture(scope="module")
def surface():
    return run_example("tnt-surface-burst")


KEYS = ("peak_overpressure", "impulse", "arrival_time")


@pytest.mark.slow
@pytest.mark.parametrize("name, mass", [("tnt-free-air-axisym", 1.0), ("tnt-surface-burst", 2.0)])
def test_rz_run_matches_the_1d_spherical_euler_run_at_the_same_dx(name, mass, axisym, surface):
    # the same scheme, cell size and remap: what differs is the r-z discretisation of a spherical wave
    # (and, for the surface burst, the rigid ground in place of the mirror half of a sphere of twice the
    # mass); target 3 % (measured <= 1.3 % peak, <= 0.4 % impulse, <= 0.3 % arrival at Z = 1, 2, 5)
    res = axisym if name == "tnt-free-air-axisym" else surface
    ref = euler_1d(mass, res.summary["dx"], res.scenario)
    for key in KEYS:
        np.testing.assert_allclose(gauge_values(res, key), gauge_values(ref, key), rtol=0.03, err_msg=key)


@pytest.mark.slow
def test_axisym_against_the_converged_lagrangian_1d_run(axisym):
    # reference: lagrangian1d with 2.6 mm air zones (within 3 % of its own next coarser grid)
    ref = blastfsi.run("tnt-free-air", set={"grid.max_ratio": 5.0, "grid.first_ratio": 5.0, "time.end": 0.015,
                                            "output.gauges": [1.0, 2.0, 5.0], "output.fields": 0,
                                            "output.plots": False})
    r = {key: gauge_values(axisym, key) / gauge_values(ref, key) for key in KEYS}
    # the positive impulse is a resolved integral: within 3 % (measured -0.6, -0.3, -0.2 %)
    assert np.all(np.abs(r["impulse"] - 1) < 0.03)
    # arrival: within 3 % at Z = 2, 5 (measured -2.7, -1.0 %: the 1 %-p0 foot of a shock captured over
    # ~3 cells runs ahead); at Z = 1 the blast was remapped 3 cells short of the gauge and the captured
    # foot crosses those 3 cells ahead of the shock: 4.8 % early (5.6 % with the former 13 mm 1D zones)
    assert np.all(np.abs(r["arrival_time"][1:] - 1) < 0.03) and abs(r["arrival_time"][0] - 1) < 0.07
    # peak: a captured shock spans ~3 cells (6 cm) while the overpressure behind it decays over a few
    # decimetres at Z <= 5, so the cell peak is low, the more so near the charge (measured 0.72, 0.83,
    # 0.86; the 1D spherical euler run at dx = 20 / 10 / 5 mm gives 0.74 / 0.84 / 0.93 of KB at Z = 1:
    # first order in dx, docs/verification.md); never above the converged value
    assert np.all((r["peak_overpressure"] > 0.65) & (r["peak_overpressure"] < 1.0))
    assert r["peak_overpressure"][0] < r["peak_overpressure"][1] < r["peak_overpressure"][2]


def front(radius, dp):
    """(shock radius, peak) of an overpressure profile: the outermost radius where dp reaches half its
    maximum (linear interpolation between samples), and that maximum."""
    peak = dp.max()
    k = np.nonzero(dp >= 0.5 * peak)[0].max()
    return radius[k] + (0.5 * peak - dp[k]) * (radius[k + 1] - radius[k]) / (dp[k + 1] - dp[k]), peak


@pytest.mark.slow
def test_axisym_just_after_the_remap_matches_the_1d_solution():
    sc, setup = euler_setup("tnt-free-air-axisym", {})
    info, g = setup.charge, setup.grid
    f = one_d_state(sc, info).fields()
    edges, p_1d = np.asarray(f["node_x"]), np.asarray(f["pressure"]) - setup.reference_pressure
    air = ~np.asarray(f["products_fraction"]).astype(bool)
    r_1d, peak_1d = front(np.asarray(f["x"])[air], p_1d[air])
    # the 1D pressure averaged over shells dx wide: what a conservative remap can put in the cells
    cum = np.r_[0.0, np.cumsum(p_1d * np.diff(edges**3))]
    shells = np.arange(0.0, edges[-1], g.dx)
    _, peak_shells = front(0.5 * (shells[1:] + shells[:-1]),
                           np.diff(np.interp(shells**3, edges**3, cum)) / np.diff(shells**3))
    dp = setup.pressure - setup.reference_pressure
    r_cells = [lo + (np.arange(n) + 0.5) * g.dx for lo, n in zip(g.lower, g.shape)]
    for ray, dist in ((dp[:, 0], np.hypot(r_cells[0], r_cells[1][0])),   # along the plane z = 0 ...
                      (dp[0, :], np.hypot(r_cells[0][0], r_cells[1]))):  # ... and along the axis
        r_2d, peak_2d = front(dist, ray)
        assert abs(r_2d - r_1d) < g.dx  # measured -0.11 dx
        assert peak_2d == pytest.approx(peak_shells, rel=0.02)  # measured -0.8 %
    # the 1D zone peak itself (5.3 mm zones) is 12 % above the best 2 cm cell: a resolution limit
    assert peak_shells < peak_1d


@pytest.mark.slow
def test_surface_burst_against_kingery_bulmash_hemispherical(surface):
    # Model limits, measured with the converged 1D run of the equivalent 2 kg sphere (2.6 mm zones)
    # against KB surface burst for 1 kg: peak 1.19 / 1.04 / 1.05, impulse 0.83 / 0.79 / 0.87, arrival
    # 0.90 / 0.94 / 0.98 at Z = 1, 2, 5. A rigid ground reflects the whole charge (2 W) where KB's
    # surface data equal ~1.8 W free air (ground losses), so peaks are above and arrivals early; the
    # impulse lacks the afterburning of the products (see the free-air tests).
    r = {key: np.array([g["ratio"][key] for g in surface.summary["gauges"]]) for key in KEYS}
    # peak: the 2 cm cells lose 13-25 % of the converged peak (measured 0.75 / 0.84 / 0.87 of the 1D
    # reference) against the rigid-ground gain above: 0.886 / 0.872 / 0.916 of KB, within 15 %
    assert np.all(np.abs(r["peak_overpressure"] - 1) < 0.15)
    assert np.all((r["impulse"] > 0.7) & (r["impulse"] < 0.95))  # measured 0.808 / 0.793 / 0.866
    # arrival within 5 % at Z = 5 (measured 0.971); at Z = 1, 2 early by the 2 W vs 1.8 W equivalence
    # and the captured foot crossing the remap margin (measured 0.852 / 0.907)
    assert abs(r["arrival_time"][2] - 1) < 0.05
    assert np.all((r["arrival_time"][:2] > 0.80) & (r["arrival_time"][:2] < 1.0))
