"""Explicit updated-Lagrangian MPM: the MUSL step of 000 Sec. 2.2, Eqs. (17)-(30).

One step of length dt (all particle loops are whole-array operations):

1. P2G of every transferred quantity at once: nodal mass (Eq. 21), momentum
   (Eq. 18), internal force (Eq. 19, with the artificial bulk viscosity q
   added to the pressure and the reference pressure p_ref taken out, sigma +
   p_ref I; on 2D/3D Cartesian grids (r-z: linear shape functions only) the
   gas particles take the gradient at their cell's centre with the cell's
   share of volume, :func:`cell_centre_gradient`;
   void gas, :func:`void_gas`, exerts none) and
   prescribed traction (Eq. 20), as one combined
   scatter (GPU) or one fused scalar scatter per channel (CPU, see
   :func:`particle_to_grid`); body force m_I b on the grid (first term of Eq. 20).
2. Nodal momentum update, Eq. (22)-(23); face conditions on the new nodal
   velocity (:mod:`blastfsi.mpm.grid`); nodes touched by particles with a
   prescribed velocity move with it (a rigid impactor's constraint), component
   by component (a sliding clamp prescribes only the normal one).
3. G2P: particle velocity by the nodal velocity increment (Eq. 24, FLIP) and
   position by the UPDATED nodal velocity p^{n+1}/m (ERRATA 000-5, standard
   MUSL; the seed's Eq. 25 prints p^n). Prescribed particles move with their
   own velocity. Optionally a fraction alpha of each material's particles'
   velocity is PIC, the interpolated updated nodal velocity (the FLIP/PIC blend
   of Brackbill & Ruppel, JCP 65 (1986) 314; Stomakhin et al., ACM TOG 32 (2013)
   102): v_p = (1 - alpha) v_FLIP + alpha v_PIC damps the particle-velocity
   modes the grid cannot see (FLIP's ringing in a gas); alpha = 0 is pure FLIP.
   The blend takes kinetic energy h_p = (|v_FLIP|^2 - |v_p|^2) / 2 per unit
   mass from the particle; that energy heats the blended particles, but not as
   h_p itself. h_p has a part of first order in alpha, alpha (S n) . delta_p, where
   delta_p = v_p^n - S g is the particle's deviation from the interpolated old
   nodal velocity g and S n the PIC velocity. That part depends on the frame:
   in a fast stream it cools every other particle by ~ alpha |v| |delta| and,
   where the kinetic energy far exceeds the internal one (air around a slab's
   edge), drove particles to negative internal energy and pressure. The heat
   is instead
       c_p = alpha (sum_I N_Ip n_I . u_I - S n . S g) + (alpha - alpha^2 / 2) |delta_p|^2,
   with u_I the alpha-weighted nodal velocity of the blended particles. The
   second term is the dissipation of the particle's own deviation. The first
   is its share of the grid's, alpha n^T (M_lumped - M_consistent) g: the
   weighted variance of the nodal velocities over its stencil, >= 0 and
   frame-independent where u = g. sum_p m_p alpha_p ((S n) . v_p^n - sum_I
   N_Ip n_I . u_I) = 0, so sum_p m_p c_p = sum_p m_p h_p exactly: the blend
   conserves the energy (tests/test_mpm.py). Only when ``Config.blend``.
   Per particle the first term has no sign where n differs from g (it holds
   the covariance of the nodal velocity and its change over the stencil), and
   for a rarefied particle, whose internal energy is small against alpha times
   the squared velocity differences across its stencil, it drove the internal
   energy below zero and the pressure negative, after which compression took
   more energy still: air at 1.2e-4-3e-4 kg/m^3 in the near vacuum behind
   steel-plate-blast's bridge fell from 2e5 to -5e5 J/kg within 10 us (with
   pure FLIP it stayed positive), and the Eulerian cells read from it became
   non-physical.
   The heat is the dissipation of velocity differences the grid cannot
   resolve, between the particles that share nodes, so it belongs to those
   nodes' gas, not to the particle whose deviation it was: each node's heat
   H_I = sum_q N_Iq m_q c_q is shared by its blended particles in proportion
   to alpha m, and a particle takes c'_p = alpha_p sum_I N_Ip H_I / A_I
   (A_I = sum_q N_Iq alpha_q m_q). sum_p m_p c'_p = sum_I H_I = sum_p m_p c_p:
   still exact; a particle alone on its nodes keeps its own c_p; particles
   sharing nodes heat by the same amount per unit mass. Kept as c_p, the
   heat went to the particles that deviate most, the light ones: rarefied
   air among heavier gas in steel-plate-blast (1e-4 to 1e-2 kg/m^3) was
   heated by ~1e6 J/kg a step to 1e8-1e9 J/kg (the Eulerian solver's gas
   there holds <= 1.4e6 J/kg from 0.18 ms) and its 8-23 km/s sound set the
   step, 40-80 ns against the steel's 169 ns; shared, the hottest held
   <= 4.1e8 J/kg.
   c'_p takes at most half the particle's internal energy,
   c'_p >= -MAX_ENERGY_SHARE max(e_p, 0) (the bound of the pressure relaxation,
   :mod:`blastfsi.mpm.relaxation`; both gases' e > 0 in every physical state:
   an ideal gas's and, on and above their detonation isentrope, the
   products'; e = 0 would give p = 0, which the run's fault check rejects:
   allowed the whole of it, steel-plate-blast stopped at 0.35 ms on a cell
   read from the particles); the energy it declines is the step's non-conservation,
   which a coupled run's budget books.
4. Velocity re-map, Eq. (26): a second scatter of the updated particle
   momentum (and of the nodes' blend heat, gathered back with the velocity
   gradient of step 5); face conditions and constraints again.
5. Strain and spin increments from the re-mapped nodal velocities, Eqs. (27)-(28)
   (gas particles where :func:`cell_centre_gradient` applies: at the cell centre, as their force);
   density, Eq. (29) (rho / (1 + d eps_kk); no deformation gradient is kept);
   q work heats the particle (000 Eq. 13 with p -> p + q); stress, energy and
   history by each material's model (Jaumann rate, Eq. 30, inside the model),
   from the start state with the gas particles of different materials that
   share nodes relaxed towards one pressure (only when ``Config.relax``,
   :mod:`blastfsi.mpm.relaxation`);
   new signal speed and q (ERRATA 000-10, :mod:`blastfsi.mpm.viscosity`).
   Void gas (:func:`void_gas`) keeps its internal energy (no stress, no work,
   no PIC share and so no blend heat) and sends no signal: its velocity alone
   enters the step.

Dimensions: positions and velocities always have 3 components. 1D is uniaxial
strain, 2D plane strain (d eps_zz = 0). The 2D axisymmetric r-z form (Sulsky &
Schreyer, CMAME 139 (1996) 409) maps r, z, theta onto Voigt x, y, z: particle
masses and volumes are those of the ring (V = 2 pi r * area), the hoop strain
rate is v_r / r at the particle, d eps_thth = dt sum_I N_I v_rI / r_p, and the
hoop stress enters the r-momentum as f_Ir -= V_p sigma_thth N_I / r_p. GIMP
on an r-z grid uses the Cartesian uGIMP weights. r-weighting them (Nairn &
Guilkey, IJNME 101 (2015) 127) does not make the hoop rate of a uniform
expansion v_r = a r exact near the axis: the error there comes from the
lumped nodal velocity sum_p m_p N_Ip v_p / m_I with ring masses m_p ~ r_p, which
over-weights the outer particles of each node's support (tests/test_mpm_gas.py).

Energy: ``point.energy`` is the specific internal energy (stress work from the
model plus q work); kinetic + internal is conserved up to the scheme's
dissipation (FLIP/MUSL and the grid's contact) when no external work is done.
``State.external_work`` accumulates the work of body force and traction
sum_p (m_p b + V_p t_p / h) . dx_p and that of the atmosphere, -p_ref dV with
V = sum_p m_p / rho_p; face conditions and prescribed velocities are not counted there:
``State.reaction`` sums their impulse m_I (v_new - v_free) on the nodes and its work on the mean of the
old and new nodal velocities (a wall's or a clamp's reaction), ``State.boundary_exchange`` that of a
nodal source's boundary force (:class:`NodalSource`).

Reference pressure (``Params.reference_pressure``, 0 by default): the model sits
in an atmosphere at p_ref. A constant isotropic stress has no divergence, so
taking it out of Eq. (19) changes nothing inside the continuum; at the model's
free faces it applies p_ref. In the discrete force it removes the particle
quadrature's error on p_ref: a gas at p_ref then exerts exactly no force however
its particles sit. The gas particles do not need it for a stable pressure force
where :func:`cell_centre_gradient` applies (not GIMP on an r-z grid).

``plastic_work`` accumulates sigma_eq d(eps_p)/rho per particle,
the plastic dissipation of a von Mises (J2) radial return (sigma' : d eps_p =
sigma_eq d eps_p at the returned state); for other yield surfaces it is the
same J2 measure.
"""
from __future__ import annotations

