"""First-run compilation of the coupled examples, this checkout against an older one on the same machine
(issue 38, item 3: "first-run compilation of coupled examples halved").

    python benchmarks/compile_baseline.py --old-src /tmp/old/src [--variants] [--out benchmarks/compile_baseline.json]

``--old-src``: the ``src`` folder of an older checkout (``git worktree add /tmp/old <commit>``), imported in
place of this one (same Python environment). Each case runs in a fresh process with ``BLASTFSI_NO_CACHE=1``
(traced and compiled afresh), one at a time: he-slab-2d to 32.5 us and steel-plate-blast to 0.1 ms, no fields,
plots or checkpoints, 101 history samples. Rows: the summary's compile_time (tracing and compiling the time loop)
and loop_time, the steps, and the whole process. ``--variants`` adds this checkout with the particle-to-grid
transfer as scalar scatters, one per channel and stencil node (``blastfsi.xla.combined_scatter`` forced off; the
CPU's form in 2D before it took rows), to show what the unrolled scatters cost in compilation and save in the
loop. Not run by the tests.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
from pathlib import Path

from machine import described

CASES = {"he-slab-2d": 3.25e-5, "steel-plate-blast": 1e-4}

RUNNER = r'''
import json, os, sys, time
started = time.perf_counter()
if os.environ.get("SCALAR") == "1":
    import blastfsi.xla
    blastfsi.xla.combined_scatter = lambda dim: False
import blastfsi
case, end = sys.argv[1], float(sys.argv[2])
s = blastfsi.run(case, set={"time.end": end, "output.fields": 0, "output.plots": False,
                            "output.history_samples": 101}).summary
print("ROW" + json.dumps({"compile_s": round(s["compile_time"], 2), "loop_s": round(s["loop_time"], 2),
                          "steps": s["steps"], "process_s": round(time.perf_counter() - started, 2),
                          "load_average": os.getloadavg()[0]}))
'''


def measured(case: str, src: Path | None, scalar: bool = False) -> dict:
    env = {**os.environ, "BLASTFSI_NO_CACHE": "1", "SCALAR": "1" if scalar else "0"}
    if src is not None:
        env["PYTHONPATH"] = str(src)
    proc = subprocess.run([sys.executable, "-c", RUNNER, case, str(CASES[case])], capture_output=True, text=True,
                          env=env, check=True)
    row = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("ROW"))[3:])
    print(case, "old" if src else ("this, scalar scatters" if scalar else "this"), row, flush=True)
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-src", type=Path, required=True)
    ap.add_argument("--variants", action="store_true")
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    old = subprocess.run(["git", "-C", str(args.old_src), "rev-parse", "--short", "HEAD"], capture_output=True,
                         text=True).stdout.strip() or str(args.old_src)
    this = subprocess.run(["git", "-C", str(Path(__file__).parent), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    rows = {}
    for case in CASES:
        rows[case] = {f"old ({old})": measured(case, args.old_src), f"this ({this})": measured(case, None)}
        if args.variants:
            rows[case][f"this ({this}), scalar scatters"] = measured(case, None, scalar=True)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    given = argv if argv is not None else sys.argv[1:]
    record = {"machine": described(), "date_utc": now,
              "command": "python benchmarks/compile_baseline.py " + " ".join(given),
              "cases": {k: f"time.end = {v} s, no output, 101 history samples" for k, v in CASES.items()},
              "rows": rows}
    args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
