"""Calorically perfect (ideal) gas, p = (gamma - 1) rho e.

Pure functions of arrays (NumPy or JAX) with gamma as an argument, so the
same code serves host-side set-up and traced, vmapped solver kernels; the
frozen :class:`IdealGas` binds a validated gamma for host use.
"""
from __future__ import annotations

from dataclasses import dataclass


def pressure(rho, e, gamma):
    """002 Eq. (4) without the viscous term."""
    return (gamma - 1.0) * rho * e


def sound_speed(e, gamma):
    """002 Eq. (13) corrected (ERRATA 002-3): a = sqrt(gamma (gamma-1) e)."""
    return (gamma * (gamma - 1.0) * e) ** 0.5


def energy(rho, p, gamma):
    """Specific internal energy from density and pressure."""
    return p / ((gamma - 1.0) * rho)


@dataclass(frozen=True)
class IdealGas:
    gamma: float

    def __post_init__(self):
        if not self.gamma > 1.0:
            raise ValueError(f"IdealGas.gamma must be > 1, got {self.gamma}")

    def pressure(self, rho, e):
        return pressure(rho, e, self.gamma)

    def sound_speed(self, rho, e):
        return sound_speed(e, self.gamma)

    def energy(self, rho, p):
        return energy(rho, p, self.gamma)
