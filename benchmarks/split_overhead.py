"""What splitting a run over devices costs in itself (issue 39, item 5): the same run on 1, 2, 4 and 8 devices,
here virtual CPU devices (``XLA_FLAGS=--xla_force_host_platform_device_count=8``) that share this machine's
cores, so the figures are the split program's overhead (the exchanges, the partitioned loop), not a speed-up.

    python benchmarks/split_overhead.py [--counts 1 2 4 8] [--out benchmarks/split_overhead.json]

Each method's case runs once per device count in this process (the first count also compiles what the others
reuse of the set-up), no output written: ``sedov-2d`` at 256^2 to t = 0.1 (euler: the grid in slabs),
``taylor-bar`` to 20 us (mpm: the particle pool in parts), ``cfdmp-shock-tube`` (cfdmp: its MPM pool in parts)
and an 8-member ``plate1d-uniform`` sweep at 2000 zones (lagrangian1d: the members). Per row: steps, loop
seconds, loop time per step and its ratio to one device's. Not run by the tests (a GPU machine gives the
speed-up figures: run it there without the XLA_FLAGS).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import sys
from pathlib import Path

if "xla_force_host_platform_device_count" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=8").strip()
os.environ.setdefault("JAX_PLATFORMS", "cpu")
os.environ.setdefault("BLASTFSI_NO_CACHE", "1")

import jax  # noqa: E402  (after the device flags)

from blastfsi import simulation  # noqa: E402
from blastfsi.api import example_data  # noqa: E402
from machine import described  # noqa: E402


def cases() -> dict:
    quiet = {"fields": 0, "plots": False, "history_samples": 101}
    sedov = example_data("sedov-2d")
    sedov["grid"]["cells"] = 256
    sedov["time"]["end"] = 0.1
    bar = example_data("taylor-bar")
    bar["time"]["end"] = 2e-5
    tube = example_data("cfdmp-shock-tube")
    sweep = example_data("plate1d-uniform")
    sweep["grid"]["cells"] = 2000
    sweep["time"]["end"] = 0.0155
    sweep["sweep"] = {"overpressure": [4e5, 8e5], "beta_s": [0.5, 1.0, 2.0, 4.0]}
    out = {"euler: sedov-2d 256^2": sedov, "mpm: taylor-bar": bar, "cfdmp: cfdmp-shock-tube": tube,
           "lagrangian1d: plate1d-uniform, 8 members": sweep}
    for data in out.values():
        data.setdefault("output", {}).update(quiet)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--counts", type=int, nargs="+", default=[1, 2, 4, 8])
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    rows = {}
    for name, data in cases().items():
        rows[name] = {}
        for n in args.counts:
            data.setdefault("numerics", {})["devices"] = n
            s = simulation.run(data).summary
            steps = max(s["steps"]) if isinstance(s["steps"], list) else s["steps"]
            loop = s["loop_time"][0] if isinstance(s["loop_time"], list) else s["loop_time"]
            rows[name][n] = {"steps": steps, "loop_s": round(loop, 3), "ms_per_step": round(1e3 * loop / steps, 4)}
            base = rows[name][args.counts[0]]["ms_per_step"]
            rows[name][n]["ratio_to_first"] = round(rows[name][n]["ms_per_step"] / base, 3)
            print(f"{name:42s} devices {n}: {rows[name][n]}", flush=True)
    record = {"machine": described(), "devices": f"{len(jax.devices())} virtual CPU devices sharing the cores",
              "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
              "command": "python benchmarks/split_overhead.py " + " ".join(argv if argv is not None else sys.argv[1:]),
              "rows": rows}
    args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
