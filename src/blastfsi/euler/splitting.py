"""The dimensional splittings of the split schemes (lax_wendroff.py, hancock.py); each directional operator L_a
is one call of the scheme's sweep.

* symmetric (Lax-Wendroff, 000 Eq. (6) with ERRATA 000-4): U^{n+1} = L_z L_y L_x L_x L_y L_z U^n, each operator
  with dt/2: second order within every step, 2 ndim operators per step;
* alternating (HLLC-Hancock): U^{n+1} = L_z L_y L_x U^n on even steps and L_x L_y L_z U^n on odd ones, each
  operator with the whole dt: ndim operators per step, second order over each pair of steps, whose product
  L_x L_y L_z L_z L_y L_x is the symmetric splitting of a double step (Strang 1968; Toro 2009 Sec. 16.4;
  LeVeque 2002 Sec. 19.5).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from blastfsi.euler.blocking import blocked
from blastfsi.euler.config import Config
from blastfsi.xla import fori


def split_step(U, sweep, consts: tuple, cfg: Config, moved=None, parity=None):
    """The 2 ndim operators of the symmetric splitting (applied right to left; in 1D two x operators) on U
    (nvar, *shape); with ``parity`` (0 or 1, may be traced: the step's index modulo 2) the ndim operators of
    the alternating splitting, x first on even steps (module docstring).

    ``sweep(consts, rows, axis, record)``: one operator along ``axis`` on a tuple of conservative rows (of a
    block spanning the axis, with ``consts`` cut to the same block), returning the new rows, and with
    ``record`` also its face transfers. The operators run in a fori_loop that switches between the ndim
    directional bodies, so each body is compiled once (on the CPU; unrolled where loops cost a host round
    trip, :func:`blastfsi.xla.fori`); each sweeps a large grid block by block (blocking.blocked). moved: None,
    or per axis a tuple of face-transfer rows (faces 0..n of that axis) onto which the transfers of the
    operators along that axis are summed; then (U_new, moved) is returned. Static: the plain step carries no
    transfers.
    """
    ndim = len(cfg.shape)
    forward, backward = tuple(range(ndim)), tuple(reversed(range(ndim)))
    rows = tuple(U)
    nvar = len(rows)

    def body(a):  # the operator along axis a on the loop state
        if moved is None:
            return lambda rows: blocked(lambda cc, r: sweep(cc, r, a, False), consts, rows, cfg, a)

        def sweep_and_add(cc, outs):  # outs: the rows, then the transfers of axis a so far
            new, t = sweep(cc, outs[:nvar], a, True)
            return new + tuple(m + x for m, x in zip(outs[nvar:], t))

        def recording(state):  # the transfers of all axes are carried, those of axis a added to
            rows, acc = state
            out = blocked(sweep_and_add, consts, rows + acc[a], cfg, a)
            return out[:nvar], acc[:a] + (out[nvar:],) + acc[a + 1:]
        return recording

    branches = [body(a) for a in range(ndim)]

    # the axis of operator i: order[i]. (An ensemble's members carry their own step counters: under vmap the
    # parity is batched and each operator evaluates every axis's sweep and selects one, the symmetric cost.)
    if parity is None:
        order, count = backward + forward, 2 * ndim
    else:
        order, count = jnp.asarray([forward, backward])[jnp.asarray(parity) % 2], ndim

    def operator(i, state):  # i traced in a loop, a Python int where the loop is unrolled (fori)
        if isinstance(i, int) and isinstance(order, tuple):
            return branches[order[i]](state)
        return jax.lax.switch(jnp.asarray(order)[i], branches, state)

    state = fori(count, operator, rows if moved is None else (rows, tuple(moved)))
    return jnp.stack(state) if moved is None else (jnp.stack(state[0]), state[1])
