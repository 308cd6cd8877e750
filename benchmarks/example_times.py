"""Run time of the shipped examples as shipped: steps, compile, loop and whole-run seconds per example.

    python benchmarks/example_times.py [--only NAME ...] [--skip NAME ...] [--out benchmarks/example_times.json]
    python benchmarks/example_times.py --table [--out benchmarks/example_times.json]   # the README table

Each example runs once, in its own Python process, with an empty compilation cache (BLASTFSI_CACHE_DIR in a
temporary directory): a user's first run. Recorded per example: the summary's ``steps``, ``compile_time`` (the
time loop's tracing and compilation), ``loop_time`` and ``wall_time`` (what the driver reports), the whole
process's seconds (imports, set-up, a charge's 1D detonation, compilation, loop, output files and plots), and
the load average before and after (a shared machine's times grow with its load). Examples whose run would
exceed ``--timeout`` are stopped and recorded as such. The JSON keeps the examples this call does not run.
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

from machine import described

CHILD = """
import json, sys
import blastfsi
res = blastfsi.run(sys.argv[1], out=sys.argv[2])
s = res.summary
print(json.dumps({k: s.get(k) for k in ("method", "status", "steps", "cells", "compile_time", "loop_time",
                                        "wall_time")}))
"""


def run_one(name: str, timeout: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, BLASTFSI_CACHE_DIR=str(Path(tmp) / "cache"))
        env.pop("BLASTFSI_NO_CACHE", None)
        load = os.getloadavg()[0]
        started = time.perf_counter()
        try:
            out = subprocess.run([sys.executable, "-c", CHILD, name, str(Path(tmp) / "out")], env=env,
                                 capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return {"status": f"stopped after {timeout:.0f} s", "load_before": load}
        process = time.perf_counter() - started
        if out.returncode != 0:
            return {"status": "failed", "error": out.stderr.strip().splitlines()[-1:], "load_before": load}
        rec = json.loads(out.stdout.strip().splitlines()[-1])
        return rec | {"process_s": process, "load_before": load, "load_after": os.getloadavg()[0]}


def minutes(seconds) -> str:
    if seconds is None:
        return "–"
    if isinstance(seconds, list):  # (an ensemble: its members run as one program)
        seconds = max(seconds)
    if seconds < 10:
        return f"{seconds:.1f} s"
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def first(value):
    """A value, or an ensemble's (a list per member): its first member's."""
    return value[0] if isinstance(value, list) else value


def table(data: dict) -> str:
    lines = ["| example | method | steps | compile | loop | whole run |", "|---|---|---|---|---|---|"]
    for name, r in sorted(data["examples"].items(), key=lambda kv: (first(kv[1].get("method")) or "~", kv[0])):
        if "steps" not in r:
            lines.append(f"| `{name}` | | | | | {r['status']} |")
            continue
        steps = max(r["steps"]) if isinstance(r["steps"], list) else r["steps"]
        lines.append(f"| `{name}` | {first(r['method'])} | {steps} | {minutes(r['compile_time'])} | "
                     f"{minutes(r['loop_time'])} | {minutes(r['process_s'])} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", default=None)
    ap.add_argument("--skip", nargs="+", default=[])
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per example (default 1800)")
    ap.add_argument("--out", default="benchmarks/example_times.json")
    ap.add_argument("--table", action="store_true", help="print the markdown table of --out and stop")
    args = ap.parse_args()
    path = Path(args.out)
    data = json.loads(path.read_text()) if path.exists() else {"examples": {}}
    if args.table:
        print(f"({data['machine']}, {data['python']}, jax {data['jax']})\n")
        print(table(data))
        return
    import jax

    from blastfsi.api import example_names

    names = args.only or [n for n in example_names() if n not in args.skip]
    data.update(machine=described(), python=platform.python_version(), jax=jax.__version__,
                command=" ".join(["python", "benchmarks/example_times.py", *sys.argv[1:]]))
    for name in names:
        rec = run_one(name, args.timeout)
        data["examples"][name] = rec
        print(f"{name:28s} {rec.get('status')}  steps {rec.get('steps')}  compile {minutes(rec.get('compile_time'))}"
              f"  loop {minutes(rec.get('loop_time'))}  process {minutes(rec.get('process_s'))}"
              f"  load {rec['load_before']:.1f}", flush=True)
        path.write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    main()
