"""The driver, one for every method: it only schedules.

A run is an ensemble (batch of size >= 1) of one method's members, advanced by
one vmapped, jitted ``advance`` (:mod:`blastfsi.method` describes the face the
driver calls). The driver compiles it once per method, static configuration
and array shapes (timed as ``compile_time``), and advances the batch in chunks
of steps (calls of about a second, :func:`next_chunk`) between the stop times of the output schedule: field snapshots,
checkpoints (any NamedTuple state, saved and restored leaf by leaf under its
field names: restart is bit for bit) and the end. Between chunks it updates
the progress bar and turns a fault flag into an error naming the time, step,
location and last checkpoint. It keeps the results directory current as the
run goes (:class:`_Recorder`: history rows appended, summary and ParaView
series rewritten at each output), so a run killed at any point leaves what it
computed; Ctrl-C stops it cleanly between chunks (:class:`RunInterrupted`).
At the end it writes the final summary and the plots. The summary (its
``status``: running, complete, interrupted or failed) times the run: ``compile_time``
(the time loop's compilation, a grown pool's included; tracing and a load from the persistent
compilation cache where it was compiled before, :mod:`blastfsi.runtime`), ``wall_time`` (the rest
of the time loop: ``loop_time``, the compiled loop's calls, plus
``output_time``, the snapshots and checkpoints written between them, with the
first-use compilation of their functions, plus the progress bar and checks);
a method with a growing particle pool adds ``pool_growths`` and ``pool_shrinks``, the times a full pool
was enlarged or a mostly empty one packed into fewer slots, and the time loop compiled again.
"""
from __future__ import annotations

import contextlib
import logging
import re
import signal
import sys
import tempfile
import threading
import time as wallclock
from dataclasses import dataclass, field
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import method as methods
from blastfsi import report
from blastfsi import runtime, xla
from blastfsi.io import results
from blastfsi.scenario import ScenarioBase, ScenarioError, expand, parse  # noqa: F401  (parse: for scripts)
from blastfsi.timeloop import FAULT_DT_COLLAPSE, FAULT_MESSAGES, FAULT_NONE, FAULT_POOL_FULL


