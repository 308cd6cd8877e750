"""The ``charge`` initial condition of the euler method: the 1D detonation on
``lagrangian1d`` (:class:`Detonation1D`: that method's own set-up and compiled time
loop, nothing written) run to the remap time, remapped conservatively by
:mod:`blastfsi.detonation.remap`. The 1D run is
spherical (j = 2) for 1D spherical, r-z and 3D Cartesian domains, and cylindrical
(j = 1) for 2D Cartesian (plane x-y) domains, where the charge is an infinitely
long cylinder along z: ``initial.mass`` is then per metre of its length [kg/m],
and so is :attr:`ChargeRemap.charge_mass`.

Remap time: ``initial.remap_time``, or automatically the arrival time
(threshold ``output.arrival_fraction`` p0) of the 1D blast at the limit radius

    R_lim = min(distance to the nearest gauge, distance to the nearest face that is
            not a mirror plane through the centre) - margin_cells dx,

found by a first 1D run with a gauge at R_lim; a second run stops there. On a fine grid the 1D
shock's foot (the zones disturbed by more than :data:`~blastfsi.detonation.remap.DISTURBED` of
ambient, the level of the remap's own disturbed-ball check) can run ahead of its
``arrival_fraction`` level by more than margin_cells dx (0.3 to 4 air zones of the 1D run,
more as the shock weakens) and cross a face by then; the remap time is then the time that foot
reaches R_lim less one 1D air zone h (the disturbed ball is read at zone edges), which keeps it
inside. A given remap time whose disturbed ball already crosses a non-mirror face, or leaves the
1D domain, is refused (ScenarioError).

Hemisphere (a surface burst, KB "surface"): its centre lies on a wall/symmetry
face; the 1D run is a sphere of twice the mass, of which the domain holds half.
In 2D Cartesian, likewise a half cylinder lying on a wall/symmetry face.

One time axis: the euler (and cfdmp) run starts at the remap time (:attr:`ChargeRemap.remap_time`),
so its history, gauges, snapshots and ``time.end`` all count from the detonation; ``time.end``
must lie after the remap time.

Stand-off charge (``initial.center`` outside the domain): R_lim is the distance from the
centre to the nearest point of the domain (or the nearest gauge) less margin_cells dx, so
the domain is still at rest at the remap. Each face the charge lies beyond is a ``blast``
face: the 1D run goes on to ``time.end`` and its conservative rows are tabulated once
(:func:`blast_table`) on radii dx / 4 apart over the distances of the layer cells (the
:data:`LAYER` cells along each blast face), at times dx / (4 S) apart, S the shock speed at
the remap (Rankine-Hugoniot from the peak overpressure: the shock only slows later). The
euler step sets those cells from the table (:func:`blastfsi.euler.boundaries.blast_layer`).
The 1D domain then reaches 1.5 c0 (time.end - t_remap) beyond the farthest layer cell: the
shock reaches its open outer end after the remap time, and the rarefaction that end sends back
runs inward at c - u, below c0 in shocked air (u grows faster than c) and near c0 in the weak
negative phase, so it cannot reach the layer before ``time.end`` (margin 1.5).

Kingery-Bulmash (:attr:`ChargeRemap.kb_burst`: "free-air" or "surface") holds for
spherical TNT charges only; for a cylinder it is None (no KB comparison).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import method as methods
from blastfsi import runtime
from blastfsi.detonation import remap as rm
from blastfsi.euler.config import MIN_CELLS, BlastTable
from blastfsi.euler.scenario import faces_toward
from blastfsi.exact import kingery_bulmash as kb
from blastfsi.materials.gases import JWLExplosive
from blastfsi.lagrangian1d.charge_problem import charge_mass, charge_radius, explosive
from blastfsi.lagrangian1d.method import METHOD as LAGRANGIAN1D
from blastfsi.scenario import AXES, ScenarioError, material, parse
from blastfsi.timeloop import FAULT_MESSAGES

EULER_GEOMETRIES = ("spherical", "axisymmetric", "cartesian")
GEOMETRY_1D = {1: "cylindrical", 2: "spherical"}  # lagrangian1d domain.geometry of exponent j
LAYER = MIN_CELLS  # cells of the blast layer along a blast face: the ghost depth of the schemes
TABLE_ROWS = 5  # products and air partial densities, radial momentum, total energy, products fraction
STEPS_PER_CALL = 20_000  # steps of one call of the 1D time loop (between the fault checks)
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ChargeRemap:
    """What the charge initial condition did (the 1D detonation and its remap), for the summary (SI units)."""

    remap_time: float  # [s] the 1D detonation's time at the remap, counted from the detonation
    remap_radius: float  # [m] the disturbed radius of the 1D blast then (remapped out to it)
    limit_radius: float  # [m] R_lim (module docstring)
    charge_radius: float  # [m]
    charge_mass: float  # [kg] the charge in the domain (half of the 1D sphere for a hemisphere; kg/m for j = 1)
    charge_center: tuple  # [m] its centre (ndim coordinates)
    kb_burst: str | None  # "free-air", "surface" (a hemisphere) or None (a 2D cylinder: no Kingery-Bulmash)
    one_d_zones: int  # zones of the 1D run
    one_d_air_zone: float  # [m] width of its air zones
    remap_share: float  # the fraction of the 1D ball inside the domain (1; 1/2 on a mirror plane ...)
    remap_mass_error: float | None = None  # relative errors of the remapped mass, products and energy against
    remap_products_error: float | None = None  # the 1D profile's inside the domain (None: nothing to compare)
    remap_energy_error: float | None = None
    blast_table_mb: float | None = None  # a stand-off charge's blast table: its memory [MB], shape (times,
    blast_table_shape: tuple | None = None  # radii, rows), the layer cells it feeds and the 1D run's length [m];
    blast_layer_cells: int | None = None  # None without blast faces
    one_d_length: float | None = None


class ChargeFields(NamedTuple):
    materials: tuple  # names: the explosive, the ambient gas
    gases: tuple  # their library entries, the scenario's overrides applied
    eos: np.ndarray
    rho_k: np.ndarray
    alpha: np.ndarray  # (n_materials, *shape) volume fractions
    velocity: np.ndarray
    pressure: np.ndarray
    reference_pressure: float
    remap: ChargeRemap
    blast: BlastTable | None = None  # a stand-off charge's blast table (host arrays), None without blast faces


def _explosive(sc) -> JWLExplosive:
    """The charge's JWL explosive, the scenario's ``[materials]`` overrides applied (else ScenarioError)."""
    return explosive(sc.initial.explosive, "initial.explosive", sc.materials.get(sc.initial.explosive))


def _ambient(sc):
    amb = sc.initial.ambient
    if amb is None:
        air = material(sc.materials, "air", "initial.ambient.material")
        return "air", air, air.density, air.pressure
    mat = material(sc.materials, amb.material, "initial.ambient.material")
    if isinstance(mat, JWLExplosive):
        raise ScenarioError(f"initial.ambient.material: {amb.material!r} is an explosive, not an ambient gas")
    if np.any(np.asarray(amb.velocity) != 0.0):
        raise ScenarioError("initial.ambient.velocity: the ambient gas around a charge must be at rest")
    return amb.material, mat, amb.density, amb.pressure


def limit_radius(sc, g, centre, mirrors, radius_1d: float) -> float:
    """R_lim (module docstring); ScenarioError if the charge itself crosses a non-mirror face."""
    d = sc.domain
    limits = []
    radial = d.geometry in ("spherical", "axisymmetric")
    if faces_toward(centre, d):  # stand-off: the nearest point of the domain
        dist = float(np.sqrt(np.sum((centre - np.clip(centre, d.lower, d.upper)) ** 2)))
        if dist < radius_1d:
            raise ScenarioError(f"initial.center: the charge (radius {radius_1d:.4g} m) overlaps the domain (its "
                                f"nearest point is {dist:.4g} m from the centre); move initial.center or the domain")
        limits.append(dist)
    for ax in range(g.ndim if not limits else 0):
        for k, face in enumerate((d.lower[ax], d.upper[ax])):
            if radial and ax == 0 and k == 0:
                continue
            dist = abs(centre[ax] - face)
            if dist <= 1e-9 * g.dx and mirrors[ax][k]:
                continue
            if dist < radius_1d:
                raise ScenarioError(f"initial: the charge (radius {radius_1d:.4g} m) overlaps the "
                                    f"{('lower', 'upper')[k]} {AXES[ax]} face of the domain ({dist:.4g} m from "
                                    "its centre); move initial.center or enlarge the domain")
            limits.append(dist)
    for p in np.asarray(sc.output.gauges, float).reshape(-1, g.ndim) if sc.output.gauges else []:
        limits.append(float(np.sqrt(np.sum((p - centre) ** 2))))
    if not limits:
        raise ScenarioError("initial.remap_time: no gauge and no open face bounds the automatic remap time; give it")
    r_lim = min(limits) - sc.initial.margin_cells * g.dx
    if r_lim <= radius_1d:
        raise ScenarioError(f"initial: the nearest gauge or face ({min(limits):.4g} m from the charge centre) "
                            f"leaves no room for the remap outside the charge (radius {radius_1d:.4g} m) with "
                            f"margin_cells = {sc.initial.margin_cells}")
    return r_lim


def arrival_time(init, hx, mass_full: float, radius: float, gas: dict, length: float, c0: float, j: int,
                 r_probe: float, level: float, overrides: dict | None = None) -> float:
    """The time the 1D blast's overpressure first exceeds ``level`` p0 at ``r_probe`` (a 1D run with a gauge
    there, to the end times of :func:`probe_times`; ``overrides``: the explosive's, :func:`one_d_scenario`);
    ScenarioError if it never does."""
    for t_probe in probe_times(init.explosive, mass_full, r_probe, c0, radius / hx.detonation_velocity, j):
        probe = Detonation1D(one_d_scenario(init.explosive, radius, init.cells, init.air_ratio, length, t_probe,
                                            gas, [r_probe], level, j, overrides=overrides))
        probe.advance_to(t_probe)
        if probe.arrival(0) is not None:
            return probe.arrival(0)
    raise ScenarioError(f"initial.remap_time: the 1D blast never reached the limit radius {r_probe:.4g} m; "
                        "give the remap time")


def one_d_scenario(explosive: str, radius: float, cells: int, air_ratio: float, length: float, t_end: float,
                   gas: dict, gauges: list | None = None, arrival_fraction: float = 0.01, j: int = 2,
                   history_samples: int = 2, overrides: dict | None = None) -> dict:
    """The ``lagrangian1d`` scenario of a charge's 1D detonation (:class:`Detonation1D`; ``blastfsi.run``
    runs it with a summary and history): a spherical (j = 2) or cylindrical (j = 1) charge of ``radius`` with
    ``cells`` zones across it, then uniform air zones ``air_ratio`` times as wide to ``length``, to
    ``t_end``, gauges at the radii ``gauges``, ``history_samples`` rows of history; ``overrides``: the
    multi-D scenario's ``[materials.<explosive>]``, so that the 1D detonation burns the explosive that the
    grid's products then follow."""
    return {"method": LAGRANGIAN1D.name, "name": "charge-1d", "charge": {"explosive": explosive, "radius": radius},
            "materials": {explosive: dict(overrides)} if overrides else {},
            "domain": {"geometry": GEOMETRY_1D[j], "length": length},
            "grid": {"cells": cells, "first_ratio": air_ratio, "max_ratio": air_ratio},
            "gas": gas, "time": {"end": t_end},
            "output": {"history_samples": history_samples, "fields": 0, "plots": False, "gauges": gauges or [],
                       "arrival_fraction": arrival_fraction}}


