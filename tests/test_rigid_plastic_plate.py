"""Fully clamped circular plate under an impulsive velocity: the rigid-plastic (Jones) reference, the
Nurick–Martin fit, the membrane mode solution of any axisymmetric impulse (Symonds–Wierzbicki), and (slow) the
project's MPM plate against them.

The fast tests check the closed form against its own derivation, term by term, by
quadrature (the dissipation of the conical mode under the square yield condition, the
modal kinetic energy and the Martin–Symonds initial modal velocity), its limits, its
inverses, the identity phi_c = lambda^(1/2) of a uniform impulse, and bad input; the membrane mode series
against the uniform impulse's closed form and against an independent finite-difference solution.
"""
import numpy as np
import pytest
from scipy.integrate import quad

from blastfsi.exact.rigid_plastic_plate import ClampedCircularPlate, jones_deflection

# steel-plate-blast's plate (seed 000 Table 1 case 1): free radius 0.25 m, 10 mm RHA;
# density and flow stress (the Johnson-Cook A) of the library's steel-rha.
R, H, RHO, SIGMA0 = 0.25, 0.01, 7830.0, 950e6
PLATE = ClampedCircularPlate(R, H, RHO, SIGMA0)


@pytest.mark.parametrize("v0", [5.0, 20.0, 59.0, 150.0])
def test_jones_is_the_energy_balance_of_the_conical_mode(v0):
    """(1/2) m Wdot0^2 int(phi^2 dA) = D(W_f), every term by quadrature:
    phi = 1 - r/R, Wdot0 = V0 int(phi dA) / int(phi^2 dA) (Martin-Symonds projection),
    D(W) = int_0^W [ int_0^R (M0 + N0 w(r)) (1/(R r)) 2 pi r dr + 2 pi R M0 / R ] dW'."""
    m, n0, m0 = RHO * H, SIGMA0 * H, SIGMA0 * H ** 2 / 4.0
    phi = lambda r: 1.0 - r / R  # noqa: E731
    a1 = quad(lambda r: phi(r) * 2 * np.pi * r, 0, R)[0]
    a2 = quad(lambda r: phi(r) ** 2 * 2 * np.pi * r, 0, R)[0]
    wdot0 = v0 * a1 / a2
    assert wdot0 == pytest.approx(2.0 * v0, rel=1e-12)
    modal_kinetic = 0.5 * m * wdot0 ** 2 * a2
    assert modal_kinetic == pytest.approx(2.0 / 3.0 * 0.5 * m * v0 ** 2 * np.pi * R ** 2, rel=1e-12)

    def rate(w_centre):  # dissipation per unit Wdot at centre deflection w_centre
        hoop = quad(lambda r: (m0 + n0 * w_centre * phi(r)) / (R * r) * 2 * np.pi * r, 0, R)[0]
        return hoop + 2 * np.pi * R * m0 / R

    wf = PLATE.jones(v0) * H
    dissipated = quad(rate, 0, wf)[0]
    assert dissipated == pytest.approx(modal_kinetic, rel=1e-9)
    # the energy-bound variant dissipates the whole initial kinetic energy
    wb = PLATE.energy_bound(v0) * H
    assert quad(rate, 0, wb)[0] == pytest.approx(0.5 * m * v0 ** 2 * np.pi * R ** 2, rel=1e-9)


def test_membrane_part_is_the_radial_stretch():
    """The membrane share of D(W), pi N0 W^2 / 2, is N0 times the area integral of (1/2) w'^2."""
    w = 0.03
    stretch = quad(lambda r: 0.5 * (w / R) ** 2 * 2 * np.pi * r, 0, R)[0]
    assert SIGMA0 * H * stretch == pytest.approx(np.pi * SIGMA0 * H * w ** 2 / 2, rel=1e-12)


def test_limits_and_damage_number():
    # uniform impulse: phi_c = lambda^(1/2) exactly
    v = np.array([1.0, 30.0, 300.0])
    assert np.allclose(PLATE.damage_number(PLATE.impulse(v)), np.sqrt(PLATE.lam(v)), rtol=1e-13)
    # small lambda (bending-dominated): sqrt(1 + x) - 1 -> x / 2, i.e. lambda / 3
    small = 0.05
    assert PLATE.jones(small) == pytest.approx(PLATE.lam(small) / 3.0, rel=1e-5)  # next term: -x/4, x = 2 lambda/3
    # large lambda (membrane): delta / t -> (2/3)^(1/2) phi_c = 0.8165 phi_c, the "0.817 phi_c" of Nurick & Martin
    big = 1e5
    ratio = PLATE.jones(big) / PLATE.damage_number(PLATE.impulse(big))
    assert ratio == pytest.approx(np.sqrt(2 / 3), rel=1e-3)  # next term: -1 / (delta/t)
    assert PLATE.membrane_limit(big) - PLATE.jones(big) == pytest.approx(1.0, rel=1e-3)
    # Jones's own notation lambda_J = m V0^2 R^2 / (M0 H) = 4 lambda: (1 + lambda_J / 6)^(1/2) - 1
    lam_j = RHO * H * 40.0 ** 2 * R ** 2 / (SIGMA0 * H ** 2 / 4 * H)
    assert PLATE.jones(40.0) == pytest.approx(np.sqrt(1 + lam_j / 6) - 1, rel=1e-13)
    assert jones_deflection(40.0, R, H, RHO, SIGMA0) == PLATE.jones(40.0)
    assert PLATE.jones(0.0) == 0.0


