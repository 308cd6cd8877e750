"""Null-strength fluid particles (air, detonation products): sigma = -p I from a JWL-row EOS.

The EOS is one :class:`blastfsi.eos.jwl.JWLParams` row, 000 Eq. (54) (ERRATA 000-6);
an ideal gas (000 Eq. 55) is the row A = B = 0, w = gamma - 1. With the
programmed burn of 000 Eqs. (52)-(53) the pressure is p = F p_EOS(rho, e).

Burn (ERRATA 000-8). ``update`` has no clock argument, so every particle
carries its own in ``history``:

* column 0, ``t - t_L``: time since its lighting time t_L (set to -t_L at t = 0,
  t_L = distance from the detonation point / D), advanced by dt in every update;
* column 1, ``h``: the particle's characteristic size [m];
* column 2, ``1 - F``: the unburnt fraction, F the burn fraction,
  F = min(1, (t - t_L) D / (1.5 h)) for t > t_L, 0 before, never decreasing, so
  it stays 1 once reached.

:func:`initial_history` builds these columns. An all-zero history is a burnt
particle (F = 1; D and h then play no role): air and products already burnt.

Energy: 000 Eq. (13) with the trapezoidal pressure, implicit in the new energy
(the form of 002 Eq. 16): p_new = F_new (f(rho_new) + w rho_new e_new).
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from blastfsi.constitutive import Model, PointState, register
from blastfsi.constitutive import tensor as T
from blastfsi.eos import jwl
from blastfsi.eos.jwl import JWLParams

HISTORY_COLUMNS = ("time_since_lighting", "size", "unburnt_fraction")


class FluidParams(NamedTuple):
    eos: JWLParams
    detonation_velocity: float  # D [m/s] (0 for a gas that never burns)


def initial_history(n: int, lighting_time=None, size=None):
    """History of n particles: burnt (F = 1) if ``lighting_time`` is None, else unburnt with
    per-particle lighting times t_L [s] (>= 0) and sizes h [m] (> 0), both scalars or (n,)."""
    if lighting_time is None:
        return jnp.zeros((n, 3))
    if size is None or not bool(jnp.all(jnp.asarray(size) > 0.0)):
        raise ValueError("size (particle characteristic size h) must be > 0 m")
    if bool(jnp.any(jnp.asarray(lighting_time) < 0.0)):
        raise ValueError("lighting_time must be >= 0 s")
    t_l = jnp.broadcast_to(jnp.asarray(lighting_time, dtype=float), (n,))
    h = jnp.broadcast_to(jnp.asarray(size, dtype=float), (n,))
    return jnp.stack([-t_l, h, jnp.ones(n)], axis=-1)


def burn_fraction(time_since_lighting, size, detonation_velocity, previous):
    """000 Eq. (53), capped at 1 and non-decreasing (ERRATA 000-8); ``previous`` is the last F."""
    safe = jnp.where(size > 0.0, size, 1.0)
    f = jnp.clip(time_since_lighting * detonation_velocity / (1.5 * safe), 0.0, 1.0)
    return jnp.maximum(f, previous)


def update(ps: PointState, dstrain, dspin, dt, params: FluidParams) -> PointState:
    de = T.to_voigt(dstrain)
    clock = ps.history[:, 0] + dt
    f_old = 1.0 - ps.history[:, 2]
    f_new = burn_fraction(clock, ps.history[:, 1], params.detonation_velocity, f_old)
    rho_old = T.old_density(ps.density, de)
    p_old = pressure(ps._replace(density=rho_old), params)  # 000 Eq. (52)
    zero = jnp.zeros_like(ps.stress)
    energy, p_new = T.energy_implicit(
        ps.energy, zero, zero, p_old,
        f_new * jwl.reference_pressure(ps.density, params.eos),  # 000 Eqs. (52), (54)
        f_new * params.eos.omega * ps.density, de, rho_old)
    history = jnp.stack([clock, ps.history[:, 1], 1.0 - f_new], axis=-1)
    return ps._replace(stress=T.compose(zero, p_new), energy=energy, history=history)


def pressure(ps: PointState, params: FluidParams):
    """p = F p_EOS(rho, e) at the particle's state, 000 Eq. (52)."""
    return (1.0 - ps.history[:, 2]) * jwl.pressure(ps.density, ps.energy, params.eos)


def wave_speed(ps: PointState, params: FluidParams):
    """Sound speed of the (fully burnt) EOS at the particle's state, 0 where c^2 < 0."""
    c2 = jwl.sound_speed_squared(ps.density, jwl.pressure(ps.density, ps.energy, params.eos), params.eos)
    return jnp.sqrt(jnp.maximum(c2, 0.0))


def params_from(material) -> FluidParams:
    """From a gas of :mod:`blastfsi.materials.gases` (anything with ``eos_params()``)."""
    return FluidParams(material.eos_params(), float(getattr(material, "detonation_velocity", 0.0)))


MODEL = register(Model("fluid", update, wave_speed, params_from, history_size=len(HISTORY_COLUMNS)))
