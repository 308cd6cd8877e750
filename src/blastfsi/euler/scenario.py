"""Scenario schema of the Eulerian method (``method = "euler"``).

Geometry is data: the domain, regions, charges and gauges are given in metres;
``grid.cells`` is the number of cells along x, every cell is a square/cube of
side dx = (upper - lower)_x / cells, and the other extents must hold a whole
number of cells.

Axes and geometries:

* ``cartesian`` in 1, 2 or 3 dimensions (x, y, z);
* ``cylindrical`` / ``spherical``: 1D radial, x is the radius r >= 0;
* ``axisymmetric``: 2D r-z, x is the radius r >= 0 and y the axial coordinate z.
"""
from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal, Optional, Union

from pydantic import Field, model_validator

from blastfsi.materials import check_overrides, lookup
from blastfsi.scenario import Numerics as SharedNumerics
from blastfsi.scenario import (AXES, Coordinate, Demand, Devices, Output, ScenarioBase, Strict, Sweep, check_box,
                               gauge_points)

Vector = Union[float, list[float]]
Limiter = Literal["van-leer", "minmod", "mc"]  # numerics.limiter of hllc-muscl and hllc-hancock (euler and cfdmp)
Limiting = Literal["characteristic", "primitive"]  # numerics.limiting: the variables the limiter acts on
BOUNDARY_KINDS = ("outflow", "wall", "symmetry", "axis", "periodic", "blast")


class GasState(Strict):
    """A uniform state of one gas from the material library."""

    material: str = Field("air", min_length=1, description="material name from the library (air, tnt, ...)")
    density: float = Field(gt=0.0, description="density [kg/m^3]")
    pressure: float = Field(gt=0.0, description="pressure [Pa]")
    velocity: Vector = Field(0.0, description="velocity [m/s]: x component, or one value per axis")


class RiemannInitial(Strict):
    """Two uniform states separated by a plane x = diaphragm (shock tubes, interface advection)."""

    kind: Literal["riemann"]
    diaphragm: float = Field(description="x position of the diaphragm [m]")
    left: GasState
    right: GasState


class PointEnergyInitial(Strict):
    """Energy released in a small volume around a point of a uniform ambient gas (Sedov)."""

    kind: Literal["point-energy"]
    ambient: GasState
    energy: float = Field(gt=0.0, description=(
        "energy released [J]; per unit length in 2D Cartesian, total (whole sphere/cylinder) otherwise"))
    center: list[float] = Field(default_factory=list, description="release point [m]; default the origin")
    radius_cells: float = Field(2.0, ge=0.5, le=50.0, description="release radius in cells (cell-volume weighted)")


class ChargeInitial(Strict):
    """A high-explosive charge detonated on a fine 1D Lagrangian grid (``lagrangian1d``, the programmed
    burn of 000 Eqs. 52-53) up to the remap time, then remapped conservatively onto this grid
    (:mod:`blastfsi.detonation.remap`, seed 000 Sec. 4.1). A sphere (1D spherical run) on 1D spherical,
    axisymmetric and 3D Cartesian domains; on a 2D Cartesian domain an infinitely long cylinder along z
    (1D cylindrical run). Times count from the detonation: the run starts at the remap time.

    Stand-off: ``center`` may lie outside the domain. The 1D blast is then run until it nears the
    domain (or the nearest gauge), the domain starts at rest, and every face the charge lies beyond is
    a ``blast`` face (``[boundaries]``): the 1D solution, continued to ``time.end`` and tabulated once,
    feeds the layer of cells along it at each cell's distance from the charge and the current time."""

    kind: Literal["charge"]
    explosive: str = Field("tnt", min_length=1, description="explosive from the material library (JWL)")
    mass: Optional[float] = Field(None, gt=0.0, le=1e6, description=(
        "charge mass [kg] (of the hemisphere for shape = 'hemisphere'); on a 2D Cartesian domain the mass "
        "per metre of the cylinder's length [kg/m] (of the half cylinder for shape = 'hemisphere')"))
    radius: Optional[float] = Field(None, gt=0.0, le=100.0, description=(
        "charge radius [m] (of the sphere; of the cylinder on a 2D Cartesian domain)"))
    shape: Literal["sphere", "hemisphere"] = Field("sphere", description=(
        "'hemisphere': centred on a wall/symmetry face (a surface burst); modelled as half of a sphere of "
        "twice the mass (on a 2D Cartesian domain: half of a cylinder lying on the face)"))
    center: list[float] = Field(default_factory=list, description="charge centre [m]; default the origin")
    ambient: Optional[GasState] = Field(None, description="ambient gas at rest; default the library's air")
    remap_time: Optional[float] = Field(None, ge=0.0, description=(
        "time after lighting at which the 1D solution is remapped [s]; default: when the blast reaches the "
        "nearest gauge or non-mirror boundary less margin_cells (earlier if the 1D shock's foot would then "
        "already cross a face)"))
    cells: int = Field(100, ge=10, le=100_000, description="1D zones across the charge radius (width h = R / cells)")
    air_ratio: float = Field(10.0, ge=1.0, le=1e4, description=(
        "1D air zones: uniform, air_ratio h wide (the first one at most R / 4; lagrangian1d grid.first_ratio = "
        "grid.max_ratio). The default, R / 10, is the tnt-free-air zoning, within 3 % of a 4x finer one at "
        "Z >= 1 (docs/verification.md)"))
    margin_cells: float = Field(3.0, ge=0.0, le=1000.0, description="margin of the automatic remap time [cells]")
    sub_cells: int = Field(4, ge=1, le=64, description="sub-cells per axis of the remap integration")
    blast_table_mb: float = Field(512.0, gt=0.0, le=1e5, description=(
        "largest memory [MB] of the tabulated 1D blast that feeds the blast faces of a stand-off charge "
        "(radii dx / 4 apart over the layer cells' distances, times dx / 4 over the shock speed apart up to "
        "time.end); a larger table is refused before the 1D run goes on"))

    @model_validator(mode="after")
    def _one_size(self):
        if (self.mass is None) == (self.radius is None):
            raise ValueError("give exactly one of initial.mass and initial.radius")
        return self


