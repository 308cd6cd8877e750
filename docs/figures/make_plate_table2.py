"""Table 2 of the CFDMP paper (Sec. 5.4): the six clamped RHA plates of Neuberger, Peles & Rittel (2007), run
as shipped (``steel-plate-blast``, ``steel-plate-blast-case2`` ... ``-case6``) with the two idealisations of
the test rig's clamp:

* ``fixed``: the plate's rim (r > D/2, under the clamping plates) held at rest, as shipped;
* ``sliding``: the rim held only along the plate's normal (``supports.hold = ["y"]``): the two thick clamping
  plates hold its faces and it pulls in without friction;
* ``sliding-wide``: as ``sliding`` with the rim widened from 0.12 to 0.2 of the free radius (the plate to the
  edge of the MPM box): how much the rim's hoop compression, which resists the pull-in, matters;
* ``fixed-recess``: as ``fixed``, with the rig's front clamping plate in front of the rim: a steel ring over
  r >= D/2 (to the edge of the MPM box), ``--recess`` deep, held at rest except its innermost column of cells,
  so the plate lies at the bottom of a recess whose wall reflects the radial flow along the plate (the flow's
  confinement by the rig). The MPM box's lower face moves so that BRIDGE_ROOM cells of gas lie in front of the
  ring (``--box-lower`` moves it for any clamp, for a baseline with the same box).

    python docs/figures/make_plate_table2.py run DIR [--cases 1 4] [--clamps fixed sliding] [--cells N] [--end T]
        [--recess DEPTH] [--box-lower Z] [--set KEY=VALUE ...]
    python docs/figures/make_plate_table2.py figures DIR    # plate_table2.json, plate_table2.png here; table
    python docs/figures/make_plate_table2.py faces RESULTS  # plate_faces.json: the gas on the plate's two faces

``faces`` reads the particle snapshots of a run written with its fields (``blastfsi run --example
steel-plate-blast --out RESULTS``): at each snapshot, the overpressure of the gas particles within one cell of the
plate's front and back faces, averaged per 5 mm ring of the free span and integrated over it (the net gas force on
each face), and the density and overpressure of the back face's first layer near the axis (r < 50 mm).

Each run is its own process (``one``) and writes ``DIR/case<k>-<clamp>[-c<cells>].json``: the centre's
deflection history (the tracer at mid-thickness on the axis), its peak and when, the last value, the steps, the
loop time and the mass/energy budget residuals. ``--cells`` overrides the grid (the three-grid study of case 1:
90, 120, 180 cells = 3.33, 2.5, 1.67 mm; the cell must divide 10 mm, which the plate's faces, its clamp and the
MPM box's lower face are multiples of). ``--set`` overrides scenario keys as ``blastfsi run --set`` does (e.g.
``numerics.gas_pic_fraction=0``: pure FLIP gas particles); the runs' names end with them. ``run`` skips runs whose
JSON exists.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
JSON = HERE / "plate_table2.json"
PNG = HERE / "plate_table2.png"
FACES_JSON = HERE / "plate_faces.json"

CLAMPS = ("fixed", "sliding", "sliding-wide", "fixed-recess")
BRIDGE_ROOM = 10  # cells of gas between the MPM box's lower face and the recess ring (the bridge needs 9: w + 4)
EXAMPLES = {"1": "steel-plate-blast", **{k: f"steel-plate-blast-case{k}" for k in "23456"}}
THICKNESS = {"1": 0.01, "2": 0.02, "3": 0.04, "4": 0.01, "5": 0.02, "6": 0.04}  # t [m], Table 1
# Table 2, delta / t: experiment (Neuberger et al. 2007), the paper's CFDMP, LS-DYNA (None: not given)
TABLE2 = {"1": (2.60, 2.69, 2.59), "2": (2.70, 2.71, 2.62), "3": (None, 2.68, None),
          "4": (4.85, 5.2, 4.98), "5": (5.35, 5.45, 5.24), "6": (None, 5.625, None)}


def scenario(case: str, clamp: str, cells: int | None, end: float | None = None, recess: float = 0.025,
             box_lower: float | None = None) -> dict:
    from blastfsi.api import example_data

    data = example_data(EXAMPLES[case])
    if box_lower is not None:
        data["mpm_region"]["lower"][1] = box_lower
    if clamp == "fixed-recess":
        plate = data["structures"][0]
        front, rim, edge = plate["lower"][1], plate["supports"][0]["lower"][0], data["mpm_region"]["upper"][0]
        dx = (data["domain"]["upper"][0] - data["domain"]["lower"][0]) / (cells or data["grid"]["cells"])
        data["mpm_region"]["lower"][1] = min(data["mpm_region"]["lower"][1], front - recess - BRIDGE_ROOM * dx)
        data["structures"].append({"lower": [rim, front - recess], "upper": [edge, front], "material": plate["material"],
                                   "supports": [{"lower": [rim + dx, front - recess], "upper": [edge, front]}]})
    if clamp.startswith("sliding"):
        for s in data["structures"]:
            s["supports"] = [{**sup, "hold": ["y"]} for sup in s.get("supports", [])]
    if clamp == "sliding-wide":
        edge = data["mpm_region"]["upper"][0]
        for s in data["structures"]:
            s["upper"][0] = edge
            for sup in s["supports"]:
                sup["upper"][0] = edge
    if cells is not None:
        data["grid"]["cells"] = cells
    if end is not None:
        data["time"]["end"] = end
    data["output"]["plots"] = False
    data["output"]["fields"] = 0
    data["output"]["checkpoint_interval"] = None
    return data


def name(case: str, clamp: str, cells: int | None, end: float | None = None, recess: float = 0.025,
         box_lower: float | None = None, overrides: tuple = ()) -> str:
    return (f"case{case}-{clamp}" + (f"{round(recess * 1e3)}mm" if clamp == "fixed-recess" else "")
            + ("" if cells is None else f"-c{cells}") + ("" if end is None else f"-e{round(end * 1e6)}us")
            + ("" if box_lower is None else f"-box{round(box_lower * 1e3)}mm")
            + "".join(f"-{item.split('.')[-1].replace('=', '')}" for item in overrides))


def cmd_one(case: str, clamp: str, cells: int | None, folder: Path, end: float | None = None, recess: float = 0.025,
            box_lower: float | None = None, overrides: tuple = ()) -> None:
    """One run, written into DIR/<name>-run (so that a run stopped by a fault keeps its history: the JSON then
    holds the history to the fault and the reason, ``stopped``), summarised in DIR/<name>.json."""
    import blastfsi
    from blastfsi.io.results import read_history
    from blastfsi.scenario import apply_overrides
    from blastfsi.simulation import SimulationError

    label = name(case, clamp, cells, end, recess, box_lower, overrides)
    out_dir = folder / f"{label}-run"
    stopped = None
    try:
        data = apply_overrides(scenario(case, clamp, cells, end, recess, box_lower), list(overrides))
        s = blastfsi.run(data, out=out_dir, overwrite=True).summary
    except SimulationError as err:
        stopped, s = str(err), None
    h = read_history(out_dir / "history.csv")
    t = np.asarray(h["time"])
    w = np.asarray(h["tracer0_displacement_y"])
    k = int(np.argmax(w))
    out = {"case": case, "clamp": clamp, "cells": cells, "thickness": THICKNESS[case],
           "recess": recess if clamp == "fixed-recess" else None, "box_lower": box_lower, "set": list(overrides),
           "peak": float(w[k]), "peak_time": float(t[k]), "last": float(w[-1]), "end_time": float(t[-1]),
           "steps": None if s is None else s["steps"], "loop_s": None if s is None else round(float(s["loop_time"]), 1),
           "mass_residual": None if s is None else s["budget"]["mass_residual_relative"],
           "energy_residual": None if s is None else s["budget"]["energy_residual_relative"],
           "stopped": stopped, "time": t.tolist(), "deflection": w.tolist()}
    (folder / f"{label}.json").write_text(json.dumps(out) + "\n")
    print(f"{label}: delta/t = {out['peak'] / THICKNESS[case]:.3f} at {out['peak_time'] * 1e3:.3f} ms"
          f" (last {out['last'] / THICKNESS[case]:.3f} at {out['end_time'] * 1e3:.3f} ms), "
          + (f"{out['steps']} steps, loop {out['loop_s']} s" if stopped is None else f"stopped: {stopped[:200]}"))


def cmd_run(folder: Path, cases, clamps, cells, end: float | None = None, recess: float = 0.025,
            box_lower: float | None = None, overrides: tuple = ()) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for case in cases:
        for clamp in clamps:
            if (folder / f"{name(case, clamp, cells, end, recess, box_lower, overrides)}.json").is_file():
                continue
            args = [sys.executable, __file__, "one", case, clamp, str(folder), "--recess", repr(recess)]
            args += ([] if cells is None else ["--cells", str(cells)]) + ([] if end is None else ["--end", repr(end)])
            args += [] if box_lower is None else ["--box-lower", repr(box_lower)]
            args += [f"--set={item}" for item in overrides]
            subprocess.run(args, check=True)


def cmd_figures(folder: Path) -> None:
    runs = [json.loads(p.read_text()) for p in sorted(folder.glob("case*.json"))]
    JSON.write_text(json.dumps({"runs": runs, "table2": TABLE2}, indent=1) + "\n")
    print("| case | experiment | paper's CFDMP | LS-DYNA | clamp | cells | this code δ/t (at) | vs experiment | last |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in sorted(runs, key=lambda r: (r["case"], r["clamp"], r["cells"] or 0)):
        exp, paper, dyna = TABLE2[r["case"]]
        ratio = r["peak"] / r["thickness"]
        rel = "–" if exp is None else f"{100 * (ratio / exp - 1):+.1f} %"
        if r.get("stopped"):  # the peak so far of a run stopped by a fault
            rel = f"run stopped at {r['end_time'] * 1e3:.2f} ms by a fault"
        fmt = lambda v: "–" if v is None else f"{v:g}"  # noqa: E731
        print(f"| {r['case']} | {fmt(exp)} | {fmt(paper)} | {fmt(dyna)} | {_clamp_label(r)} | {r['cells'] or 'shipped'} "
              f"| {ratio:.3f} ({r['peak_time'] * 1e3:.2f} ms) | {rel} | {r['last'] / r['thickness']:.3f} |")
    _figure(runs)


def cmd_faces(results: Path, ring: float = 0.005) -> None:
    import tomllib

    import h5py

    from blastfsi.materials import lookup

    sc = tomllib.loads((results / "scenario.toml").read_text())
    cell = (sc["domain"]["upper"][0] - sc["domain"]["lower"][0]) / sc["grid"]["cells"]
    free_radius = sc["structures"][0]["supports"][0]["lower"][0]  # D / 2: the clamp's inner edge
    p0 = lookup("air").pressure  # the ambient air's pressure (the run's)
    rows = []
    for file in sorted((results / "fields").glob("member0_[0-9]*.h5")):
        with h5py.File(file, "r") as f:
            P = f["particles"]
            x, p, rho = P["coordinates"][:], P["pressure"][:], P["density"][:]
            steel, t = P["structure"][:] > 0, float(f.attrs["time"])
        gas = ~steel
        edges = np.arange(0.0, free_radius + ring / 2, ring)
        k = np.clip(np.digitize(x[:, 0], edges) - 1, 0, edges.size - 2)
        top, bottom = np.full(edges.size - 1, -np.inf), np.full(edges.size - 1, np.inf)
        np.maximum.at(top, k[steel], x[steel, 1])
        np.minimum.at(bottom, k[steel], x[steel, 1])
        span = gas & (x[:, 0] < free_radius)
        back = span & (x[:, 1] > top[k]) & (x[:, 1] < top[k] + cell)
        front = span & (x[:, 1] < bottom[k]) & (x[:, 1] > bottom[k] - cell)
        area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)

        def force(layer):  # sum over rings of the mean overpressure of the layer's particles in the ring x its area
            total, count = np.zeros(area.size), np.zeros(area.size)
            np.add.at(total, k[layer], p[layer] - p0)
            np.add.at(count, k[layer], 1)
            return float(np.sum(area * total / np.maximum(count, 1)))

        axis = back & (x[:, 0] < 0.05)
        rows.append({"time": t, "front_force": force(front), "back_force": force(back),
                     "back_axis_density": float(rho[axis].mean()) if axis.any() else None,
                     "back_axis_overpressure": float(p[axis].mean() - p0) if axis.any() else None})
    FACES_JSON.write_text(json.dumps({"results": str(results), "rows": rows}, indent=1) + "\n")
    print("| t [ms] | gas force on the front [kN] | on the back [kN] | back layer r < 50 mm: rho [kg/m^3], overpressure [MPa] |")
    print("|---|---|---|---|")
    for r in rows:
        layer = "–" if r["back_axis_density"] is None else (f"{r['back_axis_density']:.2f}, "
                                                            f"{r['back_axis_overpressure'] / 1e6:.2f}")
        print(f"| {r['time'] * 1e3:.3f} | {r['front_force'] / 1e3:.1f} | {r['back_force'] / 1e3:.1f} | {layer} |")
    t = np.asarray([r["time"] for r in rows])
    print(f"impulse on the back to {t[-1] * 1e3:.2f} ms: "
          f"{np.trapezoid([r['back_force'] for r in rows], t):.2f} N s")


def _clamp_label(run: dict) -> str:
    """The clamp of a run, with the recess depth and a moved MPM box where they are set."""
    return (run["clamp"] + (f" ({run['recess'] * 1e3:.0f} mm)" if run.get("recess") else "")
            + (f", box from z = {run['box_lower'] * 1e3:.0f} mm" if run.get("box_lower") is not None else ""))


def _figure(runs) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    colours = {}
    for r in sorted(runs, key=lambda r: (r["case"], r["clamp"], r["cells"] or 0)):
        if r["cells"] is not None or r.get("box_lower") is not None:
            continue
        c = colours.setdefault(r["case"], f"C{len(colours)}")
        stopped = f" (stopped at {r['end_time'] * 1e3:.2f} ms)" if r.get("stopped") else ""
        ax.plot(np.asarray(r["time"]) * 1e3, np.asarray(r["deflection"]) / r["thickness"], color=c,
                ls={"sliding": "-", "fixed-recess": "-."}.get(r["clamp"], "--"),
                label=f"case {r['case']}, {_clamp_label(r)} clamp{stopped}")
        exp = TABLE2[r["case"]][0]
        if exp is not None:
            ax.axhline(exp, color=c, lw=0.8, ls=":")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("centre deflection δ / t")
    ax.set_title("Table 2 plates: centre deflection (dotted: experiment)")
    ax.legend(fontsize=7, loc="upper right")  # (the corner no history reaches)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(PNG, dpi=120)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    one = sub.add_parser("one")
    one.add_argument("case", choices=sorted(EXAMPLES))
    one.add_argument("clamp", choices=CLAMPS)
    one.add_argument("dir", type=Path)
    one.add_argument("--cells", type=int)
    one.add_argument("--end", type=float)
    one.add_argument("--recess", type=float, default=0.025)
    one.add_argument("--box-lower", type=float)
    one.add_argument("--set", action="append", default=[])
    run = sub.add_parser("run")
    run.add_argument("dir", type=Path)
    run.add_argument("--cases", nargs="+", default=["1", "4"], choices=sorted(EXAMPLES))
    run.add_argument("--clamps", nargs="+", default=["fixed", "sliding"], choices=CLAMPS)
    run.add_argument("--cells", type=int)
    run.add_argument("--end", type=float, help="time.end [s] (default: the example's; the sliding clamp peaks later)")
    run.add_argument("--recess", type=float, default=0.025, help="depth of the front clamping plate of fixed-recess [m]")
    run.add_argument("--box-lower", type=float, help="the MPM box's lower face z [m] (default: the example's)")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scenario override")
    fig = sub.add_parser("figures")
    fig.add_argument("dir", type=Path)
    faces = sub.add_parser("faces")
    faces.add_argument("results", type=Path)
    a = p.parse_args(argv)
    if a.cmd == "one":
        cmd_one(a.case, a.clamp, a.cells, a.dir, a.end, a.recess, a.box_lower, tuple(a.set))
    elif a.cmd == "run":
        cmd_run(a.dir, a.cases, a.clamps, a.cells, a.end, a.recess, a.box_lower, tuple(a.set))
    elif a.cmd == "faces":
        cmd_faces(a.results)
    else:
        cmd_figures(a.dir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