import dataclasses
import functools
import operator
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import xla
from blastfsi.constitutive import Model, PointState
from blastfsi.constitutive import tensor as T
from blastfsi.mpm import relaxation
from blastfsi.mpm.grid import Grid, apply_boundaries, inside
from blastfsi.mpm.particles import ParticleError, Particles, totals
from blastfsi.mpm.shape import SHAPES, Shape, expand, factors, linear_cell
from blastfsi.mpm.viscosity import DEFAULT_LINEAR, DEFAULT_QUADRATIC, bulk_viscosity, signal_speed
from blastfsi.xla import materialise, row_sum

VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))  # [xx, yy, zz, yz, xz, xy]


class MPMError(ValueError):
    """An invalid solver parameter (the message names it)."""


@dataclasses.dataclass(frozen=True)
class Config:
    """Static configuration (hashable; a change recompiles)."""

    grid: Grid
    shape: Shape
    models: tuple  # Model per material index
    prescribed: bool  # some particles have a prescribed velocity (adds the constraint channels)
    combined_scatter: bool  # one row scatter/gather of all channels, or one per channel and stencil node
    blend: bool = False  # some materials have a PIC share (Params.pic_fraction > 0; adds its channels)
    model_slots: tuple | None = None  # per model, the pool slots (start, stop) its particles can occupy
    #                                   (None: all): a model's update runs on those slots only
    relax: tuple = ()  # gas materials (fluid model) relaxed to a common pressure where they share nodes
    #                    (:mod:`blastfsi.mpm.relaxation`; empty: off)
    prescribed_slots: tuple | None = None  # the pool slots (start, stop) holding every particle that can be
    #                                        prescribed (None: all): the constraint channels are summed over these


class Params(NamedTuple):
    """Traced parameters (an ensemble may vary them)."""

    materials: tuple  # the params of each model, in the order of Config.models
    cfl: jnp.ndarray  # dt = cfl h / max signal speed, 0 < cfl <= 1
    q_quadratic: jnp.ndarray  # C_q of the bulk viscosity, >= 0
    q_linear: jnp.ndarray  # C_l of the bulk viscosity, >= 0
    gravity: jnp.ndarray  # (3,) body force per unit mass [m/s^2]
    pic_fraction: jnp.ndarray  # (n_models,) PIC share alpha of each material's G2P velocity, 0 <= alpha <= 1
    reference_pressure: jnp.ndarray  # p_ref [Pa] of the atmosphere around the model: Eq. (19) with sigma + p_ref I


class State(NamedTuple):
    particles: Particles
    external_work: jnp.ndarray  # work of body force and traction since the start [J]
    boundary_exchange: jnp.ndarray  # (dim + 1,) impulse and work of the nodal sources' boundary force since
    #                                 the start (NodalSource.boundary)
    reaction: jnp.ndarray  # (dim + 1,) impulse and work of the grid's face conditions and of the prescribed
    #                        particles (supports, impactors) on the nodes since the start: the reactions


class NodalSource(NamedTuple):
    """Contributions of something other than the particles to the nodal sums of one step: the
    Eulerian cell centres acting as particles on the interface nodes of a coupled run (000 Eqs. 37-39)."""

    mass: jnp.ndarray  # (num_nodes,) added to m_I, Eq. (37)
    momentum: jnp.ndarray  # (num_nodes, dim) added to p_I, Eq. (38), and to the re-mapped momentum, Eq. (26)
    force: jnp.ndarray  # (num_nodes, dim) added to f_I, Eq. (39)
    boundary: jnp.ndarray | None = None  # (num_nodes, dim) the part of ``force`` applied from outside the
    #   system (the traction of a flow-out face): its impulse dt f_I and work go to State.boundary_exchange (what
    #   face conditions or prescribed particles take away of it is in State.reaction). The whole impulse
    #   counts, as an Eulerian boundary flux does: on a node that also carries mirror mass (the gas outside)
    #   part of it moves that mass, and the same share of the particles' own force on the node, so for a
    #   uniform state the two cancel.


