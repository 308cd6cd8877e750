"""Face transfers of the Eulerian schemes (euler.step_with_transfers), for conservative coupling.

All schemes change every conserved row of a cell only through face terms (the radial momentum
also through the pressure force p (A+ - A-)/V; the products fraction through alpha div u), so
a step's face transfers T must balance the change of U cell by cell,

    U_new_i - U_i = sum_axes (g-_i T_{i-1/2} - g+_i T_{i+1/2}),

and the content of any sub-box must change by the content through its faces, T dx (face area).

Round-off bound used below: a cell value passes through at most 2 ndim operators (Lax-Wendroff,
HLLC-Hancock) or 2 stages of ndim face differences (HLLC-MUSCL), a few roundings of size eps s each, with s the
largest magnitude of the row or its transfers; the discrepancy is then below ~50 eps s = 1e-14 s.
The per-cell tolerance 1e-13 s leaves a factor 10; a missing or mis-weighted face term (a sweep,
the viscous flux, an RK weight) would show at the size of the step's change, here >= 1e-2 s.
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import euler
from blastfsi.eos.jwl import ideal_gas_params
from blastfsi.euler import geometry
from blastfsi.euler.config import layout
from blastfsi.materials.gases import GASES

AIR = ideal_gas_params(1.4)
TNT = GASES["tnt"].eos_params()
O, W, A, P = euler.OUTFLOW, euler.WALL, euler.AXIS, euler.PERIODIC
PER_CELL = 1e-13  # relative round-off tolerance (module docstring)

CASES = {  # shape, geometry, bc, materials: outflow, walls and a periodic axis, alpha varying
    "1d": ((12,), euler.CARTESIAN, ((O, W),), 2),
    "2d": ((10, 8), euler.CARTESIAN, ((W, O), (P, P)), 2),
    "3d": ((5, 4, 4), euler.CARTESIAN, ((O, W), (P, P), (W, O)), 1),
    "spherical": ((12,), euler.SPHERICAL, ((A, O),), 2),
    "axisymmetric": ((10, 8), euler.CYLINDRICAL, ((A, O), (W, O)), 1),
}
SCHEMES = (euler.LAX_WENDROFF, euler.HLLC_MUSCL, euler.HLLC_HANCOCK)
# compiles take 6-34 s each on the shared 2-core machine (step + recorded step): the default suite keeps the
# 2D Cartesian case of every scheme (walls, outflow and a periodic axis) and Lax-Wendroff's 1D case, the rest runs
# with -m slow
SLOW = {(s, c) for s in SCHEMES for c in ("3d", "spherical", "axisymmetric")} | {(euler.HLLC_MUSCL, "1d"),
                                                                                 (euler.HLLC_HANCOCK, "1d")}


def runs(keep=lambda case: True):
    """pytest parameters (scheme, case) of every scheme, the cases kept by keep(case)."""
    return [pytest.param(scheme, case, marks=[pytest.mark.slow] if (scheme, case) in SLOW else [])
            for scheme in SCHEMES for case in CASES if keep(case)]


step = jax.jit(euler.step, static_argnums=3)
step_with_transfers = jax.jit(euler.step_with_transfers, static_argnums=3)
stable_dt = jax.jit(euler.stable_dt, static_argnums=2)


def initial_state(cfg):
    """A blast (pressure ratio 5) in a products ball (alpha 0.05..0.95) with smooth waves in density,
    pressure and velocity (|u| up to ~80 m/s, pointing out of and into the outflow faces)."""
    x = np.meshgrid(*[(np.arange(m) + 0.5) / m for m in cfg.shape], indexing="ij")
    r2 = sum((xi - 0.4) ** 2 for xi in x)
    wave = np.prod([np.sin(2.0 * np.pi * xi + k) for k, xi in enumerate(x)], axis=0)
    p = 1.0e5 * (1.0 + 4.0 * np.exp(-r2 / 0.03) + 0.2 * wave)
    alpha = 0.05 + 0.9 / (1.0 + np.exp((np.sqrt(r2) - 0.25) / 0.05))
    rho = np.stack([1.6 * (1.0 + 0.2 * wave), 1.2 * (1.0 - 0.2 * wave)])[2 - cfg.n_materials:]
    vel = np.stack([60.0 * np.cos(2.0 * np.pi * xi + d) + 20.0 * wave for d, xi in enumerate(x)])
    prm = euler.Params(jnp.asarray([list(TNT), list(AIR)][2 - cfg.n_materials:]), jnp.asarray(0.45))
    U = euler.conservative(jnp.asarray(rho), jnp.asarray(alpha), jnp.asarray(vel), jnp.asarray(p), prm, cfg)
    return U, prm


@functools.lru_cache(maxsize=None)
def run(scheme, case):
    """(cfg, U, U_new, transfers, U_new of euler.step) of one recorded step after 3 plain steps."""
    shape, geom, bc, n = CASES[case]
    cfg = euler.Config(shape, 0.01, geom, bc, scheme, n, (0.0,) * len(shape))
    U, prm = initial_state(cfg)
    for _ in range(3):
        U = step(U, stable_dt(U, prm, cfg), prm, cfg)
    dt = stable_dt(U, prm, cfg)
    U_new, T = step_with_transfers(U, dt, prm, cfg)
    return cfg, np.asarray(U), np.asarray(U_new), [np.asarray(t) for t in T], np.asarray(step(U, dt, prm, cfg))


def balanced_rows(cfg):
    """Rows changed only by face terms: all but the products fraction and, off Cartesian grids, the
    radial momentum."""
    lay = layout(cfg)
    return [r for r in range(lay.nvar) if r != lay.alpha and not (cfg.geometry and r == lay.mom)]


def faces(t, axis, lo, hi):
    """Faces lo..hi-1 of transfer array t along grid axis `axis`."""
    return np.take(t, np.arange(lo, hi), axis=1 + axis)


def face_areas(cfg, axis):
    """Physical area of every face of one axis (broadcastable to its transfers without the row axis)."""
    nd, j = len(cfg.shape), cfg.geometry
    if axis == 0 and j != euler.CARTESIAN:
        r = cfg.origin[0] + cfg.dx * np.arange(cfg.shape[0] + 1)
        area = (2.0 * np.pi * r if j == euler.CYLINDRICAL else 4.0 * np.pi * r ** 2) * cfg.dx ** (nd - 1)
        return area.reshape((-1,) + (1,) * (nd - 1))
    return geometry.cell_volumes(cfg, np.float64) / cfg.dx  # dx^(nd-1), or pi (r+^2 - r-^2) on r-z axial faces


def scale(U, T, r):
    return max(np.abs(U[r]).max(), max(np.abs(t[r]).max() for t in T))


@pytest.mark.parametrize("scheme, case", runs())
def test_every_cell_changes_by_its_face_transfers(scheme, case):
    """U_new - U = sum over axes (g- T_low - g+ T_high) in every cell for every balanced row."""
    cfg, U, U_new, T, _ = run(scheme, case)
    change = U_new - U
    for a, t in enumerate(T):
        m = cfg.shape[a]
        lo, hi = faces(t, a, 0, m), faces(t, a, 1, m + 1)
        if a == 0 and cfg.geometry != euler.CARTESIAN:
            gp, gm = geometry.flux_factors(cfg, 0, m, np.float64)
            lo, hi = gm * lo, gp * hi
        change = change - (lo - hi)
    errors = {r: np.abs(change[r]).max() / scale(U, T, r) for r in balanced_rows(cfg)}
    print(f"scheme {scheme} {case}: max per-cell identity error / scale = {max(errors.values()):.2e}")
    assert max(errors.values()) < PER_CELL, errors
    assert max(np.abs(U_new[r] - U[r]).max() / scale(U, T, r) for r in balanced_rows(cfg)) > 1e-2  # a real step


@pytest.mark.parametrize("scheme, case", runs())
def test_sub_box_content_changes_by_content_through_its_faces(scheme, case):
    """Cut planes f along axis 0: the content of cells i < f (geometry.cell_volumes) changes by
    dx (face area) T summed over the sub-box's faces: in at face 0, out at the cut, and the
    lateral boundary faces of the other axes (the documented physical content of a transfer)."""
    cfg, U, U_new, T, _ = run(scheme, case)
    vol = np.broadcast_to(geometry.cell_volumes(cfg, np.float64), cfg.shape)
    worst = 0.0
    for f in range(1, cfg.shape[0] + 1):
        content = (faces(U_new - U, 0, 0, f) * vol[:f]).sum(axis=tuple(range(1, U.ndim)))
        through = cfg.dx * T[0] * face_areas(cfg, 0)
        moved = faces(through, 0, 0, 1) - faces(through, 0, f, f + 1)
        moved = moved.sum(axis=tuple(range(1, U.ndim)))
        for a in range(1, len(cfg.shape)):
            side = faces(cfg.dx * T[a] * face_areas(cfg, a), 0, 0, f)
            m = cfg.shape[a]
            moved = moved + (faces(side, a, 0, 1) - faces(side, a, m, m + 1)).sum(axis=tuple(range(1, U.ndim)))
        for r in balanced_rows(cfg):
            bound = 10.0 * PER_CELL * scale(U, T, r) * vol[:f].sum()  # sum of per-cell bounds, x10 for the sums
            worst = max(worst, abs(content[r] - moved[r]) / (scale(U, T, r) * vol[:f].sum()))
            assert abs(content[r] - moved[r]) < bound, (f, r, content[r], moved[r])
    print(f"scheme {scheme} {case}: max cut-plane error / (scale x sub-box volume) = {worst:.2e}")


@pytest.mark.parametrize("scheme, case", runs())
def test_no_transfer_through_mirror_faces(scheme, case):
    """At a wall, symmetry plane or axis the mirror ghost state makes the face velocity 0: no mass
    (nor energy, tangential momentum, products fraction) crosses; only the normal momentum
    (pressure impulse) does. Lax-Wendroff: exactly 0 (the corrector flux is a product with the
    face velocity, which cancels exactly). HLLC (both schemes): its flux w_L q v_L + w_R q v_R with v_R = -v_L
    cancels exactly in IEEE arithmetic, but XLA:CPU may contract it into a fused multiply-add,
    which leaves the rounding error of one product: below eps of the row's scale (exactly 0
    with FMA disabled, XLA_FLAGS=--xla_cpu_max_isa=SSE4_2)."""
    cfg, U, _, T, _ = run(scheme, case)
    lay = layout(cfg)
    checked = 0
    for a, pair in enumerate(cfg.bc):
        for side, kind in enumerate(pair):
            if kind in (W, A):
                f = side * cfg.shape[a]
                wall = faces(T[a], a, f, f + 1)
                for r in range(lay.nvar):
                    if r == lay.mom + a:
                        assert np.abs(wall[r]).max() > 0.0
                        continue
                    bound = 0.0 if scheme == euler.LAX_WENDROFF else np.finfo(float).eps * scale(U, T, r)
                    assert np.abs(wall[r]).max() <= bound, (a, side, r, np.abs(wall[r]).max())
                checked += 1
    assert checked > 0


@pytest.mark.parametrize("scheme, case", runs(lambda case: (P, P) in CASES[case][2]))
def test_periodic_faces_agree(scheme, case):
    """Faces 0 and n of a periodic axis are the same face: equal transfers."""
    cfg, U, _, T, _ = run(scheme, case)
    a = [pair for pair in cfg.bc].index((P, P))
    m = cfg.shape[a]
    for r in range(layout(cfg).nvar):
        gap = np.abs(faces(T[a], a, 0, 1)[r] - faces(T[a], a, m, m + 1)[r]).max()
        assert gap < PER_CELL * scale(U, T, r)


@pytest.mark.parametrize("scheme, case", runs())
def test_recording_leaves_the_step_unchanged(scheme, case):
    """U_new of step_with_transfers equals euler.step's to the last bits: it reads the transfers off the
    update itself, whose fused multiply-adds then contract differently (a few ulp of each row's scale)."""
    _, _, U_new, _, U_step = run(scheme, case)
    for r in range(U_new.shape[0]):
        assert np.max(np.abs(U_new[r] - U_step[r])) <= 8 * np.finfo(float).eps * np.max(np.abs(U_step[r]))


@pytest.mark.parametrize("scheme, case", [(euler.LAX_WENDROFF, "2d"), (euler.LAX_WENDROFF, "axisymmetric"),
                                          (euler.HLLC_MUSCL, "2d")]
                         + [pytest.param(s, c, marks=pytest.mark.slow) for s, c in
                            ((euler.HLLC_MUSCL, "axisymmetric"), (euler.HLLC_HANCOCK, "2d"),
                             (euler.HLLC_HANCOCK, "axisymmetric"))])
def test_blocked_sweeps_equal_the_whole_grid(scheme, case, monkeypatch):
    """All schemes sweep grids of more than blocking.BLOCKED_ABOVE cells block by block (a loop over
    slabs along another axis, updated in place: the directional operators of Lax-Wendroff and
    HLLC-Hancock, HLLC-MUSCL's flux divergence of each axis). The blocks must give the whole-grid step
    and transfers: the same per-cell arithmetic, so equal up to how XLA contracts multiply-adds (a few
    ulp of each row's scale, as in test_recording_leaves_the_step_unchanged). The shipped threshold
    leaves every test grid whole, so the blocks are forced here: several planes per block on one axis,
    one plane on the other. (HLLC-Hancock's cases run with -m slow, for their compile time: its operators share
    lax_wendroff's split_step and blocking, which the default cases cover.)"""
    from blastfsi.euler import blocking

    shape, geom, bc, n = CASES[case]
    cfg = euler.Config(shape, 0.01, geom, bc, scheme, n, (0.0,) * len(shape))
    U, prm = initial_state(cfg)
    dt = stable_dt(U, prm, cfg)

    def both():  # fresh jitted functions: the block plan is read when they are traced
        plain = jax.jit(lambda u: euler.step(u, dt, prm, cfg))(U)
        recorded = jax.jit(lambda u: euler.step_with_transfers(u, dt, prm, cfg))(U)
        return np.asarray(plain), np.asarray(recorded[0]), [np.asarray(t) for t in recorded[1]]

    whole = both()
    monkeypatch.setattr(blocking, "BLOCKED_ABOVE", 0)
    monkeypatch.setattr(blocking, "BLOCK_CELLS", 2 * min(shape))
    assert all(blocking.blocks(cfg, a) is not None for a in range(len(shape)))
    blocked = both()
    tol = 8 * np.finfo(float).eps
    for w, b in zip(whole[:2] + tuple(whole[2]), blocked[:2] + tuple(blocked[2])):
        assert np.all(np.abs(w - b) <= tol * np.max(np.abs(w), axis=tuple(range(1, w.ndim)), keepdims=True))
    assert not np.array_equal(whole[0], U)  # the step did change the state


@pytest.mark.parametrize("scheme", [pytest.param(euler.LAX_WENDROFF, marks=pytest.mark.slow), euler.HLLC_MUSCL,
                                    pytest.param(euler.HLLC_HANCOCK, marks=pytest.mark.slow)])
def test_accelerator_control_flow_gives_the_same_step(scheme, monkeypatch):
    """Where a conditional or a loop iteration costs a host round trip (a GPU), the kernels select
    between computed branches and unroll the operator and stage loops (blastfsi.xla); forced here on
    the CPU on the two-material 2D case (the JWL terms of the products phase taken, the air's not): the
    step and its transfers equal the CPU form's up to how XLA contracts multiply-adds (as in
    test_blocked_sweeps_equal_the_whole_grid)."""
    from blastfsi import xla

    shape, geom, bc, n = CASES["2d"]
    cfg = euler.Config(shape, 0.01, geom, bc, scheme, n, (0.0,) * len(shape))
    U, prm = initial_state(cfg)
    dt = stable_dt(U, prm, cfg)

    def both():  # fresh jitted functions: the form is chosen when they are traced
        plain = jax.jit(lambda u: euler.step(u, dt, prm, cfg))(U)
        recorded = jax.jit(lambda u: euler.step_with_transfers(u, dt, prm, cfg))(U)
        return [np.asarray(plain), np.asarray(recorded[0])] + [np.asarray(t) for t in recorded[1]]

    cpu = both()
    monkeypatch.setattr(xla, "device_control_flow", lambda: False)
    accelerator = both()
    tol = 8 * np.finfo(float).eps
    for c, a in zip(cpu, accelerator):
        assert np.all(np.abs(c - a) <= tol * np.max(np.abs(c), axis=tuple(range(1, c.ndim)), keepdims=True))
    assert not np.array_equal(cpu[0], U)