Initial = Annotated[Union[RiemannInitial, PointEnergyInitial, ChargeInitial], Field(discriminator="kind")]


class Domain(Strict):
    geometry: Literal["cartesian", "cylindrical", "spherical", "axisymmetric"] = Field("cartesian", description=(
        "cartesian: 1-3 axes x (, y (, z)); cylindrical, spherical: 1 axis, the radius r >= 0; axisymmetric: "
        "2 axes r >= 0 and z"))
    lower: list[Coordinate] = Field(min_length=1, max_length=3, description="lower corner [m]")
    upper: list[Coordinate] = Field(min_length=1, max_length=3, description="upper corner [m]")

    @model_validator(mode="after")
    def _box(self):
        check_box(self.lower, self.upper, "domain")
        ndim = len(self.lower)
        need = {"cylindrical": 1, "spherical": 1, "axisymmetric": 2}.get(self.geometry)
        if need is not None and ndim != need:
            raise ValueError(f"domain.geometry = {self.geometry!r} needs {need} axis/axes, got {ndim}")
        if self.geometry != "cartesian" and self.lower[0] < 0.0:
            raise ValueError(f"domain.lower[x] is the radius in {self.geometry} geometry and must be >= 0 "
                             f"(got {self.lower[0]})")
        return self

    @property
    def ndim(self) -> int:
        return len(self.lower)

    def cell_count(self, cells_x: int) -> float:
        """Cells of the grid of ``cells_x`` square cells along x (a float: may be astronomically many)."""
        dx = (self.upper[0] - self.lower[0]) / cells_x
        return math.prod(max(1.0, round((hi - lo) / dx)) for lo, hi in zip(self.lower, self.upper))


BoundaryPair = Annotated[list[Literal["outflow", "wall", "symmetry", "axis", "periodic", "blast"]],
                         Field(min_length=2, max_length=2)]


class Boundaries(Strict):
    """Kind of each face, [lower, upper] per axis: outflow (zero gradient), wall, symmetry, axis, periodic (both
    faces), blast (a face that a charge outside the domain lies beyond: fed by its 1D free-field blast)."""

    x: BoundaryPair = Field(["outflow", "outflow"], description="kinds of the lower and upper x faces (the radius "
                                                                "r in radial and r-z geometry: 'axis' at r = 0)")
    y: BoundaryPair = Field(["outflow", "outflow"], description="kinds of the lower and upper y faces (z in r-z)")
    z: BoundaryPair = Field(["outflow", "outflow"], description="kinds of the lower and upper z faces")


class Grid(Strict):
    cells: int = Field(ge=4, le=100_000, description="cells along x (square/cubic cells)")


