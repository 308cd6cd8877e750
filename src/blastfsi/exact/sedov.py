"""Sedov-Taylor (von Neumann-Sedov) point-explosion solution in planar,
cylindrical and spherical geometry (002 Sec. 3.4 uses the planar one).

Closed form of the self-similar solution in the parametrisation of
Kamm & Timmes (LA-UR-07-2849, 2007) for geometry j = 1, 2, 3, uniform ambient
density (w = 0), standard case (1 < gamma < 2). The parameter V runs from
V0 = 2/((j+2) gamma) (centre) to V2 = 4/((j+2)(gamma+1)) (shock), and
lambda = r/r_s, f = u/u_2, g = rho/rho_2, h = p/p_2 are explicit in V.

Energy: E = sigma_j int_0^r_s (rho u^2/2 + p/(gamma-1)) r^(j-1) dr = alpha rho0 r_s^(j+2)/t^2,
so r_s = xi0 (E t^2/rho0)^(1/(j+2)) with xi0 = alpha^(-1/(j+2)). sigma_3 = 4 pi
(E is the whole sphere's energy [J]), sigma_2 = 2 pi (E per unit length of the
axis [J/m]), sigma_1 = 1 (ERRATA 002-8: E per unit area on *one* side of the
symmetry plane [J/m^2]; the whole slab holds 2E). For gamma = 1.4,
alpha = 0.5387 (planar, one side), 0.9841 (cylindrical), 0.8511 (spherical).
Ambient pressure is neglected (strong-shock limit).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import integrate

GEOMETRIES = {"planar": 1, "cylindrical": 2, "spherical": 3}
_MEASURE = {1: 1.0, 2: 2.0 * math.pi, 3: 4.0 * math.pi}  # sigma_j: dV = sigma_j r^(j-1) dr
_ENERGY_UNIT = {1: "J/m^2", 2: "J/m", 3: "J"}
_CLUSTER = 6  # table/quadrature parameter s with V - V0 = (V2 - V0) s^6: resolves lambda ~ (V - V0)^(-alpha2)
_NEWTON_STEPS = 3  # from the table guess, 2 already reach rounding level


def _exponents(gamma: float, j: int):
    """Kamm & Timmes (2007) constants a..e and exponents alpha0..alpha5 for w = 0."""
    jw = j + 2.0  # j + 2 - w with w = 0
    a = jw * (gamma + 1.0) / 4.0
    b = (gamma + 1.0) / (gamma - 1.0)
    c = jw * gamma / 2.0
    d = jw * (gamma + 1.0) / (jw * (gamma + 1.0) - 2.0 * (2.0 + j * (gamma - 1.0)))
    e = (2.0 + j * (gamma - 1.0)) / 2.0
    alpha0 = 2.0 / jw
    alpha2 = -(gamma - 1.0) / (2.0 * (gamma - 1.0) + j)
    alpha1 = jw * gamma / (2.0 + j * (gamma - 1.0)) * (2.0 * j * (2.0 - gamma) / (gamma * jw**2) - alpha2)
    alpha3 = j / (2.0 * (gamma - 1.0) + j)
    alpha4 = jw * j / (j * (2.0 - gamma)) * alpha1
    alpha5 = -2.0 * j / (j * (2.0 - gamma))
    return a, b, c, d, e, alpha0, alpha1, alpha2, alpha3, alpha4, alpha5


def _volume_range(gamma: float, j: int):
    return 2.0 / ((j + 2.0) * gamma), 4.0 / ((j + 2.0) * (gamma + 1.0))


def _similarity_profiles(dV, gamma, j=1):
    """lambda = r/r_s and f = u/u_2, g = rho/rho_2, h = p/p_2 at parameter
    V = V0 + dV. Taking dV (not V) keeps x2 = b (c V - 1) = b c dV free of
    cancellation near the centre, where lambda ~ dV^(-alpha2)."""
    a, b, c, d, e, al0, al1, al2, al3, al4, al5 = _exponents(gamma, j)
    V = _volume_range(gamma, j)[0] + dV
    x1 = a * V
    x2 = b * c * dV
    x3 = d * (1.0 - e * V)
    x4 = b * (1.0 - c * V / gamma)
    lam = x1 ** (-al0) * x2 ** (-al2) * x3 ** (-al1)
    f = x1 * lam
    g = x2**al3 * x3**al4 * x4**al5
    h = x1 ** (al0 * j) * x3 ** (al4 - 2.0 * al1) * x4 ** (1.0 + al5)
    return lam, f, g, h


def _energy_constant(gamma: float, j: int) -> float:
    """alpha = E t^2/(rho0 r_s^(j+2)) = sigma_j (2/(j+2))^2 2/(gamma^2-1) int_0^1 (g f^2 + h) lambda^(j-1) dlambda.

    (rho u^2/2 + p/(gamma-1) = rho0 U^2 2/(gamma^2-1) (g f^2 + h) with U = dr_s/dt = 2 r_s/((j+2) t).)
    Integrated over s in (0, 1], V - V0 = (V2 - V0) s^6, with dlambda/ds from
    dln(lambda)/dV = -alpha0 a/x1 - alpha2/dV + alpha1 d e/x3 (adaptive quadrature, rel. tol. 1e-13).
    """
    a, _, _, d, e, al0, al1, al2, *_ = _exponents(gamma, j)
    v0, v2 = _volume_range(gamma, j)

    def integrand(s):
        dv = (v2 - v0) * s**_CLUSTER
        lam, f, g, h = _similarity_profiles(dv, gamma, j)
        v = v0 + dv
        dlam_ds = lam * ((-al0 / v + al1 * d * e / (d * (1.0 - e * v))) * _CLUSTER * (v2 - v0) * s ** (_CLUSTER - 1)
                         - al2 * _CLUSTER / s)
        return (g * f * f + h) * lam ** (j - 1) * dlam_ds

    value, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-13, limit=400)
    return _MEASURE[j] * (2.0 / (j + 2.0)) ** 2 * 2.0 / (gamma * gamma - 1.0) * value


@dataclass(frozen=True)
class Sedov:
    """Exact Sedov-Taylor blast wave: callable ``(r, t) -> (rho, u, p)``.

    Parameters: energy E (> 0; J for ``geometry="spherical"``, J/m per unit
    length for ``"cylindrical"``, J/m^2 on one side of the plane for
    ``"planar"``), ambient density rho0 [kg/m^3], gamma in (1, 2).
    """

    energy: float
    rho0: float
    gamma: float = 1.4
    geometry: str = "spherical"
    _alpha: float = field(init=False, repr=False, compare=False)
    _table: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        name = type(self).__name__
        if self.geometry not in GEOMETRIES:
            raise ValueError(f"{name}.geometry must be one of {sorted(GEOMETRIES)}, got {self.geometry!r}")
        j = GEOMETRIES[self.geometry]
        if not self.energy > 0:
            raise ValueError(f"{name}.energy must be > 0 {_ENERGY_UNIT[j]}, got {self.energy}")
        if not self.rho0 > 0:
            raise ValueError(f"{name}.rho0 must be > 0 kg/m^3, got {self.rho0}")
        if not 1.0 < self.gamma < 2.0:
            raise ValueError(f"{name}.gamma must lie in (1, 2), got {self.gamma}")
        v0, v2 = _volume_range(self.gamma, j)
        # Starting guesses for inverting lambda(V): parameter values clustered at the centre,
        # where lambda -> 0 as a power of (V - V0).
        dv = (v2 - v0) * np.linspace(0.0, 1.0, 2001)[1:] ** _CLUSTER
        lam = _similarity_profiles(dv, self.gamma, j)[0]
        object.__setattr__(self, "_table", (np.log(lam), np.log(dv)))
        object.__setattr__(self, "_alpha", _energy_constant(self.gamma, j))

    @property
    def dimension(self) -> int:
        """j = 1, 2, 3 for planar, cylindrical, spherical."""
        return GEOMETRIES[self.geometry]

    @property
    def alpha(self) -> float:
        """Energy constant: E = alpha rho0 r_s^(j+2) / t^2."""
        return self._alpha

    @property
    def xi0(self) -> float:
        """r_s = xi0 (E t^2/rho0)^(1/(j+2))."""
        return self._alpha ** (-1.0 / (self.dimension + 2.0))

    def front_position(self, t):
        j = self.dimension
        return (self.xi0 * (self.energy / self.rho0) ** (1.0 / (j + 2.0))
                * np.asarray(t, float) ** (2.0 / (j + 2.0)))

    def time_at_front(self, radius):
        """Time since the explosion at which the shock has reached ``radius``."""
        j = self.dimension
        scale = self.xi0 * (self.energy / self.rho0) ** (1.0 / (j + 2.0))
        return (np.asarray(radius, float) / scale) ** ((j + 2.0) / 2.0)

    def self_similar(self, lam):
        """f = u/u_2, g = rho/rho_2, h = p/p_2 at lambda = r/r_s (clipped to [0, 1]).

        Exact to rounding: y = ln(V - V0) solves ln lambda(y) = ln lam by Newton's method,
        d ln(lambda)/dy = (V - V0)(-alpha0/V + alpha1 d e/x3) - alpha2 > 0, started from a table
        of (ln lambda, y); ln lambda is nearly linear in y, so a few steps reach rounding level.
        """
        j, gamma = self.dimension, self.gamma
        a, b, c, d, e, al0, al1, al2, *_ = _exponents(gamma, j)
        v0, v2 = _volume_range(gamma, j)
        lam = np.clip(np.asarray(lam, dtype=float), 0.0, 1.0)
        centre = lam == 0.0
        target = np.log(np.where(centre, 1.0, lam))
        log_lam_table, log_dv_table = self._table
        y = np.interp(target, log_lam_table, log_dv_table)
        for _ in range(_NEWTON_STEPS):
            dv = np.exp(y)
            v = v0 + dv
            x3 = d * (1.0 - e * v)
            log_lam = -al0 * np.log(a * v) - al2 * (np.log(b * c) + y) - al1 * np.log(x3)  # no underflow
            slope = dv * (-al0 / v + al1 * d * e / x3) - al2
            y = np.minimum(y - (log_lam - target) / slope, np.log(v2 - v0))
        _, f, g, h = _similarity_profiles(np.where(centre, 0.0, np.exp(y)), gamma, j)
        return f, g, h

    def __call__(self, r, t):
        """Density, velocity and pressure at distance r from the centre (axis, plane) at time t > 0."""
        r = np.abs(np.asarray(r, dtype=float))
        rs = self.front_position(t)
        shock_speed = 2.0 / (self.dimension + 2.0) * rs / t
        g = self.gamma
        rho2 = self.rho0 * (g + 1.0) / (g - 1.0)
        u2 = 2.0 / (g + 1.0) * shock_speed
        p2 = 2.0 / (g + 1.0) * self.rho0 * shock_speed**2
        xi = r / rs
        inside = xi <= 1.0
        f, gg, h = self.self_similar(xi)
        rho = np.where(inside, rho2 * gg, self.rho0)
        u = np.where(inside, u2 * f, 0.0)
        p = np.where(inside, p2 * h, 0.0)
        return rho, u, p


@dataclass(frozen=True)
class PlanarSedov(Sedov):
    """Exact planar blast wave (002 Sec. 3.4): callable ``(x, t) -> (rho, u, p)``.

    Parameters: energy E0 [J/m^2, one side], ambient density rho0 [kg/m^3], gamma.
    r_s = (E0/(alpha rho0))^(1/3) t^(2/3); for gamma = 1.4, alpha = 0.5387 so
    r_s = 1.229 (E0/rho0)^(1/3) t^(2/3), the paper's Eq. (38) (ERRATA 002-8).
    """

    geometry: str = field(default="planar", init=False)
