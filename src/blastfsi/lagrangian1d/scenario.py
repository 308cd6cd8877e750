"""Scenario model of the ``lagrangian1d`` method. Either

* ``[incident]`` + ``[plate]``: a planar gas column between a piston (or
  symmetry plane) at x = 0 and a free-standing plate at x = length (seed 002); or
* ``[charge]``: a high-explosive charge centred at r = 0 in air (seed 000
  Sec. 4.1, the 1D "real detonation"), planar, cylindrical or spherical
  (``domain.geometry``); the outer end at r = length is open at the ambient
  pressure unless a ``[plate]`` is given.

Shared tables come from :mod:`blastfsi.scenario`."""
from __future__ import annotations

import copy
from typing import Annotated, ClassVar, Literal, Optional, Union

from pydantic import Field, model_validator

from blastfsi.lagrangian1d.charge_problem import GEOMETRY, charge_explosive, charge_radius
from blastfsi.materials import check_overrides
from blastfsi.scenario import Numerics as SharedNumerics
from blastfsi.scenario import Output as SharedOutput
from blastfsi.scenario import Demand, Devices, ScenarioBase, Strict, Sweep as SharedSweep, gauge_points


# Ambient air of 002 Sec. 3 (ERRATA 002-7): p0 = 1.048 bar, rho0 = 1.225 kg/m^3, gamma = 1.4.
class Gas(Strict):
    gamma: float = Field(1.4, gt=1.0, le=5.0 / 3.0, description="ratio of specific heats [-]")
    pressure: float = Field(1.048e5, gt=0.0, description="ambient pressure p0 [Pa]")
    density: float = Field(1.225, gt=0.0, description="ambient density rho0 [kg/m^3]")


class UniformIncident(Strict):
    """Uniform (step) shock driven by a piston at the left end (002 Sec. 3.1-3.2)."""

    profile: Literal["uniform"]
    overpressure: float = Field(gt=0.0, le=1e10, description="incident shock overpressure p_s [Pa]")


class ExponentialIncident(Strict):
    """Exponentially decaying blast initialised in the gas (002 Sec. 3.3)."""

    profile: Literal["exponential"]
    overpressure: float = Field(gt=0.0, le=1e10, description="initial peak overpressure p_i [Pa]")
    decay_length: float = Field(gt=0.0, description="e-folding length d_i of the overpressure [m]")
    standoff: float = Field(gt=0.0, description="distance from the initial front to the plate [m]")
    ramp_cells: int = Field(10, ge=1, le=1000, description="cells of the linear pressure ramp at the front")


class SedovIncident(Strict):
    """Planar von Neumann-Sedov point explosion (002 Sec. 3.4), symmetry plane at x = 0."""

    profile: Literal["sedov"]
    energy: float = Field(gt=0.0, description="explosion energy per unit area, one side of the plane, E0 [J/m^2]")
    front_position: float = Field(gt=0.0, description="shock position at the start of the run [m]")
    core_fraction: float = Field(0.1, ge=0.0, lt=0.5, description=(
        "zones closer to the centre than this fraction of front_position are merged into a core of uniform "
        "density and internal energy (same mass and energy); 0 keeps the exact singular profile"))


Incident = Annotated[Union[UniformIncident, ExponentialIncident, SedovIncident], Field(discriminator="profile")]


class Plate(Strict):
    """Free-standing rigid plate at the right end of the gas column (002 Eq. 7).

    Give exactly one of ``areal_mass``, ``beta_s`` (uniform shocks only) or
    ``density`` with ``thickness``; or set ``fixed = true`` for a rigid wall.
    """

    fixed: bool = Field(False, description="a rigid, immovable wall instead of a free-standing plate")
    areal_mass: Optional[float] = Field(None, ge=0.0, description=(
        "rho_p h_p [kg/m^2]; 0 makes the end a free surface held at back_pressure"))
    beta_s: Optional[float] = Field(None, gt=0.0, description="compressible FSI parameter, Eq. (28) [-]")
    density: Optional[float] = Field(None, gt=0.0, description="plate density rho_p [kg/m^3]")
    thickness: Optional[float] = Field(None, gt=0.0, description="plate thickness h_p [m]")
    back_pressure: Optional[float] = Field(None, ge=0.0, description="pressure on the free side [Pa]; default p0")

    @model_validator(mode="after")
    def _one_mass(self):
        if (self.density is None) != (self.thickness is None):
            raise ValueError("plate.density and plate.thickness must be given together")
        given = [n for n, v in (("areal_mass", self.areal_mass), ("beta_s", self.beta_s),
                                ("density/thickness", self.density)) if v is not None]
        if self.fixed and given:
            raise ValueError(f"plate.fixed = true takes no mass, but {given} given")
        if not self.fixed and len(given) != 1:
            raise ValueError("give exactly one of plate.areal_mass, plate.beta_s or plate.density+plate.thickness "
                             f"(or plate.fixed = true); got {given or 'none'}")
        return self


