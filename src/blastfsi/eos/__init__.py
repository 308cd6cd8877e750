"""Equations of state: one module per family, each exposing pressure/sound_speed/energy."""
from blastfsi.eos.ideal_gas import IdealGas

__all__ = ["IdealGas"]