def make_config(grid: Grid, models, shape: str = "linear", prescribed: bool = False,
                combined_scatter: bool | None = None, model_slots=None, blend: bool = False,
                relax=(), prescribed_slots=None) -> Config:
    """Checked :class:`Config`; ``combined_scatter`` defaults to the backend's
    choice (:func:`blastfsi.xla.combined_scatter`, see :func:`particle_to_grid`); ``model_slots``: per model the
    pool slots (start, stop) its particles can occupy, or None for all (a coupled run keeps
    the structures in the first slots and the gas after them: each model then runs on its
    own part of the pool only); ``blend``: some material will have a PIC share (without it, Params.pic_fraction
    is not read and the step is pure FLIP); ``relax``: two or more material indices of fluid-model gases
    whose particles relax to a common pressure where they share nodes (:mod:`blastfsi.mpm.relaxation`);
    ``prescribed_slots``: the pool slots (start, stop) outside which no particle is ever prescribed (a coupled
    run's structures, in the first slots), or None for all."""
    if shape not in SHAPES:
        raise MPMError(f"numerics.shape: expected one of {tuple(SHAPES)}, got {shape!r}")
    models = tuple(models)
    if not models or not all(isinstance(m, Model) for m in models):
        raise MPMError(f"materials: expected one or more constitutive Models, got {models!r}")
    if combined_scatter is None:
        combined_scatter = xla.combined_scatter(grid.dim)
    if model_slots is not None:
        model_slots = tuple((int(a), int(b)) for a, b in model_slots)
        if len(model_slots) != len(models) or any(not 0 <= a <= b for a, b in model_slots):
            raise MPMError(f"model_slots: expected one (start, stop) with 0 <= start <= stop per model, "
                           f"got {model_slots!r}")
    if prescribed_slots is not None:
        prescribed_slots = (int(prescribed_slots[0]), int(prescribed_slots[1]))
        if not 0 <= prescribed_slots[0] <= prescribed_slots[1]:
            raise MPMError(f"prescribed_slots: expected (start, stop) with 0 <= start <= stop, "
                           f"got {prescribed_slots!r}")
    relax = tuple(int(k) for k in relax)
    if relax and (len(relax) < 2 or len(set(relax)) < len(relax)
                  or any(not 0 <= k < len(models) or models[k].name != "fluid" for k in relax)):
        raise MPMError(f"relax: expected two or more distinct material indices of fluid-model gases, got {relax!r}")
    return Config(grid=grid, shape=SHAPES[shape], models=models, prescribed=bool(prescribed),
                  combined_scatter=bool(combined_scatter), model_slots=model_slots, blend=bool(blend), relax=relax,
                  prescribed_slots=prescribed_slots)


def make_params(materials, *, cfl=0.5, q_quadratic=DEFAULT_QUADRATIC, q_linear=DEFAULT_LINEAR,
                gravity=(0.0, 0.0, 0.0), pic_fraction=0.0, reference_pressure=0.0, dtype=jnp.float64) -> Params:
    """Checked :class:`Params`; ``materials`` the model params in material order; ``pic_fraction`` one
    value for all materials or one per material; ``reference_pressure`` see :func:`step`."""
    pic = np.broadcast_to(np.asarray(pic_fraction, float), (len(materials),))
    if not np.all((pic >= 0.0) & (pic <= 1.0)):
        raise MPMError(f"numerics.pic_fraction: expected 0 <= alpha <= 1, got {pic_fraction!r}")
    if not 0.0 < cfl <= 1.0:
        raise MPMError(f"numerics.cfl: expected 0 < cfl <= 1, got {cfl!r}")
    for key, value in (("q_quadratic", q_quadratic), ("q_linear", q_linear)):
        if not (np.isfinite(value) and value >= 0.0):
            raise MPMError(f"numerics.{key}: expected a finite value >= 0, got {value!r}")
    if not (np.isfinite(reference_pressure) and reference_pressure >= 0.0):
        raise MPMError(f"numerics.reference_pressure: expected a finite pressure >= 0 Pa, got {reference_pressure!r}")
    g = np.zeros(3)
    g[:len(gravity)] = gravity
    if len(gravity) > 3 or not np.all(np.isfinite(g)):
        raise MPMError(f"gravity: expected up to 3 finite components, got {gravity!r}")
    return Params(materials=tuple(materials), cfl=jnp.asarray(cfl, dtype), q_quadratic=jnp.asarray(q_quadratic, dtype),
                  q_linear=jnp.asarray(q_linear, dtype), gravity=jnp.asarray(g, dtype),
                  pic_fraction=jnp.asarray(pic, dtype), reference_pressure=jnp.asarray(reference_pressure, dtype))


def _component(stress, i, j):
    """sigma_ij, (n,), from (n, 6) Voigt [xx, yy, zz, yz, xz, xy]."""
    return stress[:, VOIGT.index((min(i, j), max(i, j)))]


def _select(mask, a, b):
    return jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)


def _per_model(evaluate, material, out, config: Config, pool: bool):
    """``out`` with each model's particles replaced by ``evaluate(k, model, slots)`` (static loop over
    models). ``pool``: the arrays are the whole pool, and a model runs on its ``model_slots`` only;
    otherwise (a batch of new particles) every model runs on all of them."""
    n = material.shape[0]
    ranges = config.model_slots if pool and config.model_slots is not None else [(0, n)] * len(config.models)
    for k, (model, (a, b)) in enumerate(zip(config.models, ranges)):
        a, b = min(a, n), min(b, n)
        if a == b:
            continue
        sl = slice(a, b)
        new = evaluate(k, model, sl)
        mine = material[sl] == k
        out = jax.tree_util.tree_map(lambda o, v: o.at[sl].set(_select(mine, v, o[sl])), out, new)
    return out


def _material_update(ps: PointState, dstrain, dspin, dt, material, params: Params, config: Config) -> PointState:
    """Each material's model on its particles' slots, selected by material index (static loop)."""
    width = ps.history.shape[1]

    def update(k, model, sl):
        hk = model.history_size
        part = jax.tree_util.tree_map(lambda a: a[sl], ps)
        new = model.update(part._replace(history=part.history[:, :hk]), dstrain[sl], dspin[sl], dt,
                           params.materials[k])
        return new._replace(history=jnp.concatenate([new.history, part.history[:, hk:width]], axis=1))

    return _per_model(update, material, ps, config, pool=True)


def wave_speed(ps: PointState, material, params: Params, config: Config, pool: bool = False):
    """Signal speed c of every particle from its material's model (``pool``: see :func:`_per_model`)."""
    def speed(k, model, sl):
        part = jax.tree_util.tree_map(lambda a: a[sl], ps)
        return model.wave_speed(part._replace(history=part.history[:, :model.history_size]), params.materials[k])

    return _per_model(speed, material, jnp.zeros_like(ps.density), config, pool)


