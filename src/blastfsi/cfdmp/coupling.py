"""Kernels of the bridge-region coupling (seed 000 Sec. 3), pure and jittable.

Notation: the Eulerian state ``U`` (rows of :mod:`blastfsi.euler.config`) covers
the whole domain; the MPM box holds particles (gas and structures); ``V`` is a
cell's volume in the units of the particle masses: dx^ndim on Cartesian grids
(per unit depth in 2D, per unit area in 1D), the ring 2 pi r dx^2 on an r-z grid
(``Layout.cell_volume``, :func:`blastfsi.euler.geometry.cell_volumes`), and a
face transfer T moves T times its face's ``measure`` (dx times the face area,
:func:`blastfsi.euler.geometry.face_measures`). One coupled step (000 Sec. 3.5,
the 14 steps regrouped):

1. :func:`fictitious`: the box cells beyond the bridge take their values
   from the gas particles (000 Eqs. 31-36): nodal sums of mass (per
   material), momentum, internal energy and phase volume, interpolated to
   the cell centre (the mean of the cell's 2^ndim nodes, N = 2^-ndim), then
   divided by the interpolated gas volume (:func:`rows_from_sums`); products
   volume fraction = products volume / gas volume. Cells the scheme never
   reads (structures stay FICTITIOUS_DEPTH cells beyond the bridge) are
   parked at their initial state.
2. :func:`interface_source`: the Eulerian cells of the ring outside the box act
   as particles on the interface nodes (000 Eqs. 37-39): mass rho V, momentum
   rho V u, and internal force + grad N_I p V (their stress is -p I; on an r-z
   grid also the hoop term + N_I p V / r on the radial component, as the MPM
   particles' own, so that a uniform pressure still balances exactly).
3. The MPM step with that source and the Eulerian step with its face transfers
   (``euler.step_with_transfers``), both over the same dt.
4. Transport (000 Sec. 3.4), written so that mass is conserved exactly:

   * what the Eulerian scheme moved across a coupled face (its own face
     transfer, not the centred estimate of Eqs. 40-44, so that the Eulerian
     region's loss is exactly what the MPM side receives) goes, per face cell
     and material, into a *reservoir* with the convective momentum and energy
     of the donor cell: m_k, m_k u, m_k (e_k + |u|^2/2); the pressure part of
     the scheme's momentum and energy transfer reaches the MPM gas through the
     interface nodes' force (step 2) and is booked as ``pressure_transfer``;
   * a reservoir holding at least the nominal particle mass
     m_nom = rho_bridge V / ppc^ndim emits particles (Eqs. 45-46: s = the whole
     multiples of m_nom, at most ppc^(ndim-1) per step, mass m/s each) in the
     first bridge cell, in the layer the gas occupies next to the face
     (Eq. 47), with the donor cell's density (:func:`cell_phases`) and the
     reservoir's velocity and internal energy (Eq. 48 generalised:
     e = E/m - |v|^2/2);
   * through a face where the gas leaves the box, the Eulerian cell outside
     keeps the scheme's transfer and its convective part becomes a debt of the
     face's reservoir; a gas particle that leaves the box through a coupled face
     is cut at the face and the part beyond (its share of the mass, momentum and
     energy, Eqs. 49-51) repays it; the reservoir's balance is settled into the
     Eulerian cell as far as that cell can take it (:func:`_settle`); through a
     box face on an outflow face of the domain the part beyond leaves the run
     (``boundary_out``).

Mass budget, exact up to round-off: Eulerian-only cells + particles +
reservoirs + boundary_out = constant from activation on. Momentum and energy: the
same sum changes only by what the MPM step does to the particles (the interface
nodes' force, supports and grid faces, and the MPM scheme's own non-conservation;
booked as ``mpm_step``; the outflow mirror's traction is the pressure flux through
the domain boundary, booked with ``boundary_out``) minus the pressure part of the
scheme's face transfer (``pressure_transfer``): with both booked the transport
(reservoirs, particle creation and deletion, settling, boundary outflow) closes
to round-off, and ``mpm_step - pressure_transfer`` is the coupling's momentum
and energy error.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from blastfsi import euler as ek
from blastfsi import mpm
from blastfsi.constitutive import PointState
from blastfsi.eos import jwl
from blastfsi.euler.config import layout as row_layout
from blastfsi.euler.mixture import cell_state, cold_pressure, eos_rows, phase_sums
from blastfsi.euler.mixture import pressure as mixture_pressure
from blastfsi.mpm.musl import wave_speed
from blastfsi.xla import row_sum

# Tuned constants of the coupling: the CFDMP paper states none of them. Derivations and measured sensitivities:
# docs/theory/cfdmp.md, "Departures from the paper and tuned constants".
INFLOW_MACH = 0.01  # inflow Mach number over which a flow-out face's mirror gas is gone (outflow_ghost): a ramp
#                     narrow against c, so rest and outflow (up to velocity noise) keep the whole mirror
FULL_FILL = 0.5  # share of a flow-out face node's half support filled with gas from which its mirror traction
#                  is whole (outflow_ghost): a gas that fills space (phi ~ 1) keeps it, a lone particle does not
FEED_FRACTION = 1e-6  # smallest reservoir mass that feeds an inflow particle, in gas particles of the bridge cell:
#                       far above round-off traces, far below a particle; what waits stays booked
PRESENT = 1e-3  # smallest mass fraction of a material in a cell that becomes particles of it (activation, inflow
#                 particles) or whose own phase density settles into a cell (_two_phase_split): traces wait


class Layout(NamedTuple):
    """Traced arrays of the coupling layout (built by :mod:`blastfsi.cfdmp.problem`)."""

    fictitious: jnp.ndarray  # (*shape) bool: box cells beyond the bridges
    parked: jnp.ndarray  # (*shape) bool: fictitious cells the scheme never reads
    outside: jnp.ndarray  # (*shape) bool: Eulerian-only cells
    park_rows: jnp.ndarray  # (nvar, *shape) the parked state (the initial state)
    ring_cells: jnp.ndarray  # (R,) flat Eulerian indices of the ring cells
    ring_idx: jnp.ndarray  # (S, R) MPM node indices of their stencils
    ring_w: jnp.ndarray  # (S, R) N_Ic
    ring_grad: jnp.ndarray  # (ndim, S, R) dN_Ic/dx
    ring_volume: jnp.ndarray  # (R,) their volumes V_c
    ring_radius: jnp.ndarray  # (R,) their centres' first coordinate (the radius on an r-z grid)
    cell_volume: jnp.ndarray  # (N,) volume of every Eulerian cell (C order)
    outflow_area: jnp.ndarray  # (num_nodes, ndim) -n A on MPM nodes of box faces on outflow domain faces, else 0
    face_out: jnp.ndarray  # (F,) flat Eulerian index of the cell outside each face cell
    face_in: jnp.ndarray  # (F,) flat Eulerian index of the bridge cell
    face_centre: jnp.ndarray  # (F, 3) centre of each face cell's face [m]
    face_measure: jnp.ndarray  # (F,) dx times its area: a transfer T through it moves T * face_measure
    face_into: jnp.ndarray  # (F,) +1 (lower box face) / -1 (upper)
    face_axis: jnp.ndarray  # (F, 3) unit normal into the box
    face_lateral: jnp.ndarray  # (F, 3, 3) rows: unit vectors along the face (zero rows beyond ndim - 1)
    gas_x: jnp.ndarray  # (G, 3) gas lattice
    gas_volume: jnp.ndarray  # (G,)
    gas_half: jnp.ndarray  # (G, 3)
    gas_cell: jnp.ndarray  # (G,)
    boundary_measure: tuple  # per axis (lower, upper) arrays over the domain faces: their face_measure where
    #                          the cell inside is Eulerian-only, else 0
    box_lower: jnp.ndarray  # (3,) [m]
    box_upper: jnp.ndarray  # (3,)


class Static(NamedTuple):
    """Hashable configuration of a coupled run."""

    euler: ek.Config
    mpm: mpm.Config
    faces: tuple  # (axis, side, plane) per coupled face
    face_sizes: tuple  # face cells per coupled face
    box_lo: tuple  # box cell range in the Eulerian grid
    box_hi: tuple
    mpm_offset: tuple  # Eulerian cell index of the MPM grid's first cell
    gas_material: tuple  # MPM material index of each Eulerian material
    n_structure: int  # structure particles (first slots of the pool)
    ppc: int  # gas particles per cell and direction
    outflow_faces: tuple  # (axis, side) per box face on an outflow face of the domain (outflow_ghost, remove_leaving)
    pool_parts: int = 1  # devices the particle pool is split over (mpm.add_particles_at)


class Reservoirs(NamedTuple):
    mass: jnp.ndarray  # (F, n_materials) [kg]
    momentum: jnp.ndarray  # (F, n_materials, 3)
    energy: jnp.ndarray  # (F, n_materials) total energy [J]
    buffer: jnp.ndarray  # (F, n_materials) int32 pool slot of each inflow particle (-1: none)


class Budget(NamedTuple):
    """Running sums of what crossed the system's boundary and what the interface exchanged."""

    boundary_out: jnp.ndarray  # (n_materials + ndim + 1,) mass per material, momentum, energy that left (the
    #                            Eulerian boundary fluxes, particles leaving the run, the flow-out mirror's traction)
    pressure_transfer: jnp.ndarray  # (ndim + 1,) momentum and energy of the scheme's face transfer not carried
    #                                 by the reservoirs (the interface pressure's impulse and work)
    required: jnp.ndarray  # () int32: active particles the last emission needed (> capacity: the run stops)
    structure_out: jnp.ndarray  # () mass of structure particles that left the box (their momentum and energy
    #                             are in boundary_out; structure mass is not part of the gas budget's rows)
    mpm_step: jnp.ndarray  # (ndim + 1,) momentum and energy the MPM steps gave the particles (mpm_content),
    #                        but the flow-out mirror's traction (booked in boundary_out, with the opposite sign)
    #                        and the reactions
    reaction: jnp.ndarray  # (ndim + 1,) impulse and work of the MPM grid's wall faces and of the supports on the
    #                        system (mpm.State.reaction)


