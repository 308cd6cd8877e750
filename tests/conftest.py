import os
import shutil
import tempfile

import jax
import pytest

# Runs set their own precision (numerics.precision), but many tests call the kernels directly on float64
# arrays and compare with float64 references: the test process computes in float64, as a user's script
# calling the kernels would after jax.config.update("jax_enable_x64", True). (tests/test_precision.py checks
# in a fresh interpreter that importing blastfsi leaves the setting alone.)
jax.config.update("jax_enable_x64", True)
# The suite's time is compilation, not computation (most tests run a few hundred steps of a small grid):
# * LLVM optimises the kernels at level 0 (XLA's default is 2): he-slab-2d compiles in 18 s instead of 24 s
#   and runs its 280 steps 2.7x slower (benchmarks/compile_flags.json). The XLA programs are the same; the
#   machine code orders some sums differently, so results agree with the default's to round-off, not bit for
#   bit (cfdmp-shock-tube, 68 steps: the fields within 7e-16 of their largest values; the budget residuals,
#   round-off themselves, in their leading digits). The examples and benchmarks run at the default. A level
#   set in XLA_FLAGS is kept.
# * One persistent compilation cache for the session, in a temporary directory that the controller makes,
#   its xdist workers share and the controller removes at the end (pytest_configure / pytest_unconfigure),
#   never the user's: a program that several tests run compiles once. Runs use the cache as a user's run
#   does by default (tests/test_runtime.py checks the cache itself in directories of its own).
if "xla_backend_optimization_level" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()
os.environ.pop("BLASTFSI_NO_CACHE", None)


def pytest_configure(config):
    if not hasattr(config, "workerinput"):  # the controller (or the one process of -n 0)
        config.blastfsi_cache = tempfile.mkdtemp(prefix="blastfsi-test-cache-")
        os.environ["BLASTFSI_CACHE_DIR"] = config.blastfsi_cache  # (inherited by the workers it starts)


def pytest_unconfigure(config):
    if hasattr(config, "blastfsi_cache"):
        shutil.rmtree(config.blastfsi_cache, ignore_errors=True)

P0, RHO0 = 1.048e5, 1.225  # 002 Sec. 3 air (ERRATA 002-7)


def uniform_data(**over):
    """A small uniform-shock scenario as a raw dict."""
    data = {
        "name": "t-uniform",
        "incident": {"profile": "uniform", "overpressure": 4.49 * P0},
        "plate": {"beta_s": 1.0},
        "domain": {"length": 2.0},
        "grid": {"cells": 400},
        "time": {"end": 2.0 / 761.9 + 2.5e-4},
        "output": {"history_samples": 201, "fields": 3, "plots": False},
    }
    for key, value in over.items():
        node = data
        parts = key.split("__")
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        if value is None:
            node.pop(parts[-1], None)
        else:
            node[parts[-1]] = value
    return data


@pytest.fixture
def small_uniform():
    return uniform_data
