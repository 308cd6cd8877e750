"""Per-gauge comparison of a TNT blast with Kingery-Bulmash (:mod:`blastfsi.exact.kingery_bulmash`).

A gauge dict holds the computed ``peak_overpressure`` [Pa], ``impulse`` (positive
phase) [Pa s] and ``arrival_time`` [s] (the keys of the euler method's gauge
summary); :func:`compare` adds ``distance`` [m], ``scaled_distance`` Z
[m/kg^(1/3)], ``kb`` (the KB values of the same three quantities and the
positive-phase duration, and which reference they are) and ``ratio`` (computed /
KB). A gauge whose Z lies outside a fit's validity range gets None there and a
``kb_note``.

The reference (:func:`infer_reference`, per gauge; ``output.gauge_references``
of the euler method sets it explicitly):

* ``incident``: the side-on (incident) overpressure and impulse of the run's
  burst: KB spherical free-air burst for a sphere, KB hemispherical surface
  burst for a hemisphere on a wall/symmetry face. A gauge in free air gets it,
  and so does a gauge on a wall or symmetry plane through the charge centre
  (the ground under a surface burst, a symmetry plane of a quarter model): the
  blast runs along such a plane (grazing incidence).
* ``surface-incident``: KB hemispherical surface burst incident with the
  charge mass as given, whatever the charge's shape (a sphere resting on the
  ground, as ConWep's surface burst treats it).
* ``reflected``: a gauge within :data:`WALL_CELLS` cells of a ``wall`` or
  ``symmetry`` face that faces the charge and does not pass through its centre
  (a symmetry plane off the charge mirrors it: the same load as a rigid wall).
  KB normally reflected and incident values at the slant range R (the gauge's
  distance), blended for the angle of incidence theta between the face's
  normal and the ray from the charge centre by the ConWep rule of
  :func:`blastfsi.exact.oblique_reflection.oblique_blend` (Randers-Pehrson &
  Bannister 1997): theta = 0 is KB reflected itself. Near several such faces
  (a corner) the one of the smallest theta is taken. The blend does not model
  the Mach stem (its rise of the reflection coefficient near 40-50 deg), and
  a gauge in free air that a Mach stem sweeps (close above the ground of a
  height-of-burst) is still compared with free-air incident values.
  The arrival time is KB's at the slant range and the positive-phase duration
  the incident one (KB has no fit of the reflected duration; ConWep uses the
  incident one likewise).

Times: KB arrival times count from the detonation of the whole charge at its
centre; the simulations start at the lighting of the centre, the same origin.
"""
from __future__ import annotations

import math

import numpy as np

from blastfsi.exact import kingery_bulmash as kb
from blastfsi.exact import oblique_reflection as obl

KB_KEYS = {"peak_overpressure": "incident_overpressure", "impulse": "incident_impulse",
           "arrival_time": "arrival_time", "positive_phase_duration": "positive_phase_duration"}
REFLECTED_KEYS = {"peak_overpressure": "reflected_overpressure", "impulse": "reflected_impulse"}
REFERENCES = ("auto", "incident", "reflected", "surface-incident")  # values of output.gauge_references
WALL_CELLS = 2.0  # a gauge this many cells or fewer from a wall/symmetry face is "on" it
AXIS_NAMES = ("x", "y", "z")


def kb_values(tnt_mass: float, distance: float, burst: str = "free-air") -> tuple[dict, list[str]]:
    """KB values (SI) of the keys of :data:`KB_KEYS` at ``distance`` from ``tnt_mass`` kg of TNT,
    and notes for the quantities outside their validity range (value None)."""
    out, notes = {}, []
    for key, quantity in KB_KEYS.items():
        try:
            out[key] = float(kb.value(quantity, tnt_mass, distance, burst))
        except ValueError as err:
            out[key] = None
            notes.append(str(err))
    return out, notes


