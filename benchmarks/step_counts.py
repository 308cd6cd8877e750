"""Steps a run takes, and how many of them the output forces (issue 38, item 1). Not run by the tests.

    python benchmarks/step_counts.py --label after [--out benchmarks/step_counts.json]

Runs each case twice, writing nothing: with its shipped ``output.history_samples``
and with 2 (the fewest: the start and the end), so the difference is the steps the
history samples cost. ``--label`` names the code measured (e.g. ``before``, a
checkout of the commit before the change, and ``after``); the file keeps one entry
per label, with the machine.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import blastfsi
from machine import cpu_model

CASES = {  # name -> (example, overrides)
    "sedov-2d lax-wendroff": ("sedov-2d", {"numerics.scheme": "lax-wendroff"}),
    "sedov-2d hllc-muscl": ("sedov-2d", {"numerics.scheme": "hllc-muscl"}),
    "sedov-2d hllc-hancock": ("sedov-2d", {"numerics.scheme": "hllc-hancock"}),
    "sedov-2d lax-wendroff at its largest cfl": ("sedov-2d", {"numerics.scheme": "lax-wendroff", "numerics.cfl": 1.5}),
    "sedov-2d hllc-hancock at its largest cfl": ("sedov-2d", {"numerics.scheme": "hllc-hancock", "numerics.cfl": 1.8}),
    "plate1d-uniform": ("plate1d-uniform", {}),
    "taylor-bar": ("taylor-bar", {}),
}


def steps(example: str, overrides: dict) -> dict:
    """Steps and loop time with the shipped history samples, and steps with 2."""
    started = time.perf_counter()
    shipped = blastfsi.run(example, set=overrides).summary
    fewest = blastfsi.run(example, set={**overrides, "output.history_samples": 2}).summary
    return {"steps": shipped["steps"], "steps_with_2_samples": fewest["steps"], "time": shipped["time"],
            "loop_time_s": round(shipped["loop_time"], 2), "wall_s": round(time.perf_counter() - started, 1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--label", required=True, help="the code measured, e.g. before or after")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("step_counts.json"))
    args = parser.parse_args()
    figures = {name: steps(*case) for name, case in CASES.items()}
    for name, f in figures.items():
        print(f"{name:24s} steps {f['steps']:6d}  (with 2 history samples: {f['steps_with_2_samples']:6d})")
    saved = json.loads(args.out.read_text()) if args.out.is_file() else {}
    saved[args.label] = {"machine": f"{cpu_model()}, {os.cpu_count()} cores", "python": platform.python_version(),
                         "cases": figures}
    args.out.write_text(json.dumps(saved, indent=2) + "\n")


if __name__ == "__main__":
    main()
