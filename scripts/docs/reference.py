"""Pages of the user guide generated from the package's own data (run at build time by ``gen_pages.py``).

* :func:`scenario_reference`: every key of every method's scenario model (pydantic), with its meaning, unit,
  default and allowed range, read from the schema itself;
* :func:`materials_reference`: every material of :mod:`blastfsi.materials` with each constant's value, unit,
  allowed range (:mod:`blastfsi.materials.ranges`) and source;
* :func:`examples_gallery`: every shipped example (``blastfsi/examples/*.toml``) with its method, description
  and, where the documentation has one, a figure.

The functions return Markdown text and import nothing of mkdocs, so the tests can check them.
"""
from __future__ import annotations

import copy
import json
import re
import sys
import tomllib
import types
import typing
from importlib import resources
from pathlib import Path
from typing import Any, Literal, NamedTuple, Union

import annotated_types
from pydantic import BaseModel
from pydantic.fields import FieldInfo

from blastfsi import method as methods
from blastfsi.materials import LIBRARY, ranges

METHODS = ("lagrangian1d", "euler", "mpm", "cfdmp")
SUMMARIES = {
    "lagrangian1d": "1D Lagrangian gas (planar, cylindrical, spherical): a blast on a free-standing plate "
                    "(`[incident]` + `[plate]`) or a high-explosive charge detonated at r = 0 (`[charge]`). "
                    "The default method: a file without `method` is read as this one.",
    "euler": "The Eulerian gas solver on a grid of square cells in 1D, 2D, 3D, 1D radial or 2D r–z: shock tubes, "
             "point explosions, TNT charges detonated in 1D and remapped onto the grid.",
    "mpm": "The material point method on its own: solids (and gases) as particles on a background grid.",
    "cfdmp": "The `euler` grid over the whole domain coupled through a bridge region to an MPM box "
             "(`[mpm_region]`) holding the gas near the structures and the structures themselves "
             "(`[[structures]]`, the `mpm` bodies).",
}

_BOUNDS = ((annotated_types.Gt, "gt", ">"), (annotated_types.Ge, "ge", ">="), (annotated_types.Lt, "lt", "<"),
           (annotated_types.Le, "le", "<="))


class Key(NamedTuple):
    """One key of a scenario: its dotted path (``[]`` marks an entry of an array of tables), the variant of a
    tagged table it belongs to (``initial.kind = "charge"``), and what the schema says of it."""

    path: str
    variant: str
    type: str
    default: str
    allowed: str
    unit: str
    meaning: str


def _strip_optional(annotation) -> tuple[Any, bool]:
    """(annotation without ``None``, whether None was allowed)."""
    if typing.get_origin(annotation) in (Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        if len(args) < len(typing.get_args(annotation)):
            return (args[0] if len(args) == 1 else Union[tuple(args)]), True
    return annotation, False


def _annotated(annotation) -> tuple[Any, list]:
    """(bare type, metadata) of an ``Annotated[...]`` type, nested ones merged."""
    meta = []
    while typing.get_origin(annotation) is typing.Annotated:
        args = typing.get_args(annotation)
        annotation, meta = args[0], meta + list(args[1:])
    return annotation, meta


def _is_model(t) -> bool:
    return isinstance(t, type) and issubclass(t, BaseModel)


def _variants(t) -> list[type[BaseModel]]:
    """The models of a union of models (a tagged table such as ``initial``), else []."""
    t, _ = _annotated(t)
    if typing.get_origin(t) in (Union, types.UnionType):
        args = [_annotated(a)[0] for a in typing.get_args(t)]
        if args and all(_is_model(a) for a in args):
            return args
    return []


def _tag(model: type[BaseModel]) -> tuple[str, str] | None:
    """(key, value) of the Literal field that selects this model inside a tagged union."""
    for name, f in model.model_fields.items():
        if typing.get_origin(f.annotation) is Literal and len(typing.get_args(f.annotation)) == 1 and f.is_required():
            return name, typing.get_args(f.annotation)[0]
    return None


def _bounds(meta) -> list[str]:
    out = []
    for m in meta:
        for cls, _, sym in _BOUNDS:
            if isinstance(m, cls):
                out.append(f"{sym} {_number(getattr(m, cls.__name__.lower()))}")
        if isinstance(m, FieldInfo):
            out += _bounds(m.metadata)
    return out


def _lengths(meta) -> str:
    lo = next((m.min_length for m in meta if isinstance(m, annotated_types.MinLen)), None)
    hi = next((m.max_length for m in meta if isinstance(m, annotated_types.MaxLen)), None)
    if lo is None and hi is None:
        return ""
    if lo == hi:
        return f"{lo} entries"
    if hi is None:
        return f"at least {lo} entr{'y' if lo == 1 else 'ies'}"
    return f"{lo or 0} to {hi} entries"


def _number(v) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, int) and abs(v) >= 10_000:
        return f"{v:_}".replace("_", " ")
    return str(v)


