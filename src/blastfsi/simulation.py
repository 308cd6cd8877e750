"""The driver: builds the batched initial state, advances it in compiled chunks,
and schedules field output, checkpoints, progress and the summary.

Physics lives in :mod:`blastfsi.lagrangian1d.scheme`; this module only schedules.
Every run is an ensemble (batch of size >= 1) advanced by one vmapped,
jitted ``advance``: a sweep of plate masses or intensities is one call.
"""
from __future__ import annotations

import functools
import time as wallclock
from dataclasses import dataclass
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi.eos import ideal_gas
from blastfsi.io import results
from blastfsi.lagrangian1d import scheme
from blastfsi.problems import plate1d
from blastfsi.scenario import Scenario, ScenarioError, member_scenario, parse


class SimulationError(RuntimeError):
    """A run stopped on a non-physical state or an exhausted step budget."""


@dataclass
class RunResult:
    scenario: Scenario
    members: list[dict]  # the sweep overrides of each member
    setups: list[plate1d.Setup]
    summaries: list[dict]
    histories: list[dict]  # column name -> array, per member
    state: scheme.State  # final batched state
    out_dir: Path | None

    @property
    def summary(self) -> dict:
        """One member: its summary; an ensemble: each key maps to the list over members."""
        if len(self.summaries) == 1:
            return dict(self.summaries[0])
        keys = dict.fromkeys(k for s in self.summaries for k in s)  # union, in order
        out = {k: [s.get(k) for s in self.summaries] for k in keys}
        out["members"] = self.members
        return out


@functools.lru_cache(maxsize=None)
def batched_advance(left_velocity_set: bool, right_fixed: bool):
    """jit(vmap(advance)) for one boundary configuration; compiled once per shapes."""
    def one(state, t_stop, max_steps, sample_interval, e0, x_right0, num, bc, gauges):
        return scheme.advance(state, t_stop, max_steps, sample_interval, e0, x_right0, num, bc, gauges,
                              left_velocity_set, right_fixed)

    vm = jax.vmap(one, in_axes=(0, None, None, None, 0, 0, 0, 0, None))
    return jax.jit(vm, donate_argnums=(0,))


def _stack(setups: list[plate1d.Setup], n_samples: int, n_gauges: int, dtype):
    def arr(values):
        return jnp.asarray(np.stack(values), dtype=dtype)

    states = [scheme.initial_state(jnp.asarray(s.x, dtype), jnp.asarray(s.v, dtype), jnp.asarray(s.e, dtype),
                                   jnp.asarray(s.zone_mass, dtype), n_samples, n_gauges) for s in setups]
    state = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *states)
    num = scheme.Numerics(*[arr([s.numerics[i] for s in setups]) for i in range(4)])
    bc = scheme.Boundaries(*[arr([s.boundaries[i] for s in setups]) for i in range(4)])
    e0 = jax.vmap(scheme.total_energy)(state, bc)
    x_right0 = arr([s.x[-1] for s in setups])
    return state, num, bc, e0, x_right0


def stop_times(sc: Scenario) -> tuple[list[float], list[float], list[float]]:
    end = sc.time.end
    fields = list(np.linspace(0.0, end, sc.output.fields)) if sc.output.fields >= 2 else (
        [end] if sc.output.fields == 1 else [])
    ckpt = []
    if sc.output.checkpoint_interval is not None:
        n = int(np.floor(end / sc.output.checkpoint_interval + 1e-9))
        ckpt = [k * sc.output.checkpoint_interval for k in range(1, n + 1)]
    return fields, ckpt, sorted(set(fields) | set(ckpt) | {end})


def _fields_of(state: scheme.State, k: int, gamma: float) -> dict:
    x = np.asarray(state.x[k])
    m = np.asarray(state.zone_mass[k])
    e = np.asarray(state.e[k])
    q = np.asarray(state.q[k])
    rho = m / np.diff(x)
    return {"x": x, "velocity": np.asarray(state.v[k]), "density": rho,
            "pressure": ideal_gas.pressure(rho, e, gamma) + q, "internal_energy": e, "viscous_pressure": q}


NODE_FIELDS = ("velocity",)
ZONE_FIELDS = ("density", "pressure", "internal_energy", "viscous_pressure")


def _prepare(data: dict | list[dict]):
    """A scenario with an optional sweep, or a list of sweep-free scenarios that
    share grid.cells, time and output settings (e.g. different domain lengths),
    as (first scenario, member overrides, setups)."""
    if isinstance(data, list):
        scs = [parse(d) for d in data]
        for key in ("grid", "time", "output"):
            if any(getattr(s, key) != getattr(scs[0], key) for s in scs):
                raise ScenarioError(f"a batch of scenarios must share its [{key}] table")
        return scs[0], [{"member": k} for k in range(len(scs))], [plate1d.build(s) for s in scs]
    sc = parse(data)
    members = sc.members()
    member_scs = [member_scenario(data, m) if m else sc for m in members]
    return sc, members, [plate1d.build(s) for s in member_scs]