# ----------------------------------------------------------------------------------------------- references
def incident_reference(burst: str = "free-air", source: str = "auto") -> dict:
    """The incident reference of a ``burst`` ("free-air" or "surface")."""
    kb._check_burst(burst)
    label = "free-air incident" if burst == "free-air" else "surface-burst incident (hemispherical)"
    return {"reference": label, "kind": "incident", "burst": burst, "angle_of_incidence_deg": None,
            "face": None, "source": source}


def reflected_reference(theta: float, burst: str = "free-air", face: str | None = None,
                        source: str = "auto") -> dict:
    """The reflected reference at angle of incidence ``theta`` [rad] (0: normal) of a ``burst``."""
    kb._check_burst(burst)
    deg = math.degrees(float(theta))
    how = "normal" if round(deg) == 0 else f"oblique, {deg:.0f} deg"
    label = f"reflected ({how})" + ("" if burst == "free-air" else ", surface burst")
    return {"reference": label, "kind": "reflected", "burst": burst, "angle_of_incidence_deg": deg,
            "face": face, "source": source}


def reflecting_faces(geometry: str, lower, upper, boundaries) -> list[dict]:
    """The ``wall`` and ``symmetry`` faces of a domain that a blast inside it can hit, each a dict with
    ``axis``, ``side`` (0 lower, 1 upper), ``coordinate`` [m], ``normal`` (unit, into the domain) and ``name``
    ("y lower wall"). ``boundaries``: per axis the pair of kinds (an object with attributes x, y, z, or a
    sequence of pairs). In 1D spherical/cylindrical and r-z geometry the lower x face is the axis (r = 0,
    where the charge sits) and the upper x face, a wall, is a sphere/cylinder r = const with normal -r."""
    ndim = len(lower)
    out = []
    for ax in range(ndim):
        kinds = boundaries[ax] if isinstance(boundaries, (list, tuple)) else getattr(boundaries, AXIS_NAMES[ax])
        for side in (0, 1):
            if kinds[side] not in ("wall", "symmetry"):
                continue
            if geometry != "cartesian" and ax == 0 and side == 0:
                continue  # r = lower: the axis side, behind the charge on the axis
            normal = np.zeros(ndim)
            normal[ax] = 1.0 if side == 0 else -1.0
            out.append({"axis": ax, "side": side, "coordinate": float((lower, upper)[side][ax]), "normal": normal,
                        "name": f"{AXIS_NAMES[ax]} {('lower', 'upper')[side]} {kinds[side]}"})
    return out


def infer_reference(point, centre, faces: list[dict], dx: float, burst: str = "free-air",
                    override: str = "auto") -> dict:
    """The KB reference of a gauge at ``point`` (see the module docstring): ``override`` "auto" infers it
    from the gauge's position (within WALL_CELLS * ``dx`` of a face of ``faces`` (:func:`reflecting_faces`)
    that faces the charge at ``centre`` and does not pass through it: reflected, else incident of ``burst``);
    "incident", "reflected" or "surface-incident" set it (reflected: at the angle of the nearest such face
    if any, else normal incidence)."""
    if override not in REFERENCES:
        raise ValueError(f"gauge reference must be one of {REFERENCES}, got {override!r}")
    source = "auto" if override == "auto" else "set"
    if override == "incident":
        return incident_reference(burst, source)
    if override == "surface-incident":
        return incident_reference("surface", source)
    p = np.asarray(point, float)
    c = np.asarray(centre, float)
    ray = c - p  # gauge -> charge
    dist = float(np.linalg.norm(ray))
    best = None
    for f in faces:
        ax = f["axis"]
        if abs(p[ax] - f["coordinate"]) > WALL_CELLS * dx * (1.0 + 1e-9):
            continue  # not on this face
        if abs(c[ax] - f["coordinate"]) <= 1e-9 * max(dx, 1.0):
            continue  # a plane through the charge centre: its own symmetry plane (or the ground of a surface burst)
        cos_t = float(np.dot(ray, f["normal"])) / dist if dist > 0.0 else 1.0
        if cos_t <= 0.0:
            continue  # the charge is behind the face
        theta = math.acos(min(1.0, cos_t))
        if best is None or theta < best[0]:
            best = (theta, f["name"])
    if best is not None:
        return reflected_reference(best[0], burst, best[1], source)
    if override == "reflected":
        return reflected_reference(0.0, burst, None, source)  # no face here: as if the gauge faced the charge
    return incident_reference(burst, source)


