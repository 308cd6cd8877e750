"""Eulerian solver kernels (blastfsi.euler): configuration checks, state conversion and the
mixture EOS (tier 1), time step and fault detection, and invariants of the schemes (tier 2):
geometric source balance, positivity, mirror symmetry, conservation in a closed box."""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import euler
from blastfsi.eos import jwl
from blastfsi.eos.jwl import ideal_gas_params
from blastfsi.euler.config import check_config
from blastfsi.materials.gases import GASES

AIR = ideal_gas_params(1.4)
TNT = GASES["tnt"].eos_params()  # seed 000 Sec. 4.1 set
SCHEMES = (euler.LAX_WENDROFF, euler.HLLC_MUSCL)


def config(shape, dx=1.0, geometry=0, bc=None, scheme=0, n=1, origin=None):
    nd = len(shape)
    return euler.Config(tuple(shape), dx, geometry, bc or ((euler.OUTFLOW, euler.OUTFLOW),) * nd, scheme, n,
                        origin or (0.0,) * nd)


def params(*rows, cfl=0.5):
    return euler.Params(jnp.asarray([list(r) for r in rows], dtype=float), jnp.asarray(cfl))


@functools.partial(jax.jit, static_argnums=(3,))
def advance(U, prm, n_steps, cfg):
    """n_steps (traced) steps at the stable time step."""
    return jax.lax.fori_loop(0, n_steps, lambda i, V: euler.step(V, stable_dt(V, prm, cfg), prm, cfg, parity=i), U)


conservative = jax.jit(euler.conservative, static_argnums=5)
primitives = jax.jit(euler.primitives, static_argnums=2)
stable_dt = jax.jit(euler.stable_dt, static_argnums=2)
first_bad_cell = jax.jit(euler.first_bad_cell, static_argnums=2)


# --- configuration --------------------------------------------------------------------------------

@pytest.mark.parametrize("bad, field", [
    (dict(shape=(1, 8)), "Config.shape"),
    (dict(dx=0.0), "Config.dx"),
    (dict(geometry=3), "Config.geometry"),
    (dict(geometry=2), "Config.geometry"),  # spherical needs 1 axis
    (dict(scheme=3), "Config.scheme"),
    (dict(n=3), "Config.n_materials"),
    (dict(bc=((0, 0),)), "Config.bc"),
    (dict(bc=((0, 4), (0, 0))), "Config.bc[0]"),
    (dict(bc=((3, 0), (0, 0))), "Config.bc[0]"),  # periodic on one side only
    (dict(bc=((0, 0), (2, 0))), "Config.bc[1]"),  # axis off the radius
    (dict(geometry=1, bc=((0, 0), (0, 0))), "Config.bc[0][0]"),  # r = 0 needs axis/wall
    (dict(geometry=1, origin=(-1.0, 0.0), bc=((1, 0), (0, 0))), "Config.origin[0]"),
    (dict(origin=(0.0,)), "Config.origin"),
])
def test_config_errors_name_the_field(bad, field):
    kw = dict(shape=(8, 8)) | bad
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        check_config(config(**kw))


def test_params_shape_error():
    cfg = config((8,), n=2)
    U = jnp.ones((euler.n_vars(cfg), 8))
    with pytest.raises(ValueError, match="Params.eos"):
        stable_dt(U, params(AIR), cfg)


# --- state conversion and the mixture EOS (tier 1) ---------------------------------------------------

