"""Where a run's time goes outside its steps: the XLA compilations made while it ran (with their start
times relative to the run) and the host functions that took the most time (cProfile).

    python benchmarks/profile_run.py NAME [END]      # a docs/figures/make_000_figures.py run, to END [s]

Prints the run's summary figures (steps, wall_time, compile_time), every compilation over 50 ms and the
top of the profile by cumulative time; appends a row to $PROFILE_OUT when set. ``numpy.asarray`` holds the
host's waits on the device (the compiled time loop's results); compilations after the time loop's own
are first-use compilations inside ``wall_time``.
"""
from __future__ import annotations

import cProfile
import io
import json
import logging
import os
import pstats
import shutil
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


class _Compilations(logging.Handler):
    def __init__(self, t0: float):
        super().__init__()
        self.t0, self.rows = t0, []

    def emit(self, record):
        msg = record.getMessage()
        if msg.startswith("Finished XLA compilation of "):
            name, seconds = msg[len("Finished XLA compilation of "):].rsplit(" in ", 1)
            self.rows.append({"finished_s": time.perf_counter() - self.t0, "name": name,
                              "seconds": float(seconds.split()[0])})


def profile(name: str, end: float | None) -> dict:
    sys.path.insert(0, str(HERE.parent / "docs" / "figures"))
    import jax
    import blastfsi
    from make_000_figures import RUNS

    example, overrides = RUNS[name]
    overrides = dict(overrides, **({"time.end": end} if end else {}))
    folder = Path("/tmp/profile_run") / name
    shutil.rmtree(folder, ignore_errors=True)
    t0 = time.perf_counter()
    handler = _Compilations(t0)
    jax.config.update("jax_log_compiles", True)
    logger = logging.getLogger("jax")
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    logger.propagate = False
    prof = cProfile.Profile()
    prof.enable()
    res = blastfsi.run(example, set=overrides, out=folder)
    prof.disable()
    total = time.perf_counter() - t0
    text = io.StringIO()
    pstats.Stats(prof, stream=text).sort_stats("cumulative").print_stats(40)
    out = {"run": name, "end": end, "device": str(jax.devices()[0]), "total_s": total,
           **{k: res.summary[k] for k in ("steps", "wall_time", "compile_time")},
           "compilations": len(handler.rows), "compile_s_all": sum(r["seconds"] for r in handler.rows),
           "long_compilations": [r for r in handler.rows if r["seconds"] > 0.05]}
    print(json.dumps({k: v for k, v in out.items() if k != "long_compilations"}))
    for r in out["long_compilations"]:
        print(f"  compiled by {r['finished_s']:8.2f} s in {r['seconds']:7.3f} s: {r['name']}")
    print(text.getvalue())
    return out


if __name__ == "__main__":
    row = profile(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else None)
    path = os.environ.get("PROFILE_OUT")
    if path:
        doc = json.loads(Path(path).read_text()) if Path(path).exists() else []
        Path(path).write_text(json.dumps(doc + [row], indent=1) + "\n")
