"""Reference MUSL step: a plain NumPy oracle for :func:`blastfsi.mpm.musl.step` (tests/test_mpm_reference.py).

Written for reading, in the manner of Taichi's mpm88: explicit loops over the particles and the nodes
of their stencils, one function per stage of the explicit updated-Lagrangian step of 000 Sec. 2.2,
Eqs. (17)-(30), as the module docstring of :mod:`blastfsi.mpm.musl` states it. It is derived from
that statement (and the shape functions' definitions in :mod:`blastfsi.mpm.shape`), not from the
vectorised code; it is slow (Python loops) and meant for a few dozen particles.

One step of length dt:

1. P2G (:func:`particle_to_grid`): nodal mass (Eq. 21), momentum (Eq. 18), internal force (Eq. 19;
   r-z: plus the hoop term -V_p sigma_thth N_I / r_p in the r-momentum), body force m_I g (Eq. 20).
2. Nodal update (:func:`nodal_update`, Eqs. 22-23) and face conditions on the new nodal velocity
   (:func:`face_conditions`: "fixed" zeroes every component on the face's nodes, "slip" the normal one).
3. G2P (:func:`grid_to_particle`): FLIP velocity v_p += sum_I N_Ip (v_I^new - v_I^old) (Eq. 24) and
   position x_p += dt sum_I N_Ip v_I^new with the UPDATED nodal velocity (Eq. 25, ERRATA 000-5).
4. Re-map (:func:`remap`, Eq. 26): nodal velocity from the updated particle momentum over the same
   nodal masses, face conditions again.
5. Strain and spin increments from the re-mapped nodal velocity (:func:`strain_increments`,
   Eqs. 27-28; r-z: d eps_thth = dt sum_I N_Ip v_rI / r_p), density rho / (1 + d eps_kk)
   (:func:`density_update`, Eq. 29), stress (:func:`stress_update`, Eq. 30).

All stages use the stencil (N_Ip, grad N_Ip) of the particle positions at the start of the step, and
r_p is the radius at the start of the step (standard MUSL).

Shape functions (:func:`weights_1d`): the linear hat N = 1 - |x_p - x_I| / h on the two nodes of the
particle's cell (000 Eq. 16), tensor products in 2D/3D; and uGIMP, written here as what it is, the
hat averaged over the particle domain [x_p - l, x_p + l] (Bardenhagen & Kober 2004),
N = (H(r + l) - H(r - l)) / 2l, dN/dx = (hat(r + l) - hat(r - l)) / 2l h, H the hat's antiderivative
(a different formula from musl's piecewise Eq. 13 of Steffen et al.), with the domain truncated to
the grid box where it reaches past it (:func:`blastfsi.mpm.shape.inside_grid`).

Stress update: the oracle calls the same constitutive model function as musl does
(``Model.update``, e.g. :data:`blastfsi.constitutive.elastic.MODEL`: Hooke's law with the
Hughes-Winget Jaumann rotation and the trapezoidal energy of Eq. 13) on the oracle's own strain
and spin increments and density, so the comparison checks the MPM transfers and grid algorithm,
not the material model.

Covered: linear and uGIMP shape functions; 2D plane strain, 3D Cartesian and 2D axisymmetric r-z
(ring masses and volumes V_p = m_p / rho_p, hoop force and hoop strain); face conditions "fixed",
"slip" and "free"; body force (gravity); one material.

Not covered (the caller must switch them off in musl): artificial bulk viscosity (q_quadratic =
q_linear = 0, so q stays 0 and does no work), the FLIP/PIC blend (Config.blend False), gas
particles (fluid models: cell-centre gradient, void gas, pressure relaxation), reference pressure
(0), surface loads, prescribed-velocity particles, nodal sources (coupling), several materials,
inactive pool slots (the oracle takes the active particles only), and the bookkeeping outputs of
musl (external work, reactions, boundary exchange, q, vol_rate, wave speed, plastic work).
"""
from __future__ import annotations

import itertools
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from blastfsi.constitutive import PointState

VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))  # [xx, yy, zz, yz, xz, xy]


class Body(NamedTuple):
    """The oracle's particles (host arrays, active particles only)."""

    x: np.ndarray  # (n, 3) position, zero beyond the grid's dim
    v: np.ndarray  # (n, 3) velocity
    mass: np.ndarray  # (n,) (r-z: the ring's mass)
    half_size: np.ndarray  # (n, 3) GIMP half-size l
    stress: np.ndarray  # (n, 6) Voigt
    density: np.ndarray  # (n,)
    energy: np.ndarray  # (n,) specific internal energy


# --- shape functions ------------------------------------------------------------------------------


def hat(y):
    """The linear hat of the regular grid in cell units, 000 Eq. (16)."""
    return max(0.0, 1.0 - abs(y))


