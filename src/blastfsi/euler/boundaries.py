"""Ghost cells by slicing (no jnp.roll), the stencil offset helper, and the blast layer.

Kinds (config): outflow = zero-gradient copy of the edge cell; wall, symmetry
plane and the axis r = 0 = mirror image with the normal vector component
negated; periodic = the cells of the opposite end. A kind + SPLIT marks the x edge of one device's slab of a
grid split along x, inside ``shard_map`` over the mesh axis SPLIT_AXIS: its ghost cells are the neighbouring
slab's edge cells (one collective permute per side), and those of the kind itself on the slabs at the domain's
ends (:func:`_from_neighbour`).

Blast faces (a charge outside the grid, :class:`blastfsi.euler.config.BlastTable`):
the scheme sees an outflow face, and the layer of cells along it is set after
every step to the 1D free-field solution at each cell's distance from the
charge centre and the step's end time (:func:`blast_layer`), the "ambient
layer" of LS-DYNA's blast-enhanced loading: the cells next to the layer then
receive the incoming blast through the scheme's own fluxes.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from blastfsi.euler.config import OUTFLOW, PERIODIC, SPLIT, BlastTable, Layout
from blastfsi.xla import SPLIT_AXIS


def _slice(x, axis, start, stop):
    idx = [slice(None)] * x.ndim
    idx[axis] = slice(start, stop)
    return x[tuple(idx)]


def _from_neighbour(x, axis, ng, upper, own, kind):
    """The ``ng`` ghost planes of a slab's edge (upper or lower) along a split ``axis``: the neighbouring slab's
    edge planes, sent by every device to the one below (upper ghosts) or above (lower ghosts), and ``own`` (the
    ghosts of the boundary ``kind``) on the slab at the domain's end; periodic: the slab at the other end's."""
    devices, k, n = jax.lax.axis_size(SPLIT_AXIS), jax.lax.axis_index(SPLIT_AXIS), x.shape[axis]
    to = -1 if upper else 1  # (a device's upper ghosts are the first planes of the one above it)
    pairs = [(j, (j + to) % devices) for j in range(devices) if kind == PERIODIC or 0 <= j + to < devices]
    got = jax.lax.ppermute(_slice(x, axis, 0, ng) if upper else _slice(x, axis, n - ng, n), SPLIT_AXIS, pairs)
    if kind == PERIODIC:
        return got
    return jnp.where(k == (devices - 1 if upper else 0), own, got)


def _ghosts(x, axis, kind, ng, sign, upper):
    if kind >= SPLIT:
        own = None if kind == SPLIT + PERIODIC else _ghosts(x, axis, kind - SPLIT, ng, sign, upper)
        return _from_neighbour(x, axis, ng, upper, own, kind - SPLIT)
    n = x.shape[axis]
    if kind == OUTFLOW:
        edge = _slice(x, axis, n - 1, n) if upper else _slice(x, axis, 0, 1)
        return edge if ng == 1 else jnp.concatenate([edge] * ng, axis=axis)
    if kind == PERIODIC:
        return _slice(x, axis, 0, ng) if upper else _slice(x, axis, n - ng, n)
    g = jnp.flip(_slice(x, axis, n - ng, n) if upper else _slice(x, axis, 0, ng), axis=axis)
    return g if sign is None else g * sign


def pad(x, axis, kinds, ng, sign=None):
    """``x`` with ``ng`` ghost cells on both sides of array axis ``axis``.

    kinds: (lo, hi) boundary kinds of that axis; sign: None, or a constant
    broadcastable to x that is -1 on the rows changing sign in a mirror (the
    velocity or momentum normal to the face) and +1 elsewhere.
    """
    lo, hi = kinds
    return jnp.concatenate([_ghosts(x, axis, lo, ng, sign, False), x, _ghosts(x, axis, hi, ng, sign, True)], axis=axis)


def shift(x, axis, start, length):
    """The ``length`` cells of ``x`` along ``axis`` starting at ``start`` (a stencil offset)."""
    return _slice(x, axis, start, start + length)


def extend(x, axis, kinds, lo, hi, sign=None):
    """``x`` with ``lo`` ghost cells below and ``hi`` above along ``axis`` (the values of :func:`pad`)."""
    lo_kind, hi_kind = kinds
    parts = ([_ghosts(x, axis, lo_kind, lo, sign, False)] if lo else []) + [x] + (
        [_ghosts(x, axis, hi_kind, hi, sign, True)] if hi else [])
    return parts[0] if len(parts) == 1 else jnp.concatenate(parts, axis=axis)


def extend_rows(rows, axis, kinds, lo, hi, flip=None):
    """:func:`extend` of each of ``rows`` (a tuple of arrays), the row numbered ``flip`` changing sign in a mirror;
    on the split axis of a slab (kinds + SPLIT) all rows are extended as one stacked array, so that their ghost
    cells cross to the neighbouring slabs in one exchange per side."""
    if max(kinds) < SPLIT:
        return tuple(extend(x, axis, kinds, lo, hi, -1.0 if r == flip else None) for r, x in enumerate(rows))
    sign = jnp.asarray([-1.0 if r == flip else 1.0 for r in range(len(rows))], rows[0].dtype)
    return tuple(extend(jnp.stack(rows), axis + 1, kinds, lo, hi, sign.reshape((-1,) + (1,) * rows[0].ndim)))


def extend_coefficient(k, axis, kinds):
    """One ghost cell each side of the viscosity coefficient k_i = eta_i |theta_i| of lax_wendroff.py.

    Equals k of the ghost cell computed from the ghost states of :func:`pad`: zero at an outflow
    face (the ghost density has no jump there, theta = 0), the mirror image at a mirror face
    (|theta| and eta are mirror-symmetric), the opposite end at a periodic face.
    """
    lo_kind, hi_kind = kinds
    n = k.shape[axis]
    if max(kinds) >= SPLIT:  # a split axis: the neighbouring slab's edge cell, the kind's ghost at the domain's end
        own = extend_coefficient(k, axis, (lo_kind % SPLIT, hi_kind % SPLIT))
        lo, hi = _slice(own, axis, 0, 1), _slice(own, axis, n + 1, n + 2)
        lo = _from_neighbour(k, axis, 1, False, lo, lo_kind - SPLIT) if lo_kind >= SPLIT else lo
        hi = _from_neighbour(k, axis, 1, True, hi, hi_kind - SPLIT) if hi_kind >= SPLIT else hi
        return jnp.concatenate([lo, k, hi], axis=axis)

    def ghost(kind, upper):  # (an outflow face's: the edge cell, zeroed below)
        if kind == PERIODIC:
            return _slice(k, axis, 0, 1) if upper else _slice(k, axis, n - 1, n)
        return _slice(k, axis, n - 1, n) if upper else _slice(k, axis, 0, 1)
    out = jnp.concatenate([ghost(lo_kind, False), k, ghost(hi_kind, True)], axis=axis)
    if OUTFLOW not in kinds:
        return out
    # zeroed by a select, not a concatenated zero: on a 1D grid split across devices XLA's partitioner
    # gathers the whole array for the latter (jax 0.10), and exchanges only the edge cells for this
    i = jax.lax.broadcasted_iota(jnp.int32, out.shape, axis)
    zero = ((i == 0) if lo_kind == OUTFLOW else False) | ((i == n + 1) if hi_kind == OUTFLOW else False)
    return jnp.where(zero, jnp.zeros((), k.dtype), out)


def blast_rows(table: BlastTable, t, dtype):
    """(5, L) table rows at the layer cells at time ``t``, bilinear in radius and time (clamped to the
    table: the last sample holds after it)."""
    n_t, n_r = table.rows.shape[:2]
    rows = table.rows.astype(dtype)
    s = jnp.clip((jnp.asarray(t, dtype) - table.t0.astype(dtype)) / table.dt.astype(dtype), 0.0, n_t - 1.0)
    k = jnp.minimum(jnp.floor(s), n_t - 2.0).astype(jnp.int32)
    a = s - k
    x = jnp.clip(table.radius.astype(dtype), 0.0, n_r - 1.0)
    i = jnp.minimum(jnp.floor(x), n_r - 2.0).astype(jnp.int32)
    b = (x - i)[:, None]
    at_r = [(1.0 - b) * rows[kk][i] + b * rows[kk][i + 1] for kk in (k, k + 1)]
    return ((1.0 - a) * at_r[0] + a * at_r[1]).T


def blast_layer(U, t, table: BlastTable, lay: Layout):
    """U with its blast-layer cells set to the tabulated free field at time ``t`` (two materials,
    products first): partial densities, momentum = radial momentum density x the cell's unit vector
    from the charge centre, total energy, products volume fraction."""
    q = blast_rows(table, t, U.dtype)
    rows = [q[0], q[1]] + [q[2] * table.unit[d].astype(U.dtype) for d in range(lay.ndim)] + [q[3], q[4]]
    flat = U.reshape(U.shape[0], -1).at[:, table.cells].set(jnp.stack(rows))
    return flat.reshape(U.shape)
