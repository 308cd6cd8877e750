"""The cfdmp method (seed 000 Sec. 3): the bridge coupling of the Eulerian and MPM solvers through the one
driver. Small grids; the 1D configurations share one compiled time loop.

* a gas at rest stays at rest through both bridges (the interface force of Eqs. 37-39 balances the
  particles' stress exactly);
* the Sod shock of ``cfdmp-shock-tube`` crosses the MPM box: mass budget closed to round-off, the wave
  reflected by the bridge back into the Eulerian region below 2 % of the incident pressure jump (issue 8);
* bad input: clear errors naming the key.
"""
import json

import jax
import numpy as np
import pytest

import blastfsi
from blastfsi.api import example_data
from blastfsi.exact.riemann import RiemannProblem
from blastfsi.scenario import ScenarioError

FAST = {"grid.cells": 200, "output.plots": False, "output.fields": 3, "output.history_samples": 61}


def assert_budget_closed(summary, mass=1e-13):
    """Mass closes to round-off; with the MPM steps' change and the Eulerian face pressure transfer booked, so
    do momentum (conserved axes) and energy: the transport (reservoirs, particle creation, cuts and deletion,
    settling, boundary outflow) loses nothing. Round-off: ~1e-16 per step and per reduction over a few 1e3
    steps (measured <= 1.2e-15 on cfdmp-shock-tube, 2.6e-16 on he-slab-2d to 15 us)."""
    b = summary["budget"]
    assert b["max_mass_residual_relative"] < mass
    transport = {k: v for k, v in b["transport"].items() if k.startswith("max_")}
    assert "max_energy_residual_relative" in transport and len(transport) > 1
    assert all(v < 1e-12 for v in transport.values()), transport


def tube(**initial):
    d = example_data("cfdmp-shock-tube")
    d["initial"].update(initial)
    return d


def shock_tube_and_its_eulerian_twin(out, overrides, coupled_only=None):
    """``cfdmp-shock-tube`` with ``overrides`` (and ``coupled_only``), and the same tube all-Eulerian
    (HLLC-MUSCL, cfl 0.4)."""
    coupled = blastfsi.run("cfdmp-shock-tube", out=out / "c", set={**overrides, **(coupled_only or {})})
    d = example_data("cfdmp-shock-tube")
    d["method"] = "euler"
    d.pop("mpm_region")
    d["numerics"] = {"scheme": "hllc-muscl", "cfl": 0.4}
    return coupled, blastfsi.run(d, out=out / "e", set=overrides)


@pytest.fixture(scope="module")
def shock(tmp_path_factory):
    return shock_tube_and_its_eulerian_twin(tmp_path_factory.mktemp("cfdmp"), FAST)


def test_gas_at_rest_stays_at_rest():
    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    res = blastfsi.run(tube(left=state, right=state), set=FAST)
    f = res.fields()
    # the view of the box comes from the particles; round-off only (1e-12 of the pressure)
    assert np.max(np.abs(f["pressure"] - 1.0e5)) < 1e-12 * 1.0e5 * 10
    assert np.max(np.abs(f["velocity"])) < 1e-9
    assert_budget_closed(res.summary, 1e-14)


@pytest.mark.parametrize("speed", [100.0, 293.3])
def test_uniform_flow_passes_through_the_box_undisturbed(speed):
    """A uniform flow through both bridges stays uniform. Gas leaves the box by the part of each particle
    beyond the exit face (coupling.cut_at_coupled_faces): deleting a particle whole when its centre crossed
    disturbed the flow by packets (1-3 % past the exit at 100 m/s) and, at the Sod star state (293 m/s, Mach
    0.73), fed a growing suction (19 % in the box, 65 % past it after 1 ms). Uniform states are mapped
    exactly by every transfer, so the bound is round-off: 1e-9 relative after ~0.3 box transits."""
    state = {"material": "air", "density": 0.2656, "pressure": 30313.0, "velocity": speed}
    res = blastfsi.run(tube(left=state, right=state), set=FAST | {"time.end": 2.5e-4})
    f = res.fields()
    assert res.summary["particles"] > 0
    assert np.max(np.abs(f["density"] / 0.2656 - 1.0)) < 1e-9
    assert np.max(np.abs(f["pressure"] / 30313.0 - 1.0)) < 1e-9
    assert np.max(np.abs(f["velocity"][:, 0] - speed)) < 1e-9 * speed
    assert_budget_closed(res.summary, 1e-14)


def test_shock_crosses_the_mpm_region(shock):
    coupled, euler = shock
    s = coupled.summary
    assert s["coupled_faces"] == ["lower x", "upper x"] and s["activation_time"] == 0.0
    # mass: Eulerian-only cells + particles + reservoirs + domain outflow, exact up to round-off
    assert_budget_closed(s, 1e-13)
    exact = RiemannProblem((1.0, 0.0, 1e5), (0.125, 0.0, 1e4), x0=0.3)
    jump = exact.p_star - 1e4
    worst = 0.0
    for _, t in coupled.snapshots[1:]:
        fc, fe = coupled.fields(t), euler.fields(t)
        left = fc["x"] < 0.5  # Eulerian region upstream of the box
        worst = max(worst, np.max(np.abs(fc["pressure"][left] - fe["pressure"][left])) / jump)
    assert worst < 0.02  # issue 8 target: reflection below 2 % of the incident jump
    assert_l1_within_a_quarter_of_euler(coupled, euler, exact)  # (measured 1.13 / 1.13 at 200 cells)
    # the shock has left the box and runs on in the Eulerian region downstream at the exact speed
    f = coupled.fields()
    p = f["pressure"]
    front = f["x"][np.nonzero(p > 1e4 + 0.5 * jump)[0].max()]
    dx = f["x"][1] - f["x"][0]
    shock_x = 0.3 + exact.right_wave_speeds[0] * coupled.summary["time"]
    assert abs(front - shock_x) < 3 * dx


def test_shock_crosses_the_mpm_region_with_the_ambient_reference_pressure(tmp_path):
    """numerics.reference_pressure = the gas ahead of the shock (1e4 Pa): the particles, the ring cells and the
    flow-out mirror take p - p_ref. Measured at 200 / 400 cells: reflection at the bridge 1.47 / 1.27 % of the
    jump (absolute stresses 1.78 / 1.59 %), L1 ratio at most 1.218 at 400 cells (absolute 1.249)."""
    coupled, euler = shock_tube_and_its_eulerian_twin(tmp_path, FAST, {"numerics.reference_pressure": 1.0e4})
    assert_budget_closed(coupled.summary, 1e-13)
    exact = RiemannProblem((1.0, 0.0, 1e5), (0.125, 0.0, 1e4), x0=0.3)
    jump = exact.p_star - 1e4
    for _, t in coupled.snapshots[1:]:
        fc, fe = coupled.fields(t), euler.fields(t)
        left = fc["x"] < 0.5
        assert np.max(np.abs(fc["pressure"][left] - fe["pressure"][left])) < 0.02 * jump, t
    assert_l1_within_a_quarter_of_euler(coupled, euler, exact)


def assert_l1_within_a_quarter_of_euler(coupled, euler, exact, after=0.0):
    """Issue 8 target: L1(rho) against the exact solution within 25 % of the all-Eulerian run's on the same
    grid, at every snapshot after the start (the shock in the box, and after it left), or after ``after``."""
    for _, t in coupled.snapshots[1:]:
        if t < after:
            continue
        fc, fe = coupled.fields(t), euler.fields(t)
        rho = exact(fc["x"], t)[0]
        assert np.sum(np.abs(fc["density"] - rho)) <= 1.25 * np.sum(np.abs(fe["density"] - rho)), t