class Detonation1D:
    """A charge's 1D detonation (``data``: :func:`one_d_scenario`), built and advanced here with the
    ``lagrangian1d`` method's own face and compiled time loop (:func:`blastfsi.method.compiled_advance`), not
    through the driver: nothing is written, one log line says what runs. It computes in float64 whatever the
    multi-D run's precision (the remap and the blast table are taken from it)."""

    def __init__(self, data: dict):
        with runtime.precision("float64"):
            self.scenario = parse(data)
            self.setup = LAGRANGIAN1D.build(self.scenario)
            self.static = LAGRANGIAN1D.static(self.setup, self.scenario)
            self.state = jax.tree_util.tree_map(  # (a batch of one member: the compiled loop's layout)
                lambda a: jnp.asarray(a)[None],
                LAGRANGIAN1D.initial_state(self.setup, self.scenario, self.scenario.output.history_samples,
                                           jnp.float64))
            self.params = jax.tree_util.tree_map(lambda a: jnp.asarray(a)[None],
                                                 LAGRANGIAN1D.params(self.setup, jnp.float64))
        time = self.scenario.time
        self._scalars = (STEPS_PER_CALL, time.end / (self.scenario.output.history_samples - 1),
                         time.dt_min_fraction)  # (as the driver's: history samples from 0 to time.end)
        self._advance = None  # the compiled time loop, at the first advance_to

    @property
    def t(self) -> float:
        return float(np.asarray(self.state.t)[0])

    def advance_to(self, t_end: float) -> None:
        """Advance to ``t_end`` (ScenarioError on a fault or an exhausted step budget)."""
        time, scalars = self.scenario.time, self._scalars
        with runtime.precision("float64"):
            if self._advance is None:
                ch = self.scenario.charge
                mass = self.setup.charge.charge_mass
                log.info(f"1D detonation of {mass:.4g} {'kg/m' if self.setup.geometry == 1 else 'kg'} "
                         f"{ch.explosive.upper()} to t = {t_end * 1e3:.4g} ms ({self.setup.explosive_zones} zones "
                         "across the charge radius)")
                self._advance, _ = methods.compiled_advance(LAGRANGIAN1D, self.static, self.state, self.params,
                                                            t_end, *scalars)
            while self.t < t_end:
                steps = int(np.asarray(self.state.step)[0])
                if steps >= time.max_steps:
                    raise ScenarioError(f"the 1D detonation of the charge took time.max_steps = {time.max_steps} "
                                        f"steps before t = {t_end:.4g} s")
                self.state = self._advance(self.state, self.params, t_end,
                                           min(STEPS_PER_CALL, time.max_steps - steps), *scalars[1:])
                fault = int(np.asarray(self.state.fault)[0])
                if fault != 0:
                    raise ScenarioError(f"the 1D detonation of the charge failed at t = {self.t:.4g} s: "
                                        f"{FAULT_MESSAGES.get(fault, f'fault {fault}')}")

    def arrival(self, k: int) -> float | None:
        """Arrival time [s] of the blast at gauge ``k`` (``arrival_fraction`` p0), None before it."""
        t = float(np.asarray(self.state.gauge_arrival)[0, k])
        return t if np.isfinite(t) else None

    def arrays(self) -> dict:
        """The state's arrays now (NumPy, by field name)."""
        return {f: np.asarray(v)[0] for f, v in self.state._asdict().items()}

    def profile(self) -> rm.Profile1D:
        """The conservative 1D profile now (:func:`blastfsi.detonation.remap.profile_from_lagrangian`)."""
        st = self.arrays()
        return rm.profile_from_lagrangian(st["x"], st["v"], st["e"], st["zone_mass"], self.setup.explosive_zones,
                                          self.setup.geometry)


