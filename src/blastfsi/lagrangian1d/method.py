"""The ``lagrangian1d`` method behind the driver's face (:class:`blastfsi.method.Method`):
set-up from :mod:`blastfsi.lagrangian1d.plate_problem` (``[incident]``) or
:mod:`blastfsi.lagrangian1d.charge_problem` (``[charge]``), the vNR scheme of
:mod:`blastfsi.lagrangian1d.scheme`, the plate/gauge (or charge/KB) summary and plots."""
from __future__ import annotations

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi.detonation.cj import chapman_jouguet
from blastfsi.detonation.kb_compare import compare
from blastfsi.lagrangian1d import charge_problem as detonation
from blastfsi.lagrangian1d import plate_problem as plate1d
from blastfsi.lagrangian1d import scheme
from blastfsi.lagrangian1d.scenario import Scenario
from blastfsi.method import Polyline, register
from blastfsi.scenario import device_count

# blastfsi.plotting (matplotlib) is imported inside the plotting functions only: it loads when plots are drawn.

CJ_WINDOW = (0.5, 0.9)  # charge-radius fractions over which the burn front's pressure is averaged


def _geometry(setup) -> int:
    return getattr(setup, "geometry", 0)


def _optional(kind, setup, name: str, dtype):
    """The setup's ``name`` fields as a ``kind`` of arrays, or None where it has none (plate problems)."""
    fields = getattr(setup, name, None)
    return None if fields is None else kind(*(jnp.asarray(f, dtype) for f in fields))


