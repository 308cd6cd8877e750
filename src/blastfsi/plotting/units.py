"""Display units chosen from the data, so that an axis reads 1-1000 of a unit an engineer uses (MPa and µs for a
close-in event, kPa and ms for a far one), never "30000 kPa" or "0.0175 ms".

Values are SI inside (Pa, s, m, J); a plot divides them by :attr:`Scale.factor` and writes :attr:`Scale.unit`
into the axis or colour-bar label.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

# quantity -> (SI unit, the decimal exponents offered, smallest first)
UNITS = {
    "pressure": ("Pa", (0, 3, 6, 9)),          # Pa, kPa, MPa, GPa
    "time": ("s", (-9, -6, -3, 0)),            # ns, µs, ms, s
    "length": ("m", (-3, 0)),                  # mm, m
    "energy": ("J", (0, 3, 6, 9)),             # J, kJ, MJ, GJ
    "impulse": ("Pa s", (0, 3, 6)),            # Pa s, kPa s, MPa s
}
PREFIX = {-9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}


class Scale(NamedTuple):
    factor: float  # SI value / factor = displayed value
    unit: str      # e.g. "MPa"

    def label(self, name: str) -> str:
        """Axis label "name [unit]"."""
        return f"{name} [{self.unit}]"


def scale(values, quantity: str) -> Scale:
    """The unit of ``quantity`` ("pressure", "time", "length", "energy", "impulse") in which the largest
    finite magnitude of ``values`` reads from 1 to below 1000: the largest offered prefix not above it (the
    smallest one for magnitudes below it, the base unit for no finite non-zero value)."""
    if quantity not in UNITS:
        raise ValueError(f"quantity must be one of {sorted(UNITS)}, got {quantity!r}")
    base, exponents = UNITS[quantity]
    magnitude = np.abs(np.asarray(values, dtype=float))
    magnitude = magnitude[np.isfinite(magnitude)]
    top = float(magnitude.max()) if magnitude.size else 0.0
    if top == 0.0:
        return Scale(1.0, base)
    exponent = max([e for e in exponents if 10.0 ** e <= top], default=exponents[0])
    return Scale(10.0 ** exponent, PREFIX[exponent] + base)


def text(value: float, quantity: str, digits: int = 4) -> str:
    """``value`` (SI) written in its own :func:`scale`, e.g. text(1.75e-5, "time") == "17.5 µs"."""
    s = scale([value], quantity)
    return f"{value / s.factor:.{digits}g} {s.unit}"
