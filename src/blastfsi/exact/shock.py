"""Normal-shock relations for a calorically perfect gas (general gamma) and the
free-standing-plate theory of seed 002 (Kambouchev, Noels & Radovitzky).

Every pressure called ``overpressure`` is measured above the ambient p0
(ERRATA 002-7). Functions accept NumPy scalars or arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _check_gas(p0, rho0, gamma):
    if np.any(np.asarray(p0) <= 0):
        raise ValueError(f"ambient pressure p0 must be > 0 Pa, got {p0}")
    if np.any(np.asarray(rho0) <= 0):
        raise ValueError(f"ambient density rho0 must be > 0 kg/m^3, got {rho0}")
    if not gamma > 1:
        raise ValueError(f"gamma must be > 1, got {gamma}")


@dataclass(frozen=True)
class ShockState:
    """State behind a shock moving into gas at rest (p0, rho0)."""

    overpressure: np.ndarray  # p_s [Pa]
    density: np.ndarray  # rho_s [kg/m^3]
    particle_velocity: np.ndarray  # u_s [m/s]
    shock_speed: np.ndarray  # U_s [m/s]
    sound_speed: np.ndarray  # a_s [m/s]


def incident_shock(overpressure, p0, rho0, gamma=1.4) -> ShockState:
    """Rankine-Hugoniot state behind a shock of given overpressure.

    For gamma = 1.4 these reduce to ERRATA 002-4 (corrected Eq. 27) and Eq. (31):
    U_s = a0 sqrt(1 + (gamma+1)/(2 gamma) p_s/p0),
    rho_s/rho0 = ((gamma+1) P + gamma-1) / ((gamma-1) P + gamma+1),  P = 1 + p_s/p0,
    u_s = U_s (1 - rho0/rho_s)   (mass conservation across the shock).
    """
    _check_gas(p0, rho0, gamma)
    ps = np.asarray(overpressure, dtype=float)
    if np.any(ps < 0):
        raise ValueError(f"shock overpressure must be >= 0 Pa, got {overpressure}")
    a0 = np.sqrt(gamma * p0 / rho0)
    ratio = 1.0 + ps / p0
    shock_speed = a0 * np.sqrt(1.0 + (gamma + 1.0) / (2.0 * gamma) * ps / p0)
    density = rho0 * ((gamma + 1.0) * ratio + gamma - 1.0) / ((gamma - 1.0) * ratio + gamma + 1.0)
    u = shock_speed * (1.0 - rho0 / density)
    a_s = np.sqrt(gamma * (p0 + ps) / density)
    return ShockState(ps, density, u, shock_speed, a_s)


def reflection_coefficient(overpressure, p0, gamma=1.4):
    """C_R = p_r / p_s for normal reflection on a rigid wall (002 Eqs. 24-25).

    General gamma: p_r,abs / p_1 = ((3 gamma - 1) P - (gamma - 1)) / ((gamma - 1) P + gamma + 1)
    with P = p_1/p0; for gamma = 1.4 this is 2 (7 p0 + 4 p_s) / (7 p0 + p_s).
    """
    ps = np.asarray(overpressure, dtype=float)
    if np.any(ps <= 0):
        raise ValueError(f"overpressure must be > 0 Pa for a reflection coefficient, got {overpressure}")
    ratio = 1.0 + ps / p0
    p1 = ratio * p0
    pr_abs = p1 * ((3.0 * gamma - 1.0) * ratio - (gamma - 1.0)) / ((gamma - 1.0) * ratio + gamma + 1.0)
    return (pr_abs - p0) / ps


def free_surface_velocity(overpressure, p0, rho0, gamma=1.4):
    """Velocity of the gas after the shocked state (p0 + p_s, u_s) expands
    isentropically back to p0 through a left-facing rarefaction:
    u_fs = u_s + 2 a_s/(gamma-1) [1 - (p0/(p0+p_s))^((gamma-1)/(2 gamma))].

    This is the velocity a vanishingly light free-standing plate acquires
    (the light-plate limit of 002 Sec. 3.2).
    """
    s = incident_shock(overpressure, p0, rho0, gamma)
    p1 = p0 + s.overpressure
    expo = (gamma - 1.0) / (2.0 * gamma)
    return s.particle_velocity + 2.0 * s.sound_speed / (gamma - 1.0) * (1.0 - (p0 / p1) ** expo)


def beta_s(overpressure, duration, areal_mass, p0, rho0, gamma=1.4):
    """Compressible FSI parameter, 002 Eq. (28): beta_s = rho_s U_s t_i / (rho_p h_p)."""
    if np.any(np.asarray(areal_mass) <= 0):
        raise ValueError(f"plate areal mass must be > 0 kg/m^2, got {areal_mass}")
    s = incident_shock(overpressure, p0, rho0, gamma)
    return s.density * s.shock_speed * duration / areal_mass


def areal_mass_from_beta_s(beta, overpressure, duration, p0, rho0, gamma=1.4):
    """Inverse of :func:`beta_s`."""
    if np.any(np.asarray(beta) <= 0):
        raise ValueError(f"beta_s must be > 0, got {beta}")
    s = incident_shock(overpressure, p0, rho0, gamma)
    return s.density * s.shock_speed * duration / beta


def f_R_eq30(overpressure, p0):
    """002 Eq. (30) as printed (gamma = 1.4 only).

    It tends to 1 in the acoustic limit and agrees with :func:`f_R` to 0.03 %
    for p_s/p0 <= 1, but falls below it for stronger shocks (8 % low at
    p_s/p0 = 4.49, 34 % at 100): the extracted formula does not reproduce the
    light-plate limit it is meant to encode, see docs/theory/lagrangian1d.md.
    """
    x = np.asarray(overpressure, dtype=float) / p0
    cr = reflection_coefficient(overpressure, p0, 1.4)
    return (6 * x + 7) * np.sqrt(((6 + cr) * x + 7) / ((x + 7) * ((1 + 6 * cr) * x + 7) * (cr * x + 7)))


def f_R(overpressure, p0, rho0, gamma=1.4):
    """Light-plate compressibility factor derived from shock theory.

    In the light-plate limit the plate momentum is m_p u_fs, so 002 Eq. (29)'s
    asymptote I_p/(C_R I_i) -> f_R/beta_s fixes
    f_R = rho_s U_s u_fs / (C_R p_s)   (-> 1 in the acoustic limit).
    """
    s = incident_shock(overpressure, p0, rho0, gamma)
    cr = reflection_coefficient(overpressure, p0, gamma)
    return s.density * s.shock_speed * free_surface_velocity(overpressure, p0, rho0, gamma) / (cr * s.overpressure)


def impulse_ratio_uniform(beta, fR):
    """002 Eq. (29): I_p / (C_R I_i) = (1 - exp(-beta_s/f_R)) / (beta_s/f_R)."""
    z = np.asarray(beta, dtype=float) / fR
    return np.where(z > 1e-8, -np.expm1(-z) / np.where(z > 1e-8, z, 1.0), 1.0 - 0.5 * z)


def impulse_ratio_exponential(beta, gamma_R, C_R, fR):
    """002 Eq. (32): I_p/I_i = gamma_R (C_R f_R/gamma_R)^(beta/(1+beta)) beta^(beta/(1-beta)).

    gamma_R is the rigid-wall impulse reflection coefficient of the exponential
    pulse (defined in the paper's ref. [12], not in the seed): it must be given.
    Limits checked in tests: beta -> 0 gives gamma_R (rigid wall); beta -> inf
    gives C_R f_R / beta (Eq. 29's light-plate limit); the acoustic case
    (gamma_R = C_R = 2, f_R = 1) gives Taylor's 2 beta^(beta/(1-beta)).
    """
    b = np.asarray(beta, dtype=float)
    if np.any(b <= 0):
        raise ValueError(f"beta_s must be > 0, got {beta}")
    near_one = np.abs(b - 1.0) < 1e-9
    safe = np.where(near_one, 2.0, b)
    taylor = np.where(near_one, np.exp(-1.0), safe ** (safe / (1.0 - safe)))
    return gamma_R * (C_R * fR / gamma_R) ** (b / (1.0 + b)) * taylor


def face_overpressure(plate_velocity, overpressure, p0, rho0, gamma=1.4):
    """Overpressure on a plate moving at ``plate_velocity`` (>= 0, away from the
    blast) and struck by the uniform shocked state (p0 + p_s, rho_s, u_s).

    Solves the Riemann problem for the left-facing wave: a shock (Hugoniot) when
    the plate is slower than u_s, a centred rarefaction (isentrope) when faster:
    v = u_s - f(p), f the standard wave function. At v = 0 this is C_R p_s
    (Eq. 25); at v = u_fs (:func:`free_surface_velocity`) it is 0.
    """
    from scipy.optimize import brentq

    s = incident_shock(overpressure, p0, rho0, gamma)
    p1 = p0 + float(s.overpressure)
    a_coef, b_coef = 2.0 / ((gamma + 1.0) * s.density), (gamma - 1.0) / (gamma + 1.0) * p1

    def wave(p):
        if p > p1:
            return (p - p1) * np.sqrt(a_coef / (p + b_coef))
        return 2.0 * s.sound_speed / (gamma - 1.0) * ((p / p1) ** ((gamma - 1.0) / (2.0 * gamma)) - 1.0)

    escape = s.particle_velocity + 2.0 * s.sound_speed / (gamma - 1.0)  # expansion to vacuum
    if plate_velocity >= escape:
        return -p0
    p = brentq(lambda q: s.particle_velocity - wave(q) - plate_velocity, 0.0, 1e3 * p1, xtol=1e-13 * p1)
    return p - p0


def quasi_steady_plate(overpressure, duration, areal_mass, p0, rho0, gamma=1.4, back_pressure=None):
    """Plate velocity after ``duration`` from m dv/dt = face_overpressure(v) + p0 - p_back.

    A reference for intermediate plate masses, where Eq. (29) is only an
    interpolation: it assumes the face pressure follows the plate velocity
    instantly (the waves the plate sends back are not re-reflected onto it).
    Exact in the acoustic limit (it then reproduces Eq. 29) and for heavy
    (v -> 0) and light (v -> u_fs) plates.
    """
    from scipy.integrate import solve_ivp

    back = p0 if back_pressure is None else back_pressure

    def rhs(_, y):
        return [(face_overpressure(y[0], overpressure, p0, rho0, gamma) + p0 - back) / areal_mass]

    sol = solve_ivp(rhs, (0.0, duration), [0.0], method="LSODA", rtol=1e-10, atol=1e-10)  # stiff for light plates
    return float(sol.y[0, -1])
