"""Where a run's compiled step spends its time, kernel by kernel, grouped by the part of the algorithm that
emitted each kernel. Not run by the tests.

    python benchmarks/step_profile.py [--example steel-plate-blast] [--at 3e-4] [--steps 20] [--repeats 3]
                                      [--label shipped] [--out benchmarks/step_profile.json]

Advances the example with its shipped compiled time loop to ``--at`` (the persistent compilation cache off),
then records ``--steps`` more steps ``--repeats`` times with the JAX profiler (on the CPU each XLA kernel,
"thunk", is a trace event) and adds up each kernel's time per step under the labels of the functions it came
from. The labels are put on the traced code here, by wrapping the library's functions in ``jax.named_scope``
before the loop is traced (the library itself carries no profiling code): every HLO instruction's
``op_name`` then holds the path of labels it was traced under, e.g. ``mpm_step/relaxation/p2g``. A fused
kernel takes the path of the instruction it was fused into (its root): the arithmetic of a channel fused
into the scatter's packing counts as ``p2g``.

Kernel times are thread times: XLA:CPU runs independent kernels, and parts of one kernel, on several threads,
so the sum over kernels can exceed the wall time of a step (both are printed). Times on a shared 2-core VM
vary by ~10 % between minutes; compare shares, or rows measured in one call.
"""
from __future__ import annotations

import argparse
import collections
import glob
import gzip
import importlib
import json
import os
import platform
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("BLASTFSI_NO_CACHE", "1")  # (the scopes change the compiled code: no stale cache entry)

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from blastfsi import method as methods, simulation  # noqa: E402
from blastfsi.api import load  # noqa: E402
from blastfsi.scenario import expand  # noqa: E402
from machine import cpu_model  # noqa: E402

# (module, attribute, label): the functions whose kernels are grouped. A function is wrapped where it is
# looked up at call time: in its own module, and in every module that imported it by name.
SCOPES = [
    ("blastfsi.cfdmp.coupling", "interface_source", "interface_source"),
    ("blastfsi.cfdmp.coupling", "outflow_ghost", "outflow_ghost"),
    ("blastfsi.cfdmp.coupling", "remove_leaving", "remove_leaving"),
    ("blastfsi.cfdmp.coupling", "receive", "receive"),
    ("blastfsi.cfdmp.coupling", "feed", "feed"),
    ("blastfsi.cfdmp.coupling", "gas_rows", "gas_rows"),
    ("blastfsi.cfdmp.coupling", "flat_primitives", "cell_primitives"),
    ("blastfsi.euler", "step_with_transfers", "euler_step"),
    ("blastfsi.euler", "step", "euler_step"),
    ("blastfsi.euler", "stable_dt", "euler_cfl"),
    ("blastfsi.mpm", "step", "mpm_step"),
    ("blastfsi.mpm", "stable_dt", "mpm_cfl"),
    ("blastfsi.mpm.musl", "materialised_stencil", "stencil"),
    ("blastfsi.mpm.musl", "cell_centre_gradient", "cell_centre_gradient"),
    ("blastfsi.mpm.musl", "particle_to_grid", "p2g"),
    ("blastfsi.mpm.musl", "grid_to_particle", "g2p"),
    ("blastfsi.mpm.musl", "gather_columns", "g2p"),
    ("blastfsi.mpm.musl", "_material_update", "constitutive"),
    ("blastfsi.mpm.musl", "wave_speed", "wave_speed"),
    ("blastfsi.mpm.musl", "mixture_signal", "mixture_signal"),
    ("blastfsi.mpm.relaxation", "relax", "relaxation"),
    ("blastfsi.diagnostics.blast_maps", "update", "blast_maps"),
]


def add_scopes() -> list:
    """Wrap every SCOPES function, where it is defined and wherever it was imported by name; returns the
    labels in use."""
    for name in methods.available():  # every method's modules loaded, so that every importer is found
        methods.get(name)
    for module, attr, label in SCOPES:
        original = getattr(importlib.import_module(module), attr)
        wrapped = jax.named_scope(label)(original)
        for name, mod in list(sys.modules.items()):
            if name.startswith("blastfsi") and getattr(mod, attr, None) is original:
                setattr(mod, attr, wrapped)
    return sorted({label for *_, label in SCOPES})


CONTROL = ("while", "conditional", "call")  # kernels that run others: their events enclose their children's


