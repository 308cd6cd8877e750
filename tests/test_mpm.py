"""MPM solver core (000 Sec. 2.2): shape functions, grid, particle pool, MUSL invariants.

Tiers 1-2: point values of the kernels and invariants of the step (exact mass,
momentum to round-off, Galilean invariance, exact free fall, prescribed loads).
Verification against closed-form solutions lives in
tests/verification/test_mpm_verification.py.
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import mpm
from blastfsi.constitutive import Model
from blastfsi.mpm import viscosity

E, NU, RHO = 1.0e4, 0.3, 1.0e3  # a soft test solid, c ~ 3.7 m/s
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def _hooke_update(ps, dstrain, dspin, dt, params):
    """Local test double of a hypoelastic solid (000 Eq. 30 with Hooke's increment and the
    midpoint-stress energy of Eq. 13), written with elementwise ops only so that it compiles fast;
    the registered ``elastic`` model is exercised in tests/verification/test_mpm_verification.py."""
    K, G = params
    s = jnp.stack([jnp.stack([ps.stress[:, VOIGT.index(tuple(sorted((i, j))))] for j in range(3)], -1)
                   for i in range(3)], -2)
    rot = jnp.sum(dspin[:, :, :, None] * s[:, None, :, :], axis=2)  # (dW sigma)_ij
    tr = dstrain[:, 0, 0] + dstrain[:, 1, 1] + dstrain[:, 2, 2]
    ds = 2.0 * G * dstrain + ((K - 2.0 * G / 3.0) * tr)[:, None, None] * jnp.eye(3)
    new = s + rot + jnp.swapaxes(rot, 1, 2) + ds
    work = 0.5 * jnp.sum((s + new) * dstrain, axis=(1, 2))
    rho_old = ps.density * (1.0 + tr)
    stress = jnp.stack([new[:, i, j] for i, j in VOIGT], -1)
    return ps._replace(stress=stress, energy=ps.energy + work / rho_old)


def _hooke_wave_speed(ps, params):
    K, G = params
    return jnp.sqrt((K + 4.0 * G / 3.0) / ps.density)


ELASTIC = Model("test-hooke", _hooke_update, _hooke_wave_speed, None, 0)
EPS = np.finfo(float).eps
CAPACITY = 128


def elastic_params(youngs=E, nu=NU):
    """(K, G) from Young's modulus and Poisson's ratio."""
    return (youngs / (3.0 * (1.0 - 2.0 * nu)), youngs / (2.0 * (1.0 + nu)))


def setup(grid, lower, upper, *, shape="linear", v=None, ppc=2, capacity=CAPACITY, q=(0.0, 0.0),
          gravity=(0.0,) * 3, cfl=0.5, youngs=E, nu=NU, prescribed=False, blend=False):
    """A body filling [lower, upper] with velocity field v(x) -> (n, 3), in a pool of ``capacity``
    (one capacity for all tests, so tests on the same grid share one compiled step)."""
    x, vol, half = mpm.lattice(grid, lower, upper, ppc)
    vel = np.zeros_like(x) if v is None else v(x)
    batch = mpm.new_particles(x, vol, RHO, v=vel, half_size=half)
    pool = mpm.make_pool(batch, capacity)
    cfg = mpm.make_config(grid, (ELASTIC,), shape=shape, prescribed=prescribed, blend=blend)
    prm = mpm.make_params((elastic_params(youngs, nu),), cfl=cfl, q_quadratic=q[0], q_linear=q[1], gravity=gravity)
    return initialize(pool, prm, cfg), prm, cfg


@functools.partial(jax.jit, static_argnames="cfg")
def advance(state, dt, nsteps, prm, cfg):
    """nsteps MUSL steps in one compiled loop (compiled once per configuration)."""
    return jax.lax.fori_loop(0, nsteps, lambda i, s: mpm.step(s, dt, prm, cfg), state)


totals = jax.jit(mpm.totals)
initialize = jax.jit(mpm.initialize, static_argnames="config")
first_fault = jax.jit(mpm.first_fault, static_argnames="config")
stable_dt = jax.jit(mpm.stable_dt, static_argnames="config")
GRID2 = mpm.Grid(origin=(0.0, 0.0), cell_size=0.1, cells=(12, 12))
GRID3 = mpm.Grid(origin=(0.0, 0.0, 0.0), cell_size=0.1, cells=(6, 6, 6))
GRID1 = mpm.Grid(origin=(0.0,), cell_size=0.05, cells=(40,))


# --- shape functions -------------------------------------------------------------------------


@pytest.mark.parametrize("shape", ["linear", "gimp"])
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_partition_of_unity_and_gradient(shape, dim):
    grid = mpm.Grid(origin=(0.0,) * dim, cell_size=0.5, cells=(6,) * dim)
    rng = np.random.default_rng(dim)
    x = np.zeros((200, 3))
    x[:, :dim] = rng.uniform(0.6, 2.4, (200, dim))  # GIMP domains inside the grid
    half = np.full((200, 3), 0.125)  # two particles per cell
    idx, w, grad = jax.jit(lambda a: mpm.stencil(a, jnp.asarray(half), grid, mpm.SHAPES[shape]))(jnp.asarray(x))
    idx, w, grad = idx.T, w.T, tuple(g.T for g in grad)  # (n, S)
    assert np.allclose(np.sum(w, axis=1), 1.0, atol=10 * EPS)
    for g in grad:
        assert np.allclose(np.sum(g, axis=1), 0.0, atol=10 * EPS / grid.cell_size)
    # linear completeness: sum_I N_I x_I = x_p and sum_I dN_I/dx_j x_Ii = delta_ij
    nodes = grid.node_positions()[np.asarray(idx)]
    assert np.allclose(np.einsum("ns,nsk->nk", w, nodes), x, atol=1e-14)
    for j, g in enumerate(grad):
        assert np.allclose(np.einsum("ns,nsk->nk", g, nodes)[:, :dim], np.eye(dim)[j], atol=1e-12)


def test_gimp_is_hat_averaged_over_particle_domain():
    """uGIMP weight = (1/2l) int N_hat over [x_p - l, x_p + l] (Bardenhagen & Kober 2004), from the
    hat's antiderivative H; its gradient = (N_hat(r + l) - N_hat(r - l)) / 2l."""
    grid = mpm.Grid(origin=(0.0,), cell_size=1.0, cells=(8,))
    hat = lambda y: np.maximum(0.0, 1.0 - np.abs(y))  # noqa: E731
    H = lambda y: np.where(y < 0.0, 0.5 * np.clip(1.0 + y, 0.0, None) ** 2,  # noqa: E731
                           1.0 - 0.5 * np.clip(1.0 - y, 0.0, None) ** 2)
    xp = np.linspace(2.0, 5.0, 61)
    x = jnp.asarray(np.pad(xp[:, None], ((0, 0), (0, 2))))
    gimp = jax.jit(lambda half: mpm.stencil(x, half, grid, mpm.GIMP))
    for l in (0.5, 0.25, 0.1):
        idx, w, (g,) = gimp(jnp.full((61, 3), l))
        idx, w, g = idx.T, w.T, g.T  # (n, S)
        r = xp[:, None] - np.asarray(idx)
        assert np.allclose(np.asarray(w), (H(r + l) - H(r - l)) / (2 * l), rtol=0.0, atol=1e-14)
        assert np.allclose(np.asarray(g), (hat(r + l) - hat(r - l)) / (2 * l), rtol=0.0, atol=1e-13)


