"""Scheme 1: unsplit HLLC fluxes, MUSCL reconstruction of primitive variables, SSP-RK2.

* Reconstruction: per axis, the primitive rows (rho_k, u, p, alpha) -- phase
  densities, not partial densities, so that at uniform p and u the face states
  stay on the mixture's pressure-equilibrium line -- with a TVD slope limiter
  (:func:`limited_slope`: van Leer's, the default, minmod or the monotonized
  central one; all second order in smooth monotone flow). Face values then
  lie between neighbouring cell values, so rho_k, alpha and p stay positive;
  a face whose two reconstructed states still fail (rho, p or c^2 <= 0, a
  negative partial density, or NaN -- e.g. a JWL mixture whose c^2 turns
  negative) falls back to first order there (the two cell-centre states).
* Flux: HLLC (Toro, Spruce & Speares, Shock Waves 4, 1994; Toro, Riemann Solvers, 3rd ed., 2009) with Einfeldt's
  wave-speed estimates for a general EOS (Einfeldt, SIAM J. Numer. Anal. 25, 1988; Toro 2009 Sec. 10.5.1):
      S_L = min(u_L - c_L, u~ - d~),  S_R = max(u_R + c_R, u~ + d~),
      u~ = (sqrt(rho_L) u_L + sqrt(rho_R) u_R) / (sqrt(rho_L) + sqrt(rho_R)),
      d~^2 = (sqrt(rho_L) c_L^2 + sqrt(rho_R) c_R^2) / (sqrt(rho_L) + sqrt(rho_R))
             + 1/2 sqrt(rho_L rho_R) / (sqrt(rho_L) + sqrt(rho_R))^2 (u_R - u_L)^2,
  contact speed s* and star states of Toro (2009) Sec. 10.4; the
  products fraction takes the HLLC flux of a volume-weighted passive scalar and
  the face velocity of Johnsen & Colonius (J. Comput. Phys. 219, 2006) for its alpha div u term:
      F = w_L q_L v_L + w_R q_R v_R,  v_K = u_K + s_K (chi_K - 1),  chi_K = (S_K - u_K)/(S_K - s*),
      w_L = (1 + sign s*)/2, w_R = 1 - w_L, s_L = min(S_L, 0), s_R = max(S_R, 0),
  which is also the form used for the partial densities (q = alpha_k rho_k).
* Time: SSP-RK2 (Shu & Osher, J. Comput. Phys. 77, 1988): U1 = U + dt L(U), U^{n+1} = (U + U1 + dt L(U1)) / 2.
* Face transfers (for conservative coupling): with L(U)_i = -(g+ F_{i+1/2} - g- F_{i-1/2})/dx + sources,
  U^{n+1} = U + dt/2 (L(U) + L(U1)), so the amount of a row moved across face i+1/2 from cell i to
  cell i+1 in one step is T = dt/dx (F(U) + F(U1))/2; it is accumulated like the state,
  T1 = T0 + dt/dx F(U), T^{n+1} = (T0 + T1 + dt/dx F(U1))/2 with T0 = 0. The radial momentum's
  pressure force and the products fraction's alpha div u term are cell sources: T of the
  products fraction is its conservative part (the HLLC flux of alpha).
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import jax.numpy as jnp

from blastfsi.euler import geometry
from blastfsi.euler.blocking import blocked
from blastfsi.euler.boundaries import extend_rows, shift
from blastfsi.euler.config import CARTESIAN, MINMOD, VAN_LEER, Config
from blastfsi.euler.mixture import assemble_rows, cell_state, closure_from_pressure, volume_fractions
from blastfsi.xla import fori, materialise

NG = 2
# products fraction spread over a cell and its two neighbours above which the cell lies at a material contact
# and its normal velocity and pressure are limited each on its own (cell_slopes)
CONTACT_SPREAD = 1e-3


class FaceState(NamedTuple):
    cons: tuple  # conservative rows
    rho: object
    u: object  # velocity normal to the face
    p: object
    c2: object


def limited_slope(d_lo, d_hi, tiny, limiter: int):
    """A cell's limited slope from its two one-sided differences (zero where their signs differ):

    * van Leer (1974), the harmonic mean 2 d_lo d_hi / (d_lo + d_hi);
    * minmod (Roe 1986), the one of smaller magnitude: the most diffusive;
    * monotonized central (van Leer 1977), minmod(2 d_lo, (d_lo + d_hi) / 2, 2 d_hi): the sharpest of the
      three at discontinuities, the central slope in smooth flow.
    """
    if limiter == VAN_LEER:
        return (d_lo * jnp.abs(d_hi) + jnp.abs(d_lo) * d_hi) / jnp.maximum(jnp.abs(d_lo) + jnp.abs(d_hi), tiny)
    a, b = jnp.abs(d_lo), jnp.abs(d_hi)
    size = jnp.minimum(a, b) if limiter == MINMOD else jnp.minimum(2.0 * jnp.minimum(a, b), 0.5 * jnp.abs(d_lo + d_hi))
    return jnp.where(d_lo * d_hi > 0.0, jnp.sign(d_lo) * size, 0.0)


def hllc_flux(left: FaceState, right: FaceState, lay, axis):
    """HLLC flux rows and the face velocity of the alpha div u term (module docstring).

    Side K contributes w_K [U_K v_K + (p_K + j_K rho_K) e_normal + (p_K u_K + j_K (rho_K s* +
    p_K/(S_K - u_K))) e_energy] with v_K = u_K + g_K, j_K = g_K (S_K - u_K),
    g_K = s_K (s* - u_K)/(S_K - s*): Toro's F_K + s_K (U*_K - U_K), row by row.
    """
    u_l, u_r = left.u, right.u
    sq_l, sq_r = jnp.sqrt(left.rho), jnp.sqrt(right.rho)
    inv = 1.0 / (sq_l + sq_r)
    u_roe = (sq_l * u_l + sq_r * u_r) * inv
    d_roe = jnp.sqrt((sq_l * left.c2 + sq_r * right.c2) * inv + 0.5 * sq_l * sq_r * inv * inv * (u_r - u_l) ** 2)
    s_left = jnp.minimum(u_l - jnp.sqrt(left.c2), u_roe - d_roe)
    s_right = jnp.maximum(u_r + jnp.sqrt(right.c2), u_roe + d_roe)
    m_l, m_r = left.rho * (s_left - u_l), right.rho * (s_right - u_r)
    s_star = (right.p - left.p + m_l * u_l - m_r * u_r) / (m_l - m_r)  # contact speed, Toro Sec. 10.4
    w_l = 0.5 * (1.0 + jnp.sign(s_star))
    wv, x_n, x_e = [], 0.0, 0.0
    for st, s_wave, s_k, w in ((left, s_left, jnp.minimum(s_left, 0.0), w_l),
                               (right, s_right, jnp.maximum(s_right, 0.0), 1.0 - w_l)):
        g = s_k * (s_star - st.u) / (s_wave - s_star)
        j = g * (s_wave - st.u)
        wv.append(w * (st.u + g))
        x_n = x_n + w * (st.p + j * st.rho)
        x_e = x_e + w * (st.p * st.u + j * (st.rho * s_star + st.p / (s_wave - st.u)))
    wv_l, wv_r = wv
    nrm = lay.mom + axis
    flux = tuple(wv_l * a + wv_r * b + (x_n if r == nrm else 0.0) + (x_e if r == lay.energy else 0.0)
                 for r, (a, b) in enumerate(zip(left.cons, right.cons)))
    return flux, wv_l + wv_r


def split_primitive(w, lay):
    """(phase densities, products fraction, velocity, pressure) of primitive rows."""
    nm, nd = lay.n, lay.ndim
    return tuple(w[:nm]), (w[nm + nd + 1] if nm == 2 else None), tuple(w[nm:nm + nd]), w[nm + nd]


def _face_state(w, rho_e, c2, lay, axis):
    """FaceState of primitive rows w with its rho e and c^2."""
    rho_k, alpha, vel, p = split_primitive(w, lay)
    partials = tuple(r * a for r, a in zip(rho_k, (1.0,) if lay.n == 1 else (alpha, 1.0 - alpha)))
    rho = partials[0] if lay.n == 1 else partials[0] + partials[1]
    return FaceState(assemble_rows(partials, rho, vel, rho_e, alpha, lay), rho, vel[axis], p, c2)


def _reconstructed(w, eos_r, lay):
    """(rho e, c^2, physical?) of a reconstructed primitive state."""
    rho_k, alpha, _, p = split_primitive(w, lay)
    partials, rho, rho_e, c2 = closure_from_pressure(rho_k, alpha, p, eos_r, lay.n)
    ok = (rho > 0.0) & (p > 0.0) & (c2 > 0.0)
    for q in partials:
        ok = ok & (q >= 0.0)
    return rho_e, c2, ok


def cell_slopes(z, nw, cfg: Config, lay, axis):
    """Limited slopes (:func:`limited_slope`, cfg.limiter) of the primitive rows z[:nw] of cells -1..n,
    z with NG ghost cells on that axis: the normal velocity and the pressure limited in the acoustic
    characteristic variables of the axis, every other row on its own.

    Acoustic pair (van Leer 1979; Toro 2009 Sec. 14.4.3, characteristic limiting): the jumps of
    w+- = p +- Z u_n, Z = rho c the cell's acoustic impedance, are limited and turned back,
    Delta p = (Delta w+ + Delta w-) / 2, Delta u_n = (Delta w+ - Delta w-) / (2 Z). Limiting u_n and p
    each on its own (cfg.characteristic False; numerics.limiting = "primitive") is not invariant under the
    mirror of a wall: beside it p's jump across the wall is 0 (so its limited slope is 0) while u_n's is
    -2 u_n, and the wall cell's inflow face then carries a velocity without the pressure that stops it:
    a shock reflecting off a wall overshoots the normal reflection in the wall cell by ~19 % at
    p_s = 9.6 p0 (first order: not at all). The characteristic jumps mirror into each other
    (w+ <-> w-), and the overshoot falls to ~5 % (tests/test_euler_method.py).
    At uniform p and u_n both slopes stay 0 (the mixture's pressure-equilibrium line is kept).

    At a material contact (the products fraction spreading by more than CONTACT_SPREAD over the cell and
    its two neighbours) u_n and p are limited each on its own, as the other rows: the decomposition with
    the cell's own impedance assumes one impedance over the stencil, and across the products-air contact
    of an expanding charge, where it jumps by orders of magnitude, it rang until a cell turned
    non-physical (steel-plate-blast-case4 at 10 us; with this rule it runs)."""
    n = z[0].shape[axis] - 2 * NG
    tiny = jnp.finfo(z[0].dtype).tiny

    def limited(x):
        jump = jnp.diff(x, axis=axis)  # between cells -2..n+1
        return limited_slope(shift(jump, axis, 0, n + 2), shift(jump, axis, 1, n + 2), tiny, cfg.limiter)

    if not cfg.characteristic:
        return [limited(x) for x in z[:nw]]
    normal, pressure = lay.n + axis, lay.n + lay.ndim
    rho_k, alpha, _, _ = split_primitive(z, lay)
    rho = sum(a * r for a, r in zip(volume_fractions(alpha, lay.n), rho_k))
    impedance = rho * jnp.sqrt(jnp.maximum(z[nw + 1], 0.0))  # cells -2..n+1
    slopes = [None if r in (normal, pressure) else limited(x) for r, x in enumerate(z[:nw])]
    z_cell = shift(impedance, axis, 1, n + 2)  # cells -1..n: each cell's own impedance turns its jumps
    jumps = [jnp.diff(z[r], axis=axis) for r in (pressure, normal)]
    lo, hi = ([shift(j, axis, s, n + 2) for j in jumps] for s in (0, 1))
    w_plus = limited_slope(lo[0] + z_cell * lo[1], hi[0] + z_cell * hi[1], tiny, cfg.limiter)
    w_minus = limited_slope(lo[0] - z_cell * lo[1], hi[0] - z_cell * hi[1], tiny, cfg.limiter)
    slopes[pressure] = 0.5 * (w_plus + w_minus)
    slopes[normal] = (0.5 * (w_plus - w_minus)) * (1.0 / jnp.maximum(z_cell, tiny))
    if lay.n == 2:  # across a material contact the primitive rows, each on its own
        a_lo, a_mid, a_hi = (shift(alpha, axis, s, n + 2) for s in (0, 1, 2))
        contact = (jnp.maximum(jnp.maximum(a_lo, a_mid), a_hi) - jnp.minimum(jnp.minimum(a_lo, a_mid), a_hi)
                   > CONTACT_SPREAD)
        for r in (pressure, normal):
            slopes[r] = jnp.where(contact, limited(z[r]), slopes[r])
    return slopes


def face_flux(w_left, w_right, z, nw, eos_r, lay, axis):
    """HLLC flux rows and face velocity at the faces 0..n of one axis from the primitive face states
    w_left (of cell f-1) and w_right (of cell f); a face where either state is non-physical takes the
    two cell-centre states of z (rows [primitive rows (nw), rho e, c^2] with NG ghost cells) instead."""
    n = z[0].shape[axis] - 2 * NG
    z1, z2 = (tuple(shift(x, axis, s, n + 1) for x in z) for s in (1, 2))  # cells f-1, f
    e_left, c2_left, ok_left = _reconstructed(w_left, eos_r, lay)
    e_right, c2_right, ok_right = _reconstructed(w_right, eos_r, lay)
    ok = ok_left & ok_right

    def pick(face, centre):  # first order at a face with a non-physical reconstructed state
        return jnp.where(ok, face, centre)

    left = _face_state(tuple(map(pick, w_left, z1[:nw])), pick(e_left, z1[nw]), pick(c2_left, z1[nw + 1]), lay, axis)
    right = _face_state(tuple(map(pick, w_right, z2[:nw])), pick(e_right, z2[nw]), pick(c2_right, z2[nw + 1]), lay,
                        axis)
    return hllc_flux(left, right, lay, axis)


def axis_flux(z, nw, eos_r, cfg: Config, lay, axis):
    """HLLC flux rows and face velocity at the faces 0..n of one axis (face f between cells f-1, f).

    z: rows [primitive rows (nw), rho e, c^2] with NG ghost cells on that axis (n + 2 NG cells;
    n is cfg.shape[axis] or the extent of a block along it).
    """
    n = z[0].shape[axis] - 2 * NG
    # the limited slope of each cell -1..n once (it enters the left state of its upper face
    # and the right state of its lower face)
    slopes = cell_slopes(z, nw, cfg, lay, axis)
    w_left = [shift(x, axis, 1, n + 1) + 0.5 * shift(s, axis, 0, n + 1) for x, s in zip(z[:nw], slopes)]
    w_right = [shift(x, axis, 2, n + 1) - 0.5 * shift(s, axis, 1, n + 1) for x, s in zip(z[:nw], slopes)]
    return face_flux(w_left, w_right, z, nw, eos_r, lay, axis)


def padded(cells, cfg: Config, lay, axis):
    """Cell rows with NG ghost cells on ``axis`` (boundaries.extend_rows; the normal velocity changes sign in a
    mirror)."""
    return extend_rows(cells, axis, cfg.bc[axis], NG, NG, lay.n + axis)


def flux_divergence(flux, u_face, p, alpha, cfg: Config, lay, axis):
    """Per conservative row, g+ F_{i+1/2} - g- F_{i-1/2} of cells 0..n-1 along ``axis`` from the flux rows
    and face velocity at faces 0..n (g+- = 1 off the radial axis, geometry.flux_factors on it): on the
    radial axis the radial momentum's row holds F - p (with p (g+ - g-) the pressure force p (A+ - A-)/V)
    and the products fraction's row subtracts alpha (g+ u_{i+1/2} - g- u_{i-1/2}), its alpha div u term.
    p, alpha: the cells' pressure and products fraction (alpha None with one material)."""
    n = cfg.shape[axis]
    radial = axis == 0 and cfg.geometry != CARTESIAN
    if radial:
        gp, gm = geometry.flux_factors(cfg, 0, n, p.dtype)
    out = []
    for r in range(lay.nvar):
        f_hi, f_lo = shift(flux[r], axis, 1, n), shift(flux[r], axis, 0, n)
        if radial and r == lay.mom + axis:
            f_hi, f_lo = f_hi - p, f_lo - p  # pressure force p (A+ - A-)/V on the radial momentum
        div = gp * f_hi - gm * f_lo if radial else f_hi - f_lo
        if r == lay.alpha:
            u_hi, u_lo = shift(u_face, axis, 1, n), shift(u_face, axis, 0, n)
            div = div - alpha * (gp * u_hi - gm * u_lo if radial else u_hi - u_lo)
        out.append(div)
    return out


def primitive_rows(rows, eos_r, lay):
    """Cell rows [phase densities, velocity, p, (alpha), rho e, c^2] that the reconstruction uses."""
    st = cell_state(rows, eos_r, lay)
    return st.rho_k + st.velocity + (st.p,) + ((rows[lay.alpha],) if lay.n == 2 else ()) + (st.rho_e, st.c2)


def rhs(rows, eos_r, cfg: Config, lay, record: bool = False):
    """Semi-discrete right-hand side L(U) of a tuple of conservative rows; record (static): return
    (L(U), fluxes), fluxes per axis the flux rows at its faces 0..n.

    Each axis is swept block by block on grids of more than BLOCKED_ABOVE cells (the blocks of
    blocking.blocked: its ghost cells, face states, fluxes and their divergence stay in cache; one
    read of the primitive rows and one update of L per block). Within a sweep the fluxes are
    materialised once (:func:`blastfsi.xla.materialise`), not recomputed by the two faces of every cell
    that read them.
    """
    cells = primitive_rows(rows, eos_r, lay)
    nm, dtype = lay.n, rows[0].dtype
    nw = len(cells) - 2
    alpha = (rows[lay.alpha],) if nm == 2 else ()
    total, fluxes = tuple(jnp.zeros_like(x) for x in rows), []
    for axis in range(lay.ndim):
        face_shape = tuple(m + (d == axis) for d, m in enumerate(rows[0].shape))
        outs = total + (tuple(jnp.zeros(face_shape, dtype) for _ in rows) if record else ())
        sweep = functools.partial(_sweep, nw=nw, eos_r=eos_r, cfg=cfg, lay=lay, axis=axis, record=record)
        outs = blocked(sweep, cells + alpha, outs, cfg, axis)
        total = outs[:lay.nvar]
        fluxes.append(outs[lay.nvar:])
    return (total, tuple(fluxes)) if record else total


def _sweep(ins, outs, nw, eos_r, cfg: Config, lay, axis, record):
    """One axis's flux divergence added to L (outs[:nvar]; record: the flux rows in outs[nvar:]) of a block
    spanning the axis: ins = primitive rows [, products fraction row]."""
    flux, u_face = materialise(lambda z: axis_flux(z, nw, eos_r, cfg, lay, axis), padded(ins[:nw + 2], cfg, lay, axis))
    divs = flux_divergence(flux, u_face, ins[lay.n + lay.ndim], ins[nw + 2] if lay.n == 2 else None, cfg, lay, axis)
    new = tuple(o - div / cfg.dx for o, div in zip(outs[:lay.nvar], divs))
    return new + (tuple(flux) if record else ())


def step(U, dt, eos_r, cfg: Config, lay, moved=None):
    """SSP-RK2 (Shu & Osher 1988): U1 = U + dt L(U), U^{n+1} = U/2 + (U1 + dt L(U1))/2.

    Both stages run in one loop body (:func:`blastfsi.xla.fori`: compiled once on the CPU). moved: None, or per
    axis a tuple of face-transfer rows (faces 0..n of that axis) onto which the
    step's transfers (module docstring) are added; then (U_new, moved) is
    returned. Static: the plain step carries no transfers. Recording reads the
    fluxes off the stage's own evaluation (one pass; U_new agrees with the
    plain step's to round-off, see blastfsi.euler.step.step_with_transfers).
    """
    a = jnp.asarray([0.0, 0.5], U.dtype)
    rows0 = tuple(U)

    def combine(i, start, now, rate):  # stage i, row by row: a_i start + (1 - a_i)(now + dt rate)
        return tuple(a[i] * x0 + (1.0 - a[i]) * (x + dt * k) for x0, x, k in zip(start, now, rate))

    record = moved is not None
    moved0 = tuple(moved) if record else None

    def advance_axis(i, start, now, flux):  # one axis's transfers advance like the state, L -> flux / dx
        return combine(i, start, now, tuple(f / cfg.dx for f in flux))

    def stage(i, state):  # state: the rows, or (rows, transfers) when recording
        rows, acc = state if record else (state, None)
        out = rhs(rows, eos_r, cfg, lay, record)
        total, fluxes = out if record else (out, None)
        new = combine(i, rows0, rows, total)
        return (new, tuple(map(functools.partial(advance_axis, i), moved0, acc, fluxes))) if record else new

    if not record:
        return jnp.stack(fori(2, stage, rows0))
    rows, moved = fori(2, stage, (rows0, moved0))
    return jnp.stack(rows), moved
