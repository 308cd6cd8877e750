"""The ``euler`` method behind the driver's face (:class:`blastfsi.method.Method`):
initial data from :mod:`blastfsi.euler.problem`, the kernels of
:mod:`blastfsi.euler`, blast maps and gauges of :mod:`blastfsi.diagnostics.blast_maps`."""
from __future__ import annotations

import dataclasses
import functools

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import euler as kernels
from blastfsi import timeloop, xla
from blastfsi.detonation import kb_compare
from blastfsi.detonation.kb_compare import scenario_references
from blastfsi.diagnostics import blast_maps
from blastfsi.euler.scenario import EulerScenario
from blastfsi.scenario import AXES, ScenarioError, device_count
from blastfsi.method import Grid, register
from blastfsi.euler import problem

# blastfsi.plotting (matplotlib) is imported inside the plotting functions only: it loads when plots are drawn.

SCHEME_CODE = {"lax-wendroff": kernels.LAX_WENDROFF, "hllc-muscl": kernels.HLLC_MUSCL,
               "hllc-hancock": kernels.HLLC_HANCOCK}
LIMITER_CODE = {"van-leer": kernels.VAN_LEER, "minmod": kernels.MINMOD, "mc": kernels.MC}
GEOMETRY_CODE = {"cartesian": kernels.CARTESIAN, "cylindrical": kernels.CYLINDRICAL,
                 "spherical": kernels.SPHERICAL, "axisymmetric": kernels.CYLINDRICAL}


class State(NamedTuple):
    U: jnp.ndarray  # conservative rows (nvar, *shape), layout of blastfsi.euler.config
    peak: jnp.ndarray  # blast maps per cell, see blastfsi.diagnostics.blast_maps
    arrival: jnp.ndarray
    end: jnp.ndarray
    impulse: jnp.ndarray
    last: jnp.ndarray
    t: jnp.ndarray
    dt_prev: jnp.ndarray
    dt0: jnp.ndarray
    step: jnp.ndarray
    fault: jnp.ndarray
    hist: jnp.ndarray
    hist_next: jnp.ndarray


class Params(NamedTuple):
    kernel: kernels.Params
    reference_pressure: jnp.ndarray  # overpressure reference [Pa]
    arrival_threshold: jnp.ndarray  # [Pa]


class Static(NamedTuple):
    cfg: kernels.Config
    gauge_cells: tuple  # flat (C-order) cell index of each gauge


def _maps(s: State) -> blast_maps.BlastMaps:
    return blast_maps.BlastMaps(s.peak, s.arrival, s.end, s.impulse, s.last)


def _pressure(U, params: Params, cfg):
    return kernels.primitives(U, params.kernel, cfg)["pressure"]


def devices(sc: EulerScenario) -> int:
    """numerics.devices as a number of devices; ScenarioError naming the key where JAX sees fewer, or
    ("all") where grid.cells is not divisible by them."""
    n = device_count(sc.numerics.devices)
    if sc.numerics.devices == "all" and sc.grid.cells % n:
        raise ScenarioError(f"numerics.devices = \"all\" is {n} devices here, and grid.cells = {sc.grid.cells} is not "
                            f"divisible by {n} (the grid is split along x in equal slabs); give grid.cells a multiple "
                            f"of {n}, or numerics.devices a divisor of {sc.grid.cells}")
    return n


def placed(s: State, cfg) -> State:
    """``s`` with its grid-shaped leaves (U and the blast maps) constrained to the split of the grid across
    cfg.devices devices along x (:func:`blastfsi.xla.split_sharding`); unchanged on one device. Inside the
    compiled loop: the compiler partitions every computation on them by slab and exchanges halos."""
    if cfg.devices <= 1:
        return s
    ndim = len(cfg.shape)
    grid = xla.split_sharding(cfg.devices, ndim)
    rows = xla.split_sharding(cfg.devices, ndim + 1, axis=1)
    keep = jax.lax.with_sharding_constraint
    return s._replace(U=keep(s.U, rows), **{k: keep(getattr(s, k), grid) for k in blast_maps.BlastMaps._fields})


