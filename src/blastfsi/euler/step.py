"""Public kernels of the Eulerian solver: state conversion, time step, fault check, step (optionally
with its face transfers), integrals.

All functions are pure and jittable with ``cfg`` static; ``params`` is traced
(vmappable). The state ``U`` is an array (nvar, *shape) in the row layout of
:mod:`blastfsi.euler.config`. The arithmetic runs in U's dtype (float32 or
float64); parameters are cast to it.
"""
from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from jax.sharding import PartitionSpec

from blastfsi import xla
from blastfsi.euler import geometry, hancock, hllc, lax_wendroff
from blastfsi.euler.boundaries import blast_layer
from blastfsi.euler.config import (HLLC_HANCOCK, HLLC_MUSCL, LAX_WENDROFF, MIN_CELLS, SPLIT, Config, Params,
                                   check_config, check_params, layout)
from blastfsi.euler.mixture import cell_state, conservative_rows, eos_rows


def _setup(U, params: Params, cfg: Config):
    check_config(cfg)
    check_params(params, cfg)
    lay = layout(cfg)
    if tuple(U.shape) != (lay.nvar, *cfg.shape):
        raise ValueError(f"U must have shape {(lay.nvar, *cfg.shape)} (nvar, *Config.shape), got {tuple(U.shape)}")
    return lay, eos_rows(jnp.asarray(params.eos, U.dtype), lay.n)


def conservative(rho_k, alpha, velocity, p, params: Params, cfg: Config):
    """U from phase densities rho_k (n_materials, *shape) (or (*shape) with one material), products
    volume fraction alpha (ignored with one material), velocity (ndim, *shape) and pressure p."""
    check_config(cfg)
    check_params(params, cfg)
    lay = layout(cfg)
    p = jnp.asarray(p)
    dtype = p.dtype
    rho_k = jnp.asarray(rho_k, dtype)
    if rho_k.ndim == len(cfg.shape):
        rho_k = rho_k[None]
    if rho_k.shape[0] != lay.n:
        raise ValueError(f"rho_k needs {lay.n} phase densities (n_materials), got shape {rho_k.shape}")
    shape = tuple(cfg.shape)
    rho_k = tuple(jnp.broadcast_to(rho_k[k], shape) for k in range(lay.n))
    vel = tuple(jnp.broadcast_to(jnp.asarray(velocity, dtype)[d], shape) for d in range(lay.ndim))
    a = jnp.broadcast_to(jnp.asarray(alpha, dtype), shape) if lay.n == 2 else None
    rows, _, _ = conservative_rows(rho_k, a, vel, jnp.broadcast_to(p, shape), eos_rows(
        jnp.asarray(params.eos, dtype), lay.n), lay)
    return jnp.stack(rows)


def primitives(U, params: Params, cfg: Config) -> dict:
    """rho, velocity (ndim, *shape), pressure, internal_energy (specific e), sound_speed,
    products_fraction (mass fraction Y; zeros with one material), alpha (ones with one material)."""
    lay, eos_r = _setup(U, params, cfg)
    st = cell_state(U, eos_r, lay)
    kinetic = 0.5 * sum(U[lay.mom + d] * st.velocity[d] for d in range(lay.ndim))
    return dict(rho=st.rho, velocity=jnp.stack(st.velocity), pressure=st.p,
                internal_energy=(U[lay.energy] - kinetic) / st.rho,
                sound_speed=jnp.sqrt(st.c2),
                products_fraction=U[0] / st.rho if lay.n == 2 else jnp.zeros_like(st.rho),
                alpha=U[lay.alpha] if lay.n == 2 else jnp.ones_like(st.rho))


