"""Johnson-Cook plasticity (000 Eq. 64) with a Mie-Grueneisen EOS (000 Eqs. 65-66).

Stress update per step:

1. Jaumann rotation of the old stress (:func:`.tensor.rotate`, 000 Eq. 30).
2. Elastic trial deviator s* = s + 2G dev(d eps), equivalent stress q* = sqrt(3/2 s*:s*).
3. Radial return solved exactly (not a one-step estimate): the plastic strain increment
   d eps_p >= 0 is the root of
       q* - 3G d eps_p - sigma_y(eps_p + d eps_p, d eps_p/dt, T) = 0,
       sigma_y = (A + B eps^n)(1 + C ln max(eps_dot/eps_dot_0, 1))(1 - T*^m),     000 Eq. (64)
   found by Halley's method safeguarded by bisection on [0, (q* - sigma_y0)/(3G)], so the
   returned stress lies on the yield surface at the end of the step to round-off. It runs in
   u = ln(d eps_p): the rate term C ln(d eps_p/dt) is linear in u, so its slope C/d eps_p
   (infinite at 0) no longer stalls the iteration near 0 (measured on yielding 3D steel with
   Newton's method: at most 9 iterations instead of 28). The bracket is kept in u too (its
   lower end -inf until a point below the root is found, the bisection then halving x from 0,
   later halving the bracket in u), so an iteration takes three transcendentals: exp(u) and
   (eps_p + x)^n. It starts from x0 with 1/x0 = 1/x_elastic + 1/x_hardening (each the root
   were the other term and the rate absent; exact were both linear), not from the upper bound
   x_elastic, from which a tiny root of a first-yield particle took 10-13 Newton iterations
   (one e-fold a step). Halley's step (cubic convergence; Newton's where the curvature
   correction exceeds 1/2) below EARLY_ACCEPT = 1e-5 in u is the last: it lands within
   ~1e-15 of the root. On the yielding steel block of benchmarks/bench_mpm.py every particle
   is done in at most 5 evaluations, most in 3 (Newton's method, checking the residual at its
   last iterate: 5-7); the benchmark step ~10 % faster. The rate
   term is floored at eps_dot* = 1 (no softening below the reference rate); T* is clipped
   to [0, 1] (sigma_y = 0 at and above melt).
4. Plastic-work heating dT = chi sigma_y d eps_p / (rho c_p), chi the Taylor-Quinney factor;
   the temperature *rise* above room temperature is kept in history (all-zero history = room
   temperature), the softening of a step uses the temperature at its start.
5. Pressure from the EOS at the new density, implicit in the new energy (000 Eq. 13 with the
   trapezoidal stress; :func:`.tensor.energy_implicit`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import xla
from blastfsi.constitutive import Model, PointState, register
from blastfsi.constitutive import tensor as T
from blastfsi.eos import mie_gruneisen as mg
from blastfsi.eos.mie_gruneisen import MieGruneisenParams
from blastfsi.materials import ranges

HISTORY_COLUMNS = ("temperature_rise",)
MAX_ITERATIONS = 60
EARLY_ACCEPT = 1e-5  # |Halley step| in u below which the step is the last (docstring, step 3)
UNROLLED_ITERATIONS = 5  # on a GPU, before the loop: on the bench's yielding block all particles are done in <= 5


class JohnsonCookParams(NamedTuple):
    shear_modulus: float
    A: float
    B: float
    n: float
    C: float
    m: float
    reference_strain_rate: float
    room_temperature: float
    melt_temperature: float
    specific_heat: float
    taylor_quinney: float
    eos: MieGruneisenParams


def homologous_temperature(temperature, p: JohnsonCookParams):
    """T* = (T - T_room)/(T_melt - T_room), clipped to [0, 1]."""
    return jnp.clip((temperature - p.room_temperature) / (p.melt_temperature - p.room_temperature), 0.0, 1.0)


def power(x, a):
    """x^a for x >= 0 as exp(a ln x) (0^a: 0 for a > 0, 1 for a = 0). XLA:CPU's general power took 7x
    the time of an exp here (measured, 32 768 values: 0.15 against 0.02 ms)."""
    positive = x > 0.0
    at_zero = jnp.where(a > 0.0, 0.0, jnp.where(a == 0.0, 1.0, jnp.inf))
    return jnp.where(positive, jnp.exp(a * jnp.log(jnp.where(positive, x, 1.0))), at_zero)


def flow_stress(eps_p, strain_rate, temperature, p: JohnsonCookParams):
    """000 Eq. (64) with eps_dot* floored at 1."""
    rate = jnp.maximum(strain_rate / p.reference_strain_rate, 1.0)
    return ((p.A + p.B * power(jnp.maximum(eps_p, 0.0), p.n)) * (1.0 + p.C * jnp.log(rate))
            * (1.0 - power(homologous_temperature(temperature, p), p.m)))


def _residual(u, q_trial, eps_p, log_kink, thermal, three_g, p: JohnsonCookParams):
    """f = q* - 3G x - sigma_y(eps_p + x, x/dt) at x = d eps_p = exp(u), and its first two derivatives
    in u (Halley's method, docstring step 3).

    In u the rate factor is R = 1 + C (u - ln(dt eps_dot_0)) above its kink (no log to take), R_u = C,
    R_uu = 0; the hardening H = A + B (eps_p + x)^n has H_u = n B (eps_p + x)^n x / (eps_p + x) and
    H_uu = H_u (1 + (n - 1) x / (eps_p + x))."""
    x = jnp.exp(u)
    eps = eps_p + x
    eps_n = power(eps, p.n)
    hard = p.A + p.B * eps_n
    above = u > log_kink
    rate_factor = 1.0 + p.C * jnp.where(above, u - log_kink, 0.0)
    rate_slope = jnp.where(above, p.C, 0.0)
    share = x / eps
    hard_u = p.n * p.B * eps_n * share
    hard_uu = hard_u * (1.0 + (p.n - 1.0) * share)
    f = q_trial - three_g * x - hard * rate_factor * thermal
    f_u = -three_g * x - (hard_u * rate_factor + hard * rate_slope) * thermal
    f_uu = -three_g * x - (hard_uu * rate_factor + 2.0 * hard_u * rate_slope) * thermal
    return f, f_u, f_uu


def plastic_increment(q_trial, eps_p, dt, temperature, p: JohnsonCookParams):
    """Root d eps_p >= 0 of q* - 3G d eps_p - sigma_y(eps_p + d eps_p, d eps_p/dt, T) = 0 (0 if elastic)."""
    thermal = 1.0 - power(homologous_temperature(temperature, p), p.m)
    three_g = 3.0 * p.shear_modulus
    tiny = jnp.finfo(q_trial.dtype).tiny
    dt = jnp.maximum(dt, tiny)
    log_kink = jnp.log(dt * p.reference_strain_rate)  # ln d eps_p where eps_dot* = 1
    eps_power = power(jnp.maximum(eps_p, 0.0), p.n)  # eps_p^n, read twice
    y0 = (p.A + p.B * eps_power) * thermal  # flow_stress(eps_p, 0, T): the rate factor is 1 below the kink
    plastic = q_trial > y0
    hi = jnp.where(plastic, (q_trial - y0) / three_g, 1.0)  # perfectly plastic bound: the root is below it
    tol = 8.0 * jnp.finfo(q_trial.dtype).eps

    def cond(c):
        return jnp.logical_and(c[-1] < MAX_ITERATIONS, ~jnp.all(c[-2]))

    def body(c):  # the bracket [u_lo, u_hi] in u; u_lo = -inf while only x = 0 is known to lie below the root
        u_lo, u_hi, u, done, it = c
        f, f_u, f_uu = _residual(u, q_trial, eps_p, log_kink, thermal, three_g, p)
        u_lo = jnp.where(f > 0.0, u, u_lo)
        u_hi = jnp.where(f > 0.0, u_hi, u)
        newton = f / f_u
        curvature = 0.5 * newton * f_uu / f_u  # Halley: u - newton / (1 - curvature), Newton where it is large
        halley = jnp.abs(curvature) < 0.5
        u_step = jnp.where(halley, newton / (1.0 - curvature), newton)
        u_next = u - u_step
        inside = (u_next > u_lo) & (u_next < u_hi) & jnp.isfinite(u_next)
        u_mid = jnp.where(jnp.isinf(u_lo), u_hi - math.log(2.0), 0.5 * (u_lo + u_hi))  # bisection: of x from 0
        u_new = jnp.where(inside, u_next, u_mid)
        on_surface = jnp.abs(f) <= tol * q_trial
        # a Halley step below EARLY_ACCEPT lands within ~EARLY_ACCEPT^3 of the root: taken, not checked
        landed = inside & halley & (jnp.abs(u_step) <= EARLY_ACCEPT)
        u = jnp.where(done | on_surface, u, u_new)
        done = done | on_surface | landed | (u_hi - u_lo <= tol)
        return u_lo, u_hi, u, done, it + 1

    # start: x0 with 1/x0 = 1/x_elastic + 1/x_hardening, the root when the rate factor is 1 and both the
    # elastic unloading 3G x and the hardening B ((eps_p + x)^n - eps_p^n) alone would absorb q* - sigma_y0
    # (exact were both linear in x); the iteration in u then needs a few steps also where the root is tiny
    a = jnp.where(plastic, q_trial - y0, 0.0) / jnp.maximum(p.B * thermal, tiny)  # (eps_p + x)^n - eps_p^n
    hardened = eps_p > 0.0
    base = jnp.where(hardened, eps_p, 1.0)
    x_hard = jnp.where(hardened, base * jnp.expm1(jnp.log1p(a / jnp.where(hardened, eps_power, 1.0)) / p.n),
                       # (no cancellation at a << eps_p^n)
                       jnp.exp(jnp.log(jnp.maximum(a, tiny)) / p.n))
    x0 = 1.0 / (1.0 / hi + 1.0 / jnp.maximum(x_hard, tiny))
    x0 = jnp.where(plastic & (x0 > 0.0) & (x0 < hi), x0, hi)
    carry = (jnp.full_like(hi, -jnp.inf), jnp.log(hi), jnp.log(x0), ~plastic, 0)
    if not xla.device_control_flow():  # the usual iterations without a host round trip each (blastfsi.xla);
        for _ in range(UNROLLED_ITERATIONS):  # converged particles keep u, so the result is the loop's
            carry = body(carry)
    _, _, u, _, _ = jax.lax.while_loop(cond, body, carry)
    return jnp.where(plastic, jnp.exp(u), 0.0)


def update(ps: PointState, dstrain, dspin, dt, params: JohnsonCookParams) -> PointState:
    de = T.to_voigt(dstrain)
    rho_old = T.old_density(ps.density, de)
    s_old = T.deviator(ps.stress)
    s_trial = T.deviator(T.rotate(ps.stress, dspin)) + 2.0 * params.shear_modulus * T.deviator(de)
    q_trial = T.von_mises(s_trial)
    temperature = params.room_temperature + ps.history[:, 0]
    d_eps = plastic_increment(q_trial, ps.plastic_strain, dt, temperature, params)
    q_new = q_trial - 3.0 * params.shear_modulus * d_eps  # = sigma_y on the surface when plastic
    s_new = T.radial_return(s_trial, q_trial, q_new)
    heating = params.taylor_quinney * q_new * d_eps / (ps.density * params.specific_heat)
    p_old = mg.pressure(rho_old, ps.energy, params.eos)  # 000 Eq. (65)
    energy, p_new = T.energy_implicit(ps.energy, s_old, s_new, p_old,
                                      mg.reference_pressure(ps.density, params.eos),
                                      mg.energy_coefficient(ps.density, params.eos), de, rho_old)
    return ps._replace(stress=T.compose(s_new, p_new), energy=energy,
                       plastic_strain=ps.plastic_strain + d_eps,
                       history=ps.history.at[:, 0].add(heating))


def wave_speed(ps: PointState, params: JohnsonCookParams):
    """sqrt(c_bulk^2 + 4G/(3 rho)) with c_bulk^2 the EOS isentropic value (floored at 0)."""
    c2 = jnp.maximum(mg.sound_speed_squared(ps.density, ps.energy, params.eos), 0.0)
    return jnp.sqrt(c2 + 4.0 / 3.0 * params.shear_modulus / ps.density)


def params_from(material) -> JohnsonCookParams:
    ranges.check(material)  # every constant in its range and order (blastfsi.materials.solids.JohnsonCookSolid)
    return JohnsonCookParams(
        material.shear_modulus, material.A, material.B, material.n, material.C, material.m,
        material.reference_strain_rate, material.room_temperature, material.melt_temperature,
        material.specific_heat, material.taylor_quinney,
        MieGruneisenParams(material.density, material.C0, material.S, material.gamma0, material.a))


def output_fields(history, p: JohnsonCookParams) -> dict:
    """``temperature`` [K]: the room temperature plus the adiabatic rise of 000 Eq. (64)'s thermal term."""
    return {"temperature": p.room_temperature + np.asarray(history[:, 0])}


MODEL = register(Model("johnson-cook", update, wave_speed, params_from, history_size=len(HISTORY_COLUMNS),
                       output_fields=output_fields))
