"""Scenario schema of the Material Point Method (``method = "mpm"``).

Geometry is data: the grid box, bodies, the impactor, tracers and gauges are
given in metres; ``grid.cells`` is the number of cells along x, every cell is a
square/cube of side h = (upper - lower)_x / cells and the other extents must
hold a whole number of cells.

Axes: x (, y (, z)) in 1, 2 (plane strain) and 3 dimensions; with
``grid.axisymmetric = true`` a 2D grid is r-z (x = r >= 0, y = z, the axis of
revolution at r = 0, where the lower x face must be ``slip``).

Tables:

* ``[grid]``: lower, upper, cells, axisymmetric, ``[grid.boundaries]`` x/y/z =
  [lower face, upper face] of "free", "slip" (symmetry: zero normal velocity),
  "fixed" (zero velocity);
* ``[[bodies]]``: boxes or cylinders of one library material each, filled with
  ``particles_per_cell`` particles per cell and direction; ``[[bodies.supports]]``:
  boxes in which the body is clamped (its particles there held at rest);
* ``[impactor]``: a rod (Taylor bar) striking the lower face of the last axis;
* ``[numerics]``: shape ("linear" | "gimp"), cfl, bulk-viscosity coefficients, capacity, reference_pressure;
* ``gravity``: body force per unit mass [m/s^2];
* ``[output]``: the shared keys plus ``tracers``.
"""
from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal, Optional, Union

from pydantic import Field, field_validator, model_validator

from blastfsi.materials import check_overrides
from blastfsi.mpm.viscosity import DEFAULT_LINEAR, DEFAULT_QUADRATIC
from blastfsi.scenario import Numerics as SharedNumerics
from blastfsi.scenario import (AXES, Coordinate, Demand, Devices, Output, ScenarioBase, Strict, Sweep, check_box,
                               gauge_points)

Vector = Union[float, list[float]]
FaceKind = Literal["free", "slip", "fixed"]
FacePair = Annotated[list[FaceKind], Field(min_length=2, max_length=2)]


class Boundaries(Strict):
    """Kind of each grid face, [lower, upper] per axis."""

    x: FacePair = Field(["free", "free"], description="kinds of the lower and upper x faces (r of an r-z grid)")
    y: FacePair = Field(["free", "free"], description="kinds of the lower and upper y faces (z of an r-z grid)")
    z: FacePair = Field(["free", "free"], description="kinds of the lower and upper z faces")


class GridSpec(Strict):
    lower: list[Coordinate] = Field(min_length=1, max_length=3, description="lower corner [m]")
    upper: list[Coordinate] = Field(min_length=1, max_length=3, description="upper corner [m]")
    cells: int = Field(ge=2, le=100_000, description="cells along x (square/cubic cells)")
    axisymmetric: bool = Field(False, description="2D r-z grid (x = r >= 0, y = z)")
    boundaries: Boundaries = Boundaries()

    @model_validator(mode="after")
    def _box(self):
        check_box(self.lower, self.upper, "grid")
        if self.axisymmetric and self.ndim != 2:
            raise ValueError(f"grid.axisymmetric needs a 2D (r, z) grid, got {self.ndim} axis/axes")
        if self.axisymmetric and self.lower[0] < 0.0:
            raise ValueError(f"grid.lower[x] is the radius of an axisymmetric grid and must be >= 0 "
                             f"(got {self.lower[0]})")
        if self.axisymmetric and self.lower[0] == 0.0 and self.boundaries.x[0] != "slip":
            raise ValueError("grid.boundaries.x: an axisymmetric grid starting at r = 0 needs 'slip' on its lower "
                             f"x face (the axis), got {self.boundaries.x[0]!r}")
        return self

    @property
    def ndim(self) -> int:
        return len(self.lower)


