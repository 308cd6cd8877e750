"""PyClaw side of the 2D blast comparison (issue 5, item 7). Not run by the tests; does not import blastfsi.

    /tmp/clawenv/bin/python benchmarks/bench_pyclaw.py --cells 400 --out benchmarks/pyclaw_blast2d.npz

PyClaw is not a dependency of blastfsi; its own environment, on a fresh Debian machine (Clawpack
builds its Riemann solvers from Fortran; as used 2026-12-04):

    apt-get install -y gfortran
    python3 -m venv /tmp/clawenv && /tmp/clawenv/bin/pip install numpy clawpack==5.14.0

Problem (the same as ``bench_euler.py --pyclaw``): ideal gas gamma = 1.4 on [-1, 1]^2,
rho = 1 everywhere, u = 0, p = 10 in the cells whose centre lies at r < 0.2 and
p = 1 elsewhere; zero-order extrapolation (outflow) on all four sides; t_end = 0.25.

Solver: PyClaw's classic (Clawpack 5) 2D wave-propagation solver, second order
(Lax-Wendroff-LeVeque correction terms) with the MC limiter on every wave, the
Roe solver ``riemann.euler_4wave_2D`` (Fortran, with its transverse solver),
unsplit with transverse corrections (``transverse_waves = 2``, corner transport);
``--split`` selects Godunov dimensional splitting instead. Variable time step with
PyClaw's defaults (cfl_desired 0.9, cfl_max 1.0; a step over cfl_max is rejected
and repeated). One thread (PyClaw's classic solver is serial Fortran).

Timing: wall time of ``Controller.run()`` with output switched off, best of
``--repeats``; cell-steps = accepted steps x cells.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from clawpack import pyclaw, riemann
from clawpack.riemann.euler_4wave_2D_constants import density, energy, num_eqn, x_momentum, y_momentum

GAMMA = 1.4  # ideal diatomic gas
P_IN, P_OUT, RHO0, R_CHARGE = 10.0, 1.0, 1.0, 0.2  # nondimensional blast (module docstring)


def build(cells: int, t_end: float, split: bool) -> pyclaw.Controller:
    solver = pyclaw.ClawSolver2D(riemann.euler_4wave_2D)
    solver.limiters = pyclaw.limiters.tvd.MC
    solver.order = 2
    solver.dimensional_split = split
    solver.transverse_waves = 0 if split else 2
    solver.all_bcs = pyclaw.BC.extrap

    x = pyclaw.Dimension(-1.0, 1.0, cells, name="x")
    y = pyclaw.Dimension(-1.0, 1.0, cells, name="y")
    domain = pyclaw.Domain([x, y])
    state = pyclaw.State(domain, num_eqn)
    state.problem_data["gamma"] = GAMMA
    xc, yc = state.grid.p_centers
    p = np.where(np.hypot(xc, yc) < R_CHARGE, P_IN, P_OUT)
    state.q[density] = RHO0
    state.q[x_momentum] = 0.0
    state.q[y_momentum] = 0.0
    state.q[energy] = p / (GAMMA - 1.0)

    claw = pyclaw.Controller()
    claw.tfinal = t_end
    claw.num_output_times = 1
    claw.solution = pyclaw.Solution(state, domain)
    claw.solver = solver
    claw.output_format = None
    claw.keep_copy = True
    claw.verbosity = 0
    return claw


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, default=400, help="cells per axis")
    ap.add_argument("--t-end", type=float, default=0.25)
    ap.add_argument("--split", action="store_true", help="dimensional splitting instead of unsplit + transverse")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", required=True, help=".npz with density, centres, steps and timing")
    args = ap.parse_args()

    walls = []
    for _ in range(args.repeats):
        claw = build(args.cells, args.t_end, args.split)
        t0 = time.perf_counter()
        claw.run()
        walls.append(time.perf_counter() - t0)
    final = claw.frames[-1].state
    steps = int(claw.solver.status["numsteps"])
    xc, yc = final.grid.p_centers
    wall = min(walls)
    cells = args.cells ** 2
    np.savez(args.out, density=np.asarray(final.q[density]), x=xc, y=yc, time=float(claw.frames[-1].t),
             steps=steps, cells=cells, wall_s=wall, walls_s=np.asarray(walls),
             cell_steps_per_s=cells * steps / wall, cfl_max_seen=float(claw.solver.status["cflmax"]),
             solver=("classic 2D, euler_4wave_2D (Roe), MC limiter, order 2, "
                     + ("dimensional splitting" if args.split else "unsplit, transverse_waves=2")))
    print(f"pyclaw {'split' if args.split else 'unsplit'} {args.cells}^2: {steps} steps, wall {wall:.3f} s, "
          f"{cells * steps / wall:.3e} cell-steps/s -> {args.out}")


if __name__ == "__main__":
    main()
