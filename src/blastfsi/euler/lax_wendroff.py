"""Scheme 0 (the paper's): split two-step Lax-Wendroff with adaptive artificial viscosity, 000 Sec. 2.1.

One directional operator L_a(dt) (:func:`sweep`) is

1. the adaptive viscosity of 000 Eqs. (3)-(5), written in flux (conservative) form,

       U_bar_i = U_i + g+_i D_{i+1/2} - g-_i D_{i-1/2},   D_{i+1/2} = 1/2 k_{i+1/2} (U_{i+1} - U_i),
       k_{i+1/2} = (k_i + k_{i+1}) / 2,   k_i = eta_i |theta_i|,
       theta_i = (|rho_{i+1}-rho_i| - |rho_i-rho_{i-1}|) / (|rho_{i+1}-rho_i| + |rho_i-rho_{i-1}|)   Eq. (4), 0/0 -> 0
       eta_i = nu_i (1 - nu_i),  nu_i = (|u_a| + c)_i dt / dx                                     Eq. (5), ERRATA 000-3

   (g+- = 1 in Cartesian axes, see geometry.py). The face coefficient is the
   mean of the two cells' coefficients, which makes Eq. (3) conservative
   without changing its weight in smooth flow. theta enters by its magnitude:
   at a jump theta = +1 on one side and -1 on the other, so its positive part
   (ERRATA 000-2) would smooth only one side and break the mirror symmetry of
   the scheme; |theta| smooths both and is never anti-diffusive
   (0 <= k/2 <= 1/8 keeps the explicit smoothing stable). The sound speed in
   nu is that of the state at the start of the full step (the paper leaves
   open which c; this saves one EOS evaluation per operator), u_a and rho are
   the current ones.

2. the two-step (Richtmyer) Lax-Wendroff scheme on U_bar, with U_bar's own
   ghost cells (boundary conditions applied again after the smoothing, so that
   a mirror wall sees the mirror image of the smoothed state and passes no
   mass or energy) (ERRATA 000-1: Eq. (7) as printed lacks the flux Jacobian;
   for a linear flux the two agree):

       U_{i+1/2} = (U_i + U_{i+1})/2 - dt/(2 dx) (F_{i+1} - F_i) - dt/2 (j/r_{i+1/2}) G_{i+1/2}
       U_i^new  = U_bar_i - dt/dx (g+_i F(U_{i+1/2}) - g-_i F(U_{i-1/2})) + geometric pressure force

   with G the radial flux without the pressure (quasi-1D form, radial axis
   only; zero at a mirror boundary face, see geometry.face_source_factor) and
   the pressure force dt/dx (g+ - g-) p_i at the half step,
   p_i = (p_{i+1/2} + p_{i-1/2})/2. The products fraction follows
   d alpha/dt + d(alpha u)/dx - alpha du/dx = 0 with the same stencils.

Full step, 000 Eq. (6) with ERRATA 000-4: U^{n+1} = L_z L_y L_x L_x L_y L_z U^n,
each operator with dt/2 (applied right to left; in 1D two x operators of dt/2).

Face transfers (for conservative coupling): both stages of an operator are
face differences, so the amount of a row moved across face i+1/2 from cell i
to cell i+1 by one operator is

    T_{i+1/2} = dt/dx F(U_{i+1/2}) - D_{i+1/2}

(the cell below changes by -g+ T, the cell above by +g- T). The radial
momentum's pressure force is a cell source, not a transfer; for the products
fraction T is its conservative part (alpha u flux and viscous term), the
alpha du/dx term is a cell source too.
"""
from __future__ import annotations

import jax.numpy as jnp

from blastfsi.euler import geometry
from blastfsi.euler.boundaries import extend_coefficient, extend_rows, shift
from blastfsi.euler.config import CARTESIAN, Config
from blastfsi.euler.mixture import cell_state, pressure_velocity
from blastfsi.euler.splitting import split_step

NG = 2  # ghost cells: theta (Eq. 4) of the cell next to a boundary face needs rho two cells out


def _fluxes(rows, p, un, lay, nrm):
    """Physical flux rows F_a(U); the products-fraction row carries alpha u_a (its conservative part)."""
    return tuple(x * un + (p if r == nrm else 0.0) + (p * un if r == lay.energy else 0.0) for r, x in enumerate(rows))


