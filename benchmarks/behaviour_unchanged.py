"""Check that a change (a refactoring) left every shipped example's results unchanged. Not run by the tests.

    python benchmarks/behaviour_unchanged.py --base REV [--head REV|WORKTREE|DIR] [--steps N]
        [--only NAME ...] [--out FILE.json] [--rtol 1e-12] [--timeout S]

What it does: every shipped example (``src/blastfsi/examples/*.toml``, listed by
``blastfsi.api.example_names()`` of each tree) is run twice, at ``--base`` (a commit,
exported with ``git archive REV src`` into a temp dir) and at ``--head`` (default
WORKTREE: this checkout's ``src``; also a commit, or a directory holding ``src/blastfsi``),
each run in its own subprocess with ``PYTHONPATH=<tree>/src`` (the child checks that it
imported that tree's package), one at a time. The two results directories are compared:
``summary.json`` and every ``history*.csv``: each number equal within ``--rtol``
relative (plus an absolute floor of 1e-300, for exact zeros; NaN equals NaN), strings,
booleans, nulls, keys, lengths, column names and file names identical. It prints one
line per example (``same``; the first differences with both values and the relative
difference; or ``failed at base/head`` with the error's last line) and a count; the
exit code is 0 only if every example is the same.

The shortened run (the same at both trees): the example as shipped except that

* it stops after about ``--steps`` steps (default 20): ``time.max_steps = N`` alone
  would end the run with an error (and a summary holding only the error), so the base
  child first runs the example with ``time.max_steps = N`` (writing nothing), notes the
  simulated time t_N the N steps reached, and then both trees run it with
  ``time.end = t_N`` (a complete run; a ``time.max_steps`` of 10 N + 100 only guards
  against a head that no longer advances). An example that ends in fewer than N steps
  keeps its ``time.end``. An example that refuses the shortened ``time.end`` (a plate's
  must lie after the shock's arrival) is run as shipped with ``time.max_steps = N``
  instead: it stops with that error, its summary.json then holds only the status and the
  error (with the time reached, 6 digits), and its history, sampled about N times over the
  N steps (``output.history_samples`` raised), carries the comparison. A charge's 1D
  detonation runs as shipped (to the shortened end). The time loop lands on ``time.end`` in ceil(left / stable step) equal steps, so a change
  of the stable step alone that leaves that count unchanged (CFL x 0.999 over 20 steps) is
  not seen in so short a run: raise ``--steps`` for such changes;
* ``output.fields = 0`` (no field snapshots), ``output.plots = false`` and no
  ``output.checkpoint_interval`` (the run is too short for them; they are not compared).

Ignored (IGNORED_KEYS, anywhere in summary.json): the wall-clock timings ``wall_time``,
``compile_time``, ``loop_time`` and ``output_time``, which depend on the host and its
load, not on the computation. The results directory's path, which a capped run's error
names, is replaced by ``<out>``. Nothing else in the summary or history is host-dependent.

JAX's persistent compilation cache is switched off in the children
(``BLASTFSI_NO_CACHE=1``, ``BLASTFSI_CACHE_DIR`` and ``JAX_COMPILATION_CACHE_DIR``
removed), so the two trees never share compiled or traced code; each run compiles
afresh (tens of seconds on a loaded 2-core CPU). ``--out`` writes the per-example results
(with the revisions, the step cap, the machine and the wall time per run) as JSON.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
IGNORED_KEYS = {"wall_time", "compile_time", "loop_time", "output_time"}  # host timings, see the docstring
ATOL = 1e-300
SHOWN = 3  # differences printed per example

# The child: run with PYTHONPATH=<tree>/src; argv[1] is a JSON request. Prints "RESULT <json>" last.
CHILD = r"""
import copy, json, math, re, sys
import numpy as np
req = json.loads(sys.argv[1])
import blastfsi
from blastfsi import api, simulation
from blastfsi.scenario import ScenarioError
if not blastfsi.__file__.startswith(req["src"]):
    sys.exit(f"imported {blastfsi.__file__}, not the tree {req['src']}")
if req["mode"] == "list":
    print("RESULT " + json.dumps(sorted(api.example_names())))
    sys.exit()
CAP = re.compile(r"time\.max_steps = \d+ reached at t = (\S+) s")
data = api.load(req["example"])
output = data.setdefault("output", {})
output.update(fields=0, plots=False)
output.pop("checkpoint_interval", None)
n, plan = req["steps"], req.get("plan")

def run(plan):  # the shortened run: {"end": t} (None: as shipped) or {"capped": samples}
    d = copy.deepcopy(data)
    if plan.get("end") is not None:
        d["time"]["end"] = plan["end"]
    if plan.get("capped"):
        d["output"]["history_samples"] = plan["capped"]
    d["time"]["max_steps"] = n if plan.get("capped") else 10 * n + 100
    try:
        api.run(d, out=req["out"])
    except Exception as err:
        if not (plan.get("capped") and CAP.search(str(err))):
            raise