# --- grid ------------------------------------------------------------------------------------


def test_grid_faces():
    grid = mpm.Grid(origin=(0.0, 0.0), cell_size=1.0, cells=(2, 3), boundaries=(("fixed", "slip"), ("free", "slip")))
    v = np.asarray(jax.jit(mpm.apply_boundaries, static_argnums=1)(jnp.ones((grid.num_nodes, 2)), grid))
    v = v.reshape(3, 4, 2)
    assert np.all(v[0] == 0.0)  # fixed x = 0 face
    assert np.all(v[2, :, 0] == 0.0) and np.all(v[1:, :3, 1] == 1.0)  # slip x = 2 face: normal (x) component
    assert np.all(v[1:, 3, 1] == 0.0) and np.all(v[1, :, 0] == 1.0)  # slip y = 3 face: y component only
    assert np.all(v[1, 0] == 1.0)  # free y = 0 face


@pytest.mark.parametrize("kw, key", [
    (dict(cells=(0,)), "grid.cells[0]"),
    (dict(cells=(1, 2, 3, 4)), "grid.cells"),
    (dict(cell_size=-1.0), "grid.cell_size"),
    (dict(origin=(0.0, 0.0)), "grid.origin"),
    (dict(boundaries=(("fixed", "sticky"),)), "grid.boundaries[0].high"),
    (dict(axisymmetric=True), "grid.axisymmetric"),
])
def test_grid_rejects_bad_input(kw, key):
    args = dict(origin=(0.0,), cell_size=1.0, cells=(4,)) | kw
    with pytest.raises(mpm.GridError, match=key.replace("[", r"\[").replace("]", r"\]")):
        mpm.Grid(**args)
    with pytest.raises(mpm.GridError, match=r"grid.origin\[0\]"):
        mpm.Grid(origin=(-1.0, 0.0), cell_size=1.0, cells=(4, 4), axisymmetric=True)


