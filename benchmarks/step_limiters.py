"""What sets the coupled step of ``steel-plate-blast`` (Table 1 case 1) over its run (issue 34: "case 1's step
count within 1.2x of what the steel and the resolved gas need"): at 24 times from the remap to the end, the
steps taken since the last, and the CFL steps of each part of the coupled state at that time: the Eulerian
cells the scheme owns (``euler.stable_dt``), the gas particles (their nodes' mixture signal, ``mpm.musl``) and
the solid particles, with the density and signal speed of the gas particle that sets the gas limit.

    python benchmarks/step_limiters.py [--out benchmarks/step_limiters.json]

The loop is the run's compiled loop without the driver's output or pool packing (one fixed pool). The steps the
steel alone would need are the sum over the intervals of (interval / its CFL step at the interval's end).
Not run by the tests (about 4 min on 2 cores).
"""
from __future__ import annotations

import argparse
import datetime
import json
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import euler as ek
from blastfsi import method as methods
from blastfsi import runtime, simulation
from blastfsi.api import load
from blastfsi.mpm import musl
from blastfsi.scenario import expand
from machine import described


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    sc, _, member_scs = expand(load("steel-plate-blast", set={"output.fields": 0, "output.plots": False}))
    rows = []
    with runtime.precision(sc.numerics.precision):
        method, _, static, state, params = simulation.prepare(sc, member_scs)
        cs, one = static.coupling, jax.tree_util.tree_map(lambda a: a[0], params)
        lay, h = one.layout, cs.mpm.grid.cell_size

        @jax.jit
        def limits(s):  # (the Eulerian cells' step, the gas particles', the solid particles', the gas's fastest)
            P = s.mpm.particles
            signal = musl.signal_speed(P.wave_speed, 0.0, P.vol_rate, h, one.mpm.q_quadratic, one.mpm.q_linear)
            gas = musl.gas_particles(P, cs.mpm)
            signal = jnp.where(gas, musl.mixture_signal(P, signal, cs.mpm), signal)
            speed = jnp.where(P.active, jnp.sqrt(jnp.sum(P.v * P.v, axis=1)) + signal, 0.0)
            fastest = jnp.argmax(jnp.where(gas, speed, 0.0))
            return (ek.stable_dt(s.U, one.euler, cs.euler, ~lay.fictitious | ~s.coupled),
                    one.mpm.cfl * h / jnp.max(jnp.where(gas, speed, 0.0)),
                    one.mpm.cfl * h / jnp.max(jnp.where(gas, 0.0, speed)), P.point.density[fastest], speed[fastest])

        begin = float(state.t[0])
        scalars = (sc.time.end, 20_000, (sc.time.end - begin) / (sc.output.history_samples - 1),
                   sc.time.dt_min_fraction)
        advance, _ = methods.compiled_advance(method, static, state, params, *scalars)
        started, last_t, last_step = time.perf_counter(), begin, 0
        for t_stop in np.linspace(begin, sc.time.end, 25)[1:]:
            while float(state.t[0]) < t_stop:
                state = advance(state, params, t_stop, *scalars[1:])
            member = jax.tree_util.tree_map(lambda a: a[0], state)
            dt_e, dt_gas, dt_solid, rho, speed = (float(x) for x in limits(member))
            t, step = float(state.t[0]), int(state.step[0])
            rows.append({"t": t, "steps": step - last_step, "mean_dt": (t - last_t) / max(step - last_step, 1),
                         "dt_euler": dt_e, "dt_gas": dt_gas, "dt_solid": dt_solid,
                         "fastest_gas_density": rho, "fastest_gas_signal": speed})
            print(json.dumps(rows[-1]), flush=True)
            last_t, last_step = t, step
    solid_need = sum((r["t"] - t0) / r["dt_solid"] for r, t0 in zip(rows, [begin] + [r["t"] for r in rows[:-1]]))
    now = datetime.datetime.now(datetime.timezone.utc)
    record = {"machine": described(), "date_utc": now.strftime("%Y-%m-%d %H:%M"),
              "command": "python benchmarks/step_limiters.py " + " ".join(sys.argv[1:]),
              "loop_seconds": round(time.perf_counter() - started, 1), "steps": last_step,
              "steel_alone_would_need": round(solid_need), "ratio": round(last_step / solid_need, 3), "rows": rows}
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"{last_step} steps; the steel alone would need {round(solid_need)}; written {args.out}")


if __name__ == "__main__":
    main()
