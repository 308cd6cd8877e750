"""Seed 000 Sec. 5.2 (explosion next to a concrete slab) through CFDMP: Figs. 10-12 and the slab's damage.

    python docs/figures/make_000_figures.py run DIR        # the runs below into DIR (~10 min on a 2-core CPU)
    python docs/figures/make_000_figures.py figures DIR    # PNG + he_slab_2d.json here, from DIR

Runs (all through ``blastfsi.run``, the shipped examples with the overrides named):

* ``w5``: ``he-slab-2d`` to its end (20 us), checkpoints every 4 us: the two symmetric gauges (Fig. 10)
  and the slab at the end; ``field-at`` continues a checkpoint to the time of Fig. 12;
* ``w2``, ``w8``: the same with ``mpm_region.bridge_cells`` = 2, 8 (Fig. 11);
* ``cfdmp-32.5us``, ``mpm-32.5us``: ``he-slab-2d`` and ``he-slab-2d-mpm`` to 32.5 us, the time of Fig. 12,
  with the final field written: pressure in the interaction region side by side, and the wall times;
* ``w5-1mm``, ``mpm-incident``, ``mpm-incident-1mm``: the incident pulse at the gauges, coupled on a 1 mm
  grid and with MPM everywhere on 2 and 1 mm, beside the 1D Lagrangian run of the same charge (``figures``
  runs it: the reference at r = 125 mm).

    python docs/figures/make_000_figures.py field-at DIR RUN TIME OUT   # RUN's fields at TIME from a checkpoint
    python docs/figures/make_000_figures.py step-cost DIR              # s per step of both Fig. 12 set-ups

The he-slab-2d figures of docs/verification.md come from these runs and from he_slab_2d.json.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = Path(__file__).parent
REMAP = 9.6e-6  # s, he-slab-2d's initial.remap_time: the runs' times count from the detonation
FIG12_TIME = REMAP + 32.5e-6  # s, 000 Fig. 12 (32.5 us after the remap)
REGION_X = (0.110, 0.160)  # m, the MPM (interaction) region of 000 Sec. 5.2
RUNS = {
    "w2": ("he-slab-2d", {"mpm_region.bridge_cells": 2}),
    "w5": ("he-slab-2d", {"output.checkpoint_interval": 4.0e-6}),
    "w8": ("he-slab-2d", {"mpm_region.bridge_cells": 8}),
    "cfdmp-32.5us": ("he-slab-2d", {"time.end": FIG12_TIME, "output.fields": 2, "output.history_samples": 131,
                                    "output.checkpoint_interval": 2.5e-6}),
    "mpm-32.5us": ("he-slab-2d-mpm", {"time.end": FIG12_TIME, "output.fields": 2, "output.history_samples": 131}),
    # the incident pulse at both gauges on a 1 mm grid (w = 5, bridge 5 mm) and with MPM everywhere at 2 mm
    "w5-1mm": ("he-slab-2d", {"grid.cells": 340, "time.end": REMAP + 1.325e-5, "output.history_samples": 266,
                              "output.fields": 0}),
    "mpm-incident": ("he-slab-2d-mpm", {"time.end": REMAP + 1.325e-5, "output.history_samples": 266, "output.fields": 0}),
    "mpm-incident-1mm": ("he-slab-2d-mpm", {"grid.cells": 340, "time.end": REMAP + 1.325e-5, "output.history_samples": 266,
                                            "output.fields": 0}),  # ~8 min on this CPU
}


def run(folder: Path, names) -> None:
    import blastfsi

    for name in names:
        example, overrides = RUNS[name]
        res = blastfsi.run(example, set=overrides, out=folder / name)
        print(name, json.dumps({k: res.summary[k] for k in ("steps", "wall_time", "compile_time")}), flush=True)


def _restored(folder: Path, name: str, time: float | None):
    """(method, setup, static, state, params, scalars) of run ``name``: its initial state, or (``time``) its
    last checkpoint at or before ``time``. (The driver's parts, called outside ``blastfsi.run``, which would set
    the run's precision: this process computes in float64.)"""
    import jax

    from blastfsi import api, method as methods, simulation
    from blastfsi.io import results

    jax.config.update("jax_enable_x64", True)
    from blastfsi.scenario import expand

    example, overrides = RUNS[name]
    sc, _, scs = expand(api.load(example, set=overrides))
    method, (setup,), static, state, params = simulation.prepare(sc, scs)
    n = sc.output.history_samples
    begin = float(state.t[0])  # the clock's start, as the driver's: a charge's remap time
    if time is not None:
        _, ckpt_times, _ = simulation.stop_times(sc, begin)
        k = max(i for i, t in enumerate(ckpt_times) if t <= time)
        file = folder / name / "checkpoints" / f"ckpt_{k + 1:04d}.h5"
        saved, _ = results.read_checkpoint(file)
        (setup,), state = simulation.fit_pool(method, [setup], saved, state)  # the pool may have grown
        state = simulation._restore(file, saved, state)
        static = method.static(setup, scs[0])
    scalars = (20_000, (sc.time.end - begin) / (n - 1), sc.time.dt_min_fraction)
    advance, _ = methods.compiled_advance(method, static, state, params, sc.time.end, *scalars)
    return method, setup, advance, state, params, scalars


def field_at(folder: Path, name: str, time: float, out: Path) -> None:
    """The fields of run ``name`` at ``time``, continued from its last checkpoint before ``time`` (for a
    run whose snapshots miss that time): written to ``out``/fields with ``out``/summary.json (steps)."""
    from blastfsi import simulation
    from blastfsi.io import results

    method, setup, advance, state, params, scalars = _restored(folder, name, time)
    t0 = float(state.t[0])
    state = advance(state, params, time, *scalars)
    member = simulation._members(state)[0]
    results.write_snapshot(out, 0, time, [method.snapshot(member, setup)])
    (out / "summary.json").write_text(json.dumps({"steps": int(member.step), "time": float(member.t),
                                                  "continued_from": t0}))


FAR = 1.0  # s, a stop time far beyond the runs (finite: the time loop spreads the steps before a stop over it)


def step_cost(folder: Path, name: str, time: float | None, steps: int = 20) -> dict:
    """Wall and CPU seconds per step of run ``name`` at its checkpoint before ``time`` (or its start),
    compiled once, best of three calls of ``steps`` steps (measure on an otherwise idle machine)."""
    import time as clock

    import jax

    method, setup, advance, state, params, (_, interval, floor) = _restored(folder, name, time)
    state = jax.block_until_ready(advance(state, params, FAR, 2, interval, floor))
    best = None
    for _ in range(3):
        w, c = clock.perf_counter(), clock.process_time()
        state = jax.block_until_ready(advance(state, params, FAR, steps, interval, floor))
        w, c = (clock.perf_counter() - w) / steps, (clock.process_time() - c) / steps
        best = (w, c) if best is None or w < best[0] else best
    return {"run": name, "at": float(state.t[0]), "particles": int(state.mpm.particles.active.sum()),
            "wall_s_per_step": best[0], "cpu_s_per_step": best[1]}


def _summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def _history(folder: Path) -> dict:
    from blastfsi.io.results import read_history

    return read_history(folder / "history.csv")


def _last_snapshot(folder: Path):
    files = sorted((folder / "fields").glob("member0_*.h5"))
    return h5py.File(files[-1], "r")


def gauge_metrics(summary: dict) -> list[dict]:
    keys = ("position", "region", "peak_overpressure", "impulse", "arrival_time", "positive_phase_duration")
    t0 = summary.get("remap_time", 0.0)  # arrival times are from the detonation, the run's time from the remap
    return [{k: g[k] for k in keys} | {"positive_phase_over": g["arrival_time"] - t0 + g["positive_phase_duration"]
                                        < summary["time"]} for g in summary["gauges"]]


def incident_pulse(h: dict, t0: float = 0.0) -> dict:
    """Peak, impulse and arrival of both gauges over the incident pulse only
    (:func:`blastfsi.diagnostics.profiles.incident_pulse`): to the first minimum of gauge 1 (the Eulerian
    side, undisturbed by the slab) after its peak. Later, gauge 2 (9 mm in front of the slab) also records
    the wave reflected by the slab, which gauge 1 never sees. Arrival times from the detonation (``t0``:
    the remap time, simulated time 0), like the summary's."""
    from blastfsi.diagnostics.profiles import incident_pulse as pulse

    out = pulse(h["time"], np.stack([h["gauge0_overpressure"], h["gauge1_overpressure"]], axis=1))
    for g in out["gauges"]:
        g["arrival_time"] = t0 + g["arrival_time"] if g["arrival_time"] is not None else None
    return {**out, "gauge2_over_gauge1": symmetry(out["gauges"])}


def reference_1d(t0: float, window_end: float, zones=(1600, 3200)) -> list[dict]:
    """The same cylindrical charge on the 1D Lagrangian solver (sharp products/air contact, graded zones),
    the blast at r = 125 mm (both gauges) before the slab's reflection: peak and arrival over the incident
    pulse window, at two zonings (finer ones fail at the burn front, docs/verification.md)."""
    from blastfsi import api
    from blastfsi.detonation.charge import _ambient, one_d_scenario
    from blastfsi.scenario import parse

    sc = parse(api.example_data("he-slab-2d"))  # the shipped charge, ambient air and gauges
    _, air, rho_a, p_a = _ambient(sc)
    gas = {"gamma": air.gamma, "pressure": p_a, "density": rho_a}
    r = float(np.hypot(*np.subtract(sc.output.gauges[0], sc.initial.center)))
    out = []
    for n in zones:
        # air zones 100 h wide (1.6 mm at 3200 zones), as the reference was measured
        res = api.run(one_d_scenario(sc.initial.explosive, sc.initial.radius, n, 100.0, 0.5, t0 + window_end, gas,
                                     [r], sc.output.arrival_fraction, j=1))
        g = res.summary["gauges"][0]
        out.append({"zones": n, "peak_overpressure": g["peak_overpressure"], "arrival_time": g["arrival_time"]})
    return out


def symmetry(gauges: list[dict]) -> dict:
    """Gauge 2 (MPM region) relative to gauge 1 (Eulerian region), the comparison of Figs. 10-11."""
    a, b = gauges
    return {key: b[key] / a[key] - 1.0 for key in ("peak_overpressure", "impulse", "arrival_time")}


def fig10_11(folder: Path, out: dict) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    out["bridge_width"] = {}
    for name in ("w2", "w5", "w8"):
        if not (folder / name / "summary.json").exists():
            continue
        s, h = _summary(folder / name), _history(folder / name)
        g = gauge_metrics(s)
        out["bridge_width"][name] = {"bridge_cells": s["bridge_cells"], "gauges": g, "gauge2_over_gauge1": symmetry(g),
                                     "incident_pulse": incident_pulse(h, s.get("remap_time", 0.0)),
                                     "steps": s["steps"], "wall_time": s["wall_time"], "budget": s["budget"],
                                     "structures": s.get("structures")}
        t = h["time"] * 1e6
        if name == "w5":
            axes[0].plot(t, h["gauge0_overpressure"] / 1e6, label="gauge 1 (-125, 250) mm, Eulerian")
            axes[0].plot(t, h["gauge1_overpressure"] / 1e6, "--", label="gauge 2 (125, 250) mm, MPM")
            pulse = out["bridge_width"][name]["incident_pulse"]
            ref = reference_1d(s.get("remap_time", 0.0), pulse["window_end"])
            out["reference_1d"] = {"what": "1D cylindrical Lagrangian run of the charge, r = 125 mm, to the end of "
                                           "the incident pulse window", "runs": ref}
            axes[0].axhline(ref[-1]["peak_overpressure"] / 1e6, color="0.5", lw=0.8,
                            label=f"1D Lagrangian peak ({ref[-1]['zones']} zones)")
        axes[1].plot(t, h["gauge1_overpressure"] / 1e6, label=f"gauge 2, w = {s['bridge_cells']}")
        if name == "w5":
            axes[1].plot(t, h["gauge0_overpressure"] / 1e6, "k:", label="gauge 1 (w = 5)")
    axes[0].set_title("Fig. 10: symmetric gauges, w = 5")
    axes[1].set_title("Fig. 11: bridge width")
    for ax in axes:
        ax.set_xlabel("time [us]"), ax.set_ylabel("overpressure [MPa]"), ax.grid(alpha=0.3), ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "he_slab_2d_gauges.png", dpi=120)
    plt.close(fig)


