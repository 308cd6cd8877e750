"""Fully clamped circular plate under an impulsive load: the rigid-plastic
(Jones) solution, the Nurick–Martin empirical fit and the membrane mode solution, as validated callables.

Problem. A circular plate of free radius R, thickness H, density rho and flow
(yield) stress sigma0, fully clamped at r = R (no rotation, no pull-in), is given
at t = 0 a transverse velocity V0, uniform over r < R: a uniform impulse per unit
area i = rho H V0, total impulse I = pi R^2 rho H V0. Quantity: the centre's
maximum permanent transverse displacement W_f (the deflection delta of blast
tests; delta/t = W_f / H).

Dimensionless groups (both forms are used in the literature):

    lambda = rho V0^2 R^2 / (sigma0 H^2)                    (Jones's lambda_J = m V0^2 R^2 / (M0 H) = 4 lambda,
                                                             m = rho H, M0 = sigma0 H^2 / 4)
    phi_c  = I / (pi R H^2 sqrt(rho sigma0))                (Nurick & Martin's damage number, uniform load)

and for a uniform impulse phi_c = lambda^(1/2) exactly (I = pi R^2 rho H V0).

1. Jones's approximate rigid-plastic solution (:meth:`ClampedCircularPlate.jones`):

       W_f / H = (1 + 2 lambda / 3)^(1/2) - 1      [= (1 + lambda_J / 6)^(1/2) - 1]
               -> (2/3)^(1/2) lambda^(1/2) = 0.8165 phi_c   for lambda >> 1 (membrane limit)

   Source: N. Jones, *Structural Impact*, Cambridge University Press (1989; 2nd ed.
   2012), Ch. 7 "Influence of finite displacements", the approximate theoretical
   procedure applied to the dynamic response of a fully clamped circular plate under
   a uniformly distributed impulsive velocity; restated with the damage number
   (delta/t -> 0.817 phi_c) by G. N. Nurick and J. B. Martin, "Deformation of thin
   plates subjected to impulsive loading - a review. Part I: theoretical
   considerations", Int. J. Impact Eng. 8 (1989) 159-170. (The book's equation
   numbers were not available to us; the formula is re-derived here from first
   principles and the derivation is checked term by term in
   tests/test_rigid_plastic_plate.py.)

   Derivation. Rigid, perfectly plastic material; square ("uncoupled") yield
   condition |M| <= M0, |N| <= N0 = sigma0 H, M0 = sigma0 H^2 / 4; conical
   displacement field w = W(t) (1 - r/R) (the static collapse mode):
   * energy dissipation rate (Jones's generalised-stress form (M0 + N0 w) theta-dot on
     the hinges): the circumferential curvature rate W-dot / (R r) over 0 < r < R
     dissipates 2 pi W-dot (M0 + N0 W / 2), the clamped boundary hinge (rotation rate
     W-dot / R, w = 0) 2 pi M0 W-dot; in all
         D-dot = 4 pi M0 W-dot (1 + W / H),     D(W) = 4 pi M0 (W + W^2 / (2 H));
     its membrane part pi N0 W^2 / 2 equals N0 times the area integral of the radial
     stretch (1/2) w'^2, i.e. it does not depend on how the stretch is shared;
   * kinetic energy of the mode: (1/2) m W-dot^2 * integral (1 - r/R)^2 dA = m W-dot^2 pi R^2 / 12;
   * initial modal velocity (Martin & Symonds' mode approximation: the projection of
     the initial velocity field on the mode, which minimises the initial kinetic-energy
     difference): W-dot_0 = V0 * integral phi dA / integral phi^2 dA = V0 (pi R^2/3)/(pi R^2/6)
     = 2 V0; the mode then carries 2/3 of the initial kinetic energy
     (1/2) m V0^2 pi R^2, the rest being taken as dissipated in the transient phase;
   * energy balance of the mode, (1/3) m V0^2 pi R^2 = D(W_f), gives
         (W_f/H)^2 + 2 (W_f/H) = 2 lambda / 3,   W_f / H = (1 + 2 lambda / 3)^(1/2) - 1.
   The same balance with the whole initial kinetic energy (an upper estimate within the
   same idealisation) gives (1 + lambda)^(1/2) - 1 (:meth:`ClampedCircularPlate.energy_bound`).

   Validity (Jones): rigid-plastic, so the input kinetic energy must be large against the
   elastic strain energy the plate can store (energy ratio >> 1;
   :meth:`ClampedCircularPlate.energy_ratio` gives (1/2) m V0^2 pi R^2 over
   pi R^2 H sigma0^2 / (2 E)); impulsive (load duration short against the response
   time, here ~0.4 ms); no strain hardening or rate effect beyond what sigma0 stands
   for (use a dynamic flow stress for sigma0 when comparing with a hardening,
   rate-sensitive material); no transverse shear failure or tearing. Being a one-mode
   approximation it is itself uncertain by some tens of per cent: the energy-bound
   variant, same mode and yield condition, lies 25-35 % above it at 1 < delta/t < 6.

2. Nurick & Martin's empirical fit (:meth:`ClampedCircularPlate.nurick_martin`):

       delta / t = 0.425 phi_c + 0.277

   fitted to experiments on fully clamped circular mild-steel plates under uniform
   impulsive (sheet-explosive) loads: G. N. Nurick and J. B. Martin, "Deformation of
   thin plates subjected to impulsive loading - a review. Part II: experimental
   studies", Int. J. Impact Eng. 8 (1989) 171-186. phi_c uses the static yield stress of
   the (strongly rate-sensitive) mild steel, so the fit's slope, about half of Jones's
   0.817, carries that steel's rate effect; applied to another steel it is indicative only.

3. The membrane mode solution for any axisymmetric impulse (:meth:`ClampedCircularPlate.membrane_mode`):
   a rigid, perfectly plastic membrane without bending resistance, flowing in equal biaxial tension
   N_r = N_theta = N0 = sigma0 H (von Mises and Tresca alike), with small slopes, moves by

       rho H d2w/dt2 = N0 (1/r) d/dr (r dw/dr),   w(R, t) = 0,   w(r, 0) = 0,   dw/dt(r, 0) = i(r) / (rho H),

   the linear wave equation with the membrane wave speed c = (sigma0 / rho)^(1/2), as long as every point
   still stretches; a point stops (its plastic flow ends) where its velocity first vanishes, so its
   permanent deflection is its first maximum. Source: P. S. Symonds and T. Wierzbicki, "Membrane mode
   solutions for impulsively loaded circular plates", J. Appl. Mech. 46 (1979) 58-64; re-derived for an
   arbitrary impulse distribution by S. A. E. Alotaibi, S. E. Rigby, M. Guadagnini and A. Tyas, "Rigid-plastic
   membrane response of thin plates under impulsive blast loads using the extended Hamilton principle",
   Int. J. Impact Eng. 178 (2023) 104624. The centre's motion is the Fourier-Bessel series

       w(0, t) = sum_n (beta_n / omega_n) sin(omega_n t),   omega_n = j_n c / R,
       beta_n = 2 / (R^2 J1(j_n)^2) int_0^R (i(r) / (rho H)) J0(j_n r / R) r dr,

   j_n the zeros of J0. For a uniform impulse the centre keeps V0 until the unloading wave from the clamp
   arrives, at t = R / c, and then stops: W_f / H = V0 R / (c H) = lambda^(1/2), 1.22 x Jones's membrane
   limit (whose one-mode approximation loses a third of the kinetic energy). Validity: deflections
   large against the thickness (bending resistance M0 neglected: for a rigid-plastic plate the solution
   overestimates the deflection, by less as delta/t grows), and the rigid-plastic conditions of item 1.

SI units throughout; every function accepts NumPy scalars or arrays for the load.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NURICK_MARTIN_SLOPE = 0.425
NURICK_MARTIN_INTERCEPT = 0.277


def _positive(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {value!r}") from None
    if not (np.isfinite(v) and v > 0.0):
        raise ValueError(f"{name}: expected a finite value > 0, got {value!r}")
    return v


def _load(name: str, value) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a < 0.0):
        raise ValueError(f"{name}: expected finite values >= 0, got {value!r}")
    return a


@dataclass(frozen=True)
class ClampedCircularPlate:
    """A fully clamped circular plate: free radius ``radius`` = R [m], ``thickness`` H [m],
    ``density`` rho [kg/m^3], ``flow_stress`` sigma0 [Pa] (the rigid-plastic yield stress),
    ``youngs_modulus`` E [Pa] (only for :meth:`energy_ratio`).

    Loads are a uniform initial velocity V0 [m/s] over r < R, or the total impulse
    I = pi R^2 rho H V0 [N s] (:meth:`velocity`). Results are delta/t = W_f / H.
    """

    radius: float
    thickness: float
    density: float
    flow_stress: float
    youngs_modulus: float = 207e9

    def __post_init__(self):
        for name in ("radius", "thickness", "density", "flow_stress", "youngs_modulus"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        if self.thickness >= self.radius:
            raise ValueError(f"thickness {self.thickness} m >= radius {self.radius} m: not a plate")

    # --- loads --------------------------------------------------------------------------------
    @property
    def mass(self) -> float:
        """Mass of the free span, rho H pi R^2 [kg]."""
        return self.density * self.thickness * np.pi * self.radius ** 2

    def velocity(self, impulse):
        """Uniform initial velocity V0 [m/s] of a total impulse I [N s] spread uniformly over r < R."""
        return _load("impulse", impulse) / self.mass

    def impulse(self, velocity):
        """Total impulse I = rho H pi R^2 V0 [N s] of a uniform initial velocity V0 [m/s]."""
        return _load("velocity", velocity) * self.mass

    def lam(self, velocity):
        """lambda = rho V0^2 R^2 / (sigma0 H^2) (Jones's lambda_J = 4 lambda)."""
        v = _load("velocity", velocity)
        return self.density * v ** 2 * self.radius ** 2 / (self.flow_stress * self.thickness ** 2)

    def damage_number(self, impulse):
        """Nurick & Martin's phi_c = I / (pi R H^2 sqrt(rho sigma0)) of a uniform impulse I [N s]."""
        i = _load("impulse", impulse)
        return i / (np.pi * self.radius * self.thickness ** 2 * np.sqrt(self.density * self.flow_stress))

    def energy_ratio(self, velocity):
        """Initial kinetic energy over the elastic energy the free span stores at yield,
        (1/2) m V0^2 pi R^2 / (pi R^2 H sigma0^2 / (2 E)): rigid-plastic theory needs it >> 1."""
        v = _load("velocity", velocity)
        kinetic = 0.5 * self.mass * v ** 2
        elastic = np.pi * self.radius ** 2 * self.thickness * self.flow_stress ** 2 / (2.0 * self.youngs_modulus)
        return kinetic / elastic

    # --- deflections ----------------------------------------------------------------------------
    def jones(self, velocity):
        """Jones's rigid-plastic delta/t = (1 + 2 lambda/3)^(1/2) - 1 (module docstring, item 1)."""
        return np.sqrt(1.0 + 2.0 * self.lam(velocity) / 3.0) - 1.0

    def energy_bound(self, velocity):
        """delta/t = (1 + lambda)^(1/2) - 1: the same mode and yield condition taking the whole
        initial kinetic energy (no loss in the transient phase)."""
        return np.sqrt(1.0 + self.lam(velocity)) - 1.0

    def membrane_limit(self, velocity):
        """Large-deflection limit of :meth:`jones`: (2 lambda / 3)^(1/2) = 0.8165 phi_c."""
        return np.sqrt(2.0 * self.lam(velocity) / 3.0)

    def membrane_mode(self, specific_impulse, modes: int = 400):
        """(delta/t, t) of the centre's permanent deflection and the time it is reached, for the membrane
        mode solution (module docstring, item 3) under the specific impulse ``specific_impulse(r)`` [Pa s]
        (a vectorised callable of the radius r [m], 0 <= r <= R), from ``modes`` terms of the series."""
        from scipy.special import j0, j1, jn_zeros

        if not isinstance(modes, int) or modes < 10:
            raise ValueError(f"modes: expected an integer >= 10, got {modes!r}")
        R, rho, H = self.radius, self.density, self.thickness
        c = np.sqrt(self.flow_stress / rho)
        n = 16 * modes  # midpoint rule, ~16 points per period of the fastest J0(j_n r / R)
        r = (np.arange(n) + 0.5) * (R / n)
        weight = np.full(n, R / n)
        v0 = _load("specific_impulse", specific_impulse(r)) / (rho * H)
        zeros = jn_zeros(0, modes)
        beta = 2.0 / (R ** 2 * j1(zeros) ** 2) * ((j0(np.outer(zeros, r) / R) * (v0 * r)) @ weight)
        omega = zeros * c / R
        t = np.linspace(0.0, 4.0 * R / c, 8001)[1:]
        w = (beta / omega) @ np.sin(np.outer(omega, t))
        # the first maximum: the largest value before w falls below 0.9 of its running maximum (the truncated
        # series rings where the velocity jumps, e.g. under a uniform impulse when the clamp's wave arrives)
        running = np.maximum.accumulate(w)
        fallen = np.nonzero(w < 0.9 * running)[0]
        k = int(np.argmax(w[:fallen[0]] if fallen.size else w))
        return float(w[k] / H), float(t[k])

    def nurick_martin(self, impulse):
        """Nurick & Martin's empirical delta/t = 0.425 phi_c + 0.277 of a uniform impulse I [N s]."""
        return NURICK_MARTIN_SLOPE * self.damage_number(impulse) + NURICK_MARTIN_INTERCEPT

    # --- inverses -------------------------------------------------------------------------------
    def jones_velocity(self, deflection_ratio):
        """V0 [m/s] at which :meth:`jones` gives delta/t: lambda = 3/2 ((1 + delta/t)^2 - 1)."""
        d = _load("deflection_ratio", deflection_ratio)
        lam = 1.5 * ((1.0 + d) ** 2 - 1.0)
        return np.sqrt(lam * self.flow_stress * self.thickness ** 2 / (self.density * self.radius ** 2))

    def nurick_martin_impulse(self, deflection_ratio):
        """I [N s] at which :meth:`nurick_martin` gives delta/t (>= 0.277, the fit's intercept)."""
        d = _load("deflection_ratio", deflection_ratio)
        if np.any(d < NURICK_MARTIN_INTERCEPT):
            raise ValueError(f"deflection_ratio: the Nurick-Martin fit starts at {NURICK_MARTIN_INTERCEPT}, "
                             f"got {deflection_ratio!r}")
        phi = (d - NURICK_MARTIN_INTERCEPT) / NURICK_MARTIN_SLOPE
        return phi * np.pi * self.radius * self.thickness ** 2 * np.sqrt(self.density * self.flow_stress)


def jones_deflection(velocity, radius, thickness, density, flow_stress):
    """delta/t of :meth:`ClampedCircularPlate.jones` in one call."""
    return ClampedCircularPlate(radius, thickness, density, flow_stress).jones(velocity)
