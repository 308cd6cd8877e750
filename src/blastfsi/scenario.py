"""One scenario schema for every method (TOML or Python dict).

A scenario names its method in a top-level ``method`` key (missing: the
default ``lagrangian1d``); :func:`parse` reads that key first and validates the
rest with the method's own model (``Method.scenario_model``, registered in
:mod:`blastfsi.method`). Every model derives from :class:`ScenarioBase`, so the
tables all methods share keep one meaning:

* ``[time]``     :class:`Time` (end, max_steps, dt_min_fraction)
* ``[output]``   :class:`Output` (history_samples, fields, checkpoint_interval, plots, gauges)
* ``[numerics]`` :class:`Numerics` (precision, cfl; methods add their own keys)
* ``[sweep]``    :class:`Sweep` (lists whose cartesian product runs as one batched call)

Types are strict (no string-to-bool, string-to-number or float-to-int
coercion; an integer is accepted where a float is expected; no NaN or infinity
anywhere). Unknown keys, missing keys, wrong types and out-of-range values are
rejected with a message naming the dotted key, the allowed range and the value
given; so are overrides of materials the scenario does not use and library
constants outside their ranges (:mod:`blastfsi.materials.ranges`). After the
model, :func:`check_resources` estimates the memory of the compiled run and
refuses one the machine cannot hold unless ``numerics.allow_large = true``.
All quantities are SI (m, kg, s, Pa, J).
"""
from __future__ import annotations

import copy
import itertools
import math
import os
import re
import tomllib
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, NamedTuple, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from blastfsi import method as methods
from blastfsi import xla
from blastfsi.materials import MaterialError, lookup

DEFAULT_METHOD = "lagrangian1d"
SAFE_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]*")


class ScenarioError(ValueError):
    """A scenario that cannot be run; the message names the key(s) at fault."""


class Strict(BaseModel):
    """Base of every scenario table: frozen, unknown keys and type coercion refused, and every number finite
    (NaN and infinity are never physical input; a field meaning "unbounded" would say so with
    ``pydantic.AllowInfNan``)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


# Positions [m]: 1000 km is beyond any blast or structure domain, and keeps float64 cell edges exact to ~1e-10 m.
MAX_COORDINATE = 1e6
Coordinate = Annotated[float, Field(ge=-MAX_COORDINATE, le=MAX_COORDINATE)]


# Checkpoints of one run: each is a full copy of the state on disk and a stop of the compiled loop; as many as
# output.fields allows snapshots (a tiny checkpoint_interval would otherwise build ~1e12 stop times).
MAX_CHECKPOINTS = 10_000


class Time(Strict):
    end: float = Field(gt=0.0, le=1e4, description="simulated time [s]")
    max_steps: int = Field(50_000_000, ge=1, description="stop with an error beyond this many steps")
    dt_min_fraction: float = Field(1e-6, ge=0.0, lt=1.0, description=(
        "stop with an error once the stable time step falls below this fraction of the run's first one "
        "(a collapsing step would otherwise run for hours); 0 disables the check"))


Point = Union[float, list[float]]


class Output(Strict):
    history_samples: int = Field(1001, ge=2, le=1_000_000, description="samples of the histories over [0, end]")
    fields: int = Field(11, ge=0, le=10_000, description="field snapshots over [0, end] (0: none)")
    checkpoint_interval: Optional[float] = Field(None, gt=0.0, description="simulated time between checkpoints [s]")
    gauges: list[Point] = Field(
        default_factory=list, max_length=100,
        description=("gauge points fixed in space [m]: a number in 1D, [x, y] or [x, y, z]; each method checks "
                     "the dimension and that the point lies inside its domain (see gauge_points)"))
    plots: bool = Field(True, description="write the method's plots (PNG) to plots/ at the end of the run")

    @field_validator("gauges", mode="before")
    @classmethod
    def _points(cls, value):
        if not isinstance(value, list):
            return value  # the type check reports it
        for k, g in enumerate(value):
            coords = g if isinstance(g, list) else [g]
            if not 1 <= len(coords) <= 3 or not all(_is_number(c) for c in coords):
                raise ValueError(f"output.gauges[{k}]: expected a position, a number or a list of 1 to 3 numbers "
                                 f"[m] (got {g!r})")
        return value


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


MAX_DEVICES = 4096  # numerics.devices
Devices = Union[Annotated[int, Field(ge=1, le=MAX_DEVICES)], Literal["all"]]  # numerics.devices of a method


class Numerics(Strict):
    """Shared numerics keys; a method subclasses it to add its own (and may change the cfl default)."""

    precision: Literal["float64", "float32"] = Field("float64", description=(
        "floating-point precision of the state and the time loop; float32 runs faster on a GPU"))
    cfl: float = Field(0.5, gt=0.0, le=1.0, description="time-step factor (Courant number)")
    allow_large: bool = Field(False, description=(
        "run even when the estimated memory exceeds what this machine has, or the sweep has more than "
        "10 000 members (blastfsi.scenario.check_resources)"))


class Sweep(Strict):
    """Ensemble: the cartesian product of the given lists runs as one batched (vmapped) call.

    A method subclasses it with one optional list field per swept quantity and
    maps each field name to the dotted scenario key it replaces in ``TARGETS``.
    """

    TARGETS: ClassVar[dict[str, str]] = {}

    def members(self) -> list[dict]:
        axes = [(self.TARGETS[n], v) for n, v in self.model_dump().items() if v is not None]
        return [dict(zip([k for k, _ in axes], combo)) for combo in itertools.product(*[v for _, v in axes])]

    def count(self) -> int:
        """Number of members (the product of the list lengths), without building them."""
        return math.prod(len(v) for v in self.model_dump().values() if v is not None)


class Demand(NamedTuple):
    """Memory one member's compiled time loop holds for one kind of item (:func:`check_resources`)."""

    key: str  # the scenario key that sets the count, e.g. "grid.cells"
    count: float  # items: cells, particles, history samples
    what: str  # their name, e.g. "cells"
    words: int  # numbers held per item: state and the step's temporaries (measured per method)


