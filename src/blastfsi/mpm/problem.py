"""Initial particles and grid of the MPM method from a validated scenario (host side, NumPy).

Materials get indices in order of first use (bodies, then the impactor). Each
body is a lattice of ``particles_per_cell`` particles per cell and direction
(:func:`blastfsi.mpm.lattice`, spacing s = h / particles_per_cell) over its
bounding box, cut to its shape. Gas bodies start at the given density and
pressure (energy from the EOS, stress -p I); solids start unstressed at the
library's reference density.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blastfsi import mpm, xla
from blastfsi.constitutive import get as get_model
from blastfsi.constitutive import models as _models  # noqa: F401  (registers the constitutive models)
from blastfsi.eos import jwl
from blastfsi.mpm.scenario import MPMScenario
from blastfsi.scenario import AXES, ScenarioError, cells_along, material

FLUID = "fluid"


@dataclass(frozen=True)
class Setup:
    grid: mpm.Grid
    materials: tuple[str, ...]  # library names, by material index
    models: tuple  # constitutive Model per material
    model_params: tuple  # host-side model parameters per material
    particles: mpm.Particles  # the pool (capacity slots, active first)
    body: np.ndarray  # (n_active,) body index of each created particle (the impactor last)
    spacing: np.ndarray  # (n_active,) particle spacing s [m]
    tracers: tuple[int, ...]  # particle index of each tracer
    gauges: np.ndarray  # (G, ndim) gauge points [m]
    prescribed: bool
    cfl: float  # numerics.cfl
    q_quadratic: float  # numerics.q_quadratic (artificial bulk viscosity)
    q_linear: float  # numerics.q_linear
    reference_pressure: float  # numerics.reference_pressure [Pa]
    gravity: tuple  # (ndim,) body force per unit mass [m/s^2]
    driven: bool  # some body moves with a prescribed velocity (its work is not booked: no energy balance)
    bodies: tuple  # per body (the impactor last): material, particles, mass, wave speed (JSON, for the summary)
    period_theory: float | None = None  # first-mode period of a fixed-free bar with a sine velocity profile [s]
    devices: int = 1  # numerics.devices: the pool is split over them in equal parts

    @property
    def cells(self) -> int:
        return int(np.prod(self.grid.cells))

    @property
    def ndim(self) -> int:
        return self.grid.dim


def model_name(material) -> str:
    """The registered constitutive model of a library entry (gases: ``fluid``)."""
    return getattr(type(material), "model", FLUID)


def grid_of(sc: MPMScenario) -> mpm.Grid:
    g = sc.grid
    h, cells = cells_along(g.lower, g.upper, g.cells, "grid")
    faces = tuple(tuple(getattr(g.boundaries, ax)) for ax in AXES[:g.ndim])
    return mpm.Grid(origin=tuple(g.lower), cell_size=h, cells=tuple(cells), boundaries=faces,
                    axisymmetric=g.axisymmetric)


def _vector(value, ndim: int, key: str, along_last: bool = False) -> np.ndarray:
    v = np.atleast_1d(np.asarray(value, float))
    if v.size == 1 and ndim > 1:
        one = float(v[0])
        v = np.zeros(ndim)
        v[-1 if along_last else 0] = one
    if v.size != ndim:
        raise ScenarioError(f"{key}: give one component or {ndim} (one per axis), got {v.size}")
    return v


def _box_of(body, grid: mpm.Grid) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box [lower, upper] of a body."""
    if body.shape == "box":
        return np.asarray(body.lower, float), np.asarray(body.upper, float)
    c = np.asarray(body.center, float)
    if grid.axisymmetric:
        return np.array([0.0, c[1] - 0.5 * body.length]), np.array([body.radius, c[1] + 0.5 * body.length])
    half = np.full(grid.dim, body.radius)
    if grid.dim == 3:
        half[2] = 0.5 * body.length
    return c - half, c + half


def inside_body(body, x: np.ndarray, grid: mpm.Grid) -> np.ndarray:
    """Which positions (n, >= ndim) lie in the body (closed shape)."""
    d = grid.dim
    lo, hi = _box_of(body, grid)
    box = np.all((x[:, :d] >= lo) & (x[:, :d] <= hi), axis=1)
    if body.shape == "box" or grid.axisymmetric:
        return box
    c = np.asarray(body.center, float)
    return box & (np.hypot(x[:, 0] - c[0], x[:, 1] - c[1]) <= body.radius)


