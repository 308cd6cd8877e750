"""Per-gauge comparison of a TNT blast with Kingery-Bulmash (:mod:`blastfsi.exact.kingery_bulmash`).

A gauge dict holds the computed ``peak_overpressure`` [Pa], ``impulse`` (positive
phase) [Pa s] and ``arrival_time`` [s] (the keys of the euler method's gauge
summary); :func:`compare` adds ``distance`` [m], ``scaled_distance`` Z
[m/kg^(1/3)], ``kb`` (the KB values of the same three quantities and the
positive-phase duration) and ``ratio`` (computed / KB). A gauge whose Z lies
outside a fit's validity range gets None there and a ``kb_note``.

Times: KB arrival times count from the detonation of the whole charge at its
centre; the simulations start at the lighting of the centre, the same origin.
"""
from __future__ import annotations

import numpy as np

from blastfsi.exact import kingery_bulmash as kb

KB_KEYS = {"peak_overpressure": "incident_overpressure", "impulse": "incident_impulse",
           "arrival_time": "arrival_time", "positive_phase_duration": "positive_phase_duration"}


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


def compare(gauges: list[dict], distances, tnt_mass: float, burst: str = "free-air") -> list[dict]:
    """Copies of ``gauges`` with distance, Z, the KB values and the ratios computed / KB."""
    out = []
    for g, r in zip(gauges, distances):
        r = float(r)
        entry = dict(g, distance=r)
        if r <= 0.0:
            entry.update(scaled_distance=0.0, kb=None, ratio=None, kb_note="gauge at the charge centre")
            out.append(entry)
            continue
        values, notes = kb_values(tnt_mass, r, burst)
        entry["scaled_distance"] = float(kb.scaled_distance(tnt_mass, r))
        entry["kb"] = values
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
