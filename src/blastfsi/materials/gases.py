"""Gases of the Eulerian solver: ideal-gas air and JWL detonation products.

Every gas maps to one :class:`blastfsi.eos.jwl.JWLParams` row (an ideal gas is
JWL with A = B = 0, w = gamma - 1), see :meth:`eos_params`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from blastfsi.eos.jwl import JWLParams, ideal_gas_params
from blastfsi.materials.ranges import constant

GAMMA_MAX = 5.0 / 3.0  # a monatomic gas has the largest ratio of specific heats of any ideal gas
_DENSITY = "a mass per unit volume is positive"


@dataclass(frozen=True)
class IdealGasMaterial:
    gamma: float = constant("p = (gamma - 1) rho e: gamma > 1 for a thermodynamically valid ideal gas (positive "
                            "pressure and sound speed); at most 5/3, the monatomic gas", gt=1.0, le=GAMMA_MAX)
    density: float = constant(_DENSITY, gt=0.0)  # ambient density [kg/m^3]
    specific_energy: float = constant("an ideal gas at positive pressure has e = p / ((gamma - 1) rho) > 0",
                                      gt=0.0)  # ambient specific internal energy [J/kg]
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)

    @property
    def pressure(self) -> float:
        return (self.gamma - 1.0) * self.density * self.specific_energy

    def eos_params(self) -> JWLParams:
        return ideal_gas_params(self.gamma)


@dataclass(frozen=True)
class JWLExplosive:
    A: float = constant("amplitude of the high-pressure term; A < 0 makes the products' pressure fall under "
                        "compression", ge=0.0)  # [Pa]
    B: float = constant("amplitude of the intermediate term; either sign occurs in published fits, "
                        "its size is bounded by A's", ge=-1e13, le=1e13)  # [Pa]
    R1: float = constant("decay rate of the A term with expansion; <= 0 makes the pressure grow without bound "
                         "as the products expand", gt=0.0)
    R2: float = constant("decay rate of the B term with expansion, as R1", gt=0.0)
    omega: float = constant("Grueneisen coefficient of the expanded products, the ideal gas p = omega rho e of "
                            "gamma = 1 + omega: > 0 for a positive pressure, <= 2/3 (gamma <= 5/3)",
                            gt=0.0, le=GAMMA_MAX - 1.0)
    E0: float = constant("detonation energy released per unit initial volume; an explosive releases energy",
                         gt=0.0)  # [J/m^3]
    density: float = constant(_DENSITY, gt=0.0)  # unreacted explosive density rho0 [kg/m^3]
    detonation_velocity: float = constant("the burn front moves outwards, and no explosive detonates faster "
                                          "than about 10 km/s", gt=0.0, le=2e4)  # D [m/s]
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)

    def eos_params(self) -> JWLParams:
        return JWLParams(self.A, self.B, self.R1, self.R2, self.omega, self.density)

    @property
    def specific_energy(self) -> float:
        """Initial specific internal energy of the products, E0 / rho0 [J/kg]."""
        return self.E0 / self.density


_SEED_000 = "seed 000 (Cui et al., CFDMP)"

GASES = {
    "air": IdealGasMaterial(
        gamma=1.4, density=1.225, specific_energy=2.0685e5,
        description="ambient air, ideal gas (p = 101.36 kPa)",
        sources={"gamma": f"{_SEED_000} Sec. 4.2 / standard diatomic gas",
                 "density": f"{_SEED_000} Sec. 4.2, Eq. (55)",
                 "specific_energy": f"{_SEED_000} Sec. 4.2, Eq. (55)"}),
    "tnt": JWLExplosive(
        A=3.712e11, B=3.21e9, R1=4.15, R2=0.95, omega=0.3, E0=6.993e9, density=1630.0,
        detonation_velocity=6930.0,
        description="TNT, JWL set of seed 000 (B = 3.21 GPa as printed, ERRATA 000-7)",
        sources={k: f"{_SEED_000} Sec. 4.1, from Liu, Liu, Lam & Zong (2003a)"
                 for k in ("A", "B", "R1", "R2", "omega", "E0", "density", "detonation_velocity")}),
}