def _type_name(t) -> str:
    """A type as a TOML user reads it."""
    t, _ = _annotated(t)
    t, optional = _strip_optional(t)
    t, _ = _annotated(t)
    origin = typing.get_origin(t)
    if origin is Literal:
        name = " \\| ".join(f'`"{a}"`' for a in typing.get_args(t))
    elif origin is list:
        (item,) = typing.get_args(t) or (Any,)
        inner = _type_name(item)
        name = f"array of ({inner})" if " or " in inner else f"array of {inner}"
    elif origin is dict:
        name = "table"
    elif origin in (Union, types.UnionType) and _variants(t):
        name = "table"
    elif origin in (Union, types.UnionType):
        name = " or ".join(_type_name(a) for a in typing.get_args(t))
    elif _is_model(t):
        name = "table"
    else:
        name = {float: "number", int: "integer", bool: "boolean", str: "string"}.get(t, getattr(t, "__name__", str(t)))
    return name


def _allowed(f: FieldInfo) -> str:
    t, meta = _annotated(f.annotation)
    t, _ = _strip_optional(t)
    t, inner = _annotated(t)
    parts = _bounds(list(f.metadata) + meta + inner)
    origin = typing.get_origin(t)
    if origin is list:
        (item,) = typing.get_args(t) or (Any,)
        item_t, item_meta = _annotated(item)
        item_bounds = _bounds(item_meta)
        if typing.get_origin(item_t) is Literal:
            item_bounds = [" \\| ".join(f'`"{a}"`' for a in typing.get_args(item_t))]
        if item_bounds:
            parts.append("each " + " and ".join(item_bounds))
        length = _lengths(list(f.metadata) + meta + inner)
        if length:
            parts.append(length)
    elif origin is str or t is str:
        length = _lengths(list(f.metadata))
        if length:
            parts.append(length.replace("entries", "characters").replace("entry", "character"))
    return ", ".join(parts)


def _default(f: FieldInfo) -> str:
    if f.is_required():
        return "**required**"
    if f.default_factory is not None:
        value = f.default_factory()
    else:
        value = f.default
    if value is None:
        return "none"
    if isinstance(value, BaseModel):
        return "(table defaults)"
    if isinstance(value, str):
        return f'`"{value}"`' if value else '`""`'
    if isinstance(value, list):
        return "`[" + ", ".join(f'"{v}"' if isinstance(v, str) else _number(v) for v in value) + "]`"
    if isinstance(value, dict):
        return "`{}`" if not value else f"`{value}`"
    return f"`{_number(value)}`"


def _tables() -> set[str]:
    """Names of scenario tables (a bracketed table name in a description is not a unit)."""
    return {name for m in METHODS for name, f in methods.get(m).scenario_model.model_fields.items()}


_UNIT = re.compile(r"\[([^\]\[]{1,30})\]")


def _unit(description: str, tables: set[str]) -> str:
    """The first bracketed unit of a description (``[m]``, ``[Pa]``, ``[-]``), else ""."""
    for match in _UNIT.finditer(description or ""):
        text = match.group(1).strip()
        if "," in text or text in tables or text in ("lower", "upper"):
            continue  # a list ([x, y]), an interval ([0, end]) or a table name ([charge])
        return text
    return ""


def _doc(model) -> str:
    """The first paragraph of a model's docstring, or ""."""
    return " ".join((model.__doc__ or "").split("\n\n")[0].split()) if model.__doc__ else ""


