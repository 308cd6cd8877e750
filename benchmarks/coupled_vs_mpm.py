"""The coupled solver against MPM everywhere on the CFDMP paper's explosion beside a slab (issue 38, item 4).

    python benchmarks/coupled_vs_mpm.py [--runs cfdmp-hllc-hancock cfdmp-hllc-muscl mpm-everywhere]
                                        [--parts] [--out benchmarks/coupled_vs_mpm_he_slab_2d.json]

``he-slab-2d`` (CFDMP: Eulerian grid, a 5-cell bridge and an MPM box around the slab) and ``he-slab-2d-mpm``
(the same case with MPM everywhere) to t = 42.1 us (32.5 us after the remap at 9.6 us, the paper's Fig. 12),
one after another in this process, nothing else running, no output written: steps, compile and loop seconds
of each, and the loop-time ratio of MPM everywhere over each coupled run. ``--parts``: where a coupled step's
time goes, each part of the coupled step of :mod:`blastfsi.cfdmp.method` compiled on its own and timed on the
state at 23.6 us (best of 5; the parts overlap a little: the MPM step includes its interface source).

The JSON keeps a list of series (one per call, with the machine and the date); the paper's ratio is 3.6x.
"""
from __future__ import annotations

import argparse
import datetime
import json
import time
from pathlib import Path

import blastfsi
from machine import described

END = 4.21e-5  # s from the detonation: 32.5 us after the remap (000 Fig. 12)
COMMON = {"time.end": END, "output.fields": 0, "output.plots": False, "output.history_samples": 131}
RUNS = {"cfdmp-hllc-hancock": ("he-slab-2d", {}),  # (the example's scheme)
        "cfdmp-hllc-muscl": ("he-slab-2d", {"numerics.scheme": "hllc-muscl"}),
        "mpm-everywhere": ("he-slab-2d-mpm", {})}
PARTS_AT = 2.36e-5  # s: the state whose step parts are timed (the blast in the box, ~27 000 particles)


def loops(names) -> dict:
    out = {}
    for name in names:
        example, overrides = RUNS[name]
        started = time.perf_counter()
        s = blastfsi.run(example, set={**COMMON, **overrides}).summary
        out[name] = {"example": example, "set": overrides, "steps": s["steps"],
                     "compile_s": round(s["compile_time"], 2), "loop_s": round(s["loop_time"], 2), "run_call_s": round(time.perf_counter() - started, 2),
                     "ms_per_step": round(1e3 * s["loop_time"] / s["steps"], 2)}
        print(name, out[name], flush=True)
    return out


def _best(fn, arg, repeats=5) -> float:
    import jax
    jax.block_until_ready(fn(arg))
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        jax.block_until_ready(fn(arg))
        best = min(best, time.perf_counter() - started)
    return best


def parts(scheme: str, example: str = "he-slab-2d", at: float = PARTS_AT) -> dict:
    """Milliseconds of each part of the coupled step of ``example`` at time ``at``, and of whole steps (20,
    through advance)."""
    import jax
    import jax.numpy as jnp

    from blastfsi import euler as ek
    from blastfsi import method as methods, mpm, simulation
    from blastfsi.api import load
    from blastfsi.cfdmp import coupling as cp
    from blastfsi.scenario import expand

    jax.config.update("jax_enable_x64", True)
    sc, _, scs = expand(load(example, set={"output.history_samples": 401, "numerics.scheme": scheme}))
    method, _, static, state, params = simulation.prepare(sc, scs)
    interval = (sc.time.end - float(state.t[0])) / (sc.output.history_samples - 1)
    floor = sc.time.dt_min_fraction
    advance, _ = methods.compiled_advance(method, static, state, params, at, 50_000, interval, floor)
    state = jax.block_until_ready(advance(state, params, at, 50_000, interval, floor))
    twenty, _ = methods.compiled_advance(method, static, state, params, 1.0, 20, interval, floor)
    whole = _best(lambda st: twenty(jax.tree_util.tree_map(jnp.copy, st), params, 1.0, 20, interval, floor),
                  state, 3) / 20

    s, prm = jax.tree_util.tree_map(lambda a: a[0], (state, params))
    cs = static.coupling
    cfg, mcfg, lay, eos = cs.euler, cs.mpm, prm.layout, prm.euler.eos
    dt = 1e-8
    prim = cp.flat_primitives(s.U, eos, cfg)
    transfers = ek.step_with_transfers(s.U, dt, prm.euler, cfg)[1]
    table = {
        "eulerian CFL step": lambda s: ek.stable_dt(s.U, prm.euler, cfg, ~lay.fictitious),
        "MPM CFL step (nodal mixture signal)": lambda s: mpm.stable_dt(s.mpm, prm.mpm, mcfg),
        "cell primitives": lambda s: cp.flat_primitives(s.U, eos, cfg),
        "MPM step with the interface source": lambda s: mpm.step(
            s.mpm, dt, prm.mpm, mcfg, cp.interface_source(cp.flat_primitives(s.U, eos, cfg), lay, cs,
                                                          prm.mpm.reference_pressure)),
        "MPM step alone": lambda s: mpm.step(s.mpm, dt, prm.mpm, mcfg, None),
        "eulerian step with face transfers": lambda s: ek.step_with_transfers(s.U, dt, prm.euler, cfg),
        "particles leaving the box": lambda s: cp.remove_leaving(s.mpm, s.reservoirs, s.budget, cs, lay),
        "reservoirs into the cells": lambda s: cp.receive(s.U, s.reservoirs, s.budget, transfers, prim, eos, cs, lay),
        "inflow particles": lambda s: cp.feed(s.mpm, s.reservoirs, s.budget, prim, eos, prm.mpm, cs, lay),
        "gas particles to cells (fictitious rows)": lambda s: cp.gas_rows(s.mpm.particles, cs),
    }
    out = {"at_s": float(s.t), "particles": int(s.mpm.particles.active.sum()),
           "pool": int(s.mpm.particles.active.shape[0]), "whole_step_ms": round(1e3 * whole, 2), "parts_ms": {}}
    for name, fn in table.items():
        out["parts_ms"][name] = round(1e3 * _best(jax.jit(fn), s), 2)
        print(f"  {scheme}: {name:42s} {out['parts_ms'][name]:8.2f} ms", flush=True)
    print(f"  {scheme}: whole step {out['whole_step_ms']} ms", flush=True)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", nargs="*", default=list(RUNS), choices=list(RUNS))
    ap.add_argument("--parts", action="store_true", help="also time the parts of a coupled step")
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("coupled_vs_mpm_he_slab_2d.json"))
    args = ap.parse_args(argv)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    series = {"machine": described(), "date_utc": now,
              "command": "python benchmarks/coupled_vs_mpm.py " + " ".join(argv or []), "runs": loops(args.runs)}
    runs = series["runs"]
    if "mpm-everywhere" in runs:
        series["loop_ratio_mpm_over"] = {k: round(runs["mpm-everywhere"]["loop_s"] / v["loop_s"], 3)
                                         for k, v in runs.items() if k != "mpm-everywhere"}
        print("loop time of MPM everywhere over:", series["loop_ratio_mpm_over"], flush=True)
    if args.parts:
        series["step_parts"] = {scheme: parts(scheme) for scheme in ("hllc-muscl", "hllc-hancock")}
    data = json.loads(args.out.read_text()) if args.out.exists() else {}
    if "series" not in data:  # (the first record, kept as the first series)
        data = {"series": [data]} if data else {"series": []}
    data["series"].append(series)
    args.out.write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    import sys
    main(sys.argv[1:])