class SimulationError(RuntimeError):
    """A run stopped on a fault (non-physical state, collapsed time step) or an exhausted step budget."""


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) stopped a run that writes a results directory, after the compiled chunk it was in:
    its checkpoint, history and summary (status "interrupted") are written; ``--restart`` continues it."""


@dataclass
class Result:
    """What a run gives back (also the Python API's result, :func:`blastfsi.run`)."""

    scenario: ScenarioBase
    members: list[dict]  # the sweep overrides of each member
    setups: list  # per member, the method's host-side set-up
    summaries: list[dict]
    histories: list[dict]  # column name -> array, per member
    state: tuple  # final batched state (device arrays)
    out_dir: Path | None
    method: methods.Method = field(repr=False)
    snapshots: list[tuple[int, float]] = field(default_factory=list)  # (index, time) written under out_dir/fields

    @property
    def summary(self) -> dict:
        """One member: its summary; an ensemble: each key maps to the list over members."""
        return _combined(self.summaries, self.members)

    @property
    def history(self) -> dict | list[dict]:
        """Column name -> samples (one member), or the list over members."""
        return self._one_or_list(self.histories)

    @property
    def gauges(self) -> dict | list[dict]:
        """Gauge histories: ``time`` (n,), ``position`` (G,) or (G, ndim), and per
        quantity an array (n, G) from the history columns gauge<k>_<quantity>."""
        position = np.asarray(self.scenario.output.gauges, float)
        return self._one_or_list([_gauge_histories(h, position) for h in self.histories])

    def fields(self, time: float | None = None) -> dict | list[dict]:
        """Field arrays (NumPy) of the final state (``time=None``, from memory) or
        of the snapshot at ``time`` (read back from the results directory); see
        ``as_fields`` of :data:`blastfsi.method.Snapshot`. Ensembles: a list per member."""
        with runtime.precision(self.scenario.numerics.precision):  # (the run's, for the method's derived fields)
            return self._fields(time)

    def _fields(self, time: float | None) -> dict | list[dict]:
        finals = _members(self.state)
        if time is None or (self.out_dir is None and time == float(np.min(np.asarray(self.state.t)))):
            return self._one_or_list([self.method.snapshot(s, setup).as_fields()
                                      for s, setup in zip(finals, self.setups)])
        if self.out_dir is None:
            raise ValueError("fields(time=...) reads the snapshots of a results directory, and this run was made "
                             "with out=None; only the final state (fields()) is kept in memory")
        tol = 1e-9 * self.scenario.time.end
        match = [i for i, t in self.snapshots if abs(t - time) <= tol]
        if not match:
            raise ValueError(f"no field snapshot at time {time!r} s; available: {[t for _, t in self.snapshots]}")
        kind = self.method.snapshot(finals[0], self.setups[0]).kind
        return self._one_or_list([results.read_snapshot(self.out_dir, kind, match[0], k).as_fields()
                                  for k in range(len(self.setups))])

    def _one_or_list(self, items: list):
        return items[0] if len(items) == 1 else items


def _combined(summaries: list[dict], members: list[dict]) -> dict:
    """One member: its summary; an ensemble: each key maps to the list over members, and ``members``."""
    if len(summaries) == 1:
        return dict(summaries[0])
    keys = dict.fromkeys(k for s in summaries for k in s)  # union, in order
    return {**{k: [s.get(k) for s in summaries] for k in keys}, "members": members}


def _gauge_histories(hist: dict, position: np.ndarray) -> dict:
    matches = [m for m in (re.fullmatch(r"gauge(\d+)_(.+)", c) for c in hist) if m]
    out = {"time": hist["time"], "position": position}
    for quantity in dict.fromkeys(m.group(2) for m in matches):
        out[quantity] = np.stack([hist[f"gauge{k}_{quantity}"] for k in range(len(position))], axis=1)
    return out


def _members(state) -> list:
    """The batched state as one NumPy state per member."""
    host = xla.to_host(state)
    n = np.shape(host.t)[0]
    return [jax.tree_util.tree_map(lambda leaf: leaf[k], host) for k in range(n)]


def _stack(trees: list, what: str):
    """Stack per-member pytrees along a new leading axis; members must agree in structure and shapes."""
    ref = jax.tree_util.tree_flatten_with_path(trees[0])[0]
    for k, tree in enumerate(trees[1:], start=1):
        for (path, a), (_, b) in zip(ref, jax.tree_util.tree_flatten_with_path(tree)[0]):
            if np.shape(a) != np.shape(b):
                raise ScenarioError(f"ensemble members must share array shapes (e.g. the grid): {what} "
                                    f"{jax.tree_util.keystr(path)} is {np.shape(a)} in member 0 but {np.shape(b)} "
                                    f"in member {k}")
    # stacked on the host and sent once per leaf: jnp.stack would compile a program for every leaf's shape
    # (~40 compilations, ~0.5 s, for one cfdmp member)
    return jax.tree_util.tree_map(lambda *xs: jnp.asarray(np.stack(xs)), *xla.to_host(trees))


def stop_times(sc: ScenarioBase, begin: float = 0.0) -> tuple[list[float], list[float], list[float]]:
    """(field snapshot times, checkpoint times, all stop times) of the output schedule of a run whose clock
    starts at ``begin`` (a charge's remap time: times count from the detonation). A checkpoint
    time within round-off (1e-9 x end) of a snapshot time or the end is that time: the time loop lands
    on every stop time, and two an ulp apart would cost a step of an ulp."""
    end = sc.time.end
    fields = [float(t) for t in np.linspace(begin, end, sc.output.fields)] if sc.output.fields >= 2 else (
        [end] if sc.output.fields == 1 else [])
    ckpt = []
    if sc.output.checkpoint_interval is not None:
        n = int(np.floor((end - begin) / sc.output.checkpoint_interval + 1e-9))
        ckpt = [_snapped(begin + k * sc.output.checkpoint_interval, [*fields, end], 1e-9 * end)
                for k in range(1, n + 1)]
    return fields, ckpt, sorted(set(fields) | set(ckpt) | {end})


def _snapped(t: float, times: list[float], tol: float) -> float:
    """The first of ``times`` within ``tol`` of ``t``, or ``t``."""
    return next((s for s in times if abs(s - t) <= tol), t)


def _leaf_names(tree) -> list[tuple[str, object]]:
    return [(jax.tree_util.keystr(p).lstrip("."), leaf) for p, leaf in jax.tree_util.tree_flatten_with_path(tree)[0]]


def _restore(file: Path, saved: dict, fresh):
    """The state of the leaves ``saved`` in checkpoint ``file``, checked against the freshly built one."""
    names = _leaf_names(fresh)
    if sorted(saved) != sorted(n for n, _ in names):
        raise results.OutputError(f"{file}: checkpoint fields {sorted(saved)} do not match this scenario's state "
                                  f"{[n for n, _ in names]}")
    for n, leaf in names:
        if saved[n].shape != leaf.shape or saved[n].dtype != leaf.dtype:
            raise results.OutputError(f"{file}: {n} is {saved[n].dtype}{list(saved[n].shape)}, this scenario "
                                      f"needs {leaf.dtype}{list(leaf.shape)}")
    return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(fresh), [jnp.asarray(saved[n]) for n, _ in names])


FIRST_CHUNK = 10  # steps of the first call of the compiled time loop; the next ones aim at CHUNK_SECONDS
CHUNK_SECONDS = 1.0  # wall-clock seconds of a call: the progress and Ctrl-C act between calls


