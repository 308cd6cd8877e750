"""Chapman–Jouguet (CJ) state of a JWL detonation-products EOS.

The unreacted explosive is at rest at (rho0, p0, specific energy 0); the
products obey 000 Eq. (54) (JWL, :mod:`blastfsi.eos.jwl`) with E the *current*
internal energy per unit initial volume (ERRATA 000-6), whose value at V = 1
is the detonation energy E0. A steady detonation takes the explosive to a
point of the products' Hugoniot

    e - E0/rho0 = (p + p0)/2 (v0 - v)                      (energy jump)

along the Rayleigh line from the unreacted state

    p - p0 = rho0^2 D^2 (v0 - v)                          (mass + momentum),

and the CJ point is where the Rayleigh line is tangent to the Hugoniot: the
smallest D that reaches it. There D = u + c (sonic in the products' frame).

With the relative volume V = v/v0 = rho0/rho and p = f(rho) + w rho e, the
Hugoniot pressure is explicit:

    p_H(V) = [f + (w/V)(E0 + p0 (1 - V)/2)] / [1 - (w/2)(1/V - 1)],

D^2(V) = (p_H - p0) / (rho0 (1 - V)), and tangency is
G(V) = p_H'(V) (1 - V) + p_H(V) - p0 = 0, solved here by bracketing the minimum
of D^2 on a grid and refining the root of G with Brent's method.
Host-side reference (NumPy/SciPy), not a jitted kernel.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from blastfsi.eos import jwl
from blastfsi.eos.jwl import JWLParams


class CJState(NamedTuple):
    pressure: float  # p_CJ [Pa]
    detonation_velocity: float  # D_CJ [m/s]
    density: float  # rho_CJ [kg/m^3]
    particle_velocity: float  # u_CJ [m/s] (lab frame, explosive at rest)
    sound_speed: float  # c_CJ [m/s] (isentropic, JWL)
    specific_energy: float  # e_CJ [J/kg], JWL energy of the products
    relative_volume: float  # V_CJ = rho0 / rho_CJ [-]


def _check(params: JWLParams, E0: float, p0: float):
    for name in ("A", "B"):
        if not getattr(params, name) >= 0.0:
            raise ValueError(f"JWL {name} must be >= 0 Pa, got {getattr(params, name)}")
    for name in ("R1", "R2", "omega", "rho0"):
        if not getattr(params, name) > 0.0:
            raise ValueError(f"JWL {name} must be > 0, got {getattr(params, name)}")
    if not E0 > 0.0:
        raise ValueError(f"detonation energy E0 must be > 0 J/m^3 (per unit initial volume), got {E0}")
    if not p0 >= 0.0:
        raise ValueError(f"initial pressure p0 must be >= 0 Pa, got {p0}")


def _minimum_relative_volume(params: JWLParams) -> float:
    """The Hugoniot pressure diverges where 1 - (w/2)(1/V - 1) = 0, V = w/(2 + w)."""
    return params.omega / (2.0 + params.omega)


def products_hugoniot_pressure(relative_volume, params: JWLParams, E0: float, p0: float = 0.0):
    """p_H(V) [Pa] on the products' Hugoniot from (rho0, p0, e = 0); 000 Eq. (54), ERRATA 000-6."""
    v = np.asarray(relative_volume, dtype=float)
    f = jwl.reference_pressure(params.rho0 / v, params)
    w = params.omega
    return (f + (w / v) * (E0 + 0.5 * p0 * (1.0 - v))) / (1.0 - 0.5 * w * (1.0 / v - 1.0))


def _hugoniot_slope(v, params: JWLParams, E0: float, p0: float):
    """dp_H/dV (quotient rule on the explicit p_H; df/dV = df/drho * (-rho0/V^2))."""
    w = params.omega
    numerator = jwl.reference_pressure(params.rho0 / v, params) + (w / v) * (E0 + 0.5 * p0 * (1.0 - v))
    denominator = 1.0 - 0.5 * w * (1.0 / v - 1.0)
    dnum = (jwl.reference_pressure_derivative(params.rho0 / v, params) * (-params.rho0 / v**2)
            - w * (E0 + 0.5 * p0) / v**2)
    dden = 0.5 * w / v**2
    return (dnum * denominator - numerator * dden) / denominator**2


def _rayleigh_d2(v, params: JWLParams, E0: float, p0: float):
    """D^2 of the Rayleigh line through (V, p_H(V)): (p_H - p0) / (rho0 (1 - V))."""
    return (products_hugoniot_pressure(v, params, E0, p0) - p0) / (params.rho0 * (1.0 - v))


def chapman_jouguet(params: JWLParams, E0: float, p0: float = 0.0) -> CJState:
    """CJ state of the JWL products `params` (rho0 = params.rho0) with detonation
    energy E0 [J/m^3 of unreacted explosive], from the explosive at rest at p0 [Pa]."""
    _check(params, E0, p0)
    v_lo = _minimum_relative_volume(params)
    grid = v_lo + (1.0 - v_lo) * np.linspace(1e-6, 1.0 - 1e-6, 4001)
    d2 = _rayleigh_d2(grid, params, E0, p0)
    k = int(np.argmin(d2))
    if k == 0 or k == grid.size - 1:
        raise ValueError("no Rayleigh-line tangency found: the products' Hugoniot has no CJ point "
                         f"for this JWL set (minimum of D^2 at the end of {v_lo:.4g} < V < 1)")

    def tangency(v):  # G(V) = p_H'(V)(1 - V) + p_H - p0
        return (_hugoniot_slope(v, params, E0, p0) * (1.0 - v)
                + products_hugoniot_pressure(v, params, E0, p0) - p0)

    v_cj = brentq(tangency, grid[k - 1], grid[k + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    p_cj = float(products_hugoniot_pressure(v_cj, params, E0, p0))
    d_cj = float(np.sqrt(_rayleigh_d2(v_cj, params, E0, p0)))
    rho_cj = params.rho0 / v_cj
    return CJState(
        pressure=p_cj,
        detonation_velocity=d_cj,
        density=float(rho_cj),
        particle_velocity=d_cj * (1.0 - v_cj),  # mass: rho0 D = rho (D - u)
        sound_speed=float(np.sqrt(jwl.sound_speed_squared(rho_cj, p_cj, params))),
        specific_energy=float(jwl.energy(rho_cj, p_cj, params)),
        relative_volume=float(v_cj),
    )