class Body(Strict):
    """A body of one material: a box [lower, upper], or a cylinder (2D plane strain: a disk
    of ``radius`` around ``center``; 3D: axis along z through ``center`` (its mid-point),
    ``length`` along z; axisymmetric: a box r in [0, radius], z in center +- length/2)."""

    shape: Literal["box", "cylinder"] = Field("box", description="a box (lower, upper) or a cylinder (center, "
                                                                 "radius, length)")
    lower: Optional[list[Coordinate]] = Field(None, min_length=1, max_length=3, description="box lower corner [m]")
    upper: Optional[list[Coordinate]] = Field(None, min_length=1, max_length=3, description="box upper corner [m]")
    center: Optional[list[Coordinate]] = Field(None, min_length=2, max_length=3, description="cylinder centre [m]")
    radius: Optional[float] = Field(None, gt=0.0, description="cylinder radius [m]")
    length: Optional[float] = Field(None, gt=0.0, description="cylinder length along its axis [m] (not in 2D plane)")
    material: str = Field(min_length=1, description="material name from the library")
    velocity: Vector = Field(0.0, description="initial velocity [m/s]: x component, or one value per axis")
    velocity_profile: Literal["uniform", "sine"] = Field("uniform", description=(
        "'sine': velocity * sin(pi (X - lower_x) / (2 L)), L the body's x extent: the first axial mode of a "
        "bar fixed at its lower x end and free at the other"))
    prescribed: bool = Field(False, description="the body moves with its initial velocity throughout (impactor)")
    particles_per_cell: int = Field(2, ge=1, le=8, description="particles per cell and direction")
    density: Optional[float] = Field(None, gt=0.0, description="initial density of a gas [kg/m^3] "
                                                                "(default: the library's)")
    pressure: Optional[float] = Field(None, gt=0.0, description="initial pressure of a gas [Pa] "
                                                                "(default: the library's ambient pressure)")
    supports: list[Support] = Field(default_factory=list, max_length=20, description=(
        "boxes where the body is clamped: its particles inside are held at rest"))
    top_traction: Optional[Vector] = Field(None, description=(
        "traction [Pa] on the body's upper face along the last axis, one value (normal, along the last axis) "
        "or one per axis; spread over the top particle layer, 000 Eq. (20)"))

    @model_validator(mode="after")
    def _geometry(self):
        if self.shape == "box":
            if self.lower is None or self.upper is None:
                raise ValueError("a box body needs lower and upper")
            if any(k is not None for k in (self.center, self.radius, self.length)):
                raise ValueError("a box body takes lower and upper, not center/radius/length")
            check_box(self.lower, self.upper, "body")
        else:
            if self.center is None or self.radius is None:
                raise ValueError("a cylinder body needs center and radius")
            if self.lower is not None or self.upper is not None:
                raise ValueError("a cylinder body takes center, radius and length, not lower/upper")
        if self.supports and self.prescribed:
            raise ValueError("supports: a prescribed (driven) body moves whole; it cannot also be clamped")
        return self


class Support(Strict):
    """A clamp: the body's particles inside the box [lower, upper] are held at zero velocity (the grid
    nodes they touch take it), in every component (a bolted or welded edge) or in those of ``hold`` only
    (a plate pressed between clamping plates that lets it slide in its plane), as the *BOUNDARY_SPC of a
    node set does in LS-DYNA."""

    lower: list[Coordinate] = Field(min_length=1, max_length=3, description="support box lower corner [m]")
    upper: list[Coordinate] = Field(min_length=1, max_length=3, description="support box upper corner [m]")
    hold: Optional[list[Literal["x", "y", "z"]]] = Field(None, min_length=1, max_length=3, description=(
        "the velocity components held at zero (default: all, a fully clamped edge); e.g. [\"y\"] for a plate "
        "lying across y between two rigid clamping plates that hold its faces and let it pull in without "
        "friction (r-z: x is r, y is z)"))

    @model_validator(mode="after")
    def _box(self):
        check_box(self.lower, self.upper, "support")
        if self.hold is not None and len(set(self.hold)) != len(self.hold):
            raise ValueError(f"hold: each axis once, got {self.hold}")
        return self


class Impactor(Strict):
    """A rod of ``length`` and ``diameter`` moving at ``velocity`` towards the lower face of the
    last axis (y in 2D, z in 3D), its axis on the lower faces of the other axes (r = 0 of an
    axisymmetric grid; symmetry planes in Cartesian grids: give them 'slip'): the Taylor test."""

    material: str = Field(min_length=1, description="material name from the library")
    velocity: float = Field(gt=0.0, le=1e4, description="impact speed [m/s]")
    length: float = Field(gt=0.0, description="rod length [m]")
    diameter: float = Field(gt=0.0, description="rod diameter [m]")
    standoff: float = Field(0.0, ge=0.0, description="gap between the rod's face and the anvil face [m]")
    particles_per_cell: int = Field(2, ge=1, le=8, description="particles per cell and direction")