class ScenarioBase(Strict):
    """Keys every scenario has. A method's model narrows ``method`` to a Literal of its name."""

    method: str
    name: str = Field(min_length=1, max_length=100, description="names the default results directory")
    description: str = Field("", description="free text saying what the scenario is (listed by blastfsi examples)")
    time: Time
    output: Output = Output()
    numerics: Numerics = Numerics()
    sweep: Optional[Sweep] = None

    @field_validator("name")
    @classmethod
    def _safe_name(cls, value: str) -> str:
        if not SAFE_NAME.fullmatch(value):
            raise ValueError("name must consist of letters, digits, '-', '_' and '.' and not start with '.' "
                             f"(it names the results directory; got {value!r})")
        return value

    @model_validator(mode="after")
    def _shared(self):
        interval = self.output.checkpoint_interval
        if interval is not None and interval > self.time.end:
            raise ValueError("output.checkpoint_interval must be <= time.end")
        if interval is not None and self.time.end / interval > MAX_CHECKPOINTS:
            raise ValueError(f"output.checkpoint_interval = {interval:g} s makes {self.time.end / interval:.3g} "
                             f"checkpoints over time.end = {self.time.end:g} s; at most {MAX_CHECKPOINTS} (each is a "
                             "full copy of the state on disk)")
        return self

    def members(self) -> list[dict]:
        """The ensemble as a list of {dotted key: value} overrides (one empty dict if no sweep)."""
        return [{}] if self.sweep is None else self.sweep.members()

    def member_count(self) -> int:
        return 1 if self.sweep is None else self.sweep.count()

    def demands(self) -> list[Demand]:
        """What one member's compiled time loop holds in memory; a method adds its cells and particles to the
        history kept here (samples x columns: time and the method's own, up to 8 quantities per gauge)."""
        return [Demand("output.history_samples", self.output.history_samples, "history samples",
                       32 + 8 * len(self.output.gauges))]

    @classmethod
    def member_data(cls, data: dict, member: dict) -> dict:
        """The raw dict of one ensemble member (no sweep); methods may also drop keys the member replaces."""
        d = copy.deepcopy(data)
        d.pop("sweep", None)
        for key, value in member.items():
            d = set_dotted(d, key, value)
        return d