def run(data: dict | list[dict], out: Path | None = None, *, overwrite: bool = False, progress: bool = False,
        restart: bool = False, chunk_steps: int = 20_000) -> RunResult:
    """Run a scenario given as a raw dict (or a list of them, see ``_prepare``)
    as one batched computation. With ``restart``, ``out`` is an existing
    results directory whose scenario and latest checkpoint are used."""
    sc, members, setups = _prepare(data)
    dtype = jnp.float32 if sc.numerics.precision == "float32" or not jax.config.jax_enable_x64 else jnp.float64
    flags = {(s.left_velocity_set, s.right_fixed) for s in setups}
    if len(flags) != 1:
        raise ScenarioError("all ensemble members must share boundary kinds")
    advance = batched_advance(*flags.pop())
    n_samples = sc.output.history_samples
    sample_interval = sc.time.end / (n_samples - 1)
    gauges = scheme.Gauges(jnp.asarray(sc.output.gauges, dtype).reshape(-1), jnp.asarray(sc.gas.pressure, dtype))
    state, num, bc, e0, x_right0 = _stack(setups, n_samples, len(sc.output.gauges), dtype)
    field_times, ckpt_times, stops = stop_times(sc)

    last_ckpt = None
    if restart:
        last_ckpt = results.latest_checkpoint(out)
        if last_ckpt is None:
            raise results.OutputError(f"--restart: no checkpoint in {out / 'checkpoints'}")
        leaves, _ = results.read_checkpoint(last_ckpt)
        state = scheme.State(**{k: jnp.asarray(leaves[k]) for k in scheme.State._fields})
        e0 = jnp.asarray(leaves["energy0"])
    elif out is not None:
        results.prepare_directory(out, overwrite)
        results.write_scenario(out, sc)
    snapshots = results.list_snapshots(out) if restart else []
    t_start = float(np.min(np.asarray(state.t)))
    snapshots = [s for s in snapshots if s[1] <= t_start]

    bar = _Progress(sc.time.end, enabled=progress)
    started = wallclock.perf_counter()
    gamma = sc.gas.gamma
    if out is not None and 0.0 in field_times and not restart:
        results.write_snapshot(out, 0, 0.0, [_fields_of(state, k, gamma) for k in range(len(setups))])
        snapshots.append((0, 0.0))
    try:
        for t_stop in (t for t in stops if t > t_start):
            while np.any(np.asarray(state.t) < t_stop):
                state = advance(state, t_stop, chunk_steps, sample_interval, e0, x_right0, num, bc, gauges)
                _check(state, sc, last_ckpt)
                bar.update(float(np.min(np.asarray(state.t))), int(np.max(np.asarray(state.step))),
                           float(np.min(np.asarray(state.dt_prev))))
            if out is None:
                continue
            if t_stop in field_times:
                index = field_times.index(t_stop)
                results.write_snapshot(out, index, t_stop, [_fields_of(state, k, gamma) for k in range(len(setups))])
                snapshots.append((index, t_stop))
            if t_stop in ckpt_times:
                ckpt_index = ckpt_times.index(t_stop) + 1
                leaves = {k: np.asarray(v) for k, v in state._asdict().items()}
                leaves["energy0"] = np.asarray(e0)
                last_ckpt = results.write_checkpoint(out, ckpt_index, leaves, {"time": t_stop})
    finally:
        bar.close()
    wall = wallclock.perf_counter() - started

    columns = scheme.history_columns(len(sc.output.gauges))
    histories = [_history_dict(np.asarray(state.hist[k]), columns) for k in range(len(setups))]
    energies = np.asarray(jax.vmap(scheme.total_energy)(state, bc))
    summaries = [_summary(sc, setups[k], histories[k], state, float(energies[k]), k, wall) for k in range(len(setups))]
    result = RunResult(sc, members, setups, summaries, histories, state, out)
    if out is not None:
        _write_outputs(out, result, snapshots)
    return result


def _history_dict(rows: np.ndarray, columns) -> dict:
    rows = rows[np.isfinite(rows[:, 0])]  # samples never reached (a fault) stay unrecorded
    return {name: rows[:, i] for i, (name, _) in enumerate(columns)}


def _check(state: scheme.State, sc: Scenario, last_ckpt) -> None:
    where = f"last checkpoint: {last_ckpt}" if last_ckpt else "no checkpoint written yet"
    if np.any(np.asarray(state.faulted)):
        k = int(np.argmax(np.asarray(state.faulted)))
        member = jax.tree_util.tree_map(lambda leaf: np.asarray(leaf[k]), state)
        zone = max(int(scheme.first_fault(member)), 0)
        x = member.x
        raise SimulationError(
            f"non-physical state (NaN, tangled zone or non-positive internal energy) in member {k} at "
            f"t = {float(state.t[k]):.9g} s, step {int(state.step[k])}: zone {zone} at x = "
            f"{0.5 * (x[zone] + x[zone + 1]):.6g} m; {where}")
    if np.any(np.asarray(state.step) >= sc.time.max_steps):
        raise SimulationError(f"time.max_steps = {sc.time.max_steps} reached at t = {float(np.min(state.t)):.6g} s "
                              f"(end {sc.time.end} s); raise time.max_steps or coarsen grid.cells; {where}")


