"""Stand-off charges against the full domain: a rigid wall facing 10 kg of TNT at scaled distances
Z = 1, 2 and 5 m/kg^1/3 (2.15, 4.3 and 10.8 m), r-z, the charge on the axis.

For each Z two runs share one grid (cell size dx, radius W): the full-domain run holds the charge
(domain z from -B to the wall); the stand-off run holds only the L metres in front of the wall, its
lower z face a ``blast`` face fed by the 1D detonation. The gauge sits on the axis in the wall's
cell. Compared: the wall's reflected peak overpressure and positive impulse (stand-off / full, the
issue's 3 % check) and the reflected peak against Kingery-Bulmash normal reflection (10 %).
Both runs end at the KB arrival plus 1.2 KB positive-phase durations. W = D: a full-domain run whose
radius is short of the distance travels its blast down a tube of zero-gradient walls that keeps it too
strong (a radius of 2 m at Z = 5 read 2.5 x KB). The full-domain runs bound dx (2 to 6 cm here), too
coarse for the reflected peak, so the KB check (``--part kb``) also runs the stand-off alone on finer
grids in a narrow domain (radius and depth about D / 10: the axis gauge's peak comes before any relief
from the side or the blast face reaches it), to the KB arrival plus 0.2 positive phases.

    .venv/bin/python benchmarks/standoff_check.py [--part pairs kb] [--z 1 2 5] [--dx DX] [--out benchmarks/standoff_check.json]

``--dx``: the pairs' cell size instead of CASES' (a pair is kept per Z and cell size).

The JSON keeps the parts already there that this call does not run.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import blastfsi
from blastfsi.exact import kingery_bulmash as kb

MASS = 10.0  # kg TNT
# per Z: wall distance D [m], cell size dx [m], radius W [m], stand-off depth L [m], depth behind the charge B [m]
CASES = {1: (2.15, 0.02, 2.2, 1.2, 0.45), 2: (4.3, 0.04, 4.4, 2.0, 0.82), 5: (10.8, 0.06, 10.8, 3.0, 1.2)}


# per Z: the stand-off-only KB runs: cell sizes [m], radius W and depth L [m]
KB_CASES = {1: ((0.005, 0.0025), 0.3, 0.3), 2: ((0.01, 0.005), 0.5, 0.5), 5: ((0.02, 0.01), 1.0, 1.0)}


def scenario(z: int, standoff: bool, kb_dx: float | None = None, pair_dx: float | None = None) -> dict:
    D, dx, W, L, B = CASES[z]
    dx = pair_dx or dx
    t_end = kb.value("arrival_time", MASS, D) + 1.2 * kb.value("positive_phase_duration", MASS, D)
    if kb_dx is not None:
        dx, W, L = kb_dx, KB_CASES[z][1], KB_CASES[z][2]
        t_end = kb.value("arrival_time", MASS, D) + 0.2 * kb.value("positive_phase_duration", MASS, D)
    lower = D - L if standoff else -B
    return {"method": "euler", "name": f"standoff-z{z}-{'standoff' if standoff else 'full'}",
            "domain": {"geometry": "axisymmetric", "lower": [0.0, lower], "upper": [W, D]},
            "boundaries": {"x": ["axis", "outflow"], "y": ["blast" if standoff else "outflow", "wall"]},
            "grid": {"cells": round(W / dx)},
            "initial": {"kind": "charge", "mass": MASS, "center": [0.0, 0.0]},
            "time": {"end": float(t_end)},
            "output": {"history_samples": 200, "fields": 0, "plots": False, "gauges": [[0.0, D - 0.5 * dx]]}}


def one(z: int, standoff: bool, kb_dx: float | None = None, pair_dx: float | None = None) -> dict:
    started = time.perf_counter()
    res = blastfsi.run(scenario(z, standoff, kb_dx, pair_dx))
    g = res.summary["gauges"][0]
    return {"wall_s": time.perf_counter() - started, "cells": res.summary["cells"], "steps": res.summary["steps"],
            "remap_time": res.summary["remap_time"], "peak_overpressure": g["peak_overpressure"],
            "impulse": g["impulse"], "arrival_time": g["arrival_time"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", nargs="+", default=["pairs", "kb"], choices=["pairs", "kb"])
    ap.add_argument("--z", type=int, nargs="+", default=sorted(CASES), choices=sorted(CASES))
    ap.add_argument("--dx", type=float, help="cell size of the pairs [m] (default: CASES, per Z)")
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    saved = json.loads(args.out.read_text()) if args.out.exists() else {}
    out = {"machine": f"{platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
           "cases": saved.get("cases", []), "kb_refinement": saved.get("kb_refinement", []), "commands": []}
    out["commands"] = saved.get("commands", []) + [" ".join([Path(sys.executable).name, *sys.argv])]
    if "pairs" in args.part:
        new = pairs(args.z, args.dx)
        out["cases"] = [c for c in out["cases"] if (c["Z"], c["dx_m"]) not in {(n["Z"], n["dx_m"]) for n in new}] + new
    if "kb" in args.part:
        out["kb_refinement"] = [c for c in out["kb_refinement"] if c["Z"] not in args.z] + kb_refinement(args.z)
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    return 0


def kb_refinement(zs) -> list[dict]:
    rows = []
    for z in zs:
        D = CASES[z][0]
        ref = kb.value("reflected_overpressure", MASS, D)
        for dx in KB_CASES[z][0]:
            so = one(z, True, dx)
            rows.append({"Z": z, "distance_m": D, "dx_m": dx, "radius_m": KB_CASES[z][1], "depth_m": KB_CASES[z][2],
                         "standoff": so, "kb_reflected_peak": ref,
                         "peak_ratio_standoff_kb": so["peak_overpressure"] / ref})
            print(f"Z = {z}, stand-off only, dx = {dx} m: peak {so['peak_overpressure'] / 1e3:.1f} kPa, KB reflected "
                  f"{ref / 1e3:.1f} kPa (x{rows[-1]['peak_ratio_standoff_kb']:.3f}), wall time {so['wall_s']:.0f} s "
                  f"({so['cells']} cells)", flush=True)
    return rows


def pairs(zs, pair_dx: float | None = None) -> list[dict]:
    rows = []
    for z in zs:
        D, dx = CASES[z][0], pair_dx or CASES[z][1]
        full, so = one(z, False, pair_dx=pair_dx), one(z, True, pair_dx=pair_dx)
        ref = kb.value("reflected_overpressure", MASS, D)
        row = {"Z": z, "distance_m": D, "dx_m": dx, "full": full, "standoff": so, "kb_reflected_peak": ref,
               "kb_reflected_impulse": kb.value("reflected_impulse", MASS, D),
               "peak_ratio_standoff_full": so["peak_overpressure"] / full["peak_overpressure"],
               "impulse_ratio_standoff_full": so["impulse"] / full["impulse"],
               "peak_ratio_standoff_kb": so["peak_overpressure"] / ref,
               "peak_ratio_full_kb": full["peak_overpressure"] / ref}
        rows.append(row)
        print(f"Z = {z}: D = {D} m, dx = {dx} m | peak full {full['peak_overpressure'] / 1e3:.1f} kPa, stand-off "
              f"{so['peak_overpressure'] / 1e3:.1f} kPa (x{row['peak_ratio_standoff_full']:.4f}), KB reflected "
              f"{ref / 1e3:.1f} kPa (stand-off x{row['peak_ratio_standoff_kb']:.3f}) | impulse full "
              f"{full['impulse']:.1f}, stand-off {so['impulse']:.1f} Pa s (x{row['impulse_ratio_standoff_full']:.4f})"
              f" | wall time full {full['wall_s']:.0f} s ({full['cells']} cells), stand-off {so['wall_s']:.0f} s "
              f"({so['cells']} cells)", flush=True)
    return rows


if __name__ == "__main__":
    raise SystemExit(main())
