"""Issue 34, deliverable 2: the structural side of steel-plate-blast verified on its own.

The clamped RHA plate of steel-plate-blast (t = 10 mm, free radius a = 0.25 m, plate to r = 0.28 m, clamped
beyond r = a; steel-rha Johnson-Cook; GIMP) is given a UNIFORM upward velocity V0 over its free span and no
other load; the centre's displacement history (tracer at mid-thickness on the axis) gives the peak deflection
and an estimate of the permanent one. Compared with the rigid-plastic solution of Jones and the Nurick-Martin
fit (blastfsi.exact.rigid_plastic_plate).

    python docs/figures/make_plate_structural.py run [NAME ...]   # the runs below (all: ~20 min on 2 cores)
    python docs/figures/make_plate_structural.py figure           # plate_structural.png from the JSON

``run`` keeps what plate_structural.json already holds (``--force`` reruns) and writes the JSON after every
run. Runs (name: method, V0 [m/s], cells across t, particles per cell and direction, end time):

* ``rz-c4-v*``: r-z at the shipped resolution (2.5 mm cells, 4 across t, 2 x 2 particles), V0 from the
  uniform-spread KB impulse of case 1 (315 N s, issue 34) up to 120 m/s, including the V0 at which Jones gives
  delta/t = 2.60 and 4.85; to 3 ms (the peak, then the permanent set as the mean over 1-3 ms, more than two
  periods of the elastic vibration that follows the peak; its min-max range is kept too);
* ``rz-c{2,8}-v*``, ``rz-c4p4-v*``: thickness convergence (2, 4, 8 cells across t; 4 cells with 4 x 4
  particles, 16 particle rows) at the two Jones V0, to 0.7 ms (peak);
* ``3d-c2-v59``: a 3D quarter model (x, y symmetry planes) with 5 mm cells (2 across t, 2 x 2 x 2 particles,
  ~50 000 particles, ~4 min), against ``rz-c2-v59``. The circular clamp is exact at particle resolution:
  the quarter plate is cut into strips of 16 particle columns (bodies of one material share the grid, so
  they form one continuum) and each column gets a support box holding its particles with r > a.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
JSON = HERE / "plate_structural.json"
PNG = HERE / "plate_structural.png"

A_FREE, R_PLATE, T = 0.25, 0.28, 0.01  # free radius, plate radius, thickness [m]
PERMANENT_FROM = 1.0e-3  # s: the permanent set is the mean of the centre deflection from here to the end
KB_IMPULSE_CASE1 = 315.0  # N s over r < 0.25 m: KB/ConWep reflected impulse of case 1 (issue 34)
EXPERIMENTS = {"case 1 (0.468 kg)": 2.60, "case 4 (1.094 kg)": 4.85}


def plate():
    """The reference plate: steel-rha's density and Johnson-Cook A as the flow stress."""
    from blastfsi.exact.rigid_plastic_plate import ClampedCircularPlate
    from blastfsi.materials import lookup

    m = lookup("steel-rha")
    bulk = m.density * m.C0 ** 2
    youngs = 9.0 * bulk * m.shear_modulus / (3.0 * bulk + m.shear_modulus)
    return ClampedCircularPlate(A_FREE, T, m.density, m.A, youngs)


def velocities() -> dict:
    p = plate()
    v26, v485 = (float(v) for v in p.jones_velocity([2.60, 4.85]))
    return {"kb": float(p.velocity(KB_IMPULSE_CASE1)), "30": 30.0, "45": 45.0, "59": v26, "75": 75.0,
            "98": v485, "120": 120.0}


def runs() -> dict:
    v = velocities()
    out = {f"rz-c4-v{k}": ("rz", v[k], 4, 2, 3.0e-3) for k in v}
    for k in ("59", "98"):
        out[f"rz-c2-v{k}"] = ("rz", v[k], 2, 2, 7e-4)
        out[f"rz-c8-v{k}"] = ("rz", v[k], 8, 2, 7e-4)
        out[f"rz-c4p4-v{k}"] = ("rz", v[k], 4, 4, 7e-4)
    out["rz-c2-v59"] = ("rz", v["59"], 2, 2, 3.0e-3)
    out["3d-c2-v59"] = ("3d", v["59"], 2, 2, 5.5e-4)
    return out


