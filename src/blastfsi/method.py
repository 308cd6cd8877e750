"""The face every solution method shows the driver, and the registry of methods.

A method (``lagrangian1d``, ``euler``, ``mpm``, ``cfdmp``) is a package
``blastfsi.<name>`` whose module ``blastfsi.<name>.method`` builds an object
with the :class:`Method` face (a :class:`Solver`: build and step; and a :class:`Reporter`: history columns,
snapshots, summary, fault location, plots; optionally a :class:`GrowingPool`) and calls :func:`register` on
it. The driver
(:mod:`blastfsi.simulation`), the schema (:mod:`blastfsi.scenario`) and the
Python API import nothing else of a method; :func:`get` imports
``blastfsi.<name>.method`` the first time the name is asked for.

Life of a run, as the driver sees it (every run is an ensemble of members of
one method, advanced together by ``jit(vmap(advance))``):

1. ``sc = scenario_model.model_validate(data)`` (through :func:`blastfsi.scenario.parse`);
2. per member, host side: ``setup = build(sc)``, ``state = initial_state(setup, sc, n_samples, dtype)``,
   ``params(setup, dtype)``, ``static(setup, sc)``; states and params are stacked
   along a new leading axis, the static configuration must be equal for all members;
3. ``advance(state, params, static, t_stop, max_steps, sample_interval, dt_floor_fraction)``
   in compiled chunks, written with :func:`blastfsi.timeloop.run_until` (a static with ``member_devices``
   n > 1 spreads the members over n devices, :func:`compiled_advance`);
4. on the host between chunks and at the end, per member (arrays without the
   ensemble axis): ``snapshot``, ``locate_fault`` (after a fault), ``summary``; the pool of a
   :class:`GrowingPool` is enlarged when full and packed into fewer slots when mostly empty (``pool_needed``,
   ``resize``), and the loop compiled again.
"""
from __future__ import annotations

import importlib
import time as wallclock
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Hashable, NamedTuple, Protocol, Sequence, Union

import jax
import numpy as np
from pydantic import BaseModel

from blastfsi import runtime, xla
from blastfsi.timeloop import CLOCK_FIELDS

if TYPE_CHECKING:  # annotations only: blastfsi.scenario imports this registry (parse looks a method's model up)
    from blastfsi.scenario import ScenarioBase

VECTOR_FIELDS = ("velocity",)  # fields with a trailing axis of length ndim in Snapshot.as_fields


class Setup(Protocol):
    """What :meth:`Method.build` returns: host-side (NumPy) initial data of one member, typed as the method
    likes; the driver reads only its number of cells."""

    @property
    def cells(self) -> int:  # total number of cells (zones) of the mesh
        ...


# ---------------------------------------------------------------------------------------------------------------
# Snapshots: the mesh and fields of one member at one time, as written to fields/ and read back.
# Each kind has a writer in blastfsi.io (results.py: polyline; fields.py: grid, particles, coupled = grid plus
# particles) and converts itself to the Python API's field dict with as_fields(): coordinates x (y, z) with the
# fields' shape, scalar fields as they are, VECTOR_FIELDS with a trailing axis of length ndim.
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Polyline:
    """1D moving mesh: ``nodes`` (N+1,) positions on the x axis, N segments
    (zones) between them; ``node_fields`` (N+1,) and ``cell_fields`` (N,).

    ``as_fields``: ``x`` the zone centres; cell fields as they are; node fields
    averaged to the zone centres (velocity as (N, 1)), and the node values
    themselves as ``node_x`` and ``node_<name>``.
    """

    kind: ClassVar[str] = "polyline"
    nodes: np.ndarray
    node_fields: dict[str, np.ndarray] = field(default_factory=dict)
    cell_fields: dict[str, np.ndarray] = field(default_factory=dict)

    def as_fields(self) -> dict[str, np.ndarray]:
        out = {"x": 0.5 * (self.nodes[1:] + self.nodes[:-1]), **self.cell_fields, "node_x": self.nodes}
        for name, values in self.node_fields.items():
            centred = 0.5 * (values[1:] + values[:-1])
            out[name] = centred[:, None] if name in VECTOR_FIELDS else centred
            out[f"node_{name}"] = values
        return out


