"""von Neumann-Richtmyer (vNR) scheme of seed 002, Eqs. (1)-(23), as pure JAX kernels,
in planar, cylindrical and spherical geometry with JWL/ideal-gas zones and the
programmed burn of seed 000 (Eqs. 52-53).

Notation (ERRATA 002-1): nodes n = 0..N carry position x and velocity v; zones
n+1/2 carry mass m, specific internal energy e and the artificial viscous
pressure q. Velocities live at half time levels (leapfrog), everything else at
whole levels.

Sign convention: the paper's Q (Eq. 5) is <= 0 and enters as p = p_eos - Q; here
q = -Q >= 0 and p = p_eos + q.

Departures from the printed paper, each argued in docs/theory/lagrangian1d.md:
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

Geometry and materials (seed 000 Sec. 4.1, the 1D detonation):
* Geometry exponent j (0 planar, 1 cylindrical, 2 spherical; static). Node n
  sits at radius r_n; zone volumes per radian^j are V = (r+^(j+1) - r-^(j+1))/(j+1),
  the node area is A_n = r_n^j and the momentum update is the compatible
  (area-weighted) form m_n dv_n/dt = A_n (p_{n-1/2} - p_{n+1/2}), whose work
  sum_n v_n A_n dp equals sum_z p_z dV_z/dt, so the semi-discrete energy is
  conserved as in the planar scheme. Planar j = 0 is the 002 scheme unchanged.
* The viscous pressure uses the node-velocity jump dv (= dx_mid D in planar,
  Eq. 12); in curved geometry it then ignores the geometric part 2u/r of the
  volume strain, as Wilkins' form does (no q in a uniform spherical expansion).
* Every zone carries a JWL row (000 Eq. 54, ERRATA 000-6; an ideal gas is the
  row A = B = 0, w = gamma - 1) and the programmed burn of 000 Eqs. (52)-(53):
  p = F p_E with F = clip((t - t_L) D / (1.5 h), 0, 1). F is a non-decreasing
  function of t, so once it reaches 1 it stays there (ERRATA 000-8); air zones
  have t_L = -inf (F = 1). The energy update (Eq. 16 generalised) is the
  trapezoidal p dV work with p/rho = F (f(rho)/rho + w e), solved exactly
  (linear in the new e); for an ideal gas it is Eq. (16) itself. The time step
  uses the EOS sound speed of the fully burnt state (F = 1), an upper bound.
* Optional afterburning (:func:`afterburn_increment`, ``Params.afterburn``; off when None): a
  prescribed energy source in the burnt products, released at a constant rate over a time window
  (Radioss /MAT/LAW5 Eadd with Tstart/Tstop, LS-DYNA *EOS_JWL_AFTERBURN constant-rate option). The
  increment enters the energy update as a source (e' = e + de - p dV work), and the released total is
  booked in the energy budget (``State.afterburn_released``).
"""
from __future__ import annotations

import functools

from typing import NamedTuple

import jax.numpy as jnp

from blastfsi import timeloop
from blastfsi.diagnostics import blast_maps
from blastfsi.eos import jwl
from blastfsi.eos.jwl import JWLParams


class Numerics(NamedTuple):
    """Scheme parameters (traced, so an ensemble may vary them; Python floats in a set-up)."""

    gamma: jnp.ndarray  # ratio of specific heats
    K1: jnp.ndarray  # quadratic viscosity coefficient, Eq. (5)
    K2: jnp.ndarray  # linear viscosity coefficient, Eq. (5)
    cfl: jnp.ndarray  # alpha in Eq. (20), 0 < alpha <= 1


