"""Throughput of the Eulerian solver (issue 5, item 7). Not run by the tests.

    python benchmarks/bench_euler.py --sizes 64 128 --schemes lax-wendroff hllc-muscl \
        --precision float64 float32 --out benchmarks/results_euler_cpu.json \
        [--pyclaw FILE.npz [--grids-2d 560 800 [--schemes-2d lax-wendroff]] [--limiter mc]] [--profile N] [--update]

3D rows: the whole step (blastfsi.euler.step) on an n^3 grid, ideal gas
gamma = 1.4, one material, outflow on all faces, a spherical blast (p = 10
inside r < 0.2, p = 1 outside, rho = 1) in [-1, 1]^3. A jitted
``lax.fori_loop`` runs N steps at a fixed dt (half the initial CFL step) so the
loop stays on the device; compilation and warm-up calls are excluded; N is
chosen so one call lasts >= --min-time s (default 10: a call's fixed costs, such
as the first touch of its temporary buffers -- about 0.4 s at 128^3 float64 --
then stay a few per cent), and cells x N / (best of --repeats calls) is
reported. float32 rows run in a subprocess with BLASTFSI_X64=0 (the benchmarks'
precision switch: they call the kernels directly, not through a run's numerics.precision).

Memory-traffic model (bytes per cell-step, b = 8 (float64) or 4 (float32), five conservative fields):
* lax-wendroff, split (000 Eq. 6): six directional operators per 3D step; each at
  best reads and writes the five fields once: 6 x (5 + 5) x b = 480 B (float64).
* hllc-muscl, unsplit SSP-RK2: stage 1 reads U and writes U1, stage 2 reads U and U1
  and writes U^{n+1}, each stage one pass over all three axes: (10 + 15) x b = 200 B.
* hllc-hancock, split as lax-wendroff: 6 x (5 + 5) x b = 480 B.
The bandwidth bound is B / (bytes per cell-step); the fraction reached is the measured
rate over that bound. B: on a CPU the best of a STREAM-like copy and triad measured
here (NumPy, one thread, and a jitted JAX kernel, all threads; each written byte counted
once as in STREAM); on a GPU the nominal HBM bandwidth (--gpu-bandwidth, H100 SXM
3.35e12 B/s) next to the measured one. Each row also gives the process CPU seconds per wall second of the timed runs
(2.0 = both cores of this machine busy for us; less = other work shared the cores) and
cell_steps_per_cpu_s, the cell-steps per process CPU second of all timed calls (less sensitive
to other work on the machine than the wall-clock rate, but not a substitute for it).

--profile N: through the public API only, a per-kernel trace of one step of each scheme at N^3
(share of padding/concatenate kernels, the slowest kernels and their ns per output element) and the
cost of the equation-of-state pass against an ideal gas written directly and a five-field copy, with
XLA's cost analysis (bytes, flops, transcendentals per cell) of each.

--pyclaw FILE.npz: the 2D blast of bench_pyclaw.py (cylindrical charge, 400^2 cells)
with every scheme, timed (adaptive CFL step, cfl = --cfl for hllc-muscl, --cfl-split for the split
schemes, whose Courant number counts the fastest axis, not the sum over axes) and compared in L1 density
error with PyClaw against a 1D cylindrical reference of our own (hllc-muscl,
--ref-cells cells on r in [0, 1.5]); the file is made with /tmp/clawenv/bin/python
(--pyclaw-python) when missing. --grids-2d adds our solves on further grids and --pyclaw-more PyClaw's
(files of bench_pyclaw.py --cells N); the time to accuracy of each code is the wall time at which its error
reaches PyClaw's on its first grid, interpolated in log-log between the two grids that bracket it:

    python benchmarks/bench_euler.py --sizes --pyclaw P400.npz --pyclaw-more P300.npz P500.npz --limiter mc \
        --cfl 0.8 --cfl-split 1.5 --grids-2d 500 600 --schemes-2d hllc-hancock hllc-muscl
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from machine import described  # (benchmarks/machine.py, beside this script)

SCHEMES = {"lax-wendroff": 0, "hllc-muscl": 1, "hllc-hancock": 2}  # blastfsi.euler.LAX_WENDROFF, HLLC_MUSCL, HLLC_HANCOCK
SPLIT_SCHEMES = ("lax-wendroff", "hllc-hancock")  # dt from the fastest axis (blastfsi.euler.step.stable_dt)
LIMITERS = {"van-leer": 0, "minmod": 1, "mc": 2}  # blastfsi.euler.VAN_LEER, MINMOD, MC
FIELD_PASSES = {"lax-wendroff": 6 * (5 + 5), "hllc-muscl": 10 + 15, "hllc-hancock": 6 * (5 + 5)}  # field reads+writes per 3D cell-step (docstring)
H100_BANDWIDTH = 3.35e12  # B/s, NVIDIA H100 SXM5 HBM3 datasheet
BLAST = dict(p_in=10.0, p_out=1.0, rho=1.0, radius=0.2, gamma=1.4)  # nondimensional blast, same as bench_pyclaw.py
T_END_2D, R_MAX_REF = 0.25, 1.5  # 2D comparison: end time (shock radius ~0.65 < 1), extent of the 1D reference
HERE = Path(__file__).resolve().parent


# ----------------------------------------------------------------------------------------------- worker side
def _jax_setup():
    import jax
    import jax.numpy as jnp
    import numpy as np

    jax.config.update("jax_enable_x64", os.environ.get("BLASTFSI_X64", "1") != "0")  # (the module docstring)
    from blastfsi import euler
    from blastfsi.eos.jwl import ideal_gas_params
    return jax, jnp, np, euler, ideal_gas_params


def _blast_state(shape, lower, upper, scheme, geometry, bc, cfl, limiter=0, characteristic=True):
    """Config, Params and U of the blast (cell-centre rule: p_in where the centre lies at r < radius);
    limiter: euler.VAN_LEER (0), MINMOD or MC, and characteristic (limiting in characteristic variables, the
    scenario's numerics.limiting = "characteristic") for the HLLC schemes."""
    jax, jnp, np, euler, ideal_gas_params = _jax_setup()
    dtype = np.float64 if jax.config.jax_enable_x64 else np.float32
    dx = (upper - lower) / shape[0]
    cfg = euler.Config(tuple(shape), dx, geometry, bc, scheme, 1, (lower,) * len(shape), limiter,
                       characteristic=characteristic)
    params = euler.Params(jnp.asarray([list(ideal_gas_params(BLAST["gamma"]))], dtype), jnp.asarray(cfl, dtype))
    axes = [lower + (np.arange(m) + 0.5) * dx for m in shape]
    r = np.sqrt(sum(c ** 2 for c in np.meshgrid(*axes, indexing="ij")))
    p = jnp.asarray(np.where(r < BLAST["radius"], BLAST["p_in"], BLAST["p_out"]), dtype)
    U = euler.conservative(jnp.full(shape, BLAST["rho"], dtype), None, jnp.zeros((len(shape),) + tuple(shape), dtype),
                           p, params, cfg)
    return cfg, params, U, axes


def _cost(compiled, cells):
    ca = compiled.cost_analysis()
    ca = ca[0] if isinstance(ca, (list, tuple)) else ca
    text = compiled.as_text()
    return {"xla_bytes_per_cell": ca.get("bytes accessed", float("nan")) / cells,
            "xla_flops_per_cell": ca.get("flops", float("nan")) / cells,
            "xla_transcendentals_per_cell": ca.get("transcendentals", float("nan")) / cells,
            "fused_kernels": len(re.findall(r"^\s*\S+ = \S+ fusion\(", text, re.M))}


def _time(fn, args, repeats):
    import jax
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        walls.append(time.perf_counter() - t0)
    return walls


def bench_3d(n, scheme, repeats, min_time, max_steps):
    """cells x N / t(N), t the best of ``repeats`` calls of N steps, N chosen from a warm-up call so a call lasts
    >= min_time: long calls make the per-call costs (dispatch, first touch of the call's temporary buffers,
    reported as temp_bytes_per_call) small against the steps."""
    jax, jnp, np, euler, _ = _jax_setup()
    cfg, params, U, _ = _blast_state((n, n, n), -1.0, 1.0, SCHEMES[scheme], 0, ((0, 0),) * 3, 0.5)
    dt = 0.5 * euler.stable_dt(U, params, cfg)

    def loop(U, dt, params, steps):
        return jax.lax.fori_loop(0, steps, lambda i, u: euler.step(u, dt, params, cfg, parity=i), U)

    one = jnp.asarray(1, jnp.int32)
    t0 = time.perf_counter()
    compiled = jax.jit(loop).lower(U, dt, params, one).compile()
    compile_s = time.perf_counter() - t0
    warm = min(_time(compiled, (U, dt, params, one), 2))
    steps = int(min(max_steps, max(1, np.ceil(min_time / warm))))
    args = (U, dt, params, jnp.asarray(steps, jnp.int32))
    load0, cpu0 = os.getloadavg()[0], time.process_time()
    walls = _time(compiled, args, repeats)
    cpu_s = time.process_time() - cpu0
    cpu_per_wall = cpu_s / sum(walls)
    out = compiled(*args)
    cells = n ** 3
    return {"size": n, "scheme": scheme, "dtype": str(U.dtype), "cells": cells, "steps": steps,
            "compile_s": compile_s, "walls_s": walls, "wall_s": min(walls),
            "cell_steps_per_s": cells * steps / min(walls),
            "cell_steps_per_cpu_s": cells * steps * repeats / cpu_s,
            "temp_bytes_per_call": compiled.memory_analysis().temp_size_in_bytes,
            "finite": bool(jnp.all(jnp.isfinite(out))), "process_cpu_s_per_wall_s": cpu_per_wall,
            "loadavg_1min_before": load0, "loadavg_1min_after": os.getloadavg()[0]}


def stream():
    """STREAM-like bandwidth [B/s] on preallocated arrays (no first-touch page faults): NumPy copy and scale
    (one thread), and jitted JAX scale and triad applied k times in place inside a fori_loop (all threads),
    timed as (t(11) - t(1)) / 10 per pass; each byte read or written counted once."""
    jax, jnp, np, _, _ = _jax_setup()
    n = 1 << 25  # 256 MiB per float64 array: far beyond any cache
    a, b = np.random.rand(n), np.random.rand(n)
    res = {"numpy_copy": 16 * n / min(_time(lambda: np.copyto(b, a), (), 5)),
           "numpy_scale": 16 * n / min(_time(lambda: np.multiply(a, 0.999, out=b), (), 5))}
    ja, jb = jnp.asarray(a), jnp.asarray(b)
    for name, body, nbytes in (("jax_scale", lambda i, v: v * 0.999, 16), ("jax_triad", lambda i, v: v + 0.5 * jb, 24)):
        passes = jax.jit(lambda x, k, body=body: jax.lax.fori_loop(0, k, body, x))
        t = {k: min(_time(passes, (ja, jnp.asarray(k)), 3 if k > 1 else 4)) for k in (1, 11)}
        res[name] = nbytes * n * 10 / (t[11] - t[1])
    res["device"] = str(jax.devices()[0])
    return res


def _run_to(U, t_end, params, cfg):
    """Adaptive CFL steps to t_end inside one while_loop; returns (U, t, steps)."""
    jax, jnp, _, euler, _ = _jax_setup()

    def body(c):
        u, t, k = c
        dt = jnp.minimum(euler.stable_dt(u, params, cfg), t_end - t)
        return euler.step(u, dt, params, cfg, parity=k), t + dt, k + 1

    return jax.lax.while_loop(lambda c: c[1] < t_end, body, (U, jnp.zeros((), U.dtype), jnp.zeros((), jnp.int32)))


def _solve(shape, lower, upper, scheme, geometry, bc, cfl, t_end, repeats, limiter=0, characteristic=True):
    jax, jnp, np, euler, _ = _jax_setup()
    cfg, params, U, axes = _blast_state(shape, lower, upper, scheme, geometry, bc, cfl, limiter, characteristic)
    t0 = time.perf_counter()
    compiled = jax.jit(_run_to, static_argnums=3).lower(U, jnp.asarray(t_end, U.dtype), params, cfg).compile()
    compile_s = time.perf_counter() - t0
    args = (U, jnp.asarray(t_end, U.dtype), params)
    walls = _time(compiled, args, repeats)
    u_end, t, steps = compiled(*args)
    rho = np.asarray(euler.primitives(u_end, params, cfg)["rho"])
    return {"rho": rho, "axes": axes, "t": float(t), "steps": int(steps), "wall_s": min(walls), "walls_s": walls,
            "compile_s": compile_s}


def compare_2d(pyclaw_npz, cfl, ref_cells, repeats, extra_grids, limiter="van-leer", extra_schemes=tuple(SCHEMES),
               cfl_split=None, limiting="characteristic", pyclaw_more=()):
    """Our 2D blast (the HLLC schemes with ``limiter``; every scheme on PyClaw's grid, ``extra_schemes`` on the
    extra_grids; the split schemes at ``cfl_split``, default ``cfl``) and PyClaw's against a 1D cylindrical
    reference (module docstring); ``limiting``: "characteristic" or "primitive" (numerics.limiting);
    ``pyclaw_more``: PyClaw's solutions on further grids (files of bench_pyclaw.py)."""
    _, _, np, euler, _ = _jax_setup()
    claw = np.load(pyclaw_npz)
    n_claw = int(claw["density"].shape[0])
    refs = {m: _solve((m,), 0.0, R_MAX_REF, euler.HLLC_MUSCL, euler.CYLINDRICAL, ((euler.AXIS, euler.OUTFLOW),),
                      cfl, T_END_2D, 1) for m in (ref_cells // 2, ref_cells)}
    ref, half = refs[ref_cells], refs[ref_cells // 2]

    def l1(rho, xc, yc, r):
        """Mean |rho - rho_ref(r)| over the square (= L1 norm / area)."""
        return float(np.mean(np.abs(rho - np.interp(np.hypot(xc, yc), r["axes"][0], r["rho"]))))

    rows = []
    for n in [n_claw] + list(extra_grids):
        for scheme, code in SCHEMES.items():
            if n != n_claw and scheme not in extra_schemes:
                continue
            courant = cfl_split if scheme in SPLIT_SCHEMES and cfl_split is not None else cfl
            s = _solve((n, n), -1.0, 1.0, code, euler.CARTESIAN, ((euler.OUTFLOW,) * 2,) * 2, courant, T_END_2D,
                       repeats, LIMITERS[limiter], limiting == "characteristic")
            xc, yc = np.meshgrid(*s["axes"], indexing="ij")
            name = f"blastfsi {scheme}" + (f" {limiter} {limiting}" if code != euler.LAX_WENDROFF else "")
            rows.append({"code": name, "grid": n, "cfl": courant, "steps": s["steps"], "t_end": s["t"],
                         "wall_s": s["wall_s"], "walls_s": s["walls_s"], "compile_s": s["compile_s"],
                         "cell_steps_per_s": n * n * s["steps"] / s["wall_s"],
                         "l1_density": l1(s["rho"], xc, yc, ref)})
    for other in [claw] + [np.load(f) for f in pyclaw_more]:
        rows.append({"code": "pyclaw " + str(other["solver"]), "grid": int(other["density"].shape[0]),
                     "cfl": "0.9 desired / 1.0 max", "steps": int(other["steps"]), "t_end": float(other["time"]),
                     "wall_s": float(other["wall_s"]), "walls_s": [float(w) for w in other["walls_s"]],
                     "cell_steps_per_s": float(other["cell_steps_per_s"]),
                     "l1_density": l1(other["density"], other["x"], other["y"], ref)})
    return {"grid": f"{n_claw}x{n_claw} on [-1,1]^2", "t_end": T_END_2D, "blast": BLAST,
            "reference": {"cells": ref_cells, "r_max": R_MAX_REF, "scheme": "hllc-muscl, 1D cylindrical",
                          "steps": ref["steps"], "wall_s": ref["wall_s"],
                          "l1_vs_half_resolution_reference": l1(np.interp(np.hypot(xc, yc), half["axes"][0],
                                                                          half["rho"]), xc, yc, ref)},
            "rows": rows}


def _output_sizes(hlo):
    """Per top-level HLO instruction: (elements, bytes) of its output (all members of a tuple output)."""
    import numpy as np
    width = {"f64": 8, "s64": 8, "u64": 8, "f32": 4, "s32": 4, "u32": 4, "pred": 1, "s8": 1, "u8": 1}
    sizes = {}
    for m in re.finditer(r"^\s*%?(\S+) = (\(.*?\)|\w+\[[\d,]*\])\S* \w", hlo, re.M):
        arrays = [(t, int(np.prod([int(v) for v in d.split(",") if v])))
                  for t, d in re.findall(r"(\w+)\[([\d,]*)\]", m.group(2))]
        sizes[m.group(1)] = (sum(k for _, k in arrays), sum(k * width.get(t, 8) for t, k in arrays))
    return sizes


def _trace_breakdown(compiled, args, cells, top):
    """Per-kernel wall time of one call from a JAX profiler trace (XLA:CPU records one event per kernel):
    shares of padding (fusions with a concatenate), copies and the other fusions; the bytes all kernels
    write per cell (a lower bound of the traffic: reads come on top); the ``top`` slowest kernels with their
    time per output element."""
    import glob
    import gzip
    import tempfile
    import jax
    sizes = _output_sizes(compiled.as_text())
    with tempfile.TemporaryDirectory() as tmp:
        with jax.profiler.trace(tmp, create_perfetto_trace=True):
            jax.block_until_ready(compiled(*args))
        events = json.load(gzip.open(glob.glob(f"{tmp}/**/*.trace.json.gz", recursive=True)[0]))["traceEvents"]
    per = {}
    for e in events:
        if e.get("ph") == "X" and e["name"] in sizes and not e["name"].startswith(("while", "cond", "call")):
            dur, count = per.get(e["name"], (0.0, 0))
            per[e["name"]] = (dur + e["dur"], count + 1)
    total = sum(d for d, _ in per.values())
    shares = {"padding (concatenate fusions)": 0.0, "copies": 0.0, "other fusions": 0.0}
    for name, (dur, _) in per.items():
        key = "copies" if name.startswith("copy") else (
            "padding (concatenate fusions)" if "concatenate" in name else "other fusions")
        shares[key] += dur / total
    slow = sorted(per.items(), key=lambda kv: -kv[1][0])[:top]
    return {"kernel_time_ms": total / 1e3, "kernel_launches": sum(c for _, c in per.values()), "shares": shares,
            "bytes_written_per_cell": sum(c * sizes[k][1] for k, (_, c) in per.items()) / cells,
            "slowest": [{"op": k, "ms": d / 1e3, "calls": c, "ns_per_output_element": 1e3 * d / c / sizes[k][0]}
                        for k, (d, c) in slow]}


def profile(n):
    """Where a step's time goes at n^3 (process precision), through the public API only: a per-kernel trace
    of one whole step of each scheme, and the cost of the equation of state -- p and c from
    euler.primitives (the JWL-row mixture closure every kernel evaluates, here with A = B = 0), the same
    two written directly for an ideal gas, and a five-field scaling (the memory floor of one pass)."""
    jax, jnp, np, euler, _ = _jax_setup()
    cfg, params, U, _ = _blast_state((n, n, n), -1.0, 1.0, 0, 0, ((0, 0),) * 3, 0.5)
    dt = 0.5 * euler.stable_dt(U, params, cfg)
    cells = n ** 3
    gamma = BLAST["gamma"]
    out = {"kernels": {}, "step_traces": {}}

    def rec(name, fn, *args):
        compiled = jax.jit(fn).lower(*args).compile()
        _time(compiled, args, 1)
        wall = min(_time(compiled, args, 5))
        out["kernels"][name] = {"ns_per_cell": 1e9 * wall / cells, **_cost(compiled, cells)}

    def p_plus_c(u, prm):
        prim = euler.primitives(u, prm, cfg)
        return prim["pressure"] + prim["sound_speed"]

    def ideal_p_plus_c(u):
        p = (gamma - 1.0) * (u[4] - 0.5 * (u[1] ** 2 + u[2] ** 2 + u[3] ** 2) / u[0])
        return p + jnp.sqrt(gamma * p / u[0])

    rec("p + c via euler.primitives (JWL rows)", p_plus_c, U, params)
    rec("p + c, ideal gas written directly", ideal_p_plus_c, U)
    rec("five-field scaling (memory floor)", lambda u: u * 1.0000001, U)
    for scheme, code in SCHEMES.items():
        c = cfg._replace(scheme=code)
        compiled = jax.jit(lambda u, dt, p, c=c: euler.step(u, dt, p, c)).lower(U, dt, params).compile()
        _time(compiled, (U, dt, params), 1)
        out["step_traces"][scheme] = {"ns_per_cell_step": 1e9 * min(_time(compiled, (U, dt, params), 3)) / cells,
                                      **_trace_breakdown(compiled, (U, dt, params), cells, 8)}
    return out


def worker(task):
    if task["kind"] == "stream":
        return stream()
    if task["kind"] == "3d":
        return bench_3d(task["n"], task["scheme"], task["repeats"], task["min_time"], task["max_steps"])
    if task["kind"] == "compare2d":
        return compare_2d(task["npz"], task["cfl"], task["ref_cells"], task["repeats"], task["extra_grids"],
                          task["limiter"], task["extra_schemes"], task.get("cfl_split"),
                          task.get("limiting", "characteristic"), task.get("pyclaw_more", ()))
    if task["kind"] == "profile":
        return profile(task["n"])
    raise ValueError(f"unknown worker task kind {task['kind']!r}")


# ----------------------------------------------------------------------------------------------- driver side
def spawn(task, precision="float64"):
    """Run one task in a fresh interpreter with the precision selected by BLASTFSI_X64."""
    env = dict(os.environ, BLASTFSI_X64="1" if precision == "float64" else "0")
    proc = subprocess.run([sys.executable, __file__, "--worker", json.dumps(task)], env=env, capture_output=True,
                          text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"worker {task} failed:\n{proc.stderr[-4000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def source_hash():
    """sha256 over src/blastfsi/euler/*.py: which version of the kernels these numbers belong to."""
    h = hashlib.sha256()
    for f in sorted((HERE.parent / "src" / "blastfsi" / "euler").glob("*.py")):
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def bound(row, bandwidth):
    b = 8 if row["dtype"] == "float64" else 4
    per_cell = FIELD_PASSES[row["scheme"]] * b
    limit = bandwidth / per_cell
    return {"model_bytes_per_cell_step": per_cell, "bandwidth_bound_cell_steps_per_s": limit,
            "fraction_of_bound": row["cell_steps_per_s"] / limit}


def run_info(started_hash):
    """When, on which machine, with what command and on which kernel sources a section was measured."""
    return {"date": time.strftime("%Y-%m-%d %H:%M %Z"), "machine": described(), "command": " ".join(["python"] + sys.argv),
            "euler_source_sha256": started_hash, "euler_source_changed_during_run": source_hash() != started_hash}


def section_3d(args, sizes, bandwidth):
    started, rows = source_hash(), []
    for precision in args.precision:
        for n in sizes:
            for scheme in args.schemes:
                row = spawn({"kind": "3d", "n": n, "scheme": scheme, "repeats": args.repeats,
                             "min_time": args.min_time, "max_steps": args.max_steps}, precision)
                row.update(bound(row, bandwidth))
                rows.append(row)
                print(f"{row['scheme']:>13} {row['dtype']:>8} {n:4d}^3  {row['cell_steps_per_s']:10.3e} cell-steps/s"
                      f"  ({row['steps']} steps, best {row['wall_s']:.2f} s, compile {row['compile_s']:.0f} s)"
                      f"  bound {row['bandwidth_bound_cell_steps_per_s']:.2e}  fraction {row['fraction_of_bound']:.3f}"
                      f"  load {row['loadavg_1min_before']:.1f}, cpu/wall {row['process_cpu_s_per_wall_s']:.2f}"
                      f"  ({row['cell_steps_per_cpu_s']:.2e} per CPU-s)",
                      flush=True)
    return {"run": run_info(started), "rows": rows}


def section_pyclaw(args):
    started = source_hash()
    if not Path(args.pyclaw).exists():
        subprocess.run([args.pyclaw_python, str(HERE / "bench_pyclaw.py"), "--cells", str(args.pyclaw_cells),
                        "--out", args.pyclaw], check=True)
    cmp = spawn({"kind": "compare2d", "npz": args.pyclaw, "cfl": args.cfl, "ref_cells": args.ref_cells,
                 "repeats": args.repeats_2d, "extra_grids": args.grids_2d, "limiter": args.limiter,
                 "extra_schemes": args.schemes_2d, "cfl_split": args.cfl_split, "limiting": args.limiting,
                 "pyclaw_more": args.pyclaw_more})
    print(f"2D blast {cmp['grid']}, t = {cmp['t_end']}; reference {cmp['reference']['cells']} cells "
          f"(L1 vs half resolution {cmp['reference']['l1_vs_half_resolution_reference']:.2e})")
    for r in cmp["rows"]:
        print(f"  {r['code'][:60]:<60} {r['grid']:4d}^2 {r['steps']:5d} steps  wall {r['wall_s']:7.2f} s  "
              f"{r['cell_steps_per_s']:10.3e} cell-steps/s  L1(rho) {r['l1_density']:.4e}", flush=True)
    target = next(r for r in cmp["rows"] if r["code"].startswith("pyclaw"))["l1_density"]
    cmp["time_to_accuracy"] = {"l1_density": target, "wall_s": time_to_accuracy(cmp["rows"], target)}
    print(f"time to PyClaw's L1(rho) {target:.4e} on its first grid (log-log interpolation between each code's grids):")
    for code, wall in cmp["time_to_accuracy"]["wall_s"].items():
        print(f"  {code[:60]:<60} {'not bracketed' if wall is None else f'{wall:7.2f} s'}")
    return {"run": run_info(started), **cmp}


def time_to_accuracy(rows, target):
    """Per code (rows of several grids): the wall time at which its L1 error reaches ``target``, interpolated
    linearly in log(wall) against log(L1) between the two grids whose errors bracket it; None where none do."""
    import math
    out = {}
    for code in dict.fromkeys(r["code"] for r in rows):
        runs = sorted((r["l1_density"], r["wall_s"]) for r in rows if r["code"] == code)
        out[code] = None
        for (e0, w0), (e1, w1) in zip(runs, runs[1:]):
            if e0 <= target <= e1:
                f = 0.0 if e1 == e0 else math.log(target / e0) / math.log(e1 / e0)
                out[code] = math.exp(math.log(w0) + f * math.log(w1 / w0))
        if out[code] is None and any(e == target for e, _ in runs):
            out[code] = next(w for e, w in runs if e == target)
    return out


def section_profile(n):
    started = source_hash()
    prof = spawn({"kind": "profile", "n": n})
    print(f"profile at {n}^3 (float64), each part jitted alone:")
    for name, r in prof["kernels"].items():
        print(f"  {name:<38} {r['ns_per_cell']:8.1f} ns/cell  XLA {r['xla_bytes_per_cell']:7.0f} B/cell "
              f"{r['xla_flops_per_cell']:7.0f} flop/cell  {r['fused_kernels']:3d} kernels", flush=True)
    for scheme, tr in prof["step_traces"].items():
        shares = ", ".join(f"{k} {100 * v:.0f}%" for k, v in tr["shares"].items())
        print(f"  one {scheme} step: {tr['ns_per_cell_step']:.0f} ns/cell-step, {tr['kernel_launches']} kernel calls "
              f"writing {tr['bytes_written_per_cell']:.0f} B/cell; {tr['kernel_time_ms']:.0f} ms in kernels: {shares}")
        for op in tr["slowest"]:
            print(f"      {op['op']:<34} {op['ms']:8.1f} ms  {op['calls']} calls  "
                  f"{op['ns_per_output_element']:6.1f} ns/output element")
    return {"run": run_info(started), "size": n, **prof}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="*", default=None,
                    help="cells per axis (default 64 128, and 256 on a GPU; none: skip the 3D rows)")
    ap.add_argument("--schemes", nargs="+", choices=sorted(SCHEMES), default=list(SCHEMES))
    ap.add_argument("--precision", nargs="+", choices=("float64", "float32"), default=["float64", "float32"])
    ap.add_argument("--gpu", action="store_true", help="bound from --gpu-bandwidth, default sizes with 256")
    ap.add_argument("--gpu-bandwidth", type=float, default=H100_BANDWIDTH)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--min-time", type=float, default=10.0, help="seconds per timed call (chooses N)")
    ap.add_argument("--max-steps", type=int, default=500)
    ap.add_argument("--pyclaw", default=None, help="PyClaw .npz of bench_pyclaw.py; runs the 2D comparison")
    ap.add_argument("--pyclaw-more", nargs="*", default=[],
                    help="PyClaw .npz files of bench_pyclaw.py on further grids (rows of their own)")
    ap.add_argument("--pyclaw-python", default="/tmp/clawenv/bin/python")
    ap.add_argument("--pyclaw-cells", type=int, default=400)
    ap.add_argument("--cfl", type=float, default=0.5, help="Courant number of the 2D comparison (scenario default)")
    ap.add_argument("--limiting", choices=("characteristic", "primitive"), default="characteristic",
                    help="slope limiting of the HLLC schemes in the 2D comparison (numerics.limiting)")
    ap.add_argument("--cfl-split", type=float, default=None,
                    help="Courant number of the split schemes in the 2D comparison (default --cfl; their linear limit is 2)")
    ap.add_argument("--ref-cells", type=int, default=20000)
    ap.add_argument("--limiter", choices=sorted(LIMITERS), default="van-leer",
                    help="hllc-muscl limiter of the 2D comparison")
    ap.add_argument("--grids-2d", type=int, nargs="*", default=[], help="further grids for our 2D solves")
    ap.add_argument("--schemes-2d", nargs="+", choices=sorted(SCHEMES), default=list(SCHEMES),
                    help="schemes solved on the --grids-2d (all always run on PyClaw's grid)")
    ap.add_argument("--repeats-2d", type=int, default=2, help="timed runs of each 2D comparison solve")
    ap.add_argument("--profile", type=int, default=None, metavar="N", help="per-kernel profile at N^3 (float64)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--update", action="store_true", help="keep the sections of --out that this run does not make")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        print(json.dumps(worker(json.loads(args.worker))))
        return

    st = spawn({"kind": "stream"})
    on_gpu = args.gpu or "cpu" not in st["device"].lower()
    measured = max(v for k, v in st.items() if k != "device")
    bandwidth = args.gpu_bandwidth if on_gpu else measured
    sizes = ([64, 128, 256] if on_gpu else [64, 128]) if args.sizes is None else args.sizes
    report = json.loads(Path(args.out).read_text()) if args.update and args.out and Path(args.out).exists() else {}
    report.update({"machine": described(), "cpu_count": os.cpu_count(),
                   "device": st["device"], "stream_bytes_per_s": st, "bandwidth_used_bytes_per_s": bandwidth,
                   "bandwidth_source": "nominal (--gpu-bandwidth)" if on_gpu else "measured STREAM-like best",
                   "bytes_model": {"lax-wendroff": "6 half-sweeps x (5 read + 5 write) fields x b",
                                   "hllc-muscl": "SSP-RK2: (5+5) + (10+5) fields x b",
                                   "hllc-hancock": "6 half-sweeps x (5 read + 5 write) fields x b",
                                   "b": "8 float64, 4 float32"}})
    if sizes:
        report["throughput_3d"] = section_3d(args, sizes, bandwidth)
    if args.pyclaw:
        report["pyclaw_compare"] = section_pyclaw(args)
    if args.profile:
        report["profile"] = section_profile(args.profile)
    if args.out:
        Path(args.out).write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
