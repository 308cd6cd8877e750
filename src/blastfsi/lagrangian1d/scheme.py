"""von Neumann-Richtmyer (vNR) scheme of seed 002, Eqs. (1)-(23), as pure JAX kernels.

Notation (ERRATA 002-1): nodes n = 0..N carry position x and velocity v; zones
n+1/2 carry mass m, specific internal energy e and the artificial viscous
pressure q. Velocities live at half time levels (leapfrog), everything else at
whole levels.

Sign convention: the paper's Q (Eq. 5) is <= 0 and enters as p = p_eos - Q; here
q = -Q >= 0 and p = p_eos + q.

Departures from the printed paper, each argued in docs/theory.md:
* Eq. (9) uses 1/2 (dt_j + dt_{j+1}) (ERRATA 002-2).
* Eq. (12) uses the current zone density rho (not the reference rho0) in both
  viscous terms, the classical vNR form; rho0 Dx = rho0_ref DX makes the two
  differ only by the compression factor.
* The plate (Eqs. 7, 21-23) is the end node carrying the plate's areal mass
  plus the lumped half-mass of its neighbouring zone, advanced with the same
  leapfrog as every other node. The paper's forward-Euler update with the
  plate mass alone is unstable for plates lighter than a zone
  (beta_s > ~10^3 at 5000 cells); the lumped form converges to it as the zone
  mass -> 0 and stays stable for any plate mass.
* The time step (Eq. 20, ERRATA 002-5) includes the viscous signal speed so the
  scheme stays stable inside shocks: dt = alpha min dx / (s + sqrt(s^2 + a^2)),
  s = max(2 (K1^2 |dv| + K2 a), |dv|) for compressing zones, dv = v_{n+1} - v_n < 0
  the latest node-velocity difference (the stability bound of the explicit
  scheme with a diffusive q, cf. Benson, CMAME 99, 1992). With |dv| in s a zone
  can never be crushed in one step, also at a piston's first step and with
  the viscosity switched off.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from blastfsi.eos import ideal_gas


class Numerics(NamedTuple):
    """Scheme parameters (traced, so an ensemble may vary them)."""

    gamma: jnp.ndarray  # ratio of specific heats
    K1: jnp.ndarray  # quadratic viscosity coefficient, Eq. (5)
    K2: jnp.ndarray  # linear viscosity coefficient, Eq. (5)
    cfl: jnp.ndarray  # alpha in Eq. (20), 0 < alpha <= 1


class Boundaries(NamedTuple):
    """Boundary data. Static flags choose the kind; arrays carry the values.

    Left end: prescribed velocity (piston; 0 = fixed wall / symmetry plane) when
    ``left_velocity_set`` else a prescribed pressure (free end).
    Right end: fixed wall when ``right_fixed`` else a node of extra mass
    ``right_mass`` (the plate, kg/m^2; 0 = free end) loaded by ``right_pressure``
    on its free side (the back pressure p0 of 002 Sec. 2).
    """

    left_velocity: jnp.ndarray
    left_pressure: jnp.ndarray
    right_mass: jnp.ndarray
    right_pressure: jnp.ndarray


class Gauges(NamedTuple):
    """Pressure gauges fixed in space (Eulerian), read in the zone that holds them."""

    positions: jnp.ndarray  # (G,) [m]
    ambient_pressure: jnp.ndarray  # overpressure reference p0 [Pa]


class State(NamedTuple):
    x: jnp.ndarray  # node positions at t_j, (N+1,)
    v: jnp.ndarray  # node velocities at t_{j-1/2}, (N+1,)
    e: jnp.ndarray  # zone specific internal energy at t_j, (N,)
    q: jnp.ndarray  # zone viscous pressure at t_{j-1/2}, (N,)
    zone_mass: jnp.ndarray  # (N,), constant in time (Lagrangian)
    t: jnp.ndarray
    dt_prev: jnp.ndarray  # dt_j, the step that led to t_j (0 at start)
    step: jnp.ndarray
    face_impulse: jnp.ndarray  # int (p_{N-1/2} - p_right) dt on the right end
    peak_face_overpressure: jnp.ndarray
    boundary_work: jnp.ndarray  # work done on the system by the boundaries
    faulted: jnp.ndarray  # True once the state is non-physical (see first_fault for where)
    gauge_impulse: jnp.ndarray  # (G,) int max(p - p0, 0) dt at each gauge
    gauge_peak: jnp.ndarray  # (G,) peak overpressure at each gauge
    hist: jnp.ndarray  # (n_samples, N_HIST + G) histories sampled in compiled code
    hist_next: jnp.ndarray  # index of the next history sample to record


HISTORY_COLUMNS = (
    ("time", "s"),
    ("plate_displacement", "m"),
    ("plate_velocity", "m/s"),
    ("plate_overpressure", "Pa"),
    ("plate_impulse", "Pa*s"),
    ("surface_impulse", "Pa*s"),
    ("left_overpressure", "Pa"),
    ("energy_error", "J/m^2"),
)
N_HIST = len(HISTORY_COLUMNS)


def history_columns(n_gauges: int) -> tuple:
    """(name, unit) of every history column: the plate's, then one per gauge."""
    return HISTORY_COLUMNS + tuple((f"gauge{k}_overpressure", "Pa") for k in range(n_gauges))


