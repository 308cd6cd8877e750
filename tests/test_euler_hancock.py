"""Scheme 2, HLLC-Hancock (blastfsi.euler.hancock: split MUSCL-Hancock with HLLC fluxes): exact solutions
(Sod, a smooth 2D wave, Sedov in r-z and spherical geometry), conservation in 2D and 3D, a products|air
interface at uniform pressure and velocity, positivity of a strong 2D point blast.

Compiles dominate the time of this file (2-7 s per grid configuration on the shared 2-core machine). One
compiled program per configuration (:func:`run`: conversion, time loop, primitives and totals; its other
arguments are traced) serves several tests, and hllc-muscl's errors on the same grids are the recorded
HLLC_MUSCL_L1 (recomputed by the slow test_recorded_hllc_muscl_errors) rather than compiled here again.
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi  # noqa: F401  (float64)
from blastfsi import euler
from blastfsi.euler import geometry
from blastfsi.eos.jwl import ideal_gas_params
from blastfsi.exact.riemann import toro_test
from blastfsi.exact.sedov import Sedov
from blastfsi.materials.gases import GASES

AIR = ideal_gas_params(1.4)
TNT = GASES["tnt"].eos_params()
H, M = euler.HLLC_HANCOCK, euler.HLLC_MUSCL
O, W, A, P = euler.OUTFLOW, euler.WALL, euler.AXIS, euler.PERIODIC
SEDOV_GRIDS = {"spherical": ((60,), euler.SPHERICAL, ((A, O),)),
               "axisymmetric": ((24, 24), euler.CYLINDRICAL, ((A, O), (W, O)))}  # r-z, symmetry plane z = 0
HLLC_MUSCL_L1 = {"sod-100": 5.6796e-3, "sod-200": 3.1065e-3,  # mean |rho - exact| of hllc-muscl (measured,
                 "sedov-spherical": 9.7677e-2, "sedov-axisymmetric": 2.2542e-1}  # characteristic limiting)


@functools.partial(jax.jit, static_argnums=(4,))
def run(initial, prm, t_end, max_steps, cfg):
    """From the primitive state initial = (rho_k, alpha, velocity, p) (euler.conservative's arguments),
    advance at the stable step to t_end (the last step shortened onto it) or max_steps steps, stopping at a
    non-physical state. Returns euler.primitives of the end state and t, steps, physical (no non-physical
    cell at the end), the totals (euler.total) at the start and the end."""
    U = euler.conservative(*initial, prm, cfg)

    def body(state):
        V, t, k, _ = state
        dt = jnp.minimum(euler.stable_dt(V, prm, cfg), t_end - t)
        return euler.step(V, dt, prm, cfg, parity=k), t + dt, k + 1, jnp.isfinite(dt)

    start = (U, jnp.zeros((), U.dtype), jnp.zeros((), jnp.int32), jnp.ones((), bool))
    V, t, k, _ = jax.lax.while_loop(lambda s: s[3] & (s[1] < t_end) & (s[2] < max_steps), body, start)
    return dict(euler.primitives(V, prm, cfg), t=t, steps=k, physical=jnp.isfinite(euler.stable_dt(V, prm, cfg)),
                total0=euler.total(U, cfg), total=euler.total(V, cfg))


def params(*rows, cfl=0.5):
    return euler.Params(jnp.asarray([list(r) for r in rows]), jnp.asarray(cfl))


def centres(cfg):
    return np.meshgrid(*[cfg.origin[d] + (np.arange(m) + 0.5) * cfg.dx for d, m in enumerate(cfg.shape)],
                       indexing="ij")


def run_air(cfg, rho, velocity, p, t_end, max_steps=10 ** 6, cfl=0.5):
    """:func:`run` of an ideal-gas (air, gamma 1.4) state; every cell physical at the end."""
    out = run((rho, None, velocity, p), params(AIR, cfl=cfl), t_end, max_steps, cfg)
    assert bool(out["physical"])
    return out


# --- Sod (Toro 2009 Table 4.1, Test 1) ------------------------------------------------------------------

def sod_l1(n, scheme):
    """Mean |rho - exact| of Toro's Test 1 on n cells at t = 0.25."""
    case = toro_test(1)
    cfg = euler.Config((n,), 1.0 / n, 0, ((O, O),), scheme, 1, (0.0,))
    x = centres(cfg)[0]
    left = x < 0.5
    out = run_air(cfg, np.where(left, 1.0, 0.125), np.zeros((1, n)), np.where(left, 1.0, 0.1), case.end_time)
    assert float(out["t"]) == pytest.approx(case.end_time, rel=1e-14)
    return float(np.mean(np.abs(np.asarray(out["rho"]) - case.problem(x, case.end_time)[0])))


def test_sod_error_matches_hllc_muscl_and_converges():
    """Same reconstruction, limiter and flux as hllc-muscl: its L1 density error at 100 and 200 cells is
    held within 1.5x of hllc-muscl's (measured 0.89x: 5.04e-3 / 2.77e-3 against 5.68e-3 / 3.11e-3). With
    discontinuities the L1 order of any scheme is at most 1 (the shock and contact are smeared over a few
    cells, the rarefaction corners are first order): measured 0.87, held to >= 0.6."""
    hancock = np.array([sod_l1(n, H) for n in (100, 200)])
    muscl = np.array([HLLC_MUSCL_L1[f"sod-{n}"] for n in (100, 200)])
    print(f"Sod L1(rho) at 100, 200 cells: hllc-hancock {hancock}, hllc-muscl {muscl}")
    assert np.all(hancock < 1.5 * muscl), (hancock, muscl)
    assert np.log2(hancock[0] / hancock[1]) >= 0.6


# --- 2D Cartesian, periodic: smooth wave, conservation, strong blast ---------------------------------------

PERIODIC_2D = euler.Config((64, 64), 1.0 / 64, 0, ((P, P),) * 2, H, 1, (0.0, 0.0))


def test_smooth_diagonal_wave_is_second_order():
    """rho = 1 + 0.2 sin(2 pi k (x + y)), u = (1, 1), p = 1 on the periodic unit square (64^2), after one
    period t = 1/(2k): k = 2 is, by the scale invariance of the Euler equations (x, t -> x/2, t/2), the
    k = 1 problem on 32^2 cells tiled 2 x 2, so k = 2, 1 measure the error at 32 and 64 cells per
    wavelength with one grid. A TVD limiter clips each extremum to first order over O(dx), so the L1 order
    tends to 2 from below: measured 1.92 (32 -> 64 cells), held to >= 1.8. The sweep order alternates with
    the step's index (the loop's counter): second order in time over each pair of steps."""
    x, y = centres(PERIODIC_2D)
    errors = []
    for k in (2, 1):
        rho0 = 1.0 + 0.2 * np.sin(2.0 * np.pi * k * (x + y))
        out = run_air(PERIODIC_2D, rho0, np.ones((2,) + x.shape), np.ones(x.shape), 0.5 / k)
        errors.append(float(np.mean(np.abs(np.asarray(out["rho"]) - rho0))))
    order = np.log2(errors[0] / errors[1])
    print(f"smooth 2D wave: L1(rho) {errors} at 32, 64 cells per wavelength, order {order:.3f}")
    assert order >= 1.8, (errors, order)


@pytest.mark.parametrize("cfg", [PERIODIC_2D, pytest.param(euler.Config((8, 8, 8), 1.0 / 8, 0, ((P, P),) * 3, H, 1,
                                                                      (0.0,) * 3), marks=pytest.mark.slow)],
                         ids=["2d", "3d"])  # (3D: its compile time; the split step's axes are those of 2D)
def test_periodic_box_conserves_mass_momentum_energy(cfg):
    """20 steps of a blast (a ball of radius 0.15 at pressure ratio 10, density 1 | 0.125) with a smooth
    velocity field (|u| <= 0.4, every momentum total non-zero) on a periodic box: every update is a face
    difference of fluxes (hancock.py), so the totals change by round-off only, a few eps per cell and step
    (~1e-14 of the scale here); bound 1e-12, momentum relative to mass x the largest signal speed."""
    x = centres(cfg)
    inside = sum((xi - 0.43) ** 2 for xi in x) < 0.15 ** 2
    velocity = np.stack([0.3 * np.sin(2.0 * np.pi * (xi + 0.1 * d)) + 0.1 for d, xi in enumerate(x)])
    out = run_air(cfg, np.where(inside, 1.0, 0.125), velocity, np.where(inside, 10.0, 1.0), 1.0, max_steps=20)
    assert int(out["steps"]) == 20
    (m0, q0, e0), (m1, q1, e1) = out["total0"], out["total"]
    speed = np.sqrt(1.4 * 10.0) + 0.4  # the ball's sound speed and the largest initial |u|
    assert abs(float(m1 / m0) - 1.0) < 1e-12 and abs(float(e1 / e0) - 1.0) < 1e-12
    assert float(jnp.max(jnp.abs(q1 - q0))) < 1e-12 * float(m0) * speed, (q0, q1)
    assert float(jnp.max(jnp.abs(out["pressure"] - np.where(inside, 10.0, 1.0)))) > 1.0  # the blast did move


@pytest.mark.parametrize("cfl", [0.5, 0.9])
def test_strong_point_blast_stays_physical(cfl):
    """A sedov-2d-like point blast: the blast energy in the cells within 2 cells of the centre, the ambient
    pressure 1e-6 of theirs, 200 steps at cfl 0.5 and at the schema's cap 0.9 (each operator then at
    Courant number 0.9): no non-physical cell, positive density and pressure."""
    x, y = centres(PERIODIC_2D)
    hot = (x - 0.5) ** 2 + (y - 0.5) ** 2 < (2.0 * PERIODIC_2D.dx) ** 2
    out = run_air(PERIODIC_2D, np.ones(x.shape), np.zeros((2,) + x.shape), np.where(hot, 1.0, 1e-6), 1e9,
                  max_steps=200, cfl=cfl)
    assert int(out["steps"]) == 200
    assert float(out["rho"].min()) > 0.0 and float(out["pressure"].min()) > 0.0


# --- products | air interface -----------------------------------------------------------------------------

def test_interface_keeps_pressure_and_velocity_uniform():
    """A TNT-products slab (JWL, 1000 kg/m^3) in air (50 kg/m^3) at p = 1 GPa, u = 2 km/s, carried 10 cells:
    the isobaric closure keeps p and u exactly uniform in exact arithmetic (mixture.py: the predictor moves
    rho_k and alpha at uniform p and u, and alpha's update has the partial densities' weights). Round-off of
    the JWL closure at 1 GPa leaves 2.5e-9 (p) and 2.8e-9 (u) here, hllc-muscl 2.8e-9 and 1.0e-9; bound 1e-8
    (a mass-fraction mixture would show O(10 %) pressure spikes)."""
    n, p0, u0 = 100, 1.0e9, 2000.0
    cfg = euler.Config((n,), 1.0 / n, 0, ((P, P),), H, 2, (0.0,))
    x = centres(cfg)[0]
    alpha = np.where((x > 0.25) & (x < 0.5), 1.0, 0.0)
    initial = (np.stack([np.full(n, 1000.0), np.full(n, 50.0)]), alpha, np.full((1, n), u0), np.full(n, p0))
    out = run(initial, params(TNT, AIR), 10 * cfg.dx / u0, 10 ** 6, cfg)
    assert bool(out["physical"])
    assert float(jnp.max(jnp.abs(out["pressure"] / p0 - 1.0))) < 1e-8
    assert float(jnp.max(jnp.abs(out["velocity"][0] / u0 - 1.0))) < 1e-8
    assert float(jnp.mean(out["alpha"])) == pytest.approx(0.25, abs=1e-12)  # the slab's volume is kept
    assert float(jnp.mean(jnp.abs(out["alpha"] - np.roll(alpha, 10)))) < 0.05  # moved 10 cells: 0.021 (0.2 unmoved)


# --- Sedov in radial geometry ------------------------------------------------------------------------------

def sedov_config(case, scheme):
    shape, kind, bc = SEDOV_GRIDS[case]
    return euler.Config(shape, 1.2 / shape[0], kind, bc, scheme, 1, (0.0,) * len(shape))


def sedov_l1(cfg):
    """Mean |rho - exact| of a spherical Sedov blast (E = 1, rho0 = 1, gamma 1.4, ambient p 1e-6) at t = 1:
    the energy (1/2 of it in an r-z half z >= 0) put uniformly into the cells whose centre lies within
    2.5 cells of the origin."""
    x = centres(cfg)
    dist = np.sqrt(sum(xi ** 2 for xi in x))
    hot = dist < 2.5 * cfg.dx
    vol = np.broadcast_to(geometry.cell_volumes(cfg, np.float64), cfg.shape)
    share = 0.5 if len(cfg.shape) == 2 else 1.0
    p = np.where(hot, 0.4 * share / np.sum(vol * hot), 1e-6)  # (gamma - 1) x energy density
    out = run_air(cfg, np.ones(cfg.shape), np.zeros((len(cfg.shape),) + cfg.shape), p, 1.0)
    return float(np.mean(np.abs(np.asarray(out["rho"]) - Sedov(1.0, 1.0, 1.4, "spherical")(dist, 1.0)[0])))


@pytest.mark.parametrize("case", SEDOV_GRIDS)
def test_sedov_error_matches_hllc_muscl(case):
    """Sedov in 1D spherical and r-z geometry on [0, 1.2]^d against the exact solution: the error, set by the
    captured front (a density jump of 6 over a few cells), within 1.5x of hllc-muscl's on the same grid."""
    error = sedov_l1(sedov_config(case, H))
    print(f"Sedov {case}: L1(rho) hllc-hancock {error:.4e}, hllc-muscl {HLLC_MUSCL_L1['sedov-' + case]:.4e}")
    assert error < 1.5 * HLLC_MUSCL_L1["sedov-" + case]


@pytest.mark.slow
def test_recorded_hllc_muscl_errors():
    """HLLC_MUSCL_L1 are hllc-muscl's errors on the grids of the tests above (recomputed here, ~20 s)."""
    errors = {f"sod-{n}": sod_l1(n, M) for n in (100, 200)}
    errors.update({f"sedov-{case}": sedov_l1(sedov_config(case, M)) for case in SEDOV_GRIDS})
    print(errors)
    for key, value in errors.items():
        assert value == pytest.approx(HLLC_MUSCL_L1[key], rel=1e-4), key
