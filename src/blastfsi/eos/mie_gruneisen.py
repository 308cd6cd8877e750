"""Mie-Grueneisen EOS with a shock-Hugoniot reference, 000 Eqs. (65)-(66).

    p = p_H(mu) (1 - Gamma mu / 2) + Gamma rho e,          mu = rho/rho0 - 1,
    p_H = rho0 C0^2 [mu + (2S - 1) mu^2 + (S - 1)(3S - 1) mu^3]   (mu > 0),
    p_H = rho0 C0^2 mu                                          (mu <= 0),

with e the specific internal energy [J/kg] (the "E" of Eq. 65 must be per unit
mass for rho E to be a pressure). Eq. (65) is p = p_H + Gamma rho (e - e_H) with
the Rankine-Hugoniot energy e_H = p_H mu / (2 rho0 (1 + mu)) and a constant
Gamma; we allow the first-order volume correction Gamma = Gamma0 + a mu
(a = 0 is Eq. 65 as printed). The cubic p_H of Eq. (66) is the third-order
expansion in mu of the linear U_s-u_p Hugoniot rho0 C0^2 mu (1 + mu)/(1 - (S - 1) mu)^2.

Like :mod:`blastfsi.eos.jwl` the EOS has the form p = f(rho) + g(rho) e with
g = Gamma rho, which the implicit energy update uses. Pure functions of NumPy
or JAX arrays; parameters may be floats or traced arrays.
"""
from __future__ import annotations

from typing import NamedTuple


class MieGruneisenParams(NamedTuple):
    rho0: float  # reference (stress-free) density [kg/m^3]
    C0: float  # bulk sound speed, intercept of U_s = C0 + S u_p [m/s]
    S: float  # slope of U_s = C0 + S u_p [-]
    gamma0: float  # Grueneisen coefficient at rho0 [-]
    a: float  # first-order volume correction, Gamma = gamma0 + a mu [-]


def _where(cond, x, y):
    return cond * x + (1 - cond) * y


def compression(rho, p: MieGruneisenParams):
    """mu = rho/rho0 - 1."""
    return rho / p.rho0 - 1.0


def hugoniot_pressure(mu, p: MieGruneisenParams):
    """000 Eq. (66)."""
    k = p.rho0 * p.C0 ** 2
    poly = mu + (2.0 * p.S - 1.0) * mu ** 2 + (p.S - 1.0) * (3.0 * p.S - 1.0) * mu ** 3
    return k * _where(mu > 0.0, poly, mu)


def hugoniot_pressure_derivative(mu, p: MieGruneisenParams):
    """dp_H/dmu."""
    k = p.rho0 * p.C0 ** 2
    dpoly = 1.0 + 2.0 * (2.0 * p.S - 1.0) * mu + 3.0 * (p.S - 1.0) * (3.0 * p.S - 1.0) * mu ** 2
    return k * _where(mu > 0.0, dpoly, 1.0)


def gruneisen(mu, p: MieGruneisenParams):
    return p.gamma0 + p.a * mu


def reference_pressure(rho, p: MieGruneisenParams):
    """f(rho) = p_H (1 - Gamma mu / 2), the e = 0 part of 000 Eq. (65)."""
    mu = compression(rho, p)
    return hugoniot_pressure(mu, p) * (1.0 - 0.5 * gruneisen(mu, p) * mu)


def energy_coefficient(rho, p: MieGruneisenParams):
    """g(rho) = dp/de at constant rho = Gamma rho."""
    return gruneisen(compression(rho, p), p) * rho


def pressure(rho, e, p: MieGruneisenParams):
    """000 Eq. (65)."""
    return reference_pressure(rho, p) + energy_coefficient(rho, p) * e


def energy(rho, pres, p: MieGruneisenParams):
    """Specific internal energy e with p(rho, e) = pres."""
    return (pres - reference_pressure(rho, p)) / energy_coefficient(rho, p)


def sound_speed_squared(rho, e, p: MieGruneisenParams):
    """c^2 = dp/drho|_e + (p/rho^2) dp/de|_rho (isentropic bulk sound speed squared)."""
    mu = compression(rho, p)
    gam = gruneisen(mu, p)
    ph = hugoniot_pressure(mu, p)
    dfdrho = (hugoniot_pressure_derivative(mu, p) * (1.0 - 0.5 * gam * mu)
              - 0.5 * ph * (p.a * mu + gam)) / p.rho0
    dgdrho = gam + rho * p.a / p.rho0
    pres = pressure(rho, e, p)
    return dfdrho + dgdrho * e + pres * gam / rho


def sound_speed(rho, e, p: MieGruneisenParams):
    return sound_speed_squared(rho, e, p) ** 0.5