def cells_along(lower, upper, cells_x: int, key: str) -> tuple[float, tuple[int, ...]]:
    """Square/cubic cells: the size dx = (upper - lower)_x / cells_x and the cell count
    along every axis; a ScenarioError (naming ``key``) when an extent is not a whole
    number of cells."""
    dx = (upper[0] - lower[0]) / cells_x
    counts = []
    for ax, lo, hi in zip("xyz", lower, upper):
        n = (hi - lo) / dx
        if abs(n - round(n)) > 1e-6 * max(n, 1.0):
            raise ScenarioError(f"{key}: the {ax} extent {hi - lo:g} m is not a whole number of cells of "
                                f"{dx:g} m (grid.cells = {cells_x} along x); adjust the extent or grid.cells")
        counts.append(int(round(n)))
    return dx, tuple(counts)


AXES = ("x", "y", "z")


def device_count(requested) -> int:
    """numerics.devices (an int >= 1 or "all") as a number of devices; ScenarioError naming the key where
    JAX sees fewer (:func:`blastfsi.xla.device_count`)."""
    try:
        return xla.device_count(requested)
    except ValueError as err:
        raise ScenarioError(str(err)) from None


def check_box(lower, upper, key: str) -> None:
    """A box [lower, upper]: as many coordinates in both corners, upper above lower on every axis (errors name
    ``key``, e.g. "domain")."""
    if len(lower) != len(upper):
        raise ValueError(f"{key}.lower and {key}.upper need the same number of coordinates, got {len(lower)} "
                         f"and {len(upper)}")
    for ax, lo, hi in zip(AXES, lower, upper):
        if not hi > lo:
            raise ValueError(f"{key}.upper[{ax}] ({hi}) must exceed {key}.lower[{ax}] ({lo})")


def gauge_points(gauges: list, ndim: int, lower, upper) -> list[tuple]:
    """The gauges as ndim-tuples, each checked to lie in the box [lower, upper]
    (per-axis sequences); a ValueError names the gauge and the domain's extent."""
    axes = "xyz"[:ndim]
    extent = ", ".join(f"{a} in [{lo:g}, {hi:g}]" for a, lo, hi in zip(axes, lower, upper))
    out = []
    for k, g in enumerate(gauges):
        p = tuple(g) if isinstance(g, list) else (g,)
        if len(p) != ndim:
            raise ValueError(f"output.gauges[{k}] = {g!r}: expected {ndim} coordinate(s) ({', '.join(axes)}) [m]")
        if not all(lo <= c <= hi for c, lo, hi in zip(p, lower, upper)):
            raise ValueError(f"output.gauges[{k}] = {g!r} m lies outside the domain ({extent} m)")
        out.append(p)
    return out


def _location(data: Any, loc: tuple) -> str:
    """Dotted key of an error location, without the union tags pydantic inserts
    (a tag is a path element that is not a key of the data at that level)."""
    parts, node = [], data
    for i, p in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, dict) and p not in node and not last:
            continue  # a union tag
        parts.append(f"[{p}]" if isinstance(p, int) else f".{p}")
        node = node.get(p) if isinstance(node, dict) else (
            node[p] if isinstance(node, list) and isinstance(p, int) and p < len(node) else None)
    return "".join(parts).lstrip(".")


MAX_ERRORS = 20  # lines of an error listing (500 000 unknown keys would otherwise make a 13 MB message)
MAX_SHOWN = 80  # characters of a value quoted in a message
MAX_DEPTH = 16  # nesting of tables and arrays; a scenario needs 5 (bodies -> supports -> lower -> number)


def show(value) -> str:
    """A value as a message quotes it: plain numbers (no ``np.float64(...)``), at most MAX_SHOWN characters."""
    if hasattr(value, "tolist"):  # NumPy scalars and arrays
        value = value.tolist()
    text = repr(value)
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN] + " ..."


def _error_line(e: dict, data: dict) -> str:
    sym = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    loc = _location(data, e["loc"])
    msg = e["msg"]
    if e["type"] == "extra_forbidden":
        msg = "unknown key"
    elif e["type"] == "missing":
        msg = "missing required key"
    elif e["type"] == "value_error":
        msg = msg.removeprefix("Value error, ")
        if not loc:
            return f"  {msg}"  # a model-level check: its message names the key(s)
    ctx = e.get("ctx") or {}
    bounds = " and ".join(f"{sym[k]} {show(ctx[k])}" for k in ("gt", "ge", "lt", "le") if k in ctx)
    if bounds:
        msg = f"{msg} (allowed: {bounds}; got {show(e.get('input'))})"
    elif e["type"] not in ("missing", "extra_forbidden", "value_error") and "input" in e \
            and not isinstance(e["input"], dict):
        msg = f"{msg} (got {show(e['input'])})"
    return f"  {loc or '<scenario>'}: {msg}"


