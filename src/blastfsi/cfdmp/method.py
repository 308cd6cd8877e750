"""The ``cfdmp`` method behind the driver's face: the Eulerian solver (:mod:`blastfsi.euler`) and the MPM
solver (:mod:`blastfsi.mpm`) coupled through the bridge region (:mod:`blastfsi.cfdmp.coupling`, seed 000 Sec. 3).

Before activation only the Eulerian solver runs, over the whole domain; when the overpressure in a cell
bordering the MPM box exceeds ``mpm_region.activation_overpressure`` the gas of the box becomes particles
(:func:`coupling.activate`) and every later step is the coupled step of 000 Sec. 3.5. The history books the
conservation budget of the coupled system: Eulerian-only cells + particles + reservoirs + what left through
the domain boundary, against its value at activation. With ``numerics.reference_pressure`` the MPM region's
force takes the stresses relative to it (the particles' and the Eulerian ring cells' alike, so a uniform
pressure still balances exactly).
"""
from __future__ import annotations

import dataclasses
import functools
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import euler as ek
from blastfsi import mpm, timeloop, xla
from blastfsi.cfdmp import coupling as cp
from blastfsi.cfdmp.scenario import CfdmpScenario
from blastfsi.diagnostics import blast_maps, damage
from blastfsi.euler.method import GEOMETRY_CODE, LIMITER_CODE, SCHEME_CODE, signal_speed
from blastfsi.scenario import AXES, device_count
from blastfsi.method import Coupled, Grid, Particles, register
from blastfsi.mpm import relaxation
from blastfsi.mpm.method import (VOIGT_TO_TENSOR, particle_signal_speed, placed, tracer_columns, tracer_row,
                                 tracer_summary)
from blastfsi.cfdmp import problem
from blastfsi.euler import problem as euler_problem

# blastfsi.plotting (matplotlib) is imported inside the plotting functions only: it loads when plots are drawn.


class State(NamedTuple):
    U: jnp.ndarray  # Eulerian rows, fictitious cells consistent with the particles
    peak: jnp.ndarray  # blast maps of the viewed field (Eulerian cells and the particles' cells)
    arrival: jnp.ndarray
    end: jnp.ndarray
    impulse: jnp.ndarray
    last: jnp.ndarray
    mpm: mpm.State
    reservoirs: cp.Reservoirs
    budget: cp.Budget
    coupled: jnp.ndarray  # () bool
    baseline: jnp.ndarray  # (n + ndim + 1,) system totals at activation (mass per material, momentum, energy)
    displaced: jnp.ndarray  # (n + ndim + 1,) gas of the box not turned into particles (inside structures)
    t: jnp.ndarray
    dt_prev: jnp.ndarray
    dt0: jnp.ndarray
    step: jnp.ndarray
    fault: jnp.ndarray
    hist: jnp.ndarray
    hist_next: jnp.ndarray


class Params(NamedTuple):
    euler: ek.Params
    mpm: mpm.Params
    layout: cp.Layout
    reference_pressure: jnp.ndarray
    arrival_threshold: jnp.ndarray
    activation: jnp.ndarray  # overpressure that starts the coupling [Pa]
    structure_x0: jnp.ndarray  # (n_structure, 3) initial positions


class Static(NamedTuple):
    coupling: cp.Static
    gauge_cells: tuple
    capacity: int
    pool_margin: int  # a growing pool counts as full when fewer slots are free than one step can fill (one
    #                   inflow particle per face cell and material), so no emission is ever refused; 0 for a
    #                   fixed pool, full when an emission did not fit
    tracers: tuple  # structure particle of each output.tracers point
    devices: int = 1  # numerics.devices: the particle pool is split over them (blastfsi.mpm.method.placed)


def _maps(s: State) -> blast_maps.BlastMaps:
    return blast_maps.BlastMaps(s.peak, s.arrival, s.end, s.impulse, s.last)


# compiled once (params() runs for every snapshot); run eagerly, each would compile its every operation
# (~60 small programs, ~3 s of a coupled run's start on a 2-core CPU)
_conservative = jax.jit(ek.conservative, static_argnums=5)
_stencil = jax.jit(mpm.stencil, static_argnums=(2, 3))


def _grid_pressure(U, prm: Params, cs: cp.Static):
    """The pressure of every cell of U, on the grid's shape."""
    return cp.flat_primitives(U, prm.euler.eos, cs.euler)["pressure"].reshape(cs.euler.shape)


_grid_pressure_compiled = jax.jit(_grid_pressure, static_argnums=2)  # (the initial state's, outside the loop)


@functools.partial(jax.jit, static_argnums=2)
def _viewed_primitives(st: State, prm: Params, cs: cp.Static):
    """(primitives of the viewed grid, cells without gas, positive-phase duration) for a snapshot: one
    compiled function, not some hundred operations each compiled on first use."""
    rows, gas_mass = cp.gas_rows(st.mpm.particles, cs)
    U = jnp.where(st.coupled, cp.view(st.U, rows, gas_mass, prm.layout), st.U)
    return (ek.primitives(U, prm.euler, cs.euler), st.coupled & prm.layout.fictitious & ~(gas_mass > 0.0),
            blast_maps.duration(_maps(st), st.t))


def _cast(tree, dtype):
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype) if jnp.issubdtype(jnp.asarray(a).dtype,
                                                                                    jnp.floating) else a, tree)


def _axis_names(geometry: str) -> tuple:
    """The axes' names of a domain geometry: r, z on an r-z grid, else x, y, z."""
    return ("r", "z") if geometry == "axisymmetric" else AXES


def _cell_at(setup: problem.Setup, idx) -> str:
    """'cell (i, j) at r = .. m, z = .. m' (x, y, z on Cartesian grids) of an Eulerian cell index."""
    g = setup.euler.grid
    centre = ", ".join(f"{a} = {g.lower[d] + (i + 0.5) * g.dx:.6g} m"
                       for d, (a, i) in enumerate(zip(_axis_names(g.geometry), idx)))
    return f"cell {tuple(int(i) for i in idx)} at {centre}"


def _pad3(a: np.ndarray) -> np.ndarray:
    a = np.atleast_2d(np.asarray(a, float))
    return np.pad(a, ((0, 0), (0, 3 - a.shape[1])))


def outflow_faces(setup: problem.Setup) -> tuple:
    """(axis, side) of every box face that lies on an outflow face of the domain (its nodes carry the
    mirror's area, ``setup.outflow_area``: -n A, positive on a lower face, negative on an upper one)."""
    nd = setup.grid.dim
    block = np.asarray(setup.outflow_area).reshape(setup.grid.nodes + (nd,))
    return tuple((ax, side) for ax in range(nd) for side in (0, 1)
                 if np.any(np.take(block[..., ax], -side, axis=ax) * (1.0 - 2.0 * side) > 0.0))


