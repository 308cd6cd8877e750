from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def plate_histories(file: Path, histories: list[dict], members: list[dict]) -> None:
    """Four panels: plate overpressure, transmitted impulse, displacement, velocity."""
    panels = (("plate_overpressure", "overpressure on plate [Pa]"), ("plate_impulse", "transmitted impulse [Pa s]"),
              ("plate_displacement", "plate displacement [m]"), ("plate_velocity", "plate velocity [m/s]"))
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for ax, (key, label) in zip(axes.flat, panels):
        for hist, member in zip(histories, members):
            tag = ", ".join(f"{k.split('.')[-1]}={v:g}" for k, v in member.items()) or None
            ax.plot(hist["time"] * 1e3, hist[key], lw=1.2, label=tag)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time [ms]")
    if len(histories) > 1 and len(histories) <= 12:
        axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)


def _position(p) -> str:
    coords = p if isinstance(p, (list, tuple)) else [p]
    return "(" + ", ".join(f"{c:g}" for c in coords) + ") m" if len(coords) > 1 else f"x = {coords[0]:g} m"


def _time_label(detonation_offset: float) -> str:
    return "time after detonation [ms]" if detonation_offset else "time [ms]"


def gauge_histories(file: Path, histories: list[dict], positions: list, detonation_offset: float = 0.0) -> None:
    """Overpressure at each gauge (member 0 of an ensemble); positions are numbers (1D) or points.
    ``detonation_offset``: the run's t = 0 after the detonation (a charge remapped from 1D at that time),
    added to the time axis so that it reads as the summary's arrival times do."""
    hist = histories[0]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, x in enumerate(positions):
        ax.plot((hist["time"] + detonation_offset) * 1e3, hist[f"gauge{k}_overpressure"] / 1e3, lw=1.2,
                label=_position(x))
    ax.set_xlabel(_time_label(detonation_offset)), ax.set_ylabel("overpressure [kPa]"), ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)


def tracer_histories(file: Path, histories: list[dict], positions: list, axes, detonation_offset: float = 0.0) -> None:
    """Displacement components of each tracer (member 0 of an ensemble) against time, in mm: a plate
    centre's deflection history, its peak and its permanent set (``detonation_offset``: see
    :func:`gauge_histories`)."""
    hist = histories[0]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, x in enumerate(positions):
        for a in axes:
            ax.plot((hist["time"] + detonation_offset) * 1e3, hist[f"tracer{k}_displacement_{a}"] * 1e3, lw=1.2,
                    label=f"{_position(x)}, {a}")
    ax.set_xlabel(_time_label(detonation_offset)), ax.set_ylabel("displacement [mm]"), ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)
