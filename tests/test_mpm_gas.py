"""MPM gas particles (fluid models): the pressure force of a gas at rest, sub-cell sound, void gas, r-z hoop rate.

* A uniform gas at rest (absolute stresses, no ``numerics.reference_pressure``) stays at rest to round-off
  with GIMP on 2D/3D Cartesian grids, in an ``mpm`` and a ``cfdmp`` box: the gas particles' force and volume
  change use the cell-centre gradient, an overfilled cell's weights normalised to its volume
  (mpm.musl.cell_centre_gradient). Before, the uniform pressure had a negative stiffness through the
  particle quadrature of GIMP: growth ~1.05 per step in an ``mpm`` box, ~1.0095 per step in a ``cfdmp`` box.
* Sub-cell sound in a 2D gas: between c and c sqrt(1 - p / K) (at c with the ambient reference pressure).
* Void gas (density below mpm.musl.VOID_DENSITY) neither sets the step nor exerts stress or does work.
* r-z: the hoop rate v_r / r of a uniform radial expansion v_r = a r.
"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import blastfsi
from blastfsi.mpm.method import zero_crossing_period
from blastfsi import mpm
from blastfsi.constitutive import Model, fluid
from blastfsi.constitutive import tensor as T
from blastfsi.eos import jwl
from blastfsi.materials import lookup

AIR = {"material": "air", "density": 1.2, "pressure": 1.0e5}


def _box(shape, axisymmetric, end, velocity=0.0):
    return {"method": "mpm", "name": "rest", "time": {"end": end},
            "grid": {"lower": [0.0, 0.0], "upper": [0.012, 0.012], "cells": 12, "axisymmetric": axisymmetric,
                     "boundaries": {"x": ["slip", "slip"], "y": ["slip", "slip"]}},
            "bodies": [{"lower": [0.0, 0.0], "upper": [0.012, 0.012], **AIR, "velocity": velocity}],
            "numerics": {"shape": shape, "cfl": 0.5},
            "output": {"history_samples": 3, "fields": 0, "plots": False}}


def test_gimp_gas_at_rest_stays_at_rest_with_absolute_stresses():
    """Air at 1 bar filling a 12 x 12-cell slip box, GIMP, 2 x 2 particles per cell, cfl 0.5, ~1000 steps.
    With the particles' own GIMP gradient this grew 1.053 per step from round-off (1e-7 m/s after 436 steps,
    non-physical by ~800). Round-off bound as in test_mpm_method.py's linear twin: the nodal force sums terms
    p V_p |grad N| whose rounding accelerates the nodes by ~eps p / (rho h) ~ 1e-8 m/s^2, ~1e-11 m/s over the
    run (measured 7.6e-13 m/s after 1451 steps). r-z GIMP keeps its own gradient (mpm.musl.cell_centre_gradient)."""
    res = blastfsi.run(_box("gimp", False, 1.4e-3))
    assert res.summary["steps"] >= 1000
    f = res.fields()
    assert np.max(np.abs(f["velocity"])) < 1e-9
    assert np.max(np.abs(f["pressure"] / 1.0e5 - 1.0)) < 1e-12


def test_gimp_air_in_motion_stays_bounded_and_conserves_energy_with_absolute_stresses():
    """Air at 1 bar sloshing at 1 m/s in the 12 x 12-cell slip box, GIMP, ~870 steps, absolute stresses. With
    the particles' own GIMP gradient this stopped non-physical at step 737 (test_mpm_method.py needed
    numerics.reference_pressure to run it). The sloshing stays bounded (measured max |v| 0.65 m/s at the end,
    as with the reference pressure) and kinetic + internal energy is conserved to the scheme's dissipation
    (measured -5.5e-7 of the total)."""
    res = blastfsi.run(_box("gimp", False, 1.2e-3, velocity=1.0))
    assert res.summary["steps"] >= 800
    assert np.max(np.abs(res.fields()["velocity"])) < 1.0
    assert abs(res.summary["energy_balance_relative"]) < 1e-5


def _cfdmp_box(geometry):
    """Air at rest in a cfdmp domain, the MPM box inside it with its bridges, default GIMP and gas PIC share."""
    if geometry == "3d":
        n, lower, upper, box = 12, [0.0] * 3, [0.012] * 3, ([0.002] * 3, [0.010] * 3)
    else:
        n, lower, upper = 16, [0.0, 0.0], [0.016, 0.016]
        box = ([0.004, 0.004], [0.012, 0.012])
    domain = {"lower": lower, "upper": upper}
    bounds = {a: ["outflow", "outflow"] for a in "xyz"[:len(lower)]}
    return {"method": "cfdmp", "name": "rest", "domain": domain, "boundaries": bounds, "grid": {"cells": n},
            "initial": {"kind": "riemann", "diaphragm": 0.002, "left": AIR, "right": AIR},
            "mpm_region": {"lower": box[0], "upper": box[1], "activation_overpressure": 0.0, "bridge_cells": 2},
            "time": {"end": 1.8e-3 if geometry == "3d" else 6.0e-3},
            "output": {"history_samples": 3, "fields": 0, "plots": False}}


@pytest.mark.parametrize("geometry", [pytest.param(g, marks=pytest.mark.slow) for g in ("2d", "3d")])
def test_gas_at_rest_stays_at_rest_in_a_cfdmp_box(geometry):  # (slow: tests/test_cfdmp.py's gas at rest stays)
    """Air at 1 bar in a cfdmp box (absolute stresses, GIMP, the default gas PIC share and cfl): 10^4 steps in
    2D, ~3000 in 3D. With the particles' own GIMP gradient this 2D layout reached 9.7 m/s and a 3 % pressure
    error after 3092 steps. With the cell-centre gradient but the particles that touch a coupled face cut for
    the round-off of their motion (coupling.CUT_TOLERANCE = 0) it still ran away at 1.003-1.005 per step
    (0.01 m/s after 8540 steps). Round-off bound as above (measured 3.9e-11 m/s after 10 247 steps, 2D)."""
    res = blastfsi.run(_cfdmp_box(geometry))
    assert res.summary["steps"] >= (2500 if geometry == "3d" else 10_000)
    f = res.fields()
    assert np.nanmax(np.abs(f["velocity"])) < 1e-9
    assert np.nanmax(np.abs(f["pressure"] / 1.0e5 - 1.0)) < 1e-12


@pytest.mark.parametrize("shape, reference", [("linear", 0.0), ("gimp", 0.0), ("gimp", 1.0e5)])
def test_sub_cell_sound_speed_of_a_2d_air_column(shape, reference):
    """The fundamental of a 20 mm air column at 1 bar in 2D (20 x 2 cells, slip walls, 0.1 m/s quarter-sine
    velocity, no bulk viscosity) has the period 2 L / c. Sub-cell (small-amplitude) motion: the gas particles'
    cell-centre force (mpm.musl.cell_centre_gradient) has the stiffness K where the particles expand in place
    (the overfilled cell's weight normalised to its volume) and K - p where they compress in place
    (underfilled, weight V_p): the period lies between 1 and 1 / sqrt(1 - p / K) = 1.87 (air); measured
    1.219, linear and GIMP (1.86 linear before, with V_p everywhere; GIMP's own gradient gave 0.998 but an
    unstable gas). With the ambient reference pressure p_ref = 1 bar, p - p_ref ~ 0 and the column rings at c.
    Bounds: the history sampling (0.5 %), the lumped-mass grid's dispersion at 20 cells per wave (0.1 %) and
    the third mode shifting the zero crossings (test_mpm_method.py): 2 % with p_ref; 1.30 without (> 1.219 by
    the same margins, far below the 1.86 of the plain cell-centre force)."""
    L, c = 0.02, np.sqrt(1.4e5 / 1.2)
    period = 2.0 * L / c
    d = {"method": "mpm", "name": "column", "time": {"end": 4.0 * period},
         "grid": {"lower": [0.0, 0.0], "upper": [L, 0.002], "cells": 20,
                  "boundaries": {"x": ["slip", "slip"], "y": ["slip", "slip"]}},
         "bodies": [{"lower": [0.0, 0.0], "upper": [L, 0.002], **AIR, "velocity": [0.1, 0.0],
                     "velocity_profile": "sine"}],
         "numerics": {"shape": shape, "cfl": 0.3, "q_linear": 0.0, "q_quadratic": 0.0,
                      "reference_pressure": reference},
         "output": {"history_samples": 801, "fields": 0, "plots": False}}
    h = blastfsi.run(d).histories[0]
    measured = zero_crossing_period(np.asarray(h["time"]), np.asarray(h["momentum_x"]))  # (4 periods: 8 crossings)
    assert measured is not None
    ratio = measured / period
    if reference:
        assert abs(ratio - 1.0) < 0.02
    else:
        assert 1.0 < ratio < 1.30


def test_void_gas_sets_no_step_exerts_no_stress_and_does_no_work():
    """Air at 1 bar against a slip wall (8 particles, 2 per 1 mm cell) and, five cells beyond its free face, one
    air particle at 1e-6 kg/m^3 moving at 300 m/s whose internal energy (1e9 J/kg) gives it a sound speed of
    ~24 km/s, as the edge of the expanding products cloud had in steel-plate-blast. It is void (below
    VOID_DENSITY): the step is the resolved air's, cfl h / c, not ~1/70 of it, and over 20 steps it keeps its
    internal energy and moves ballistically (its own pressure, 0.4 kPa, would have pushed it: no other mass
    shares its nodes). Without the void rule it set the step and accelerated itself."""
    air = fluid.params_from(lookup("air"))
    h = 1e-3
    grid = mpm.Grid(origin=(0.0,), cell_size=h, cells=(20,), boundaries=(("slip", "free"),))
    x = np.append(0.25 * h + 0.5 * h * np.arange(8), 9.75 * h)
    rho = np.append(np.full(8, 1.2), 1e-6)
    e = np.append(np.full(8, float(jwl.energy(1.2, 1.0e5, air.eos))), 1e9)
    p = np.asarray(jwl.pressure(jnp.asarray(rho), jnp.asarray(e), air.eos))
    v = np.zeros((9, 3))
    v[8, 0] = 300.0
    batch = mpm.new_particles(x[:, None], 0.5 * h, rho, v=v, half_size=np.full((9, 3), 0.25 * h),
                              stress=np.asarray(T.compose(jnp.zeros((9, 6)), jnp.asarray(p))), energy=e,
                              history_size=3)
    cfg = mpm.make_config(grid, (fluid.MODEL,), shape="gimp")
    prm = mpm.make_params((air,), cfl=0.2)
    state = jax.jit(mpm.initialize, static_argnames="config")(mpm.make_pool(batch, 16), prm, cfg)
    c_air = float(jnp.sqrt(jwl.sound_speed_squared(1.2, 1.0e5, air.eos)))
    dt = float(jax.jit(mpm.stable_dt, static_argnames="config")(state, prm, cfg))
    assert dt == pytest.approx(0.2 * h / c_air, rel=1e-12)
    before = mpm.totals(state.particles)
    run = jax.jit(lambda s: jax.lax.fori_loop(0, 20, lambda i, a: mpm.step(a, dt, prm, cfg), s))
    P = run(state).particles
    assert float(P.point.energy[8]) == 1e9
    assert np.all(np.asarray(P.point.stress[8]) == 0.0) and float(P.wave_speed[8]) == 0.0
    assert float(P.v[8, 0]) == pytest.approx(300.0, rel=1e-12)
    assert float(P.x[8, 0]) == pytest.approx(9.75 * h + 20 * dt * 300.0, rel=1e-12)
    assert float(mpm.totals(P).mass) == pytest.approx(float(before.mass), rel=1e-15)


def test_void_gas_takes_no_blend_heat():
    """With a PIC share (the FLIP/PIC blend of a coupled run's gas), a void particle among moving air keeps its
    internal energy exactly: it takes no PIC share, so the blend heats it by nothing. Before, it took the
    blend heat like any gas particle, and in the near vacuum between charge and plate late in steel-plate-blast
    void particles reached 1e10-5e13 J/kg. Air at 1 bar on a ramp of velocities (-50 to +50 m/s, 2 particles
    per 1 mm cell), the void particle (1e-6 kg/m^3, 1e9 J/kg, 300 m/s) in the middle of it."""
    air = fluid.params_from(lookup("air"))
    h = 1e-3
    grid = mpm.Grid(origin=(0.0,), cell_size=h, cells=(20,), boundaries=(("free", "free"),))
    x = np.append(5 * h + 0.25 * h + 0.5 * h * np.arange(16), 9.1 * h)
    rho = np.append(np.full(16, 1.2), 1e-6)
    e = np.append(np.full(16, float(jwl.energy(1.2, 1.0e5, air.eos))), 1e9)
    p = np.asarray(jwl.pressure(jnp.asarray(rho), jnp.asarray(e), air.eos))
    v = np.zeros((17, 3))
    v[:16, 0] = np.linspace(-50.0, 50.0, 16)
    v[16, 0] = 300.0
    batch = mpm.new_particles(x[:, None], 0.5 * h, rho, v=v, half_size=np.full((17, 3), 0.25 * h),
                              stress=np.asarray(T.compose(jnp.zeros((17, 6)), jnp.asarray(p))), energy=e,
                              history_size=3)
    cfg = mpm.make_config(grid, (fluid.MODEL,), shape="gimp", blend=True)
    prm = mpm.make_params((air,), cfl=0.2, pic_fraction=0.05)
    state = jax.jit(mpm.initialize, static_argnames="config")(mpm.make_pool(batch, 24), prm, cfg)
    dt = float(jax.jit(mpm.stable_dt, static_argnames="config")(state, prm, cfg))
    P = jax.jit(lambda s: jax.lax.fori_loop(0, 20, lambda i, a: mpm.step(a, dt, prm, cfg), s))(state).particles
    assert float(P.point.energy[16]) == 1e9
    assert np.all(np.isfinite(np.asarray(P.point.energy[:16])))


def _hot_and_cold_air(grid, light):
    """Air at 1 bar on a 2 x 2-per-cell lattice filling ``grid``, every other particle ``light`` times lighter and
    as much hotter (the same pressure), velocities a fixed pseudo-random +-1 m/s."""
    air = fluid.params_from(lookup("air"))
    x, vol, half = mpm.lattice(grid, grid.origin, grid.upper, 2)
    n = len(x)
    rho = np.where(np.arange(n) % 2 == 0, 1.2, 1.2 / light)
    e = np.asarray(jwl.energy(jnp.asarray(rho), 1.0e5, air.eos))
    v = np.zeros((n, 3))
    v[:, :2] = np.random.default_rng(7).uniform(-1.0, 1.0, (n, 2))
    stress = np.asarray(T.compose(jnp.zeros((n, 6)), jnp.full(n, 1.0e5)))
    batch = mpm.new_particles(x, vol, rho, v=v, half_size=half, stress=stress, energy=e, history_size=3)
    return air, batch


def test_a_light_hot_gas_particle_steps_at_the_signal_of_its_nodes():
    """Air at 1 bar in a 2D slip box of 8 x 8 cells, GIMP, pure FLIP, cfl 0.4, velocities +-1 m/s; every other
    particle 100 times lighter and hotter (the same pressure, its own sound speed 10x). The step is set by
    what the nodes carry (mpm.musl.stable_dt: the mass-weighted mean of c^2), not by the light particles'
    own c: measured 5.41x the per-particle step. Over 400 steps at it the gas stays bounded and keeps its
    kinetic + internal energy (measured: max |v| 2.31 m/s, energy +2.4e-8 of the internal; stable up to
    2x that step, as a uniform cold gas is up to 1.5x its own). At 3x it goes unstable within 400 steps
    (measured max |v| 564 m/s): the estimate sits within a factor 3 of the real limit, not far above it.
    A uniform gas keeps its own signal, to round-off."""
    h = 1e-3
    grid = mpm.Grid(origin=(0.0, 0.0), cell_size=h, cells=(8, 8), boundaries=(("slip", "slip"), ("slip", "slip")))
    init = jax.jit(mpm.initialize, static_argnames="config")
    stable = jax.jit(mpm.stable_dt, static_argnames="config")

    def setup(light):
        air, batch = _hot_and_cold_air(grid, light)
        cfg = mpm.make_config(grid, (fluid.MODEL,), shape="gimp")
        prm = mpm.make_params((air,), cfl=0.4)
        state = init(mpm.make_pool(batch, len(batch.mass)), prm, cfg)
        P = state.particles
        own = 0.4 * h / float(jnp.max(P.wave_speed + jnp.linalg.norm(P.v, axis=1)))  # each particle's own signal
        return state, prm, cfg, float(stable(state, prm, cfg)), own

    _, _, _, dt, own = setup(1.0)
    assert dt == pytest.approx(own, rel=1e-12)
    state, prm, cfg, dt, own = setup(100.0)
    assert dt > 5.0 * own

    def energy(P):
        return float(jnp.sum(P.mass * (P.point.energy + 0.5 * jnp.sum(P.v ** 2, axis=1))))

    internal = float(jnp.sum(state.particles.mass * state.particles.point.energy))
    run = jax.jit(lambda s, dt: jax.lax.fori_loop(0, 400, lambda i, a: mpm.step(a, dt, prm, cfg), s))
    P = run(state, dt).particles
    assert float(jnp.max(jnp.linalg.norm(P.v, axis=1))) < 3.0  # started at up to 1.41 m/s
    assert abs(energy(P) - energy(state.particles)) < 1e-6 * internal
    P = run(state, 3.0 * dt).particles
    assert not float(jnp.max(jnp.linalg.norm(P.v, axis=1))) < 100.0  # (NaN counts as unstable)


def test_the_blend_takes_at_most_a_gas_particles_internal_energy():
    """A rarefied air particle (2e-4 kg/m^3, 10 Pa, e0 = 1.25e5 J/kg; PIC share 0.05) at rest on the nodes of a
    dense air slab (1.2 kg/m^3, 1 bar, no PIC share) moving at 1000 m/s, 1D, GIMP, cfl 0.2. Its nodes move
    with the slab, so its blend heat is negative (the nodal velocity it is blended towards is not its own
    blended particles'): its internal energy fell by ~1e4 J/kg a step at constant density and went below zero
    (-4.4e4 J/kg at step 15: a gas under tension), as the rarefied air behind steel-plate-blast's bridge did
    until the Eulerian cells read from it were non-physical. The blend now takes at most half the particle's
    internal energy a step (mpm.musl, step 3), and the gas heats up again as the slab drags it."""
    air = fluid.params_from(lookup("air"))
    h = 1e-3
    grid = mpm.Grid(origin=(0.0,), cell_size=h, cells=(40,), boundaries=(("free", "free"),))
    slab = 10 * h + 0.25 * h + 0.5 * h * np.arange(8)
    x = np.append(slab, slab[-1] + 0.5 * h)
    rho = np.append(np.full(8, 1.2), 2e-4)
    p = np.append(np.full(8, 1.0e5), 10.0)
    e = np.asarray(jwl.energy(jnp.asarray(rho), jnp.asarray(p), air.eos))
    v = np.zeros((9, 3))
    v[:8, 0] = 1000.0
    batch = mpm.new_particles(x[:, None], 0.5 * h, rho, v=v, half_size=np.full((9, 3), 0.25 * h),
                              material=np.append(np.ones(8, int), 0),
                              stress=np.asarray(T.compose(jnp.zeros((9, 6)), jnp.asarray(p))), energy=e, history_size=3)
    cfg = mpm.make_config(grid, (fluid.MODEL, fluid.MODEL), shape="gimp", blend=True)
    prm = mpm.make_params((air, air), cfl=0.2, pic_fraction=(0.05, 0.0))
    state = jax.jit(mpm.initialize, static_argnames="config")(mpm.make_pool(batch, 9), prm, cfg)
    dt = float(jax.jit(mpm.stable_dt, static_argnames="config")(state, prm, cfg))

    def body(i, carry):
        s, low = carry
        s = mpm.step(s, dt, prm, cfg)
        return s, jnp.minimum(low, s.particles.point.energy[8])

    s, low = jax.jit(lambda s: jax.lax.fori_loop(0, 40, body, (s, jnp.asarray(np.inf))))(state)
    assert float(low) > -0.01 * e[8]
    assert float(s.particles.point.energy[8]) > e[8]


def _hooke(ps, dstrain, dspin, dt, params):
    """A linear-elastic test solid with Poisson's ratio 0 (sigma_ii += E d eps_ii): the hoop stress reads back
    the hoop strain increment."""
    de = T.to_voigt(dstrain)
    return ps._replace(stress=ps.stress + params * de)


def test_rz_hoop_rate_of_a_uniform_expansion_and_the_r_weighted_gimp_weights():
    """r-z, a solid filling r < 12 h (2 x 2 particles per cell, slip axis) given v_r = a r: the exact hoop rate is
    a everywhere. The step's hoop rate (read back from the hoop stress of one small step) is over-estimated by
    the lumped nodal velocity: v_I = sum_p m_p N_Ip v_p / m_I with ring masses m_p ~ r_p gives
    v_I = a r_I (1 + s^2 / r_I^2), s^2 = sum N (r_p - r_I)^2 / sum N = 3 h^2 / 16 for this lattice, so the error
    is ~(3/16) (h / r)^2: 6.1 % at r = 1.75 h, 1.2 % at 4 h; it is the same with linear and GIMP weights (at
    the lattice positions with l = h/4 they coincide), and bounded near the axis, where the axis node's
    v_r = 0 holds (measured 14 % on the two innermost columns). r-weighting the GIMP weights (Nairn &
    Guilkey 2015, S_Ip = int_p N_I r dr / int_p r dr) leaves the bias at the first node off the axis almost
    as it is (7/6 against 19/16 of a h, computed below): it is not the remedy."""
    h, a, E = 0.1, 1.0, 1.0e4
    grid = mpm.Grid(origin=(0.0, 0.0), cell_size=h, cells=(16, 4), axisymmetric=True,
                    boundaries=(("slip", "free"), ("free", "free")))
    x, vol, half = mpm.lattice(grid, (0.0, 0.0), (12 * h, 4 * h), 2)
    v = np.zeros_like(x)
    v[:, 0] = a * x[:, 0]
    model = Model("test-hooke-nu0", _hooke, lambda ps, E: jnp.sqrt(E / ps.density), None, 0)
    dt = 1e-6
    hoop = {}
    for shape in ("linear", "gimp"):
        pool = mpm.make_pool(mpm.new_particles(x, vol, 1.0e3, v=v, half_size=half), 512)
        cfg = mpm.make_config(grid, (model,), shape=shape)
        prm = mpm.make_params((E,), cfl=0.5, q_quadratic=0.0, q_linear=0.0)
        P = mpm.step(mpm.initialize(pool, prm, cfg), dt, prm, cfg).particles
        hoop[shape] = np.asarray(P.point.stress[:len(x), 2]) / (E * dt * a) - 1.0  # relative error
    np.testing.assert_allclose(hoop["gimp"], hoop["linear"], atol=1e-9)
    r = x[:, 0]
    model_error = 3.0 / 16.0 * (h / r) ** 2
    far = (r > 1.5 * h) & (r < 10 * h)  # off the axis, the body's free surface at 12 h a cell away
    assert np.all(np.abs(hoop["gimp"][far] / model_error[far] - 1.0) < 0.1)  # measured <= 3.2 %
    assert np.all(np.abs(hoop["gimp"][r < 1.5 * h]) < 0.2)  # measured 0.141
    # the nodal velocity at r = h from the r-weighted weights of the four particles of its support (host side)
    def s_weight(rp, node):
        rr = np.linspace(rp - 0.25 * h, rp + 0.25 * h, 20001)
        hat = np.clip(1.0 - np.abs(rr - node) / h, 0.0, None)
        return np.trapezoid(hat * rr, rr) / np.trapezoid(rr, rr)
    rp = np.array([0.25, 0.75, 1.25, 1.75]) * h
    weighted = np.array([rpi * s_weight(rpi, h) for rpi in rp])  # m_p S_Ip, m_p ~ r_p
    cartesian = rp * np.array([0.25, 0.75, 0.75, 0.25])
    assert np.sum(weighted * a * rp) / np.sum(weighted) / (a * h) == pytest.approx(7.0 / 6.0, rel=1e-6)
    assert np.sum(cartesian * a * rp) / np.sum(cartesian) / (a * h) == pytest.approx(19.0 / 16.0, rel=1e-12)
