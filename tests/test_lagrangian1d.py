"""Tiers 1-2 for the vNR solver: jump conditions, invariants, ensembles, faults."""
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from blastfsi import simulation, timeloop
from blastfsi.exact import shock
from blastfsi.io.results import read_checkpoint
from blastfsi.lagrangian1d import scheme
from conftest import P0, RHO0, uniform_data

NO_GAUGES = scheme.Gauges(jnp.zeros((0,)), jnp.asarray(P0))
NUM = scheme.Numerics(*map(jnp.asarray, (1.4, 1.5, 0.1, 0.5)))
BC = scheme.Boundaries(*map(jnp.asarray, (0.0, P0, 0.0, P0)))
PARAMS = scheme.Params(NUM, BC, NO_GAUGES, jnp.asarray(1.0))
WALLS = scheme.Static(left_velocity_set=True, right_fixed=False)


def gas_at_rest(n):
    x = jnp.linspace(0.0, 1.0, n + 1)
    return x, scheme.initial_state(x, jnp.zeros(n + 1), jnp.full(n, P0 / (0.4 * RHO0)), jnp.full(n, RHO0 / n), 1.4, 4)


def wall_run(ratio, cells=400, length=2.0, **over):
    """Uniform shock on a rigid wall, run for the clean window after arrival."""
    s = shock.incident_shock(ratio * P0, P0, RHO0)
    data = uniform_data(incident__overpressure=ratio * P0, plate__beta_s=None, plate__fixed=True,
                        grid__cells=cells, domain__length=length, output__fields=0, **over)
    sc = simulation.parse(data)
    from blastfsi.lagrangian1d.plate_problem import clean_window

    data["time"]["end"] = length / s.shock_speed + 0.95 * clean_window(sc, ratio * P0)
    return simulation.run(data)


@pytest.mark.parametrize("ratio", [0.1, 4.49, 100.0])
def test_rigid_wall_reflection_coefficient(ratio):
    # The plateau behind the reflected shock satisfies the jump conditions exactly
    # for a conservative shock-capturing scheme; 1 % covers the start-up and
    # wall-heating transients still inside the averaging window at 400 zones.
    res = wall_run(ratio)
    cr = res.summary["reflection_coefficient"]
    assert cr == pytest.approx(shock.reflection_coefficient(ratio * P0, P0), rel=1e-2)


def test_energy_budget_closes_and_converges_with_the_time_step():
    # vNR with the Eq. (16) update is conservative only up to the time
    # staggering of the pressure in the momentum and energy equations: the
    # defect is first order in dt/dx (the CFL factor alpha), independent of N.
    errs = [abs(wall_run(4.49, cells=200, numerics={"cfl": c}).summary["energy_error_relative"]) for c in (0.5, 0.25)]
    assert errs[0] < 2e-3
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.1)


def test_gas_at_rest_stays_at_rest():
    x, st = gas_at_rest(50)
    out = scheme.advance(st, PARAMS, WALLS, 1e-3, 10_000, 1e-3 / 3, 1e-6)
    assert int(out.step) > 10  # at rest up to round-off of the unequal linspace spacings
    np.testing.assert_allclose(np.asarray(out.x), np.asarray(x), rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.asarray(out.e), np.asarray(st.e), rtol=1e-13)
    assert np.max(np.abs(np.asarray(out.v))) < 1e-13 * 346.0  # round-off relative to the sound speed