def _bad_and_speed(U, params, cfg):
    lay, eos_r = _setup(U, params, cfg)
    st = cell_state(U, eos_r, lay)
    bad = ~((st.rho > 0.0) & (st.p > 0.0) & (st.c2 > 0.0) & jnp.isfinite(st.rho) & jnp.isfinite(st.p)
            & jnp.isfinite(st.c2))
    c = jnp.sqrt(jnp.maximum(st.c2, 0.0))
    speeds = [jnp.abs(v) + c for v in st.velocity]
    if cfg.scheme == HLLC_MUSCL:  # unsplit
        rate = sum(speeds)
    else:  # split: the fastest axis
        rate = speeds[0]
        for s in speeds[1:]:
            rate = jnp.maximum(rate, s)
    return bad, rate


def stable_dt(U, params: Params, cfg: Config, owned=None):
    """CFL step; NaN exactly when some cell is non-physical (NaN or inf, rho <= 0, p <= 0 or c^2 <= 0).

    ``owned`` ((*shape) bool, default every cell): the cells whose update is kept. The step bounds the
    signal of these and of their face neighbours (a face's flux reads the waves of both sides); the
    cells beyond (a coupled run's fictitious cells deeper than one cell, which the scheme only reads
    through its reconstruction) do not set it. The fault check covers every cell.

    Split schemes (Lax-Wendroff, HLLC-Hancock): dt = cfl dx / max over cells and axes of (|u_d| + c);
    Lax-Wendroff's directional operators then run at Courant number <= cfl/2 (dt/2 each), so its linear
    limit is cfl = 2; HLLC-Hancock's at <= cfl (dt each, alternating), linear limit 1. HLLC-MUSCL
    (unsplit): dt = cfl dx / max over cells of sum_d (|u_d| + c), linear limit cfl = 1. Measured (Sod
    200 cells; 2D blasts of pressure ratio 10 and 1e5, 48^2 walls, 200 steps): LW runs up to cfl 1.8 in
    1D and 1.5 in 2D (NaN at 1.95 / 1.8); HLLC-MUSCL up to 1.0 (1.1 in 1D); HLLC-Hancock up to 1.2 (the
    highest tried) on 2D blasts, and the sod and sedov-2d examples (sedov-2d: ambient pressure 1e-6 of
    the blast's) at 1.1; HLLC-MUSCL the sedov-2d example at its cap 1.0. The scenario's caps per scheme:
    blastfsi.euler.scenario.CFL_MAX. cfl <= 0.5 keeps margin for the positivity of HLLC-MUSCL near
    strong blasts.
    """
    bad, rate = _bad_and_speed(U, params, cfg)
    if owned is not None:
        rate = jnp.where(_with_face_neighbours(owned), rate, 0.0)
    dt = jnp.asarray(params.cfl, U.dtype) * cfg.dx / jnp.max(rate)
    return jnp.where(jnp.any(bad), jnp.nan, dt)


def _with_face_neighbours(cells):
    """``cells`` (bool, *shape) and every cell that shares a face with one of them."""
    out = cells
    for axis in range(cells.ndim):
        padded = jnp.pad(cells, [(1, 1) if a == axis else (0, 0) for a in range(cells.ndim)])
        n = cells.shape[axis]
        out = out | jax.lax.slice_in_dim(padded, 0, n, axis=axis) | jax.lax.slice_in_dim(padded, 2, n + 2, axis=axis)
    return out


def first_bad_cell(U, params: Params, cfg: Config):
    """Flat (C-order) index of the first non-physical cell, or -1."""
    bad, _ = _bad_and_speed(U, params, cfg)
    flat = bad.reshape(-1)
    return jnp.where(jnp.any(flat), jnp.argmax(flat), -1)


def _scheme(cfg: Config):
    """The scheme's step (U, dt, eos_r, cfg, lay, moved=None, parity=0); only HLLC-Hancock reads ``parity``
    (it alternates its sweeps)."""
    if cfg.scheme == HLLC_HANCOCK:
        return hancock.step
    plain = {LAX_WENDROFF: lax_wendroff.step, HLLC_MUSCL: hllc.step}[cfg.scheme]
    return lambda U, dt, eos_r, cfg, lay, moved=None, parity=0: plain(U, dt, eos_r, cfg, lay, moved)


