"""One library of named, sourced material constant sets.

Each family lives in its own module (``gases``; solids are added beside it) as
frozen dataclasses whose fields carry the constants and whose ``sources``
mapping names the reference of every constant. :func:`lookup` resolves a name,
applying scenario overrides key by key with a clear error for unknown keys.
"""
from __future__ import annotations

import dataclasses

from blastfsi.materials.gases import GASES
from blastfsi.materials.solids import SOLIDS

LIBRARY: dict[str, object] = {**GASES, **SOLIDS}


class MaterialError(ValueError):
    """Unknown material or an override that the material does not have."""


def lookup(name: str, overrides: dict | None = None, *, field: str = "material"):
    """The constant set ``name`` with ``overrides`` applied (dataclasses.replace).

    ``field`` is the scenario key naming the material, quoted when the name is unknown;
    an unknown or non-numeric override is reported as ``materials.<name>.<key>``.
    """
    if name not in LIBRARY:
        raise MaterialError(f"{field}: unknown material {name!r}; available: {', '.join(sorted(LIBRARY))}")
    entry = LIBRARY[name]
    overrides = dict(overrides or {})
    names = {f.name for f in dataclasses.fields(entry)} - {"sources", "description"}
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise MaterialError(f"materials.{name}: material {name!r} has no key(s) {unknown}; "
                            f"its keys: {sorted(names)}")
    for key, value in overrides.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise MaterialError(f"materials.{name}.{key}: expected a number, got {value!r}")
    return dataclasses.replace(entry, **{k: float(v) for k, v in overrides.items()})
