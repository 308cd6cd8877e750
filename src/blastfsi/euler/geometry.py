"""Finite-volume metric of the radial axis (axis 0) in cylindrical (j = 1) and spherical (j = 2) geometry.

Cell i spans r_{i-1/2} = origin_0 + i dx to r_{i+1/2}; face area A = r^j and
cell volume V_i = (r_{i+1/2}^{j+1} - r_{i-1/2}^{j+1}) / (j + 1), per radian^j
(the factors 2 pi and 4 pi cancel in the update; :func:`cell_volumes` restores
them). A radial flux divergence is written

    (1/V_i) (A_{i+1/2} F_{i+1/2} - A_{i-1/2} F_{i-1/2}) = (g+_i F_{i+1/2} - g-_i F_{i-1/2}) / dx,
    g+-_i = A_{i+-1/2} dx / V_i,

and the pressure force on the radial momentum p_i (A_{i+1/2} - A_{i-1/2}) / V_i,
which balances the pressure flux exactly in a uniform state at rest. All
factors are host-side NumPy constants of the static configuration; on one device's slab of a grid split along
the radius (x kinds + SPLIT, inside ``shard_map``) they are the whole grid's, cut at the slab's place.
"""
from __future__ import annotations

import jax
import numpy as np

from blastfsi.euler.config import AXIS, CARTESIAN, SPLIT, WALL, Config
from blastfsi.xla import SPLIT_AXIS


def _on_slab(factor, cfg: Config, first: int, count: int, dtype):
    """``factor(cfg, first, count, dtype)`` on a slab (cfg.bc[0] kinds + SPLIT): the whole grid's values at the
    slab's cells first .. first+count-1, the slab being the axis_index-th of axis_size equal ones."""
    devices = jax.lax.axis_size(SPLIT_AXIS)
    (lo, hi), n = cfg.bc[0], cfg.shape[0]
    whole = cfg._replace(shape=(n * devices, *cfg.shape[1:]), bc=((lo - SPLIT, hi - SPLIT), *cfg.bc[1:]))
    start = jax.lax.axis_index(SPLIT_AXIS) * n + first
    values = factor(whole, 0, whole.shape[0] + count - n, dtype)  # (faces: count = n + 1)
    cut = [jax.lax.dynamic_slice_in_dim(np.asarray(v), start, count, axis=0) for v in
           (values if isinstance(values, tuple) else (values,))]
    return tuple(cut) if isinstance(values, tuple) else cut[0]


def _along_axis0(v, ndim, dtype):
    return np.asarray(v, dtype=dtype).reshape((-1,) + (1,) * (ndim - 1))


def _faces(cfg: Config, first: int, count: int):
    """Radii of the count+1 faces bounding cells first .. first+count-1."""
    return cfg.origin[0] + cfg.dx * np.arange(first, first + count + 1, dtype=np.float64)


def flux_factors(cfg: Config, first: int, count: int, dtype):
    """(g+, g-) of cells first .. first+count-1."""
    if cfg.bc[0][0] >= SPLIT:
        return _on_slab(flux_factors, cfg, first, count, dtype)
    j = cfg.geometry
    r = _faces(cfg, first, count)
    area = r ** j
    vol = np.diff(r ** (j + 1)) / (j + 1)
    nd = len(cfg.shape)
    return _along_axis0(area[1:] * cfg.dx / vol, nd, dtype), _along_axis0(area[:-1] * cfg.dx / vol, nd, dtype)


def cell_source_factor(cfg: Config, first: int, count: int, dtype):
    """j dx / r at the centres of cells first .. first+count-1 (MUSCL-Hancock's geometric source)."""
    if cfg.bc[0][0] >= SPLIT:
        return _on_slab(cell_source_factor, cfg, first, count, dtype)
    r = cfg.origin[0] + cfg.dx * (np.arange(first, first + count) + 0.5)
    return _along_axis0(cfg.geometry * cfg.dx / r, len(cfg.shape), dtype)


def face_source_factor(cfg: Config, first: int, count: int, dtype):
    """j dx / r at faces first .. first+count-1 (face f is the lower face of cell f); 0 at r = 0 and
    at a mirror (wall/axis) boundary face.

    Multiplies the quasi-one-dimensional source -(j/r) G of the Lax-Wendroff
    predictor. At a mirror face the normal velocity vanishes, and so must the
    predicted normal momentum there (the mirror average gives exactly 0 without
    the source), so that no mass or energy crosses the wall.
    """
    if cfg.bc[0][0] >= SPLIT:
        return _on_slab(face_source_factor, cfg, first, count, dtype)
    f = np.arange(first, first + count)
    r = cfg.origin[0] + cfg.dx * f.astype(np.float64)
    mirror = ((f == 0) & (cfg.bc[0][0] in (WALL, AXIS))) | ((f == cfg.shape[0]) & (cfg.bc[0][1] in (WALL, AXIS)))
    keep = (r != 0.0) & ~mirror
    return _along_axis0(np.where(keep, cfg.geometry * cfg.dx / np.where(keep, r, 1.0), 0.0), len(cfg.shape), dtype)


def cell_volumes(cfg: Config, dtype):
    """Volume of every cell [m^ndim]: dx^ndim (Cartesian), pi (r+^2 - r-^2) dx^(ndim-1) (cylindrical:
    per unit length in 1D, exact ring volumes in r-z), (4 pi / 3)(r+^3 - r-^3) (spherical)."""
    nd = len(cfg.shape)
    if cfg.geometry == CARTESIAN:
        return np.asarray(cfg.dx ** nd, dtype=dtype)
    j = cfg.geometry
    r = _faces(cfg, 0, cfg.shape[0])
    shell = (2.0 * np.pi if j == 1 else 4.0 * np.pi) * np.diff(r ** (j + 1)) / (j + 1)
    return _along_axis0(shell * cfg.dx ** (nd - 1), nd, dtype)


def face_measures(cfg: Config, axis: int, dtype):
    """dx times the area of every face of ``axis`` [m^ndim], broadcastable to the faces' shape (cfg.shape
    with shape[axis] + 1): the physical content a face transfer T of ``euler.step_with_transfers`` moves
    is T times this. dx^ndim (Cartesian); radial faces 2 pi r_f dx^ndim (cylindrical: per unit length in
    1D, rings in r-z) or 4 pi r_f^2 dx (spherical); axial faces of an r-z grid pi (r+^2 - r-^2) dx, the
    volume of the cell column they bound (V_i g+-_i = A_{i+-1/2} dx, as in :func:`flux_factors`)."""
    nd = len(cfg.shape)
    if cfg.geometry == CARTESIAN:
        return np.asarray(cfg.dx ** nd, dtype=dtype)
    if axis != 0:
        return cell_volumes(cfg, dtype)
    r = _faces(cfg, 0, cfg.shape[0])
    area = 2.0 * np.pi * r * cfg.dx ** (nd - 1) if cfg.geometry == 1 else 4.0 * np.pi * r ** 2
    return _along_axis0(area * cfg.dx, nd, dtype)
