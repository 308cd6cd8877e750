"""Sensitivity of he-slab-2d to the CFDMP coupling's tuned constants.

For each constant (docs/theory/cfdmp.md, "Departures from the paper and tuned constants") the shipped
example ``he-slab-2d`` is run at the shipped value and at two alternatives, each in its own subprocess in
which the module constant is set before the run (module globals are read when the time loop is traced;
the gas PIC share goes through its scenario key ``numerics.gas_pic_fraction``). The runs use a snapshot of
the committed source so that concurrent edits of the working tree do not leak into them::

    git -C . archive HEAD src | tar -x -C /tmp/sens_snap && git -C . rev-parse HEAD > /tmp/sens_snap/COMMIT
    BLASTFSI_NO_CACHE=1 PYTHONPATH=/tmp/sens_snap/src python benchmarks/coupling_sensitivity.py \
        --snapshot /tmp/sens_snap --work /tmp/sens_runs

Each run's figures are written to ``--work`` as soon as it ends (a rerun skips those present) and the
collected table, with the relative change of every figure against the shipped value, to
``benchmarks/coupling_sensitivity.json``. One run at a time: the runs time the loop. ``--end`` runs past the
example's end into the late phase where the gas behind the slab is rarefied (4.21e-5 s: the CFDMP paper's
Fig. 12, 32.5 us after the remap), into another ``--work``; those go under ``extended`` in the same file::

    ... coupling_sensitivity.py --work /tmp/sens_runs_421 --end 4.21e-5 --timeout 300 \
        --only INFLOW_MACH FULL_FILL SETTLE_FRACTIONS GAS_PIC_FRACTION
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
EXAMPLE = "he-slab-2d"

# constant -> (where, shipped value, alternatives); "key:" marks a scenario key instead of a module global
CASES = {
    "INFLOW_MACH": ("blastfsi.cfdmp.coupling", 0.01, [0.0025, 0.04]),
    "FULL_FILL": ("blastfsi.cfdmp.coupling", 0.5, [0.25, 1.0]),
    "FEED_FRACTION": ("blastfsi.cfdmp.coupling", 1e-6, [2.5e-7, 4e-6]),
    "PRESENT": ("blastfsi.cfdmp.coupling", 1e-3, [2.5e-4, 4e-3]),
    "SETTLE_FRACTIONS": ("blastfsi.cfdmp.coupling", (1.0, 0.5, 0.25, 0.125),
                         [(1.0,), (1.0, 0.5, 0.25, 0.125, 0.0625)]),
    "GAS_PIC_FRACTION": ("key:numerics.gas_pic_fraction", 0.05, [0.0, 0.2]),
    "GROWTH": ("blastfsi.simulation", 1.25, [1.1, 2.0]),
    "CUT_TOLERANCE": ("blastfsi.cfdmp.coupling", 1e-6, [0.0, 1e-4]),
}
# overrides that every run of a constant gets (its shipped value then has a run of its own): he-slab-2d's default
# pool (numerics.pool_headroom = 1.5) never fills before its end, so GROWTH is measured with a pool that does
EXTRA = {"GROWTH": {"numerics.pool_headroom": 1.0}}


def run_one(constant: str, value, out_dir: Path, end: float | None = None) -> dict:
    """Run he-slab-2d with ``constant`` = ``value`` (in this process) and return its figures."""
    import importlib

    import numpy as np

    where = CASES[constant][0]
    overrides = dict(EXTRA.get(constant, {}))
    if end is not None:
        overrides["time.end"] = end
    if where.startswith("key:"):
        overrides[where[4:]] = value
    else:
        mod = importlib.import_module(where)
        assert hasattr(mod, constant), (where, constant)
        setattr(mod, constant, tuple(value) if isinstance(value, list) else value)
    import blastfsi

    t0 = time.perf_counter()
    res = blastfsi.run(EXAMPLE, set=overrides or None, out=out_dir, overwrite=True)
    wall = time.perf_counter() - t0
    summary = res.summary
    hist = {k: np.asarray(v) for k, v in res.history.items()}
    fig = {"wall_s": wall, "overrides": overrides, "summary": _plain(summary)}
    for col in ("mass_budget_residual", "energy_budget_residual"):
        if col in hist:
            v = hist[col]
            fig[col + "_final"] = float(v[-1])
            fig[col + "_max_abs"] = float(np.nanmax(np.abs(v)))
    fig["history_columns"] = sorted(hist)
    fig["time_final"] = float(hist["time"][-1]) if "time" in hist else None
    return fig


def _plain(x):
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    try:
        import numpy as np
        if isinstance(x, np.ndarray):
            return _plain(x.tolist())
        if isinstance(x, np.generic):
            return x.item()
    except ImportError:
        pass
    if isinstance(x, float) and not math.isfinite(x):
        return repr(x)
    return x


def _tag(constant, value) -> str:
    return f"{constant}={json.dumps(value)}".replace(" ", "")


def _scalars(fig: dict) -> dict:
    """Flat name -> number of the figures compared between values."""
    out = {}
    s = fig.get("summary", {})
    for i, g in enumerate(s.get("gauges", [])):
        for k in ("peak_overpressure", "impulse", "arrival_time"):
            out[f"gauge{i}.{k}"] = g.get(k)
    b = s.get("budget", {})
    for k in ("mass_residual_relative", "energy_residual_relative", "momentum_x_residual_relative",
              "momentum_y_residual_relative"):
        if k in b:
            out["budget." + k] = b[k]
    for k in ("max_displacement", "max_damage", "damaged_fraction", "failed_volume"):
        if k in s.get("structures", {}):
            out["structures." + k] = s["structures"][k]
    for k in ("mass_budget_residual_final", "mass_budget_residual_max_abs",
              "energy_budget_residual_final", "energy_budget_residual_max_abs"):
        if k in fig:
            out[k] = fig[k]
    for k in ("time", "steps", "loop_time", "compile_time", "wall_time", "pool_growths", "particles", "capacity"):
        if isinstance(s.get(k), (int, float)):
            out[k] = s[k]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snapshot", default="/tmp/sens_snap", help="snapshot root (holds src/)")
    ap.add_argument("--work", default="/tmp/sens_runs", help="per-run results and figures")
    ap.add_argument("--out", default=str(HERE / "coupling_sensitivity.json"))
    ap.add_argument("--only", nargs="*", help="constants to run (default: all)")
    ap.add_argument("--end", type=float, help="time.end [s] instead of the example's (use another --work)")
    ap.add_argument("--timeout", type=float, help="wall-clock limit of one run [s]: a run over it counts as failed")
    ap.add_argument("--one", nargs=2, metavar=("CONSTANT", "VALUE_JSON"), help=argparse.SUPPRESS)
    ap.add_argument("--collect", action="store_true", help="only collect the finished runs")
    args = ap.parse_args(argv)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)

    if args.one:  # child: one run
        constant, value = args.one[0], json.loads(args.one[1])
        tag = _tag(constant, value)
        fig = run_one(constant, value, work / "runs" / tag, args.end)
        (work / f"{tag}.json").write_text(json.dumps(fig, indent=1))
        return 0

    snap_src = str(Path(args.snapshot) / "src")
    env = dict(os.environ, BLASTFSI_NO_CACHE="1", PYTHONPATH=snap_src)
    commit = None
    if (Path(args.snapshot) / "COMMIT").exists():
        commit = (Path(args.snapshot) / "COMMIT").read_text().strip()
    constants = args.only or list(CASES)
    if not args.collect:
        # shipped value once (the reference of every constant), then the alternatives
        plan = [("INFLOW_MACH", CASES["INFLOW_MACH"][1])]
        for c in constants:
            plan += [(c, v) for v in ([CASES[c][1]] if c in EXTRA else []) + CASES[c][2]]
        for c, v in plan:
            tag = _tag(c, v)
            if (work / f"{tag}.json").exists() or (work / f"{tag}.failed").exists():
                continue
            print(f"[{datetime.datetime.now():%H:%M:%S}] {tag}", flush=True)
            cmd = [sys.executable, __file__, "--work", str(work), "--one", c, json.dumps(v)]
            cmd += ["--end", repr(args.end)] if args.end is not None else []
            with open(work / f"{tag}.log", "w") as log:
                try:
                    rc = subprocess.call(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, timeout=args.timeout)
                except subprocess.TimeoutExpired:
                    rc = f"timed out after {args.timeout} s"
            if rc != 0:
                (work / f"{tag}.failed").write_text(f"exit {rc}\n")
            collect(work, args.out, commit, args.end)
    collect(work, args.out, commit, args.end)
    return 0


def collect(work: Path, out: str, commit: str | None, end: float | None = None):
    table = {}
    for c, (where, shipped, alts) in CASES.items():
        ref_tag = _tag(c if c in EXTRA else "INFLOW_MACH", shipped if c in EXTRA else CASES["INFLOW_MACH"][1])
        ref = json.loads((work / f"{ref_tag}.json").read_text()) if (work / f"{ref_tag}.json").exists() else None
        ref_s = _scalars(ref) if ref else {}
        rows = []
        for v in [shipped] + alts:
            tag = ref_tag if v == shipped else _tag(c, v)
            row = {"value": list(v) if isinstance(v, tuple) else v, "shipped": v == shipped}
            f = work / f"{tag}.json"
            if f.exists():
                fig = json.loads(f.read_text())
                row["completed"] = fig["summary"].get("status") == "complete"
                row["wall_s"] = fig["wall_s"]
                row["time_final"] = fig.get("time_final")
                row["figures"] = _scalars(fig)
                row["relative_change"] = {
                    k: (val - ref_s[k]) / abs(ref_s[k]) if isinstance(ref_s.get(k), (int, float)) and ref_s[k] != 0
                    else None for k, val in row["figures"].items() if isinstance(val, (int, float))}
            elif (work / f"{tag}.failed").exists():
                row["completed"] = False
                log = work / f"{tag}.log"
                row["error_tail"] = log.read_text()[-1500:] if log.exists() else ""
            else:
                row["completed"] = None  # not run
            rows.append(row)
        table[c] = {"where": where, "extra_overrides": EXTRA.get(c, {}), "runs": rows}
    doc = {
        "example": EXAMPLE,
        "time_end": end,  # None: the example's own
        "machine": {"platform": platform.platform(), "python": platform.python_version(),
                    "cpu_count": os.cpu_count(), "processor": platform.processor()},
        "date": datetime.date.today().isoformat(),
        "commit": commit,
        "note": ("relative_change: (value - shipped) / |shipped| of each figure; the shipped run is shared by the "
                 "constants without extra_overrides; loop and wall times share the CPU with other work"),
        "constants": table,
    }
    # runs with --end go under "extended" of the same file, keyed by their end time; the example's own stay on top
    path = Path(out)
    old = json.loads(path.read_text()) if path.exists() else {}
    if end is None:
        if "extended" in old:
            doc["extended"] = old["extended"]
    else:
        old.setdefault("extended", {})[repr(end)] = doc
        doc = old
    path.write_text(json.dumps(doc, indent=1))


if __name__ == "__main__":
    sys.exit(main())