@pytest.mark.slow  # default-suite time: the same bound at 200 cells is checked by test_shock_crosses_the_mpm_region
def test_shipped_shock_tube_error_stays_within_a_quarter_of_the_eulerian_one(tmp_path):
    """``cfdmp-shock-tube`` as shipped (400 cells, 1.2 ms). Deleting a particle whole when its centre crossed
    the exit face gave L1 ratios 1.20 / 1.46 at 0.6 / 1.2 ms (a suction ahead of the exit, packets past
    it); cutting particles at the face (coupling.cut_at_coupled_faces): 1.21 / 1.16."""
    coupled, euler = shock_tube_and_its_eulerian_twin(
        tmp_path, {"output.plots": False, "output.fields": 3, "output.history_samples": 61})
    assert_l1_within_a_quarter_of_euler(coupled, euler, RiemannProblem((1.0, 0.0, 1e5), (0.125, 0.0, 1e4), x0=0.3))


def test_a_collapsed_step_names_its_fastest_signal(shock):
    """A run stopped on a collapsed step (no non-physical cell or particle) is located at its fastest signal
    |u| + c: of the cells that set the step (Eulerian and bridge cells: region 0 and 1 of the fields) and of
    the active particles; the message names the cell or particle, where it is and its state."""
    coupled, _ = shock
    member = jax.tree_util.tree_map(lambda a: np.asarray(a)[0], coupled.state)
    message = coupled.method.locate_fault(member, coupled.setups[0])
    f = coupled.fields()
    cells = np.where(f["region"] < 2, f["sound_speed"] + np.abs(f["velocity"]), 0.0)
    particles = np.asarray(member.mpm.particles.wave_speed) + np.abs(np.asarray(member.mpm.particles.v)[:, 0])
    fastest = max(float(np.max(cells)), float(np.max(particles[np.asarray(member.mpm.particles.active)])))
    assert message.startswith("fastest signal ") and " at x = " in message and "density" in message, message
    assert float(message.split()[2]) == pytest.approx(fastest, rel=1e-3), message  # (printed to 4 digits)


def test_a_non_physical_cell_is_named_with_its_region_and_state(shock):
    """A run stopped on a non-physical cell names the cell, where it is, its region (Eulerian, bridge or
    fictitious) and its state."""
    coupled, _ = shock
    member = jax.tree_util.tree_map(lambda a: np.asarray(a)[0], coupled.state)
    setup = coupled.setups[0]
    for region, cell in (("an Eulerian cell", int(np.argmax(setup.outside))),
                         ("a bridge cell", int(np.argmax(~setup.outside & ~setup.fictitious))),
                         ("a fictitious cell", int(np.argmax(setup.fictitious)))):
        U = np.array(member.U)
        U[-1, cell] = -1.0  # a negative total energy: p < 0
        message = coupled.method.locate_fault(member._replace(U=U), setup)
        assert message.startswith(f"cell ({cell},) at x = ") and region in message, message
        assert "density" in message and "pressure -" in message, message


@pytest.mark.slow  # default-suite time (< 10 min on 2 cores)
def test_strong_shock_leaves_the_mpm_region():
    """A 500:1 shock (13 MPa, like the he-slab-2d blast at its gauges) crosses the box and leaves it into the
    Eulerian region. Settling each step's outflow debt at once emptied the first Eulerian cell past the
    exit face when the shock reached it (non-physical state at 123 us: the fine history sampling shortens the
    steps, so several steps' debt came due before the particle that repays it crossed the face); now the
    run goes on, the mass budget
    stays exact, and the shock runs on downstream at the exact speed."""
    L, R = (6.0, 0.0, 5e7), (1.2, 0.0, 1e5)
    res = blastfsi.run(tube(left={"material": "air", "density": L[0], "pressure": L[2]},
                            right={"material": "air", "density": R[0], "pressure": R[2]}),
                       set={**FAST, "grid.cells": 400, "time.end": 1.6e-4, "output.history_samples": 2001})
    assert_budget_closed(res.summary, 1e-13)
    exact = RiemannProblem(L, R, x0=0.3)
    f = res.fields()
    x, p = f["x"], f["pressure"]
    front = x[np.nonzero(p > R[2] + 0.5 * (exact.p_star - R[2]))[0].max()]
    assert front > 0.75 and abs(front - (0.3 + exact.right_wave_speeds[0] * 1.6e-4)) < 3 * (x[1] - x[0])
    assert np.all(f["density"] > 0.5 * R[0])


@pytest.mark.slow  # default-suite time (< 10 min on 2 cores)
def test_a_full_pool_grows_and_a_fixed_one_stops_the_run():
    """A default pool (structures + numerics.pool_headroom x the box's gas particles + one step's emissions;
    here a headroom of 1, so that the box's gas, compressed to 1.51 x its particles, surely fills it) fills as
    the shock compresses the box's gas and the bridge creates particles: the loop stops while the pool still has
    room for one step's emissions, the driver enlarges it, compiles the loop once more (summary
    ``pool_growths``) and the run goes on. No emission is refused, so the solution is the
    one of a run with room to spare, to round-off (the extra slots add exact zeros to every sum; only the
    order of the pool reductions changes), and the mass budget stays exact. With ``numerics.capacity`` set,
    the same pool stops the run when an emission does not fit, with the size needed."""
    from blastfsi import api, method as methods
    from blastfsi.scenario import expand
    from blastfsi.simulation import SimulationError

    tight = {**FAST, "numerics.pool_headroom": 1.0}
    coupled = blastfsi.run("cfdmp-shock-tube", set=tight)
    initial = methods.get("cfdmp").build(expand(api.load("cfdmp-shock-tube", set=tight))[2][0]).capacity
    assert np.nanmax(coupled.history["particles"]) > initial and coupled.summary["capacity"] > initial
    assert coupled.summary["pool_growths"] == 1
    assert_budget_closed(coupled.summary, 1e-13)
    roomy = blastfsi.run("cfdmp-shock-tube", set={**FAST, "numerics.capacity": 20 * initial})
    assert roomy.summary["capacity"] == 20 * initial and roomy.summary["pool_growths"] == 0
    assert coupled.summary["steps"] == roomy.summary["steps"]
    f, g = coupled.fields(), roomy.fields()
    for name in ("density", "pressure", "velocity"):
        assert np.max(np.abs(f[name] - g[name])) <= 1e-9 * np.max(np.abs(g[name]))
    with pytest.raises(SimulationError, match=r"particle pool full.*numerics.capacity >= \d+"):
        blastfsi.run("cfdmp-shock-tube", set={**FAST, "numerics.capacity": initial})


@pytest.mark.slow  # default-suite time: a restart into a resized pool is in the default suite (the packed pool's)
def test_restart_from_a_grown_pool_is_bit_for_bit(tmp_path):
    """A checkpoint written after the pool grew holds the larger pool; --restart rebuilds the run's initial
    state, grows its pool to the checkpoint's and continues bit for bit. (A headroom of 1: the box's gas
    compresses to 1.51 x its particles, so the pool surely grows.)"""
    import shutil

    from blastfsi.io import results

    end = example_data("cfdmp-shock-tube")["time"]["end"]
    over = {**FAST, "output.checkpoint_interval": 0.75 * end, "numerics.pool_headroom": 1.0}
    res = blastfsi.run("cfdmp-shock-tube", out=tmp_path / "a", set=over)
    checkpoint = sorted((tmp_path / "a" / "checkpoints").glob("ckpt_*.h5"))
    assert len(checkpoint) == 1
    saved, _ = results.read_checkpoint(checkpoint[0])
    assert saved["mpm.particles.active"].shape[1] == res.summary["capacity"]  # grown before 0.75 end
    assert res.summary["pool_growths"] == 1
    copy = tmp_path / "b"
    shutil.copytree(tmp_path / "a", copy)
    again = blastfsi.restart(copy)
    a, b = res.fields(), again.fields()
    for key in ("density", "pressure", "velocity"):
        np.testing.assert_array_equal(a[key], b[key])
    assert again.summary["steps"] == res.summary["steps"] and again.summary["capacity"] == res.summary["capacity"]
    assert again.summary["pool_growths"] == 0  # rebuilt at the checkpoint's size before its one compilation


