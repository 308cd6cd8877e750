"""Pressure relaxation between gas materials sharing MPM nodes (blastfsi.mpm.relaxation)."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from blastfsi import mpm
from blastfsi.constitutive import PointState, fluid
from blastfsi.constitutive import tensor as T
from blastfsi.eos import jwl
from blastfsi.materials import lookup
from blastfsi.mpm import musl, relaxation

jax.config.update("jax_enable_x64", True)

AIR, PRODUCTS = 0, 1


def _gases():
    return [fluid.params_from(lookup(name)) for name in ("air", "tnt")]


def _state(x, material, density, pressure, params):
    """Gas particles (1D, 1 mm cells) at given densities and pressures, burnt (F = 1)."""
    n = len(x)
    rho = jnp.asarray(density, float)
    p = jnp.asarray(pressure, float)
    e = jnp.stack([jwl.energy(rho[i], p[i], params[material[i]].eos) for i in range(n)])
    point = PointState(stress=T.compose(jnp.zeros((n, 6)), p), density=rho, energy=e,
                       plastic_strain=jnp.zeros(n), damage=jnp.zeros(n), history=jnp.zeros((n, 3)))
    c = jnp.stack([jnp.sqrt(jwl.sound_speed_squared(rho[i], p[i], params[material[i]].eos)) for i in range(n)])
    return point, c


def _relax(point, mass, material, c, x, grid, params, combined=False):
    xs = jnp.zeros((len(x), 3)).at[:, 0].set(jnp.asarray(x))
    half = jnp.full((len(x), 3), 0.25 * grid.cell_size)
    idx, w, _ = mpm.stencil(xs, half, grid, mpm.SHAPES["gimp"])
    n = grid.num_nodes
    rho, e = relaxation.relax(point, mass, jnp.asarray(material), c, idx, w, (AIR, PRODUCTS), n,
                              scatter=lambda ch: musl.particle_to_grid(idx, ch, n, combined),
                              interpolate=lambda t: musl.grid_to_particle(idx, w, t, combined))
    new = point._replace(density=rho, energy=e)
    p = sum(jnp.where(jnp.asarray(material) == k, fluid.pressure(new, params[k]), 0.0) for k in (AIR, PRODUCTS))
    return new._replace(stress=T.compose(jnp.zeros_like(point.stress), p))


def _sound_speed(point, material, params):
    m = jnp.asarray(material)
    return sum(jnp.where(m == k, fluid.wave_speed(point, params[k]), 0.0) for k in (AIR, PRODUCTS))


def _pressure(point):
    return -(point.stress[:, 0] + point.stress[:, 1] + point.stress[:, 2]) / 3.0


def test_mixed_particles_reach_a_common_pressure_conserving_volume_and_energy():
    """Air over-compressed next to products (the he-slab-2d contact: 44 vs 21 MPa), each air particle sharing
    its place with a products one: repeated relaxations (no motion) bring each pair to one pressure between
    the two; each relaxation conserves the gas volume and the internal energy to round-off (the exchange
    works at the node pressure, module docstring)."""
    params = _gases()
    grid = mpm.Grid(origin=(0.0,), cell_size=1e-3, cells=(6,))
    x = [2.3e-3, 2.3e-3, 2.7e-3, 2.7e-3]
    material = [AIR, PRODUCTS, AIR, PRODUCTS]
    point, c = _state(x, material, [8.6, 72.0, 8.0, 70.0], [44e6, 21e6, 40e6, 20e6], params)
    mass = jnp.asarray([8.6e-4, 7.2e-4, 8.6e-4, 7.2e-4])  # kg per unit area, volumes ~1e-4 and 1e-5 m
    energy0 = float(jnp.sum(mass * point.energy))
    for _ in range(30):
        new = _relax(point, mass, material, c, x, grid, params)
        assert float(jnp.sum(mass / new.density)) == pytest.approx(float(jnp.sum(mass / point.density)), rel=1e-13)
        assert float(jnp.sum(mass * new.energy)) == pytest.approx(energy0, rel=1e-13)
        point = new
        c = _sound_speed(point, material, params)
    p = np.asarray(_pressure(point))
    assert 20e6 < p.min() and p.max() < 44e6
    # each pair's mismatch (initially 23 and 20 MPa) below 1e-3 of it: the pairs share nodes, and the kernel
    # equalises the materials' mean pressures per node, so two pairs at different places keep a small residue
    assert np.all(np.abs(p[0::2] - p[1::2]) < 1e-3 * 20e6)
    one = _state(x[:2], material[:2], [8.6, 72.0], [44e6, 21e6], params)
    point, c = one
    for _ in range(30):
        point = _relax(point, mass[:2], material[:2], c, x[:2], grid, params)
        c = _sound_speed(point, material[:2], params)
    p = np.asarray(_pressure(point))
    assert p[0] == pytest.approx(p[1], rel=1e-9)  # one pair: converged (measured: in 6 relaxations, the first
    # two held by the 25 % volume cap)


def test_single_material_particles_are_left_alone():
    """Particles of one gas at different pressures sharing nodes are not relaxed (chi = 0): the kernel
    equilibrates materials, not a material's own pressure gradient."""
    params = _gases()
    grid = mpm.Grid(origin=(0.0,), cell_size=1e-3, cells=(6,))
    x = [2.3e-3, 2.45e-3, 2.6e-3]
    material = [AIR, AIR, AIR]
    point, c = _state(x, material, [8.6, 6.0, 4.0], [44e6, 30e6, 20e6], params)
    new = _relax(point, jnp.full(3, 1e-4), material, c, x, grid, params)
    np.testing.assert_array_equal(np.asarray(new.density), np.asarray(point.density))
    np.testing.assert_array_equal(np.asarray(new.energy), np.asarray(point.energy))