def test_solver_rejects_bad_input():
    grid = mpm.Grid(origin=(0.0,), cell_size=1.0, cells=(4,))
    with pytest.raises(mpm.MPMError, match="numerics.shape"):
        mpm.make_config(grid, (ELASTIC,), shape="cubic")
    with pytest.raises(mpm.MPMError, match="numerics.cfl"):
        mpm.make_params((elastic_params(),), cfl=1.5)
    with pytest.raises(mpm.MPMError, match="numerics.q_linear"):
        mpm.make_params((elastic_params(),), q_linear=-0.1)
    with pytest.raises(mpm.MPMError, match="numerics.pic_fraction"):
        mpm.make_params((elastic_params(),), pic_fraction=1.5)
    with pytest.raises(mpm.MPMError, match="numerics.reference_pressure"):
        mpm.make_params((elastic_params(),), reference_pressure=-1.0e5)
    with pytest.raises(mpm.ParticleError, match="smaller than one particle spacing"):
        mpm.lattice(grid, (1.0,), (1.1,), 2)
    with pytest.raises(mpm.ParticleError, match="leaves the grid"):
        mpm.lattice(grid, (1.0,), (5.0,), 2)
    with pytest.raises(mpm.ParticleError, match="leaves the grid"):
        mpm.lattice(grid, (grid.origin[0] - 0.01 * grid.cell_size,), (1.0,), 2)
    # a box whose edges are cell edges computed in floating point (x_c - h/2) is inside: the grid
    # origin 0.02 - 0.002 is 0.018000000000000002 > 0.018 (a coupled r-z run's ring cells hit this)
    edge = mpm.Grid(origin=(0.02 - 0.002,), cell_size=0.002, cells=(10,))
    assert len(mpm.lattice(edge, (0.018,), (0.02,), 2)[0]) == 2
    with pytest.raises(mpm.ParticleError, match="capacity"):
        mpm.empty(0)
    with pytest.raises(mpm.ParticleError, match="volume"):
        mpm.new_particles([[0.5]], [-1.0], RHO)


def test_check_particles_names_the_field():
    x, vol, half = mpm.lattice(GRID2, (0.2, 0.2), (0.4, 0.4), 2)
    cfg = mpm.make_config(GRID2, (ELASTIC,), shape="gimp")
    good = mpm.new_particles(x, vol, RHO, half_size=half)
    mpm.check_particles(good, cfg)
    cases = [
        (dict(x=_set(good.x, (3, 0), 1.5)), r"particles.x: particle 3 at .* outside the grid"),
        (dict(x=_set(good.x, (2, 2), 0.1)), r"particles.x: particle 2 has a non-zero component"),
        (dict(v=_set(good.v, (6, 2), 0.1)), r"particles.v: particle 6 has a non-zero component"),
        (dict(material=_set(good.material, 5, 1)), r"particles.material: particle 5 has index 1"),
        (dict(half_size=_set(good.half_size, (4, 1), 0.06)), r"particles.half_size: particle 4"),
        (dict(mass=_set(good.mass, 1, 0.0)), r"particles.mass: particle 1"),
    ]
    for change, message in cases:
        with pytest.raises(mpm.ParticleError, match=message):
            mpm.check_particles(good._replace(**change), cfg)
    axi = mpm.make_config(mpm.Grid(origin=(0.0, 0.0), cell_size=0.1, cells=(4, 4), axisymmetric=True), (ELASTIC,))
    with pytest.raises(mpm.ParticleError, match="radius <= 0"):
        mpm.check_particles(good._replace(x=_set(good.x, (0, 0), 0.0)), axi)


# --- particle pool ---------------------------------------------------------------------------


def _batch(n, seed, size=8):
    """``n`` active particles in a batch of ``size`` slots (one shape, one compile)."""
    rng = np.random.default_rng(seed)
    batch = mpm.new_particles(rng.uniform(0.1, 0.9, (size, 2)), rng.uniform(1.0, 2.0, size), RHO,
                              v=rng.standard_normal((size, 2)), energy=rng.uniform(0.0, 5.0, size))
    return batch._replace(active=jnp.asarray(np.arange(size) < n))


def _set(a, index, value):
    """A host copy of ``a`` with ``a[index] = value`` (no compiled scatter)."""
    b = np.array(a)
    b[index] = value
    return b


def _same_totals(a, b):
    return all(np.allclose(x, y, rtol=1e-13, atol=0.0) for x, y in zip(a, b))


add_particles = jax.jit(mpm.add_particles)