def scenario_rz(v0: float, cells_per_t: int, ppc: int, t_end: float) -> dict:
    h = T / cells_per_t
    return {"method": "mpm", "name": "plate-rz",
            "grid": {"lower": [0.0, -0.01], "upper": [0.3, 0.08], "cells": int(round(0.3 / h)), "axisymmetric": True,
                     "boundaries": {"x": ["slip", "free"], "y": ["free", "free"]}},
            "bodies": [{"lower": [0.0, 0.0], "upper": [R_PLATE, T], "material": "steel-rha", "velocity": [0.0, v0],
                        "particles_per_cell": ppc, "supports": [{"lower": [A_FREE, 0.0], "upper": [R_PLATE, T]}]}],
            "numerics": {"shape": "gimp"}, "time": {"end": t_end},
            "output": {"history_samples": int(round(t_end / 2.5e-6)) + 1, "fields": 0, "tracers": [[0.0, T / 2]]}}


def scenario_3d(v0: float, cells_per_t: int, ppc: int, t_end: float, strip: int = 16) -> dict:
    h = T / cells_per_t
    s = h / ppc
    columns = int(round(R_PLATE / s))
    if columns % strip:
        raise ValueError(f"{columns} particle columns are not a whole number of strips of {strip}")
    bodies = []
    for k in range(columns // strip):
        x0 = k * strip * s
        supports = []
        for j in range(strip):
            xc = x0 + (j + 0.5) * s  # the column's particle centres; clamp those with r > a
            y_clamp = np.sqrt(max(A_FREE ** 2 - xc ** 2, 0.0))
            supports.append({"lower": [xc - 0.25 * s, y_clamp, 0.0], "upper": [xc + 0.25 * s, R_PLATE, T]})
        bodies.append({"lower": [x0, 0.0, 0.0], "upper": [x0 + strip * s, R_PLATE, T], "material": "steel-rha",
                       "velocity": [0.0, 0.0, v0], "particles_per_cell": ppc, "supports": supports})
    edge = R_PLATE + 0.01
    return {"method": "mpm", "name": "plate-3d",
            "grid": {"lower": [0.0, 0.0, -0.01], "upper": [edge, edge, 0.07], "cells": int(round(edge / h)),
                     "boundaries": {"x": ["slip", "free"], "y": ["slip", "free"], "z": ["free", "free"]}},
            "bodies": bodies, "numerics": {"shape": "gimp"}, "time": {"end": t_end},
            "output": {"history_samples": int(round(t_end / 5e-6)) + 1, "fields": 0,
                       "tracers": [[0.0, 0.0, T / 2]]}}


def measure(kind: str, v0: float, cells_per_t: int, ppc: int, t_end: float) -> dict:
    import blastfsi

    sc = (scenario_rz if kind == "rz" else scenario_3d)(v0, cells_per_t, ppc, t_end)
    started = time.perf_counter()
    res = blastfsi.run(sc)
    total = time.perf_counter() - started
    t = np.asarray(res.history["time"])
    w = np.asarray(res.history["tracer0_displacement_z"])
    k = int(np.argmax(w))
    out = {"kind": kind, "V0": v0, "impulse": float(plate().impulse(v0)), "cells_across_t": cells_per_t,
           "particles_per_cell": ppc, "cell_size": T / cells_per_t, "t_end": t_end,
           "peak_delta_over_t": float(w[k] / T), "t_peak": float(t[k]), "final_delta_over_t": float(w[-1] / T),
           "permanent_delta_over_t": None, "steps": int(res.summary["steps"]),
           "loop_wall_s": float(res.summary["wall_time"]), "compile_s": float(res.summary["compile_time"]),
           "total_s": total, "particles": int(res.summary["particles"]),
           "max_plastic_strain": float(res.summary["max_plastic_strain"]),
           "energy_balance_relative": res.summary["energy_balance_relative"],
           "history": {"t": t[::4].tolist(), "delta_over_t": (w[::4] / T).tolist()}}
    if t_end >= 2.0e-3:  # permanent set: mean over t >= 1 ms (> 2 periods of the elastic vibration)
        late = t >= PERMANENT_FROM
        out["permanent_delta_over_t"] = float(np.mean(w[late]) / T)
        out["permanent_range"] = [float(w[late].min() / T), float(w[late].max() / T)]
    return out


def load() -> dict:
    return json.loads(JSON.read_text()) if JSON.is_file() else {}


def references(data: dict) -> dict:
    p = plate()
    v = np.linspace(0.0, 130.0, 131)
    i = p.impulse(v)
    v26, v485 = (float(x) for x in p.jones_velocity([2.60, 4.85]))
    return {"plate": {"radius": p.radius, "thickness": p.thickness, "density": p.density,
                      "flow_stress": p.flow_stress, "youngs_modulus": p.youngs_modulus, "mass": p.mass},
            "curves": {"V0": v.tolist(), "impulse": i.tolist(), "jones": p.jones(v).tolist(),
                       "energy_bound": p.energy_bound(v).tolist(), "nurick_martin": p.nurick_martin(i).tolist()},
            "jones_for_2.60": {"V0": v26, "impulse": float(p.impulse(v26)), "energy_ratio": float(p.energy_ratio(v26))},
            "jones_for_4.85": {"V0": v485, "impulse": float(p.impulse(v485)),
                               "energy_ratio": float(p.energy_ratio(v485))},
            "nurick_martin_for_2.60": {"impulse": float(p.nurick_martin_impulse(2.60))},
            "nurick_martin_for_4.85": {"impulse": float(p.nurick_martin_impulse(4.85))},
            "kb_case1_uniform": {"impulse": KB_IMPULSE_CASE1, "V0": float(p.velocity(KB_IMPULSE_CASE1)),
                                 "jones": float(p.jones(p.velocity(KB_IMPULSE_CASE1)))},
            "mpm_rz_impulse_for": mpm_impulse_for(data)}


def mpm_impulse_for(data: dict) -> dict:
    """Uniform impulse [N s] at which the shipped-resolution r-z MPM plate reaches delta/t = 2.60 and 4.85
    (peak and permanent), by linear interpolation between the runs rz-c4-v*."""
    rz = sorted((r for n, r in data.get("runs", {}).items() if n.startswith("rz-c4-v")), key=lambda r: r["V0"])
    out = {}
    for key in ("peak_delta_over_t", "permanent_delta_over_t"):
        pts = [(r[key], r["impulse"]) for r in rz if r[key] is not None]
        if len(pts) >= 2:
            d, i = np.asarray(pts).T
            out[key] = {str(x): (float(np.interp(x, d, i)) if d.min() <= x <= d.max() else None) for x in (2.60, 4.85)}
    return out


def run(names, force: bool = False) -> None:
    table = runs()
    data = load()
    data.setdefault("runs", {})
    for name in names or list(table):
        if name in data["runs"] and not force:
            continue
        r = measure(*table[name])
        data["runs"][name] = r
        data["references"] = references(data)
        JSON.write_text(json.dumps(data, indent=1))
        print(name, json.dumps({k: r[k] for k in ("V0", "peak_delta_over_t", "t_peak", "permanent_delta_over_t",
                                                    "steps", "loop_wall_s", "total_s")}), flush=True)


def figure() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = load()
    data["references"] = ref = references(data)
    JSON.write_text(json.dumps(data, indent=1))
    c = ref["curves"]
    i = np.asarray(c["impulse"])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    ax.plot(i, c["jones"], "k-", label="Jones rigid-plastic $(1+2\\lambda/3)^{1/2}-1$")
    ax.plot(i, c["energy_bound"], "k--", lw=0.9, label="same mode, all kinetic energy $(1+\\lambda)^{1/2}-1$")
    nm = np.asarray(c["nurick_martin"])
    ax.plot(i, nm, "g-", lw=1.0, label="Nurick–Martin $0.425\\phi_c+0.277$ (mild steel)")
    ax.fill_between(i, 0.8 * nm, 1.2 * nm, color="g", alpha=0.12, lw=0, label="±20 % (indicative)")
    rz = sorted((r for n, r in data["runs"].items() if n.startswith("rz-c4-v")), key=lambda r: r["V0"])
    ax.plot([r["impulse"] for r in rz], [r["peak_delta_over_t"] for r in rz], "bo-", label="MPM r–z peak (4 cells/t)")
    perm = [r for r in rz if r["permanent_delta_over_t"] is not None]
    mean = np.asarray([r["permanent_delta_over_t"] for r in perm])
    spread = np.asarray([r.get("permanent_range", [m, m]) for r, m in zip(perm, mean)]).reshape(-1, 2)
    ax.errorbar([r["impulse"] for r in perm], mean, yerr=[mean - spread[:, 0], spread[:, 1] - mean], fmt="bs--",
                mfc="none", capsize=3, label="MPM r–z permanent (mean over 1–3 ms, bar: min–max)")
    for name, mk, lab in (("rz-c2-v59", "c^", "MPM r–z peak, 2 cells/t"),
                          ("3d-c2-v59", "r*", "MPM 3D peak, 2 cells/t")):
        if name in data["runs"]:
            r = data["runs"][name]
            ax.plot(r["impulse"], r["peak_delta_over_t"], mk, ms=10, mfc="none" if mk == "c^" else mk[0], label=lab)
    for (label, d), mk in zip(EXPERIMENTS.items(), ("D", "d")):
        ax.axhline(d, color="m", lw=0.6, ls=":")
        ax.text(1250, d + 0.07, f"experiment {label}: {d}", color="m", fontsize=7)
    ax.plot(KB_IMPULSE_CASE1, EXPERIMENTS["case 1 (0.468 kg)"], "mD", mfc="none",
            label="case 1 at its KB reflected impulse (concentrated load)")
    ax.set_xlabel("total impulse over r < 0.25 m, uniform [N s]")
    ax.set_ylabel("centre deflection δ/t")
    ax.set_xlim(0, 2000)
    ax.set_ylim(0, 8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Clamped RHA plate (t = 10 mm, a = 0.25 m), uniform impulsive velocity")
    for name, style in (("rz-c4-v59", "b-"), ("rz-c2-v59", "c-"), ("rz-c8-v59", "k:"), ("rz-c4p4-v59", "y--"),
                        ("3d-c2-v59", "r-"), ("rz-c4-v98", "b-"), ("rz-c8-v98", "k:"), ("rz-c2-v98", "c-")):
        if name in data["runs"]:
            h = data["runs"][name]["history"]
            bx.plot(np.asarray(h["t"]) * 1e3, h["delta_over_t"], style, lw=1.0, label=name)
    bx.axhline(2.60, color="m", lw=0.6, ls=":")
    bx.axhline(4.85, color="m", lw=0.6, ls=":")
    bx.set_xlabel("t [ms]")
    bx.set_ylabel("centre deflection δ/t")
    bx.set_title("centre histories at the Jones V0 for 2.60 (59 m/s) and 4.85 (98 m/s)")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(PNG, dpi=120)
    plt.close(fig)
    print(f"wrote {PNG} and {JSON}")


if __name__ == "__main__":
    args = sys.argv[1:]
    force = "--force" in args
    args = [a for a in args if a != "--force"]
    if not args or args[0] not in ("run", "figure"):
        sys.exit(__doc__)
    run(args[1:], force) if args[0] == "run" else figure()
