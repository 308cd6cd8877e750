"""Reflected blast load on a flat rigid surface at oblique incidence (ConWep / LS-DYNA ``*LOAD_BLAST``).

A spherical TNT charge of mass W [kg] stands at distance R (the standoff) from an infinite flat rigid
surface, on its normal through the point r = 0. A point of the surface at radius r sees the blast

    slant range        R_s = sqrt(R^2 + r^2),
    scaled distance    Z   = R_s / W^(1/3)            [m/kg^(1/3)],
    angle of incidence theta = arctan(r / R)          (0: normal incidence),

and the Kingery-Bulmash (1984) free-air values at Z (:mod:`blastfsi.exact.kingery_bulmash`): incident and
normally reflected peak overpressure P_i, P_r and positive-phase impulse I_i, I_r.

The load at oblique incidence is the blend of Randers-Pehrson and Bannister (1997), the one the ConWep
implementation in LS-DYNA uses for ``*LOAD_BLAST`` / ``*LOAD_BLAST_ENHANCED`` (ConWep option):

    Q(theta) = Q_r cos^2(theta) + Q_i (1 + cos(theta) - 2 cos^2(theta))    for cos(theta) >= 0,
    Q(theta) = Q_i                                                          for cos(theta) <  0,

applied alike to the peak overpressure (Q = P) and to the positive-phase impulse (Q = I).
Source: G. Randers-Pehrson and K. A. Bannister, "Airblast Loading Model for DYNA2D and DYNA3D", Technical
Report ARL-TR-1310, US Army Research Laboratory, March 1997; quoted in the LS-DYNA Keyword User's Manual,
``*LOAD_BLAST``. It gives Q_r at theta = 0 and Q_i at grazing incidence (theta = 90 deg) and, because
Q_r >= 2 Q_i for any shock (the acoustic limit of normal reflection is 2), it decreases monotonically from
one to the other. It is an approximation of the charts of UFC 3-340-02 (2008), Fig. 2-193 (reflected
pressure coefficient against angle of incidence) and Fig. 2-194 (scaled reflected impulse): it does NOT
reproduce the rise of the reflection coefficient near the Mach-stem (critical) angle, ~40-50 deg for strong
shocks, that those charts show; below ~30-40 deg the two agree within the reading of the charts.
At the close-in scaled distances of this module's intended use (Z ~ 0.1-0.4 m/kg^(1/3)) the KB fits are
inside their stated validity range (Z >= 0.0531 for the pressures and impulses) but the target stands in
the detonation products' cloud, which the far-field-fitted KB values do not describe.
"""
from __future__ import annotations

import numpy as np

from blastfsi.exact import kingery_bulmash as kb


def _finite(name: str, value, lower: float | None = None, strict: bool = False) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if lower is not None and (np.any(a <= lower) if strict else np.any(a < lower)):
        raise ValueError(f"{name} must be {'>' if strict else '>='} {lower:g}, got {value!r}")
    return a


def slant_range(standoff, r):
    """R_s = sqrt(R^2 + r^2) [m]: charge centre to the point at radius r [m] of a surface at standoff R [m]."""
    standoff = _finite("standoff", standoff, 0.0, strict=True)
    r = _finite("r", r, 0.0)
    return np.hypot(standoff, r)


def angle_of_incidence(standoff, r):
    """theta = arctan(r / R) [rad]: angle between the blast's ray and the surface normal."""
    standoff = _finite("standoff", standoff, 0.0, strict=True)
    r = _finite("r", r, 0.0)
    return np.arctan2(r, standoff)


def oblique_blend(reflected, incident, theta):
    """Randers-Pehrson & Bannister (1997): Q_r cos^2 t + Q_i (1 + cos t - 2 cos^2 t) (cos t >= 0), else Q_i.

    ``reflected`` Q_r and ``incident`` Q_i (>= 0, the same quantity: peak overpressure or impulse) at the
    slant range; ``theta`` in [0, pi] rad. Raises ValueError on non-finite or negative values, theta outside
    [0, pi], or Q_r < Q_i (normal reflection never weakens a blast).
    """
    q_r = _finite("reflected", reflected, 0.0)
    q_i = _finite("incident", incident, 0.0)
    t = _finite("theta", theta)
    if np.any(t < 0.0) or np.any(t > np.pi):
        raise ValueError(f"theta must lie in [0, pi] rad, got {theta!r}")
    if np.any(q_r < q_i):
        raise ValueError(f"reflected ({reflected!r}) must be >= incident ({incident!r})")
    c = np.cos(t)
    return np.where(c >= 0.0, q_r * c ** 2 + q_i * (1.0 + c - 2.0 * c ** 2), q_i)


def plate_load(mass: float, standoff: float, r, burst: str = "free-air") -> dict:
    """ConWep-style load at radii ``r`` [m] of a rigid plane at ``standoff`` [m] from ``mass`` kg TNT.

    Returns a dict of arrays (SI): ``r``, ``slant_range``, ``theta`` [rad], ``scaled_distance``,
    ``incident_overpressure``, ``reflected_overpressure``, ``incident_impulse``, ``reflected_impulse``
    (KB at the slant range, normal reflection) and ``peak_overpressure``, ``impulse`` (the oblique blend).
    A slant range outside the KB fits' validity raises ValueError (from kingery_bulmash).
    """
    mass = float(_finite("mass", mass, 0.0, strict=True))
    standoff = float(_finite("standoff", standoff, 0.0, strict=True))
    r = np.atleast_1d(_finite("r", r, 0.0))
    rs = slant_range(standoff, r)
    theta = angle_of_incidence(standoff, r)
    out = {"r": r, "slant_range": rs, "theta": theta, "scaled_distance": kb.scaled_distance(mass, rs)}
    for q in ("incident_overpressure", "reflected_overpressure", "incident_impulse", "reflected_impulse"):
        out[q] = np.asarray(kb.value(q, mass, rs, burst), dtype=float)
    out["peak_overpressure"] = oblique_blend(out["reflected_overpressure"], out["incident_overpressure"], theta)
    out["impulse"] = oblique_blend(out["reflected_impulse"], out["incident_impulse"], theta)
    return out


def total_impulse(mass: float, standoff: float, radius: float, burst: str = "free-air", points: int = 64) -> float:
    """J = integral_0^a I(r) 2 pi r dr [N s] of the blended impulse over the disc r < ``radius`` = a.

    Gauss-Legendre quadrature with ``points`` nodes (I(r) is smooth; 64 nodes converge to < 1e-8).
    """
    radius = float(_finite("radius", radius, 0.0, strict=True))
    if not isinstance(points, (int, np.integer)) or points < 2:
        raise ValueError(f"points must be an integer >= 2, got {points!r}")
    x, w = np.polynomial.legendre.leggauss(int(points))
    r = 0.5 * radius * (x + 1.0)
    load = plate_load(mass, standoff, r, burst)
    return float(np.sum(0.5 * radius * w * load["impulse"] * 2.0 * np.pi * r))
