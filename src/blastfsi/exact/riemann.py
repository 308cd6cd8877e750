"""Exact solution of the Riemann problem for the 1D Euler equations.

Each side of the diaphragm holds its own gas, described by one
:class:`blastfsi.eos.jwl.JWLParams` row (JWL detonation products, or an ideal
gas as the row A = B = 0, w = gamma - 1), so products | air problems are
covered. The solution is self-similar in xi = (x - x0)/t: a left wave, a
contact moving at u*, a right wave.

Method (Toro, *Riemann Solvers and Numerical Methods for Fluid Dynamics*,
3rd ed., 2009, ch. 4, generalised to Mie-Grueneisen gases as in Kamm,
LA-UR-15-21616, 2015):

* The star pressure p* is the root of
  g(p) = f_L(p) + f_R(p) + u_R - u_L  (Toro Eq. 4.5), bracketed and solved
  with Brent's method; u* = (u_L + u_R)/2 + (f_R(p*) - f_L(p*))/2 (Eq. 4.9).
* Shock (p > p_K): the post-shock specific volume v solves the Hugoniot
  e(1/v, p) - e_K = (p + p_K)(v_K - v)/2 of the side's own EOS; then
  f_K = sqrt((p - p_K)(v_K - v)) and the mass flux is m = sqrt((p - p_K)/(v_K - v)).
* Rarefaction (p < p_K): the gas stays on the isentrope through the initial
  state. With V = rho0/rho the relative volume and E = rho0 e, the JWL
  isentropes (dE = -p dV) are, in closed form,
      p_s(V) = A exp(-R1 V) + B exp(-R2 V) + C V^-(1+w),
      C = (p_K - A exp(-R1 V_K) - B exp(-R2 V_K)) V_K^(1+w)
  (check: with E_s = A/R1 exp(-R1 V) + B/R2 exp(-R2 V) + C/w V^-w one has
  -dE_s/dV = p_s and p(V, E_s) = p_s by 000 Eq. (54); an ideal gas gives
  p V^gamma = C). The Riemann invariant du = c dln(V) (= -c drho/rho) is
  integrated numerically (scipy quad / DOP853 at relative tolerance 1e-13),
  with c^2 from :func:`blastfsi.eos.jwl.sound_speed_squared`.
* Ideal gases on both sides use Toro's closed forms (Eqs. 4.6-4.8, 4.50-4.56)
  unless ``closed_form_ideal_gas=False``.
* Vacuum generation (u_R - u_L >= 2 c_L/(gamma_L - 1) + 2 c_R/(gamma_R - 1),
  Toro Eq. 4.40) is solved for ideal gases on both sides (Toro Sec. 4.6);
  a JWL side that would expand to vacuum raises :class:`ValueError`.
  In vacuum, density and pressure are 0 and the returned velocity is x/t
  (the velocity is undefined there; x/t is continuous with both fan edges).

All waves are computed for a left-facing wave; the right wave is the mirror
image (x -> -x, u -> -u).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import integrate, optimize

from blastfsi.eos import jwl
from blastfsi.eos.jwl import JWLParams, ideal_gas_params
from blastfsi.materials.gases import GASES

_RTOL = 1e-13  # relative tolerance of the quadratures and of the fan ODE
_ROOT_RTOL = 4.0 * np.finfo(float).eps  # Brent's method: converge to machine precision
_ROOT_XTOL = np.finfo(float).tiny
_FAN_BISECTIONS = 64  # halvings of the fan's ln V interval: 2^-64 of it is below double precision


def _brent(fun, lo, hi):
    return optimize.brentq(fun, lo, hi, xtol=_ROOT_XTOL, rtol=_ROOT_RTOL, maxiter=1000)


class _IdealGasWave:
    """Left-facing wave into an ideal-gas state K (Toro ch. 4 closed forms)."""

    supports_vacuum = True

    def __init__(self, rho, u, p, gamma):
        self.rho, self.u, self.p, self.gamma = rho, u, p, gamma
        self.c = math.sqrt(gamma * p / rho)

    def velocity_change(self, p):
        """f_K(p) of Toro Eqs. (4.6)-(4.8): u* = u_K - f_K(p*) for a left wave."""
        g = self.gamma
        if p > self.p:
            a_k = 2.0 / ((g + 1.0) * self.rho)
            b_k = (g - 1.0) / (g + 1.0) * self.p
            return (p - self.p) * math.sqrt(a_k / (p + b_k))
        return 2.0 * self.c / (g - 1.0) * ((p / self.p) ** ((g - 1.0) / (2.0 * g)) - 1.0)

    def wave(self, p_star, u_star):
        g = self.gamma
        ratio = p_star / self.p
        if p_star > self.p:
            gm = (g - 1.0) / (g + 1.0)
            rho_star = self.rho * (ratio + gm) / (gm * ratio + 1.0)  # Toro Eq. (4.50)
            s = self.u - self.c * math.sqrt((g + 1.0) / (2.0 * g) * ratio + (g - 1.0) / (2.0 * g))  # Eq. (4.52)
            return _Wave("shock", s, s, rho_star, None)
        rho_star = self.rho * ratio ** (1.0 / g)  # Toro Eq. (4.53)
        c_star = self.c * ratio ** ((g - 1.0) / (2.0 * g))  # Eq. (4.54)
        return _Wave("rarefaction", self.u - self.c, u_star - c_star, rho_star, self.fan)  # Eq. (4.55)

    def fan(self, xi):
        """State inside the left fan at xi = x/t, Toro Eq. (4.56)."""
        g = self.gamma
        base = 2.0 / (g + 1.0) + (g - 1.0) / ((g + 1.0) * self.c) * (self.u - xi)
        rho = self.rho * base ** (2.0 / (g - 1.0))
        u = 2.0 / (g + 1.0) * (self.c + 0.5 * (g - 1.0) * self.u + xi)
        p = self.p * base ** (2.0 * g / (g - 1.0))
        return rho, u, p


class _MieGruneisenWave:
    """Left-facing wave into a state K of a JWL (Mie-Grueneisen) gas."""

    supports_vacuum = False

    def __init__(self, rho, u, p, eos: JWLParams):
        self.rho, self.u, self.p, self.eos = rho, u, p, eos
        self.e = float(jwl.energy(rho, p, eos))
        self.c = math.sqrt(jwl.sound_speed_squared(rho, p, eos))
        v_rel = eos.rho0 / rho
        self.s = math.log(v_rel)  # ln V_K
        self.isentrope_constant = (p - self._cold_isentrope(v_rel)) * v_rel ** (1.0 + eos.omega)  # C

    # --- isentrope through K, parametrised by s = ln V --------------------------------
    def _cold_isentrope(self, v_rel):
        q = self.eos
        return q.A * np.exp(-q.R1 * v_rel) + q.B * np.exp(-q.R2 * v_rel)

    def _isentrope_pressure(self, s):
        v_rel = np.exp(s)
        return self._cold_isentrope(v_rel) + self.isentrope_constant * v_rel ** (-(1.0 + self.eos.omega))

    def _isentrope_sound_speed_squared(self, s):
        rho = self.eos.rho0 / np.exp(s)
        return jwl.sound_speed_squared(rho, self._isentrope_pressure(s), self.eos)

    def _isentrope_sound_speed(self, s):
        return np.sqrt(self._isentrope_sound_speed_squared(s))

    def _isentrope_log_volume(self, p):
        """ln V on the isentrope where the pressure has dropped to p <= p_K."""
        lo = hi = self.s
        if self._isentrope_pressure(lo) <= p:  # p = p_K to rounding
            return lo
        for _ in range(400):  # expand V by 25 % steps until the pressure has dropped below p
            hi = hi + math.log(1.25)
            if self._isentrope_pressure(hi) <= p or not self._isentrope_sound_speed_squared(hi) > 0.0:
                break
            lo = hi
        if self._isentrope_pressure(hi) <= p:
            s = _brent(lambda s: self._isentrope_pressure(s) - p, lo, hi)
            if self._isentrope_sound_speed_squared(s) > 0.0:
                return s
        raise ValueError(f"a rarefaction from the state (rho={self.rho}, p={self.p}) cannot reach p={p}: "
                         f"the isentrope leaves the EOS's hyperbolic range (c^2 <= 0) first")

    def _riemann_invariant_change(self, s):
        """integral of c dlnV from ln V_K to s (the velocity gained through a left fan)."""
        value, _ = integrate.quad(self._isentrope_sound_speed, self.s, s, epsabs=0.0, epsrel=_RTOL, limit=400)
        return value

    # --- shock -------------------------------------------------------------------------
    def _hugoniot_volume(self, p):
        """Specific volume behind a shock to pressure p > p_K (Rankine-Hugoniot energy jump)."""
        v_k = 1.0 / self.rho

        def mismatch(v):
            return float(jwl.energy(1.0 / v, p, self.eos)) - self.e - 0.5 * (p + self.p) * (v_k - v)

        # mismatch(v_K) = e(rho_K, p) - e_K > 0; start below at the constant-w strong-shock limit
        lo = v_k * self.eos.omega / (self.eos.omega + 2.0)
        for _ in range(200):
            if mismatch(lo) < 0.0:
                break
            lo *= 0.5
        else:
            raise ValueError(f"no Hugoniot state at p={p} from (rho={self.rho}, p={self.p})")
        return _brent(mismatch, lo, v_k)

    def velocity_change(self, p):
        """f_K(p): u* = u_K - f_K(p*) for a left wave (shock: Rankine-Hugoniot; rarefaction: isentrope)."""
        if p == self.p:
            return 0.0
        if p > self.p:
            return math.sqrt((p - self.p) * (1.0 / self.rho - self._hugoniot_volume(p)))
        return -self._riemann_invariant_change(self._isentrope_log_volume(p))

    def wave(self, p_star, u_star):
        if p_star > self.p:
            v = self._hugoniot_volume(p_star)
            mass_flux = math.sqrt((p_star - self.p) / (1.0 / self.rho - v))
            s = self.u - mass_flux / self.rho
            return _Wave("shock", s, s, 1.0 / v, None)
        s_star = self._isentrope_log_volume(p_star)
        tail = u_star - float(self._isentrope_sound_speed(s_star))
        return _Wave("rarefaction", self.u - self.c, tail, self.eos.rho0 / math.exp(s_star),
                     self._fan_sampler(s_star))

    def _fan_sampler(self, s_star):
        """Fan state at xi: find ln V with u(V) - c(V) = xi by bisection (u - c grows from head to tail)."""
        if s_star == self.s:  # p* = p_K: the fan has zero width
            return None
        span = s_star - self.s
        sol = integrate.solve_ivp(lambda s, y: [self._isentrope_sound_speed(s)], (self.s, s_star), [0.0],
                                  method="DOP853", rtol=_RTOL, atol=_RTOL * self.c * span, dense_output=True).sol

        def fan(xi):
            lo = np.full_like(xi, self.s)
            hi = np.full_like(xi, s_star)
            for _ in range(_FAN_BISECTIONS):
                mid = 0.5 * (lo + hi)
                short = self.u + sol(mid)[0] - self._isentrope_sound_speed(mid) < xi
                lo = np.where(short, mid, lo)
                hi = np.where(short, hi, mid)
            s = 0.5 * (lo + hi)
            return self.eos.rho0 / np.exp(s), self.u + sol(s)[0], self._isentrope_pressure(s)

        return fan


@dataclass(frozen=True)
class _Wave:
    kind: str  # "shock" | "rarefaction"
    head: float  # speed of the edge facing the undisturbed state
    tail: float  # speed of the edge facing the star state (= head for a shock)
    rho_star: float
    fan: object  # callable xi -> (rho, u, p) inside a rarefaction, else None


def _sample_left(wave_curve, wave: _Wave, xi, p_star, u_star):
    """(rho, u, p) at xi for points left of the contact, in the left-wave orientation."""
    rho = np.where(xi < wave.head, wave_curve.rho, wave.rho_star)
    u = np.where(xi < wave.head, wave_curve.u, u_star)
    p = np.where(xi < wave.head, wave_curve.p, p_star)
    if wave.fan is not None:
        in_fan = (xi >= wave.head) & (xi < wave.tail)
        if np.any(in_fan):
            f_rho, f_u, f_p = wave.fan(xi[in_fan])
            rho[in_fan], u[in_fan], p[in_fan] = f_rho, f_u, f_p
    return rho, u, p


def _as_state(name, value):
    try:
        rho, u, p = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"RiemannProblem.{name} must be a (rho, u, p) triple of numbers, got {value!r}") from None
    if not (math.isfinite(rho) and math.isfinite(u) and math.isfinite(p)):
        raise ValueError(f"RiemannProblem.{name} must be finite, got {value!r}")
    if not rho > 0.0:
        raise ValueError(f"RiemannProblem.{name} density must be > 0 kg/m^3, got {rho}")
    if not p > 0.0:
        raise ValueError(f"RiemannProblem.{name} pressure must be > 0 Pa, got {p}")
    return rho, u, p


def _as_eos(name, value):
    try:
        eos = JWLParams(*(float(v) for v in value))
    except (TypeError, ValueError):
        raise ValueError(f"RiemannProblem.{name} must be a JWLParams row (A, B, R1, R2, omega, rho0), "
                         f"got {value!r}") from None
    if not all(math.isfinite(v) for v in eos):
        raise ValueError(f"RiemannProblem.{name} must be finite, got {eos}")
    if not eos.omega > 0.0:
        raise ValueError(f"RiemannProblem.{name}.omega must be > 0, got {eos.omega}")
    if not eos.rho0 > 0.0:
        raise ValueError(f"RiemannProblem.{name}.rho0 must be > 0 kg/m^3, got {eos.rho0}")
    if not (eos.R1 > 0.0 and eos.R2 > 0.0):
        raise ValueError(f"RiemannProblem.{name}.R1 and R2 must be > 0, got {eos.R1}, {eos.R2}")
    return eos


@dataclass(frozen=True)
class RiemannProblem:
    """Exact Riemann solution: callable ``(x, t) -> (rho, u, p)``.

    Parameters: ``left``/``right`` initial states (rho [kg/m^3], u [m/s], p [Pa]);
    ``eos_left``/``eos_right`` the gas on each side (default: ideal gas,
    gamma = 1.4); ``x0`` the diaphragm position [m]; ``closed_form_ideal_gas``
    uses Toro's closed forms when both sides are ideal gases (set False to
    force the general Mie-Grueneisen path).

    After construction: ``p_star``, ``u_star`` (nan in vacuum),
    ``rho_star_left``, ``rho_star_right``, ``left_wave``/``right_wave``
    ("shock" or "rarefaction"), ``left_wave_speeds``/``right_wave_speeds``
    as (head, tail) with the head the edge facing the undisturbed state
    (head = tail for a shock), ``vacuum`` (True where a vacuum forms;
    the wave tails are then the vacuum fronts).
    """

    left: tuple
    right: tuple
    eos_left: JWLParams = ideal_gas_params(1.4)
    eos_right: JWLParams = ideal_gas_params(1.4)
    x0: float = 0.0
    closed_form_ideal_gas: bool = True
    p_star: float = field(init=False)
    u_star: float = field(init=False)
    rho_star_left: float = field(init=False)
    rho_star_right: float = field(init=False)
    left_wave: str = field(init=False)
    right_wave: str = field(init=False)
    left_wave_speeds: tuple = field(init=False)
    right_wave_speeds: tuple = field(init=False)
    vacuum: bool = field(init=False)
    _sides: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        left, right = _as_state("left", self.left), _as_state("right", self.right)
        eos_l, eos_r = _as_eos("eos_left", self.eos_left), _as_eos("eos_right", self.eos_right)
        if not math.isfinite(self.x0):
            raise ValueError(f"RiemannProblem.x0 must be finite, got {self.x0}")
        for key, value in (("left", left), ("right", right), ("eos_left", eos_l), ("eos_right", eos_r),
                           ("x0", float(self.x0))):
            object.__setattr__(self, key, value)  # normalised: tuples of floats, JWLParams rows
        for name, (rho, _, p), eos in (("left", left, eos_l), ("right", right, eos_r)):
            if not jwl.sound_speed_squared(rho, p, eos) > 0.0:
                raise ValueError(f"RiemannProblem.{name} state is outside the EOS's hyperbolic range (c^2 <= 0)")
        # both waves in the left-facing orientation: the right side is mirrored (u -> -u)
        wl = self._wave_curve(left, eos_l)
        wr = self._wave_curve((right[0], -right[1], right[2]), eos_r)
        du = right[1] - left[1]
        vacuum = wl.supports_vacuum and wr.supports_vacuum and (
            wl.velocity_change(0.0) + wr.velocity_change(0.0) + du >= 0.0)  # Toro Eq. (4.40)
        if vacuum:
            p_star, u_star = 0.0, math.nan
            u_l, u_r = left[1] - wl.velocity_change(0.0), right[1] + wr.velocity_change(0.0)  # vacuum fronts
        else:
            p_star = self._star_pressure(wl, wr, du, min(left[2], right[2]), max(left[2], right[2]))
            u_l = left[1] - wl.velocity_change(p_star)
            u_r = right[1] + wr.velocity_change(p_star)
            u_star = 0.5 * (u_l + u_r)  # Toro Eq. (4.9)
            u_l = u_r = u_star
        wave_l, wave_r = wl.wave(p_star, u_l), wr.wave(p_star, -u_r)
        values = dict(p_star=p_star, u_star=u_star, rho_star_left=wave_l.rho_star, rho_star_right=wave_r.rho_star,
                      left_wave=wave_l.kind, right_wave=wave_r.kind,
                      left_wave_speeds=(wave_l.head, wave_l.tail), right_wave_speeds=(-wave_r.head, -wave_r.tail),
                      vacuum=vacuum, _sides=((wl, wave_l, u_l), (wr, wave_r, -u_r)))
        for key, value in values.items():
            object.__setattr__(self, key, value)

    def _wave_curve(self, state, eos):
        if self.closed_form_ideal_gas and eos.A == 0.0 and eos.B == 0.0:
            return _IdealGasWave(*state, 1.0 + eos.omega)
        return _MieGruneisenWave(*state, eos)

    @staticmethod
    def _star_pressure(wl, wr, du, p_min, p_max):
        def g(p):  # Toro Eq. (4.5), increasing in p
            return wl.velocity_change(p) + wr.velocity_change(p) + du

        lo, hi = p_min, p_max
        for _ in range(200):  # g grows without bound with p
            if g(hi) >= 0.0:
                break
            lo, hi = hi, 4.0 * hi
        while g(lo) > 0.0:
            if lo < 1e-12 * p_min:
                raise ValueError("the star pressure is below 1e-12 of the smaller initial pressure: vacuum or "
                                 "near-vacuum with a JWL side is not supported (vacuum is solved for ideal gases)")
            lo, hi = 0.25 * lo, lo
        return _brent(g, lo, hi)

    def __call__(self, x, t):
        """Density, velocity and pressure at positions x [m] and time t > 0 [s]."""
        if not (math.isfinite(t) and t > 0.0):
            raise ValueError(f"RiemannProblem: time t must be > 0 s and finite, got {t}")
        x = np.asarray(x, dtype=float)
        xi = np.atleast_1d((x - self.x0) / t)
        (wl, wave_l, u_l), (wr, wave_r, u_r) = self._sides
        rho_l, vel_l, p_l = _sample_left(wl, wave_l, xi, self.p_star, u_l)
        rho_r, vel_r, p_r = _sample_left(wr, wave_r, -xi, self.p_star, u_r)
        split = 0.5 * (wave_l.tail - wave_r.tail) if self.vacuum else self.u_star
        on_left = xi < split
        rho = np.where(on_left, rho_l, rho_r)
        u = np.where(on_left, vel_l, -vel_r)
        p = np.where(on_left, p_l, p_r)
        u = np.where(rho > 0.0, u, xi)  # vacuum: velocity undefined, return x/t
        return rho.reshape(x.shape), u.reshape(x.shape), p.reshape(x.shape)


# --- reference problems ---------------------------------------------------------------------------

@dataclass(frozen=True)
class RiemannCase:
    """A named Riemann problem: the solution, its domain [m], end time [s] and source."""

    problem: RiemannProblem
    domain: tuple
    end_time: float
    source: str


_TORO_TESTS = {  # Toro (2009) Table 4.1: (rho, u, p) left, right, output time; gamma = 1.4, x in [0, 1], x0 = 0.5
    1: ((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), 0.25),
    2: ((1.0, -2.0, 0.4), (1.0, 2.0, 0.4), 0.15),
    3: ((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), 0.012),
    4: ((1.0, 0.0, 0.01), (1.0, 0.0, 100.0), 0.035),
    5: ((5.99924, 19.5975, 460.894), (5.99242, -6.19633, 46.0950), 0.035),
}


def toro_test(number: int) -> RiemannCase:
    """Toro (2009) ch. 4 test ``number`` (1-5), ideal gas gamma = 1.4, dimensionless units."""
    if number not in _TORO_TESTS:
        raise ValueError(f"toro_test number must be one of 1..5, got {number}")
    left, right, t_end = _TORO_TESTS[number]
    return RiemannCase(RiemannProblem(left, right, x0=0.5), (0.0, 1.0), t_end,
                       f"Toro, Riemann Solvers and Numerical Methods for Fluid Dynamics, 3rd ed. (2009), "
                       f"Table 4.1, Test {number}")


def sod_000() -> RiemannCase:
    """Seed 000 Sec. 5.1 Sod shock tube in SI (ERRATA 000-12).

    The paper's 1 g/mm^3 | 0.125 g/mm^3, 1 MPa | 0.1 MPa, 1 mm tube, t = 0.143 ms is
    the standard Sod problem (Toro Test 1) in a consistent mm-g-ms system:
    rho 1e6 | 1.25e5 kg/m^3, p 1e6 | 1e5 Pa, gamma = 1.4, tube [0, 1e-3] m,
    diaphragm at 5e-4 m, t = 1.43e-4 s (velocities in m/s equal the
    dimensionless ones; the shock has run ~0.25 mm, as the paper says).
    """
    return RiemannCase(RiemannProblem((1.0e6, 0.0, 1.0e6), (1.25e5, 0.0, 1.0e5), x0=5.0e-4), (0.0, 1.0e-3),
                       1.43e-4, "seed 000 Sec. 5.1 (Sod 1978), SI units per ERRATA 000-12")


# cm-g-us system (p in Mbar) -> SI: the Euler equations with the JWL EOS are invariant
# under this consistent change of units, so published values convert with the same factors.
CGS_US_TO_SI = {"density": 1.0e3, "pressure": 1.0e11, "velocity": 1.0e4, "length": 1.0e-2, "time": 1.0e-6}

_SHYUE_EOS = JWLParams(8.545, 0.205, 4.6, 1.35, 0.25, 1.84)  # Shyue (2001) Sec. 6 JWL; A, B in Mbar, rho0 g/cm^3


def _jwl_to_si(eos: JWLParams) -> JWLParams:
    f = CGS_US_TO_SI
    return JWLParams(eos.A * f["pressure"], eos.B * f["pressure"], eos.R1, eos.R2, eos.omega,
                     eos.rho0 * f["density"])


def _state_to_si(rho, u, p):
    f = CGS_US_TO_SI
    return rho * f["density"], u * f["velocity"], p * f["pressure"]


def shyue_jwl() -> RiemannCase:
    """JWL Riemann problem of Shyue (J. Comput. Phys. 171, 678-707, 2001), in SI.

    Both sides are the same JWL gas, A = 8.545, B = 0.205 (Mbar), R1 = 4.6,
    R2 = 1.35, w = 0.25, rho0 = 1.84 g/cm^3; left (rho, u, p) = (1.7, 0, 10),
    right (1, 0, 0.5); x in [0, 100], diaphragm at 50, t = 12 (cm, us), as
    set up in LANL ExactPack (``Test_RiemannJWL_Shyue``). Left rarefaction,
    right shock. ExactPack's printed star state for it (p* = 4.40936,
    rho*_R = 3.76686) is not used as a reference: it is inconsistent with this
    EOS (its printed e*_R = 3.72966 against e(rho*_R, p*) = 3.75981, and a
    Rankine-Hugoniot energy jump off by 1.4 %). Converted to SI with
    :data:`CGS_US_TO_SI`.
    """
    eos = _jwl_to_si(_SHYUE_EOS)
    f = CGS_US_TO_SI
    problem = RiemannProblem(_state_to_si(1.7, 0.0, 10.0), _state_to_si(1.0, 0.0, 0.5), eos, eos,
                             x0=50.0 * f["length"])
    return RiemannCase(problem, (0.0, 100.0 * f["length"]), 12.0 * f["time"],
                       "Shyue, J. Comput. Phys. 171 (2001) 678, as set up in LANL ExactPack")


_LEE_EOS = JWLParams(632.1, -0.04472, 11.3, 1.13, 0.8938, 1.905)  # Lee et al. (2013) JWL; A, B in Mbar


def lee_jwl() -> RiemannCase:
    """JWL Riemann problem of Lee, Toro, Castro & Nikiforakis (J. Comput. Phys. 246, 2013), in SI.

    Both sides: A = 632.1, B = -0.04472 (Mbar), R1 = 11.3, R2 = 1.13,
    w = 0.8938, rho0 = 1.905 g/cm^3; left (0.9525, 0, 1), right (3.81, 0, 2);
    x in [0, 100], diaphragm at 50, t = 20 (cm, us). Left shock, right
    rarefaction. Reference star state: Kamm's general-EOS solver as printed in
    LANL ExactPack (exactpack/tests/test_riemann_jwl.py): p* = 1.1911644,
    u* = -0.13299659, rho*_L = 1.0445603, rho*_R = 3.5156642, c*_L = 1.4692505,
    c*_R = 1.5222130, converged to about 1e-6 (see tests/test_exact_riemann.py).
    ExactPack's other solver (RiemannGenEOS, test_riemann.py) prints
    p* = 1.19069729, 4e-4 away; like its Shyue values it does not satisfy this
    EOS's jump conditions and is not used. Converted to SI with :data:`CGS_US_TO_SI`.
    """
    eos = _jwl_to_si(_LEE_EOS)
    f = CGS_US_TO_SI
    problem = RiemannProblem(_state_to_si(0.9525, 0.0, 1.0), _state_to_si(3.81, 0.0, 2.0), eos, eos,
                             x0=50.0 * f["length"])
    return RiemannCase(problem, (0.0, 100.0 * f["length"]), 20.0 * f["time"],
                       "Lee, Toro, Castro & Nikiforakis, J. Comput. Phys. 246 (2013); star values from LANL "
                       "ExactPack")


def tnt_air() -> RiemannCase:
    """TNT detonation products | ambient air, the products | air interface of the CFDMP runs.

    Left: seed 000 TNT JWL set at the constant-volume explosion state
    (rho0 = 1630 kg/m^3, e = E0/rho0, p = 8.38 GPa); right: seed 000 air
    (ideal gas, gamma = 1.4, 1.225 kg/m^3, 101.3 kPa); both at rest; tube
    [0, 1] m, diaphragm at 0.5 m, t = 80 us (all waves stay inside).
    Constants from :mod:`blastfsi.materials.gases`. No published star state:
    checked by its jump conditions and isentrope (tests/test_exact_riemann.py).
    """
    tnt, air = GASES["tnt"], GASES["air"]
    products = tnt.eos_params()
    p_products = float(jwl.pressure(tnt.density, tnt.specific_energy, products))
    problem = RiemannProblem((tnt.density, 0.0, p_products), (air.density, 0.0, air.pressure), products,
                             air.eos_params(), x0=0.5)
    return RiemannCase(problem, (0.0, 1.0), 8.0e-5, "seed 000 Sec. 4 TNT JWL and air constants")