def hat_integral(y):
    """H(y) = int_{-inf}^{y} hat: 0, (1 + y)^2 / 2, 1 - (1 - y)^2 / 2, 1."""
    if y <= -1.0:
        return 0.0
    if y <= 0.0:
        return 0.5 * (1.0 + y) ** 2
    if y < 1.0:
        return 1.0 - 0.5 * (1.0 - y) ** 2
    return 1.0


def weights_1d(xi, half, cells, shape):
    """[(node i, N, dN/dxi)] in one direction for a particle at xi (cell units, from the grid's origin),
    GIMP half-size ``half`` (cell units), on a grid of ``cells`` cells (nodes 0 .. cells)."""
    if shape == "linear":  # the two nodes of the particle's cell (the last cell for xi = cells)
        c = min(max(math.floor(xi), 0), cells - 1)
        f = xi - c
        return [(c, 1.0 - f, -1.0), (c + 1, f, 1.0)]
    if shape != "gimp":
        raise ValueError(f"shape: expected 'linear' or 'gimp', got {shape!r}")
    centre, l = xi, half
    if xi - half < 0.0 or xi + half > cells:  # the part of the particle domain inside the grid
        lo, hi = max(xi - half, 0.0), min(xi + half, float(cells))
        centre, l = 0.5 * (lo + hi), 0.5 * (hi - lo)
    out = []
    for i in range(math.floor(centre - l) - 1, math.ceil(centre + l) + 2):
        if 0 <= i <= cells:
            r = centre - i  # particle minus node
            N = (hat_integral(r + l) - hat_integral(r - l)) / (2.0 * l)  # mean of the hat over the domain
            dN = (hat(r + l) - hat(r - l)) / (2.0 * l)
            if N != 0.0 or dN != 0.0:
                out.append((i, N, dN))
    return out


def stencil(x, half_size, grid, shape):
    """[(flat node index, N_Ip, grad N_Ip (dim,))] of one particle: tensor products of the 1D factors."""
    d, h = grid.dim, grid.cell_size
    per_dim = [weights_1d((x[j] - grid.origin[j]) / h, half_size[j] / h, grid.cells[j], shape) for j in range(d)]
    out = []
    for combo in itertools.product(*per_dim):
        node = sum(i * stride for (i, _, _), stride in zip(combo, grid.strides))
        N = math.prod(Nj for _, Nj, _ in combo)
        grad = np.array([math.prod((dNj / h if j == k else Nj) for j, (_, Nj, dNj) in enumerate(combo))
                         for k in range(d)])
        out.append((node, N, grad))
    return out


def stress_tensor(voigt):
    """(3, 3) from a Voigt row [xx, yy, zz, yz, xz, xy]."""
    s = np.zeros((3, 3))
    for k, (i, j) in enumerate(VOIGT):
        s[i, j] = s[j, i] = voigt[k]
    return s


# --- the stages of one step -----------------------------------------------------------------------


def particle_to_grid(body: Body, stencils, grid, gravity):
    """P2G, 000 Eqs. (18)-(21): m_I = sum_p N_Ip m_p (Eq. 21), p_I = sum_p N_Ip m_p v_p (Eq. 18),
    f_iI = -sum_p V_p sigma_ij dN_Ip/dx_j (Eq. 19) with V_p = m_p / rho_p, on an r-z grid
    also -V_p sigma_thth N_Ip / r_p in the r-component; plus the body force m_I g (Eq. 20, first term)."""
    d, n_nodes = grid.dim, grid.num_nodes
    m_I, p_I, f_I = np.zeros(n_nodes), np.zeros((n_nodes, d)), np.zeros((n_nodes, d))
    for p, nodes in enumerate(stencils):
        m, v = body.mass[p], body.v[p, :d]
        V = body.mass[p] / body.density[p]
        sigma = stress_tensor(body.stress[p])
        r = body.x[p, 0]
        for node, N, grad in nodes:
            m_I[node] += N * m
            p_I[node] += N * m * v
            f_I[node] -= V * (sigma[:d, :d] @ grad)
            if grid.axisymmetric:
                f_I[node, 0] -= V * sigma[2, 2] * N / r
    f_I += m_I[:, None] * np.asarray(gravity, float)[:d]
    return m_I, p_I, f_I


def face_conditions(v_I, grid):
    """Face conditions on nodal velocities (num_nodes, dim): on the nodes of a "fixed" face every
    component is zero, on a "slip" face the normal one; "free" faces leave the node alone."""
    v = v_I.copy()
    for flat, multi in enumerate(np.ndindex(*grid.nodes)):  # C order = the grid's flat numbering
        for j, (low, high) in enumerate(grid.boundaries):
            for kind, on_face in ((low, multi[j] == 0), (high, multi[j] == grid.cells[j])):
                if on_face and kind == "fixed":
                    v[flat, :] = 0.0
                elif on_face and kind == "slip":
                    v[flat, j] = 0.0
    return v


def nodal_velocity(momentum, m_I):
    """p_I / m_I where the node has mass, 0 elsewhere."""
    v = np.zeros_like(momentum)
    for node in range(len(m_I)):
        if m_I[node] > 0.0:
            v[node] = momentum[node] / m_I[node]
    return v