def mpm_content(P: mpm.Particles, ndim: int):
    """(ndim + 1,) momentum and total energy of the active particles: the MPM step changes them (not the
    mass), and ``Budget.mpm_step`` books each step's change."""
    _, mom, energy = particle_content(P)
    on = P.active
    return jnp.concatenate([jnp.sum(jnp.where(on[:, None], mom, 0.0), axis=0)[:ndim],
                            jnp.sum(jnp.where(on, energy, 0.0))[None]])


def flat_primitives(U, eos, cfg: ek.Config) -> dict:
    """rho (N,), velocity (ndim, N), pressure (N,), specific internal energy (N,), phase densities rho_k and
    mass fractions (n, N) of every cell (C order)."""
    lay = row_layout(cfg)
    rows = tuple(U.reshape(U.shape[0], -1))
    st = cell_state(rows, eos_rows(eos, lay.n), lay)
    return {"rho": st.rho, "velocity": jnp.stack(st.velocity), "pressure": st.p, "rho_k": jnp.stack(st.rho_k),
            "internal_energy": st.rho_e / st.rho,
            "mass_fraction": jnp.stack([rows[k] / st.rho for k in range(lay.n)])}


def _gas_index(static: Static, material):
    """Eulerian material slot of each particle (-1: a structure)."""
    slot = jnp.full(material.shape, -1, jnp.int32)
    for k, m in enumerate(static.gas_material):
        slot = jnp.where(material == m, k, slot)
    return slot


def _node_to_cell(nodal, grid: mpm.Grid):
    """(num_nodes, C) -> (*cells, C): mean of each cell's 2^dim nodes (N = 2^-dim at the centre)."""
    block = nodal.reshape(grid.nodes + (nodal.shape[1],))
    out = 0.0
    d = grid.dim
    for corner in range(2 ** d):
        idx = tuple(slice(1, None) if (corner >> j) & 1 else slice(None, -1) for j in range(d))
        out = out + block[idx]
    return out / 2 ** d


def gas_sums(P: mpm.Particles, static: Static):
    """Per MPM cell (*cells, 2 n + ndim + 1): mass and volume per material, momentum, internal energy
    (000 Eqs. 31-33), from the gas particles only."""
    cfg = static.mpm
    grid, d = cfg.grid, cfg.grid.dim
    n = len(static.gas_material)
    slot = _gas_index(static, P.material)
    gas = P.active & (slot >= 0)
    idx, w, _ = mpm.materialised_stencil(P, grid, cfg.shape)
    m = jnp.where(gas, P.mass, 0.0)
    vol = m / P.point.density
    channels = [w * jnp.where(slot == k, m, 0.0) for k in range(n)]
    channels += [w * jnp.where(slot == k, vol, 0.0) for k in range(n)]
    channels += [w * (m * P.v[:, i]) for i in range(d)]
    channels += [w * (m * P.point.energy)]
    nodal = mpm.musl.particle_to_grid(idx, channels, grid.num_nodes, cfg.combined_scatter)
    return _node_to_cell(nodal, grid)


def _embed(cells, static: Static, shape):
    """MPM-cell array (*mpm_cells, C) -> Eulerian-grid rows (C, *shape), zero outside the MPM grid."""
    sl = tuple(slice(o, o + c) for o, c in zip(static.mpm_offset, static.mpm.grid.cells))
    out = jnp.zeros((cells.shape[-1],) + tuple(shape), cells.dtype)
    return out.at[(slice(None),) + sl].set(jnp.moveaxis(cells, -1, 0))


def rows_from_sums(sums, n: int, d: int):
    """Conservative rows (partials, momentum, E, alpha) and the gas volume from per-cell sums.

    000 Eqs. (34)-(36) divide the interpolated mass, momentum and energy by the cell volume V_c; here they
    are divided by the interpolated volume of the gas particles themselves (sum N m/rho), i.e. the rows
    hold the mass-weighted means of the particles' density, velocity and specific energy. For a uniform gas
    both agree; the particles' version stays exact when their spacing is uneven (after the bridge has
    created particles) and next to structures, where V_c would count the structure's volume as gas.
    """
    mass_k = [sums[k] for k in range(n)]
    vol_k = [sums[n + k] for k in range(n)]
    mom = [sums[2 * n + i] for i in range(d)]
    internal = sums[2 * n + d]
    m = sum(mass_k)
    vol = sum(vol_k)
    safe_m = jnp.where(m > 0.0, m, 1.0)
    safe_v = jnp.where(vol > 0.0, vol, 1.0)
    energy = (internal + 0.5 * sum(p * p for p in mom) / safe_m) / safe_v
    rows = [mk / safe_v for mk in mass_k] + [p / safe_v for p in mom] + [energy]
    if n == 2:
        rows.append(vol_k[0] / safe_v)
    return jnp.stack(rows), vol