def next_chunk(steps: int, seconds: float, cap: int, planned: int = 0) -> int:
    """Steps of the next call of the time loop, after one of ``steps`` steps took ``seconds``: as many as
    take CHUNK_SECONDS at that rate, at most 4 x the steps that call was ``planned`` to take (the first calls are
    short; a call cut short by an output time or a look at the pool does not shrink the next) and ``cap``."""
    steps = max(steps, 1)
    aim = steps * CHUNK_SECONDS / seconds if seconds > 0.0 else 4.0 * steps
    return int(max(1, min(aim, 4 * max(steps, planned), cap)))


GROWTH = 1.25  # a full particle pool grows to GROWTH x (the particles it needed), in whole thousands: a growth
#                costs a recompilation and every step costs in proportion to the pool, so geometric growth keeps
#                the growths logarithmic in the need and the empty slots below 25 % (no effect on results;
#                docs/theory/cfdmp.md, "Departures from the paper and tuned constants")
SHRINK = 0.6  # a mostly empty pool is packed into SHRINK x its slots (two significant digits: the same sizes from
#               run to run, which the persistent compilation cache then holds) once GROWTH x its need fits there: a
#               pool that emptied (the gas that the blast pushed into an MPM box flowing out again) stops
#               costing its empty slots; packing changes only the order of the pool's sums (round-off)
PACK_SLOT_STEPS = 2.0e7  # slot-steps (steps left x slots removed) a packing must save to be made: what compiling the
#                          time loop again costs, counted in the pool's slot-steps (steel-plate-blast on the 2-core CPU:
#                          1.3e-6 s a slot-step, from 41.8 ms a step with 25 264 slots and 27.1 ms with 14 000 in one
#                          state, against a 25-40 s compilation). A count, not a clock: identical runs pack at the
#                          same step, so that they give identical results (docs/theory/cfdmp.md)
POOL_CHECK_WORK = 5.0e6  # cell- and slot-updates between two looks at a resizable pool (at least POOL_CHECK_STEPS
POOL_CHECK_STEPS = 100  # steps): the calls of the time loop end at multiples of that many steps, where it is looked at


def _pool_size(method: methods.Method, state) -> int:
    """Capacity of the particle pool of a batched state (method.pool_leaf, axis 1)."""
    return int(np.shape(dict(_leaf_names(state))[method.pool_leaf])[1])


def _resized(method: methods.Method, setups: list, state, capacity: int | None = None):
    """(setups, state) with every member's particle pool resized to one common ``capacity`` (default: enlarged
    to GROWTH x the largest need); None when the method cannot resize its pool (not a methods.GrowingPool, or
    the scenario fixed it)."""
    if not isinstance(method, methods.GrowingPool):
        return None
    members = _members(state)
    if capacity is None:
        needed = max(method.pool_needed(m, setup) for m, setup in zip(members, setups))
        capacity = int(np.ceil(GROWTH * needed / 1000.0)) * 1000
    resized = [method.resize(setup, m, capacity) for setup, m in zip(setups, members)]
    if any(r is None for r in resized):
        return None
    return [r[0] for r in resized], _stack([r[1]._replace(fault=np.zeros_like(r[1].fault)) for r in resized], "state")


def shrunk_capacity(capacity: int, needed: int, steps_left: float) -> int | None:
    """The smaller pool a mostly empty one of ``capacity`` slots is packed into, or None to keep it: SHRINK x
    ``capacity`` rounded up to two significant digits (the same sizes from run to run), when ``needed`` slots
    with GROWTH's headroom fit there (the pool then has the room a growth would give it) and the ``steps_left``
    save more than PACK_SLOT_STEPS slot-steps (a compilation's cost)."""
    digits = 10 ** max(len(str(int(SHRINK * capacity))) - 2, 0)
    smaller = int(np.ceil(SHRINK * capacity / digits)) * digits
    if smaller >= capacity or GROWTH * needed > smaller:
        return None
    return smaller if steps_left * (capacity - smaller) > PACK_SLOT_STEPS else None


def pool_check_steps(cells: int, capacity: int) -> int:
    """Steps between two looks at a resizable pool of ``capacity`` slots beside ``cells`` cells: about
    POOL_CHECK_WORK cell- and slot-updates, at least POOL_CHECK_STEPS (a look costs a transfer of the pool's
    flags to the host). It depends on the sizes only, so the looks fall on the same steps in every run."""
    return max(POOL_CHECK_STEPS, int(np.ceil(POOL_CHECK_WORK / max(cells + capacity, 1))))


def _sparse_pool(method: methods.Method, setups: list, state, t_end: float) -> int | None:
    """:func:`shrunk_capacity` of the batch's pool (the largest need of its members; the steps left at the
    last step's length), or None; only for a pool the method may resize."""
    if not isinstance(method, methods.GrowingPool):
        return None
    capacity = _pool_size(method, state)
    active = int(np.max(np.sum(np.asarray(dict(_leaf_names(state))[method.pool_leaf]), axis=1)))
    if GROWTH * active > SHRINK * capacity:  # (the cheap test first: the full need reads every member)
        return None
    needed = max(method.pool_needed(m, setup) for m, setup in zip(_members(state), setups))
    dt = float(np.min(np.asarray(state.dt_prev)))
    steps_left = (t_end - float(np.min(np.asarray(state.t)))) / dt if dt > 0.0 else 0.0
    return shrunk_capacity(capacity, needed, steps_left)


