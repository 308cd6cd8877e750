"""Seed 002 problems: uniform, exponential and planar-Sedov blasts on a plate.

The gas column occupies [0, L]; the plate (or rigid wall) is the node at x = L,
so the paper's plate position x = 0 maps to x = L and the plate displacement
is xi = x_N - L.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from blastfsi.eos import ideal_gas
from blastfsi.exact import shock
from blastfsi.exact.sedov import PlanarSedov
from blastfsi.lagrangian1d.scenario import Scenario
from blastfsi.lagrangian1d.scheme import Boundaries, Numerics
from blastfsi.scenario import ScenarioError


@dataclass(frozen=True)
class Theory:
    """Theory values and metadata of a plate run; None where the problem has none
    (the shock values for the Sedov blast, the Sedov values for the others)."""

    plate_areal_mass: float  # [kg/m^2]; 0 for a rigid wall or a free end
    incident_overpressure: float | None = None  # p_s [Pa]
    shock_speed: float | None = None  # U_s [m/s]
    shocked_density: float | None = None  # rho_s [kg/m^3]
    particle_velocity: float | None = None  # u_s [m/s]
    reflection_coefficient_theory: float | None = None  # C_R = p_r / p_s, 002 Eqs. (24)-(25) [-]
    f_R: float | None = None  # light-plate compressibility factor from shock theory [-]
    f_R_eq30: float | None = None  # f_R of 002 Eq. (30) as printed [-]; None unless gamma = 1.4
    free_surface_velocity: float | None = None  # gas velocity after the shocked state expands to 0 [m/s]
    duration: float | None = None  # t_i [s]
    incident_impulse: float | None = None  # I_i = p_s t_i [Pa s]
    beta_s: float | None = None  # 002 Eq. (28) [-]; 0 for a rigid wall, None for a free end
    impulse_ratio_theory: float | None = None  # I_p / (C_R I_i), 002 Eq. (29) [-]
    arrival_time: float | None = None  # time the incident shock reaches the plate [s]
    clean_duration: float | None = None  # window after arrival free of waves re-reflected by the piston [s]
    nominal: bool = False  # the shock values are those of the nominal p_s, t_i (the exponential blast)
    explosion_time: float | None = None  # time from the explosion to simulated time 0 (Sedov) [s]
    sedov_alpha: float | None = None  # alpha of the planar Sedov solution [-]
    front_speed_initial: float | None = None  # Sedov front speed at simulated time 0 [m/s]


@dataclass(frozen=True)
class Setup:
    """Initial data, scheme parameters and boundary data of one run (NumPy, host side)."""

    x: np.ndarray  # node positions (N+1,)
    v: np.ndarray  # node velocities (N+1,)
    e: np.ndarray  # zone specific internal energy (N,)
    zone_mass: np.ndarray  # (N,) kg/m^2
    numerics: Numerics  # of Python floats
    boundaries: Boundaries  # of Python floats
    left_velocity_set: bool
    right_fixed: bool
    theory: Theory
    gauges: np.ndarray = field(default_factory=lambda: np.zeros(0))  # gauge positions [m]
    ambient_pressure: float = 0.0  # overpressure reference p0 of the gauges [Pa]
    arrival_fraction: float = 0.0  # output.arrival_fraction: a gauge's arrival overpressure, of p0 (set by build)

    @property
    def cells(self) -> int:
        return self.zone_mass.size


def _uniform_grid(sc: Scenario):
    n = sc.grid.cells
    x = np.linspace(0.0, sc.domain.length, n + 1)
    return x, np.diff(x)


def _plate_mass(sc: Scenario, beta_mass=None) -> float:
    p = sc.plate
    if p.fixed:
        return 0.0
    if p.areal_mass is not None:
        return p.areal_mass
    if p.density is not None:
        return p.density * p.thickness
    return beta_mass


def _theory(sc: Scenario, ps: float, duration, plate_mass: float, **metadata) -> Theory:
    """Eq. (25), (28)-(30) values for an incident overpressure ps lasting duration, with ``metadata``."""
    g = sc.gas
    s = shock.incident_shock(ps, g.pressure, g.density, g.gamma)
    f_r = float(shock.f_R(ps, g.pressure, g.density, g.gamma))
    beta = ratio = None
    if duration is not None and (sc.plate.fixed or plate_mass > 0):  # a free end (mass 0) has no beta_s
        if sc.plate.fixed:
            beta = 0.0
        else:
            beta = float(shock.beta_s(ps, duration, plate_mass, g.pressure, g.density, g.gamma))
        ratio = float(shock.impulse_ratio_uniform(beta, f_r))
    return Theory(
        plate_areal_mass=plate_mass,
        incident_overpressure=float(ps),
        shock_speed=float(s.shock_speed),
        shocked_density=float(s.density),
        particle_velocity=float(s.particle_velocity),
        reflection_coefficient_theory=float(shock.reflection_coefficient(ps, g.pressure, g.gamma)),
        f_R=f_r,
        f_R_eq30=float(shock.f_R_eq30(ps, g.pressure)) if g.gamma == 1.4 else None,
        free_surface_velocity=float(shock.free_surface_velocity(ps, g.pressure, g.density, g.gamma)),
        duration=duration,
        incident_impulse=None if duration is None else float(ps * duration),
        beta_s=beta,
        impulse_ratio_theory=ratio,
        **metadata,
    )


def clean_window(sc: Scenario, ps: float) -> float:
    """Time after shock arrival during which the plate sees only the incident
    shock and its own reflection.

    At arrival the shocked column between piston and plate is L rho0/rho_s long.
    The fastest wave the plate can send back is the wall-reflected shock,
    W = rho_s u_s/(rho_r - rho_s) in the lab frame, or for light plates a
    rarefaction whose head closes on the piston at a_s. The window is the time
    that wave needs to reach the piston, a lower bound on its round trip.
    """
    g = sc.gas
    s = shock.incident_shock(ps, g.pressure, g.density, g.gamma)
    pr = ps * shock.reflection_coefficient(ps, g.pressure, g.gamma)
    # density behind the reflected shock: Hugoniot through the shocked state
    p1, p2 = g.pressure + ps, g.pressure + pr
    gp, gm = g.gamma + 1.0, g.gamma - 1.0
    rho_r = s.density * (gp * p2 + gm * p1) / (gm * p2 + gp * p1)
    w = s.density * s.particle_velocity / (rho_r - s.density)
    closing = max(w + s.particle_velocity, s.sound_speed)
    return float(sc.domain.length * g.density / s.density / closing)


def build_uniform(sc: Scenario) -> Setup:
    """002 Sec. 3.1-3.2: piston at u_s(p_s) into gas at rest; plate/wall at x = L."""
    g, inc = sc.gas, sc.incident
    x, dx = _uniform_grid(sc)
    s = shock.incident_shock(inc.overpressure, g.pressure, g.density, g.gamma)
    arrival = sc.domain.length / float(s.shock_speed)
    duration = sc.time.end - arrival
    if duration <= 0:
        raise ScenarioError(f"time.end ({sc.time.end} s) must exceed the shock arrival time at the plate, "
                            f"domain.length/U_s = {arrival:.6g} s")
    beta_mass = None
    if sc.plate.beta_s is not None:
        beta_mass = float(shock.areal_mass_from_beta_s(sc.plate.beta_s, inc.overpressure, duration,
                                                        g.pressure, g.density, g.gamma))
    mass = _plate_mass(sc, beta_mass)
    v = np.zeros_like(x)
    v[0] = s.particle_velocity
    theory = _theory(sc, inc.overpressure, duration, mass, arrival_time=arrival,
                     clean_duration=clean_window(sc, inc.overpressure))
    return Setup(
        x=x, v=v, e=np.full(dx.shape, ideal_gas.energy(g.density, g.pressure, g.gamma)), zone_mass=g.density * dx,
        numerics=_numerics(sc), boundaries=Boundaries(float(s.particle_velocity), g.pressure, mass, _back(sc)),
        left_velocity_set=True, right_fixed=sc.plate.fixed, theory=theory,
    )


def build_exponential(sc: Scenario) -> Setup:
    """002 Sec. 3.3: exponential overpressure behind a front at L - standoff,
    ramped linearly to zero over ``ramp_cells`` cells at the front; velocity
    and density from the Rankine-Hugoniot relations at the local overpressure
    (Eq. 27 corrected, Eq. 31). Left end: free, at the initial end pressure.

    beta_s and the theory values use the nominal p_s = p_i and
    t_i = d_i / U_s(p_i) (the decay time of the undistorted profile).
    """
    g, inc = sc.gas, sc.incident
    x, dx = _uniform_grid(sc)
    front = sc.domain.length - inc.standoff
    ramp = inc.ramp_cells * dx[0]

    def overpressure(pos):
        behind = np.clip((front - pos) / ramp, 0.0, 1.0)
        return inc.overpressure * np.exp(-np.maximum(front - pos, 0.0) / inc.decay_length) * behind

    xc = 0.5 * (x[1:] + x[:-1])
    pz = overpressure(xc)
    zs = shock.incident_shock(pz, g.pressure, g.density, g.gamma)
    v = shock.incident_shock(overpressure(x), g.pressure, g.density, g.gamma).particle_velocity
    p_abs = g.pressure + pz
    nominal = shock.incident_shock(inc.overpressure, g.pressure, g.density, g.gamma)
    duration = inc.decay_length / float(nominal.shock_speed)
    mass = _plate_mass(sc)
    theory = _theory(sc, inc.overpressure, duration, mass, arrival_time=inc.standoff / float(nominal.shock_speed),
                     nominal=True)
    return Setup(
        x=x, v=np.asarray(v, float), e=ideal_gas.energy(zs.density, p_abs, g.gamma), zone_mass=zs.density * dx,
        numerics=_numerics(sc), boundaries=Boundaries(0.0, float(p_abs[0]), mass, _back(sc)),
        left_velocity_set=False, right_fixed=sc.plate.fixed, theory=theory,
    )


def build_sedov(sc: Scenario) -> Setup:
    """002 Sec. 3.4: planar point explosion with its symmetry plane at x = 0
    (a fixed wall), initialised from the exact solution when the front is at
    ``incident.front_position``. Zone mass and total energy are the exact
    cell averages (8-point Gauss quadrature), so the integrable singularity at
    the centre (rho -> 0, e -> inf) is represented without loss of mass or energy.
    Simulated time 0 is explosion time ``explosion_time`` (in ``theory``).

    Near the centre rho ~ x^2.5 and e ~ x^-2.5, so the first zone's sound speed
    grows without bound under refinement (dt ~ dx^2.25). The "finite radius of
    the explosion" of Sec. 3.4: zones inside ``core_fraction * front_position``
    get the core's mean density and specific internal energy, which keeps its
    mass and internal energy exactly and its pressure at the (nearly uniform,
    h ~ 0.39) central value. The rest of the profile is untouched.
    """
    g, inc = sc.gas, sc.incident
    x, dx = _uniform_grid(sc)
    blast = PlanarSedov(inc.energy, g.density, g.gamma)
    t0 = float(blast.time_at_front(inc.front_position))

    def fields(pos):
        rho, u, p = blast(pos, t0)
        inside = pos <= inc.front_position
        return np.where(inside, rho, g.density), u, np.where(inside, np.maximum(p, g.pressure), g.pressure)

    nodes, weights = np.polynomial.legendre.leggauss(8)
    xq = 0.5 * (x[1:] + x[:-1])[:, None] + 0.5 * dx[:, None] * nodes[None, :]
    rho, u, p = fields(xq)
    w = 0.5 * weights[None, :]
    mass_avg = np.sum(w * rho, axis=1)
    mom_avg = np.sum(w * rho * u, axis=1)
    energy_avg = np.sum(w * (0.5 * rho * u**2 + p / (g.gamma - 1.0)), axis=1)
    e = (energy_avg - 0.5 * mom_avg**2 / mass_avg) / mass_avg
    core = 0.5 * (x[1:] + x[:-1]) < inc.core_fraction * inc.front_position
    if np.any(core):
        core_mass = np.sum(mass_avg[core] * dx[core])
        e[core] = np.sum(mass_avg[core] * dx[core] * e[core]) / core_mass
        mass_avg[core] = core_mass / np.sum(dx[core])
    v = fields(x)[1]
    v[0] = 0.0
    mass = _plate_mass(sc)
    theory = Theory(plate_areal_mass=mass, explosion_time=t0, sedov_alpha=blast.alpha,
                    front_speed_initial=2.0 / 3.0 * inc.front_position / t0)
    return Setup(
        x=x, v=v, e=e, zone_mass=mass_avg * dx, numerics=_numerics(sc),
        boundaries=Boundaries(0.0, g.pressure, mass, _back(sc)), left_velocity_set=True, right_fixed=sc.plate.fixed,
        theory=theory,
    )


def _numerics(sc: Scenario) -> Numerics:
    return Numerics(sc.gas.gamma, sc.numerics.K1, sc.numerics.K2, sc.numerics.cfl)


def _back(sc: Scenario) -> float:
    return sc.gas.pressure if sc.plate.back_pressure is None else sc.plate.back_pressure


BUILDERS = {"uniform": build_uniform, "exponential": build_exponential, "sedov": build_sedov}


def build(sc: Scenario) -> Setup:
    setup = BUILDERS[sc.incident.profile](sc)
    return replace(setup, gauges=np.asarray(sc.output.gauges, float), ambient_pressure=sc.gas.pressure,
                   arrival_fraction=sc.output.arrival_fraction)
