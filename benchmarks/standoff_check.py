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

    .venv/bin/python benchmarks/standoff_check.py [--part pairs kb incident oned sph startup] [--z 1 2 5] [--dx DX]
        [--out benchmarks/standoff_check.json]

``--dx``: the pairs' cell size instead of CASES' (a pair is kept per Z and cell size).

What the wall gauge's peak measures, and the waves the pair carries (parts ``startup``, ``sph``,
``incident``, ``oned``):

``startup``: a planar step shock of overpressure p_s onto a rigid wall, 1D Cartesian euler. The exact
wall pressure is the normal reflection p_r = C_R p_s, C_R = 2 (7 p0 + 4 p_s) / (7 p0 + p_s) for
gamma = 1.4 (:func:`blastfsi.exact.shock.reflection_coefficient`); the wall cell's recorded peak is its
largest cell-average pressure over the steps, which holds the start-up error of the reflection (the
reflected shock forms inside the wall cell, which fills with incoming gas whose kinetic energy its
average turns into internal energy until the shock leaves it). The transient lasts a few reflected-shock
cell crossings, a time proportional to dx, so refinement shortens it without shrinking it: where its
relative size (peak / C_R p_s - 1, per scheme and p_s) does not fall with the cell count, the recorded
peak of a decaying blast tends, as dx -> 0, to that multiple of C_R p_s rather than to C_R p_s.

``sph``: the pair in 1D spherical euler (the same scheme, no second dimension): the full-domain run
remapped when its blast reaches radius B (the depth behind the charge of the r-z pair), the stand-off
fed through its lower face; the gauge in the cell at D (outer face a wall: the reflected peak; outflow:
the incident one), over a sequence of cell sizes.

``incident``: the r-z pair with the wall replaced by an outflow face: the incident peak and impulse at
the wall's cell on the axis, and the normal reflection C_R p_s of each incident peak.

``oned``: the incident peak at D of the 1D detonation (lagrangian1d, the solver that feeds the blast
face) against its own zoning, its normal reflection, and KB incident and reflected values.

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
from blastfsi.detonation.charge import one_d_scenario
from blastfsi.exact import kingery_bulmash as kb
from blastfsi.exact import shock
from blastfsi.lagrangian1d.charge_problem import charge_radius
from blastfsi.materials.gases import GASES

AIR = GASES["air"]
AIR_1D = {"gamma": AIR.gamma, "pressure": AIR.pressure, "density": AIR.density}  # the 1D detonation's air

MASS = 10.0  # kg TNT
# per Z: wall distance D [m], cell size dx [m], radius W [m], stand-off depth L [m], depth behind the charge B [m]
CASES = {1: (2.15, 0.02, 2.2, 1.2, 0.45), 2: (4.3, 0.04, 4.4, 2.0, 0.82), 5: (10.8, 0.06, 10.8, 3.0, 1.2)}


# per Z: the stand-off-only KB runs: cell sizes [m], radius W and depth L [m]
KB_CASES = {1: ((0.005, 0.0025), 0.3, 0.3), 2: ((0.01, 0.005), 0.5, 0.5), 5: ((0.02, 0.01), 1.0, 1.0)}
# per Z: the cell sizes [m] of the 1D spherical pairs (part sph) and the 1D zonings (zones across the charge
# radius, air zone / charge zone) of the 1D detonation (part oned)
SPH_DX = {1: (0.02, 0.01, 0.005, 0.0025), 2: (0.04, 0.02, 0.01, 0.005), 5: (0.06, 0.03, 0.015)}
ONED_ZONING = {1: ((100, 10.0), (200, 5.0), (400, 5.0)), 2: ((100, 10.0), (200, 5.0)), 5: ((100, 10.0),)}
# part startup: step-shock overpressures [Pa] (about the incident peaks at Z = 1, 2, 5), cells over 1 m
STARTUP_PS = (0.96e6, 0.2e6, 0.05e6)
STARTUP_CELLS = (100, 400)
STARTUP_SCHEMES = ("hllc-muscl", "hllc-hancock", "lax-wendroff")