class MPMNumerics(SharedNumerics):
    shape: Literal["linear", "gimp"] = Field("linear", description="grid shape functions: 000 Eq. (16) or uGIMP")
    cfl: float = Field(0.5, gt=0.0, le=1.0, description="dt = cfl h / max signal speed")
    q_quadratic: float = Field(DEFAULT_QUADRATIC, ge=0.0, le=10.0, description="bulk viscosity C_q (ERRATA 000-10)")
    q_linear: float = Field(DEFAULT_LINEAR, ge=0.0, le=10.0, description="bulk viscosity C_l (ERRATA 000-10)")
    pressure_relaxation: bool = Field(True, description=(
        "gas particles of different materials (detonation products, air) that share grid nodes relax to a "
        "common pressure, as the Eulerian mixture cells do (blastfsi.mpm.relaxation); false: they take the "
        "same strain, and a products/air contact over-compresses the air"))
    capacity: Optional[int] = Field(None, ge=1, le=500_000_000, description=(
        "particle pool size (default: the particles the bodies create)"))
    reference_pressure: float = Field(0.0, ge=0.0, le=1.0e9, description=(
        "p_ref [Pa] of an atmosphere around the whole model: the internal force takes the stress relative to it "
        "(sigma + p_ref I; in cfdmp the Eulerian cells acting as particles too), so a gas at p_ref is in "
        "equilibrium however its particles sit, and free faces carry p_ref; in mpm its work -p_ref dV is booked "
        "in external_work. Set it to the ambient air's pressure when air is modelled with particles: with "
        "numerics.shape = 'gimp' an air body at rest is otherwise unstable (docs/theory/cfdmp.md); 0: absolute stresses"))


class MPMMethodNumerics(MPMNumerics):
    """The mpm method's numerics: MPMNumerics and the devices the particles are spread over."""

    devices: Devices = Field(1, description=(
        "devices (GPUs of this machine; an integer >= 1) the particle pool is spread over in equal parts, "
        "stepped together as one program: each device maps its particles to the grid, the nodal sums are added "
        "across devices, every device updates the (whole) grid and moves its own particles; the pool "
        "(numerics.capacity) is rounded up to a multiple of it. 'all': every device JAX sees. Results agree "
        "with one device's to round-off (the nodal sums are added in another order)"))


class Tracers(Strict):
    """Points of the structures whose displacement history is recorded (a plate's centre, a slab's back face)."""

    tracers: list[list[float]] = Field(default_factory=list, max_length=100, description=(
        "points [m] whose displacement history is recorded: the particle nearest to each at t = 0"))


class MPMOutput(Output, Tracers):
    pass


class MPMSweep(Sweep):
    """Ensemble over the impact speed or the Courant number."""

    TARGETS: ClassVar[dict[str, str]] = {"velocity": "impactor.velocity", "cfl": "numerics.cfl"}
    velocity: Optional[list[Annotated[float, Field(gt=0.0, le=1e4)]]] = Field(None, min_length=1)
    cfl: Optional[list[Annotated[float, Field(gt=0.0, le=1.0)]]] = Field(None, min_length=1)


def body_materials(bodies: list[Body], key: str) -> dict[str, str]:
    """The library materials of ``bodies`` (the scenario list ``key``): name -> the key naming it first."""
    used = {}
    for k, b in enumerate(bodies):
        used.setdefault(b.material, f"{key}[{k}].material")
    return used


def lattice_count(sides, h: float, per_cell: int) -> float:
    """Particles of a box of the given side lengths filled with ``per_cell`` particles per cell of side h and
    direction (at least one per direction)."""
    return math.prod(max(1.0, s / h * per_cell) for s in sides)


def body_particles(body: Body, h: float, ndim: int) -> float:
    """Particles a body creates on cells of side h (its bounding box: at most 4/pi too many for a cylinder)."""
    if body.shape == "box":
        sides = [hi - lo for lo, hi in zip(body.lower, body.upper)]
    elif body.length is None:  # a disk of a 2D plane-strain grid
        sides = [2.0 * body.radius] * 2
    else:  # 3D, the axis along z; r-z, r in [0, radius] (over-counted twice)
        sides = [2.0 * body.radius] * (ndim - 1) + [body.length]
    return lattice_count(sides, h, body.particles_per_cell)


# Numbers the compiled MUSL loop holds per particle (the particle state, ~33, and the step's gathers and
# scatters; XLA's memory analysis of taylor-bar, 6000 particles on 2100 cells: 94) and per grid node (mass,
# momentum, force and boundary masks with their temporaries; an estimate, small beside the particles).
WORDS_PER_PARTICLE = 100
WORDS_PER_NODE = 24


def particle_demand(capacity: int | None, particles: float, key: str) -> Demand:
    """The particle pool's memory: ``numerics.capacity`` when set, else ``particles`` (set by the scenario key
    ``key``)."""
    if capacity is not None:
        return Demand("numerics.capacity", capacity, "particles", WORDS_PER_PARTICLE)
    return Demand(key, particles, "particles", WORDS_PER_PARTICLE)