def test_a_pool_packed_into_fewer_slots_keeps_every_particle_and_reference(shock):
    """cfdmp's resize to fewer slots: the structures keep their slots, the gas particles in use follow in their
    order with every field unchanged, the reservoirs' inflow slots follow their particles (a freed slot's is
    dropped); resized back up, the packed slots stay."""
    import jax

    from blastfsi import method as methods
    from blastfsi.simulation import _members

    cfdmp = methods.get("cfdmp")
    coupled = shock[0]
    setup, member = coupled.setups[0], _members(coupled.state)[0]
    P = member.mpm.particles
    used = np.flatnonzero(P.active)
    free = np.flatnonzero(~P.active[: used[-1]])
    assert used.size > 10 and free.size > 0  # gas left the box: the pool has holes to pack
    buffer = np.full_like(member.reservoirs.buffer, -1)
    buffer.flat[0], buffer.flat[1] = used[-1], free[0]
    member = member._replace(reservoirs=member.reservoirs._replace(buffer=buffer))
    n_struct = setup.coupling.structure_particles
    capacity = used.size + 7
    small_setup, small = cfdmp.resize(setup, member, capacity)
    Q = small.mpm.particles
    assert small_setup.capacity == capacity == Q.active.shape[0]
    assert np.array_equal(np.flatnonzero(Q.active), np.arange(used.size))
    for a, b in zip(jax.tree_util.tree_leaves(P), jax.tree_util.tree_leaves(Q)):
        np.testing.assert_array_equal(np.asarray(b)[: used.size], np.asarray(a)[used])
        np.testing.assert_array_equal(np.asarray(b)[:n_struct], np.asarray(a)[:n_struct])
    assert small.reservoirs.buffer.flat[0] == used.size - 1 and small.reservoirs.buffer.flat[1] == -1
    assert cfdmp.pool_needed(small, small_setup) == cfdmp.pool_needed(member, setup)
    big_setup, big = cfdmp.resize(small_setup, small, 2 * capacity)
    assert big_setup.capacity == 2 * capacity and not np.any(big.mpm.particles.active[capacity:])
    np.testing.assert_array_equal(big.mpm.particles.x[:capacity], Q.x)
    with pytest.raises(ValueError, match="cannot hold"):
        cfdmp.resize(setup, member, used.size - 1)


def test_a_read_fictitious_cell_without_gas_keeps_its_last_state(shock):
    """A fictitious cell that the scheme reads but whose nodes carry no gas (the gas expanded away) keeps the
    state the particles last gave it, exactly: the scheme's own update there runs at a step its signal does not
    bound (only the fictitious cells next to the scheme's own set it) and grew without bound in
    steel-plate-blast (an empty cell between the bridge and the plate, 1e-4 -> 0.24 kg/m^3 -> NaN at 0.48 ms).
    Here every gas particle of the tube's box is removed and one step taken (the loop the fixture compiled);
    the read cells beyond the bridges keep their values to the bit, while the bridge cells (the scheme's own)
    change."""
    import jax.numpy as jnp

    from blastfsi import method as methods
    from blastfsi.simulation import _members, _stack

    coupled = shock[0]
    cfdmp = methods.get("cfdmp")
    setup, member = coupled.setups[0], _members(coupled.state)[0]
    P = member.mpm.particles
    member = member._replace(mpm=member.mpm._replace(particles=P._replace(active=np.zeros_like(P.active))))
    params = cfdmp.params(setup, jnp.float64)
    read = np.asarray(params.layout.fictitious & ~params.layout.parked)
    bridge = ~np.asarray(params.layout.fictitious | params.layout.outside)
    assert read.sum() >= 4 and bridge.sum() >= 4
    static = cfdmp.static(setup, coupled.scenario)
    state, batched = _stack([member], "state"), _stack([params], "params")
    sample = coupled.scenario.time.end / (coupled.scenario.output.history_samples - 1)
    advance, _ = methods.compiled_advance(cfdmp, static, state, batched, coupled.scenario.time.end + 1.0, 1,
                                          sample, coupled.scenario.time.dt_min_fraction)
    after = _members(advance(state, batched, coupled.scenario.time.end + 1.0, 1, sample,
                             coupled.scenario.time.dt_min_fraction))[0]
    assert int(after.step) == int(member.step) + 1 and int(after.fault) == 0
    np.testing.assert_array_equal(after.U[:, read], member.U[:, read])
    assert np.any(after.U[:, bridge] != member.U[:, bridge])


def test_a_pool_waiting_for_its_activation_keeps_room_for_it(shock):
    """Before the coupling starts (a stand-off charge's blast still on its way) a pool needs what the activation
    will make, the structures and the box's gas, not the few particles in use: packed to those, it had to grow
    again at the activation (two compilations of the loop for nothing). Once coupled, the particles in use."""
    from blastfsi import method as methods
    from blastfsi.simulation import _members

    cfdmp = methods.get("cfdmp")
    coupled = shock[0]
    setup, member = coupled.setups[0], _members(coupled.state)[0]
    c = setup.coupling
    P = member.mpm.particles
    empty = member._replace(mpm=member.mpm._replace(particles=P._replace(active=np.zeros_like(P.active))),
                            budget=member.budget._replace(required=np.zeros_like(member.budget.required)))
    assert c.activation_particles > 0 and c.pool_margin > 0
    assert cfdmp.pool_needed(empty._replace(coupled=np.asarray(False)), setup) == c.activation_particles + c.pool_margin
    assert cfdmp.pool_needed(empty._replace(coupled=np.asarray(True)), setup) == c.pool_margin


def test_a_mostly_empty_pool_is_packed_only_when_the_steps_left_repay_the_compilation():
    """SHRINK x the slots to two significant digits, once GROWTH x the need fits there, and only when the steps
    left x the slots removed exceed PACK_SLOT_STEPS (a compilation's cost in slot-steps); the pool is looked at
    every POOL_CHECK_WORK cell- and slot-updates, at least every POOL_CHECK_STEPS steps."""
    from blastfsi.simulation import (GROWTH, PACK_SLOT_STEPS, POOL_CHECK_STEPS, POOL_CHECK_WORK, SHRINK,
                                     pool_check_steps, shrunk_capacity)

    assert (GROWTH, SHRINK, PACK_SLOT_STEPS, POOL_CHECK_WORK, POOL_CHECK_STEPS) == (1.25, 0.6, 2e7, 5e6, 100)
    # steel-plate-blast at 0.15 ms: 25 264 slots, ~12 000 needed; 9264 slots removed
    assert shrunk_capacity(25_264, 12_000, 2200) == 16_000  # 2200 x 9264 = 2.04e7 slot-steps saved
    assert shrunk_capacity(25_264, 12_000, 2100) is None  # 1.95e7: not worth a compilation
    assert shrunk_capacity(25_264, 12_900, 1e9) is None  # 1.25 x 12 900 > 16 000: no headroom left
    assert shrunk_capacity(2_002, 100, 1e9) == 1_300 and shrunk_capacity(1_300, 100, 1e9) == 780
    assert shrunk_capacity(10, 1, 1e9) == 6 and shrunk_capacity(6, 4, 1e9) is None
    assert pool_check_steps(50_000, 25_264) == 100 and pool_check_steps(400, 600) == 5000