def _meaning(model: type[BaseModel], name: str, f: FieldInfo, t) -> str:
    """What a key means: its description; a tag key (``kind``, ``profile``) its variant's docstring; a sweep
    list the key it replaces; a table its model's docstring; the top-level ``method`` key says it."""
    if f.description:
        return f.description
    if name == "method":
        return "the solution method (the solver); it decides which other keys the scenario takes"
    if _tag(model) is not None and _tag(model)[0] == name:
        return _doc(model)
    targets = getattr(model, "TARGETS", {})
    if name in targets:
        return (f"values of `{targets[name]}` to run, one ensemble member each (several sweep lists: their "
                "cartesian product); all members run as one batched call")
    if _is_model(t) and model.__doc__ != t.__doc__:
        return _doc(t)
    return ""


def scenario_keys(model: type[BaseModel], prefix: str = "", variant: str = "") -> list[Key]:
    """Every key of ``model``, depth first: a table's own row, then its keys; each variant of a tagged table."""
    tables = _tables()
    out = []
    for name, f in model.model_fields.items():
        path = f"{prefix}{name}"
        if isinstance(f.annotation, typing.ForwardRef):  # a model declared below its user (mpm's Support)
            f = copy.copy(f)
            f.annotation = eval(f.annotation.__forward_arg__, vars(sys.modules[model.__module__]))
        t, _ = _annotated(f.annotation)
        t, _ = _strip_optional(t)
        t, _ = _annotated(t)
        item = typing.get_args(t)[0] if typing.get_origin(t) is list and typing.get_args(t) else None
        item = _annotated(item)[0] if item is not None else None
        meaning = _meaning(model, name, f, t if not _is_model(item) else item)
        table = _is_model(t) or bool(_variants(t))
        out.append(Key(path, variant, _type_name(f.annotation), _default(f), _allowed(f),
                       "" if table else _unit(meaning, tables), _clean(meaning)))
        if _is_model(t):
            out += scenario_keys(t, path + ".", variant)
        elif _is_model(item):
            out += scenario_keys(item, path + "[].", variant)
        else:
            for v in _variants(t):
                tag = _tag(v)
                label = f'{path}.{tag[0]} = "{tag[1]}"' if tag else v.__name__
                out += scenario_keys(v, path + ".", label)
    return out


def _clean(text: str) -> str:
    """One line, without the class docstrings' reST markup, safe inside a table cell."""
    text = " ".join(text.split()).replace("``", "`").replace("|", "\\|")
    return re.sub(r":(?:func|class|mod|meth):`~?([^`]+)`", r"`\1`", text)


def scenario_reference() -> str:
    """The Scenario reference page: one table per method."""
    lines = ["# Scenario reference", "",
             "Generated from the scenario schema itself (the pydantic models the validator uses), so it cannot "
             "drift from what `blastfsi run` accepts. Every key of every method: its meaning, unit, default and "
             "allowed range. All quantities are SI (m, kg, s, Pa, J). A `[]` in a key marks an entry of an "
             "array of tables (`[[bodies]]`); keys listed under a variant (e.g. `initial.kind = \"charge\"`) "
             "belong to that variant only.", "",
             "Types are strict: no `\"yes\"` for a boolean, no `100.0` for an integer (an integer is fine for a "
             "number), no `nan` or `inf`. Unknown keys, missing required keys and out-of-range values are "
             "refused with the key and the allowed range. Checks that involve several keys (a gauge inside the "
             "domain, exactly one of `mass` and `radius`, ...) are stated in the meaning column and applied too. "
             "An empty unit column means a count or a dimensionless number.",
             ""]
    for m in METHODS:
        model = methods.get(m).scenario_model
        lines += [f"## `method = \"{m}\"`", "", SUMMARIES[m], "",
                  "| key | type | default | allowed | unit | meaning |", "|---|---|---|---|---|---|"]
        variant = ""
        for k in scenario_keys(model):
            if k.variant != variant:
                variant = k.variant
                label = f"only with {variant}" if variant else f"every `{m}` scenario (continued)"
                lines.append(f"| **{label}** | | | | | |")
            lines.append(f"| `{k.path}` | {k.type} | {k.default} | {k.allowed} | {k.unit} | {k.meaning} |")
        lines.append("")
    return "\n".join(lines)




# --- materials ------------------------------------------------------------------------------------------------

