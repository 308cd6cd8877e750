"""The ``charge`` initial condition of the euler method: the 1D detonation on
``lagrangian1d`` (through the same driver, nothing written) run to the remap
time, remapped conservatively by :mod:`blastfsi.detonation.remap`. The 1D run is
spherical (j = 2) for 1D spherical, r-z and 3D Cartesian domains, and cylindrical
(j = 1) for 2D Cartesian (plane x-y) domains, where the charge is an infinitely
long cylinder along z: ``initial.mass`` is then per metre of its length [kg/m],
and so is ``info["charge_mass"]``.

Remap time: ``initial.remap_time``, or automatically the arrival time
(threshold ``output.arrival_fraction`` p0) of the 1D blast at the limit radius

    R_lim = min(distance to the nearest gauge, distance to the nearest face that is
            not a mirror plane through the centre) - margin_cells dx,

found by a first 1D run with a gauge at R_lim; a second run stops there. A given
remap time whose disturbed ball already crosses a non-mirror face, or leaves the
1D domain, is refused (ScenarioError).

Hemisphere (a surface burst, KB "surface"): its centre lies on a wall/symmetry
face; the 1D run is a sphere of twice the mass, of which the domain holds half.
In 2D Cartesian, likewise a half cylinder lying on a wall/symmetry face.
Simulated time 0 of the euler run is the remap time (``info["remap_time"]``).

Kingery-Bulmash (``info["kb_burst"]``: "free-air" or "surface") holds for
spherical TNT charges only; for a cylinder it is None (no KB comparison).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from blastfsi.detonation import remap as rm
from blastfsi.scenario import AXES
from blastfsi.materials import MaterialError, lookup
from blastfsi.materials.gases import GASES, JWLExplosive
from blastfsi.problems.detonation import EXPLOSIVES, charge_mass, charge_radius
from blastfsi.scenario import ScenarioError

EULER_GEOMETRIES = ("spherical", "axisymmetric", "cartesian")
GEOMETRY_1D = {1: "cylindrical", 2: "spherical"}  # lagrangian1d domain.geometry of exponent j


class ChargeFields(NamedTuple):
    materials: tuple
    eos: np.ndarray
    rho_k: np.ndarray
    alpha: np.ndarray  # (n_materials, *shape) volume fractions
    velocity: np.ndarray
    pressure: np.ndarray
    reference_pressure: float
    info: dict


def _material(sc, name: str, key: str):
    try:
        return lookup(name, sc.materials.get(name), field=key)
    except MaterialError as err:
        raise ScenarioError(str(err)) from None


def _explosive(sc) -> JWLExplosive:
    name = sc.initial.explosive
    if name not in GASES or not isinstance(GASES[name], JWLExplosive):
        raise ScenarioError(f"initial.explosive: unknown explosive {name!r}; available: {', '.join(EXPLOSIVES)}")
    return _material(sc, name, "initial.explosive")


def _ambient(sc):
    amb = sc.initial.ambient
    if amb is None:
        air = _material(sc, "air", "initial.ambient.material")
        return "air", air, air.density, air.pressure
    mat = _material(sc, amb.material, "initial.ambient.material")
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
    for ax in range(g.ndim):
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


def run_1d(explosive: str, radius: float, cells: int, air_ratio: float, length: float, t_end: float, gas: dict,
           gauges: list | None = None, arrival_fraction: float = 0.01, j: int = 2):
    """The 1D spherical (j = 2) or cylindrical (j = 1) detonation on ``lagrangian1d`` to ``t_end``
    (a :class:`blastfsi.simulation.Result`): ``cells`` zones across the charge radius, then uniform air
    zones ``air_ratio`` times as wide."""
    from blastfsi import simulation

    data = {"method": "lagrangian1d", "name": "charge-1d", "charge": {"explosive": explosive, "radius": radius},
            "domain": {"geometry": GEOMETRY_1D[j], "length": length},
            "grid": {"cells": cells, "first_ratio": air_ratio, "max_ratio": air_ratio},
            "gas": gas, "time": {"end": t_end},
            "output": {"history_samples": 2, "fields": 0, "plots": False, "gauges": gauges or [],
                       "arrival_fraction": arrival_fraction}}
    return simulation.run(data)


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
    length = 1.5 * r_lim + 10.0 * radius
    c0 = np.sqrt(air.gamma * p_a / rho_a)
    if init.remap_time is None:
        probe = run_1d(init.explosive, radius, init.cells, init.air_ratio, length,
                       r_lim / c0 + radius / hx.detonation_velocity, gas, [r_lim], sc.output.arrival_fraction, j)
        t_remap = probe.summary["gauges"][0]["arrival_time"]
        if t_remap is None:
            raise ScenarioError("initial.remap_time: the 1D blast never reached the limit radius "
                                f"{r_lim:.4g} m; give the remap time")
    else:
        t_remap = init.remap_time
    # t_remap = 0: the unburnt charge, lit at 1e-12 s (the "artificial detonation" of 000 Sec. 4.1)
    res = run_1d(init.explosive, radius, init.cells, init.air_ratio, length, max(t_remap, 1e-12), gas, j=j)
    setup = res.setups[0]
    st = {k: np.asarray(v)[0] for k, v in res.state._asdict().items()}
    profile = rm.profile_from_lagrangian(st["x"], st["v"], st["e"], st["zone_mass"], setup.explosive_zones,
                                         setup.geometry)
    r_dist = rm.disturbed_radius(profile, rho_a, p_a / air.eos_params().omega)
    if r_dist >= 0.99 * length:
        raise ScenarioError(f"initial.remap_time = {t_remap:g} s: the blast has left the 1D domain by then")
    edges = tuple(lo + np.arange(n + 1) * g.dx for lo, n in zip(g.lower, g.shape))
    try:
        out = rm.remap(profile, edges, d.geometry, centre, mirrors, rho_a, p_a, hx.eos_params(), air.eos_params(),
                       n_sub=init.sub_cells, r_max=r_dist)
    except rm.RemapError as err:
        raise ScenarioError(f"initial.remap_time = {t_remap:g} s: {err}") from None
    eos = np.array([list(hx.eos_params()), list(air.eos_params())], float)
    mass = mass_full * out.share if hemi else mass_full
    kb_burst = None if j == 1 else "surface" if hemi else "free-air"
    info = {"remap_time": float(t_remap), "remap_radius": float(r_dist), "limit_radius": float(r_lim),
            "charge_radius": float(radius), "charge_mass": float(mass), "charge_center": centre.tolist(),
            "kb_burst": kb_burst, "one_d_zones": int(setup.cells),
            "one_d_air_zone": float(init.air_ratio * radius / init.cells),
            "remap_share": out.share,
            "remap_mass_error": float(np.sum(out.mass) / out.targets[0] - 1.0),
            "remap_products_error": float(np.sum(out.products) / out.targets[1] - 1.0),
            "remap_energy_error": float(np.sum(out.energy) / out.targets[2] - 1.0)}
    alpha = np.stack([out.alpha, 1.0 - out.alpha])  # (n_materials, *shape), the layout of the euler Setup
    return ChargeFields((init.explosive, air_name), eos, out.rho_k, alpha, out.velocity, out.pressure, float(p_a),
                        info)