def conserved_momentum_axes(geometry: int, ndim: int) -> tuple:
    """The axes whose momentum the equations conserve: all on a Cartesian grid; not the radial one of a
    cylindrical, spherical or r-z grid (the pressure's geometric source, the hoop stress)."""
    return tuple(range(ndim)) if geometry == GEOMETRY_CODE["cartesian"] else tuple(range(1, ndim))


def system_totals(U, P: mpm.Particles, res: cp.Reservoirs, layout: cp.Layout, static: cp.Static):
    """(n + ndim + 1,) mass per material, momentum and total energy of Eulerian-only cells + particles +
    reservoirs, and the same three parts separately."""
    cfg = static.euler
    n, d = cfg.n_materials, len(cfg.shape)
    lay = ek.config.layout(cfg)
    axes = tuple(range(1, U.ndim))
    rows = jnp.concatenate([U[:n], U[lay.mom:lay.mom + d], U[lay.energy:lay.energy + 1]])
    V = layout.cell_volume.reshape(cfg.shape)
    euler = jnp.sum(jnp.where(layout.outside, rows * V, 0.0), axis=axes)
    slot = cp._gas_index(static, P.material)
    on = P.active
    per_material = [jnp.sum(jnp.where(on & (slot == k), P.mass, 0.0)) for k in range(n)]
    structure = jnp.sum(jnp.where(on & (slot < 0), P.mass, 0.0))
    particles = jnp.concatenate([jnp.stack(per_material), cp.mpm_content(P, d)])
    reservoirs = jnp.concatenate([jnp.sum(res.mass, axis=0), jnp.sum(res.momentum, axis=(0, 1))[:d],
                                  jnp.sum(res.energy)[None]])
    return euler + particles + reservoirs, euler, particles, reservoirs, structure


