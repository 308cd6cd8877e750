"""One library of named, sourced material constant sets.

Each family lives in its own module (``gases``; solids are added beside it) as
frozen dataclasses whose fields carry the constants, each with its valid range
and the physical reason for it (:mod:`blastfsi.materials.ranges`), and whose
``sources`` mapping names the reference of every constant. :func:`lookup`
resolves a name, applying scenario overrides key by key with a clear error for
unknown keys and for constants outside their ranges; :func:`check_overrides`
validates a scenario's ``[materials]`` table against the materials it uses.
"""
from __future__ import annotations

import dataclasses

from blastfsi.materials import ranges
from blastfsi.materials.gases import GASES
from blastfsi.materials.solids import SOLIDS

LIBRARY: dict[str, object] = {**GASES, **SOLIDS}


class MaterialError(ValueError):
    """Unknown material, an override that the material does not have, or a constant outside its range."""


def lookup(name: str, overrides: dict | None = None, *, field: str = "material"):
    """The constant set ``name`` with ``overrides`` applied (dataclasses.replace), every constant checked
    against its range.

    ``field`` is the scenario key naming the material, quoted when the name is unknown;
    an unknown, non-numeric or out-of-range constant is reported as ``materials.<name>.<key>``.
    """
    if name not in LIBRARY:
        raise MaterialError(f"{field}: unknown material {name!r}; available: {', '.join(sorted(LIBRARY))}")
    entry = LIBRARY[name]
    overrides = dict(overrides or {})
    names = set(ranges.ranges(entry))
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise MaterialError(f"materials.{name}: material {name!r} has no key(s) {unknown}; "
                            f"its keys: {sorted(names)}")
    for key, value in overrides.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise MaterialError(f"materials.{name}.{key}: expected a number, got {value!r}")
    entry = dataclasses.replace(entry, **{k: float(v) for k, v in overrides.items()})
    try:
        ranges.check(entry, f"materials.{name}.")
    except ValueError as err:
        raise MaterialError(str(err)) from None
    return entry


def check_overrides(overrides: dict, used: dict[str, str]) -> None:
    """Validate a scenario's ``[materials]`` table: every library material in ``used`` (name -> the scenario
    key naming it) resolves with its overrides (:func:`lookup`), and every overridden material is in use (an
    override of an unused material is a typo that would otherwise be ignored). A name not in the library is
    left to the method, which says what kind of material it needs there (an explosive, a gas, ...)."""
    unused = sorted(set(overrides) - set(used))
    if unused:
        raise MaterialError(f"materials.{unused[0]}: overrides a material this scenario does not use; materials in "
                            f"use: {', '.join(sorted(used)) or 'none'}")
    for name, key in used.items():
        if name in LIBRARY:
            lookup(name, overrides.get(name), field=key)
