"""Tier 1: point values and limits of the shock relations and plate theory (seed 002)."""
import numpy as np
import pytest

from blastfsi.exact import shock
from conftest import P0, RHO0


@pytest.mark.parametrize("ratio", [0.01, 0.5, 4.49, 100.0, 1000.0])
def test_rankine_hugoniot_matches_corrected_eq27_eq31(ratio):
    # ERRATA 002-4 (gamma = 1.4 forms) against the general-gamma implementation
    ps = ratio * P0
    s = shock.incident_shock(ps, P0, RHO0, 1.4)
    a0 = np.sqrt(1.4 * P0 / RHO0)
    assert s.particle_velocity == pytest.approx(a0 * 5 / 7 * ratio / np.sqrt(1 + 6 / 7 * ratio), rel=1e-12)
    assert s.shock_speed == pytest.approx(a0 * np.sqrt(1 + 6 / 7 * ratio), rel=1e-12)
    assert s.density == pytest.approx(RHO0 * (7 + 6 * ratio) / (7 + ratio), rel=1e-12)


@pytest.mark.parametrize("gamma", [1.2, 1.4, 5 / 3])
def test_jump_conditions_conserve_momentum_and_energy(gamma):
    ps = 3.0 * P0
    s = shock.incident_shock(ps, P0, RHO0, gamma)
    U, u = s.shock_speed, s.particle_velocity
    # momentum: p1 - p0 = rho0 U u ; energy: e1 - e0 = (p1 + p0)/2 (1/rho0 - 1/rho1)
    assert ps == pytest.approx(RHO0 * U * u, rel=1e-12)
    e0, e1 = P0 / ((gamma - 1) * RHO0), (P0 + ps) / ((gamma - 1) * s.density)
    assert e1 - e0 == pytest.approx(0.5 * (2 * P0 + ps) * (1 / RHO0 - 1 / s.density), rel=1e-12)


def test_reflection_coefficient_eq25_and_limits():
    ps = np.array([0.3, 4.49, 50.0]) * P0
    np.testing.assert_allclose(shock.reflection_coefficient(ps, P0), 2 * (7 * P0 + 4 * ps) / (7 * P0 + ps), rtol=1e-12)
    assert shock.reflection_coefficient(1e-8 * P0, P0) == pytest.approx(2.0, rel=1e-7)
    assert shock.reflection_coefficient(1e9 * P0, P0) == pytest.approx(8.0, rel=1e-7)  # Eq. (26)
    # general gamma strong-shock limit (3 gamma - 1)/(gamma - 1): 6 for gamma = 5/3
    assert shock.reflection_coefficient(1e9 * P0, P0, 5 / 3) == pytest.approx(6.0, rel=1e-6)


def test_reflected_state_is_at_rest_by_face_pressure():
    # the Riemann solver against a fixed plate (v = 0) must give Eq. (25)
    for r in (0.1, 4.49, 100.0):
        ps = r * P0
        assert shock.face_overpressure(0.0, ps, P0, RHO0) / ps == pytest.approx(
            shock.reflection_coefficient(ps, P0), rel=1e-9)
        ufs = shock.free_surface_velocity(ps, P0, RHO0)
        assert abs(shock.face_overpressure(ufs, ps, P0, RHO0)) < 1e-8 * ps


def test_f_R_limits_and_eq30_weak_shock_agreement():
    assert shock.f_R(1e-6 * P0, P0, RHO0) == pytest.approx(1.0, rel=1e-5)
    assert shock.f_R_eq30(1e-6 * P0, P0) == pytest.approx(1.0, rel=1e-5)
    for r in (0.01, 0.1, 1.0):  # the printed Eq. (30) agrees for weak shocks only (docs/theory/lagrangian1d.md)
        assert shock.f_R_eq30(r * P0, P0) == pytest.approx(shock.f_R(r * P0, P0, RHO0), rel=3e-4)


def test_eq29_limits():
    assert shock.impulse_ratio_uniform(1e-10, 1.3) == pytest.approx(1.0, rel=1e-9)  # heavy plate = wall
    b = np.array([1e4, 1e5])
    np.testing.assert_allclose(shock.impulse_ratio_uniform(b, 1.3), 1.3 / b, rtol=1e-12)  # slope -1


def test_eq32_limits():
    g_r, c_r, f_r = 3.1, 4.3, 1.37
    assert shock.impulse_ratio_exponential(1e-9, g_r, c_r, f_r) == pytest.approx(g_r, rel=1e-6)
    big = 1e7
    assert shock.impulse_ratio_exponential(big, g_r, c_r, f_r) == pytest.approx(c_r * f_r / big, rel=1e-4)
    # acoustic: Taylor's 2 beta^(beta/(1-beta)), continuous through beta = 1
    for b in (0.3, 2.0):
        assert shock.impulse_ratio_exponential(b, 2.0, 2.0, 1.0) == pytest.approx(2 * b ** (b / (1 - b)), rel=1e-12)
    assert shock.impulse_ratio_exponential(1.0, 2.0, 2.0, 1.0) == pytest.approx(
        shock.impulse_ratio_exponential(1.0 + 1e-7, 2.0, 2.0, 1.0), rel=1e-6)


def test_quasi_steady_plate_is_eq29_for_acoustic_waves():
    ps, ti = 1e-4 * P0, 1e-3
    for beta in (0.3, 3.0):
        m = shock.areal_mass_from_beta_s(beta, ps, ti, P0, RHO0)
        v = shock.quasi_steady_plate(ps, ti, m, P0, RHO0)
        cr = shock.reflection_coefficient(ps, P0)
        assert m * v / (cr * ps * ti) == pytest.approx(shock.impulse_ratio_uniform(beta, 1.0), rel=1e-4)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="p0"):
        shock.incident_shock(1.0, -1.0, RHO0)
    with pytest.raises(ValueError, match="areal mass"):
        shock.beta_s(P0, 1e-3, 0.0, P0, RHO0)
