"""Seed 000 Sec. 5.3 and 5.5 through CFDMP: concrete pavement slabs under a charge 0.5 m above them.

    python docs/figures/make_slab_figures.py run DIR [RUN ...]   # the runs below into DIR/RUN (all by default)
    python docs/figures/make_slab_figures.py figures DIR         # concrete_slab.json + PNGs here, from DIR
    python docs/figures/make_slab_figures.py point               # the top face as one material point (seconds)

Runs (``blastfsi.run`` on the shipped examples with the overrides named; each writes DIR/RUN):

* ``rz-<W>kg-5mm``: ``concrete-slab-blast`` (r-z, 5 mm cells) with ``initial.mass`` = W = 2, 4 (the shipped
  example), 10, 20 kg TNT: the crushing diameters of Fig. 15;
* ``rz-4kg-10mm``, ``rz-4kg-25mm``: the grid study (10 mm with the thinnest box at that grid; 25 mm with the 3D
  model's grid and box);
* ``3d-4kg-25mm``: ``concrete-slab-blast-3d``, the quarter model of the square slab, 25 mm cells;
* ``defect-4kg-5mm``: the shipped ``concrete-slab-defect`` (Sec. 5.5), beside ``rz-4kg-5mm``.

``point``: one particle of ``concrete-25mpa`` in the top face's state, uniaxial strain, loaded to a peak axial
stress S at a strain rate of 10^3 /s and released to zero axial stress; its HJC damage D at the end, for the peak
loads of the runs and of Kingery-Bulmash, and the largest D any S up to 1 GPa gives (into concrete_slab.json).

The crushing diameter is the summary's ``structures.faces[k].crushing_diameter`` (the zone around the axis
whose top-face particles failed; blastfsi.diagnostics.damage); Eq. (67) from blastfsi.exact.concrete_crushing.
"""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from blastfsi.exact.concrete_crushing import crushing_diameter  # noqa: E402
from blastfsi.io.results import read_snapshot  # noqa: E402

HERE = Path(__file__).parent
HEIGHT = 0.5  # m, the charge's centre above the slab's top face (000 Sec. 5.3)
MASSES = (2.0, 4.0, 10.0, 20.0)  # kg TNT, 000 Sec. 5.3
EXPERIMENT = {4.0: 0.250, 10.0: 0.300}  # m, crushing diameters of the tests (000 Sec. 5.3)
PAPER = {4.0: 0.261}  # m, the seed's CFDMP (Sec. 5.3)
COARSE = {"grid.cells": 32, "mpm_region.upper": [0.8, 0.15], "mpm_region.bridge_cells": 2,
          "mpm_region.gas_particles_per_cell": 1}  # concrete-slab-blast-3d's grid and box in r-z
RUNS = {  # in the order they run
    "rz-4kg-5mm": ("concrete-slab-blast", {}),
    "defect-4kg-5mm": ("concrete-slab-defect", {}),
    "rz-10kg-5mm": ("concrete-slab-blast", {"initial.mass": 10.0}),
    "rz-4kg-25mm": ("concrete-slab-blast", COARSE),
    "3d-4kg-25mm": ("concrete-slab-blast-3d", {}),
    "rz-4kg-10mm": ("concrete-slab-blast", {"grid.cells": 80, "mpm_region.upper": [0.8, 0.1]}),
    "rz-2kg-5mm": ("concrete-slab-blast", {"initial.mass": 2.0}),
    "rz-20kg-5mm": ("concrete-slab-blast", {"initial.mass": 20.0}),
}


def run(folder: Path, names: list[str]) -> None:
    import blastfsi

    for name in names or RUNS:
        example, overrides = RUNS[name]
        out = folder / name
        if (out / "summary.json").exists():
            print(f"{name}: done already")
            continue
        res = blastfsi.run(example, set=overrides, out=out)
        print(f"{name}: {res.summary['steps']} steps, loop {res.summary['loop_time']:.0f} s")


def _final_particles(out: Path) -> dict:
    """The last snapshot's particle fields, positions as ``coordinates`` (n, ndim)."""
    last = sorted((out / "fields").glob("member0_*.h5"))[-1]
    snap = read_snapshot(out, "coupled", int(last.stem.split("_")[-1]), 0).particles
    return {"coordinates": snap.positions, **snap.point_fields}


def _row(name: str, summary: dict) -> dict:
    example, overrides = RUNS[name]
    faces = summary["structures"]["faces"]
    budget = summary["budget"]
    return {"run": name, "example": example, "overrides": overrides, "dx": summary["dx"],
            "mass": overrides.get("initial.mass", 4.0),
            "faces": [{"structure": f["structure"], "crushing_diameter": f["crushing_diameter"],
                       "breach_diameter": f.get("breach_diameter"),
                       "failed": f["failed"]["by_threshold"], "compressive": f["compressive_damage"]["by_threshold"],
                       "back_face_tensile": f["back_face_tensile_damage"]["by_threshold"]} for f in faces],
            "failed_volume": summary["structures"]["failed_volume"],
            "damaged_volume": summary["structures"]["damaged_volume"],
            "mass_residual_relative": budget["max_mass_residual_relative"],
            "energy_residual_relative": budget["energy_residual_relative"],
            "gauges": [{k: g[k] for k in ("position", "peak_overpressure", "impulse")} for g in summary["gauges"]],
            "steps": summary["steps"], "loop_time": summary["loop_time"], "compile_time": summary["compile_time"]}


