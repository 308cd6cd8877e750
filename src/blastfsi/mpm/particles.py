"""Material points in a fixed-capacity pool with an active mask (DESIGN "Fixed shapes").

Every field is an array with leading axis ``capacity``; inactive slots carry
finite placeholder values and contribute nothing (every kernel selects with
``active``). The coupling creates and deletes particles with
:func:`add_particles` / :func:`remove_particles`; :func:`compact` and
:func:`sort_by_cell` reorder them. Nothing here loses mass silently: an add
that does not fit changes nothing and returns the capacity it needed
(:func:`insert` raises :class:`CapacityError` with it on the host), and a
removal returns the mass, momentum and energy it took out.

Density is updated from the trace of the strain increment (000 Eq. 29); no
deformation gradient is stored. The particle volume is ``mass / density``
(for an axisymmetric grid, the volume of the ring, 2 pi r * area).
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi.constitutive import PointState
from blastfsi.mpm.grid import cell_index


class Particles(NamedTuple):
    x: jnp.ndarray  # (n, 3) position [m], zero beyond the grid's dim
    v: jnp.ndarray  # (n, 3) velocity [m/s]
    mass: jnp.ndarray  # (n,) [kg] (axisymmetric: mass of the ring)
    volume0: jnp.ndarray  # (n,) initial volume [m^3]
    half_size: jnp.ndarray  # (n, 3) GIMP half-size l per direction [m] (uGIMP: fixed)
    material: jnp.ndarray  # (n,) int32 index into the solver's material list
    active: jnp.ndarray  # (n,) bool
    point: PointState  # stress (n, 6) Voigt, density, energy, plastic strain, damage, history
    q: jnp.ndarray  # (n,) artificial bulk viscosity [Pa], added to the pressure in the forces
    vol_rate: jnp.ndarray  # (n,) volumetric strain rate D_kk of the last step [1/s]
    wave_speed: jnp.ndarray  # (n,) material signal speed c [m/s] (for the CFL step and q)
    plastic_work: jnp.ndarray  # (n,) accumulated plastic work [J/kg]
    prescribed: jnp.ndarray  # (n, 3) bool: which velocity components are prescribed (an impactor or a
    #                          clamp: all; a sliding clamp: the normal one)
    prescribed_velocity: jnp.ndarray  # (n, 3) [m/s]
    surface_load: jnp.ndarray  # (n, 3) traction / boundary-layer thickness, t/h of 000 Eq. (20) [N/m^3]


class Totals(NamedTuple):
    mass: jnp.ndarray  # [kg]
    momentum: jnp.ndarray  # (3,) [kg m/s]
    kinetic: jnp.ndarray  # [J]
    internal: jnp.ndarray  # [J], stress work + q work (includes the plastic work)
    plastic: jnp.ndarray  # [J], the plastic part of ``internal``


class CapacityError(RuntimeError):
    """The particle pool is too small; the message gives the capacity needed."""


class ParticleError(ValueError):
    """An invalid particle-set parameter (the message names it)."""


def _check_count(name, value, low):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ParticleError(f"{name}: expected an integer >= {low}, got {value!r}")


def empty(capacity: int, history_size: int = 0, dtype=jnp.float64) -> Particles:
    """A pool with every slot inactive (placeholders: unit density, zero stress). Host side."""
    _check_count("capacity", capacity, 1)
    _check_count("history_size", history_size, 0)
    n = int(capacity)

    def zeros(*shape, value=0.0):
        return jnp.asarray(np.full((n,) + shape, value), dtype)

    point = PointState(stress=zeros(6), density=zeros(value=1.0), energy=zeros(), plastic_strain=zeros(),
                       damage=zeros(), history=zeros(int(history_size)))
    return Particles(x=zeros(3), v=zeros(3), mass=zeros(), volume0=zeros(value=1.0), half_size=zeros(3),
                     material=jnp.asarray(np.zeros(n, np.int32)), active=jnp.asarray(np.zeros(n, bool)), point=point,
                     q=zeros(), vol_rate=zeros(), wave_speed=zeros(), plastic_work=zeros(),
                     prescribed=jnp.asarray(np.zeros((n, 3), bool)), prescribed_velocity=zeros(3), surface_load=zeros(3))


def make_pool(batch: Particles, capacity: int) -> Particles:
    """A pool of ``capacity`` slots holding the active particles of ``batch`` first (host side,
    no compilation); raises :class:`CapacityError` when they do not fit."""
    _check_count("capacity", capacity, 1)
    keep = np.asarray(batch.active)
    n_active = int(keep.sum())
    check_capacity(n_active, int(capacity))
    pad = int(capacity) - n_active
    filler = empty(max(pad, 1), batch.point.history.shape[1], batch.mass.dtype)
    return jax.tree_util.tree_map(lambda a, b: jnp.asarray(np.concatenate([np.asarray(a)[keep], np.asarray(b)[:pad]])),
                                  batch, filler)


def _pad3(a, n):
    """(n, 3) float array from None (zeros) or rows of up to 3 components."""
    if a is None:
        return np.zeros((n, 3))
    a = np.atleast_2d(np.asarray(a, float))
    return np.broadcast_to(np.pad(a, ((0, 0), (0, 3 - a.shape[1]))), (n, 3))


def _held(prescribed, held, n) -> np.ndarray:
    """(n, 3) bool mask of the prescribed velocity components of a batch."""
    if prescribed is None:
        if held is not None:
            raise ParticleError("held: only a batch with a prescribed velocity holds components")
        return np.zeros((n, 3), bool)
    mask = np.ones(3, bool) if held is None else np.asarray(held, bool).reshape(3)
    return np.broadcast_to(mask, (n, 3))


def new_particles(x, volume, density, *, v=None, material=0, half_size=None, stress=None, energy=None,
                  history=None, history_size: int = 0, prescribed=None, held=None, surface_load=None,
                  dtype=jnp.float64) -> Particles:
    """A batch of active particles from host arrays (positions (n, d<=3) are padded to 3).

    ``volume`` (n,) and ``density`` (scalar or (n,)) give the mass; ``v`` (n, 3)
    the velocity (default: ``prescribed`` or zero); ``prescribed`` (n, 3) or
    None: the prescribed velocity of an impactor, all particles of the batch
    move with it (build bodies as separate batches, join with :func:`concatenate`); ``held`` (3,)
    bool: the components of ``prescribed`` that are imposed (default all; a plate between clamping
    plates that lets it slide: only its normal one), the others evolve freely;
    ``surface_load`` (n, 3): t/h of 000 Eq. (20), see :func:`surface_load`;
    ``stress`` (n, 6) Voigt.
    """
    x = np.atleast_2d(np.asarray(x, float))
    n, d = x.shape
    if d > 3:
        raise ParticleError(f"x: expected at most 3 coordinates per particle, got {d}")
    x = np.pad(x, ((0, 0), (0, 3 - d)))
    volume = np.broadcast_to(np.asarray(volume, float), (n,))
    density = np.broadcast_to(np.asarray(density, float), (n,))
    if not np.all(volume > 0.0):
        raise ParticleError("volume: expected values > 0")
    if not np.all(density > 0.0):
        raise ParticleError("density: expected values > 0")

    zero = np.zeros(n)
    point = PointState(
        stress=np.zeros((n, 6)) if stress is None else np.broadcast_to(np.asarray(stress, float), (n, 6)),
        density=density, energy=zero if energy is None else np.broadcast_to(np.asarray(energy, float), (n,)),
        plastic_strain=zero, damage=zero,
        history=np.zeros((n, history_size)) if history is None else np.broadcast_to(np.asarray(history, float),
                                                                                    (n, history_size)))
    batch = Particles(
        x=x, v=_pad3(prescribed if v is None else v, n), mass=volume * density, volume0=volume,
        half_size=_pad3(half_size, n), material=np.broadcast_to(np.asarray(material, np.int32), (n,)),
        active=np.ones(n, bool), point=point, q=zero, vol_rate=zero, wave_speed=zero, plastic_work=zero,
        prescribed=_held(prescribed, held, n), prescribed_velocity=_pad3(prescribed, n),
        surface_load=_pad3(surface_load, n))
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype if np.issubdtype(a.dtype, np.floating) else None),
                                  batch)


def concatenate(*batches: Particles) -> Particles:
    """One particle set from several (e.g. bodies built separately), host side."""
    return jax.tree_util.tree_map(lambda *a: jnp.asarray(np.concatenate([np.asarray(x) for x in a])), *batches)


def surface_load(traction, layer_thickness):
    """t / h of 000 Eq. (20): the traction [Pa] spread over the boundary layer of
    thickness h [m] (usually the particle spacing normal to the surface)."""
    h = np.asarray(layer_thickness, float)
    if not np.all(h > 0.0):
        raise ParticleError(f"layer_thickness: expected values > 0, got {layer_thickness!r}")
    return np.asarray(traction, float) / np.reshape(h, np.shape(h) + (1,) * (np.ndim(traction) - np.ndim(h)))


def lattice(grid, lower, upper, per_cell: int = 2):
    """Regular particle positions filling the box [lower, upper] (host side).

    ``per_cell`` particles per grid cell and direction, spacing s = h / per_cell,
    at the centres of the sub-cells counted from ``lower``. Returns positions
    (n, 3), volumes (n,) (axisymmetric: 2 pi r s^2) and GIMP half-sizes (n, 3) = s/2.
    """
    _check_count("per_cell", per_cell, 1)
    lower, upper = np.atleast_1d(np.asarray(lower, float)), np.atleast_1d(np.asarray(upper, float))
    if lower.shape != (grid.dim,) or upper.shape != (grid.dim,):
        raise ParticleError(f"lower/upper: expected {grid.dim} coordinates each")
    s = grid.cell_size / per_cell
    counts = np.rint((upper - lower) / s).astype(int)
    if np.any(counts < 1):
        raise ParticleError(f"upper - lower = {upper - lower}: the box is smaller than one particle spacing {s}")
    slack = 1e-12 * grid.cell_size  # round-off of boxes given as cell edges (x_c -+ h/2)
    if np.any(lower < np.asarray(grid.origin) - slack) or np.any(upper > np.asarray(grid.upper) + slack):
        raise ParticleError(f"lower/upper: the box [{lower}, {upper}] leaves the grid [{grid.origin}, {grid.upper}]")
    axes = [lo + s * (np.arange(c) + 0.5) for lo, c in zip(lower, counts)]
    pos = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, grid.dim)
    volume = np.full(len(pos), s ** grid.dim)
    if grid.axisymmetric:
        volume = 2.0 * np.pi * pos[:, 0] * s ** 2
    half = np.zeros((len(pos), 3))
    half[:, :grid.dim] = 0.5 * s
    return np.pad(pos, ((0, 0), (0, 3 - grid.dim))), volume, half


def _select(mask, a, b):
    return jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)


def add_particles(pool: Particles, batch: Particles, first_slot: int = 0, parts: int = 1):
    """:func:`add_particles_at` without the slots."""
    pool, required, _ = add_particles_at(pool, batch, first_slot, parts)
    return pool, required


def add_particles_at(pool: Particles, batch: Particles, first_slot: int = 0, parts: int = 1):
    """Fill free slots of ``pool`` from ``first_slot`` on with the active particles of ``batch`` (jittable;
    a coupled run keeps its structures in the slots before ``first_slot``, freed or not).

    The k-th active particle of the batch goes to the k-th free slot (ranks by
    cumulative sums, no sort). Returns ``(pool, required, slots)``: ``required`` is
    the number of active particles after the add plus the slots before ``first_slot`` that are free.
    When it exceeds the capacity nothing is added (the pool comes back unchanged) so the caller
    can stop and report it. Also returns the slot of every batch entry
    (``capacity`` for inactive entries and when nothing was added).

    ``parts``: the pool is split over that many devices in equal parts (a divisor of the capacity). Every
    per-slot step is then local to the part holding the slot: the free slots are ranked within each part and
    offset by the free slots of the parts before it (``parts`` counts cross the devices, not the pool), each
    slot reads the batch entry of its rank from the (small, whole) batch, and the slots of the batch entries
    are one sum over the parts. The same slots for any ``parts``.
    """
    capacity, batch_size = pool.mass.shape[0], batch.mass.shape[0]
    usable = jnp.arange(capacity) >= first_slot
    free = ~pool.active & usable
    required = jnp.sum(pool.active | ~usable) + jnp.sum(batch.active)
    by_part = free.reshape(parts, capacity // parts).astype(jnp.int32)
    before = jnp.cumsum(jnp.sum(by_part, axis=1)) - jnp.sum(by_part, axis=1)  # free slots in the parts before
    free_rank = (jnp.cumsum(by_part, axis=1) + before[:, None]).reshape(capacity) - 1
    rank = jnp.cumsum(batch.active) - 1  # of the batch's active entries
    entry_of_rank = jnp.zeros(batch_size, jnp.int32).at[jnp.where(batch.active, rank, batch_size)].set(
        jnp.arange(batch_size, dtype=jnp.int32), mode="drop")
    filled = free & (free_rank < jnp.sum(batch.active)) & (required <= capacity)
    source = entry_of_rank[jnp.clip(free_rank, 0, batch_size - 1)]
    pool = jax.tree_util.tree_map(lambda p, b: _select(filled, b[source], p), pool, batch)
    # the slot of each rank: one slot per filled rank, the others none (-1), summed over the slots
    slot_of_rank = jnp.zeros(batch_size, jnp.int32).at[jnp.where(filled, free_rank, batch_size)].add(
        jnp.arange(capacity, dtype=jnp.int32) + 1, mode="drop") - 1
    target = jnp.where(batch.active, slot_of_rank[jnp.clip(rank, 0, batch_size - 1)], -1)
    return pool, required, jnp.where(target >= 0, target, capacity)


_add_particles_compiled = jax.jit(add_particles)


def insert(pool: Particles, batch: Particles) -> Particles:
    """Host-side :func:`add_particles` that raises :class:`CapacityError` on overflow."""
    new_pool, required = _add_particles_compiled(pool, batch)
    check_capacity(required, pool.mass.shape[0])
    return new_pool


def check_capacity(required, capacity: int):
    """Raise :class:`CapacityError` when ``required`` particles do not fit (host side)."""
    required = int(required)
    if required > capacity:
        raise CapacityError(f"particle pool capacity {capacity} is too small: {required} active particles "
                            f"needed; set the capacity to at least {required}")


def remove_particles(pool: Particles, mask):
    """Deactivate the active particles where ``mask``; returns ``(pool, removed)``
    with ``removed`` the :class:`Totals` of what was taken out (for the budget)."""
    gone = mask & pool.active
    removed = totals(pool._replace(active=gone))
    return pool._replace(active=pool.active & ~gone), removed


def compact(pool: Particles) -> Particles:
    """Active particles moved to the front, inactive ones behind, both in their order (a stable
    partition by cumulative sums, no sort)."""
    act = pool.active
    n_active = jnp.sum(act)
    dest = jnp.where(act, jnp.cumsum(act) - 1, n_active + jnp.cumsum(~act) - 1)
    order = jnp.zeros_like(dest).at[dest].set(jnp.arange(dest.shape[0], dtype=dest.dtype), unique_indices=True)
    return jax.tree_util.tree_map(lambda a: a[order], pool)


def sort_by_cell(pool: Particles, grid) -> Particles:
    """Active particles sorted by the flat index of their cell (stable), inactive
    last: neighbouring particles scatter to neighbouring nodes."""
    key = jnp.where(pool.active, cell_index(pool.x, grid), jnp.iinfo(jnp.int32).max)
    order = jnp.argsort(key, stable=True)
    return jax.tree_util.tree_map(lambda a: a[order], pool)


def totals(p: Particles) -> Totals:
    """Mass, momentum and energies over the active particles.

    Axisymmetric: masses are ring masses, and only the axial momentum
    component (index 1) is a conserved total.
    """
    m = jnp.where(p.active, p.mass, 0.0)
    return Totals(mass=jnp.sum(m), momentum=jnp.sum(m[:, None] * p.v, axis=0),
                  kinetic=0.5 * jnp.sum(m * jnp.sum(p.v * p.v, axis=1)),
                  internal=jnp.sum(m * p.point.energy), plastic=jnp.sum(m * p.plastic_work))


def total_mass(p: Particles):
    return totals(p).mass


def total_momentum(p: Particles):
    return totals(p).momentum


def total_energy(p: Particles):
    """Kinetic + internal energy of the active particles [J]."""
    t = totals(p)
    return t.kinetic + t.internal


def model_output_fields(material: np.ndarray, history: np.ndarray, models, model_params) -> dict:
    """The constitutive models' derived snapshot fields (``Model.output_fields``) over particles of
    material indices ``material`` with history rows ``history``: NaN where a particle's model has no
    such field; every model's fields are there, whether its particles are or not (one layout per series).
    Host side."""
    out = {}
    for k, (model, params) in enumerate(zip(models, model_params)):
        mine = material == k
        for name, values in model.output_fields(history[mine], params).items():
            out.setdefault(name, np.full(material.shape, np.nan))[mine] = values
    return out
