"""Regular background grid of the MPM region and its per-face boundary conditions.

The grid covers a box of ``cells[j]`` cubic cells of edge ``cell_size`` from
``origin`` in each of its ``dim`` = 1, 2 or 3 directions; nodes are numbered in
C order over ``(cells[0] + 1, ..., cells[dim-1] + 1)``. Particle positions and
velocities always carry three components; the ones beyond ``dim`` are zero.

Axisymmetric grids (``dim == 2``, ``axisymmetric=True``) are r-z grids:
coordinate 0 is the radius r >= 0, coordinate 1 the axial z, and the third
(padded) direction is the hoop direction theta (see :mod:`blastfsi.mpm.musl`).

Boundary conditions act on the nodal velocities of the nodes lying on a face
(000 Sec. 2.2 solves the momentum equation on the grid, so a face condition is
a nodal constraint): ``"fixed"`` zeroes all components, ``"slip"`` (symmetry)
zeroes the normal component, ``"free"`` leaves the node alone.
"""
from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

FACE_KINDS = ("free", "slip", "fixed")


class GridError(ValueError):
    """An invalid background-grid parameter (the message names it)."""


@dataclasses.dataclass(frozen=True)
class Grid:
    origin: tuple  # lower corner [m], one entry per grid direction
    cell_size: float  # h [m], the same in every direction
    cells: tuple  # number of cells per direction
    boundaries: tuple = ()  # per direction (low face, high face) from FACE_KINDS; default all "free"
    axisymmetric: bool = False  # r-z grid (dim 2 only)

    def __post_init__(self):
        cells = tuple(self.cells)
        if not 1 <= len(cells) <= 3:
            raise GridError(f"grid.cells: expected 1 to 3 directions, got {len(cells)}")
        for j, n in enumerate(cells):
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
                raise GridError(f"grid.cells[{j}]: expected an integer >= 1, got {n!r}")
        origin = tuple(float(o) for o in self.origin)
        if len(origin) != len(cells):
            raise GridError(f"grid.origin: expected {len(cells)} coordinates, got {len(origin)}")
        if not np.all(np.isfinite(origin)):
            raise GridError(f"grid.origin: expected finite coordinates, got {origin}")
        h = float(self.cell_size)
        if not (np.isfinite(h) and h > 0.0):
            raise GridError(f"grid.cell_size: expected a finite value > 0, got {self.cell_size!r}")
        bounds = tuple(tuple(b) for b in self.boundaries) or (("free", "free"),) * len(cells)
        if len(bounds) != len(cells) or any(len(b) != 2 for b in bounds):
            raise GridError(f"grid.boundaries: expected {len(cells)} (low, high) pairs, got {self.boundaries!r}")
        for j, pair in enumerate(bounds):
            for side, kind in zip(("low", "high"), pair):
                if kind not in FACE_KINDS:
                    raise GridError(f"grid.boundaries[{j}].{side}: expected one of {FACE_KINDS}, got {kind!r}")
        if self.axisymmetric and len(cells) != 2:
            raise GridError(f"grid.axisymmetric: needs a 2-direction (r, z) grid, got {len(cells)} directions")
        if self.axisymmetric and origin[0] < 0.0:
            raise GridError(f"grid.origin[0]: the radius of an axisymmetric grid starts at r >= 0, got {origin[0]}")
        object.__setattr__(self, "cells", tuple(int(n) for n in cells))
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "cell_size", h)
        object.__setattr__(self, "boundaries", bounds)
        object.__setattr__(self, "axisymmetric", bool(self.axisymmetric))

    @property
    def dim(self) -> int:
        return len(self.cells)

    @property
    def nodes(self) -> tuple:
        """Nodes per direction."""
        return tuple(n + 1 for n in self.cells)

    @property
    def num_nodes(self) -> int:
        return int(np.prod(self.nodes))

    @property
    def upper(self) -> tuple:
        """Upper corner [m]."""
        return tuple(o + n * self.cell_size for o, n in zip(self.origin, self.cells))

    @property
    def strides(self) -> tuple:
        """Flat-index stride of each direction (C order)."""
        nodes = self.nodes
        return tuple(int(np.prod(nodes[j + 1:])) for j in range(self.dim))

    def node_positions(self) -> np.ndarray:
        """(num_nodes, 3) node coordinates, padded with zeros (host side)."""
        axes = [o + self.cell_size * np.arange(n) for o, n in zip(self.origin, self.nodes)]
        mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, self.dim)
        return np.pad(mesh, ((0, 0), (0, 3 - self.dim)))


def _face_factors(grid: Grid) -> list:
    """Per direction j an (nodes[j], 3) array of 0/1 factors on the velocity
    components of the nodes in layer i of direction j (host side, small)."""
    factors = []
    for j, (low, high) in enumerate(grid.boundaries):
        f = np.ones((grid.nodes[j], 3))
        for layer, kind in ((0, low), (-1, high)):
            if kind == "fixed":
                f[layer, :] = 0.0
            elif kind == "slip":
                f[layer, j] = 0.0
        factors.append(f)
    return factors


def apply_boundaries(v, grid: Grid):
    """Nodal velocities (num_nodes, k), k <= 3 components, with the face conditions imposed.

    The mask is the product of one small factor per direction, broadcast over
    the node block, so no (num_nodes, k) constant is embedded in the program.
    """
    if all(kind == "free" for pair in grid.boundaries for kind in pair):
        return v
    k = v.shape[1]
    block = v.reshape(grid.nodes + (k,))
    for j, f in enumerate(_face_factors(grid)):
        shape = [1] * grid.dim + [k]
        shape[j] = grid.nodes[j]
        block = block * jnp.asarray(f[:, :k], v.dtype).reshape(shape)
    return block.reshape(v.shape)


def cell_index(x, grid: Grid):
    """Flat index of the cell holding each position (clipped into the grid), (n,) int32."""
    idx = jnp.zeros(x.shape[0], jnp.int32)
    stride = 1
    for j in reversed(range(grid.dim)):
        c = jnp.floor((x[:, j] - grid.origin[j]) / grid.cell_size).astype(jnp.int32)
        idx = idx + stride * jnp.clip(c, 0, grid.cells[j] - 1)
        stride *= grid.cells[j]
    return idx


def inside(x, grid: Grid):
    """True where a position lies in the closed grid box (active directions only)."""
    ok = jnp.ones(x.shape[0], bool)
    for j in range(grid.dim):
        ok = ok & (x[:, j] >= grid.origin[j]) & (x[:, j] <= grid.upper[j])
    return ok