class Boundaries(NamedTuple):
    """Boundary data. Static flags choose the kind; arrays carry the values (Python floats in a set-up).

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
    arrival_threshold: jnp.ndarray = 0.0  # overpressure that marks the arrival (blast_maps) [Pa]


class Zones(NamedTuple):
    """Per-zone material (JWL row, 000 Eq. 54) and programmed burn (000 Eqs. 52-53), each (N,)."""

    A: jnp.ndarray  # [Pa]
    B: jnp.ndarray  # [Pa]
    R1: jnp.ndarray
    R2: jnp.ndarray
    omega: jnp.ndarray
    rho0: jnp.ndarray  # [kg/m^3]
    lighting_time: jnp.ndarray  # t_L [s]; -inf for inert gas
    burn_rate: jnp.ndarray  # D / (1.5 h) [1/s]

    def eos(self) -> JWLParams:
        return JWLParams(self.A, self.B, self.R1, self.R2, self.omega, self.rho0)


class Afterburn(NamedTuple):
    """Afterburning energy source (see :func:`afterburn_increment`)."""

    rate: jnp.ndarray  # (N,) specific power released in each zone over the window [J/(kg s)]; 0 in inert gas
    start: jnp.ndarray  # start of the window [s]
    end: jnp.ndarray  # end of the window [s]


class Params(NamedTuple):
    """Everything the step reads besides the state (traced; stacked over an ensemble).
    ``zones`` None: every zone is the ideal gas of ``num.gamma`` (the plate problems).
    ``afterburn`` None: no afterburning (the step is then the scheme without it, bit for bit)."""

    num: Numerics
    bc: Boundaries
    gauges: Gauges
    x_right0: jnp.ndarray  # initial plate position [m]
    zones: Zones | None = None
    afterburn: Afterburn | None = None


class Static(NamedTuple):
    """Boundary kinds and geometry exponent, fixed at compile time (see :class:`Boundaries`); the devices an
    ensemble's members are spread over (:func:`blastfsi.method.compiled_advance`)."""

    left_velocity_set: bool
    right_fixed: bool
    geometry: int = 0  # j: 0 planar, 1 cylindrical, 2 spherical
    member_devices: int = 1


class State(NamedTuple):
    x: jnp.ndarray  # node positions at t_j, (N+1,)
    v: jnp.ndarray  # node velocities at t_{j-1/2}, (N+1,)
    e: jnp.ndarray  # zone specific internal energy at t_j, (N,)
    q: jnp.ndarray  # zone viscous pressure at t_{j-1/2}, (N,)
    a: jnp.ndarray  # zone sound speed at t_j, Eq. (13), (N,): computed once per step
    zone_mass: jnp.ndarray  # (N,), constant in time (Lagrangian)
    energy0: jnp.ndarray  # total energy at t = 0 (reference of the energy budget)
    face_impulse: jnp.ndarray  # int (p_{N-1/2} - p_right) dt on the right end
    peak_face_overpressure: jnp.ndarray
    boundary_work: jnp.ndarray  # work done on the system by the boundaries
    gauge_impulse: jnp.ndarray  # (G,) int max(p - p0, 0) dt at each gauge
    gauge_peak: jnp.ndarray  # (G,) peak overpressure at each gauge
    gauge_arrival: jnp.ndarray  # (G,) blast_maps arrival time [s]
    gauge_end: jnp.ndarray  # (G,) end of the positive phase [s]
    gauge_positive_impulse: jnp.ndarray  # (G,) positive-phase impulse [Pa s]
    gauge_last: jnp.ndarray  # (G,) overpressure at the previous step [Pa]
    zone_burnt: jnp.ndarray  # (N,) pressure F p_E of each zone at the step its burn completes (F reaches 1) [Pa]
    # energy released so far by afterburning, sum_z m_z de_z (per radian^j, J/m^2 in planar); stays 0
    # without afterburning (Params.afterburn None)
    afterburn_released: jnp.ndarray
    # clock fields of blastfsi.timeloop
    t: jnp.ndarray
    dt_prev: jnp.ndarray  # dt_j, the step that led to t_j (0 at start)
    dt0: jnp.ndarray  # the run's first stable step
    step: jnp.ndarray
    fault: jnp.ndarray  # timeloop fault code (first_fault locates a non-physical zone)
    hist: jnp.ndarray  # (n_samples, columns of history) histories sampled in compiled code
    hist_next: jnp.ndarray  # index of the next history sample to record


def ideal_gas_zones(gamma, n: int, dtype) -> Zones:
    """Every zone the ideal gas p = (gamma - 1) rho e (JWL row A = B = 0, w = gamma - 1), always burnt."""
    one = jnp.ones((n,), dtype)
    zero = jnp.zeros((n,), dtype)
    return Zones(zero, zero, one, one, (gamma - 1.0) * one, one, jnp.full((n,), -jnp.inf, dtype), one)