@dataclass(frozen=True)
class Grid:
    """Cell-centred fields on a rectilinear grid of 1, 2 or 3 dimensions.

    ``edges[i]``: the n_i + 1 cell-edge coordinates along axis i (x, y, z; for
    axisymmetric r-z grids x = r, y = z); ``cell_fields`` of shape
    (n_x[, n_y[, n_z]]) for scalars, with a trailing axis of length ndim for
    VECTOR_FIELDS. ``as_fields``: ``x`` (``y``, ``z``) the cell centres
    broadcast to the fields' shape (``indexing="ij"``), and the cell fields.
    """

    kind: ClassVar[str] = "grid"
    edges: tuple[np.ndarray, ...]
    cell_fields: dict[str, np.ndarray] = field(default_factory=dict)

    def as_fields(self) -> dict[str, np.ndarray]:
        centres = [0.5 * (e[1:] + e[:-1]) for e in self.edges]
        coords = np.meshgrid(*centres, indexing="ij")
        return {**dict(zip("xyz", coords)), **self.cell_fields}


@dataclass(frozen=True)
class Particles:
    """Point cloud (active particles only): ``positions`` (P, ndim), ``point_fields``
    (P,) or (P, ndim) for VECTOR_FIELDS. ``as_fields``: ``x`` (``y``, ``z``) (P,), and the point fields."""

    kind: ClassVar[str] = "particles"
    positions: np.ndarray
    point_fields: dict[str, np.ndarray] = field(default_factory=dict)

    def as_fields(self) -> dict[str, np.ndarray]:
        return {**{a: self.positions[:, i] for i, a in enumerate("xyz"[:self.positions.shape[1]])},
                **self.point_fields}


@dataclass(frozen=True)
class Coupled:
    """An Eulerian grid and a particle cloud of the same member at the same time (cfdmp: grid + MPM).

    ``as_fields``: the grid's ``as_fields`` entries, and every entry of the particles' ``as_fields``
    prefixed ``particle_`` (``particle_x``, ``particle_pressure``, ...).
    """

    kind: ClassVar[str] = "coupled"
    grid: Grid
    particles: Particles

    def as_fields(self) -> dict[str, np.ndarray]:
        return {**self.grid.as_fields(), **{f"particle_{name}": v for name, v in self.particles.as_fields().items()}}


Snapshot = Union[Polyline, Grid, Particles, Coupled]


