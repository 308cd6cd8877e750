"""Typed, validated scenario schema (TOML or Python dict).

Unknown keys, missing keys, wrong types and out-of-range values are rejected
with a message naming the dotted key and the allowed range. All quantities are
SI (m, kg, s, Pa, J).
"""
from __future__ import annotations

import copy
import itertools
import tomllib
from pathlib import Path
from typing import Annotated, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator


class ScenarioError(ValueError):
    """A scenario that cannot be run; the message names the key(s) at fault."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


# Ambient air of 002 Sec. 3 (ERRATA 002-7): p0 = 1.048 bar, rho0 = 1.225 kg/m^3, gamma = 1.4.
class Gas(_Strict):
    gamma: float = Field(1.4, gt=1.0, le=5.0 / 3.0, description="ratio of specific heats [-]")
    pressure: float = Field(1.048e5, gt=0.0, description="ambient pressure p0 [Pa]")
    density: float = Field(1.225, gt=0.0, description="ambient density rho0 [kg/m^3]")


class UniformIncident(_Strict):
    """Uniform (step) shock driven by a piston at the left end (002 Sec. 3.1-3.2)."""

    profile: Literal["uniform"]
    overpressure: float = Field(gt=0.0, le=1e10, description="incident shock overpressure p_s [Pa]")


class ExponentialIncident(_Strict):
    """Exponentially decaying blast initialised in the gas (002 Sec. 3.3)."""

    profile: Literal["exponential"]
    overpressure: float = Field(gt=0.0, le=1e10, description="initial peak overpressure p_i [Pa]")
    decay_length: float = Field(gt=0.0, description="e-folding length d_i of the overpressure [m]")
    standoff: float = Field(gt=0.0, description="distance from the initial front to the plate [m]")
    ramp_cells: int = Field(10, ge=1, le=1000, description="cells of the linear pressure ramp at the front")


class SedovIncident(_Strict):
    """Planar von Neumann-Sedov point explosion (002 Sec. 3.4), symmetry plane at x = 0."""

    profile: Literal["sedov"]
    energy: float = Field(gt=0.0, description="explosion energy per unit area, one side of the plane, E0 [J/m^2]")
    front_position: float = Field(gt=0.0, description="shock position at the start of the run [m]")
    core_fraction: float = Field(0.1, ge=0.0, lt=0.5, description=(
        "zones closer to the centre than this fraction of front_position are merged into a core of uniform "
        "density and internal energy (same mass and energy); 0 keeps the exact singular profile"))


Incident = Annotated[Union[UniformIncident, ExponentialIncident, SedovIncident], Field(discriminator="profile")]


class Plate(_Strict):
    """Free-standing rigid plate at the right end of the gas column (002 Eq. 7).

    Give exactly one of ``areal_mass``, ``beta_s`` (uniform shocks only) or
    ``density`` with ``thickness``; or set ``fixed = true`` for a rigid wall.
    """

    fixed: bool = False
    areal_mass: Optional[float] = Field(None, ge=0.0, description=(
        "rho_p h_p [kg/m^2]; 0 makes the end a free surface held at back_pressure"))
    beta_s: Optional[float] = Field(None, gt=0.0, description="compressible FSI parameter, Eq. (28) [-]")
    density: Optional[float] = Field(None, gt=0.0, description="plate density rho_p [kg/m^3]")
    thickness: Optional[float] = Field(None, gt=0.0, description="plate thickness h_p [m]")
    back_pressure: Optional[float] = Field(None, ge=0.0, description="pressure on the free side [Pa]; default p0")

    @model_validator(mode="after")
    def _one_mass(self):
        if (self.density is None) != (self.thickness is None):
            raise ValueError("plate.density and plate.thickness must be given together")
        given = [n for n, v in (("areal_mass", self.areal_mass), ("beta_s", self.beta_s),
                                ("density/thickness", self.density)) if v is not None]
        if self.fixed and given:
            raise ValueError(f"plate.fixed = true takes no mass, but {given} given")
        if not self.fixed and len(given) != 1:
            raise ValueError("give exactly one of plate.areal_mass, plate.beta_s or plate.density+plate.thickness "
                             f"(or plate.fixed = true); got {given or 'none'}")
        return self


class Domain(_Strict):
    length: float = Field(gt=0.0, le=1e5, description="initial gas column length; the plate sits at x = length [m]")


class Grid(_Strict):
    cells: int = Field(ge=10, le=10_000_000, description="number of Lagrangian zones")


class Numerics(_Strict):
    # Defaults chosen in docs/theory.md: K1^2 = 2.25 spreads a shock over ~3 zones,
    # K2 = 0.1 damps post-shock ringing; alpha = 0.5 leaves margin below the bound.
    K1: float = Field(1.5, ge=0.0, le=5.0, description="quadratic viscosity coefficient, Eq. (5)")
    K2: float = Field(0.1, ge=0.0, le=2.0, description="linear viscosity coefficient, Eq. (5)")
    cfl: float = Field(0.5, gt=0.0, le=1.0, description="time-step factor alpha, Eq. (20)")
    precision: Literal["float64", "float32"] = "float64"


class Time(_Strict):
    end: float = Field(gt=0.0, le=1e4, description="simulated time [s]")
    max_steps: int = Field(50_000_000, ge=1, description="stop with an error beyond this many steps")


class Output(_Strict):
    history_samples: int = Field(1001, ge=2, le=1_000_000, description="samples of the histories over [0, end]")
    fields: int = Field(11, ge=0, le=10_000, description="field snapshots over [0, end] (0: none)")
    checkpoint_interval: Optional[float] = Field(None, gt=0.0, description="simulated time between checkpoints [s]")
    gauges: list[Annotated[float, Field(ge=0.0)]] = Field(
        default_factory=list, max_length=100,
        description="positions of pressure gauges fixed in space [m]: overpressure history, peak, positive impulse")
    plots: bool = True


class Sweep(_Strict):
    """Ensemble: the cartesian product of the lists runs as one batched call."""

    overpressure: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    beta_s: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    areal_mass: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)
    thickness: Optional[list[Annotated[float, Field(gt=0.0)]]] = Field(None, min_length=1)

    @model_validator(mode="after")
    def _one_mass_list(self):
        masses = [n for n in ("beta_s", "areal_mass", "thickness") if getattr(self, n) is not None]
        if len(masses) > 1:
            raise ValueError(f"sweep takes at most one of beta_s, areal_mass, thickness; got {masses}")
        return self


class Scenario(_Strict):
    name: str = Field(min_length=1, max_length=100)
    description: str = ""
    gas: Gas = Gas()
    incident: Incident
    plate: Plate
    domain: Domain
    grid: Grid
    numerics: Numerics = Numerics()
    time: Time
    output: Output = Output()
    sweep: Optional[Sweep] = None

    @model_validator(mode="after")
    def _consistent(self):
        inc = self.incident
        if self.plate.beta_s is not None and inc.profile != "uniform":
            raise ValueError("plate.beta_s is defined for uniform shocks only; give plate.areal_mass")
        if self.sweep is not None:
            if self.sweep.overpressure is not None and inc.profile == "sedov":
                raise ValueError("sweep.overpressure does not apply to a sedov incident profile")
            if self.sweep.beta_s is not None and inc.profile != "uniform":
                raise ValueError("sweep.beta_s is defined for uniform shocks only")
            if self.sweep.thickness is not None and self.plate.density is None:
                raise ValueError("sweep.thickness needs plate.density")
            mass_sweep = any(getattr(self.sweep, n) is not None for n in ("beta_s", "areal_mass", "thickness"))
            if self.plate.fixed and mass_sweep:
                raise ValueError("a plate-mass sweep needs plate.fixed = false")
        if inc.profile == "exponential":
            if inc.standoff >= self.domain.length:
                raise ValueError(f"incident.standoff ({inc.standoff} m) must be < domain.length "
                                 f"({self.domain.length} m)")
            dx = self.domain.length / self.grid.cells
            if inc.ramp_cells * dx >= self.domain.length - inc.standoff:
                raise ValueError("incident.ramp_cells span more than the gas behind the front")
        if inc.profile == "sedov" and inc.front_position >= self.domain.length:
            raise ValueError(f"incident.front_position ({inc.front_position} m) must be < domain.length "
                             f"({self.domain.length} m)")
        if self.output.checkpoint_interval is not None and self.output.checkpoint_interval > self.time.end:
            raise ValueError("output.checkpoint_interval must be <= time.end")
        return self

    def members(self) -> list[dict]:
        """The ensemble as a list of {dotted key: value} overrides (one empty dict if no sweep)."""
        if self.sweep is None:
            return [{}]
        axes = [(f"{'incident' if n == 'overpressure' else 'plate'}.{n}", v)
                for n, v in self.sweep.model_dump().items() if v is not None]
        return [dict(zip([k for k, _ in axes], combo)) for combo in itertools.product(*[v for _, v in axes])]


def _format_errors(err: ValidationError) -> str:
    lines = []
    for e in err.errors():
        # drop the discriminator tags pydantic inserts in union locations
        loc = ".".join(str(p) for p in e["loc"] if p not in ("uniform", "exponential", "sedov"))
        msg = e["msg"]
        if e["type"] == "extra_forbidden":
            msg = "unknown key"
        elif e["type"] == "missing":
            msg = "missing required key"
        ctx = e.get("ctx") or {}
        bounds = ", ".join(f"{k} {ctx[k]}" for k in ("gt", "ge", "lt", "le") if k in ctx)
        sym = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
        if bounds:
            bounds = " and ".join(f"{sym[k]} {ctx[k]}" for k in ("gt", "ge", "lt", "le") if k in ctx)
            msg = f"{msg} (allowed: {bounds}; got {e.get('input')!r})"
        elif e["type"] not in ("missing", "extra_forbidden") and "input" in e and not isinstance(e["input"], dict):
            msg = f"{msg} (got {e['input']!r})"
        lines.append(f"  {loc or '<scenario>'}: {msg}")
    return "invalid scenario:\n" + "\n".join(lines)


def parse(data: dict) -> Scenario:
    try:
        return Scenario.model_validate(data)
    except ValidationError as err:
        raise ScenarioError(_format_errors(err)) from None


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


def member_scenario(data: dict, member: dict) -> Scenario:
    """One ensemble member as a plain (sweep-free) validated scenario."""
    d = copy.deepcopy(data)
    d.pop("sweep", None)
    plate = d.setdefault("plate", {})
    if any(k in member for k in ("plate.areal_mass", "plate.beta_s")):
        for k in ("areal_mass", "beta_s", "density", "thickness"):
            plate.pop(k, None)
    for key, value in member.items():
        d = set_dotted(d, key, value)
    return parse(d)