# Largest Courant numbers accepted per scheme (blastfsi.euler.step.stable_dt): the unsplit scheme's linear limit is
# 1 on the summed signal speeds; Lax-Wendroff's operators run at cfl / 2 (linear limit 2), HLLC-Hancock's at cfl
# (alternating sweeps of the whole step, limit 1). Lax-Wendroff was measured stable on Sod and 2D blasts of
# pressure ratio 1e5 up to 1.5 (NaN at 1.8 in 2D): 1.5. HLLC-Hancock on 2D blasts of pressure ratio 10 and 1e5
# (48^2, walls, 200 steps) up to 1.2, the highest tried, and on sod and sedov-2d at 1.1; 0.9 keeps MUSCL-Hancock's
# usual margin below its limit 1 (Toro 2009 Sec. 14.4).
CFL_MAX = {"hllc-muscl": 1.0, "lax-wendroff": 1.5, "hllc-hancock": 0.9}


class Numerics(SharedNumerics):
    scheme: Literal["lax-wendroff", "hllc-muscl", "hllc-hancock"] = Field("hllc-muscl", description=(
        "lax-wendroff: the CFDMP paper's split Lax-Wendroff with adaptive artificial viscosity; hllc-muscl: "
        "unsplit HLLC fluxes on a limited MUSCL reconstruction, second order in space and time; hllc-hancock: "
        "dimensionally split MUSCL-Hancock with the same HLLC fluxes and reconstruction, second order (the sweep "
        "order alternates from step to step), one flux evaluation per direction and step and Lax-Wendroff's time "
        "step (in 2D/3D 2-3x longer than hllc-muscl's)"))
    cfl: float = Field(0.5, gt=0.0, le=max(CFL_MAX.values()), description=(
        "Courant number of the full time step: dt = cfl dx / max(|u| + c), summed over the axes for the unsplit "
        f"hllc-muscl (at most {CFL_MAX['hllc-muscl']:g}), the fastest axis for the split schemes (lax-wendroff, "
        f"whose directional operators run at cfl / 2: at most {CFL_MAX['lax-wendroff']:g}; hllc-hancock, whose "
        f"operators take the whole step: at most {CFL_MAX['hllc-hancock']:g})"))
    limiter: Limiter = Field("van-leer", description=(
        "slope limiter of the reconstruction of hllc-muscl and hllc-hancock: van-leer (default), minmod (most "
        "diffusive) or mc (monotonized central, the sharpest); ignored by lax-wendroff"))
    limiting: Limiting = Field("characteristic", description=(
        "what the limiter of hllc-muscl and hllc-hancock is applied to: characteristic (default): the normal "
        "velocity and the pressure through the acoustic characteristic variables p +- rho c u (at a "
        "products-air contact each on its own), the other rows each on its own; primitive: every primitive row "
        "on its own (a shock reflecting off a wall then overshoots the normal reflection in the wall cell, by "
        "~19 % at 9.6 bar overpressure; kept to reproduce earlier results); ignored by lax-wendroff"))
    devices: Devices = Field(1, description=(
        "devices (GPUs of this machine; an integer >= 1) the grid is split across, along x in equal slabs "
        "(grid.cells divisible by it), stepped together as one program that exchanges the slabs' boundary "
        "cells; 'all': every device JAX sees. Results agree with one device's to round-off"))

    @model_validator(mode="after")
    def _cfl_of_the_scheme(self):
        if self.cfl > CFL_MAX[self.scheme]:
            others = ", ".join(f"{k} {v:g}" for k, v in CFL_MAX.items() if k != self.scheme)
            raise ValueError(f"cfl: {self.scheme} is stable for 0 < cfl <= {CFL_MAX[self.scheme]:g}, got "
                             f"{self.cfl:g} (the other schemes' limits: {others})")
        return self


class EulerOutput(Output):
    arrival_fraction: float = Field(0.01, gt=0.0, le=10.0, description=(
        "arrival time = first time the overpressure exceeds this fraction of the ambient pressure"))
    plot_plane_z: Optional[float] = Field(None, description=(
        "z [m] of the plane shown in pressure.png of a 3D run (default: the middle of the domain); a plane "
        "through the charge is the usual choice"))


GaugeReference = Literal["auto", "incident", "reflected", "surface-incident"]


