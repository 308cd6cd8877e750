"""What every plot shares: plain tick labels (no offset or exponent text: the unit is scaled instead,
:mod:`blastfsi.plotting.units`) and saving."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import ScalarFormatter  # noqa: E402


def plain(*axes) -> None:
    """Tick labels of each matplotlib Axis (``ax.xaxis``, a colour bar's ``cbar.ax.yaxis``) as plain numbers."""
    for axis in axes:
        formatter = ScalarFormatter(useOffset=False)
        formatter.set_scientific(False)
        axis.set_major_formatter(formatter)


def save(fig, png) -> None:
    fig.savefig(Path(png), dpi=120)
    plt.close(fig)
