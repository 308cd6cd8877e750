"""Initial data and the coupling layout of the ``cfdmp`` method (host side, NumPy; seed 000 Sec. 3).

Composition, not duplication: the Eulerian part is :func:`blastfsi.euler.problem.build_gas`
on the same domain, grid and initial condition; the structures are placed by
:func:`blastfsi.mpm.problem.place` on the MPM background grid. This module adds
the coupling layout (cell indices in the Eulerian grid, C order):

* the MPM box ``[box_lo, box_hi)`` in cells; a face of it not on the domain
  boundary is *coupled*; the MPM background grid is the box plus one ring of
  cells outward on coupled sides (their centres are the Eulerian "particles" of
  000 Eqs. 37-39 for the interface nodes on the box faces);
* ``fictitious``: box cells beyond the bridge, whose Eulerian values come from
  the particles (000 Eqs. 31-36); ``outside``: the Eulerian-only cells;
* per face cell of every coupled face (lateral cells of the box face): the
  Eulerian cell outside, the bridge cell inside, the index of the face in the
  scheme's transfer arrays, and the direction into the box;
* the gas lattice of the box (``gas_particles_per_cell`` per cell and
  direction, points inside structures left out) that the gas becomes at activation.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from blastfsi import mpm, xla
from blastfsi.cfdmp import coupling as cp_kernels
from blastfsi.cfdmp.scenario import FICTITIOUS_DEPTH, CfdmpScenario
from blastfsi.constitutive import get as get_model
from blastfsi.euler import geometry
from blastfsi.euler.config import Config as EulerConfig
from blastfsi.euler.method import GEOMETRY_CODE
from blastfsi.euler.scenario import gas_materials
from blastfsi.euler import problem as euler_problem
from blastfsi.mpm import problem as mpm_problem
from blastfsi.scenario import AXES, ScenarioError


@dataclass(frozen=True)
class Face:
    """One coupled face of the box: axis, side (0 lower, 1 upper) and its face cells."""

    axis: int
    side: int
    plane: int  # index of the face plane among the faces of that axis (0 .. shape[axis])
    lateral: tuple  # index arrays of the face cells' lateral positions (one per other axis)
    outside: np.ndarray  # flat Eulerian index of the cell outside the box
    bridge: np.ndarray  # flat Eulerian index of the bridge cell inside
    centre: np.ndarray  # (F, ndim) centre of each face cell's face [m]
    measure: np.ndarray  # (F,) dx times each face cell's face area (geometry.face_measures)

    @property
    def into_box(self) -> float:
        """+1 when the face's positive direction points into the box (lower face), -1 otherwise."""
        return 1.0 if self.side == 0 else -1.0


@dataclass(frozen=True)
class Coupling:
    """What the coupled step reads of the scenario besides the geometry, typed; each value is checked once,
    by the scenario model (``numerics``, ``mpm_region``) or by :func:`build`."""

    structure_particles: int  # the structures' particles: the first slots of the pool, never deleted
    gas_particles_per_cell: int  # per axis, in the box's gas lattice (mpm_region.gas_particles_per_cell)
    bridge_cells: int  # width of the bridge region in cells (mpm_region.bridge_cells)
    shape_functions: str  # numerics.shape ("linear" or "gimp")
    clamped: bool  # some structure has supports (prescribed-velocity particles)
    pic_fraction: tuple  # per MPM material: numerics.gas_pic_fraction for the gases, 0 for the structures
    pressure_relaxation: bool  # numerics.pressure_relaxation (mixed gas particles relaxed to one pressure)
    mpm_cfl: float  # numerics.cfl of the MPM step
    q_quadratic: float  # numerics.q_quadratic, artificial bulk viscosity of the particles
    q_linear: float  # numerics.q_linear
    mpm_reference_pressure: float  # numerics.reference_pressure [Pa]
    activation_overpressure: float  # mpm_region.activation_overpressure [Pa]: starts the coupling (0: at once)
    capacity_grows: bool  # the pool grows when full (numerics.capacity not set and some face coupled)
    pool_margin: int  # a growing pool is full when fewer slots are free than one step can fill
    activation_particles: int  # the structures' and the box's initial gas particles: what activation makes
    tracers: tuple  # structure particle of each output.tracers point
    coupled_faces: tuple  # "lower x", "upper y", ... the box faces coupled to the Eulerian grid


