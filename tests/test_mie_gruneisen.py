"""Mie-Grueneisen EOS, 000 Eqs. (65)-(66): point values, Hugoniot consistency, sound speed."""
import numpy as np
import pytest

import blastfsi  # noqa: F401
from blastfsi.eos import mie_gruneisen as mg
from blastfsi.eos.mie_gruneisen import MieGruneisenParams

# seed 000 Sec. 4.5 steel Hugoniot with the 4340 density of the library
STEEL = MieGruneisenParams(rho0=7830.0, C0=4569.0, S=1.49, gamma0=2.17, a=0.0)


def test_point_value_by_hand():
    # mu = 0.1: p_H = rho0 C0^2 [0.1 + (2*1.49 - 1)*0.01 + 0.49*3.47*0.001], Eq. (66)
    k = 7830.0 * 4569.0 ** 2
    p_h = k * (0.1 + 1.98 * 0.01 + 0.49 * 3.47 * 0.001)
    rho = 1.1 * 7830.0
    e = 1.0e5
    expected = p_h * (1.0 - 2.17 * 0.1 / 2.0) + 2.17 * rho * e  # Eq. (65)
    assert mg.pressure(rho, e, STEEL) == pytest.approx(expected, rel=1e-14)
    # tension: p_H = rho0 C0^2 mu
    assert mg.pressure(0.95 * 7830.0, 0.0, STEEL) == pytest.approx(k * -0.05 * (1.0 + 2.17 * 0.05 / 2.0),
                                                                     rel=1e-14)


def test_hugoniot_state_satisfies_rankine_hugoniot_energy():
    """On the Hugoniot, e_H = p_H mu / (2 rho0 (1 + mu)) (from rest, e0 = 0) gives p = p_H exactly."""
    mu = np.linspace(0.01, 0.4, 9)
    rho = STEEL.rho0 * (1.0 + mu)
    p_h = mg.hugoniot_pressure(mu, STEEL)
    e_h = p_h * mu / (2.0 * STEEL.rho0 * (1.0 + mu))
    np.testing.assert_allclose(mg.pressure(rho, e_h, STEEL), p_h, rtol=1e-13)


def test_cubic_hugoniot_is_expansion_of_linear_us_up():
    """Eq. (66) agrees with rho0 C0^2 mu (1+mu)/(1-(S-1)mu)^2 to O(mu^4)."""
    def exact(mu):
        return STEEL.rho0 * STEEL.C0 ** 2 * mu * (1.0 + mu) / (1.0 - (STEEL.S - 1.0) * mu) ** 2
    mus = np.array([0.02, 0.01, 0.005])
    err = np.abs(mg.hugoniot_pressure(mus, STEEL) - exact(mus))
    orders = np.log2(err[:-1] / err[1:])
    np.testing.assert_allclose(orders, 4.0, atol=0.1)


def test_sound_speed_reference_and_isentrope():
    # at rho0, e = 0: c = C0 (bulk sound speed)
    assert mg.sound_speed(STEEL.rho0, 0.0, STEEL) == pytest.approx(STEEL.C0, rel=1e-14)
    # c^2 = dp/drho along de = p/rho^2 drho (isentrope), by central differences (error O(h^2))
    p = STEEL._replace(a=0.3)
    for rho, e in ((8500.0, 2e5), (7600.0, 5e4)):
        h = 1e-3
        p0 = mg.pressure(rho, e, p)
        dp = (mg.pressure(rho + h, e + p0 / rho ** 2 * h, p) - mg.pressure(rho - h, e - p0 / rho ** 2 * h, p))
        assert mg.sound_speed_squared(rho, e, p) == pytest.approx(dp / (2 * h), rel=1e-6)


def test_energy_round_trip():
    rho = np.array([7000.0, 7830.0, 9000.0])
    e = np.array([1e4, 3e5, 2e6])
    # round-off bound: eps |f(rho)| / (Gamma rho e) <= 1e-8 for these states
    np.testing.assert_allclose(mg.energy(rho, mg.pressure(rho, e, STEEL), STEEL), e, rtol=1e-7)
