"""Mixture equation of state of the five-equation model (ERRATA 000-9).

Products (JWL) and air (ideal gas) share a cell through the reduced
(Kapila) five-equation model of Allaire, Clerc & Kokh (J. Comput. Phys. 181,
577-616, 2002; "ACK"): partial densities
alpha_k rho_k, mixture momentum and total energy, and the products volume
fraction alpha_0, with pressure equilibrium (isobaric closure). Every phase has
Mie-Grueneisen form p_k = f_k(rho_k) + G_k rho_k e_k (blastfsi.eos.jwl, G = omega),
so rho e = sum_k alpha_k rho_k e_k = p xi - sum_k alpha_k f_k / G_k gives the
explicit mixture pressure

    p = (rho e + sum_k alpha_k f_k(rho_k) / G_k) / xi,        xi = sum_k alpha_k / G_k       (ACK 2002)

and the (frozen) mixture sound speed of the five-equation model (ACK 2002)

    xi rho c^2 = sum_k (alpha_k / G_k) rho_k c_k^2,
    rho_k c_k^2 = rho_k f_k'(rho_k) + (1 + G_k) p - f_k(rho_k)          (blastfsi.eos.jwl.sound_speed_squared)

Both are affine in the alpha_k at fixed rho_k and p, which is why a scheme that
updates alpha with the same linear weights as the partial densities keeps p
and u exactly uniform across a products/air interface.

Phase densities rho_k = (alpha_k rho_k) / alpha_k: the division is guarded only
where |alpha_k| < ALPHA_EPS (alpha_k replaced by ALPHA_EPS there) and rho_k is
floored at RHO_FLOOR_REL * rho0_k before entering f_k. The volume fractions
themselves enter xi and the sums unclamped: a clamp to [eps, 1 - eps] would
break the affine property above wherever a scheme's small over/undershoot
leaves alpha_k outside [0, 1] (Lax-Wendroff does), and a clamped cell at an
interface would show a pressure blip of order (overshoot) x f_k/(G_k p).

With one material the formulas reduce to p = f + G rho e and the pure-phase c^2.
"""
from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from blastfsi.eos.jwl import JWLParams, reference_pressure, reference_pressure_derivative
from blastfsi.xla import materialise

ALPHA_EPS = 1e-8  # |alpha_k| below this is replaced in the division rho_k = (alpha_k rho_k)/alpha_k
RHO_FLOOR_REL = 1e-12  # rho_k >= 1e-12 rho0_k inside f_k: keeps rho0/rho_k finite (f_k ~ 0 there)


class Phases(NamedTuple):
    """Volume-fraction-weighted phase sums that fix p(rho e) and c^2 at given rho_k, alpha_k."""

    xi: object  # sum alpha_k / G_k
    s_f: object  # sum alpha_k f_k / G_k
    s_c: object  # sum (alpha_k rho_k f_k' - alpha_k f_k) / G_k
    s_t: object  # sum alpha_k (1 + G_k) / G_k


def eos_rows(eos, n: int) -> list[JWLParams]:
    """The JWL rows of the (n, 6) parameter array as scalars."""
    return [JWLParams(*(eos[k, i] for i in range(6))) for k in range(n)]


def volume_fractions(alpha, n: int):
    """alpha_k for k = 0..n-1 from the products fraction (one material: alpha = 1)."""
    return (1.0,) if n == 1 else (alpha, 1.0 - alpha)


def phase_densities(partials, alphas):
    """rho_k = (alpha_k rho_k) / alpha_k, division guarded where |alpha_k| < ALPHA_EPS."""
    out = []
    for q, a in zip(partials, alphas):
        if isinstance(a, float):
            out.append(q / a)
        else:
            out.append(q / jnp.where(jnp.abs(a) < ALPHA_EPS, ALPHA_EPS, a))
    return out


def _has_cold_terms(row: JWLParams):
    """False for an ideal-gas phase (A = B = 0): its JWL terms are zeros."""
    return (row.A != 0.0) | (row.B != 0.0)


def cold_terms(rho_k, row: JWLParams):
    """(f_k, f_k') of one phase, rho_k floored at RHO_FLOOR_REL rho0_k; zeros for an ideal gas (A = B = 0).

    On the CPU a conditional skips the exponentials of an ideal-gas phase; it also
    stores f and f' once for all their consumers (:func:`blastfsi.xla.materialise`).
    """
    rr = jnp.maximum(rho_k, RHO_FLOOR_REL * row.rho0)
    return materialise(lambda r: (reference_pressure(r, row), reference_pressure_derivative(r, row)), rr,
                       _has_cold_terms(row))


