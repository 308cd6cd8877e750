"""Where a step's time goes on a GPU: kernel time against wall time, from a JAX profiler trace.

    python benchmarks/gpu_profile.py mpm CELLS      # bench_mpm.py's 3D Johnson-Cook block (precision: BLASTFSI_X64)
    python benchmarks/gpu_profile.py slab NAME T    # a docs/figures/make_000_figures.py run, stepped from T [s]

Each task times ``--steps`` steps (best of 3 calls, compiled once) and then traces one more call: the
summary gives the wall time per step, the device's kernel time per step (the union of the kernel
intervals on the device's streams), the kernels per step, and the kernels that take most of the time.
Kernel time well under the wall time means the device waits for the host (launches, host round trips of
conditionals and loops); kernel time near it means the kernels themselves are the cost.
"""
from __future__ import annotations

import collections
import glob
import gzip
import json
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def summarise(trace_dir: str, steps: int, top: int = 25) -> dict:
    """Kernel statistics of the newest perfetto trace under ``trace_dir``."""
    path = sorted(glob.glob(f"{trace_dir}/plugins/profile/*/perfetto_trace.json.gz"))[-1]
    events = json.load(gzip.open(path))["traceEvents"]
    processes = {e["pid"]: e["args"]["name"] for e in events if e.get("ph") == "M" and e.get("name") == "process_name"}
    device = {pid for pid, name in processes.items() if "GPU" in name or "device" in name.lower()}
    kernels = [e for e in events if e.get("ph") == "X" and e.get("pid") in device]
    spans = sorted((e["ts"], e["ts"] + e["dur"]) for e in kernels)
    busy, end = 0.0, -1.0
    for a, b in spans:  # union of the intervals
        if b > end:
            busy += b - max(a, end)
            end = b
    by_name = collections.defaultdict(lambda: [0, 0.0])
    for e in kernels:
        by_name[e["name"]][0] += 1
        by_name[e["name"]][1] += e["dur"]
    rows = sorted(by_name.items(), key=lambda kv: -kv[1][1])[:top]
    return {"processes": sorted(processes.values()), "kernels_per_step": len(kernels) / steps,
            "kernel_busy_s_per_step": busy * 1e-6 / steps,
            "window_s": (spans[-1][1] - spans[0][0]) * 1e-6 if spans else 0.0,
            "top": [{"name": n[:90], "count_per_step": c / steps, "s_per_step": d * 1e-6 / steps} for n, (c, d) in rows]}


def measure(call, steps: int, label: str) -> dict:
    import jax

    jax.block_until_ready(call())  # compiled and warm
    walls = []
    for _ in range(3):
        t0 = time.perf_counter()
        jax.block_until_ready(call())
        walls.append((time.perf_counter() - t0) / steps)
    with tempfile.TemporaryDirectory() as d:
        with jax.profiler.trace(d, create_perfetto_trace=True):
            jax.block_until_ready(call())
        prof = summarise(d, steps)
    out = {"task": label, "device": str(jax.devices()[0]), "x64": bool(jax.config.jax_enable_x64),
           "steps": steps, "wall_s_per_step": min(walls), **prof}
    print(f"{label}: wall {out['wall_s_per_step'] * 1e3:.3f} ms/step, kernels busy "
          f"{out['kernel_busy_s_per_step'] * 1e3:.3f} ms/step, {out['kernels_per_step']:.0f} kernels/step")
    for r in out["top"]:
        print(f"  {r['s_per_step'] * 1e6:9.1f} us {r['count_per_step']:6.1f}x  {r['name']}")
    return out


def mpm_task(cells: int, steps: int) -> dict:
    sys.path.insert(0, str(HERE))
    import jax
    from bench_mpm import setup

    _, _, _, mpm, cfg, prm, st, n = setup(cells, None)
    dt = 0.5 * mpm.stable_dt(st, prm, cfg)
    loop = jax.jit(lambda s: jax.lax.fori_loop(0, steps, lambda i, s: mpm.step(s, dt, prm, cfg), s))
    out = measure(lambda: loop(st), steps, f"mpm {cells}^3 x8, {n} particles")
    out["particle_steps_per_s"] = n / out["wall_s_per_step"]
    return out


def slab_task(name: str, start: float, steps: int) -> dict:
    sys.path.insert(0, str(HERE.parent / "docs" / "figures"))
    import jax
    from make_000_figures import _restored

    _, _, advance, state, params, (_, interval, floor) = _restored(Path("/nonexistent"), name, None)
    state = jax.block_until_ready(advance(state, params, start, 1_000_000, interval, floor))
    holder = {"s": state}

    def call():  # steps further each call (the state is donated)
        holder["s"] = advance(holder["s"], params, float("inf"), steps, interval, floor)
        return holder["s"]

    out = measure(call, steps, f"{name} from {start:g} s")
    out["particles"] = int(holder["s"].mpm.particles.active.sum())
    return out


if __name__ == "__main__":
    what, steps = sys.argv[1], int(os.environ.get("STEPS", "20"))
    res = mpm_task(int(sys.argv[2]), steps) if what == "mpm" else slab_task(sys.argv[2], float(sys.argv[3]), steps)
    out = os.environ.get("PROFILE_OUT")
    if out:
        doc = json.loads(Path(out).read_text()) if Path(out).exists() else []
        Path(out).write_text(json.dumps(doc + [res], indent=1) + "\n")
