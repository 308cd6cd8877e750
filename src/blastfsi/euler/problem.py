"""Initial conditions of the Eulerian method from a validated scenario (host side, NumPy).

Materials: the gases named by the initial condition, explosives (JWL) first, so
material 0 is the detonation products when there are two; at most two.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blastfsi.detonation.charge import ChargeRemap, charge_initial
from blastfsi.euler.config import BlastTable
from blastfsi.euler.scenario import Boundaries, Domain, EulerOutput, EulerScenario, Grid, Initial
from blastfsi.materials.gases import JWLExplosive
from blastfsi.scenario import AXES, ScenarioError, Time, cells_along, material

GEOMETRY_CODE = {"cartesian": 0, "cylindrical": 1, "spherical": 2, "axisymmetric": 1}
# a blast face is an outflow face to the scheme; its layer of cells is set from the blast table
BOUNDARY_CODE = {"outflow": 0, "wall": 1, "symmetry": 1, "axis": 2, "periodic": 3, "blast": 0}


@dataclass(frozen=True)
class GasPart:
    """What the Eulerian builder reads: the gas keys of a validated scenario (``euler``'s, or the whole-domain
    grid of ``cfdmp``'s, which shares these keys' schema) and the Courant number of the Eulerian step."""

    domain: Domain
    boundaries: Boundaries
    grid: Grid
    initial: Initial
    materials: dict  # per-material overrides of library constants, of the gases only
    time: Time
    output: EulerOutput  # gauges, arrival_fraction (and, for a charge, the points its remap must not reach)
    cfl: float

    @classmethod
    def of(cls, sc: EulerScenario) -> "GasPart":
        return cls(sc.domain, sc.boundaries, sc.grid, sc.initial, sc.materials, sc.time, sc.output, sc.numerics.cfl)


@dataclass(frozen=True)
class GridGeometry:
    shape: tuple[int, ...]
    dx: float
    lower: tuple[float, ...]
    geometry: str

    @property
    def ndim(self) -> int:
        return len(self.shape)

    def centres(self) -> list[np.ndarray]:
        """Cell-centre coordinates along each axis."""
        return [lo + (np.arange(n) + 0.5) * self.dx for lo, n in zip(self.lower, self.shape)]

    def mesh(self) -> list[np.ndarray]:
        return np.meshgrid(*self.centres(), indexing="ij")

    def cell_of(self, point) -> tuple[int, ...]:
        return tuple(int(np.clip(np.floor((p - lo) / self.dx), 0, n - 1))
                     for p, lo, n in zip(point, self.lower, self.shape))


@dataclass(frozen=True)
class Setup:
    grid: GridGeometry
    materials: tuple[str, ...]
    gases: tuple  # the materials' library entries (blastfsi.materials.gases), the scenario's overrides applied
    eos: np.ndarray  # (n_materials, 6) JWL rows
    bc: tuple[tuple[int, int], ...]
    rho_k: np.ndarray  # (n_materials, *shape) phase densities
    alpha: np.ndarray  # (n_materials, *shape) volume fractions
    velocity: np.ndarray  # (ndim, *shape)
    pressure: np.ndarray  # (*shape)
    reference_pressure: float
    gauges: np.ndarray  # (G, ndim) positions
    gauge_cells: tuple[tuple[int, ...], ...]
    cfl: float  # numerics.cfl
    arrival_fraction: float  # output.arrival_fraction: the overpressure that marks arrival, of the ambient pressure
    start_time: float = 0.0  # the simulated time of the initial state: a charge's remap time (detonation at 0)
    charge: ChargeRemap | None = None  # a charge's 1D detonation and remap (the summary's); None for other kinds
    blast: BlastTable | None = None  # a stand-off charge's blast table (host arrays), None without blast faces
    devices: int = 1  # devices the grid is split across (numerics.devices, resolved by the euler method)

    @property
    def cells(self) -> int:
        return int(np.prod(self.grid.shape))


def grid_geometry(sc: GasPart) -> GridGeometry:
    d = sc.domain
    dx, shape = cells_along(d.lower, d.upper, sc.grid.cells, "domain")
    return GridGeometry(shape, dx, tuple(d.lower), d.geometry)


def boundary_codes(sc: GasPart) -> tuple[tuple[int, int], ...]:
    out = []
    for k, ax in enumerate(AXES[: sc.domain.ndim]):
        lo, hi = getattr(sc.boundaries, ax)
        radial = k == 0 and sc.domain.geometry != "cartesian"
        for side, kind in (("lower", lo), ("upper", hi)):
            if kind == "axis" and not (radial and side == "lower" and sc.domain.lower[0] == 0.0):
                raise ScenarioError(f"boundaries.{ax}: 'axis' is allowed only on the lower x face of a radial "
                                    "(cylindrical, spherical, axisymmetric) domain starting at r = 0")
        if radial and sc.domain.lower[0] == 0.0 and lo != "axis":
            raise ScenarioError(f"boundaries.x: the {sc.domain.geometry} domain starts at r = 0 and needs "
                                f"'axis' on its lower face, got {lo!r}")
        if (lo == "periodic") != (hi == "periodic"):
            raise ScenarioError(f"boundaries.{ax}: 'periodic' must be given on both faces, got {[lo, hi]}")
        if radial and "periodic" in (lo, hi):
            raise ScenarioError(f"boundaries.{ax}: the radius of a {sc.domain.geometry} domain cannot be periodic")
        out.append((BOUNDARY_CODE[lo], BOUNDARY_CODE[hi]))
    return tuple(out)


def _velocity(value, ndim: int, key: str) -> np.ndarray:
    v = np.atleast_1d(np.asarray(value, float))
    if v.size == 1:
        v = np.concatenate([v, np.zeros(ndim - 1)])
    if v.size != ndim:
        raise ScenarioError(f"{key}: give one velocity component or {ndim} (one per axis), got {v.size}")
    return v


def _order(names: list[str], mats: dict) -> tuple[str, ...]:
    unique = list(dict.fromkeys(names))
    if len(unique) > 2:
        raise ScenarioError(f"at most two materials in one grid, got {unique}")
    return tuple(sorted(unique, key=lambda n: not isinstance(mats[n], JWLExplosive)))


def _gauges(sc: GasPart, g: GridGeometry):
    """Gauge points (validated inside the domain by the schema) and the cell holding each."""
    pts = np.asarray([np.atleast_1d(np.asarray(raw, float)) for raw in sc.output.gauges], float).reshape(-1, g.ndim)
    return pts, tuple(g.cell_of(p) for p in pts)


def blast_params(setup: Setup, dtype):
    """The traced blast table of ``setup`` (:class:`blastfsi.euler.config.BlastTable`), or None."""
    import jax.numpy as jnp

    b = setup.blast
    if b is None:
        return None
    return BlastTable(jnp.asarray(b.cells, jnp.int32), *(jnp.asarray(v, dtype) for v in b[1:]))


def build(sc: EulerScenario) -> Setup:
    return build_gas(GasPart.of(sc))


def build_gas(sc: GasPart) -> Setup:
    """The initial grid of the gas part ``sc`` (also the whole-domain grid of a coupled run)."""
    g = grid_geometry(sc)
    bc = boundary_codes(sc)
    init = sc.initial
    if init.kind == "charge":
        c = charge_initial(sc, g)
        gauges, gauge_cells = _gauges(sc, g)
        return Setup(grid=g, materials=c.materials, gases=c.gases, eos=c.eos, bc=bc, rho_k=c.rho_k, alpha=c.alpha,
                     velocity=c.velocity, pressure=c.pressure, reference_pressure=c.reference_pressure,
                     gauges=gauges, gauge_cells=gauge_cells, cfl=sc.cfl,
                     arrival_fraction=sc.output.arrival_fraction, start_time=c.remap.remap_time,
                     charge=c.remap, blast=c.blast)
    ndim = g.ndim
    mesh = g.mesh()
    if init.kind == "riemann":
        states = {"initial.left": init.left, "initial.right": init.right}
    else:
        states = {"initial.ambient": init.ambient}
    mats = {s.material: material(sc.materials, s.material, f"{key}.material") for key, s in states.items()}
    materials = _order([s.material for s in states.values()], mats)
    nm = len(materials)
    shape = g.shape
    rho_k = np.zeros((nm, *shape))
    alpha = np.zeros((nm, *shape))
    velocity = np.zeros((ndim, *shape))
    pressure = np.zeros(shape)
    if init.kind == "riemann":
        if not sc.domain.lower[0] < init.diaphragm < sc.domain.upper[0]:
            raise ScenarioError(f"initial.diaphragm ({init.diaphragm} m) must lie inside the domain along x "
                                f"({sc.domain.lower[0]} .. {sc.domain.upper[0]} m)")
        left = mesh[0] < init.diaphragm
        for region, s, key in ((left, init.left, "initial.left"), (~left, init.right, "initial.right")):
            k = materials.index(s.material)
            alpha[k][region] = 1.0
            pressure[region] = s.pressure
            velocity[:, region] = _velocity(s.velocity, ndim, f"{key}.velocity")[:, None]
        # phase densities uniform within each phase over the whole grid (the absent phase takes
        # its density from where it is present), so pure advection keeps them uniform
        for s in (init.left, init.right):
            rho_k[materials.index(s.material)] = s.density
        if init.left.material == init.right.material:
            rho_k[0] = np.where(left, init.left.density, init.right.density)
        p_ref = init.right.pressure
    else:
        amb = init.ambient
        alpha[0] = 1.0
        rho_k[0] = amb.density
        velocity[:] = _velocity(amb.velocity, ndim, "initial.ambient.velocity").reshape(ndim, *([1] * ndim))
        centre = np.asarray(init.center or [0.0] * ndim, float)
        if centre.size != ndim:
            raise ScenarioError(f"initial.center needs {ndim} coordinate(s), got {centre.size}")
        pressure[:] = amb.pressure
        p_ref = amb.pressure
        pressure = pressure + _point_energy_pressure(sc, g, centre, mats[amb.material])
    eos = np.array([list(mats[m].eos_params()) for m in materials], float)
    gauges, gauge_cells = _gauges(sc, g)
    return Setup(grid=g, materials=materials, gases=tuple(mats[m] for m in materials), eos=eos, bc=bc, rho_k=rho_k, alpha=alpha, velocity=velocity,
                 pressure=pressure, reference_pressure=float(p_ref), gauges=gauges, gauge_cells=gauge_cells,
                 cfl=sc.cfl, arrival_fraction=sc.output.arrival_fraction)


def cell_volumes(g: GridGeometry) -> np.ndarray:
    """Exact cell volumes: Cartesian dx^ndim (per unit length/area in 1D/2D), radial shells
    (2 pi r dr per unit length, 4/3 pi (r+^3 - r-^3)) and axisymmetric rings pi (r+^2 - r-^2) dz."""
    r = g.centres()[0]
    rm, rp = r - 0.5 * g.dx, r + 0.5 * g.dx
    if g.geometry == "cartesian":
        return np.full(g.shape, g.dx ** g.ndim)
    if g.geometry == "spherical":
        return 4.0 / 3.0 * np.pi * (rp**3 - rm**3)
    ring = np.pi * (rp**2 - rm**2)
    return ring if g.ndim == 1 else np.broadcast_to(ring[:, None] * g.dx, g.shape).copy()


def _point_energy_pressure(sc: GasPart, g: GridGeometry, centre, material) -> np.ndarray:
    """Overpressure that puts ``initial.energy`` as internal energy into the cells within
    ``radius_cells`` of the centre (weight = cell volume inside the sphere, sub-sampled),
    exactly: sum over cells of volume * delta(rho e) = E (ideal gas or JWL alike, since
    delta(rho e) = delta p / omega at fixed density)."""
    init = sc.initial
    radius = init.radius_cells * g.dx
    n_sub = 8
    offsets = (np.arange(n_sub) + 0.5) / n_sub - 0.5
    frac = np.zeros(g.shape)
    sub = np.meshgrid(*[offsets] * g.ndim, indexing="ij")
    mesh = g.mesh()
    for idx in np.ndindex(*sub[0].shape):
        d2 = sum((mesh[k] + sub[k][idx] * g.dx - centre[k]) ** 2 for k in range(g.ndim))
        frac += d2 <= radius**2
    frac /= n_sub**g.ndim
    weight = frac * cell_volumes(g)
    # mirror images: a centre on a symmetry/axis face has part of its sphere outside the domain;
    # the energy given is that of the whole (physical) blast, so count only the simulated part
    total = np.sum(weight)
    if total <= 0.0:
        raise ScenarioError("initial.center/radius_cells: the release volume holds no cell of the domain")
    omega = material.eos_params().omega
    # uniform energy density inside the sphere: sum over cells of V * delta(rho e) = E exactly
    return omega * init.energy * _domain_share(sc, g, centre) * frac / total


def _domain_share(sc: GasPart, g: GridGeometry, centre) -> float:
    """Fraction of a blast centred at ``centre`` that the domain simulates: 1/2 per
    symmetry plane or wall through the centre (the rest is its mirror image); the
    radial axis of a cylindrical/spherical/axisymmetric grid needs no such factor."""
    share = 1.0
    for k, ax in enumerate(AXES[: g.ndim]):
        if k == 0 and g.geometry != "cartesian":
            continue  # the radius: rings and shells already hold the whole blast
        lo_kind, hi_kind = getattr(sc.boundaries, ax)
        if abs(centre[k] - sc.domain.lower[k]) < 1e-9 * g.dx and lo_kind in ("wall", "symmetry"):
            share *= 0.5
        if abs(centre[k] - sc.domain.upper[k]) < 1e-9 * g.dx and hi_kind in ("wall", "symmetry"):
            share *= 0.5
    return share
