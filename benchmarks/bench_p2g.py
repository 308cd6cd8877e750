"""The P2G scatter alone, in the layouts XLA can be given (issue 7, item 6: the scatter is ~55 % of the 3D
Johnson-Cook step on a GPU, benchmarks/profile_gpu.json). Not run by the tests.

    python benchmarks/bench_p2g.py --cells 80 [--repeats 5]     # precision: BLASTFSI_X64

The particles of bench_mpm.py's block (8 per cell, sorted by cell) and its linear stencil; C = 7 channels
(mass, momentum and force in 3D) of (S, n) values, computed before the timed call. Every layout returns
the (num_nodes, C) sums; each row gives its best time of --repeats calls, the scatter's updates per second
(S n C / time) and its largest difference from the first layout (summation order only).

* ``rows-s``: one scatter of (S n, C) rows, stencil node major (``mpm.musl.particle_to_grid``, combined)
* ``rows-p``: the same rows particle major (n S, C): a particle's S nodes side by side
* ``rows-s-promise``: ``rows-s`` with ``mode="promise_in_bounds"`` (no bounds test per update)
* ``channels``: one scalar scatter of S n values per channel
* ``channels-s``: per channel, S scalar scatters of n values (the CPU form of ``particle_to_grid``);
  ``channels-s-promise`` the same with ``mode="promise_in_bounds"``
* ``sorted-s``: S scatters of (n, C) rows, one per stencil node, ``indices_are_sorted=True`` (the particles
  sorted by cell make each node's indices non-decreasing)
* ``rows-s-shuffled``: ``rows-s`` with the particles in a random order (what sorting by cell buys)
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def layouts(jnp, num_nodes):
    from blastfsi.mpm.musl import particle_to_grid  # (after bench_mpm.setup has set the precision)

    def rows_s_promise(idx, ch):  # particle_to_grid's combined form with mode="promise_in_bounds"
        packed = jnp.stack(ch, axis=-1).reshape(-1, len(ch))
        return jnp.zeros((num_nodes, len(ch)), ch[0].dtype).at[idx.reshape(-1)].add(packed, mode="promise_in_bounds")

    def rows_p(idx, ch):
        packed = jnp.stack(ch, axis=-1).transpose(1, 0, 2).reshape(-1, len(ch))
        return jnp.zeros((num_nodes, len(ch)), ch[0].dtype).at[idx.T.reshape(-1)].add(packed)

    def channels(idx, ch):
        flat = idx.reshape(-1)
        return jnp.stack([jnp.zeros(num_nodes, c.dtype).at[flat].add(c.reshape(-1)) for c in ch], axis=1)

    def channels_s_promise(idx, ch):  # particle_to_grid's CPU form with mode="promise_in_bounds"
        def one(c):
            acc = jnp.zeros(num_nodes, c.dtype)
            for s in range(c.shape[0]):
                acc = acc.at[idx[s]].add(c[s], mode="promise_in_bounds")
            return acc
        return jnp.stack([one(c) for c in ch], axis=1)

    def sorted_s(idx, ch):
        packed = jnp.stack(ch, axis=-1)  # (S, n, C)
        acc = jnp.zeros((num_nodes, len(ch)), ch[0].dtype)
        for s in range(idx.shape[0]):
            acc = acc.at[idx[s]].add(packed[s], indices_are_sorted=True)
        return acc

    return {"rows-s": lambda idx, ch: particle_to_grid(idx, ch, num_nodes, True), "rows-p": rows_p,
            "rows-s-promise": rows_s_promise, "channels": channels,
            "channels-s": lambda idx, ch: particle_to_grid(idx, ch, num_nodes, False),
            "channels-s-promise": channels_s_promise, "sorted-s": sorted_s}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, default=80)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args(argv)
    from bench_mpm import setup

    jax, jnp, np, mpm, cfg, prm, st, n = setup(a.cells, True)
    from blastfsi.mpm import musl

    P = mpm.sort_by_cell(st.particles, cfg.grid)
    idx, w, grad = musl.materialised_stencil(P, cfg.grid, cfg.shape)
    m = jnp.where(P.active, P.mass, 0.0)
    mw = m * w
    ch = [mw] + [mw * P.v[:, i] for i in range(3)] + [(m * (1.0 + i)) * grad[i] for i in range(3)]
    ch = jax.block_until_ready([jnp.asarray(c) for c in ch])
    shuffle = np.random.default_rng(0).permutation(idx.shape[1])
    cases = dict(layouts(jnp, cfg.grid.num_nodes))
    cases["rows-s-shuffled"] = cases["rows-s"]
    rows, ref = [], None
    for name, fn in cases.items():
        args = (idx[:, shuffle], [c[:, shuffle] for c in ch]) if name.endswith("shuffled") else (idx, ch)
        f = jax.jit(fn)
        out = jax.block_until_ready(f(*args))
        walls = []
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            jax.block_until_ready(f(*args))
            walls.append(time.perf_counter() - t0)
        ref = out if ref is None else ref
        scale = jnp.max(jnp.abs(ref), axis=0)
        row = {"layout": name, "device": str(jax.devices()[0]), "dtype": str(ch[0].dtype), "particles": n,
               "updates": int(idx.size * len(ch)), "best_s": min(walls),
               "updates_per_s": idx.size * len(ch) / min(walls),
               "max_rel_diff": float(jnp.max(jnp.max(jnp.abs(out - ref), axis=0) / jnp.where(scale > 0, scale, 1.0)))}
        rows.append(row)
        print(json.dumps(row), flush=True)
    if a.out:
        doc = json.loads(a.out.read_text()) if a.out.exists() else []
        a.out.write_text(json.dumps(doc + rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