def test_pool_add_remove_compact_keep_totals():
    grid = mpm.Grid(origin=(0.0, 0.0), cell_size=0.25, cells=(4, 4))
    gone = jnp.asarray(np.isin(np.arange(16), [1, 4, 8]))
    a, b, c = _batch(7, 0), _batch(5, 1), _batch(3, 2)
    pool, n1 = add_particles(mpm.empty(16), a)
    pool, n2 = add_particles(pool, b)
    removed_pool, removed = jax.jit(mpm.remove_particles)(pool, gone)
    refilled, n3 = add_particles(removed_pool, c)
    compacted = jax.jit(mpm.compact)(removed_pool)
    ordered = jax.jit(mpm.sort_by_cell, static_argnums=1)(refilled, grid)
    assert [int(k) for k in (n1, n2, n3)] == [7, 12, 12]
    both = totals(pool)
    assert _same_totals(both, [x + y for x, y in zip(totals(a), totals(b))])
    assert float(removed.mass) > 0.0
    assert _same_totals(totals(removed_pool), [x - y for x, y in zip(both, removed)])
    assert np.all(np.asarray(compacted.active) == (np.arange(16) < 9))
    assert _same_totals(totals(compacted), totals(removed_pool))
    kept = np.asarray(removed_pool.mass)[np.asarray(removed_pool.active)]
    assert np.array_equal(np.asarray(compacted.mass)[:9], kept)  # stable order
    assert np.all(np.asarray(refilled.active)[[1, 4, 8]])  # the freed slots are filled first
    assert _same_totals(totals(refilled), [x + y for x, y in zip(totals(removed_pool), totals(c))])
    assert _same_totals(totals(ordered), totals(refilled))
    cells = np.floor(np.asarray(ordered.x)[:12, :2] / 0.25) @ np.array([4, 1])
    assert np.all(np.diff(cells) >= 0)


def test_capacity_overflow_reports_needed_capacity():
    pool = mpm.insert(mpm.empty(16), _batch(7, 0))
    pool = mpm.insert(pool, _batch(3, 3))
    with pytest.raises(mpm.CapacityError, match="at least 17"):
        mpm.insert(pool, _batch(7, 1))
    new_pool, required = add_particles(pool, _batch(7, 1))
    assert int(required) == 17
    assert _same_totals(totals(new_pool), totals(pool))  # nothing added, nothing lost
    with pytest.raises(mpm.CapacityError, match="at least 7"):
        mpm.make_pool(_batch(7, 0), 6)
    packed = mpm.make_pool(_batch(7, 0), 16)
    assert _same_totals(totals(packed), totals(_batch(7, 0)))


# --- invariants of the step ------------------------------------------------------------------


@pytest.mark.parametrize("shape", ["linear", "gimp"])
def test_free_block_mass_exact_momentum_to_roundoff(shape):
    """No external force: sum_I f_int = 0 (sum_I grad N_I = 0), so momentum changes by round-off only."""
    spin = lambda x: np.stack([0.3 - 2.0 * (x[:, 1] - 0.6), 0.1 + 2.0 * (x[:, 0] - 0.6) + 3.0 * (x[:, 0] - 0.6) ** 2,
                               0.0 * x[:, 0]], 1)  # noqa: E731
    state, prm, cfg = setup(GRID2, (0.35, 0.4), (0.85, 0.8), shape=shape, v=spin, q=(1.5, 0.06))
    t0 = totals(state.particles)
    dt = float(stable_dt(state, prm, cfg))
    state = advance(state, dt, 60, prm, cfg)
    t1 = totals(state.particles)
    assert float(t1.mass) == float(t0.mass)
    scale = float(t0.mass) * 1.0  # |v| ~ 1 m/s
    assert np.allclose(np.asarray(t1.momentum), np.asarray(t0.momentum), rtol=0.0, atol=200 * EPS * scale)
    assert float(jnp.max(jnp.abs(state.particles.point.stress))) > 1.0  # the block did deform


@pytest.mark.parametrize("shape, grid", [
    ("linear", GRID2), ("gimp", GRID2), ("linear", GRID3),
    pytest.param("gimp", GRID3, marks=pytest.mark.slow),  # one more 3D compilation
], ids=["2d-linear", "2d-gimp", "3d-linear", "3d-gimp"])
def test_translating_block_stays_unstressed(shape, grid):
    """Galilean invariance: uniform velocity -> nodal velocity p_I/m_I = v exactly, grad v = 0,
    also while particles cross cell boundaries (the block moves 1.6 cells)."""
    dim = grid.dim
    vel = np.array([0.7, -0.4, 0.3])[:dim]
    state, prm, cfg = setup(grid, (0.2,) * dim, (0.4,) * (dim - 1) + (0.5,), shape=shape,
                            v=lambda x: np.tile(np.pad(vel, (0, 3 - dim)), (len(x), 1)))
    x0 = np.asarray(state.particles.x)
    dt, steps = 0.008, 20
    state = advance(state, dt, steps, prm, cfg)
    p = state.particles
    assert np.allclose(np.asarray(p.x), x0 + steps * dt * np.pad(vel, (0, 3 - dim)) * np.asarray(p.active)[:, None],
                       atol=1e-14)
    # round-off strain ~ eps per step -> stress ~ E * eps * steps
    assert float(jnp.max(jnp.abs(p.point.stress))) < 10 * steps * EPS * E
    assert np.allclose(np.asarray(p.point.density)[np.asarray(p.active)], RHO, rtol=10 * steps * EPS)