def sweep(rows, c, dt, eos_r, cfg: Config, lay, axis: int, record: bool = False):
    """One directional operator L_axis(dt) on a tuple of conservative rows (module docstring);
    c: sound speed of the state at the start of the full step. record (static): also return
    the face transfers T (rows at faces 0..n of the axis, module docstring).

    Ghost cells are attached only where a stencil reaches past the grid, one cell deep: the
    density (for theta), the rows (for D at the boundary faces), the viscosity coefficient
    (boundaries.extend_coefficient, which equals k of the ghost cell without its density jumps)
    and U_bar; the values are those of the two-cell padding of the paper's formulation.
    """
    n, lam, nrm, kinds = cfg.shape[axis], dt / cfg.dx, lay.mom + axis, cfg.bc[axis]
    dtype = rows[0].dtype
    radial = axis == 0 and cfg.geometry != CARTESIAN

    def ext(rows):  # the rows with a ghost cell each side (the normal momentum changes sign in a mirror)
        return extend_rows(rows, axis, kinds, 1, 1, nrm)

    # 000 Eqs. (3)-(5): adaptive viscosity; cells 0..n-1, faces 0..n (face f between cells f-1 and f).
    rows_ext = ext(rows)
    rho = rows[0] if lay.n == 1 else rows[0] + rows[1]
    jump = jnp.abs(jnp.diff(rows_ext[0] if lay.n == 1 else rows_ext[0] + rows_ext[1], axis=axis))  # faces 0..n
    d_lo, d_hi = shift(jump, axis, 0, n), shift(jump, axis, 1, n)
    theta = jnp.abs(d_hi - d_lo) / jnp.maximum(d_hi + d_lo, jnp.finfo(dtype).tiny)
    nu = (jnp.abs(rows[nrm] / rho) + c) * lam
    k_cell = extend_coefficient(nu * (1.0 - nu) * theta, axis, kinds)  # cells -1..n
    k_face = 0.25 * (shift(k_cell, axis, 0, n + 1) + shift(k_cell, axis, 1, n + 1))  # 1/2 of the mean, faces 0..n
    if radial:
        gp, gm = geometry.flux_factors(cfg, 0, n, dtype)
    ubar, visc = [], []
    for x, x_ext in zip(rows, rows_ext):
        d = k_face * jnp.diff(x_ext, axis=axis)
        visc.append(d)
        d_hi, d_lo = shift(d, axis, 1, n), shift(d, axis, 0, n)
        ubar.append(x + (gp * d_hi - gm * d_lo if radial else d_hi - d_lo))
    # the operator acts on U_bar with its own boundary values (one ghost cell each side: cells -1..n)
    ubar = ext(tuple(ubar))

    # Richtmyer predictor at faces -1/2 .. n-1/2.
    p, un = pressure_velocity(ubar, eos_r, lay, axis)
    f = _fluxes(ubar, p, un, lay, nrm)
    if radial:
        src = 0.25 * lam * geometry.face_source_factor(cfg, 0, n + 1, dtype)
    half = []
    for r, (x, fx) in enumerate(zip(ubar, f)):
        avg = 0.5 * (shift(x, axis, 0, n + 1) + shift(x, axis, 1, n + 1))
        h = avg - 0.5 * lam * (shift(fx, axis, 1, n + 1) - shift(fx, axis, 0, n + 1))
        if r == lay.alpha:
            h = h + 0.5 * lam * avg * (shift(un, axis, 1, n + 1) - shift(un, axis, 0, n + 1))
        elif radial:
            g = fx - p if r == nrm else fx  # radial flux without the pressure
            h = h - src * (shift(g, axis, 0, n + 1) + shift(g, axis, 1, n + 1))
        half.append(h)
    half = tuple(half)

    # Corrector on cells 0..n-1.
    ph, uh = pressure_velocity(half, eos_r, lay, axis)
    fh = _fluxes(half, ph, uh, lay, nrm)
    if radial:
        p_mid = 0.5 * (shift(ph, axis, 0, n) + shift(ph, axis, 1, n))  # pressure force at the half step
    out = []
    for r, (x, fx) in enumerate(zip(ubar, fh)):
        f_hi, f_lo = shift(fx, axis, 1, n), shift(fx, axis, 0, n)
        if radial and r == nrm:
            f_hi, f_lo = f_hi - p_mid, f_lo - p_mid
        new = shift(x, axis, 1, n) - lam * (gp * f_hi - gm * f_lo if radial else f_hi - f_lo)
        if r == lay.alpha:
            u_hi, u_lo = shift(uh, axis, 1, n), shift(uh, axis, 0, n)
            a_mid = 0.5 * (shift(half[r], axis, 0, n) + shift(half[r], axis, 1, n))
            new = new + lam * a_mid * (gp * u_hi - gm * u_lo if radial else u_hi - u_lo)
        out.append(new)
    if record:
        return tuple(out), tuple(lam * fx - d for fx, d in zip(fh, visc))
    return tuple(out)


def step(U, dt, eos_r, cfg: Config, lay, moved=None):
    """000 Eq. (6): L_z L_y L_x L_x L_y L_z, each operator with dt/2 (ERRATA 000-4).

    The operators and the transfers (moved) as in :func:`blastfsi.euler.splitting.split_step`.
    Recording reads the transfers off the operator's own intermediates (one
    pass; U_new agrees with the plain step's to round-off, not bit for bit:
    see blastfsi.euler.step.step_with_transfers).
    """
    c = jnp.sqrt(jnp.maximum(cell_state(tuple(U), eos_r, lay).c2, 0.0))  # the start's c (module docstring)
    return split_step(U, lambda cc, rows, a, record: sweep(rows, cc[0], 0.5 * dt, eos_r, cfg, lay, a, record=record),
                      (c,), cfg, moved)
