"""The user guide (docs/, built by mkdocs in CI): its generated pages cover the code's data, and the scenario files
of its guides are valid scenarios. Fast: no run, no mkdocs."""
from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import jax
import pytest

from blastfsi import method as methods
from blastfsi.materials import LIBRARY, ranges
from blastfsi.scenario import parse, read_toml

ROOT = Path(__file__).resolve().parents[1]
GUIDES = sorted((ROOT / "docs" / "guides").glob("*.toml"))


def _load_reference():
    spec = importlib.util.spec_from_file_location("docs_reference", ROOT / "scripts" / "docs" / "reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


reference = _load_reference()


def _schema_paths(schema: dict, defs: dict, prefix: str = "") -> set[str]:
    """Every key path of a JSON Schema (pydantic's), walked independently of the generator: objects' properties,
    arrays of objects (``[]``), unions (anyOf / oneOf) and $ref."""
    if "$ref" in schema:
        return _schema_paths(defs[schema["$ref"].split("/")[-1]], defs, prefix)
    out = set()
    for sub in schema.get("anyOf", []) + schema.get("oneOf", []):
        out |= _schema_paths(sub, defs, prefix)
    if schema.get("type") == "array" and isinstance(schema.get("items"), dict):
        out |= _schema_paths(schema["items"], defs, prefix + "[]")
    for name, sub in schema.get("properties", {}).items():
        path = f"{prefix}.{name}" if prefix else name
        out.add(path)
        out |= _schema_paths(sub, defs, path)
    return out


@pytest.mark.parametrize("name", reference.METHODS)
def test_scenario_reference_covers_every_key_of_the_schema(name):
    """Every key of the method's JSON Schema has a row, and every row a key; every leaf key has a meaning."""
    model = methods.get(name).scenario_model
    schema = model.model_json_schema()
    expected = _schema_paths(schema, schema.get("$defs", {}))  # "bodies[].material": a key of each [[bodies]]
    keys = reference.scenario_keys(model)
    documented = {k.path for k in keys}
    assert expected - documented == set(), f"keys without a row in the scenario reference: {expected - documented}"
    assert documented - expected == set(), f"rows that are not keys: {documented - expected}"
    page = reference.scenario_reference()
    for k in keys:
        assert f"| `{k.path}` |" in page
        if k.type != "table":
            assert k.meaning, f"{name}: {k.path} has no description in the schema"


def test_scenario_reference_states_ranges_and_defaults_from_the_schema():
    """Point values read off the schema by hand: a bound, a default, a required key, a unit and a variant."""
    keys = {(k.path, k.variant): k for k in reference.scenario_keys(methods.get("euler").scenario_model)}
    cfl = keys[("numerics.cfl", "")]
    assert cfl.default == "`0.5`" and cfl.allowed == "> 0, <= 1.5"  # (the largest scheme cap, lax-wendroff)
    assert keys[("grid.cells", "")].default == "**required**"
    assert keys[("grid.cells", "")].allowed == ">= 4, <= 100 000"
    mass = keys[("initial.mass", 'initial.kind = "charge"')]
    assert mass.unit == "kg" and mass.default == "none"
    assert keys[("domain.lower", "")].unit == "m"
    assert ("initial.diaphragm", 'initial.kind = "riemann"') in keys


def test_material_library_page_lists_every_constant_with_unit_range_and_source():
    page = reference.materials_reference()
    for name, entry in LIBRARY.items():
        assert f"## `{name}`" in page
        rows = reference.material_rows(entry)
        assert {r.name for r in rows} == set(ranges.ranges(entry))
        for r in rows:
            assert r.unit, f"{name}.{r.name}: no unit"
            assert r.source, f"{name}.{r.name}: no source"
            assert re.search(rf"\| `{re.escape(r.name)}` \| {re.escape(f'{r.value:g}')} \|", page)


def test_examples_gallery_lists_every_example_and_shows_existing_pictures():
    from blastfsi.api import example_names

    page = reference.examples_gallery()
    for name in example_names():
        assert f"## `{name}`" in page
    assert set(reference.FIGURES) <= set(example_names())
    for name in example_names():
        figure = reference.figure_of(name)
        if figure is not None:
            assert (ROOT / "docs" / figure).is_file()
            assert f"![{name}]({figure})" in page


def test_example_descriptions_say_what_the_case_is_in_words():
    """No bare paper numbers ("seed 000 Sec.", "002 Sec.") or issue talk in a description."""
    for e in reference.examples():
        assert e.description, e.name
        assert not re.search(r"\bseed\b|\bissue \d|\b00[02] (Sec|Eq|Fig)", e.description, re.I), e.name


def test_there_is_a_guide_scenario_for_each_guide_page():
    pages = {p.stem for p in (ROOT / "docs" / "guides").glob("*.md")}
    assert pages == {p.stem for p in GUIDES} == {"close-in-plate", "standoff-wall", "concrete-slab"}
    for p in GUIDES:
        assert f'--8<-- "guides/{p.name}"' in (p.with_suffix(".md")).read_text(encoding="utf-8")


@pytest.mark.parametrize("path", GUIDES, ids=[p.stem for p in GUIDES])
def test_guide_scenario_validates(path):
    assert parse(read_toml(path)).name == f"my-{path.stem}"


# The stand-off charge's build runs its 1D detonation on to time.end for the blast faces (~10 s of CPU): slow.
BUILDS = [pytest.param(p, marks=pytest.mark.slow) if p.stem == "standoff-wall" else p for p in GUIDES]


@pytest.mark.parametrize("path", BUILDS, ids=[p.stem for p in GUIDES])
def test_guide_scenario_builds(path):
    """The method builds its initial state from it, as `blastfsi run` does before the first step: the checks that
    need the layout (a structure clear of the bridge) and, for a charge, the 1D detonation up to the remap."""
    sc = parse(read_toml(path))
    with jax.enable_x64(sc.numerics.precision == "float64"):  # as the driver runs it
        setup = methods.get(sc.method).build(sc)
    assert setup.cells > 0


def test_standoff_guide_puts_the_charge_outside_the_domain():
    sc = parse(read_toml(ROOT / "docs" / "guides" / "standoff-wall.toml"))
    inside = all(lo <= c <= hi for c, lo, hi in zip(sc.initial.center, sc.domain.lower, sc.domain.upper))
    assert sc.initial.kind == "charge" and not inside


def test_mkdocs_nav_names_existing_or_generated_pages():
    """Every page of mkdocs.yml's nav exists in docs/ or is written by the generator (gen_pages.PAGES)."""
    nav = re.findall(r":\s*([\w/.-]+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(encoding="utf-8"), re.M)
    generated = set(re.findall(r'"([\w/.-]+\.md)":', (ROOT / "scripts" / "docs" / "gen_pages.py").read_text()))
    assert nav
    for page in nav:
        assert (ROOT / "docs" / page).is_file() or page in generated, page

