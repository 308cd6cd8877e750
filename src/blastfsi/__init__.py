"""blastfsi: air-blast and blast-structure interaction solvers built on JAX.

float64 is the default precision (DESIGN.md); set ``BLASTFSI_X64=0`` before the
first import to compute in float32.

Python API (:mod:`blastfsi.api`, the command line's engine)::

    res = blastfsi.run("plate1d-uniform", set={"grid.cells": 2000})
    res.summary, res.fields(), res.history, res.gauges
"""
import os

import jax

jax.config.update("jax_enable_x64", os.environ.get("BLASTFSI_X64", "1") != "0")

__version__ = "0.1.0"

from blastfsi.api import Result, restart, run  # noqa: E402  (after the precision is set)

__all__ = ["Result", "restart", "run"]