class Euler:
    name = "euler"
    scenario_model = EulerScenario

    def build(self, sc: EulerScenario) -> problem.Setup:
        n = devices(sc)  # (before a charge's 1D detonation)
        return dataclasses.replace(problem.build(sc), devices=n)

    def _cfg(self, setup: problem.Setup, sc: EulerScenario) -> kernels.Config:
        return kernels.Config(shape=setup.grid.shape, dx=float(setup.grid.dx),
                              geometry=GEOMETRY_CODE[setup.grid.geometry], bc=setup.bc,
                              scheme=SCHEME_CODE[sc.numerics.scheme], n_materials=len(setup.materials),
                              origin=tuple(float(v) for v in setup.grid.lower),
                              limiter=LIMITER_CODE[sc.numerics.limiter], devices=setup.devices,
                              characteristic=sc.numerics.limiting == "characteristic")

    def static(self, setup: problem.Setup, sc: EulerScenario) -> Static:
        flat = tuple(int(np.ravel_multi_index(c, setup.grid.shape)) for c in setup.gauge_cells)
        return Static(self._cfg(setup, sc), flat)

    def params(self, setup: problem.Setup, dtype) -> Params:
        return Params(kernels.Params(jnp.asarray(setup.eos, dtype), jnp.asarray(setup.cfl, dtype),
                                     problem.blast_params(setup, dtype)),
                      jnp.asarray(setup.reference_pressure, dtype),
                      jnp.asarray(setup.arrival_fraction * setup.reference_pressure, dtype))

    def initial_state(self, setup: problem.Setup, sc: EulerScenario, n_samples: int, dtype) -> State:
        static = self.static(setup, sc)
        params = self.params(setup, dtype)
        U = kernels.conservative(jnp.asarray(setup.rho_k, dtype), jnp.asarray(setup.alpha[0], dtype),
                                 jnp.asarray(setup.velocity, dtype), jnp.asarray(setup.pressure, dtype),
                                 params.kernel, static.cfg)
        maps = blast_maps.initial(_pressure(U, params, static.cfg) - params.reference_pressure)
        n_cols = len(self.history_columns(setup, sc))
        clock = timeloop.clock(n_samples, n_cols, dtype)  # a charge's clock starts at its remap time
        clock["t"] = jnp.asarray(setup.start_time, dtype)
        return State(U, *maps, **clock)

    def advance(self, state, params: Params, static: Static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        cfg = static.cfg

        def stable_dt(s):
            return kernels.stable_dt(s.U, params.kernel, cfg)

        def step(s, dt):
            U = kernels.step(s.U, dt, params.kernel, cfg, s.t, parity=s.step)
            dp = _pressure(U, params, cfg) - params.reference_pressure
            maps = blast_maps.update(_maps(s), dp, s.t, dt, params.arrival_threshold)
            return placed(s._replace(U=U, **maps._asdict()), cfg)

        def history_row(s):
            return history(static, s, params).values(s.t.dtype)

        return timeloop.run_until(placed(state, cfg), t_stop, max_steps, sample_interval, dt_floor_fraction,
                                  stable_dt=stable_dt, step=step, history_row=history_row)

    def history_columns(self, setup: problem.Setup, sc: EulerScenario) -> tuple:
        return history(self.static(setup, sc)).columns

    def _cell_fields(self, state: State, setup: problem.Setup, cfg) -> dict:
        params = self.params(setup, np.asarray(state.U).dtype)
        prim = {k: np.asarray(v) for k, v in kernels.primitives(jnp.asarray(state.U), params.kernel, cfg).items()}
        out = {"density": prim["rho"], "pressure": prim["pressure"],
               "velocity": np.moveaxis(prim["velocity"], 0, -1), "internal_energy": prim["internal_energy"],
               "sound_speed": prim["sound_speed"]}
        if len(setup.materials) == 2:
            out["products_fraction"] = prim["products_fraction"]
        arrival = np.asarray(state.arrival)
        out.update(peak_overpressure=np.asarray(state.peak),
                   arrival_time=np.where(np.isfinite(arrival), arrival, np.nan),
                   positive_impulse=np.asarray(state.impulse),
                   positive_duration=np.asarray(blast_maps.duration(_maps(state), state.t)))
        return out

    def snapshot(self, state: State, setup: problem.Setup) -> Grid:
        g = setup.grid
        edges = tuple(lo + np.arange(n + 1) * g.dx for lo, n in zip(g.lower, g.shape))
        cfg = kernels.Config(g.shape, float(g.dx), GEOMETRY_CODE[g.geometry], setup.bc, 0, len(setup.materials),
                             tuple(float(v) for v in g.lower))
        return Grid(edges=edges, cell_fields=self._cell_fields(state, setup, cfg))

    def locate_fault(self, state: State, setup: problem.Setup) -> str:
        g = setup.grid
        cfg = kernels.Config(g.shape, float(g.dx), GEOMETRY_CODE[g.geometry], setup.bc, 0, len(setup.materials),
                             tuple(float(v) for v in g.lower))
        params = self.params(setup, np.asarray(state.U).dtype)
        U = jnp.asarray(state.U)
        flat = int(kernels.first_bad_cell(U, params.kernel, cfg))
        prim = kernels.primitives(U, params.kernel, cfg)
        if flat < 0:  # a collapsed step: name the cell with the fastest signal
            speed = signal_speed(prim)
            flat = int(np.argmax(speed))
            what = f"fastest signal {speed.reshape(-1)[flat]:.4g} m/s"
        else:
            what = (f"density {float(np.asarray(prim['rho']).reshape(-1)[flat]):.4g} kg/m^3, "
                    f"pressure {float(np.asarray(prim['pressure']).reshape(-1)[flat]):.4g} Pa")
        idx = np.unravel_index(flat, g.shape)
        centre = [g.lower[k] + (i + 0.5) * g.dx for k, i in enumerate(idx)]
        where = ", ".join(f"{a} = {c:.6g} m" for a, c in zip(AXES, centre))
        return f"cell {tuple(int(i) for i in idx)} at {where} ({what})"

    def summary(self, sc: EulerScenario, setup: problem.Setup, hist: dict, state: State) -> dict:
        t = float(state.t)
        out = {"scheme": sc.numerics.scheme, "geometry": setup.grid.geometry, "materials": list(setup.materials),
               "dx": setup.grid.dx}
        if sc.numerics.scheme != "lax-wendroff":  # the HLLC schemes' limiter and what it acts on
            out["limiter"] = sc.numerics.limiter
            out["limiting"] = sc.numerics.limiting
        for q in ("mass", "energy"):
            first, last = hist[q][0], hist[q][-1]
            out[f"{q}_change_relative"] = float((last - first) / abs(first)) if first != 0 else None
        gauges = []
        for k, (pos, cell) in enumerate(zip(setup.gauges, setup.gauge_cells)):
            arrival = float(state.arrival[cell])
            end = float(state.end[cell])
            gauges.append({
                "position": [float(v) for v in pos],
                "peak_overpressure": float(state.peak[cell]),
                "impulse": float(state.impulse[cell]),
                "arrival_time": arrival if np.isfinite(arrival) else None,
                "positive_phase_duration": (min(end, t) - arrival) if np.isfinite(arrival) else None,
            })
        info = setup.charge
        if info is not None and gauges:
            if info.kb_burst is not None:  # KB holds for spherical TNT charges only (None: a 2D cylinder)
                r = kb_compare.distances(setup.gauges, info.charge_center)
                refs = kb_compare.scenario_references(sc, info.charge_center, info.kb_burst,
                                                      float(setup.grid.dx))  # by position, or set
                gauges = kb_compare.compare(gauges, r, info.charge_mass, info.kb_burst, refs)
            out.update(charge_mass=info.charge_mass, remap_time=info.remap_time, one_d_air_zone=info.one_d_air_zone)
        out["gauges"] = gauges
        return out

    def plots(self, folder, sc: EulerScenario, setups: list, histories: list[dict], members: list[dict],
              finals: list) -> None:
        """Gauge overpressure histories and the final pressure field (3D: the plane output.plot_plane_z), member 0."""
        from blastfsi.plotting.fields import plot_pressure_field
        from blastfsi.plotting.histories import gauge_histories
        from blastfsi.plotting.units import text

        if sc.output.gauges:
            gauge_histories(folder / "gauges.png", histories, sc.output.gauges)
            info = setups[0].charge
            if info is not None and info.kb_burst is not None:
                from blastfsi.plotting.kb import kb_gauge_histories

                kb_gauge_histories(folder / "gauges_kb.png", histories[0], sc.output.gauges, info.charge_mass,
                                   info.kb_burst, centre=info.charge_center,
                                   references=scenario_references(sc, info.charge_center, info.kb_burst,
                                                                  float(setups[0].grid.dx)))
        grid = finals[0]
        labels = ("r", "z") if sc.domain.geometry != "cartesian" else ("x", "y", "z")
        plot_pressure_field(folder / "pressure.png", tuple(e[0] for e in grid.edges), grid.edges[0][1] - grid.edges[0][0],
                            grid.cell_fields["pressure"], axis_labels=labels,
                            title=f"{sc.name}: pressure at t = {text(sc.time.end, 'time')}",
                            z_plane=sc.output.plot_plane_z)


def _per(cfg: kernels.Config, unit: str) -> str:
    """``unit`` of a whole-domain total: per metre (1D cylinder, 2D plane) or per square metre (1D slab) where
    the grid stands for an infinite extent."""
    nd = len(cfg.shape)
    if nd == 3 or cfg.geometry == kernels.SPHERICAL or (cfg.geometry == kernels.CYLINDRICAL and nd == 2):
        return unit
    if cfg.geometry == kernels.CYLINDRICAL or nd == 2:
        return f"{unit}/m"
    return f"{unit}/m^2"


METHOD = register(Euler())


def history(static: Static, s: State | None = None, params: Params | None = None) -> timeloop.Row:
    """The history row of state ``s``: the time, the grid's mass, energy and momentum, and per gauge the
    overpressure, density and velocity of its cell. Without a state only its columns (``.columns``) can be
    read."""
    cfg = static.cfg
    nd = len(cfg.shape)
    gauges = jnp.asarray(static.gauge_cells, jnp.int32)

    @functools.cache
    def totals():  # (traced: only when s is given)
        return kernels.total(s.U, cfg)

    @functools.cache
    def prim():
        return kernels.primitives(s.U, params.kernel, cfg)

    def at_gauges(field):
        return field.reshape(-1)[gauges]

    row = timeloop.Row()
    row.add("time", "s", lambda: s.t)
    row.add("mass", _per(cfg, "kg"), lambda: totals()[0])
    row.add("energy", _per(cfg, "J"), lambda: totals()[2])
    row.add_block([(f"momentum_{a}", _per(cfg, "kg*m/s")) for a in AXES[:nd]], lambda: totals()[1])
    for k in range(len(static.gauge_cells)):
        row.add(f"gauge{k}_overpressure", "Pa", lambda k=k: at_gauges(prim()["pressure"])[k] - params.reference_pressure)
        row.add(f"gauge{k}_density", "kg/m^3", lambda k=k: at_gauges(prim()["rho"])[k])
        row.add_block([(f"gauge{k}_velocity_{a}", "m/s") for a in AXES[:nd]],
                      lambda k=k: jnp.stack([at_gauges(prim()["velocity"][d])[k] for d in range(nd)]))
    return row


def signal_speed(prim: dict) -> np.ndarray:
    """Each cell's fastest signal max_d |u_d| + c (m/s) from :func:`blastfsi.euler.primitives` (the CFL step's,
    named when a step collapses)."""
    return np.asarray(prim["sound_speed"]) + np.max(np.abs(np.asarray(prim["velocity"])), axis=0)
