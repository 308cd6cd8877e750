"""What sets the time step of a coupled (``cfdmp``) run, step by step (issue 34). The tests run it on
``cfdmp-shock-tube`` only (tests/test_step_budget.py).

    python benchmarks/step_budget.py [--example steel-plate-blast] [--end 2e-4] [--label before]
                                     [--out benchmarks/step_budget.json]

Advances the scenario with the shipped compiled time loop one step per call (the same steps as
``blastfsi run``: the loop's step does not depend on how the steps are grouped into calls) and, before each
step, evaluates the three stable steps of the coupled step's rule, dt = min(dt_E, dt_M)
(:meth:`blastfsi.cfdmp.method.Cfdmp.advance`):

* dt_E, the Eulerian grid's CFL step (:func:`blastfsi.euler.step.stable_dt`; HLLC-MUSCL:
  cfl dx / max_cells sum_d (|u_d| + c)), over the cells the coupled step reads it from: once coupled, the
  fictitious box cells only next to the scheme's own (entries before ``shipped_full_owned_cells`` took every
  cell the grid holds, the deeper fictitious ones included, which the run's step does not read);
* dt_M over the structure particles, and dt_M over the gas particles (:func:`blastfsi.mpm.musl.stable_dt`:
  cfl h / max_p (|v_p| + a_p), a_p = s_p + sqrt(s_p^2 + c_p^2), s the bulk viscosity's signal speed, a gas
  particle's a_p that of the mixture its nodes carry, :func:`blastfsi.mpm.musl.mixture_signal`);

and names the smallest (the step taken is the time left to ``time.end`` in the fewest equal steps no
longer than it, :func:`blastfsi.timeloop.step_to`), with the cell or particle that sets it (its kind,
density, speed, sound speed, position). Beside them, the steps of what the physics needs: the steel's own,
and the resolved gas's (cells and gas particles denser than RESOLVED x the ambient density, the median of
the grid at the start; ``dt_gas_resolved``: the step the run's rule would give if only the resolved gas
counted). Beside the rule, each gas particle's own signal |v_p| + a_p (``dt_gas_own``, ``dt_gas_resolved_own``:
the stricter measure, and the one of the entries before ``shipped_full_owned_cells``).

The per-step rows are summarised (which limit set how many steps; the steps the needed step would take over
the same time, sum dt / dt_needed) and sampled every ``--every`` steps into the JSON file, one entry per
``--label``.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import api, runtime
from blastfsi import method as methods
from blastfsi.cfdmp import coupling as cp
from blastfsi.euler.step import _bad_and_speed, _with_face_neighbours
from blastfsi.mpm.musl import VOID_DENSITY, mixture_signal
from blastfsi.mpm.viscosity import signal_speed
from blastfsi.scenario import expand
from blastfsi.method import compiled_advance
from blastfsi.simulation import _resized, _stack
from blastfsi.timeloop import FAULT_NONE, FAULT_POOL_FULL
from machine import cpu_model

RESOLVED = 0.01  # resolved gas: density above this share of the ambient density
LIMITS = ("euler", "structure", "gas")


def budget_of(s, params, static, rho_resolved):
    """The stable steps of state ``s`` (one member) and what sets each (traced)."""
    cs = static.coupling
    cfg, mcfg = cs.euler, cs.mpm
    lay = params.layout
    _, rate = _bad_and_speed(s.U, params.euler, cfg)
    # the cells whose signal the coupled step's rule reads (Cfdmp.advance's stable_dt): once coupled, the
    # fictitious box cells only next to the scheme's own cells
    rate = jnp.where(_with_face_neighbours(~lay.fictitious | ~s.coupled), rate, 0.0).reshape(-1)
    prim = cp.flat_primitives(s.U, params.euler.eos, cfg)
    # 0: Eulerian-only, 1: bridge, 2: fictitious
    cell_kind = jnp.where(lay.outside.reshape(-1), 0, jnp.where(lay.fictitious.reshape(-1), 2, 1))
    cfl_e = jnp.asarray(params.euler.cfl, s.U.dtype)
    k_e = jnp.argmax(rate)
    resolved_cells = prim["rho"] > rho_resolved
    k_er = jnp.argmax(jnp.where(resolved_cells, rate, 0.0))

    P = s.mpm.particles
    d = mcfg.grid.dim
    tracer = static.tracers[0] if static.tracers else 0  # the first output.tracers point (the plate's centre)
    h = mcfg.grid.cell_size
    prm = params.mpm
    speed_v = jnp.sqrt(jnp.sum(P.v * P.v, axis=1))
    slot = jnp.arange(P.active.shape[0])
    structure = P.active & (slot < cs.n_structure)
    gas = P.active & (slot >= cs.n_structure)
    gas_resolved = gas & (P.point.density > rho_resolved)
    # the MPM step's rule (mpm.musl.stable_dt): |v| plus the wave signal, a gas particle's that of the mixture its
    # nodes carry (mpm.musl.mixture_signal); beside it each gas particle's own signal (the stricter)
    own = signal_speed(P.wave_speed, 0.0, P.vol_rate, h, prm.q_quadratic, prm.q_linear)
    signal = speed_v + jnp.where(gas, mixture_signal(P, own, mcfg), own)
    signal_own = speed_v + own

    def fastest(mask, values):
        k = jnp.argmax(jnp.where(mask, values, 0.0))
        return k, jnp.where(jnp.any(mask), values[k], 0.0)

    k_s, v_s = fastest(structure, signal)
    _, v_s_elastic = fastest(structure, P.wave_speed + speed_v)  # c_L + |v| without the bulk viscosity
    k_g, v_g = fastest(gas, signal)
    k_gr, v_gr = fastest(gas_resolved, signal)
    _, v_g_own = fastest(gas, signal_own)
    _, v_gr_own = fastest(gas_resolved, signal_own)
    dt_s = prm.cfl * h / v_s
    dt_g = prm.cfl * h / v_g
    faster_than_steel = jnp.sum(gas & (signal > v_s))

    def particle(k):
        return dict(slot=k, density=P.point.density[k], speed=speed_v[k], sound_speed=P.wave_speed[k],
                    signal=signal[k], material=P.material[k], x=P.x[k, :d],
                    energy=P.point.energy[k])

    def cell(k):
        return dict(index=k, kind=cell_kind[k], density=prim["rho"][k], rate=rate[k],
                    speed=jnp.sqrt(jnp.sum(prim["velocity"][:, k] ** 2)), pressure=prim["pressure"][k],
                    products=prim["mass_fraction"][0, k] if prim["mass_fraction"].shape[0] == 2 else 0.0)

    return dict(
        t=s.t, coupled=s.coupled,
        dt_euler=cfl_e * cfg.dx / rate[k_e], dt_euler_resolved=cfl_e * cfg.dx / rate[k_er],
        dt_structure=dt_s, dt_structure_elastic=prm.cfl * h / v_s_elastic,
        dt_gas=dt_g, dt_gas_resolved=prm.cfl * h / v_gr,
        dt_gas_own=prm.cfl * h / v_g_own, dt_gas_resolved_own=prm.cfl * h / v_gr_own,
        euler_cell=cell(k_e), euler_resolved_cell=cell(k_er),
        structure_particle=particle(k_s), gas_particle=particle(k_g), gas_resolved_particle=particle(k_gr),
        gas_particles=jnp.sum(gas), void_gas_particles=jnp.sum(gas & (P.point.density < VOID_DENSITY)),
        gas_faster_than_structure=faster_than_steel,
        centre_displacement=(P.x[tracer, :d] - params.structure_x0[tracer, :d] if static.tracers
                             else jnp.zeros(d)))


def to_host(tree):
    return jax.tree_util.tree_map(lambda a: np.asarray(a).tolist(), jax.device_get(tree))


def measure(example: str, end: float, every: int, overrides: dict) -> dict:
    """Run ``example`` to ``end`` with ``overrides`` one step per call and summarise its step budget."""
    data = api.load(example, set={"time.end": end, **overrides})
    sc, _, member_scs = expand(data)
    method = methods.get(sc.method)
    with runtime.precision(sc.numerics.precision), runtime.compilation_cache():
        setups = [method.build(member_scs[0])]
        dtype = jnp.float64 if sc.numerics.precision == "float64" else jnp.float32
        static = method.static(setups[0], member_scs[0])
        state = _stack([method.initial_state(setups[0], member_scs[0], sc.output.history_samples, dtype)], "state")
        params = _stack([method.params(setups[0], dtype)], "params")
        begin = float(np.asarray(state.t)[0])
        sample_interval = (sc.time.end - begin) / (sc.output.history_samples - 1)
        scalars = (1, sample_interval, sc.time.dt_min_fraction)
        advance, _ = compiled_advance(method, static, state, params, sc.time.end, *scalars)
        first = jax.tree_util.tree_map(lambda a: a[0], (state, params))
        rho_ambient = float(np.median(np.asarray(cp.flat_primitives(first[0].U, first[1].euler.eos,
                                                                    static.coupling.euler)["rho"])))
        rho_resolved = RESOLVED * rho_ambient

        def compiled_budget(static):  # budget_of the batch's one member
            return jax.jit(lambda st, pa: budget_of(*jax.tree_util.tree_map(lambda a: a[0], (st, pa)), static,
                                                    rho_resolved))

        diag = compiled_budget(static)
        rows, loop_s, diag_s = [], 0.0, 0.0
        while float(np.asarray(state.t)[0]) < sc.time.end:
            t0 = time.perf_counter()
            row = jax.block_until_ready(diag(state, params)) if bool(np.asarray(state.coupled)[0]) else None
            t1 = time.perf_counter()
            state = jax.block_until_ready(advance(state, params, sc.time.end, 1, *scalars[1:]))
            t2 = time.perf_counter()
            diag_s, loop_s = diag_s + t1 - t0, loop_s + t2 - t1
            fault = int(np.asarray(state.fault)[0])
            if fault == FAULT_POOL_FULL:
                setups, state = _resized(method, setups, state)
                static = method.static(setups[0], member_scs[0])
                advance, _ = compiled_advance(method, static, state, params, sc.time.end, *scalars)
                diag = compiled_budget(static)
                continue
            if fault != FAULT_NONE:
                raise RuntimeError(f"fault {fault} at t = {float(np.asarray(state.t)[0])}")
            if row is not None:
                row = to_host(row)
                row["dt"] = float(np.asarray(state.dt_prev)[0])
                rows.append(row)
        steps = int(np.asarray(state.step)[0])
        final = to_host(diag(state, params))
    return summarise(rows, final, steps, every, rho_ambient, loop_s, diag_s, example, end, overrides)


def summarise(rows, final, steps, every, rho_ambient, loop_s, diag_s, example, end, overrides) -> dict:
    dt = np.array([r["dt"] for r in rows])
    limits = np.array([[r["dt_euler"], r["dt_structure"], r["dt_gas"]] for r in rows])
    setter = np.argmin(limits, axis=1)
    needed = np.array([min(r["dt_structure"], r["dt_euler_resolved"], r["dt_gas_resolved"]) for r in rows])
    needed_own = np.array([min(r["dt_structure"], r["dt_euler_resolved"], r["dt_gas_resolved_own"]) for r in rows])
    steel = np.array([r["dt_structure"] for r in rows])
    kinds = ("Eulerian-only", "bridge", "fictitious")
    euler_set = [r["euler_cell"] for r, k in zip(rows, setter) if k == 0]
    return {
        "example": example, "end": end, "overrides": overrides, "steps": steps, "coupled_steps": len(rows),
        "rho_ambient": rho_ambient, "resolved_density": RESOLVED * rho_ambient,
        "loop_s_one_step_per_call": round(loop_s, 1), "diagnostic_s": round(diag_s, 1),
        "set_by": {name: int(np.sum(setter == k)) for k, name in enumerate(LIMITS)},
        "euler_set_by_cell_kind": {kinds[k]: int(sum(c["kind"] == k for c in euler_set)) for k in range(3)},
        "steps_at_needed_step": float(np.sum(dt / needed)),
        "steps_at_steel_step": float(np.sum(dt / steel)),
        "ratio_steps_to_needed": float(len(rows) / np.sum(dt / needed)),
        "steps_at_needed_step_own_signal": float(np.sum(dt / needed_own)),
        "ratio_steps_to_needed_own_signal": float(len(rows) / np.sum(dt / needed_own)),
        "coupled_time": float(np.sum(dt)),
        "end_time": final["t"], "centre_displacement_end": final["centre_displacement"],
        "rows": [r for i, r in enumerate(rows) if i % every == 0 or i == len(rows) - 1],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--example", default="steel-plate-blast")
    parser.add_argument("--end", type=float, default=2e-4, help="time.end [s]")
    parser.add_argument("--every", type=int, default=25, help="keep every n-th row")
    parser.add_argument("--label", default="shipped", help="the code measured, e.g. before or after")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scenario override")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("step_budget.json"))
    args = parser.parse_args()
    overrides = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    result = measure(args.example, args.end, args.every, overrides)
    print(json.dumps({k: v for k, v in result.items() if k != "rows"}, indent=1))
    saved = json.loads(args.out.read_text()) if args.out.is_file() else {}
    saved[args.label] = {"machine": f"{cpu_model()}, {os.cpu_count()} cores (shared)", **result}
    args.out.write_text(json.dumps(saved, indent=1) + "\n")


if __name__ == "__main__":
    main()