def zone_pressure(zone_mass, x, e, q, gamma):
    """002 Eq. (11) (with q = -Q): p = (gamma-1) rho e + q, rho = m / dx."""
    return ideal_gas.pressure(zone_mass / (x[1:] - x[:-1]), e, gamma) + q


def node_masses(zone_mass, right_mass):
    """Lumped node masses: half of each neighbouring zone, plus the plate at node N.
    Equivalent to rho0^(n) DX in 002 Eq. (10) with Eq. (18)."""
    half = 0.5 * zone_mass
    m = jnp.concatenate([half[:1], half[1:] + half[:-1], half[-1:]])
    return m.at[-1].add(right_mass)


def stable_dt(dx, a, v, num: Numerics):
    """002 Eq. (20) with the viscous signal speed (see module docstring).

    NaN (NaN or negative energy somewhere) or <= 0 (a tangled zone) exactly when
    the state is non-physical, so the time-step reduction doubles as the fault check.
    """
    dv = v[1:] - v[:-1]
    # the max keeps dt |dv| <= alpha dx / 2 (no zone crushed in one step) even without viscosity
    s = jnp.where(dv < 0.0, jnp.maximum(2.0 * (num.K1**2 * jnp.abs(dv) + num.K2 * a), jnp.abs(dv)), 0.0)
    return num.cfl * jnp.min(dx / (s + jnp.sqrt(s * s + a * a)))


def viscous_pressure(rho_mid, dx_mid, D, a, num: Numerics):
    """002 Eq. (12), q = -Q >= 0, active in compression only (Eq. 5)."""
    q = rho_mid * (num.K1 * dx_mid * D) ** 2 + rho_mid * num.K2 * a * dx_mid * jnp.abs(D)
    return jnp.where(D < 0.0, q, 0.0)


def implicit_energy(e, q, rho_mid, dtD, gamma):
    """002 Eq. (16) with Q = -q: trapezoidal (implicit) p dV work of the gas pressure."""
    return (e + ((1.0 - gamma) * 0.5 * e - q / rho_mid) * dtD) / (1.0 + 0.5 * (gamma - 1.0) * dtD)


def total_energy(state: State, bc: Boundaries):
    """Internal + kinetic energy per unit area (kinetic from the half-step velocities)."""
    nm = node_masses(state.zone_mass, bc.right_mass)
    return jnp.sum(state.zone_mass * state.e) + 0.5 * jnp.sum(nm * state.v**2)


