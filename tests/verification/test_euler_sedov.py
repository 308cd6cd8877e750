"""Sedov blast: shock-radius error of the euler method in 1D spherical, 2D axisymmetric,
2D and 3D Cartesian geometry against the exact front (exact/sedov.py), and the 3D
solution's symmetry under axis permutation.

The captured front is the mid-height of the captured density jump (diagnostics.fronts,
biased outward by up to 1-2 cells where the clipped Sedov peak is coarse). Tolerance: the
issue's target, 1 % at the finest grid run here."""
import numpy as np
import pytest

import blastfsi
from blastfsi.diagnostics.fronts import front_radius
from blastfsi.exact.sedov import Sedov

XI = {"spherical": Sedov(1.0, 1.0, 1.4, "spherical"), "cylindrical": Sedov(1.0, 1.0, 1.4, "cylindrical")}


def _radial_error(example, cells, blast, line):
    res = blastfsi.run(example, set={"grid.cells": cells, "output.fields": 0, "output.plots": False})
    f = res.fields()
    r, rho = line(f)
    exact = blast.front_position(1.0)
    return front_radius(r, rho, 1.0) / exact - 1.0, res


@pytest.mark.slow
@pytest.mark.parametrize("example, cells, blast, line", [
    ("sedov-spherical", 400, "spherical", lambda f: (f["x"], f["density"])),
    ("sedov-axisym", 240, "spherical", lambda f: (f["x"][:, 0], f["density"][:, 0])),
    ("sedov-2d", 192, "cylindrical", lambda f: (f["x"][f["x"].shape[0] // 2:, f["x"].shape[1] // 2],
                                                f["density"][f["x"].shape[0] // 2:, f["x"].shape[1] // 2])),
])
def test_sedov_front_within_one_percent(example, cells, blast, line):
    err, _ = _radial_error(example, cells, XI[blast], line)
    assert abs(err) < 0.01, err


@pytest.mark.slow
def test_sedov_3d_front_and_axis_permutation_symmetry():
    res = blastfsi.run("sedov-3d", set={"grid.cells": 64, "output.fields": 0, "output.plots": False})
    f = res.fields()
    rho = f["density"]
    n = rho.shape[0]
    for perm in ((1, 0, 2), (2, 1, 0), (0, 2, 1)):
        assert np.max(np.abs(rho - np.transpose(rho, perm))) <= 1e-12 * np.max(rho)
    r, line = f["x"][n // 2:, n // 2, n // 2], rho[n // 2:, n // 2, n // 2]
    err = front_radius(r, line, 1.0) / XI["spherical"].front_position(1.0) - 1.0
    assert abs(err) < 0.02, err