def _kernel(cfg: Config, parity):
    """The scheme's step (U, dt, eos_r, cfg, lay, moved) at ``parity``; a grid split over devices steps slab by
    slab (:func:`_slab_by_slab`)."""
    if cfg.devices > 1 and cfg.shape[0] // cfg.devices >= MIN_CELLS:
        return functools.partial(_slab_by_slab, _scheme(cfg), parity)
    return functools.partial(_scheme(cfg), parity=parity)


def _slab_by_slab(scheme, parity, U, dt, eos_r, cfg: Config, lay, moved=None):
    """The step of a grid split in slabs along x over cfg.devices devices, halos exchanged by hand: inside
    ``shard_map`` each device steps its own slab, whose x edges (kinds + SPLIT) take their ghost cells from the
    neighbouring slabs (boundaries.py: one collective permute per side and exchange point, all rows at once)
    and those of the boundary at the domain's ends; a radial metric is the whole grid's, cut at the slab's
    place (geometry.py). The compiler's own partitioning of the whole grid's step exchanged each row and
    stencil shift on its own (46 permutes in sedov-2d's compiled HLLC-MUSCL step, against 2) and was 1.6-4.3x
    slower on 2-8 virtual CPU devices (benchmarks/halo_exchange.py). The step with face transfers (``moved``:
    the coupled solver's, whose grid is not split) keeps the compiler's partitioning, as do slabs thinner than
    the ghost depth MIN_CELLS."""
    if moved is not None:
        return scheme(U, dt, eos_r, cfg, lay, moved, parity=parity)
    lo, hi = cfg.bc[0]
    slab = cfg._replace(shape=(cfg.shape[0] // cfg.devices, *cfg.shape[1:]), bc=((lo + SPLIT, hi + SPLIT), *cfg.bc[1:]))
    rows, whole = PartitionSpec(None, xla.SPLIT_AXIS), PartitionSpec()
    local = jax.shard_map(lambda u, dt, eos_r, parity: scheme(u, dt, eos_r, slab, lay, parity=parity),
                          mesh=xla.split_sharding(cfg.devices, 1).mesh, in_specs=(rows, whole, whole, whole),
                          out_specs=rows, check_vma=False)
    return local(U, dt, eos_r, jnp.asarray(parity))


def step(U, dt, params: Params, cfg: Config, t=None, parity=0):
    """One full time step of length dt from time t with the scheme of cfg.scheme; with a blast table
    (``params.blast``) its layer is then set at t + dt (:func:`with_blast`). ``parity``: the step's index
    (modulo 2, may be traced), which alternates HLLC-Hancock's sweep order (hancock.py); a loop of steps
    passes its counter, or that scheme is first order in time."""
    lay, eos_r = _setup(U, params, cfg)
    return with_blast(_kernel(cfg, parity)(U, jnp.asarray(dt, U.dtype), eos_r, cfg, lay), t, dt, params, cfg)


@functools.partial(jax.jit, static_argnums=(3,))
def advance_to(U, params: Params, t_end, cfg: Config):
    """``U`` advanced from t = 0 to ``t_end`` at the stable step (:func:`stable_dt`; the last step shortened
    onto t_end), in one compiled loop: the kernels' own time loop, without output (the runs' loop, with
    output, gauges and faults, is :func:`blastfsi.timeloop.run_until`)."""
    def body(state):
        V, t, k = state
        dt = jnp.minimum(stable_dt(V, params, cfg), t_end - t)
        return step(V, dt, params, cfg, parity=k), t + dt, k + 1
    return jax.lax.while_loop(lambda s: s[1] < t_end, body, (U, jnp.zeros((), U.dtype), jnp.zeros((), jnp.int32)))[0]


def with_blast(U, t, dt, params: Params, cfg: Config):
    """U with the blast layer of ``params.blast`` set to the free field at t + dt
    (:func:`blastfsi.euler.boundaries.blast_layer`); U itself without a table. A table needs t."""
    if params.blast is None:
        return U
    if t is None:
        raise ValueError("a step with a blast table (Params.blast) needs the time t of its start")
    return blast_layer(U, jnp.asarray(t, U.dtype) + jnp.asarray(dt, U.dtype), params.blast, layout(cfg))


def face_shape(cfg: Config, axis: int) -> tuple:
    """Shape of the faces of one axis: cfg.shape with shape[axis] + 1 (face f between cells f-1 and f)."""
    return tuple(m + (d == axis) for d, m in enumerate(cfg.shape))


def step_with_transfers(U, dt, params: Params, cfg: Config, parity=0):
    """(U_new, transfers): U_new as step(U, dt, params, cfg) gives it without the blast layer (apply
    :func:`with_blast` after it, booking its change as inflow) and the amounts each face passed
    (``parity`` as in :func:`step`).

    transfers: one array per axis a, of shape (nvar, *face_shape(cfg, a)). T[r, ..., f, ...] is the
    amount of row r moved across face f of axis a (between cells f-1 and f) from the low to the
    high side during the step, as a row-r density (content per unit cell volume) with the
    geometric factors removed: the cell below the face changes by -g+ T, the cell above by +g- T
    (g+- = geometry.flux_factors on the radial axis of a cylindrical/spherical grid, 1 elsewhere).
    For every row but the products fraction (and, off Cartesian grids, the radial momentum, which
    also feels the pressure force p (A+ - A-)/V) a cell's change is exactly (to round-off) the sum
    of these face terms. The physical content through a face is T dx times its area: dx^(ndim-1)
    (Cartesian), 2 pi r_f dx^(ndim-1) or 4 pi r_f^2 (radial faces, cylindrical or spherical; per
    unit length in 1D cylindrical), pi (r+^2 - r-^2) (axial faces of an r-z grid), consistent
    with geometry.cell_volumes (V_i g+-_i = A_{i+-1/2} dx, geometry.py). The products-fraction
    row holds its conservative part (the flux of alpha u, with Lax-Wendroff's viscous term); its
    alpha div u term is a cell source. Schemes: lax_wendroff.py, hllc.py and hancock.py (module docstrings).

    All schemes read the transfers off the update's own intermediates, at about the cost of a
    plain step. XLA:CPU then contracts a*b + c into fused multiply-adds differently, so U_new may
    differ from step's in the last bits (1 ulp, in 5 of the 10 configurations of
    tests/test_euler_transfers.py; bit-identical in all 10 with FMA disabled,
    XLA_FLAGS=--xla_cpu_max_isa=SSE4_2); recomputing the transfers behind an optimization barrier
    kept U_new bit-identical at twice the cost. The transfers balance U_new to round-off.
    """
    lay, eos_r = _setup(U, params, cfg)
    zeros = tuple((jnp.zeros(face_shape(cfg, a), U.dtype),) * lay.nvar for a in range(lay.ndim))
    U_new, moved = _kernel(cfg, parity)(U, jnp.asarray(dt, U.dtype), eos_r, cfg, lay, zeros)
    return U_new, tuple(jnp.stack(m) for m in moved)


def total(U, cfg: Config):
    """(mass, momentum (ndim,), energy): volume integrals over the grid (geometry.cell_volumes).

    In cylindrical/spherical geometry only mass, energy and the axial momentum
    are conserved; the radial entry is the integral of rho u_r.
    """
    check_config(cfg)
    lay = layout(cfg)
    vol = geometry.cell_volumes(cfg, U.dtype)
    axes = tuple(range(1, U.ndim))
    sums = jnp.sum(U * vol, axis=axes)
    return sums[:lay.n].sum(), sums[lay.mom:lay.mom + lay.ndim], sums[lay.energy]