def check_bodies(bodies, nd: int, axisymmetric: bool, key: str) -> None:
    """The bodies against the grid they stand on (``nd`` axes, r-z or not): coordinates per axis, supports'
    axes, a cylinder's centre and length; errors name ``key[k]`` (the mpm method's bodies, cfdmp's
    structures)."""
    for k, b in enumerate(bodies):
        body_key = f"{key}[{k}]"
        for name in ("lower", "upper"):
            value = getattr(b, name)
            if value is not None and len(value) != nd:
                raise ValueError(f"{body_key}.{name}: expected {nd} coordinate(s), got {len(value)}")
        for j, sup in enumerate(b.supports):
            if len(sup.lower) != nd:
                raise ValueError(f"{body_key}.supports[{j}]: expected {nd} coordinate(s), got {len(sup.lower)}")
            if sup.hold is not None and any(AXES.index(a) >= nd for a in sup.hold):
                raise ValueError(f"{body_key}.supports[{j}].hold: a {nd}D grid has the axes {list(AXES[:nd])}, "
                                 f"got {sup.hold}")
        if b.shape == "cylinder":
            if nd == 1:
                raise ValueError(f"{body_key}.shape: a cylinder needs a 2D or 3D grid")
            if len(b.center) != nd:
                raise ValueError(f"{body_key}.center: expected {nd} coordinate(s), got {len(b.center)}")
            plane = nd == 2 and not axisymmetric
            if plane and b.length is not None:
                raise ValueError(f"{body_key}.length: a cylinder in a 2D plane-strain grid is a disk; omit length")
            if not plane and b.length is None:
                raise ValueError(f"{body_key}.length: a cylinder in a {'3D' if nd == 3 else 'r-z'} grid needs length")
            if axisymmetric and b.center[0] != 0.0:
                raise ValueError(f"{body_key}.center: a cylinder on an axisymmetric grid lies on the axis, "
                                 f"center[r] must be 0 (got {b.center[0]})")


class MPMScenario(ScenarioBase):
    method: Literal["mpm"] = "mpm"
    grid: GridSpec
    bodies: list[Body] = Field(default_factory=list, max_length=100)
    impactor: Optional[Impactor] = None
    materials: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="per-material overrides of library constants, e.g. "
                                          "{copper-ofhc = {A = 9.0e7}}")
    gravity: list[float] = Field(default_factory=list, max_length=3, description="body force per unit mass [m/s^2]")
    numerics: MPMMethodNumerics = MPMMethodNumerics()
    output: MPMOutput = MPMOutput()
    sweep: Optional[MPMSweep] = None

    @field_validator("gravity")
    @classmethod
    def _finite(cls, value):
        if any(abs(g) > 1e9 for g in value):
            raise ValueError(f"gravity components must lie within +-1e9 m/s^2, got {value}")
        return value

    @model_validator(mode="after")
    def _consistent(self):
        g = self.grid
        nd = g.ndim
        if not self.bodies and self.impactor is None:
            raise ValueError("bodies: give at least one [[bodies]] entry or an [impactor]")
        if self.gravity and len(self.gravity) != nd:
            raise ValueError(f"gravity: expected {nd} component(s), got {len(self.gravity)}")
        gauge_points(self.output.gauges, nd, g.lower, g.upper)
        for k, p in enumerate(self.output.tracers):
            if len(p) != nd:
                raise ValueError(f"output.tracers[{k}] = {p}: expected {nd} coordinate(s)")
        check_bodies(self.bodies, nd, g.axisymmetric, "bodies")
        if self.impactor is not None and nd == 1:
            raise ValueError("impactor: needs a 2D or 3D grid (the rod's axis is the last axis)")
        if self.sweep is not None and self.sweep.velocity is not None and self.impactor is None:
            raise ValueError("sweep.velocity needs an [impactor]")
        used = body_materials(self.bodies, "bodies")
        if self.impactor is not None:
            used.setdefault(self.impactor.material, "impactor.material")
        check_overrides(self.materials, used)
        for k, p in enumerate(self.output.tracers):
            if not all(lo <= c <= hi for c, lo, hi in zip(p, g.lower, g.upper)):
                raise ValueError(f"output.tracers[{k}] = {p} m lies outside the grid {g.lower} - {g.upper} m")
        return self

    def demands(self) -> list[Demand]:
        """The grid nodes and the particle pool (numerics.capacity, or the bodies' and the impactor's)."""
        g = self.grid
        h = (g.upper[0] - g.lower[0]) / g.cells
        nodes = math.prod(round((hi - lo) / h) + 1 for lo, hi in zip(g.lower, g.upper))
        particles = sum(body_particles(b, h, g.ndim) for b in self.bodies)
        if self.impactor is not None:
            rod = self.impactor
            particles += lattice_count([rod.diameter] * (g.ndim - 1) + [rod.length], h, rod.particles_per_cell)
        pool = particle_demand(self.numerics.capacity, particles, "bodies" if self.bodies else "impactor")
        return super().demands() + [Demand("grid.cells", nodes, "grid nodes", WORDS_PER_NODE), pool]
