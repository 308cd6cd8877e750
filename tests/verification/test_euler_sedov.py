"""Sedov blast: shock-radius error of the euler method in 1D spherical, 2D axisymmetric,
2D and 3D Cartesian geometry against the exact front (exact/sedov.py), and the 3D
solution's symmetry under axis permutation.

The captured front is the mid-height of the captured density jump (diagnostics.fronts).
Tolerance: two cells. A first-order-smeared shock spreads over 2-3 cells and the clipped
Sedov peak moves the mid-height up to about 1.5 cells ahead of the exact front (measured:
+1.2 to +1.6 cells in 2D/axisymmetric); the error converges at first order (1D spherical
0.65 %, 0.34 %, 0.17 % at 200, 400, 800 cells; 2D 2.5 %, 1.1 % at 96, 192 cells)."""
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