@functools.partial(jax.jit, static_argnames="config")
def initialize(particles: Particles, params: Params, config: Config) -> State:
    """Initial :class:`State`: the signal speeds of the active particles filled in (void gas: 0; compiled: each model's
    wave speed run eagerly made ~60 compilations of single operations in a he-slab-2d-mpm run)."""
    c = wave_speed(particles.point, particles.material, params, config)
    void = void_gas(particles, config, particles.point.density)
    if void is not None:  # void gas sends no signal (step)
        c = jnp.where(void, 0.0, c)
    p = particles._replace(wave_speed=jnp.where(particles.active, c, particles.wave_speed))
    return State(particles=p, external_work=jnp.zeros((), p.mass.dtype),
                 boundary_exchange=jnp.zeros(config.grid.dim + 1, p.mass.dtype),
                 reaction=jnp.zeros(config.grid.dim + 1, p.mass.dtype))


def _constrain(v, p_fixed, m_fixed, grid: Grid, prescribed: bool):
    """Face conditions on nodal velocities (num_nodes, dim), then each component of the nodes touched
    by particles prescribing it takes those particles' mass-weighted value (m_fixed, p_fixed: (num_nodes, dim),
    per component the mass and momentum of the particles that prescribe it)."""
    v = apply_boundaries(v, grid)
    if prescribed:
        has = m_fixed > 0.0
        v = jnp.where(has, p_fixed / jnp.where(has, m_fixed, 1.0), v)
    return v


def particle_to_grid(idx, channels, num_nodes: int, combined: bool):
    """sum_p over the stencil of each (S, n) channel -> (num_nodes, C).

    ``combined``: one scatter of the stacked channels (rows of C values), the
    form of GPUs and of 1D and 2D grids on the CPU. Otherwise scalar scatters
    per channel, for 3D on the CPU, where XLA:CPU scatters and gathers rows with
    a generic per-element loop (the 3D Johnson-Cook step 1.15x faster with
    scalar ones; :func:`blastfsi.xla.combined_scatter` gives the measurements):
    a channel is added one stencil node at a time (S scatters of n values,
    each reading a row of the channel where it is computed, in the same order
    of additions as one scatter of all S n values: bit for bit the same sums).
    """
    dtype = channels[0].dtype
    if combined:  # (indexed by the (S, n) stencil itself, not a flattened copy: a pool split over devices along
        #          n stays split, and each device's partial sums are added across them; flattening S n made
        #          the partitioner gather the whole pool's rows)
        return jnp.zeros((num_nodes, len(channels)), dtype).at[idx].add(jnp.stack(channels, axis=-1))

    def scatter(c):
        acc = jnp.zeros(num_nodes, dtype)
        for s in range(c.shape[0]):
            acc = acc.at[idx[s]].add(c[s])
        return acc
    return jnp.stack([scatter(c) for c in channels], axis=1)


def stencil_sum(a):
    """Sum over the stencil axis of an (S, n) array, as S - 1 elementwise adds (XLA:CPU runs
    them fused and vectorised; its reduction over a short leading axis was measured ~5x slower)."""
    return functools.reduce(operator.add, [a[s] for s in range(a.shape[0])])


def grid_to_particle(idx, w, table, combined: bool):
    """sum_I N_Ip table_Ik for every column k of the nodal (num_nodes, K) table -> K arrays (n,)."""
    return [stencil_sum(w * column) for column in gather_columns(idx, table, combined)]


def gather_columns(idx, table, combined: bool):
    """Nodal columns at every particle's stencil nodes, K arrays (S, n)."""
    if combined:
        gathered = table[idx]
        return [gathered[:, :, k] for k in range(table.shape[1])]
    return [table[:, k][idx] for k in range(table.shape[1])]


def _tensor(entries):
    """(n, 3, 3) from a dict {(i, j): (n,)} of the non-zero entries."""
    zero = jnp.zeros_like(next(iter(entries.values())))
    return jnp.stack([jnp.stack([entries.get((i, j), zero) for j in range(3)], -1) for i in range(3)], -2)


def _pad3(columns):
    """(n, 3) from up to 3 (n,) columns, zero-padded."""
    zero = jnp.zeros_like(columns[0])
    return jnp.stack(list(columns) + [zero] * (3 - len(columns)), axis=1)


def materialised_stencil(P: Particles, grid: Grid, shape: Shape):
    """:func:`stencil` of the active particles (zero weights for inactive ones).

    The per-direction factors (k values per particle and direction) are
    materialised (:func:`blastfsi.xla.materialise`), not recomputed in each of the ~20
    per-channel fusions that read them; their tensor products stay cheap
    enough to be fused into the consumers.
    """
    def compute(p):
        per_dim = factors(p.x, p.half_size, grid, shape)
        (node, N, dN), rest = per_dim[0], per_dim[1:]
        return ((node, jnp.where(p.active, N, 0.0), jnp.where(p.active, dN, 0.0)),) + rest

    return expand(materialise(compute, P, jnp.any(P.active)))


VOID_DENSITY = 1.0e-4  # [kg/m^3] below it a gas particle is void (:func:`void_gas`)


def void_gas(P: Particles, config: Config, density):
    """The active gas (fluid-model) particles whose ``density`` is below VOID_DENSITY, or None without gas.

    A void particle is kept (mass, momentum and internal energy, so every budget still closes) but exerts no
    stress, does no work, takes no PIC share of its velocity update (so no blend heat) and sends no signal:
    its velocity alone enters the step. The blend heat is kinetic energy per unit mass, however thin the gas:
    with it, void particles in the near vacuum that opens between charge and plate late in steel-plate-blast
    reached 1e10-5e13 J/kg. Why void at all: at the edge of an
    expanding products cloud a few particles reach 1e-8 to 3e-5 kg/m^3 with |v| + c of 10-50 km/s and set a
    step 1.5-3x below the structure's (steel-plate-blast). Such gas is vacuum to the problem: below 1e-4 kg/m^3
    (under 1e-4 of sea-level air's 1.225 kg/m^3), p = (gamma - 1) rho e stays under 1 kPa
    (1 % of an atmosphere) for any internal energy below 2.5e7 J/kg, over five times TNT's heat of detonation
    (4.5e6 J/kg, Dobratz & Crawford, LLNL Explosives Handbook, UCRL-52997, 1985), and its momentum
    and energy are as small beside the resolved gas around it. A void particle that is compressed again
    above the floor rejoins with the internal energy it kept (no work is booked while void)."""
    gas = gas_particles(P, config)
    return None if gas is None else gas & P.active & (density < VOID_DENSITY)


def gas_particles(P: Particles, config: Config):
    """(n,) bool: the particles of a fluid-model material (gases, detonation products); None without any."""
    fluids = relaxation.fluid_materials(config.models)
    return functools.reduce(operator.or_, [P.material == k for k in fluids]) if fluids else None