def test_first_fault_locates_the_bad_zone():
    x, st = gas_at_rest(20)
    assert int(scheme.first_fault(st)) == -1
    assert int(scheme.first_fault(st._replace(e=st.e.at[7].set(-1.0)))) == 7
    assert int(scheme.first_fault(st._replace(e=st.e.at[3].set(jnp.nan)))) == 3
    assert int(scheme.first_fault(st._replace(x=st.x.at[12].set(0.5)))) == 11  # tangled: x_12 < x_11
    # advance refuses to step from a non-physical state and flags it (the sound speed, like e, is NaN)
    bad_e = st._replace(e=st.e.at[7].set(-1.0), a=st.a.at[7].set(jnp.nan))
    for bad in (bad_e, st._replace(x=st.x.at[12].set(0.5))):
        out = scheme.advance(bad, PARAMS, WALLS, 1e-3, 100, 1e-3 / 3, 1e-6)
        assert int(out.fault) == timeloop.FAULT_NONPHYSICAL and int(out.step) == 0


def test_driver_reports_time_step_location(tmp_path):
    # no artificial viscosity and alpha = 1: the captured shock rings until an
    # energy goes negative, well after the first checkpoints (the zone being
    # crushed first collapses the time step: that check is switched off here)
    data = uniform_data(numerics={"K1": 0.0, "K2": 0.0, "cfl": 1.0}, grid__cells=200, time__end=2 / 700,
                        output__checkpoint_interval=2e-4, time__dt_min_fraction=0.0)
    with pytest.raises(simulation.SimulationError) as err:
        simulation.run(data, tmp_path / "r")
    msg = str(err.value)
    assert "non-physical state" in msg and "t = " in msg and "step" in msg and "x = " in msg
    t_fault = float(msg.split("t = ")[1].split()[0])
    ckpt = Path(msg.split("last checkpoint: ")[1])
    leaves, meta = read_checkpoint(ckpt)  # the last checkpoint is intact and earlier than the fault
    assert meta["time"] < t_fault and not leaves["fault"].any()
    assert np.all(np.diff(leaves["x"][0]) > 0) and np.all(leaves["e"] > 0)


def test_ensemble_equals_individual_runs():
    sweep = {"overpressure": [0.5 * P0, 4.49 * P0], "beta_s": [0.1, 10.0]}
    ens = simulation.run(uniform_data(sweep=sweep, grid__cells=200, output__fields=0, time__end=0.0055))
    assert len(ens.summaries) == 4
    for k, member in enumerate(ens.members):
        single = simulation.run(uniform_data(incident__overpressure=member["incident.overpressure"],
                                             plate__beta_s=member["plate.beta_s"], grid__cells=200, output__fields=0,
                                             time__end=0.0055))
        for key in ("plate_velocity", "plate_impulse", "plate_displacement"):
            assert ens.summaries[k][key] == pytest.approx(single.summary[key], rel=1e-12, abs=1e-14)


def test_compiled_once_for_a_whole_run():
    compiles = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, secs, **kw: compiles.append(event) if event == "/jax/core/compile/backend_compile_duration"
        else None)
    first = simulation.run(uniform_data(grid__cells=150, output__fields=5), chunk_steps=50)  # many chunks and stops
    assert first.summary["compile_time"] > 0.0 and first.summary["steps"] > 10 * 50
    compiles.clear()
    again = simulation.run(uniform_data(grid__cells=150, output__fields=5, plate__beta_s=3.0), chunk_steps=50)
    assert again.summary["compile_time"] == 0.0 and compiles == []  # nothing compiled for the same shapes


def test_plate_matches_quasi_steady_theory():
    # p_s/p0 = 4.49, beta_s = 1: the plate velocity of the quasi-steady Riemann
    # model (exact at both ends of the motion) and of the simulation agree;
    # 1.5 % covers the shock smearing (3 zones) at 800 zones.
    ps = 4.49 * P0
    res = simulation.run(uniform_data(grid__cells=800, output__fields=0))
    theory = res.setups[0].theory
    v_theory = shock.quasi_steady_plate(ps, theory.duration, theory.plate_areal_mass, P0, RHO0)
    assert res.summary["plate_velocity"] == pytest.approx(v_theory, rel=1.5e-2)