def faces_figure(out: Path, png: Path) -> None:
    """Fig. 14: the run's own plots/faces.png (the top face's failure, the back face's tensile damage)."""
    shutil.copyfile(out / "plots" / "faces.png", png)


def section_figure(runs: dict[str, Path], png: Path) -> None:
    """r-z sections of the damage at the end, side by side (000 Sec. 5.5: with and without the defect)."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(8, 2.2 * len(runs)), squeeze=False)
    for ax, (label, out) in zip(axes[:, 0], runs.items()):
        p = _final_particles(out)
        concrete = ~np.isnan(p["compressive_damage"])
        x = p["coordinates"][concrete]
        m = ax.scatter(x[:, 0], x[:, 1], c=p["damage"][concrete], s=1.0, vmin=0, vmax=1, cmap="inferno_r")
        ax.set_title(label, fontsize=9), ax.set_aspect("equal")
        ax.set_xlabel("r [m]"), ax.set_ylabel("z [m]")
    fig.colorbar(m, ax=axes[:, 0].tolist(), label="damage (1: failed)")
    fig.savefig(png, dpi=120)
    plt.close(fig)


def figures(folder: Path) -> None:
    rows = [_row(n, json.loads((folder / n / "summary.json").read_text()))
            for n in RUNS if (folder / n / "summary.json").exists()]
    eq67 = {f"{w:g}": crushing_diameter(w, HEIGHT) for w in MASSES}
    path = HERE / "concrete_slab.json"
    kept = {k: v for k, v in (json.loads(path.read_text()) if path.exists() else {}).items() if k == "material_point"}
    path.write_text(json.dumps(
        {**kept, "height": HEIGHT, "experiment": {f"{k:g}": v for k, v in EXPERIMENT.items()},
         "paper_cfdmp": {f"{k:g}": v for k, v in PAPER.items()}, "eq67": eq67, "runs": rows}, indent=1))

    fig, ax = plt.subplots(figsize=(6, 4.5))
    s = np.linspace(2.0, 6.0, 100)
    ax.plot(s, np.exp(0.1838 * s) / 3.63, "k-", label="Eq. (67), Luccioni & Luege (2006)")
    ax.plot([w ** (1 / 3) / HEIGHT for w in EXPERIMENT], [d / HEIGHT for d in EXPERIMENT.values()], "ks",
            mfc="none", ms=8, label="experiment")
    ax.plot([w ** (1 / 3) / HEIGHT for w in PAPER], [d / HEIGHT for d in PAPER.values()], "b^", label="seed CFDMP")
    for marker, pick, label in (("o", lambda r: r["run"].startswith("rz-") and r["dx"] == 0.005, "this code, r-z 5 mm"),
                                ("D", lambda r: r["run"].startswith("rz-") and r["dx"] > 0.005, "this code, r-z 10, 25 mm"),
                                ("v", lambda r: r["run"].startswith("3d-"), "this code, 3D quarter 25 mm")):
        pts = [(r["mass"] ** (1 / 3) / HEIGHT, r["faces"][0]["crushing_diameter"] / HEIGHT) for r in rows if pick(r)]
        if pts:
            ax.plot(*zip(*pts), marker, ls="none", label=label)
    breach = [(r["mass"] ** (1 / 3) / HEIGHT, r["faces"][0]["breach_diameter"] / HEIGHT) for r in rows
              if r["run"].startswith("rz-") and r["dx"] == 0.005 and r["faces"][0].get("breach_diameter") is not None]
    if breach:
        ax.plot(*zip(*breach), "o", mfc="none", color="C0", label="this code, r-z 5 mm: breach (half the thickness failed)")
    ax.set_xlabel(r"$W^{1/3}/h$ [kg$^{1/3}$/m]"), ax.set_ylabel(r"$D/h$ [-]")
    ax.set_title("Crushing diameter, slab 0.15 m, h = 0.5 m (000 Fig. 15)", fontsize=10)
    ax.grid(alpha=0.3), ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "concrete_slab_fig15.png", dpi=120)
    plt.close(fig)

    for name, png in (("rz-4kg-5mm", "concrete_slab_faces.png"), ("defect-4kg-5mm", "concrete_slab_defect_faces.png")):
        if (folder / name / "summary.json").exists():
            faces_figure(folder / name, HERE / png)
    pair = {n: folder / n for n in ("rz-4kg-5mm", "defect-4kg-5mm") if (folder / n / "summary.json").exists()}
    if pair:
        section_figure(pair, HERE / "concrete_slab_defect_sections.png")
    print(markdown_tables(rows, eq67))


POINT_LOADS = {"4 kg, this code (5 mm)": 57.8e6, "4 kg, Kingery-Bulmash reflected": 76.6e6,
               "10 kg, this code (5 mm)": 140.8e6, "20 kg, this code (5 mm)": 282.4e6}  # Pa, on the axis (tables)


def uniaxial_strain_damage(peak: float, rate: float = 1e3, increment: float = 2e-6) -> float:
    """HJC damage of one ``concrete-25mpa`` particle compressed in uniaxial strain (z) to the axial stress
    ``peak`` [Pa] and released to zero axial stress, at ``rate`` [1/s] in strain steps of ``increment``."""
    import jax
    import jax.numpy as jnp

    from blastfsi.constitutive import PointState, hjc
    from blastfsi.materials import SOLIDS

    with jax.enable_x64(True):
        p = hjc.params_from(SOLIDS["concrete-25mpa"])
        update = jax.jit(lambda ps, de: hjc.update(ps, de, jnp.zeros((1, 3, 3)), increment / rate, p))
        ps = PointState(jnp.zeros((1, 6)), jnp.full((1,), p.density), jnp.zeros(1), jnp.zeros(1), jnp.zeros(1),
                        jnp.zeros((1, 4)))
        for sign in (-1.0, 1.0):  # load, then release
            de = jnp.zeros((1, 3, 3)).at[0, 2, 2].set(sign * increment)
            while True:
                ps = update(ps._replace(density=ps.density / (1.0 + sign * increment)), de)
                axial = -float(ps.stress[0, 2])
                if (axial >= peak) if sign < 0 else (axial <= 0.0):
                    break
        return float(ps.history[0, 2])


def material_point() -> dict:
    """The top face as one material point: D after each load of POINT_LOADS, and over peaks up to 1 GPa."""
    loads = {name: {"peak": s, "damage": uniaxial_strain_damage(s)} for name, s in POINT_LOADS.items()}
    sweep = {f"{s / 1e6:g}": uniaxial_strain_damage(s) for s in (250e6, 500e6, 1000e6)}
    out = {"path": "uniaxial strain, loaded to the peak axial stress at 1e3 /s, released to zero axial stress",
           "loads": loads, "sweep_peak_MPa": sweep}
    path = HERE / "concrete_slab.json"
    data = json.loads(path.read_text()) if path.exists() else {}
    path.write_text(json.dumps({**data, "material_point": out}, indent=1))
    print("| load | peak axial stress [MPa] | HJC damage D after release |\n|---|---|---|")
    for name, v in loads.items():
        print(f"| {name} | {v['peak'] / 1e6:.1f} | {v['damage']:.3f} |")
    for s, d in sweep.items():
        print(f"| sweep | {s} | {d:.3f} |")
    return out


def markdown_tables(rows: list[dict], eq67: dict) -> str:
    """The tables of docs/validation.md (Sec. 2), from the runs' rows."""
    def mm(v):
        return "–" if v is None else f"{v * 1e3:.0f}"

    out = ["| run | W [kg] | cells | top face failed D (thresholds 0.5 / 0.75 / 1) [mm] | compressive D (1) [mm] "
           "| breach D [mm] | back face D_t >= 0.5 D [mm] | Eq. 67 [mm] | experiment [mm] | failed volume [L] "
           "| mass / energy residual | steps | loop [s] |", "|" + "---|" * 13]
    for r, f in ((r, f) for r in rows for f in r["faces"]):
        key, run = f"{r['mass']:g}", r["run"] + (f" (structure {f['structure']})" if len(r["faces"]) > 1 else "")
        failed = " / ".join(mm(t["diameter"]) for t in f["failed"])
        out.append(f"| {run} | {r['mass']:g} | {r['dx'] * 1e3:g} mm | {failed} | {mm(f['compressive'][-1]['diameter'])} "
                   f"| {mm(f['breach_diameter'])} | {mm(f['back_face_tensile'][0]['diameter'])} "
                   f"| {mm(eq67[key])} | {mm(EXPERIMENT.get(r['mass']))} "
                   f"| {r['failed_volume'] * 1e3:.1f} | {r['mass_residual_relative']:.0e} / {r['energy_residual_relative']:.1e} "
                   f"| {r['steps']} | {r['loop_time']:.0f} |")
    loads = ["| run | " + " | ".join(f"r = {g['position'][0] * 1e3:.0f} mm" for g in rows[0]["gauges"]) + " |",
             "|---|" + "---|" * len(rows[0]["gauges"])]
    for r in rows:
        loads.append(f"| {r['run']} | " + " | ".join(f"{g['peak_overpressure'] / 1e6:.1f} MPa, {g['impulse'] / 1e3:.2f} kPa s"
                                                   for g in r["gauges"]) + " |")
    return "\n".join(out) + "\n\nLoad on the top face (half a cell above it; peak overpressure, positive-phase impulse):\n\n" + \
        "\n".join(loads)

if __name__ == "__main__":
    command, folder = sys.argv[1], Path(sys.argv[2]) if len(sys.argv) > 2 else None
    {"run": lambda: run(folder, sys.argv[3:]), "figures": lambda: figures(folder), "point": material_point}[command]()