def fit_pool(method: methods.Method, setups: list, saved: dict, fresh):
    """(setups, fresh) with the particle pool of the freshly built state ``fresh`` resized to that of the
    checkpoint leaves ``saved`` (a pool that grew or shrank before the checkpoint); unchanged otherwise."""
    name = method.pool_leaf if isinstance(method, methods.GrowingPool) else None
    if name is None or name not in saved or np.shape(saved[name])[1] == _pool_size(method, fresh):
        return setups, fresh
    # (only the shapes of fresh are kept, the checkpoint gives every value: its pool is emptied first, so that
    # a pool packed before the checkpoint fits, however many particles the initial state holds)
    emptied = [np.zeros_like(leaf) if n == name else leaf for n, leaf in _leaf_names(xla.to_host(fresh))]
    fresh = jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(fresh), emptied)
    resized = _resized(method, setups, fresh, int(np.shape(saved[name])[1]))
    return (setups, fresh) if resized is None else resized  # (not resized: the shape check names the mismatch)


def run(data: dict | list[dict], out: Path | None = None, *, overwrite: bool = False, progress: bool = False,
        restart: bool = False, chunk_steps: int = 20_000) -> Result:
    """Run a scenario given as a raw dict (or a list of them, see
    :func:`blastfsi.scenario.expand`) as one batched computation. With
    ``restart``, ``out`` is an existing results directory whose latest readable
    checkpoint is continued; ``out=None`` writes nothing. Ctrl-C while writing
    ``out`` raises :class:`RunInterrupted` once the run is saved. With ``progress`` it says on
    stderr what it is doing (:class:`_Progress`; the set-up's own ``logging`` messages of level INFO and above under
    the ``blastfsi`` logger, e.g. a charge's 1D detonation, are shown as stage lines). The run computes in
    ``numerics.precision`` and keeps its compiled time loop in the persistent cache
    (:mod:`blastfsi.runtime`)."""
    bar = _Progress(progress and xla.writes_results())
    with bar.logged():
        bar.stage("validating the scenario")
        sc, members, member_scs = expand(data)
        with (runtime.precision(sc.numerics.precision), runtime.compilation_cache(),  # (both restored after the run)
              _written_here(out) as target):
            return _run(sc, members, member_scs, out, target, overwrite=overwrite, bar=bar, restart=restart,
                        chunk_steps=chunk_steps)


@contextlib.contextmanager
def _written_here(out: Path | None):
    """Where this process writes the results of a run that writes ``out``: ``out`` itself, or, in the other
    processes of a run over several hosts (:func:`blastfsi.xla.writes_results`), a scratch directory removed
    after the run. They write the same files there, so every process takes the same steps: the transfers of
    the split state to the host that the writing needs are collectives (:func:`blastfsi.xla.to_host`)."""
    if out is None or xla.writes_results():
        yield out
        return
    with tempfile.TemporaryDirectory(prefix=f"blastfsi-process{jax.process_index()}-") as scratch:
        yield Path(scratch) / "results"