def _fill(grid: mpm.Grid, lower, upper, per_cell: int, key: str, grid_name: str):
    """Lattice positions, volumes and GIMP half-sizes in [lower, upper], with errors naming ``key`` and
    ``grid_name``."""
    g_lo, g_hi = np.asarray(grid.origin), np.asarray(grid.upper)
    tol = 1e-9 * grid.cell_size
    if np.any(lower < g_lo - tol) or np.any(upper > g_hi + tol):
        raise ScenarioError(f"{key}: the body [{np.asarray(lower).tolist()}, {np.asarray(upper).tolist()}] m leaves "
                            f"{grid_name} [{g_lo.tolist()}, {g_hi.tolist()}] m")
    small = (upper - lower) < grid.cell_size * (1.0 - 1e-9)
    if np.any(small):
        ax = AXES[int(np.argmax(small))]
        raise ScenarioError(f"{key}: the body is {float((upper - lower)[small][0]):g} m thick along {ax}, less than "
                            f"one cell (h = {grid.cell_size:g} m); refine grid.cells or enlarge the body")
    return mpm.lattice(grid, np.clip(lower, g_lo, g_hi), np.clip(upper, g_lo, g_hi), per_cell)


def _clamped(body, x: np.ndarray, key: str, d: int) -> np.ndarray:
    """(n, 3) bool: the velocity components the body's support boxes hold, per particle (a particle in
    several boxes is held in each one's components); a support holding no particle is an error."""
    held = np.zeros((len(x), 3), bool)
    for j, sup in enumerate(body.supports):
        inside = np.all((x[:, :d] >= np.asarray(sup.lower)) & (x[:, :d] <= np.asarray(sup.upper)), axis=1)
        if not inside.any():
            raise ScenarioError(f"{key}.supports[{j}]: the box [{sup.lower}, {sup.upper}] m holds no particle of "
                                f"the body; it must overlap the body by at least half a particle spacing")
        axes = np.arange(3) < d if sup.hold is None else np.isin(np.arange(3), [AXES.index(a) for a in sup.hold])
        held |= inside[:, None] & axes
    if held[:, :d].all():
        raise ScenarioError(f"{key}.supports: the supports hold the whole body; clamp only part of it")
    return held


def _initial_gas_state(material, density, pressure, key: str):
    """(density, specific energy, pressure) of a gas body."""
    rho = material.density if density is None else density
    if pressure is None:
        if not hasattr(material, "pressure"):
            raise ScenarioError(f"{key}.pressure: give the initial pressure of the {type(material).__name__} gas")
        pressure = material.pressure
    e = float(jwl.energy(rho, pressure, material.eos_params()))
    if not e > 0.0:
        raise ScenarioError(f"{key}.pressure: {pressure:g} Pa at density {rho:g} kg/m^3 gives a non-positive "
                            "internal energy")
    return rho, e, pressure


@dataclass(frozen=True)
class Placement:
    """Bodies placed on a grid (:func:`place`): materials by index, the created particles (active only, in body
    order), and per particle its body and spacing."""

    names: tuple[str, ...]  # library names, by material index
    library: tuple  # the library entry of each material
    models: tuple  # constitutive Model per material
    model_params: tuple  # host-side model parameters per material
    particles: mpm.Particles  # (n,) created particles
    body: np.ndarray  # (n,) body index (the impactor last)
    spacing: np.ndarray  # (n,) particle spacing s [m]
    extents: tuple[float, ...]  # per body of ``bodies``, its extent along x [m]
    tracers: tuple[int, ...]  # particle index of each tracer point