def test_light_plate_reaches_free_surface_velocity():
    ps = 4.49 * P0
    res = simulation.run(uniform_data(plate__beta_s=1e3, grid__cells=800, output__fields=0))
    assert res.summary["plate_velocity"] == pytest.approx(float(shock.free_surface_velocity(ps, P0, RHO0)), rel=1e-2)


def test_float32_run_keeps_precision_and_accuracy():
    res = wall_run(4.49, numerics={"precision": "float32"})
    assert res.state.x.dtype == jnp.float32 and res.state.hist.dtype == jnp.float32
    assert res.summary["reflection_coefficient"] == pytest.approx(shock.reflection_coefficient(4.49 * P0, P0), rel=1e-2)


def test_free_end_expands_to_the_free_surface_velocity():
    # plate.areal_mass = 0: the end node is a free surface held at p0; after the
    # shock arrives it leaves at u_fs (isentropic expansion to p0, docs/theory/lagrangian1d.md)
    ps = 4.49 * P0
    res = simulation.run(uniform_data(plate__beta_s=None, plate__areal_mass=0.0, grid__cells=800, output__fields=0))
    assert res.summary["beta_s"] is None and res.summary["plate_impulse"] == 0.0
    assert res.summary["plate_velocity"] == pytest.approx(float(shock.free_surface_velocity(ps, P0, RHO0)), rel=1e-2)


def test_gauges_see_the_incident_shock_and_its_impulse():
    # Gauges at 1.5 m and 1.8 m of a 2 m column: the uniform incident shock passes with
    # overpressure p_s (jump conditions) and arrival x/U_s; before the reflected
    # wave returns the positive impulse is p_s (t - x/U_s).
    ps = 4.49 * P0
    s = shock.incident_shock(ps, P0, RHO0)
    t_end = 2.0 / s.shock_speed + 1e-5  # just after arrival at the wall: no reflection back at the gauges
    res = simulation.run(uniform_data(plate__beta_s=None, plate__fixed=True, grid__cells=800, time__end=t_end,
                                      output__fields=0, output__gauges=[1.5, 1.8, 0.5]))
    summ, hist = res.summary, res.histories[0]
    # the piston (at u_p) passes the gauge at 0.5 m: from then on it lies outside the gas
    passed = hist["time"] > 0.5 / s.particle_velocity
    assert np.all(np.isnan(hist["gauge2_overpressure"][passed])) and np.all(np.isfinite(
        hist["gauge2_overpressure"][~passed]))
    for k, x in enumerate((1.5, 1.8)):
        late = hist["time"] > x / s.shock_speed + 2e-4
        np.testing.assert_allclose(hist[f"gauge{k}_overpressure"][late], ps, rtol=2e-3)
        # smeared shock of ~3 zones shifts the impulse by ~ 3 dx / U_s * p_s / 2
        assert summ["gauge_impulse"][k] == pytest.approx(ps * (t_end - x / s.shock_speed), rel=0.02)
        assert summ["gauge_peak_overpressure"][k] == pytest.approx(ps, rel=0.05)


@pytest.mark.parametrize("zones", [100, 8000, 20000])
def test_stable_dt_flags_a_nan_zone_on_long_grids(zones):
    """The time-step reduction is the fault check: one NaN zone anywhere gives a NaN step (XLA:CPU's
    vectorised min does not propagate NaN on long arrays: found on 6400-zone detonation runs that ran on
    with a NaN state)."""
    num = scheme.Numerics(*(jnp.asarray(v) for v in (1.4, 1.5, 0.06, 0.5)))
    dx = jnp.full(zones, 1e-3)
    v = jnp.zeros(zones + 1)
    for bad in (0, zones // 2 + 3, zones - 1):
        a = jnp.full(zones, 340.0).at[bad].set(jnp.nan)
        assert np.isnan(float(jax.jit(scheme.stable_dt)(dx, a, v, num)))
    assert float(jax.jit(scheme.stable_dt)(dx, jnp.full(zones, 340.0), v, num)) == pytest.approx(0.5e-3 / 340.0)