def reflected(ps: float) -> float:
    """Normal reflection C_R p_s of an incident overpressure p_s in ideal air (gamma, p0 of the library air)."""
    return float(shock.reflection_coefficient(ps, AIR.pressure, AIR.gamma) * ps)


def scenario(z: int, standoff: bool, kb_dx: float | None = None, pair_dx: float | None = None,
             upper: str = "wall") -> dict:
    D, dx, W, L, B = CASES[z]
    dx = pair_dx or dx
    t_end = kb.value("arrival_time", MASS, D) + 1.2 * kb.value("positive_phase_duration", MASS, D)
    if kb_dx is not None:
        dx, W, L = kb_dx, KB_CASES[z][1], KB_CASES[z][2]
        t_end = kb.value("arrival_time", MASS, D) + 0.2 * kb.value("positive_phase_duration", MASS, D)
    lower = D - L if standoff else -B
    return {"method": "euler", "name": f"standoff-z{z}-{'standoff' if standoff else 'full'}",
            "domain": {"geometry": "axisymmetric", "lower": [0.0, lower], "upper": [W, D]},
            "boundaries": {"x": ["axis", "outflow"], "y": ["blast" if standoff else "outflow", upper]},
            "grid": {"cells": round(W / dx)},
            "initial": {"kind": "charge", "mass": MASS, "center": [0.0, 0.0]},
            "time": {"end": float(t_end)},
            "output": {"history_samples": 200, "fields": 0, "plots": False, "gauges": [[0.0, D - 0.5 * dx]]}}


