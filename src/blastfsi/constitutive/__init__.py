"""Constitutive models of the MPM solver, registered by name (CB-Geo style).

Every model is a :class:`Model`: pure functions on the arrays of all particles
of one material (leading axis n), no branching on strings inside them.

* Stress in Voigt order ``[xx, yy, zz, yz, xz, xy]`` (Cauchy, tension positive),
  shape (n, 6), also in 1D and 2D (plane strain / axisymmetric keep all six).
* ``update(ps, dstrain, dspin, dt, params) -> PointState``: the stress update
  over one step from the strain increment ``dstrain`` (n, 3, 3, symmetric part
  of the velocity gradient times dt) and spin increment ``dspin`` (n, 3, 3,
  antisymmetric part times dt), including the objective (Jaumann) rotation,
  000 Eq. (30), and the internal-energy update of 000 Eq. (13) for the stress
  work. ``ps.density`` is already the updated density when ``update`` is called.
* ``wave_speed(ps, params) -> (n,)``: the longitudinal signal speed for the CFL step.
* ``params_from(material) -> Params``: the traced parameter NamedTuple from a
  library entry of :mod:`blastfsi.materials`.
* ``history_size``: columns of ``ps.history`` the model uses.
* ``output_fields(history, params) -> dict``: named per-particle quantities derived from the
  history columns for the snapshots (host side, NumPy; e.g. a temperature, a damage split).
"""
from __future__ import annotations

from typing import Callable, NamedTuple


class PointState(NamedTuple):
    stress: object  # (n, 6) Voigt, Pa
    density: object  # (n,) current density, kg/m^3
    energy: object  # (n,) specific internal energy, J/kg
    plastic_strain: object  # (n,) equivalent plastic strain
    damage: object  # (n,) 0 (intact) .. 1 (failed)
    history: object  # (n, H) model-specific (temperature, tensile damage, burn fraction, ...)


def no_output_fields(history, params) -> dict:
    return {}


class Model(NamedTuple):
    name: str
    update: Callable
    wave_speed: Callable
    params_from: Callable
    history_size: int
    output_fields: Callable = no_output_fields


MODELS: dict[str, Model] = {}


def register(model: Model) -> Model:
    if model.name in MODELS:
        raise ValueError(f"constitutive model {model.name!r} registered twice")
    MODELS[model.name] = model
    return model


def get(name: str) -> Model:
    if name not in MODELS:
        raise KeyError(f"unknown constitutive model {name!r}; available: {', '.join(sorted(MODELS))}")
    return MODELS[name]
