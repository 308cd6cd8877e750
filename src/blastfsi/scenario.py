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
coercion; an integer is accepted where a float is expected). Unknown keys,
missing keys, wrong types and out-of-range values are rejected with a message
naming the dotted key, the allowed range and the value given. All quantities
are SI (m, kg, s, Pa, J).
"""
from __future__ import annotations

import copy
import itertools
import re
import tomllib
from pathlib import Path
from typing import Any, ClassVar, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

DEFAULT_METHOD = "lagrangian1d"
SAFE_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]*")


class ScenarioError(ValueError):
    """A scenario that cannot be run; the message names the key(s) at fault."""


class Strict(BaseModel):
    """Base of every scenario table: frozen, unknown keys and type coercion refused."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


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
    plots: bool = True

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


class Numerics(Strict):
    """Shared numerics keys; a method subclasses it to add its own (and may change the cfl default)."""

    precision: Literal["float64", "float32"] = "float64"
    cfl: float = Field(0.5, gt=0.0, le=1.0, description="time-step factor (Courant number)")


class Sweep(Strict):
    """Ensemble: the cartesian product of the given lists runs as one batched (vmapped) call.

    A method subclasses it with one optional list field per swept quantity and
    maps each field name to the dotted scenario key it replaces in ``TARGETS``.
    """

    TARGETS: ClassVar[dict[str, str]] = {}

    def members(self) -> list[dict]:
        axes = [(self.TARGETS[n], v) for n, v in self.model_dump().items() if v is not None]
        return [dict(zip([k for k, _ in axes], combo)) for combo in itertools.product(*[v for _, v in axes])]


class ScenarioBase(Strict):
    """Keys every scenario has. A method's model narrows ``method`` to a Literal of its name."""

    method: str
    name: str = Field(min_length=1, max_length=100, description="names the default results directory")
    description: str = ""
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
        if self.output.checkpoint_interval is not None and self.output.checkpoint_interval > self.time.end:
            raise ValueError("output.checkpoint_interval must be <= time.end")
        return self

    def members(self) -> list[dict]:
        """The ensemble as a list of {dotted key: value} overrides (one empty dict if no sweep)."""
        return [{}] if self.sweep is None else self.sweep.members()

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


def _format_errors(err: ValidationError, data: dict) -> str:
    sym = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    lines = []
    for e in err.errors():
        loc = _location(data, e["loc"])
        msg = e["msg"]
        if e["type"] == "extra_forbidden":
            msg = "unknown key"
        elif e["type"] == "missing":
            msg = "missing required key"
        ctx = e.get("ctx") or {}
        bounds = " and ".join(f"{sym[k]} {ctx[k]}" for k in ("gt", "ge", "lt", "le") if k in ctx)
        if bounds:
            msg = f"{msg} (allowed: {bounds}; got {e.get('input')!r})"
        elif e["type"] not in ("missing", "extra_forbidden", "value_error") and "input" in e \
                and not isinstance(e["input"], dict):
            msg = f"{msg} (got {e['input']!r})"
        lines.append(f"  {loc or '<scenario>'}: {msg}")
    return "invalid scenario:\n" + "\n".join(lines)


def parse(data: dict) -> ScenarioBase:
    """Validate a raw scenario dict with the model of its ``method``."""
    from blastfsi import method as methods

    if not isinstance(data, dict):
        raise ScenarioError(f"a scenario is a table of keys, got {type(data).__name__}")
    name = data.get("method", DEFAULT_METHOD)
    if not isinstance(name, str):
        raise ScenarioError(f"invalid scenario:\n  method: expected a string (got {name!r})")
    try:
        model = methods.get(name).scenario_model
    except KeyError as err:
        raise ScenarioError(f"invalid scenario:\n  method: {err.args[0]}") from None
    try:
        return model.model_validate({**data, "method": name})
    except ValidationError as err:
        raise ScenarioError(_format_errors(err, data)) from None


def parse_value(text: str):
    """A ``--set`` value: TOML syntax (numbers, booleans, strings, lists), else a bare string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def set_dotted(data: dict, key: str, value) -> dict:
    """A copy of ``data`` with ``value`` at the dotted ``key`` (tables created as needed)."""
    parts = key.strip().split(".")
    if not all(parts):
        raise ScenarioError(f"key {key!r} is not a dotted key path")
    out = copy.deepcopy(data)
    node = out
    for p in parts[:-1]:
        node = node.setdefault(p, {})
        if not isinstance(node, dict):
            raise ScenarioError(f"{key}: {p!r} is a value, not a table")
    node[parts[-1]] = value
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
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"{path}: not valid TOML: {err}") from None


def expand(data: dict | list[dict]) -> tuple[ScenarioBase, list[dict], list[ScenarioBase]]:
    """(scenario, member overrides, member scenarios) of a scenario with an
    optional sweep, or of a list of sweep-free scenarios of one method that
    share their [time] and [output] tables and precision (e.g. different
    domain lengths; the members are then {"member": k})."""
    if isinstance(data, list):
        if not data:
            raise ScenarioError("an empty list of scenarios")
        scs = [parse(d) for d in data]
        for key in ("method", "time", "output"):
            if any(getattr(s, key) != getattr(scs[0], key) for s in scs):
                raise ScenarioError(f"a batch of scenarios must share its {key!r} key/table")
        if any(s.numerics.precision != scs[0].numerics.precision for s in scs):
            raise ScenarioError("a batch of scenarios must share numerics.precision")
        return scs[0], [{"member": k} for k in range(len(scs))], scs
    sc = parse(data)
    members = sc.members()
    return sc, members, [parse(type(sc).member_data(data, m)) if m else sc for m in members]
