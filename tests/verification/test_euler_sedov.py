"""Sedov blast: shock-radius error of the euler method in 1D spherical, 2D axisymmetric,
2D and 3D Cartesian geometry against the exact front (exact/sedov.py), and the 3D
solution's symmetry under axis permutation.

The captured front is the mid-height of the captured density jump (diagnostics.fronts).
Tolerance: two cells. A first-order-smeared shock spreads over 2-3 cells and the clipped
Sedov peak moves the mid-height up to about 1.5 cells ahead of the exact front (measured:
+1.2 to +1.6 cells in 2D/axisymmetric); the error converges at first order (1D spherical
0.65 %, 0.34 %, 0.17 % at 200, 400, 800 cells; 2D 2.5 %, 1.1 % at 96, 192 cells).

Fine grids at the cost of coarse ones: the blast is symmetric, so a quadrant (2D) / octant (3D)
[0, 1.2]^d with symmetry on the lower faces, or the r-z half domain z >= 0, holds the same cells
at twice the resolution per axis; it equals the corresponding part of the full-box run to
round-off (checked here on coarse grids). Errors measured on such grids (docs/verification.md, Verification
item 4) give the 1 % target of issue 5 on the grids below."""
import numpy as np
import pytest

import blastfsi
from blastfsi.diagnostics.fronts import front_radius
from blastfsi.exact.sedov import Sedov

EXACT = {"spherical": Sedov(1.0, 1.0, 1.4, "spherical").front_position(1.0),
         "cylindrical": Sedov(1.0, 1.0, 1.4, "cylindrical").front_position(1.0)}


@pytest.mark.slow
@pytest.mark.parametrize("example, cells, blast, line", [
    ("sedov-spherical", 400, "spherical", lambda f: (f["x"], f["density"])),
    ("sedov-axisym", 120, "spherical", lambda f: (f["x"][:, 0], f["density"][:, 0])),
    ("sedov-2d", 192, "cylindrical", lambda f: (f["x"][f["x"].shape[0] // 2:, f["x"].shape[1] // 2],
                                                f["density"][f["x"].shape[0] // 2:, f["x"].shape[1] // 2])),
])
def test_sedov_front_within_two_cells(example, cells, blast, line):
    res = blastfsi.run(example, set={"grid.cells": cells, "output.fields": 0, "output.plots": False})
    r, rho = line(res.fields())
    dx = res.summary["dx"]
    assert abs(front_radius(r, rho, 1.0) - EXACT[blast]) < 2 * dx


@pytest.mark.slow
def test_sedov_3d_front_and_axis_permutation_symmetry():
    res = blastfsi.run("sedov-3d", set={"grid.cells": 48, "output.fields": 0, "output.plots": False})
    f = res.fields()
    rho = f["density"]
    n = rho.shape[0]
    for perm in ((1, 0, 2), (2, 1, 0), (0, 2, 1)):  # hllc-muscl is unsplit: symmetric to round-off
        assert np.max(np.abs(rho - np.transpose(rho, perm))) <= 1e-12 * np.max(rho)
    r = front_radius(f["x"][n // 2:, n // 2, n // 2], rho[n // 2:, n // 2, n // 2], 1.0)
    assert abs(r - EXACT["spherical"]) < 2 * res.summary["dx"]


SYMMETRIC_PART = {  # example -> overrides that cut the full box to its symmetric part
    "sedov-2d": {"domain.lower": [0.0, 0.0], "domain.upper": [1.2, 1.2],
                 "boundaries.x": ["symmetry", "outflow"], "boundaries.y": ["symmetry", "outflow"]},
    "sedov-3d": {"domain.lower": [0.0, 0.0, 0.0], "domain.upper": [1.2, 1.2, 1.2],
                 "boundaries.x": ["symmetry", "outflow"], "boundaries.y": ["symmetry", "outflow"],
                 "boundaries.z": ["symmetry", "outflow"]},
    "sedov-axisym": {},  # the example is already the half domain z >= 0
}
FULL = {"sedov-2d": {}, "sedov-3d": {},
        "sedov-axisym": {"domain.lower": [0.0, -1.2], "boundaries.y": ["outflow", "outflow"]}}


def sedov_density(example, cells, scheme="hllc-muscl", part=True):
    over = SYMMETRIC_PART[example] if part else FULL[example]
    res = blastfsi.run(example, set={"grid.cells": cells, "numerics.scheme": scheme, "output.fields": 0,
                                     "output.plots": False, "output.gauges": [], **over})
    f = res.fields()
    return np.asarray(f["x"]), np.asarray(f["density"]), res.summary["dx"]


@pytest.mark.slow
@pytest.mark.parametrize("example, full_cells", [("sedov-2d", 48), ("sedov-3d", 24), ("sedov-axisym", 30)])
def test_symmetric_part_equals_the_full_domain(example, full_cells):
    """The quadrant / octant / r-z half run equals the matching part of the full-box run to round-off
    (HLLC-MUSCL; measured 4e-15, 2.4e-15, 2.5e-15 of the peak density): a symmetry face is the
    mirror image of the other half, and the point energy is halved per symmetry plane."""
    _, full, _ = sedov_density(example, full_cells, part=False)
    _, part, _ = sedov_density(example, full_cells // 2 if example != "sedov-axisym" else full_cells)
    if example == "sedov-axisym":
        sub = full[:, full.shape[1] // 2:]
    else:
        sub = full[tuple(slice(n // 2, None) for n in full.shape)]
    assert sub.shape == part.shape
    assert np.max(np.abs(sub - part)) <= 1e-12 * np.max(full)


@pytest.mark.slow
@pytest.mark.parametrize("example, cells, scheme, blast", [
    ("sedov-2d", 96, "lax-wendroff", "cylindrical"),   # measured +0.23 % (= 192 cells across the full box)
    ("sedov-2d", 192, "hllc-muscl", "cylindrical"),    # +0.96 % (= 384 across the full box), ~4 min
    ("sedov-axisym", 120, "lax-wendroff", "spherical"),  # +0.76 % along z = 0 (HLLC-MUSCL: +1.55 %)
    ("sedov-3d", 64, "lax-wendroff", "spherical"),  # octant = 128 across the full box: +0.54 %, ~13 min
])
def test_sedov_front_within_one_percent_on_fine_grids(example, cells, scheme, blast):
    """Issue 5: shock-radius error <= 1 % at the finest grid, along the ray through the first cell
    row off the symmetry plane (the ray of test_sedov_front_within_two_cells)."""
    x, rho, dx = sedov_density(example, cells, scheme)
    ray = (slice(None),) + (0,) * (rho.ndim - 1)
    r = front_radius(x[ray], rho[ray], 1.0)
    assert abs(r / EXACT[blast] - 1) <= 0.01, (r, EXACT[blast])