def test_free_fall_is_exact():
    """Uniform body force: every node accelerates by g, so v_n = n g dt and (MUSL with the updated
    velocity, ERRATA 000-5) x_n = x_0 + g dt^2 n (n + 1) / 2; the body stays unstressed."""
    g = np.array([0.0, -9.81, 0.0])
    state, prm, cfg = setup(GRID2, (0.3, 0.6), (0.5, 0.9), gravity=g[:2], shape="gimp")
    x0, mass = np.asarray(state.particles.x), float(totals(state.particles).mass)
    dt, n = 0.004, 50
    state = advance(state, dt, n, prm, cfg)
    p = state.particles
    on = np.asarray(p.active)
    assert np.allclose(np.asarray(p.v)[on], n * dt * g, rtol=1e-13, atol=1e-15)
    assert np.allclose(np.asarray(p.x)[on], x0[on] + g * dt**2 * n * (n + 1) / 2, rtol=0.0, atol=1e-13)
    assert float(jnp.max(jnp.abs(p.point.stress))) < 1e-8 * E
    # work of gravity sum m g . dx = M g^2 dt^2 n(n+1)/2
    assert float(state.external_work) == pytest.approx(mass * 9.81**2 * dt**2 * n * (n + 1) / 2, rel=1e-12)


def _bar(grid, lower, upper, **kw):
    x, vol, half = mpm.lattice(grid, lower, upper, 2)
    return x, vol, mpm.new_particles(x, vol, RHO, half_size=half, **kw)


def test_traction_impulse():
    """000 Eq. (20): a traction t on a layer of thickness h adds N_I V t/h; the total
    momentum grows at the applied force sum_p V_p t/h (free boundaries)."""
    x, vol, _ = _bar(GRID1, (0.2,), (0.8,))
    t_x, layer = 50.0, 0.025  # Pa on the end x = 0.8, carried by the last particle (thickness h/2)
    load = np.zeros((len(vol), 3))
    load[-1] = mpm.surface_load([t_x, 0.0, 0.0], layer)
    _, _, batch = _bar(GRID1, (0.2,), (0.8,), surface_load=load)
    pool = mpm.make_pool(batch, CAPACITY)
    cfg = mpm.make_config(GRID1, (ELASTIC,), prescribed=True)  # no prescribed particles: the same step
    prm = mpm.make_params((elastic_params(),))
    state = initialize(pool, prm, cfg)
    dt, n, k = 1e-3, 100, len(vol) - 1
    impulse = 0.0
    for _ in range(n):  # the force is V_p t/h with the particle's current volume V_p = m_p / rho_p
        impulse += dt * float(state.particles.mass[k] / state.particles.point.density[k]) * t_x / layer
        state = advance(state, dt, 1, prm, cfg)
    assert float(totals(state.particles).momentum[0]) == pytest.approx(impulse, rel=1e-12)
    assert float(state.external_work) > 0.0


def test_prescribed_impactor_moves_with_its_velocity_and_pushes_the_target():
    speed = 0.5
    xi, vi, impactor = _bar(GRID1, (0.2,), (0.4,), prescribed=[[speed, 0.0, 0.0]])
    _, _, target = _bar(GRID1, (0.45,), (0.9,))
    pool = mpm.make_pool(mpm.concatenate(impactor, target), CAPACITY)
    cfg = mpm.make_config(GRID1, (ELASTIC,), prescribed=True)
    prm = mpm.make_params((elastic_params(),))
    state = initialize(pool, prm, cfg)
    dt, n = 2e-3, 150
    state = advance(state, dt, n, prm, cfg)
    p = state.particles
    hit = np.asarray(p.prescribed).all(axis=1)
    rest = np.asarray(p.active) & ~hit
    assert np.allclose(np.asarray(p.x)[hit, 0], xi[:, 0] + n * dt * speed, atol=1e-13)
    assert np.allclose(np.asarray(p.v)[hit, 0], speed)
    assert np.all(np.abs(np.asarray(p.point.stress)[hit]) < 1e-8 * E)  # rigid: its nodes move with it
    target_momentum = float(np.sum(np.asarray(p.mass)[rest] * np.asarray(p.v)[rest, 0]))
    assert target_momentum > 0.1 * float(np.sum(np.asarray(p.mass)[rest])) * speed