class Charge(Strict):
    """Explosive charge centred at r = 0 (a sphere, an infinite cylinder, or the slab |x| <= radius
    of which [0, radius] is simulated), lit at its centre and burnt by 000 Eqs. (52)-(53).
    Give exactly one of ``mass`` and ``radius``. Optional afterburning (off by default):
    ``afterburn_energy`` Q [J per m^3 of unreacted explosive] released in the burnt products at the
    constant rate Q / (rho0 (afterburn_end - afterburn_start)) per unit mass between
    ``afterburn_start`` and ``afterburn_end`` (s after lighting; Radioss LAW5 Eadd/Tstart/Tstop,
    LS-DYNA *EOS_JWL_AFTERBURN constant rate)."""

    explosive: str = Field("tnt", min_length=1, description="explosive from the material library (JWL)")
    mass: Optional[float] = Field(None, gt=0.0, le=1e7, description=(
        "charge mass: kg (spherical), kg/m (cylindrical), kg/m^2 of the half slab [0, radius] (planar)"))
    radius: Optional[float] = Field(None, gt=0.0, le=100.0, description="charge radius [m]")
    detonation_velocity: Optional[float] = Field(None, gt=0.0, le=2e4, description=(
        "D of the programmed burn [m/s]; default the explosive's"))
    afterburn_energy: float = Field(0.0, ge=0.0, le=1e12, description=(
        "afterburning: energy added to the detonation products per unit volume of unreacted explosive "
        "[J/m^3] (Radioss LAW5 Eadd), released at a constant rate between afterburn_start and "
        "afterburn_end; 0 (default): no afterburning"))
    afterburn_start: float = Field(0.0, ge=0.0, le=1e3, description=(
        "afterburning: start of the release [s after lighting] (Tstart); at least the time the "
        "programmed burn of the whole charge completes, (R + h) / D"))
    afterburn_end: Optional[float] = Field(None, gt=0.0, le=1e3, description=(
        "afterburning: end of the release [s after lighting] (Tstop), > afterburn_start; required "
        "with afterburn_energy > 0"))

    @model_validator(mode="after")
    def _one_size(self):
        if (self.mass is None) == (self.radius is None):
            raise ValueError("give exactly one of charge.mass and charge.radius")
        if self.afterburn_end is not None and self.afterburn_end <= self.afterburn_start:
            raise ValueError(f"charge.afterburn_end ({self.afterburn_end} s) must be > charge.afterburn_start "
                             f"({self.afterburn_start} s)")
        if self.afterburn_energy > 0.0 and self.afterburn_end is None:
            raise ValueError("charge.afterburn_end: required when charge.afterburn_energy > 0 (the release "
                             "window is [afterburn_start, afterburn_end))")
        return self


class Domain(Strict):
    length: float = Field(gt=0.0, le=1e5, description=(
        "initial gas column length; the plate (or the open end of a charge domain) sits at x = length [m]"))
    geometry: Literal["planar", "cylindrical", "spherical"] = Field("planar", description=(
        "planar, cylindrical or spherical (radius x); the plate problems ([incident]) are planar"))


class Grid(Strict):
    cells: int = Field(ge=10, le=10_000_000, description=(
        "number of Lagrangian zones; with a [charge]: zones across the charge radius (uniform)"))
    growth: float = Field(1.05, ge=1.0, le=1.2, description=(
        "[charge] width ratio of neighbouring air zones, growing away from the charge"))
    first_ratio: float = Field(100.0, ge=0.1, le=1e4, description=(
        "[charge] width of the first air zone / charge zone width"))
    max_ratio: float = Field(100.0, ge=1.0, le=1e5, description=(
        "[charge] largest air zone width / charge zone width (the air zones stop growing there)"))


class Output(SharedOutput):
    arrival_fraction: float = Field(0.01, gt=0.0, le=10.0, description=(
        "gauge arrival time = first time the overpressure exceeds this fraction of the ambient pressure"))


class Numerics(SharedNumerics):
    # Defaults chosen in docs/theory/lagrangian1d.md: K1^2 = 2.25 spreads a shock over ~3 zones,
    # K2 = 0.1 damps post-shock ringing; alpha = cfl = 0.5 leaves margin below the bound.
    K1: float = Field(1.5, ge=0.0, le=5.0, description="quadratic viscosity coefficient, Eq. (5)")
    K2: float = Field(0.1, ge=0.0, le=2.0, description="linear viscosity coefficient, Eq. (5)")
    cfl: float = Field(0.5, gt=0.0, le=1.0, description="time-step factor alpha, Eq. (20)")
    devices: Devices = Field(1, description=(
        "devices (GPUs of this machine; an integer >= 1) the members of a [sweep] are spread over, in equal "
        "shares (the member count divisible by it); each member's chain stays whole on one device (10^3-10^5 "
        "zones: splitting it would only add an exchange to every step); 'all': every device JAX sees. "
        "Results equal one device's"))


# Numbers per zone the compiled vNR loop holds (state and the step's temporaries); XLA's memory analysis of
# plate1d-uniform (5000 zones): 22.
WORDS_PER_ZONE = 24

PLATE_MASS_KEYS = ("areal_mass", "beta_s", "density", "thickness")