def zone_materials(params: Params, n: int, dtype) -> Zones:
    return ideal_gas_zones(params.num.gamma, n, dtype) if params.zones is None else params.zones


def zone_volume(x, j: int):
    """Zone volume per radian^j, (r+^(j+1) - r-^(j+1)) / (j+1), written as
    dr * mean_k(r+^k r-^(j-k)) (no cancellation for thin zones far from the centre)."""
    lo, hi = x[:-1], x[1:]
    return (hi - lo) * sum(hi**k * lo ** (j - k) for k in range(j + 1)) / (j + 1)


def node_area(x, j: int):
    """A_n = r_n^j (1 in planar geometry)."""
    return x**j


def burn_fraction(t, zones: Zones):
    """000 Eq. (53): F = clip((t - t_L) D / (1.5 h), 0, 1); non-decreasing in t (ERRATA 000-8)."""
    return jnp.clip((t - zones.lighting_time) * zones.burn_rate, 0.0, 1.0)


def eos_pressure(rho, e, t, zones: Zones):
    """000 Eq. (52): p = F p_E, p_E the JWL pressure (Eq. 54) of the zone's row."""
    return burn_fraction(t, zones) * jwl.pressure(rho, e, zones.eos())


def eos_sound_speed(rho, e, zones: Zones):
    """Sound speed of the burnt state (F = 1), :func:`blastfsi.eos.jwl.sound_speed_squared`;
    for an ideal gas sqrt(gamma (gamma-1) e), 002 Eq. (13) (ERRATA 002-3). NaN for e < 0 (fault check)."""
    c2 = jwl.sound_speed_squared(rho, jwl.pressure(rho, e, zones.eos()), zones.eos())
    return jnp.where(e > 0.0, c2, jnp.nan) ** 0.5


def zone_pressure(s, zones: Zones, j: int):
    """002 Eq. (11) (with q = -Q): p = F p_E(rho, e) + q, rho = m / V."""
    return eos_pressure(s.zone_mass / zone_volume(s.x, j), s.e, s.t, zones) + s.q


def node_masses(zone_mass, right_mass):
    """Lumped node masses: half of each neighbouring zone, plus the plate at node N.
    Equivalent to rho0^(n) DX in 002 Eq. (10) with Eq. (18)."""
    half = 0.5 * zone_mass
    m = jnp.concatenate([half[:1], half[1:] + half[:-1], half[-1:]])
    return m.at[-1].add(right_mass)


def zone_dt(dx, a, v, num: Numerics):
    """002 Eq. (20) per zone, with the viscous signal speed (see module docstring)."""
    dv = v[1:] - v[:-1]
    # the max keeps dt |dv| <= alpha dx / 2 (no zone crushed in one step) even without viscosity
    s = jnp.where(dv < 0.0, jnp.maximum(2.0 * (num.K1**2 * jnp.abs(dv) + num.K2 * a), jnp.abs(dv)), 0.0)
    return num.cfl * dx / (s + jnp.sqrt(s * s + a * a))


def stable_dt(dx, a, v, num: Numerics):
    """The smallest :func:`zone_dt`. NaN (NaN or negative energy somewhere) or
    <= 0 (a tangled zone) exactly when the state is non-physical, so the
    time-step reduction doubles as the fault check. (The NaN is set explicitly: XLA:CPU's vectorised min
    reduction does not propagate NaN on long arrays; seen at 8000 zones, where a NaN state ran on.)"""
    dt = zone_dt(dx, a, v, num)
    return jnp.where(jnp.all(jnp.isfinite(dt)), jnp.min(dt), jnp.nan)


def viscous_pressure(rho_mid, dv, a, num: Numerics):
    """002 Eq. (12), q = -Q >= 0, active in compression only (Eq. 5); dv = v_{n+1} - v_n
    (= dx_mid D in planar geometry)."""
    q = rho_mid * (num.K1 * dv) ** 2 + rho_mid * num.K2 * a * jnp.abs(dv)
    return jnp.where(dv < 0.0, q, 0.0)


