"""The ``mpm`` method behind the driver's face (:class:`blastfsi.method.Method`):
particles and grid from :mod:`blastfsi.mpm.problem`, the MUSL step of
:mod:`blastfsi.mpm.musl`, one ``timeloop.run_until``.

Snapshot (:class:`blastfsi.method.Particles`, active particles): ``density``,
``pressure`` (-tr(sigma)/3, without the bulk viscosity), ``viscous_pressure``
(q), ``velocity`` (n, ndim; r-z: v_r, v_z), ``stress`` the full Cauchy tensor
(n, 3, 3) (tension positive; 2D plane strain keeps sigma_zz, r-z keeps the hoop
stress sigma_thth as the zz entry), ``plastic_strain``, ``damage`` (1: failed),
``internal_energy`` (J/kg), ``material`` (index into summary ``materials``),
``body`` (index of the body, the impactor last) and the models' own fields
(``Model.output_fields``, NaN for the other materials): ``temperature`` (Johnson-Cook),
``compressive_damage`` and ``tensile_damage`` (HJC).

Histories: kinetic, internal (stress and q work, incl. plastic), plastic work
and external work, the energy balance kinetic + internal - initial - external
work, mass and momentum, the reactions (impulse and work of the grid's fixed and slip faces and of the
prescribed particles on the nodes, ``mpm.State.reaction``: an anvil's or a clamp's force); per tracer its displacement (summary: final and peak); per gauge (a point fixed
in space) the pressure, density and velocity of the active particle nearest to
it (NaN when none lies within one cell). Energies per unit area in 1D, per unit
length in 2D plane strain, whole rings in r-z.

Failure: a particle whose damage reaches 1 keeps its mass and compressive
response but no tension or deviatoric stress (the models'); the elastic energy
it held is released as kinetic energy of the neighbours or stays as internal
energy, so the budget stays closed (no erosion, nothing removed).
"""
from __future__ import annotations

import functools

from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import mpm, timeloop, xla
from blastfsi.method import Particles, register
from blastfsi.mpm import relaxation
from blastfsi.mpm.scenario import MPMScenario
from blastfsi.scenario import AXES, device_count
from blastfsi.mpm import problem

# blastfsi.plotting (matplotlib) is imported inside the plotting functions only: it loads when plots are drawn.

VOIGT_TO_TENSOR = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2]])  # Voigt [xx, yy, zz, yz, xz, xy] -> 3 x 3


class State(NamedTuple):
    mpm: mpm.State
    t: jnp.ndarray
    dt_prev: jnp.ndarray
    dt0: jnp.ndarray
    step: jnp.ndarray
    fault: jnp.ndarray
    hist: jnp.ndarray
    hist_next: jnp.ndarray


class Params(NamedTuple):
    mpm: mpm.Params
    tracer_x0: jnp.ndarray  # (T, 3) initial positions of the tracer particles
    gauges: jnp.ndarray  # (G, 3) gauge points


class Static(NamedTuple):
    config: mpm.Config
    tracers: tuple  # particle index of each tracer
    n_gauges: int  # output.gauges
    devices: int = 1  # numerics.devices: the pool is split over them (:func:`placed`)


def placed(s: State, devices: int) -> State:
    """``s`` with its particle arrays constrained to the split of the pool over ``devices`` devices in equal
    parts (:func:`blastfsi.xla.split_sharding` along the pool's axis); unchanged on one device. Inside the
    compiled loop every particle computation runs where its particle lies; the particle-to-grid sums are
    partial sums per device that the compiler adds across devices (an all-reduce of the nodal arrays), the
    grid update runs on every device, and the grid-to-particle step reads the (replicated) nodes locally."""
    if devices <= 1:
        return s
    P = jax.tree_util.tree_map(lambda a: jax.lax.with_sharding_constraint(a, xla.split_sharding(devices, a.ndim)),
                               s.mpm.particles)
    return s._replace(mpm=s.mpm._replace(particles=P))


def _cast(tree, dtype):
    return jax.tree_util.tree_map(
        lambda a: jnp.asarray(a, dtype) if jnp.issubdtype(jnp.asarray(a).dtype, jnp.floating) else jnp.asarray(a),
        tree)