class Sweep(SharedSweep):
    TARGETS: ClassVar[dict[str, str]] = {"overpressure": "incident.overpressure", "beta_s": "plate.beta_s",
                                         "areal_mass": "plate.areal_mass", "thickness": "plate.thickness"}
    overpressure: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    beta_s: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    areal_mass: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    thickness: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)

    @model_validator(mode="after")
    def _one_mass_list(self):
        masses = [n for n in ("beta_s", "areal_mass", "thickness") if getattr(self, n) is not None]
        if len(masses) > 1:
            raise ValueError(f"sweep takes at most one of beta_s, areal_mass, thickness; got {masses}")
        return self


class Scenario(ScenarioBase):
    method: Literal["lagrangian1d"] = "lagrangian1d"
    gas: Gas = Gas()
    incident: Optional[Incident] = None
    charge: Optional[Charge] = None
    plate: Optional[Plate] = None
    domain: Domain
    grid: Grid
    materials: dict[str, dict[str, float]] = Field(default_factory=dict, description=(
        "overrides of the charge's explosive's library constants, e.g. {tnt = {E0 = 7.0e9}} (the ambient gas "
        "is [gas])"))
    numerics: Numerics = Numerics()
    output: Output = Output()
    sweep: Optional[Sweep] = None

    @model_validator(mode="after")
    def _consistent(self):
        if (self.incident is None) == (self.charge is None):
            raise ValueError("give exactly one of [incident] (a blast on a plate, seed 002) and [charge] "
                             "(an explosive detonated at r = 0)")
        check_overrides(self.materials, {} if self.charge is None else {self.charge.explosive: "charge.explosive"})
        if self.charge is not None:
            return self._charge_consistent()
        if self.plate is None:
            raise ValueError("plate: missing required key (an [incident] blast needs a [plate])")
        if self.domain.geometry != "planar":
            raise ValueError(f"domain.geometry = {self.domain.geometry!r}: the [incident] plate problems are "
                             "planar; curved geometry needs a [charge]")
        inc = self.incident
        if self.plate.beta_s is not None and inc.profile != "uniform":
            raise ValueError("plate.beta_s is defined for uniform shocks only; give plate.areal_mass")
        if self.sweep is not None:
            if self.sweep.overpressure is not None and inc.profile == "sedov":
                raise ValueError("sweep.overpressure does not apply to a sedov incident profile")
            if self.sweep.beta_s is not None and inc.profile != "uniform":
                raise ValueError("sweep.beta_s is defined for uniform shocks only")
            if self.sweep.thickness is not None and self.plate.density is None:
                raise ValueError("sweep.thickness needs plate.density")
            mass_sweep = any(getattr(self.sweep, n) is not None for n in ("beta_s", "areal_mass", "thickness"))
            if self.plate.fixed and mass_sweep:
                raise ValueError("a plate-mass sweep needs plate.fixed = false")
        if inc.profile == "exponential":
            if inc.standoff >= self.domain.length:
                raise ValueError(f"incident.standoff ({inc.standoff} m) must be < domain.length "
                                 f"({self.domain.length} m)")
            dx = self.domain.length / self.grid.cells
            if inc.ramp_cells * dx >= self.domain.length - inc.standoff:
                raise ValueError("incident.ramp_cells span more than the gas behind the front")
        if inc.profile == "sedov" and inc.front_position >= self.domain.length:
            raise ValueError(f"incident.front_position ({inc.front_position} m) must be < domain.length "
                             f"({self.domain.length} m)")
        gauge_points(self.output.gauges, 1, (0.0,), (self.domain.length,))
        return self

    def _charge_consistent(self):
        charge_explosive(self)  # a JWL explosive of the library, within its ranges with the overrides
        if self.sweep is not None:
            raise ValueError("sweep: the plate sweeps need an [incident]; a [charge] run takes no sweep")
        if self.plate is not None and self.plate.beta_s is not None:
            raise ValueError("plate.beta_s is defined for uniform shocks only; give plate.areal_mass")
        gauge_points(self.output.gauges, 1, (0.0,), (self.domain.length,))
        return self

    def demands(self) -> list[Demand]:
        """The zones: grid.cells, or with a [charge] the zones across its radius R (width h = R / cells) plus
        the air zones out to domain.length, none narrower than min(first_ratio, max_ratio) h."""
        zones = float(self.grid.cells)
        if self.charge is not None:
            c, g = self.charge, self.grid
            j = GEOMETRY[self.domain.geometry]
            radius = c.radius or charge_radius(c.mass, charge_explosive(self).density, j)
            zones += self.domain.length / (min(g.first_ratio, g.max_ratio) * radius / g.cells)
        return super().demands() + [Demand("grid.cells", zones, "zones", WORDS_PER_ZONE)]

    @classmethod
    def member_data(cls, data: dict, member: dict) -> dict:
        """A swept plate mass replaces whichever plate mass the scenario gives."""
        d = copy.deepcopy(data)
        if any(k in member for k in ("plate.areal_mass", "plate.beta_s")):
            for k in PLATE_MASS_KEYS:
                d.get("plate", {}).pop(k, None)
        return super().member_data(d, member)
