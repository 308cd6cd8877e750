"""Detonation: Chapman–Jouguet state of a products EOS (burn models and the 1D -> 2D/3D remap join here)."""
from blastfsi.detonation.cj import CJState, chapman_jouguet, products_hugoniot_pressure

__all__ = ["CJState", "chapman_jouguet", "products_hugoniot_pressure"]
