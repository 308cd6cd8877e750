"""The optimised MUSL step (:func:`blastfsi.mpm.musl.step`) against the plain NumPy oracle of
tests/mpm_reference.py: a small elastic body (random but seeded positions inside its cells, random
velocities and small random stresses) next to a fixed and a slip face, with free faces elsewhere,
3 steps; positions, velocities, stresses, densities and energies agree to round-off. And the oracle
conserves momentum for a free body (so it is not merely mirroring the optimised step's bugs)."""
import jax
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import mpm
from blastfsi.constitutive import elastic

import mpm_reference as ref

MODEL = elastic.MODEL
PARAMS = elastic.moduli(1.0e4, 0.3)  # a soft solid: c ~ 3.7 m/s at RHO
RHO, H = 1.0e3, 0.1
RTOL = 1e-12
ROUND_OFF = 1e-14  # a few ulps of a field's largest value, carried over STEPS steps
STEPS = 3
PPC = 2  # particles per cell and direction

GEOMETRIES = {
    # plane strain: a fixed wall at x = 0 and a slip floor at y = 0, the other faces free
    "2d": dict(cells=(5, 4), body=(3, 3), bounds=(("fixed", "free"), ("slip", "free")), axi=False),
    # 3D: fixed at x = 0, slip at z = 0; musl's combined (GPU) scatter form, ~3x faster to compile here than
    # the per-channel CPU form that the 2D cases check
    "3d": dict(cells=(4, 3, 3), body=(2, 2, 2), bounds=(("fixed", "free"), ("free", "free"), ("slip", "free")),
               axi=False, combined=True),
    # r-z: the axis (slip) at r = 0, a fixed floor at z = 0
    "rz": dict(cells=(4, 4), body=(3, 3), bounds=(("slip", "free"), ("fixed", "free")), axi=True),
}

_step = jax.jit(mpm.step, static_argnames="config")


def make_body(name, seed, offset=0, bounds=None):
    """(grid, oracle Body, musl pool) of a body of ``body`` cells from cell ``offset`` in each direction,
    PPC^d particles per cell at random points of their sub-cells."""
    g = GEOMETRIES[name]
    d = len(g["cells"])
    grid = mpm.Grid(origin=(0.0,) * d, cell_size=H, cells=tuple(c + 2 * offset for c in g["cells"]),
                    boundaries=bounds or g["bounds"], axisymmetric=g["axi"])
    rng = np.random.default_rng(seed)
    s = H / PPC
    counts = [PPC * b for b in g["body"]]
    sub = np.array(list(np.ndindex(*counts)), float)
    x = np.zeros((len(sub), 3))
    x[:, :d] = offset * H + s * (sub + rng.uniform(0.15, 0.85, sub.shape))
    n = len(x)
    volume = 2.0 * np.pi * x[:, 0] * s ** 2 if g["axi"] else np.full(n, s ** d)
    half = np.zeros((n, 3))
    half[:, :d] = 0.5 * s
    v = np.zeros((n, 3))
    v[:, :d] = rng.uniform(-0.1, 0.1, (n, d))
    stress = rng.uniform(-50.0, 50.0, (n, 6))
    if d == 2:
        stress[:, 3:5] = 0.0  # no out-of-plane shear in plane strain or r-z
    density = RHO * (1.0 + 0.05 * rng.uniform(-1.0, 1.0, n))
    energy = rng.uniform(0.0, 1.0, n)
    batch = mpm.new_particles(x[:, :d], volume, density, v=v, half_size=half, stress=stress, energy=energy)
    body = ref.Body(x=x, v=v, mass=np.asarray(batch.mass), half_size=half, stress=stress, density=density,
                    energy=energy)
    return grid, body, mpm.make_pool(batch, n + 3)  # three inactive slots


def assert_close(a, b, what):
    """|a - b| <= RTOL max|b| over the whole field (normwise relative)."""
    a, b = np.asarray(a), np.asarray(b)
    scale = np.max(np.abs(b))
    err = np.max(np.abs(a - b))
    assert err <= RTOL * scale, f"{what}: max |musl - oracle| = {err:.3e}, {err / scale:.3e} of max |oracle|"


SLOW = pytest.mark.slow  # (compile time: each shape is checked in every geometry with -m slow)


@pytest.mark.parametrize("name, shape", [("2d", "linear"), ("rz", "gimp"), ("3d", "gimp"),
                                         pytest.param("2d", "gimp", marks=SLOW),
                                         pytest.param("rz", "linear", marks=SLOW),
                                         pytest.param("3d", "linear", marks=SLOW)])
def test_musl_step_matches_the_reference(name, shape):
    grid, body, pool = make_body(name, seed=sum(map(ord, name + shape)))
    gravity = (0.0, -9.81, 0.0) if grid.dim == 2 else (2.0, -9.81, 1.0)
    cfg = mpm.make_config(grid, (MODEL,), shape=shape, combined_scatter=GEOMETRIES[name].get("combined", False))
    prm = mpm.make_params((PARAMS,), q_quadratic=0.0, q_linear=0.0, gravity=gravity)
    mpm.check_particles(pool, cfg)
    x0 = body.x
    state = mpm.initialize(pool, prm, cfg)
    dt = 0.3 * H / float(np.max(state.particles.wave_speed))
    for _ in range(STEPS):
        state = _step(state, dt, prm, config=cfg)
        body = ref.step(body, dt, grid, shape, MODEL, PARAMS, gravity)
    P = jax.tree_util.tree_map(np.asarray, state.particles)
    n = len(body.mass)
    assert np.all(P.active[:n]) and not np.any(P.active[n:])
    assert np.max(np.abs(body.x - x0)) > 1e-3 * H  # the body moved
    assert_close(P.x[:n], body.x, "x")
    assert_close(P.v[:n], body.v, "v")
    assert_close(P.point.stress[:n], body.stress, "stress")
    assert_close(P.point.density[:n], body.density, "density")
    assert_close(P.point.energy[:n], body.energy, "energy")


