"""Conservative remap of a 1D spherical or cylindrical detonation (``lagrangian1d``)
onto an Eulerian grid (seed 000 Sec. 4.1: "solving a 1D TNT explosion problem first
and map the result to the 3D region as the initial condition").

Geometry exponent j: a sphere (j = 2) on 1D spherical, r-z and 3D Cartesian
grids; an infinitely long cylinder (j = 1, amounts per metre of its length) on
2D Cartesian (plane x-y) grids. The ball of radius r is then the sphere or the
disc, of measure B_j r^(j+1) with B_2 = 4 pi / 3, B_1 = pi (:data:`UNIT_BALL`).

1D profile (:func:`profile_from_lagrangian`): zone edges r, and per zone the
physical mass, products mass, radial momentum and total energy. The node
velocities are staggered: each node's lumped mass is half of each neighbouring
zone, so zone z gets momentum m_z (v_n + v_{n+1})/2 and kinetic energy
m_z (v_n^2 + v_{n+1}^2)/4; the sums over zones are exactly the 1D totals.

Remap (:func:`remap`): zones are merged into radial bins at least one sub-cell
diagonal wide, never across the products/air interface; beyond the disturbed
radius r_max the ambient air is one more bin. Every grid cell is cut into
n_sub^ndim sub-cells, each carrying its exact volume (sub-shells in 1D
spherical, sub-rings in r-z, squares in 2D, cubes in 3D) spread over the radial
interval of its size around its centre's distance from the charge centre (in 1D
spherical exactly its sub-shell) and shared between the bins that interval
overlaps in proportion to their r^(j+1) extent (the measure of the shells); each bin's
content is shared among its sub-cells in proportion to their volumes, scaled
so that the bin's total on the grid equals its 1D total times the share f of
the ball inside the domain (1/2 per wall/symmetry plane through the centre).
Mass, products mass, radial momentum and total energy are therefore
conserved to round-off. Cells the ball cannot reach keep the ambient state
exactly; in the cells it reaches, the ambient bin's target is the ambient state
times their exact volume less f B_j r_max^(j+1), so the sampling error of the
ball's edge stays in those cells (a relative perturbation of the ambient
there of the order of the sub-cell sampling error).

Cell state from the remapped sums: products volume fraction alpha = (products
sub-volume)/V, phase densities = phase mass / phase volume, velocity =
momentum / mass (the radial momentum of each sub-cell points along its own
radial direction), pressure from the mixture EOS of the five-equation model
(:mod:`blastfsi.euler.mixture`, isobaric closure) at the remapped internal
energy, so that :func:`blastfsi.euler.conservative` returns the same sums.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from blastfsi.eos import jwl
from blastfsi.eos.jwl import JWLParams
from blastfsi.lagrangian1d.charge_problem import MEASURE

UNIT_BALL = {1: np.pi, 2: 4.0 / 3.0 * np.pi}  # B_j = MEASURE[j] / (j + 1): unit disc, unit sphere


class Profile1D(NamedTuple):
    """A spherically (j = 2) or cylindrically (j = 1) symmetric state: zone edges and per-zone totals
    (physical: whole sphere; whole cylinder per metre of length)."""

    edges: np.ndarray  # (N+1,) [m]
    mass: np.ndarray  # (N,) [kg] (j = 1: kg/m)
    products: np.ndarray  # (N,) products mass [kg]
    momentum: np.ndarray  # (N,) radial momentum [kg m/s]
    energy: np.ndarray  # (N,) total energy [J]
    j: int = 2  # geometry exponent: 2 sphere, 1 cylinder


def shell_measures(edges, j: int) -> np.ndarray:
    """Measures B_j (r_{k+1}^(j+1) - r_k^(j+1)) of the shells between ``edges`` (volumes; areas per
    metre of length for j = 1)."""
    return UNIT_BALL[j] * np.diff(np.asarray(edges, float) ** (j + 1))


def ball_exponent(geometry: str, ndim: int) -> int:
    """j of the blast a grid holds: a cylinder (1) on a 2D Cartesian grid, a sphere (2) otherwise."""
    return 1 if geometry == "cartesian" and ndim == 2 else 2


class RemapError(ValueError):
    """A remap that cannot conserve: the disturbed ball crosses a boundary that is not a mirror plane."""


def profile_from_lagrangian(x, v, e, zone_mass, explosive_zones: int, j: int) -> Profile1D:
    """The 1D profile of a ``lagrangian1d`` spherical (j = 2) or cylindrical (j = 1) state, whose zone
    masses are per radian^j (times MEASURE[j] = 4 pi, 2 pi: whole sphere, whole cylinder per metre)."""
    m = MEASURE[j] * np.asarray(zone_mass, float)
    v = np.asarray(v, float)
    prod = np.where(np.arange(m.size) < explosive_zones, m, 0.0)
    mom = 0.5 * m * (v[:-1] + v[1:])
    kin = 0.25 * m * (v[:-1] ** 2 + v[1:] ** 2)
    return Profile1D(np.asarray(x, float), m, prod, mom, m * np.asarray(e, float) + kin, j)


DISTURBED = 1e-6  # relative departure from ambient that counts as disturbed (density, energy density, pressure)


def disturbed_radius(profile: Profile1D, ambient_density: float, ambient_pressure_energy: float,
                     rel: float = DISTURBED) -> float:
    """Outer edge of the last zone whose density or energy density differs from ambient by > rel."""
    vol = shell_measures(profile.edges, profile.j)
    rho = profile.mass / vol
    eden = profile.energy / vol
    off = (np.abs(rho / ambient_density - 1.0) > rel) | (np.abs(eden / ambient_pressure_energy - 1.0) > rel)
    k = int(np.nonzero(off)[0].max()) if np.any(off) else 0
    return float(profile.edges[k + 1])


def _bins(profile: Profile1D, r_max: float, min_width: float):
    """Bin edges (from 0 to r_max) over whole zones, each >= min_width wide except when a
    material change forces a cut; per-bin totals."""
    edges = profile.edges
    inside = np.nonzero(edges[1:] <= r_max + 1e-12 * r_max)[0]
    n = inside.size
    is_prod = profile.products[:n] > 0.0
    cuts = [0]
    for z in range(1, n):
        if is_prod[z] != is_prod[z - 1]:
            if edges[z] - edges[cuts[-1]] < min_width and len(cuts) > 1 and is_prod[cuts[-2]] == is_prod[z - 1]:
                cuts.pop()  # a narrow last bin of a material joins the one before it
            cuts.append(z)
        elif edges[z] - edges[cuts[-1]] >= min_width:
            cuts.append(z)
    if edges[n] - edges[cuts[-1]] < min_width and len(cuts) > 1 and is_prod[cuts[-2]] == is_prod[n - 1]:
        cuts.pop()
    cuts.append(n)
    starts = np.asarray(cuts[:-1])
    tot = [np.add.reduceat(q[:n], starts) for q in (profile.mass, profile.products, profile.momentum, profile.energy)]
    return edges[np.r_[starts, n]], tot, is_prod[starts]


def _sub_samples(edges_axes, geometry: str, n_sub: int, cells_idx):
    """Sub-cell centres (S, ndim), exact sub-cell volumes (S,) and owning cell index (S,)
    of the cells ``cells_idx`` (tuple of index arrays), each cut in n_sub per axis (2D Cartesian:
    areas, per metre of length)."""
    ndim = len(edges_axes)
    frac = (np.arange(n_sub) + 0.5) / n_sub
    lo_f = np.arange(n_sub) / n_sub
    hi_f = (np.arange(n_sub) + 1.0) / n_sub
    coords, vols = [], []
    for ax in range(ndim):
        lo = edges_axes[ax][cells_idx[ax]]
        hi = edges_axes[ax][cells_idx[ax] + 1]
        w = hi - lo
        c = lo[:, None] + w[:, None] * frac[None, :]
        a, b = lo[:, None] + w[:, None] * lo_f[None, :], lo[:, None] + w[:, None] * hi_f[None, :]
        if ax == 0 and geometry == "spherical":
            vol = 4.0 / 3.0 * np.pi * (b**3 - a**3)
        elif ax == 0 and geometry == "axisymmetric":
            vol = np.pi * (b**2 - a**2)
        else:
            vol = b - a
        coords.append(c)
        vols.append(vol)
    nc = cells_idx[0].size
    pts = np.zeros((nc, n_sub**ndim, ndim))
    vol = np.ones((nc, n_sub**ndim))
    grids = np.meshgrid(*[np.arange(n_sub)] * ndim, indexing="ij")
    for ax in range(ndim):
        k = grids[ax].ravel()
        pts[:, :, ax] = coords[ax][:, k]
        vol *= vols[ax][:, k]
    owner = np.repeat(np.arange(nc), n_sub**ndim)
    return pts.reshape(-1, ndim), vol.reshape(-1), owner


class Remapped(NamedTuple):
    """Cell sums (physical) and the primitive fields for :mod:`blastfsi.euler.problem`."""

    mass: np.ndarray  # (*shape) [kg]
    products: np.ndarray
    momentum: np.ndarray  # (ndim, *shape)
    energy: np.ndarray
    rho_k: np.ndarray  # (2, *shape) products, air phase densities
    alpha: np.ndarray  # (*shape) products volume fraction
    velocity: np.ndarray  # (ndim, *shape)
    pressure: np.ndarray  # (*shape)
    volume: np.ndarray  # (*shape) cell volumes [m^3]
    share: float  # f, fraction of the ball (sphere or cylinder) inside the domain
    radius: float  # r_max, outer radius of the remapped (disturbed) ball [m]
    targets: tuple | None  # exact (mass, products mass, energy) the grid must hold; None: centre outside


def cell_volumes(edges_axes, geometry: str) -> np.ndarray:
    """Exact cell volumes [m^3] (1D Cartesian: per m^2; 2D Cartesian: per m)."""
    d = [np.diff(e) for e in edges_axes]
    if geometry == "spherical":
        first = shell_measures(edges_axes[0], 2)
    elif geometry == "axisymmetric":
        first = np.pi * np.diff(edges_axes[0] ** 2)
    else:
        first = d[0]
    out = first
    for k in range(1, len(d)):
        out = np.multiply.outer(out, d[k])
    return out


def remap(profile: Profile1D, edges_axes, geometry: str, centre, mirrors, ambient_density: float,
          ambient_pressure: float, products_eos: JWLParams, air_eos: JWLParams, n_sub: int = 4,
          r_max: float | None = None) -> Remapped:
    """Remap ``profile`` (centred at ``centre``) onto the grid with cell edges ``edges_axes``.

    geometry: "spherical" (1D, r from 0, centre [0]), "axisymmetric" (r-z, centre [0, z_c]) or
    "cartesian" (3D; 2D: a cylindrical ``profile`` (j = 1), its axis along z; 1D Cartesian is
    refused). The profile's j must be the grid's (:func:`ball_exponent`). ``mirrors``: per
    axis (lower, upper) booleans, True where that face is a wall/symmetry plane; a mirror face
    through the centre halves the share f. The ball of radius ``r_max`` (default: the disturbed
    radius) must not cross any other face (RemapError).

    A centre outside the grid (a stand-off charge): the ball may reach into the grid anywhere; each
    sub-cell then takes its bins' mean densities (bin total / shell measure) over its share of them,
    so the grid holds the integral of the binned profile over the domain to the sub-cell sampling
    error (``share``: the sampled fraction of the ball inside, ``targets`` None); cells out of its
    reach, all of them before the blast arrives, hold the ambient state exactly."""
    ndim = len(edges_axes)
    centre = np.asarray(centre, float)
    if geometry == "spherical" and (ndim != 1 or centre[0] != 0.0):
        raise RemapError("a 1D spherical grid holds a charge at r = 0 only")
    if geometry == "axisymmetric" and (ndim != 2 or centre[0] != 0.0):
        raise RemapError("an axisymmetric grid holds a spherical charge on its axis (r = 0) only")
    if geometry == "cartesian" and ndim == 1:
        raise RemapError("a 1D Cartesian grid holds neither a spherical nor a cylindrical charge")
    j = ball_exponent(geometry, ndim)
    if profile.j != j:
        raise RemapError(f"a {('', 'cylindrical', 'spherical')[profile.j]} 1D profile cannot be remapped onto a "
                         f"{ndim}D {geometry} grid, which holds a {('', 'cylindrical', 'spherical')[j]} blast")
    air_e = ambient_pressure / air_eos.omega  # rho e of the ambient ideal gas (f = 0)
    r_max = disturbed_radius(profile, ambient_density, air_e) if r_max is None else float(r_max)
    share = 1.0
    radial_axis = 0 if geometry in ("spherical", "axisymmetric") else None
    outside = any(not edges_axes[ax][0] <= centre[ax] <= edges_axes[ax][-1] for ax in range(ndim))
    for ax in range(ndim if not outside else 0):
        lo, hi = edges_axes[ax][0], edges_axes[ax][-1]
        for side, face in (("lower", lo), ("upper", hi)):
            dist = abs(centre[ax] - face)
            if ax == radial_axis and side == "lower":
                continue  # the axis / the centre of a spherical grid
            if dist <= 1e-9 * (hi - lo) and mirrors[ax][0 if side == "lower" else 1]:
                share *= 0.5
            elif dist < r_max:
                raise RemapError(f"the disturbed ball (r = {r_max:.4g} m at the remap time) crosses the {side} "
                                 f"{'xyz'[ax]} face of the domain ({dist:.4g} m from the charge centre); "
                                 "remap earlier or move the charge")
    min_cell = min(float(np.min(np.diff(e))) for e in edges_axes)
    s = min_cell / n_sub
    bin_edges, (b_mass, b_prod, b_mom, b_en), b_is_prod = _bins(profile, r_max, s * np.sqrt(ndim) * 1.0001)
    r_max = float(bin_edges[-1])
    nb = b_mass.size
    ball = share * UNIT_BALL[j] * r_max ** (j + 1)
    vols = cell_volumes(edges_axes, geometry)
    # cells the ball can reach: nearest point of the cell within r_max
    near = np.ones(vols.shape, bool)
    dist2 = 0.0
    for ax in range(ndim):
        e = edges_axes[ax]
        gap = np.maximum(np.maximum(e[:-1] - centre[ax], centre[ax] - e[1:]), 0.0)
        shape = [1] * ndim
        shape[ax] = -1
        dist2 = dist2 + gap.reshape(shape) ** 2
    near &= dist2 < r_max**2
    if outside and not np.any(near):  # a stand-off charge remapped before its blast reaches the domain
        z = np.zeros(vols.shape)
        return _primitives(vols * ambient_density, z, np.zeros((ndim,) + vols.shape), vols * air_e, z, vols, vols,
                           0.0, ambient_density, products_eos, air_eos, profile, r_max, None)
    idx = np.nonzero(near)
    pts, svol, owner = _sub_samples(edges_axes, geometry, n_sub, idx)
    rel = pts - centre[None, :]
    radius = np.sqrt(np.sum(rel**2, axis=1))
    # each sub-cell spreads over the radial interval [rho - s/2, rho + s/2] (in 1D spherical: its own
    # sub-shell exactly), shared between the (at most two) bins it overlaps in proportion to r^(j+1)
    lo = np.maximum(radius - 0.5 * s, 0.0)
    hi = radius + 0.5 * s
    bin_of = np.r_[bin_edges, np.inf]
    b_lo = np.minimum(np.searchsorted(bin_of, lo, side="right") - 1, nb)
    b_hi = np.minimum(np.searchsorted(bin_of, hi, side="right") - 1, nb)
    split = np.where(b_hi > b_lo, bin_of[np.minimum(b_lo + 1, nb)], hi)
    q = j + 1
    f_lo = (split**q - lo**q) / (hi**q - lo**q)
    b = np.r_[b_lo, b_hi]
    w = np.r_[svol * f_lo, svol * (1.0 - f_lo)]
    own = np.r_[owner, owner]
    unit = np.where(radius[:, None] > 0.0, rel / np.where(radius > 0.0, radius, 1.0)[:, None], 0.0)
    unit = np.r_[unit, unit]
    W = np.bincount(b, weights=w, minlength=nb + 1)
    if not outside and np.any(W[:nb] <= 0.0):
        raise RemapError("a radial bin received no sub-cell (grid too coarse for the remap sampling)")
    v_near = float(np.sum(vols[near]))  # exact volume of the cells the ball reaches
    f = share
    if outside:  # the domain holds a part of the ball known only by sampling: each bin's mean densities
        share = float(np.sum(W[:nb]) / (UNIT_BALL[j] * r_max ** (j + 1)))  # (sampled, reported)
        f, amb_vol, W = 1.0, 1.0, np.r_[shell_measures(bin_edges, j), 1.0]
    else:
        amb_vol = v_near - ball  # exact ambient volume inside those cells; the rest of the grid is ambient as is
    scale_vol = np.r_[f * shell_measures(bin_edges, j), amb_vol] / W
    t_mass = np.r_[f * b_mass, ambient_density * amb_vol] / W
    t_prod = np.r_[f * b_prod, 0.0] / W
    t_mom = np.r_[f * b_mom, 0.0] / W
    t_en = np.r_[f * b_en, amb_vol * air_e] / W
    ncell = idx[0].size
    mass_n = np.bincount(own, weights=t_mass[b] * w, minlength=ncell)
    prod_n = np.bincount(own, weights=t_prod[b] * w, minlength=ncell)
    en_n = np.bincount(own, weights=t_en[b] * w, minlength=ncell)
    is_prod = np.r_[b_is_prod, False]
    pvol_n = np.bincount(own, weights=np.where(is_prod[b], scale_vol[b] * w, 0.0), minlength=ncell)
    vol_n = np.bincount(own, weights=scale_vol[b] * w, minlength=ncell)
    mom_n = [np.bincount(own, weights=t_mom[b] * w * unit[:, ax], minlength=ncell) for ax in range(ndim)]

    mass = vols * ambient_density  # cells out of the ball's reach: the ambient state
    products = np.zeros(vols.shape)
    energy = vols * air_e
    momentum = np.zeros((ndim,) + vols.shape)
    pvol = np.zeros(vols.shape)
    cvol = vols.copy()
    mass[idx], products[idx], energy[idx], pvol[idx], cvol[idx] = mass_n, prod_n, en_n, pvol_n, vol_n
    for ax in range(ndim):
        momentum[ax][idx] = mom_n[ax]
    v_amb = float(np.sum(vols)) - ball
    targets = None if outside else (share * float(np.sum(b_mass)) + ambient_density * v_amb,
                                    share * float(np.sum(b_prod)), share * float(np.sum(b_en)) + air_e * v_amb)
    return _primitives(mass, products, momentum, energy, pvol, cvol, vols, share, ambient_density,
                       products_eos, air_eos, profile, r_max, targets)


def _primitives(mass, products, momentum, energy, pvol, cvol, vols, share, ambient_density, products_eos,
                air_eos, profile, r_max, targets) -> Remapped:
    alpha = np.clip(pvol / cvol, 0.0, 1.0)
    air_mass = mass - products
    has_p = products > 0.0
    has_a = air_mass > 0.0
    prod_zones = profile.products > 0.0
    prod_vol = shell_measures(profile.edges, profile.j)
    fill_p = (float(np.sum(profile.products) / np.sum(prod_vol[prod_zones])) if np.any(prod_zones)
              else products_eos.rho0)  # mean products density (unused without products)
    rho_p = np.where(has_p & (alpha > 0.0), products / np.where(alpha > 0.0, alpha * vols, 1.0), fill_p)
    rho_a = np.where(has_a & (alpha < 1.0), air_mass / np.where(alpha < 1.0, (1.0 - alpha) * vols, 1.0),
                     ambient_density)
    alpha = np.where(has_p, alpha, 0.0)
    alpha = np.where(has_a, alpha, 1.0)
    rho = mass / vols
    velocity = momentum / mass[None]
    rho_e = energy / vols - 0.5 * rho * np.sum(velocity**2, axis=0)
    # isobaric closure (blastfsi.euler.mixture): p = (rho e + sum alpha_k f_k / G_k) / xi
    a_k = (alpha, 1.0 - alpha)
    r_k = (rho_p, rho_a)
    xi = sum(a / row.omega for a, row in zip(a_k, (products_eos, air_eos)))
    s_f = sum(a * jwl.reference_pressure(r, row) / row.omega for a, r, row in zip(a_k, r_k, (products_eos, air_eos)))
    pressure = (rho_e + s_f) / xi
    return Remapped(mass, products, momentum, energy, np.stack([rho_p, rho_a]), alpha, velocity, pressure, vols,
                    share, r_max, targets)
