"""Throughput of the 1D vNR solver (issue 2, item 6). Not run by the tests.

    python benchmarks/bench_plate1d.py [--out FILE]

Measures (a) one plate1d-uniform run at 5000 cells, (b) the whole 002 Fig. 5
sweep (5 intensities x 13 beta_s = 65 members, 1000 cells) as one batched call.
Each is run twice: the first includes JIT compilation, the second is reported.
Throughput = members x cells x steps / wall time (cell-updates per second).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import jax
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "figures"))
from make_002_figures import fig5_batch  # noqa: E402

from blastfsi import simulation  # noqa: E402
from blastfsi.cli import example_data  # noqa: E402


def timed(data):
    t0 = time.perf_counter()
    res = simulation.run(data)
    jax.block_until_ready(res.state.x)
    return time.perf_counter() - t0, res


def measure(name, data):
    first, _ = timed(data)
    wall, res = timed(data)
    cells = res.setups[0].zone_mass.size
    steps = int(np.max(np.asarray(res.state.step)))
    members = len(res.setups)
    return {"case": name, "members": members, "cells": cells, "steps": steps, "wall_s_first_with_compile": first,
            "wall_s": wall, "cell_updates_per_s": members * cells * steps / wall}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    data = example_data("plate1d-uniform")
    data["output"] = {"history_samples": 1001, "fields": 0, "plots": False}
    rows = [measure("plate1d-uniform, 5000 cells", data)]
    _, _, batch = fig5_batch(1000)
    rows.append(measure("Fig. 5 sweep, 65 members x 1000 cells, one batched call", batch))
    report = {"device": str(jax.devices()[0]), "backend": jax.default_backend(), "cpu_count": os.cpu_count(),
              "machine": platform.processor() or platform.machine(), "jax": jax.__version__,
              "precision": "float64", "rows": rows}
    text = json.dumps(report, indent=2)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
