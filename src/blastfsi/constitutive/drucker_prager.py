"""Drucker-Prager soil with shear and tension failure, 000 Eqs. (59)-(63) (Itasca FLAC3D form).

Tension positive; tau = sqrt(J2), sigma_m = I1/3. Elastic trial stress from Hooke's law
in rate form after the Jaumann rotation, then (FLAC3D return, non-associated in shear
with the dilation angle psi, associated in tension):

* f^s = tau + q_phi sigma_m - k_phi (Eq. 62), f^t = sigma_m - sigma^t (Eq. 63),
  h = tau - tau^p - alpha^p (sigma_m - sigma^t) (Eq. 59), tau^p = k_phi - q_phi sigma^t (Eq. 60),
  alpha^p = sqrt(1 + q_phi^2) - q_phi (Eq. 61).
* shear failure (f^s > 0, h > 0): lambda = f^s / (G + K q_phi q_psi),
  tau <- tau - G lambda, sigma_m <- sigma_m - K q_psi lambda (on the cone for psi = 0);
* tension failure (f^t > 0, h <= 0), and any sigma_m still above sigma^t after the shear
  correction: sigma_m <- sigma^t, then tau <- min(tau, tau^p) (the cone/cut-off corner).

k_phi, q_phi (and q_psi) from cohesion c and friction angle phi by the cone through the
compressive meridian of Mohr-Coulomb (FLAC3D):
q_phi = 6 sin(phi) / (sqrt(3) (3 - sin(phi))), k_phi = 6 c cos(phi) / (sqrt(3) (3 - sin(phi))).
sigma^t is capped at the apex k_phi / q_phi. Equivalent plastic strain: d eps_p = d tau / (sqrt(3) G).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

from blastfsi.constitutive import Model, PointState, register
from blastfsi.constitutive import tensor as T
from blastfsi.constitutive.elastic import hooke_increment, moduli
from blastfsi.materials import ranges


class DruckerPragerParams(NamedTuple):
    bulk_modulus: float
    shear_modulus: float
    k_phi: float
    q_phi: float
    q_psi: float
    tensile_strength: float  # sigma^t, already capped at the apex


def cone(cohesion: float, angle_deg: float) -> tuple[float, float]:
    """(k, q) of the Drucker-Prager cone through the compressive meridian of Mohr-Coulomb."""
    s = math.sin(math.radians(angle_deg))
    d = math.sqrt(3.0) * (3.0 - s)
    return 6.0 * cohesion * math.cos(math.radians(angle_deg)) / d, 6.0 * s / d


def return_map(sigma_m, tau, p: DruckerPragerParams):
    """FLAC3D Drucker-Prager correction of a trial (sigma_m, tau); returns the corrected pair."""
    tau_corner = p.k_phi - p.q_phi * p.tensile_strength  # Eq. (60)
    alpha = jnp.sqrt(1.0 + p.q_phi ** 2) - p.q_phi  # Eq. (61)
    f_shear = tau + p.q_phi * sigma_m - p.k_phi  # Eq. (62)
    h = tau - tau_corner - alpha * (sigma_m - p.tensile_strength)  # Eq. (59)
    shear = (f_shear > 0.0) & (h > 0.0)
    lam = jnp.where(shear, f_shear / (p.shear_modulus + p.bulk_modulus * p.q_phi * p.q_psi), 0.0)
    tau = jnp.maximum(tau - p.shear_modulus * lam, 0.0)
    sigma_m = sigma_m - p.bulk_modulus * p.q_psi * lam
    tension = sigma_m > p.tensile_strength  # Eq. (63): f^t > 0
    tau = jnp.where(tension, jnp.minimum(tau, tau_corner), tau)
    return jnp.minimum(sigma_m, p.tensile_strength), tau


def update(ps: PointState, dstrain, dspin, dt, params: DruckerPragerParams) -> PointState:
    de = T.to_voigt(dstrain)
    trial = T.rotate(ps.stress, dspin) + hooke_increment(de, params.bulk_modulus, params.shear_modulus)
    s = T.deviator(trial)
    tau = jnp.sqrt(0.5 * T.contract(s, s))
    sigma_m, tau_new = return_map(-T.pressure(trial), tau, params)
    s_new = T.radial_return(s, tau, tau_new)
    stress = T.compose(s_new, -sigma_m)
    rho_old = T.old_density(ps.density, de)
    energy = T.energy_trapezoidal(ps.energy, ps.stress, stress, de, rho_old)  # 000 Eq. (13)
    d_eps = (tau - tau_new) / (math.sqrt(3.0) * params.shear_modulus)
    return ps._replace(stress=stress, energy=energy, plastic_strain=ps.plastic_strain + d_eps)


def wave_speed(ps: PointState, params: DruckerPragerParams):
    return jnp.sqrt((params.bulk_modulus + 4.0 / 3.0 * params.shear_modulus) / ps.density)


def params_from(material) -> DruckerPragerParams:
    ranges.check(material)  # every constant in its range and order (blastfsi.materials.solids.DruckerPragerSoil)
    el = moduli(material.youngs_modulus, material.poisson_ratio)
    k_phi, q_phi = cone(material.cohesion, material.friction_angle)
    _, q_psi = cone(0.0, material.dilation_angle)
    apex = k_phi / q_phi if q_phi > 0.0 else math.inf
    return DruckerPragerParams(el.bulk_modulus, el.shear_modulus, k_phi, q_phi, q_psi,
                               min(material.tensile_strength, apex))


MODEL = register(Model("drucker-prager", update, wave_speed, params_from, history_size=0))
