"""Artificial bulk viscosity of the MPM particles (ERRATA 000-10).

von Neumann-Richtmyer quadratic plus Landshoff linear term, active in
compression only, in the form of 002 Eq. (5) with D the volumetric strain rate
D_kk and l the grid cell size h (the width over which MPM smears a shock):

    q = rho l (C_q l D^2 + C_l c |D|)   for D < 0,   q = 0 otherwise.

q >= 0 is added to the pressure in the internal forces (000 Eq. 19), and its
work -q dV heats the particle (000 Eq. 13 with p -> p + q).
Usual coefficients: C_q = 1.5, C_l = 0.06 (the defaults of LS-DYNA's
*CONTROL_BULK_VISCOSITY, Q1 and Q2; LS-DYNA Keyword User's Manual).
"""
from __future__ import annotations

import jax.numpy as jnp

DEFAULT_QUADRATIC = 1.5  # C_q: LS-DYNA *CONTROL_BULK_VISCOSITY Q1 default
DEFAULT_LINEAR = 0.06  # C_l: LS-DYNA *CONTROL_BULK_VISCOSITY Q2 default


def viscous_signal(c, vol_rate, length, quadratic, linear):
    """s = C_l c + C_q l |D| in compression (0 in expansion) [m/s], so that q = rho l |D| s."""
    return jnp.where(vol_rate < 0.0, linear * c + quadratic * length * jnp.abs(vol_rate), 0.0)


def bulk_viscosity(density, c, vol_rate, length, quadratic, linear):
    """ERRATA 000-10 (002 Eq. 5 form): q = rho l |D| (C_l c + C_q l |D|) for D < 0 [Pa]."""
    return density * length * jnp.abs(vol_rate) * viscous_signal(c, vol_rate, length, quadratic, linear)


def signal_speed(c, speed, vol_rate, length, quadratic, linear):
    """Speed in the CFL step, |v| + s + sqrt(s^2 + c^2): the critical step
    l / (s + sqrt(s^2 + c^2)) of an explicit scheme with bulk viscosity (Benson,
    CMAME 99 (1992) 235; the LS-DYNA element time step) plus the particle speed."""
    s = viscous_signal(c, vol_rate, length, quadratic, linear)
    return speed + s + jnp.sqrt(s * s + c * c)
