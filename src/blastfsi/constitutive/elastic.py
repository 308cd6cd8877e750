"""Linear elastic solid: Hooke's law in rate form with the Jaumann rotation (000 Eq. 30).

    sigma_new = R sigma R^T + K tr(d eps) I + 2 G dev(d eps)

(R the Hughes-Winget rotation, see :mod:`.tensor`); the internal energy follows
000 Eq. (13) with the midpoint stress. No history.
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from blastfsi.constitutive import Model, PointState, register
from blastfsi.constitutive import tensor as T


class ElasticParams(NamedTuple):
    bulk_modulus: float  # K [Pa]
    shear_modulus: float  # G [Pa]


def moduli(youngs_modulus: float, poisson_ratio: float) -> ElasticParams:
    """K = E / (3 (1 - 2 nu)), G = E / (2 (1 + nu)); raises for E <= 0 or nu outside (-1, 0.5)."""
    if not youngs_modulus > 0.0:
        raise ValueError(f"youngs_modulus must be > 0 Pa, got {youngs_modulus}")
    if not -1.0 < poisson_ratio < 0.5:
        raise ValueError(f"poisson_ratio must be in (-1, 0.5), got {poisson_ratio}")
    return ElasticParams(youngs_modulus / (3.0 * (1.0 - 2.0 * poisson_ratio)),
                         youngs_modulus / (2.0 * (1.0 + poisson_ratio)))


def hooke_increment(dstrain_voigt, bulk_modulus, shear_modulus):
    """d sigma = K tr(d eps) I + 2 G dev(d eps) (Voigt)."""
    return (bulk_modulus * T.trace(dstrain_voigt))[..., None] * T.IDENTITY_VOIGT \
        + 2.0 * shear_modulus * T.deviator(dstrain_voigt)


def update(ps: PointState, dstrain, dspin, dt, params: ElasticParams) -> PointState:
    de = T.to_voigt(dstrain)
    stress = T.rotate(ps.stress, dspin) + hooke_increment(de, params.bulk_modulus, params.shear_modulus)
    rho_old = T.old_density(ps.density, de)
    energy = T.energy_trapezoidal(ps.energy, ps.stress, stress, de, rho_old)  # 000 Eq. (13)
    return ps._replace(stress=stress, energy=energy)


def wave_speed(ps: PointState, params: ElasticParams):
    """Longitudinal (P-wave) speed sqrt((K + 4G/3) / rho)."""
    return jnp.sqrt((params.bulk_modulus + 4.0 / 3.0 * params.shear_modulus) / ps.density)


def params_from(material) -> ElasticParams:
    return moduli(material.youngs_modulus, material.poisson_ratio)


MODEL = register(Model("elastic", update, wave_speed, params_from, history_size=0))
