"""Plots of run results (matplotlib, Agg backend: no screen needed)."""
from blastfsi.plotting.histories import gauge_histories, plate_histories

__all__ = ["gauge_histories", "plate_histories"]