def one(z: int, standoff: bool, kb_dx: float | None = None, pair_dx: float | None = None,
        upper: str = "wall") -> dict:
    started = time.perf_counter()
    res = blastfsi.run(scenario(z, standoff, kb_dx, pair_dx, upper))
    g = res.summary["gauges"][0]
    return {"wall_s": time.perf_counter() - started, "cells": res.summary["cells"], "steps": res.summary["steps"],
            "remap_time": res.summary["remap_time"], "peak_overpressure": g["peak_overpressure"],
            "impulse": g["impulse"], "arrival_time": g["arrival_time"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", nargs="+", default=["pairs", "kb"], choices=list(PARTS))
    ap.add_argument("--z", type=int, nargs="+", default=sorted(CASES), choices=sorted(CASES))
    ap.add_argument("--dx", type=float, help="cell size of the pairs [m] (default: CASES, per Z)")
    ap.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = ap.parse_args(argv)
    saved = json.loads(args.out.read_text()) if args.out.exists() else {}
    out = {"machine": f"{platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
           "cases": saved.get("cases", []), "kb_refinement": saved.get("kb_refinement", []), "commands": []}
    out.update({key: saved.get(key, []) for key in PARTS.values() if key not in out})
    out["commands"] = saved.get("commands", []) + [" ".join([Path(sys.executable).name, *sys.argv])]
    if "pairs" in args.part:
        new = pairs(args.z, args.dx)
        out["cases"] = [c for c in out["cases"] if (c["Z"], c["dx_m"]) not in {(n["Z"], n["dx_m"]) for n in new}] + new
    if "kb" in args.part:
        out["kb_refinement"] = [c for c in out["kb_refinement"] if c["Z"] not in args.z] + kb_refinement(args.z)
    if "incident" in args.part:
        new = incident(args.z, args.dx)
        kept = {(n["Z"], n["dx_m"]) for n in new}
        out["incident"] = [c for c in out["incident"] if (c["Z"], c["dx_m"]) not in kept] + new
    if "oned" in args.part:
        out["oned"] = [c for c in out["oned"] if c["Z"] not in args.z] + oned(args.z)
    if "sph" in args.part:
        out["sph"] = [c for c in out["sph"] if c["Z"] not in args.z] + sph(args.z)
    if "startup" in args.part:
        out["startup"] = startup()
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


def incident(zs, pair_dx: float | None = None) -> list[dict]:
    """The r-z pair with an outflow face for the wall: the incident wave at the wall's cell on the axis."""
    rows = []
    for z in zs:
        D, dx = CASES[z][0], pair_dx or CASES[z][1]
        full, so = one(z, False, pair_dx=pair_dx, upper="outflow"), one(z, True, pair_dx=pair_dx, upper="outflow")
        row = {"Z": z, "distance_m": D, "dx_m": dx, "full": full, "standoff": so,
               "kb_incident_peak": kb.value("incident_overpressure", MASS, D),
               "peak_ratio_standoff_full": so["peak_overpressure"] / full["peak_overpressure"],
               "impulse_ratio_standoff_full": so["impulse"] / full["impulse"],
               "reflection_of_full_peak": reflected(full["peak_overpressure"]),
               "reflection_of_standoff_peak": reflected(so["peak_overpressure"])}
        rows.append(row)
        print(f"Z = {z}, dx = {dx} m, incident (outflow face for the wall): peak full "
              f"{full['peak_overpressure'] / 1e3:.1f} kPa, stand-off {so['peak_overpressure'] / 1e3:.1f} kPa "
              f"(x{row['peak_ratio_standoff_full']:.4f}); impulse x{row['impulse_ratio_standoff_full']:.4f}; their "
              f"normal reflections {row['reflection_of_full_peak'] / 1e3:.1f}, "
              f"{row['reflection_of_standoff_peak'] / 1e3:.1f} kPa", flush=True)
    return rows


def oned(zs) -> list[dict]:
    """The 1D detonation's incident peak at D against its own zoning (ONED_ZONING), to the pairs' end time."""
    gas, radius = AIR_1D, charge_radius(MASS, GASES["tnt"].density, 2)
    rows = []
    for z in zs:
        D = CASES[z][0]
        t_end = kb.value("arrival_time", MASS, D) + 0.5 * kb.value("positive_phase_duration", MASS, D)
        for cells, ratio in ONED_ZONING[z]:
            started = time.perf_counter()
            g = blastfsi.run(one_d_scenario("tnt", radius, cells, ratio, 1.6 * D + 10.0 * radius, t_end, gas,
                                            [D])).summary["gauges"][0]
            row = {"Z": z, "distance_m": D, "zones_across_charge": cells, "air_zone_m": ratio * radius / cells,
                   "peak_overpressure": g["peak_overpressure"], "impulse": g["impulse"],
                   "arrival_time": g["arrival_time"], "reflection_of_peak": reflected(g["peak_overpressure"]),
                   "kb_incident_peak": kb.value("incident_overpressure", MASS, D),
                   "kb_reflected_peak": kb.value("reflected_overpressure", MASS, D),
                   "wall_s": time.perf_counter() - started}
            row["peak_ratio_kb_incident"] = row["peak_overpressure"] / row["kb_incident_peak"]
            row["reflection_ratio_kb_reflected"] = row["reflection_of_peak"] / row["kb_reflected_peak"]
            rows.append(row)
            print(f"Z = {z}, 1D detonation, air zones {1e3 * row['air_zone_m']:.2f} mm: incident peak at {D} m "
                  f"{g['peak_overpressure'] / 1e3:.1f} kPa (x{row['peak_ratio_kb_incident']:.3f} KB incident), its "
                  f"normal reflection {row['reflection_of_peak'] / 1e3:.1f} kPa "
                  f"(x{row['reflection_ratio_kb_reflected']:.3f} KB reflected)", flush=True)
    return rows


def sph(zs) -> list[dict]:
    """The pair in 1D spherical euler (module docstring), outer face a wall and an outflow face."""
    gas, radius = AIR_1D, charge_radius(MASS, GASES["tnt"].density, 2)
    rows = []
    for z in zs:
        D, _, _, L, B = CASES[z]
        t_end = float(kb.value("arrival_time", MASS, D) + 1.2 * kb.value("positive_phase_duration", MASS, D))
        probe = blastfsi.run(one_d_scenario("tnt", radius, 100, 10.0, 1.5 * B + 10.0 * radius,
                                            1.5 * kb.value("arrival_time", MASS, B), gas, [B]))
        t_remap = probe.summary["gauges"][0]["arrival_time"]  # the full run's remap: the blast at radius B
        for dx in SPH_DX[z]:
            row = {"Z": z, "distance_m": D, "dx_m": dx, "full_remap_time": t_remap}
            for upper in ("wall", "outflow"):
                for kind in ("full", "standoff"):
                    lower = D - L if kind == "standoff" else 0.0
                    init = {"kind": "charge", "mass": MASS, "center": [0.0]}
                    if kind == "full":
                        init["remap_time"] = t_remap
                    data = {"method": "euler", "name": f"standoff-sph-z{z}-{kind}",
                            "domain": {"geometry": "spherical", "lower": [lower], "upper": [D]},
                            "boundaries": {"x": ["blast" if kind == "standoff" else "axis", upper]},
                            "grid": {"cells": round((D - lower) / dx)}, "initial": init, "time": {"end": t_end},
                            "output": {"history_samples": 2, "fields": 0, "plots": False, "gauges": [D - 0.5 * dx]}}
                    g = blastfsi.run(data).summary["gauges"][0]
                    row[f"{kind}_{upper}"] = {"peak_overpressure": g["peak_overpressure"], "impulse": g["impulse"]}
                row[f"peak_ratio_standoff_full_{upper}"] = (row[f"standoff_{upper}"]["peak_overpressure"]
                                                           / row[f"full_{upper}"]["peak_overpressure"])
            rows.append(row)
            print(f"Z = {z}, 1D spherical, dx = {dx} m: reflected peak full "
                  f"{row['full_wall']['peak_overpressure'] / 1e3:.1f}, stand-off "
                  f"{row['standoff_wall']['peak_overpressure'] / 1e3:.1f} kPa "
                  f"(x{row['peak_ratio_standoff_full_wall']:.4f}); incident full "
                  f"{row['full_outflow']['peak_overpressure'] / 1e3:.1f}, stand-off "
                  f"{row['standoff_outflow']['peak_overpressure'] / 1e3:.1f} kPa "
                  f"(x{row['peak_ratio_standoff_full_outflow']:.4f})", flush=True)
    return rows


def startup() -> list[dict]:
    """Planar step shocks onto a wall (module docstring): the wall cell's recorded peak against C_R p_s."""
    p0, rho0 = AIR.pressure, AIR.density
    rows = []
    for scheme in STARTUP_SCHEMES:
        for ps in STARTUP_PS:
            s = shock.incident_shock(ps, p0, rho0, AIR.gamma)
            for n in STARTUP_CELLS:
                data = {"method": "euler", "name": "standoff-startup", "domain": {"lower": [0.0], "upper": [1.0]},
                        "boundaries": {"x": ["outflow", "wall"]}, "grid": {"cells": n},
                        "numerics": {"scheme": scheme},
                        "initial": {"kind": "riemann", "diaphragm": 0.5,
                                    "left": {"density": float(s.density), "pressure": p0 + ps,
                                             "velocity": float(s.particle_velocity)},
                                    "right": {"density": rho0, "pressure": p0}},
                        "time": {"end": float(0.6 / s.shock_speed)},  # the reflected shock stays in the domain
                        "output": {"history_samples": 2, "fields": 0, "plots": False, "gauges": [1.0 - 0.5 / n]}}
                res = blastfsi.run(data)
                peak = res.summary["gauges"][0]["peak_overpressure"]
                last = float(res.history["gauge0_overpressure"][-1])
                rows.append({"scheme": scheme, "incident_overpressure": ps, "cells": n,
                             "exact_reflected": reflected(ps),
                             "peak_ratio": peak / reflected(ps), "final_ratio": last / reflected(ps)})
                print(f"{scheme}, p_s = {ps / 1e3:.0f} kPa, {n} cells: wall-cell peak x{rows[-1]['peak_ratio']:.4f} "
                      f"C_R p_s, wall pressure at the end x{rows[-1]['final_ratio']:.4f}", flush=True)
    return rows


PARTS = {"pairs": "cases", "kb": "kb_refinement", "incident": "incident", "oned": "oned", "sph": "sph",
         "startup": "startup"}


if __name__ == "__main__":
    raise SystemExit(main())
