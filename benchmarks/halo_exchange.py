"""Halos exchanged by the compiler or by hand (issue 39, item 1): one Eulerian step of a grid split in slabs
along x over P devices, compiled two ways and compared.

* **compiler**: the scheme's step on the whole grid (:func:`blastfsi.euler.hllc.step`, or Lax-Wendroff's, with
  ``Config.devices = P``) on an array split along x; XLA's SPMD partitioner inserts the exchanges where a stencil
  reads across a slab's edge (what shipped before, and what radial grids and the coupled step still use).
* **explicit** (what ships for Cartesian grids): :func:`blastfsi.euler.step.step`, which steps each slab inside
  ``jax.shard_map``; a slab's x edges take two planes of the neighbouring slab per stage, all rows in one
  ``ppermute`` per side (:func:`blastfsi.euler.boundaries.extend_rows`), or the boundary's ghosts at the ends.

Per device count: the collectives in each compiled loop (count, and the elements of the largest), the time per
step of a compiled loop of fixed steps (best of 3), and the largest difference from one device's result.
Virtual CPU devices (``XLA_FLAGS=--xla_force_host_platform_device_count=8``) share this machine's cores: the
times compare the two programs' overheads on the CPU, not a speed-up; on GPUs, where each collective has a
latency, the counts matter more.

    python benchmarks/halo_exchange.py [--cells 256] [--counts 2 4 8] [--steps 50] [--out benchmarks/halo_exchange.json]

Not run by the tests.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import sys
import time
from pathlib import Path

if "xla_force_host_platform_device_count" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=8").strip()
os.environ.setdefault("JAX_PLATFORMS", "cpu")
os.environ.setdefault("BLASTFSI_NO_CACHE", "1")

import jax  # noqa: E402  (after the device flags)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from jax.sharding import Mesh, NamedSharding, PartitionSpec  # noqa: E402

from blastfsi import simulation  # noqa: E402
from blastfsi.api import example_data  # noqa: E402
from blastfsi import euler as kernels  # noqa: E402
from blastfsi.euler import hllc, lax_wendroff  # noqa: E402
from blastfsi.euler.config import HLLC_MUSCL, LAX_WENDROFF  # noqa: E402
from blastfsi.euler.config import layout  # noqa: E402
from blastfsi.euler.mixture import eos_rows  # noqa: E402
from blastfsi.scenario import expand  # noqa: E402
from machine import described  # noqa: E402

SCHEMES = {HLLC_MUSCL: "hllc-muscl", LAX_WENDROFF: "lax-wendroff"}
COLLECTIVE = re.compile(r"= (\S+) (all-gather|all-reduce|collective-permute|all-to-all|reduce-scatter)(-start)?\(")


def sedov(cells: int, scheme: str):
    """(U, kernel params, cfg, dt) of sedov-2d (Cartesian) at cells^2 with ``scheme``, its initial state."""
    jax.config.update("jax_enable_x64", True)
    data = example_data("sedov-2d")
    data["grid"]["cells"] = cells
    data["numerics"]["scheme"] = scheme
    sc, _, member_scs = expand(data)
    _, _, static, state, params = simulation.prepare(sc, member_scs)
    U, kp = state.U[0], jax.tree_util.tree_map(lambda a: a[0], params.kernel)
    dt = 0.5 * float(kernels.stable_dt(U, kp, static.cfg))
    return U, kp, static.cfg, dt


def loop(step_fn, steps: int):
    """``steps`` applications of ``step_fn`` in one compiled loop."""
    return lambda U: jax.lax.fori_loop(0, steps, lambda i, u: step_fn(u), U)


def split(U, mesh):
    return jax.device_put(U, NamedSharding(mesh, PartitionSpec(None, "x")))


def compiler_split(U, kp, cfg, dt, mesh, steps):
    """The scheme's whole-grid step on the grid split along x (axis 1 of U), partitioned by the compiler."""
    whole = cfg._replace(devices=mesh.size)
    lay = layout(whole)
    eos_r = eos_rows(jnp.asarray(kp.eos, U.dtype), lay.n)
    scheme = {"hllc-muscl": hllc.step, "lax-wendroff": lax_wendroff.step}[SCHEMES[cfg.scheme]]
    return jax.jit(loop(lambda u: scheme(u, dt, eos_r, whole, lay), steps)), split(U, mesh)


def explicit_split(U, kp, cfg, dt, mesh, steps):
    """The shipped step: slab by slab in shard_map, halos exchanged by ppermute."""
    return jax.jit(loop(lambda u: kernels.step(u, dt, kp, cfg._replace(devices=mesh.size)), steps)), split(U, mesh)


def collectives(compiled) -> dict:
    """Per kind: the count of the compiled program's collectives and the elements of its largest array."""
    out = {}
    for m in COLLECTIVE.finditer(compiled.as_text()):
        shape = re.findall(r"\[([\d,]*)\]", m.group(1))
        size = max((int(np.prod([int(d) for d in s.split(",") if d])) for s in shape), default=1)
        kind = out.setdefault(m.group(2), {"count": 0, "largest_elements": 0})
        kind["count"] += 1
        kind["largest_elements"] = max(kind["largest_elements"], size)
    return out


def timed(fn, U0, repeats: int = 3) -> tuple[float, object]:
    """Best wall time of ``repeats`` calls (after one to compile), and the result."""
    out = jax.block_until_ready(fn(U0))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn(U0))
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=256)
    ap.add_argument("--counts", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    rows = {}
    for scheme in SCHEMES.values():
        U, kp, cfg, dt = sedov(args.cells, scheme)
        t_one, ref = timed(jax.jit(loop(lambda u: kernels.step(u, dt, kp, cfg), args.steps)), U)
        scale = float(jnp.max(jnp.abs(ref)))
        rows[scheme] = {"1": {"ms_per_step": round(1e3 * t_one / args.steps, 3)}}
        print(f"{scheme}, 1 device: {rows[scheme]['1']['ms_per_step']} ms a step", flush=True)
        for parts in args.counts:
            mesh = Mesh(np.array(jax.devices()[:parts]), ("x",))
            row = {}
            for name, build in (("compiler", compiler_split), ("explicit", explicit_split)):
                fn, U0 = build(U, kp, cfg, dt, mesh, args.steps)
                seconds, out = timed(fn, U0)
                row[name] = {"ms_per_step": round(1e3 * seconds / args.steps, 3),
                             "collectives_in_loop": collectives(fn.lower(U0).compile()),
                             "max_difference_from_one_device": float(jnp.max(jnp.abs(out - ref))) / scale}
                print(f"{scheme}, {parts} devices, {name}: {row[name]}", flush=True)
            row["compiler_over_explicit"] = round(row["compiler"]["ms_per_step"] / row["explicit"]["ms_per_step"], 2)
            rows[scheme][str(parts)] = row
    record = {"machine": described(), "devices": "virtual CPU devices sharing the cores",
              "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
              "command": "python benchmarks/halo_exchange.py " + " ".join(sys.argv[1:]),
              "case": f"sedov-2d {args.cells}^2 (Cartesian), its initial state, fixed dt, {args.steps} steps in one "
                      f"compiled loop; collectives counted in the compiled loop (a loop body of HLLC-MUSCL holds "
                      f"one stage: per step twice its count)",
              "rows": rows}
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"written {args.out}")


if __name__ == "__main__":
    main()