def _summary(sc: Scenario, setup: plate1d.Setup, hist: dict, state, energy: float, k: int, wall: float) -> dict:
    info = setup.info
    fixed = sc.plate.fixed
    v_plate = 0.0 if fixed else float(state.v[k, -1])
    impulse = float(state.face_impulse[k]) if fixed else float(state.v[k, -1]) * info["plate_areal_mass"]
    cr_theory = info.get("reflection_coefficient_theory")
    incident_impulse = info.get("incident_impulse")
    out = {
        "plate_velocity": v_plate,
        "plate_displacement": float(state.x[k, -1] - setup.x[-1]),
        "plate_impulse": impulse,
        "plate_impulse_max": float(np.max(hist["plate_impulse"])),
        "peak_overpressure": _finite(state.peak_face_overpressure[k]),
        "beta_s": info.get("beta_s"),
        "reflection_coefficient_theory": cr_theory,
        "impulse_ratio_theory": info.get("impulse_ratio_theory"),
        "impulse_ratio": impulse / (cr_theory * incident_impulse) if cr_theory and incident_impulse else None,
        "plate_areal_mass": info["plate_areal_mass"],
        "time": float(state.t[k]),
        "steps": int(state.step[k]),
        "wall_time": wall,
        "energy_error_relative": float(hist["energy_error"][-1]) / energy,
    }
    if sc.output.gauges:
        out["gauge_positions"] = list(sc.output.gauges)
        out["gauge_peak_overpressure"] = [_finite(v) for v in np.asarray(state.gauge_peak[k])]
        out["gauge_impulse"] = [_finite(v) for v in np.asarray(state.gauge_impulse[k])]
    if sc.incident.profile == "uniform":
        out["reflection_coefficient"] = _measured_reflection(hist, info)
        for key in ("arrival_time", "duration", "clean_duration", "f_R", "f_R_eq30", "free_surface_velocity"):
            out[key] = info.get(key)
        if info["duration"] > info["clean_duration"]:
            out["warning"] = (f"waves re-reflected by the piston reach the plate {info['clean_duration']:.4g} s after "
                              f"shock arrival, before the end of the run ({info['duration']:.4g} s after arrival); "
                              "lengthen domain.length or shorten time.end")
    if sc.incident.profile == "sedov":
        out["explosion_time"] = info["explosion_time"]
    return out


def _finite(value):
    """A float for JSON; None where nothing was measured (a gauge never inside the gas)."""
    value = float(value)
    return value if np.isfinite(value) else None


def _measured_reflection(hist: dict, info: dict):
    """Mean wall overpressure over the second half of the clean window, / p_s (002 Fig. 2)."""
    window = min(info["duration"], info["clean_duration"])
    t = hist["time"] - info["arrival_time"]
    sel = (t >= 0.5 * window) & (t <= window)
    if not np.any(sel):
        return None
    return float(np.mean(hist["plate_overpressure"][sel]) / info["incident_overpressure"])


def _write_outputs(out: Path, res: RunResult, snapshots) -> None:
    from blastfsi.plotting import gauge_histories, plate_histories

    many = len(res.setups) > 1
    columns = scheme.history_columns(len(res.scenario.output.gauges))
    for k, hist in enumerate(res.histories):
        name = f"history_member{k}.csv" if many else "history.csv"
        rows = np.stack([hist[n] for n, _ in columns], axis=1)
        results.write_history(out / name, columns, rows)
        if snapshots:
            results.write_xdmf(out, k, sorted(snapshots), NODE_FIELDS, ZONE_FIELDS, res.setups[k].x.size)
    results.write_summary(out, res.summary)
    if res.scenario.output.plots:
        plate_histories(out / "plots" / "plate_histories.png", res.histories, res.members)
        if res.scenario.output.gauges:
            gauge_histories(out / "plots" / "gauges.png", res.histories, res.scenario.output.gauges)


class _Progress:
    """Progress bar (simulated time, step, dt, ETA) on a terminal; silent otherwise."""

    def __init__(self, end: float, enabled: bool):
        self._bar = None
        if enabled:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._bar = Progress(TextColumn("[bold]t = {task.fields[t]:.4e} s"), BarColumn(),
                                 TextColumn("step {task.fields[step]}  dt = {task.fields[dt]:.2e} s"),
                                 TimeElapsedColumn(), TimeRemainingColumn(), transient=False)
            self._task = self._bar.add_task("run", total=end, t=0.0, step=0, dt=0.0)
            self._bar.start()

    def update(self, t: float, step: int, dt: float) -> None:
        if self._bar is not None:
            self._bar.update(self._task, completed=t, t=t, step=step, dt=dt)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