def _energy_unit(grid: mpm.Grid, unit: str) -> str:
    """``unit`` of a whole-body total: per metre (plane strain) or per square metre (1D) where the grid stands
    for an infinite extent."""
    if grid.axisymmetric or grid.dim == 3:
        return unit
    return f"{unit}/m" if grid.dim == 2 else f"{unit}/m^2"


def tracer_columns(n: int, axes) -> list:
    """History columns of ``n`` tracers' displacements."""
    return [(f"tracer{k}_displacement_{a}", "m") for k in range(n) for a in axes]


def tracer_row(P, tracers, x0, d: int) -> list:
    """History entries of the tracer particles ``tracers``: displacement from x0 (T, 3), d components each."""
    return list((P.x[tracers, :d] - x0[:, :d]).reshape(-1))


def tracer_summary(hist: dict, n: int, axes) -> dict:
    """Per tracer and axis the final displacement and the peak one (the signed value of largest magnitude
    over the history: a plate's maximum deflection, where the final one is its permanent set)."""
    if not n:
        return {}
    series = [[np.asarray(hist[f"tracer{k}_displacement_{a}"]) for a in axes] for k in range(n)]
    return {"tracer_displacement": [[float(c[-1]) for c in t] for t in series],
            "tracer_peak_displacement": [[float(c[np.argmax(np.abs(c))]) for c in t] for t in series]}


def _pad3(points: np.ndarray) -> np.ndarray:
    """(n, 3) from (n, d) points, zero-padded."""
    return np.pad(points, ((0, 0), (0, 3 - points.shape[1])))


