"""The one compiled time loop every method's ``advance`` runs.

A method's state is a NamedTuple that carries, besides its own arrays, the
clock fields listed in :data:`CLOCK_FIELDS`. The loop advances it with the
method's three pure functions

* ``stable_dt(state) -> dt``: the stability-limited step; NaN or <= 0 exactly
  when the state is non-physical (the reduction doubles as the fault check);
* ``step(state, dt) -> state``: the physics of one step of length dt (it does
  not touch the clock fields);
* ``history_row(state) -> (n_columns,)``: one history sample, first column time;

until ``t_stop``, ``max_steps`` more steps, or a fault. The steps land exactly
on ``t_stop`` and on every history sample time k * sample_interval, where row k
is recorded: the time left to the next of these is split into the fewest equal
steps no longer than the stable one, n = ceil(left / dt_stable), dt = left / n.
So a run whose stable step does not change takes one constant step, whatever
the output times. Shortening only the step that would overshoot (a short step
in every sample interval) modulates dt, and explicit integrators (the MPM's
symplectic Euler, any central difference) pump their high-frequency modes under
such a modulation: an elastic clamped beam of 0.5 mm particles' cells
(``tests/verification/test_mpm_verification.py``) gained its energy 1e3-fold in
~12 000 steps with 2001 samples and stayed within 1e-4 with 41 (a scalar
oscillator at omega dt = 1 under random shortening of one step in seven gains
1e5 in 2000 cycles). A method with a particle pool
may pass a fourth function, ``pool_full(state) -> bool``: true when the pool
has too few free slots for the next step (or the last step could not add the
particles it needed; the state is still consistent: what did not fit waits
where it was), and the loop then stops, before stepping, with FAULT_POOL_FULL
for the driver to enlarge the pool and go on. Fault codes in
``state.fault``:
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


def clock(n_samples: int, n_columns: int, dtype) -> dict:
    """Initial values of the clock fields (splice into a method's State)."""
    zero = jnp.zeros((), dtype)
    return dict(t=zero, dt_prev=zero, dt0=zero, step=jnp.zeros((), jnp.int32), fault=jnp.zeros((), jnp.int32),
                hist=jnp.full((n_samples, n_columns), jnp.nan, dtype), hist_next=jnp.zeros((), jnp.int32))


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

    def next_sample_time(st):
        return jnp.where(st.hist_next < n_samples, st.hist_next * sample_interval, jnp.inf)

    def record_if(st, due):
        k = jnp.minimum(st.hist_next, n_samples - 1)
        row = jax.lax.cond(due, lambda: history_row(st).astype(st.hist.dtype), lambda: st.hist[k])
        return st._replace(hist=st.hist.at[k].set(row), hist_next=st.hist_next + due.astype(st.hist_next.dtype))

    state = record_if(state, (state.hist_next == 0) & (state.step == 0))

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
            target = jnp.minimum(t_stop, next_sample_time(st))
            left = target - st.t
            # (the 1 - 1e-12 keeps round-off in t from adding a step: dt may exceed dt_stable by that much)
            n = jnp.maximum(jnp.ceil(left / dt_stable * (1.0 - 1e-12)), 1.0)
            lands = n == 1.0
            dt = jnp.where(lands, left, left / n)
            new = step(st, dt)
            new = new._replace(t=jnp.where(lands, target, st.t + dt), dt_prev=dt, step=st.step + 1)
            due = lands & (target == next_sample_time(st))
            return record_if(new, due)

        return jax.lax.cond(fault == FAULT_NONE, go, lambda st: st._replace(fault=fault.astype(st.fault.dtype)), st)

    return jax.lax.while_loop(cond, body, state)
