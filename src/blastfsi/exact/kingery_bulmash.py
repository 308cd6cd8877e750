"""Kingery–Bulmash (1984) air-blast parameters of TNT: spherical free-air burst
and hemispherical surface burst.

Source of the fits: C. N. Kingery and G. Bulmash, "Airblast Parameters from TNT
Spherical Air Burst and Hemispherical Surface Burst", Technical Report
ARBRL-TR-02555, US Army Ballistic Research Laboratory, April 1984. The same
polynomials underlie the charts of UFC 3-340-02 (2008), Figs. 2-7 (free air) and
2-15 (surface burst), and the CONWEP program. Every quantity is, on each range
of scaled distance Z = R / W^(1/3) [m/kg^(1/3)],

    U = k0 + k1 log10(Z),        log10(Y) = sum_i c_i U^i,

with Y in the report's metric units: kPa for pressures, kPa·ms/kg^(1/3) for
impulses, ms/kg^(1/3) for times and m/ms for the shock-front velocity. Scaled
impulses and times are multiplied by W^(1/3) to get the physical values; the
functions here return SI (Pa, Pa·s, s, m/s).

Provenance of the coefficient values. The report itself was not available to
us; the metric coefficients below were transcribed from independent public
implementations of the KB polynomials and kept only where at least two of them
agree to the digits they print:
  (a) BlastLoadService (TypeScript; "spherical_*"/"hemispherical_*" functions),
  (b) BLC by J. H. Chung (Fortran, cites ARBRL-TR-02555) and the Python
      "Evaluate" tables of the same family,
  (c) lightsquared/kingery_bulmash (kb_old.py, kb_equation_data.csv; also gives
      the imperial set, which must differ from the metric one only in k0 and c0),
  (d) mbozkaya/the-kingery-bulmash-blast-parameter-calculator (C#, surface
      burst) and a Titanium JS blast calculator (surface burst).
Disagreements found and how they were settled (majority of copies, then the
physical checks in tests/test_kingery_bulmash.py: normal reflection and shock
speed against Rankine–Hugoniot in the weak-shock range, arrival time against
the integral of 1/U, continuity of the piecewise fits):
  * free-air reflected pressure c2 = 0.035119031446 [(a), (b)] not 0.35119031446 [(c)];
    c9 = -0.00397126276058 [(b), (c)] not -0.00387126276058 [(a)];
  * free-air shock velocity c7 = 0.0898926178054 [(a), (c)] not 0.098926178054 [(b)];
  * free-air duration, middle range: c0 = +0.23031841078 [(b), (c)] not negative [(a)];
    c5 = -0.00106321963576 [(a), (b), (c) imperial] not positive [(c) metric];
  * free-air duration, far range: c5 = -0.00246738509321 [(a), (b) Fortran, (c)];
  * surface shock velocity / arrival time: k0 = -0.202425716178 [(a), (c), and
    consistent with the imperial k0 through the ft/lb -> m/kg scaling used by
    every other fit], c3 = 0.443812098136 [(a), (c)] (the copies (b), (d-JS) print
    0.4438112098136; the difference, 9e-7, is below any consequence);
  * surface duration, far range: c3 = -0.00226884995013 [(a), (d-C#), (b)-Fortran].

Validity ranges (outside them a ValueError names Z, the quantity and the range)
are the report's: 0.0531 <= Z <= 40 for the free-air fits (0.147 <= Z for the
duration), 0.0674 <= Z <= 40 for the surface-burst fits (0.178 <= Z for the
duration); 0.0674 m/kg^(1/3) is the imperial lower limit 0.17 ft/lb^(1/3) of copy
(c) (copies (b) and (d-JS) cut the surface overpressure at 0.064 instead). The
report's page and table numbers could not be checked here. The fits are for
sea-level standard air; no ambient correction is applied.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


class _Fit(NamedTuple):
    """One range of a KB fit: U = k0 + k1 log10(Z), log10 Y = sum c_i U^i."""

    z_min: float
    z_max: float
    k0: float
    k1: float
    c: tuple


# Unit factors from the report's metric units to SI.
_KPA = 1.0e3  # kPa -> Pa
_KPA_MS = 1.0  # kPa·ms -> Pa·s (1e3 * 1e-3)
_MS = 1.0e-3  # ms -> s
_M_PER_MS = 1.0e3  # m/ms -> m/s

QUANTITIES = {
    # name: (SI factor, scales with W^(1/3), unit)
    "incident_overpressure": (_KPA, False, "Pa"),
    "reflected_overpressure": (_KPA, False, "Pa"),
    "incident_impulse": (_KPA_MS, True, "Pa*s"),
    "reflected_impulse": (_KPA_MS, True, "Pa*s"),
    "arrival_time": (_MS, True, "s"),
    "positive_phase_duration": (_MS, True, "s"),
    "shock_velocity": (_M_PER_MS, False, "m/s"),
}
BURSTS = ("free-air", "surface")

_U_PSO = (-0.214362789151, 1.35034249993)  # shared by several fits (KB 1984)

_FITS = {
    "free-air": {
        "incident_overpressure": (
            _Fit(0.0531, 40.0, *_U_PSO,
                 (2.611368669, -1.69012801396, 0.00804973591951, 0.336743114941,
                  -0.00516226351334, -0.0809228619888, -0.00478507266747,
                  0.00793030472242, 0.0007684469735)),),
        "reflected_overpressure": (
            _Fit(0.0531, 40.0, *_U_PSO,
                 (3.22958031387, -2.21400538997, 0.035119031446, 0.657599992109,
                  0.0141818951887, -0.243076636231, -0.0158699803158,
                  0.0492741184234, 0.00227639644004, -0.00397126276058)),),
        "incident_impulse": (
            _Fit(0.0531, 0.792, 2.34723921354, 3.24299066475,
                 (2.38830516757, -0.443749377691, 0.168825414684, 0.0348138030308,
                  -0.010435192824)),
            _Fit(0.792, 40.0, -1.75305660315, 2.30629231803,
                 (1.55197227115, -0.40463292088, -0.0142721946082, 0.00912366316617,
                  -0.0006750681404, -0.00800863718901, 0.00314819515931,
                  0.00152044783382, -0.0007470265899)),
        ),
        "reflected_impulse": (
            _Fit(0.0531, 40.0, -0.204004553231, 1.37882996018,
                 (2.55875660396, -0.903118886091, 0.101771877942, -0.0242139751146)),),
        "arrival_time": (
            _Fit(0.0531, 40.0, -0.253273111999, 1.37407043777,
                 (0.0720707787637, 1.36456871214, -0.0570035692784, -0.182832224796,
                  0.0118851436014, 0.0432648687627, -0.0007997367834,
                  -0.00436073555033)),),
        "positive_phase_duration": (
            _Fit(0.147, 0.888, 2.26367268496, 5.11588554305,
                 (-0.686608550419, 0.164953518069, 0.127788499497, 0.00291430135946,
                  0.00187957449227, 0.0173413962543, 0.00269739758043,
                  -0.00361976502798, -0.00100926577934)),
            _Fit(0.888, 2.28, -1.33361206714, 9.2996288611,
                 (0.23031841078, -0.0297944268969, 0.0306329542941, 0.0183405574074,
                  -0.0173964666286, -0.00106321963576, 0.0056206003128,
                  0.0001618217499, -0.0006860188944)),
            _Fit(2.28, 40.0, -3.13005805346, 3.1524725364,
                 (0.621036276475, 0.0967031995552, -0.00801302059667, 0.00482705779732,
                  0.00187587272287, -0.00246738509321, -0.000841116668,
                  0.0006193291052)),
        ),
        "shock_velocity": (
            _Fit(0.0531, 40.0, *_U_PSO,
                 (-0.144615443471, -0.650507560471, 0.291320654009, 0.307916322787,
                  -0.183361123489, -0.197740454538, 0.0909119559768, 0.0898926178054,
                  -0.0287370990248, -0.0248730221702, 0.00496311705671,
                  0.00372242076361, -0.0003533736952, -0.0002292913709)),),
    },
    "surface": {
        "incident_overpressure": (
            _Fit(0.0674, 40.0, *_U_PSO,
                 (2.78076916577, -1.6958988741, -0.154159376846, 0.514060730593,
                  0.0988534365274, -0.293912623038, -0.0268112345019, 0.109097496421,
                  0.00162846756311, -0.0214631030242, 0.0001456723382,
                  0.00167847752266)),),
        "reflected_overpressure": (
            _Fit(0.0674, 40.0, -0.240657322658, 1.36637719229,
                 (3.40283217581, -2.21030870597, -0.218536586295, 0.895319589372,
                  0.24989009775, -0.569249436807, -0.11791682383, 0.224131161411,
                  0.0245620259375, -0.0455116002694, -0.0019093073888,
                  0.00361471193389)),),
        "incident_impulse": (
            _Fit(0.0674, 0.955, 2.06761908721, 3.0760329666,
                 (2.52455620925, -0.502992763686, 0.171335645235, 0.0450176963051,
                  -0.0118964626402)),
            _Fit(0.955, 40.0, -1.94708846747, 2.40697745406,
                 (1.67281645863, -0.384519026965, -0.0260816706301, 0.00595798753822,
                  0.0145445261077, -0.00663289334734, -0.00284189327204,
                  0.0013644816227)),
        ),
        "reflected_impulse": (
            _Fit(0.0674, 40.0, -0.246208804814, 1.33422049854,
                 (2.70588058103, -0.949516092853, 0.112136118689, -0.0250659183287)),),
        "arrival_time": (
            _Fit(0.0674, 40.0, -0.202425716178, 1.37784223635,
                 (-0.0591634288046, 1.35706496258, 0.052492798645, -0.196563954086,
                  -0.0601770052288, 0.0696360270891, 0.0215297490092,
                  -0.0161658930785, -0.00232531970294, 0.00147752067524)),),
        "positive_phase_duration": (
            _Fit(0.178, 1.01, 1.92946154068, 5.25099193925,
                 (-0.614227603559, 0.130143717675, 0.134872511954, 0.0391574276906,
                  -0.00475933664702, -0.00428144598008)),
            _Fit(1.01, 2.78, -2.12492525216, 9.2996288611,
                 (0.315409245784, -0.0297944268976, 0.030632954288, 0.0183405574086,
                  -0.0173964666211, -0.00106321963633, 0.00562060030977,
                  0.0001618217499, -0.0006860188944)),
            _Fit(2.78, 40.0, -3.53626218091, 3.46349745571,
                 (0.686906642409, 0.0933035304009, -0.0005849420883, -0.00226884995013,
                  -0.00295908591505, 0.00148029868929)),
        ),
        "shock_velocity": (
            _Fit(0.0674, 40.0, -0.202425716178, 1.37784223635,
                 (-0.06621072854, -0.698029762594, 0.158916781906, 0.443812098136,
                  -0.113402023921, -0.369887075049, 0.129230567449, 0.19857981197,
                  -0.0867636217397, -0.0620391900135, 0.0307482926566,
                  0.0102657234407, -0.00546533250772, -0.000693180974,
                  0.0003847494916)),),
    },
}


def _check_burst(burst):
    if burst not in BURSTS:
        raise ValueError(f"burst must be one of {BURSTS}, got {burst!r}")


def _check_quantity(quantity):
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {tuple(QUANTITIES)}, got {quantity!r}")


def validity_range(quantity: str, burst: str = "free-air") -> tuple[float, float]:
    """(Z_min, Z_max) [m/kg^(1/3)] of the KB fit of `quantity`."""
    _check_burst(burst)
    _check_quantity(quantity)
    fits = _FITS[burst][quantity]
    return fits[0].z_min, fits[-1].z_max


def _log10_polynomial(z, fit: _Fit):
    """KB 1984: log10 Y = sum_i c_i U^i with U = k0 + k1 log10 Z (Horner form)."""
    u = fit.k0 + fit.k1 * np.log10(z)
    acc = np.zeros_like(u)
    for c in reversed(fit.c):
        acc = acc * u + c
    return acc


def scaled_value(quantity: str, z, burst: str = "free-air"):
    """KB value at scaled distance z [m/kg^(1/3)], in SI.

    Pressures [Pa] and the shock velocity [m/s] are returned as they are;
    impulses [Pa·s/kg^(1/3)] and times [s/kg^(1/3)] are per unit W^(1/3) and
    must be multiplied by W^(1/3) (see :func:`value`).
    """
    _check_burst(burst)
    _check_quantity(quantity)
    z = np.asarray(z, dtype=float)
    z_min, z_max = validity_range(quantity, burst)
    if not np.all(np.isfinite(z)) or np.any(z < z_min) or np.any(z > z_max):
        raise ValueError(
            f"scaled distance Z = {z} m/kg^(1/3) is outside the Kingery-Bulmash validity range "
            f"of {quantity} ({burst} burst): {z_min} <= Z <= {z_max} m/kg^(1/3)")
    fits = _FITS[burst][quantity]
    log_y = np.zeros_like(z)
    for i, fit in enumerate(fits):
        last = i == len(fits) - 1
        inside = (z >= fit.z_min) & ((z <= fit.z_max) if last else (z < fit.z_max))
        log_y = np.where(inside, _log10_polynomial(z, fit), log_y)
    return QUANTITIES[quantity][0] * 10.0 ** log_y


def scaled_distance(mass, distance):
    """Z = R / W^(1/3) [m/kg^(1/3)] for a TNT mass W [kg] at distance R [m]."""
    mass = np.asarray(mass, dtype=float)
    distance = np.asarray(distance, dtype=float)
    if not np.all(np.isfinite(mass)) or np.any(mass <= 0):
        raise ValueError(f"charge mass must be > 0 kg TNT, got {mass}")
    if not np.all(np.isfinite(distance)) or np.any(distance <= 0):
        raise ValueError(f"distance must be > 0 m, got {distance}")
    return distance / np.cbrt(mass)


def value(quantity: str, mass, distance, burst: str = "free-air"):
    """KB `quantity` in SI for a TNT mass [kg] at distance [m] (Hopkinson–Cranz scaling)."""
    _check_quantity(quantity)
    z = scaled_distance(mass, distance)
    scaled = scaled_value(quantity, z, burst)
    return scaled * np.cbrt(np.asarray(mass, dtype=float)) if QUANTITIES[quantity][1] else scaled


def kb_report(mass: float, distance: float, burst: str = "free-air") -> dict:
    """All KB quantities for `mass` kg TNT at `distance` m, in SI, for `blastfsi kb`.

    Returns a flat dict: mass [kg], distance [m], burst, scaled_distance
    [m/kg^(1/3)], and every name of :data:`QUANTITIES` in SI, plus "units"
    mapping each key to its unit. A quantity whose validity range does not hold
    Z is None, with its range [Z_min, Z_max] in "out_of_range" (close-in
    charges: the reflected impulse holds from Z = 0.0531, the positive phase
    duration only from 0.147); a Z outside every range raises ValueError naming
    Z, a quantity and its range.
    """
    _check_burst(burst)
    z = float(scaled_distance(mass, distance))
    report = {"mass": float(mass), "distance": float(distance), "burst": burst, "scaled_distance": z}
    outside = {}
    for name in QUANTITIES:
        lo, hi = validity_range(name, burst)
        if lo <= z <= hi:
            report[name] = float(value(name, mass, distance, burst))
        else:
            report[name], outside[name] = None, [lo, hi]
    if len(outside) == len(QUANTITIES):
        value(next(iter(QUANTITIES)), mass, distance, burst)  # raises, naming Z and the range
    report["out_of_range"] = outside
    report["units"] = {"mass": "kg", "distance": "m", "scaled_distance": "m/kg^(1/3)",
                       **{name: unit for name, (_, _, unit) in QUANTITIES.items()}}
    return report
