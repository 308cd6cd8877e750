"""Plots of run results (matplotlib, Agg backend: no screen needed)."""
from blastfsi.plotting.histories import plate_histories

__all__ = ["plate_histories"]
