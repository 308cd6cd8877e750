"""Solids of the MPM solver: linear elastic, Johnson-Cook metals, HJC concrete, Drucker-Prager soil.

Every entry is a frozen dataclass with numeric constants (SI units) and a
``sources`` mapping giving the reference of each constant; ``model`` names the
registered constitutive model (:mod:`blastfsi.constitutive`) that reads it.

Abbreviations used in the sources:
* SEED: seed 000 (Cui et al., CFDMP), Sec. 4.3-4.5.
* JC83: G.R. Johnson, W.H. Cook, "A constitutive model and data for metals subjected
  to large strains, high strain rates and high temperatures", 7th Int. Symp. Ballistics,
  The Hague (1983), Table 1; the 4340 constants also in Johnson & Cook, Eng. Fract. Mech.
  21 (1985) 31-48. OFHC copper C = 0.025 (not the 0.0025 typo, ERRATA "Material models").
* HJC93: T.J. Holmquist, G.R. Johnson, W.H. Cook, "A computational constitutive model for
  concrete subjected to large strains, high strain rates, and high pressures", 14th Int.
  Symp. Ballistics, Quebec (1993), constants for the 48 MPa concrete.
* CALLISTER: W.D. Callister, Materials Science and Engineering: An Introduction, Table 6.1
  (room-temperature E, G, nu of metal alloys) and Appendix B (plain carbon steel 1020).
* STEINBERG: D.J. Steinberg, "Equation of state and strength properties of selected
  materials", LLNL UCRL-MA-106439 (1996) (Cu: C0, S1, gamma0 as in Marsh, LASL Shock
  Hugoniot Data, 1980).
* ACI318: ACI 318-19 Sec. 19.2.2.1, E_c = 4700 sqrt(f_c') [MPa] (E_c proportional to sqrt(f_c')).
* FLAC3D: Itasca, FLAC3D Constitutive Models (2005), Drucker-Prager model (the seed's
  Eqs. 59-63); tension and dilation properties default to 0.
* ISO554: ISO 554 standard atmosphere for testing, 20 C.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from blastfsi.materials.ranges import Order, constant

# Reasons shared by several families (materials.ranges: every constant has a range and its physical reason).
_DENSITY = "a mass per unit volume is positive"
_MODULUS = "an elastic modulus is positive, or the material has no stiffness (or a negative one)"
_POISSON = "-1 < nu < 0.5 keeps the bulk and shear moduli positive (a stable, positive-definite elasticity)"
_STRENGTH = "a strength (stress) is non-negative"
_RATE0 = "reference strain rate: the log-rate term ln(rate / rate0) needs rate0 > 0"
_NONNEG = "a hardening or rate coefficient < 0 would soften the material as it is loaded harder"


@dataclass(frozen=True)
class LinearElasticSolid:
    model: ClassVar[str] = "elastic"
    density: float = constant(_DENSITY, gt=0.0)  # [kg/m^3]
    youngs_modulus: float = constant(_MODULUS, gt=0.0)  # E [Pa]
    poisson_ratio: float = constant(_POISSON, gt=-1.0, lt=0.5)  # nu [-]
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class JohnsonCookSolid:
    """Johnson-Cook strength (000 Eq. 64) + Mie-Grueneisen EOS (000 Eqs. 65-66)."""
    model: ClassVar[str] = "johnson-cook"
    ORDER: ClassVar[tuple] = (Order("room_temperature", "melt_temperature", "the homologous temperature "
                                    "T* = (T - T_room) / (T_melt - T_room) needs a melting point above room "
                                    "temperature"),)
    density: float = constant(_DENSITY, gt=0.0)  # reference density rho0 [kg/m^3]
    shear_modulus: float = constant(_MODULUS, gt=0.0)  # G [Pa]
    A: float = constant("yield stress: " + _STRENGTH, ge=0.0)  # yield stress [Pa]
    B: float = constant("hardening modulus: " + _NONNEG, ge=0.0)  # hardening modulus [Pa]
    n: float = constant("hardening exponent: B eps_p^n hardens monotonically only for n >= 0 (n < 0 is "
                        "infinite at yield)", ge=0.0)  # hardening exponent [-]
    C: float = constant("strain-rate coefficient: " + _NONNEG, ge=0.0)  # strain-rate coefficient [-]
    m: float = constant("thermal-softening exponent: 1 - T*^m falls from 1 at room temperature to 0 at melt "
                        "only for m > 0", gt=0.0)  # thermal-softening exponent [-]
    reference_strain_rate: float = constant(_RATE0, gt=0.0)  # [1/s]
    room_temperature: float = constant("an absolute temperature is positive", gt=0.0)  # [K]
    melt_temperature: float = constant("an absolute temperature is positive", gt=0.0)  # [K]
    specific_heat: float = constant("heat raises the temperature: c_p > 0", gt=0.0)  # c_p [J/(kg K)]
    taylor_quinney: float = constant("a fraction of the plastic work", ge=0.0, le=1.0)  # to heat [-]
    C0: float = constant("the bulk sound speed is positive", gt=0.0)  # Hugoniot U_s = C0 + S u_p intercept [m/s]
    S: float = constant("Hugoniot slope: the shock speed does not fall with the particle speed", ge=0.0)  # [-]
    gamma0: float = constant("Grueneisen coefficient: heating at constant volume raises the pressure",
                             ge=0.0)  # [-]
    a: float = constant("first-order volume correction of Gamma = gamma0 + a mu: a >= 0 keeps Gamma >= 0 "
                        "under compression", ge=0.0)  # [-]
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class HJCConcrete:
    """Holmquist-Johnson-Cook concrete (000 Eqs. 56-57) with Jiang tensile damage (000 Eq. 58)."""
    model: ClassVar[str] = "hjc"
    ORDER: ClassVar[tuple] = (
        Order("P_crush", "P_lock", "the compaction (crush) line runs from P_crush up to P_lock"),
        Order("initial_tensile_damage", "tensile_damage_limit", "tensile damage grows from its initial value "
                                                                "to the spall limit"))
    density: float = constant(_DENSITY, gt=0.0)  # rho0 [kg/m^3]
    shear_modulus: float = constant(_MODULUS, gt=0.0)  # G [Pa]
    fc: float = constant("the normalising compressive strength f_c' > 0 (stresses are divided by it)",
                         gt=0.0)  # quasi-static uniaxial compressive strength f_c' [Pa]
    A: float = constant("normalised cohesion: " + _STRENGTH, ge=0.0)  # normalised cohesive strength [-]
    B: float = constant("pressure hardening: " + _NONNEG, ge=0.0)  # normalised pressure hardening [-]
    N: float = constant("pressure-hardening exponent: B P*^N rises with pressure only for N > 0",
                        gt=0.0)  # [-]
    C: float = constant("strain-rate coefficient: " + _NONNEG, ge=0.0)  # [-]
    SMAX: float = constant("the normalised strength cap is positive", gt=0.0)  # normalised maximum strength [-]
    reference_strain_rate: float = constant(_RATE0, gt=0.0)  # [1/s]
    T: float = constant("tensile strength (normalises T* = T / f_c'): the concrete holds some tension",
                        gt=0.0)  # maximum tensile hydrostatic pressure [Pa]
    D1: float = constant("damage constant: the plastic strain to fracture D1 (P* + T*)^D2 is positive",
                         gt=0.0)  # [-]
    D2: float = constant("damage exponent: the strain to fracture grows with pressure", ge=0.0)  # [-]
    EFMIN: float = constant("minimum strain to fracture: damage divides the plastic strain by it",
                            gt=0.0)  # [-]
    P_crush: float = constant("crush pressure: the end of the elastic range lies in compression", gt=0.0)  # [Pa]
    mu_crush: float = constant("volumetric strain at P_crush: compression is positive", gt=0.0)  # [-]
    K1: float = constant("bulk modulus of the fully dense material: " + _MODULUS, gt=0.0)  # [Pa]
    K2: float = constant("second-order coefficient of the dense curve: either sign (HJC 1993 has K2 < 0); "
                         "P_lock must be reached (checked by the model)", ge=-1e15, le=1e15)  # [Pa]
    K3: float = constant("third-order coefficient of the dense curve: either sign, as K2", ge=-1e15,
                         le=1e15)  # [Pa]
    P_lock: float = constant("locking pressure (full compaction) lies in compression", gt=0.0)  # [Pa]
    mu_lock: float = constant("locking volumetric strain: compression is positive", gt=0.0)  # [-]
    tensile_damage_rate: float = constant("Jiang growth rate: damage does not heal", ge=0.0)  # Jiang a [1/s]
    tensile_threshold: float = constant("Jiang over-stress normalisation sigma_0: a positive stress",
                                        gt=0.0)  # Jiang sigma_0 [Pa]
    tensile_exponent: float = constant("Jiang exponent: damage grows with the over-stress", gt=0.0)  # gamma [-]
    initial_tensile_damage: float = constant("Eq. 58 is logistic: D_t = 0 never grows, D_t = 1 is spalled",
                                             gt=0.0, lt=1.0)  # D_t at t = 0 [-]
    tensile_damage_limit: float = constant("a damage fraction; Eq. 58 tends to 1 only asymptotically",
                                           gt=0.0, lt=1.0)  # spall when D_t reaches it [-]
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class DruckerPragerSoil:
    """Drucker-Prager with shear and tension failure (000 Eqs. 59-63)."""
    model: ClassVar[str] = "drucker-prager"
    ORDER: ClassVar[tuple] = (Order("dilation_angle", "friction_angle", "a soil dilates no more than the "
                                    "associated flow rule (psi <= phi) would make it", strict=False),)
    density: float = constant(_DENSITY, gt=0.0)  # [kg/m^3]
    youngs_modulus: float = constant(_MODULUS, gt=0.0)  # [Pa]
    poisson_ratio: float = constant(_POISSON, gt=-1.0, lt=0.5)  # [-]
    cohesion: float = constant("cohesion: " + _STRENGTH, ge=0.0)  # c [Pa]
    friction_angle: float = constant("an angle of internal friction in [0, 90) degrees (tan(phi) finite)",
                                     ge=0.0, lt=90.0)  # phi [degrees]
    dilation_angle: float = constant("a dilation angle in [0, 90) degrees", ge=0.0, lt=90.0)  # psi [degrees]
    tensile_strength: float = constant("tensile strength: " + _STRENGTH, ge=0.0)  # sigma^t [Pa] (capped at the
    #                                                                                apex k_phi/q_phi)
    description: str = ""
    sources: dict = field(default_factory=dict, compare=False)


# --- steels and copper ----------------------------------------------------------------------

_JC_4340_THERMAL = {"density": "JC83 Table 1, 4340 steel (7830 kg/m^3)",
                    "specific_heat": "JC83 Table 1, 4340 steel (477 J/kg K)",
                    "melt_temperature": "JC83 Table 1, 4340 steel (1793 K)"}
_COMMON_STEEL = {"shear_modulus": "CALLISTER Table 6.1, steel (83 GPa)",
                 "room_temperature": "ISO554 (20 C = 293.15 K)",
                 "taylor_quinney": "Taylor & Quinney, Proc. R. Soc. A 143 (1934) 307: ~0.9 of plastic work to heat",
                 "a": "000 Eq. (65) as printed has a constant Gamma (a = 0)"}
_SEED_HUGONIOT = {k: "SEED Sec. 4.5 (gamma = 2.17, C0 = 4569 m/s, S = 1.49)" for k in ("C0", "S", "gamma0")}

_RHA_SOURCES = {
    **_JC_4340_THERMAL, **_COMMON_STEEL, **_SEED_HUGONIOT,
    **{k: "SEED Sec. 4.5, from Neuberger, Peles & Rittel (2007), RHA steel"
       for k in ("A", "B", "n", "C", "m", "reference_strain_rate")},
}

SOLIDS = {
    "elastic-steel": LinearElasticSolid(
        density=7850.0, youngs_modulus=207e9, poisson_ratio=0.30,
        description="linear elastic plain carbon steel (AISI 1020), for verification",
        sources={"density": "CALLISTER App. B, steel 1020 (7.85 g/cm^3)",
                 "youngs_modulus": "CALLISTER Table 6.1, steel (207 GPa)",
                 "poisson_ratio": "CALLISTER Table 6.1, steel (0.30)"}),
    "steel-rha": JohnsonCookSolid(
        density=7830.0, shear_modulus=83e9, A=950e6, B=560e6, n=0.26, C=0.014, m=1.0,
        reference_strain_rate=1.0, room_temperature=293.15, melt_temperature=1793.0,
        specific_heat=477.0, taylor_quinney=0.9, C0=4569.0, S=1.49, gamma0=2.17, a=0.0,
        description="RHA armour steel of seed 000 Sec. 4.5/5.4 (JC strength of Neuberger et al. 2007, "
                    "seed Hugoniot; density and thermal constants of the similar Ni-Cr-Mo steel 4340)",
        sources=_RHA_SOURCES),
    "steel-4340": JohnsonCookSolid(
        density=7830.0, shear_modulus=83e9, A=792e6, B=510e6, n=0.26, C=0.014, m=1.03,
        reference_strain_rate=1.0, room_temperature=293.15, melt_temperature=1793.0,
        specific_heat=477.0, taylor_quinney=0.9, C0=4569.0, S=1.49, gamma0=2.17, a=0.0,
        description="AISI 4340 steel (Rockwell C30), Johnson-Cook 1983/1985",
        sources={**_JC_4340_THERMAL, **_COMMON_STEEL, **_SEED_HUGONIOT,
                 **{k: "JC83 Table 1 / Johnson & Cook (1985) Table 1, 4340 steel"
                    for k in ("A", "B", "n", "C", "m")},
                 "reference_strain_rate": "JC83 (1 /s)"}),
    "copper-ofhc": JohnsonCookSolid(
        density=8960.0, shear_modulus=46e9, A=90e6, B=292e6, n=0.31, C=0.025, m=1.09,
        reference_strain_rate=1.0, room_temperature=293.15, melt_temperature=1356.0,
        specific_heat=383.0, taylor_quinney=0.9, C0=3940.0, S=1.489, gamma0=2.02, a=0.0,
        description="OFHC copper (Rockwell F-30), Johnson-Cook 1983",
        sources={**{k: "JC83 Table 1, OFHC copper"
                    for k in ("density", "specific_heat", "melt_temperature", "A", "B", "n", "C", "m")},
                 "reference_strain_rate": "JC83 (1 /s)",
                 "shear_modulus": "CALLISTER Table 6.1, copper (46 GPa)",
                 "room_temperature": _COMMON_STEEL["room_temperature"],
                 "taylor_quinney": _COMMON_STEEL["taylor_quinney"],
                 **{k: "STEINBERG, Cu (C0 = 3.94 km/s, S1 = 1.489, gamma0 = 2.02)" for k in ("C0", "S", "gamma0")},
                 "a": _COMMON_STEEL["a"]}),
}

# --- concrete ------------------------------------------------------------------------------

_HJC93_48 = dict(density=2440.0, shear_modulus=14.86e9, fc=48e6, A=0.79, B=1.60, N=0.61, C=0.007,
                 SMAX=7.0, reference_strain_rate=1.0, T=4e6, D1=0.04, D2=1.0, EFMIN=0.01,
                 P_crush=16e6, mu_crush=0.001, K1=85e9, K2=-171e9, K3=208e9, P_lock=0.8e9, mu_lock=0.1)

# Jiang (2010) is a thesis we could not obtain; Eq. (58) constants are ASSUMED, stated here:
_JIANG_ASSUMED = {
    "tensile_threshold": "ASSUMED = T (damage starts at the quasi-static tensile strength); "
                         "Jiang (2010) not available",
    "tensile_exponent": "ASSUMED 1 (linear over-stress growth, as the Curran-Seaman NAG growth law); "
                        "Jiang (2010) not available",
    "tensile_damage_rate": "ASSUMED 1e6 /s (ln(1/D_t0) ~ 7 e-foldings within ~10 us at over-stress 1, "
                           "spall times of concrete plate-impact tests); Jiang (2010) not available",
    "initial_tensile_damage": "ASSUMED 1e-3 (Eq. 58 needs D_t > 0 to grow)",
    "tensile_damage_limit": "ASSUMED 0.99 (Eq. 58 tends to 1 asymptotically)",
}


def _jiang(tensile_strength: float) -> dict:
    return dict(tensile_damage_rate=1e6, tensile_threshold=tensile_strength, tensile_exponent=1.0,
                initial_tensile_damage=1e-3, tensile_damage_limit=0.99)


_SCALE_25 = (25.0 / 48.0) ** 0.5  # elastic moduli and tensile strength scale with sqrt(f_c') (ACI318)
_K_ELASTIC_48 = _HJC93_48["P_crush"] / _HJC93_48["mu_crush"]  # 16 GPa
_P_CRUSH_25 = 25e6 / 3.0  # P_crush = f_c'/3, the pressure at failure in a uniaxial compression test (HJC93)

_CONCRETE_25 = {
    **_HJC93_48, "fc": 25e6, "shear_modulus": 14.86e9 * _SCALE_25, "T": 4e6 * _SCALE_25,
    "P_crush": _P_CRUSH_25, "mu_crush": _P_CRUSH_25 / (_K_ELASTIC_48 * _SCALE_25),
}

SOLIDS.update({
    "concrete-48mpa": HJCConcrete(
        **_HJC93_48, **_jiang(_HJC93_48["T"]),
        description="HJC 1993 concrete, f_c' = 48 MPa, with Jiang tensile damage (assumed constants)",
        sources={**{k: "HJC93" for k in _HJC93_48}, **_JIANG_ASSUMED}),
    "concrete-25mpa": HJCConcrete(
        **_CONCRETE_25, **_jiang(_CONCRETE_25["T"]),
        description="25 MPa concrete of seed 000 Sec. 5.3 (Luccioni & Luege 2006 slab), HJC 1993 set "
                    "scaled to f_c' = 25 MPa",
        sources={**{k: "HJC93 (normalised or fully-dense constant, independent of f_c')" for k in _HJC93_48},
                 "density": "HJC93 (2440 kg/m^3 kept: the seed and Luccioni & Luege give no density we could check)",
                 "fc": "SEED Sec. 5.3 (Luccioni & Luege 2006: 25 MPa)",
                 "shear_modulus": "HJC93 14.86 GPa x sqrt(25/48) (ACI318: moduli ~ sqrt(f_c'))",
                 "T": "HJC93 4 MPa x sqrt(25/48) (tensile strength ~ sqrt(f_c'), ACI318 Sec. 19.2.3)",
                 "P_crush": "f_c'/3 (HJC93: P_crush is the pressure at the uniaxial compressive strength)",
                 "mu_crush": "P_crush / K_elastic, K_elastic = HJC93 16 GPa x sqrt(25/48)",
                 **_JIANG_ASSUMED}),
})

# --- soil ----------------------------------------------------------------------------------

SOLIDS["soil-sec44"] = DruckerPragerSoil(
    density=1200.0, youngs_modulus=100e6, poisson_ratio=0.3, cohesion=0.11e6, friction_angle=20.0,
    dilation_angle=0.0, tensile_strength=0.0,
    description="soil of seed 000 Sec. 4.4 (from Luccioni & Luege 2006), Drucker-Prager",
    sources={**{k: "SEED Sec. 4.4, from Luccioni & Luege (2006)"
                for k in ("density", "youngs_modulus", "poisson_ratio", "cohesion", "friction_angle")},
             "dilation_angle": "FLAC3D default (0, non-dilatant); not given by the seed",
             "tensile_strength": "FLAC3D default (0); not given by the seed"})
