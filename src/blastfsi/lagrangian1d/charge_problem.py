"""Seed 000 Sec. 4.1, the 1D "real detonation": a high-explosive charge centred at
r = 0 in air, lit at the centre and burnt by the programmed burn of 000
Eqs. (52)-(53), on the ``lagrangian1d`` method (planar, cylindrical or spherical).

Zoning: ``grid.cells`` equal zones across the charge radius R (h = R / cells,
the h of Eq. 53); the air zones start at width ``grid.first_ratio`` h (at most R/4) and grow by ``grid.growth``
per zone up to ``grid.max_ratio`` h, to the outer radius ``domain.length``
(the last zone is stretched to end there exactly). Refining ``grid.cells``
refines the whole grid in proportion.

Materials: the explosive (JWL, 000 Eq. 54) at rest at its density rho0 with
specific internal energy E0 / rho0 (the products released with the seed's
detonation energy); the air at rest at the ambient state. Unless ``[gas]`` is
given, the ambient air is the library's ``air`` (seed 000 Sec. 4.2: rho = 1.225
kg/m^3, e = 2.0685e5 J/kg, gamma = 1.4, p = 101.36 kPa), not the 002 air the
plate problems default to. Lighting time t_L = (zone-centre distance from the
centre) / D; air zones are never lit (t_L = -inf: F = 1).

Outer end: open at the ambient pressure (a free end of zero mass) unless a
``[plate]`` is given (then the 002 plate or rigid wall).

Afterburning (optional, ``charge.afterburn_energy`` Q > 0): each explosive zone gains specific
internal energy at the constant rate Q / (rho0 (t_e - t_s)) over [t_s, t_e) =
[``afterburn_start``, ``afterburn_end``) (:func:`blastfsi.lagrangian1d.scheme.afterburn_increment`),
Q x charge volume in all. The release is restricted to burnt products (F = 1), and t_s must be at
least (R + h) / D, the time the programmed burn of the last zone completes, so that no zone is
partly burnt during the release and the whole of Q is released.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from blastfsi.lagrangian1d.scheme import Boundaries, Numerics, zone_volume
from blastfsi.materials import LIBRARY, MaterialError, lookup
from blastfsi.materials.gases import GASES, JWLExplosive
from blastfsi.scenario import ScenarioError

if TYPE_CHECKING:  # annotations only: the scenario validates a [charge] with this module's functions
    from blastfsi.lagrangian1d.scenario import Scenario

GEOMETRY = {"planar": 0, "cylindrical": 1, "spherical": 2}
MEASURE = {0: 1.0, 1: 2.0 * np.pi, 2: 4.0 * np.pi}  # physical amount per radian^j quantity
EXPLOSIVES = tuple(sorted(n for n, m in GASES.items() if isinstance(m, JWLExplosive)))


@dataclass(frozen=True)
class ChargeInfo:
    """The charge and ambient air of a charge run. Amounts "per geometry" are kg (J) for a
    sphere, per metre of a cylinder, per m^2 of the half slab (planar)."""

    charge_mass: float  # [kg per geometry]
    charge_radius: float  # R [m]
    charge_zone_width: float  # h = R / grid.cells, of 000 Eq. (53) [m]
    detonation_velocity: float  # D [m/s]
    explosive: str  # material library name
    explosive_energy: float  # E0 x charge volume [J per geometry]
    ambient_pressure: float  # [Pa]
    ambient_density: float  # [kg/m^3]
    gamma: float  # of the ambient air [-]
    geometry: str  # "planar", "cylindrical" or "spherical"
    measure: float  # physical amount per radian^j quantity (MEASURE) [-]
    plate_areal_mass: float  # [kg/m^2]; 0 without a plate or for a rigid wall
    afterburn_energy: float  # charge.afterburn_energy x charge volume [J per geometry]


@dataclass(frozen=True)
class Setup:
    """Initial data of a charge run (NumPy, host side); the fields of
    :class:`blastfsi.lagrangian1d.plate_problem.Setup`, with ``charge`` in place of ``theory``, plus
    geometry and per-zone materials."""

    x: np.ndarray  # node radii (N+1,)
    v: np.ndarray
    e: np.ndarray  # zone specific internal energy (N,)
    zone_mass: np.ndarray  # (N,) kg per radian^j (per m^2 in planar)
    numerics: Numerics  # of Python floats
    boundaries: Boundaries  # of Python floats
    left_velocity_set: bool
    right_fixed: bool
    geometry: int  # j
    zones: tuple  # scheme.Zones fields as NumPy arrays (N,)
    explosive_zones: int  # zones 0 .. explosive_zones-1 hold the explosive
    arrival_fraction: float  # output.arrival_fraction: a gauge's arrival overpressure, of p0
    charge: ChargeInfo
    gauges: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ambient_pressure: float = 0.0
    afterburn: tuple | None = None  # scheme.Afterburn fields (rate (N,), start, end); None: no afterburning

    @property
    def cells(self) -> int:
        return self.zone_mass.size


def explosive(name: str, field_name: str = "charge.explosive", overrides: dict | None = None) -> JWLExplosive:
    """The JWL explosive ``name`` from the material library with the scenario's ``[materials.<name>]``
    ``overrides`` applied; ScenarioError for anything else (an override out of range: naming it)."""
    if name not in LIBRARY:
        raise ScenarioError(f"{field_name}: unknown explosive {name!r}; available: {', '.join(EXPLOSIVES)}")
    try:
        mat = lookup(name, overrides, field=field_name)
    except MaterialError as err:
        raise ScenarioError(str(err)) from None
    if not isinstance(mat, JWLExplosive):
        raise ScenarioError(f"{field_name}: {name!r} is not an explosive; available: {', '.join(EXPLOSIVES)}")
    return mat


def charge_explosive(sc: Scenario) -> JWLExplosive:
    """The explosive of the scenario's ``[charge]``, its ``[materials]`` overrides applied."""
    return explosive(sc.charge.explosive, overrides=sc.materials.get(sc.charge.explosive))