def place(bodies, grid: mpm.Grid, overrides: dict, *, tracers=(), impactor=None, key: str = "bodies",
          grid_name: str = "the grid") -> Placement:
    """Fill ``bodies`` (and the ``impactor`` rod) with particles on ``grid``; ``overrides`` the scenario's
    ``[materials]``; ``tracers`` points, each mapped to the nearest particle. Errors name ``key[k]`` for the
    k-th body and ``grid_name`` for the grid (the ``mpm`` method's ``bodies`` and grid, or the structures in
    the MPM box of a coupled run)."""
    d = grid.dim
    names: list[str] = []
    library: dict[str, object] = {}

    def index(name: str, field: str) -> int:
        if name not in library:
            library[name] = material(overrides, name, field)
            names.append(name)
        return names.index(name)

    batches, body_ids, spacings, extents = [], [], [], []
    for k, b in enumerate(bodies):
        body_key = f"{key}[{k}]"
        mat_index = index(b.material, f"{body_key}.material")
        mat = library[b.material]
        lower, upper = _box_of(b, grid)
        x, vol, half = _fill(grid, lower, upper, b.particles_per_cell, body_key, grid_name)
        keep = inside_body(b, x, grid)
        if not keep.any():
            raise ScenarioError(f"{body_key}: the body holds no particle; enlarge it or refine grid.cells")
        x, vol, half = x[keep], vol[keep], half[keep]
        for j, other in enumerate(bodies[:k]):
            clash = inside_body(other, x, grid)
            if clash.any():
                raise ScenarioError(f"{key}[{j}] and {body_key} overlap (e.g. at {x[clash][0, :d].tolist()} m); "
                                    "bodies must not share volume")
        s = grid.cell_size / b.particles_per_cell
        v = np.zeros((len(vol), 3))
        v[:, :d] = _vector(b.velocity, d, f"{body_key}.velocity")
        if b.velocity_profile == "sine":
            v *= np.sin(0.5 * np.pi * (x[:, :1] - lower[0]) / (upper[0] - lower[0]))
        is_gas = model_name(mat) == FLUID
        if not is_gas and (b.density is not None or b.pressure is not None):
            raise ScenarioError(f"{body_key}: density and pressure are initial states of gases; {b.material!r} is a "
                                f"solid (override its reference density under materials.{b.material})")
        if is_gas:
            rho, energy, p = _initial_gas_state(mat, b.density, b.pressure, body_key)
            stress = [-p, -p, -p, 0.0, 0.0, 0.0]
        else:
            rho, energy, stress = mat.density, 0.0, None
        load = None
        if b.top_traction is not None:
            traction = np.zeros(3)
            traction[:d] = _vector(b.top_traction, d, f"{body_key}.top_traction", along_last=True)
            top = x[:, d - 1] > np.max(x[:, d - 1]) - 0.5 * s
            load = np.where(top[:, None], mpm.surface_load(traction, s), 0.0)
        held = _clamped(b, x, body_key, d)
        free = ~held.any(axis=1)
        parts = [(free, dict(v=v[free], prescribed=v[free] if b.prescribed else None))]
        for mask in np.unique(held[~free], axis=0):  # clamped: zero prescribed velocity in the held components,
            part = np.all(held == mask, axis=1)  # one batch per set of held components
            parts.append((part, dict(v=None, prescribed=np.zeros((int(part.sum()), 3)), held=mask)))
        for part, motion in parts:
            batches.append(dict(x=x[part], volume=vol[part], density=rho, material=mat_index, half_size=half[part],
                                stress=stress, energy=energy, surface_load=None if load is None else load[part],
                                **motion))
            body_ids.append(np.full(int(part.sum()), k))
            spacings.append(np.full(int(part.sum()), s))
        extents.append(float(upper[0] - lower[0]))

    imp = impactor
    if imp is not None:
        mat_index = index(imp.material, "impactor.material")
        mat = library[imp.material]
        if model_name(mat) == FLUID:
            raise ScenarioError(f"impactor.material: {imp.material!r} is a gas; the impactor is a solid rod")
        lower = np.asarray(grid.origin, float).copy()
        upper = lower.copy()
        upper[:d - 1] += 0.5 * imp.diameter
        lower[d - 1] += imp.standoff
        upper[d - 1] = lower[d - 1] + imp.length
        x, vol, half = _fill(grid, lower, upper, imp.particles_per_cell, "impactor", grid_name)
        if d == 3:
            keep = np.hypot(x[:, 0] - grid.origin[0], x[:, 1] - grid.origin[1]) <= 0.5 * imp.diameter
            x, vol, half = x[keep], vol[keep], half[keep]
        for j, other in enumerate(bodies):
            clash = inside_body(other, x, grid)
            if clash.any():
                raise ScenarioError(f"{key}[{j}] and the impactor overlap (e.g. at {x[clash][0, :d].tolist()} m)")
        v = np.zeros((len(vol), 3))
        v[:, d - 1] = -imp.velocity
        batches.append(dict(x=x, volume=vol, density=mat.density, v=v, material=mat_index, half_size=half,
                            stress=None, energy=0.0, prescribed=None, surface_load=None))
        body_ids.append(np.full(len(vol), len(bodies)))
        spacings.append(np.full(len(vol), grid.cell_size / imp.particles_per_cell))

    history = max(get_model(model_name(library[n])).history_size for n in names)
    parts = [mpm.new_particles(b.pop("x")[:, :d], b.pop("volume"), b.pop("density"), history_size=history, **b)
             for b in batches]
    batch = mpm.concatenate(*parts)
    models = tuple(get_model(model_name(library[n_])) for n_ in names)
    params = []
    for name, model in zip(names, models):
        try:
            params.append(model.params_from(library[name]))
        except ValueError as err:
            raise ScenarioError(f"materials.{name}: {err}") from None
    x0 = np.asarray(batch.x)[:, :d]
    found = []
    for k, p in enumerate(tracers):
        dist = np.linalg.norm(x0 - np.asarray(p, float), axis=1)
        j = int(np.argmin(dist))
        if dist[j] > grid.cell_size:
            raise ScenarioError(f"output.tracers[{k}] = {p} m: no particle within one cell (h = {grid.cell_size:g} m)")
        found.append(j)
    return Placement(tuple(names), tuple(library[n_] for n_ in names), models, tuple(params), batch,
                     np.concatenate(body_ids), np.concatenate(spacings), tuple(extents), tuple(found))