def implicit_energy(e, q, rho_mid, dtD, p_over_rho_old, F_new, f_over_rho_new, omega):
    """002 Eq. (16) with Q = -q, for p = F (f(rho) + w rho e) (000 Eqs. 52, 54): trapezoidal p dV work,
    e' = e - (1/2 (p/rho + p'/rho') + q/rho_mid) dtD with p'/rho' = F' (f'/rho' + w e'), linear in e'.
    For an ideal gas (f = 0, w = gamma - 1, F = 1) this is Eq. (16) as printed."""
    return (e - (0.5 * p_over_rho_old + 0.5 * F_new * f_over_rho_new + q / rho_mid) * dtD) / (
        1.0 + 0.5 * F_new * omega * dtD)


def afterburn_increment(t, dt, afterburn: Afterburn, zones: Zones):
    """Specific internal energy each zone gains by afterburning over the step [t, t + dt].

    Models the optional afterburning energy of JWL products with a constant release rate: Radioss
    /MAT/LAW5 ``Eadd`` released linearly in time between ``Tstart`` and ``Tstop``, LS-DYNA
    *EOS_JWL_AFTERBURN with the constant-rate option. With Q the added energy per unit volume of
    unreacted explosive (density rho0) and [t_s, t_e) the window, a burnt zone gains

        de/dt = Q / (rho0 (t_e - t_s))   for t_s <= t < t_e, and 0 otherwise,

    here ``afterburn.rate`` per zone (0 in the air). The rate is integrated exactly over the overlap
    of the step with the window,

        de = rate * max(0, min(t + dt, t_e) - max(t, t_s, t_b)),

    so the increments of successive steps add up to rate (t_e - t_s): Q per unit initial volume,
    Q V_charge in all. t_b = t_L + 1.5 h / D is the time the zone's programmed burn completes
    (000 Eq. 53, F reaches 1): unburnt or partly burnt explosive gains nothing. (The charge set-up
    requires t_s >= the burn completion time of every zone, so no energy is withheld.)"""
    burnt = zones.lighting_time + 1.0 / zones.burn_rate  # F = 1 from here on (-inf in inert gas)
    lo = jnp.maximum(jnp.maximum(t, afterburn.start), burnt)
    hi = jnp.minimum(t + dt, afterburn.end)
    return afterburn.rate * jnp.maximum(hi - lo, 0.0)


def total_energy(state: State, bc: Boundaries):
    """Internal + kinetic energy per unit area (kinetic from the half-step velocities)."""
    nm = node_masses(state.zone_mass, bc.right_mass)
    return jnp.sum(state.zone_mass * state.e) + 0.5 * jnp.sum(nm * state.v**2)