def scope_paths(hlo_text: str, labels: list) -> dict:
    """HLO instruction name -> the path of labels in its op_name ('' when none), control flow left out."""
    paths = {}
    known = set(labels)
    for line in hlo_text.splitlines():
        m = re.match(r"\s*(?:ROOT )?%?([\w.\-]+) = (?:\(.*?\)|\S+) ([\w\-]+)\(.*?op_name=\"([^\"]+)\"", line)
        if m and m.group(2) not in CONTROL:
            path = [p for p in m.group(3).split("/") if p in known]
            paths[m.group(1)] = "/".join(p for i, p in enumerate(path) if i == 0 or p != path[i - 1])
    return paths


def kernel_times(trace_dir: str) -> collections.Counter:
    """Summed duration [s] of each trace event (XLA:CPU kernels are named after their HLO instruction)."""
    data = json.load(gzip.open(glob.glob(f"{trace_dir}/**/perfetto_trace.json.gz", recursive=True)[0]))
    events = data["traceEvents"] if isinstance(data, dict) else data
    out = collections.Counter()
    for e in events:
        if e.get("ph") == "X":
            out[e["name"]] += 1e-6 * e.get("dur", 0)
    return out


def profile(example: str, at: float, steps: int, repeats: int) -> dict:
    labels = add_scopes()
    jax.config.update("jax_enable_x64", True)
    sc, _, scs = expand(load(example, set={"output.history_samples": 401}))
    method, _, static, state, params = simulation.prepare(sc, scs)
    interval = (sc.time.end - float(state.t[0])) / (sc.output.history_samples - 1)
    floor = sc.time.dt_min_fraction
    advance, _ = methods.compiled_advance(method, static, state, params, at, 10 ** 9, interval, floor)
    state = jax.block_until_ready(advance(state, params, at, 10 ** 9, interval, floor))
    paths = scope_paths(advance.as_text(), labels)

    def run():
        return jax.block_until_ready(advance(jax.tree_util.tree_map(jnp.copy, state), params, 1.0, steps,
                                             interval, floor))
    run()
    walls = []
    trace_dir = tempfile.mkdtemp(prefix="step_profile_")
    with jax.profiler.trace(trace_dir, create_perfetto_trace=True):
        for _ in range(repeats):
            started = time.perf_counter()
            run()
            walls.append(time.perf_counter() - started)
    times = kernel_times(trace_dir)
    shutil.rmtree(trace_dir, ignore_errors=True)
    per_step = 1e3 / (steps * repeats)
    by_path = collections.Counter()
    for name, seconds in times.items():
        if name in paths:
            by_path[paths[name] or "(unlabelled)"] += seconds * per_step
    kernels = sum(by_path.values())
    top = sorted(((s * per_step, n, paths[n]) for n, s in times.items() if n in paths), reverse=True)[:15]
    P = state.mpm.particles if hasattr(state, "mpm") else None
    return {
        "example": example, "at_s": float(np.asarray(state.t)[0]), "steps": steps, "repeats": repeats,
        "pool": int(P.active.shape[-1]) if P is not None else None,
        "active_particles": int(np.asarray(P.active).sum()) if P is not None else None,
        "wall_ms_per_step": round(1e3 * min(walls) / steps, 2),
        "kernel_ms_per_step": round(kernels, 2),
        "by_scope_ms_per_step": {k: round(v, 3) for k, v in by_path.most_common()},
        "top_kernels_ms_per_step": [{"kernel": n, "scope": p, "ms": round(ms, 3)} for ms, n, p in top],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--example", default="steel-plate-blast")
    ap.add_argument("--at", type=float, default=3e-4, help="time to advance to before profiling [s]")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--label", default="shipped")
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("step_profile.json"))
    args = ap.parse_args()
    row = profile(args.example, args.at, args.steps, args.repeats)
    row.update(label=args.label, machine=f"{cpu_model()}, {os.cpu_count()} CPUs", jax=jax.__version__,
               python=platform.python_version(), date_utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
               command="python benchmarks/step_profile.py " + " ".join(
                   f"--{k} {v}" for k, v in vars(args).items() if k not in ("out",)))
    print(f"{row['example']} at {row['at_s']:.3g} s: wall {row['wall_ms_per_step']} ms/step, "
          f"kernels {row['kernel_ms_per_step']} ms/step (thread time)")
    for path, ms in row["by_scope_ms_per_step"].items():
        print(f"  {ms:8.2f} ms  {100 * ms / row['kernel_ms_per_step']:5.1f} %  {path}")
    saved = json.loads(args.out.read_text()) if args.out.is_file() else {"rows": []}
    saved["rows"].append(row)
    args.out.write_text(json.dumps(saved, indent=1) + "\n")


if __name__ == "__main__":
    main()