def gas_rows(P: mpm.Particles, static: Static):
    """Conservative rows over the Eulerian grid from the gas particles (000 Eqs. 31-36) and the interpolated
    gas volume per cell (zero outside the MPM grid)."""
    cfg = static.euler
    sums = _embed(gas_sums(P, static), static, cfg.shape)
    return rows_from_sums(sums, cfg.n_materials, len(cfg.shape))


def fictitious(U, rows, gas_volume, layout: Layout, previous):
    """U for the scheme: the fictitious cells it reads from the particles, the parked ones at their
    initial state (step 1 of the module docstring). A read cell that holds no gas (its nodes carry no gas
    particle's weight: the gas expanded away from it) keeps its state of ``previous`` (the step's start),
    the last the particles gave it: the scheme's own update of such a cell would run at a step that its
    signal does not bound (only the fictitious cells next to the scheme's own set the step) and grow
    without bound there (steel-plate-blast, 0.48 ms: an empty cell between the bridge and the plate went
    from ~1e-4 to 0.24 kg/m^3 beside 5e-5 and then to NaN)."""
    read = layout.fictitious & ~layout.parked
    return jnp.where(layout.parked, layout.park_rows,
                     jnp.where(read & (gas_volume > 0.0), rows, jnp.where(read, previous, U)))


def view(U, rows, gas_mass, layout: Layout):
    """U for fields and gauges: every box cell beyond the bridges that holds gas from the particles."""
    return jnp.where(layout.fictitious & (gas_mass > 0.0), rows, U)


def outflow_ghost(P: mpm.Particles, layout: Layout, static: Static, reference, stencil=None) -> mpm.musl.NodalSource:
    """The gas beyond the box faces that lie on an outflow face of the domain, on those faces' MPM nodes:
    it continues the gas inside (zero gradient, like the Eulerian outflow ghost cells) instead of the vacuum a
    free MPM face would be. The particles give such a node only the half of its support inside the box; the
    mirror half adds the same mass and momentum (so the node keeps the particles' velocity and the inertia of
    a full support) and the traction -p_I A n, p_I = sum_p N_Ip V_p p_p / sum_p N_Ip V_p the volume-weighted
    pressure of the gas particles around the node (a node on k such faces: 2^k - 1 mirrors). Without the
    mirror mass a rarefied node (gas blown past a slab's corner) took the whole traction on a sliver of mass,
    and a gas at rest in such a box ran away (tests/test_cfdmp.py).

    Volume, not mass, weights the pressure: the traction stands for the outside continuation of the
    particles' own pressure force on the node, sum_p V_p p_p dN_I/dn, a volume integral. Mass weights let a
    small, compressed, hot particle set the traction of a rarefied node it barely fills; a uniform state
    gets the same traction either way.

    The mirror models outflow and rest only: no gas enters the box through such a face (no particles are
    created there), so where the node's gas flows in, the mirror's traction would push ever fewer particles
    without bringing mass and the rarefied gas behind a structure's edge would run away. The mirror is
    therefore scaled by clip(1 + u_n / (INFLOW_MACH c), 0, 1), u_n the node's outward velocity and c its
    mass-weighted sound speed: whole for outflow and rest, gone for inflow faster than INFLOW_MACH c (the node
    is then a free face), linear between (no switching; docs/theory/cfdmp.md, "Departures from the paper").
    ``reference``: the MPM step's reference pressure (the traction is that of p_I - p_ref, as the particles'
    force). ``stencil``: the particles' (idx, w) when the caller
    has them (the MUSL step's own, see mpm.musl.step).

    The traction p_I A stands for gas that fills the node's support. Particles whose volumes leave most of
    it empty (a lone products particle at the edge of the cloud, compressed) push the node with sum_p V_p
    p_p dN_I/dn only, a fraction phi_I = sum_p N_Ip V_p / (A h / 2) of p_I A: the mirror continues that, so
    the traction is scaled by clip(phi_I / FULL_FILL, 0, 1) (whole for a node at least half full: a gas
    that fills space, however it moves, keeps the exact balance of a uniform state; a lone particle with
    phi_I << 1 is no longer pushed by the whole traction of its own pressure)."""
    cfg = static.mpm
    d = cfg.grid.dim
    zero = jnp.zeros_like(layout.outflow_area)
    if not static.outflow_faces:
        return mpm.musl.NodalSource(zero[:, 0], zero, zero, zero)
    slot = _gas_index(static, P.material)
    m = jnp.where(P.active & (slot >= 0), P.mass, 0.0)
    p = -(P.point.stress[:, 0] + P.point.stress[:, 1] + P.point.stress[:, 2]) / 3.0 + P.q
    idx, w = stencil if stencil is not None else mpm.materialised_stencil(P, cfg.grid, cfg.shape)[:2]
    mc = jnp.where(m > 0.0, m * P.wave_speed, 0.0)  # (free slots may hold any wave speed)
    vol = jnp.where(m > 0.0, m / P.point.density, 0.0)
    channels = [w * m, w * vol, w * mc, w * (vol * p)] + [w * (m * P.v[:, i]) for i in range(d)]
    nodal = mpm.musl.particle_to_grid(idx, channels, cfg.grid.num_nodes, cfg.combined_scatter)
    m_node, v_node, mc_node, momentum = nodal[:, 0], nodal[:, 1], nodal[:, 2], nodal[:, 4:]
    p_node = jnp.where(v_node > 0.0, nodal[:, 3] / jnp.where(v_node > 0.0, v_node, 1.0), 0.0)
    # u_n / c as a ratio of the nodal sums (m u_n) / (m c): no division by a node's (possibly tiny) mass;
    # outflow_area is -A n_out per axis
    area = jnp.sqrt(row_sum(layout.outflow_area ** 2))
    area = jnp.where(area > 0.0, area, 1.0)  # (nodes off such faces: any non-zero value, their area rows are 0)
    outward = -row_sum(momentum * layout.outflow_area) / area
    ok = mc_node > 0.0
    share = jnp.where(ok, jnp.clip(1.0 + outward / (INFLOW_MACH * jnp.where(ok, mc_node, 1.0)), 0.0, 1.0), 1.0)
    # a node on k such faces gets 1 / 2^k of its support from the particles: the mirrors add 2^k - 1 times that
    mirrors = share * (2.0 ** jnp.sum(layout.outflow_area != 0.0, axis=1) - 1.0)
    filled = jnp.clip(v_node / (FULL_FILL * 0.5 * cfg.grid.cell_size * area), 0.0, 1.0)
    traction = jnp.where(v_node > 0.0, share * filled * (p_node - reference), 0.0)
    force = traction[:, None] * layout.outflow_area
    return mpm.musl.NodalSource(mirrors * m_node, mirrors[:, None] * momentum, force, boundary=force)