def _format_errors(err: ValidationError, data: dict) -> str:
    errors = err.errors()
    lines = [_error_line(e, data) for e in errors[:MAX_ERRORS]]
    if len(errors) > MAX_ERRORS:
        lines.append(f"  ... and {len(errors) - MAX_ERRORS} more")
    return "invalid scenario:\n" + "\n".join(lines)


def validate_model(model: type[Strict], data: dict) -> Strict:
    """``model.model_validate(data)`` with pydantic's errors as one ScenarioError naming the keys (also for
    the models a method validates internally, e.g. the cfdmp method's Eulerian and MPM parts)."""
    try:
        return model.model_validate(data)
    except ValidationError as err:
        raise ScenarioError(_format_errors(err, data)) from None


def _too_deep(data, limit: int = MAX_DEPTH) -> str | None:
    """The dotted key of the first value nested deeper than ``limit`` tables/arrays, or None (iterative: a
    hostile file may nest thousands of levels)."""
    stack = [(data, "", 0)]
    while stack:
        node, key, depth = stack.pop()
        if depth > limit:
            return key or "<scenario>"
        items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
        for k, v in items:
            stack.append((v, f"{key}[{k}]" if isinstance(k, int) else f"{key}.{k}".lstrip("."), depth + 1))
    return None


def check_depth(data) -> None:
    """ScenarioError when ``data`` nests tables/arrays deeper than MAX_DEPTH."""
    key = _too_deep(data)
    if key is not None:
        raise ScenarioError(f"invalid scenario:\n  {key.split('[')[0]}: tables and arrays nested deeper than "
                            f"{MAX_DEPTH} levels")


# Resources (check_resources). Above this share of the machine's memory a run swaps or is killed; members are
# validated and set up one by one on the host before the first step (~10 ms each: 10 000 take minutes).
MEMORY_FRACTION = 0.8
MAX_MEMBERS = 10_000


def machine_memory() -> float:
    """Bytes of memory this process may use: the physical memory, or a lower container (cgroup) limit;
    inf where the platform does not say."""
    try:
        total = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        total = math.inf
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        return min(total, float(limit)) if limit.isdigit() else total
    except OSError:
        return total


def _gib(n: float) -> str:
    return f"{n / 2 ** 30:.3g} GiB"


def check_resources(sc: ScenarioBase, members: int | None = None) -> None:
    """ScenarioError, unless ``numerics.allow_large``, for a run of ``members`` members (default the sweep's)
    with more than MAX_MEMBERS members or whose estimated memory (``sc.demands()``: items x numbers each x
    the precision's bytes x members) exceeds MEMORY_FRACTION of :func:`machine_memory`."""
    if sc.numerics.allow_large:
        return
    members = sc.member_count() if members is None else members
    insist = "or set numerics.allow_large = true to run anyway"
    if members > MAX_MEMBERS:
        raise ScenarioError(f"sweep: {members} members, more than {MAX_MEMBERS} (each is set up on the host before "
                            f"the first step); split the sweep, {insist}")
    demands = sorted(sc.demands(), key=lambda d: -d.count * d.words)
    itemsize = 4 if sc.numerics.precision == "float32" else 8
    need = members * itemsize * sum(d.count * d.words for d in demands)
    have = machine_memory()
    if need > MEMORY_FRACTION * have:
        detail = "; ".join(f"{d.key}: {d.count:.3g} {d.what} x {d.words} numbers" for d in demands)
        per = f" x {members} sweep members" if members > 1 else ""
        raise ScenarioError(f"{demands[0].key}: the run needs about {_gib(need)} of memory ({detail}{per}; "
                            f"{sc.numerics.precision}) and this machine has {_gib(have)}; reduce it, {insist}")


def material(overrides: dict, name: str, field: str):
    """The library material ``name`` with the scenario's ``[materials.<name>]`` overrides (``overrides``:
    the ``materials`` table) applied and checked (:func:`blastfsi.materials.lookup`); ScenarioError naming
    ``field`` for an unknown material or an override out of range."""
    try:
        return lookup(name, overrides.get(name), field=field)
    except MaterialError as err:
        raise ScenarioError(str(err)) from None


