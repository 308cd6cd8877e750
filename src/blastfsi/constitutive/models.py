"""Importing this module registers every constitutive model of the package.

Registered names: ``elastic``, ``fluid``, ``johnson-cook``, ``hjc``, ``drucker-prager``;
each library material of :mod:`blastfsi.materials.solids` names its model in ``model``
(gases use ``fluid``). An all-zero ``history`` is every model's virgin state except
burning explosive particles (see :func:`blastfsi.constitutive.fluid.initial_history`).
"""
from blastfsi.constitutive import drucker_prager, elastic, fluid, hjc, johnson_cook  # noqa: F401