def interface_source(prim_flat: dict, layout: Layout, static: Static, reference):
    """000 Eqs. (37)-(39): the ring cells as particles of mass rho V and stress -p I (their force, like the
    particles', from p - p_ref, ``reference`` the MPM step's reference pressure); plus the outflow
    gas of :func:`outflow_ghost` beyond box faces that lie on outflow faces of the domain. Returns the
    source as a function of the particles and their stencil, which the MUSL step calls with its own."""
    grid = static.mpm.grid
    d = grid.dim
    V = layout.ring_volume
    rho = prim_flat["rho"][layout.ring_cells]
    vel = prim_flat["velocity"][:, layout.ring_cells]
    p = prim_flat["pressure"][layout.ring_cells] - reference
    idx = layout.ring_idx.reshape(-1)

    def scatter(values):
        return jnp.zeros(grid.num_nodes, rho.dtype).at[idx].add(values.reshape(-1))

    w = layout.ring_w
    mass = scatter(w * (rho * V))
    mom = jnp.stack([scatter(w * (rho * V * vel[i])) for i in range(d)], axis=1)
    force = [scatter(layout.ring_grad[i] * (p * V)) for i in range(d)]
    if grid.axisymmetric:  # the hoop stress -p of the ring cells, as in the particles' r-momentum (mpm.musl)
        force[0] = force[0] + scatter(w * (p * V / layout.ring_radius))
    force = jnp.stack(force, axis=1)

    def source(P: mpm.Particles, idx, w) -> mpm.musl.NodalSource:
        ghost = outflow_ghost(P, layout, static, reference, (idx, w))
        return mpm.musl.NodalSource(mass + ghost.mass, mom + ghost.momentum, force + ghost.force, ghost.boundary)

    return source


def face_transfers(T, static: Static):
    """(nvar, F): the scheme's transfer through every face cell of the coupled faces, low to high side."""
    out = []
    for (axis, _side, plane), size in zip(static.faces, static.face_sizes):
        sl = [slice(None)]
        for a in range(len(static.euler.shape)):
            sl.append(plane if a == axis else slice(static.box_lo[a], static.box_hi[a]))
        out.append(T[axis][tuple(sl)].reshape(T[axis].shape[0], size))
    return jnp.concatenate(out, axis=1)


def cell_phases(prim_flat: dict, cells, eos, n: int):
    """The density and specific internal energy that every material's gas takes from ``cells`` (activation,
    inflow particles, the convective energy of a transfer). Returns (rho_k, e_k), lists of n arrays.

    Where the five-equation model's isobaric split is a physical state, each material takes its own phase:
    rho_k = (alpha_k rho_k) / alpha_k and e_k = (p - f_k(rho_k)) / (G_k rho_k) at the cell's pressure p (the
    Mie-Grueneisen form p = f(rho) + G rho e of :mod:`blastfsi.eos.jwl`). The particles then fill the cell's
    volume, carry its internal energy and have its pressure, all exactly: the blast crosses the bridge
    unchanged. The split is physical where every material makes up at least PRESENT of the cell's mass (a
    trace's phase density is the scheme's round-off, down to 1e-200 kg/m3) and no phase lies below zero
    internal energy, p >= f_k(rho_k): the products' principal (CJ) isentrope has e > 0 at every density and
    shocks and mixing only raise entropy, so products with e < 0 hold less entropy than the detonation gave
    them, a state of the scheme's diffused contact, not of the flow. Measured in steel-plate-blast (r-z,
    2.5 mm cells) 10 us after detonation, on the axis: the contact's mixed cells, 10 cells wide, held products
    at phase densities of 270-1150 kg/m3 (the core's, carried out by the diffusion of the volume fraction)
    with e down to -4.7e6 J/kg and, to make up the cell's energy, air at 0.2-0.9 kg/m3 with 1e8-1e10 J/kg;
    as particles that air kept 1e8-1e9 J/kg and, with |v| + c up to 27 km/s, set the step of the whole run
    at 1.5-4x below the steel's.

    Elsewhere every material takes the cell's density rho and shares its internal energy so that all are at
    one pressure p' = (rho e + sum_k Y_k f_k(rho) / G_k) / sum_k (Y_k / G_k) (Y_k the mass fractions: the
    mixture closure with every phase at the cell's density): e_k = (p' - f_k(rho)) / (G_k rho). Volume and
    internal energy stay exact; the pressure is p', not p (in a mixed cell p' < p where the dense products
    hold more of the mass than of the volume, sum_k Y_k / G_k > sum_k alpha_k / G_k). Given to every cell,
    this rule lowered the incident blast's impulse at he-slab-2d's gauge behind the bridge by 11.6 % against
    its mirror in the Eulerian air (4.8 % with the split where it is physical). Where p' <= 0 too (the cell's
    e < 0; 13 of 807 mixed bridge cells in the first 24 us of steel-plate-blast) no state at the cell's
    density gives every material a positive pressure, and every material takes the cell's e, which leaves
    air below zero pressure until the relaxation and the flow compress it: the split there stopped
    steel-plate-blast at 0.52 ms on a non-physical fictitious cell in the near vacuum behind the bridge."""
    rho, e = prim_flat["rho"][cells], prim_flat["internal_energy"][cells]
    rows = eos_rows(eos, n)
    y = [prim_flat["mass_fraction"][k][cells] for k in range(n)]
    present = jnp.all(jnp.stack([yk >= PRESENT for yk in y]), axis=0)
    own = [jnp.where(present, prim_flat["rho_k"][k][cells], rho) for k in range(n)]
    p = prim_flat["pressure"][cells]
    e_own = [(p - cold_pressure(r, row)) / (row.omega * r) for r, row in zip(own, rows)]
    split = present & jnp.all(jnp.stack([ek >= 0.0 for ek in e_own]), axis=0)
    p_even = mixture_pressure(rho * e, phase_sums([rho] * n, [yk * rho for yk in y], y, rows))
    e_even = [jnp.where(p_even > 0.0, (p_even - cold_pressure(rho, row)) / (row.omega * rho), e) for row in rows]
    return ([jnp.where(split, r, rho) for r in own],
            [jnp.where(split, eo, ee) for eo, ee in zip(e_own, e_even)])


def _add_to_cells(U, cells, mass_k, momentum, energy, volume_k, lay, volume):
    """Add per-entry content (mass per material (n, E), momentum (d, E), energy (E,), phase volume (n, E)) to the
    Eulerian cells ``cells`` (E,) (000 Eqs. 49-51) of volumes ``volume`` (N,); the products fraction becomes the
    volume-weighted mean of the cell's and the added gas (a scatter, entries may share a cell), each phase's
    volume floored at zero: renormalising a debt's removal (total volume below V) would multiply a products
    trace's round-off-level negative fraction by up to 2 every step, without bound."""
    flat = U.reshape(U.shape[0], -1)
    n, d = lay.n, lay.ndim
    V = volume[cells]
    new = [flat[k].at[cells].add(mass_k[k] / V) for k in range(n)]
    new += [flat[lay.mom + i].at[cells].add(momentum[i] / V) for i in range(d)]
    new += [flat[lay.energy].at[cells].add(energy / V)]
    if n == 2:
        added_p = jnp.zeros_like(flat[0]).at[cells].add(volume_k[0])
        added_a = jnp.zeros_like(flat[0]).at[cells].add(volume_k[1])
        products = jnp.maximum(flat[lay.alpha] * volume + added_p, 0.0)
        gas = products + jnp.maximum((1.0 - flat[lay.alpha]) * volume + added_a, 0.0)
        new += [jnp.where(gas > 0.0, products / jnp.where(gas > 0.0, gas, 1.0), flat[lay.alpha])]
    return jnp.stack(new).reshape(U.shape)