def parse(data: dict) -> ScenarioBase:
    """Validate a raw scenario dict with the model of its ``method``, then its resources (:func:`check_resources`)."""
    if not isinstance(data, dict):
        raise ScenarioError(f"a scenario is a table of keys, got {type(data).__name__}")
    check_depth(data)
    name = data.get("method", DEFAULT_METHOD)
    if not isinstance(name, str):
        raise ScenarioError(f"invalid scenario:\n  method: expected a string (got {show(name)})")
    try:
        model = methods.get(name).scenario_model
    except KeyError as err:
        raise ScenarioError(f"invalid scenario:\n  method: {err.args[0]}") from None
    if not issubclass(model, ScenarioBase):
        raise TypeError(f"method {name!r}: scenario_model must derive from blastfsi.scenario.ScenarioBase")
    sc = validate_model(model, {**data, "method": name})
    check_resources(sc)
    return sc


def parse_value(text: str):
    """A ``--set`` value: TOML syntax (numbers, booleans, strings, lists), else a bare string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise ScenarioError(f"--set value nested deeper than {MAX_DEPTH} levels") from None


def set_dotted(data: dict, key: str, value) -> dict:
    """A copy of ``data`` with ``value`` at the dotted ``key`` (tables created as needed). A whole-number part
    indexes a list: ``structures.0.material`` is the first structure's material, ``domain.upper.1`` the second
    coordinate; an index must name an entry that exists."""
    parts = key.strip().split(".")
    if not all(parts):
        raise ScenarioError(f"key {key!r} is not a dotted key path")
    out = copy.deepcopy(data)
    node, path = out, []
    for p, last in zip(parts, [False] * (len(parts) - 1) + [True]):
        where = ".".join(path) or "the scenario"
        if isinstance(node, list):
            if not p.isdigit() or int(p) >= len(node):
                raise ScenarioError(f"{key}: {where} is a list of {len(node)} entries, so {p!r} must be an index "
                                    f"from 0 to {len(node) - 1}")
            p = int(p)
        elif not isinstance(node, dict):
            raise ScenarioError(f"{key}: {where} is a value, not a table")
        if last:
            node[p] = value
        else:
            node = node.setdefault(p, {}) if isinstance(node, dict) else node[p]
        path.append(str(p))
    return out


def apply_overrides(data: dict, overrides: list[str]) -> dict:
    """Apply ``--set key.path=value`` overrides to a raw scenario dict (validated later with the rest)."""
    for item in overrides:
        if "=" not in item:
            raise ScenarioError(f"--set expects key.path=value, got {item!r}")
        key, text = item.split("=", 1)
        data = set_dotted(data, key, parse_value(text.strip()))
    return data


def read_toml(path: str | Path) -> dict:
    """The raw dict of a TOML scenario file (validated later, after any overrides)."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"scenario file not found: {path}")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as err:
        raise ScenarioError(f"{path}: not a text (UTF-8) file: byte {err.start} is {err.object[err.start]:#04x}") \
            from None
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"{path}: not valid TOML: {err}") from None
    except RecursionError:
        raise ScenarioError(f"{path}: tables or arrays nested deeper than {MAX_DEPTH} levels") from None
    except OSError as err:
        raise ScenarioError(f"{path}: cannot be read: {err.strerror}") from None
    check_depth(data)
    return data


def expand(data: dict | list[dict]) -> tuple[ScenarioBase, list[dict], list[ScenarioBase]]:
    """(scenario, member overrides, member scenarios) of a scenario with an
    optional sweep, or of a list of sweep-free scenarios of one method that
    share their [time] and [output] tables and precision (e.g. different
    domain lengths; the members are then {"member": k})."""
    if isinstance(data, list):
        if not data:
            raise ScenarioError("an empty list of scenarios")
        scs = [parse(d) for d in data]
        check_resources(scs[0], len(scs))
        for key in ("method", "time", "output"):
            if any(getattr(s, key) != getattr(scs[0], key) for s in scs):
                raise ScenarioError(f"a batch of scenarios must share its {key!r} key/table")
        if any(s.numerics.precision != scs[0].numerics.precision for s in scs):
            raise ScenarioError("a batch of scenarios must share numerics.precision")
        return scs[0], [{"member": k} for k in range(len(scs))], scs
    sc = parse(data)
    members = sc.members()
    return sc, members, [parse(type(sc).member_data(data, m)) if m else sc for m in members]
