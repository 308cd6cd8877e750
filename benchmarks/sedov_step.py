"""What sets the time step of the 2D point blast (issue 38, item 2): the schemes' step counts on ``sedov-2d``
at one Courant number, their hot interior against the exact solution, and the step the exact solution itself
would need on the same grid.

    python benchmarks/sedov_step.py [--cells 200] [--cfl 0.5] [--out benchmarks/sedov_step.json]

For each scheme: steps to t = 1, the largest sound speed at the end, the mean density inside r < 0.3 (the
blast's radius is 1.0 at t = 1) and the mean |rho - exact| inside r < 0.5. For the exact cylindrical Sedov
solution (:class:`blastfsi.exact.sedov.Sedov`) sampled at the cell centres: the largest signal speed
|u_d| + c over the cells farther than k cells from the centre (k = 0, 2, 5) at t = 0.25, 0.5, 1 and the
step it allows at the same Courant number. Not run by the tests.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import blastfsi
from blastfsi.exact.sedov import Sedov
from machine import described

SCHEMES = ("lax-wendroff", "hllc-hancock", "hllc-muscl")
HALF_WIDTH = 1.2  # sedov-2d's domain [-1.2, 1.2]^2


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=200)
    ap.add_argument("--cfl", type=float, default=0.5)
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    n, cfl = args.cells, args.cfl
    dx = 2.0 * HALF_WIDTH / n
    centres = -HALF_WIDTH + (np.arange(n) + 0.5) * dx
    X, Y = np.meshgrid(centres, centres, indexing="ij")
    R = np.hypot(X, Y)
    exact = Sedov(1.0, 1.0, 1.4, "cylindrical")  # sedov-2d: E = 1 per unit length, rho0 = 1, gamma 1.4

    need = []
    for t in (0.25, 0.5, 1.0):
        rho, u, p = exact(R, t)
        axis_speed = np.abs(u) * np.maximum(np.abs(X), np.abs(Y)) / np.maximum(R, 1e-300)  # max_d |u_d|
        rate = axis_speed + np.sqrt(1.4 * p / np.maximum(rho, 1e-300))
        for k in (0, 2, 5):
            fastest = float(rate[R > k * dx].max())
            need.append({"t": t, "beyond_cells": k, "max_signal": fastest, "dt": cfl * dx / fastest})
            print(f"exact, t = {t}: largest |u_d| + c beyond {k} cells of the centre {fastest:.4g}, "
                  f"dt {cfl * dx / fastest:.3e}", flush=True)

    rho_end = exact(R, 1.0)[0]
    runs = {}
    for scheme in SCHEMES:
        r = blastfsi.run("sedov-2d", set={"grid.cells": n, "numerics.scheme": scheme, "numerics.cfl": cfl,
                                          "output.fields": 0, "output.plots": False})
        f = r.fields()
        rho = np.asarray(f["density"])
        runs[scheme] = {"steps": r.summary["steps"], "loop_s": round(r.summary["loop_time"], 2),
                        "max_sound_speed_end": float(np.max(f["sound_speed"])),
                        "mean_density_r_below_0.3": float(rho[R < 0.3].mean()),
                        "mean_abs_density_error_r_below_0.5": float(np.mean(np.abs(rho - rho_end)[R < 0.5]))}
        print(scheme, runs[scheme], flush=True)
    record = {"machine": described(), "command": "python benchmarks/sedov_step.py " + " ".join(argv or []),
              "cells": n, "cfl": cfl, "exact_mean_density_r_below_0.3": float(rho_end[R < 0.3].mean()),
              "runs": runs, "exact_step": need}
    print("exact mean density inside r < 0.3:", record["exact_mean_density_r_below_0.3"])
    args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    import sys
    main(sys.argv[1:])
