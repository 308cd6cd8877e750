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


def incident_pulse(time, gauges, reference: int = 0, arrival_fraction: float = 0.01, fall: float = 0.5) -> dict:
    """Peak, positive impulse and arrival of every gauge over the incident pulse only: from the first sample
    to the first one after the ``reference`` gauge's peak where that gauge, fallen below ``fall`` of its
    peak, rises again (a gauge that never sees a reflection sets the window; later, a gauge in front of a
    structure records the reflected wave too; ``fall`` keeps a wiggle behind the peak from ending it).
    ``gauges`` (n, G) overpressure histories; arrival: the first sample above ``arrival_fraction`` of the
    gauge's own peak. Returns the window's end and one dict per gauge."""
    t = np.asarray(time)
    g = np.asarray(gauges)
    ref = g[:, reference]
    k = int(np.argmax(ref))
    turning = (np.diff(ref[k:]) > 0.0) & (ref[k:-1] < fall * ref[k])
    if not turning.any():
        raise ValueError("the reference gauge does not fall below fall x its peak and rise again: no incident "
                         "pulse to cut")
    end = k + int(np.argmax(turning))
    tw, gw = t[:end + 1], g[:end + 1]
    out = []
    for col in gw.T:
        peak = float(col.max())
        hit = np.nonzero(col > arrival_fraction * peak)[0]
        out.append({"peak_overpressure": peak, "impulse": float(np.trapezoid(np.maximum(col, 0.0), tw)),
                    "arrival_time": float(tw[hit[0]]) if hit.size else None})
    return {"window_end": float(t[end]), "gauges": out}