def charge_radius(mass: float, density: float, j: int) -> float:
    """R of a charge of ``mass`` (kg, kg/m, kg/m^2 of the half slab for j = 2, 1, 0)."""
    return (mass * (j + 1) / (MEASURE[j] * density)) ** (1.0 / (j + 1))


def charge_mass(radius: float, density: float, j: int) -> float:
    return MEASURE[j] * density * radius ** (j + 1) / (j + 1)


def graded_nodes(radius: float, cells: int, length: float, growth: float, max_ratio: float,
                 first_ratio: float) -> np.ndarray:
    """Node radii: ``cells`` equal zones on [0, radius], then air zones from width ``first_ratio`` h
    (at most radius / 4: a wider first air zone is crushed by the products) growing by ``growth``
    up to ``max_ratio`` h until ``length`` (last zone merged so that it ends at length)."""
    h = radius / cells
    widths, total, w = [], radius, min(first_ratio * h, 0.25 * radius)
    while total < length:
        widths.append(w)
        total += w
        w = min(w * growth, max_ratio * h)
    air = np.cumsum(widths)
    air = radius + air * (length - radius) / air[-1]  # stretch by < one zone width to end at length
    if air.size > 1 and air[-1] - air[-2] < 0.5 * widths[-1]:
        air = np.delete(air, -2)
    return np.concatenate([np.linspace(0.0, radius, cells + 1), air])


def charge_size(sc: Scenario) -> tuple[float, float]:
    """(radius [m], mass [kg, kg/m or kg/m^2]) of the scenario's charge."""
    ch = sc.charge
    j = GEOMETRY[sc.domain.geometry]
    hx = charge_explosive(sc)
    radius = ch.radius if ch.radius is not None else charge_radius(ch.mass, hx.density, j)
    return radius, charge_mass(radius, hx.density, j)


