"""Why the two mirrored gauges of ``he-slab-3d`` disagree: the example as shipped, and again without its
slab (``structures = []``), the gauges sampled 401 times.

Gauge 0 (x = -125 mm) lies in the Eulerian air, gauge 1 (x = +125 mm) the same distance from the charge on
the other side, 25 mm inside the MPM box (1 gas particle per 5 mm cell) and 9 mm in front of the slab's face
(x = 134 mm). Without the slab the two read the same incident blast but for the discretisation (what the MPM
gas does to it); with the slab gauge 1 also reads the flow stopped by the slab. Written per run: the gauges'
summaries and histories; and the bound on what the slab can add, the rigid-wall reflection of the incident
state at gauge 1 (its pressure, density and normal velocity at its incident peak, shocked air, ideal gas
gamma = 1.4): the exact Riemann problem of that state against its mirror image
(:class:`blastfsi.exact.riemann.RiemannProblem`).

    .venv/bin/python benchmarks/he_slab_3d_gauges.py [--out benchmarks/he_slab_3d_gauges.json]

About 5 min per run on a 2-core CPU.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import blastfsi
from blastfsi.api import load
from blastfsi.exact.riemann import RiemannProblem
from blastfsi.materials.gases import GASES

SAMPLES = 401


def one(with_slab: bool) -> dict:
    data = load("he-slab-3d")
    data["output"].update({"fields": 0, "plots": False, "history_samples": SAMPLES})
    if not with_slab:
        data["structures"] = []
    started = time.perf_counter()
    res = blastfsi.run(data)
    h = res.history
    keys = ["time"] + [f"gauge{k}_{q}" for k in (0, 1) for q in ("overpressure", "density", "velocity_x")]
    return {"wall_s": time.perf_counter() - started, "steps": res.summary["steps"], "gauges": res.summary["gauges"],
            "history": {k: np.asarray(h[k]).tolist() for k in keys}}


def incident_comparison(run: dict) -> dict:
    """Gauge 1 against gauge 0 without the slab: peak, impulse, time of the peak."""
    h = {k: np.asarray(v) for k, v in run["history"].items()}
    g0, g1 = run["gauges"]
    t_peak = [float(h["time"][np.argmax(h[f"gauge{k}_overpressure"])]) for k in (0, 1)]
    return {"peak_ratio": g1["peak_overpressure"] / g0["peak_overpressure"],
            "impulse_ratio": g1["impulse"] / g0["impulse"],
            "peak_time_s": t_peak, "peak_time_lag_s": t_peak[1] - t_peak[0]}


def rigid_reflection(run: dict) -> dict:
    """The rigid-wall reflection of gauge 1's state at its incident peak (no-slab run)."""
    h = {k: np.asarray(v) for k, v in run["history"].items()}
    i = int(np.argmax(h["gauge1_overpressure"]))
    p0 = GASES["air"].pressure
    state = (float(h["gauge1_density"][i]), float(h["gauge1_velocity_x"][i]), float(h["gauge1_overpressure"][i] + p0))
    rp = RiemannProblem(left=state, right=(state[0], -state[1], state[2]))
    return {"state_rho_u_p": state, "reflected_overpressure": rp.p_star - p0}


def departure_time(slab: dict, free: dict, rel: float = 0.05) -> float:
    """First time gauge 1 with the slab reads more than (1 + rel) x gauge 1 without it (above 1 MPa)."""
    a = np.asarray(slab["history"]["gauge1_overpressure"])
    b = np.asarray(free["history"]["gauge1_overpressure"])
    hit = np.nonzero((a > (1.0 + rel) * b) & (a > 1e6))[0]
    return float(np.asarray(slab["history"]["time"])[hit[0]]) if hit.size else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    free, slab = one(False), one(True)
    out = {"machine": f"{platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
           "command": " ".join([Path(sys.executable).name, *sys.argv]),
           "incident_gauge1_over_gauge0": incident_comparison(free),
           "rigid_reflection_of_gauge1_incident": rigid_reflection(free),
           "slab_departure_time_s": departure_time(slab, free),
           "with_slab_peaks_pa": [g["peak_overpressure"] for g in slab["gauges"]],
           "runs": {"no_slab": free, "slab": slab}}
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    inc, refl = out["incident_gauge1_over_gauge0"], out["rigid_reflection_of_gauge1_incident"]
    print(f"no slab: gauge 1 / gauge 0 peak {inc['peak_ratio']:.3f}, impulse {inc['impulse_ratio']:.3f}, "
          f"peak {inc['peak_time_lag_s'] * 1e6:+.2f} us later")
    print(f"slab: gauge peaks {out['with_slab_peaks_pa'][0] / 1e6:.2f} / {out['with_slab_peaks_pa'][1] / 1e6:.2f} MPa; "
          f"gauge 1 leaves the no-slab history at {out['slab_departure_time_s'] * 1e6:.2f} us; rigid-wall "
          f"reflection of its incident state {refl['reflected_overpressure'] / 1e6:.1f} MPa")
    return 0


if __name__ == "__main__":
    sys.exit(main())