class MPM:
    name = "mpm"
    scenario_model = MPMScenario

    def build(self, sc: MPMScenario) -> problem.Setup:
        return problem.build(sc, device_count(sc.numerics.devices))

    def static(self, setup: problem.Setup, sc: MPMScenario) -> Static:
        relax = relaxation.gas_materials(setup.models, sc.numerics.pressure_relaxation)
        return Static(mpm.make_config(setup.grid, setup.models, shape=sc.numerics.shape,
                                      prescribed=setup.prescribed, relax=relax), setup.tracers, len(setup.gauges),
                      setup.devices)

    def params(self, setup: problem.Setup, dtype) -> Params:
        prm = mpm.make_params(setup.model_params, cfl=setup.cfl, q_quadratic=setup.q_quadratic,
                              q_linear=setup.q_linear, gravity=setup.gravity,
                              reference_pressure=setup.reference_pressure, dtype=dtype)
        x0 = np.asarray(setup.particles.x)[list(setup.tracers)].reshape(-1, 3)
        return Params(_cast(prm, dtype), jnp.asarray(x0, dtype), jnp.asarray(_pad3(setup.gauges), dtype))

    def initial_state(self, setup: problem.Setup, sc: MPMScenario, n_samples: int, dtype) -> State:
        prm = self.params(setup, dtype)
        s = mpm.initialize(_cast(setup.particles, dtype), prm.mpm, self.static(setup, sc).config)
        n_cols = len(self.history_columns(setup, sc))
        return State(s, **timeloop.clock(n_samples, n_cols, dtype))

    def advance(self, state, params: Params, static: Static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        cfg = static.config

        def stable_dt(s):
            return mpm.stable_dt(s.mpm, params.mpm, cfg)

        def step(s, dt):
            return placed(s._replace(mpm=mpm.step(s.mpm, dt, params.mpm, cfg)), static.devices)

        def history_row(s):
            return history(static, s, params).values(s.hist.dtype)

        return timeloop.run_until(placed(state, static.devices), t_stop, max_steps, sample_interval, dt_floor_fraction,
                                  stable_dt=stable_dt, step=step, history_row=history_row)

    def history_columns(self, setup: problem.Setup, sc: MPMScenario) -> tuple:
        return history(self.static(setup, sc)).columns

    def snapshot(self, state: State, setup: problem.Setup) -> Particles:
        P = state.mpm.particles
        on = np.asarray(P.active)
        d = setup.ndim
        ps = P.point
        stress = np.asarray(ps.stress)[on]
        fields = {"density": np.asarray(ps.density)[on],
                  "pressure": -stress[:, :3].sum(axis=1) / 3.0,
                  "viscous_pressure": np.asarray(P.q)[on],
                  "velocity": np.asarray(P.v)[on, :d],
                  "stress": stress[:, VOIGT_TO_TENSOR],
                  "plastic_strain": np.asarray(ps.plastic_strain)[on],
                  "damage": np.asarray(ps.damage)[on],
                  "internal_energy": np.asarray(ps.energy)[on],
                  "material": np.asarray(P.material)[on],
                  "body": np.pad(setup.body, (0, on.size - setup.body.size), constant_values=-1)[on]}
        fields.update(mpm.model_output_fields(fields["material"], np.asarray(ps.history)[on], setup.models,
                                              setup.model_params))
        return Particles(positions=np.asarray(P.x)[on, :d], point_fields=fields)

    def locate_fault(self, state: State, setup: problem.Setup) -> str:
        P = state.mpm.particles
        cfg = mpm.make_config(setup.grid, setup.models)
        k = int(mpm.first_fault(jax.tree_util.tree_map(jnp.asarray, state.mpm), cfg))
        if k < 0:  # a collapsed step: name the particle with the fastest signal
            speed = particle_signal_speed(P)
            k = int(np.argmax(speed))
            what = f"fastest signal {speed[k]:.4g} m/s"
        else:
            what = (f"density {float(P.point.density[k]):.4g} kg/m^3, velocity "
                    f"{np.asarray(P.v[k, :setup.ndim]).tolist()} m/s (non-finite, non-positive density or "
                    "outside the grid)")
        axes = ("r", "z") if setup.grid.axisymmetric else AXES
        where = ", ".join(f"{a} = {float(c):.6g} m" for a, c in zip(axes, np.asarray(P.x[k, :setup.ndim])))
        body = int(setup.body[k]) if k < setup.body.size else -1
        return f"particle {k} (body {body}, {setup.materials[int(P.material[k])]}) at {where} ({what})"

    def summary(self, sc: MPMScenario, setup: problem.Setup, hist: dict, state: State) -> dict:
        P = state.mpm.particles
        on = np.asarray(P.active)
        d = setup.ndim
        kinetic, internal = hist["kinetic_energy"], hist["internal_energy"]
        balance = kinetic + internal - (kinetic[0] + internal[0]) - hist["external_work"]
        scale = max(float(np.max(kinetic + internal)), float(np.max(np.abs(hist["external_work"]))), 1e-300)
        axes = ("r", "z") if setup.grid.axisymmetric else AXES[:d]
        out = {"particles": int(on.sum()), "capacity": int(on.size), "shape": sc.numerics.shape,
               "cell_size": setup.grid.cell_size, "grid_cells": list(setup.grid.cells),
               "materials": list(setup.materials), "bodies": list(setup.bodies),
               "mass": float(hist["mass"][-1]), "mass_change_relative": float(hist["mass"][-1] / hist["mass"][0] - 1.0),
               "kinetic_energy": float(kinetic[-1]), "internal_energy": float(internal[-1]),
               "plastic_work": float(hist["plastic_work"][-1]), "external_work": float(hist["external_work"][-1]),
               # a driven (prescribed, impactor) body does work that external_work does not count; a clamp does
               # none in the continuum (its grid nodes are at rest), so a clamped body's balance is reported
               "energy_balance_relative": None if setup.driven else float(balance[-1] / scale),
               # the same less the reactions' work (grid faces and prescribed particles on the nodes): also for
               # a driven body, whose driver's work is that of its nodes' reactions
               "energy_balance_with_reactions_relative": float((balance[-1] - hist["reaction_work"][-1]) / scale),
               "momentum": [float(hist[f"momentum_{a}"][-1]) for a in axes],
               # impulse and work of the grid's fixed/slip faces and the prescribed particles on the nodes
               "reaction": {"impulse": [float(hist[f"reaction_impulse_{a}"][-1]) for a in axes],
                            "work": float(hist["reaction_work"][-1])},
               "max_plastic_strain": float(np.max(np.asarray(P.point.plastic_strain)[on])),
               "max_damage": float(np.max(np.asarray(P.point.damage)[on])),
               "failed_particles": int(np.sum(np.asarray(P.point.damage)[on] >= 1.0))}
        out.update(tracer_summary(hist, len(setup.tracers), axes))
        if setup.period_theory is not None:
            out["period_theory"] = setup.period_theory
            out["period"] = (zero_crossing_period(hist["time"], hist[f"tracer0_displacement_{axes[0]}"])
                             if setup.tracers else None)
        if sc.impactor is not None:
            out.update(impactor_shape(np.asarray(P.x)[:, :d], setup, len(sc.bodies)))
        return out

    def plots(self, folder: Path, sc: MPMScenario, setups: list, histories: list[dict], members: list[dict],
              finals: list) -> None:
        """Energy histories of every member, tracer displacements, the final particles of member 0 coloured
        by pressure (1D: the pressure profile) and, with a damage model, the final damage (1D: the profiles
        of damage and of the models' tensile and compressive damage, which show a spall plane)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from blastfsi.plotting.common import plain, save
        from blastfsi.plotting.fields import plot_particle_damage
        from blastfsi.plotting.histories import tracer_histories
        from blastfsi.plotting.units import scale, text

        folder.mkdir(parents=True, exist_ok=True)
        axes = ("r", "z") if sc.grid.axisymmetric else AXES[:sc.grid.ndim]
        if sc.output.tracers:
            tracer_histories(folder / "tracers.png", histories, sc.output.tracers, axes)
        quantities = ("kinetic_energy", "internal_energy", "plastic_work")
        ts = scale(np.concatenate([h["time"] for h in histories]), "time")
        es = scale(np.concatenate([h[q] for h in histories for q in quantities]), "energy")
        per = _energy_unit(setups[0].grid, "J")[1:]  # ("/m^2" in 1D, "/m" in plane 2D)
        fig, ax = plt.subplots(figsize=(6, 4))
        for k, h in enumerate(histories):
            for q in quantities:
                ax.plot(h["time"] / ts.factor, h[q] / es.factor, label=f"{q} (member {k})" if len(histories) > 1 else q)
        ax.set_xlabel(ts.label("time"))
        ax.set_ylabel(f"energy [{es.unit}{per}]")
        plain(ax.xaxis, ax.yaxis)
        ax.legend(fontsize=7)
        fig.tight_layout()
        save(fig, folder / "energies.png")
        snap = finals[0]
        pos, f = snap.positions, snap.point_fields
        when = f"t = {text(sc.time.end, 'time')}"
        ls, ps = scale(pos, "length"), scale(f["pressure"], "pressure")
        fig, ax = plt.subplots(figsize=(6, 4))
        if pos.shape[1] == 1:
            order = np.argsort(pos[:, 0])
            ax.plot(pos[order, 0] / ls.factor, f["pressure"][order] / ps.factor, ".-", ms=2, lw=0.8)
            ax.set_ylabel(ps.label("pressure")), ax.grid(alpha=0.3)
        else:
            art = ax.scatter(pos[:, 0] / ls.factor, pos[:, 1] / ls.factor, c=f["pressure"] / ps.factor, s=2,
                             cmap="viridis")
            bar = fig.colorbar(art, ax=ax, label=ps.label("pressure"))
            plain(bar.ax.yaxis)
            ax.set_aspect("equal")
            ax.set_ylabel(ls.label(axes[1]))
        ax.set_xlabel(ls.label(axes[0]))
        plain(ax.xaxis, ax.yaxis)
        ax.set_title(f"{sc.name}: {when}")
        fig.tight_layout()
        save(fig, folder / "particles.png")
        if np.any(f["damage"] > 0.0) or "tensile_damage" in f:
            profiles = {name.replace("_", " "): f[name] for name in ("tensile_damage", "compressive_damage")
                        if name in f and pos.shape[1] == 1}
            plot_particle_damage(folder / "damage.png", pos, f["damage"], cell_size=setups[0].grid.cell_size,
                                 axis_labels=axes, title=f"{sc.name}: damage at {when}", profiles=profiles)


def zero_crossing_period(t: np.ndarray, signal: np.ndarray):
    """Period of an oscillation about zero: twice the mean spacing of its zero crossings
    (linear interpolation between samples); None with fewer than 3 crossings."""
    k = np.nonzero(np.sign(signal[1:]) * np.sign(signal[:-1]) < 0)[0]
    if len(k) < 3:
        return None
    crossings = t[k] - signal[k] * (t[k + 1] - t[k]) / (signal[k + 1] - signal[k])
    return float(2.0 * np.mean(np.diff(crossings)))


def impactor_shape(x: np.ndarray, setup: problem.Setup, body: int) -> dict:
    """Final length and footprint (impact-face) diameter of the impactor rod from its particles:
    length = axial extent of the particle centres + one spacing s; footprint = 2 (largest
    distance from the rod's axis among the particles within s of the anvil-side end + s/2)."""
    mine = setup.body == body
    pts = x[:setup.body.size][mine]
    s = float(setup.spacing[mine][0])
    axial = pts[:, -1]
    axis = np.asarray(setup.grid.origin[:-1], float)
    radial = np.linalg.norm(pts[:, :-1] - axis, axis=1)
    face = axial <= np.min(axial) + s
    return {"final_length": float(np.max(axial) - np.min(axial) + s),
            "footprint_diameter": float(2.0 * (np.max(radial[face]) + 0.5 * s))}


def history(static: Static, s: State | None = None, params: Params | None = None) -> timeloop.Row:
    """The history row of state ``s``: the time, the energies (kinetic, internal, plastic work, external work),
    mass and momentum, the supports' reaction, the tracers' displacements and per gauge the pressure, density
    and velocity of the nearest particle within one cell (NaN where none is). Without a state only its
    columns (``.columns``) can be read."""
    grid = static.config.grid
    d = grid.dim
    axes = ("r", "z") if grid.axisymmetric else AXES[:d]
    J, kg, mom = (_energy_unit(grid, u) for u in ("J", "kg", "kg*m/s"))
    P = None if s is None else s.mpm.particles

    @functools.cache
    def totals():  # (traced: only when s is given)
        return mpm.totals(P)

    row = timeloop.Row()
    row.add("time", "s", lambda: s.t)
    row.add("kinetic_energy", J, lambda: totals().kinetic)
    row.add("internal_energy", J, lambda: totals().internal)
    row.add("plastic_work", J, lambda: totals().plastic)
    row.add("external_work", J, lambda: mpm.energies(s.mpm)["external_work"])
    row.add("mass", kg, lambda: totals().mass)
    row.add_block([(f"momentum_{a}", mom) for a in axes], lambda: totals().momentum[:d])
    row.add_block([(f"reaction_impulse_{a}", mom) for a in axes] + [("reaction_work", J)], lambda: s.mpm.reaction)
    tracers = jnp.asarray(static.tracers, jnp.int32)
    row.add_block(tracer_columns(len(static.tracers), axes),
                  lambda: jnp.stack(tracer_row(P, tracers, params.tracer_x0, d)))

    @functools.cache
    def near():  # per gauge: [pressure, density, velocity...] of the nearest particle within one cell, or NaN
        dist = jnp.linalg.norm(P.x[None, :, :d] - params.gauges[:, None, :d], axis=2)
        dist = jnp.where(P.active[None, :], dist, jnp.inf)
        i = jnp.argmin(dist, axis=1)
        found = jnp.min(dist, axis=1) <= grid.cell_size
        pressure = -(P.point.stress[i, 0] + P.point.stress[i, 1] + P.point.stress[i, 2]) / 3.0
        cols = [pressure, P.point.density[i]] + [P.v[i, c] for c in range(d)]
        return jnp.where(found[:, None], jnp.stack(cols, axis=1), jnp.nan)

    for k in range(static.n_gauges):
        row.add_block([(f"gauge{k}_pressure", "Pa"), (f"gauge{k}_density", "kg/m^3")]
                      + [(f"gauge{k}_velocity_{a}", "m/s") for a in axes], lambda k=k: near()[k])
    return row


def particle_signal_speed(P) -> np.ndarray:
    """Each particle's signal |v| + c (m/s; -inf in the free slots), named when a step collapses."""
    speed = np.asarray(P.wave_speed) + np.linalg.norm(np.asarray(P.v), axis=1)
    return np.where(np.asarray(P.active), speed, -np.inf)


METHOD = register(MPM())