def vnr_step(s: State, dt, node_mass, num: Numerics, bc: Boundaries, static: Static, zones: Zones,
             afterburn: Afterburn | None = None):
    """Advance one time step dt = dt_{j+1} (002 Sec. 2 sequence); ``node_mass``
    from :func:`node_masses`. Pure; leaves the clock fields to the time loop. ``afterburn``: the
    energy source of :func:`afterburn_increment`, added to e in the energy update."""
    j = static.geometry
    vol = zone_volume(s.x, j)
    rho = s.zone_mass / vol
    F = burn_fraction(s.t, zones)
    p_eos = F * jwl.pressure(rho, s.e, zones.eos())  # 000 Eqs. (52), (54)
    p = p_eos + s.q
    p_left = p[0] if static.left_velocity_set else bc.left_pressure
    p_ext = jnp.concatenate([jnp.reshape(p_left, (1,)), p, jnp.reshape(bc.right_pressure, (1,))])
    area = node_area(s.x, j)
    acc = area * (p_ext[:-1] - p_ext[1:]) / node_mass  # Eq. (10), Eq. (23), area-weighted
    v = s.v + 0.5 * (s.dt_prev + dt) * acc  # Eq. (9), ERRATA 002-2
    if static.left_velocity_set:
        v = v.at[0].set(bc.left_velocity)
    if static.right_fixed:
        v = v.at[-1].set(0.0)
    x = s.x + dt * v  # Eq. (8)
    vol_new = zone_volume(x, j)
    dtD = 2.0 * (vol_new - vol) / (vol_new + vol)  # dt * Eq. (14)
    rho_mid = 0.5 * s.zone_mass * (1.0 / vol_new + 1.0 / vol)  # Eq. (17)
    q = viscous_pressure(rho_mid, v[1:] - v[:-1], s.a, num)
    rho_new = s.zone_mass / vol_new
    F_new = burn_fraction(s.t + dt, zones)
    # the afterburning source of de/dt = -p dv/dt + S, booked exactly as m de (0 without: e + 0.0 = e)
    de = 0.0 if afterburn is None else afterburn_increment(s.t, dt, afterburn, zones)
    e = implicit_energy(s.e + de, q, rho_mid, dtD, p_eos / rho, F_new,
                        jwl.reference_pressure(rho_new, zones.eos()) / rho_new, zones.omega)
    area_new = node_area(x, j)
    work = dt * (p_left * v[0] * area_new[0] - bc.right_pressure * v[-1] * area_new[-1])
    face_over = p[-1] - bc.right_pressure
    return s._replace(
        x=x, v=v, e=e, q=q, a=eos_sound_speed(rho_new, e, zones),  # Eq. (13) at t_{j+1}
        face_impulse=s.face_impulse + dt * face_over,
        peak_face_overpressure=jnp.maximum(s.peak_face_overpressure, face_over),
        boundary_work=s.boundary_work + work,
        zone_burnt=jnp.where((F < 1.0) & (F_new >= 1.0), F_new * jwl.pressure(rho_new, e, zones.eos()),
                             s.zone_burnt),
        afterburn_released=s.afterburn_released + jnp.sum(s.zone_mass * de),
    )


def gauge_overpressure(s: State, gauges: Gauges, zones: Zones, j: int):
    """Overpressure in the zone holding each gauge; NaN for a gauge outside the gas."""
    k = jnp.clip(jnp.searchsorted(s.x, gauges.positions) - 1, 0, s.e.shape[0] - 1)
    xk = jnp.stack([s.x[k], s.x[k + 1]])
    rho = s.zone_mass[k] / zone_volume(xk, j)[0]
    p = eos_pressure(rho, s.e[k], s.t, Zones(*(f[k] for f in zones))) + s.q[k]
    inside = (gauges.positions >= s.x[0]) & (gauges.positions <= s.x[-1])
    return jnp.where(inside, p - gauges.ambient_pressure, jnp.nan)


def first_fault(s: State):
    """Index of the first zone with a non-physical state (NaN, tangled zone,
    non-positive internal energy), or -1 when the state is healthy. Works on
    NumPy and JAX arrays (the driver calls it on the host after a fault)."""
    dx = s.x[1:] - s.x[:-1]
    bad = ~(jnp.isfinite(dx) & (dx > 0.0) & jnp.isfinite(s.e) & (s.e > 0.0) & jnp.isfinite(s.v[1:]))
    return jnp.where(jnp.any(bad), jnp.argmax(bad), -1).astype(jnp.int32)


def history(n_gauges: int, s: State | None = None, params: Params | None = None, static: Static | None = None,
            zones: Zones | None = None) -> timeloop.Row:
    """The history row of state ``s``: the plate's displacement, velocity, overpressure and impulse, the
    impulse on the right face, the left end's overpressure and the energy error, then the overpressure of each
    of the ``n_gauges`` gauges. Without a state only its columns (``.columns``) can be read."""

    @functools.cache
    def pressure():  # (traced: only when s is given)
        return zone_pressure(s, zones, static.geometry)

    def plate_velocity():
        return 0.0 * s.v[-1] if static.right_fixed else s.v[-1]

    def plate_impulse():
        return s.face_impulse if static.right_fixed else params.bc.right_mass * s.v[-1]

    def energy_error():  # the afterburning source is booked as supplied (0 without afterburning)
        return total_energy(s, params.bc) - s.energy0 - s.boundary_work - s.afterburn_released

    row = timeloop.Row()
    row.add("time", "s", lambda: s.t)
    row.add("plate_displacement", "m", lambda: s.x[-1] - params.x_right0)
    row.add("plate_velocity", "m/s", plate_velocity)
    row.add("plate_overpressure", "Pa", lambda: pressure()[-1] - params.bc.right_pressure)
    row.add("plate_impulse", "Pa*s", plate_impulse)
    row.add("surface_impulse", "Pa*s", lambda: s.face_impulse)
    row.add("left_overpressure", "Pa", lambda: pressure()[0] - params.bc.right_pressure)
    row.add("energy_error", "J/m^2", energy_error)
    row.add_block([(f"gauge{k}_overpressure", "Pa") for k in range(n_gauges)],
                  lambda: gauge_overpressure(s, params.gauges, zones, static.geometry))
    return row