def vnr_step(s: State, dt, a, node_mass, num: Numerics, bc: Boundaries, left_velocity_set: bool,
             right_fixed: bool):
    """Advance one time step dt = dt_{j+1} (002 Sec. 2 sequence); ``a`` the zone
    sound speeds at t_j, ``node_mass`` from :func:`node_masses`. Pure."""
    gamma = num.gamma
    dx = s.x[1:] - s.x[:-1]
    p = zone_pressure(s.zone_mass, s.x, s.e, s.q, gamma)
    p_left = p[0] if left_velocity_set else bc.left_pressure
    p_ext = jnp.concatenate([jnp.reshape(p_left, (1,)), p, jnp.reshape(bc.right_pressure, (1,))])
    acc = (p_ext[:-1] - p_ext[1:]) / node_mass  # Eq. (10), Eq. (23)
    v = s.v + 0.5 * (s.dt_prev + dt) * acc  # Eq. (9), ERRATA 002-2
    if left_velocity_set:
        v = v.at[0].set(bc.left_velocity)
    if right_fixed:
        v = v.at[-1].set(0.0)
    x = s.x + dt * v  # Eq. (8)
    dx_new = x[1:] - x[:-1]
    dtD = 2.0 * (dx_new - dx) / (dx_new + dx)  # dt * Eq. (14)
    dx_mid = 0.5 * (dx + dx_new)  # Eq. (15)
    rho_mid = 0.5 * s.zone_mass * (1.0 / dx_new + 1.0 / dx)  # Eq. (17)
    q = viscous_pressure(rho_mid, dx_mid, dtD / dt, a, num)
    e = implicit_energy(s.e, q, rho_mid, dtD, gamma)
    work = dt * (p_left * v[0] - bc.right_pressure * v[-1])
    face_over = p[-1] - bc.right_pressure
    return s._replace(
        x=x, v=v, e=e, q=q, t=s.t + dt, dt_prev=dt, step=s.step + 1,
        face_impulse=s.face_impulse + dt * face_over,
        peak_face_overpressure=jnp.maximum(s.peak_face_overpressure, face_over),
        boundary_work=s.boundary_work + work,
    )


def gauge_overpressure(s: State, gauges: Gauges, gamma):
    """Overpressure in the zone holding each gauge; NaN for a gauge outside the gas."""
    k = jnp.clip(jnp.searchsorted(s.x, gauges.positions) - 1, 0, s.e.shape[0] - 1)
    rho = s.zone_mass[k] / (s.x[k + 1] - s.x[k])
    p = ideal_gas.pressure(rho, s.e[k], gamma) + s.q[k]
    inside = (gauges.positions >= s.x[0]) & (gauges.positions <= s.x[-1])
    return jnp.where(inside, p - gauges.ambient_pressure, jnp.nan)


def first_fault(s: State):
    """Index of the first zone with a non-physical state (NaN, tangled zone,
    non-positive internal energy), or -1 when the state is healthy. Works on
    NumPy and JAX arrays (the driver calls it on the host after a fault)."""
    dx = s.x[1:] - s.x[:-1]
    bad = ~(jnp.isfinite(dx) & (dx > 0.0) & jnp.isfinite(s.e) & (s.e > 0.0) & jnp.isfinite(s.v[1:]))
    return jnp.where(jnp.any(bad), jnp.argmax(bad), -1).astype(jnp.int32)


def history_row(s: State, bc: Boundaries, gauges: Gauges, e0, x_right0, right_fixed: bool, gamma):
    p = zone_pressure(s.zone_mass, s.x, s.e, s.q, gamma)
    v_plate = 0.0 * s.v[-1] if right_fixed else s.v[-1]
    plate_impulse = s.face_impulse if right_fixed else bc.right_mass * s.v[-1]
    energy_error = total_energy(s, bc) - e0 - s.boundary_work
    plate = jnp.stack([
        s.t, s.x[-1] - x_right0, v_plate, p[-1] - bc.right_pressure, plate_impulse,
        s.face_impulse, p[0] - bc.right_pressure, energy_error,
    ])
    return jnp.concatenate([plate, gauge_overpressure(s, gauges, gamma)])


