"""The one compiled time loop every method's ``advance`` runs.

A method's state is a NamedTuple that carries, besides its own arrays, the
clock fields listed in :data:`CLOCK_FIELDS`. The loop advances it with the
method's three pure functions

* ``stable_dt(state) -> dt``: the stability-limited step; NaN or <= 0 exactly
  when the state is non-physical (the reduction doubles as the fault check);
* ``step(state, dt) -> state``: the physics of one step of length dt (it does
  not touch the clock fields);
* ``history_row(state) -> (n_columns,)``: one history sample, first column time;

until ``t_stop``, ``max_steps`` more steps, or a fault.

Only ``t_stop`` (the driver's stop times: snapshots, checkpoints, the end) is
landed on, and without a short step: the time left to it is split into the
fewest equal steps no longer than the stable one, n = ceil(left / dt_stable),
dt = left / n (:func:`step_to`), recomputed each step. A run whose stable step
does not change thus takes one constant step, and a step is never shorter than
about half the stable one because of output. (Shortening only the step that
would overshoot modulates dt, and explicit integrators (the MPM's symplectic
Euler, any central difference) pump their high-frequency modes under such a
modulation: an elastic clamped beam of 0.5 mm particles' cells
(``tests/verification/test_mpm_verification.py``) gained its energy 1e3-fold in
~12 000 steps with a short step in each of 2001 intervals; a scalar oscillator
at omega dt = 1 under random shortening of one step in seven gains 1e5 in 2000
cycles.)

History samples never shorten a step: row k is the history at the sample time
t_0 + k * sample_interval (t_0: the time of the first row, the clock's start),
interpolated linearly in time between the rows at the start and the end of the
step that reaches it (:func:`interpolated`), both computed only for such a
step; a step may reach several. The first row (t_0) is the initial state's, and the last, at the end (a stop time), the final
state's, both exact. A quantity linear in time within a step (time, an impulse
or work accumulated with the step's rate) is sampled exactly.

A method with a particle pool may pass a fourth function, ``pool_full(state)
-> bool``: true when the pool has too few free slots for the next step (or the
last step could not add the particles it needed; the state is still
consistent: what did not fit waits where it was), and the loop then stops,
before stepping, with FAULT_POOL_FULL for the driver to enlarge the pool and go
on. Fault codes in ``state.fault``:
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

FAULT_NONE, FAULT_NONPHYSICAL, FAULT_DT_COLLAPSE, FAULT_POOL_FULL = 0, 1, 2, 3
FAULT_MESSAGES = {
    FAULT_NONPHYSICAL: "non-physical state",
    FAULT_DT_COLLAPSE: "time step collapsed",
    FAULT_POOL_FULL: "particle pool full",
}
CLOCK_FIELDS = ("t", "dt_prev", "dt0", "step", "fault", "hist", "hist_next")


class Row:
    """A history row written as named entries, so that its columns and its values cannot drift apart.

    A method writes one function that adds every entry in order, ``row.add(name, unit, value)`` or, for
    several columns computed together, ``row.add_block([(name, unit), ...], values)``, where ``value`` and
    ``values`` are nullary callables (a scalar; an array of as many elements as the block has columns).
    :attr:`columns` (host side: the method's ``history_columns``) calls none of them, so the function may run
    there without a state; :meth:`values` (under trace: the method's ``history_row``) calls them all.
    """

    def __init__(self):
        self._entries = []  # (columns, callable)

    def add(self, name: str, unit: str, value) -> "Row":
        self._entries.append((((name, unit),), value))
        return self

    def add_block(self, columns, values) -> "Row":
        self._entries.append((tuple(columns), values))
        return self

    @property
    def columns(self) -> tuple:
        return tuple(c for cols, _ in self._entries for c in cols)

    def values(self, dtype):
        parts = []
        for cols, value in self._entries:
            if not cols:
                continue
            part = jnp.reshape(jnp.asarray(value(), dtype), (-1,))
            if part.shape[0] != len(cols):
                raise ValueError(f"history entries {[c[0] for c in cols]}: {part.shape[0]} values")
            parts.append(part)
        return jnp.concatenate(parts)


def clock(n_samples: int, n_columns: int, dtype) -> dict:
    """Initial values of the clock fields (splice into a method's State)."""
    zero = jnp.zeros((), dtype)
    return dict(t=zero, dt_prev=zero, dt0=zero, step=jnp.zeros((), jnp.int32), fault=jnp.zeros((), jnp.int32),
                hist=jnp.full((n_samples, n_columns), jnp.nan, dtype), hist_next=jnp.zeros((), jnp.int32))


def step_to(t, t_stop, dt_stable):
    """(dt, t_new) of the next step from ``t`` toward ``t_stop``: the time left
    in the fewest equal steps no longer than the stable one, n = max(ceil(left /
    dt_stable), 1), dt = left / n; the last (n = 1) lands on ``t_stop`` exactly.
    (The 1 - 1e-12 keeps round-off in t from adding a step: dt may exceed
    dt_stable by that much.)"""
    left = t_stop - t
    n = jnp.maximum(jnp.ceil(left / dt_stable * (1.0 - 1e-12)), 1.0)
    return left / n, jnp.where(n == 1.0, t_stop, t + left / n)


def samples_reached(t, sample_interval, n_samples):
    """How many of the sample times k * sample_interval (k = 0 .. n_samples - 1)
    lie at or before ``t``, a relative 4 eps of t / sample_interval counting as
    at: so the last, (n_samples - 1) * sample_interval = the end up to
    round-off, is reached at the end."""
    k = jnp.floor(t / sample_interval * (1.0 + 4.0 * jnp.finfo(t.dtype).eps))
    return jnp.minimum(k, n_samples - 1).astype(jnp.int32) + 1


def interpolated(row_a, row_b, t):
    """The history row at time ``t`` from the rows at the start and the end of a
    step (first column time), linear in time: row_a + w (row_b - row_a),
    w = (t - t_a) / (t_b - t_a) clipped to [0, 1]; row_b itself at w = 1."""
    w = jnp.clip((t - row_a[0]) / (row_b[0] - row_a[0]), 0.0, 1.0)
    return jnp.where(w < 1.0, row_a + w * (row_b - row_a), row_b)


def recorded(hist, first, stop, row_a, row_b, sample_interval):
    """``hist`` with rows ``first`` .. ``stop - 1``, those of the sample times t_0 + k * sample_interval
    (t_0 = hist[0, 0], the first row's time) a step from row_a to row_b reached, interpolated in time."""
    def one(k, hist):
        return hist.at[k].set(interpolated(row_a, row_b, hist[0, 0] + k.astype(hist.dtype) * sample_interval))

    return jax.lax.fori_loop(first, stop, one, hist)


def run_until(state, t_stop, max_steps, sample_interval, dt_floor_fraction, *, stable_dt, step, history_row,
              pool_full=None):
    """Advance ``state`` in one ``lax.while_loop`` (see module docstring).

    ``dt0`` is the first stable step of the run; a later stable step below
    ``dt_floor_fraction * dt0`` stops the loop with FAULT_DT_COLLAPSE (a
    collapsing step would otherwise run for hours without a word). The faulted
    state is returned unstepped for the driver to locate.
    """
    n_samples = state.hist.shape[0]
    step_limit = state.step + max_steps

    def row(st):
        return history_row(st).astype(st.hist.dtype)

    fresh = (state.hist_next == 0) & (state.step == 0)  # the first row: the initial state's
    state = state._replace(hist=state.hist.at[0].set(jax.lax.cond(fresh, lambda: row(state), lambda: state.hist[0])),
                           hist_next=jnp.where(fresh, 1, state.hist_next).astype(state.hist_next.dtype))

    def cond(st):
        return (st.t < t_stop) & (st.step < step_limit) & (st.fault == FAULT_NONE)

    def body(st):
        dt_stable = stable_dt(st)
        dt0 = jnp.where(st.step == 0, dt_stable, st.dt0)
        st = st._replace(dt0=dt0)
        fault = jnp.where(dt_stable > 0.0, jnp.where(dt_stable >= dt_floor_fraction * dt0, FAULT_NONE,
                                                     FAULT_DT_COLLAPSE), FAULT_NONPHYSICAL)
        if pool_full is not None:
            fault = jnp.where(pool_full(st), FAULT_POOL_FULL, fault)

        def go(st):
            dt, t_new = step_to(st.t, t_stop, dt_stable)
            reached = samples_reached(t_new - st.hist[0, 0], sample_interval, n_samples)
            samples = reached > st.hist_next  # the step reaches samples: the rows at its start and end
            row_a = jax.lax.cond(samples, lambda: row(st), lambda: jnp.zeros(st.hist.shape[1:], st.hist.dtype))
            new = step(st, dt)._replace(t=t_new, dt_prev=dt, step=st.step + 1)
            hist = jax.lax.cond(samples, lambda: recorded(new.hist, st.hist_next, reached, row_a, row(new),
                                                          sample_interval), lambda: new.hist)
            return new._replace(hist=hist, hist_next=jnp.maximum(reached, st.hist_next))

        return jax.lax.cond(fault == FAULT_NONE, go, lambda st: st._replace(fault=fault.astype(st.fault.dtype)), st)

    return jax.lax.while_loop(cond, body, state)