def phase_sums(rho_k, partials, alphas, rows) -> Phases:
    """The sums of :class:`Phases` from phase densities, partial densities and volume fractions."""
    xi = s_f = s_c = s_t = 0.0
    for r, q, a, row in zip(rho_k, partials, alphas, rows):
        inv_g = 1.0 / row.omega
        f, df = cold_terms(r, row)
        xi = xi + a * inv_g
        s_f = s_f + a * f * inv_g
        s_c = s_c + (q * df - a * f) * inv_g
        s_t = s_t + a * (1.0 + row.omega) * inv_g
    return Phases(xi, s_f, s_c, s_t)


def pressure(rho_e, ph: Phases):
    """Isobaric-closure mixture pressure p = (rho e + sum alpha_k f_k/G_k) / xi (ACK 2002)."""
    return (rho_e + ph.s_f) / ph.xi


def internal_energy_density(p, ph: Phases):
    """rho e = p xi - sum alpha_k f_k / G_k (inverse of :func:`pressure`)."""
    return p * ph.xi - ph.s_f


def sound_speed_squared(rho, p, ph: Phases):
    """Mixture c^2 = sum_k (alpha_k/G_k) rho_k c_k^2 / (xi rho) (ACK 2002 five-equation model)."""
    return (ph.s_c + p * ph.s_t) / (ph.xi * rho)


class CellState(NamedTuple):
    """Primitive and derived quantities of a conservative state."""

    rho: object
    velocity: tuple
    p: object
    c2: object
    rho_e: object  # internal energy per unit volume
    rho_k: tuple


def _kinematics(rows, lay):
    """(partials, rho, velocity, rho e, volume fractions, phase densities) of conservative rows."""
    n, ndim = lay.n, lay.ndim
    partials = tuple(rows[k] for k in range(n))
    rho = partials[0] if n == 1 else partials[0] + partials[1]
    inv_rho = 1.0 / rho
    vel = tuple(rows[lay.mom + d] * inv_rho for d in range(ndim))
    kinetic = 0.5 * sum(rows[lay.mom + d] * vel[d] for d in range(ndim))
    rho_e = rows[lay.energy] - kinetic
    alphas = volume_fractions(rows[lay.alpha] if n == 2 else None, n)
    return partials, rho, vel, rho_e, alphas, phase_densities(partials, alphas)


def cell_state(rows, eos_r, lay) -> CellState:
    """Primitive quantities of conservative rows (stacked, in the layout of config.Layout)."""
    partials, rho, vel, rho_e, alphas, rho_k = _kinematics(rows, lay)
    ph = phase_sums(rho_k, partials, alphas, eos_r)
    p = pressure(rho_e, ph)
    return CellState(rho, vel, p, sound_speed_squared(rho, p, ph), rho_e, tuple(rho_k))


def cold_pressure(rho_k, row: JWLParams):
    """f_k of one phase as in :func:`cold_terms` (without f_k'); zeros for an ideal gas."""
    rr = jnp.maximum(rho_k, RHO_FLOOR_REL * row.rho0)
    return materialise(lambda r: reference_pressure(r, row), rr, _has_cold_terms(row))


def pressure_velocity(rows, eos_r, lay, axis):
    """(p, u_axis) of conservative rows: the part of :func:`cell_state` a flux needs (no c^2)."""
    _, _, vel, rho_e, alphas, rho_k = _kinematics(rows, lay)
    xi = s_f = 0.0
    for r, a, row in zip(rho_k, alphas, eos_r):
        inv_g = 1.0 / row.omega
        xi = xi + a * inv_g
        s_f = s_f + a * cold_pressure(r, row) * inv_g
    return (rho_e + s_f) / xi, vel[axis]


def closure_from_pressure(rho_k, alpha, p, eos_r, n):
    """(partial densities, rho, rho e, c^2) of phase densities, products fraction and pressure."""
    alphas = volume_fractions(alpha, n)
    partials = tuple(a * r for a, r in zip(alphas, rho_k))
    rho = partials[0] if n == 1 else partials[0] + partials[1]
    ph = phase_sums(rho_k, partials, alphas, eos_r)
    return partials, rho, internal_energy_density(p, ph), sound_speed_squared(rho, p, ph)


def assemble_rows(partials, rho, vel, rho_e, alpha, lay):
    """Conservative rows (partials, rho u, E, alpha) from their parts."""
    mom = tuple(rho * v for v in vel)
    energy = rho_e + 0.5 * sum(m * v for m, v in zip(mom, vel))
    return partials + mom + (energy,) + ((alpha,) if lay.n == 2 else ())


def conservative_rows(rho_k, alpha, vel, p, eos_r, lay):
    """Conservative rows (and rho, c^2) from phase densities, products fraction, velocity and pressure."""
    partials, rho, rho_e, c2 = closure_from_pressure(rho_k, alpha, p, eos_r, lay.n)
    return assemble_rows(partials, rho, vel, rho_e, alpha, lay), rho, c2
