"""Gauge overpressure histories beside Kingery-Bulmash (one panel per gauge).

Each panel shows the computed overpressure history and, from KB at the gauge's
distance and of the gauge's reference (free-air or surface-burst incident, or
reflected at the angle of incidence: :mod:`blastfsi.detonation.kb_compare`,
named in the panel's title and legend): the peak overpressure (horizontal
dashed line), the arrival time (vertical dashed line), and the positive phase
as the triangle of the KB peak, duration and impulse-equivalent decay: the
triangle from (t_a, p_KB) with area equal to the KB positive impulse, i.e.
ending at t_a + 2 I_KB / p_KB.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from blastfsi.detonation.kb_compare import distances, incident_reference, reference_values  # noqa: E402
from blastfsi.plotting.common import plain, save  # noqa: E402
from blastfsi.plotting.units import scale, text  # noqa: E402


def kb_gauge_histories(file: Path, hist: dict, gauges: list, tnt_mass: float, burst: str = "free-air",
                       centre=None, references: list[dict] | None = None) -> None:
    """:func:`kb_gauge_histories_figure` saved to ``file``."""
    save(kb_gauge_histories_figure(hist, gauges, tnt_mass, burst, centre, references), file)


def kb_gauge_histories_figure(hist: dict, gauges: list, tnt_mass: float, burst: str = "free-air", centre=None,
                              references: list[dict] | None = None):
    """One panel per gauge: ``hist["gauge<k>_overpressure"]`` vs time with the KB marks; one time unit for
    all panels, each panel's pressure unit from its larger of computed and KB peak.
    ``gauges``: distances (1D) or points (with ``centre``, the charge centre); ``references``: the KB
    reference of each gauge (kb_compare.infer_reference; None: the incident one of ``burst``)."""
    pts = np.asarray([g if isinstance(g, (list, tuple)) else [g] for g in gauges], float)
    r = distances(pts, np.zeros(pts.shape[1]) if centre is None else centre)
    n = len(r)
    refs = [incident_reference(burst)] * n if references is None else references
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), squeeze=False)
    ts = scale(hist["time"], "time")
    t = hist["time"] / ts.factor
    for k, ax in enumerate(axes.flat):
        if k >= n:
            ax.axis("off")
            continue
        z = r[k] / np.cbrt(tnt_mass)
        values, _ = reference_values(tnt_mass, r[k], refs[k]) if r[k] > 0 else ({}, [])
        p, ta, imp = values.get("peak_overpressure"), values.get("arrival_time"), values.get("impulse")
        computed = hist[f"gauge{k}_overpressure"]
        ps = scale(np.append(computed, [] if p is None else [p]), "pressure")
        ax.plot(t, computed / ps.factor, lw=1.1, label="computed")
        kind = refs[k]["kind"]
        if p is not None:
            ax.axhline(p / ps.factor, color="k", ls="--", lw=0.8, label=f"KB {kind} peak")
        if ta is not None:
            ax.axvline(ta / ts.factor, color="tab:red", ls="--", lw=0.8, label="KB arrival")
        if None not in (p, ta, imp):
            td = 2.0 * imp / p
            ax.fill(np.array([ta, ta, ta + td]) / ts.factor, [0.0, p / ps.factor, 0.0], color="tab:orange",
                    alpha=0.3, label=f"KB {kind} impulse {imp:.3g} Pa s")
        ax.set_title(f"R = {text(r[k], 'length', 3)}, Z = {z:.3g} m/kg$^{{1/3}}$\nKB: {refs[k]['reference']}",
                     fontsize=9)
        ax.set_xlabel(ts.label("time"))
        ax.set_ylabel(ps.label("overpressure"))
        ax.grid(alpha=0.3)
        plain(ax.xaxis, ax.yaxis)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig
