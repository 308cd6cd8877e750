"""The MPM step of a coupled run with the supports' constraint sums over the whole pool or over the structures'
slots only (``mpm.Config.prescribed_slots``), timed side by side in one process on one state.

    python benchmarks/constraint_sums.py [--example steel-plate-blast] [--at 2e-4]
                                         [--out benchmarks/constraint_sums.json]

The example runs to ``--at`` (s from the detonation, no output); then the MPM step with its interface source
(the bulk of a coupled step) is compiled both ways and timed alternately, best of 5 x 5 calls, and the two
results are compared bit for bit; so are 20 whole coupled steps (the compiled time loop, best of 3). A record is
appended to the JSON with the machine and the date.
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import time
from pathlib import Path

from machine import described


def measure(example: str, at: float) -> dict:
    import jax
    import jax.numpy as jnp
    import numpy as np

    from blastfsi import method as methods, mpm, simulation
    from blastfsi.api import load
    from blastfsi.cfdmp import coupling as cp
    from blastfsi.scenario import expand

    jax.config.update("jax_enable_x64", True)
    sc, _, scs = expand(load(example, set={"output.history_samples": 401}))
    method, _, static, state, params = simulation.prepare(sc, scs)
    interval = (sc.time.end - float(state.t[0])) / (sc.output.history_samples - 1)
    floor = sc.time.dt_min_fraction
    advance, _ = methods.compiled_advance(method, static, state, params, at, 50_000, interval, floor)
    state = jax.block_until_ready(advance(state, params, at, 50_000, interval, floor))
    s, prm = jax.tree_util.tree_map(lambda a: a[0], (state, params))
    cs = static.coupling
    cfg, lay, eos = cs.euler, prm.layout, prm.euler.eos
    dt = 1e-8
    forms = {"whole pool": None, "structure slots": cs.mpm.prescribed_slots}
    steps = {}
    for label, slots in forms.items():
        mcfg = dataclasses.replace(cs.mpm, prescribed_slots=slots)
        steps[label] = jax.jit(lambda st, mcfg=mcfg: mpm.step(
            st.mpm, dt, prm.mpm, mcfg, cp.interface_source(cp.flat_primitives(st.U, eos, cfg), lay, cs,
                                                           prm.mpm.reference_pressure)))
    results = [jax.tree_util.tree_leaves(jax.block_until_ready(f(s))) for f in steps.values()]
    same = all(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True) for a, b in zip(*results))
    best = dict.fromkeys(steps, float("inf"))
    for _ in range(5):
        for label, f in steps.items():
            started = time.perf_counter()
            for _ in range(5):
                jax.block_until_ready(f(s))
            best[label] = min(best[label], (time.perf_counter() - started) / 5)
    loops = {}
    for label, slots in forms.items():
        mcfg = dataclasses.replace(cs.mpm, prescribed_slots=slots)
        loops[label] = methods.compiled_advance(method, static._replace(coupling=cs._replace(mpm=mcfg)), state, params,
                                                1.0, 20, interval, floor)[0]
        jax.block_until_ready(loops[label](jax.tree_util.tree_map(jnp.copy, state), params, 1.0, 20, interval, floor))
    whole = dict.fromkeys(loops, float("inf"))
    for _ in range(3):
        for label, f in loops.items():
            fresh = jax.tree_util.tree_map(jnp.copy, state)
            started = time.perf_counter()
            jax.block_until_ready(f(fresh, params, 1.0, 20, interval, floor))
            whole[label] = min(whole[label], (time.perf_counter() - started) / 20)
    out = {"example": example, "at_s": float(s.t), "pool": int(s.mpm.particles.active.shape[0]),
           "active": int(s.mpm.particles.active.sum()), "structure_slots": list(cs.mpm.prescribed_slots),
           "mpm_step_ms": {k: round(1e3 * v, 2) for k, v in best.items()},
           "speedup": round(best["whole pool"] / best["structure slots"], 3), "bit_identical": bool(same),
           "coupled_step_ms": {k: round(1e3 * v, 2) for k, v in whole.items()},
           "coupled_speedup": round(whole["whole pool"] / whole["structure slots"], 3)}
    print(out, flush=True)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--example", default="steel-plate-blast")
    ap.add_argument("--at", type=float, default=2e-4)
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("constraint_sums.json"))
    args = ap.parse_args(argv)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    record = {"machine": described(), "date_utc": now,
              "command": "python benchmarks/constraint_sums.py " + " ".join(argv or []),
              **measure(args.example, args.at)}
    data = json.loads(args.out.read_text()) if args.out.exists() else {"records": []}
    data["records"].append(record)
    args.out.write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    import sys
    main(sys.argv[1:])