if plan is None:  # the time the first n steps reach (exact, from the driver's stop check where it has one)
    probe = copy.deepcopy(data)
    probe["time"]["max_steps"] = n
    seen, check = {}, getattr(simulation, "_stop_reason", None)
    if check is not None:
        def spy(state, *args, **kwargs):
            seen["t"] = float(np.min(np.asarray(state.t)))
            return check(state, *args, **kwargs)
        simulation._stop_reason = spy
    plan = {"end": None}
    try:
        api.run(probe)
    except Exception as err:
        m = CAP.search(str(err))
        if m is None:
            raise
        plan["end"] = seen.get("t", float(m.group(1)))
    if check is not None:
        simulation._stop_reason = check
    try:
        run(plan)
    except ScenarioError:  # e.g. a plate's end must lie after the shock's arrival: capped at n steps instead,
        end = data["time"]["end"]  # with about n history samples over them (the summary holds only the error)
        samples = output.get("history_samples", 1001)
        plan = {"end": None, "capped": min(100_000, max(samples, math.ceil(n * end / plan["end"]) + 1))}
        run(plan)
else:
    run(plan)
print("RESULT " + json.dumps(plan))
"""


def git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(REPO), *args], check=True, capture_output=True, text=True).stdout.strip()


def tree_of(spec: str, tmp: Path, label: str) -> tuple[Path, str]:
    """(directory holding src/blastfsi, description) of WORKTREE, a directory or a commit (exported)."""
    if spec == "WORKTREE":
        dirty = " (modified)" if git("status", "--porcelain", "--", "src") else ""
        return REPO, f"WORKTREE at {git('rev-parse', 'HEAD')}{dirty}"
    if Path(spec).is_dir():
        root = Path(spec).resolve()
        if not (root / "src" / "blastfsi").is_dir():
            sys.exit(f"--{label} {spec}: no src/blastfsi in this directory")
        return root, f"directory {root}"
    commit = git("rev-parse", "--verify", f"{spec}^{{commit}}")
    root = tmp / label
    root.mkdir()
    archive = subprocess.Popen(["git", "-C", str(REPO), "archive", commit, "src"], stdout=subprocess.PIPE)
    subprocess.run(["tar", "-x", "-C", str(root)], stdin=archive.stdout, check=True)
    if archive.wait() != 0:
        sys.exit(f"git archive {commit} failed")
    return root, f"{spec} = {commit}"


def child(tree: Path, request: dict, tmp: Path, timeout: float) -> tuple[dict | list | None, str, float]:
    """(result, error's last line or "", wall seconds) of one child process at ``tree``."""
    env = {k: v for k, v in os.environ.items() if k not in ("BLASTFSI_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR")}
    env.update(PYTHONPATH=str(tree / "src"), BLASTFSI_NO_CACHE="1")
    request = {**request, "src": str(tree / "src")}
    started = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-c", CHILD, json.dumps(request)], cwd=tmp, env=env,
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, f"timed out after {timeout:g} s", time.perf_counter() - started
    wall = time.perf_counter() - started
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not lines:
        last = [ln for ln in (p.stderr + p.stdout).splitlines() if ln.strip()]
        return None, (last[-1] if last else f"exit code {p.returncode}"), wall
    return json.loads(lines[-1][len("RESULT "):]), "", wall


def close(a: float, b: float, rtol: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b or abs(a - b) <= rtol * max(abs(a), abs(b)) + ATOL


def rel(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), abs(b)) if max(abs(a), abs(b)) > 0 else 0.0


def is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def compare_json(a, b, rtol: float, path: str = "summary") -> list[str]:
    """Differences between two JSON values (IGNORED_KEYS skipped)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}.{k}: only in {'base' if k in a else 'head'}" for k in sorted(set(a) ^ set(b))
               if k not in IGNORED_KEYS]
        for k in a:
            if k in b and k not in IGNORED_KEYS:
                out += compare_json(a[k], b[k], rtol, f"{path}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length base={len(a)} head={len(b)}"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in compare_json(x, y, rtol, f"{path}[{i}]")]
    if is_number(a) and is_number(b):
        return [] if close(float(a), float(b), rtol) else [f"{path}: base={a!r} head={b!r} rel={rel(a, b):.3g}"]
    return [] if (type(a) is type(b) and a == b) else [f"{path}: base={a!r} head={b!r}"]


def read_csv(file: Path) -> tuple[list[str], np.ndarray]:
    with open(file) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float).reshape(-1, len(rows[0]))


def compare_history(a: Path, b: Path, rtol: float) -> list[str]:
    (ha, xa), (hb, xb) = read_csv(a), read_csv(b)
    if ha != hb:
        return [f"{a.name}: columns base={ha} head={hb}"]
    if xa.shape != xb.shape:
        return [f"{a.name}: rows base={len(xa)} head={len(xb)}"]
    same = (np.abs(xa - xb) <= rtol * np.maximum(np.abs(xa), np.abs(xb)) + ATOL) | (np.isnan(xa) & np.isnan(xb))
    out = []
    for r, c in zip(*np.nonzero(~same)):
        x, y = float(xa[r, c]), float(xb[r, c])
        out.append(f"{a.name}[row {r}, {ha[c]}]: base={x!r} head={y!r} rel={rel(x, y):.3g}")
    return out


def compare(a: Path, b: Path, rtol: float) -> list[str]:
    def summary(d: Path):  # (a capped run's error names its results directory)
        return json.loads((d / "summary.json").read_text().replace(str(d), "<out>"))
    out = compare_json(summary(a), summary(b), rtol)
    files_a, files_b = sorted(p.name for p in a.glob("history*.csv")), sorted(p.name for p in b.glob("history*.csv"))
    if files_a != files_b:
        return out + [f"history files: base={files_a} head={files_b}"]
    for name in files_a:
        out += compare_history(a / name, b / name, rtol)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="a commit (git archive REV src), or a directory with src/blastfsi")
    ap.add_argument("--head", default="WORKTREE", help="WORKTREE (default), a commit, or a directory with src/blastfsi")
    ap.add_argument("--steps", type=int, default=20, help="steps of the shortened run (default 20)")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="these examples only")
    ap.add_argument("--out", type=Path, help="write the per-example results here (JSON)")
    ap.add_argument("--rtol", type=float, default=1e-12, help="relative tolerance (default 1e-12)")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per child process (default 1800)")
    args = ap.parse_args()

    tmp = Path(tempfile.mkdtemp(prefix="behaviour_unchanged_"))
    try:
        (base, base_rev), (head, head_rev) = tree_of(args.base, tmp, "base"), tree_of(args.head, tmp, "head")
        print(f"base: {base_rev}\nhead: {head_rev}\nsteps: {args.steps}, rtol: {args.rtol:g}", flush=True)
        names = {}
        for label, tree in (("base", base), ("head", head)):
            listed, err, _ = child(tree, {"mode": "list"}, tmp, args.timeout)
            if listed is None:
                sys.exit(f"listing the examples at {label} failed: {err}")
            names[label] = set(listed)
        every = sorted(names["base"] | names["head"])
        if args.only:
            unknown = sorted(set(args.only) - set(every))
            if unknown:
                sys.exit(f"unknown examples: {', '.join(unknown)}; available: {', '.join(every)}")
            every = [n for n in every if n in args.only]

        results = {}
        for name in every:
            entry = {"wall_s": {}}
            missing = [label for label in ("base", "head") if name not in names[label]]
            if missing:
                entry.update(result="failed", error=f"no such example at {missing[0]}")
            else:
                out_base, out_head = tmp / "out" / name / "base", tmp / "out" / name / "head"
                request = {"mode": "run", "example": name, "steps": args.steps}
                got, err, entry["wall_s"]["base"] = child(base, {**request, "out": str(out_base)}, tmp, args.timeout)
                if got is None:
                    entry.update(result="failed", error=f"failed at base: {err}")
                else:
                    entry["plan"] = got
                    entry["steps"] = json.loads((out_base / "summary.json").read_text()).get("steps")
                    got, err, entry["wall_s"]["head"] = child(
                        head, {**request, "plan": got, "out": str(out_head)}, tmp, args.timeout)
                    if got is None:
                        entry.update(result="failed", error=f"failed at head: {err}")
                    else:
                        diffs = compare(out_base, out_head, args.rtol)
                        entry.update(result="differ" if diffs else "same", differences=diffs)
                shutil.rmtree(tmp / "out" / name, ignore_errors=True)
            results[name] = entry
            wall = "+".join(f"{w:.0f}" for w in entry["wall_s"].values())
            if entry["result"] == "same":
                capped = " capped" if entry["plan"].get("capped") else ""
                line = f"same ({entry['steps'] or '-'}{capped} steps; {wall} s)"
            elif entry["result"] == "failed":
                line = entry["error"]
            else:
                d = entry["differences"]
                line = f"DIFFERS in {len(d)} values: " + "; ".join(d[:SHOWN]) + (" ..." if len(d) > SHOWN else "")
            print(f"{name:28s} {line}", flush=True)

        count = {k: sum(e["result"] == k for e in results.values()) for k in ("same", "differ", "failed")}
        print(f"{count['same']} same, {count['differ']} differ, {count['failed']} failed, of {len(results)} examples")
        if args.out:
            args.out.write_text(json.dumps({
                "base": base_rev, "head": head_rev, "steps": args.steps, "rtol": args.rtol, "atol": ATOL,
                "ignored_keys": sorted(IGNORED_KEYS),
                "machine": {"platform": platform.platform(), "processor": platform.processor(),
                            "cpu_count": os.cpu_count(), "python": platform.python_version()},
                "count": count, "examples": results}, indent=2) + "\n")
        return 0 if results and count["same"] == len(results) else 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