# Units of the library's constants (SI), by constant name; :func:`material_rows` refuses a constant missing here.
UNITS = {
    "gamma": "-", "density": "kg/m³", "specific_energy": "J/kg", "A": "Pa", "B": "Pa", "R1": "-", "R2": "-",
    "omega": "-", "E0": "J/m³", "detonation_velocity": "m/s", "youngs_modulus": "Pa", "poisson_ratio": "-",
    "shear_modulus": "Pa", "n": "-", "C": "-", "m": "-", "reference_strain_rate": "1/s", "room_temperature": "K",
    "melt_temperature": "K", "specific_heat": "J/(kg K)", "taylor_quinney": "-", "C0": "m/s", "S": "-",
    "gamma0": "-", "a": "-", "fc": "Pa", "N": "-", "SMAX": "-", "T": "Pa", "D1": "-", "D2": "-", "EFMIN": "-",
    "P_crush": "Pa", "mu_crush": "-", "K1": "Pa", "K2": "Pa", "K3": "Pa", "P_lock": "Pa", "mu_lock": "-",
    "tensile_damage_rate": "1/s", "tensile_threshold": "Pa", "tensile_exponent": "-",
    "initial_tensile_damage": "-", "tensile_damage_limit": "-", "cohesion": "Pa", "friction_angle": "degrees",
    "dilation_angle": "degrees", "tensile_strength": "Pa",
}
# The normalised HJC strength constants are dimensionless (A, B of HJCConcrete), unlike Johnson-Cook's A, B [Pa].
DIMENSIONLESS = {("HJCConcrete", "A"), ("HJCConcrete", "B")}


class Constant(NamedTuple):
    name: str
    value: float
    unit: str
    allowed: str
    why: str
    source: str


def material_rows(entry) -> list[Constant]:
    """The constants of one library entry with unit, range and source; KeyError for a constant without a unit."""
    rows = []
    for name, rng in ranges.ranges(entry).items():
        unit = "-" if (type(entry).__name__, name) in DIMENSIONLESS else UNITS[name]
        rows.append(Constant(name, getattr(entry, name), unit, rng.text(), rng.why,
                             entry.sources.get(name, "")))
    return rows


def materials_reference() -> str:
    """The Material library page: one table per material."""
    kinds = {"IdealGasMaterial": "ideal gas", "JWLExplosive": "explosive (JWL)",
             "LinearElasticSolid": "linear elastic solid (`elastic`)",
             "JohnsonCookSolid": "Johnson–Cook strength + Mie–Grüneisen EOS (`johnson-cook`)",
             "HJCConcrete": "Holmquist–Johnson–Cook concrete with Jiang tensile damage (`hjc`)",
             "DruckerPragerSoil": "Drucker–Prager soil (`drucker-prager`)"}
    lines = ["# Material library", "",
             "Generated from `blastfsi.materials` (the library the solvers read). A scenario names a material "
             "(`material = \"steel-rha\"`, `explosive = \"tnt\"`) and may override any constant key by key in "
             "`[materials.<name>]`, e.g. `[materials.air] gamma = 1.3`; every constant, overridden or not, is "
             "checked against the range below, and an override of a material the scenario does not use is "
             "refused. Sources are abbreviated as in the list at the end (\"seed 000\" and SEED are the CFDMP paper, "
             "ERRATA items its errata); [References](../references.md) gives them in full.", "",
             "| material | kind | description |", "|---|---|---|"]
    for name in sorted(LIBRARY):
        e = LIBRARY[name]
        lines.append(f"| [`{name}`](#{name}) | {kinds[type(e).__name__]} | {_clean(e.description)} |")
    for name in sorted(LIBRARY):
        e = LIBRARY[name]
        lines += ["", f"## `{name}` {{#{name}}}", "", f"{kinds[type(e).__name__]}: {_clean(e.description)}", "",
                  "| constant | value | unit | allowed | why | source |", "|---|---|---|---|---|---|"]
        for c in material_rows(e):
            lines.append(f"| `{c.name}` | {c.value:g} | {c.unit} | {c.allowed} | {_clean(c.why)} | "
                         f"{_clean(c.source)} |")
        for order in getattr(e, "ORDER", ()):
            lines.append(f"\nAlso `{order.lower}` {'<' if order.strict else '<='} `{order.upper}`: {order.why}.")
    lines += ["", "## Abbreviations of the sources", "", _solids_abbreviations()]
    return "\n".join(lines)


