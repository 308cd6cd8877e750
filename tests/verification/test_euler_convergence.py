"""Eulerian solver kernels against exact solutions (tier 3) and conservation in 3D (tier 2).

* Sod in SI (seed 000 Sec. 5.1, ERRATA 000-12; exact: blastfsi.exact.riemann.sod_000): L1 errors
  bounded by discontinuities captured within a few cells; observed L1 order on 5 grids (slow).
* Products | air shock tube (exact.riemann.tnt_air): the two-material model against the exact
  JWL | ideal-gas Riemann solution (slow).
* Sod along y and z (2D, 3D tubes a few cells across) equals the 1D run: axes are equivalent.
* Smooth density wave advected at uniform u, p on a periodic grid (1D, 2D and 3D diagonal):
  observed L1 order of both schemes (slow).
* Products | air slab advected at uniform p, u (ERRATA 000-9): p and u stay uniform.
* Closed 3D box with an off-centre blast: mass, momentum and energy conserved to round-off;
  3D solution symmetric under axis permutation (slow).
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import euler
from blastfsi.eos.jwl import ideal_gas_params
from blastfsi.exact.riemann import sod_000, tnt_air
from blastfsi.materials.gases import GASES

AIR = ideal_gas_params(1.4)
TNT = GASES["tnt"].eos_params()  # seed 000 Sec. 4.1 set
SCHEMES = (euler.LAX_WENDROFF, euler.HLLC_MUSCL)


def params(*rows, cfl=0.5, dtype=jnp.float64):
    return euler.Params(jnp.asarray([list(r) for r in rows], dtype), jnp.asarray(cfl, dtype))


@functools.partial(jax.jit, static_argnums=(4,))
def run_fixed(U, prm, dt, n_steps, cfg):
    return jax.lax.fori_loop(0, n_steps, lambda i, V: euler.step(V, dt, prm, cfg, parity=i), U)


def centres(cfg):
    return np.meshgrid(*[cfg.origin[d] + (np.arange(m) + 0.5) * cfg.dx for d, m in enumerate(cfg.shape)],
                       indexing="ij")


# --- Sod -------------------------------------------------------------------------------------------

def sod(n, scheme, dtype=jnp.float64):
    """Seed 000 Sod tube (1 mm, diaphragm 0.5 mm, outflow ends) at t = 0.143 ms: (x, rho, u, p) and exact."""
    case = sod_000()
    (x0, x1), pb = case.domain, case.problem
    cfg = euler.Config((n,), (x1 - x0) / n, 0, ((euler.OUTFLOW, euler.OUTFLOW),), scheme, 1, (x0,))
    x = centres(cfg)[0]
    left = x < pb.x0
    prm = params(AIR, dtype=dtype)
    U = euler.conservative(jnp.asarray(np.where(left, pb.left[0], pb.right[0]), dtype), None,
                           jnp.zeros((1, n), dtype), jnp.asarray(np.where(left, pb.left[2], pb.right[2]), dtype),
                           prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, case.end_time, cfg), prm, cfg)
    return x, out, pb(x, case.end_time)


def sod_l1(n, scheme, dtype=jnp.float64):
    """Mean |error| of rho, u, p scaled by rho_L, u*, p_L."""
    _, out, (rho, u, p) = sod(n, scheme, dtype)
    pb = sod_000().problem
    return (np.mean(np.abs(np.asarray(out["rho"], float) - rho)) / pb.left[0],
            np.mean(np.abs(np.asarray(out["velocity"][0], float) - u)) / pb.u_star,
            np.mean(np.abs(np.asarray(out["pressure"], float) - p)) / pb.left[2])


@pytest.mark.parametrize("scheme, dtype", [
    (0, jnp.float64), (1, jnp.float64), (0, jnp.float32),
    pytest.param(1, jnp.float32, marks=pytest.mark.slow)])  # compile time: one float32 run by default
def test_sod_l1_error(scheme, dtype):
    """1000 cells, as in seed 000 Fig. 6. A captured discontinuity spread over w cells contributes
    about w dx |jump| / L to the mean error; with w = 8 and the exact jumps (contact + shock in rho:
    0.30 rho_L; shock in u: u*; shock in p: 0.20 p_L) the bounds are 8/1000 x those jumps. float32
    meets the same bounds (its round-off, ~1e-7, is far below them)."""
    pb = sod_000().problem
    w_dx = 8.0 / 1000
    jumps = ((pb.rho_star_left - pb.right[0]) / pb.left[0], 1.0, (pb.p_star - pb.right[2]) / pb.left[2])
    errors = sod_l1(1000, scheme, dtype)
    for err, jump in zip(errors, jumps):
        assert err < w_dx * jump, (errors, jumps)


@pytest.mark.slow
@pytest.mark.parametrize("scheme", SCHEMES)
def test_sod_observed_order(scheme):
    """L1 order over 5 grids (100..1600 cells). Captured contacts converge at p/(p+1) = 2/3 for a
    second-order scheme and shocks at 1 (Banks, Aslam & Rider, J. Comput. Phys. 227, 2008), so
    the density/velocity/pressure orders lie in [0.6, 1.1]."""
    grids = (100, 200, 400, 800, 1600)
    errors = np.array([sod_l1(n, scheme) for n in grids])
    orders = np.log2(errors[:-1] / errors[1:])
    fit = -np.polyfit(np.log(grids), np.log(errors), 1)[0]
    print(f"scheme {scheme}: L1 errors {errors.tolist()}, pairwise orders {orders.tolist()}, fitted {fit}")
    assert np.all((fit > 0.6) & (fit < 1.1)), fit


@pytest.mark.slow
@pytest.mark.parametrize("scheme", SCHEMES)
def test_tnt_air_shock_tube_converges(scheme):
    """TNT products (JWL) | air (ideal gas), two materials in one grid, against the exact Riemann
    solution: the L1 errors of rho, u, p converge with a fitted order >= 0.6 over 200..800 cells
    (captured contact: 2/3, shock: 1, as for Sod)."""
    case = tnt_air()
    pb, (x0, x1) = case.problem, case.domain
    errors = []
    for n in (200, 400, 800):
        cfg = euler.Config((n,), (x1 - x0) / n, 0, ((euler.OUTFLOW, euler.OUTFLOW),), scheme, 2, (x0,))
        x = centres(cfg)[0]
        left = x < pb.x0
        prm = params(pb.eos_left, pb.eos_right)
        U = euler.conservative(jnp.stack([jnp.full(n, pb.left[0]), jnp.full(n, pb.right[0])]),
                               jnp.asarray(left, float), jnp.zeros((1, n)),
                               jnp.asarray(np.where(left, pb.left[2], pb.right[2])), prm, cfg)
        out = euler.primitives(euler.advance_to(U, prm, case.end_time, cfg), prm, cfg)
        rho, u, p = pb(x, case.end_time)
        errors.append((np.mean(np.abs(np.asarray(out["rho"]) - rho)) / pb.left[0],
                       np.mean(np.abs(np.asarray(out["velocity"][0]) - u)) / pb.u_star,
                       np.mean(np.abs(np.asarray(out["pressure"]) - p)) / pb.left[2]))
    errors = np.array(errors)
    fit = -np.polyfit(np.log([200, 400, 800]), np.log(errors), 1)[0]
    print(f"scheme {scheme}: tnt|air L1 errors (200, 400, 800 cells) {errors.tolist()}, fitted orders {fit}")
    assert np.all(fit > 0.6), fit


@pytest.mark.slow  # the default suite checks x against y in 2D (tests/test_euler_kernels.py)
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("ndim", [2, 3])
def test_sod_along_last_axis_equals_1d(scheme, ndim):
    """The Sod tube along y (2D) or z (3D), 4 cells across with walls, equals the 1D run with the same
    fixed steps to round-off: every axis runs the same operator, and transverse operators act on a
    transversally uniform state as the identity."""
    n, pb = 100, sod_000().problem
    dt, steps = 0.16 * 1e-3 / n, 60  # |u| + c < 2.2 m/s, c < 1.2 m/s: HLLC sum <= 0.72 in 3D, LW <= 0.18
    results = []
    for shape in ((n,), (4,) * (ndim - 1) + (n,)):
        nd = len(shape)
        cfg = euler.Config(shape, 1e-3 / n, 0, ((euler.WALL, euler.WALL),) * (nd - 1) + ((0, 0),), scheme, 1,
                           (0.0,) * nd)
        left = centres(cfg)[-1] < pb.x0
        prm = params(AIR)
        U = euler.conservative(jnp.asarray(np.where(left, pb.left[0], pb.right[0])), None, jnp.zeros((nd,) + shape),
                               jnp.asarray(np.where(left, pb.left[2], pb.right[2])), prm, cfg)
        out = euler.primitives(run_fixed(U, prm, dt, steps, cfg), prm, cfg)
        results.append((np.asarray(out["rho"]), np.asarray(out["velocity"][-1]), np.asarray(out["pressure"])))
    for a, b in zip(results[0], results[1]):
        np.testing.assert_allclose(b, np.broadcast_to(a, b.shape), rtol=1e-12, atol=1e-12 * np.abs(a).max())


# --- smooth flow ------------------------------------------------------------------------------------

def advected_wave_error(n, ndim, scheme):
    """rho = 1 + 0.2 sin(2 pi sum_d x_d), u_d = 1, p = 1 (gamma 1.4) on the periodic unit box, after
    one period (t = 1): mean |rho - exact|."""
    cfg = euler.Config((n,) * ndim, 1.0 / n, 0, ((euler.PERIODIC, euler.PERIODIC),) * ndim, scheme, 1, (0.0,) * ndim)
    phase = sum(centres(cfg))
    prm = params(AIR)
    U = euler.conservative(jnp.asarray(1.0 + 0.2 * np.sin(2 * np.pi * phase)), None, jnp.ones((ndim,) + cfg.shape),
                           jnp.ones(cfg.shape), prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, 1.0, cfg), prm, cfg)
    return float(np.mean(np.abs(np.asarray(out["rho"]) - (1.0 + 0.2 * np.sin(2 * np.pi * phase)))))


@pytest.mark.slow
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("ndim, grids", [(1, (64, 128, 256, 512)), (2, (64, 128, 256)), (3, (32, 64))])
def test_smooth_advection_order(scheme, ndim, grids):
    """Both schemes are second order on smooth flow: the observed L1 order between the two finest
    grids is >= 1.8 in 1D and 2D. LW's adaptive viscosity (Eqs. 3-5) has |theta| = O(1) in an
    O(dx) band around each extremum, where it clips at first order; the L1 order approaches 2
    from below (1D: 1.39, 1.81, 1.84 at 32..256 cells), so 3D, affordable here only at 32 and
    64 cells, is held to >= 1.3 (pre-asymptotic) and printed; finer 3D levels:
    test_smooth_advection_order_3d_finer."""
    errors = np.array([advected_wave_error(n, ndim, scheme) for n in grids])
    orders = np.log2(errors[:-1] / errors[1:])
    print(f"scheme {scheme} {ndim}D: L1 errors {errors.tolist()} orders {orders.tolist()}")
    assert orders[-1] >= (1.8 if ndim < 3 else 1.3), orders


@pytest.mark.slow
@pytest.mark.parametrize("scheme, grids", [(euler.LAX_WENDROFF, (128, 160)), (euler.HLLC_MUSCL, (64, 80))])
def test_smooth_advection_order_3d_finer(scheme, grids):
    """Issue 5 item 2: the 3D diagonal wave of test_smooth_advection_order on finer grids, held to the
    issue's >= 1.8 (LW 128 -> 160: ~20 min, HLLC 64 -> 80: ~10 min on the 2-core CPU; measured 1.86 and
    1.81). LW's pairwise orders rise only from 96 cells on (1.22 / 1.41 / 1.74 / 1.86 over 48..160):
    the adaptive viscosity clips each x-, y- and z-line's extremum band, three times per step in 3D, and
    this higher-harmonic part of the error, first order on coarse grids, dominates until ~128 cells,
    while the wave's amplitude error converges at order 2.2-2.5 and its phase error at 1.6-2.0 from 64
    cells on (docs/verification.md, Verification, item 2)."""
    errors = np.array([advected_wave_error(n, 3, scheme) for n in grids])
    order = np.log(errors[0] / errors[1]) / np.log(grids[1] / grids[0])
    print(f"scheme {scheme} 3D: L1 errors {errors.tolist()} at {grids}, order {order}")
    assert order >= 1.8, order


# --- two materials ----------------------------------------------------------------------------------

@pytest.mark.parametrize("scheme", SCHEMES)
def test_interface_advection_keeps_pressure_and_velocity(scheme):
    """A TNT-products slab (JWL, 1000 kg/m^3) in air (50 kg/m^3) at p = 1 GPa, u = 2 km/s is carried
    once around a periodic 1 m domain. The five-equation model with the isobaric closure keeps
    p and u exactly uniform in exact arithmetic (ERRATA 000-9): both schemes update alpha with the
    weights of the partial densities. Bound 1e-3: a mass-fraction mixture would show O(10 %)
    pressure spikes at the interfaces; round-off gives ~1e-9 here."""
    n, p0, u0 = 100, 1.0e9, 2000.0
    cfg = euler.Config((n,), 1.0 / n, 0, ((euler.PERIODIC, euler.PERIODIC),), scheme, 2, (0.0,))
    x = centres(cfg)[0]
    alpha = np.where((x > 0.25) & (x < 0.75), 1.0, 0.0)
    prm = params(TNT, AIR)
    U = euler.conservative(jnp.stack([jnp.full(n, 1000.0), jnp.full(n, 50.0)]), jnp.asarray(alpha),
                           jnp.full((1, n), u0), jnp.full(n, p0), prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, 1.0 / u0, cfg), prm, cfg)
    assert float(jnp.max(jnp.abs(out["pressure"] / p0 - 1.0))) < 1e-3
    assert float(jnp.max(jnp.abs(out["velocity"][0] / u0 - 1.0))) < 1e-3
    # the slab came back: its volume is kept, and each interface is smeared over < 10 cells
    assert abs(float(jnp.mean(out["alpha"])) - 0.5) < 1e-9  # alpha div u at round-off, ~700 steps
    assert float(jnp.mean(jnp.abs(out["alpha"] - alpha))) < 2 * 10 / n


# --- closed 3D box ----------------------------------------------------------------------------------

def box_blast(scheme, n=16, centre=(0.4, 0.4, 0.4), bc=((euler.WALL, euler.WALL),) * 3):
    cfg = euler.Config((n,) * 3, 1.0 / n, 0, bc, scheme, 1, (0.0,) * 3)
    r2 = sum((x - c) ** 2 for x, c in zip(centres(cfg), centre))
    prm = params(AIR, cfl=0.4)
    U = euler.conservative(jnp.asarray(np.where(r2 < 0.15 ** 2, 1.0, 0.125)), None, jnp.zeros((3,) + cfg.shape),
                           jnp.asarray(np.where(r2 < 0.15 ** 2, 10.0, 1.0)), prm, cfg)
    return U, prm, cfg


@pytest.mark.parametrize("scheme", [euler.LAX_WENDROFF, pytest.param(euler.HLLC_MUSCL, marks=pytest.mark.slow)])
def test_closed_box_conserves_3d(scheme):  # HLLC: 3D compile time; its 2D closed box runs by default
    """Closed box (walls on x and y, periodic in z), blast off-centre in all three directions, 20
    steps: the waves reach and reflect off the walls. Both schemes are in flux form, and a mirror
    wall passes no mass or energy: mass and energy change only by round-off, < 1e-12 per 1000 steps
    (bound scaled to the 20 steps run). The z momentum (no wall across z) is conserved to the same
    bound relative to mass x max sound speed; x and y momentum change by the wall pressure forces."""
    periodic_z = ((euler.WALL, euler.WALL),) * 2 + ((euler.PERIODIC, euler.PERIODIC),)
    U0, prm, cfg = box_blast(scheme, centre=(0.4, 0.45, 0.3), bc=periodic_z)
    dt = euler.stable_dt(U0, prm, cfg)
    U = run_fixed(U0, prm, dt, 20, cfg)
    (m0, p0, e0), (m1, p1, e1) = euler.total(U0, cfg), euler.total(U, cfg)
    c_max = float(jnp.max(euler.primitives(U0, prm, cfg)["sound_speed"]))
    bound = 1e-12 * 20 / 1000
    assert abs(float(m1 / m0) - 1.0) < bound
    assert abs(float(e1 / e0) - 1.0) < bound
    assert abs(float(p1[2] - p0[2])) / (float(m0) * c_max) < bound
    assert float(jnp.max(jnp.abs(p1[:2] - p0[:2]))) / (float(m0) * c_max) > 1e3 * bound  # the walls did act


@pytest.mark.slow
@pytest.mark.parametrize("scheme", SCHEMES)
def test_axis_permutation_symmetry_3d(scheme):
    """Blast centred on the box diagonal, run until it has reflected off the walls: the solution is
    symmetric under permutations of (x, y, z). HLLC-MUSCL (unsplit) keeps it to round-off; the
    split LW (Eq. 6: z y x x y z) breaks it at the splitting error, printed and bounded by 1 % of
    the density range."""
    U0, prm, cfg = box_blast(scheme, n=24)
    U = euler.advance_to(U0, prm, 0.35, cfg)
    rho = np.asarray(euler.primitives(U, prm, cfg)["rho"])
    asym = max(np.max(np.abs(rho - np.transpose(rho, perm))) for perm in ((1, 0, 2), (0, 2, 1), (2, 1, 0)))
    asym /= rho.max() - rho.min()
    print(f"scheme {scheme}: max permutation asymmetry of rho / (rho max - rho min) = {asym:.3e}")
    assert asym < (1e-12 if scheme == euler.HLLC_MUSCL else 1e-2)
