"""Tier 3: a clamped-clamped elastic beam (plane strain) under a suddenly applied uniform pressure, through
the driver (``[[bodies.supports]]``, ``output.tracers``), against beam theory.

Steel beam (``elastic-steel``: E = 207 GPa, nu = 0.3, rho = 7850 kg/m^3), span L = 100 mm between the
supports, thickness t = 10 mm, clamped over 5 mm at each end, q = 1 MPa on its top face from t = 0.
Static midspan deflection, Timoshenko beam in plane strain (E' = E / (1 - nu^2), shear coefficient 5/6;
Timoshenko & Gere, Mechanics of Materials, clamped-clamped beam under uniform load, plus the shear term):

    w = q L^4 / (384 E' I) + q L^2 / (8 kappa G t) = 13.74 + 1.89 = 15.62 um,   I = t^3 / 12.

Under a step load a linear structure oscillates about its static deflection: the time average over whole
periods of the fundamental mode is w, the first peak 2 w (dynamic load factor 2; the higher symmetric modes
add ~1 % at midspan). Measured (2026-12-03, linear shape functions, 2 x 2 particles per cell, cfl 0.5):
mean / w = 0.909 / 0.995 / 0.9986 at h = 2 / 1 / 0.5 mm; peak / mean 2.02 at 1 mm; the period converges
to 1.074 / 1.076 x the Euler-Bernoulli one at 1 / 0.5 mm (shear and rotary inertia lengthen it).
"""
import numpy as np
import pytest

import blastfsi

L, T, CLAMP = 0.1, 0.01, 0.005
E, NU, RHO, Q = 207e9, 0.3, 7850.0, 1e6
E_PLANE = E / (1.0 - NU ** 2)
SHEAR = E / (2.0 * (1.0 + NU))
W_STATIC = Q * L ** 4 / (384.0 * E_PLANE * T ** 3 / 12.0) + Q * L ** 2 / (8.0 * (5.0 / 6.0) * SHEAR * T)
# Euler-Bernoulli fundamental period of the clamped-clamped beam (lambda = 4.730); shear and rotary inertia
# lengthen it a few per cent at L / t = 10, so it only sizes the run
PERIOD_EB = 2.0 * np.pi / (4.730 ** 2 * np.sqrt(E_PLANE * T ** 3 / 12.0 / (RHO * T * L ** 4)))


def beam(h, periods, samples):
    cells = int(round((L + 2 * CLAMP) / h))
    return {"method": "mpm", "name": "clamped-beam",
            "grid": {"lower": [0.0, 0.0], "upper": [L + 2 * CLAMP, 0.03], "cells": cells},
            "bodies": [{"lower": [0.0, 0.01], "upper": [L + 2 * CLAMP, 0.02], "material": "elastic-steel",
                        "top_traction": -Q,
                        "supports": [{"lower": [0.0, 0.0], "upper": [CLAMP, 0.03]},
                                     {"lower": [L + CLAMP, 0.0], "upper": [L + 2 * CLAMP, 0.03]}]}],
            "numerics": {"q_quadratic": 0.0, "q_linear": 0.0},
            "time": {"end": periods * PERIOD_EB},
            "output": {"tracers": [[CLAMP + L / 2, 0.015], [0.5 * CLAMP, 0.015]], "history_samples": samples,
                       "fields": 0, "plots": False}}


def mean_over_whole_periods(t, w):
    """Time average of w between its first and last deepest troughs (whole periods of the fundamental)."""
    troughs = [i for i in range(1, len(w) - 1) if w[i] < w[i - 1] and w[i] <= w[i + 1] and w[i] < 0.5 * w.min()]
    assert len(troughs) >= 2, "the run must span at least one whole period"
    i0, i1 = troughs[0], troughs[-1]
    return np.trapezoid(w[i0:i1 + 1], t[i0:i1 + 1]) / (t[i1] - t[i0])


def test_clamped_beam_deflects_as_beam_theory_says():
    res = blastfsi.run(beam(1e-3, 2.3, 801))
    h, s = res.history, res.summary
    w = -h["tracer0_displacement_y"]
    mean = mean_over_whole_periods(h["time"], -w)
    assert -mean == pytest.approx(W_STATIC, rel=0.02)  # 0.995 measured; 0.909 at h = 2 mm
    assert s["tracer_peak_displacement"][0][1] / mean == pytest.approx(2.0, abs=0.05)  # dynamic load factor
    # the clamped particles do not move at all; the clamp does no work, so the energy balance stays closed
    assert s["tracer_displacement"][1] == [0.0, 0.0] and s["tracer_peak_displacement"][1] == [0.0, 0.0]
    assert abs(s["energy_balance_relative"]) < 1e-3  # -1.2e-4 measured


@pytest.mark.slow  # ~2 min
def test_dense_history_sampling_does_not_destabilise_the_beam():
    """0.5 mm cells, 2001 history samples: when only the step that overshot a sample time was shortened,
    this run's kinetic energy grew 1e3-fold after ~12 000 steps (blastfsi.timeloop); now the steps are equal."""
    res = blastfsi.run(beam(5e-4, 3.2, 2001))
    h = res.history
    assert abs(res.summary["energy_balance_relative"]) < 1e-3
    assert np.max(h["kinetic_energy"][len(h["time"]) // 2:]) < 1.5 * np.max(h["kinetic_energy"][:len(h["time"]) // 2])