@pytest.mark.parametrize("shape", ["linear", "gimp"])
def test_wall_reaction_is_the_momentum_the_wall_takes(shape):
    """A block thrown onto a fixed grid face: with no other external force, sum_I f_int = 0 (sum_I grad N_I
    = 0 wherever the particles sit; GIMP domains pushed past the face are truncated to the grid,
    shape.inside_grid: without that the momentum change was 15 % off) and the particles' momentum changes by
    exactly the impulse the face condition applies to the nodes (State.reaction), which pushes the block back
    and holds it sideways."""
    grid = mpm.Grid(origin=(0.0, 0.0), cell_size=0.1, cells=(12, 12), boundaries=(("free", "free"), ("fixed", "free")))
    state, prm, cfg = setup(grid, (0.35, 0.0), (0.85, 0.3), shape=shape,
                            v=lambda x: np.tile([0.2, -1.0, 0.0], (len(x), 1)))
    p0 = np.asarray(totals(state.particles).momentum)
    state = advance(state, 0.002, 200, prm, cfg)
    p1 = np.asarray(totals(state.particles).momentum)
    reaction = np.asarray(state.reaction)
    assert np.allclose(p1[:2] - p0[:2], reaction[:2], rtol=0.0, atol=1e-12 * np.abs(p0).max())
    assert reaction[1] > 0.5 * -p0[1] > 0.0 and reaction[0] < 0.0
    assert np.all(np.asarray(state.boundary_exchange) == 0.0)  # no nodal source


# --- bulk viscosity, time step, faults -------------------------------------------------------


def test_bulk_viscosity_point_values():
    rho, c, h = 2.0, 300.0, 0.01
    D = -50.0
    q = viscosity.bulk_viscosity(rho, c, D, h, 1.5, 0.06)
    assert float(q) == pytest.approx(rho * h * abs(D) * (0.06 * c + 1.5 * h * abs(D)), rel=1e-15)
    assert float(viscosity.bulk_viscosity(rho, c, 50.0, h, 1.5, 0.06)) == 0.0  # expansion
    s = 0.06 * c + 1.5 * h * abs(D)
    assert float(viscosity.signal_speed(c, 2.0, D, h, 1.5, 0.06)) == pytest.approx(2.0 + s + np.hypot(s, c))
    assert float(viscosity.signal_speed(c, 2.0, 50.0, h, 1.5, 0.06)) == pytest.approx(2.0 + c)


def test_stable_dt_and_fault_location():
    state, prm, cfg = setup(GRID1, (0.2,), (0.6,), v=lambda x: np.tile([2.0, 0.0, 0.0], (len(x), 1)), cfl=0.4,
                            nu=0.0, prescribed=True)
    c = np.sqrt(E / RHO)  # nu = 0: K + 4G/3 = E
    assert float(stable_dt(state, prm, cfg)) == pytest.approx(0.4 * 0.05 / (c + 2.0), rel=1e-14)
    assert int(first_fault(state, cfg)) == -1
    bad = state._replace(particles=state.particles._replace(x=_set(state.particles.x, (3, 0), 2.5)))
    assert np.isnan(float(stable_dt(bad, prm, cfg)))
    assert int(first_fault(bad, cfg)) == 3


def test_inactive_slots_contribute_nothing():
    """A pool with garbage (NaN) in an inactive slot steps exactly like the clean one."""
    state, prm, cfg = setup(GRID2, (0.2, 0.2), (0.5, 0.4), v=lambda x: 0.5 * (x - 0.35))
    junk = state.particles._replace(x=_set(state.particles.x, -1, np.nan), mass=_set(state.particles.mass, -1, 7.0))
    a = advance(state, 0.005, 5, prm, cfg)
    b = advance(state._replace(particles=junk), 0.005, 5, prm, cfg)
    n = int(jnp.sum(state.particles.active))
    assert np.array_equal(np.asarray(a.particles.x)[:n], np.asarray(b.particles.x)[:n])
    assert np.array_equal(np.asarray(a.particles.point.stress)[:n], np.asarray(b.particles.point.stress)[:n])


def test_model_slots_give_the_same_step():
    """A pool whose first slots hold one material and the rest another (a coupled run: structures, then
    gas) may run each model on its own slots only (``model_slots``): the step is unchanged (to round-off:
    XLA fuses the sliced updates differently)."""
    soft, stiff = ELASTIC, Model("test-hooke-2", _hooke_update, _hooke_wave_speed, None, 0)
    xa, va, ha = mpm.lattice(GRID2, (0.2, 0.2), (0.6, 0.6), 2)
    xb, vb, hb = mpm.lattice(GRID2, (0.6, 0.2), (1.0, 0.6), 2)
    a = mpm.new_particles(xa, va, RHO, v=np.tile([0.5, 0.0, 0.0], (len(xa), 1)), half_size=ha)
    b = mpm.new_particles(xb, vb, RHO, half_size=hb, material=1)
    pool = mpm.make_pool(mpm.concatenate(a, b), CAPACITY)
    prm = mpm.make_params((elastic_params(), elastic_params(youngs=4 * E)))
    out = []
    for slots in (None, ((0, len(xa)), (len(xa), CAPACITY))):
        cfg = mpm.make_config(GRID2, (soft, stiff), model_slots=slots)
        state = advance(initialize(pool, prm, cfg), 2e-3, 30, prm, cfg)
        out.append(state.particles)
    assert float(jnp.max(jnp.abs(out[0].point.stress))) > 1.0
    for x, y in zip(jax.tree_util.tree_leaves(out[0]), jax.tree_util.tree_leaves(out[1])):
        x, y = np.asarray(x), np.asarray(y)  # same arithmetic, fused differently: round-off
        assert np.allclose(x, y, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(x), initial=0.0)))
    with pytest.raises(mpm.MPMError, match="model_slots"):
        mpm.make_config(GRID2, (soft, stiff), model_slots=((0, 4),))