@pytest.mark.slow  # default-suite time; the packing itself (resize) and its rule (shrunk_capacity) stay in it
def test_a_mostly_empty_pool_shrinks_and_the_run_goes_on(shock, tmp_path, monkeypatch):  # (shock: its loop)
    """A pool of 20 x the box's gas (numerics.pool_headroom) is packed into fewer slots once the driver sees it
    mostly empty (looked at every POOL_CHECK_STEPS steps and the compilation cost waived, once, mid-run: the
    tube's pool is too small to be looked at or to repay it): the loop is compiled again (``pool_shrinks``) and
    the run gives the solution of a snug pool to round-off (only the order of the pool's sums changes), its mass budget closed. The
    same run in calls of other lengths (the clock sets them) packs at the same step and gives the same results to
    the bit; a restart from a checkpoint written after the packing rebuilds the pool at the checkpoint's size and
    continues bit for bit."""
    import shutil

    from blastfsi import api, method as methods, simulation
    from blastfsi.io import results
    from blastfsi.scenario import expand

    shrinks = []

    def worth_it_once(capacity, needed, steps_left, real=simulation.shrunk_capacity):
        smaller = None if shrinks or steps_left > 250 else real(capacity, needed, 1e12)  # (mid-run, in motion)
        shrinks.extend([smaller] if smaller else [])
        return smaller

    monkeypatch.setattr(simulation, "shrunk_capacity", worth_it_once)
    monkeypatch.setattr(simulation, "POOL_CHECK_WORK", 0.0)
    end = example_data("cfdmp-shock-tube")["time"]["end"]
    over = {**FAST, "numerics.pool_headroom": 20.0, "output.checkpoint_interval": 0.75 * end}
    res = blastfsi.run("cfdmp-shock-tube", out=tmp_path / "a", set=over)
    assert res.summary["pool_shrinks"] == 1 and res.summary["pool_growths"] == 0
    assert_budget_closed(res.summary, 1e-13)
    initial = methods.get("cfdmp").build(expand(api.load("cfdmp-shock-tube", set=over))[2][0]).capacity
    assert res.summary["capacity"] == shrinks[0] < initial
    snug = blastfsi.run("cfdmp-shock-tube", set={**FAST, "output.checkpoint_interval": 0.75 * end})
    assert res.summary["steps"] == snug.summary["steps"]
    f, g = res.fields(), snug.fields()
    for name in ("density", "pressure", "velocity"):
        assert np.max(np.abs(f[name] - g[name])) <= 1e-9 * np.max(np.abs(g[name]))
    shrinks.clear()
    monkeypatch.setattr(simulation, "next_chunk", lambda *a: 7)  # calls of 7 steps instead of about a second
    seven = blastfsi.run("cfdmp-shock-tube", set=over)
    assert seven.summary["pool_shrinks"] == 1 and seven.summary["steps"] == res.summary["steps"]
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree_util.tree_leaves(seven.state),
                                                     jax.tree_util.tree_leaves(res.state)))
    checkpoint = sorted((tmp_path / "a" / "checkpoints").glob("ckpt_*.h5"))
    assert len(checkpoint) == 1
    saved, _ = results.read_checkpoint(checkpoint[0])
    assert saved["mpm.particles.active"].shape[1] == shrinks[0]  # packed before 0.75 end
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    again = blastfsi.restart(tmp_path / "b")
    assert again.summary["capacity"] == shrinks[0] and again.summary["pool_shrinks"] == 0
    h = again.fields()
    for name in ("density", "pressure", "velocity"):
        np.testing.assert_array_equal(h[name], f[name])


def test_euler_cfl_sets_the_eulerian_courant_number_only():
    """numerics.euler_cfl is the Eulerian step's Courant number, numerics.cfl stays the MPM's; unset, both
    are numerics.cfl."""
    import jax.numpy as jnp

    from blastfsi import api, method as methods
    from blastfsi.scenario import expand

    cfdmp = methods.get("cfdmp")
    for over, (euler, particles) in (({}, (0.4, 0.4)), ({"numerics.euler_cfl": 0.8}, (0.8, 0.4)),
                                     ({"numerics.cfl": 0.3, "numerics.euler_cfl": 0.6}, (0.6, 0.3))):
        prm = cfdmp.params(cfdmp.build(expand(api.load("cfdmp-shock-tube", set={**FAST, **over}))[2][0]),
                           jnp.float64)
        assert (float(prm.euler.cfl), float(prm.mpm.cfl)) == (euler, particles)


def test_bad_input_is_named():
    base = example_data("cfdmp-shock-tube")

    def fails(match, **changes):
        d = {**base, **changes}
        with pytest.raises(ScenarioError, match=match):
            blastfsi.run(d, set={"output.plots": False})

    fails("leaves the domain", mpm_region={"lower": [0.5], "upper": [1.2]})
    fails("too narrow", mpm_region={"lower": [0.5], "upper": [0.53], "bridge_cells": 5})
    fails("cell face", mpm_region={"lower": [0.5013], "upper": [0.75]})
    fails("numerics.capacity", numerics={"capacity": 10})
    fails("numerics.pool_headroom", numerics={"pool_headroom": 0.5})
    slab = {"lower": [0.505], "upper": [0.6], "material": "concrete-48mpa"}
    fails("crosses the bridge", structures=[slab])
    fails("whole domain", mpm_region={"lower": [0.0], "upper": [1.0], "activation_overpressure": 1e4})
    fails("no \\[\\[structures\\]\\]", output={"tracers": [[0.7]]})
    far = {"lower": [0.7], "upper": [0.75], "material": "elastic-steel"}
    fails("output.tracers\\[0\\]", structures=[far], output={"tracers": [[0.6]]})


@pytest.mark.slow  # (the default suite's time: ~1 min / ~25 s)
def test_clamped_plate_deflects_and_its_supports_hold():
    """The shock of a 200 bar air driver hits a 10 mm steel plate across a 2D channel, clamped over 10 mm at
    both walls ([[structures.supports]]); tracers at its centre and in a clamp (output.tracers). The clamped
    particles do not move at all; the centre is pushed downstream and springs back (peak beyond the final
    displacement); the mass budget closes to round-off."""
    d = {"method": "cfdmp", "name": "clamped-plate",
         "domain": {"lower": [0.0, 0.0], "upper": [0.24, 0.12]}, "grid": {"cells": 48},
         "initial": {"kind": "riemann", "diaphragm": 0.06,
                     "left": {"density": 10.0, "pressure": 2.0e7}, "right": {"density": 1.2, "pressure": 1.0e5}},
         "boundaries": {"x": ["outflow", "outflow"], "y": ["wall", "wall"]},
         "mpm_region": {"lower": [0.12, 0.0], "upper": [0.24, 0.12]},
         "structures": [{"lower": [0.19, 0.0], "upper": [0.20, 0.12], "material": "elastic-steel",
                         "supports": [{"lower": [0.19, 0.0], "upper": [0.20, 0.01]},
                                      {"lower": [0.19, 0.11], "upper": [0.20, 0.12]}]}],
         "time": {"end": 2e-4}, "output": {"history_samples": 41, "fields": 0, "plots": False,
                                            "tracers": [[0.195, 0.06], [0.195, 0.005]]}}
    res = blastfsi.run(d)
    s, h = res.summary, res.history
    centre, clamp = s["tracer_displacement"]
    peak = s["tracer_peak_displacement"][0][0]
    assert clamp == [0.0, 0.0] and s["tracer_peak_displacement"][1] == [0.0, 0.0]
    assert np.all(h["tracer0_displacement_x"] >= 0.0) and peak > 2.0 * centre[0] > 0.0  # measured 4.8e-4, 1.5e-4 m
    assert abs(centre[1]) < 1e-2 * peak  # symmetric about the channel's mid-plane
    assert_budget_closed(s, 1e-13)


@pytest.mark.slow
def test_three_dimensional_coupling_closes_its_mass_budget():
    """Issue 8 item 5: a coarse 3D case (a Sod shock entering an MPM box that holds a steel block)."""
    d = {"method": "cfdmp", "name": "cfdmp-3d",
         "domain": {"lower": [0.0, 0.0, 0.0], "upper": [0.24, 0.12, 0.12]}, "grid": {"cells": 24},
         "initial": {"kind": "riemann", "diaphragm": 0.1,
                     "left": {"density": 1.0, "pressure": 1.0e5}, "right": {"density": 0.125, "pressure": 1.0e4}},
         "mpm_region": {"lower": [0.12, 0.0, 0.0], "upper": [0.24, 0.12, 0.12]},
         "structures": [{"lower": [0.21, 0.03, 0.03], "upper": [0.24, 0.09, 0.09], "material": "elastic-steel"}],
         "time": {"end": 5e-5}, "output": {"history_samples": 21, "fields": 0, "plots": False,
                                            "gauges": [[0.03, 0.06, 0.06], [0.125, 0.06, 0.06]]}}
    res = blastfsi.run(d)
    s = res.summary
    assert s["coupled_faces"] == ["lower x"]
    assert_budget_closed(s, 1e-13)
    # the shock (554 m/s) reaches the box face at 36 us and the first bridge cells before the end
    assert s["gauges"][1]["region"] == "bridge" and s["gauges"][1]["peak_overpressure"] > 1e4