def receive(U, res: Reservoirs, budget: Budget, T, prim_flat, eos, static: Static, layout: Layout):
    """The scheme's transfers through the coupled faces (module docstring): inflow into the reservoirs;
    through an outflow face the Eulerian cell keeps the scheme's transfer and its convective part is booked
    as a debt of the face's reservoir, which the deleted particles repay (:func:`remove_leaving`); then
    :func:`_settle` hands the outflow reservoirs' balance to the Eulerian cells."""
    cfg = static.euler
    n, d = cfg.n_materials, len(cfg.shape)
    lay = row_layout(cfg)
    tf = face_transfers(T, static) * (layout.face_into * layout.face_measure)  # content into the box
    m_k = tf[:n]  # (n, F)
    inflow = jnp.sum(m_k, axis=0) > 0.0
    donor = jnp.where(inflow, layout.face_out, layout.face_in)
    u = prim_flat["velocity"][:, donor]  # (d, F)
    rho_k, e_k = cell_phases(prim_flat, donor, eos, n)
    ke = 0.5 * jnp.sum(u * u, axis=0)
    carried_mom = jnp.sum(m_k, axis=0)[None] * u
    carried_e = jnp.stack([m_k[k] * (e_k[k] + ke) for k in range(n)])  # (n, F)
    pressure = jnp.concatenate([jnp.sum(tf[lay.mom:lay.mom + d] - carried_mom, axis=1),
                                jnp.sum(tf[lay.energy] - jnp.sum(carried_e, axis=0))[None]])
    u3 = jnp.zeros((3,) + u.shape[1:], u.dtype).at[:d].set(u)
    res = res._replace(mass=res.mass + m_k.T, momentum=res.momentum + (m_k[:, None, :] * u3[None]).transpose(2, 0, 1),
                       energy=res.energy + carried_e.T)
    U, res = _settle(U, res, ~inflow, rho_k, lay, layout)  # (outflow faces: the donor is the bridge cell)
    return U, res, budget._replace(pressure_transfer=budget.pressure_transfer + pressure)


SETTLE_FRACTIONS = (1.0, 0.5, 0.25, 0.125)  # shares of an outflow reservoir's balance tried, largest first
#                                             (halvings; docs/theory/cfdmp.md, "Departures from the paper")


def _settle(U, res: Reservoirs, outflow, rho_k, lay, layout: Layout):
    """Move the balance of the outflow faces' reservoirs (debt of the scheme's convective transfer plus the
    deleted particles' content) into the Eulerian cells outside those faces; ``rho_k`` the densities each material
    takes from the donor (bridge) cells (:func:`cell_phases`), for the volume a settled material absent from
    the cell beyond takes.

    Particles cross a face one at a time, each carrying ~1/ppc^ndim of a bridge cell's mass, while the scheme
    transfers a little every step: settling each step's debt at once (before the particle that repays it has
    crossed) can take more than the cell holds when a strong shock leaves the box. So a cell takes the largest
    share in SETTLE_FRACTIONS (halvings: each refusal halves the step's share, down to 1/8) that leaves it at
    least half of its density and of its internal energy density; the rest waits in the reservoir for the next
    particles. Mass, momentum and energy move together (budget exact). docs/theory/cfdmp.md, "Departures from
    the paper"."""
    flat = U.reshape(U.shape[0], -1)
    n, d = lay.n, lay.ndim
    cells = layout.face_out
    V = layout.cell_volume[cells]
    mass = jnp.sum(res.mass, axis=1)  # (F,)
    mom = jnp.sum(res.momentum, axis=1)[:, :d]  # (F, d)
    energy = jnp.sum(res.energy, axis=1)
    rho0 = sum(flat[k][cells] for k in range(n))
    mom0 = jnp.stack([flat[lay.mom + i][cells] for i in range(d)], axis=1)
    e0 = flat[lay.energy][cells]

    def internal(rho, m, E):
        return E - 0.5 * jnp.sum(m * m, axis=1) / jnp.where(rho > 0.0, rho, 1.0)

    i0 = internal(rho0, mom0, e0)
    share = jnp.zeros_like(mass)
    for f in SETTLE_FRACTIONS[::-1]:  # the largest acceptable share wins
        rho = rho0 + f * mass / V
        ok = (rho >= 0.5 * rho0) & (internal(rho, mom0 + f * mom / V[:, None], e0 + f * energy / V) >= 0.5 * i0)
        share = jnp.where(ok, f, share)
    share = jnp.where(outflow, share, 0.0)
    moved_m = share[:, None] * res.mass  # (F, n)
    moved_p = share[:, None, None] * res.momentum
    moved_e = share[:, None] * res.energy
    if n == 2:
        given_m, vol_k = _two_phase_split(moved_m, [flat[k][cells] for k in range(n)], flat[lay.alpha][cells], V,
                                          rho_k)
    else:
        given_m, vol_k = moved_m, None  # (one material: no volume fraction to update)
    U = _add_to_cells(U, cells, given_m.T, jnp.sum(moved_p, axis=1)[:, :d].T, jnp.sum(moved_e, axis=1), vol_k,
                      lay, layout.cell_volume)
    return U, res._replace(mass=res.mass - moved_m, momentum=res.momentum - moved_p, energy=res.energy - moved_e)


def _two_phase_split(moved_m, partial, alpha, V, rho_donor):
    """Per-material masses (F, 2) and phase volumes (2, F) that settled balances ``moved_m`` (F, 2) give the
    cells of partial densities ``partial`` (2 arrays (F,)), products fraction ``alpha`` and volumes ``V``.

    A reservoir's balance per material is the difference between the scheme's transfer (with the bridge
    cell's composition) and the content of the particles deleted so far: where the two disagree (a mixing
    layer leaving the box), one material's balance is a debt larger than what the cell beyond the face still
    holds of it. Taken as it stood it can drive that cell's partial density and products fraction below zero
    (then c^2 < 0 in that cell). So a debt takes at most half of the cell's
    partial density of its material, and the rest of it is taken from the other material: the settled
    total mass, momentum and energy are unchanged (the budget books the materials' sum); only the split
    between products and air moves, by at most the scheme's composition mismatch.

    Volumes: a debt leaves with its share of its material's volume (m_k / (alpha_k rho_k V) of alpha_k V), so
    both stay positive and that material's phase density is unchanged; an addition takes the phase density
    of its material in the cell where that material makes up at least PRESENT of the cell's mass (adding
    at the cell's own phase densities scales both phases alike), else the bridge cell's ``rho_donor``."""
    rho = partial[0] + partial[1]
    alphas = (alpha, 1.0 - alpha)
    beyond = [jnp.minimum(moved_m[:, k] + 0.5 * jnp.maximum(partial[k], 0.0) * V, 0.0) for k in range(2)]
    given = jnp.stack([moved_m[:, 0] - beyond[0] + beyond[1], moved_m[:, 1] - beyond[1] + beyond[0]], axis=1)
    vol = []
    for k in range(2):
        m, q, a = given[:, k], partial[k], alphas[k]
        holds = (q > 0.0) & (a > 0.0)
        own = jnp.where(holds, q / jnp.where(holds, a, 1.0), 1.0)  # the cell's phase density
        trusted = holds & (q >= PRESENT * rho)
        taken = jnp.where(holds, m / own, 0.0)
        added = jnp.where(m != 0.0, m / jnp.where(trusted, own, rho_donor[k]), 0.0)
        vol.append(jnp.where(m < 0.0, taken, added))
    return given, jnp.stack(vol)