@pytest.mark.parametrize("shape", ["linear", "gimp"])
@pytest.mark.parametrize("name", sorted(GEOMETRIES))
def test_reference_conserves_momentum_of_a_free_body(name, shape):
    """No face touched, no gravity: sum_I f_I = 0 (sum_I grad N_I = 0), so FLIP keeps sum_p m_p v_p
    (r-z: the axial component only; the hoop stress pushes radially)."""
    d = len(GEOMETRIES[name]["cells"])
    grid, body, _ = make_body(name, seed=7, offset=1, bounds=(("free", "free"),) * d)  # r-z: off the axis
    v0 = body.v
    before = ref.momentum(body)
    scale = np.sum(body.mass[:, None] * np.abs(body.v))
    for _ in range(STEPS):
        body = ref.step(body, 2e-3, grid, shape, MODEL, PARAMS)
    after = ref.momentum(body)
    kept = [1] if grid.axisymmetric else list(range(d))
    assert np.max(np.abs(after - before)[kept]) <= 1e-13 * scale
    assert np.max(np.abs(body.v - v0)) > 1e-3  # the stresses did push


def test_row_and_scalar_transfers_give_the_same_step_bit_for_bit():
    """The particle-to-grid and grid-to-particle transfers as one scatter of rows or as scalar scatters per
    channel and stencil node add in the same order (:func:`blastfsi.mpm.musl.particle_to_grid`), so the backend
    policy (:func:`blastfsi.xla.combined_scatter`) changes no result: r-z GIMP, the coupled examples' form."""
    grid, _, pool = make_body("rz", seed=7)
    prm = mpm.make_params((PARAMS,), q_quadratic=0.0, q_linear=0.0, gravity=(0.0, -9.81, 0.0))
    out = []
    for combined in (True, False):
        cfg = mpm.make_config(grid, (MODEL,), shape="gimp", combined_scatter=combined)
        state = mpm.initialize(pool, prm, cfg)
        dt = 0.3 * H / float(np.max(state.particles.wave_speed))
        for _ in range(STEPS):
            state = _step(state, dt, prm, config=cfg)
        out.append(jax.tree_util.tree_map(np.asarray, state.particles))
    for field in ("x", "v", "mass"):
        assert np.array_equal(getattr(out[0], field), getattr(out[1], field)), field
    for field in ("stress", "density", "energy"):
        assert np.array_equal(getattr(out[0].point, field), getattr(out[1].point, field)), field
    assert np.max(np.abs(out[0].x - np.asarray(pool.x))) > 0.0  # the body moved


def test_constraint_sums_over_the_prescribed_slots_give_the_same_step():
    """The nodal mass and momentum of the prescribed particles summed over Config.prescribed_slots only (a coupled
    run's structures, in the first slots) or as columns of the step's scatter over the whole pool: the other
    slots add zeros, so the sums are the same and the steps agree to round-off (r-z GIMP, the row scatter: the
    scalar form adds in the same order, test_row_and_scalar_transfers_give_the_same_step_bit_for_bit;
    measured: 1 ulp in a velocity after 3 steps, where the compiler fuses and contracts the other channels'
    products differently without the constraint columns; a prescribed particle dropped from the sums would
    leave its node free, an O(1) error); and the held particles really hold their nodes (they stay at rest
    while the rest of the body moves)."""
    grid, _, pool = make_body("rz", seed=11)
    held = 6  # the first slots hold all components at rest
    prescribed = np.zeros(np.shape(pool.prescribed), bool)
    prescribed[:held] = True
    pool = pool._replace(prescribed=prescribed, v=np.where(prescribed, 0.0, np.asarray(pool.v)))
    prm = mpm.make_params((PARAMS,), q_quadratic=0.0, q_linear=0.0, gravity=(0.0, -9.81, 0.0))
    out = []
    for slots in (None, (0, held)):
        cfg = mpm.make_config(grid, (MODEL,), shape="gimp", combined_scatter=True, prescribed=True,
                              prescribed_slots=slots)
        state = mpm.initialize(pool, prm, cfg)
        dt = 0.3 * H / float(np.max(state.particles.wave_speed))
        for _ in range(STEPS):
            state = _step(state, dt, prm, config=cfg)
        out.append(jax.tree_util.tree_map(np.asarray, state))
    a, b = out
    for (path, leaf_a), leaf_b in zip(jax.tree_util.tree_flatten_with_path(a)[0], jax.tree_util.tree_leaves(b)):
        if leaf_a.dtype.kind != "f":
            assert np.array_equal(leaf_a, leaf_b), jax.tree_util.keystr(path)
            continue
        worst = np.max(np.abs(leaf_a - leaf_b), initial=0.0)
        assert worst <= ROUND_OFF * float(np.max(np.abs(leaf_a), initial=0.0)), (jax.tree_util.keystr(path), worst)
    assert np.array_equal(a.particles.x[:held], np.asarray(pool.x)[:held])  # held at rest
    assert np.max(np.abs(a.particles.x[held:] - np.asarray(pool.x)[held:])) > 0.0
    assert np.max(np.abs(a.reaction)) > 0.0  # the supports pushed back


def test_prescribed_slots_checked():
    grid, _, _ = make_body("rz", seed=1)
    with pytest.raises(mpm.MPMError, match=r"prescribed_slots: expected \(start, stop\)"):
        mpm.make_config(grid, (MODEL,), prescribed=True, prescribed_slots=(5, 2))
