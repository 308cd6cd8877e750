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


def kb_gauge_histories(file: Path, hist: dict, gauges: list, tnt_mass: float, burst: str = "free-air",
                       centre=None, references: list[dict] | None = None) -> None:
    """One panel per gauge: ``hist["gauge<k>_overpressure"]`` vs time with the KB marks.
    ``gauges``: distances (1D) or points (with ``centre``, the charge centre); ``references``: the KB
    reference of each gauge (kb_compare.infer_reference; None: the incident one of ``burst``)."""
    pts = np.asarray([g if isinstance(g, (list, tuple)) else [g] for g in gauges], float)
    r = distances(pts, np.zeros(pts.shape[1]) if centre is None else centre)
    n = len(r)
    refs = [incident_reference(burst)] * n if references is None else references
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), squeeze=False)
    t = hist["time"] * 1e3
    for k, ax in enumerate(axes.flat):
        if k >= n:
            ax.axis("off")
            continue
        ax.plot(t, hist[f"gauge{k}_overpressure"] / 1e3, lw=1.1, label="computed")
        z = r[k] / np.cbrt(tnt_mass)
        values, _ = reference_values(tnt_mass, r[k], refs[k]) if r[k] > 0 else ({}, [])
        p, ta, imp = values.get("peak_overpressure"), values.get("arrival_time"), values.get("impulse")
        kind = refs[k]["kind"]
        if p is not None:
            ax.axhline(p / 1e3, color="k", ls="--", lw=0.8, label=f"KB {kind} peak")
        if ta is not None:
            ax.axvline(ta * 1e3, color="tab:red", ls="--", lw=0.8, label="KB arrival")
        if None not in (p, ta, imp):
            td = 2.0 * imp / p
            ax.fill([ta * 1e3, ta * 1e3, (ta + td) * 1e3], [0.0, p / 1e3, 0.0], color="tab:orange", alpha=0.3,
                    label=f"KB {kind} impulse {imp:.3g} Pa s")
        ax.set_title(f"R = {r[k]:.3g} m, Z = {z:.3g} m/kg$^{{1/3}}$\nKB: {refs[k]['reference']}", fontsize=9)
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("overpressure [kPa]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(file, dpi=110)
    plt.close(fig)