def layer_mask(sc, g) -> np.ndarray:
    """The cells of the blast layer: the LAYER cells along each ``blast`` face."""
    mask = np.zeros(g.shape, bool)
    for ax, name in enumerate(AXES[:g.ndim]):
        for side, kind in enumerate(getattr(sc.boundaries, name)):
            if kind == "blast":
                sl = [slice(None)] * g.ndim
                sl[ax] = slice(0, LAYER) if side == 0 else slice(g.shape[ax] - LAYER, g.shape[ax])
                mask[tuple(sl)] = True
    return mask


def shock_speed(st, explosive_zones: int, j: int, gamma: float, p_a: float, rho_a: float) -> float:
    """Speed of the leading shock of a 1D state (lagrangian1d arrays ``st``): the normal-shock relation
    S = c0 sqrt(1 + (gamma + 1) / (2 gamma) dp / p0) of an ideal gas at the peak air overpressure dp."""
    rho = np.asarray(st["zone_mass"]) / np.diff(np.asarray(st["x"]) ** (j + 1)) * (j + 1)  # per radian^j
    p = (gamma - 1.0) * rho[explosive_zones:] * np.asarray(st["e"])[explosive_zones:]
    dp = max(float(np.max(p)) - p_a, 0.0)
    return float(np.sqrt(gamma * p_a / rho_a * (1.0 + (gamma + 1.0) / (2.0 * gamma) * dp / p_a)))


def table_rows(profile: rm.Profile1D, radii: np.ndarray) -> np.ndarray:
    """(n_radii, TABLE_ROWS) conservative rows of a 1D profile at ``radii``, linear between zone centres
    (constant beyond the first and the last)."""
    vol = rm.shell_measures(profile.edges, profile.j)
    centres = 0.5 * (profile.edges[1:] + profile.edges[:-1])
    cols = (profile.products / vol, (profile.mass - profile.products) / vol, profile.momentum / vol,
            profile.energy / vol, (profile.products > 0.0).astype(float))
    return np.stack([np.interp(radii, centres, c) for c in cols], axis=1)


def table_plan(sc, g, centre, mask, t_remap: float, speed: float) -> dict:
    """Radii and times of the blast table (module docstring), its memory checked against
    ``initial.blast_table_mb``."""
    pts = np.stack([m[mask] for m in g.mesh()], axis=1)
    rel = pts - centre[None, :]
    dist = np.sqrt(np.sum(rel**2, axis=1))
    dr = 0.25 * g.dx
    r0 = max(float(np.min(dist)) - g.dx, 0.0)
    n_r = int(np.ceil((float(np.max(dist)) + g.dx - r0) / dr)) + 1
    dt = dr / speed
    n_t = int(np.ceil((sc.time.end - t_remap) / dt)) + 1
    mb = n_t * n_r * TABLE_ROWS * 8 / 1e6
    if mb > sc.initial.blast_table_mb:
        raise ScenarioError(f"initial.blast_table_mb = {sc.initial.blast_table_mb:g}: the blast table of the blast "
                            f"faces needs {mb:.4g} MB ({n_t} times x {n_r} radii, dx / 4 apart over "
                            f"{float(np.max(dist)) - r0:.4g} m of distances and time.end - remap time = "
                            f"{sc.time.end - t_remap:.4g} s); raise it, shorten time.end or coarsen grid.cells")
    flat = np.nonzero(mask.reshape(-1))[0]
    unit = (rel / np.where(dist > 0.0, dist, 1.0)[:, None]).T
    return {"cells": flat, "radius": (dist - r0) / dr, "unit": unit, "t0": float(t_remap), "dt": float(dt),
            "radii": r0 + dr * np.arange(n_r), "times": t_remap + dt * np.arange(n_t), "mb": mb}


