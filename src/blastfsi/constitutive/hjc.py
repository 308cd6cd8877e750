"""Holmquist-Johnson-Cook concrete (000 Eqs. 56-57) with Jiang tensile damage (000 Eq. 58).

Equation of state (HJC 1993), mu = rho/rho0 - 1, compression positive:

* region I, mu <= mu_crush: P = K_e mu, K_e = P_crush/mu_crush;
* region II (crushing), mu_crush < mu <= mu_plock: the straight crush line from
  (mu_crush, P_crush) to (mu_plock, P_lock);
* region III (fully dense): P = K1 x + K2 x^2 + K3 x^3 (K1 x in tension),
  x = (mu - mu_lock)/(1 + mu_lock) the modified volumetric strain.

Locking (ERRATA "HJC locking"): we follow HJC 1993 as written, reading (a): mu_lock is
the locking strain of the fully dense material, the zero-pressure origin of the
region-III curve (x = 0), and the crush line ends at mu_plock, where that curve reaches
P_lock: K1 x_p + K2 x_p^2 + K3 x_p^3 = P_lock, mu_plock = mu_lock + x_p (1 + mu_lock).
The curve is then continuous at both ends of the crush line by construction.

Unloading from the largest compression reached, mu_max (history): regions I-II unload
linearly, P = P_load(mu_max) - K_u (mu_max - mu), with K_u interpolated between K_e and
K1 by F = (mu_max - mu_crush)/(mu_plock - mu_crush) (K_u = K_e in region I, so region I
is reversible); after locking the region-III curve is followed both ways. Tension is
limited to P >= -T (1 - D).

Plastic volumetric strain mu_p (for 000 Eq. 57) is the permanent crush, the zero-pressure
intercept mu_max - P_load(mu_max)/K_u of the unloading line, frozen once locked.

Strength, 000 Eq. (56): sigma* = [A (1 - D) + B P*^N][1 + C ln eps_dot*] <= SMAX for
P* >= 0 and, in hydrostatic tension, sigma* = A (1 - D)(1 + P*/T*)(1 + C ln eps_dot*)
(the linear closure to zero at P* = -T* of the HJC tension region; same in the HJC
implementations of IMPETUS MAT_HJC_CONCRETE and OpenRadioss LAW126). eps_dot* is the
total equivalent strain rate over eps_dot_0, floored at 1. Radial return to sigma* fc.

Damage, 000 Eq. (57): D += (d eps_p + d mu_p) / max(EFMIN, D1 (P* + T*)^D2), D <= 1.

Tensile damage, 000 Eq. (58): dD_t/dt = a D_t (1 - D_t)(sigma_s/sigma_0 - 1)^gamma for
sigma_s > sigma_0. Jiang's cracks are "equivalent micro holes" (spherical cavities), so
sigma_s is the hydrostatic tension the volumetric strain demands, -P of the EOS *before*
the tension cut-off -T (1 - D): the cut-off is what the material carries, the excess
drives crack growth (with sigma_0 = T damage starts exactly when the cut-off is reached;
the largest principal stress would not do, since the cut-off and the vanishing tensile
strength keep it near T, so it could never exceed sigma_0 in sustained tension). The
logistic equation is integrated exactly over a step at frozen sigma_s: logit D_t grows by
L = integral of a (sigma_s/sigma_0 - 1)^gamma dt. History keeps L (so all-zero history is
the virgin state D_t = D_t0). When D_t reaches its limit the particle has spalled
(failed): from then on it carries no deviatoric stress and no tension (P >= 0), keeps
its mass and compressive EOS; ``damage`` reports 1 for it (else the HJC damage D).

Energy: 000 Eq. (13) with the trapezoidal stress (the HJC pressure does not depend on e).
History columns: mu_max, mu_p, D (HJC damage), L (tensile damage growth exponent).
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from blastfsi.constitutive import Model, PointState, register
from blastfsi.constitutive import tensor as T
from blastfsi.materials import ranges

HISTORY_COLUMNS = ("mu_max", "plastic_volumetric_strain", "hjc_damage", "tensile_damage_exponent")


class HJCParams(NamedTuple):
    density: float
    shear_modulus: float
    fc: float
    A: float
    B: float
    N: float
    C: float
    SMAX: float
    reference_strain_rate: float
    T: float
    D1: float
    D2: float
    EFMIN: float
    P_crush: float
    mu_crush: float
    K1: float
    K2: float
    K3: float
    P_lock: float
    mu_lock: float
    mu_plock: float  # derived: end of the crush line (reading (a), see module docstring)
    tensile_damage_rate: float
    tensile_threshold: float
    tensile_exponent: float
    initial_tensile_damage: float
    failure_exponent: float  # derived: L at which D_t reaches the tensile damage limit


def dense_pressure(x, p):
    """Region III, P(x) = K1 x + K2 x^2 + K3 x^3 for x >= 0, K1 x in tension."""
    return jnp.where(x >= 0.0, p.K1 * x + p.K2 * x ** 2 + p.K3 * x ** 3, p.K1 * x)


def dense_modulus(x, p):
    """dP/dmu of region III (x = (mu - mu_lock)/(1 + mu_lock))."""
    return jnp.where(x >= 0.0, p.K1 + 2.0 * p.K2 * x + 3.0 * p.K3 * x ** 2, p.K1) / (1.0 + p.mu_lock)


def modified_strain(mu, p):
    return (mu - p.mu_lock) / (1.0 + p.mu_lock)


def elastic_bulk_modulus(p):
    return p.P_crush / p.mu_crush


def crush_line(mu, p):
    """Region II loading line through (mu_crush, P_crush) and (mu_plock, P_lock)."""
    return p.P_crush + (p.P_lock - p.P_crush) * (mu - p.mu_crush) / (p.mu_plock - p.mu_crush)


def loading_pressure(mu, p):
    """The virgin loading curve of regions I-III."""
    return jnp.where(mu <= p.mu_crush, elastic_bulk_modulus(p) * mu,
                     jnp.where(mu <= p.mu_plock, crush_line(mu, p), dense_pressure(modified_strain(mu, p), p)))


def unloading_modulus(mu_max, p):
    """K_u = (1 - F) K_e + F K1, F = (mu_max - mu_crush)/(mu_plock - mu_crush) clipped to [0, 1]."""
    f = jnp.clip((mu_max - p.mu_crush) / (p.mu_plock - p.mu_crush), 0.0, 1.0)
    return (1.0 - f) * elastic_bulk_modulus(p) + f * p.K1


def uncut_pressure(mu, mu_max, p):
    """HJC pressure at compression mu after a largest compression mu_max >= mu, without tension cut-off."""
    locked = mu_max > p.mu_plock
    partial = loading_pressure(mu_max, p) - unloading_modulus(mu_max, p) * (mu_max - mu)
    return jnp.where(locked, dense_pressure(modified_strain(mu, p), p), partial)


def eos_pressure(mu, mu_max, damage, p):
    """HJC pressure with the tension cut-off P >= -T (1 - D)."""
    return jnp.maximum(uncut_pressure(mu, mu_max, p), -p.T * (1.0 - damage))


def plastic_volumetric_strain(mu_max, p):
    """Permanent crush: zero-pressure intercept of the unloading line (0 in region I, frozen when locked)."""
    m = jnp.minimum(mu_max, p.mu_plock)
    return jnp.maximum(m - loading_pressure(m, p) / unloading_modulus(m, p), 0.0)


def strength(pressure, damage, strain_rate, p):
    """000 Eq. (56) (normalised sigma*), with the linear closure in hydrostatic tension."""
    pstar = pressure / p.fc
    tstar = p.T / p.fc
    rate = 1.0 + p.C * jnp.log(jnp.maximum(strain_rate / p.reference_strain_rate, 1.0))
    compressive = jnp.minimum((p.A * (1.0 - damage) + p.B * jnp.maximum(pstar, 0.0) ** p.N) * rate, p.SMAX)
    tensile = jnp.maximum(p.A * (1.0 - damage) * (1.0 + pstar / tstar) * rate, 0.0)
    return jnp.where(pstar >= 0.0, compressive, tensile)


def fracture_strain(pressure, p):
    """Denominator of 000 Eq. (57): max(EFMIN, D1 (P* + T*)^D2)."""
    return jnp.maximum(p.EFMIN, p.D1 * jnp.maximum((pressure + p.T) / p.fc, 0.0) ** p.D2)


def tensile_damage(exponent, p):
    """D_t from logit(D_t) = logit(D_t0) + L (exact solution of 000 Eq. 58 at frozen stress)."""
    d0 = p.initial_tensile_damage
    return 1.0 / (1.0 + (1.0 - d0) / d0 * jnp.exp(-exponent))


def tensile_damage_growth(tension, dt, p):
    """L increment a (sigma_s/sigma_0 - 1)^gamma dt for sigma_s > sigma_0, else 0."""
    over = jnp.maximum(tension / p.tensile_threshold - 1.0, 0.0)
    return p.tensile_damage_rate * over ** p.tensile_exponent * dt


def update(ps: PointState, dstrain, dspin, dt, params: HJCParams) -> PointState:
    p = params
    de = T.to_voigt(dstrain)
    mu_max_old, mu_p_old, d_old, growth_old = (ps.history[:, k] for k in range(4))
    failed_old = growth_old >= p.failure_exponent
    mu = ps.density / p.density - 1.0
    mu_max = jnp.maximum(mu_max_old, mu)
    pres_uncut = uncut_pressure(mu, mu_max, p)
    pres = jnp.maximum(pres_uncut, jnp.where(failed_old, 0.0, -p.T * (1.0 - d_old)))

    s_trial = T.deviator(T.rotate(ps.stress, dspin)) + 2.0 * p.shear_modulus * T.deviator(de)
    q_trial = T.von_mises(s_trial)
    rate = T.equivalent_strain(de) / jnp.maximum(dt, jnp.finfo(de.dtype).tiny)
    q_yield = jnp.where(failed_old, 0.0, p.fc * strength(pres, d_old, rate, p))
    s_new = T.radial_return(s_trial, q_trial, q_yield)
    d_eps = jnp.maximum(q_trial - q_yield, 0.0) / (3.0 * p.shear_modulus)

    mu_p = jnp.maximum(plastic_volumetric_strain(mu_max, p), mu_p_old)
    d_new = jnp.minimum(d_old + (d_eps + mu_p - mu_p_old) / fracture_strain(pres, p), 1.0)  # 000 Eq. (57)

    stress = T.compose(s_new, pres)
    growth = growth_old + tensile_damage_growth(-pres_uncut, dt, p)  # 000 Eq. (58)
    failed = growth >= p.failure_exponent
    stress = jnp.where(failed[:, None], T.compose(jnp.zeros_like(s_new), jnp.maximum(pres, 0.0)), stress)

    rho_old = T.old_density(ps.density, de)
    energy = T.energy_trapezoidal(ps.energy, ps.stress, stress, de, rho_old)  # 000 Eq. (13)
    history = jnp.stack([mu_max, mu_p, d_new, growth], axis=-1)
    return ps._replace(stress=stress, energy=energy, plastic_strain=ps.plastic_strain + d_eps,
                       damage=jnp.where(failed, 1.0, d_new), history=history)


def wave_speed(ps: PointState, params: HJCParams):
    """sqrt((K + 4G/3)/rho) with K the stiffest of the current unloading and dense-branch moduli."""
    mu = ps.density / params.density - 1.0
    mu_max = jnp.maximum(ps.history[:, 0], mu)
    k_dense = jnp.where(mu_max > params.mu_plock, dense_modulus(modified_strain(mu, params), params), 0.0)
    k = jnp.maximum(unloading_modulus(mu_max, params), k_dense)
    return jnp.sqrt((k + 4.0 / 3.0 * params.shear_modulus) / ps.density)


def locking_strain(K1: float, K2: float, K3: float, P_lock: float, mu_lock: float) -> float:
    """mu_plock: where the region-III curve, starting at mu_lock, reaches P_lock (reading (a))."""
    roots = np.roots([K3, K2, K1, -P_lock])
    real = sorted(r.real for r in roots if abs(r.imag) < 1e-12 * max(1.0, abs(r)) and r.real > 0.0)
    if not real:
        raise ValueError(f"P_lock = {P_lock} Pa is never reached by the dense curve K1 x + K2 x^2 + K3 x^3")
    return mu_lock + real[0] * (1.0 + mu_lock)


def params_from(material) -> HJCParams:
    m = material
    ranges.check(m)  # every constant in its range and order (blastfsi.materials.solids.HJCConcrete)
    mu_plock = locking_strain(m.K1, m.K2, m.K3, m.P_lock, m.mu_lock)
    if not mu_plock > m.mu_crush:
        raise ValueError(f"mu_lock ({m.mu_lock}) puts the end of the crush line {mu_plock} below mu_crush")

    def logit(x):
        return float(np.log(x / (1.0 - x)))

    return HJCParams(
        m.density, m.shear_modulus, m.fc, m.A, m.B, m.N, m.C, m.SMAX, m.reference_strain_rate, m.T,
        m.D1, m.D2, m.EFMIN, m.P_crush, m.mu_crush, m.K1, m.K2, m.K3, m.P_lock, m.mu_lock, mu_plock,
        m.tensile_damage_rate, m.tensile_threshold, m.tensile_exponent, m.initial_tensile_damage,
        logit(m.tensile_damage_limit) - logit(m.initial_tensile_damage))


def output_fields(history, p: HJCParams) -> dict:
    """The two damages apart: ``compressive_damage`` the HJC D of 000 Eq. (57) (crushing: 1 = crushed),
    ``tensile_damage`` the Jiang D_t of 000 Eq. (58) (the particle spalls at ``tensile_damage_limit``)."""
    return {"compressive_damage": np.asarray(history[:, 2]),
            "tensile_damage": np.asarray(tensile_damage(np.asarray(history[:, 3]), p))}


MODEL = register(Model("hjc", update, wave_speed, params_from, history_size=len(HISTORY_COLUMNS),
                       output_fields=output_fields))
