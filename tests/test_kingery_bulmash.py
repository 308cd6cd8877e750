"""Kingery–Bulmash (1984) TNT air-blast fits: printed reference values,
physical consistency, scaling and bad input.

No expected number here comes from our own output: the references are
(1) the DoD quantity–distance overpressures at given K-factors, which are KB
    hemispherical-surface-burst values rounded to two significant figures,
(2) Swisdak (1994)'s independently fitted ln–polynomial representation of the
    same KB surface-burst curves, evaluated from its printed coefficients,
(3) Rankine–Hugoniot (ideal gas, gamma = 1.4) in the weak-shock range, which
    ties the separately fitted overpressure, reflected pressure, shock velocity
    and arrival-time polynomials to one another.
"""
import json
import math

import numpy as np
import pytest
from scipy.integrate import quad

from blastfsi.exact import kingery_bulmash as kb
from blastfsi.exact import shock

P_ATM = 101325.0  # KB fits are for sea-level standard air [Pa]
RHO_ATM = 1.225  # [kg/m^3], sea-level standard air (15 degC)
A_ATM = math.sqrt(1.4 * P_ATM / RHO_ATM)  # 340.3 m/s
PSI = 6894.757293168  # Pa
FT_PER_LB3_TO_M_PER_KG3 = 0.3048 / 0.45359237 ** (1.0 / 3.0)  # 1 ft/lb^(1/3) in m/kg^(1/3)


# --- (1) printed values: DoD 6055.09-M quantity-distance K-factors ------------
# Overpressure (psi) expected at scaled distance K (ft/lb^(1/3)) for a hemispherical
# TNT surface burst, as quoted in the DoD explosives-safety QD criteria (K40 = 1.2 psi
# inhabited-building distance, K24 = 2.3 psi public-traffic-route distance, K18 =
# 3.5 psi unbarricaded intraline distance, K11 = 8 psi, K9 = 12 psi barricaded
# intraline). They are printed to two significant figures, so the tolerance is half
# a unit of the last printed digit.
@pytest.mark.parametrize("k_factor, printed_psi, half_digit", [
    (9.0, 12.0, 0.5), (11.0, 8.0, 0.05), (18.0, 3.5, 0.05), (24.0, 2.3, 0.05), (40.0, 1.2, 0.05)])
def test_surface_overpressure_matches_dod_k_factor_table(k_factor, printed_psi, half_digit):
    z = k_factor * FT_PER_LB3_TO_M_PER_KG3
    psi = kb.scaled_value("incident_overpressure", z, "surface") / PSI
    assert abs(psi - printed_psi) <= half_digit


# --- (2) Swisdak (1994), "Simplified Kingery Airblast Calculations", Minutes of the
# 26th DoD Explosives Safety Seminar (DTIC ADA526744): metric fits
# y = exp(sum_i a_i (ln Z)^i) per range of Z, hemispherical surface burst.
# Units: kPa, kPa·ms/kg^(1/3), ms/kg^(1/3), m/ms. Overpressure coefficients agree in
# two public copies (fcento100/kingery-bulmash, Freeyolo/tangos); the reflected-
# impulse top coefficient is -0.01123 as in the imperial table (the top coefficient
# of a polynomial in ln Z does not change with the unit of Z).
SWISDAK = {
    "incident_overpressure": (1e3, False, [
        (0.2, 2.9, (7.2106, -2.1069, -0.3229, 0.1117, 0.0685)),
        (2.9, 23.8, (7.5938, -3.0523, 0.40977, 0.0261, -0.01267)),
        (23.8, 40.0, (6.0536, -1.4066))]),
    "reflected_overpressure": (1e3, False, [
        (0.06, 2.0, (9.006, -2.6893, -0.6295, 0.1011, 0.29255, 0.13505, 0.019736)),
        (2.0, 40.0, (8.8396, -1.733, -2.64, 2.293, -0.8232, 0.14247, -0.0099))]),
    "incident_impulse": (1.0, True, [
        (0.2, 0.96, (5.522, 1.117, 0.6, -0.292, -0.087)),
        (0.96, 2.38, (5.465, -0.308, -1.464, 1.362, -0.432)),
        (2.38, 33.7, (5.2749, -0.4677, -0.2499, 0.0588, -0.00554)),
        (33.7, 40.0, (5.9825, -1.062))]),
    "reflected_impulse": (1.0, True, [
        (0.06, 40.0, (6.7853, -1.3466, 0.101, -0.01123))]),
    "arrival_time": (1e-3, True, [
        (0.06, 1.5, (-0.7604, 1.8058, 0.1257, -0.0437, -0.0310, -0.00669)),
        (1.5, 40.0, (-0.7137, 1.5732, 0.5561, -0.4213, 0.1054, -0.00929))]),
    "positive_phase_duration": (1e-3, True, [
        (0.2, 1.02, (0.5426, 3.2299, -1.5931, -5.9667, -4.0815, -0.9149)),
        (1.02, 2.8, (0.5440, 2.7082, -9.7354, 14.3425, -9.7791, 2.8535)),
        (2.8, 40.0, (-2.4608, 7.1639, -5.6215, 2.2711, -0.44994, 0.03486))]),
    "shock_velocity": (1e3, False, [
        (0.06, 1.5, (0.1794, -0.956, -0.0866, 0.109, 0.0699, 0.01218)),
        (1.5, 40.0, (0.2597, -1.326, 0.3767, 0.0396, -0.0351, 0.00432))]),
}


