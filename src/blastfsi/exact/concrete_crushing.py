"""Empirical crushing diameter of a concrete slab under a spherical charge above it: Luccioni & Luege (2006),
quoted as 000 Eq. (67) (ERRATA 13):

    ln(3.63 D / h) = 0.1838 W^(1/3) / h,

D the diameter of the crushed zone on the slab's top face [m], h the height of the charge above the top face [m],
W the TNT-equivalent mass [kg]; both lengths in metres, so 0.1838 carries m / kg^(1/3). Fitted by its authors to
their tests at h = 0.5 m (W = 4 kg: D ~ 250 mm; 10 kg: ~ 300 mm) and to their AUTODYN runs of 25 MPa concrete
pavement slabs 0.15 m thick; outside W^(1/3)/h ~ 2-6 kg^(1/3)/m it is an extrapolation.

B.M. Luccioni, M. Luege, "Concrete pavement slab under blast loads", Int. J. Impact Eng. 32 (2006) 1248-1266.
"""
from __future__ import annotations

import math

SLOPE = 0.1838  # m / kg^(1/3), 000 Eq. (67)
FACTOR = 3.63  # [-], 000 Eq. (67)
FIT_RANGE = (2.0, 6.0)  # W^(1/3)/h [kg^(1/3)/m] of the tests and runs behind the fit (h = 0.5 m, W = 1-25 kg)


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def crushing_diameter(mass: float, height: float) -> float:
    """D [m] of 000 Eq. (67) for a TNT-equivalent ``mass`` [kg] at ``height`` [m] above the top face."""
    mass, height = _positive("mass", mass), _positive("height", height)
    return height / FACTOR * math.exp(SLOPE * mass ** (1.0 / 3.0) / height)


def charge_mass(diameter: float, height: float) -> float:
    """The inverse: the TNT-equivalent mass [kg] that crushes ``diameter`` [m] at ``height`` [m]."""
    diameter, height = _positive("diameter", diameter), _positive("height", height)
    ratio = FACTOR * diameter / height
    if ratio <= 1.0:
        raise ValueError(f"diameter must exceed height / {FACTOR} = {height / FACTOR:.4g} m (Eq. 67 gives D >= "
                         f"h / 3.63 as W -> 0), got {diameter}")
    return (height * math.log(ratio) / SLOPE) ** 3