def test_point_values_for_steel_plate_blast():
    """Hand values: mass 15.374 kg; V0 = 59.01 m/s (I = 907 N s) for delta/t = 2.60; Nurick-Martin at phi_c = 1."""
    assert PLATE.mass == pytest.approx(RHO * H * np.pi * R ** 2)
    lam = 1.5 * (3.6 ** 2 - 1)  # = 17.94
    v = np.sqrt(lam * SIGMA0 * H ** 2 / (RHO * R ** 2))
    assert PLATE.jones_velocity(2.6) == pytest.approx(v, rel=1e-13)
    assert PLATE.jones(PLATE.jones_velocity([2.6, 4.85])) == pytest.approx([2.6, 4.85], rel=1e-12)
    assert PLATE.impulse(v) == pytest.approx(907.3, abs=0.5)
    unit_phi = np.pi * R * H ** 2 * np.sqrt(RHO * SIGMA0)  # the impulse of phi_c = 1
    assert PLATE.nurick_martin(unit_phi) == pytest.approx(0.425 + 0.277, rel=1e-13)
    assert PLATE.nurick_martin_impulse(2.6) == pytest.approx((2.6 - 0.277) / 0.425 * unit_phi, rel=1e-13)
    e_r = (0.5 * PLATE.mass * v ** 2) / (np.pi * R ** 2 * H * SIGMA0 ** 2 / (2 * 207e9))
    assert PLATE.energy_ratio(v) == pytest.approx(e_r, rel=1e-13)


@pytest.mark.parametrize("kwargs, word", [
    (dict(radius=-0.25), "radius"), (dict(thickness=0.0), "thickness"), (dict(density=float("nan")), "density"),
    (dict(flow_stress="x"), "flow_stress"), (dict(thickness=0.3), "not a plate")])
def test_bad_plate(kwargs, word):
    args = dict(radius=R, thickness=H, density=RHO, flow_stress=SIGMA0) | kwargs
    with pytest.raises(ValueError, match=word):
        ClampedCircularPlate(**args)


def test_bad_load():
    with pytest.raises(ValueError, match="velocity"):
        PLATE.jones(-1.0)
    with pytest.raises(ValueError, match="impulse"):
        PLATE.nurick_martin([100.0, np.inf])
    with pytest.raises(ValueError, match="intercept|starts"):
        PLATE.nurick_martin_impulse(0.1)


def mpm_plate(v0, cells_per_thickness=4, t_end=6.0e-4, ppc=2):
    """The r-z MPM scenario of steel-plate-blast's plate alone (GIMP, steel-rha, clamped beyond r = 0.25 m,
    plate to r = 0.28 m) given a uniform upward velocity v0 over the free span; tracer at the centre."""
    h = H / cells_per_thickness
    return {"method": "mpm", "name": "clamped-plate-impulse",
            "grid": {"lower": [0.0, -0.01], "upper": [0.3, 0.08], "cells": int(round(0.3 / h)), "axisymmetric": True,
                     "boundaries": {"x": ["slip", "free"], "y": ["free", "free"]}},
            "bodies": [{"lower": [0.0, 0.0], "upper": [0.28, H], "material": "steel-rha", "velocity": [0.0, v0],
                        "particles_per_cell": ppc, "supports": [{"lower": [R, 0.0], "upper": [0.28, H]}]}],
            "numerics": {"shape": "gimp"}, "time": {"end": t_end},
            "output": {"history_samples": 121, "fields": 0, "tracers": [[0.0, H / 2]]}}