def _solids_abbreviations() -> str:
    """The abbreviation list of :mod:`blastfsi.materials.solids` (its docstring), as Markdown."""
    from blastfsi.materials import solids

    doc = solids.__doc__.split("Abbreviations used in the sources:")[1]
    items = re.split(r"\n\* ", "\n" + doc.strip())
    return "\n".join(f"- {' '.join(i.split())}" for i in items if i.strip())


# --- examples -------------------------------------------------------------------------------------------------

# A figure of the verification and validation pages that shows an example's case (paths relative to docs/); the
# cheap examples have a picture of their own, docs/figures/examples/<name>.png (scripts/docs/example_pictures.py).
DOCS = Path(__file__).resolve().parents[2] / "docs"
FIGURES = {
    "he-slab-2d-mpm": "figures/he_slab_2d_fig12.png",
    "plate1d-uniform": "figures/fig5_impulse.png",
    "plate1d-exponential": "figures/fig7_exponential.png",
    "plate1d-sedov": "figures/sedov_plates.png",
    "he-slab-2d": "figures/he_slab_2d_slab.png",
    "concrete-slab-blast": "figures/concrete_slab_faces.png",
    "concrete-slab-defect": "figures/concrete_slab_defect_faces.png",
    "steel-plate-blast": "figures/plate_structural.png",
    "steel-plate-blast-case4": "figures/plate_load.png",
}


class Example(NamedTuple):
    name: str
    method: str
    description: str
    dimensions: str
    end: float


def examples() -> list[Example]:
    out = []
    for f in sorted(resources.files("blastfsi.examples").iterdir(), key=lambda p: p.name):
        if not f.name.endswith(".toml"):
            continue
        data = tomllib.loads(f.read_text(encoding="utf-8"))
        m = data.get("method", "lagrangian1d")
        out.append(Example(f.name[:-5], m, data.get("description", ""), _dimensions(data, m), data["time"]["end"]))
    return out


def _dimensions(data: dict, m: str) -> str:
    if m == "lagrangian1d":
        return f"1D {data.get('domain', {}).get('geometry', 'planar')}"
    if m == "mpm":
        g = data["grid"]
        return "2D r–z" if g.get("axisymmetric") else f"{len(g['lower'])}D"
    d = data["domain"]
    geometry = d.get("geometry", "cartesian")
    return {"axisymmetric": "2D r–z", "cylindrical": "1D cylindrical", "spherical": "1D spherical"}.get(
        geometry, f"{len(d['lower'])}D")


def picture_runs() -> dict:
    """What scripts/docs/example_pictures.py ran for each picture (docs/figures/examples/pictures.json)."""
    path = DOCS / "figures" / "examples" / "pictures.json"
    return json.loads(path.read_text(encoding="utf-8"))["runs"] if path.is_file() else {}


def figure_of(name: str) -> str | None:
    """The picture of an example, relative to docs/: its own from a short run, else a V&V figure, else None."""
    own = f"figures/examples/{name}.png"
    return own if (DOCS / own).is_file() else FIGURES.get(name)


def examples_gallery() -> str:
    lines = ["# Examples", "",
             "Every shipped scenario (`blastfsi examples` lists them; `blastfsi run --example NAME` runs one; "
             "its file is `src/blastfsi/examples/NAME.toml`, a starting point for your own case). Generated "
             "from the example files; the pictures of the quick examples come from short runs "
             "(`scripts/docs/example_pictures.py`), those of the long coupled ones from the verification and validation "
             "pages, and the 3D and parameter-variant examples have none.", "",
             "| example | method | geometry | simulated time | what it is |", "|---|---|---|---|---|"]
    for e in examples():
        lines.append(f"| [`{e.name}`](#{e.name}) | `{e.method}` | {e.dimensions} | {e.end:g} s | "
                     f"{_clean(e.description)} |")
    for e in examples():
        lines += ["", f"## `{e.name}` {{#{e.name}}}", "", _clean(e.description).replace("\\|", "|"), "",
                  f"```bash\nblastfsi run --example {e.name}\n```"]
        figure = figure_of(e.name)
        if figure:
            lines += ["", f"![{e.name}]({figure})"]
            coarse = {k: v for k, v in picture_runs().get(e.name, {}).get("set", {}).items() if k != "output.fields"}
            if coarse:
                lines += ["", "(picture from a coarser run: " + ", ".join(f"`{k} = {v}`" for k, v in coarse.items())
                          + ")"]
    return "\n".join(lines)