def boundary_outflow(T, static: Static, layout: Layout):
    """Mass per material, momentum and energy that left the Eulerian-only cells through domain faces."""
    cfg = static.euler
    n, d = cfg.n_materials, len(cfg.shape)
    lay = row_layout(cfg)
    rows = list(range(n)) + list(range(lay.mom, lay.mom + d)) + [lay.energy]
    out = 0.0
    for axis in range(d):
        t = T[axis][jnp.asarray(rows)]
        lo, hi = jnp.take(t, 0, axis=1 + axis), jnp.take(t, cfg.shape[axis], axis=1 + axis)
        a_lo, a_hi = layout.boundary_measure[axis]
        red = tuple(range(1, lo.ndim))
        out = out + jnp.sum(hi * a_hi, axis=red) - jnp.sum(lo * a_lo, axis=red)
    return out


def particle_content(P: mpm.Particles):
    """(mass, momentum (n, 3), total energy) of every particle."""
    ke = 0.5 * row_sum(P.v * P.v)
    return P.mass, P.mass[:, None] * P.v, P.mass * (P.point.energy + ke)


CUT_TOLERANCE = 1.0e-6  # share of a particle's width beyond a box face below which it is not cut (:func:`_cut`):
#                         far above the round-off of its position (~1e-16 of it), far below what the overlap
#                         could matter (the ring cell beyond counts 1e-6 of a particle twice at most)


def _cut(x, half, lo, hi, axis: int, side: int, axisymmetric: bool):
    """One face of the box, ``axis`` and ``side`` (0 lower, 1 upper): per particle the share of its mass
    beyond the face, and its centre and half-size along ``axis`` once cut to the part inside.

    A particle occupies [x - l, x + l] per direction (l its GIMP half-size). The fraction
    phi = clip((x + l - hi) / 2l, 0, 1) of it lies beyond an upper face (lower face mirrored); on the radial
    axis of an r-z grid its mass share is that of the ring, ((x + l)^2 - hi^2) / ((x + l)^2 - (x - l)^2).
    The part inside, [x - l, hi], is the new domain: centre hi - l', half-size l' = (1 - phi) l.

    A particle is cut only when more than CUT_TOLERANCE of its width lies beyond the face. A cut particle
    cannot grow back when it moves in again, so cutting the round-off overlap of a particle that touches the
    face (the box's lattice fills it to the face) pumps the box's gas into the face's reservoir at every
    round-off oscillation: gas at rest then ran away at 1.003-1.005 per step (a 2D cfdmp box of air at 1 bar,
    Eulerian cfl 0.38 to 0.5; tests/test_mpm_gas.py)."""
    l = half[:, axis]
    past = (x[:, axis] + l - hi[axis]) if side == 1 else (lo[axis] - x[:, axis] + l)
    phi = jnp.clip(past / jnp.where(l > 0.0, 2.0 * l, 1.0), 0.0, 1.0)
    phi = jnp.where(phi > CUT_TOLERANCE, phi, 0.0)
    if axisymmetric and axis == 0:  # ring particles: the share of the ring's mass, r dr
        inner, outer = x[:, 0] - l, x[:, 0] + l
        span = jnp.where(l > 0.0, outer ** 2 - inner ** 2, 1.0)
        edge = hi[0] if side == 1 else lo[0]
        mass_phi = jnp.clip(((outer ** 2 - edge ** 2) if side == 1 else (edge ** 2 - inner ** 2)) / span, 0.0, 1.0)
    else:
        mass_phi = phi
    l_in = (1.0 - phi) * l
    cut = phi > 0.0
    centre = jnp.where(cut, (hi[axis] - l_in) if side == 1 else (lo[axis] + l_in), x[:, axis])
    return jnp.where(cut, mass_phi, 0.0), centre, jnp.where(cut, l_in, l)


def cut_at_coupled_faces(x, half, lo, hi, static: Static):
    """Gas particles straddling a coupled face, cut at it (:func:`_cut`): per particle (share of it beyond the
    face, index of that face cell or -1, centre and half-size of the part inside (n, d), index of the face cell
    whose face the part inside touches or -1).

    The share beyond leaves to the face cell's reservoir and the particle keeps the part inside. So the
    particles never overlap the ring cells beyond the face, which stand for that gas on the interface nodes
    (000 Eqs. 37-39), and the gas leaves at the rate it crosses the face instead of one particle at a time
    (docs/theory/cfdmp.md)."""
    d = static.mpm.grid.dim
    h = static.mpm.grid.cell_size
    share = jnp.zeros(x.shape[:1], x.dtype)
    face = jnp.full(x.shape[:1], -1, jnp.int32)
    touching = jnp.full(x.shape[:1], -1, jnp.int32)
    first = 0
    for (axis, side, _plane), size in zip(static.faces, static.face_sizes):
        lateral = jnp.zeros(x.shape[:1], jnp.int32)
        for a in range(d):
            if a == axis:
                continue
            n_a = static.box_hi[a] - static.box_lo[a]
            i = jnp.clip(jnp.floor((x[:, a] - lo[a]) / h).astype(jnp.int32), 0, n_a - 1)
            lateral = lateral * n_a + i
        phi, centre, l_in = _cut(x, half, lo, hi, axis, side, static.mpm.grid.axisymmetric)
        x, half = x.at[:, axis].set(centre), half.at[:, axis].set(l_in)
        face = jnp.where(phi > 0.0, first + lateral, face)
        share = 1.0 - (1.0 - share) * (1.0 - phi)  # (cut at two faces: a corner)
        gap = (x[:, axis] - l_in - lo[axis]) if side == 0 else (hi[axis] - x[:, axis] - l_in)
        touching = jnp.where(gap <= CUT_TOLERANCE * 2.0 * l_in, first + lateral, touching)
        first += size
    return share, face, x, half, touching


def cut_at_outflow_faces(x, half, lo, hi, static: Static):
    """Particles straddling a box face that lies on an outflow face of the domain, cut at it (:func:`_cut`):
    per particle (share of it beyond the face, centre and half-size of the part inside). The share beyond
    leaves the run. Particles leaving whole once their centre crossed would hold back a uniform outflow: a
    particle half beyond the face no longer pushes the face nodes with its outer half while the mirror's
    traction (:func:`outflow_ghost`) still pushes them back with the whole pressure, so the outflow would
    stagnate at the face, nearly as at a wall."""
    share = jnp.zeros(x.shape[:1], x.dtype)
    for axis, side in static.outflow_faces:
        phi, centre, l_in = _cut(x, half, lo, hi, axis, side, static.mpm.grid.axisymmetric)
        x, half = x.at[:, axis].set(centre), half.at[:, axis].set(l_in)
        share = 1.0 - (1.0 - share) * (1.0 - phi)
    return share, x, half


