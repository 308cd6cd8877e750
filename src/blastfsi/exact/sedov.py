"""Planar von Neumann-Sedov point-explosion solution (002 Sec. 3.4).

Closed form of the self-similar solution in the parametrisation of
Kamm & Timmes (LA-UR-07-2849, 2007) for geometry j = 1, uniform ambient
density (w = 0), standard case (1 < gamma < 2). The parameter V runs from
V0 = 2/(3 gamma) (centre) to V2 = 4/(3 (gamma+1)) (shock).

Energy convention (ERRATA 002-8): E0 is the energy per unit area on *one* side
of the symmetry plane, r_s = (E0/(alpha rho0))^(1/3) t^(2/3); for gamma = 1.4,
alpha = 0.5387 so r_s = 1.22904 (E0/rho0)^(1/3) t^(2/3), the paper's Eq. (38).
Ambient pressure is neglected (strong-shock limit).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _exponents(gamma: float):
    j = 1.0
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


def _similarity_profiles(dV, gamma):
    """lambda = r/r_s and f = u/u_2, g = rho/rho_2, h = p/p_2 at parameter
    V = V0 + dV. Taking dV (not V) keeps x2 = b (c V - 1) = b c dV free of
    cancellation near the centre, where lambda ~ dV^(-alpha2)."""
    a, b, c, d, e, al0, al1, al2, al3, al4, al5 = _exponents(gamma)
    V = 2.0 / (3.0 * gamma) + dV
    x1 = a * V
    x2 = b * c * dV
    x3 = d * (1.0 - e * V)
    x4 = b * (1.0 - c * V / gamma)
    lam = x1 ** (-al0) * x2 ** (-al2) * x3 ** (-al1)
    f = x1 * lam
    g = x2**al3 * x3**al4 * x4**al5
    h = x1**al0 * x3 ** (al4 - 2.0 * al1) * x4 ** (1.0 + al5)  # x1^(alpha0 j), j = 1
    return lam, f, g, h


@dataclass(frozen=True)
class PlanarSedov:
    """Exact planar blast wave: callable ``(x, t) -> (rho, u, p)``.

    Parameters: energy E0 [J/m^2, one side], ambient density rho0 [kg/m^3], gamma.
    """

    energy: float
    rho0: float
    gamma: float = 1.4
    _table: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not self.energy > 0:
            raise ValueError(f"PlanarSedov.energy must be > 0 J/m^2, got {self.energy}")
        if not self.rho0 > 0:
            raise ValueError(f"PlanarSedov.rho0 must be > 0 kg/m^3, got {self.rho0}")
        if not 1.0 < self.gamma < 2.0:
            raise ValueError(f"PlanarSedov.gamma must lie in (1, 2), got {self.gamma}")
        g = self.gamma
        v0, v2 = 2.0 / (3.0 * g), 4.0 / (3.0 * (g + 1.0))
        # Cluster parameter values near the centre, where lambda -> 0 as a power of (V - V0).
        s = np.linspace(0.0, 1.0, 20001)
        object.__setattr__(self, "_table", _similarity_profiles((v2 - v0) * s**6, g))

    @property
    def alpha(self) -> float:
        """Energy constant: E0 = alpha rho0 r_s^3 / t^2 (one side of the plane)."""
        return _alpha(self.gamma)

    def front_position(self, t):
        return (self.energy / (self.alpha * self.rho0)) ** (1.0 / 3.0) * np.asarray(t, float) ** (2.0 / 3.0)

    def time_at_front(self, radius):
        """Time since the explosion at which the shock has reached ``radius``."""
        return (np.asarray(radius, float) / (self.energy / (self.alpha * self.rho0)) ** (1.0 / 3.0)) ** 1.5

    def __call__(self, x, t):
        """Density, velocity and pressure at distance x >= 0 from the plane at time t > 0."""
        x = np.abs(np.asarray(x, dtype=float))
        rs = self.front_position(t)
        shock_speed = 2.0 / 3.0 * rs / t
        g = self.gamma
        rho2 = self.rho0 * (g + 1.0) / (g - 1.0)
        u2 = 2.0 / (g + 1.0) * shock_speed
        p2 = 2.0 / (g + 1.0) * self.rho0 * shock_speed**2
        lam, f, gg, h = self._table
        xi = x / rs
        inside = xi <= 1.0
        rho = np.where(inside, rho2 * np.interp(xi, lam, gg), self.rho0)
        u = np.where(inside, u2 * np.interp(xi, lam, f), 0.0)
        p = np.where(inside, p2 * np.interp(xi, lam, h), 0.0)
        return rho, u, p


def _alpha(gamma: float) -> float:
    """alpha = E0 t^2/(rho0 r_s^3), the energy integral over 0 <= lambda <= 1.

    With r_s = K t^(2/3): U = 2/3 r_s/t, u2 = 2U/(gamma+1), rho2 = rho0 (gamma+1)/(gamma-1),
    p2 = 2 rho0 U^2/(gamma+1); integrated by the trapezoidal rule on a parameter
    grid clustered at the centre (converged to < 1e-7 relative).
    """
    v0, v2 = 2.0 / (3.0 * gamma), 4.0 / (3.0 * (gamma + 1.0))
    s = np.linspace(0.0, 1.0, 400001)
    lam, f, g, h = _similarity_profiles((v2 - v0) * s**6, gamma)
    kinetic = 0.5 * (gamma + 1.0) / (gamma - 1.0) * g * (2.0 / (gamma + 1.0)) ** 2 * f**2
    internal = 2.0 / (gamma + 1.0) * h / (gamma - 1.0)
    return float(np.trapezoid(kinetic + internal, lam)) * (2.0 / 3.0) ** 2