def uses_cell_centre_gradient(config: Config) -> bool:
    """Whether :func:`cell_centre_gradient` applies: some gas material on a 2D/3D Cartesian grid, or on an
    r-z grid with linear shape functions (there without the cell's volume normalisation)."""
    cartesian = not config.grid.axisymmetric
    return (config.grid.dim > 1 and bool(relaxation.fluid_materials(config.models))
            and (cartesian or config.shape.name == "linear"))


def cell_centre_gradient(P: Particles, grid: Grid, config: Config, w, grad, r, vol):
    """The gas particles' (fluid models') shape-function gradient, weight and radius of the internal force
    (Eq. 19, and the r-z hoop term) and of the strain increment (Eqs. 27-28) in 2D/3D: those of the centre
    x_c of the particle's cell, on the cell's 2^d nodes within the particle's stencil (N = 2^-d, grad N = the
    bilinear / trilinear one at x_c), whatever the shape functions of its mass and momentum; and ``fill``,
    the factor min(1, V_c / sum_{q in c} V_q) (all particles whose centre lies in the cell; V_c the cell's
    volume h^d) that scales the gas particle's quadrature weight V_p in Eq. (19)
    and its strain increment alike. Returns (grad, w_hoop, r_hoop, fill); solids keep theirs (fill 1).

    Applies on Cartesian grids, whatever the shape functions, and on r-z grids with linear shape functions
    only, there with fill = None (the particles' own V_p). On an r-z grid a cfdmp box's gas at rest became
    unstable with it (air at 1 bar, 16 x 16 cells of 1 mm, the box on the axis: ~100 m/s after 1500 steps
    with GIMP, with or without the fill; an ``mpm`` r-z box with slip walls stayed at rest): not traced, so
    r-z GIMP gas keeps its own gradient and the slow growth of the quadrature's negative stiffness.

    Why. About a gas at rest at pressure p (stress -p I; bulk modulus K = rho c^2; displacement u, the
    particles moving with the grid), the Eq. (19) force f_I = sum_p V_p p_p grad N_I(x_p) linearises to

        delta f_I = -sum_p V_p (K - p) (div u)_p grad N_I(x_p)  +  p sum_p V_p [grad grad N_I](x_p) u_p,

    the first term from the particle's pressure and volume (Eq. 29), the second from the particle moving
    through the position-dependent gradient. In the continuum the second integrates by parts to
    +p int (div u) grad N_I and the stiffness is K (div u)^2; the particle quadrature does not integrate it
    by parts exactly (the bilinear gradient jumps at cell faces; uGIMP's particle domains do not deform), and
    what is left is indefinite: the uniform pressure has a negative stiffness, growth at a rate up to
    sqrt(p / rho) / h per unit time whatever dt (air at 1 bar, 1 mm cells: 1.31 per step at cfl 0.5 with
    linear shape functions, 1.05 with GIMP, ~1.0095 in a cfdmp box; docs/cfdmp.md).

    (i) The cell-centre gradient (the cell's mean dilatation: Nagtegaal, Parks & Rice, CMAME 4 (1974) 153;
    Hughes, IJNME 15 (1980) 1413, B-bar; FLIP's cell-centred pressure, Brackbill & Ruppel, JCP 65 (1986)
    314) does not depend on where the particles sit in their cells: the second term is gone. (ii) With V_p
    alone the first would be sum_c (sum_{p in c} V_p) (K - p) (div u(x_c))^2, >= 0 for K >= p (ideal gas:
    K = gamma p), but particles that expand in place overfill their fixed cell and sub-cell sound ran at
    c sqrt(1 - p / K) = 0.53 c for air. The cell's force is the integral over the cell, so an overfilled
    cell's weights are normalised to its volume, sum_{p in c} fill V_p = V_c, which does not vary with the
    particles' expansion: stiffness K there. An underfilled cell (particles compressed in place, a free
    surface, a lone particle) keeps V_p: normalised up it would stiffen its particles by the factor
    V_c / sum V_q (their signal speed by as much, beyond the CFL step; steel-plate-blast stopped at 39 us in
    the reflected shock in front of the plate). So sub-cell sound is at K when expanding, K - p when
    compressing in place: period 1.22 x 2 L / c for an air column in 2D, linear or GIMP (1.86 / 1.00 with
    V_p and the cell-centre / the particle's GIMP gradient; 1.00 with ``reference_pressure`` at the
    ambient, which takes p out of K - p). (iii) Force and volume change use the same gradient and weight, so
    the pressure's power on the nodal velocities, sum_p fill V_p p_p div v(x_c), is the work each particle's
    energy update books (up to the MUSL re-map, as before): energy stays conserved. A uniform gas at rest
    whose particles sit symmetrically in their cells has the same nodal forces as with its own gradients.
    In r-z the hoop term's N_I / r is taken at the cell centre too (N_I(x_c) = 1/4, r_c).
    """
    d, h, shape = grid.dim, grid.cell_size, config.shape
    gas = gas_particles(P, config) & P.active
    per_dim, cell = [], []
    for j in range(d):  # the cell's nodes within the particle's stencil: N = 1/2, dN/dx = -+1/h there, else 0
        xi = (P.x[:, j] - grid.origin[j]) / h
        first = shape.basis(xi, P.half_size[:, j] / h, grid.cells[j])[0]
        c = linear_cell(xi, grid.cells[j]).astype(first.dtype)
        cell.append(c)
        a = jnp.arange(shape.nodes_per_dim, dtype=first.dtype)[:, None] - (c - first)[None, :]
        per_dim.append((a, jnp.where((a == 0) | (a == 1), 0.5, 0.0),  # (the node indices are not used)
                        jnp.where(a == 0, -1.0 / h, jnp.where(a == 1, 1.0 / h, 0.0))))
    _, w_c, grad_c = expand(per_dim)
    grad = tuple(jnp.where(gas, grad_c[j], grad[j]) for j in range(d))
    if not grid.axisymmetric:
        flat = functools.reduce(lambda acc, j: acc * grid.cells[j] + cell[j], range(1, d), cell[0])
        filled = jax.ops.segment_sum(vol, flat, num_segments=int(np.prod(grid.cells)))[flat]  # sum_{q in c} V_q
        return grad, w, r, jnp.where(gas, jnp.minimum(h ** d / jnp.where(gas, filled, 1.0), 1.0), 1.0)
    r_c = grid.origin[0] + (cell[0] + 0.5) * h
    return grad, jnp.where(gas, w_c, w), jnp.where(gas, r_c, r), None


