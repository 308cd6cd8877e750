"""Blast-effect maps accumulated every step, per cell: peak overpressure,
arrival time, positive-phase impulse and duration.

Definitions (one set, used for the per-cell maps and for gauges, which read
the map at the cell that holds them):

* overpressure dp = p - p_ref, p_ref the ambient pressure of the scenario;
* arrival time: first time dp exceeds ``threshold`` (``output.arrival_fraction``
  x p_ref), the time of the step that crosses it interpolated linearly;
* positive phase: from arrival to the first later time dp falls below zero;
  its impulse is the time integral of dp over it (trapezoidal in time, with
  the crossing steps cut at the interpolated crossings) and its duration the
  difference of the two crossing times;
* peak overpressure: maximum of dp over the whole run.

A pure update on arrays of any shape (the cells of the grid, or the gauges).
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp


class BlastMaps(NamedTuple):
    peak: jnp.ndarray  # max dp [Pa]
    arrival: jnp.ndarray  # [s], +inf before arrival
    end: jnp.ndarray  # end of the positive phase [s], +inf while it lasts
    impulse: jnp.ndarray  # positive-phase impulse [Pa s]
    last: jnp.ndarray  # dp at the previous update [Pa]


def initial(dp0) -> BlastMaps:
    inf = jnp.full_like(dp0, jnp.inf)
    return BlastMaps(peak=dp0, arrival=inf, end=inf, impulse=jnp.zeros_like(dp0), last=dp0)


def update(m: BlastMaps, dp, t0, dt, threshold) -> BlastMaps:
    """Advance the maps over a step [t0, t0 + dt] in which dp went from m.last to dp."""
    a, b = m.last, dp
    t1 = t0 + dt
    # linear interpolation of a crossing of level L inside the step
    def crossing(level):
        frac = jnp.clip((level - a) / jnp.where(b != a, b - a, 1.0), 0.0, 1.0)
        return t0 + frac * dt

    arrives = jnp.isinf(m.arrival) & (b > threshold)
    arrival = jnp.where(arrives, crossing(threshold), m.arrival)
    started = jnp.isfinite(arrival)
    ends = started & jnp.isinf(m.end) & (b < 0.0)
    end = jnp.where(ends, crossing(0.0), m.end)
    # part of the step inside the positive phase
    lo = jnp.where(arrives, arrival, t0)
    hi = jnp.where(ends, end, t1)
    active = started & (jnp.isinf(m.end))
    # dp at lo and hi by linear interpolation within the step
    def at(t):
        return a + (b - a) * jnp.where(dt > 0, (t - t0) / dt, 1.0)

    inc = jnp.where(active, 0.5 * (at(lo) + at(hi)) * (hi - lo), 0.0)
    return BlastMaps(peak=jnp.maximum(m.peak, b), arrival=arrival, end=end, impulse=m.impulse + inc, last=b)


def duration(m: BlastMaps, t_now):
    """Positive-phase duration; a phase still open at t_now counts up to t_now."""
    return jnp.where(jnp.isfinite(m.arrival), jnp.minimum(m.end, t_now) - m.arrival, jnp.nan)
