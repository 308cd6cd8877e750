"""Jones-Wilkins-Lee (JWL) detonation products, 000 Eq. (54) with ERRATA 000-6.

    p = A (1 - w/(R1 V)) exp(-R1 V) + B (1 - w/(R2 V)) exp(-R2 V) + w E / V

with V = rho0/rho the relative volume and E the *current* internal energy per
unit initial volume, E = rho0 e, so w E / V = w rho e. JWL is therefore of
Mie-Grueneisen form

    p = f(rho) + Gamma rho e,   Gamma = w,
    f(rho) = A (1 - w rho/(R1 rho0)) exp(-R1 rho0/rho) + B (1 - w rho/(R2 rho0)) exp(-R2 rho0/rho),

and an ideal gas is the special case A = B = 0, w = gamma - 1 (see
:func:`ideal_gas_params`). Every gas in the Eulerian solver is described by one
:class:`JWLParams` row, so the kernels evaluate one formula without branching
on the material.

All functions are pure and work on NumPy or JAX arrays; the parameters may be
Python floats or (traced) arrays.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


class JWLParams(NamedTuple):
    A: float  # [Pa]
    B: float  # [Pa]
    R1: float  # [-]
    R2: float  # [-]
    omega: float  # Grueneisen coefficient w [-]
    rho0: float  # reference (unreacted explosive) density [kg/m^3]


def ideal_gas_params(gamma: float) -> JWLParams:
    """An ideal gas p = (gamma - 1) rho e as a JWL row (A = B = 0, w = gamma - 1)."""
    return JWLParams(0.0, 0.0, 1.0, 1.0, gamma - 1.0, 1.0)


def _exp(x):
    """exp in the argument's own array library (NumPy on the host, jax.numpy when traced)."""
    return x.__array_namespace__().exp(x) if hasattr(x, "__array_namespace__") else np.exp(x)


def reference_pressure(rho, p: JWLParams):
    """f(rho), the cold (e = 0) part of the pressure [Pa]."""
    v = p.rho0 / rho  # relative volume V
    return (p.A * (1.0 - p.omega / (p.R1 * v)) * _exp(-p.R1 * v)
            + p.B * (1.0 - p.omega / (p.R2 * v)) * _exp(-p.R2 * v))


def reference_pressure_derivative(rho, p: JWLParams):
    """df/drho [Pa m^3/kg] (d/drho of each term of f)."""
    v = p.rho0 / rho
    out = 0.0
    for a, r in ((p.A, p.R1), (p.B, p.R2)):
        ex = _exp(-r * v)
        # f_i = a (1 - w/(r V)) exp(-r V), dV/drho = -V/rho
        dfdv = a * ex * (p.omega / (r * v * v) - r * (1.0 - p.omega / (r * v)))
        out = out + dfdv * (-v / rho)
    return out


def pressure(rho, e, p: JWLParams):
    """000 Eq. (54): p = f(rho) + w rho e."""
    return reference_pressure(rho, p) + p.omega * rho * e


def energy(rho, pres, p: JWLParams):
    """Specific internal energy e with p(rho, e) = pres."""
    return (pres - reference_pressure(rho, p)) / (p.omega * rho)


def sound_speed_squared(rho, pres, p: JWLParams):
    """c^2 = dp/drho|_s = f'(rho) + ((1 + w) p - f(rho)) / rho.

    From dp/drho|_s = dp/drho|_e + (p/rho^2) dp/de|_rho with dp/drho|_e = f' + w e
    and dp/de|_rho = w rho; w e = (p - f)/rho eliminates e.
    """
    return reference_pressure_derivative(rho, p) + ((1.0 + p.omega) * pres - reference_pressure(rho, p)) / rho


def sound_speed(rho, e, p: JWLParams):
    return sound_speed_squared(rho, pressure(rho, e, p), p) ** 0.5