class Cfdmp:
    name = "cfdmp"
    scenario_model = CfdmpScenario
    pool_leaf = "mpm.particles.active"  # a blastfsi.method.GrowingPool: the driver grows a full pool

    def build(self, sc: CfdmpScenario) -> problem.Setup:
        return problem.build(sc, device_count(sc.numerics.devices))

    def static(self, setup: problem.Setup, sc: CfdmpScenario) -> Static:
        return self._static(setup, SCHEME_CODE[sc.numerics.scheme], LIMITER_CODE[sc.numerics.limiter],
                            sc.numerics.limiting == "characteristic")

    @staticmethod
    def _static(setup: problem.Setup, scheme: int, limiter: int = ek.VAN_LEER, characteristic: bool = True) -> Static:
        e = setup.euler
        cfg = ek.Config(shape=e.grid.shape, dx=float(e.grid.dx), geometry=GEOMETRY_CODE[e.grid.geometry], bc=e.bc,
                        scheme=scheme, n_materials=len(e.materials),
                        origin=tuple(float(v) for v in e.grid.lower), limiter=limiter,
                        characteristic=characteristic)
        c = setup.coupling
        n_struct = c.structure_particles
        # the structures fill the first slots of the pool and are never deleted; the gas lives after them. A pool
        # split over devices runs every model on every slot instead: a slice of the split pool at n_struct would
        # move the particles between devices each step
        slots = None if setup.devices > 1 else tuple(
            (n_struct, setup.capacity) if k in setup.gas_material else (0, n_struct) for k in range(len(setup.models)))
        mcfg = mpm.make_config(setup.grid, setup.models, shape=c.shape_functions, model_slots=slots,
                               prescribed=c.clamped, prescribed_slots=None if slots is None else (0, n_struct),
                               blend=any(a > 0.0 for a in c.pic_fraction),
                               relax=relaxation.gas_materials(setup.models, c.pressure_relaxation))
        faces = tuple((f.axis, f.side, f.plane) for f in setup.faces)
        sizes = tuple(int(f.outside.size) for f in setup.faces)
        offset = tuple(int(round((o - lo) / e.grid.dx)) for o, lo in zip(setup.grid.origin, e.grid.lower))
        coupling = cp.Static(cfg, mcfg, faces, sizes, tuple(setup.box_lo), tuple(setup.box_hi), offset,
                             tuple(setup.gas_material), n_struct, c.gas_particles_per_cell,
                             outflow_faces(setup), setup.devices)
        flat = tuple(int(np.ravel_multi_index(c, e.grid.shape)) for c in e.gauge_cells)
        return Static(coupling, flat, setup.capacity, c.pool_margin, c.tracers, setup.devices)

    def params(self, setup: problem.Setup, dtype) -> Params:
        e = setup.euler
        nd = e.grid.ndim
        grid = setup.grid
        kp = ek.Params(jnp.asarray(e.eos, dtype), jnp.asarray(e.cfl, dtype), euler_problem.blast_params(e, dtype))
        c = setup.coupling
        mp = mpm.make_params(setup.model_params, cfl=c.mpm_cfl, q_quadratic=c.q_quadratic, q_linear=c.q_linear,
                             pic_fraction=c.pic_fraction, reference_pressure=c.mpm_reference_pressure,
                             dtype=dtype)
        shape = mpm.SHAPES[c.shape_functions]
        if setup.ring_cells.size:
            ridx, rw, rgrad = _stencil(jnp.asarray(setup.ring_x, dtype), jnp.asarray(setup.ring_half, dtype), grid,
                                       shape)
        else:  # MPM everywhere: no ring
            S = shape.nodes_per_dim ** nd
            ridx, rw, rgrad = jnp.zeros((S, 0), jnp.int32), jnp.zeros((S, 0), dtype), [jnp.zeros((S, 0), dtype)] * nd
        def cat(parts, shape):
            return np.concatenate(parts) if parts else np.zeros((0,) + shape)

        axis_vec = cat([np.tile(np.eye(3)[f.axis] * f.into_box, (f.outside.size, 1)) for f in setup.faces], (3,))
        lateral = []
        for f in setup.faces:
            rows = np.zeros((3, 3))
            for j, a in enumerate(a for a in range(nd) if a != f.axis):
                rows[j, a] = 1.0
            lateral.append(np.tile(rows[None], (f.outside.size, 1, 1)))
        box_lo = np.zeros(3)
        box_hi = np.zeros(3)
        box_lo[:nd] = [e.grid.lower[a] + setup.box_lo[a] * e.grid.dx for a in range(nd)]
        box_hi[:nd] = [e.grid.lower[a] + setup.box_hi[a] * e.grid.dx for a in range(nd)]
        U0 = self._initial_rows(setup, kp, dtype)
        layout = cp.Layout(
            fictitious=jnp.asarray(setup.fictitious), parked=jnp.asarray(setup.parked),
            outside=jnp.asarray(setup.outside), park_rows=U0,
            ring_cells=jnp.asarray(setup.ring_cells, jnp.int32), ring_idx=ridx, ring_w=rw, ring_grad=jnp.stack(rgrad),
            ring_volume=jnp.asarray(setup.ring_volume, dtype), ring_radius=jnp.asarray(setup.ring_x[:, 0], dtype),
            cell_volume=jnp.asarray(setup.cell_volume, dtype),
            outflow_area=jnp.asarray(setup.outflow_area, dtype),
            face_out=jnp.asarray(cat([f.outside for f in setup.faces], ()), jnp.int32),
            face_in=jnp.asarray(cat([f.bridge for f in setup.faces], ()), jnp.int32),
            face_centre=jnp.asarray(_pad3(cat([f.centre for f in setup.faces], (nd,))), dtype),
            face_measure=jnp.asarray(cat([f.measure for f in setup.faces], ()), dtype),
            face_into=jnp.asarray(cat([np.full(f.outside.size, f.into_box) for f in setup.faces], ()), dtype),
            face_axis=jnp.asarray(axis_vec, dtype), face_lateral=jnp.asarray(cat(lateral, (3, 3)), dtype),
            gas_x=jnp.asarray(setup.gas_x, dtype), gas_volume=jnp.asarray(setup.gas_volume, dtype),
            gas_half=jnp.asarray(setup.gas_half, dtype), gas_cell=jnp.asarray(setup.gas_cell, jnp.int32),
            boundary_measure=tuple(tuple(jnp.asarray(m, dtype) for m in pair) for pair in setup.boundary_measure),
            box_lower=jnp.asarray(box_lo, dtype), box_upper=jnp.asarray(box_hi, dtype))
        x0 = np.zeros((0, 3)) if setup.structures is None else np.asarray(setup.structures.x)
        return Params(kp, _cast(mp, dtype), layout, jnp.asarray(e.reference_pressure, dtype),
                      jnp.asarray(e.arrival_fraction * e.reference_pressure, dtype),
                      jnp.asarray(c.activation_overpressure, dtype), jnp.asarray(x0, dtype))

    @staticmethod
    def _initial_rows(setup: problem.Setup, kp: ek.Params, dtype):
        e = setup.euler
        cfg = ek.Config(e.grid.shape, float(e.grid.dx), GEOMETRY_CODE[e.grid.geometry], e.bc, 1, len(e.materials),
                        tuple(e.grid.lower))
        return _conservative(jnp.asarray(e.rho_k, dtype), jnp.asarray(e.alpha[0], dtype),
                             jnp.asarray(e.velocity, dtype), jnp.asarray(e.pressure, dtype), kp, cfg)

    def initial_state(self, setup: problem.Setup, sc: CfdmpScenario, n_samples: int, dtype) -> State:
        static = self.static(setup, sc)
        prm = self.params(setup, dtype)
        cs = static.coupling
        n, d = cs.euler.n_materials, len(cs.euler.shape)
        U = prm.layout.park_rows
        hist = max(m.history_size for m in setup.models)
        if setup.structures is None:
            pool = mpm.empty(setup.capacity, hist, dtype)
        else:
            batch = setup.structures
            pad = hist - np.asarray(batch.point.history).shape[1]
            batch = batch._replace(point=batch.point._replace(
                history=np.pad(np.asarray(batch.point.history), ((0, 0), (0, pad)))))
            pool = mpm.make_pool(mpm.concatenate(batch), setup.capacity)
        ms = mpm.initialize(_cast(pool, dtype), prm.mpm, cs.mpm)
        F = sum(cs.face_sizes)
        res = cp.Reservoirs(jnp.zeros((F, n), dtype), jnp.zeros((F, n, 3), dtype), jnp.zeros((F, n), dtype),
                            jnp.full((F, n), -1, jnp.int32))
        budget = cp.Budget(jnp.zeros(n + d + 1, dtype), jnp.zeros(d + 1, dtype), jnp.zeros((), jnp.int32),
                           jnp.zeros((), dtype), jnp.zeros(d + 1, dtype), jnp.zeros(d + 1, dtype))
        zeros = jnp.zeros(n + d + 1, dtype)
        maps = blast_maps.initial(_grid_pressure_compiled(U, prm, cs) - prm.reference_pressure)
        n_cols = len(self.history_columns(setup, sc))
        clock = timeloop.clock(n_samples, n_cols, dtype)  # a charge's clock starts at its remap time
        clock["t"] = jnp.asarray(setup.euler.start_time, dtype)
        state = State(U, *maps, mpm=ms, reservoirs=res, budget=budget, coupled=jnp.asarray(False), baseline=zeros,
                      displaced=zeros, **clock)
        if setup.coupling.activation_overpressure == 0.0:
            state = jax.jit(_activate, static_argnums=2)(state, prm, cs)
        return state

    def advance(self, state, params: Params, static: Static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        cs = static.coupling
        cfg, mcfg = cs.euler, cs.mpm
        lay = params.layout
        d = len(cfg.shape)
        pref = params.mpm.reference_pressure
        n = cfg.n_materials

        def stable_dt(s):  # once coupled, the fictitious cells set the Eulerian step only next to the scheme's own
            owned = ~lay.fictitious | ~s.coupled
            dt = ek.stable_dt(s.U, params.euler, cfg, owned) if cs.faces else jnp.inf
            return jnp.minimum(dt, jnp.where(s.coupled, mpm.stable_dt(s.mpm, params.mpm, mcfg), jnp.inf))

        # each branch returns the new state and the viewed grid (blast maps), one gas P2G per step
        def euler_only(s, dt):
            s = s._replace(U=ek.step(s.U, dt, params.euler, cfg, s.t, parity=s.step))
            dp = cp.flat_primitives(s.U, params.euler.eos, cfg)["pressure"][lay.ring_cells] - params.reference_pressure
            hot = jnp.max(dp, initial=-jnp.inf) > params.activation  # (no ring cells: MPM everywhere)
            s = jax.lax.cond(hot, lambda s: _activate(s, params, cs), lambda s: s, s)
            return s, s.U

        def mpm_step(s, dt, source):  # the MPM step; its change of the particles' momentum and energy booked:
            # the flow-out mirror's traction with what crossed the domain boundary, the reactions of the
            # grid's wall faces and the supports, the rest as mpm_step
            before = cp.mpm_content(s.mpm.particles, d)
            ms = mpm.step(s.mpm, dt, params.mpm, mcfg, source)
            change = cp.mpm_content(ms.particles, d) - before
            boundary = ms.boundary_exchange - s.mpm.boundary_exchange
            reaction = ms.reaction - s.mpm.reaction
            return ms, s.budget._replace(mpm_step=s.budget.mpm_step + change - boundary - reaction,
                                         boundary_out=s.budget.boundary_out.at[n:].add(-boundary),
                                         reaction=s.budget.reaction + reaction)

        def mpm_only(s, dt):  # the box is the whole domain: MPM everywhere
            ms, budget = mpm_step(s, dt, lambda P, idx, w: cp.outflow_ghost(P, lay, cs, pref, (idx, w)))
            ms, res, budget = cp.remove_leaving(ms, s.reservoirs, budget, cs, lay)
            rows, gas_volume = cp.gas_rows(ms.particles, cs)
            return s._replace(mpm=ms, reservoirs=res, budget=budget), cp.view(s.U, rows, gas_volume, lay)

        def coupled(s, dt):
            eos = params.euler.eos
            prim = cp.flat_primitives(s.U, eos, cfg)
            ms, budget = mpm_step(s, dt, cp.interface_source(prim, lay, cs, pref))
            U, T = ek.step_with_transfers(s.U, dt, params.euler, cfg, parity=s.step)
            U, budget = _blast_inflow(U, ek.with_blast(U, s.t, dt, params.euler, cfg), budget, lay, cs)
            ms, res, budget = cp.remove_leaving(ms, s.reservoirs, budget, cs, lay)
            U, res, budget = cp.receive(U, res, budget, T, prim, eos, cs, lay)
            budget = budget._replace(boundary_out=budget.boundary_out + cp.boundary_outflow(T, cs, lay))
            ms, res, budget = cp.feed(ms, res, budget, cp.flat_primitives(U, eos, cfg), eos, params.mpm, cs, lay)
            rows, gas_volume = cp.gas_rows(ms.particles, cs)
            U = cp.fictitious(U, rows, gas_volume, lay, s.U)
            return (s._replace(U=U, mpm=ms, reservoirs=res, budget=budget), cp.view(U, rows, gas_volume, lay))

        def step(s, dt):
            new, viewed = jax.lax.cond(s.coupled, coupled if cs.faces else mpm_only, euler_only, s, dt)
            dp = _grid_pressure(viewed, params, cs) - params.reference_pressure
            new = placed(new, static.devices)
            return new._replace(**blast_maps.update(_maps(new), dp, s.t, dt, params.arrival_threshold)._asdict())

        def pool_full(s):  # (Static.pool_margin)
            in_use = jnp.maximum(s.budget.required, jnp.sum(s.mpm.particles.active))
            return in_use + static.pool_margin > static.capacity

        def history_row(s):
            return history(static, s, params).values(s.t.dtype)

        return timeloop.run_until(placed(state, static.devices), t_stop, max_steps, sample_interval,
                                  dt_floor_fraction, stable_dt=stable_dt, step=step, history_row=history_row,
                                  pool_full=pool_full)

    @staticmethod
    def _view(s: State, cs: cp.Static, lay: cp.Layout):
        rows, gas_mass = cp.gas_rows(s.mpm.particles, cs)
        return jnp.where(s.coupled, cp.view(s.U, rows, gas_mass, lay), s.U)

    def history_columns(self, setup: problem.Setup, sc: CfdmpScenario) -> tuple:
        return history(self.static(setup, sc)).columns

    def snapshot(self, state: State, setup: problem.Setup) -> Coupled:
        """The viewed grid (Eulerian cells, and the box cells beyond the bridges from the particles; cells
        without gas, inside structures, are NaN; ``region`` 0 Eulerian, 1 bridge, 2 particles) and the
        particles (gas and structures: pressure, stress, plastic strain, damage, the models' own fields such as
        HJC's compressive and tensile damage; the structures' displacement from their reference position, NaN
        for gas)."""
        cs = self._static(setup, 0).coupling
        prm = self.params(setup, np.asarray(state.U).dtype)
        prim, empty, duration = jax.device_get(_viewed_primitives(state, prm, cs))
        e = setup.euler

        def masked(a):
            return np.where(empty if a.ndim == empty.ndim else empty[..., None], np.nan, a)

        fields = {"density": prim["rho"], "pressure": prim["pressure"],
                  "velocity": np.moveaxis(prim["velocity"], 0, -1), "internal_energy": prim["internal_energy"],
                  "sound_speed": prim["sound_speed"]}
        if len(e.materials) == 2:
            fields["products_fraction"] = prim["products_fraction"]
        fields = {k: masked(v) for k, v in fields.items()}
        arrival = np.asarray(state.arrival)
        fields.update(peak_overpressure=np.asarray(state.peak),
                      arrival_time=np.where(np.isfinite(arrival), arrival, np.nan),
                      positive_impulse=np.asarray(state.impulse),
                      positive_duration=duration,
                      region=np.where(setup.outside, 0, np.where(setup.fictitious, 2, 1)).astype(float))
        g = e.grid
        edges = tuple(lo + np.arange(n + 1) * g.dx for lo, n in zip(g.lower, g.shape))
        P = state.mpm.particles
        on = np.asarray(P.active)
        stress = np.asarray(P.point.stress)[on]
        nst = setup.coupling.structure_particles
        points = {"pressure": -stress[:, :3].sum(axis=1) / 3.0, "density": np.asarray(P.point.density)[on],
                  "velocity": np.asarray(P.v)[on, :g.ndim], "stress": stress[:, VOIGT_TO_TENSOR],
                  "plastic_strain": np.asarray(P.point.plastic_strain)[on], "damage": np.asarray(P.point.damage)[on],
                  "material": np.asarray(P.material)[on].astype(float),
                  "structure": (np.arange(on.size) < nst)[on].astype(float)}
        displacement = np.full((on.size, g.ndim), np.nan)  # of the structures' particles from their reference
        if nst:
            displacement[:nst] = np.asarray(P.x)[:nst, :g.ndim] - np.asarray(setup.structures.x)[:, :g.ndim]
        points["displacement"] = displacement[on]
        points.update({k: v.astype(float) for k, v in mpm.model_output_fields(
            np.asarray(P.material)[on], np.asarray(P.point.history)[on], setup.models, setup.model_params).items()})
        return Coupled(grid=Grid(edges=edges, cell_fields=fields),
                       particles=Particles(positions=np.asarray(P.x)[on, :g.ndim], point_fields=points))

    @staticmethod
    def pool_needed(state: State, setup: problem.Setup) -> int:
        """The particles in use (or the last emission's need) and a step's inflow margin; before the coupling
        starts (``mpm_region.activation_overpressure``: a stand-off charge's blast still on its way), what the
        activation will make: a pool packed to the few structure particles of a box still waiting for its gas
        had to grow again at once (tnt-standoff-plate: packed 14 920 -> 9000 slots at 0.82 ms, grown to 13 000
        at the activation, 0.91 ms; each a compilation of the time loop)."""
        c = setup.coupling
        active = int(np.sum(np.asarray(state.mpm.particles.active)))
        waiting = 0 if bool(np.asarray(state.coupled)) else c.activation_particles
        return max(int(state.budget.required), max(active, waiting) + c.pool_margin)

    @staticmethod
    def resize(setup: problem.Setup, state: State, capacity: int):
        """One member's host state in a pool of ``capacity`` slots; None when ``numerics.capacity`` fixed the
        pool. A larger pool gets its new, empty slots at the end (the slots in use keep their indices); a
        smaller one gets the gas particles in use packed, in their order, right after the structures (which
        keep the first slots), and the inflow particles' slots that the reservoirs keep are renumbered (those
        of freed slots dropped, as a removed particle's)."""
        if not setup.coupling.capacity_grows:
            return None
        capacity = xla.equal_parts(capacity, setup.devices)
        P = jax.tree_util.tree_map(np.asarray, state.mpm.particles)
        old = P.active.shape[0]
        n_struct = setup.coupling.structure_particles
        if capacity >= old:
            keep = np.arange(old)
        else:
            keep = np.concatenate([np.arange(n_struct), n_struct + np.flatnonzero(P.active[n_struct:])])
            if keep.size > capacity:
                raise ValueError(f"a pool of {capacity} slots cannot hold the {keep.size} slots in use")
        new_slot = np.full(old, -1, np.int64)
        new_slot[keep] = np.arange(keep.size)
        pad = jax.tree_util.tree_map(np.asarray, mpm.empty(capacity - keep.size, P.point.history.shape[1],
                                                           P.mass.dtype))
        resized = jax.tree_util.tree_map(lambda a, b: np.concatenate([a[keep], b]), P, pad)
        buffer = np.asarray(state.reservoirs.buffer)
        buffer = np.where(buffer >= 0, new_slot[np.clip(buffer, 0, old - 1)], -1).astype(buffer.dtype)
        setup = dataclasses.replace(setup, capacity=int(capacity))
        return setup, state._replace(mpm=state.mpm._replace(particles=resized),
                                     reservoirs=state.reservoirs._replace(buffer=buffer))

    def locate_fault(self, state: State, setup: problem.Setup) -> str:
        budget = state.budget
        if int(budget.required) > setup.capacity:
            return (f"particle pool capacity {setup.capacity} is too small: the bridge needed "
                    f"{int(budget.required)} active particles; set numerics.capacity >= {int(budget.required)} "
                    f"(or leave it unset: the default pool grows)")
        cs = self._static(setup, 0).coupling
        prm = self.params(setup, np.asarray(state.U).dtype)
        U = jnp.asarray(state.U)
        flat = int(ek.first_bad_cell(U, prm.euler, cs.euler))
        g = setup.euler.grid
        if flat >= 0:
            idx = np.unravel_index(flat, g.shape)
            prim = ek.primitives(U, prm.euler, cs.euler)
            where = ("a fictitious cell (from the particles)" if setup.fictitious[idx] else
                     "an Eulerian cell" if setup.outside[idx] else "a bridge cell")
            return (f"{_cell_at(setup, idx)}, {where} (density {float(np.asarray(prim['rho'])[idx]):.4g} kg/m^3, "
                    f"pressure {float(np.asarray(prim['pressure'])[idx]):.4g} Pa, specific internal energy "
                    f"{float(np.asarray(prim['internal_energy'])[idx]):.4g} J/kg)")
        ms = jax.tree_util.tree_map(jnp.asarray, state.mpm)
        k = int(mpm.first_fault(ms, cs.mpm))
        if k >= 0:
            x = np.asarray(state.mpm.particles.x)[k, :g.ndim]
            name = setup.materials[int(state.mpm.particles.material[k])]
            return f"particle {k} ({name}) at {x.tolist()} m (non-finite, non-positive density or off the grid)"
        return self._fastest_signal(state, setup, prm, cs)

    @staticmethod
    def _fastest_signal(state: State, setup: problem.Setup, prm: Params, cs) -> str:
        """Where a collapsed step's fastest signal is: the Eulerian cell (fictitious cells excluded: they set no
        step) or the active particle with the largest |u| + c, and its state."""
        g = setup.euler.grid
        prim = ek.primitives(jnp.asarray(state.U), prm.euler, cs.euler)
        cell_speed = np.where(setup.fictitious, -np.inf, np.nan_to_num(signal_speed(prim), nan=np.inf))
        flat = int(np.argmax(cell_speed))
        P = state.mpm.particles
        part_speed = particle_signal_speed(P)
        k = int(np.argmax(part_speed))
        if cell_speed.reshape(-1)[flat] >= part_speed[k]:
            idx = np.unravel_index(flat, g.shape)
            state_of = {key: float(np.asarray(prim[key])[idx]) for key in ("rho", "pressure", "products_fraction")}
            return (f"fastest signal {cell_speed[idx]:.4g} m/s in {_cell_at(setup, idx)} "
                    f"(density {state_of['rho']:.4g} kg/m^3, pressure {state_of['pressure']:.4g} Pa, products "
                    f"mass fraction {state_of['products_fraction']:.3g})")
        where = ", ".join(f"{a} = {float(c):.6g} m"
                          for a, c in zip(_axis_names(g.geometry), np.asarray(P.x)[k, :g.ndim]))
        return (f"fastest signal {part_speed[k]:.4g} m/s in particle {k} ({setup.materials[int(P.material[k])]}) "
                f"at {where} (density {float(P.point.density[k]):.4g} kg/m^3, specific internal energy "
                f"{float(P.point.energy[k]):.4g} J/kg)")

    def summary(self, sc: CfdmpScenario, setup: problem.Setup, hist: dict, state: State) -> dict:
        e = setup.euler
        t = float(state.t)
        gauges = []
        for pos, cell in zip(e.gauges, e.gauge_cells):
            arrival, end = float(state.arrival[cell]), float(state.end[cell])
            region = "euler" if setup.outside[cell] else ("particles" if setup.fictitious[cell] else "bridge")
            gauges.append({"position": [float(v) for v in pos], "region": region,
                           "peak_overpressure": float(state.peak[cell]), "impulse": float(state.impulse[cell]),
                           "arrival_time": arrival if np.isfinite(arrival) else None,
                           "positive_phase_duration": (min(end, t) - arrival) if np.isfinite(arrival) else None})
        coupled = np.asarray(hist["coupled"]) > 0.5
        n = len(e.materials)
        nd = e.grid.ndim
        conserved = [AXES[a] for a in conserved_momentum_axes(GEOMETRY_CODE[e.grid.geometry], nd)]
        baseline = np.asarray(state.baseline)
        out = {"scheme": sc.numerics.scheme, "materials": list(e.materials), "mpm_materials": list(setup.materials),
               "dx": e.grid.dx, "bridge_cells": setup.coupling.bridge_cells,
               **({"remap_time": e.charge.remap_time, "one_d_air_zone": e.charge.one_d_air_zone}
                  if e.charge is not None else {}),
               "coupled_faces": list(setup.coupling.coupled_faces),
               "activation_time": float(hist["time"][np.argmax(coupled)]) if coupled.any() else None,
               "particles": int(np.asarray(state.mpm.particles.active).sum()), "capacity": setup.capacity,
               "budget": {
                   "accounts": "Eulerian-only cells + particles (gas and structures) + bridge reservoirs + what "
                               "left through the domain boundary - the reactions of the MPM grid's wall faces and "
                               "the supports, against their sum at activation",
                   "reaction": {"impulse": [float(hist[f"reaction_impulse_{a}"][-1]) for a in AXES[:nd]],
                                "work": float(hist["reaction_work"][-1])},
                   "mass_residual_relative": float(hist["mass_budget_residual"][-1]),
                   "max_mass_residual_relative": float(np.max(np.abs(hist["mass_budget_residual"]))),
                   "energy_residual_relative": float(hist["energy_budget_residual"][-1]),
                   "energy_pressure_transfer": float(hist["energy_pressure_transfer"][-1]),
                   "energy_mpm_step": float(hist["energy_mpm_step"][-1]),
                   "transport": {
                       "accounts": "the sum above with the MPM steps' change of the particles' momentum and energy "
                                   "(interface force, the MPM scheme's non-conservation; the flow-out mirror's "
                                   "traction with the boundary outflow, the reactions apart) and the pressure part of "
                                   "the Eulerian face transfer booked; momentum relative to sqrt(2 M E) at activation, conserved "
                                   "axes only, largest over the history samples",
                       "max_energy_residual_relative": float(np.max(np.abs(hist["energy_transport_residual"]))),
                       **{f"max_momentum_{a}_residual_relative":
                          float(np.max(np.abs(hist[f"momentum_{a}_transport_residual"]))) for a in conserved}},
                   **{f"momentum_{a}_residual_relative": float(hist[f"momentum_{a}_budget_residual"][-1])
                      for a in conserved},
                   "mass_at_activation": float(baseline[:n].sum()), "energy_at_activation": float(baseline[-1]),
                   "mass_boundary_out": float(hist["mass_boundary_out"][-1]),
                   "mass_in_reservoirs": float(hist["mass_reservoirs"][-1]),
                   "displaced_by_structures": {"mass": float(np.asarray(state.displaced)[:n].sum()),
                                               "energy": float(np.asarray(state.displaced)[-1])}},
               "gauges": gauges}
        out.update(tracer_summary(hist, len(setup.coupling.tracers), AXES[:setup.euler.grid.ndim]))
        if setup.coupling.structure_particles:
            P = state.mpm.particles
            nst = setup.coupling.structure_particles
            on = np.asarray(P.active)[:nst]  # fragments that left the box are gone (mass_left_the_box)
            dmg = np.asarray(P.point.damage)[:nst][on]
            vol = np.asarray(P.mass)[:nst][on] / np.asarray(P.point.density)[:nst][on]
            x = np.asarray(P.x)[:nst, :nd][on]
            damaged = dmg >= 0.5
            out["structures"] = {
                "max_displacement": float(hist["structure_max_displacement"][-1]),
                "max_damage": float(dmg.max(initial=0.0)), "max_plastic_strain": float(hist["structure_max_plastic_strain"][-1]),
                "damaged_volume": float(vol[damaged].sum()),
                "damaged_fraction": float(vol[damaged].sum() / vol.sum()) if on.any() else None,
                "damaged_extent": ([[float(v) for v in x[damaged].min(axis=0)], [float(v) for v in x[damaged].max(axis=0)]]
                                   if damaged.any() else None),
                "mass_left_the_box": float(state.budget.structure_out),
                "failed_volume": float(vol[dmg >= 1.0].sum())}
            faces = _loaded_faces(sc, setup, state)
            if faces:
                out["structures"]["faces"] = faces
        return out

    def plots(self, folder: Path, sc: CfdmpScenario, setups: list, histories: list[dict], members: list[dict],
              finals: list) -> None:
        """Gauge overpressures, tracer displacements, the final pressure field, the structures' final damage
        (3D: the particles near the plane output.plot_plane_z), and the budget's residuals."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from blastfsi.plotting.fields import plot_particle_damage, plot_pressure_field
        from blastfsi.plotting.histories import gauge_histories, tracer_histories
        from blastfsi.plotting.units import scale, text

        folder.mkdir(parents=True, exist_ok=True)
        labels = _axis_names(sc.domain.geometry)
        if sc.output.gauges:
            gauge_histories(folder / "gauges.png", histories, sc.output.gauges)
        if sc.output.tracers:
            nd = sc.domain.ndim  # (the history's columns are named x, y, z in r-z too)
            tracer_histories(folder / "tracers.png", histories, sc.output.tracers, AXES[:nd], labels=labels[:nd])
        grid = finals[0].grid
        plot_pressure_field(folder / "pressure.png", tuple(e[0] for e in grid.edges), grid.edges[0][1] - grid.edges[0][0],
                            grid.cell_fields["pressure"], axis_labels=labels,
                            title=f"{sc.name}: pressure at t = {text(sc.time.end, 'time')}",
                            z_plane=sc.output.plot_plane_z)
        particles = finals[0].particles
        solid = particles.point_fields["structure"] == 1.0
        if solid.any():
            plot_particle_damage(folder / "damage.png", particles.positions[solid],
                                 particles.point_fields["damage"][solid], cell_size=setups[0].grid.cell_size,
                                 axis_labels=labels,
                                 title=f"{sc.name}: structure damage at t = {text(sc.time.end, 'time')}",
                                 z_plane=sc.output.plot_plane_z)
            if sc.initial.kind == "charge" and "compressive_damage" in particles.point_fields:
                _face_damage_plot(folder / "faces.png", sc, particles, setups[0].grid.cell_size)
        h = histories[0]
        ts = scale(h["time"], "time")
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(h["time"] / ts.factor, h["mass_budget_residual"], label="mass")
        ax.plot(h["time"] / ts.factor, h["energy_transport_residual"], label="energy, transport")
        ax.plot(h["time"] / ts.factor, h["energy_budget_residual"], label="energy, coupling error")
        for key in h:
            if key.startswith("momentum_") and key.endswith("_budget_residual"):
                ax.plot(h["time"] / ts.factor, h[key], "--", label=f"momentum {key.split('_')[1]}, coupling error")
        ax.set_xlabel(ts.label("time")), ax.set_ylabel("budget residual (relative) [-]"), ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(folder / "budget.png", dpi=120)
        plt.close(fig)


METHOD = register(Cfdmp())


def history(static: Static, s: State | None = None, params: Params | None = None) -> timeloop.Row:
    """The history row of state ``s``: the system's budget (mass, energy and momentum, with their residuals
    against the totals at activation, 0 before it), the reactions, the structures' extremes, the tracers and
    the gauges. Without a state only its columns (``.columns``) can be read."""
    cs = static.coupling
    cfg = cs.euler
    nd, n = len(cfg.shape), cfg.n_materials
    axes = AXES[:nd]
    full = nd == 3 or cs.mpm.grid.axisymmetric  # (r-z: the rings' whole content)
    kg, J, mom = ("kg", "J", "kg*m/s") if full else (("kg/m", "J/m", "kg*m/s/m") if nd == 2 else
                                                        ("kg/m^2", "J/m^2", "kg*m/s/m^2"))

    @functools.cache
    def sums():  # totals, account against the baseline, residual scales (traced: only when s is given)
        P = s.mpm.particles
        total, euler, particles, reservoirs, structure = system_totals(s.U, P, s.reservoirs, params.layout, cs)
        account = (total + s.budget.boundary_out).at[n:].add(-s.budget.reaction)
        scale = jnp.where(s.coupled, jnp.abs(s.baseline), 1.0)
        # with the MPM steps' change and the face pressure transfer booked: the transport alone
        transport = account[n:] - s.baseline[n:] - (s.budget.mpm_step - s.budget.pressure_transfer)
        # momentum relative to sqrt(2 M E) at activation (the momentum the system's energy could carry)
        p_scale = jnp.where(s.coupled, jnp.sqrt(2.0 * jnp.sum(scale[:n]) * scale[-1]), 1.0)
        return dict(total=total, euler=euler, particles=particles, reservoirs=reservoirs, structure=structure,
                    account=account, scale=scale, transport=transport, p_scale=p_scale)

    def when_coupled(value):
        return jnp.where(s.coupled, value, 0.0)

    row = timeloop.Row()
    row.add("time", "s", lambda: s.t)
    row.add("coupled", "1", lambda: s.coupled)
    row.add("particles", "1", lambda: jnp.sum(s.mpm.particles.active))
    row.add("mass_euler", kg, lambda: jnp.sum(sums()["euler"][:n]))
    row.add("mass_gas_particles", kg, lambda: jnp.sum(sums()["particles"][:n]))
    row.add("mass_structures", kg, lambda: sums()["structure"])
    row.add("mass_reservoirs", kg, lambda: jnp.sum(sums()["reservoirs"][:n]))
    row.add("mass_boundary_out", kg, lambda: jnp.sum(s.budget.boundary_out[:n]))
    row.add("mass_budget_residual", "1", lambda: when_coupled(
        (jnp.sum(sums()["account"][:n]) - jnp.sum(s.baseline[:n])) / jnp.sum(sums()["scale"][:n])))
    row.add("energy_euler", J, lambda: sums()["euler"][-1])
    row.add("energy_particles", J, lambda: sums()["particles"][-1])
    row.add("energy_reservoirs", J, lambda: sums()["reservoirs"][-1])
    row.add("energy_boundary_out", J, lambda: s.budget.boundary_out[-1])
    row.add("energy_pressure_transfer", J, lambda: s.budget.pressure_transfer[-1])
    row.add("energy_budget_residual", "1", lambda: when_coupled(
        (sums()["account"][-1] - s.baseline[-1]) / sums()["scale"][-1]))
    row.add("energy_mpm_step", J, lambda: s.budget.mpm_step[-1])
    row.add("energy_transport_residual", "1", lambda: when_coupled(sums()["transport"][-1] / sums()["scale"][-1]))
    for a in conserved_momentum_axes(cfg.geometry, nd):
        row.add(f"momentum_{AXES[a]}_budget_residual", "1", lambda a=a: when_coupled(
            (sums()["account"][n + a] - s.baseline[n + a]) / sums()["p_scale"]))
        row.add(f"momentum_{AXES[a]}_transport_residual", "1",
                lambda a=a: when_coupled(sums()["transport"][a] / sums()["p_scale"]))
    row.add_block([(f"reaction_impulse_{a}", mom) for a in axes] + [("reaction_work", J)], lambda: s.budget.reaction)
    row.add_block([(f"momentum_{a}", mom) for a in axes], lambda: sums()["total"][n:n + nd])
    if cs.n_structure:
        def on():  # (fragments that left the box no longer count)
            return s.mpm.particles.active[:cs.n_structure]

        def largest(values):
            return jnp.max(jnp.where(on(), values[:cs.n_structure], 0.0))

        P = None if s is None else s.mpm.particles
        row.add("structure_max_displacement", "m",
                lambda: largest(jnp.linalg.norm(P.x[:cs.n_structure] - params.structure_x0, axis=1)))
        row.add("structure_max_damage", "1", lambda: largest(P.point.damage))
        row.add("structure_max_plastic_strain", "1", lambda: largest(P.point.plastic_strain))
    tracers = jnp.asarray(static.tracers, jnp.int32)  # (structure slots: never deleted or moved)
    row.add_block(tracer_columns(len(static.tracers), axes),
                  lambda: jnp.stack(tracer_row(s.mpm.particles, tracers, params.structure_x0[tracers], nd)))
    if static.gauge_cells:
        def gauge_values():
            prim = cp.flat_primitives(Cfdmp._view(s, cs, params.layout), params.euler.eos, cfg)
            g = jnp.asarray(static.gauge_cells, jnp.int32)
            flat = [prim["pressure"][g] - params.reference_pressure, prim["rho"][g]]
            flat += [prim["velocity"][k][g] for k in range(nd)]
            return jnp.stack(flat, axis=1)

        columns = []
        for k in range(len(static.gauge_cells)):
            columns += [(f"gauge{k}_overpressure", "Pa"), (f"gauge{k}_density", "kg/m^3")]
            columns += [(f"gauge{k}_velocity_{a}", "m/s") for a in axes]
        row.add_block(columns, gauge_values)
    return row


def _face_damage_plot(png, sc: CfdmpScenario, particles, cell_size: float) -> None:
    """plots/faces.png: the failure (damage 1) on the concrete's face toward the charge and the tensile damage
    on the opposite face, in the reference configuration (000 Fig. 14)."""
    from blastfsi.plotting.fields import plot_face_damage
    from blastfsi.plotting.units import text

    f = particles.point_fields
    concrete = ~np.isnan(f["compressive_damage"])
    if not concrete.any():
        return
    nd = particles.positions.shape[1]
    reference = (particles.positions - np.nan_to_num(f["displacement"]))[concrete]
    sides = damage.sides_toward(sc.initial.center[-1], reference[:, -1])
    if sides is None:
        return
    loaded, back = sides
    front_layer = damage.face_layer(reference[:, -1], loaded, cell_size)  # (one cell deep)
    back_layer = damage.face_layer(reference[:, -1], back, cell_size)
    lateral = reference[:, :nd - 1]
    plot_face_damage(png, [(f"{loaded} face: failed (damage 1)", lateral[front_layer],
                            (f["damage"][concrete][front_layer] >= 1.0).astype(float)),
                           (f"{back} face: tensile damage D_t", lateral[back_layer],
                            f["tensile_damage"][concrete][back_layer])],
                     axisymmetric=sc.domain.geometry == "axisymmetric",
                     title=f"{sc.name}: concrete faces at t = {text(sc.time.end, 'time')} (reference positions)")


BACK_FACE_THRESHOLDS = (0.5, 0.75, 0.99)  # of the tensile damage D_t (concrete-25mpa spalls at 0.99)


def _loaded_faces(sc: CfdmpScenario, setup: problem.Setup, state: State) -> list[dict]:
    """Per HJC structure under a charge, on its face toward the charge (normal to the last axis): the zone of
    failed particles (damage 1, crushed or spalled: 000 Sec. 5.3's failure area) and of compressive failure
    (HJC damage), and on the opposite face the tensile damage (diagnostics.damage); damaged areas mirrored
    across symmetry planes through the charge's axis."""
    if sc.initial.kind != "charge":
        return []
    nd, nst = setup.euler.grid.ndim, setup.coupling.structure_particles
    axis = nd - 1
    center = np.asarray(sc.initial.center, float)
    P = state.mpm.particles
    material = np.asarray(P.material)[:nst]
    fields = mpm.model_output_fields(material, np.asarray(P.point.history)[:nst], setup.models, setup.model_params)
    failed = np.asarray(P.point.damage)[:nst]
    reference, volume0 = np.asarray(setup.structures.x)[:, :nd], np.asarray(setup.structures.volume0)
    axisymmetric = sc.domain.geometry == "axisymmetric"
    mirror = 1.0
    for a in range(nd if axisymmetric else 0, nd - 1):
        if getattr(sc.boundaries, AXES[a])[0] == "symmetry" and center[a] == sc.domain.lower[a]:
            mirror *= 2.0
    out = []
    for b, body in enumerate(sc.structures):
        mine = setup.body == b
        if setup.models[material[mine][0]].name != "hjc":
            continue
        sides = damage.sides_toward(center[axis], reference[mine, axis])
        if sides is None:
            continue
        loaded, back = sides

        def face(values, side, **kw):
            return damage.damaged_face(reference[mine], volume0[mine], values[mine], normal_axis=axis, side=side,
                                       spacing=setup.grid.cell_size / body.particles_per_cell,
                                       rows=body.particles_per_cell, load_axis=center,
                                       ring_width=setup.grid.cell_size, mirror=mirror,
                                       planar=nd == 2 and not axisymmetric, **kw)

        front = face(failed, loaded)
        out.append({"structure": b, "loaded_face": f"{loaded} {AXES[axis]}",
                    "crushing_diameter": next(r["diameter"] for r in front["by_threshold"] if r["threshold"] == 1.0),
                    "crushing_diameter_definition": (
                        "diameter of the zone around the charge's axis where at least half of the loaded face's area "
                        "(one cell deep, reference configuration; rings one cell wide) failed (damage 1: crushed or "
                        "spalled)"),
                    "breach_diameter": damage.breach_diameter(reference[mine], volume0[mine], failed[mine],
                                                              normal_axis=axis, load_axis=center,
                                                              ring_width=setup.grid.cell_size),
                    "breach_diameter_definition": (
                        "diameter of the zone around the charge's axis where at least half of the structure's "
                        "volume through its thickness failed"),
                    "failed": front, "compressive_damage": face(fields["compressive_damage"], loaded),
                    "back_face": f"{back} {AXES[axis]}",
                    "back_face_tensile_damage": face(fields["tensile_damage"], back, thresholds=BACK_FACE_THRESHOLDS)})
    return out



def _blast_inflow(U, U_fed, budget: cp.Budget, lay: cp.Layout, cs: cp.Static):
    """(U_fed, budget): the blast layer's change of the Eulerian-only cells' content (mass per material,
    momentum, energy; see :func:`system_totals`) booked as inflow through the domain boundary."""
    cfg = cs.euler
    n, d = cfg.n_materials, len(cfg.shape)
    k = ek.config.layout(cfg)
    V = lay.cell_volume.reshape(cfg.shape)
    axes = tuple(range(1, U.ndim))

    def content(X):
        rows = jnp.concatenate([X[:n], X[k.mom:k.mom + d], X[k.energy:k.energy + 1]])
        return jnp.sum(jnp.where(lay.outside, rows * V, 0.0), axis=axes)

    return U_fed, budget._replace(boundary_out=budget.boundary_out - (content(U_fed) - content(U)))


def _activate(s: State, params: Params, cs: cp.Static) -> State:
    """The coupling starts: the box's gas becomes particles and the budget's baseline is taken; the gas
    of box cells that did not become particles (inside structures) is booked as ``displaced``."""
    lay = params.layout
    prim = cp.flat_primitives(s.U, params.euler.eos, cs.euler)
    ms, required = cp.activate(s.U, s.mpm, prim, params.euler.eos, params.mpm, cs, lay)
    box_gas = system_totals(s.U, s.mpm.particles, s.reservoirs, lay._replace(outside=~lay.outside), cs)[1]
    created = (system_totals(s.U, ms.particles, s.reservoirs, lay, cs)[2]
               - system_totals(s.U, s.mpm.particles, s.reservoirs, lay, cs)[2])
    rows, gas_mass = cp.gas_rows(ms.particles, cs)
    U = cp.fictitious(s.U, rows, gas_mass, lay, s.U)
    baseline = system_totals(U, ms.particles, s.reservoirs, lay, cs)[0]
    budget = s.budget._replace(required=required.astype(jnp.int32))
    return s._replace(U=U, mpm=ms, budget=budget, coupled=jnp.asarray(True), baseline=baseline,
                      displaced=box_gas - created)