@pytest.mark.slow  # ~5 min on 2 cores
def test_he_slab_3d_runs_and_closes_its_mass_budget():
    """Issue 8 item 5 on the shipped coarse 3D explosion-slab case: the run reaches its end with the mass
    budget closed to round-off, the blast reaches both gauges and the slab is damaged. Gauge 1 (Eulerian)
    must lie below the 1D spherical reference at r = 125 mm (24.3 MPa, lagrangian1d with 3200 zones) --
    a 5 mm grid smears the thin shocked layer -- but within a factor 2 of it (measured 15.7 MPa)."""
    res = blastfsi.run("he-slab-3d", set={"output.fields": 0, "output.plots": False})
    s = res.summary
    assert s["coupled_faces"] == ["lower x"] and s["time"] == pytest.approx(res.scenario.time.end)
    assert s["pool_growths"] == 0  # the default pool holds the bridge's particles: one compilation (DESIGN.md)
    assert_budget_closed(s, 1e-13)
    g1, g2 = s["gauges"]
    assert g1["region"] == "euler" and g2["region"] == "particles"
    assert 0.5 * 24.3e6 < g1["peak_overpressure"] < 24.3e6
    assert g2["peak_overpressure"] > g1["peak_overpressure"]  # (9 mm in front of the slab: the reflection)
    assert s["structures"]["max_damage"] == 1.0 and s["structures"]["mass_left_the_box"] == 0.0


def test_cell_phases_split_where_physical_else_cell_density_at_one_pressure():
    """What the particles of each material take from a cell (``coupling.cell_phases``). Cells: a products trace in
    air (the he-slab-2d cell whose trace phase state overflowed, 1e-124 kg/m3 at a volume fraction of 1e-36), a
    resolved mixture, and two diffused contact cells as measured in steel-plate-blast 10 and 8 us after
    detonation (products fractions 0.372 and 0.22 at phase densities of 345 and 637 kg/m3, air at 0.58 and
    0.94 kg/m3). The resolved mixture keeps the five-equation model's isobaric split: each phase its own density
    and the cell's pressure. In the contact cells that split gives the products a negative internal energy
    (below their principal isentrope) and the air ~1e8 J/kg; there, and in the trace cell, every material takes
    the cell's density at one pressure p' > 0, or the cell's own specific energy where none is positive (the
    second contact cell). In every cell the particles fill the cell's volume and carry its internal energy."""
    import jax.numpy as jnp

    from blastfsi import euler
    from blastfsi.cfdmp import coupling as cp
    from blastfsi.eos import jwl
    from blastfsi.eos.jwl import ideal_gas_params
    from blastfsi.materials.gases import GASES

    eos = jnp.asarray([list(GASES["tnt"].eos_params()), list(ideal_gas_params(1.4))])
    cfg = euler.Config(shape=(4,), dx=1e-3, geometry=euler.CARTESIAN, bc=((euler.OUTFLOW, euler.OUTFLOW),),
                       scheme=euler.HLLC_MUSCL, n_materials=2, origin=(0.0,))
    rho_k = jnp.asarray([[4.787892e-97 / 1.941234e-36, 20.0, 345.0, 637.0], [1.225, 1.225, 0.581, 0.935]])
    alpha = jnp.asarray([1.941234e-36, 0.5, 0.372, 0.22])
    p = jnp.asarray([1.0136e5, 2.0e5, 2.23e7, 6.47e7])
    U = euler.conservative(rho_k, alpha, jnp.zeros((1, 4)), p, euler.Params(eos, jnp.asarray(0.5)), cfg)
    prim = cp.flat_primitives(U, eos, cfg)
    rows = euler.mixture.eos_rows(eos, 2)
    e_split = np.asarray([[float((p[c] - euler.mixture.cold_pressure(rho_k[k, c], rows[k]))
                                 / (rows[k].omega * rho_k[k, c])) for c in range(4)] for k in range(2)])
    assert np.all(e_split[:, 1] > 0.0)  # the resolved mixture: a physical split
    assert np.all(e_split[0, 2:] < 0.0) and np.all(e_split[1, 2:] > 5e7)  # the contact: not one
    assert float(prim["internal_energy"][3]) < 0.0  # the cell's own specific energy
    rho, e = cp.cell_phases(prim, jnp.arange(4), eos, 2)
    rho, e = np.asarray(jnp.stack(rho)), np.asarray(jnp.stack(e))
    assert np.all(np.isfinite(rho)) and np.all(np.isfinite(e))
    partial = np.asarray(rho_k) * np.stack([np.asarray(alpha), 1.0 - np.asarray(alpha)])
    np.testing.assert_allclose(np.sum(partial / rho, axis=0), 1.0, rtol=1e-13)  # the cell's volume, filled
    rho_e = np.asarray(prim["rho"]) * np.asarray(prim["internal_energy"])
    np.testing.assert_allclose(np.sum(partial * e, axis=0), rho_e, rtol=1e-12)  # its internal energy, carried
    pressure = np.stack([np.asarray(jwl.pressure(jnp.asarray(rho[k]), jnp.asarray(e[k]), rows[k])) for k in range(2)])
    # cell 1: the split, at the cell's own pressure
    np.testing.assert_allclose(rho[:, 1], np.asarray(rho_k)[:, 1], rtol=1e-12)
    np.testing.assert_allclose(e[:, 1], e_split[:, 1], rtol=1e-10)
    np.testing.assert_allclose(pressure[:, 1], float(prim["pressure"][1]), rtol=1e-10)
    # cells 0, 2, 3: the cell's density for every material
    cells = [0, 2, 3]
    np.testing.assert_allclose(rho[:, cells], np.broadcast_to(np.asarray(prim["rho"])[cells], (2, 3)), rtol=1e-14)
    # cells 0 and 2: one positive pressure (cell 0 up to the trace's round-off); the contact's air at the cell's
    # density is not the split's ~1e8 J/kg
    assert np.all(pressure[:, [0, 2]] > 0.0) and np.all(e[1, [0, 2]] > 0.0) and e[1, 2] < 1e7
    np.testing.assert_allclose(pressure[0, [0, 2]], pressure[1, [0, 2]], rtol=1e-10)
    # cell 3: no state at the cell's density gives both a positive pressure; both take the cell's e
    np.testing.assert_allclose(e[:, 3], float(prim["internal_energy"][3]), rtol=1e-14)