@pytest.mark.parametrize("alpha", [0.0, 0.25, 1.0])
@pytest.mark.parametrize("stream", [0.0, 50.0])
def test_pic_share_damps_the_mode_the_grid_cannot_see_and_heats(alpha, stream):
    """FLIP/PIC blend (musl docstring, step 3): a checkerboard velocity +-delta of the two particles of every
    cell (1D, linear shape functions), on a uniform stream U, gives every interior node the velocity U, so the
    grid cannot see the checkerboard. FLIP (alpha = 0) keeps it; a PIC share alpha scales it by (1 - alpha) in
    one step. The kinetic energy taken, (1 - (1 - alpha)^2) delta^2 / 2 per unit mass in the frame moving with
    the stream, heats every interior particle by that amount whatever U (Galilean invariance; the kinetic
    energy each particle loses is that +- alpha U delta, which, booked as its heat, cooled every other
    particle). Momentum is unchanged and, with a vanishing modulus (no strain energy), the total energy
    sum_p m_p (e_p + |v_p|^2 / 2) too, to round-off."""
    delta = 2.0
    U = stream * delta

    def checkerboard(x):
        v = np.zeros_like(x)
        v[:, 0] = U + delta * np.where(np.floor(x[:, 0] / 0.025).astype(int) % 2 == 0, 1.0, -1.0)
        return v

    state, prm, cfg = setup(GRID1, (0.5,), (1.5,), v=checkerboard, youngs=1e-9, blend=True)
    prm = prm._replace(pic_fraction=jnp.full((1,), alpha))
    new = mpm.step(state, 1e-6, prm, cfg).particles
    old = state.particles
    x = np.asarray(old.x[:, 0])
    interior = np.asarray(old.active) & (x > 0.6) & (x < 1.4)  # nodes with a full support, a cell from the ends
    v0, v1 = np.asarray(old.v[:, 0]), np.asarray(new.v[:, 0])
    assert np.allclose(v1[interior] - U, (1.0 - alpha) * (v0[interior] - U), rtol=0.0, atol=1e-12 * (delta + U))
    heat = np.asarray(new.point.energy - old.point.energy)[interior]
    # round-off: the heat is a difference of terms ~ alpha U^2
    assert np.allclose(heat, 0.5 * (1.0 - (1.0 - alpha) ** 2) * delta ** 2, rtol=0.0,
                       atol=1e-12 * (delta + U) ** 2)
    m = np.where(np.asarray(old.active), np.asarray(old.mass), 0.0)
    momentum = [float(np.sum(m * np.asarray(p.v[:, 0]))) for p in (old, new)]
    assert abs(momentum[1] - momentum[0]) < 1e-13 * float(np.sum(m)) * (delta + U)
    energy = [float(np.sum(m * (np.asarray(p.point.energy) + 0.5 * np.asarray(p.v[:, 0]) ** 2))) for p in (old, new)]
    assert abs(energy[1] - energy[0]) < 1e-12 * float(np.sum(m)) * (delta + U) ** 2