class Solver(Protocol):
    """What solves: a method's scenario model, its builder and its compiled step. ``state`` is a NamedTuple
    of arrays that carries the clock fields of :mod:`blastfsi.timeloop` (``CLOCK_FIELDS``, made with
    ``timeloop.clock``) besides its own; checkpoints save and restore it by field name."""

    name: str
    scenario_model: type[ScenarioBase]  # its pydantic model, with method: Literal[name]

    def build(self, sc) -> Setup:
        """Host-side initial data of one member; raises ScenarioError for inconsistent input."""

    def initial_state(self, setup: Setup, sc, n_samples: int, dtype) -> NamedTuple:
        """The initial state (with ``n_samples`` history rows of ``len(history_columns)``)."""

    def params(self, setup: Setup, dtype) -> Any:
        """Pytree of arrays the step reads (traced: may differ between members)."""

    def static(self, setup: Setup, sc) -> Hashable:
        """Hashable configuration fixed at compile time; must be equal for all members."""

    def advance(self, state, params, static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        """Pure, jittable, one member: ``timeloop.run_until`` with the method's step."""


class Reporter(Protocol):
    """What reports: the history's columns and the host-side views of one member's state (NumPy arrays)."""

    def history_columns(self, setup: Setup, sc) -> Sequence[tuple[str, str]]:
        """(name, SI unit) of each history column; first ``time``; gauge columns named
        ``gauge<k>_<quantity>`` (k the index in output.gauges)."""

    def snapshot(self, state, setup: Setup) -> Snapshot:
        """Mesh and fields of one member (host side)."""

    def summary(self, sc, setup: Setup, history: dict, state) -> dict:
        """The method's JSON-able summary quantities of one member (the driver adds
        time, steps, cells, wall_time, compile_time, loop_time, output_time; pool_growths for a
        :class:`GrowingPool`)."""

    def locate_fault(self, state, setup: Setup) -> str:
        """Where a faulted (or step-collapsed) member fails, e.g. 'zone 12 at x = 0.1 m'."""

    def plots(self, folder: Path, sc, setups: list, histories: list[dict], members: list[dict],
              finals: list) -> None:
        """Write the method's PNG plots into ``folder`` from each member's setup, history
        and final snapshot (``finals``, as returned by :meth:`snapshot`)."""


class Method(Solver, Reporter, Protocol):
    """The face of a method: a :class:`Solver` and a :class:`Reporter`."""


@typing.runtime_checkable
class GrowingPool(Protocol):
    """An optional capability: a particle pool that may fill up (the method's advance passes ``pool_full`` to
    ``timeloop.run_until``) or empty. The driver then enlarges the pool, or packs a mostly empty one into fewer
    slots, and goes on (:func:`blastfsi.simulation._resized`, :func:`blastfsi.simulation.shrunk_capacity`)."""

    pool_leaf: str  # name of a state leaf whose length (axis 0 of a member) is the pool's capacity

    def pool_needed(self, state, setup: Setup) -> int:
        """The slots one member's (host) state needs."""

    def resize(self, setup: Setup, state, capacity: int):
        """(setup, state) of one member in a pool of ``capacity`` slots: more than now (the new slots empty) or
        fewer, but at least ``pool_needed`` (the particles in use packed into them, every reference to a slot
        renumbered); None when the pool is fixed (the scenario set its size): a full pool then stops the run
        with the pool-full fault."""


SOLVER_FACE = ("name", "scenario_model", "build", "initial_state", "params", "static", "advance")
REPORTER_FACE = ("history_columns", "snapshot", "summary", "locate_fault", "plots")
FACE = SOLVER_FACE + REPORTER_FACE
POOL_FACE = ("pool_leaf", "pool_needed", "resize")
METHODS: dict[str, Method] = {}
_PACKAGE = Path(__file__).parent


def register(method: Method) -> Method:
    """Add a method (and with it its scenario model) to the registry."""
    missing = [n for n in FACE if not hasattr(method, n)]
    if missing:
        raise TypeError(f"method {getattr(method, 'name', method)!r} lacks {missing} of the Method face")
    pool = [n for n in POOL_FACE if hasattr(method, n)]
    if pool and len(pool) < len(POOL_FACE):
        raise TypeError(f"method {method.name!r} has {pool} of the GrowingPool capability but lacks "
                        f"{[n for n in POOL_FACE if n not in pool]}")
    if not (isinstance(method.scenario_model, type) and issubclass(method.scenario_model, BaseModel)
            and "method" in method.scenario_model.model_fields):
        raise TypeError(f"method {method.name!r}: scenario_model must be a pydantic model with a `method` key, "
                        "derived from blastfsi.scenario.ScenarioBase (checked when a scenario is parsed)")
    tags = typing.get_args(method.scenario_model.model_fields["method"].annotation)
    if tags != (method.name,):
        raise TypeError(f"method {method.name!r}: its scenario model's `method` key must be "
                        f"Literal[{method.name!r}], not Literal{list(tags)}")
    METHODS[method.name] = method
    return method


def available() -> list[str]:
    """Registered methods and the ``blastfsi.<name>.method`` modules that would register one."""
    found = {p.parent.name for p in _PACKAGE.glob("*/method.py")}
    return sorted(found | set(METHODS))


def get(name: str) -> Method:
    """The method registered as ``name``, importing ``blastfsi.<name>.method`` when needed.
    KeyError (with the available names) for an unknown method."""
    if name not in METHODS and name.isidentifier() and (_PACKAGE / name / "method.py").is_file():
        importlib.import_module(f"blastfsi.{name}.method")
    if name not in METHODS:
        raise KeyError(f"unknown method {name!r}; available: {', '.join(available())}")
    return METHODS[name]


def check_state(state) -> None:
    """TypeError unless ``state`` is a NamedTuple carrying the timeloop clock fields."""
    fields = getattr(state, "_fields", ())
    missing = [f for f in CLOCK_FIELDS if f not in fields]
    if missing:
        raise TypeError(f"a method state must be a NamedTuple with the clock fields {CLOCK_FIELDS}; missing {missing}")


def member_devices(static) -> int:
    """The devices a method's static configuration spreads an ensemble's members over: its ``member_devices``
    (lagrangian1d's numerics.devices), else 1 (a method that splits its own arrays, or one device)."""
    return getattr(static, "member_devices", 1)


_EXECUTABLES: dict = {}  # (method, static, argument types) -> compiled jit(vmap(advance)), or jit(advance) for one member


def compiled_advance(method: Method, static, state, params, *scalars):
    """The compiled batched ``advance`` of ``method`` (states and params with a leading member axis; the
    scalars ``t_stop, max_steps, sample_interval, dt_floor_fraction``) for these argument types, and the
    seconds spent compiling it now (0 when it was compiled before in this process). A ``static`` with
    ``member_devices`` n > 1 (lagrangian1d's numerics.devices) spreads the members over n devices in equal
    shares: every leaf is split along its member axis, so each device advances its members alone. Traced and
    lowered through :func:`blastfsi.runtime.lowered` (kept in the persistent cache inside a run)."""
    leaves, tree = jax.tree_util.tree_flatten((state, params))
    key = (method.name, static, tree, tuple(jax.typeof(x) for x in leaves), tuple(type(s) for s in scalars),
           jax.config.jax_enable_x64)  # (the scalars' compiled types)
    if key in _EXECUTABLES:
        return _EXECUTABLES[key], 0.0

    def one(st, pa, t_stop, max_steps, sample_interval, dt_floor_fraction):
        return method.advance(st, pa, static, t_stop, max_steps, sample_interval, dt_floor_fraction)

    def single(st, pa, *rest):
        # a batch of one runs unbatched: under vmap every lax.cond of the loop (a sample due, a fault, a
        # coupled step or not) becomes a select that evaluates both branches each step; measured on
        # he-slab-2d at 20 us: 245 ms per coupled step batched, 105 ms unbatched
        out = one(*jax.tree_util.tree_map(lambda a: a[0], (st, pa)), *rest)
        return jax.tree_util.tree_map(lambda a: a[None], out)

    members = leaves[0].shape[0]
    batched = single if members == 1 else jax.vmap(one, in_axes=(0, 0, None, None, None, None))
    parts = member_devices(static)
    if parts > 1:  # the members spread over devices in equal shares, each member's arrays whole on its device
        def split(tree):
            return jax.tree_util.tree_map(
                lambda a: jax.lax.with_sharding_constraint(a, xla.split_sharding(parts, a.ndim)), tree)

        whole = batched

        def batched(st, pa, *rest):
            return split(whole(split(st), split(pa), *rest))
    started = wallclock.perf_counter()
    _EXECUTABLES[key] = runtime.lowered(batched, (state, params, *scalars), ("advance", method.name, static, members),
                                        donate_argnums=(0,)).compile()
    return _EXECUTABLES[key], wallclock.perf_counter() - started