class EulerGaugeOutput(EulerOutput):
    """The euler method's outputs: ``EulerOutput`` plus the Kingery-Bulmash reference of each gauge."""

    gauge_references: Optional[list[GaugeReference]] = Field(None, max_length=100, description=(
        "Kingery-Bulmash reference of each gauge of a TNT charge, one per entry of output.gauges: 'auto' (the "
        "default: 'reflected' for a gauge within 2 cells of a wall or symmetry face that faces the charge and "
        "does not pass through its centre, normal or oblique by the ConWep blend at the angle of incidence; "
        "else 'incident'), 'incident' (side-on; KB free-air burst for a sphere, hemispherical surface burst "
        "for a hemisphere), 'reflected', 'surface-incident' (KB hemispherical surface burst of the charge mass)"))


def check_plot_plane(output: EulerOutput, domain) -> None:
    """output.plot_plane_z: a 3D domain only, inside its z extent."""
    z = output.plot_plane_z
    if z is None:
        return
    if domain.ndim != 3:
        raise ValueError(f"output.plot_plane_z: applies to 3D domains only (this one is {domain.ndim}D)")
    if not domain.lower[2] <= z <= domain.upper[2]:
        raise ValueError(f"output.plot_plane_z = {z:g} m must lie in the domain's z extent "
                         f"[{domain.lower[2]:g}, {domain.upper[2]:g}] m")


def check_devices(devices, cells: int) -> None:
    """numerics.devices (an int; "all" is checked when the run knows the devices): the x slabs must be equal."""
    if devices != "all" and cells % devices:
        allowed = [n for n in range(1, min(cells, 64) + 1) if cells % n == 0]
        raise ValueError(f"numerics.devices = {devices}: the grid is split along x in equal slabs, and grid.cells = "
                         f"{cells} is not divisible by it; give grid.cells a multiple of {devices}, or "
                         f"numerics.devices one of {allowed}")


def gas_materials(initial) -> dict[str, str]:
    """The library materials an initial condition uses: name -> the scenario key naming it first."""
    if initial.kind == "riemann":
        pairs = [("initial.left.material", initial.left.material), ("initial.right.material", initial.right.material)]
    elif initial.kind == "point-energy":
        pairs = [("initial.ambient.material", initial.ambient.material)]
    else:  # a charge; its ambient defaults to the library's air (blastfsi.detonation.charge)
        pairs = [("initial.explosive", initial.explosive),
                 ("initial.ambient.material", "air" if initial.ambient is None else initial.ambient.material)]
    used = {}
    for key, name in pairs:
        used.setdefault(name, key)
    return used


def check_gas_part(sc, used: dict[str, str]) -> None:
    """The checks the euler and cfdmp models share: the ``[materials]`` table against the materials in
    ``used``; gauges, the plot plane and the release point or charge centre inside the domain; a given
    charge remap time before the blast has crossed the whole domain."""
    d, init = sc.domain, sc.initial
    check_overrides(sc.materials, used)
    gauge_points(sc.output.gauges, d.ndim, d.lower, d.upper)
    check_plot_plane(sc.output, d)
    if init.kind in ("point-energy", "charge") and init.center:
        c = init.center
        if len(c) != d.ndim or (init.kind == "point-energy"
                                and not all(lo <= v <= hi for v, lo, hi in zip(c, d.lower, d.upper))):
            extent = ", ".join(f"{a} in [{lo:g}, {hi:g}]" for a, lo, hi in zip(AXES, d.lower, d.upper))
            raise ValueError(f"initial.center = {c} must be {d.ndim} coordinate(s)"
                             + (f" inside the domain ({extent} m)" if init.kind == "point-energy" else ""))
    check_blast_faces(sc)
    if init.kind == "charge" and init.remap_time is not None:
        _check_remap_time(sc)


def faces_toward(centre, domain) -> list[tuple[int, int]]:
    """(axis, side) of every face of ``domain`` that a point ``centre`` lies strictly beyond."""
    return [(ax, side) for ax in range(domain.ndim) for side in (0, 1)
            if (centre[ax] < domain.lower[ax] if side == 0 else centre[ax] > domain.upper[ax])]