def blast_table(one_d: Detonation1D, plan: dict) -> BlastTable:
    """The table of ``plan``: the 1D run ``one_d`` (at the remap time) advanced to each of its times."""
    rows = np.empty((plan["times"].size, plan["radii"].size, TABLE_ROWS))
    for k, t in enumerate(plan["times"]):
        one_d.advance_to(float(t))
        rows[k] = table_rows(one_d.profile(), plan["radii"])
    return BlastTable(plan["cells"], plan["radius"], plan["unit"], plan["t0"], plan["dt"], rows)


def probe_times(explosive: str, mass: float, r_lim: float, c0: float, burn: float, j: int) -> list[float]:
    """End times of the 1D run that finds the blast's arrival at R_lim: for a TNT sphere first 1.5 x the
    Kingery-Bulmash arrival there (the 1D TNT blast arrives within 13 % of it at Z >= 0.5,
    docs/verification.md), then the sure bound R_lim / c0 + burn time (the blast front outruns sound)."""
    sure = r_lim / c0 + burn
    try:
        guess = 1.5 * float(kb.value("arrival_time", mass, r_lim)) if explosive == "tnt" and j == 2 else sure
    except ValueError:  # outside KB's range
        guess = sure
    return [guess, sure] if guess < sure else [sure]


def charge_initial(sc, g) -> ChargeFields:
    init = sc.initial
    d = sc.domain
    if d.geometry not in EULER_GEOMETRIES or (d.geometry == "cartesian" and g.ndim == 1):
        raise ScenarioError(f"initial.kind = 'charge' needs a spherical (1D), axisymmetric, 2D Cartesian "
                            f"(a cylindrical charge) or 3D Cartesian domain, got {d.geometry} in {g.ndim}D")
    j = rm.ball_exponent(d.geometry, g.ndim)
    hx = _explosive(sc)
    air_name, air, rho_a, p_a = _ambient(sc)
    centre = np.asarray(init.center or [0.0] * g.ndim, float)
    if d.geometry in ("spherical", "axisymmetric") and centre[0] != 0.0:
        raise ScenarioError(f"initial.center: in {d.geometry} geometry the charge sits on the axis (r = 0), "
                            f"got r = {centre[0]}")
    mirrors = tuple(tuple(k in ("wall", "symmetry") for k in getattr(sc.boundaries, ax)) for ax in AXES[:g.ndim])
    hemi = init.shape == "hemisphere"
    if hemi and not any(abs(centre[ax] - (d.lower, d.upper)[k][ax]) <= 1e-9 * g.dx and mirrors[ax][k]
                        for ax in range(g.ndim) for k in (0, 1) if not (d.geometry != "cartesian" and ax == 0)):
        raise ScenarioError("initial.shape = 'hemisphere' needs initial.center on a wall or symmetry face"
                            + (" (in 2D Cartesian: a half cylinder lying on it)" if j == 1 else ""))
    mass_full = None if init.mass is None else init.mass * (2.0 if hemi else 1.0)  # kg, or kg/m for j = 1
    radius = init.radius if init.radius is not None else charge_radius(mass_full, hx.density, j)
    mass_full = charge_mass(radius, hx.density, j)
    r_lim = limit_radius(sc, g, centre, mirrors, radius)
    gas = {"gamma": air.gamma, "pressure": p_a, "density": rho_a}
    c0 = np.sqrt(air.gamma * p_a / rho_a)
    mask = layer_mask(sc, g)
    edges = tuple(lo + np.arange(n + 1) * g.dx for lo, n in zip(g.lower, g.shape))
    air_zone = init.air_ratio * radius / init.cells
    # the remap time's rules, in turn (module docstring): (gauge radius, its overpressure level / p0)
    rules = [(r_lim, sc.output.arrival_fraction)]
    if init.remap_time is None and r_lim - air_zone > radius:
        rules.append((r_lim - air_zone, rm.DISTURBED))
    far = float(np.max(np.sqrt(sum((m[mask] - c) ** 2 for m, c in zip(g.mesh(), centre))))) if mask.any() else 0.0
    for k, (r_probe, level) in enumerate(rules):
        length = 1.5 * r_lim + 10.0 * radius
        t_remap = init.remap_time if init.remap_time is not None else \
            arrival_time(init, hx, mass_full, radius, gas, length, c0, j, r_probe, level,
                         sc.materials.get(init.explosive))
        if sc.time.end <= t_remap:
            raise ScenarioError(f"time.end = {sc.time.end:g} s counts from the detonation and must lie after the "
                                f"remap time {t_remap:.6g} s (the blast reaches the limit radius {r_lim:.4g} m then)")
        if mask.any():  # the 1D run goes on to time.end and must reach beyond the farthest layer cell
            length = max(length, far + g.dx + 1.5 * c0 * (sc.time.end - t_remap) + 10.0 * radius)
        # t_remap = 0: the unburnt charge, lit at 1e-12 s (the "artificial detonation" of 000 Sec. 4.1)
        # (without a blast layer: the probe's zoning and gauge, the same compiled 1D loop)
        t_start = max(t_remap, 1e-12)
        one_d = Detonation1D(one_d_scenario(init.explosive, radius, init.cells, init.air_ratio, length,
                                            sc.time.end if mask.any() else t_start, gas, [r_probe], level, j,
                                            overrides=sc.materials.get(init.explosive)))
        one_d.advance_to(t_start)
        setup, profile = one_d.setup, one_d.profile()
        r_dist = rm.disturbed_radius(profile, rho_a, p_a / air.eos_params().omega)
        if r_dist >= 0.99 * length:
            raise ScenarioError(f"initial.remap_time = {t_remap:g} s: the blast has left the 1D domain by then")
        try:
            out = rm.remap(profile, edges, d.geometry, centre, mirrors, rho_a, p_a, hx.eos_params(),
                           air.eos_params(), n_sub=init.sub_cells, r_max=r_dist)
            break
        except rm.RemapError as err:
            if k + 1 == len(rules):
                raise ScenarioError(f"initial.remap_time = {t_remap:g} s: {err}") from None
    eos = np.array([list(hx.eos_params()), list(air.eos_params())], float)
    mass = mass_full * out.share if hemi else mass_full
    kb_burst = None if j == 1 else "surface" if hemi else "free-air"
    errors = {} if out.targets is None else {
        "remap_mass_error": float(np.sum(out.mass) / out.targets[0] - 1.0),
        "remap_products_error": float(np.sum(out.products) / out.targets[1] - 1.0),
        "remap_energy_error": float(np.sum(out.energy) / out.targets[2] - 1.0)}
    table, layer = None, {}
    if mask.any():
        speed = shock_speed(one_d.arrays(), setup.explosive_zones, j, air.gamma, p_a, rho_a)
        plan = table_plan(sc, g, centre, mask, float(t_remap), speed)
        table = blast_table(one_d, plan)
        layer = {"blast_table_mb": plan["mb"], "blast_table_shape": table.rows.shape,
                 "blast_layer_cells": int(mask.sum()), "one_d_length": float(length)}
    info = ChargeRemap(remap_time=float(t_remap), remap_radius=float(r_dist), limit_radius=float(r_lim),
                      charge_radius=float(radius), charge_mass=float(mass), charge_center=tuple(centre.tolist()),
                      kb_burst=kb_burst, one_d_zones=int(setup.cells),
                      one_d_air_zone=float(air_zone), remap_share=out.share,
                      **errors, **layer)
    alpha = np.stack([out.alpha, 1.0 - out.alpha])  # (n_materials, *shape), the layout of the euler Setup
    return ChargeFields((init.explosive, air_name), (hx, air), eos, out.rho_k, alpha, out.velocity, out.pressure,
                        float(p_a), info, table)
