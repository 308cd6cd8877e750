"""Scenario schema of the coupled Eulerian-MPM method (``method = "cfdmp"``, seed 000 Sec. 3).

The whole domain is the Eulerian grid of the ``euler`` method (same ``domain``,
``boundaries``, ``grid``, ``initial`` and ``materials`` keys); ``[mpm_region]``
is an axis-aligned box of whole cells inside it (on an r-z grid, ``domain.geometry =
"axisymmetric"``, a ring or, touching the axis, a cylinder) where the gas becomes
particles and ``[[structures]]`` (the ``mpm`` method's bodies) stand. Every face
of the box that is not on the domain boundary borders the Eulerian region and
carries a bridge ``bridge_cells`` wide inside the box (000 Sec. 3.1).
"""
from __future__ import annotations

from typing import Literal, Optional

from pydantic import Field, model_validator

from blastfsi.euler.scenario import (Boundaries, Domain, EulerOutput, Grid, Initial, Limiter, Limiting, check_gas_part,
                                     gas_materials, grid_demand)
from blastfsi.mpm.scenario import (Body, MPMNumerics, Tracers, body_materials, body_particles, check_bodies,
                                   lattice_count, particle_demand)
from blastfsi.scenario import AXES, Coordinate, Demand, Devices, ScenarioBase, Strict, check_box

# Eulerian cells beyond the bridge whose values the scheme's two stages (or two sweeps) of two-cell stencils
# read when updating the bridge: the fictitious cells of 000 Eqs. (31)-(36). Structures stay beyond them.
FICTITIOUS_DEPTH = 4


class MPMRegion(Strict):
    """The MPM box, its bridge and the activation of the coupling."""

    lower: list[Coordinate] = Field(min_length=1, max_length=3, description="lower corner [m] (on cell faces)")
    upper: list[Coordinate] = Field(min_length=1, max_length=3, description="upper corner [m] (on cell faces)")
    bridge_cells: int = Field(5, ge=1, le=50, description="bridge width w [cells] on every face bordering the "
                                                          "Eulerian region (000 Sec. 3.1)")
    activation_overpressure: float = Field(0.0, ge=0.0, description=(
        "overpressure [Pa] in the Eulerian cells bordering the box that starts the coupling (the gas in the box "
        "then becomes particles); 0: coupled from the start"))
    gas_particles_per_cell: int = Field(2, ge=1, le=4, description="gas particles per cell and direction")

    @model_validator(mode="after")
    def _box(self):
        check_box(self.lower, self.upper, "mpm_region")
        return self


# PIC share of the gas particles' velocity update. Pure FLIP lets the velocity modes the grid cannot see grow in
# the rarefied gas that wraps around a structure's edges; a PIC share alpha damps them by 1 - alpha a step
# (e-folding in 1/alpha = 20 steps) and returns the kinetic energy it removes as heat. Not in the CFDMP paper:
# docs/theory/cfdmp.md, "Departures from the paper and tuned constants".
GAS_PIC_FRACTION = 0.05


class CfdmpNumerics(MPMNumerics):
    """The MPM solver's numerics (bulk viscosity, pressure relaxation) with the coupled run's defaults, and
    the Eulerian scheme's."""

    scheme: Literal["lax-wendroff", "hllc-muscl", "hllc-hancock"] = Field("hllc-muscl", description=(
        "Eulerian scheme (see the euler method's numerics.scheme)"))
    limiter: Limiter = Field("van-leer", description=(
        "slope limiter of the Eulerian hllc-muscl and hllc-hancock schemes (see the euler method's numerics.limiter)"))
    limiting: Limiting = Field("characteristic", description=(
        "what the Eulerian schemes' limiter acts on (see the euler method's numerics.limiting)"))
    cfl: float = Field(0.4, gt=0.0, le=1.0, description=(
        "Courant number of the MPM step, and of the Eulerian one unless euler_cfl is set (one common step: the "
        "smaller of the two)"))
    euler_cfl: Optional[float] = Field(None, gt=0.0, le=1.0, description=(
        "Courant number of the Eulerian step (default: cfl). HLLC-MUSCL's is taken on the sum of the directions' "
        "signal speeds (stable to 1), so at equal numbers its step is 1/ndim of the MPM's"))
    shape: Literal["linear", "gimp"] = Field("gimp", description="MPM shape functions ('linear' in 1D only)")
    gas_pic_fraction: float = Field(GAS_PIC_FRACTION, ge=0.0, le=1.0, description=(
        "PIC share alpha of the gas particles' G2P velocity (FLIP/PIC blend, its kinetic-energy loss heats the "
        "particle; 0: pure FLIP; structures stay FLIP)"))
    capacity: Optional[int] = Field(None, ge=1, le=500_000_000, description=(
        "fixed particle pool size: the run stops when the bridge needs more (default: a pool that grows, sized "
        "by pool_headroom; with MPM everywhere, which creates none, structures + the gas particles)"))
    pool_headroom: float = Field(1.5, ge=1.0, le=20.0, description=(
        "default pool (numerics.capacity unset) with coupled faces: room for the structures, pool_headroom x "
        "the box's gas particles and one step's emissions. The bridge fills the box as the blast compresses its "
        "gas (by about 1.2-1.3 x in the shipped slab examples); a full pool is enlarged and "
        "the time loop compiled again (summary pool_growths), and every step costs in proportion to the pool"))
    devices: Devices = Field(1, description=(
        "devices (GPUs of this machine; an integer >= 1) the MPM region's particle pool is spread over in equal "
        "parts, stepped together as one program: each device maps its particles to the MPM grid, the nodal sums "
        "and the gas's sums per Eulerian cell are added across devices, every device updates the (whole) "
        "Eulerian and MPM grids and moves its own particles; the pool is rounded up to a multiple of it. 'all': "
        "every device JAX sees. Results agree with one device's to round-off (the sums are added in another "
        "order)"))


