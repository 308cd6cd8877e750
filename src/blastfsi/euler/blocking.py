"""Sweeping a large grid block by block (both schemes).

An operator along one axis is independent across the other axes, so a large grid is swept
block by block along the outermost other axis: the operator's many temporaries (ghost cells,
face states, fluxes) then live in cache instead of main memory, and the arithmetic of every
cell is unchanged (up to how XLA contracts multiply-adds).
"""
from __future__ import annotations

import math

import jax

from blastfsi import xla
from blastfsi.euler.config import Config

BLOCK_CELLS = 32768  # cells per block of a blocked operator (its temporaries stay in the 2 MiB L2 of a core)
BLOCKED_ABOVE = 1 << 17  # grids of more cells are swept block by block (below, one block is faster)


def blocks(cfg: Config, axis: int):
    """(blocking axis, planes per block) of the operator along ``axis``, or None (one block).

    Measured with jax 0.10 on this 2-core CPU (docs/verification.md): Lax-Wendroff's blocks are 1.3-1.7x
    faster on 64^3, 128^3, 512^2 and 1024^2 grids and 1.8x slower on 200^2, hence BLOCKED_ABOVE;
    HLLC-MUSCL's (its flux divergence per axis) 2.1x faster at 128^3. CPU only
    (:func:`blastfsi.xla.blocked_sweeps`), and not on a grid split across devices (cfg.devices > 1: a block's
    dynamic slice across the split axis would gather the whole grid on every device).
    """
    if (len(cfg.shape) == 1 or math.prod(cfg.shape) <= BLOCKED_ABOVE or not xla.blocked_sweeps()
            or cfg.devices > 1):
        return None
    b = 0 if axis != 0 else 1
    m = cfg.shape[b]
    planes = max(1, min(m, BLOCK_CELLS * m // math.prod(cfg.shape)))  # equal blocks of about BLOCK_CELLS cells
    while m % planes:
        planes -= 1
    return None if planes == m else (b, planes)


def blocked(fn, ins, outs, cfg: Config, axis: int):
    """fn(ins, outs) -> new outs, applied block by block (:func:`blocks`); the blocks of ``outs`` are
    updated in place (ins and outs: tuples of arrays spanning the blocking axis)."""
    spec = blocks(cfg, axis)
    if spec is None:
        return fn(ins, outs)
    b, ch = spec

    def body(j, outs):
        start = j * ch
        cut = lambda x: jax.lax.dynamic_slice_in_dim(x, start, ch, axis=b)  # noqa: E731
        new = fn(tuple(map(cut, ins)), tuple(map(cut, outs)))
        return tuple(jax.lax.dynamic_update_slice_in_dim(o, x, start, axis=b) for o, x in zip(outs, new))
    return jax.lax.fori_loop(0, cfg.shape[b] // ch, body, tuple(outs))