@dataclass(frozen=True)
class Setup:
    euler: euler_problem.Setup
    grid: mpm.Grid  # MPM background grid
    materials: tuple  # MPM material names (structures first, then the gases)
    models: tuple
    model_params: tuple
    gas_material: tuple  # MPM material index of each Eulerian material (products, air)
    structures: mpm.Particles  # active structure particles (host batch), may be empty
    body: np.ndarray  # body index of each structure particle
    capacity: int
    devices: int  # numerics.devices: the pool is split over them in equal parts (capacity a multiple of it)
    box_lo: tuple
    box_hi: tuple
    faces: tuple  # Face per coupled face
    fictitious: np.ndarray  # bool mask over the Eulerian grid
    parked: np.ndarray  # bool: fictitious cells beyond the FICTITIOUS_DEPTH the scheme reads
    outside: np.ndarray  # bool mask over the Eulerian grid: the Eulerian-only region
    ring_cells: np.ndarray  # (n,) flat Eulerian index of each ring point's cell (outside the box, inside the MPM grid)
    ring_x: np.ndarray  # (n, 3) the ring points: cell centres (Cartesian) or the gas lattice in each cell (r-z)
    ring_volume: np.ndarray  # (n,) their volumes
    ring_half: np.ndarray  # (n, 3) their GIMP half-sizes
    cell_volume: np.ndarray  # (N,) volume of every Eulerian cell (C order; rings on an r-z grid)
    gas_x: np.ndarray  # (n_gas, 3) gas lattice positions
    gas_volume: np.ndarray  # (n_gas,)
    gas_half: np.ndarray  # (n_gas, 3) GIMP half-sizes
    gas_cell: np.ndarray  # (n_gas,) flat Eulerian cell of each lattice point
    boundary_measure: tuple  # per axis (lower, upper): face measures over that domain face where the cell inside
    #                          is Eulerian-only, else 0 (their transfers are the run's boundary exchange)
    outflow_area: np.ndarray  # (num_nodes, ndim) -n A on MPM nodes of box faces on outflow domain faces
    coupling: Coupling

    @property
    def cells(self) -> int:
        return self.euler.cells

    @property
    def gauges(self):
        return self.euler.gauges


def _cell_index(sc: CfdmpScenario, value: float, ax: int, dx: float, key: str) -> int:
    n = (value - sc.domain.lower[ax]) / dx
    if abs(n - round(n)) > 1e-6:
        raise ScenarioError(f"{key}[{AXES[ax]}] = {value:g} m must lie on a cell face (cells of {dx:g} m from "
                            f"domain.lower[{AXES[ax]}] = {sc.domain.lower[ax]:g} m)")
    return int(round(n))


def _gas_part(sc: CfdmpScenario) -> euler_problem.GasPart:
    """The whole-domain Eulerian grid's keys. A charge's automatic remap time must also come before the blast
    reaches the MPM box: its point nearest to the charge is added as a last gauge (dropped again by
    :func:`build`)."""
    output = sc.output
    if sc.initial.kind == "charge" and sc.initial.remap_time is None:
        centre = np.asarray(sc.initial.center or [0.0] * sc.domain.ndim, float)
        nearest = np.clip(centre, sc.mpm_region.lower, sc.mpm_region.upper)
        if np.any(nearest != centre):  # (a charge inside the box: MPM everywhere, the gauges set the time)
            output = output.model_copy(update={"gauges": list(output.gauges) + [nearest.tolist()]})
    return euler_problem.GasPart(
        sc.domain, sc.boundaries, sc.grid, sc.initial,
        {k: v for k, v in sc.materials.items() if k in gas_materials(sc.initial)}, sc.time, output,
        sc.numerics.euler_cfl or sc.numerics.cfl)  # (euler_cfl > 0 when set)