class CfdmpOutput(EulerOutput, Tracers):
    """The Eulerian solver's outputs plus ``tracers``: points of the structures (a plate's centre) whose
    displacement history is recorded, each the structure particle nearest to it at t = 0."""


class CfdmpScenario(ScenarioBase):
    method: Literal["cfdmp"] = "cfdmp"
    domain: Domain
    boundaries: Boundaries = Boundaries()
    grid: Grid
    initial: Initial
    mpm_region: MPMRegion
    structures: list[Body] = Field(default_factory=list, max_length=100)
    materials: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="per-material overrides of library constants")
    numerics: CfdmpNumerics = CfdmpNumerics()
    output: CfdmpOutput = CfdmpOutput()

    @model_validator(mode="after")
    def _consistent(self):
        d, box = self.domain, self.mpm_region
        nd = d.ndim
        if d.geometry not in ("cartesian", "axisymmetric"):
            raise ValueError(f"domain.geometry: cfdmp runs on Cartesian grids (1D, 2D plane strain, 3D) and 2D "
                             f"axisymmetric (r-z) ones, got {d.geometry!r}")
        if len(box.lower) != nd:
            raise ValueError(f"mpm_region.lower: expected {nd} coordinate(s), got {len(box.lower)}")
        for ax, lo, hi, dlo, dhi in zip(AXES, box.lower, box.upper, d.lower, d.upper):
            if lo < dlo or hi > dhi:
                raise ValueError(f"mpm_region: the box [{lo:g}, {hi:g}] m along {ax} leaves the domain "
                                 f"[{dlo:g}, {dhi:g}] m")
        if all(lo == dlo and hi == dhi for lo, hi, dlo, dhi in zip(box.lower, box.upper, d.lower, d.upper)) \
                and box.activation_overpressure > 0.0:
            raise ValueError("mpm_region covers the whole domain (MPM everywhere, the grid only carries the initial "
                             "condition): mpm_region.activation_overpressure must be 0")
        if self.numerics.shape == "linear" and nd > 1:
            raise ValueError("numerics.shape = 'linear' runs cfdmp in 1D only: in 2D and 3D the gas particles of the "
                             "MPM box cross cells, and linear shape functions' cell-crossing error (a gradient that "
                             "jumps as a particle crosses a cell face) drives lone particles of the expanding gas to "
                             "non-physical states; use 'gimp' (the default), whose gradients are continuous")
        for kinds, ax in zip((self.boundaries.x, self.boundaries.y, self.boundaries.z), AXES[:nd]):
            if "periodic" in kinds:
                raise ValueError(f"boundaries.{ax}: periodic faces are not supported by cfdmp")
        check_bodies(self.structures, nd, d.geometry == "axisymmetric", "structures")
        for k, b in enumerate(self.structures):
            if b.prescribed:
                raise ValueError(f"structures[{k}].prescribed: structures are not driven bodies")
        for k, p in enumerate(self.output.tracers):
            if not self.structures:
                raise ValueError(f"output.tracers[{k}]: tracers follow structure particles; this scenario has "
                                 "no [[structures]]")
            if len(p) != nd:
                raise ValueError(f"output.tracers[{k}] = {p}: expected {nd} coordinate(s)")
            if not all(lo <= c <= hi for c, lo, hi in zip(p, box.lower, box.upper)):
                raise ValueError(f"output.tracers[{k}] = {p} m lies outside mpm_region (tracers follow structure "
                                 "particles)")
        check_gas_part(self, {**body_materials(self.structures, "structures"), **gas_materials(self.initial)})
        return self

    def demands(self) -> list[Demand]:
        """The grid, and the particle pool: numerics.capacity, or the default pool's pool_headroom x the box's
        gas particles plus the structures' (blastfsi.cfdmp.problem)."""
        box, nd = self.mpm_region, self.domain.ndim
        dx = (self.domain.upper[0] - self.domain.lower[0]) / self.grid.cells
        gas = lattice_count([hi - lo for lo, hi in zip(box.lower, box.upper)], dx, box.gas_particles_per_cell)
        particles = self.numerics.pool_headroom * gas + sum(body_particles(s, dx, nd) for s in self.structures)
        return super().demands() + [grid_demand(self), particle_demand(self.numerics.capacity, particles, "mpm_region")]