def test_blend_heat_is_shared_by_the_particles_of_a_node():
    """The blend heat is the dissipation of velocity differences the grid cannot resolve; it goes to the gas
    of the nodes where they are dissipated, in proportion to alpha m (musl docstring, step 3), not to the
    particle that deviated. 1D, linear shape functions, two particles a cell at rest except every second one,
    1000 times lighter, moving at delta: the lights' deviation is ~delta, the heavies' ~0. Every interior
    node carries the same weights of both kinds, so every interior particle heats by the same amount per
    unit mass, the mass-weighted mean of what they gave: about 1e-3 of the lights' own dissipation
    (1 - (1 - alpha)^2) delta^2 / 2, which they took before (and which made rarefied air among heavier gas
    1e8-1e9 J/kg hot in steel-plate-blast). Total energy and momentum are kept to round-off."""
    delta, alpha, light = 100.0, 0.25, 1e-3
    state, prm, cfg = setup(GRID1, (0.5,), (1.5,), youngs=1e-9, blend=True)
    prm = prm._replace(pic_fraction=jnp.full((1,), alpha))
    P = state.particles
    x = np.asarray(P.x[:, 0])
    lights = np.asarray(P.active) & (np.floor(x / 0.025).astype(int) % 2 == 1)
    scale = np.where(lights, light, 1.0)
    v = np.zeros(np.shape(P.v))
    v[:, 0] = np.where(lights, delta, 0.0)
    old = P._replace(mass=P.mass * scale, point=P.point._replace(density=P.point.density * scale), v=jnp.asarray(v))
    new = mpm.step(state._replace(particles=old), 1e-6, prm, cfg).particles
    interior = np.asarray(old.active) & (x > 0.6) & (x < 1.4)
    heat = np.asarray(new.point.energy - old.point.energy)[interior]
    own = 0.5 * (1.0 - (1.0 - alpha) ** 2) * delta ** 2  # what a light particle took of its own deviation
    assert np.all(heat > 0.0)
    assert np.allclose(heat, heat[0], rtol=1e-9, atol=0.0)  # lights and heavies alike
    assert heat[0] < 2.0 * light * own
    m = np.where(np.asarray(old.active), np.asarray(old.mass), 0.0)
    momentum = [float(np.sum(m * np.asarray(p.v[:, 0]))) for p in (old, new)]
    assert abs(momentum[1] - momentum[0]) < 1e-13 * float(np.sum(m)) * delta
    energy = [float(np.sum(m * (np.asarray(p.point.energy) + 0.5 * np.asarray(p.v[:, 0]) ** 2))) for p in (old, new)]
    assert abs(energy[1] - energy[0]) < 1e-12 * float(np.sum(m * scale)) * delta ** 2


def test_pic_share_needs_the_blend_config():
    """Without ``Config.blend`` the step is pure FLIP whatever Params.pic_fraction says (a static switch: runs
    without a PIC share carry none of its channels)."""
    def checkerboard(x):
        v = np.zeros_like(x)
        v[:, 0] = np.where(np.floor(x[:, 0] / 0.025).astype(int) % 2 == 0, 1.0, -1.0)
        return v

    state, prm, cfg = setup(GRID1, (0.5,), (1.5,), v=checkerboard)
    new = mpm.step(state, 1e-6, prm._replace(pic_fraction=jnp.full((1,), 0.5)), cfg).particles
    x = np.asarray(state.particles.x[:, 0])
    interior = np.asarray(state.particles.active) & (x > 0.6) & (x < 1.4)
    assert np.allclose(np.asarray(new.v[:, 0])[interior], np.asarray(state.particles.v[:, 0])[interior], atol=1e-12)


def test_added_particles_skip_the_reserved_slots():
    """``first_slot``: a coupled run keeps its structures in the first slots; a freed structure slot (a
    fragment that left the box) must not take a gas particle, which its model would never update."""
    x, vol, half = mpm.lattice(GRID2, (0.2, 0.2), (0.4, 0.4), 2)  # 16 particles
    pool = mpm.make_pool(mpm.new_particles(x, vol, RHO, half_size=half), 24)
    pool = pool._replace(active=pool.active.at[:4].set(False))  # 4 freed slots before first_slot
    batch = mpm.new_particles(x[:6], vol[:6], RHO, half_size=half[:6])
    new, required, slots = mpm.add_particles_at(pool, batch, 8)
    assert np.all(np.asarray(slots) >= 16) and not np.any(np.asarray(new.active[:4]))
    assert int(required) == 12 + 4 + 6  # active + reserved free + batch
    _, required, slots = mpm.add_particles_at(pool, mpm.concatenate(batch, batch), 8)
    assert int(required) == 28 and np.all(np.asarray(slots) == 24)  # does not fit: nothing added


def test_accelerator_control_flow_gives_the_same_step(monkeypatch):
    """Where a conditional costs a host round trip (a GPU), the step computes the materialised values
    unconditionally and selects (blastfsi.xla.materialise); forced here on the CPU: the same particles
    after 10 steps, to round-off (the same arithmetic, fused differently)."""
    from blastfsi import xla

    state, prm, cfg = setup(GRID2, (0.2, 0.2), (0.6, 0.5), v=lambda x: 0.5 * (x - 0.4))

    def run():  # a fresh jitted loop: the form is chosen when it is traced
        return jax.jit(lambda s: jax.lax.fori_loop(0, 10, lambda i, s: mpm.step(s, 0.005, prm, cfg), s))(state)

    cpu = run().particles
    monkeypatch.setattr(xla, "device_control_flow", lambda: False)
    accelerator = run().particles
    assert float(jnp.max(jnp.abs(cpu.point.stress))) > 0.0
    for x, y in zip(jax.tree_util.tree_leaves(cpu), jax.tree_util.tree_leaves(accelerator)):
        x, y = np.asarray(x), np.asarray(y)
        assert np.allclose(x, y, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(x), initial=0.0)))
