"""Issue 34, deliverable 3: the load side verified on its own. Reflected overpressure and impulse over a rigid
plate from the ``euler`` method alone, for the geometries of seed 000 Table 1 case 1 (0.468 kg TNT) and case 4
(1.094 kg TNT), plate front face R = 0.1 m from the charge centre, against Kingery-Bulmash (normal incidence)
and the ConWep oblique-reflection blend (blastfsi.exact.oblique_reflection).

    python docs/figures/make_plate_load.py run DIR [--cases 1 4] [--cells 120 160 240 360]
    python docs/figures/make_plate_load.py figures DIR      # plate_load.json, plate_load.png here; tables on stdout
    python docs/figures/make_plate_load.py coupled DIR [--cases 1 4]  # the coupled solver's load; table on stdout
    python docs/figures/make_plate_load.py energy DIR   # the load against the explosive's energy; plate_load_energy.json

Set-up (r-z, ``domain.geometry = "axisymmetric"``): r in [0, 0.3] m (axis, flow-out at r = 0.3 m), z in
[-0.08, 0.1] m (flow-out behind the charge, the rigid plate = a ``wall`` at z = 0.1 m); the charge centre at
the origin; square cells dx = 0.3 m / cells (120, 160, 240, 360: 2.5, 1.875, 1.25, 0.833 mm); HLLC-MUSCL
(the default). The 1D detonation uses 100 zones across the charge radius and 1D air zones 2 h wide
(``air_ratio = 2``: 0.82 mm for case 1, 1.09 mm for case 4), the same on every grid, and is remapped at one
time per case (the automatic remap time of the coarsest grid, blast 3 cells short of the z = -0.08 m face),
so the grids differ only in the 2D solution. Gauges at every wall cell centre (every 2nd/4th on the finer grids: at most
100 gauges; z = 0.1 - dx/2, half a cell off the wall), histories every 1 us to 0.5 ms; field snapshots every 5 us (the products' mass fraction at
the wall) on the 1.25 mm grid only (the 2.5 mm run of case 1 has them every 5 us), removed after reading
(writing one costs ~1 s).

``coupled``: the same load from the ``cfdmp`` method, the shipped examples of the two cases (``steel-plate-blast``,
``steel-plate-blast-case4``: 2.5 mm cells, the plate in the MPM box, the gas in front of it as particles) with the
plate held at rest (one support over all of it but its back row of particles: a rigid plate of the same
shape, r < 0.28 m). The supports' reaction is the load's total impulse on the plate's faces (front and back; the
ambient pressure on the two cancels), and gauges half a cell in front of the face, at the cell centres nearest R_GAUGES, give the positive-phase impulse
there (from the gas particles); against the ``euler`` run of the same cells (``DIR/case<k>-c120.json`` of ``run``:
its wall cells' impulse, totalled over the same r < 0.28 m). Writes ``DIR/coupled-case<k>.json``.

``energy``: how the load grows with the energy the products carry (what afterburning could add at most): the
2.5 mm grid of ``run`` for each case with the explosive's JWL detonation energy E0 scaled by ENERGY_FACTORS
(``materials.tnt.E0``, which the 1D detonation and the grid's products both take; the automatic remap time of
each run). Writes ``DIR/energy-case<k>-x<factor>.json`` and ``plate_load_energy.json`` here (the axis impulse and
the total over the free span, and their ratios to factor 1); the table on stdout.

Per run (``DIR/<case>-c<cells>.json``): along the wall, per cell, the positive-phase impulse and the peak
overpressure (the solver's per-step blast maps), the impulse to 0.5 ms (history, trapezoid), the
products-weighted impulse (sum of dp Y dt over the snapshots, Y the products' mass fraction, against the same
sum with Y = 1: the products' share), and the net force on the free span r < 0.25 m against time.
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
JSON = HERE / "plate_load.json"
PNG = HERE / "plate_load.png"

CASES = {"1": 0.468, "4": 1.094}  # seed 000 Table 1: TNT mass [kg]
STANDOFF = 0.1  # plate front face from the charge centre [m]
R_MAX, Z_LO = 0.3, -0.08
A_FREE = 0.25  # free span radius [m]
T_END = 5.0e-4
SAMPLE = 1.0e-6
FIELD_EVERY = 1.0e-5
PRODUCTS_CELLS = (240,)  # grids with snapshots every FIELD_EVERY (the products' share); the others: t = 0 and end
R_GAUGES = (0.0, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.25)
CELLS = (120, 160, 240, 360)
ENERGY_FACTORS = {"1": (1.0, 1.2, 1.5), "4": (1.0, 1.2)}  # E0 / E0 of the library's TNT, per case
ENERGY_CELLS = 120
JSON_ENERGY = HERE / "plate_load_energy.json"


def scenario(mass: float, cells: int, remap_time: float | None, energy_factor: float = 1.0) -> dict:
    dx = R_MAX / cells
    rc = (np.arange(cells) + 0.5) * dx
    init = {"kind": "charge", "explosive": "tnt", "mass": mass, "center": [0.0, 0.0], "cells": 100,
            "air_ratio": 2.0}
    if remap_time is not None:
        init["remap_time"] = remap_time
    from blastfsi.materials import lookup

    materials = {} if energy_factor == 1.0 else {"tnt": {"E0": energy_factor * lookup("tnt").E0}}
    return {"method": "euler", "name": "plate-load", "materials": materials,
            "domain": {"geometry": "axisymmetric", "lower": [0.0, Z_LO], "upper": [R_MAX, STANDOFF]},
            "boundaries": {"x": ["axis", "outflow"], "y": ["outflow", "wall"]},
            "grid": {"cells": cells}, "initial": init, "time": {"end": T_END},
            "output": {"history_samples": int(round(T_END / SAMPLE)) + 1,
                       "fields": int(round(T_END / FIELD_EVERY)) + 1 if cells in PRODUCTS_CELLS else 2,
                       "plots": False,
                       "gauges": [[float(r), STANDOFF - 0.5 * dx] for r in rc[::_stride(cells)]]}}


def _stride(cells: int) -> int:
    """Every k-th wall cell carries a gauge (at most 100 gauges per run)."""
    return -(-cells // 100)


def _trapz(y, x, axis=-1):
    y = np.asarray(y)
    d = np.diff(x)
    s0 = [slice(None)] * y.ndim
    s1 = list(s0)
    s0[axis], s1[axis] = slice(1, None), slice(None, -1)
    shape = [1] * y.ndim
    shape[axis] = -1
    return np.sum(0.5 * (y[tuple(s0)] + y[tuple(s1)]) * d.reshape(shape), axis=axis)


def measure(case: str, cells: int, folder: Path, remap_time: float | None, energy_factor: float = 1.0) -> dict:
    import blastfsi

    mass = CASES[case]
    sc = scenario(mass, cells, remap_time, energy_factor)
    out = folder / (f"case{case}-c{cells}" + ("" if energy_factor == 1.0 else f"-x{energy_factor:g}"))
    started = time.perf_counter()
    res = blastfsi.run(sc, out=out, overwrite=out.exists())
    total = time.perf_counter() - started
    s = res.summary
    dx = R_MAX / cells
    rc = (np.arange(cells) + 0.5) * dx
    h = res.history
    t = np.asarray(h["time"])
    rg = rc[::_stride(cells)]
    p = np.stack([np.asarray(h[f"gauge{k}_overpressure"]) for k in range(len(rg))])  # (gauges, samples)
    p = np.stack([np.interp(rc, rg, p[:, j]) for j in range(p.shape[1])], axis=1)  # onto every wall cell
    cum = _trapz(p, t, axis=1)
    span = rc < A_FREE
    ring = 2.0 * np.pi * rc * dx
    force = np.sum(p[span] * ring[span, None], axis=0)
    # per-step maps: the last row of cells (z = 0.1 - dx/2), from the final snapshot
    snaps = sorted(tw for _, tw in res.snapshots)
    final = res.fields(time=snaps[-1])
    pos_imp = np.asarray(final["positive_impulse"])[:, -1]
    peak = np.asarray(final["peak_overpressure"])[:, -1]
    arrival = np.asarray(final["arrival_time"])[:, -1]
    # products' share: sum dp Y dt / sum dp dt over the snapshots (trapezoid), at the wall row
    dps, ys = [], []
    for tw in (snaps if len(snaps) > 2 else []):
        f = res.fields(time=tw)
        dps.append(np.asarray(f["pressure"])[:, -1])
        ys.append(np.asarray(f["products_fraction"])[:, -1])
    if dps:
        dps = np.asarray(dps) - float(sc_ambient_pressure())
        ys = np.asarray(ys)
        tsn = np.asarray(snaps)
        i_all = _trapz(dps.T, tsn, axis=1).tolist()
        i_prod = _trapz((dps * ys).T, tsn, axis=1).tolist()
        y_max = ys.max(axis=0).tolist()
    else:
        i_all = i_prod = y_max = None
    shutil.rmtree(out / "fields", ignore_errors=True)
    shutil.rmtree(out / "checkpoints", ignore_errors=True)
    return {"case": case, "mass": mass, "cells": cells, "dx": dx, "r": rc.tolist(),
            "remap_time": s["remap_time"], "steps": s["steps"], "loop_time": s["loop_time"],
            "compile_time": s["compile_time"], "run_wall_time": total,
            "positive_impulse": pos_imp.tolist(), "peak_overpressure": peak.tolist(),
            "arrival_time": (arrival + s["remap_time"]).tolist(),
            "impulse_to_end": cum.tolist(), "snapshot_impulse": i_all, "products_impulse": i_prod,
            "products_fraction_max": y_max, "field_snapshots": len(snaps),
            "time": (t + s["remap_time"]).tolist(), "force_free_span": force.tolist(),
            "mass_change_relative": s["mass_change_relative"]}


def sc_ambient_pressure() -> float:
    from blastfsi.materials import lookup

    return float(lookup("air").pressure)


def cmd_run(folder: Path, cases, cells_list) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for case in cases:
        remap = None
        for cells in sorted(cells_list):
            path = folder / f"case{case}-c{cells}.json"
            if path.exists():
                d = json.loads(path.read_text())
                remap = remap or d["remap_time"]
                print(f"case {case}, {cells} cells: kept ({path})", flush=True)
                continue
            started = time.perf_counter()
            d = measure(case, cells, folder, remap)
            remap = remap or d["remap_time"]
            path.write_text(json.dumps(d))
            print(f"case {case}, {cells} cells (dx {1e3 * d['dx']:.3f} mm): {d['steps']} steps, loop "
                  f"{d['loop_time']:.1f} s, total {time.perf_counter() - started:.1f} s; axis impulse "
                  f"{d['positive_impulse'][0]:.1f} Pa s, peak {d['peak_overpressure'][0] / 1e6:.1f} MPa",
                  flush=True)


def _at(rc, values, r):
    """Value at radius r by linear interpolation between cell centres (the axis: the first cell)."""
    return float(np.interp(r, rc, values))


def _span_total(rc, dx, values):
    rc = np.asarray(rc)
    span = rc < A_FREE
    return float(np.sum(np.asarray(values)[span] * 2.0 * np.pi * rc[span] * dx))


def cmd_figures(folder: Path) -> None:
    from blastfsi.exact import kingery_bulmash as kb
    from blastfsi.exact import oblique_reflection as obl

    runs = sorted((json.loads(p.read_text()) for p in folder.glob("case*-c*.json")),
                  key=lambda d: (d["case"], d["cells"]))
    out = {"standoff": STANDOFF, "free_span_radius": A_FREE, "r_gauges": list(R_GAUGES), "cases": {}}
    for case, mass in CASES.items():
        rr = [d for d in runs if d["case"] == case]
        if not rr:
            continue
        load = obl.plate_load(mass, STANDOFF, np.asarray(R_GAUGES))
        z0 = float(kb.scaled_distance(mass, STANDOFF))
        c = {"mass": mass, "scaled_distance": z0,
             "kb_validity": {q: kb.validity_range(q) for q in ("reflected_overpressure", "reflected_impulse",
                                                              "positive_phase_duration")},
             "conwep": {k: np.asarray(v).tolist() for k, v in load.items()},
             "conwep_total_impulse": obl.total_impulse(mass, STANDOFF, A_FREE), "grids": []}
        for d in rr:
            rc = np.asarray(d["r"])
            g = {"cells": d["cells"], "dx": d["dx"], "steps": d["steps"], "loop_time": d["loop_time"],
                 "run_wall_time": d["run_wall_time"], "remap_time": d["remap_time"]}
            for key in ("positive_impulse", "peak_overpressure", "impulse_to_end", "arrival_time"):
                g[key] = [_at(rc, d[key], r) for r in R_GAUGES]
            g["total_positive_impulse"] = _span_total(rc, d["dx"], d["positive_impulse"])
            g["total_impulse_to_end"] = _span_total(rc, d["dx"], d["impulse_to_end"])
            if d["products_impulse"] is not None:
                g["snapshot_interval"] = T_END / (d["field_snapshots"] - 1)
                g["total_products_impulse"] = _span_total(rc, d["dx"], d["products_impulse"])
                g["total_snapshot_impulse"] = _span_total(rc, d["dx"], d["snapshot_impulse"])
                g["products_share"] = g["total_products_impulse"] / g["total_snapshot_impulse"]
                g["products_share_r"] = [_at(rc, d["products_impulse"], r) / _at(rc, d["snapshot_impulse"], r)
                                         for r in R_GAUGES]
                g["products_fraction_max"] = [_at(rc, d["products_fraction_max"], r) for r in R_GAUGES]
            g["ratio_kb_axis_impulse"] = g["positive_impulse"][0] / load["reflected_impulse"][0]
            g["ratio_kb_axis_peak"] = g["peak_overpressure"][0] / load["reflected_overpressure"][0]
            g["ratio_conwep_total"] = g["total_positive_impulse"] / c["conwep_total_impulse"]
            g["force_time"] = d["time"][::5]
            g["force_free_span"] = d["force_free_span"][::5]
            g["profile_r"] = d["r"]
            g["profile_positive_impulse"] = d["positive_impulse"]
            g["profile_peak_overpressure"] = d["peak_overpressure"]
            c["grids"].append(g)
        # observed order of the axis impulse and of the total from the three finest grids (constant ratio 1.5)
        gs = [g for g in c["grids"] if g["cells"] in (160, 240, 360)]
        for key in ("axis_positive_impulse", "total_positive_impulse", "total_impulse_to_end"):
            if len(gs) == 3:
                vals = [g["positive_impulse"][0] if key == "axis_positive_impulse" else g[key] for g in gs]
                d1, d2 = vals[1] - vals[0], vals[2] - vals[1]
                ratio = 1.5
                entry = {"values": vals, "changes": [d1, d2]}
                if d1 * d2 > 0 and abs(d2) < abs(d1):
                    order = np.log(abs(d1 / d2)) / np.log(ratio)
                    entry.update(order=float(order),
                                 richardson=float(vals[2] + d2 / (ratio ** order - 1.0)))
                c.setdefault("convergence", {})[key] = entry
        out["cases"][case] = c
    JSON.write_text(json.dumps(out, indent=1))
    _tables(out)
    _figure(out)


def _tables(out) -> None:
    for case, c in out["cases"].items():
        cw = c["conwep"]
        print(f"\n### Case {case}: W = {c['mass']} kg TNT, R = {STANDOFF} m, Z = {c['scaled_distance']:.4f} m/kg^1/3")
        head = "| r [mm] | " + " | ".join(f"{1e3 * r:.0f}" for r in out["r_gauges"]) + " |"
        sep = "|---" * (len(out["r_gauges"]) + 1) + "|"
        print("\nPositive-phase reflected impulse [kPa·s]\n\n" + head + "\n" + sep)
        print("| KB / ConWep | " + " | ".join(f"{v / 1e3:.2f}" for v in cw["impulse"]) + " |")
        for g in c["grids"]:
            print(f"| dx {1e3 * g['dx']:.3f} mm | " + " | ".join(f"{v / 1e3:.2f}" for v in g["positive_impulse"]) + " |")
        print("\nImpulse to 0.5 ms after the detonation [kPa·s]\n\n" + head + "\n" + sep)
        for g in c["grids"]:
            print(f"| dx {1e3 * g['dx']:.3f} mm | " + " | ".join(f"{v / 1e3:.2f}" for v in g["impulse_to_end"]) + " |")
        print("\nPeak reflected overpressure [MPa]\n\n" + head + "\n" + sep)
        print("| KB / ConWep | " + " | ".join(f"{v / 1e6:.1f}" for v in cw["peak_overpressure"]) + " |")
        for g in c["grids"]:
            print(f"| dx {1e3 * g['dx']:.3f} mm | " + " | ".join(f"{v / 1e6:.1f}" for v in g["peak_overpressure"]) + " |")
        print("\n| dx [mm] | steps | loop [s] | J+ (r < 0.25 m) [N·s] | J to 0.5 ms [N·s] | axis I / KB | axis peak / KB | "
              "J+ / ConWep | products' share (span, axis) |\n|---|---|---|---|---|---|---|---|---|")
        for g in c["grids"]:
            print(f"| {1e3 * g['dx']:.3f} | {g['steps']} | {g['loop_time']:.0f} | {g['total_positive_impulse']:.0f} | "
                  f"{g['total_impulse_to_end']:.0f} | {g['ratio_kb_axis_impulse']:.3f} | {g['ratio_kb_axis_peak']:.3f} | "
                  f"{g['ratio_conwep_total']:.3f} | " + (f"{g['products_share']:.2f}, {g['products_share_r'][0]:.2f} |"
                                                        if "products_share" in g else "– |"))
        print(f"| KB / ConWep | | | {c['conwep_total_impulse']:.0f} | | 1 | 1 | 1 | |")
        for key, e in c.get("convergence", {}).items():
            print(f"\n{key}: values {[round(v, 1) for v in e['values']]}, changes {[round(v, 1) for v in e['changes']]}, "
                  f"order {e.get('order', float('nan')):.2f}, Richardson {e.get('richardson', float('nan')):.1f}")


def _figure(out) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(out["cases"].items())
    fig, axes = plt.subplots(2, len(cases), figsize=(6 * len(cases), 8), squeeze=False)
    for j, (case, c) in enumerate(cases):
        rfine = np.linspace(0.0, 0.3, 121)
        from blastfsi.exact import oblique_reflection as obl

        load = obl.plate_load(c["mass"], STANDOFF, rfine)
        ax_i, ax_p = axes[0, j], axes[1, j]
        for g in c["grids"]:
            r = 1e3 * np.asarray(g["profile_r"])
            lab = f"euler dx = {1e3 * g['dx']:.3g} mm"
            ax_i.plot(r, np.asarray(g["profile_positive_impulse"]) / 1e3, label=lab)
            ax_p.plot(r, np.asarray(g["profile_peak_overpressure"]) / 1e6, label=lab)
        ax_i.plot(1e3 * rfine, load["impulse"] / 1e3, "k--", label="KB + ConWep oblique (RPB 1997)")
        ax_p.plot(1e3 * rfine, load["peak_overpressure"] / 1e6, "k--", label="KB + ConWep oblique (RPB 1997)")
        ax_i.plot(1e3 * rfine, load["reflected_impulse"] / 1e3, "k:", label="KB normal reflection at slant range")
        ax_p.plot(1e3 * rfine, load["reflected_overpressure"] / 1e6, "k:", label="KB normal reflection at slant range")
        for ax in (ax_i, ax_p):
            ax.axvline(1e3 * A_FREE, color="0.6", lw=0.8)
            ax.set_xlabel("r [mm]")
            ax.grid(alpha=0.3)
        ax_i.set_ylabel("positive-phase reflected impulse [kPa s]")
        ax_p.set_ylabel("peak reflected overpressure [MPa]")
        ax_i.set_title(f"case {case}: {c['mass']} kg TNT, R = {STANDOFF} m (Z = {c['scaled_distance']:.3f})")
        ax_i.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(PNG, dpi=120)


COUPLED_EXAMPLES = {"1": "steel-plate-blast", "4": "steel-plate-blast-case4"}


def coupled_scenario(case: str, cells: int | None = None) -> dict:
    """The shipped example of ``case`` with its plate held at rest (rigid) and gauges half a cell in front of it;
    ``cells``: another grid than the example's (the cell must divide the plate's 10 mm)."""
    from blastfsi.api import example_data

    data = example_data(COUPLED_EXAMPLES[case])
    if cells is not None:
        data["grid"]["cells"] = cells
    plate = data["structures"][0]
    dx = (data["domain"]["upper"][0] - data["domain"]["lower"][0]) / data["grid"]["cells"]
    # (a body cannot be held whole: all of it but the back row of particles, which the rest holds elastically)
    plate["supports"] = [{"lower": list(plate["lower"]), "upper": [plate["upper"][0], plate["upper"][1] - 0.5 * dx]}]
    rc = [(np.floor(r / dx) + 0.5) * dx for r in R_GAUGES]  # the cell centre at or just beyond each radius
    data["output"].update(fields=0, plots=False, checkpoint_interval=None, tracers=[],
                          gauges=[[float(r), plate["lower"][1] - 0.5 * dx] for r in rc])
    return data


def cmd_coupled(folder: Path, cases, cells: int | None = None) -> None:
    import blastfsi
    from blastfsi.io.results import read_history

    for case in cases:
        label = f"coupled-case{case}" + ("" if cells is None else f"-c{cells}")
        path = folder / f"{label}.json"
        if not path.exists():
            data = coupled_scenario(case, cells)
            res = blastfsi.run(data, out=folder / f"{label}-run", overwrite=True)
            s, h = res.summary, read_history(folder / f"{label}-run" / "history.csv")
            path.write_text(json.dumps({
                "case": case, "gauge_r": [g["position"][0] for g in s["gauges"]],
                "positive_impulse": [g["impulse"] for g in s["gauges"]],
                "peak_overpressure": [g["peak_overpressure"] for g in s["gauges"]],
                "reaction_impulse": -float(np.asarray(h["reaction_impulse_y"])[-1]), "time_end": s["time"],
                "held_radius": data["structures"][0]["upper"][0], "steps": s["steps"], "cells": data["grid"]["cells"],
                "loop_time": s["loop_time"]}) + "\n")
        c = json.loads(path.read_text())
        grid = c.get("cells", 120)  # (the runs written before --cells: the examples' 120)
        euler_file = folder / f"case{case}-c{grid}.json"
        if not euler_file.exists():
            print(f"case {case}, {grid} cells: impulse on the held plate {c['reaction_impulse']:.1f} N s "
                  f"(coupled, to {c['time_end'] * 1e3:.2f} ms; no euler run of these cells in {folder}); {c['steps']} "
                  f"steps, loop {c['loop_time']:.0f} s")
            continue
        e = json.loads(euler_file.read_text())
        rc, dx = np.asarray(e["r"]), e["dx"]
        held = rc < c["held_radius"]
        total = float(np.sum(np.asarray(e["positive_impulse"])[held] * 2.0 * np.pi * rc[held] * dx))
        print(f"case {case}: impulse on the held plate (r < {c['held_radius']} m): coupled {c['reaction_impulse']:.1f} "
              f"N s (supports' reaction to {c['time_end'] * 1e3:.2f} ms), euler {total:.1f} N s (positive phase, "
              f"wall cells), ratio {c['reaction_impulse'] / total:.3f}; {c['steps']} steps, loop {c['loop_time']:.0f} s")
        print("| r [mm] | " + " | ".join(f"{1e3 * r:.1f}" for r in c["gauge_r"]) + " |")
        print("|---" * (len(c["gauge_r"]) + 1) + "|")
        euler = [_at(rc, e["positive_impulse"], r) for r in c["gauge_r"]]
        print("| euler [kPa s] | " + " | ".join(f"{v / 1e3:.2f}" for v in euler) + " |")
        print("| cfdmp [kPa s] | " + " | ".join(f"{v / 1e3:.2f}" for v in c["positive_impulse"]) + " |")
        print("| cfdmp / euler | " + " | ".join(f"{a / b:.3f}" for a, b in zip(c["positive_impulse"], euler)) + " |")


def cmd_energy(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    out = {"cells": ENERGY_CELLS, "dx": R_MAX / ENERGY_CELLS, "free_span_radius": A_FREE, "cases": {}}
    print("| case | E0 factor | axis impulse [kPa s] | / factor 1 | J (r < 0.25 m) [N s] | / factor 1 | remap [us] |")
    print("|---|---|---|---|---|---|---|")
    for case, factors in ENERGY_FACTORS.items():
        rows = []
        for factor in factors:
            path = folder / f"energy-case{case}-x{factor:g}.json"
            if not path.exists():
                d = measure(case, ENERGY_CELLS, folder, None, factor)
                path.write_text(json.dumps(d))
            d = json.loads(path.read_text())
            rows.append({"energy_factor": factor, "axis_impulse": d["positive_impulse"][0],
                         "span_impulse": _span_total(d["r"], d["dx"], d["positive_impulse"]),
                         "remap_time": d["remap_time"], "steps": d["steps"]})
        for row in rows:
            row["axis_ratio"] = row["axis_impulse"] / rows[0]["axis_impulse"]
            row["span_ratio"] = row["span_impulse"] / rows[0]["span_impulse"]
            print(f"| {case} | {row['energy_factor']:g} | {row['axis_impulse'] / 1e3:.2f} | {row['axis_ratio']:.3f} | "
                  f"{row['span_impulse']:.0f} | {row['span_ratio']:.3f} | {row['remap_time'] * 1e6:.2f} |")
        out["cases"][case] = {"mass": CASES[case], "runs": rows}
    JSON_ENERGY.write_text(json.dumps(out, indent=1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("dir", type=Path)
    r.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    r.add_argument("--cells", nargs="+", type=int, default=list(CELLS))
    f = sub.add_parser("figures")
    f.add_argument("dir", type=Path)
    c = sub.add_parser("coupled")
    c.add_argument("dir", type=Path)
    c.add_argument("--cases", nargs="+", default=list(COUPLED_EXAMPLES), choices=list(COUPLED_EXAMPLES))
    c.add_argument("--cells", type=int, default=None, help="another grid than the examples' 120 cells")
    e = sub.add_parser("energy")
    e.add_argument("dir", type=Path)
    a = ap.parse_args(argv)
    if a.cmd == "energy":
        cmd_energy(a.dir)
    elif a.cmd == "run":
        cmd_run(a.dir, a.cases, a.cells)
    elif a.cmd == "coupled":
        cmd_coupled(a.dir, a.cases, a.cells)
    else:
        cmd_figures(a.dir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