def nodal_update(m_I, p_I, f_I, dt, grid):
    """Eqs. (22)-(23): p_I^{n+1} = p_I^n + dt f_I; returns the old nodal velocity p_I^n / m_I and the new
    one p_I^{n+1} / m_I after the face conditions."""
    v_old = nodal_velocity(p_I, m_I)
    v_new = face_conditions(nodal_velocity(p_I + dt * f_I, m_I), grid)
    return v_old, v_new


def grid_to_particle(body: Body, stencils, v_old, v_new, dt, grid):
    """G2P, Eqs. (24)-(25): v_p^{n+1} = v_p^n + sum_I N_Ip (v_I^new - v_I^old) (FLIP), and
    x_p^{n+1} = x_p^n + dt sum_I N_Ip v_I^new with the UPDATED nodal velocity (ERRATA 000-5)."""
    d = grid.dim
    x, v = body.x.copy(), body.v.copy()
    for p, nodes in enumerate(stencils):
        for node, N, _ in nodes:
            v[p, :d] += N * (v_new[node] - v_old[node])
            x[p, :d] += dt * N * v_new[node]
    return x, v


def remap(body: Body, stencils, v_p, m_I, grid):
    """Eq. (26): the re-mapped nodal velocity sum_p N_Ip m_p v_p^{n+1} / m_I, face conditions again."""
    d = grid.dim
    p_I = np.zeros((grid.num_nodes, d))
    for p, nodes in enumerate(stencils):
        for node, N, _ in nodes:
            p_I[node] += N * body.mass[p] * v_p[p, :d]
    return face_conditions(nodal_velocity(p_I, m_I), grid)


def strain_increments(body: Body, stencils, v_I, dt, grid):
    """Eqs. (27)-(28) from the re-mapped nodal velocity: L_ij = sum_I v_iI dN_Ip/dx_j (i, j < dim; r-z:
    also L_thth = sum_I N_Ip v_rI / r_p, the hoop rate), d eps = dt (L + L^T) / 2, d omega = dt (L - L^T) / 2,
    both (n, 3, 3)."""
    d, n = grid.dim, len(body.mass)
    deps, dspin = np.zeros((n, 3, 3)), np.zeros((n, 3, 3))
    for p, nodes in enumerate(stencils):
        L = np.zeros((3, 3))
        for node, N, grad in nodes:
            L[:d, :d] += np.outer(v_I[node], grad)
            if grid.axisymmetric:
                L[2, 2] += N * v_I[node, 0] / body.x[p, 0]
        deps[p] = 0.5 * dt * (L + L.T)
        dspin[p] = 0.5 * dt * (L - L.T)
    return deps, dspin


def density_update(density, deps):
    """Eq. (29): rho^{n+1} = rho^n / (1 + d eps_kk)."""
    return np.array([rho / (1.0 + np.trace(e)) for rho, e in zip(density, deps)])


def stress_update(body: Body, density, deps, dspin, dt, model, params):
    """Eq. (30): the material model's stress (and energy, Eq. 13) update from the increments, with the
    updated density (the convention of :class:`blastfsi.constitutive.Model`): the same model function
    musl calls, on all particles of the one material at once."""
    n = len(density)
    zero = jnp.zeros(n, jnp.float64)
    ps = PointState(stress=jnp.asarray(body.stress, jnp.float64), density=jnp.asarray(density, jnp.float64),
                    energy=jnp.asarray(body.energy, jnp.float64), plastic_strain=zero, damage=zero,
                    history=jnp.zeros((n, model.history_size), jnp.float64))
    new = model.update(ps, jnp.asarray(deps, jnp.float64), jnp.asarray(dspin, jnp.float64), dt, params)
    return np.asarray(new.stress), np.asarray(new.energy)


def step(body: Body, dt, grid, shape, model, params, gravity=(0.0, 0.0, 0.0)) -> Body:
    """One MUSL step of length dt (module docstring); ``shape`` "linear" or "gimp"; ``model`` a
    :class:`blastfsi.constitutive.Model` and ``params`` its parameters."""
    stencils = [stencil(body.x[p], body.half_size[p], grid, shape) for p in range(len(body.mass))]
    m_I, p_I, f_I = particle_to_grid(body, stencils, grid, gravity)
    v_old, v_new = nodal_update(m_I, p_I, f_I, dt, grid)
    x, v = grid_to_particle(body, stencils, v_old, v_new, dt, grid)
    v2_I = remap(body, stencils, v, m_I, grid)
    deps, dspin = strain_increments(body, stencils, v2_I, dt, grid)
    rho = density_update(body.density, deps)
    stress, energy = stress_update(body, rho, deps, dspin, dt, model, params)
    return body._replace(x=x, v=v, stress=stress, density=rho, energy=energy)


def momentum(body: Body):
    """Total momentum sum_p m_p v_p (3,)."""
    return np.sum(body.mass[:, None] * body.v, axis=0)
