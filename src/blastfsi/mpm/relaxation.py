"""Pressure relaxation between gas particles of different materials that share grid nodes.

MPM gives every particle the strain of the nodal velocity field around it, so where detonation
products and air particles share nodes (at their contact, and wherever the bridge creates particles of
both from a mixed Eulerian cell) both take the same volumetric strain: an iso-strain mixture. Air is the
stiffer of the two there (rho c^2 = gamma p ~ 47 MPa for air at 34 MPa, ~ 27 MPa for the products at
21 MPa), so a decelerating contact over-compresses it: in he-slab-2d (w = 5, 2 mm, 10 us after the
remap) air particles next to products stood at 44 MPa while the products beside them held 21 MPa,
and the mixed cells this made lifted gauge 2's peak 10-13 % above gauge 1's (docs/theory/cfdmp.md, step 11).
The Eulerian cells assume pressure equilibrium between the phases they hold (the mixture closure of
ERRATA 000-9); this kernel gives the particles the same: an instantaneous mechanical relaxation (Saurel
& Abgrall, JCP 150 (1999) 425) that exchanges volume between the gas particles of a node at the node's
equilibrium pressure.

Per gas particle p of material k (mass m, volume V, pressure p_p, compliance a_p = V_p / K_p, K = rho c^2
the adiabatic bulk modulus) and node I (shape function N_Ip):

    A_kI = sum_{p in k} N_Ip a_p,   pbar_kI = sum_{p in k} N_Ip a_p p_p / A_kI   (material k's mean pressure)
    p*_I = sum_k A_kI pbar_kI / sum_k A_kI                      (the node's linearised equilibrium pressure)
    dV_Ip = s_I chi_I N_Ip a_p (pbar_kI - p*_I)                 (volume the particle gives up at node I)
    dV_p = sum_I dV_Ip,   m_p de_p = -sum_I p*_I dV_Ip          (the exchange works at p*_I)

sum_p dV_Ip = chi_I s_I sum_k A_kI (pbar_kI - p*_I) = 0 at every node, so the gas volume of every node is
kept and the internal energy exchanged, -sum_I p*_I sum_p dV_Ip, sums to zero: mass, momentum and total
energy are conserved exactly. Every particle of a material moves by its material's mismatch at the node,
so the pressure differences within a material (its gradient) are left as they are: an earlier version that
relaxed each particle's own pressure to p*_I flattened the products' gradient wherever a trace of air
shared their nodes. chi_I = clip((1 - max_k A_kI / sum_k A_kI) / MIXED, 0, 1) (one minus the largest
material's share of the node's compliance) confines the exchange to nodes where the materials meet:
single-gas runs are unchanged.
s_I = min(1, MAX_VOLUME_CHANGE / (max_k |pbar_kI - p*_I| max_p 1/K_p), MAX_ENERGY_SHARE min_p e_p rho_p K_p / max_k
p*_I (pbar_kI - p*_I) over the node's particles and the materials that give up energy there) bounds
|dV_p| / V_p by MAX_VOLUME_CHANGE and the work a particle does, p*_I dV_p, by MAX_ENERGY_SHARE of its internal
energy: a particle moves with its material's mismatch, not its own, so a cold particle among hotter ones of its
material expands at a node where that material stands above p*, working at p*_I far above its own pressure
(steel-plate-blast, 0.42 ms: a products particle at 7 Pa beside air at 50 Pa went from 3.7 kJ/kg to -2.4 kJ/kg
in one step, and the fictitious cell made from it became non-physical). The MUSL step relaxes the state the
step starts from (pressures of the last step, compliances from its sound speeds, the step's stencil), before
the strain increment and the material update, which then evaluate the EOS at the relaxed density and energy:
the linearisation only sets the rate of approach, and each step relaxes the remaining mismatch again. Particles
still burning (F < 1) take no part.
"""
from __future__ import annotations

import functools
import operator

import jax.numpy as jnp

from blastfsi.constitutive import PointState
from blastfsi.xla import row_sum

MIXED = 0.01  # minority share of a node's gas compliance from which its particles relax fully (chi_I = 1)
MAX_VOLUME_CHANGE = 0.25  # largest relative volume change of a particle in one relaxation
MAX_ENERGY_SHARE = 0.5  # largest share of its internal energy a particle gives up in one relaxation


def fluid_materials(models) -> tuple:
    """Indices of the fluid-model materials (gases, detonation products)."""
    return tuple(k for k, m in enumerate(models) if m.name == "fluid")


def gas_materials(models, enabled: bool = True) -> tuple:
    """The material indices to relax (``Config.relax``): every fluid-model material when ``enabled`` and there
    are two or more of them, else none."""
    gases = fluid_materials(models)
    return gases if enabled and len(gases) > 1 else ()