def initial_state(x, v, e, zone_mass, gamma, n_samples: int, n_gauges: int = 0, right_mass=0.0,
                  zones: Zones | None = None, geometry: int = 0) -> State:
    """State at t = 0; ``right_mass`` (the plate) enters the reference energy; ``zones``
    None: the ideal gas of ``gamma`` everywhere."""
    x = jnp.asarray(x)
    e = jnp.asarray(e)
    zone_mass = jnp.asarray(zone_mass)
    zones = ideal_gas_zones(jnp.asarray(gamma, x.dtype), e.shape[0], x.dtype) if zones is None else zones
    g = jnp.zeros((n_gauges,), x.dtype)
    zero = jnp.zeros((), x.dtype)
    s = State(
        x=x, v=jnp.asarray(v), e=e, q=jnp.zeros_like(e), a=eos_sound_speed(zone_mass / zone_volume(x, geometry), e,
                                                                            zones),
        zone_mass=zone_mass, energy0=zero, face_impulse=zero,
        peak_face_overpressure=jnp.asarray(-jnp.inf, x.dtype), boundary_work=zero,
        gauge_impulse=g, gauge_peak=g - jnp.inf, gauge_arrival=g + jnp.inf, gauge_end=g + jnp.inf,
        gauge_positive_impulse=g, gauge_last=g, zone_burnt=jnp.zeros_like(e),
        afterburn_released=zero, **timeloop.clock(n_samples, len(history(n_gauges).columns), x.dtype),
    )
    right = Boundaries(zero, zero, jnp.asarray(right_mass, x.dtype), zero)
    return s._replace(energy0=total_energy(s, right))


def advance(s: State, params: Params, static: Static, t_stop, max_steps, sample_interval,
            dt_floor_fraction) -> State:
    """Advance one member with :func:`blastfsi.timeloop.run_until` until t_stop,
    max_steps more steps, or a fault (non-physical state, or the step below
    ``dt_floor_fraction`` of the first). Gauge impulses and peaks are
    accumulated every step, from the state at t_j like the plate load."""
    num, bc, gauges = params.num, params.bc, params.gauges
    node_mass = node_masses(s.zone_mass, bc.right_mass)
    zones = zone_materials(params, s.e.shape[0], s.e.dtype)
    j = static.geometry

    def stable(st):
        return stable_dt(st.x[1:] - st.x[:-1], st.a, st.v, num)

    def step(st, dt):
        new = vnr_step(st, dt, node_mass, num, bc, static, zones, params.afterburn)
        pg = gauge_overpressure(st, gauges, zones, j)
        pg_new = jnp.nan_to_num(gauge_overpressure(new._replace(t=st.t + dt), gauges, zones, j))
        maps = blast_maps.update(blast_maps.BlastMaps(st.gauge_peak, st.gauge_arrival, st.gauge_end,
                                                      st.gauge_positive_impulse, st.gauge_last),
                                 pg_new, st.t, dt, gauges.arrival_threshold)
        return new._replace(gauge_impulse=st.gauge_impulse + dt * jnp.nan_to_num(jnp.maximum(pg, 0.0)),
                            gauge_peak=jnp.fmax(st.gauge_peak, pg), gauge_arrival=maps.arrival,
                            gauge_end=maps.end, gauge_positive_impulse=maps.impulse, gauge_last=maps.last)

    return timeloop.run_until(s, t_stop, max_steps, sample_interval, dt_floor_fraction, stable_dt=stable, step=step,
                              history_row=lambda st: history(gauges.positions.shape[0], st, params, static, zones).values(st.t.dtype))