def gauge_references(points, centre, geometry: str, lower, upper, boundaries, dx: float,
                     burst: str = "free-air", overrides=None) -> list[dict]:
    """:func:`infer_reference` for every gauge point; ``overrides``: None (all "auto") or one entry per gauge."""
    faces = reflecting_faces(geometry, lower, upper, boundaries)
    overrides = ["auto"] * len(points) if overrides is None else list(overrides)
    if len(overrides) != len(points):
        raise ValueError(f"{len(overrides)} gauge references for {len(points)} gauges")
    return [infer_reference(p, centre, faces, dx, burst, o) for p, o in zip(points, overrides)]


def scenario_references(sc, centre, burst: str, dx: float) -> list[dict]:
    """The references of the gauges of an euler scenario ``sc`` with a charge centred at ``centre``, KB
    ``burst`` ("free-air" or "surface"), on a grid of spacing ``dx``."""
    d = sc.domain
    points = [g if isinstance(g, (list, tuple)) else [g] for g in sc.output.gauges]
    return gauge_references(points, centre, d.geometry, d.lower, d.upper, sc.boundaries, dx, burst,
                            getattr(sc.output, "gauge_references", None))


def reference_values(tnt_mass: float, distance: float, reference: dict | None = None) -> tuple[dict, list[str]]:
    """KB values (SI) of the keys of :data:`KB_KEYS` for a ``reference`` (:func:`infer_reference`; None: the
    free-air incident one) at ``distance`` (the slant range), with notes as :func:`kb_values`."""
    reference = incident_reference() if reference is None else reference
    values, notes = kb_values(tnt_mass, distance, reference["burst"])
    if reference["kind"] == "reflected":
        theta = math.radians(reference["angle_of_incidence_deg"])
        for key, quantity in REFLECTED_KEYS.items():
            q_i = values[key]
            try:
                q_r = float(kb.value(quantity, tnt_mass, distance, reference["burst"]))
            except ValueError as err:
                values[key] = None
                notes.append(str(err))
                continue
            values[key] = None if q_i is None else float(obl.oblique_blend(q_r, q_i, theta))
    return values, notes


def compare(gauges: list[dict], distances, tnt_mass: float, burst: str = "free-air",
            references: list[dict] | None = None) -> list[dict]:
    """Copies of ``gauges`` with distance, Z, the KB values (of ``references``, one per gauge; None: the
    incident ones of ``burst``) with the reference's description, and the ratios computed / KB."""
    out = []
    references = [incident_reference(burst)] * len(gauges) if references is None else references
    for g, r, ref in zip(gauges, distances, references):
        r = float(r)
        entry = dict(g, distance=r)
        if r <= 0.0:
            entry.update(scaled_distance=0.0, kb=None, ratio=None, kb_note="gauge at the charge centre")
            out.append(entry)
            continue
        values, notes = reference_values(tnt_mass, r, ref)
        entry["scaled_distance"] = float(kb.scaled_distance(tnt_mass, r))
        entry["kb"] = {**ref, **values}
        entry["ratio"] = {k: (g[k] / v if g.get(k) is not None and v else None)
                          for k, v in values.items() if k in g}
        if notes:
            entry["kb_note"] = "; ".join(notes)
        out.append(entry)
    return out


def distances(points, centre) -> np.ndarray:
    """Euclidean distance of each gauge point from the charge centre."""
    pts = np.atleast_2d(np.asarray(points, float))
    return np.sqrt(np.sum((pts - np.asarray(centre, float)[None, :]) ** 2, axis=1))