class Lagrangian1D:
    name = "lagrangian1d"
    scenario_model = Scenario

    def build(self, sc: Scenario) -> plate1d.Setup | detonation.Setup:
        return plate1d.build(sc) if sc.charge is None else detonation.build(sc)

    def initial_state(self, setup, sc: Scenario, n_samples: int, dtype) -> scheme.State:
        def arr(values):
            return jnp.asarray(values, dtype)

        return scheme.initial_state(arr(setup.x), arr(setup.v), arr(setup.e), arr(setup.zone_mass),
                                    setup.numerics.gamma, n_samples, setup.gauges.size, setup.boundaries.right_mass,
                                    zones=_optional(scheme.Zones, setup, "zones", dtype), geometry=_geometry(setup))

    def params(self, setup, dtype) -> scheme.Params:
        def arr(values):
            return jnp.asarray(values, dtype)

        threshold = setup.arrival_fraction * setup.ambient_pressure
        return scheme.Params(num=jax.tree_util.tree_map(arr, setup.numerics),
                             bc=jax.tree_util.tree_map(arr, setup.boundaries),
                             gauges=scheme.Gauges(arr(setup.gauges), arr(setup.ambient_pressure), arr(threshold)),
                             x_right0=arr(setup.x[-1]), zones=_optional(scheme.Zones, setup, "zones", dtype),
                             afterburn=_optional(scheme.Afterburn, setup, "afterburn", dtype))

    def static(self, setup, sc: Scenario) -> scheme.Static:
        return scheme.Static(setup.left_velocity_set, setup.right_fixed, _geometry(setup), member_devices(sc))

    def advance(self, state, params, static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        return scheme.advance(state, params, static, t_stop, max_steps, sample_interval, dt_floor_fraction)

    def history_columns(self, setup: plate1d.Setup, sc: Scenario) -> tuple:
        return scheme.history(len(sc.output.gauges)).columns

    def snapshot(self, state: scheme.State, setup) -> Polyline:
        j = _geometry(setup)
        zones = _optional(scheme.Zones, setup, "zones", np.asarray(state.e).dtype)
        zones = scheme.ideal_gas_zones(setup.numerics.gamma, state.e.size, state.e.dtype) if zones is None else zones
        rho = state.zone_mass / scheme.zone_volume(state.x, j)
        cells = {"density": rho,
                 "pressure": np.asarray(scheme.eos_pressure(rho, state.e, state.t, zones)) + state.q,
                 "internal_energy": state.e, "viscous_pressure": state.q}
        if hasattr(setup, "explosive_zones"):
            cells["products_fraction"] = (np.arange(state.e.size) < setup.explosive_zones).astype(state.e.dtype)
            cells["burn_fraction"] = np.asarray(scheme.burn_fraction(state.t, zones))
        return Polyline(nodes=state.x, node_fields={"velocity": state.v}, cell_fields=cells)

    def locate_fault(self, state: scheme.State, setup: plate1d.Setup) -> str:
        x = state.x
        zone = int(scheme.first_fault(state))
        if zone >= 0:
            return (f"zone {zone} at x = {0.5 * (x[zone] + x[zone + 1]):.6g} m "
                    "(NaN, tangled zone or non-positive internal energy)")
        dt = np.asarray(scheme.zone_dt(np.diff(x), state.a, state.v, setup.numerics))
        zone = int(np.argmin(dt))
        return (f"zone {zone} at x = {0.5 * (x[zone] + x[zone + 1]):.6g} m (width {x[zone + 1] - x[zone]:.3g} m) "
                f"limits the step to {dt[zone]:.3g} s")

    def summary(self, sc: Scenario, setup, hist: dict, state: scheme.State) -> dict:
        if sc.charge is not None:
            return charge_summary(sc, setup, hist, state)
        theory = setup.theory
        fixed = sc.plate.fixed
        v_plate = 0.0 if fixed else float(state.v[-1])
        impulse = float(state.face_impulse) if fixed else float(state.v[-1]) * theory.plate_areal_mass
        cr_theory = theory.reflection_coefficient_theory
        incident_impulse = theory.incident_impulse
        energy = float(scheme.total_energy(state, setup.boundaries))
        out = {
            "plate_velocity": v_plate,
            "plate_displacement": float(state.x[-1] - setup.x[-1]),
            "plate_impulse": impulse,
            "plate_impulse_max": float(np.max(hist["plate_impulse"])),
            "peak_overpressure": _finite(state.peak_face_overpressure),
            "beta_s": theory.beta_s,
            "reflection_coefficient_theory": cr_theory,
            "impulse_ratio_theory": theory.impulse_ratio_theory,
            "impulse_ratio": impulse / (cr_theory * incident_impulse) if cr_theory and incident_impulse else None,
            "plate_areal_mass": theory.plate_areal_mass,
            "energy_error_relative": float(hist["energy_error"][-1]) / energy,
        }
        if sc.output.gauges:
            out["gauge_positions"] = list(sc.output.gauges)
            out["gauge_peak_overpressure"] = [_finite(v) for v in state.gauge_peak]
            out["gauge_impulse"] = [_finite(v) for v in state.gauge_impulse]
        if sc.incident.profile == "uniform":
            out["reflection_coefficient"] = _measured_reflection(hist, theory)
            out.update(arrival_time=theory.arrival_time, duration=theory.duration,
                       clean_duration=theory.clean_duration, f_R=theory.f_R, f_R_eq30=theory.f_R_eq30,
                       free_surface_velocity=theory.free_surface_velocity)
            if theory.duration > theory.clean_duration:
                out["warning"] = (f"waves re-reflected by the piston reach the plate {theory.clean_duration:.4g} s "
                                  f"after shock arrival, before the end of the run ({theory.duration:.4g} s after "
                                  "arrival); lengthen domain.length or shorten time.end")
        if sc.incident.profile == "sedov":
            out["explosion_time"] = theory.explosion_time
        return out

    def plots(self, folder: Path, sc: Scenario, setups: list, histories: list[dict], members: list[dict],
              finals: list) -> None:
        from blastfsi.plotting import gauge_histories, plate_histories

        if sc.charge is not None:
            if sc.output.gauges:
                gauge_histories(folder / "gauges.png", histories, sc.output.gauges)
                if sc.domain.geometry == "spherical" and sc.charge.explosive == "tnt":
                    from blastfsi.plotting.kb import kb_gauge_histories

                    mass = detonation.charge_size(sc)[1]
                    kb_gauge_histories(folder / "gauges_kb.png", histories[0], sc.output.gauges, mass, "free-air")
            return
        plate_histories(folder / "plate_histories.png", histories, members)
        if sc.output.gauges:
            gauge_histories(folder / "gauges.png", histories, sc.output.gauges)


def member_devices(sc: Scenario) -> int:
    """numerics.devices as a number of devices (ScenarioError naming the key where JAX sees fewer): the
    ensemble's members are spread over them (the driver checks that they divide the members)."""
    return device_count(sc.numerics.devices)


def burn_front_pressure(setup, state: scheme.State) -> float:
    """Mean over the explosive zones with centres in CJ_WINDOW x R of the pressure F p_E (000 Eq. 52)
    each zone has when its burn completes (F reaches 1): the end of the programmed burn's reaction
    zone, which a steady wave at D ~ D_CJ leaves at the CJ point."""
    x0 = setup.x
    centre = 0.5 * (x0[1:] + x0[:-1])[: setup.explosive_zones] / setup.charge.charge_radius
    sel = (centre >= CJ_WINDOW[0]) & (centre <= CJ_WINDOW[1])
    return float(np.mean(np.asarray(state.zone_burnt)[: setup.explosive_zones][sel]))


def charge_summary(sc: Scenario, setup, hist: dict, state: scheme.State) -> dict:
    """Charge, CJ check (burn front pressure vs the CJ pressure of the JWL set), energy budget and,
    per gauge, peak overpressure, positive impulse, arrival time (blast_maps definitions) beside
    the Kingery-Bulmash values for a spherical TNT charge."""
    charge = setup.charge
    hx = detonation.charge_explosive(sc)
    cj = chapman_jouguet(hx.eos_params(), hx.E0)
    energy = float(scheme.total_energy(state, setup.boundaries))
    burnt = float(state.t) >= charge.charge_radius / charge.detonation_velocity
    front = burn_front_pressure(setup, state) if burnt else None
    out = {
        "charge_mass": charge.charge_mass, "charge_radius": charge.charge_radius,
        "charge_zone_width": charge.charge_zone_width, "geometry": charge.geometry,
        "detonation_velocity": charge.detonation_velocity,
        "cj_pressure": cj.pressure, "burn_front_pressure": front,
        "burn_front_pressure_ratio": None if front is None else front / cj.pressure,
        "energy_error_relative": float(hist["energy_error"][-1]) / energy,
        # afterburning energy released by the end of the run [J, J/m or J/m^2 like charge_mass]; 0 without
        "afterburn_energy_released": charge.measure * float(state.afterburn_released),
        "afterburn_energy_total": charge.afterburn_energy,  # charge.afterburn_energy x charge volume
    }
    t = float(state.t)
    gauges = []
    for k in range(len(sc.output.gauges)):
        arrival = float(state.gauge_arrival[k])
        seen = np.isfinite(arrival)
        gauges.append({"position": float(sc.output.gauges[k]),
                       "peak_overpressure": _finite(state.gauge_peak[k]),
                       "impulse": float(state.gauge_positive_impulse[k]),
                       "arrival_time": arrival if seen else None,
                       "positive_phase_duration": (min(float(state.gauge_end[k]), t) - arrival) if seen else None})
    if gauges and sc.domain.geometry == "spherical" and sc.charge.explosive == "tnt":
        gauges = compare(gauges, [g["position"] for g in gauges], charge.charge_mass, "free-air")
    out["gauges"] = gauges
    return out


def _finite(value):
    """A float for JSON; None where nothing was measured (a gauge never inside the gas)."""
    value = float(value)
    return value if np.isfinite(value) else None


def _measured_reflection(hist: dict, theory: plate1d.Theory):
    """Mean wall overpressure over the second half of the clean window, / p_s (002 Fig. 2)."""
    window = min(theory.duration, theory.clean_duration)
    t = hist["time"] - theory.arrival_time
    sel = (t >= 0.5 * window) & (t <= window)
    if not np.any(sel):
        return None
    return float(np.mean(hist["plate_overpressure"][sel]) / theory.incident_overpressure)


METHOD = register(Lagrangian1D())