def step(state: State, dt, params: Params, config: Config, source: NodalSource | None = None) -> State:
    """One MUSL step of length dt (module docstring). Pure; jit with ``config`` static.
    ``source``: nodal mass, momentum and force from outside the particles (a coupled run), or None; or a
    function ``source(particles, idx, w) -> NodalSource`` called with this step's stencil (a source that
    depends on the particles' own nodal sums then needs no stencil of its own).

    Grid vectors carry the grid's ``dim`` components (the padded particle
    components stay zero); per-particle stencil arrays are kept component by
    component, (S, n) each, since small trailing axes vectorise badly on CPU.
    """
    P, grid = state.particles, config.grid
    d, n_nodes, combined = grid.dim, grid.num_nodes, config.combined_scatter
    act = P.active
    idx, w, grad = materialised_stencil(P, grid, config.shape)
    m = jnp.where(act, P.mass, 0.0)
    vol = jnp.where(act, P.mass / P.point.density, 0.0)  # m_p / rho_p of Eq. (19)
    r = jnp.where(act, P.x[:, 0], 1.0)  # radius (axisymmetric)
    w_hoop, r_hoop, fill = w, r, None
    if uses_cell_centre_gradient(config):  # gas in 2D/3D: a stable pressure force
        grad, w_hoop, r_hoop, fill = cell_centre_gradient(P, grid, config, w, grad, r, vol)
    stress = P.point.stress

    def sigma(i, j):  # q raises the pressure (ERRATA 000-10); the atmosphere's p_ref is taken out
        return _component(stress, i, j) + ((params.reference_pressure - P.q) if i == j else 0.0)

    # Eq. (19): f_iI = -sum_p V_p sigma_ij dN_I/dx_j ; Eq. (20): + N_I V_p t_i / h
    vol_f = vol if fill is None else vol * fill  # the stress's quadrature weight
    void = void_gas(P, config, P.point.density)
    if void is not None:  # void gas exerts no stress
        vol_f = jnp.where(void, 0.0, vol_f)
    forces = []
    for i in range(d):
        f = (vol * P.surface_load[:, i]) * w
        for j in range(d):
            f = f - (vol_f * sigma(i, j)) * grad[j]
        if grid.axisymmetric and i == 0:
            f = f - (vol_f * sigma(2, 2) / r_hoop) * w_hoop  # hoop stress in the r-momentum
        forces.append(f)
    mw = m * w
    channels = [mw] + [mw * P.v[:, i] for i in range(d)] + forces
    if config.prescribed and config.prescribed_slots is None:  # the constraint channels of the whole pool
        channels += _prescribed_channels(P, mw, slice(None), d)
    blend_at = len(channels)
    if config.blend:  # the alpha-weighted nodal mass and momentum of the blend heat (step 3)
        alpha = params.pic_fraction[jnp.clip(P.material, 0, len(config.models) - 1)]
        free = act & ~jnp.any(P.prescribed, axis=1) if config.prescribed else act
        if void is not None:  # void gas takes no PIC share: its internal energy is not heated (docstring)
            free = free & ~void
        alpha = jnp.where(free, alpha, 0.0)
        amw = alpha * mw
        channels += [amw] + [amw * P.v[:, i] for i in range(d)]
    nodal = particle_to_grid(idx, channels, n_nodes, combined)
    m_I, p_I, f_I = nodal[:, 0], nodal[:, 1:1 + d], nodal[:, 1 + d:1 + 2 * d]  # Eqs. (21), (18), (19)
    if callable(source):  # evaluated once, kept in memory: fused into the step, XLA:CPU took 5.7 ms more a step of
        #                   steel-plate-blast at 0.3 ms (19.2 against 13.5 ms, with the source's own 2.2 ms)
        source_of = source
        source = materialise(lambda a: source_of(*a), (P, idx, w))
    if source is not None:  # Eqs. (37)-(39)
        m_I, p_I, f_I = m_I + source.mass, p_I + source.momentum, f_I + source.force
    f_I = f_I + m_I[:, None] * params.gravity[:d]  # Eq. (23), body force of Eq. (20)
    m_fix, p_fix = _prescribed_sums(P, idx, mw, nodal, config)
    has = m_I > 0.0
    inv_m = jnp.where(has, 1.0 / jnp.where(has, m_I, 1.0), 0.0)[:, None]
    v_old = p_I * inv_m
    v_free = (p_I + dt * f_I) * inv_m  # Eq. (22)
    v_new = _constrain(v_free, p_fix, m_fix, grid, config.prescribed)
    reaction = state.reaction + _impulse_and_work(m_I[:, None] * (v_new - v_free), v_old, v_new)
    exchange = state.boundary_exchange
    if source is not None and source.boundary is not None:
        exchange = exchange + _impulse_and_work(dt * source.boundary, v_old, v_new)
    # G2P: Eq. (24), and Eq. (25) with the updated nodal velocity (ERRATA 000-5)
    table = [v_new - v_old, v_new]
    if config.blend:
        m_a = nodal[:, blend_at]
        m_a = jnp.where(m_a > 0.0, m_a, 1.0)[:, None]  # (nodes without blended mass: any divisor, nothing to share)
        u_I = nodal[:, blend_at + 1:blend_at + 1 + d] / m_a
        table.append(row_sum(v_new * u_I)[:, None])
    moved = grid_to_particle(idx, w, jnp.concatenate(table, axis=1), combined)
    increment, pic = _pad3(moved[:d]), _pad3(moved[d:2 * d])  # S (n - g), S n
    v_flip = P.v + increment
    if config.blend:  # step 3: v_p = v_FLIP - alpha delta, and the heat c_p
        old_grid = pic - increment  # S g
        delta = P.v - old_grid
        v_p = jnp.where(act[:, None], v_flip - alpha[:, None] * delta, P.v)
        blend_heat = (alpha * (moved[2 * d] - row_sum(pic * old_grid))
                      + (alpha - 0.5 * alpha ** 2) * row_sum(delta * delta))
    else:
        v_p, blend_heat = jnp.where(act[:, None], v_flip, P.v), 0.0
    x_p = jnp.where(act[:, None], P.x + dt * pic, P.x)
    if config.prescribed:
        v_p = jnp.where(P.prescribed, P.prescribed_velocity, v_p)
        x_p = jnp.where(P.prescribed & act[:, None], P.x + dt * P.prescribed_velocity, x_p)
    # Eq. (26): re-map of the updated particle momentum; with the blend, each node's blend heat too (step 3)
    remap = [mw * v_p[:, i] for i in range(d)] + ([mw * blend_heat] if config.blend else [])
    p2 = particle_to_grid(idx, remap, n_nodes, combined)
    p2, heat_I = p2[:, :d], p2[:, d:]
    if source is not None:
        p2 = p2 + source.momentum
    v2_I = _constrain(p2 * inv_m, p_fix, m_fix, grid, config.prescribed)
    # Eqs. (27)-(28) from the velocity gradient L_ij = sum_I v_iI dN_I/dx_j (r-z: and the hoop rate v_r / r)
    pairs = [(i, j) for i in range(d) for j in range(d)]

    def velocity_gradient(a):  # (rows of L, and with the blend the heat share sum_I N_Ip H_I / A_I last)
        table, idx, w, grad, w_hoop, r_hoop = a
        v2 = gather_columns(idx, table, combined)
        rows = [stencil_sum(v2[i] * grad[j]) for i, j in pairs]
        rows += [stencil_sum(w_hoop * v2[0]) / r_hoop] if grid.axisymmetric else []
        return jnp.stack(rows + ([stencil_sum(w * v2[d])] if config.blend else []))

    table = v2_I
    if config.blend:  # H_I / A_I: the node's blend heat per unit alpha-weighted mass
        table = jnp.concatenate([v2_I, heat_I / m_a], axis=1)
    # rows kept in memory (materialise): fused into the (n, 3, 3) increments, XLA:CPU gathered and summed
    # each of their elements on its own (the 3D Johnson-Cook step ~1.3x slower, measured)
    rows = materialise(velocity_gradient, (table, idx, w, grad, w_hoop, r_hoop))
    if config.blend:  # step 3: the particle's share of its nodes' blend heat
        rows, blend_heat = rows[:-1], alpha * rows[-1]
    if fill is not None:  # the gas particle's share of its cell's volume change (cell_centre_gradient)
        rows = rows * fill
    L = {ij: rows[k] for k, ij in enumerate(pairs)}
    if grid.axisymmetric:
        L[2, 2] = rows[-1]
    sym = {(i, j): 0.5 * dt * (L[i, j] + L[j, i]) for i, j in L}
    skew = {(i, j): 0.5 * dt * (L[i, j] - L[j, i]) for i, j in L if i != j}
    dvol = sum(sym[i, i] for i in range(3) if (i, i) in sym)
    dstrain = _tensor(sym)
    dspin = _tensor(skew) if skew else jnp.zeros_like(dstrain)
    ps = P.point
    if config.relax:  # gases sharing nodes brought towards one pressure (compliance from the last step's c)
        relaxed = relaxation.relax(ps, m, P.material, P.wave_speed, idx, w, config.relax, n_nodes,
                                   scatter=lambda ch: particle_to_grid(idx, ch, n_nodes, combined),
                                   interpolate=lambda t: grid_to_particle(idx, w, t, combined))
        ps = ps._replace(density=relaxed[0], energy=relaxed[1])
    rho = ps.density / (1.0 + dvol)  # Eq. (29)
    # q work, -q dV per unit mass (Eq. 13 with p + q); the kinetic energy the PIC share takes heats the gas
    energy = ps.energy - P.q * dvol / ps.density
    # the blend heat is indefinite per particle (its first term; docstring step 3): it takes at most half the
    # particle's internal energy, what it declines stays with the particle (booked as the step's change)
    energy = energy + jnp.maximum(blend_heat, -relaxation.MAX_ENERGY_SHARE * jnp.maximum(energy, 0.0))
    if void is not None:  # void gas does no work (and takes no blend heat: alpha = 0)
        energy = jnp.where(void, ps.energy, energy)
    # the models read the increments many times: materialised, not recomputed from the gathers in each read
    # (measured, 3D Johnson-Cook: the step 1.25x faster)
    model_in = materialise(lambda a: a, (ps._replace(density=rho, energy=energy), dstrain, dspin), jnp.any(act))
    new = _material_update(*model_in, dt, P.material, params, config)
    c = wave_speed(new, P.material, params, config, pool=True)
    rate = dvol / dt
    q = bulk_viscosity(rho, c, rate, grid.cell_size, params.q_quadratic, params.q_linear)
    if void is not None:  # void now: no stress, and no signal but its velocity in the next step's CFL
        new = new._replace(stress=jnp.where(void[:, None], 0.0, new.stress), energy=jnp.where(void, energy, new.energy))
        void_next = void_gas(P, config, rho)
        c, q, rate = (jnp.where(void_next, 0.0, a) for a in (c, q, rate))
    d_plastic = new.plastic_strain - ps.plastic_strain
    plastic_work = P.plastic_work + T.von_mises(T.deviator(new.stress)) * d_plastic / rho
    point = jax.tree_util.tree_map(lambda a, b: _select(act, a, b), new, ps)
    particles = P._replace(
        x=x_p, v=v_p, point=point, q=jnp.where(act, q, P.q), vol_rate=jnp.where(act, rate, P.vol_rate),
        wave_speed=jnp.where(act, c, P.wave_speed), plastic_work=jnp.where(act, plastic_work, P.plastic_work))
    load = m[:, None] * params.gravity + vol[:, None] * P.surface_load
    # the atmosphere's work on the model, -p_ref dV, with dV the particles' volume change (Eq. 29)
    felt = act if void is None else act & ~void  # the volumes the atmosphere pushed on (void gas: none)
    expansion = jnp.sum(jnp.where(felt, m / point.density - vol, 0.0))
    work = jnp.sum(load * (x_p - P.x)) - params.reference_pressure * expansion
    return State(particles=particles, external_work=state.external_work + work, boundary_exchange=exchange,
                 reaction=reaction)


