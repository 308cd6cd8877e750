"""The JSON Schema of a scenario file (``blastfsi schema [METHOD]``), for editors and other tools.

An editor validates and completes a TOML scenario against it with a first line ``#:schema ./file.json``
(taplo, and VS Code's Even Better TOML, which uses taplo).

* :func:`scenario_schema` of one method: pydantic's validation schema of the method's scenario model
  (``Method.scenario_model``), with ``method`` required except for the default method (a file without it
  is a ``lagrangian1d`` scenario). The most precise: an error names the key at fault.
* without a method: one schema for every method, a ``oneOf`` of the methods' schemas (each under
  ``$defs/<method>``, its own definitions renamed ``<method>.<name>``) told apart by ``method``; an editor
  completes the keys of all methods, and a wrong key is reported as matching none of them.

The schema is what the scenario models declare (keys, types, ranges, defaults, descriptions); the run also
checks what a schema cannot say: strict types (JSON Schema counts 100.0 as an integer, the scenario does
not) and the conditions across keys (a gauge inside the domain, ...).
"""
from __future__ import annotations

from blastfsi import method as methods
from blastfsi.scenario import DEFAULT_METHOD

DIALECT = "https://json-schema.org/draft/2020-12/schema"  # the JSON Schema version pydantic writes


def method_schema(name: str) -> dict:
    """The JSON Schema of a scenario of method ``name`` (its definitions under ``$defs``); KeyError with
    the available methods for an unknown one."""
    schema = methods.get(name).scenario_model.model_json_schema(mode="validation")
    if name != DEFAULT_METHOD:
        schema["required"] = ["method", *(k for k in schema.get("required", []) if k != "method")]
    return schema


def scenario_schema(method: str | None = None) -> dict:
    """The JSON Schema of a scenario of ``method``, or of any method (module docstring)."""
    if method is not None:
        return {"$schema": DIALECT, **method_schema(method)}
    names = methods.available()
    defs = {}
    for name in names:
        one = method_schema(name)
        for key, value in one.pop("$defs", {}).items():
            defs[f"{name}.{key}"] = _renamed(value, name)
        defs[name] = _renamed(one, name)
    return {"$schema": DIALECT, "title": "blastfsi scenario",
            "description": f"a scenario of any method, told apart by the key `method` (default {DEFAULT_METHOD!r})",
            "type": "object", "oneOf": [{"$ref": f"#/$defs/{name}"} for name in names], "$defs": defs}


def _renamed(node, name: str):
    """``node`` with its references to ``#/$defs/X`` made ``#/$defs/<name>.X``."""
    if isinstance(node, dict):
        return {k: (f"#/$defs/{name}.{v.removeprefix('#/$defs/')}" if k == "$ref" and isinstance(v, str)
                    and v.startswith("#/$defs/") else _renamed(v, name)) for k, v in node.items()}
    if isinstance(node, list):
        return [_renamed(v, name) for v in node]
    return node
