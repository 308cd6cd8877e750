"""Issue 6, the 1D detonation on lagrangian1d: programmed burn (000 Eqs. 52-53), curved geometry,
two materials, charge set-up, gauge/KB summary, cube-root scaling and bad input."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi
from blastfsi.detonation.cj import chapman_jouguet
from blastfsi.lagrangian1d import scheme
from blastfsi.lagrangian1d.charge_problem import charge_radius, graded_nodes
from blastfsi.materials import lookup
from blastfsi.scenario import ScenarioError, parse

RHO_TNT = 1630.0  # seed 000 Sec. 4.1


def charge_data(**over):
    data = {"method": "lagrangian1d", "name": "t-charge", "charge": {"mass": 1.0},
            "domain": {"geometry": "spherical", "length": 1.2},
            "grid": {"cells": 40, "first_ratio": 4.0, "growth": 1.1, "max_ratio": 20.0},
            "time": {"end": 4e-4}, "output": {"history_samples": 101, "fields": 0, "plots": False,
                                              "gauges": [0.5, 0.9]}}
    for key, value in over.items():
        node = data
        parts = key.split("__")
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = value
    return data


@pytest.fixture(scope="module")
def one_kg():
    return blastfsi.run(charge_data())


def test_burn_fraction_ramps_caps_and_stays_at_one():
    # 000 Eq. (53) with ERRATA 000-8: 0 before t_L, linear over 1.5 h / D, then 1 for ever
    zones = scheme.Zones(*(jnp.zeros(1) for _ in range(6)), jnp.asarray([1e-6]), jnp.asarray([6930.0 / 1.5e-4]))
    t = jnp.linspace(0.0, 1e-4, 2001)
    F = np.asarray(jnp.stack([scheme.burn_fraction(tt, zones)[0] for tt in t]))
    assert np.all(F[np.asarray(t) < 1e-6] == 0.0) and np.all(np.diff(F) >= 0.0)
    reached = np.argmax(F >= 1.0)
    assert np.all(F[reached:] == 1.0)
    assert float(t[reached]) == pytest.approx(1e-6 + 1.5e-4 / 6930.0, abs=float(t[1] - t[0]))


@pytest.mark.parametrize("j", [1, 2])
def test_curved_gas_at_rest_stays_at_rest(j):
    # area-weighted momentum: uniform pressure exerts no net force on any node in any geometry
    n = 40
    x = jnp.linspace(0.0, 1.0, n + 1)
    vol = scheme.zone_volume(x, j)
    e = jnp.full(n, 1e5 / (0.4 * 1.2))
    st = scheme.initial_state(x, jnp.zeros(n + 1), e, 1.2 * vol, 1.4, 4, geometry=j)
    params = scheme.Params(scheme.Numerics(*map(jnp.asarray, (1.4, 1.5, 0.1, 0.5))),
                           scheme.Boundaries(*map(jnp.asarray, (0.0, 1e5, 0.0, 1e5))),
                           scheme.Gauges(jnp.zeros(0), jnp.asarray(1e5)), jnp.asarray(1.0))
    out = scheme.advance(st, params, scheme.Static(True, False, j), 1e-3, 5000, 1e-3 / 3, 1e-6)
    assert int(out.step) > 10
    assert np.max(np.abs(np.asarray(out.v))) < 1e-10  # round-off of r^j (p - p) against 345 m/s
    np.testing.assert_allclose(np.asarray(out.e), np.asarray(e), rtol=1e-12)


def test_graded_zones_resolve_the_charge_and_grow_away_from_it():
    x = graded_nodes(0.05, 300, 2.0, 1.05, 100.0, 10.0)
    w = np.diff(x)
    np.testing.assert_allclose(w[:300], 0.05 / 300, rtol=1e-12)
    assert x[-1] == pytest.approx(2.0, rel=1e-14) and np.all(w > 0)
    air = w[300:-2]
    assert air[0] == pytest.approx(10 * 0.05 / 300, rel=0.1)
    assert np.all(air[1:] / air[:-1] <= 1.05 * (1 + 1e-9)) and air.max() <= 100 * 0.05 / 300 * 1.1


def test_charge_mass_and_radius_agree_in_each_geometry():
    for j, mass in ((0, 81.5), (1, 12.8), (2, 1.0)):
        r = charge_radius(mass, RHO_TNT, j)
        measure = {0: 1.0, 1: 2 * np.pi, 2: 4 * np.pi}[j]
        assert measure * RHO_TNT * r ** (j + 1) / (j + 1) == pytest.approx(mass, rel=1e-13)
    assert charge_radius(1.0, RHO_TNT, 2) == pytest.approx(0.052712, rel=1e-4)  # (3/(4 pi 1630))^(1/3)


def test_spherical_detonation_conserves_energy_and_reports_gauges(one_kg):
    s = one_kg.summary
    # the vNR energy defect is first order in dt (docs/theory/lagrangian1d.md); strong burn fronts make it
    # 0.3 % at 40 zones (measured 0.25-0.35 % over 100-1600 zones in the CJ study)
    assert abs(s["energy_error_relative"]) < 1e-2
    total = one_kg.setups[0].charge.measure * float(np.sum(one_kg.setups[0].zone_mass[:40]))
    assert total == pytest.approx(1.0, rel=1e-12) and s["charge_mass"] == pytest.approx(1.0, rel=1e-12)
    g = s["gauges"]
    assert [x["position"] for x in g] == [0.5, 0.9]
    for x in g:
        assert x["peak_overpressure"] > 1e5 and x["impulse"] > 0 and x["arrival_time"] > 0
        assert x["kb"]["peak_overpressure"] > 0
        assert x["ratio"]["peak_overpressure"] == pytest.approx(x["peak_overpressure"] / x["kb"]["peak_overpressure"])
    assert g[0]["arrival_time"] < g[1]["arrival_time"]
    # the burn reached the whole charge: every explosive zone completed its burn; the front pressure
    # converges to p_CJ like h^(1/2) in spherical geometry (0.83, 0.87, 0.90, 0.93 at 200..1600 zones,
    # docs/verification.md), so at 40 zones it lies well below and far above half of p_CJ
    burnt = np.asarray(one_kg.state.zone_burnt)[0][:40]
    assert np.all(burnt > 0.0)
    assert 0.5 < s["burn_front_pressure_ratio"] < 1.0


def test_cube_root_scaling_is_exact_for_the_1d_detonation(one_kg):
    # The equations have no length or time scale besides the charge: 8 kg with every length x2 and
    # time x2 (same zone count) gives the same scaled history up to round-off; 1e-9 leaves room
    # for the round-off of the graded zoning and of the time-step sequence.
    big = blastfsi.run(charge_data(charge__mass=8.0, domain__length=2.4, time__end=8e-4,
                                   output__gauges=[1.0, 1.8]))
    assert big.summary["cells"] == one_kg.summary["cells"]
    for a, b in zip(one_kg.summary["gauges"], big.summary["gauges"]):
        assert b["peak_overpressure"] == pytest.approx(a["peak_overpressure"], rel=1e-9)
        assert b["impulse"] == pytest.approx(2.0 * a["impulse"], rel=1e-9)
        assert b["arrival_time"] == pytest.approx(2.0 * a["arrival_time"], rel=1e-9)
        assert b["scaled_distance"] == pytest.approx(a["scaled_distance"], rel=1e-12)


E0_TNT = 6.993e9  # J/m^3, the seed's JWL detonation energy
AFTERBURN = {"charge__afterburn_energy": E0_TNT, "charge__afterburn_start": 1e-5, "charge__afterburn_end": 3e-4}


@pytest.mark.parametrize("over,fragments", [
    ({"charge__mass": -1.0}, ["charge.mass", "> 0"]),
    ({"charge__mass": 0.0}, ["charge.mass", "> 0"]),
    ({"charge__radius": 0.05}, ["exactly one of charge.mass and charge.radius"]),
    ({"domain__geometry": "toroidal"}, ["domain.geometry"]),
    ({"incident": {"profile": "uniform", "overpressure": 1e5}}, ["exactly one of [incident]"]),
    ({"output__gauges": [2.0]}, ["output.gauges[0]", "outside the domain"]),
    ({"charge__afterburn_energy": -1.0}, ["charge.afterburn_energy", ">= 0"]),
    ({"charge__afterburn_start": -1e-5}, ["charge.afterburn_start", ">= 0"]),
    ({**AFTERBURN, "charge__afterburn_end": 1e-5}, ["charge.afterburn_end", "must be > charge.afterburn_start"]),
    ({**AFTERBURN, "charge__afterburn_end": 5e-6}, ["charge.afterburn_end", "must be > charge.afterburn_start"]),
    ({"charge__afterburn_energy": E0_TNT}, ["charge.afterburn_end: required"]),
])
def test_bad_charge_scenarios_are_rejected(over, fragments):
    with pytest.raises(ScenarioError) as err:
        parse(charge_data(**over))
    for f in fragments:
        assert f in str(err.value)


def test_charge_outside_domain_and_unknown_explosive_are_rejected():
    with pytest.raises(ScenarioError, match="outside the domain"):
        blastfsi.run(charge_data(domain__length=0.05))
    with pytest.raises(ScenarioError, match="unknown explosive 'semtex'.*tnt"):
        blastfsi.run(charge_data(charge__explosive="semtex"))
    with pytest.raises(ScenarioError, match="not an explosive"):
        blastfsi.run(charge_data(charge__explosive="air"))


def test_the_explosives_constants_can_be_overridden_and_nothing_else():
    """``[materials.<explosive>]`` reaches the charge: the detonation energy it books and the CJ pressure it
    checks the burn against are those of the overridden constants. An override of a material the run does
    not use is refused by its key (the ambient gas is ``[gas]``), as it is for the plate problems."""
    short = {"time__end": 2e-5, "output__gauges": []}
    base = blastfsi.run(charge_data(**short))
    hot = blastfsi.run(charge_data(**short, materials={"tnt": {"E0": 1.2 * E0_TNT}}))
    volume = 1.0 / RHO_TNT  # the 1 kg charge
    assert base.setups[0].charge.explosive_energy == pytest.approx(E0_TNT * volume, rel=1e-12)
    assert hot.setups[0].charge.explosive_energy == pytest.approx(1.2 * E0_TNT * volume, rel=1e-12)
    hx = lookup("tnt", {"E0": 1.2 * E0_TNT})
    assert hot.summary["cj_pressure"] == pytest.approx(chapman_jouguet(hx.eos_params(), hx.E0).pressure, rel=1e-12)
    assert hot.summary["cj_pressure"] > base.summary["cj_pressure"]
    internal = [r.setups[0].charge.measure * float(np.sum(r.setups[0].zone_mass * r.setups[0].e)) for r in (base, hot)]
    assert internal[1] - internal[0] == pytest.approx(0.2 * E0_TNT * volume, rel=1e-9)  # what the zones start with
    with pytest.raises(ScenarioError, match="materials.air: overrides a material this scenario does not use"):
        parse(charge_data(materials={"air": {"gamma": 1.3}}))
    with pytest.raises(ScenarioError, match="materials.tnt.E0"):
        parse(charge_data(materials={"tnt": {"E0": -1.0}}))
    plate = {"method": "lagrangian1d", "name": "t-plate", "incident": {"profile": "uniform", "overpressure": 1e5},
             "plate": {"fixed": True}, "domain": {"length": 1.0}, "grid": {"cells": 50},
             "time": {"end": 1e-4}, "materials": {"tnt": {"E0": E0_TNT}}}
    with pytest.raises(ScenarioError, match="materials.tnt: overrides a material this scenario does not use"):
        parse(plate)


def test_plate_problem_without_charge_still_needs_a_plate():
    data = charge_data()
    del data["charge"]
    data["incident"] = {"profile": "uniform", "overpressure": 1e5}
    data["domain"]["geometry"] = "planar"
    with pytest.raises(ScenarioError, match="plate"):
        parse(data)
    data["plate"] = {"fixed": True}
    data["domain"]["geometry"] = "spherical"
    with pytest.raises(ScenarioError, match="planar"):
        parse(data)


# Afterburning (charge.afterburn_energy / afterburn_start / afterburn_end; scheme.afterburn_increment):
# Radioss LAW5 Eadd/Tstart/Tstop, LS-DYNA *EOS_JWL_AFTERBURN constant rate.


def test_afterburn_increment_integrates_the_window_exactly():
    # arbitrary steps straddling both window ends: the increments add up to rate (t_e - t_s) in a burnt
    # zone; nothing before its burn completes (t_L + 1/burn_rate), nothing in inert gas (rate 0)
    zones = scheme.Zones(*(jnp.zeros(3) for _ in range(6)), jnp.asarray([0.0, 2e-5, -jnp.inf]),
                         jnp.asarray([1e6, 1e6, 1.0]))
    ab = scheme.Afterburn(jnp.asarray([2.0, 2.0, 0.0]), jnp.asarray(1e-5), jnp.asarray(5e-5))
    dts = np.random.default_rng(0).uniform(1e-7, 3e-6, 60)
    t, total = 0.0, np.zeros(3)
    for dt in dts:
        total += np.asarray(scheme.afterburn_increment(jnp.asarray(t), jnp.asarray(dt), ab, zones))
        t += dt
    assert t > 5e-5
    assert total[0] == pytest.approx(2.0 * 4e-5, rel=1e-12)
    assert total[1] == pytest.approx(2.0 * (5e-5 - 2.1e-5), rel=1e-12)  # burnt at 2e-5 + 1e-6
    assert total[2] == 0.0


def test_afterburn_off_is_the_scheme_without_it(one_kg):
    # zero energy (with a window given) builds no source: the state and histories are those of the
    # run without the keys, bit for bit, and the summary reports no afterburning
    off = blastfsi.run(charge_data(charge__afterburn_energy=0.0, charge__afterburn_start=1e-5,
                                   charge__afterburn_end=3e-4))
    assert off.setups[0].afterburn is None and np.all(np.asarray(off.state.afterburn_released) == 0.0)
    ref, new = jax.tree_util.tree_leaves(one_kg.state), jax.tree_util.tree_leaves(off.state)
    assert len(ref) == len(new)
    for a, b in zip(ref, new):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    for key in one_kg.history:
        np.testing.assert_array_equal(np.asarray(one_kg.history[key]), np.asarray(off.history[key]))
    assert off.summary["afterburn_energy_released"] == 0.0 and off.summary["afterburn_energy_total"] == 0.0


def test_afterburn_is_booked_in_the_energy_budget(one_kg):
    run = blastfsi.run(charge_data(**AFTERBURN))
    s, charge = run.summary, run.setups[0].charge
    volume = charge.charge_mass / RHO_TNT
    assert s["afterburn_energy_total"] == pytest.approx(E0_TNT * volume, rel=1e-12)
    # the whole window lies inside the run: exactly Q x charge volume released (round-off of ~1e3 steps)
    assert s["afterburn_energy_released"] == pytest.approx(E0_TNT * volume, rel=1e-12)
    # the budget closes as without afterburning (same first-order vNR defect, 0.1-0.2 %), although the
    # source doubled the charge's energy: unbooked, the error would be ~ the released energy itself
    assert abs(s["energy_error_relative"]) < 1e-2
    err = abs(float(run.history["energy_error"][-1]))
    err0 = abs(float(one_kg.history["energy_error"][-1]))
    released = s["afterburn_energy_released"] / charge.measure
    assert err < 3.0 * err0 and err < 0.01 * released
    # the added energy drives a stronger blast at both gauges
    for g, g0 in zip(s["gauges"], one_kg.summary["gauges"]):
        assert g["impulse"] > g0["impulse"]


def test_afterburn_before_the_burn_completes_is_rejected():
    # 40 zones across R = 52.7 mm: the last zone's burn completes at (R + h) / D = 7.80 us
    with pytest.raises(ScenarioError, match=r"charge.afterburn_start \(5e-06 s\) must be >= 7.796.*e-06 s"):
        blastfsi.run(charge_data(**{**AFTERBURN, "charge__afterburn_start": 5e-6}))