def test_settled_debt_keeps_both_phases_positive():
    """An outflow reservoir's balance settled into the cell beyond the face (``coupling._two_phase_split``): a
    products debt larger than the cell holds takes at most half of the cell's products and the rest from its
    air (total mass unchanged); a debt leaves its material's phase density unchanged; an addition to a
    material present takes the cell's own phase density, to one absent (below PRESENT) the bridge cell's.
    Before, the debt was taken at the bridge cell's phase density and as it stood: the products fraction of
    a mostly-air cell went negative (steel-plate-blast, pure FLIP gas)."""
    import jax.numpy as jnp

    from blastfsi.cfdmp import coupling as cp

    V = jnp.asarray([1.0, 1.0, 1.0, 1.0])
    rho_p, rho_a = 4.0, 1.2  # the cells' phase densities
    alpha = jnp.asarray([0.02, 0.02, 0.5, 1e-6])
    partial = [alpha * rho_p, (1.0 - alpha) * rho_a]
    donor = [jnp.full(4, 2.0), jnp.full(4, 1.0)]
    moved = jnp.asarray([[-0.2, 0.05],     # products debt 2.5 times what the cell holds
                         [-0.01, 0.0],     # a small products debt
                         [0.1, 0.2],       # additions to both, both present
                         [1e-3, 0.0]])     # products added to a cell with a trace of them
    given, vol = cp._two_phase_split(moved, partial, alpha, V, donor)
    given, vol = np.asarray(given), np.asarray(vol)
    np.testing.assert_allclose(given.sum(axis=1), np.asarray(moved).sum(axis=1), rtol=0, atol=1e-15)
    new_partial = np.stack([np.asarray(q) for q in partial], axis=1) + given
    assert new_partial[0, 0] == pytest.approx(0.5 * float(partial[0][0]), rel=1e-14)  # half of its products
    assert np.all(new_partial >= 0.0)
    np.testing.assert_allclose(given[1:], np.asarray(moved)[1:], rtol=0, atol=1e-15)  # nothing relabelled
    new_alpha = (np.asarray(alpha) + vol[0]) / (1.0 + vol[0] + vol[1])
    assert np.all((new_alpha > 0.0) & (new_alpha < 1.0))
    # a debt: the products phase density is unchanged by removing products with their share of the volume
    assert float(partial[0][1] + given[1, 0]) / float(alpha[1] + vol[0, 1]) == pytest.approx(rho_p, rel=1e-12)
    # additions at the cell's own phase densities (cell 2): both phases scale by the same factor
    assert vol[0, 2] == pytest.approx(0.1 / rho_p, rel=1e-14) and vol[1, 2] == pytest.approx(0.2 / rho_a, rel=1e-14)
    # products added where they are a trace (mass fraction 3e-6 < PRESENT): the bridge cell's phase density
    assert vol[0, 3] == pytest.approx(1e-3 / 2.0, rel=1e-14)


def test_shock_leaves_through_a_flow_out_box_face(tmp_path):
    """The Sod shock runs through the box [0.5, 1] m and out of the tube through the box face on the domain's
    flow-out end (at ~1.2 ms). Measured at 200 cells (L1(rho) ratio to the all-Eulerian run at 1.2 / 1.4 /
    1.6 / 1.8 / 2.0 ms): 1.21 / 1.09 / 1.14 / 1.14 / 0.99 with particles cut at the face; 1.21 / 1.12 / 1.19 /
    1.35 / 1.53 with particles leaving whole (the face held the outflow back). At 400 cells 1.23 / 1.14 /
    1.23 / 1.28 / 1.21 against 1.23 / 1.16 / 1.49 / 1.79 / 2.07. Checked once the shock has left (1.6 ms
    on): while it crosses this box, twice the shipped one, the MPM gas's own error (~6x HLLC's) takes the
    ratio to 1.29 at 0.8 ms."""
    d = example_data("cfdmp-shock-tube")
    d["mpm_region"] = {"lower": [0.5], "upper": [1.0], "bridge_cells": 5}
    over = FAST | {"time.end": 2.0e-3, "output.fields": 11}
    coupled = blastfsi.run(d, out=tmp_path / "c", set=over)
    d.update(method="euler", numerics={"scheme": "hllc-muscl", "cfl": 0.4})
    d.pop("mpm_region")
    euler = blastfsi.run(d, out=tmp_path / "e", set=over)
    assert coupled.summary["coupled_faces"] == ["lower x"]
    assert_l1_within_a_quarter_of_euler(coupled, euler, RiemannProblem((1.0, 0.0, 1e5), (0.125, 0.0, 1e4), x0=0.3),
                                        after=1.6e-3)
    assert_budget_closed(coupled.summary, 1e-13)


@pytest.mark.parametrize("speed", [100.0, 293.3])
def test_uniform_flow_leaves_through_a_flow_out_box_face(speed):
    """The box reaches the domain's flow-out end: gas leaves the run by the part of each particle beyond the
    face (coupling.cut_at_outflow_faces). With particles leaving whole once their centre crossed, the face
    held the flow back (at 100 m/s: +30 % pressure and 30 m/s at the face after 1 ms, nearly a wall's
    reflection). A uniform state is mapped exactly, so the bound is round-off, and so are the coupling's
    momentum and energy errors (the inflow face's pressure transfer against the outflow mirror's traction)."""
    state = {"material": "air", "density": 0.2656, "pressure": 30313.0, "velocity": speed}
    d = tube(left=state, right=state)
    d["mpm_region"] = {"lower": [0.5], "upper": [1.0], "bridge_cells": 5}
    res = blastfsi.run(d, set=FAST | {"time.end": 4.0e-4})
    f = res.fields()
    assert np.max(np.abs(f["pressure"] / 30313.0 - 1.0)) < 1e-9
    assert np.max(np.abs(f["velocity"][:, 0] - speed)) < 1e-9 * speed
    assert_budget_closed(res.summary, 1e-14)
    b = res.summary["budget"]
    # steady: what leaves through the box face is what enters at the tube's other end (rho u t per m^2)
    assert abs(b["mass_boundary_out"]) < 1e-9 * 0.2656 * speed * 4.0e-4
    assert max(abs(b["energy_residual_relative"]), abs(b["momentum_x_residual_relative"])) < 1e-12


@pytest.mark.slow  # (the default suite's time: ~1 min / ~25 s)
def test_gas_at_rest_stays_at_rest_on_outflow_box_faces():
    """A 2D box whose faces lie on outflow faces of the domain (the he-slab-2d layout): the mirror gas of
    ``outflow_ghost`` (mass, momentum and traction on those faces' nodes) balances the particles' stress.

    The traction without the mirror mass let this gas at rest run away (non-physical state at 197 us, step
    843); with the volume-weighted traction the largest disturbance after 200 us is 7e-14 p (2026-12-04;
    2.3e-5 p at the domain corner before). The mirror's traction is booked as the pressure flux through
    the domain boundary: the coupled face's pressure impulse and the opposite faces' tractions cancel, so
    the momentum and energy errors are round-off (with the traction unbooked, the x momentum error grows as
    p A t)."""
    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    d = {"method": "cfdmp", "name": "rest-2d", "domain": {"lower": [0.0, 0.0], "upper": [0.06, 0.03]},
         "boundaries": {"x": ["outflow", "outflow"], "y": ["outflow", "outflow"]}, "grid": {"cells": 30},
         "initial": {"kind": "riemann", "diaphragm": 0.02, "left": state, "right": state},
         "mpm_region": {"lower": [0.03, 0.0], "upper": [0.06, 0.03], "activation_overpressure": 0.0},
         "time": {"end": 2.0e-4}, "output": {"history_samples": 11, "fields": 0, "plots": False}}
    res = blastfsi.run(d)
    f = res.fields()
    assert res.summary["steps"] > 40
    assert np.nanmax(np.abs(f["pressure"] - 1.0e5)) < 1e-9 * 1.0e5  # a uniform state, mapped exactly
    assert res.summary["bridge_cells"] == 5 and isinstance(res.summary["bridge_cells"], int)  # (was an array)
    json.dumps(res.summary)  # the summary.json of a results directory
    assert_budget_closed(res.summary, 1e-14)
    b = res.summary["budget"]
    assert max(abs(b["energy_residual_relative"]), abs(b["momentum_x_residual_relative"]),
               abs(b["momentum_y_residual_relative"])) < 1e-12


