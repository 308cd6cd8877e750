"""Reproduce seed 002's verification figures and write PNG + JSON here.

    python docs/figures/make_002_figures.py fig2|fig5|light|sedov|convergence|all

Every number in docs/verification.md comes from the JSON files this writes.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from blastfsi import simulation  # noqa: E402
from blastfsi.diagnostics import front_position, l1_relative_error, zone_profile  # noqa: E402
from blastfsi.exact import shock  # noqa: E402
from blastfsi.exact.sedov import PlanarSedov  # noqa: E402
from blastfsi.lagrangian1d.plate_problem import clean_window  # noqa: E402

HERE = Path(__file__).parent
P0, RHO0 = 1.048e5, 1.225  # 002 Sec. 3 air (ERRATA 002-7)


def uniform(ratio, length, cells, end, plate, samples=2001):
    return {"name": "fig", "incident": {"profile": "uniform", "overpressure": ratio * P0}, "plate": plate,
            "domain": {"length": length}, "grid": {"cells": cells}, "time": {"end": end},
            "output": {"history_samples": samples, "fields": 0, "plots": False}}


def clean_fraction(ratio):
    """(arrival time, clean window) per metre of domain for a uniform shock."""
    sc = simulation.parse(uniform(ratio, 1.0, 10, 1.0, {"fixed": True}))
    return 1.0 / float(shock.incident_shock(ratio * P0, P0, RHO0).shock_speed), clean_window(sc, ratio * P0)


def dump(name, payload):
    (HERE / f"{name}.json").write_text(json.dumps(payload, indent=2) + "\n")
    print(json.dumps(payload, indent=2))


def fig2(cells=5000, length=8.0):
    """Rigid-wall reflection coefficient vs Eq. (25), 002 Fig. 2."""
    ratios = np.logspace(-2, 3, 11)
    rows = []
    for r in ratios:
        arrive, clean = clean_fraction(r)
        end = length * (arrive + 0.95 * clean)
        res = simulation.run(uniform(r, length, cells, end, {"fixed": True}))
        cr, th = res.summary["reflection_coefficient"], shock.reflection_coefficient(r * P0, P0)
        rows.append({"ps_over_p0": r, "C_R_sim": cr, "C_R_eq25": float(th), "rel_error": cr / th - 1.0,
                     "peak_over_theory": res.summary["peak_overpressure"] / (th * r * P0)})
    fig, ax = plt.subplots(figsize=(6, 4))
    fine = np.logspace(-2.5, 3.5, 200)
    ax.semilogx(fine, shock.reflection_coefficient(fine * P0, P0), "k-", label="Eq. (25)")
    ax.semilogx(ratios, [x["C_R_sim"] for x in rows], "o", mfc="none", label=f"vNR, {cells} zones")
    ax.set_xlabel("$p_s/p_0$"), ax.set_ylabel("$C_R = p_r/p_s$"), ax.grid(alpha=0.3), ax.legend()
    fig.tight_layout(), fig.savefig(HERE / "fig2_reflection.png", dpi=130)
    dump("fig2_reflection", {"cells": cells, "length_m": length, "rows": rows,
                             "max_abs_error_le_100": max(abs(x["rel_error"]) for x in rows if x["ps_over_p0"] <= 100),
                             "max_abs_error_gt_100": max(abs(x["rel_error"]) for x in rows if x["ps_over_p0"] > 100)})


def fig5_batch(cells, end=2e-3, ratios=(0.1, 1.0, 4.49, 10.0, 100.0), betas=np.logspace(-2, 4, 13)):
    """One batched call: every intensity gets the domain length that makes its
    clean window (0.9 of it) end at the common end time."""
    batch = []
    for r in ratios:
        arrive, clean = clean_fraction(r)
        length = end / (arrive + 0.9 * clean)
        batch += [uniform(r, length, cells, end, {"beta_s": float(b)}, samples=201) for b in betas]
    return ratios, betas, batch


def fig5(cells=1000):
    ratios, betas, batch = fig5_batch(cells)
    t0 = time.perf_counter()
    res = simulation.run(batch)
    wall = time.perf_counter() - t0
    out, fig, ax = {}, *plt.subplots(figsize=(6.5, 4.5))
    z = np.logspace(-3, 4.5, 300)
    ax.loglog(z, shock.impulse_ratio_uniform(z, 1.0), "k-", label="Eq. (29)")
    for i, r in enumerate(ratios):
        summ = res.summaries[i * len(betas):(i + 1) * len(betas)]
        fr = shock.f_R(r * P0, P0, RHO0)
        sim = np.array([s["impulse_ratio"] for s in summ])
        theory = np.array([s["impulse_ratio_theory"] for s in summ])
        qs = []
        for s, setup in zip(summ, res.setups[i * len(betas):(i + 1) * len(betas)]):
            m, ti = setup.theory.plate_areal_mass, setup.theory.duration
            v = shock.quasi_steady_plate(r * P0, ti, m, P0, RHO0)
            qs.append(m * v / (s["reflection_coefficient_theory"] * r * P0 * ti))
        qs = np.array(qs)
        dev = sim / theory - 1.0
        out[str(r)] = {"f_R": float(fr), "f_R_eq30": float(shock.f_R_eq30(r * P0, P0)), "beta_s": betas.tolist(),
                       "impulse_ratio_sim": sim.tolist(), "impulse_ratio_eq29": theory.tolist(),
                       "impulse_ratio_quasi_steady": qs.tolist(),
                       "worst_deviation_eq29": float(dev[np.argmax(np.abs(dev))]),
                       "worst_at_beta_s": float(betas[np.argmax(np.abs(dev))]),
                       "worst_deviation_quasi_steady": float(np.max(np.abs(sim / qs - 1.0)))}
        ax.loglog(betas / fr, sim, "o", mfc="none", label=f"$p_s/p_0$ = {r:g}")
    ax.set_xlabel(r"$\beta_s/f_R$"), ax.set_ylabel(r"$I_p/(C_R I_i)$"), ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8), fig.tight_layout(), fig.savefig(HERE / "fig5_impulse.png", dpi=130)
    dump("fig5_impulse", {"cells": cells, "members": len(batch), "wall_time_s": wall, "intensities": out})


def light(cells=5000, length=8.0, ti=1e-3):
    """Sec. 3.2 light-plate limit at p_s/p0 = 4.49."""
    r, betas = 4.49, [67.3, 673.0, 6730.0]
    arrive, clean = clean_fraction(r)
    end = length * arrive + ti
    assert ti < length * clean
    res = simulation.run([uniform(r, length, cells, end, {"beta_s": b}) for b in betas])
    ufs = float(shock.free_surface_velocity(r * P0, P0, RHO0))
    s0 = shock.incident_shock(r * P0, P0, RHO0)
    # plate velocity implied by the printed Eq. (30): u = f_R C_R p_s / (rho_s U_s)
    u_eq30 = float(shock.f_R_eq30(r * P0, P0) * shock.reflection_coefficient(r * P0, P0) * r * P0
                   / (s0.density * s0.shock_speed))
    paper = [1006.5, 1005.6, 1005.5]  # 002 Sec. 3.2
    dump("light_plate", {"cells": cells, "t_i": ti, "free_surface_velocity": ufs, "f_R_eq30_velocity": u_eq30,
                         "rows": [{"beta_s": b, "u_p_sim": s["plate_velocity"], "u_p_paper": p,
                                   "sim_over_free_surface": s["plate_velocity"] / ufs}
                                  for b, s, p in zip(betas, res.summaries, paper)]})


def sedov(cells=10000, length=100.0):
    """Sec. 3.4: front 22.5 m -> 81.2 m against the exact solution (ambient
    pressure 1e-6 p0, so the strong-shock solution is the exact reference)."""
    blast = PlanarSedov(5e8, RHO0)
    t0, t1 = blast.time_at_front(22.5), blast.time_at_front(81.2)
    data = {"name": "sedov-verify", "gas": {"pressure": 1e-6 * P0},
            "incident": {"profile": "sedov", "energy": 5e8, "front_position": 22.5}, "plate": {"fixed": True},
            "domain": {"length": length}, "grid": {"cells": cells}, "time": {"end": float(t1 - t0)},
            "output": {"history_samples": 11, "fields": 0, "plots": False}}
    res = simulation.run(data)
    xc, dx, p = zone_profile(res.state, 0, 1.4)
    p_exact = np.where(xc <= 81.2, blast(xc, t1)[2], 1e-6 * P0)
    peak = np.max(p)
    front = front_position(xc, p, 0.5 * peak)  # half-peak crossing on the front
    l1 = l1_relative_error(p, p_exact, dx)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(xc, p / 1e6, label="vNR")
    ax.plot(xc, p_exact / 1e6, "k--", label="exact (Sedov)")
    ax.set_xlim(0, 90), ax.set_xlabel("x [m]"), ax.set_ylabel("p [MPa]"), ax.legend(), ax.grid(alpha=0.3)
    fig.tight_layout(), fig.savefig(HERE / "sedov_profile.png", dpi=130)
    payload = {"cells": cells, "front_exact_m": 81.2, "front_sim_m": front, "front_error_m": front - 81.2,
               "front_error_rel": (front - 81.2) / (81.2 - 22.5), "pressure_L1_error_rel": l1,
               "peak_over_exact_peak": float(peak / np.max(p_exact))}
    # plates 2 mm and 20 mm at 32 m (the plate1d-sedov example)
    from blastfsi.cli import example_data

    ex = simulation.run(example_data("plate1d-sedov"))
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for hist, m in zip(ex.histories, ex.members):
        lab = f"h = {m['plate.thickness'] * 1e3:g} mm"
        axes[0].plot(hist["time"] * 1e3, hist["plate_overpressure"] / 1e6, label=lab)
        axes[1].plot(hist["time"] * 1e3, hist["plate_displacement"], label=lab)
        axes[2].plot(hist["time"] * 1e3, hist["plate_velocity"], label=lab)
    for ax, lab in zip(axes, ("plate overpressure [MPa]", "displacement [m]", "velocity [m/s]")):
        ax.set_xlabel("t [ms] (from front at 22.5 m)"), ax.set_ylabel(lab), ax.grid(alpha=0.3), ax.legend()
    fig.tight_layout(), fig.savefig(HERE / "sedov_plates.png", dpi=130)
    keys = ("plate_velocity", "plate_displacement", "plate_impulse", "peak_overpressure")
    payload["plates"] = [{"thickness": m["plate.thickness"], **{k: s[k] for k in keys}}
                         for m, s in zip(ex.members, ex.summaries)]
    dump("sedov", payload)


def convergence(ratio=4.49, beta=1.0, length=8.0, ti=1e-3, cells=(1250, 2500, 5000, 10000)):
    """Transmitted impulse at beta_s = 1 under refinement; observed order from the three finest."""
    arrive, _ = clean_fraction(ratio)
    end = length * arrive + ti
    imp = []
    for n in cells:
        res = simulation.run(uniform(ratio, length, n, end, {"beta_s": beta}, samples=11))
        imp.append(res.summary["plate_impulse"])
    i1, i2, i3 = imp[-3:]
    order = float(np.log(abs(i1 - i2) / abs(i2 - i3)) / np.log(2.0))
    extrap = i3 + (i3 - i2) / (2**order - 1)
    dump("convergence", {"ps_over_p0": ratio, "beta_s": beta, "cells": list(cells), "plate_impulse": imp,
                         "observed_order": order, "richardson_impulse": float(extrap),
                         "rel_error_vs_richardson": [float(i / extrap - 1) for i in imp]})


def exponential_case(ratio, plate, cells=3000, length=30.0, decay=2.0, standoff=1.0):
    """An exponential pulse run until 8 decay times after nominal arrival; returns (data, t_i)."""
    s = shock.incident_shock(ratio * P0, P0, RHO0)
    ti = decay / float(s.shock_speed)
    end = standoff / float(s.shock_speed) + 8 * ti
    data = {"name": "fig7", "incident": {"profile": "exponential", "overpressure": ratio * P0, "decay_length": decay,
                                         "standoff": standoff}, "plate": plate, "domain": {"length": length},
            "grid": {"cells": cells}, "time": {"end": end},
            "output": {"history_samples": 401, "fields": 0, "plots": False}}
    return data, ti


def fig7(ratios=(0.1, 2.0), betas=np.logspace(-1.5, 2.5, 9)):
    """002 Fig. 7: exponential pulses against Eq. (32). gamma_R (not in the seed) is
    measured by a rigid-wall run of the same pulse; I_p is the plate's maximum
    momentum (Taylor's definition: afterwards the back pressure decelerates it)."""
    out, fig, ax = {}, *plt.subplots(figsize=(6.5, 4.5))
    for r in ratios:
        wall_data, ti = exponential_case(r, {"fixed": True})
        incident_impulse = r * P0 * ti
        gamma_r = simulation.run(wall_data).summary["plate_impulse"] / incident_impulse
        s = shock.incident_shock(r * P0, P0, RHO0)
        masses = s.density * s.shock_speed * ti / betas
        res = simulation.run([exponential_case(r, {"areal_mass": float(m)})[0] for m in masses])
        sim = np.array([x["plate_impulse_max"] for x in res.summaries]) / incident_impulse
        theory = shock.impulse_ratio_exponential(betas, gamma_r, shock.reflection_coefficient(r * P0, P0),
                                                 shock.f_R(r * P0, P0, RHO0))
        dev = sim / theory - 1.0
        out[str(r)] = {"gamma_R_measured": gamma_r, "beta_s": betas.tolist(), "Ip_over_Ii_sim": sim.tolist(),
                       "Ip_over_Ii_eq32": theory.tolist(), "deviation": dev.tolist(),
                       "worst_deviation": float(dev[np.argmax(np.abs(dev))])}
        line, = ax.loglog(betas, theory, "-", label=f"Eq. (32), $p_i/p_0$ = {r:g}")
        ax.loglog(betas, sim, "o", mfc="none", color=line.get_color())
    ax.set_xlabel(r"$\beta_s$ (nominal)"), ax.set_ylabel(r"$I_p/I_i$"), ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8), fig.tight_layout(), fig.savefig(HERE / "fig7_exponential.png", dpi=130)
    dump("fig7_exponential", {"cells": 3000, "decay_length_m": 2.0, "standoff_m": 1.0, "intensities": out})


if __name__ == "__main__":
    jobs = {"fig2": fig2, "fig5": fig5, "light": light, "sedov": sedov, "convergence": convergence, "fig7": fig7}
    for name in (jobs if sys.argv[1:] == ["all"] else sys.argv[1:]):
        jobs[name]()
