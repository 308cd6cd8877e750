"""Shock-front position from a sampled profile (host side, NumPy)."""
from __future__ import annotations

import numpy as np


def front_radius(r: np.ndarray, rho: np.ndarray, ambient: float) -> float:
    """Outermost position where the density falls through the mid-height between its
    (captured) peak and the ambient value, linearly interpolated (r increasing outward).

    For a shock spread over a few cells this is the middle of the captured jump. Where
    the post-shock profile decays steeply (Sedov) the captured peak is clipped on coarse
    grids and this estimate lies up to about one to two cells ahead of the exact front;
    the bias vanishes at first order in the cell size.
    """
    r, rho = np.asarray(r, float), np.asarray(rho, float)
    k_peak = int(np.argmax(rho))
    level = 0.5 * (rho[k_peak] + ambient)
    beyond = np.nonzero(rho[k_peak:] < level)[0]
    if beyond.size == 0:
        raise ValueError("front_radius: the density never falls back to ambient beyond its peak (front outside?)")
    k = k_peak + int(beyond[0])
    r0, r1, d0, d1 = r[k - 1], r[k], rho[k - 1], rho[k]
    return float(r0 + (level - d0) * (r1 - r0) / (d1 - d0))
