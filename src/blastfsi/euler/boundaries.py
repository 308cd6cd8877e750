"""Ghost cells by slicing (no jnp.roll), and the stencil offset helper.

Kinds (config): outflow = zero-gradient copy of the edge cell; wall, symmetry
plane and the axis r = 0 = mirror image with the normal vector component
negated; periodic = the cells of the opposite end.
"""
from __future__ import annotations

import jax.numpy as jnp

from blastfsi.euler.config import OUTFLOW, PERIODIC


def _slice(x, axis, start, stop):
    idx = [slice(None)] * x.ndim
    idx[axis] = slice(start, stop)
    return x[tuple(idx)]


def _ghosts(x, axis, kind, ng, sign, upper):
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


def extend_coefficient(k, axis, kinds):
    """One ghost cell each side of the viscosity coefficient k_i = eta_i |theta_i| of lax_wendroff.py.

    Equals k of the ghost cell computed from the ghost states of :func:`pad`: zero at an outflow
    face (the ghost density has no jump there, theta = 0), the mirror image at a mirror face
    (|theta| and eta are mirror-symmetric), the opposite end at a periodic face.
    """
    lo_kind, hi_kind = kinds
    n = k.shape[axis]

    def ghost(kind, upper):
        if kind == OUTFLOW:
            return jnp.zeros_like(_slice(k, axis, 0, 1))
        if kind == PERIODIC:
            return _slice(k, axis, 0, 1) if upper else _slice(k, axis, n - 1, n)
        return _slice(k, axis, n - 1, n) if upper else _slice(k, axis, 0, 1)
    return jnp.concatenate([ghost(lo_kind, False), k, ghost(hi_kind, True)], axis=axis)
