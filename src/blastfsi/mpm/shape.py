"""Grid shape functions N_I(x_p) and their gradients (000 Eq. 16 and GIMP).

Both are tensor products of 1D functions of the scaled distance to a node:

* ``LINEAR``: the hat function of the regular grid, 000 Eq. (16) (the 8-node
  hexahedron in 3D, bilinear in 2D, linear in 1D): 2 nodes per direction.
* ``GIMP``: the uniform GIMP function (uGIMP, Bardenhagen & Kober, CMES 5 (2004)
  477; Steffen, Kirby & Berzins, IJNME 76 (2008) 922, Eq. 13), the hat function
  averaged over the particle domain [x_p - l, x_p + l] of fixed half-size l
  (half the initial particle spacing, 0 < l <= h/2): 3 nodes per direction.

Nodes outside the grid get weight 0; particles must stay inside the grid box
(:func:`blastfsi.mpm.musl.first_fault` reports those that leave). A GIMP domain
that reaches past the grid's end is truncated to the grid (:func:`inside_grid`),
so the partition of unity and sum_I grad N_I = 0 hold there too.
"""
from __future__ import annotations

import functools
import itertools
import operator
from typing import Callable, NamedTuple

import jax.numpy as jnp


class Shape(NamedTuple):
    name: str
    nodes_per_dim: int
    basis: Callable  # (xi (n,), half (n,) in cell units, cells) -> (first node (n,), [N_a (n,)], [dN_a/dxi (n,)])


def linear_cell(xi, cells):
    """Index (float) of the cell holding the scaled position xi, the first node of its linear stencil."""
    return jnp.clip(jnp.floor(xi), 0, cells - 1)


def _linear_basis(xi, half, cells):
    """000 Eq. (16) in one direction: N = 1 - |xi - i| on the two nodes of the cell."""
    first = linear_cell(xi, cells)
    f = xi - first
    one = jnp.ones_like(f)
    return first.astype(jnp.int32), [1.0 - f, f], [-one, one]


def inside_grid(xi, half, cells):
    """The part of a GIMP domain [xi - l, xi + l] (cell units) inside the grid [0, cells], as its centre and
    half-size; unchanged (bit for bit) for a domain inside. The weights of the part beyond the grid's end
    would fall on nodes that do not exist: without the truncation the weights no longer sum to 1 and the
    gradients to 0, so a particle pressed against a wall face, or leaving through a free one, was pushed by
    its own stress (a block thrown at a fixed face: the particles' momentum change 15 % off the wall's
    reaction, tests/test_mpm.py; docs/theory/cfdmp.md, fragments leaving the box)."""
    lo, hi = jnp.maximum(xi - half, 0.0), jnp.minimum(xi + half, float(cells))
    past = (xi - half < 0.0) | (xi + half > cells)
    return jnp.where(past, 0.5 * (lo + hi), xi), jnp.where(past, jnp.maximum(0.5 * (hi - lo), 1e-6 * half), half)


def _gimp_basis(xi, half, cells):
    """uGIMP weight in one direction (Steffen et al. 2008, Eq. 13) in cell units,
    r = xi - i the particle-to-node distance, l = half:
    N = 1 - (r^2 + l^2) / (2 l)      for |r| < l
    N = 1 - |r|                      for l <= |r| < 1 - l
    N = (1 + l - |r|)^2 / (4 l)      for 1 - l <= |r| < 1 + l, else 0.
    The domain is first truncated to the grid (:func:`inside_grid`).
    """
    xi, l = inside_grid(xi, half, cells)
    first = jnp.floor(xi + 0.5).astype(jnp.int32) - 1
    N, dN = [], []
    for a in range(3):
        r = xi - (first + a)  # particle minus node, cell units
        d = jnp.abs(r)
        s = jnp.sign(r)
        inner, middle, outer = d < l, d < 1.0 - l, d < 1.0 + l
        N.append(jnp.where(inner, 1.0 - (r * r + l * l) / (2.0 * l),
                           jnp.where(middle, 1.0 - d, jnp.where(outer, (1.0 + l - d) ** 2 / (4.0 * l), 0.0))))
        dN.append(jnp.where(inner, -r / l,
                            jnp.where(middle, -s, jnp.where(outer, -s * (1.0 + l - d) / (2.0 * l), 0.0))))
    return first, N, dN


LINEAR = Shape("linear", 2, _linear_basis)
GIMP = Shape("gimp", 3, _gimp_basis)
SHAPES = {s.name: s for s in (LINEAR, GIMP)}


def factors(x, half_size, grid, shape: Shape):
    """Per-direction factors of the stencil: for each grid direction j a tuple
    (node index times stride (k, n) int32, N (k, n), dN/dx (k, n)), zero outside the grid.

    x, half_size: (n, 3) positions and GIMP half-sizes [m] (half_size unused by LINEAR).
    """
    h, k = grid.cell_size, shape.nodes_per_dim
    out = []
    for j in range(grid.dim):
        xi = (x[:, j] - grid.origin[j]) / h
        first, N, dN = shape.basis(xi, half_size[:, j] / h, grid.cells[j])
        node = first[None, :] + jnp.arange(k, dtype=first.dtype)[:, None]
        valid = (node >= 0) & (node <= grid.cells[j])
        out.append((grid.strides[j] * jnp.clip(node, 0, grid.cells[j]),
                    jnp.where(valid, jnp.stack(N), 0.0), jnp.where(valid, jnp.stack(dN) / h, 0.0)))
    return tuple(out)


def expand(per_dim):
    """Tensor-product stencil from :func:`factors`: ``idx`` (S, n) flat node indices,
    ``w`` (S, n) = N_Ip and ``grad``, a tuple of ``dim`` arrays (S, n) = dN_Ip/dx_j,
    S = k ** dim, stencil nodes in C order. The stencil axis leads (one contiguous
    row per node): small trailing axes vectorise badly on CPU. Each row is the product of
    one row of each direction's factors, stacked (written as broadcasts of (k, n) blocks,
    XLA:CPU computed every element with the index arithmetic of the broadcast: the four
    (8, n) weight arrays of a 3D step took ~1 ns per element, measured)."""
    d = len(per_dim)
    k = per_dim[0][1].shape[0]
    nodes = list(itertools.product(range(k), repeat=d))  # C order: the last direction varies fastest

    def rows(pick):  # pick(j, a): row a of direction j's factor -> (S, n), the rows' product per node
        return jnp.stack([functools.reduce(operator.mul, [pick(j, a) for j, a in enumerate(node)])
                          for node in nodes])

    idx = jnp.stack([functools.reduce(operator.add, [per_dim[j][0][a] for j, a in enumerate(node)])
                     for node in nodes])
    w = rows(lambda j, a: per_dim[j][1][a])
    grad = tuple(rows(lambda j, a, i=i: per_dim[j][2 if j == i else 1][a]) for i in range(d))
    return idx, w, grad


def stencil(x, half_size, grid, shape: Shape):
    """Node indices, weights and weight gradients of every particle, see :func:`expand`."""
    return expand(factors(x, half_size, grid, shape))