def _stalled(P: mpm.Particles, slot, touching, res: Reservoirs, candidates):
    """Gas particles that still touch a coupled face (``touching``, :func:`cut_at_coupled_faces`) while an inflow
    particle of their material grows at that face cell (:func:`feed`), and are not that inflow particle: gas
    that entered earlier and has not left the layer the new gas enters. Where the flow stalls at the face (the
    rarefied gas between a charge and a plate after the blast has passed), :func:`feed` would otherwise place
    inflow particle after inflow particle over them, each with the bridge cell's density: steel-plate-blast
    piled up to 420 particles in one face cell, whose volumes m / rho added up to 550 times the cell's, so
    their pressure never rose to push them off the face and the pool grew from 17 000 to 32 000 particles.
    :func:`remove_leaving` hands them whole to the face's reservoir, which :func:`feed` adds to the inflow
    particle (compressed where the layer overfills). None stall without a coupled face (MPM everywhere)."""
    if res.buffer.shape[0] == 0:
        return jnp.zeros_like(candidates)
    n = res.buffer.shape[1]
    cap = P.active.shape[0]
    k = jnp.clip(slot, 0, n - 1)
    f = jnp.clip(touching, 0, res.buffer.shape[0] - 1)
    alive = (res.buffer >= 0) & P.active[jnp.clip(res.buffer, 0, cap - 1)]  # (F, n) inflow particles growing
    own = jnp.arange(cap, dtype=res.buffer.dtype)
    return candidates & (touching >= 0) & (slot >= 0) & alive[f, k] & (res.buffer[f, k] != own)


def remove_leaving(state: mpm.State, res: Reservoirs, budget: Budget, static: Static, layout: Layout):
    """Gas leaving the box. At a coupled face the part of a particle beyond it leaves
    (:func:`cut_at_coupled_faces`) with its share of the particle's mass, momentum and energy, which goes to
    the reservoir of the face cell (000 Eqs. 49-51; :func:`receive` settles it into the Eulerian cell); at a
    face on an outflow face of the domain the part beyond leaves the run (:func:`cut_at_outflow_faces`,
    ``boundary_out``); the particle keeps the part inside and is deleted once wholly beyond. Gas stalled at a
    coupled face (:func:`_stalled`) goes whole to the face's reservoir. A gas particle
    whose centre is still outside after the cuts (through a wall face) leaves the run whole. Structure
    fragments leave the run through any face (the grid holds no solid outside the box): their momentum and
    energy are booked in ``boundary_out``, their mass in ``structure_out``."""
    P = state.particles
    d = static.mpm.grid.dim
    n = len(static.gas_material)
    slot = _gas_index(static, P.material)
    lo, hi = layout.box_lower[:d], layout.box_upper[:d]
    x0, half0 = P.x[:, :d], P.half_size[:, :d]
    outside = P.active & jnp.any((x0 < lo) | (x0 > hi), axis=1)
    gas = P.active & (slot >= 0)
    share, face, x1, half1, touching = cut_at_coupled_faces(x0, half0, lo, hi, static)
    to_euler = gas & (face >= 0) & (share > 0.0)
    x1, half1 = jnp.where(to_euler[:, None], x1, x0), jnp.where(to_euler[:, None], half1, half0)
    out_share, x2, half2 = cut_at_outflow_faces(x1, half1, lo, hi, static)
    leaving = gas & (out_share > 0.0)
    x2, half2 = jnp.where(leaving[:, None], x2, x1), jnp.where(leaving[:, None], half2, half1)
    fragment = outside & (slot < 0)
    gone = (gas & ~jnp.all((x2 >= lo) & (x2 <= hi), axis=1)) | fragment  # whole, out of the run
    to_euler, leaving = to_euler & ~gone, leaving & ~gone
    stalled = _stalled(P, slot, touching, res, gas & ~gone & ~leaving)
    to_euler, face = to_euler | stalled, jnp.where(stalled, touching, face)
    to_reservoir = jnp.where(stalled, 1.0, jnp.where(to_euler, share, 0.0))  # shares of each particle's content
    to_boundary = jnp.where(gone, 1.0, jnp.where(leaving, (1.0 - to_reservoir) * out_share, 0.0))
    mass, mom, energy = particle_content(P)
    at = (jnp.where(to_euler, face, layout.face_out.shape[0]), jnp.clip(slot, 0, n - 1))  # (that index is dropped)
    res = res._replace(mass=res.mass.at[at].add(to_reservoir * mass, mode="drop"),
                       momentum=res.momentum.at[at].add(to_reservoir[:, None] * mom, mode="drop"),
                       energy=res.energy.at[at].add(to_reservoir * energy, mode="drop"))
    left = jnp.concatenate([jnp.stack([jnp.sum(jnp.where(slot == j, to_boundary * mass, 0.0)) for j in range(n)]),
                            jnp.sum(to_boundary[:, None] * mom, axis=0)[:d],
                            jnp.sum(to_boundary * energy)[None]])
    keep = 1.0 - to_reservoir - to_boundary
    whole = (to_euler | leaving) & (keep <= 0.0)
    P = P._replace(active=P.active & ~gone & ~whole, mass=P.mass * keep, volume0=P.volume0 * keep,
                   x=P.x.at[:, :d].set(x2), half_size=P.half_size.at[:, :d].set(half2))
    return state._replace(particles=P), res, budget._replace(
        boundary_out=budget.boundary_out + left, structure_out=budget.structure_out + jnp.sum(jnp.where(
            fragment, mass, 0.0)))


