"""Tier 1: the planar von Neumann-Sedov solution against its own conservation laws and the seed."""
import numpy as np
import pytest

from blastfsi.exact.sedov import PlanarSedov


@pytest.fixture(scope="module")
def blast():
    return PlanarSedov(5e8, 1.225, 1.4)


def test_energy_constant_matches_seed_eq38(blast):
    # ERRATA 002-8: K1 = 1.22904 (E0/rho0)^(1/3) <=> alpha = 1.22904^-3 (one-side convention)
    assert blast.alpha ** (-1 / 3) == pytest.approx(1.22904, rel=1e-4)


def test_mass_and_energy_integrals(blast):
    t = blast.time_at_front(22.5)
    x = np.linspace(0.0, 22.5, 400001)
    rho, u, p = blast(x, t)
    assert np.trapezoid(rho, x) == pytest.approx(1.225 * 22.5, rel=1e-6)  # swept mass
    assert np.trapezoid(0.5 * rho * u**2 + p / 0.4, x) == pytest.approx(5e8, rel=1e-5)


def test_euler_equations_residual(blast):
    g, t, h, dt = 1.4, 0.01, 1e-4, 1e-8
    x = np.linspace(2.0, 0.9 * blast.front_position(t), 9)

    def cons(x, t):
        r, u, p = blast(x, t)
        return np.array([r, r * u, 0.5 * r * u * u + p / (g - 1)])

    def flux(x, t):
        r, u, p = blast(x, t)
        E = 0.5 * r * u * u + p / (g - 1)
        return np.array([r * u, r * u * u + p, (E + p) * u])

    dudt = (cons(x, t + dt) - cons(x, t - dt)) / (2 * dt)
    res = dudt + (flux(x + h, t) - flux(x - h, t)) / (2 * h)
    assert np.max(np.abs(res) / np.abs(dudt)) < 1e-3  # finite-difference + table interpolation error


def test_centre_to_front_pressure_ratio_matches_seed_eq37(blast):
    # Eq. (37) at theta = 0 over theta = 1: (1/2)^(2/3) ((2g-1)/(g+1))^((5g^2+g-4)/(3(2-g)(g+1)))
    g = 1.4
    expected = 0.5 ** (2 / 3) * ((2 * g - 1) / (g + 1)) ** ((5 * g * g + g - 4) / (3 * (2 - g) * (g + 1)))
    t = 0.01
    rs = blast.front_position(t)
    ratio = blast(np.array([0.0]), t)[2][0] / blast(np.array([rs * (1 - 1e-12)]), t)[2][0]
    assert ratio == pytest.approx(expected, rel=1e-4)


def test_rankine_hugoniot_at_the_front(blast):
    t = 0.01
    rs = blast.front_position(t)
    U = 2 / 3 * rs / t
    rho, u, p = blast(np.array([rs * (1 - 1e-12)]), t)
    assert rho[0] == pytest.approx(1.225 * 6.0, rel=1e-6)
    assert u[0] == pytest.approx(2 * U / 2.4, rel=1e-6)
    assert p[0] == pytest.approx(2 * 1.225 * U**2 / 2.4, rel=1e-6)


def test_validation():
    with pytest.raises(ValueError, match="gamma"):
        PlanarSedov(1.0, 1.0, 2.5)
    with pytest.raises(ValueError, match="energy"):
        PlanarSedov(-1.0, 1.0)
