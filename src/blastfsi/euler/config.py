"""Static configuration, traced parameters and the row layout of the Eulerian state.

The conservative state ``U`` has shape ``(nvar, *shape)``; its rows are (n = n_materials)

    alpha_k rho_k   k = 0..n-1   partial densities (material 0 = products when n = 2)
    rho u_d         d = 0..ndim-1
    E               total energy per unit volume
    alpha_0         products volume fraction (only when n = 2)

Inside a step the kernels carry U as a tuple of these rows: XLA:CPU then
fuses each row's stencil on its own, instead of recomputing the quantities
shared by all rows once per row of a stacked array (several times slower).
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax

CARTESIAN, CYLINDRICAL, SPHERICAL = 0, 1, 2
OUTFLOW, WALL, AXIS, PERIODIC = 0, 1, 2, 3
SPLIT = 8  # added to an x boundary kind inside one device's slab of a grid split along x (blastfsi.euler.step: the
#            explicit halo exchange): the slab's edge takes its ghost cells from the neighbouring slab, and those
#            of its own kind at the domain's end (boundaries.py)
LAX_WENDROFF, HLLC_MUSCL, HLLC_HANCOCK = 0, 1, 2
VAN_LEER, MINMOD, MC = 0, 1, 2  # slope limiters of the HLLC schemes (hllc.limited_slope)

MIN_CELLS = 2  # ghost depth of both schemes (mirror boundaries copy this many cells)


class Config(NamedTuple):
    """Static (hashable) description of the grid and the scheme; a static jit argument.

    shape: cells per axis; dx: cell size [m] (square/cubic cells); geometry:
    0 Cartesian, 1 cylindrical (1D radial, or 2D axisymmetric r-z), 2 spherical
    (1D radial) -- the radius is axis 0; bc: one (lo, hi) pair of boundary kinds
    per axis (0 outflow, 1 wall/symmetry plane, 2 axis r = 0, 3 periodic);
    scheme: 0 Lax-Wendroff (000 Sec. 2.1), 1 HLLC-MUSCL (unsplit), 2 HLLC-Hancock
    (split MUSCL-Hancock); n_materials: 1, or 2 for [products, air]; origin:
    lower corner of the grid [m]; limiter: the slope limiter of the two HLLC
    schemes, 0 van Leer, 1 minmod, 2 monotonized central (unused by Lax-Wendroff); devices: the
    devices the grid is split across along axis 0 (:func:`blastfsi.xla.split_sharding`; 1: not split);
    characteristic: the HLLC schemes limit the normal velocity and the pressure in acoustic characteristic
    variables (True) or each on its own (:func:`blastfsi.euler.hllc.cell_slopes`).
    """

    shape: tuple
    dx: float
    geometry: int
    bc: tuple
    scheme: int
    n_materials: int
    origin: tuple
    limiter: int = VAN_LEER
    devices: int = 1
    characteristic: bool = True


class BlastTable(NamedTuple):
    """The free-field blast of a charge outside the grid, fed into the layer of cells along the faces
    that face it (:func:`blastfsi.euler.boundaries.blast_layer`): the conservative rows of the 1D
    solution tabulated on uniform radii and times, and where the layer cells lie in it.

    cells (L,) flat (C-order) indices of the layer cells; radius (L,) their distance from the
    charge centre as a fractional index into the radii (r - r_0) / dr; unit (ndim, L) the unit
    vector from the centre to each; t0, dt: first time and spacing of the samples [s]; rows
    (n_times, n_radii, 5): per sample, products partial density, air partial density, radial
    momentum density, total energy density and products volume fraction."""

    cells: jax.Array
    radius: jax.Array
    unit: jax.Array
    t0: jax.Array
    dt: jax.Array
    rows: jax.Array


class Params(NamedTuple):
    """Traced (vmappable) parameters: eos (n_materials, 6) JWL rows [A, B, R1, R2, omega, rho0]
    (see blastfsi.eos.jwl; an ideal gas is A = B = 0, omega = gamma - 1), cfl: Courant number,
    blast: the table of a charge outside the grid, or None."""

    eos: jax.Array
    cfl: jax.Array
    blast: Optional[BlastTable] = None


class Layout(NamedTuple):
    n: int  # materials
    ndim: int

    @property
    def mom(self) -> int:
        return self.n

    @property
    def energy(self) -> int:
        return self.n + self.ndim

    @property
    def nvar(self) -> int:
        return 2 * self.n + self.ndim

    @property
    def alpha(self):
        """Row of the products fraction, None with one material."""
        return self.n + self.ndim + 1 if self.n == 2 else None


def layout(cfg: Config) -> Layout:
    return Layout(cfg.n_materials, len(cfg.shape))


def n_vars(cfg: Config) -> int:
    return layout(cfg).nvar


def check_config(cfg: Config) -> None:
    """Raise ValueError naming the offending field; runs once per trace (cfg is static)."""
    ndim = len(cfg.shape)
    if ndim not in (1, 2, 3):
        raise ValueError(f"Config.shape must have 1, 2 or 3 axes, got {cfg.shape}")
    if any(int(m) < MIN_CELLS for m in cfg.shape):
        raise ValueError(f"Config.shape needs >= {MIN_CELLS} cells per axis, got {cfg.shape}")
    if not cfg.dx > 0.0:
        raise ValueError(f"Config.dx must be > 0, got {cfg.dx}")
    if cfg.geometry not in (CARTESIAN, CYLINDRICAL, SPHERICAL):
        raise ValueError(f"Config.geometry must be 0 (Cartesian), 1 (cylindrical) or 2 (spherical), got {cfg.geometry}")
    if cfg.geometry == CYLINDRICAL and ndim > 2:
        raise ValueError(f"Config.geometry = 1 (cylindrical) allows 1 or 2 axes (r or r-z), got {ndim}")
    if cfg.geometry == SPHERICAL and ndim != 1:
        raise ValueError(f"Config.geometry = 2 (spherical) needs 1 axis, got {ndim}")
    if len(cfg.origin) != ndim:
        raise ValueError(f"Config.origin needs {ndim} entries, got {cfg.origin}")
    if cfg.geometry != CARTESIAN and cfg.origin[0] < 0.0:
        raise ValueError(f"Config.origin[0] is the inner radius and must be >= 0, got {cfg.origin[0]}")
    if len(cfg.bc) != ndim or any(len(pair) != 2 for pair in cfg.bc):
        raise ValueError(f"Config.bc needs one (lo, hi) pair per axis ({ndim}), got {cfg.bc}")
    for axis, (lo, hi) in enumerate(cfg.bc):
        if lo not in (OUTFLOW, WALL, AXIS, PERIODIC) or hi not in (OUTFLOW, WALL, AXIS, PERIODIC):
            raise ValueError(f"Config.bc[{axis}] kinds must be 0 outflow, 1 wall, 2 axis or 3 periodic, got {(lo, hi)}")
        if (lo == PERIODIC) != (hi == PERIODIC):
            raise ValueError(f"Config.bc[{axis}] periodic must be set on both sides, got {(lo, hi)}")
        if hi == AXIS or (lo == AXIS and (axis != 0 or cfg.geometry == CARTESIAN)):
            raise ValueError(f"Config.bc[{axis}] kind 2 (axis) is only allowed at the lower radial face, got {(lo, hi)}")
    if cfg.geometry != CARTESIAN and cfg.origin[0] == 0.0 and cfg.bc[0][0] not in (WALL, AXIS):
        raise ValueError(f"Config.bc[0][0] at r = 0 must be 1 (wall) or 2 (axis), got {cfg.bc[0][0]}")
    if cfg.geometry != CARTESIAN and cfg.bc[0][0] == PERIODIC:
        raise ValueError("Config.bc[0] cannot be periodic along the radius")
    if cfg.scheme not in (LAX_WENDROFF, HLLC_MUSCL, HLLC_HANCOCK):
        raise ValueError(f"Config.scheme must be 0 (lax-wendroff), 1 (hllc-muscl) or 2 (hllc-hancock), "
                         f"got {cfg.scheme}")
    if cfg.limiter not in (VAN_LEER, MINMOD, MC):
        raise ValueError(f"Config.limiter must be 0 (van Leer), 1 (minmod) or 2 (MC), got {cfg.limiter}")
    if cfg.n_materials not in (1, 2):
        raise ValueError(f"Config.n_materials must be 1 or 2, got {cfg.n_materials}")


def check_params(params: Params, cfg: Config) -> None:
    """Shape checks (values are traced and cannot be checked here)."""
    if tuple(params.eos.shape) != (cfg.n_materials, 6):
        raise ValueError(f"Params.eos must have shape ({cfg.n_materials}, 6) [A, B, R1, R2, omega, rho0] rows, "
                         f"got {tuple(params.eos.shape)}")