def resolution(folder: Path, out: dict) -> None:
    """The incident pulse at both gauges against the 1D reference: w = 5 and MPM everywhere (both its gauges
    read particles), at 2 mm and 1 mm."""
    ref = out.get("reference_1d", {}).get("runs", [{}])[-1].get("peak_overpressure")
    rows = {}
    for name in ("w5", "w5-1mm", "mpm-incident", "mpm-incident-1mm"):
        if not (folder / name / "summary.json").exists():
            continue
        s, h = _summary(folder / name), _history(folder / name)
        pulse = incident_pulse(h, s.get("remap_time", 0.0))
        rows[name] = {"dx": s["dx"], "gauges": pulse["gauges"], "gauge2_over_gauge1": pulse["gauge2_over_gauge1"],
                      "peak_over_reference_1d": [g["peak_overpressure"] / ref - 1.0 for g in pulse["gauges"]]
                      if ref else None, "steps": s["steps"], "wall_time": s["wall_time"]}
    out["resolution"] = rows


def _region_pressure(snap):
    g = snap["grid"]
    origin, spacing, shape = g.attrs["origin"], g.attrs["spacing"], g.attrs["shape"]
    x = origin[0] + (np.arange(shape[0]) + 0.5) * spacing[0]
    y = origin[1] + (np.arange(shape[1]) + 0.5) * spacing[1]
    p = np.asarray(g["pressure"]).reshape(shape[1], shape[0])  # (ny, nx): stored one row per cell, x fastest
    cols = (x > REGION_X[0]) & (x < REGION_X[1])
    return x[cols], y, p[:, cols], float(g.attrs["time"])


