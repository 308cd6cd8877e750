"""What numerics.limiting changes in the HLLC schemes: the two limitings side by side on the Eulerian
verification problems (docs/verification.md, Eulerian solver, items 1-3).

    .venv/bin/python benchmarks/limiting_check.py [--out benchmarks/limiting_check.json]

* Sod (the CFDMP paper's Sec. 5.1 in SI, exact: blastfsi.exact.riemann.sod_000) at 100-1000 cells: L1 of
  rho [kg/m^2], u [m^2/s], p [Pa m] over the 1 mm tube, and the observed order of rho per doubling;
* the smooth density wave (rho = 1 + 0.2 sin 2 pi sum x_d, u_d = 1, p = 1, one period on the periodic unit
  box) in 1D (64-512 cells) and 2D diagonal (64-256): mean |rho - exact| and observed orders;
* TNT products | air at uniform p = 1 GPa, u = 2 km/s carried once round a periodic 1 m domain (100
  cells): the largest relative p and u deviations.

Each for hllc-muscl with numerics.limiting = characteristic (the default) and primitive.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import euler
from blastfsi.eos.jwl import ideal_gas_params
from blastfsi.exact.riemann import sod_000
from blastfsi.materials.gases import GASES

from machine import described  # benchmarks/machine.py

jax.config.update("jax_enable_x64", True)  # the kernels called directly, on float64 arrays

AIR = ideal_gas_params(1.4)
TNT = GASES["tnt"].eos_params()
LIMITINGS = {"characteristic": True, "primitive": False}


def _params(*rows):
    return euler.Params(jnp.asarray([list(r) for r in rows]), jnp.asarray(0.5))


def _config(n, ndim, bc, characteristic, materials=1, origin=0.0, length=1.0):
    return euler.Config((n,) * ndim, length / n, 0, (bc,) * ndim, euler.HLLC_MUSCL, materials, (origin,) * ndim,
                        characteristic=characteristic)


def _centres(cfg):
    return np.meshgrid(*[cfg.origin[d] + (np.arange(m) + 0.5) * cfg.dx for d, m in enumerate(cfg.shape)],
                       indexing="ij")


def sod(n, characteristic):
    case = sod_000()
    (x0, x1), pb = case.domain, case.problem
    cfg = _config(n, 1, (euler.OUTFLOW, euler.OUTFLOW), characteristic, origin=x0, length=x1 - x0)
    x = _centres(cfg)[0]
    left = x < pb.x0
    prm = _params(AIR)
    U = euler.conservative(jnp.asarray(np.where(left, pb.left[0], pb.right[0])), None, jnp.zeros((1, n)),
                           jnp.asarray(np.where(left, pb.left[2], pb.right[2])), prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, case.end_time, cfg), prm, cfg)
    rho, u, p = pb(x, case.end_time)
    return [float(np.sum(np.abs(np.asarray(a) - b)) * cfg.dx)
            for a, b in ((out["rho"], rho), (out["velocity"][0], u), (out["pressure"], p))]


def wave(n, ndim, characteristic):
    cfg = _config(n, ndim, (euler.PERIODIC, euler.PERIODIC), characteristic)
    exact = 1.0 + 0.2 * np.sin(2 * np.pi * sum(_centres(cfg)))
    prm = _params(AIR)
    U = euler.conservative(jnp.asarray(exact), None, jnp.ones((ndim,) + cfg.shape), jnp.ones(cfg.shape), prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, 1.0, cfg), prm, cfg)
    return float(np.mean(np.abs(np.asarray(out["rho"]) - exact)))


def interface(characteristic, n=100, p0=1.0e9, u0=2000.0):
    cfg = _config(n, 1, (euler.PERIODIC, euler.PERIODIC), characteristic, materials=2)
    x = _centres(cfg)[0]
    prm = _params(TNT, AIR)
    U = euler.conservative(jnp.stack([jnp.full(n, 1000.0), jnp.full(n, 50.0)]),
                           jnp.asarray(np.where((x > 0.25) & (x < 0.75), 1.0, 0.0)), jnp.full((1, n), u0),
                           jnp.full(n, p0), prm, cfg)
    out = euler.primitives(euler.advance_to(U, prm, 1.0 / u0, cfg), prm, cfg)
    return {"pressure": float(jnp.max(jnp.abs(out["pressure"] / p0 - 1.0))),
            "velocity": float(jnp.max(jnp.abs(out["velocity"][0] / u0 - 1.0)))}


def _orders(errors, cells):
    return [float(np.log(errors[i] / errors[i + 1]) / np.log(cells[i + 1] / cells[i])) for i in range(len(cells) - 1)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    out = {"machine": described(), "scheme": "hllc-muscl (van Leer)", "results": {}}
    started = time.perf_counter()
    for name, characteristic in LIMITINGS.items():
        res = out["results"][name] = {}
        cells = [100, 200, 400, 800, 1000]
        l1 = [sod(n, characteristic) for n in cells]
        res["sod"] = {"cells": cells, "l1_rho_u_p": l1, "order_rho": _orders([e[0] for e in l1], cells)}
        for ndim, grids in ((1, [64, 128, 256, 512]), (2, [64, 128, 256])):
            errors = [wave(n, ndim, characteristic) for n in grids]
            res[f"wave_{ndim}d"] = {"cells": grids, "l1_rho": errors, "orders": _orders(errors, grids)}
        res["interface"] = interface(characteristic)
        print(name, json.dumps(res), flush=True)
    out["wall_s"] = time.perf_counter() - started
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