def _membrane_by_finite_differences(v0, cells=800):
    """The membrane mode problem solved independently of the series: rho H w_tt = N0 (1/r) (r w_r)_r on
    cells of r < R (cell-centred, w = 0 at the clamp by a mirrored ghost, symmetry at r = 0), leapfrog in time
    at Courant number 0.4; the centre's first maximum (second order in the cell)."""
    c = np.sqrt(SIGMA0 / RHO)
    dr = R / cells
    r = (np.arange(cells) + 0.5) * dr
    faces = np.arange(cells + 1) * dr
    w, v = np.zeros(cells), v0(r).astype(float)
    dt, t, best = 0.4 * dr / c, 0.0, (0.0, 0.0)
    while True:
        ghost = np.concatenate([[w[0]], w, [-w[-1]]])
        flux = faces * np.diff(ghost) / dr
        v += dt * c ** 2 * np.diff(flux) / (r * dr)
        w += dt * v
        t += dt
        if w[0] > best[0]:
            best = (w[0], t)
        elif v[0] < 0.0:
            return best[0] / H, best[1]


def test_membrane_mode_of_a_uniform_impulse_is_v0_r_over_c():
    """Uniform V0: the centre keeps V0 until the clamp's unloading wave arrives at t = R / c, then stops, so
    delta/t = lambda^(1/2), reached at R / c. The truncated series rings where the centre's velocity jumps
    (Gibbs): 0.4-0.6 % above at 300-600 terms, so 1 %; the time within 0.5 %."""
    c = np.sqrt(SIGMA0 / RHO)
    for v0 in (30.0, 59.0):
        ratio, t = PLATE.membrane_mode(lambda r, v=v0: np.full_like(r, RHO * H * v))
        assert ratio == pytest.approx(float(np.sqrt(PLATE.lam(v0))), rel=1e-2)
        assert t == pytest.approx(R / c, rel=5e-3)
    assert np.sqrt(PLATE.lam(59.0)) / PLATE.membrane_limit(59.0) == pytest.approx(np.sqrt(1.5), rel=1e-12)


def test_membrane_mode_of_a_concentrated_impulse_against_finite_differences():
    """A smooth impulse peaked on the axis (the shape of a close-in blast's): the series and an independent
    finite-difference solution of the same wave equation agree within the latter's error (its change from
    400 to 800 cells is 1e-5; measured agreement 3e-6, so 1e-4); the deflection is linear in the impulse."""
    def impulse(r):
        return 9.0e3 * np.exp(-(r / 0.07) ** 2)

    ratio, t = PLATE.membrane_mode(impulse)
    fd, t_fd = _membrane_by_finite_differences(lambda r: impulse(r) / (RHO * H))
    assert ratio == pytest.approx(fd, rel=1e-4)
    assert t == pytest.approx(t_fd, rel=1e-2)
    doubled, t2 = PLATE.membrane_mode(lambda r: 2.0 * impulse(r))
    assert doubled == pytest.approx(2.0 * ratio, rel=1e-9) and t2 == t


def test_membrane_mode_refuses_bad_input():
    with pytest.raises(ValueError, match="modes"):
        PLATE.membrane_mode(lambda r: np.ones_like(r), modes=5)
    with pytest.raises(ValueError, match="specific_impulse"):
        PLATE.membrane_mode(lambda r: -np.ones_like(r))
    with pytest.raises(ValueError, match="specific_impulse"):
        PLATE.membrane_mode(lambda r: np.full_like(r, np.nan))


@pytest.mark.slow
def test_mpm_plate_peak_deflection_against_rigid_plastic_bracket():
    """The shipped resolution of steel-plate-blast (2.5 mm cells, 4 across t, GIMP, 2 particles per cell and
    direction) at the uniform V0 for which Jones gives delta/t = 2.60 (59.0 m/s, 907 N s;
    about 1 min on 2 shared cores).

    Tolerance: the rigid-plastic W_f is no exact target for an elastic-plastic plate's peak. Jones's modal
    solution drops 1/3 of the initial kinetic energy in the transient phase (lower curve); the same mode with
    all of it is the energy bound (upper curve, 3.35 here); the elastic-plastic peak adds the elastic stretch
    (sigma0/E = 0.46 % against membrane strains ~1 %: energy ratio 6.3), and the flow stress (JC A, no
    hardening, no rate, square yield vs von Mises) is uncertain by -20 / +15 %. The peak must lie in
    [0.85 x Jones, 1.15 x energy bound] = [2.21, 3.85]; a plate 30 % too stiff or too soft in the
    membrane regime leaves it (measured 2026-12-05: 3.34, at 0.46 ms)."""
    import blastfsi

    v0 = float(PLATE.jones_velocity(2.6))
    res = blastfsi.run(mpm_plate(v0))
    w = np.asarray(res.history["tracer0_displacement_z"])
    peak = float(w.max()) / H
    assert 0.85 * PLATE.jones(v0) <= peak <= 1.15 * PLATE.energy_bound(v0)
    assert res.summary["max_damage"] < 1.0