def _swisdak(coeffs, z):
    ln_z = np.log(z)
    return np.exp(sum(a * ln_z ** i for i, a in enumerate(coeffs)))


def test_swisdak_own_joint_discontinuity_sets_the_tolerance():
    # Swisdak's incident-impulse fit jumps by ~2.4 % at its own joint Z = 2.38:
    # a simplified fit cannot represent KB better than that, hence 2.5 % below.
    pieces = SWISDAK["incident_impulse"][2]
    jump = _swisdak(pieces[1][2], 2.38) / _swisdak(pieces[2][2], 2.38) - 1.0
    assert 0.02 < jump < 0.025


@pytest.mark.parametrize("quantity", list(SWISDAK))
def test_surface_burst_matches_swisdak_1994(quantity):
    factor, _, pieces = SWISDAK[quantity]
    z_min = kb.validity_range(quantity, "surface")[0]
    for lo, hi, coeffs in pieces:
        z = np.geomspace(max(lo, z_min), hi, 7)
        ours = kb.scaled_value(quantity, z, "surface")
        np.testing.assert_allclose(ours, factor * _swisdak(coeffs, z), rtol=0.025)


# --- (3) physical consistency --------------------------------------------------
@pytest.mark.parametrize("burst", kb.BURSTS)
def test_reflected_over_incident_is_rankine_hugoniot_in_weak_shock_range(burst):
    # For p_s <= ~60 kPa air is a gamma = 1.4 ideal gas and normal reflection follows
    # 002 Eq. (25). The two KB fits are independent, each ~1 % accurate: 2 %.
    z = np.geomspace(3.0, 40.0, 12)
    ps = kb.scaled_value("incident_overpressure", z, burst)
    pr = kb.scaled_value("reflected_overpressure", z, burst)
    np.testing.assert_allclose(pr / ps, shock.reflection_coefficient(ps, P_ATM), rtol=0.02)


@pytest.mark.parametrize("burst", kb.BURSTS)
def test_shock_velocity_is_rankine_hugoniot_of_overpressure(burst):
    # U = a0 sqrt(1 + 6/7 p_s/p0) (ERRATA 002-4) for 2 <= Z <= 40 (p_s <= ~220 kPa);
    # both fits ~0.5 % accurate there: 1 %. Also U -> a0 far out.
    z = np.geomspace(2.0, 40.0, 12)
    ps = kb.scaled_value("incident_overpressure", z, burst)
    u = kb.scaled_value("shock_velocity", z, burst)
    np.testing.assert_allclose(u, shock.incident_shock(ps, P_ATM, RHO_ATM).shock_speed, rtol=0.01)
    assert kb.scaled_value("shock_velocity", 40.0, burst) == pytest.approx(A_ATM, rel=0.01)


@pytest.mark.parametrize("burst", kb.BURSTS)
def test_arrival_time_is_integral_of_inverse_shock_velocity(burst):
    # t_a(Z2) - t_a(Z1) = int dZ / U (scaled units); two independent fits: 2 %.
    for z1, z2 in [(0.2, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 40.0)]:
        travel = quad(lambda z: 1.0 / float(kb.scaled_value("shock_velocity", z, burst)), z1, z2)[0]
        dt = kb.scaled_value("arrival_time", z2, burst) - kb.scaled_value("arrival_time", z1, burst)
        assert dt == pytest.approx(travel, rel=0.02), (z1, z2)


@pytest.mark.parametrize("burst", kb.BURSTS)
def test_piecewise_fits_join_continuously(burst):
    # KB's ranges meet on the same curve; the joins differ by the fit error (< 2 %).
    for quantity in kb.QUANTITIES:
        fits = kb._FITS[burst][quantity]
        for left, right in zip(fits[:-1], fits[1:]):
            z = left.z_max
            assert z == right.z_min
            below = 10 ** kb._log10_polynomial(z, left)
            above = 10 ** kb._log10_polynomial(z, right)
            assert below == pytest.approx(above, rel=0.02), (quantity, z)