def fig12(folder: Path, out: dict) -> None:
    c, m = folder / "cfdmp-32.5us", folder / "mpm-32.5us"
    if not ((c / "summary.json").exists() and (m / "summary.json").exists()):
        return
    sc, sm = _summary(c), _summary(m)
    fig, axes = plt.subplots(1, 3, figsize=(9, 7), gridspec_kw={"width_ratios": [1, 1, 2.6]})
    panels = {}
    for label, folder_k in (("MPM everywhere", m), ("CFDMP", c)):
        with _last_snapshot(folder_k) as snap:
            x, y, p, t = _region_pressure(snap)
        panels[label] = (x, y, p, t)
    vmax = max(np.nanmax(p) for _, _, p, _ in panels.values()) / 1e6
    for ax, (label, (x, y, p, t)) in zip(axes, panels.items()):
        im = ax.pcolormesh(x * 1e3, y * 1e3, p / 1e6, vmin=0.0, vmax=vmax, shading="nearest", cmap="viridis")
        ax.set_title(f"{label}\nt = {t * 1e6:.1f} us", fontsize=9), ax.set_xlabel("x [mm]"), ax.set_aspect("equal")
        ax.set_xticks([110, 160])
    axes[0].set_ylabel("y [mm]")
    axes[1].set_yticklabels([])
    fig.colorbar(im, ax=axes[:2], label="pressure [MPa]", location="bottom", shrink=0.9)
    (xm, y, pm, _), (xc, _, pc, _) = panels["MPM everywhere"], panels["CFDMP"]
    row = np.argmin(np.abs(y - 0.25))
    ax = axes[2]
    ax.plot(xm * 1e3, pm[row] / 1e6, label="MPM everywhere")
    ax.plot(xc * 1e3, pc[row] / 1e6, "--", label="CFDMP")
    ax.set_xlabel("x [mm]"), ax.set_ylabel("pressure [MPa] at y = 250 mm"), ax.legend(), ax.grid(alpha=0.3)
    fig.savefig(HERE / "he_slab_2d_fig12.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    both = np.isfinite(pm) & np.isfinite(pc)
    out["fig12"] = {
        "time": FIG12_TIME,
        "steps": {"cfdmp": sc["steps"], "mpm_everywhere": sm["steps"]},
        "wall_time_of_the_runs": {"cfdmp": sc.get("wall_time"), "mpm_everywhere": sm.get("wall_time")},
        "max_pressure_region": {"cfdmp": float(np.nanmax(pc)), "mpm_everywhere": float(np.nanmax(pm))},
        "mean_abs_difference_over_mean_pressure": float(np.mean(np.abs(pm - pc)[both]) / np.mean(pc[both])),
    }
    if (folder / "step_cost.json").exists():
        cost = {c["run"]: c for c in json.loads((folder / "step_cost.json").read_text())}
        c_c, c_m = cost["cfdmp-32.5us"]["wall_s_per_step"], cost["mpm-32.5us"]["wall_s_per_step"]
        out["fig12"]["step_cost"] = list(cost.values())
        out["fig12"]["estimated_wall_time_ratio_mpm_over_cfdmp"] = sm["steps"] * c_m / (sc["steps"] * c_c)


def slab(folder: Path, out: dict) -> None:
    f = folder / "w5"
    if not (f / "summary.json").exists():
        return
    with _last_snapshot(f) as snap:
        P = snap["particles"]
        on = np.asarray(P["structure"]) > 0.5
        x = np.asarray(P["coordinates"])[on]
        damage = np.asarray(P["damage"])[on]
        s = np.asarray(P["stress"])[on].reshape(-1, 3, 3)
        t = float(P.attrs["time"])
    pressure = -np.trace(s, axis1=1, axis2=2) / 3.0
    dev = s + pressure[:, None, None] * np.eye(3)
    mises = np.sqrt(1.5 * np.sum(dev * dev, axis=(1, 2)))
    fig, axes = plt.subplots(1, 3, figsize=(12, 6), sharey=True)
    for ax, (value, label, cmap) in zip(axes, ((damage, "damage", "magma"), (pressure / 1e6, "pressure [MPa]", "coolwarm"),
                                               (mises / 1e6, "von Mises stress [MPa]", "viridis"))):
        sc = ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=value, s=4, cmap=cmap)
        fig.colorbar(sc, ax=ax, label=label)
        ax.set_xlabel("x [mm]"), ax.set_aspect("equal")
    axes[0].set_ylabel("y [mm]")
    fig.suptitle(f"he-slab-2d (w = 5): concrete slab at t = {t * 1e6:.0f} us")
    fig.tight_layout()
    fig.savefig(HERE / "he_slab_2d_slab.png", dpi=120)
    plt.close(fig)
    summary = _summary(f)["structures"]
    front = x[:, 0] < np.median(x[:, 0])
    cracked = damage >= 0.5
    out["slab"] = {"time": t, **summary,
                   "damaged_particles": int(cracked.sum()), "particles": int(on.sum()),
                   "damaged_in_front_half": int((cracked & front).sum()),
                   "damaged_in_back_half": int((cracked & ~front).sum()),
                   "damaged_y_range": ([float(x[cracked, 1].min()), float(x[cracked, 1].max())] if cracked.any()
                                       else None),
                   "max_pressure": float(pressure.max()), "max_von_mises": float(mises.max())}


def figures(folder: Path) -> None:
    out: dict = {}
    fig10_11(folder, out)
    resolution(folder, out)
    fig12(folder, out)
    slab(folder, out)
    (HERE / "he_slab_2d.json").write_text(json.dumps(out, indent=1))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    what, folder = sys.argv[1], Path(sys.argv[2])
    if what == "run":
        run(folder, sys.argv[3:] or list(RUNS))
    elif what == "field-at":  # field-at DIR RUN TIME OUT
        field_at(folder, sys.argv[3], float(sys.argv[4]), Path(sys.argv[5]))
    elif what == "step-cost":  # step-cost DIR: both Fig. 12 configurations, to DIR/step_cost.json
        costs = [step_cost(folder, "cfdmp-32.5us", 2.0e-5), step_cost(folder, "mpm-32.5us", None)]
        (folder / "step_cost.json").write_text(json.dumps(costs, indent=1))
        print(json.dumps(costs, indent=1))
    elif what == "figures":
        figures(folder)
    else:
        raise SystemExit(__doc__)