def test_relax_needs_two_fluid_materials():
    """``relax`` names two or more distinct fluid-model materials; anything else is refused by name."""
    from blastfsi.constitutive import elastic

    grid = mpm.Grid(origin=(0.0,), cell_size=1e-3, cells=(6,))
    gases = (fluid.MODEL, fluid.MODEL, elastic.MODEL)
    assert mpm.make_config(grid, gases, relax=(0, 1)).relax == (0, 1)
    for bad in ((0,), (0, 0), (0, 2), (0, 3)):
        with pytest.raises(mpm.MPMError, match="relax"):
            mpm.make_config(grid, gases, relax=bad)


def test_combined_transfers_give_the_same_relaxation():
    """The GPU form of the transfers (one row scatter / gather of all channels) relaxes as the CPU form."""
    params = _gases()
    grid = mpm.Grid(origin=(0.0,), cell_size=1e-3, cells=(6,))
    x = [2.3e-3, 2.45e-3, 2.6e-3, 3.4e-3]
    material = [AIR, PRODUCTS, AIR, PRODUCTS]
    point, c = _state(x, material, [8.6, 72.0, 8.0, 70.0], [44e6, 21e6, 40e6, 20e6], params)
    mass = jnp.asarray([8.6e-4, 7.2e-4, 8.6e-4, 7.2e-4])
    a = _relax(point, mass, material, c, x, grid, params)
    b = _relax(point, mass, material, c, x, grid, params, combined=True)
    assert not np.allclose(np.asarray(a.density), np.asarray(point.density))
    np.testing.assert_allclose(np.asarray(b.density), np.asarray(a.density), rtol=1e-14)
    np.testing.assert_allclose(np.asarray(b.energy), np.asarray(a.energy), rtol=1e-14)


def test_a_cold_particle_gives_up_at_most_half_its_internal_energy(monkeypatch):
    """A cold products particle among hot ones at a node they share with air (the rarefied gas in front of
    steel-plate-blast's plate late in the run: products at 7 Pa and at 4 kPa, air at 50 Pa): every products
    particle moves by its material's mean mismatch, so the cold one expands and works at the node pressure,
    far above its own. Without the work bound it gives up 96 % of its internal energy in one relaxation (in
    the run, with the rest of the step's work, it went below zero); with it, it keeps 1 - MAX_ENERGY_SHARE of
    it, the gas volume and the internal energy are conserved to round-off and the hot products still expand
    towards the air."""
    params = _gases()
    grid = mpm.Grid(origin=(0.0,), cell_size=1e-3, cells=(6,))
    x = [2.3e-3, 2.3e-3, 2.3e-3]
    material = [AIR, PRODUCTS, PRODUCTS]
    point, c = _state(x, material, [5e-3, 5e-3, 5e-3], [50.0, 4000.0, 7.5], params)
    mass = jnp.asarray([100.0, 100.0, 1.0]) * 5e-3 * 2.5e-4  # the cold particle a remnant beside larger ones
    cold = 2
    monkeypatch.setattr(relaxation, "MAX_ENERGY_SHARE", jnp.inf)
    unbounded = _relax(point, mass, material, c, x, grid, params)
    assert float(unbounded.energy[cold]) < 0.1 * float(point.energy[cold])  # the set-up exercises the bound
    monkeypatch.undo()
    new = _relax(point, mass, material, c, x, grid, params)
    assert float(new.energy[cold]) >= (1.0 - relaxation.MAX_ENERGY_SHARE) * float(point.energy[cold]) > 0.0
    assert float(jnp.sum(mass / new.density)) == pytest.approx(float(jnp.sum(mass / point.density)), rel=1e-13)
    assert float(jnp.sum(mass * new.energy)) == pytest.approx(float(jnp.sum(mass * point.energy)), rel=1e-13)
    assert float(new.density[1]) < float(point.density[1])  # the hot products still expand