def test_outflow_mirror_is_one_way():
    """The mirror gas of a flow-out box face models outflow and rest only (no gas enters there): on the
    face's nodes it is whole for outflow, scaled by 1 + u_n / (INFLOW_MACH c) for slow inflow and gone for
    inflow faster than INFLOW_MACH c (outflow_ghost's docstring; in he-slab-2d the mirror's traction on
    gas drawn back into the box drove it to c = 142 km/s)."""
    import jax.numpy as jnp

    from blastfsi import method as methods
    from blastfsi.cfdmp import coupling as cp
    from blastfsi.scenario import parse

    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    d = {"method": "cfdmp", "name": "mirror-2d", "domain": {"lower": [0.0, 0.0], "upper": [0.06, 0.03]},
         "boundaries": {"x": ["outflow", "outflow"], "y": ["wall", "wall"]}, "grid": {"cells": 30},
         "initial": {"kind": "riemann", "diaphragm": 0.02, "left": state, "right": state},
         "mpm_region": {"lower": [0.03, 0.0], "upper": [0.06, 0.03], "activation_overpressure": 0.0},
         "time": {"end": 1.0e-5}}
    sc = parse(d)
    cfdmp = methods.get("cfdmp")
    setup = cfdmp.build(sc)
    cs, prm = cfdmp.static(setup, sc).coupling, cfdmp.params(setup, jnp.float64)
    st = cfdmp.initial_state(setup, sc, 2, jnp.float64)
    # (the coupling's functions compiled, as in a run: op by op they took twice the test's time)
    ms, _ = jax.jit(cp.activate, static_argnums=5)(st.U, st.mpm, cp.flat_primitives(st.U, prm.euler.eos, cs.euler),
                                                   prm.euler.eos, prm.mpm, cs, prm.layout)
    area = np.asarray(prm.layout.outflow_area)
    face = area[:, 0] != 0.0  # the upper x face (the box's only face on a flow-out boundary)
    assert face.sum() == cs.mpm.grid.nodes[1] and np.all(area[face, 0] < 0.0)
    c = float(np.max(np.asarray(ms.particles.wave_speed)))
    assert c == pytest.approx(np.sqrt(1.4 * 1.0e5 / 1.2), rel=1e-12)

    def mirror(mach):
        P = ms.particles
        P = P._replace(v=P.v.at[:, 0].set(jnp.where(P.active, mach * c, 0.0)))
        src = jax.jit(cp.outflow_ghost, static_argnums=2)(P, prm.layout, cs, 0.0)
        return np.asarray(src.mass)[face], np.asarray(src.force)[face, 0]

    m_out, f_out = mirror(0.5)
    assert np.all(m_out > 0.0)
    np.testing.assert_allclose(f_out, 1.0e5 * area[face, 0], rtol=1e-12)  # the traction -p A n of the gas
    half = 0.5 * cp.INFLOW_MACH
    m_half, f_half = mirror(-half)
    np.testing.assert_allclose(m_half, 0.5 * m_out, rtol=1e-9)
    np.testing.assert_allclose(f_half, 0.5 * f_out, rtol=1e-9)
    m_in, f_in = mirror(-2.0 * cp.INFLOW_MACH)
    assert np.all(m_in == 0.0) and np.all(f_in == 0.0)

    # the traction's pressure is volume-weighted: every other particle compressed tenfold (same mass) and
    # at 100x the pressure; mass weights would give these half the say, volume weights 1/11
    from blastfsi import mpm

    P = ms.particles
    hot = P.active & (jnp.arange(P.mass.shape[0]) % 2 == 0)
    p_hot, p_cold = 1.0e7, 1.0e5
    pressure = jnp.where(hot, p_hot, p_cold)
    P = P._replace(point=P.point._replace(
        density=jnp.where(hot, 10.0, 1.0) * P.point.density,
        stress=jnp.where(P.active[:, None], -pressure[:, None] * jnp.array([1.0, 1, 1, 0, 0, 0]), 0.0)))
    idx, w = (np.asarray(a) for a in mpm.materialised_stencil(P, cs.mpm.grid, cs.mpm.shape)[:2])
    on = np.asarray(P.active)
    vol = np.where(on, np.asarray(P.mass / P.point.density), 0.0)
    sums = np.zeros((cs.mpm.grid.num_nodes, 3))
    for col, q in enumerate((vol, vol * np.asarray(pressure), np.where(on, np.asarray(P.mass), 0.0))):
        np.add.at(sums[:, col], idx.ravel(), (w * q[None, :]).ravel())
    expected = sums[face, 1] / sums[face, 0]
    # inner face nodes see equal numbers of both: (p_hot / 10 + p_cold) / (1 / 10 + 1) = 1e6 (mass weights 5.05e6)
    np.testing.assert_allclose(expected[1:-1], (0.1 * p_hot + p_cold) / 1.1, rtol=1e-12)
    f_hot = np.asarray(cp.outflow_ghost(P, prm.layout, cs, 0.0).force)[face, 0]
    # the fill phi = sum_p N_Ip V_p / (A h / 2): 0.55 on the inner face nodes (whole traction), less at the corners
    phi = sums[face, 0] / (0.5 * cs.mpm.grid.cell_size * np.abs(area[face, 0]))
    np.testing.assert_allclose(phi[1:-1], 0.55, rtol=1e-12)
    np.testing.assert_allclose(f_hot, np.minimum(1.0, phi / cp.FULL_FILL) * expected * area[face, 0], rtol=1e-12)

    # gas that fills a fraction phi of the face nodes' half support (every particle compressed by 1 / phi at
    # one pressure): the traction is whole down to phi = FULL_FILL, then phi / FULL_FILL of it (docstring)
    for phi in (0.6, 0.25 * cp.FULL_FILL):
        P = ms.particles
        P = P._replace(point=P.point._replace(density=P.point.density / phi))
        f = np.asarray(cp.outflow_ghost(P, prm.layout, cs, 0.0).force)[face, 0]
        np.testing.assert_allclose(f, min(1.0, phi / cp.FULL_FILL) * 1.0e5 * area[face, 0], rtol=1e-12)


@pytest.mark.parametrize("shape", [pytest.param("linear", marks=pytest.mark.slow), "gimp"])  # (gimp: the default)
def test_structure_fragments_leave_through_a_flow_out_face(shape):
    """A steel block flying at 600 m/s out through the flow-out face the MPM box shares with the domain:
    its particles are deleted as they cross (before, the first one off the grid stopped the run as a
    non-physical state), its mass is reported, and its momentum and energy are booked with what left
    through the domain boundary. GIMP: before the domains were truncated to the grid (mpm.shape.inside_grid)
    a particle whose support reached past the grid's last node lost its partition of unity and its own stress
    pushed it (+3.7 % of the system's energy, the last particle sprang back into the box); now the energy
    error is 2.0e-6 (linear 9.1e-5, 2026-12-04)."""
    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    d = tube(left=state, right=state)
    d["mpm_region"] = {"lower": [0.5], "upper": [1.0], "bridge_cells": 5}
    d["structures"] = [{"lower": [0.9], "upper": [0.96], "material": "elastic-steel", "velocity": 600.0}]
    res = blastfsi.run(d, set={**FAST, "numerics.shape": shape, "time.end": 2.4e-4})
    s = res.summary
    block = 7850.0 * 0.06  # kg/m^2: the library's steel density x length (1D: per unit area)
    assert s["structures"]["mass_left_the_box"] == pytest.approx(block, rel=1e-12)
    assert res.history["mass_structures"][-1] == 0.0
    assert_budget_closed(s, 1e-13)
    # the block holds ~all of the system's energy, 1/24 of it per particle: one particle's energy unbooked
    # would leave a residual of 4e-2 (measured 9.1e-5 / 2.0e-6: the work on the air through MUSL)
    assert abs(s["budget"]["energy_residual_relative"]) < 1e-3


@pytest.mark.parametrize("lower, upper", [([0.0, 0.015], [0.03, 0.045]),  # (the box on the axis; off it: slow)
                                          pytest.param([0.015, 0.015], [0.045, 0.045], marks=pytest.mark.slow)])