def test_mixture_is_isobaric_closure():
    """conservative -> primitives returns the input state, and with two materials each phase at the
    common pressure carries its own JWL (000 Eq. 54) / ideal-gas energy,
    rho e = sum alpha_k rho_k e_k(rho_k, p), and c^2 = sum (alpha_k/G_k) rho_k c_k^2 / (xi rho)
    (Allaire, Clerc & Kokh 2002); a pure-products cell (alpha = 1) is plain JWL."""
    cfg = config((5,), n=2)
    alpha = jnp.asarray([1.0, 0.75, 0.5, 0.25, 0.0])
    rho_k = jnp.stack([jnp.asarray([1630.0, 1000.0, 800.0, 300.0, 100.0]), jnp.full(5, 50.0)])
    p = jnp.full(5, 1.0e9)
    prm = params(TNT, AIR)
    U = conservative(rho_k, alpha, jnp.full((1, 5), 30.0), p, prm, cfg)
    out = primitives(U, prm, cfg)
    np.testing.assert_allclose(out["velocity"], 30.0, rtol=1e-13)
    np.testing.assert_allclose(out["internal_energy"][0], jwl.energy(1630.0, 1.0e9, TNT), rtol=1e-12)
    np.testing.assert_allclose(out["sound_speed"][0] ** 2, jwl.sound_speed_squared(1630.0, 1.0e9, TNT), rtol=1e-12)
    a_k = (alpha, 1.0 - alpha)
    rho = a_k[0] * rho_k[0] + a_k[1] * rho_k[1]
    rho_e = sum(a * r * jwl.energy(r, p, row) for a, r, row in zip(a_k, rho_k, (TNT, AIR)))
    xi = sum(a / row.omega for a, row in zip(a_k, (TNT, AIR)))
    c2 = sum(a / row.omega * r * jwl.sound_speed_squared(r, p, row) for a, r, row in zip(a_k, rho_k, (TNT, AIR))) / (
        xi * rho)
    np.testing.assert_allclose(out["pressure"], p, rtol=1e-12)
    np.testing.assert_allclose(out["rho"] * out["internal_energy"], rho_e, rtol=1e-12)
    np.testing.assert_allclose(out["sound_speed"] ** 2, c2, rtol=1e-12)
    np.testing.assert_allclose(out["products_fraction"], a_k[0] * rho_k[0] / rho, rtol=1e-14)
    np.testing.assert_allclose(out["alpha"], alpha, rtol=0, atol=0)


def test_stable_dt_formulas():
    """LW (split): cfl dx / max_d (|u_d| + c); HLLC (unsplit): cfl dx / sum_d (|u_d| + c)."""
    rho, p, u, v = 1.2, 1.0e5, 30.0, -70.0
    c = np.sqrt(1.4 * p / rho)
    prm = params(AIR, cfl=0.4)
    U = conservative(jnp.full((4, 4), rho), None, jnp.stack([jnp.full((4, 4), u), jnp.full((4, 4), v)]),
                     jnp.full((4, 4), p), prm, config((4, 4), dx=0.01))
    for scheme, expected in ((0, 0.4 * 0.01 / (abs(v) + c)), (1, 0.4 * 0.01 / (abs(u) + abs(v) + 2.0 * c))):
        cfg = config((4, 4), dx=0.01, scheme=scheme)
        np.testing.assert_allclose(stable_dt(U, prm, cfg), expected, rtol=1e-14)
        assert int(first_bad_cell(U, prm, cfg)) == -1


def test_stable_dt_counts_the_owned_cells_and_their_face_neighbours():
    """With ``owned`` (a coupled run's cells outside the fictitious ones): a fast cell two cells from the owned
    ones does not set the step, one that shares a face with them does (its waves enter that face's flux), and
    a non-physical cell anywhere still gives NaN."""
    prm = params(AIR, cfl=0.4)
    cfg = config((6, 4), dx=0.01, scheme=1)
    u = jnp.zeros((2, 6, 4))
    U = conservative(jnp.full((6, 4), 1.2), None, u, jnp.full((6, 4), 1.0e5), prm, cfg)
    owned = jnp.zeros((6, 4), bool).at[:3].set(True)  # x-columns 0-2 owned, 3-5 fictitious
    calm = float(stable_dt(U, prm, cfg))
    far = conservative(jnp.full((6, 4), 1.2), None, u.at[0, 4, 2].set(3000.0), jnp.full((6, 4), 1.0e5), prm, cfg)
    near = conservative(jnp.full((6, 4), 1.2), None, u.at[0, 3, 2].set(3000.0), jnp.full((6, 4), 1.0e5), prm, cfg)
    with_owned = jax.jit(euler.stable_dt, static_argnums=2)
    assert float(with_owned(far, prm, cfg, owned)) == pytest.approx(calm, rel=1e-14)
    assert float(stable_dt(far, prm, cfg)) < 0.2 * calm  # (without the mask it sets the step)
    assert float(with_owned(near, prm, cfg, owned)) == pytest.approx(float(stable_dt(near, prm, cfg)), rel=1e-14)
    assert np.isnan(float(with_owned(far.at[3, 5, 0].set(-1.0e6), prm, cfg, owned)))


