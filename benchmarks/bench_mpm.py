"""Throughput of the full 3D MUSL step (issue 7, item 6). Not run by the tests.

    python benchmarks/bench_mpm.py --cells 16 24 --precision float64 float32 \
        --out benchmarks/results_mpm_cpu.json [--combined auto|on|off] [--sort-every K]

Each row: a cube of ``cells``^3 grid cells filled with 8 particles per cell (2 per
direction) of Johnson-Cook steel (``steel-4340`` of the material library), inside a
grid of (cells + 4)^3 cells, moving at 200 m/s towards a slip face with a
superposed shear (so the particles yield: the radial-return Newton iteration runs),
every other face free (the grid leaves 2 cells around the block: its free sides bulge out at up to
~350 m/s, and at 80 cells the first particle is flagged by :func:`blastfsi.mpm.first_fault` after
~180 steps, measured on this CPU (the block non-finite by step 260), so ``--max-steps`` defaults to 150 and
each row says whether the state at the end is ``healthy``, :func:`blastfsi.mpm.first_fault`; an unhealthy
row is not a valid figure: past the fault the state goes non-finite, and the Newton loop runs to its
iteration limit). A jitted ``lax.fori_loop`` runs N steps of
``blastfsi.mpm.step`` at a fixed dt (half the initial CFL step), so the loop stays
on the device; compilation and a warm-up call are excluded; N is chosen so one call
lasts >= --min-time s; particles x N / (best of --repeats calls) is reported as
particle-steps/s. ``--sort-every K`` sorts the particles by cell every K steps
inside the loop (:func:`blastfsi.mpm.sort_by_cell`), the sort counted in the time.
Each row also gives the process CPU seconds per wall second of the timed calls
(2.0 = both cores of this machine busy for us; less = other work shared them) and
the 1-minute load average before and after. float32 rows run in a subprocess with
BLASTFSI_X64=0 (the benchmarks' precision switch: they call the kernels directly, not
through a run's numerics.precision).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from bench_euler import _time  # same folder: the one timing loop of the benchmarks

HERE = Path(__file__).resolve().parent


def setup(cells: int, combined):
    import jax
    import jax.numpy as jnp
    import numpy as np

    jax.config.update("jax_enable_x64", os.environ.get("BLASTFSI_X64", "1") != "0")  # (the module docstring)
    from blastfsi import mpm
    from blastfsi.constitutive import get
    from blastfsi.constitutive import models as _models  # noqa: F401
    from blastfsi.materials import lookup

    dtype = jnp.float64 if jax.config.jax_enable_x64 else jnp.float32
    mat = lookup("steel-4340", None, field="material")
    model = get("johnson-cook")
    h = 1e-3
    n = cells + 4
    grid = mpm.Grid(origin=(0.0, 0.0, 0.0), cell_size=h, cells=(n, n, n),
                    boundaries=(("free", "free"), ("free", "free"), ("slip", "free")))
    lo, hi = np.full(3, 2 * h), np.full(3, (2 + cells) * h)
    lo[2] = 0.0
    hi[2] = cells * h
    x, vol, half = mpm.lattice(grid, lo, hi, 2)
    v = np.zeros_like(x)
    v[:, 2] = -200.0
    v[:, 0] = 50.0 * (x[:, 2] - x[:, 2].mean()) / (cells * h)  # shear: the particles yield
    p = mpm.new_particles(x[:, :3], vol, mat.density, v=v, history_size=model.history_size)
    cfg = mpm.make_config(grid, (model,), combined_scatter=combined)
    prm = mpm.make_params((model.params_from(mat),), cfl=0.5, dtype=dtype)
    cast = jax.tree_util.tree_map(
        lambda a: jnp.asarray(a, dtype) if jnp.issubdtype(jnp.asarray(a).dtype, jnp.floating) else jnp.asarray(a), p)
    st = mpm.initialize(cast, prm, cfg)
    return jax, jnp, np, mpm, cfg, prm, st, int(np.asarray(p.active).sum())


def bench(cells: int, repeats: int, min_time: float, max_steps: int, combined, sort_every: int):
    jax, jnp, np, mpm, cfg, prm, st, n_particles = setup(cells, combined)
    dt = 0.5 * mpm.stable_dt(st, prm, cfg)

    def loop(st, dt, steps):
        def body(i, s):
            if sort_every:
                s = jax.lax.cond(i % sort_every == 0,
                                 lambda s: s._replace(particles=mpm.sort_by_cell(s.particles, cfg.grid)),
                                 lambda s: s, s)
            return mpm.step(s, dt, prm, cfg)
        return jax.lax.fori_loop(0, steps, body, st)

    one = jnp.asarray(1, jnp.int32)
    t0 = time.perf_counter()
    compiled = jax.jit(loop).lower(st, dt, one).compile()
    compile_s = time.perf_counter() - t0
    warm = min(_time(compiled, (st, dt, one), 2))
    steps = int(min(max_steps, max(1, np.ceil(min_time / warm))))
    args = (st, dt, jnp.asarray(steps, jnp.int32))
    load0, cpu0 = os.getloadavg()[0], time.process_time()
    walls = _time(compiled, args, repeats)
    cpu_per_wall = (time.process_time() - cpu0) / sum(walls)
    out = compiled(*args)
    P = out.particles
    finite = bool(jnp.all(jnp.isfinite(P.x)) & jnp.all(jnp.isfinite(P.point.stress)))
    healthy = int(mpm.first_fault(out, cfg)) < 0  # no particle non-finite, compressed to nothing or off the grid
    return {"cells": cells, "grid_cells": cfg.grid.cells[0], "particles": n_particles,
            "dtype": str(st.particles.x.dtype), "combined_scatter": cfg.combined_scatter, "sort_every": sort_every,
            "steps": steps, "compile_s": compile_s, "walls_s": walls, "wall_s": min(walls),
            "particle_steps_per_s": n_particles * steps / min(walls), "finite": finite, "healthy": healthy,
            "max_plastic_strain": float(jnp.max(P.point.plastic_strain)),
            "process_cpu_s_per_wall_s": cpu_per_wall,
            "loadavg_1min_before": load0, "loadavg_1min_after": os.getloadavg()[0]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, nargs="+", default=[16, 24])
    ap.add_argument("--precision", nargs="+", default=["float64", "float32"], choices=["float64", "float32"])
    ap.add_argument("--combined", default="auto", choices=["auto", "on", "off"])
    ap.add_argument("--sort-every", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--min-time", type=float, default=5.0)
    ap.add_argument("--max-steps", type=int, default=150)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--label", default="")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    combined = {"auto": None, "on": True, "off": False}[a.combined]
    if a.worker:  # one precision, rows as JSON on stdout
        rows = [bench(c, a.repeats, a.min_time, a.max_steps, combined, a.sort_every) for c in a.cells]
        print("ROWS " + json.dumps(rows))
        return
    rows = []
    for prec in a.precision:
        env = dict(os.environ, BLASTFSI_X64="1" if prec == "float64" else "0")
        cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", "--cells", *map(str, a.cells),
               "--combined", a.combined, "--sort-every", str(a.sort_every), "--repeats", str(a.repeats),
               "--min-time", str(a.min_time), "--max-steps", str(a.max_steps)]
        res = subprocess.run(cmd, env=env, capture_output=True, text=True)
        line = [ln for ln in res.stdout.splitlines() if ln.startswith("ROWS ")]
        if res.returncode or not line:
            sys.stderr.write(res.stdout + res.stderr)
            raise SystemExit(f"worker for {prec} failed (rc {res.returncode})")
        for r in json.loads(line[0][5:]):
            r["label"] = a.label
            rows.append(r)
            print(f"{prec:8s} cells {r['cells']:3d} particles {r['particles']:7d} combined {r['combined_scatter']!s:5s} "
                  f"sort {r['sort_every']:3d}: {r['particle_steps_per_s']:.3e} particle-steps/s "
                  f"(steps {r['steps']}, wall {r['wall_s']:.2f} s, cpu/wall {r['process_cpu_s_per_wall_s']:.2f}, "
                  f"load {r['loadavg_1min_before']:.2f}->{r['loadavg_1min_after']:.2f})"
                  f"{'' if r['healthy'] else '  FAULTED: not a valid figure'}", flush=True)
    if a.out:
        import jax
        doc = json.loads(a.out.read_text()) if a.out.exists() else {}
        doc.update({"machine": platform.machine(), "cpu_count": os.cpu_count(), "device": str(jax.devices()[0]),
                    "problem": "3D MUSL step, Johnson-Cook steel-4340, 8 particles per cell, block at 200 m/s "
                               "onto a slip face with shear (bench_mpm.py docstring)"})
        doc.setdefault("runs", []).append({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                                           "command": "python benchmarks/bench_mpm.py " + " ".join(argv or sys.argv[1:]),
                                           "rows": rows})
        a.out.write_text(json.dumps(doc, indent=2) + "\n")


if __name__ == "__main__":
    main()