def test_axisymmetric_gas_at_rest_stays_at_rest(lower, upper):
    """r-z coupling (a cylinder on the axis, a ring off it): ring volumes 2 pi r dx^2, face measures, the ring
    cells' hoop force and their gas-lattice quadrature balance the particles' stress to round-off (with one
    point per ring cell the box corners were pushed: 0.7 m/s after 200 us)."""
    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    d = {"method": "cfdmp", "name": "rest-axi", "domain": {"geometry": "axisymmetric", "lower": [0.0, 0.0],
                                                            "upper": [0.06, 0.06]},
         "boundaries": {"x": ["axis", "outflow"], "y": ["outflow", "outflow"]}, "grid": {"cells": 60},
         "initial": {"kind": "riemann", "diaphragm": 0.01, "left": state, "right": state},
         "mpm_region": {"lower": lower, "upper": upper, "activation_overpressure": 0.0},
         "time": {"end": 5.0e-5}, "output": {"history_samples": 6, "fields": 0, "plots": False}}
    res = blastfsi.run(d)
    f = res.fields()
    assert res.summary["steps"] > 50
    assert np.nanmax(np.abs(f["pressure"] - 1.0e5)) < 1e-12 * 1.0e5 * 10
    assert np.nanmax(np.abs(f["velocity"])) < 1e-9
    assert_budget_closed(res.summary, 1e-14)
    assert abs(res.summary["budget"]["energy_residual_relative"]) < 1e-12


@pytest.mark.slow  # ~3 min on 2 cores
def test_steel_plate_blast_starts_as_the_paper_case():
    """Seed 000 Sec. 5.4 case 1 (``steel-plate-blast``) to 0.1 ms: the plate's centre is driven away from the
    charge at ~100 m/s (its peak deflection at ~0.4 ms is in docs/validation.md), the clamped rim does not move,
    the plate stays elastic-plastic without damage, and the mass budget closes to round-off."""
    res = blastfsi.run("steel-plate-blast", set={"time.end": 1e-4, "output.fields": 0, "output.plots": False,
                                                  "output.tracers": [[0.0, 0.105], [0.27, 0.105]]})
    s, h = res.summary, res.history
    assert s["coupled_faces"] == ["lower y"]
    assert_budget_closed(s, 1e-13)
    centre, rim = s["tracer_displacement"]
    assert rim == [0.0, 0.0]
    assert 0.004 < centre[1] < 0.012  # measured 7.9 mm at 0.1 ms (2026-12-03)
    assert 0.0 < s["structures"]["max_plastic_strain"] < 0.2 and s["structures"]["max_damage"] == 0.0
    w = h["tracer0_displacement_y"]
    assert w[-1] > np.interp(5e-5, h["time"], w) > 0.0  # still moving away (2.4 mm at 0.05 ms)



def test_gas_stalled_at_a_coupled_face_joins_the_inflow_particle():
    """Gas that still touches a coupled face while an inflow particle of its material grows at that face cell
    (coupling._stalled) goes whole to the face's reservoir, and feed adds it to the inflow particle, compressed
    to the density that fills the face cell's layer when it overfills it. Particles clear of the face, of the
    other material or at a face cell with no inflow particle are left alone. Before, feed placed inflow particle
    over inflow particle where the flow stalled at the face: up to 420 in one face cell of steel-plate-blast,
    whose volumes added up to 550 times the cell's, and the pool grew from 17 000 to 32 000 particles."""
    import jax
    import jax.numpy as jnp

    from blastfsi import method as methods
    from blastfsi.cfdmp import coupling as cp
    from blastfsi.cfdmp.method import _activate
    from blastfsi.scenario import expand

    jax.config.update("jax_enable_x64", True)
    sc, _, scs = expand(tube(left={"material": "air", "density": 1.2, "pressure": 1.0e5},
                             right={"material": "air", "density": 1.2, "pressure": 1.0e5}))
    method = methods.get("cfdmp")
    setup = method.build(scs[0])
    static, params = method.static(setup, scs[0]), method.params(setup, jnp.float64)
    cs, lay = static.coupling, params.layout
    # (the coupling's functions compiled, as in a run: op by op they took four times the test's time)
    s = jax.jit(_activate, static_argnums=2)(method.initial_state(setup, scs[0], 3, jnp.float64), params, cs)
    P = s.mpm.particles
    h, lo = cs.mpm.grid.cell_size, float(lay.box_lower[0])
    gas = np.where(np.asarray(P.active))[0]
    inflow, stalled, clear, unfed = (int(k) for k in gas[:4])
    half = np.asarray(P.half_size)[:, 0]
    x = np.asarray(P.x)[:, 0].copy()
    x[inflow] = x[stalled] = lo + half[stalled]  # both touch the lower face (face cell 0)
    x[clear] = lo + half[clear] + 1e-3 * h  # clear of it
    x[unfed] = float(lay.box_upper[0]) - half[unfed]  # touches the upper face, where no inflow particle grows
    P = P._replace(x=P.x.at[:, 0].set(jnp.asarray(x)), v=P.v.at[stalled, 0].set(-30.0),
                   mass=P.mass.at[stalled].multiply(3.0))  # (with the inflow particle: more than the layer holds)
    upper = sum(cs.face_sizes[:1])  # the upper face's cell (the lower face comes first: one cell per face in 1D)
    assert cs.faces[0][1] == 0 and upper == 1
    buffer = s.reservoirs.buffer.at[0, 0].set(inflow)
    res = s.reservoirs._replace(buffer=buffer)
    ms, res, budget = jax.jit(cp.remove_leaving, static_argnums=3)(s.mpm._replace(particles=P), res, s.budget, cs, lay)
    active = np.asarray(ms.particles.active)
    assert not active[stalled] and active[inflow] and active[clear] and active[unfed]
    m_stalled = float(P.mass[stalled])
    assert float(res.mass[0, 0]) == pytest.approx(m_stalled, rel=1e-14)  # whole, into face cell 0's reservoir
    assert float(res.momentum[0, 0, 0]) == pytest.approx(-30.0 * m_stalled, rel=1e-14)
    assert float(jnp.sum(res.mass)) == pytest.approx(m_stalled, rel=1e-14)
    prim = cp.flat_primitives(s.U, params.euler.eos, cs.euler)
    fed, res, _ = jax.jit(cp.feed, static_argnums=6)(ms, res, budget, prim, params.euler.eos, params.mpm, cs, lay)
    Q = fed.particles
    m_in = float(P.mass[inflow]) + m_stalled
    assert float(Q.mass[inflow]) == pytest.approx(m_in, rel=1e-14) and float(res.mass[0, 0]) == 0.0
    area = float(lay.face_measure[0]) / h
    rho_bridge = float(prim["rho"][lay.face_in[0]])
    assert m_in / (area * h) > 1.5 * rho_bridge  # overfilled: compressed
    assert float(Q.point.density[inflow]) == pytest.approx(m_in / (area * h), rel=1e-12)


def test_mpm_everywhere_gas_at_rest_stays_at_rest():
    """The MPM box is the whole domain (he-slab-2d-mpm's layout, here in 1D: no coupled face, every face a
    flow-out face): the gas becomes particles at the start and, at rest, stays at rest to round-off; the
    budget closes. (The stalled-gas rule of remove_leaving once failed to compile here: with no coupled face
    it indexed an empty reservoir table; he-slab-2d-mpm did not compile.)"""
    state = {"material": "air", "density": 1.2, "pressure": 1.0e5}
    d = {"method": "cfdmp", "name": "rest-mpm-everywhere", "domain": {"lower": [0.0], "upper": [0.03]},
         "boundaries": {"x": ["outflow", "outflow"]}, "grid": {"cells": 30},
         "initial": {"kind": "riemann", "diaphragm": 0.01, "left": state, "right": state},
         "mpm_region": {"lower": [0.0], "upper": [0.03], "activation_overpressure": 0.0},
         "time": {"end": 5.0e-5}, "output": {"history_samples": 6, "fields": 0, "plots": False}}
    res = blastfsi.run(d)
    assert res.summary["steps"] > 10
    assert np.nanmax(np.abs(res.fields()["pressure"] - 1.0e5)) < 1e-9 * 1.0e5
    assert_budget_closed(res.summary, 1e-14)
