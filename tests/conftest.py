import os

import jax
import pytest

# Runs set their own precision (numerics.precision), but many tests call the kernels directly on float64
# arrays and compare with float64 references: the test process computes in float64, as a user's script
# calling the kernels would after jax.config.update("jax_enable_x64", True). (tests/test_precision.py checks
# in a fresh interpreter that importing blastfsi leaves the setting alone.)
jax.config.update("jax_enable_x64", True)
# No persistent compilation cache: the suite never writes to the user's cache directory, and each test
# compiles what it runs (tests/test_runtime.py exercises the cache in a temporary directory).
os.environ["BLASTFSI_NO_CACHE"] = "1"

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