def build(sc: MPMScenario, devices: int = 1) -> Setup:
    """The set-up of ``sc``; ``devices``: the pool is split over that many devices in equal parts, so its
    capacity is rounded up to a multiple of it."""
    grid = grid_of(sc)
    d = grid.dim
    imp = sc.impactor
    pl = place(sc.bodies, grid, sc.materials, tracers=sc.output.tracers, impactor=imp)
    n = int(np.asarray(pl.particles.active).sum())
    capacity = sc.numerics.capacity or n
    if capacity < n:
        raise ScenarioError(f"numerics.capacity = {capacity} is too small: the bodies hold {n} particles; "
                            f"set numerics.capacity >= {n}")
    pool = mpm.make_pool(pl.particles, xla.equal_parts(capacity, devices))
    gauges = np.asarray(sc.output.gauges, float).reshape(-1, d)
    body = pl.body
    mass = np.asarray(pool.mass)[:n]
    speeds = np.asarray(mpm.initialize(pool, mpm.make_params(pl.model_params), mpm.make_config(grid, pl.models))
                        .particles.wave_speed)[:n]
    bodies = tuple({"material": (sc.bodies[k].material if k < len(sc.bodies) else imp.material),
                    "particles": int(np.sum(body == k)), "mass": float(np.sum(mass[body == k])),
                    "wave_speed": float(np.max(speeds[body == k]))}
                   for k in range(len(sc.bodies) + (imp is not None)))
    sine = [k for k, b in enumerate(sc.bodies) if b.velocity_profile == "sine"]
    # fixed-free bar, first mode: T = 4 L / c (c the longitudinal wave speed)
    period = 4.0 * pl.extents[sine[0]] / bodies[sine[0]]["wave_speed"] if sine else None
    num = sc.numerics
    return Setup(grid=grid, materials=pl.names, models=pl.models, model_params=pl.model_params, particles=pool,
                 body=body, spacing=pl.spacing, tracers=pl.tracers, gauges=gauges,
                 prescribed=any(b.prescribed or b.supports for b in sc.bodies), cfl=num.cfl,
                 q_quadratic=num.q_quadratic, q_linear=num.q_linear, reference_pressure=num.reference_pressure,
                 gravity=tuple(sc.gravity) or (0.0,) * d, driven=any(b.prescribed for b in sc.bodies),
                 bodies=bodies, period_theory=period, devices=devices)