def build(sc: CfdmpScenario, devices: int = 1) -> Setup:
    """The set-up of ``sc``; ``devices``: the particle pool is split over that many devices in equal parts, so
    its capacity is rounded up to a multiple of it."""
    gas = _gas_part(sc)
    g = euler_problem.grid_geometry(gas)  # (the grid's layout first: the structures are checked before a
    #                                       charge's 1D detonation runs)
    nd, dx, shape = g.ndim, g.dx, g.shape
    box = sc.mpm_region
    lo = tuple(_cell_index(sc, v, ax, dx, "mpm_region.lower") for ax, v in enumerate(box.lower))
    hi = tuple(_cell_index(sc, v, ax, dx, "mpm_region.upper") for ax, v in enumerate(box.upper))
    coupled = [(lo[ax] > 0, hi[ax] < shape[ax]) for ax in range(nd)]
    for ax in range(nd):
        for side in (0, 1):
            if getattr(sc.boundaries, AXES[ax])[side] == "blast" and not coupled[ax][side]:
                raise ScenarioError(f"mpm_region: the box reaches the {('lower', 'upper')[side]} {AXES[ax]} face of "
                                    "the domain, a 'blast' face (fed by the charge's 1D blast); keep it inside")
    w = box.bridge_cells
    for ax in range(nd):
        need = w * sum(coupled[ax]) + FICTITIOUS_DEPTH
        if any(coupled[ax]) and hi[ax] - lo[ax] < need:
            raise ScenarioError(f"mpm_region: the box is {hi[ax] - lo[ax]} cells wide along {AXES[ax]}, too narrow "
                                f"for bridges of mpm_region.bridge_cells = {w} on {sum(coupled[ax])} face(s) plus "
                                f"{FICTITIOUS_DEPTH} fictitious cells; need >= {need} cells")
    g_lo = tuple(lo[ax] - int(coupled[ax][0]) for ax in range(nd))
    g_hi = tuple(hi[ax] + int(coupled[ax][1]) for ax in range(nd))
    kinds = []
    for ax in range(nd):
        pair = []
        for side in (0, 1):
            face = getattr(sc.boundaries, AXES[ax])[side]
            pair.append("free" if coupled[ax][side] or face == "outflow" else "slip")
        kinds.append(tuple(pair))
    axisymmetric = g.geometry == "axisymmetric"
    grid = mpm.Grid(origin=tuple(g.lower[ax] + g_lo[ax] * dx for ax in range(nd)), cell_size=dx,
                    cells=tuple(g_hi[ax] - g_lo[ax] for ax in range(nd)), boundaries=tuple(kinds),
                    axisymmetric=axisymmetric)
    # the bridge and fictitious cells; structures must stay beyond the cells the bridge reads
    idx = np.indices(shape)
    in_box = np.ones(shape, bool)
    core = np.ones(shape, bool)  # box cells beyond the bridges
    clear = np.ones(shape, bool)  # box cells beyond bridge + fictitious depth
    for ax in range(nd):
        i = idx[ax]
        in_box &= (i >= lo[ax]) & (i < hi[ax])
        c_lo, c_hi = lo[ax] + w * coupled[ax][0], hi[ax] - w * coupled[ax][1]
        core &= (i >= c_lo) & (i < c_hi)
        clear &= (i >= c_lo + FICTITIOUS_DEPTH * coupled[ax][0]) & (i < c_hi - FICTITIOUS_DEPTH * coupled[ax][1])

    placed = mpm_problem.place(sc.structures, grid, sc.materials, tracers=sc.output.tracers, key="structures",
                               grid_name="the MPM box (mpm_region)") if sc.structures else None
    names, models, params = ([], [], []) if placed is None else (list(placed.names), list(placed.models),
                                                                 list(placed.model_params))
    structures = None if placed is None else placed.particles
    body = np.zeros(0, int) if placed is None else placed.body
    tracers = () if placed is None else placed.tracers
    clamped = any(b.supports for b in sc.structures)
    box_lower = np.array([g.lower[ax] + lo[ax] * dx for ax in range(nd)])
    box_upper = np.array([g.lower[ax] + hi[ax] * dx for ax in range(nd)])
    if structures is not None:
        xs = np.asarray(structures.x)[:, :nd]
        cells = tuple(np.clip(np.floor((xs[:, ax] - g.lower[ax]) / dx).astype(int), 0, shape[ax] - 1)
                      for ax in range(nd))
        outside_box = np.any((xs < box_lower) | (xs > box_upper), axis=1)
        near = ~clear[cells] | outside_box
        if near.any():
            k = int(body[np.argmax(near)])
            raise ScenarioError(f"structures[{k}] crosses the bridge or its {FICTITIOUS_DEPTH} fictitious cells "
                                f"(particle at {xs[np.argmax(near)].tolist()} m): keep structures inside "
                                f"mpm_region and at least {w + FICTITIOUS_DEPTH} cells from every face bordering "
                                "the Eulerian region")

    esetup = euler_problem.build_gas(gas)
    n_gauges = len(sc.output.gauges)
    if len(gas.output.gauges) > n_gauges:  # drop the box's limit point
        esetup = dataclasses.replace(esetup, gauges=esetup.gauges[:n_gauges], gauge_cells=esetup.gauge_cells[:n_gauges])
    metric = EulerConfig(shape, dx, GEOMETRY_CODE[g.geometry], esetup.bc, 1, len(esetup.materials), tuple(g.lower))
    cell_volume = np.broadcast_to(geometry.cell_volumes(metric, np.float64), shape).ravel()

    def face_measure(ax):  # (faces of axis ax) dx x area
        return np.broadcast_to(geometry.face_measures(metric, ax, np.float64),
                               tuple(m + (a == ax) for a, m in enumerate(shape)))

    # gases: the Eulerian materials as fluid particles
    gas_material = []
    for name, mat in zip(esetup.materials, esetup.gases):
        if name not in names:
            model = get_model(mpm_problem.model_name(mat))
            names.append(name)
            models.append(model)
            params.append(model.params_from(mat))
        gas_material.append(names.index(name))

    # gas lattice of the box, points inside structures left out
    ppc = box.gas_particles_per_cell
    gx, gvol, ghalf = mpm.lattice(grid, box_lower, box_upper, ppc)
    keep = np.ones(len(gvol), bool)
    for b in sc.structures:
        keep &= ~mpm_problem.inside_body(b, gx, grid)
    gx, gvol, ghalf = gx[keep], gvol[keep], ghalf[keep]
    gcell = np.ravel_multi_index(tuple(np.clip(np.floor((gx[:, ax] - g.lower[ax]) / dx).astype(int), 0,
                                               shape[ax] - 1) for ax in range(nd)), shape)
    n_struct = 0 if structures is None else int(np.asarray(structures.mass).size)

    # coupled faces and their face cells
    faces = []
    for ax in range(nd):
        for side in (0, 1):
            if not coupled[ax][side]:
                continue
            plane = lo[ax] if side == 0 else hi[ax]
            others = [a for a in range(nd) if a != ax]
            lat = np.meshgrid(*[np.arange(lo[a], hi[a]) for a in others], indexing="ij")
            lat = tuple(x.ravel() for x in lat) if others else ()
            n_f = lat[0].size if others else 1

            def flat(i_axis):
                full = [None] * nd
                full[ax] = np.full(n_f, i_axis)
                for a, x in zip(others, lat):
                    full[a] = x
                return np.ravel_multi_index(tuple(full), shape)

            centre = np.zeros((n_f, nd))
            centre[:, ax] = g.lower[ax] + plane * dx
            for a, x in zip(others, lat):
                centre[:, a] = g.lower[a] + (x + 0.5) * dx
            out_i, in_i = (plane - 1, plane) if side == 0 else (plane, plane - 1)
            at = [None] * nd
            at[ax] = np.full(n_f, plane)
            for a, x in zip(others, lat):
                at[a] = x
            faces.append(Face(ax, side, plane, tuple(x - lo[a] for a, x in zip(others, lat)), flat(out_i),
                              flat(in_i), centre, face_measure(ax)[tuple(at)].copy()))

    # MPM everywhere (no coupled face) never creates particles: the pool is what activation makes at the start,
    # one particle per lattice point and material present there (coupling.activate)
    partial = esetup.alpha * esetup.rho_k  # (n, *shape)
    present = partial >= cp_kernels.PRESENT * np.sum(partial, axis=0)
    at_start = int(np.sum(present.reshape(len(partial), -1)[:, gcell]))
    # a growing pool counts as full when fewer slots are free than one step can fill: one inflow particle per
    # face cell and gas material (coupling.feed), so no emission is ever refused
    grows = bool(faces) and sc.numerics.capacity is None
    pool_margin = sum(int(f.outside.size) for f in faces) * len(gas_material) if grows else 0
    gas_slots = max(at_start, int(np.ceil(sc.numerics.pool_headroom * gvol.size))) + pool_margin
    capacity = sc.numerics.capacity or n_struct + (gas_slots if faces else at_start)
    if capacity < n_struct + at_start:
        raise ScenarioError(f"numerics.capacity = {capacity} is too small: the structures ({n_struct}) and the gas "
                            f"of the MPM box ({at_start}) need {n_struct + at_start} particles; set "
                            f"numerics.capacity >= {n_struct + at_start} (the bridge creates more as gas flows in)")
    capacity = xla.equal_parts(capacity, devices)

    # ring cells: MPM-grid cells outside the box
    ring = np.ones(shape, bool)
    for ax in range(nd):
        ring &= (idx[ax] >= g_lo[ax]) & (idx[ax] < g_hi[ax])
    ring &= ~in_box
    # Each ring cell is one point of its cell's volume on Cartesian grids. On an r-z grid it is the gas lattice
    # of the cell (ppc x ppc points of 2 pi r s^2), the quadrature of the box's particles: with one point per cell
    # the axial force of the cell's pressure, 2 pi int r N_r dr dN_z/dz, is integrated with another error
    # (r_c int N_r dr) than on the particles' side of the face, and where a ring column meets a particle column
    # (the box's corners) a gas at rest would be pushed
    ring_cells = np.flatnonzero(ring)
    ring_x = np.zeros((ring_cells.size, 3))
    for ax, i in enumerate(np.unravel_index(ring_cells, shape)):
        ring_x[:, ax] = g.lower[ax] + (i + 0.5) * dx
    ring_half = np.zeros_like(ring_x)
    ring_half[:, :nd] = 0.5 * dx
    if axisymmetric and ring_cells.size:  # (mpm.lattice of each ring cell: positions, ring volumes 2 pi r s^2,
        #                                     half-sizes s/2)
        points = [mpm.lattice(grid, x[:2] - 0.5 * dx, x[:2] + 0.5 * dx, ppc) for x in ring_x]
        ring_x, ring_volume, ring_half = (np.concatenate(parts) for parts in zip(*points))
        ring_cells = np.repeat(ring_cells, ppc ** 2)
    else:
        ring_volume = cell_volume[ring_cells]

    # domain faces whose adjacent cell is Eulerian-only (their transfers are the run's boundary exchange)
    boundary_measure = []
    for ax in range(nd):
        pair = []
        for i, f in ((0, 0), (shape[ax] - 1, shape[ax])):
            pair.append(np.where(np.take(~in_box, i, axis=ax), np.take(face_measure(ax), f, axis=ax), 0.0))
        boundary_measure.append(tuple(pair))

    # MPM nodes on box faces that lie on outflow faces of the domain: -n A, n the outward normal, A the node's
    # share of the face, the integral of N_I over it: h per lateral direction, h/2 at the grid's edges (where the
    # particles' P2G is one-sided); on an r-z grid the area element is 2 pi r dr (faces normal to z) or
    # 2 pi R dz (the face r = R)
    outflow_area = np.zeros(grid.nodes + (nd,))
    for ax in range(nd):
        for side, sign in ((0, -1.0), (1, 1.0)):
            if coupled[ax][side] or getattr(sc.boundaries, AXES[ax])[side] != "outflow":
                continue
            area = np.ones(())
            for a in range(nd):
                if a == ax:
                    radius = grid.origin[0] if side == 0 else grid.upper[0]
                    share = np.full(1, 2.0 * np.pi * radius if axisymmetric and a == 0 else 1.0)
                elif axisymmetric and a == 0:  # 2 pi int N_I r dr
                    r = grid.origin[0] + dx * np.arange(grid.nodes[0])
                    share = 2.0 * np.pi * dx * r
                    share[0], share[-1] = np.pi * dx * (r[0] + dx / 3.0), np.pi * dx * (r[-1] - dx / 3.0)
                else:
                    share = np.full(grid.nodes[a], dx)
                    share[[0, -1]] *= 0.5
                area = np.multiply.outer(area, share)
            sl = [slice(None)] * nd
            sl[ax] = slice(0, 1) if side == 0 else slice(-1, None)
            outflow_area[tuple(sl) + (ax,)] = -sign * area
    outflow_area = outflow_area.reshape(grid.num_nodes, nd)

    coupling = Coupling(
        structure_particles=n_struct, gas_particles_per_cell=ppc, bridge_cells=w, shape_functions=sc.numerics.shape,
        clamped=bool(clamped),
        pic_fraction=tuple(sc.numerics.gas_pic_fraction if k in gas_material else 0.0 for k in range(len(models))),
        pressure_relaxation=sc.numerics.pressure_relaxation, mpm_cfl=sc.numerics.cfl,
        q_quadratic=sc.numerics.q_quadratic, q_linear=sc.numerics.q_linear,
        mpm_reference_pressure=sc.numerics.reference_pressure,
        activation_overpressure=box.activation_overpressure, capacity_grows=grows, pool_margin=pool_margin,
        activation_particles=n_struct + at_start, tracers=tuple(tracers),
        coupled_faces=tuple(f"{'lower' if f.side == 0 else 'upper'} {AXES[f.axis]}" for f in faces))
    return Setup(euler=esetup, grid=grid, materials=tuple(names), models=tuple(models), model_params=tuple(params),
                 gas_material=tuple(gas_material), structures=structures, body=body, capacity=int(capacity),
                 devices=devices, box_lo=lo, box_hi=hi, faces=tuple(faces), fictitious=core, parked=core & clear,
                 outside=~in_box, ring_cells=ring_cells, ring_x=ring_x, ring_volume=ring_volume, ring_half=ring_half,
                 cell_volume=cell_volume, gas_x=gx, gas_volume=gvol, gas_half=ghalf, gas_cell=gcell,
                 boundary_measure=tuple(boundary_measure), outflow_area=outflow_area, coupling=coupling)
