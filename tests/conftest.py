import pytest

import blastfsi  # noqa: F401  (enables float64)

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
