"""Compile time of a first and a repeated run of examples, with the persistent compilation cache.

    python benchmarks/compile_cache.py [--cases he-slab-2d steel-plate-blast] [--out benchmarks/compile_cache.json]

Each case runs twice, each run in its own Python process sharing one fresh cache directory
(BLASTFSI_CACHE_DIR): the first compiles and stores its time loop, the second loads it. Reported per run:
the summary's ``compile_time`` (the time loop's: tracing, lowering and XLA compilation or the cache's
load), the process's seconds in ``blastfsi.run`` (``run_call``: also the set-up's and output's small
compilations and the time loop itself) and the whole process's (``process``: with the imports), and the
machine with its load average (a shared machine's compile times vary with its load). ``same_summary``: the
second run's summary equals the first's (timings aside); with ``--check`` a third run without the cache
(BLASTFSI_NO_CACHE=1: traced and compiled afresh) is compared too.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax

from machine import cpu_model

# coarse, short runs: compilation does not depend on the end time, and little on the grid
CASES = {
    # to 10 us: past the automatic remap of the 1D detonation (9.6 us), so the coupled loop runs
    "he-slab-2d": {"time.end": 1.0e-5, "output.history_samples": 101},
    "steel-plate-blast": {"time.end": 2.0e-5, "output.history_samples": 101, "output.checkpoint_interval": 2.0e-5},
    "plate1d-uniform": {"grid.cells": 1000},
    "sedov-2d": {"grid.cells": 100},
}
QUIET = {"output.fields": 0, "output.plots": False}

CHILD = """
import json, sys, time
t0 = time.perf_counter()
import blastfsi
t1 = time.perf_counter()
res = blastfsi.run(sys.argv[1], set=json.loads(sys.argv[2]))
t2 = time.perf_counter()
s = res.summary
times = {"compile_time", "loop_time", "wall_time", "output_time"}
print(json.dumps({"compile_time": s["compile_time"], "loop_time": s["loop_time"], "steps": s["steps"],
                  "run_call": t2 - t1, "import": t1 - t0,
                  "summary": {k: v for k, v in s.items() if k not in times}}, default=str))
"""


def one_run(name: str, overrides: dict, cache: str, use_cache: bool = True) -> dict:
    env = dict(os.environ, BLASTFSI_CACHE_DIR=cache)
    env.pop("BLASTFSI_NO_CACHE", None)
    if not use_cache:
        env["BLASTFSI_NO_CACHE"] = "1"
    started = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", CHILD, name, json.dumps(overrides)], env=env, capture_output=True,
                         text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{name} {overrides}: exit {out.returncode}\n{out.stderr[-3000:]}")
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "process": time.perf_counter() - started,
            "load_average": os.getloadavg()[0]}


def cache_size(directory: str) -> int:
    return sum(f.stat().st_size for f in Path(directory).rglob("*") if f.is_file())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--check", action="store_true", help="also run without the cache and compare the summaries")
    args = ap.parse_args(argv)
    rows = []
    report = {"machine": {"platform": platform.platform(), "processor": cpu_model(), "cpu_count": os.cpu_count(),
                          "device": str(jax.devices()[0]), "jax": jax.__version__, "python": platform.python_version()},
              "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
              "command": (f"PYTHONPATH={os.environ['PYTHONPATH']} " if os.environ.get("PYTHONPATH") else "")
              + "python benchmarks/compile_cache.py " + " ".join(sys.argv[1:]), "rows": rows}
    for name in args.cases:
        overrides = {**CASES[name], **QUIET}
        with tempfile.TemporaryDirectory(prefix="blastfsi-cache-") as cache:
            first = one_run(name, overrides, cache)
            second = one_run(name, overrides, cache)
            summary = first.pop("summary")
            row = {"case": name, "set": overrides, "first": first, "second": second,
                   "cache_bytes": cache_size(cache), "same_summary": second.pop("summary") == summary}
            if args.check:
                plain = one_run(name, overrides, cache, use_cache=False)
                row["without_cache"] = plain
                row["same_summary_without_cache"] = plain.pop("summary") == summary
        rows.append(row)
        print(f"{name:18s} compile_time first {first['compile_time']:7.2f} s, second {second['compile_time']:6.2f} s;"
              f" run call {first['run_call']:7.2f} -> {second['run_call']:7.2f} s; process {first['process']:7.2f}"
              f" -> {second['process']:7.2f} s (load {first['load_average']:.1f}/{second['load_average']:.1f}, "
              f"cache {row['cache_bytes'] / 1e6:.1f} MB); same summary: {row['same_summary']}"
              + (f", without the cache: compile_time {row['without_cache']['compile_time']:.2f} s, same summary: "
                 f"{row['same_summary_without_cache']}" if args.check else ""), flush=True)
        if args.out is not None:  # (after each case: a long series keeps what it measured)
            args.out.write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