def feed(state: mpm.State, res: Reservoirs, budget: Budget, prim_flat, eos, params: mpm.Params, static: Static,
         layout: Layout):
    """Move the reservoirs' content into the inflow particles (module docstring, Eqs. 45-48).

    Each face cell and material has one *inflow particle* that represents the gas entered through it since
    the last release: the layer next to the face, of thickness m / (rho A) (A the face's area), spanning the face cell
    (GIMP half-sizes: half the thickness normal to the face, h/2 along it), with the bridge cell's density
    (:func:`cell_phases`; the density m / (A h) that fills the face cell where that is more), the mass-weighted
    velocity and the internal energy left by the total energy (Eq. 48
    generalised: e = E/m - |v|^2/2; where that is negative, e = 0 and the deficit stays in the reservoir),
    stress -p I from its EOS. It is released to move with the MPM solution
    once it is as thick as a gas particle (h / ppc), and the next one starts at the face; so no gap opens
    between the face and the gas inside.
    """
    cfg, grid = static.euler, static.mpm.grid
    d, h, ppc = grid.dim, grid.cell_size, static.ppc
    n = cfg.n_materials
    P = state.particles
    cap = P.mass.shape[0]
    gm = jnp.asarray(static.gas_material, jnp.int32)
    rho = jnp.stack(cell_phases(prim_flat, layout.face_in, eos, n)[0], axis=1)  # (F, n)
    b = jnp.clip(res.buffer, 0, cap - 1)
    near = jnp.all(jnp.abs(P.x[b] - layout.face_centre[:, None, :]) <= 1.01 * h, axis=-1)  # slot not reused
    has = (res.buffer >= 0) & P.active[b] & (P.material[b] == gm[None, :]) & near
    m_old = jnp.where(has, P.mass[b], 0.0)
    v_old = jnp.where(has[..., None], P.v[b], 0.0)
    e_old = jnp.where(has, P.point.energy[b], 0.0)
    # a material feeds its inflow particle once the reservoir holds a meaningful share of a gas particle's
    # mass and the bridge cell holds at least PRESENT of it (numerical diffusion leaves traces down to
    # ~1e-200 kg); traces wait in the reservoir
    m_gas = prim_flat["rho"][layout.face_in] * layout.face_measure / ppc ** d
    present = jnp.stack([prim_flat["mass_fraction"][k][layout.face_in] for k in range(n)], axis=1) >= PRESENT
    fed = (res.mass >= FEED_FRACTION * m_gas[:, None]) & present
    fed = fed | (has & (res.mass > 0.0))
    m = m_old + jnp.where(fed, res.mass, 0.0)
    safe = jnp.where(m > 0.0, m, 1.0)
    v = (m_old[..., None] * v_old + jnp.where(fed[..., None], res.momentum, 0.0)) / safe[..., None]
    e = ((m_old * (e_old + 0.5 * jnp.sum(v_old * v_old, axis=-1)) + jnp.where(fed, res.energy, 0.0)) / safe
         - 0.5 * jnp.sum(v * v, axis=-1))
    # a reservoir that took debts (outflow) between inflows can hold less energy than its momentum's kinetic
    # energy: the particle gets e = 0 and the deficit m e < 0 stays in the reservoir for the next inflow
    deficit = jnp.where(fed, jnp.minimum(e, 0.0) * m, 0.0)
    e = jnp.maximum(e, 0.0)
    area = (layout.face_measure / h)[:, None]  # (h^(ndim-1) on Cartesian grids, the ring's 2 pi r h on r-z ones)
    # more gas than the bridge cell's density fits into the face cell's layer (it is stalled at the face,
    # :func:`_stalled`): the inflow particle is compressed to fill the cell, so its pressure rises
    rho = jnp.maximum(rho, m / (area * h))
    thick = jnp.clip(m / (rho * area), 0.0, h)
    x = layout.face_centre[:, None, :] + layout.face_axis[:, None, :] * (0.5 * thick)[..., None]
    half = jnp.abs(layout.face_axis)[:, None, :] * (0.5 * thick)[..., None]
    half = half + jnp.sum(jnp.abs(layout.face_lateral), axis=1)[:, None, :] * (0.5 * h)
    rows = eos_rows(eos, n)
    material = jnp.broadcast_to(gm[None, :], m.shape)
    pressure = jnp.stack([jwl.pressure(rho[:, k], e[:, k], rows[k]) for k in range(n)], axis=1)

    def flat(a):
        return a.reshape((-1,) + a.shape[2:])

    zero = jnp.zeros(flat(m).shape, m.dtype)
    hist = P.point.history.shape[1]
    point = PointState(stress=jnp.stack([-flat(pressure)] * 3 + [zero] * 3, axis=1), density=flat(rho),
                       energy=flat(e), plastic_strain=zero, damage=zero, history=jnp.zeros((zero.shape[0], hist),
                                                                                           zero.dtype))
    batch = mpm.Particles(x=flat(x), v=flat(v), mass=flat(safe), volume0=flat(safe) / flat(rho), half_size=flat(half),
                          material=flat(material), active=flat(fed & ~has), point=point, q=zero, vol_rate=zero,
                          wave_speed=zero, plastic_work=zero, prescribed=jnp.zeros(zero.shape + (3,), bool),
                          prescribed_velocity=jnp.zeros_like(flat(x)), surface_load=jnp.zeros_like(flat(x)))
    batch = batch._replace(wave_speed=wave_speed(batch.point, batch.material, params, static.mpm))
    pool, required, slots = mpm.add_particles_at(P, batch, static.n_structure, static.pool_parts)
    fits = required <= cap
    # grow the existing inflow particles in place
    grow = flat(fed & has) & fits
    idx = jnp.where(grow, flat(b), cap)
    pool = jax.tree_util.tree_map(lambda p, q: p.at[idx].set(q, mode="drop"), pool, batch._replace(
        active=jnp.ones_like(batch.active), volume0=pool.volume0[flat(b)]))
    buffer = jnp.where(flat(fed & ~has), slots, flat(jnp.where(has, res.buffer, -1))).reshape(m.shape)
    buffer = jnp.where(fits, buffer, res.buffer)
    released = thick >= h / ppc
    buffer = jnp.where(released & fits, -1, buffer).astype(jnp.int32)
    keep = ~fits | ~fed
    res = Reservoirs(mass=jnp.where(keep, res.mass, 0.0), momentum=jnp.where(keep[..., None], res.momentum, 0.0),
                     energy=jnp.where(keep, res.energy, deficit), buffer=buffer)
    budget = budget._replace(required=required.astype(jnp.int32))
    return state._replace(particles=pool), res, budget


def activate(U, state: mpm.State, prim_flat, eos, params: mpm.Params, static: Static, layout: Layout):
    """The gas of the box becomes particles (000 Sec. 3, activation): one particle per lattice point and
    material present (at least PRESENT of the cell's mass), mass = partial density x lattice volume, the
    cell's velocity, density and specific internal energy (:func:`cell_phases`; so the cell's mass, momentum,
    energy and volume carry over exactly). Returns the new state and the number of active particles
    needed."""
    cfg, d = static.euler, static.mpm.grid.dim
    n = cfg.n_materials
    cell = layout.gas_cell
    flat = U.reshape(U.shape[0], -1)[:, cell]  # (nvar, G)
    rho_k, e_k = cell_phases(prim_flat, cell, eos, n)
    u = prim_flat["velocity"][:, cell]  # (d, G)
    G = cell.shape[0]
    mass = jnp.stack([flat[k] * layout.gas_volume for k in range(n)])  # (n, G)
    cell_mass = jnp.sum(mass, axis=0)
    present = mass >= PRESENT * cell_mass[None]  # traces stay behind (booked as displaced)
    rho = jnp.where(present, jnp.stack(rho_k), 1.0)
    energy = jnp.stack(e_k)
    material = jnp.broadcast_to(jnp.asarray(static.gas_material, jnp.int32)[:, None], (n, G))
    rows = eos_rows(eos, n)
    pressure = jnp.stack([jwl.pressure(rho[k], energy[k], rows[k]) for k in range(n)])
    zero = jnp.zeros(n * G, U.dtype)
    hist = state.particles.point.history.shape[1]
    point = PointState(stress=jnp.stack([-pressure.reshape(-1)] * 3 + [zero] * 3, axis=1), density=rho.reshape(-1),
                       energy=energy.reshape(-1), plastic_strain=zero, damage=zero,
                       history=jnp.zeros((n * G, hist), U.dtype))
    vel = jnp.zeros((n, G, 3), U.dtype).at[:, :, :d].set(jnp.broadcast_to(u.T[None], (n, G, d)))
    x = jnp.broadcast_to(layout.gas_x[None], (n, G, 3)).reshape(-1, 3)
    half = jnp.broadcast_to(layout.gas_half[None], (n, G, 3)).reshape(-1, 3)
    m = jnp.where(present, mass, 0.0).reshape(-1)
    batch = mpm.Particles(x=x, v=vel.reshape(-1, 3), mass=jnp.where(m > 0.0, m, 1.0),
                          volume0=jnp.where(m > 0.0, m, 1.0) / rho.reshape(-1), half_size=half,
                          material=material.reshape(-1), active=present.reshape(-1), point=point, q=zero,
                          vol_rate=zero, wave_speed=zero, plastic_work=zero, prescribed=jnp.zeros((n * G, 3), bool),
                          prescribed_velocity=jnp.zeros_like(half), surface_load=jnp.zeros_like(half))
    batch = batch._replace(wave_speed=wave_speed(batch.point, batch.material, params, static.mpm))
    pool, required = mpm.add_particles(state.particles, batch, static.n_structure, static.pool_parts)
    return state._replace(particles=pool), required