def initial_state(x, v, e, zone_mass, n_samples: int, n_gauges: int = 0) -> State:
    x = jnp.asarray(x)
    g = jnp.zeros((n_gauges,), x.dtype)
    z = jnp.zeros_like(jnp.asarray(e))
    zero = jnp.zeros((), x.dtype)
    return State(
        x=x, v=jnp.asarray(v), e=jnp.asarray(e), q=z, zone_mass=jnp.asarray(zone_mass),
        t=zero, dt_prev=zero, step=jnp.zeros((), jnp.int32), face_impulse=zero,
        peak_face_overpressure=jnp.asarray(-jnp.inf, x.dtype), boundary_work=zero,
        faulted=jnp.asarray(False), gauge_impulse=g, gauge_peak=g - jnp.inf,
        hist=jnp.full((n_samples, N_HIST + n_gauges), jnp.nan, x.dtype),
        hist_next=jnp.zeros((), jnp.int32),
    )


def advance(s: State, t_stop, max_steps, sample_interval, e0, x_right0, num: Numerics, bc: Boundaries,
            gauges: Gauges, left_velocity_set: bool, right_fixed: bool) -> State:
    """Advance in compiled code until t_stop, max_steps more steps, or a fault.

    Steps are shortened to land exactly on t_stop and on every history sample
    time k * sample_interval, where history row k is recorded. Gauge impulses
    and peaks are accumulated every step. A
    non-physical state (detected by the time-step reduction) sets ``faulted``
    and ends the loop without stepping; the state returned is that state, for
    :func:`first_fault` to locate (the last checkpoint on disk stays usable).
    """
    n_samples = s.hist.shape[0]
    step_limit = s.step + max_steps
    node_mass = node_masses(s.zone_mass, bc.right_mass)

    def next_sample_time(st):
        return jnp.where(st.hist_next < n_samples, st.hist_next * sample_interval, jnp.inf)

    def record_if(st, due):
        k = jnp.minimum(st.hist_next, n_samples - 1)
        row = jax.lax.cond(due, lambda: history_row(st, bc, gauges, e0, x_right0, right_fixed, num.gamma),
                           lambda: st.hist[k])
        return st._replace(hist=st.hist.at[k].set(row), hist_next=st.hist_next + due.astype(st.hist_next.dtype))

    s = record_if(s, (s.hist_next == 0) & (s.step == 0))

    def cond(st):
        return (st.t < t_stop) & (st.step < step_limit) & ~st.faulted

    def body(st):
        a = ideal_gas.sound_speed(st.e, num.gamma)  # Eq. (13)
        dt_cfl = stable_dt(st.x[1:] - st.x[:-1], a, st.v, num)

        def go(st):
            target = jnp.minimum(t_stop, next_sample_time(st))
            lands = st.t + dt_cfl >= target
            dt = jnp.where(lands, target - st.t, dt_cfl)
            new = vnr_step(st, dt, a, node_mass, num, bc, left_velocity_set, right_fixed)
            pg = gauge_overpressure(st, gauges, num.gamma)  # at t_j, like the plate load
            new = new._replace(gauge_impulse=st.gauge_impulse + dt * jnp.nan_to_num(jnp.maximum(pg, 0.0)),
                               gauge_peak=jnp.fmax(st.gauge_peak, pg))
            due = lands & (target == next_sample_time(st))
            return record_if(new._replace(t=jnp.where(lands, target, new.t)), due)

        return jax.lax.cond(dt_cfl > 0.0, go, lambda st: st._replace(faulted=jnp.asarray(True)), st)

    return jax.lax.while_loop(cond, body, s)