@pytest.mark.parametrize("row, value", [(0, -1.0), (0, np.nan), (3, -1.0e6), (3, np.inf), (1, np.inf)])
def test_stable_dt_flags_nonphysical_cells(row, value):
    """NaN/inf, rho <= 0 or p <= 0 in one cell (rows rho, rho u, rho v, E): stable_dt is NaN and
    first_bad_cell points at it."""
    cfg = config((4, 4), dx=0.01)
    prm = params(AIR, cfl=0.4)
    U = conservative(jnp.ones((4, 4)), None, jnp.zeros((2, 4, 4)), jnp.full((4, 4), 1.0e5), prm, cfg)
    U = U.at[row, 1, 3].set(value)
    dt = stable_dt(U, prm, cfg)
    assert not dt > 0.0
    assert int(first_bad_cell(U, prm, cfg)) == 1 * 4 + 3


def test_total_uses_exact_shell_volumes():
    rho, e = 2.0, 3.0
    for geometry, shape, exact in ((2, (10,), 4.0 / 3.0 * np.pi), (1, (10,), np.pi), (1, (10, 5), np.pi * 0.5)):
        nd = len(shape)
        cfg = config(shape, dx=0.1, geometry=geometry, bc=((euler.AXIS, 0),) + ((0, 0),) * (nd - 1))
        U = jnp.zeros((euler.n_vars(cfg),) + shape).at[0].set(rho).at[nd + 1].set(e)
        mass, mom, energy = euler.total(U, cfg)
        np.testing.assert_allclose(mass, rho * exact, rtol=1e-13)
        np.testing.assert_allclose(energy, e * exact, rtol=1e-13)


# --- invariants of the schemes (tier 2) ---------------------------------------------------------------

AXISYMMETRIC = dict(shape=(16, 12), dx=1.0 / 16, geometry=euler.CYLINDRICAL,
                    bc=((euler.AXIS, euler.WALL), (euler.WALL, euler.WALL)))


@pytest.mark.parametrize("scheme, grid", [
    (0, dict(shape=(16,), dx=0.01, geometry=euler.SPHERICAL, bc=((euler.AXIS, euler.WALL),))),
    (1, dict(shape=(16,), dx=0.01, geometry=euler.SPHERICAL, bc=((euler.AXIS, euler.WALL),))),
    (0, AXISYMMETRIC),
    pytest.param(1, AXISYMMETRIC, marks=pytest.mark.slow)])  # 2D compile time: one scheme by default
def test_uniform_state_at_rest_stays_at_rest_in_radial_geometry(scheme, grid):
    """The pressure force p (A+ - A-)/V balances the radial pressure flux: a uniform gas at rest
    (spherical 1D, axisymmetric r-z) keeps u = 0 and its pressure to round-off."""
    cfg = config(scheme=scheme, **grid)
    shape, nd = cfg.shape, len(cfg.shape)
    prm = params(AIR)
    U0 = conservative(jnp.full(shape, 1.2), None, jnp.zeros((nd,) + shape), jnp.full(shape, 1.0e5), prm, cfg)
    out = primitives(advance(U0, prm, 20, cfg), prm, cfg)
    c = float(np.sqrt(1.4e5 / 1.2))
    assert float(jnp.max(jnp.abs(out["velocity"]))) < 1e-12 * c
    np.testing.assert_allclose(out["pressure"], 1.0e5, rtol=1e-13)


def blast(cfg, centre, ratio=10.0):
    """Sod-like blast: a ball of radius 0.15 at (ratio p0, rho0) in (p0, rho0/8), at rest."""
    axes = [(np.arange(m) + 0.5) * cfg.dx for m in cfg.shape]
    r2 = sum((x - c) ** 2 for x, c in zip(np.meshgrid(*axes, indexing="ij"), centre))
    prm = params(AIR, cfl=0.4)
    U = conservative(jnp.asarray(np.where(r2 < 0.15 ** 2, 1.0, 0.125)), None, jnp.zeros((len(cfg.shape),) + cfg.shape),
                     jnp.asarray(np.where(r2 < 0.15 ** 2, ratio, 1.0)), prm, cfg)
    return U, prm


