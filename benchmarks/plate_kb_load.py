"""Issue 34: the clamped plate of steel-plate-blast under the ConWep-distributed impulse of case 1, r-z against 3D.

The structural study of docs/validation.md checks the plate under a UNIFORM impulse only; the blast load of
case 1 is concentrated on the axis (the reflected impulse falls ~25x from r = 0 to r = 0.25 m). This script
gives the plate, as an initial velocity v_z(r) = I(r) / (rho t), the oblique-reflection (ConWep) impulse
distribution of W kg TNT at R = 0.1 m (blastfsi.exact.oblique_reflection) times a factor, and measures the
centre's peak deflection in r-z and in a 3D quarter model with the same cells, so that an axis defect of
the r-z treatment under a concentrated load (Cartesian GIMP weights, the hoop rate on the innermost column)
would show.

    python benchmarks/plate_kb_load.py rz 4 [--mass 1.094] [--factor 1.0] [--clamp sliding] [--end 5.5e-4]
    python benchmarks/plate_kb_load.py 3d 2
    python benchmarks/plate_kb_load.py all       # the set below, into benchmarks/plate_kb_load.json (~2 min)

Prints one JSON line per run (peak delta/t, its time, steps, wall time). ``all``: r-z with 4 cells across t
(the shipped resolution) for case 1 (0.468 kg) and case 4 (1.094 kg), clamp fixed and sliding, to 1.2 ms (the
sliding plate peaks at ~0.7 ms), the fixed clamp also perfectly plastic (flow stress A, no hardening or rate
effect: the material of the rigid-plastic references); r-z against a 3D quarter model with 2 cells across t,
case 1, fixed; and the rigid-plastic membrane mode solution of the same plate under the same load.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "figures"))
import make_plate_structural as mps  # noqa: E402  (the shipped plate study's scenarios)

import blastfsi  # noqa: E402
from blastfsi.exact.oblique_reflection import plate_load  # noqa: E402
from blastfsi.materials import lookup  # noqa: E402
from blastfsi.mpm import method as mpm_method  # noqa: E402

STANDOFF = 0.1  # m, case 1 and case 4


def main(kind: str, cells_per_t: int, factor: float = 1.0, mass: float = 0.468, t_end: float = 5.5e-4,
         clamp: str = "fixed", perfectly_plastic: bool = False) -> dict:
    rho = lookup("steel-rha").density
    build = mpm_method.MPM.build
    delivered = {}

    def loaded(self, sc):  # the shipped builder, then v_z(r) = factor I(r) / (rho t) on the free span
        setup = build(self, sc)
        P = setup.particles
        x = np.asarray(P.x)
        r = x[:, 0] if kind == "rz" else np.hypot(x[:, 0], x[:, 1])
        vz = np.zeros(len(r))
        free = (r < mps.A_FREE) & np.asarray(P.active) & ~np.any(np.asarray(P.prescribed), axis=1)
        vz[free] = factor * plate_load(mass, STANDOFF, r[free])["impulse"] / (rho * mps.T)
        v = np.array(P.v)
        v[:, 1 if kind == "rz" else 2] = vz
        delivered["impulse_Ns"] = float(np.sum(np.asarray(P.mass) * vz)) * (1.0 if kind == "rz" else 4.0)
        return dataclasses.replace(setup, particles=P._replace(v=v.astype(np.asarray(P.v).dtype)))

    sc = (mps.scenario_rz if kind == "rz" else mps.scenario_3d)(0.0, cells_per_t, 2, t_end)
    if clamp == "sliding":  # the rim held only along the plate's normal (docs/validation.md, the clamp)
        for body in sc["bodies"]:
            for support in body["supports"]:
                support["hold"] = ["y" if kind == "rz" else "z"]
    if perfectly_plastic:  # flow stress A: no hardening, no rate effect (the rigid-plastic references' sigma0)
        sc.setdefault("materials", {})["steel-rha"] = {"B": 0.0, "C": 0.0}
    started = time.perf_counter()
    mpm_method.MPM.build = loaded
    try:
        res = blastfsi.run(sc)
    finally:
        mpm_method.MPM.build = build
    t = np.asarray(res.history["time"])
    w = np.asarray(res.history["tracer0_displacement_z"])
    k = int(np.argmax(w))
    out = {"kind": kind, "cells_across_t": cells_per_t, "factor": factor, "mass": mass, "clamp": clamp,
           "perfectly_plastic": perfectly_plastic,
           "delivered_impulse_Ns": delivered["impulse_Ns"],
           "peak_delta_over_t": float(w[k] / mps.T), "t_peak": float(t[k]), "steps": int(res.summary["steps"]),
           "particles": int(res.summary["particles"]), "total_s": time.perf_counter() - started,
           "energy_balance_relative": res.summary["energy_balance_relative"]}
    print(json.dumps(out), flush=True)
    return out


def membrane_references() -> dict:
    """The rigid-plastic membrane mode solution (blastfsi.exact.rigid_plastic_plate, Symonds & Wierzbicki) of the
    same plate (flow stress = Johnson-Cook A) under the same ConWep impulse: the centre's delta/t and its time."""
    plate = mps.plate()
    out = {}
    for case, mass in (("case1", 0.468), ("case4", 1.094)):
        ratio, t = plate.membrane_mode(lambda r, m=mass: plate_load(m, STANDOFF, r)["impulse"])
        out[case] = {"mass": mass, "delta_over_t": ratio, "t": t}
    return out


def run_all() -> None:
    import platform

    runs = {}
    for case, mass in (("case1", 0.468), ("case4", 1.094)):
        for clamp in ("fixed", "sliding"):
            runs[f"rz-c4-{case}-{clamp}"] = main("rz", 4, 1.0, mass, 1.2e-3, clamp)
        runs[f"rz-c4-{case}-fixed-perfectly-plastic"] = main("rz", 4, 1.0, mass, 1.2e-3, "fixed", True)
    runs["rz-c2-case1-fixed"] = main("rz", 2, 1.0, 0.468, 5.5e-4, "fixed")
    runs["3d-c2-case1-fixed"] = main("3d", 2, 1.0, 0.468, 5.5e-4, "fixed")
    out = {"machine": f"{platform.machine()}, {os.cpu_count()} CPUs", "standoff_m": STANDOFF,
           "load": "ConWep oblique-reflection impulse I(r) as the initial velocity I(r) / (rho t) of the free span",
           "runs": runs, "membrane_mode": membrane_references()}
    (Path(__file__).parent / "plate_kb_load.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    import argparse

    if sys.argv[1:] == ["all"]:
        run_all()
        sys.exit(0)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=["rz", "3d"])
    ap.add_argument("cells_per_t", type=int)
    ap.add_argument("--factor", type=float, default=1.0, help="multiplies the ConWep impulse")
    ap.add_argument("--mass", type=float, default=0.468, help="kg TNT (case 1: 0.468, case 4: 1.094)")
    ap.add_argument("--end", type=float, default=5.5e-4, help="end time [s]")
    ap.add_argument("--clamp", choices=["fixed", "sliding"], default="fixed")
    a = ap.parse_args()
    main(a.kind, a.cells_per_t, a.factor, a.mass, a.end, a.clamp)