def _prescribed_channels(P: Particles, mw, slots, d: int):
    """Per velocity component, the (S, n) mass and momentum channels of the particles in ``slots`` prescribing it."""
    mwp = [jnp.where(P.prescribed[slots, i], mw[:, slots], 0.0) for i in range(d)]
    return mwp + [mwp[i] * P.prescribed_velocity[slots, i] for i in range(d)]


def _prescribed_sums(P: Particles, idx, mw, nodal, config: Config):
    """(m_fixed, p_fixed) of :func:`_constrain`, (num_nodes, dim) each, or (None, None) without prescribed
    particles. Over the whole pool they are columns of the step's first scatter (``nodal``, after the mass,
    momentum and force); with Config.prescribed_slots a scatter of those slots only: the other slots would add
    zeros, the same sums at the pool's cost (a coupled run's plate can be a few per cent of its pool:
    steel-plate-blast at 0.2 ms, its MPM step 1.20-1.28x and its whole coupled step 1.15x faster;
    benchmarks/constraint_sums.py)."""
    if not config.prescribed:
        return None, None
    d = config.grid.dim
    if config.prescribed_slots is None:
        return nodal[:, 1 + 2 * d:1 + 3 * d], nodal[:, 1 + 3 * d:1 + 4 * d]
    held = slice(*config.prescribed_slots)
    sums = particle_to_grid(idx[:, held], _prescribed_channels(P, mw, held, d), config.grid.num_nodes,
                            config.combined_scatter)
    return sums[:, :d], sums[:, d:]