CARTESIAN_BOX = dict(shape=(24, 24), dx=1.0 / 24, bc=((euler.WALL, euler.WALL),) * 2, scheme=euler.HLLC_MUSCL)


@pytest.mark.parametrize("grid, centre, mirrors", [
    (CARTESIAN_BOX, (0.5, 0.5), (1, 2)),  # HLLC, about x = 1/2 and y = 1/2
    (AXISYMMETRIC | dict(scheme=euler.LAX_WENDROFF), (0.0, 0.375), (2,)),  # LW r-z, about z = 3/8
])
def test_mirror_symmetry(grid, centre, mirrors):
    """A blast centred between mirror-image boundaries stays mirror-symmetric to round-off (both
    schemes use symmetric stencils; LW takes |theta| in Eq. 4 for that reason). Mass and energy
    in the closed box are conserved to round-off meanwhile."""
    cfg = config(**grid)
    U0, prm = blast(cfg, centre)
    U = advance(U0, prm, 30, cfg)
    scale = jnp.max(jnp.abs(U), axis=tuple(range(1, U.ndim)), keepdims=True)
    for axis in mirrors:
        mirrored = jnp.flip(U, axis=axis).at[axis].multiply(-1.0)  # rows rho, rho u_1, ..: momentum row = axis
        assert float(jnp.max(jnp.abs(mirrored - U) / scale)) < 1e-12
    (m0, _, e0), (m1, _, e1) = euler.total(U0, cfg), euler.total(U, cfg)
    assert abs(float(m1 / m0) - 1.0) < 1e-13 and abs(float(e1 / e0) - 1.0) < 1e-13


@pytest.mark.parametrize("grid", [CARTESIAN_BOX, pytest.param(CARTESIAN_BOX | dict(scheme=euler.LAX_WENDROFF),
                                                                 marks=pytest.mark.slow)])
def test_shock_tube_along_x_equals_along_y(grid):
    """Sod's tube along x and along y of the same square box (walls) give transposed states to
    round-off: both axes run the same operator, and the transverse one leaves a transversally
    uniform state unchanged (LW's Eq. (6) order y x x y is then x x)."""
    cfg = config(**grid)
    x = (np.arange(cfg.shape[0]) + 0.5) * cfg.dx
    prm = params(AIR, cfl=0.4)
    rho = np.broadcast_to(np.where(x < 0.5, 1.0, 0.125)[:, None], cfg.shape)
    p = np.broadcast_to(np.where(x < 0.5, 1.0, 0.1)[:, None], cfg.shape)
    along_x = advance(conservative(jnp.asarray(rho), None, jnp.zeros((2,) + cfg.shape), jnp.asarray(p), prm, cfg),
                      prm, 40, cfg)
    along_y = advance(conservative(jnp.asarray(rho.T), None, jnp.zeros((2,) + cfg.shape), jnp.asarray(p.T), prm, cfg),
                      prm, 40, cfg)
    swapped = jnp.stack([along_y[0].T, along_y[2].T, along_y[1].T, along_y[3].T])
    scale = jnp.max(jnp.abs(along_x), axis=(1, 2), keepdims=True)  # rows rho, rho u, rho v (= 0), E
    assert float(jnp.max(jnp.abs(swapped - along_x) / jnp.where(scale > 0.0, scale, 1.0))) < 1e-12


def test_strong_blast_stays_positive():
    """HLLC-MUSCL with Einfeldt speeds on a 1e6 pressure-ratio blast (near-vacuum core): no NaN,
    positive density and pressure after the blast has expanded."""
    cfg = config(**CARTESIAN_BOX)
    U, prm = blast(cfg, (0.35, 0.45), ratio=1.0e6)
    U = advance(U, prm, 60, cfg)
    out = primitives(U, prm, cfg)
    assert bool(jnp.isfinite(stable_dt(U, prm, cfg)))
    assert float(out["rho"].min()) > 0.0 and float(out["pressure"].min()) > 0.0