@pytest.mark.parametrize("burst", kb.BURSTS)
def test_monotone_in_scaled_distance(burst):
    z = np.geomspace(kb.validity_range("incident_overpressure", burst)[0], 40.0, 400)
    for quantity in ("incident_overpressure", "reflected_overpressure", "shock_velocity"):
        assert np.all(np.diff(kb.scaled_value(quantity, z, burst)) < 0), quantity
    assert np.all(np.diff(kb.scaled_value("arrival_time", z, burst)) > 0)


def test_surface_burst_is_free_air_burst_of_1_8_times_the_mass_for_impulse_and_duration():
    # Rule of thumb for a surface burst on a real ground: a free-air burst of 1.8 W (2 W for a
    # perfect reflector, less the energy spent cratering; UFC 3-340-02 Sec. 2-13). In KB it
    # holds for 0.1 <= Z <= 40 for the impulses to 2 % (one fit error each); the duration
    # fits are rougher (their own joints jump by up to 1.8 %, see the continuity test), so 4 %
    # for two of them. Peak overpressure does not follow it closely: the surface curve lies
    # 6-12 % below the 1.8 W free-air curve at 0.5 <= Z <= 3 and up to 6 % above it at Z = 40.
    factor = 1.8 ** (1.0 / 3.0)
    cases = (("incident_impulse", 0.02), ("reflected_impulse", 0.02), ("positive_phase_duration", 0.04))
    for quantity, rtol in cases:
        lo = max(0.1, kb.validity_range(quantity, "surface")[0],
                 factor * kb.validity_range(quantity, "free-air")[0])
        z = np.geomspace(lo, 40.0, 60)
        surface = kb.scaled_value(quantity, z, "surface")
        free_air = factor * kb.scaled_value(quantity, z / factor, "free-air")
        np.testing.assert_allclose(surface, free_air, rtol=rtol, err_msg=quantity)


@pytest.mark.parametrize("burst", kb.BURSTS)
def test_cube_root_scaling(burst):
    # Hopkinson-Cranz: equal Z gives equal pressures/velocity and times/impulses
    # proportional to W^(1/3).
    ratio = 100.0 ** (1.0 / 3.0)
    for quantity, (_, scales, _) in kb.QUANTITIES.items():
        small = kb.value(quantity, 1.0, 2.0, burst)
        large = kb.value(quantity, 100.0, 2.0 * ratio, burst)
        assert large == pytest.approx(small * (ratio if scales else 1.0), rel=1e-12)


# --- report and bad input --------------------------------------------------------
def test_kb_report_is_si_and_json_ready():
    rep = kb.kb_report(8.0, 10.0, burst="surface")
    assert rep["scaled_distance"] == pytest.approx(5.0)
    assert rep["incident_overpressure"] == pytest.approx(kb.scaled_value("incident_overpressure", 5.0, "surface"))
    assert rep["arrival_time"] == pytest.approx(2.0 * kb.scaled_value("arrival_time", 5.0, "surface"))
    assert set(kb.QUANTITIES) <= set(rep) and rep["units"]["incident_impulse"] == "Pa*s"
    json.dumps(rep)
    free = kb.kb_report(1.0, 3.0)
    assert free["burst"] == "free-air" and free["incident_overpressure"] < rep["incident_overpressure"] * 2


def test_close_in_report_gives_the_quantities_whose_fits_hold():
    """Z = 0.1 (1 t at 1 m, surface burst): below the positive phase duration's fit (from Z = 0.178) but
    inside the others': that one is None with its range, the rest are the fits' values."""
    rep = kb.kb_report(1000.0, 1.0, burst="surface")
    assert rep["positive_phase_duration"] is None
    assert rep["out_of_range"] == {"positive_phase_duration": list(kb.validity_range("positive_phase_duration",
                                                                                       "surface"))}
    assert rep["reflected_impulse"] == pytest.approx(kb.value("reflected_impulse", 1000.0, 1.0, "surface"))
    json.dumps(rep)


@pytest.mark.parametrize("mass, distance, burst, match", [
    (1.0, 50.0, "free-air", r"Z = 50.0 .*incident_overpressure.*0.0531 <= Z <= 40.0"),
    (0.0, 1.0, "free-air", r"charge mass must be > 0"),
    (-1.0, 1.0, "free-air", r"charge mass must be > 0"),
    (1.0, 0.0, "free-air", r"distance must be > 0"),
    (1.0, 1.0, "underwater", r"burst must be one of"),
])
def test_bad_input_raises_named_errors(mass, distance, burst, match):
    with pytest.raises(ValueError, match=match):
        kb.kb_report(mass, distance, burst)


def test_unknown_quantity_and_nan():
    with pytest.raises(ValueError, match="quantity must be one of"):
        kb.scaled_value("dynamic_pressure", 1.0)
    with pytest.raises(ValueError, match="outside the Kingery-Bulmash validity range"):
        kb.scaled_value("arrival_time", float("nan"))