def check_blast_faces(sc) -> None:
    """``blast`` faces: with a charge only, each facing it (the charge lies beyond its plane); every face a
    charge lies beyond is a blast face or a wall/symmetry plane (which the blast then never crosses)."""
    d, init = sc.domain, sc.initial
    blast = [(ax, side) for ax, a in enumerate(AXES[:d.ndim]) for side in (0, 1)
             if getattr(sc.boundaries, a)[side] == "blast"]
    if blast and init.kind != "charge":
        ax, side = blast[0]
        raise ValueError(f"boundaries.{AXES[ax]}: a 'blast' face needs a charge (initial.kind = 'charge') outside "
                         f"the domain, not initial.kind = {init.kind!r}")
    if init.kind != "charge":
        return
    toward = faces_toward(init.center or [0.0] * d.ndim, d)
    for ax, side in blast:
        if (ax, side) not in toward:
            raise ValueError(f"boundaries.{AXES[ax]}: the {('lower', 'upper')[side]} {AXES[ax]} face is 'blast' but "
                             f"does not face the charge: initial.center[{AXES[ax]}] must lie beyond it "
                             f"({'below' if side == 0 else 'above'} {(d.lower, d.upper)[side][ax]:g} m)")
    for ax, side in toward:
        kind = getattr(sc.boundaries, AXES[ax])[side]
        if kind not in ("blast", "wall", "symmetry"):
            raise ValueError(f"initial.center = {init.center} lies outside the domain, beyond its "
                             f"{('lower', 'upper')[side]} {AXES[ax]} face: move it inside, or (a stand-off charge) "
                             f"make that face 'blast' in boundaries.{AXES[ax]} (fed by the charge's 1D blast; "
                             f"'wall' or 'symmetry' also hold), got {kind!r}")


def _check_remap_time(sc) -> None:
    """A blast's leading shock outruns the ambient sound speed, itself above the isothermal one sqrt(p / rho)
    (gamma > 1): a remap time at which the shock has passed the farthest corner of the domain can only fail,
    and only after the 1D detonation has run to it (minutes), so it is refused here."""
    d, init = sc.domain, sc.initial
    if init.ambient is None:
        air = lookup("air", sc.materials.get("air"))
        density, pressure = air.density, air.pressure
    else:
        density, pressure = init.ambient.density, init.ambient.pressure
    speed = math.sqrt(pressure / density)
    centre = init.center or [0.0] * d.ndim
    reach = math.hypot(*(max(abs(c - lo), abs(hi - c)) for c, lo, hi in zip(centre, d.lower, d.upper)))
    if init.remap_time * speed > reach:
        raise ValueError(f"initial.remap_time = {init.remap_time:g} s: the blast front, faster than "
                         f"sqrt(p / rho) = {speed:.4g} m/s, crosses the whole domain (its farthest point is "
                         f"{reach:.4g} m from the charge) before {reach / speed:.3g} s; give an earlier time, or none "
                         "for the automatic one")


class EulerSweep(Sweep):
    """Ensemble over the released energy (point-energy) or the Courant number."""

    TARGETS: ClassVar[dict[str, str]] = {"energy": "initial.energy", "cfl": "numerics.cfl"}
    energy: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    cfl: Optional[list[Annotated[float, Field(gt=0.0, le=1.0)]]] = Field(None, min_length=1)


class EulerScenario(ScenarioBase):
    method: Literal["euler"] = "euler"
    domain: Domain
    boundaries: Boundaries = Boundaries()
    grid: Grid
    initial: Initial
    materials: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="per-material overrides of library constants, e.g. {air = {gamma = 1.3}}")
    numerics: Numerics = Numerics()
    output: EulerGaugeOutput = EulerGaugeOutput()
    sweep: Optional[EulerSweep] = None

    @model_validator(mode="after")
    def _inside(self):
        check_gas_part(self, gas_materials(self.initial))
        refs, gauges = self.output.gauge_references, self.output.gauges
        if refs is not None and len(refs) != len(gauges):
            raise ValueError(f"output.gauge_references: {len(refs)} entries for {len(gauges)} gauges "
                             "(output.gauges); give one per gauge")
        if refs is not None and self.initial.kind != "charge":
            raise ValueError("output.gauge_references: Kingery-Bulmash references apply to a TNT charge "
                             f"(initial.kind = 'charge'), not initial.kind = {self.initial.kind!r}")
        if self.sweep is not None and self.sweep.energy is not None and self.initial.kind != "point-energy":
            raise ValueError("sweep.energy needs initial.kind = 'point-energy'")
        check_devices(self.numerics.devices, self.grid.cells)
        return self

    def demands(self) -> list[Demand]:
        return super().demands() + [grid_demand(self)]


# Numbers per cell the compiled Eulerian loop holds: state (up to 7 conserved rows and 5 blast maps) and the
# step's primitives, slopes and fluxes; XLA's memory analysis of sedov-3d at 24^3 cells: 80 (53 in 2D).
WORDS_PER_CELL = 80


def grid_demand(sc) -> Demand:
    """The Eulerian grid's memory (euler and cfdmp)."""
    return Demand("grid.cells", sc.domain.cell_count(sc.grid.cells), "cells", WORDS_PER_CELL)