def build(sc: Scenario) -> Setup:
    ch = sc.charge
    j = GEOMETRY[sc.domain.geometry]
    hx = charge_explosive(sc)
    D = ch.detonation_velocity or hx.detonation_velocity
    radius, mass = charge_size(sc)
    if radius >= sc.domain.length:
        raise ScenarioError(f"charge radius {radius:.6g} m must be < domain.length ({sc.domain.length} m): "
                            "the charge lies outside the domain")
    if "gas" in sc.model_fields_set:
        gamma, rho_a, p_a = sc.gas.gamma, sc.gas.density, sc.gas.pressure
    else:
        air = GASES["air"]
        gamma, rho_a, p_a = air.gamma, air.density, air.pressure
    x = graded_nodes(radius, sc.grid.cells, sc.domain.length, sc.grid.growth, sc.grid.max_ratio,
                     sc.grid.first_ratio)
    n, nc = x.size - 1, sc.grid.cells
    hx_zone = np.arange(n) < nc
    centre = 0.5 * (x[1:] + x[:-1])
    rho = np.where(hx_zone, hx.density, rho_a)
    e = np.where(hx_zone, hx.E0 / hx.density, p_a / ((gamma - 1.0) * rho_a))
    h = radius / nc
    eos = hx.eos_params()
    zones = (np.where(hx_zone, eos.A, 0.0), np.where(hx_zone, eos.B, 0.0), np.where(hx_zone, eos.R1, 1.0),
             np.where(hx_zone, eos.R2, 1.0), np.where(hx_zone, eos.omega, gamma - 1.0),
             np.where(hx_zone, eos.rho0, 1.0),
             np.where(hx_zone, centre / D, -np.inf),  # 000 Sec. 4.1: t_L = distance / D
             np.full(n, D / (1.5 * h)))  # 000 Eq. (53)
    plate = sc.plate
    right_fixed = plate is not None and plate.fixed
    right_mass = 0.0 if plate is None or plate.fixed else (
        plate.areal_mass if plate.areal_mass is not None else plate.density * plate.thickness)
    back = p_a if plate is None or plate.back_pressure is None else plate.back_pressure
    afterburn = None
    if ch.afterburn_energy > 0.0:
        burnt = float(np.max((zones[6] + 1.0 / zones[7])[:nc]))  # (R + h) / D: the last zone's F reaches 1
        if ch.afterburn_start < burnt:
            raise ScenarioError(f"charge.afterburn_start ({ch.afterburn_start:.6g} s) must be >= {burnt:.6g} s, the "
                                "time the programmed burn of this charge completes ((R + h) / D): the afterburning "
                                "energy is released in burnt products only")
        rate = ch.afterburn_energy / (hx.density * (ch.afterburn_end - ch.afterburn_start))
        afterburn = (np.where(hx_zone, rate, 0.0), ch.afterburn_start, ch.afterburn_end)
    charge = ChargeInfo(charge_mass=mass, charge_radius=radius, charge_zone_width=h, detonation_velocity=D,
                        explosive=ch.explosive, explosive_energy=hx.E0 * mass / hx.density,
                        ambient_pressure=p_a, ambient_density=rho_a, gamma=gamma, geometry=sc.domain.geometry,
                        measure=MEASURE[j], plate_areal_mass=right_mass,
                        afterburn_energy=ch.afterburn_energy * mass / hx.density)
    return Setup(x=x, v=np.zeros_like(x), e=e, zone_mass=rho * zone_volume(x, j),
                 numerics=Numerics(gamma, sc.numerics.K1, sc.numerics.K2, sc.numerics.cfl),
                 boundaries=Boundaries(0.0, p_a, right_mass, back), left_velocity_set=True, right_fixed=right_fixed,
                 geometry=j, zones=zones, explosive_zones=nc, charge=charge,
                 gauges=np.asarray(sc.output.gauges, float), ambient_pressure=p_a,
                 arrival_fraction=sc.output.arrival_fraction, afterburn=afterburn)