def prepare(sc: ScenarioBase, member_scs: list, stage=lambda message: None):
    """(method, setups, static, state, params) of a validated scenario (:func:`blastfsi.scenario.expand`): the
    members' set-ups, the static configuration they share, and their initial states and parameters stacked
    along a leading member axis, in ``numerics.precision`` (the arrays :func:`blastfsi.method.compiled_advance`
    takes). What :func:`run` starts from; for studies of the time loop outside a run (a step's cost, its
    parts). ``stage``: called with a line per set-up built (the progress display)."""
    method = methods.get(sc.method)
    setups = []
    for k, s in enumerate(member_scs):
        n = len(member_scs)
        if n == 1 or k % max(n // 10, 1) == 0 or k == n - 1:
            stage(f"building the {sc.method} set-up" + (f": member {k + 1} of {n}" if n > 1 else ""))
        setups.append(method.build(s))
    dtype = jnp.float64 if sc.numerics.precision == "float64" else jnp.float32
    statics = {method.static(setup, s) for setup, s in zip(setups, member_scs)}
    if len(statics) != 1:
        raise ScenarioError(f"all ensemble members must share the static configuration compiled into the time loop; "
                            f"got {sorted(map(repr, statics))}")
    static = statics.pop()
    parts = methods.member_devices(static)  # (methods.compiled_advance spreads the members over them)
    if len(member_scs) % parts:
        asked = sc.numerics.devices
        raise ScenarioError(f"numerics.devices = {asked!r}{f' is {parts} devices here' if asked == 'all' else ''}: "
                            f"the members of an ensemble (a [sweep], or a list of scenarios) are spread over the "
                            f"devices in equal shares, and this run has {len(member_scs)} member(s); give a member "
                            f"count that is a multiple of {parts}, or numerics.devices a divisor of "
                            f"{len(member_scs)}")
    n_samples = sc.output.history_samples
    state = _stack([method.initial_state(setup, s, n_samples, dtype) for setup, s in zip(setups, member_scs)], "state")
    methods.check_state(state)
    params = _stack([method.params(setup, dtype) for setup in setups], "params")
    return method, setups, static, state, params


def _run(sc: ScenarioBase, members: list[dict], member_scs: list, source: Path | None, out: Path | None, *,
         overwrite: bool, bar: _Progress, restart: bool, chunk_steps: int) -> Result:
    """:func:`run` of the validated scenario ``sc`` (its members' overrides and scenarios), in its precision;
    ``source``: the results directory of the run (read on restart), ``out``: where this process writes it
    (:func:`_written_here`)."""
    method, setups, static, state, params = prepare(sc, member_scs, bar.stage)
    begin = float(np.min(np.asarray(state.t)))  # the clock's start: 0, or a charge's remap time
    sample_interval = (sc.time.end - begin) / (sc.output.history_samples - 1)
    field_times, ckpt_times, stops = stop_times(sc, begin)

    last_ckpt = None
    if restart:
        last_ckpt, setups, state = _restored(source, method, setups, state)
        if out != source:  # (another host's scratch copy: a fresh results directory)
            results.prepare_directory(out, overwrite=False)
        bar.stage(f"continuing from {last_ckpt} (t = {report.quantity(float(np.min(np.asarray(state.t))), 's')})")
        static = method.static(setups[0], member_scs[0])
    elif out is not None:
        results.prepare_directory(out, overwrite)
        results.write_scenario(out, sc)
    t_start = float(np.min(np.asarray(state.t)))
    rec = _Recorder(out, method, method.history_columns(setups[0], sc), state, last_ckpt,
                    [(i, t) for i, t in enumerate(field_times) if t <= t_start] if restart else [])
    scalars = (chunk_steps, sample_interval, sc.time.dt_min_fraction)
    with _CtrlC(enabled=out is not None) as ctrl_c:  # (from the compilation on: Ctrl-C while compiling
        #                                               stops before the first chunk)
        bar.stage(f"compiling the time loop ({setups[0].cells} cells" + (f" x {len(setups)} members)" if
                                                                         len(setups) > 1 else ")"))
        advance, compile_time = methods.compiled_advance(method, static, state, params, stops[-1], *scalars)
        bar.stage(f"compiled in {report.duration(compile_time)}" if compile_time else
                  "time loop compiled earlier in this process: reused")
        bar.start(sc.time.end, t_start, int(np.max(np.asarray(state.step))))
        chunk = min(FIRST_CHUNK, chunk_steps)  # steps of the next call of the time loop (next_chunk)
        started, resize_compile, resizes = wallclock.perf_counter(), 0.0, {"pool_growths": 0, "pool_shrinks": 0}
        every = (pool_check_steps(setups[0].cells, _pool_size(method, state))  # (None: no pool to look at, or
                 if isinstance(method, methods.GrowingPool) else None)          # one the scenario fixed, found below)
        spent = {"loop": 0.0, "output": 0.0}  # the compiled time loop's calls; snapshots, checkpoints, history, summary

        def timed(part, fn, *args):
            t0 = wallclock.perf_counter()
            value = fn(*args)
            spent[part] += wallclock.perf_counter() - t0
            return value

        def advanced(state, t_stop):  # the time loop's call of at most `chunk` steps, waited for; sizes the next
            nonlocal chunk
            before, t0 = int(np.max(np.asarray(state.step))), wallclock.perf_counter()
            steps = max(1, min(chunk, sc.time.max_steps - before, every - before % every if every else chunk))
            state = jax.block_until_ready(advance(state, params, t_stop, steps, *scalars[1:]))
            taken, seconds = int(np.max(np.asarray(state.step))) - before, wallclock.perf_counter() - t0
            chunk = next_chunk(taken, seconds, chunk_steps, chunk)
            return state

        def summary(host, status: str) -> list[dict]:  # of each member (host: the batched state on the host)
            timing = {"wall_time": wallclock.perf_counter() - started - resize_compile,  # (the time loop only)
                      "compile_time": compile_time, "loop_time": spent["loop"], "output_time": spent["output"],
                      **(resizes if isinstance(method, methods.GrowingPool) else {})}
            return _summaries(method, sc, member_scs, setups, host, status, timing)

        def outputs(t_stop, host):  # the schedule's at t_stop
            if t_stop in field_times:
                timed("output", rec.snapshot, field_times.index(t_stop), t_stop, host, setups)
            if t_stop in ckpt_times:
                timed("output", rec.checkpoint, ckpt_times.index(t_stop) + 1, t_stop, host)

        try:
            if out is not None and not restart and field_times and field_times[0] == begin:
                outputs(begin, xla.to_host(state))
            for t_stop in (t for t in stops if t > t_start):
                while not ctrl_c.pressed and np.any(np.asarray(state.t) < t_stop):
                    state = timed("loop", advanced, state, t_stop)
                    fault = np.asarray(state.fault)
                    full = np.any(fault == FAULT_POOL_FULL)
                    look = (every is not None and int(np.max(np.asarray(state.step))) % every == 0
                            and np.all(fault == FAULT_NONE))  # (on the same steps in every run: see advanced)
                    smaller = _sparse_pool(method, setups, state, stops[-1]) if look else None
                    resized = _resized(method, setups, state, smaller) if full or smaller else None
                    if smaller is not None and resized is None:  # (numerics.capacity)
                        every = None
                    if resized is not None:  # the resized pool and its compiled loop (its compilation counts as such)
                        setups, state = resized
                        now = report.quantity(float(np.min(np.asarray(state.t))), 's')
                        bar.stage(f"t = {now}: particle pool " + ("full, grown" if full else "mostly empty, packed")
                                  + f" to {_pool_size(method, state)} slots (compiling the time loop again)")
                        static = method.static(setups[0], member_scs[0])
                        advance, more = methods.compiled_advance(method, static, state, params, stops[-1], *scalars)
                        compile_time += more
                        resize_compile += more
                        resizes["pool_growths" if full else "pool_shrinks"] += 1
                        every = pool_check_steps(setups[0].cells, _pool_size(method, state))
                        continue
                    stop = _stop_reason(state, method, setups, sc)
                    if stop is not None:  # (the history up to it is kept, as are the snapshots and checkpoints)
                        kept = rec.failed(xla.to_host(state), stop, setups, len(field_times))
                        raise SimulationError(f"{stop}; {kept}")
                    bar.update(float(np.min(np.asarray(state.t))), int(np.max(np.asarray(state.step))))
                if ctrl_c.pressed and np.any(np.asarray(state.t) < t_stop):
                    break
                if out is None:
                    continue
                host = xla.to_host(state)
                outputs(t_stop, host)
                if ctrl_c.pressed:
                    break
                if t_stop < stops[-1]:
                    timed("output", rec.update, host, setups, _combined(summary(host, "running"), members))
        finally:
            bar.finish()

        host = xla.to_host(state)
        t_now = float(np.min(host.t))
        interrupted = ctrl_c.pressed and t_now < stops[-1]
        summaries = summary(host, "interrupted" if interrupted else "complete")
        result = Result(sc, members, setups, summaries, _histories(method, setups, sc, host), state, source, method,
                        sorted(rec.snapshots))
        if out is not None:
            if interrupted and rec.ckpt_time != t_now:
                rec.checkpoint(sum(t <= t_now for t in ckpt_times), t_now, host, "_interrupted")
            rec.update(host, setups, result.summary)
            if sc.output.plots and not interrupted:
                bar.stage("writing the plots")
                method.plots(out / "plots", sc, setups, result.histories, members,
                             [method.snapshot(f, u) for f, u in zip(_members(host), setups)])
    if interrupted:
        raise RunInterrupted(f"interrupted at t = {t_now:.9g} s (step {int(np.max(host.step))}); "
                             f"checkpoint {rec.last_ckpt}")
    return result


def _restored(out: Path, method: methods.Method, setups: list, fresh) -> tuple[Path, list, object]:
    """(checkpoint, setups, state) of the newest readable checkpoint in ``out`` (saying on stderr which
    newer ones it skipped), checked against the freshly built state (its particle pool enlarged to the saved
    one's, as the setups)."""
    file, saved, skipped = results.read_latest_checkpoint(out)
    for reason in skipped:
        _warn(f"--restart: unreadable checkpoint skipped: {reason}")
    if skipped:
        _warn(f"--restart: continuing from {file}, the newest readable checkpoint")
    setups, fresh = fit_pool(method, setups, saved, fresh)
    return file, setups, _restore(file, saved, fresh)


def _warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _summaries(method: methods.Method, sc: ScenarioBase, member_scs: list, setups: list, host, status: str,
               timing: dict) -> list[dict]:
    """Each member's summary: method, status, time, steps, cells, the driver's ``timing``, the method's own."""
    histories = _histories(method, setups, sc, host)
    return [{"method": sc.method, "status": status, "time": float(s.t), "steps": int(s.step), "cells": int(setup.cells),
             **timing, **method.summary(msc, setup, hist, s)}
            for s, setup, msc, hist in zip(_members(host), setups, member_scs, histories)]


def _histories(method: methods.Method, setups: list, sc: ScenarioBase, state) -> list[dict]:
    """Each member's recorded history, column name -> samples."""
    columns = method.history_columns(setups[0], sc)
    return [{name: rows[:, i] for i, (name, _) in enumerate(columns)}
            for rows in map(_recorded, np.asarray(state.hist))]


def _recorded(rows: np.ndarray) -> np.ndarray:
    """The history rows a member has recorded (samples not reached, e.g. after a fault, are NaN)."""
    return rows[np.isfinite(rows[:, 0])]


def _stop_reason(state, method: methods.Method, setups: list, sc: ScenarioBase) -> str | None:
    """Why the run cannot go on, or None: a fault (its time, step and location) or the spent step budget."""
    fault = np.asarray(state.fault)
    if np.any(fault != FAULT_NONE):
        k = int(np.argmax(fault != FAULT_NONE))
        member = _members(state)[k]
        location = method.locate_fault(member, setups[k])
        if fault[k] == FAULT_DT_COLLAPSE:
            what = (f"time step collapsed below time.dt_min_fraction x initial ({sc.time.dt_min_fraction:g} x "
                    f"{float(member.dt0):.3g} s)")
        else:
            what = FAULT_MESSAGES[int(fault[k])]
        return f"{what} in member {k} at t = {float(member.t):.9g} s, step {int(member.step)}: {location}"
    if np.any(np.asarray(state.step) >= sc.time.max_steps):
        return (f"time.max_steps = {sc.time.max_steps} reached at t = {float(np.min(state.t)):.6g} s "
                f"(end {sc.time.end} s); raise time.max_steps or coarsen the grid")
    return None


class _Recorder:
    """The results directory ``out`` kept current as the run goes: the snapshots and checkpoints of the
    output schedule and, at each output (:meth:`update`), the history rows recorded since the last
    (appended), the snapshots' ParaView series and the summary, so a run killed at any point leaves what it
    computed. The history files start with the rows of the state it is made with (a restart's, from its
    checkpoint: any later rows of the run that wrote them are dropped). With ``out`` None (a run that
    writes nothing) it makes no file and the driver calls none of its writers."""

    def __init__(self, out: Path | None, method: methods.Method, columns, state, last_ckpt: Path | None,
                 snapshots: list[tuple[int, float]]):
        self.out, self.method, self.last_ckpt, self.snapshots = out, method, last_ckpt, snapshots
        self.ckpt_time = float(np.min(np.asarray(state.t))) if last_ckpt else None
        self.templates = None  # the last snapshot of each member written (field names and sizes for the series)
        self.summary = {"method": method.name}  # the last written
        rows = [_recorded(h) for h in np.asarray(state.hist)] if out is not None else []
        self.histories = [out / (f"history_member{k}.csv" if len(rows) > 1 else "history.csv")
                          for k in range(len(rows))]
        for file, member_rows in zip(self.histories, rows):
            results.write_history(file, columns, member_rows)
        self.written = [len(r) for r in rows]

    def snapshot(self, index: int, t: float, host, setups: list) -> None:
        self.templates = [self.method.snapshot(s, u) for s, u in zip(_members(host), setups)]
        results.write_snapshot(self.out, index, t, self.templates)
        self.snapshots.append((index, t))

    def checkpoint(self, index: int, t: float, host, suffix: str = "") -> None:
        leaves = {n: np.asarray(leaf) for n, leaf in _leaf_names(host)}
        self.last_ckpt = results.write_checkpoint(self.out, index, leaves, {"time": t, "method": self.method.name},
                                                  suffix)
        self.ckpt_time = t

    def update(self, host, setups: list, summary: dict) -> None:
        """Append the new history rows, rewrite the series and the summary."""
        self._append_history(host)
        if self.snapshots:
            templates = self.templates or [self.method.snapshot(s, u) for s, u in zip(_members(host), setups)]
            for k, template in enumerate(templates):
                results.write_series(self.out, k, sorted(self.snapshots), template)
        self.summary = summary
        results.write_summary(self.out, summary)

    def failed(self, host, reason: str, setups: list, index: int) -> str:
        """The history up to a fault, the fields of the faulted state (snapshot ``index``, past every scheduled
        one, the last of the series: where the run went wrong, for ParaView) and the last summary marked
        failed; returns what is kept, for the error."""
        where = f"last checkpoint: {self.last_ckpt}" if self.last_ckpt else "no checkpoint written yet"
        if self.out is None:
            return where
        t = float(np.min(np.asarray(host.t)))
        try:
            with np.errstate(all="ignore"):  # (the faulted state holds the non-physical values it is written for)
                self.snapshot(index, t, host, setups)
            files = sorted(str(p) for p in (self.out / "fields").glob(f"*{index:04d}*.h5"))
            fields = f"fields at the fault (t = {t:.9g} s): {', '.join(files)}"
        except Exception as err:  # (a snapshot that cannot be made must not hide the fault's own report)
            fields = f"no fields at the fault ({type(err).__name__}: {err})"
        self.update(host, setups, {**self.summary, "status": "failed", "error": reason})
        return f"history to the fault: {', '.join(map(str, self.histories))}; {fields}; {where}"

    def _append_history(self, host) -> None:
        for k, (file, hist) in enumerate(zip(self.histories, np.asarray(host.hist))):
            rows = _recorded(hist)
            results.append_history(file, rows[self.written[k]:])
            self.written[k] = len(rows)


class _CtrlC:
    """Ctrl-C (SIGINT) during a run that writes a results directory: noted (``pressed``) for the driver to
    stop after the compiled chunk in progress (a compiled call cannot be stopped midway); a second Ctrl-C
    interrupts at once, as usual. Only in the main thread (where Python delivers signals)."""

    def __init__(self, enabled: bool):
        self.pressed = False
        self._enabled = enabled and threading.current_thread() is threading.main_thread()

    def __enter__(self):
        if self._enabled:
            self._previous = signal.signal(signal.SIGINT, self._note)
        return self

    def _note(self, signum, frame) -> None:
        self.pressed = True
        signal.signal(signal.SIGINT, self._previous)

    def __exit__(self, *exc) -> None:
        if self._enabled:
            signal.signal(signal.SIGINT, self._previous)


class _Progress:
    """What a run says on stderr when ``enabled`` (silent otherwise): stage lines with the wall-clock time
    since it started (:meth:`stage`, and the set-up's log messages: :meth:`logged`), then from :meth:`start` to :meth:`finish` the
    progress after each call of the time loop: simulated time, step, the time step (the mean over the call,
    the stable one: :func:`blastfsi.report.shown_step`), steps per second and the ETA from the
    simulated-time rate, both averaged over the last ~20 s of wall-clock time
    (:func:`blastfsi.report.decayed`). On a terminal a bar; otherwise (a log) a plain line at each tenth of
    the run and at least every minute."""

    def __init__(self, enabled: bool):
        self.enabled, self.started = enabled, wallclock.perf_counter()
        self._bar = self._end = self._last = self._plain = self._dt = None
        self._totals = (0.0, 0.0, 0.0)  # simulated time, steps and wall-clock time, decayed (report.decayed)

    def stage(self, message: str) -> None:
        if not self.enabled:
            return
        line = report.stage_line(wallclock.perf_counter() - self.started, message)
        if self._bar is not None:
            self._bar.console.print(line, markup=False, highlight=False)
        else:
            print(line, file=sys.stderr, flush=True)

    def start(self, end: float, t: float, step: int) -> None:
        """The time loop starts at simulated time ``t``, step ``step``, and runs to ``end``."""
        self._end, self._last = end, (wallclock.perf_counter(), t, step)
        self._plain = (t / end, self._last[0])  # (fraction of the run, wall-clock time) of the last plain line
        if self.enabled and sys.stderr.isatty():
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

            self._bar = Progress(TextColumn("{task.fields[head]}", markup=False), BarColumn(),
                                 TextColumn("{task.percentage:>3.0f} %"),
                                 TextColumn("{task.fields[tail]}", markup=False), TimeElapsedColumn(),
                                 console=Console(stderr=True), transient=False)
            head, tail = report.progress_parts(t, end, step, None, None, None)
            self._task = self._bar.add_task("run", total=end, completed=t, head=head, tail=tail)
            self._bar.start()

    def update(self, t: float, step: int) -> None:
        """After a call of the time loop: simulated time ``t`` (the least over members), step (the most)."""
        now = wallclock.perf_counter()
        wall0, t0, step0 = self._last
        self._last = (now, t, step)
        if not self.enabled or now <= wall0:
            return
        self._totals = tuple(report.decayed(total, amount, now - wall0)
                             for total, amount in zip(self._totals, (t - t0, step - step0, now - wall0)))
        sim, steps, wall = self._totals
        self._dt = report.shown_step(self._dt, t - t0, step - step0)
        shown = (t, self._end, step, self._dt, steps / wall, report.remaining(t, self._end, sim / wall))
        if self._bar is not None:
            head, tail = report.progress_parts(*shown)
            self._bar.update(self._task, completed=t, head=head, tail=tail)
        elif report.plain_due(t / self._end, self._plain[0], now - self._plain[1]):
            self._plain = (t / self._end, now)
            self.stage(report.progress_line(*shown))

    def finish(self) -> None:
        """The time loop is over: the bar stops (stage lines go on as plain lines)."""
        if self._bar is not None:
            self._bar.stop()
            self._bar = None

    @contextlib.contextmanager
    def logged(self):
        """Context of a run: when enabled, the messages of the ``blastfsi`` loggers (level INFO and above; the
        set-up's, e.g. a charge's 1D detonation) are stage lines; the logger's level is restored after."""
        if not self.enabled:
            yield
            return
        logger, handler = logging.getLogger(LOGGER), _StageLines(self)
        level = logger.level
        logger.addHandler(handler)
        if logger.getEffectiveLevel() > logging.INFO:
            logger.setLevel(logging.INFO)
        try:
            yield
        finally:
            logger.removeHandler(handler)
            logger.setLevel(level)


LOGGER = "blastfsi"  # the package's loggers are its module names (logging.getLogger(__name__))


class _StageLines(logging.Handler):
    """A log record as a stage line of a run's progress."""

    def __init__(self, progress: _Progress):
        super().__init__(logging.INFO)
        self._progress = progress

    def emit(self, record: logging.LogRecord) -> None:
        self._progress.stage(record.getMessage())
