"""Valid ranges of material constants, declared once beside each constant.

A library dataclass declares every numeric constant with :func:`constant`, which
records its range (any of gt, ge, lt, le) and the physical reason for it, and may
list ordered pairs of its constants in ``ORDER`` (e.g. room < melting temperature).
:func:`check` reports the first constant that is non-finite, outside its range
or out of order, naming the key and the allowed range; the scenario validation
(:func:`blastfsi.materials.lookup`) and the constitutive models' ``params_from``
both call it, so no model repeats the checks.
"""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple, Optional

_SYMBOLS = (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<="))


class Range(NamedTuple):
    """An interval of allowed values and why values outside it are unphysical."""

    why: str
    gt: Optional[float] = None
    ge: Optional[float] = None
    lt: Optional[float] = None
    le: Optional[float] = None

    def contains(self, value: float) -> bool:
        return (math.isfinite(value)
                and (self.gt is None or value > self.gt) and (self.ge is None or value >= self.ge)
                and (self.lt is None or value < self.lt) and (self.le is None or value <= self.le))

    def text(self) -> str:
        bounds = [f"{sym} {getattr(self, k):g}" for k, sym in _SYMBOLS if getattr(self, k) is not None]
        return " and ".join(bounds) if bounds else "any finite value"


class Order(NamedTuple):
    """Constants ``lower`` < ``upper`` (or <= when not ``strict``) and why."""

    lower: str
    upper: str
    why: str
    strict: bool = True


def constant(why: str, *, gt: float | None = None, ge: float | None = None, lt: float | None = None,
             le: float | None = None):
    """A dataclass field (no default) for a material constant with its valid range and the physical reason."""
    return dataclasses.field(metadata={"range": Range(why, gt, ge, lt, le)})


def ranges(entry) -> dict[str, Range]:
    """Constant name -> its declared range, for a library dataclass (or its class)."""
    return {f.name: f.metadata["range"] for f in dataclasses.fields(entry) if "range" in f.metadata}


def check(entry, prefix: str = "") -> None:
    """ValueError naming ``prefix + key`` for the first constant of ``entry`` outside its range or order."""
    for key, rng in ranges(entry).items():
        value = getattr(entry, key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not rng.contains(float(value)):
            raise ValueError(f"{prefix}{key} = {_show(value)} is outside its valid range {rng.text()} ({rng.why})")
    for order in getattr(entry, "ORDER", ()):
        lo, hi = getattr(entry, order.lower), getattr(entry, order.upper)
        if not (lo < hi if order.strict else lo <= hi):
            raise ValueError(f"{prefix}{order.upper} = {_show(hi)} must be {'>' if order.strict else '>='} "
                             f"{prefix}{order.lower} = {_show(lo)} ({order.why})")


def _show(value) -> str:
    return f"{float(value):g}" if isinstance(value, (int, float)) and not isinstance(value, bool) else repr(value)
