"""blastfsi: air-blast and blast-structure interaction solvers built on JAX.

Importing the package changes no JAX setting: each run computes in its scenario's
``numerics.precision`` (float64 by default, DESIGN.md; float32 selectable), set for
the run's duration only, and keeps its compiled time loop in a persistent cache
(:mod:`blastfsi.runtime`).

Python API (:mod:`blastfsi.api`, the command line's engine)::

    res = blastfsi.run("plate1d-uniform", set={"grid.cells": 2000})
    res.summary, res.fields(), res.history, res.gauges
"""
from blastfsi.api import Result, restart, run

__version__ = "0.1.0"

__all__ = ["Result", "restart", "run"]