def _impulse_and_work(impulse, v_old, v_new):
    """(dim + 1,) the sum of nodal impulses (num_nodes, dim) and their work on the mean of the old and new
    nodal velocities."""
    return jnp.concatenate([jnp.sum(impulse, axis=0), jnp.sum(impulse * 0.5 * (v_old + v_new))[None]])


def stable_dt(state: State, params: Params, config: Config):
    """CFL step dt = cfl h / max_p (|v_p| + a_p) over the active particles (inf for an empty pool), with the
    wave signal a_p = s_p + sqrt(s_p^2 + c_p^2) (s: viscous signal speed, :func:`signal_speed`). NaN when an
    active particle is non-physical (see :func:`first_fault`), so the reduction doubles as the fault check.

    A gas particle's wave signal is that of the gas and structure its nodes carry, not its own:
    a_p^2 = sum_I N_Ip A_I^2 with A_I^2 = sum_q N_Iq m_q a_q^2 / sum_q N_Iq m_q (:func:`mixture_signal`).
    The grid, not the particle, carries the waves: the stiffness that a particle's pressure adds to a node
    is V_p rho_p c_p^2 = m_p c_p^2 and the node's inertia is its whole lumped mass, so the node's highest
    frequency is set by the mass-weighted mean of c^2 of the particles it carries (the frozen sound speed
    of their mixture), which is the particle's own c where it is alone on its nodes. A light, hot gas
    particle in pressure equilibrium among heavier ones (air heated in a numerically diffused contact,
    its own c at 10-12 km/s in steel-plate-blast where the gas and the steel around it need 6.5 km/s) no
    longer sets the step. Solid particles keep their own signal."""
    P = state.particles
    signal = signal_speed(P.wave_speed, 0.0, P.vol_rate, config.grid.cell_size, params.q_quadratic,
                          params.q_linear)
    gas = gas_particles(P, config)
    if gas is not None:
        signal = jnp.where(gas, mixture_signal(P, signal, config), signal)
    fastest = jnp.max(jnp.where(P.active, jnp.sqrt(row_sum(P.v * P.v)) + signal, 0.0))
    dt = params.cfl * config.grid.cell_size / fastest
    return jnp.where(jnp.any(_bad(P, config.grid)), jnp.nan, dt)


def mixture_signal(P: Particles, signal, config: Config):
    """sqrt(sum_I N_Ip A_I^2) with A_I^2 the mass-weighted mean over its particles of the squared ``signal``
    at node I (the frozen sound speed of what the node carries; :func:`stable_dt`)."""
    grid = config.grid
    idx, w, _ = materialised_stencil(P, grid, config.shape)
    mw = jnp.where(P.active, P.mass, 0.0) * w
    squared = jnp.where(P.active, signal ** 2, 0.0)  # (a free slot's stale values stay out of the nodes)
    nodal = particle_to_grid(idx, [mw, mw * squared], grid.num_nodes, config.combined_scatter)
    mean = nodal[:, 1] / jnp.where(nodal[:, 0] > 0.0, nodal[:, 0], 1.0)
    return jnp.sqrt(jnp.maximum(grid_to_particle(idx, w, mean[:, None], config.combined_scatter)[0], 0.0))


def _bad(P: Particles, grid: Grid):
    ps = P.point
    finite = (jnp.all(jnp.isfinite(P.x), axis=1) & jnp.all(jnp.isfinite(P.v), axis=1)
              & jnp.all(jnp.isfinite(ps.stress), axis=1) & jnp.isfinite(ps.energy) & jnp.isfinite(ps.density))
    return P.active & ~(finite & (ps.density > 0.0) & inside(P.x, grid))


def first_fault(state: State, config: Config):
    """Index of the first active particle that is non-finite, has non-positive
    density or left the grid; -1 when all are healthy."""
    bad = _bad(state.particles, config.grid)
    return jnp.where(jnp.any(bad), jnp.argmax(bad), -1).astype(jnp.int32)


def check_particles(particles: Particles, config: Config):
    """Host-side check of a particle set against the configuration; raises
    :class:`~blastfsi.mpm.particles.ParticleError` naming the field and the particle."""
    grid = config.grid
    p = jax.tree_util.tree_map(np.asarray, particles)
    on = p.active
    x = p.x[on]

    def fail(field, k, why):
        raise ParticleError(f"particles.{field}: particle {int(np.flatnonzero(on)[k])} {why}")

    lo, hi = np.asarray(grid.origin), np.asarray(grid.upper)
    outside = np.any((x[:, :grid.dim] < lo) | (x[:, :grid.dim] > hi), axis=1)
    if outside.any():
        k = int(np.argmax(outside))
        fail("x", k, f"at {x[k, :grid.dim]} lies outside the grid box [{lo}, {hi}]")
    for field, values in (("x", x), ("v", p.v[on])):
        padded = np.any(values[:, grid.dim:] != 0.0, axis=1)
        if padded.any():
            fail(field, int(np.argmax(padded)), f"has a non-zero component beyond the grid's {grid.dim} directions")
    if grid.axisymmetric and np.any(x[:, 0] <= 0.0):
        fail("x", int(np.argmax(x[:, 0] <= 0.0)), "has radius <= 0 on an axisymmetric grid (expected r > 0)")
    for field, values in (("mass", p.mass[on]), ("point.density", p.point.density[on])):
        if np.any(~(values > 0.0)):
            k = int(np.argmax(~(values > 0.0)))
            fail(field, k, f"has {field} {values[k]} (expected > 0)")
    material = p.material[on]
    if np.any((material < 0) | (material >= len(config.models))):
        k = int(np.argmax((material < 0) | (material >= len(config.models))))
        fail("material", k, f"has index {material[k]}, expected 0 .. {len(config.models) - 1}")
    if config.shape.nodes_per_dim == 3:
        half = p.half_size[on][:, :grid.dim]
        bad = np.any(~((half > 0.0) & (half <= 0.5 * grid.cell_size * (1 + 1e-12))), axis=1)
        if bad.any():
            fail("half_size", int(np.argmax(bad)), f"has GIMP half-size {half[np.argmax(bad)]}, expected "
                 f"0 < l <= h/2 = {0.5 * grid.cell_size}")
    needed = max(m.history_size for m in config.models)
    if p.point.history.shape[1] < needed:
        raise ParticleError(f"particles.point.history: {p.point.history.shape[1]} columns, the materials need "
                            f"{needed}")


def energies(state: State):
    """Kinetic, internal (incl. plastic), plastic energy and external work [J]."""
    t = totals(state.particles)
    return {"kinetic": t.kinetic, "internal": t.internal, "plastic": t.plastic, "external_work": state.external_work}
