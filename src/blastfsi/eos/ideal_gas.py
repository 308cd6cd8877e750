"""Calorically perfect (ideal) gas, p = (gamma - 1) rho e.

Works on NumPy and JAX arrays alike (only arithmetic and sqrt through the
array's own namespace)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class IdealGas:
    gamma: float

    def __post_init__(self):
        if not self.gamma > 1.0:
            raise ValueError(f"IdealGas.gamma must be > 1, got {self.gamma}")

    def pressure(self, rho, e):
        """002 Eq. (4) without the viscous term."""
        return (self.gamma - 1.0) * rho * e

    def sound_speed(self, rho, e):
        """002 Eq. (13) corrected (ERRATA 002-3): a = sqrt(gamma (gamma-1) e)."""
        return (self.gamma * (self.gamma - 1.0) * e) ** 0.5

    def energy(self, rho, p):
        return p / ((self.gamma - 1.0) * rho)

    def sound_speed_from_pressure(self, rho, p):
        return np.sqrt(self.gamma * p / rho)
