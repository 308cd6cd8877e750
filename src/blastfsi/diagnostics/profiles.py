from __future__ import annotations

import numpy as np

from blastfsi.eos import ideal_gas


def zone_profile(state, member: int, gamma: float):
    """Zone centres, zone widths and pressures (including q) of one ensemble member."""
    x = np.asarray(state.x[member])
    dx = np.diff(x)
    rho = np.asarray(state.zone_mass[member]) / dx
    return 0.5 * (x[1:] + x[:-1]), dx, ideal_gas.pressure(rho, np.asarray(state.e[member]), gamma) + np.asarray(
        state.q[member])


def front_position(xc, p, level: float) -> float:
    """Position of the right-running front: where p last drops through ``level``
    (linear interpolation between the last zone at or above it and the next)."""
    above = np.nonzero(p >= level)[0]
    if above.size == 0 or above[-1] == p.size - 1:
        raise ValueError(f"no front crossing level {level:g} inside the domain")
    i = above[-1]
    return float(xc[i] + (level - p[i]) * (xc[i + 1] - xc[i]) / (p[i + 1] - p[i]))


def l1_relative_error(values, reference, widths) -> float:
    """sum |values - reference| dx / sum |reference| dx."""
    return float(np.sum(np.abs(values - reference) * widths) / np.sum(np.abs(reference) * widths))
