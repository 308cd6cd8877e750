"""Tier 1: the Sedov-Taylor blast wave in planar, cylindrical and spherical geometry
against published similarity tables, an independent integration of the
self-similar ODEs and its own conservation integrals."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from blastfsi.exact.sedov import PlanarSedov, Sedov

GEOMETRIES = {"planar": 1, "cylindrical": 2, "spherical": 3}
MEASURE = {1: 1.0, 2: 2.0 * math.pi, 3: 4.0 * math.pi}


@pytest.fixture(scope="module", params=list(GEOMETRIES))
def blast(request):
    return Sedov(2.0e6, 1.225, 1.4, request.param)


def alpha_from_similarity_odes(gamma, j, lam_min=1e-7):
    """alpha by integrating the self-similar Euler equations from the shock inward (test's own derivation).

    With lambda = r/r_s, u = 2/(g+1) U f, rho = (g+1)/(g-1) rho0 g_, p = 2/(g+1) rho0 U^2 h, U = dr_s/dt
    and dU/dt = -(j/2) U^2/r_s, the mass, momentum and entropy equations become (w = 2/(g+1) f - lambda)
        w g_' + 2/(g+1) g_ f' = -(j-1) 2/(g+1) g_ f/lambda,
        w f' + (g-1)/(g+1) h'/g_ = (j/2) f,
        w (h'/h - g g_'/g_) = j,
    with f = g_ = h = 1 at lambda = 1 (strong shock).
    """
    a1, b1 = 2.0 / (gamma + 1.0), (gamma + 1.0) / (gamma - 1.0)

    def rhs(lam, y):
        f, g, h, _ = y
        w = a1 * f - lam
        m = np.array([[a1 * g, w, 0.0], [w, 0.0, 1.0 / (b1 * g)], [0.0, -gamma * w / g, w / h]])
        df, dg, dh = np.linalg.solve(m, [-(j - 1) * a1 * g * f / lam, 0.5 * j * f, float(j)])
        return [df, dg, dh, -(g * f * f + h) * lam ** (j - 1)]

    sol = solve_ivp(rhs, (1.0, lam_min), [1.0, 1.0, 1.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14)
    f, g, h, integral = sol.y[:, -1]
    integral += h * lam_min**j / j  # the core lambda < lam_min: h ~ h(0), g f^2 ~ 0
    return MEASURE[j] * (2.0 / (j + 2.0)) ** 2 * 2.0 / (gamma**2 - 1.0) * integral


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
@pytest.mark.parametrize("gamma", [1.4, 5.0 / 3.0])
def test_energy_constant_matches_independent_ode_integration(geometry, gamma):
    # both integrations run at relative tolerance <= 1e-12
    assert Sedov(1.0, 1.0, gamma, geometry).alpha == pytest.approx(
        alpha_from_similarity_odes(gamma, GEOMETRIES[geometry]), rel=1e-9)


def test_xi0_against_published_values_for_gamma_1_4():
    """Kamm & Timmes (LA-UR-07-2849, 2007), as the defaults of LANL ExactPack's Sedov solvers:
    E0 = 0.851072 (sphere), 0.311357 (cylinder), 0.0673185 (plane, dV = dr) put the shock at
    r_s = 1, 0.75, 0.5 at t = 1 with rho0 = 1, i.e. alpha = E0/r_s^(j+2).

    Spherical: equal to the 6 printed digits. The cylindrical and planar defaults deviate from the
    exact alpha by 3e-5 and 4e-4 (alpha above agrees with an independent ODE integration to 1e-9);
    the literature spreads as much (seed 002 Eq. 38: planar xi0 = 1.22904, ExactPack 1.22911),
    so there xi0 is checked to 2e-4.
    """
    sphere = Sedov(1.0, 1.0, 1.4, "spherical")
    assert abs(sphere.alpha - 0.851072) <= 5e-7
    assert sphere.xi0 == pytest.approx(1.033, abs=5e-4)
    assert Sedov(1.0, 1.0, 1.4, "cylindrical").xi0 == pytest.approx((0.311357 / 0.75**4) ** -0.25, rel=2e-4)
    planar = Sedov(1.0, 1.0, 1.4, "planar")
    assert planar.xi0 == pytest.approx((0.0673185 / 0.5**3) ** (-1 / 3), rel=2e-4)
    assert planar.xi0 == pytest.approx(1.22904, rel=2e-4)


# Sedov (1959) similarity tables as printed in Kamm (LA-UR-00-6055, 2000) Tables 1-3 (rows away
# from the shock and centre): lambda, f = u/u2, g = rho/rho2, h = p/p2 for gamma = 1.4.
SEDOV_TABLES = {
    "spherical": [(0.9080, 0.8335, 0.2275, 0.5238), (0.7950, 0.6952, 0.0620, 0.4021),
                  (0.5794, 0.4971, 0.0052, 0.3672), (0.2000, 0.1714, 0.0000, 0.3655)],
    "cylindrical": [(0.9096, 0.8514, 0.3450, 0.5982), (0.7242, 0.6327, 0.0718, 0.4074),
                    (0.5180, 0.4448, 0.0123, 0.3760), (0.2000, 0.1714, 0.0001, 0.3729)],
    "planar": [(0.8050, 0.7390, 0.3020, 0.5458), (0.6553, 0.5780, 0.1453, 0.4437),
               (0.4161, 0.3580, 0.0415, 0.3964), (0.1040, 0.0891, 0.0013, 0.3900)],
}


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_profiles_against_sedov_tables(geometry):
    blast = Sedov(1.0, 1.0, 1.4, geometry)
    half = 5e-5  # every entry, lambda included, is printed to 4 decimals
    for lam, *printed in SEDOV_TABLES[geometry]:
        values = np.array(blast.self_similar(lam))
        slope = (np.array(blast.self_similar(lam + half)) - np.array(blast.self_similar(lam - half))) / (2 * half)
        assert np.all(np.abs(values - printed) <= half + half * np.abs(slope)), (lam, values, printed)


def test_energy_and_mass_integrals_of_the_profile(blast):
    j = blast.dimension
    t = blast.time_at_front(3.0)
    r_s = blast.front_position(t)  # the grid ends exactly on the front (r/r_s = 1 is inside)
    r = np.linspace(0.0, r_s, 400001)
    rho, u, p = blast(r, t)
    weight = MEASURE[j] * r ** (j - 1)
    energy = np.trapezoid((0.5 * rho * u**2 + p / (blast.gamma - 1.0)) * weight, r)
    assert energy == pytest.approx(blast.energy, rel=1e-8)  # trapezoid rule, h = r_s/4e5: O(h^2) ~ 1e-10
    assert np.trapezoid(rho * weight, r) == pytest.approx(1.225 * MEASURE[j] * r_s**j / j, rel=1e-8)  # swept mass


def test_front_law_and_rankine_hugoniot(blast):
    j, t = blast.dimension, 2.5e-3
    r_s = blast.front_position(t)
    assert r_s == pytest.approx(blast.xi0 * (blast.energy * t**2 / blast.rho0) ** (1 / (j + 2)), rel=1e-14)
    assert blast.time_at_front(r_s) == pytest.approx(t, rel=1e-13)
    shock_speed = 2.0 / (j + 2.0) * r_s / t
    rho, u, p = blast(np.array([r_s * (1 - 1e-12), r_s * (1 + 1e-12)]), t)
    assert rho[0] == pytest.approx(1.225 * 6.0, rel=1e-6)
    assert u[0] == pytest.approx(2 * shock_speed / 2.4, rel=1e-6)
    assert p[0] == pytest.approx(2 * 1.225 * shock_speed**2 / 2.4, rel=1e-6)
    assert (rho[1], u[1], p[1]) == (1.225, 0.0, 0.0)


def test_euler_equations_residual_with_geometric_source(blast):
    """d_t U + d_r F + (j-1)/r S = 0, S = (rho u, rho u^2, (E + p) u)."""
    j, g, t, dt = blast.dimension, blast.gamma, 0.01, 1e-8
    r_s = blast.front_position(t)
    r = np.linspace(0.1 * r_s, 0.9 * r_s, 9)
    h = 1e-4 * r_s

    def cons(r, t):
        rho, u, p = blast(r, t)
        return np.array([rho, rho * u, 0.5 * rho * u * u + p / (g - 1)])

    def flux(r, t):
        rho, u, p = blast(r, t)
        energy = 0.5 * rho * u * u + p / (g - 1)
        return np.array([rho * u, rho * u * u + p, (energy + p) * u])

    def source(r, t):
        rho, u, p = blast(r, t)
        energy = 0.5 * rho * u * u + p / (g - 1)
        return (j - 1) / r * np.array([rho * u, rho * u * u, (energy + p) * u])

    dudt = (cons(r, t + dt) - cons(r, t - dt)) / (2 * dt)
    res = dudt + (flux(r + h, t) - flux(r - h, t)) / (2 * h) + source(r, t)
    assert np.max(np.abs(res) / np.abs(dudt)) < 1e-3  # finite-difference + table interpolation error


def test_planar_geometry_is_the_plate_solvers_planar_sedov():
    x = np.linspace(-30.0, 30.0, 2001)
    general, planar = Sedov(5e8, 1.225, 1.4, "planar"), PlanarSedov(5e8, 1.225, 1.4)
    assert general.alpha == planar.alpha
    for a, b in zip(general(x, 0.01), planar(x, 0.01)):
        np.testing.assert_array_equal(a, b)


def test_validation():
    with pytest.raises(ValueError, match="geometry"):
        Sedov(1.0, 1.0, 1.4, "conical")
    with pytest.raises(ValueError, match="energy must be > 0 J/m,"):
        Sedov(0.0, 1.0, 1.4, "cylindrical")
    with pytest.raises(ValueError, match="rho0"):
        Sedov(1.0, -1.0)
    with pytest.raises(ValueError, match="gamma"):
        Sedov(1.0, 1.0, 2.0)
