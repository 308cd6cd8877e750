"""History plots: gauges (one panel each), plate and tracer histories, in units chosen from the data."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np

from blastfsi.plotting.common import plain, save
from blastfsi.plotting.units import scale

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


NO_SIGNAL = 1e-9  # of the largest |overpressure| of all gauges: below it a gauge has only round-off (not reached)


def _time_label(detonation_offset: float) -> str:
    return "time after detonation" if detonation_offset else "time"


def plate_histories_figure(histories: list[dict], members: list[dict]):
    """Four panels: plate overpressure, transmitted impulse, displacement, velocity."""
    panels = (("plate_overpressure", "overpressure on plate", "pressure"),
              ("plate_impulse", "transmitted impulse", "impulse"),
              ("plate_displacement", "plate displacement", "length"), ("plate_velocity", "plate velocity", None))
    ts = scale(np.concatenate([h["time"] for h in histories]), "time")
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for ax, (key, label, quantity) in zip(axes.flat, panels):
        s = scale(np.concatenate([h[key] for h in histories]), quantity) if quantity else None
        for hist, member in zip(histories, members):
            tag = ", ".join(f"{k.split('.')[-1]}={v:g}" for k, v in member.items()) or None
            ax.plot(hist["time"] / ts.factor, hist[key] / (s.factor if s else 1.0), lw=1.2, label=tag)
        ax.set_ylabel(s.label(label) if s else f"{label} [m/s]")
        ax.grid(alpha=0.3)
        plain(ax.xaxis, ax.yaxis)
    for ax in axes[1]:
        ax.set_xlabel(ts.label("time"))
    if 1 < len(histories) <= 12:
        axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def plate_histories(file: Path, histories: list[dict], members: list[dict]) -> None:
    save(plate_histories_figure(histories, members), file)


def _coordinates(p) -> list:
    return list(p) if isinstance(p, (list, tuple)) else [p]


def _positions(positions: list) -> list[str]:
    """Each position as "x = 2 m" (1D) or "(0.1, 0.2) m", all in the unit of the largest coordinate."""
    s = scale(np.concatenate([_coordinates(p) for p in positions]) if positions else [], "length")
    out = []
    for p in positions:
        coords = [f"{c / s.factor:g}" for c in _coordinates(p)]
        out.append(f"x = {coords[0]} {s.unit}" if len(coords) == 1 else f"({', '.join(coords)}) {s.unit}")
    return out


def gauge_histories_figure(histories: list[dict], positions: list, detonation_offset: float = 0.0):
    """Overpressure at each gauge (member 0 of an ensemble), ONE PANEL PER GAUGE on a shared time axis, each
    panel in its own pressure unit: near and far gauges differ by orders of magnitude, and what an engineer
    reads off each (arrival, peak, positive phase, negative phase) stays on a linear scale, which a log scale
    would hide (the negative phase) or distort. Positions are numbers (1D) or points; ``detonation_offset``
    is the run's t = 0 after the detonation (a charge remapped from 1D at that time), added to the time
    axis so that it reads as the summary's arrival times do."""
    hist = histories[0]
    time = hist["time"] + detonation_offset
    ts = scale(time, "time")
    n, names = len(positions), _positions(positions)
    largest = max(np.nanmax(np.abs(hist[f"gauge{k}_overpressure"]), initial=0.0) for k in range(n)) if n else 0.0
    cols = 1 if n < 4 else 2
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(8 if cols == 1 else 11, 1.0 + 2.0 * rows), sharex=True,
                             squeeze=False)
    for k, ax in enumerate(axes.flat):
        if k >= n:
            ax.axis("off")
            continue
        p = hist[f"gauge{k}_overpressure"]
        ps = scale(p, "pressure")
        ax.plot(time / ts.factor, p / ps.factor, lw=1.2)
        ax.axhline(0.0, color="k", lw=0.5)
        if np.nanmax(np.abs(p), initial=0.0) < NO_SIGNAL * largest:
            ax.set_ylim(-1.0, 1.0)  # (in Pa: not its round-off magnified)
        ax.set_title(f"gauge {k}: {names[k]}", fontsize=9)
        ax.set_ylabel(ps.label("overpressure"))
        ax.grid(alpha=0.3)
        plain(ax.xaxis, ax.yaxis)
    for col in range(min(cols, n)):
        lowest = axes.flat[max(k for k in range(n) if k % cols == col)]
        lowest.set_xlabel(ts.label(_time_label(detonation_offset)))
        lowest.xaxis.set_tick_params(labelbottom=True)
    fig.tight_layout()
    return fig


def gauge_histories(file: Path, histories: list[dict], positions: list, detonation_offset: float = 0.0) -> None:
    """:func:`gauge_histories_figure` saved to ``file``."""
    save(gauge_histories_figure(histories, positions, detonation_offset), file)


def tracer_histories_figure(histories: list[dict], positions: list, axes, detonation_offset: float = 0.0,
                            labels=None):
    """Displacement components of each tracer (member 0 of an ensemble) against time: a plate centre's
    deflection history, its peak and its permanent set (``axes``: the suffixes of the history columns
    ``tracer<k>_displacement_<axis>``; ``labels``: their names in the legend, e.g. r and z for x and y of
    an r-z run, default ``axes``; ``detonation_offset``: see :func:`gauge_histories_figure`)."""
    hist = histories[0]
    time = hist["time"] + detonation_offset
    names_of = dict(zip(axes, labels or axes))
    keys = [(k, names_of[a], f"tracer{k}_displacement_{a}") for k in range(len(positions)) for a in axes]
    ts = scale(time, "time")
    ds = scale(np.concatenate([hist[key] for *_, key in keys]), "length")
    names = _positions(positions)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, a, key in keys:
        ax.plot(time / ts.factor, hist[key] / ds.factor, lw=1.2, label=f"{names[k]}, {a}")
    ax.set_xlabel(ts.label(_time_label(detonation_offset))), ax.set_ylabel(ds.label("displacement"))
    ax.grid(alpha=0.3)
    plain(ax.xaxis, ax.yaxis)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def tracer_histories(file: Path, histories: list[dict], positions: list, axes, detonation_offset: float = 0.0,
                     labels=None) -> None:
    """:func:`tracer_histories_figure` saved to ``file``."""
    save(tracer_histories_figure(histories, positions, axes, detonation_offset, labels), file)