def relax(point: PointState, mass, material, wave_speed, idx, w, gas: tuple, num_nodes: int, scatter, interpolate):
    """Density and energy of ``point`` with the gas particles of materials ``gas`` relaxed towards their
    nodes' common pressure (module docstring), their pressure read from ``point.stress``. ``mass`` is zero
    for inactive particles; ``wave_speed`` the sound speed that sets each particle's compliance; (idx, w)
    the stencil; the transfers: ``scatter(channels) -> (num_nodes, C)`` and ``interpolate(table) -> K
    arrays (n,)``, sum_I N_Ip table_Ik. Returns (density, energy); the caller's EOS gives the pressure."""
    p = -(point.stress[:, 0] + point.stress[:, 1] + point.stress[:, 2]) / 3.0
    burnt = point.history[:, 2] == 0.0  # unburnt fraction 1 - F (constitutive.fluid)
    stiffness = point.density * wave_speed ** 2
    mine = [(material == k) & (mass > 0.0) & burnt & (stiffness > 0.0) for k in gas]
    ok = functools.reduce(operator.or_, mine)
    safe_k = jnp.where(ok, stiffness, 1.0)
    compliance = jnp.where(ok, mass / point.density / safe_k, 0.0)
    channels = []
    for k in mine:
        a_k = jnp.where(k, compliance, 0.0)
        channels += [w * a_k, w * (a_k * p)]
    nodal = scatter(channels)
    a_I, b_I = nodal[:, 0::2], nodal[:, 1::2]  # (num_nodes, n_gas) each
    has = a_I > 0.0
    p_mean = jnp.where(has, b_I / jnp.where(has, a_I, 1.0), 0.0)  # pbar_kI
    a_all = row_sum(a_I)
    safe_a = jnp.where(a_all > 0.0, a_all, 1.0)
    p_star = row_sum(b_I) / safe_a  # p*_I
    gap = jnp.where(has, p_mean - p_star[:, None], 0.0)
    chi = jnp.clip((1.0 - jnp.max(a_I, axis=1) / safe_a) / MIXED, 0.0, 1.0)
    # per node, max_p 1 / K_p (the volume bound) and min_p e_p rho_p K_p (the work bound: a particle of material k
    # that expands at node I gives up p*_I dV_Ip <= s_I p*_I gap_kI m_p / (rho_p K_p), so s_I <= MAX_ENERGY_SHARE
    # min_p e_p rho_p K_p / max_k p*_I gap_kI keeps the sum over its nodes, whose weights sum to 1, within
    # MAX_ENERGY_SHARE of every particle's internal energy), one stencil row at a time (a particle pool split over
    # devices stays split; max is exact in any order)
    room = jnp.maximum(point.energy, 0.0) * point.density * safe_k
    touches = (w > 0.0) & ok
    rows = jnp.stack([jnp.where(touches, 1.0 / safe_k, 0.0), jnp.where(touches, -room, -jnp.inf)], axis=-1)
    extremes = jnp.stack([jnp.zeros(num_nodes, p.dtype), jnp.full(num_nodes, -jnp.inf, p.dtype)], axis=-1)
    for row in range(idx.shape[0]):
        extremes = extremes.at[idx[row]].max(rows[row])
    softest, least_room = extremes[:, 0], -extremes[:, 1]
    worst = jnp.max(jnp.abs(gap), axis=1) * softest
    loss = jnp.max(p_star[:, None] * gap, axis=1)  # > 0 where some material gives up energy at node I
    limit = jnp.where(loss > 0.0, least_room / jnp.where(loss > 0.0, loss, 1.0), jnp.inf)
    weight = chi * jnp.minimum(jnp.minimum(1.0, MAX_VOLUME_CHANGE / jnp.where(worst > 0.0, worst, 1.0)),
                               MAX_ENERGY_SHARE * limit)
    columns = interpolate(jnp.concatenate([weight[:, None] * gap, (weight * p_star)[:, None] * gap], axis=1))
    n_gas = len(gas)
    d_volume = compliance * sum(jnp.where(k, columns[j], 0.0) for j, k in enumerate(mine))
    d_work = compliance * sum(jnp.where(k, columns[n_gas + j], 0.0) for j, k in enumerate(mine))
    volume = jnp.where(ok, mass / point.density, 1.0)
    density = jnp.where(ok, mass / (volume + d_volume), point.density)
    energy = jnp.where(ok, point.energy - d_work / jnp.where(ok, mass, 1.0), point.energy)
    return density, energy
