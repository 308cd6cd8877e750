"""The driver serves any registered method: a toy method registered here (exact
exponential decay on a 1D grid) runs through the same schema, ensembles, grid
snapshots, checkpoints/restart and fault reports as lagrangian1d; and the
time-step collapse stop of a real lagrangian1d run."""
from dataclasses import dataclass, field
from typing import ClassVar, Literal, NamedTuple, Optional

import jax.numpy as jnp
import numpy as np
import pytest
import tomli_w
from pydantic import Field, model_validator

from blastfsi import cli, method, simulation, timeloop
from blastfsi.exact import shock
from blastfsi.io.results import read_history
from blastfsi.scenario import ScenarioBase, ScenarioError, Strict, Sweep, gauge_points, parse
from conftest import P0, RHO0


# ------------------------------------------------------------------ a toy method: y' = -k(x) y, y(0) = 1
class DecayTable(Strict):
    rate: float = Field(gt=0.0, description="k at x = 0 [1/s]; k(x) = rate (1 + x)")
    cells: int = Field(8, ge=1, le=1000)
    collapse_time: Optional[float] = Field(None, gt=0.0, description="stable step cfl (T - t): collapses at T")


class DecaySweep(Sweep):
    TARGETS: ClassVar[dict[str, str]] = {"rate": "decay.rate"}
    rate: Optional[list[float]] = None


class DecayScenario(ScenarioBase):
    method: Literal["decay"] = "decay"
    decay: DecayTable
    sweep: Optional[DecaySweep] = None

    @model_validator(mode="after")
    def _gauges(self):
        gauge_points(self.output.gauges, 1, (0.0,), (1.0,))
        return self


@dataclass(frozen=True)
class DecaySetup:
    edges: np.ndarray
    rate: np.ndarray
    collapse_time: float
    cfl: float
    gauge_cells: tuple
    info: dict = field(default_factory=dict)

    @property
    def cells(self) -> int:
        return self.rate.size


class DecayState(NamedTuple):
    y: jnp.ndarray
    t: jnp.ndarray
    dt_prev: jnp.ndarray
    dt0: jnp.ndarray
    step: jnp.ndarray
    fault: jnp.ndarray
    hist: jnp.ndarray
    hist_next: jnp.ndarray


class Decay:
    name = "decay"
    scenario_model = DecayScenario

    def build(self, sc):
        edges = np.linspace(0.0, 1.0, sc.decay.cells + 1)
        centres = 0.5 * (edges[1:] + edges[:-1])
        cells = tuple(int(np.clip(np.searchsorted(edges, g) - 1, 0, centres.size - 1)) for g in sc.output.gauges)
        return DecaySetup(edges, sc.decay.rate * (1.0 + centres), sc.decay.collapse_time or np.inf,
                          sc.numerics.cfl, cells)

    def initial_state(self, setup, sc, n_samples, dtype):
        cols = len(self.history_columns(setup, sc))
        return DecayState(jnp.ones(setup.cells, dtype), **timeloop.clock(n_samples, cols, dtype))

    def params(self, setup, dtype):
        return (jnp.asarray(setup.rate, dtype), jnp.asarray(setup.collapse_time, dtype), jnp.asarray(setup.cfl, dtype))

    def static(self, setup, sc):
        return setup.gauge_cells

    def advance(self, state, params, static, t_stop, max_steps, sample_interval, dt_floor_fraction):
        rate, collapse, cfl = params
        return timeloop.run_until(
            state, t_stop, max_steps, sample_interval, dt_floor_fraction,
            stable_dt=lambda s: jnp.where(jnp.isfinite(collapse), cfl * (collapse - s.t), cfl / jnp.max(rate)),
            step=lambda s, dt: s._replace(y=s.y * jnp.exp(-rate * dt)),
            history_row=lambda s: decay_history(static, s).values(s.t.dtype))

    def history_columns(self, setup, sc):
        return decay_history(self.static(setup, sc)).columns

    def snapshot(self, state, setup):
        return method.Grid(edges=(setup.edges,), cell_fields={"density": state.y,
                                                              "velocity": np.zeros((setup.cells, 1))})

    def summary(self, sc, setup, history, state):
        return {"mean_final": float(np.mean(state.y))}

    def locate_fault(self, state, setup):
        return f"cell {int(np.argmin(state.y))}"

    def plots(self, folder, sc, setups, histories, members, finals):
        (folder / "decay.txt").write_text("no plot\n")


def decay_history(gauge_cells, s=None) -> timeloop.Row:
    """The history row as named entries: its columns without a state, its values from ``s``."""
    row = timeloop.Row().add("time", "s", lambda: s.t).add("mean", "-", lambda: jnp.mean(s.y))
    return row.add_block([(f"gauge{k}_value", "-") for k in range(len(gauge_cells))],
                         lambda: s.y[jnp.asarray(gauge_cells, jnp.int32)])


method.register(Decay())


def decay_data(**over):
    data = {"method": "decay", "name": "toy", "decay": {"rate": 2.0, "cells": 8}, "time": {"end": 0.5},
            "numerics": {"cfl": 0.05}, "output": {"history_samples": 11, "fields": 6, "gauges": [0.3, 0.9]}}
    for key, value in over.items():
        parts = key.split("__")
        node = data
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = value
    return data


def exact(setup, t):
    return np.exp(-setup.rate * t)  # y' = -k y, y(0) = 1


# ------------------------------------------------------------------------------------------------ tests
def test_schema_dispatches_on_the_method_key():
    assert isinstance(parse(decay_data()), DecayScenario)
    with pytest.raises(ScenarioError, match=r"method: unknown method 'nope'; available: .*lagrangian1d"):
        parse(decay_data(method="nope"))
    with pytest.raises(ScenarioError, match=r"decay.rate: .*> 0"):
        parse(decay_data(decay__rate=-1.0))
    with pytest.raises(ScenarioError, match=r"output.gauges\[1\] = 1.5 m lies outside the domain \(x in \[0, 1\] m\)"):
        parse(decay_data(output__gauges=[0.5, 1.5]))
    with pytest.raises(TypeError, match="lacks"):
        method.register(type("Faceless", (), {"name": "faceless"})())
    half_pool = type("HalfPool", (Decay,), {"pool_leaf": "y"})()  # a GrowingPool needs all three members
    with pytest.raises(TypeError, match=r"GrowingPool capability but lacks \['pool_needed', 'resize'\]"):
        method.register(half_pool)
    assert not isinstance(Decay(), method.GrowingPool) and not isinstance(half_pool, method.GrowingPool)


def test_a_history_row_and_its_columns_come_from_the_same_entries():
    setup = Decay().build(parse(decay_data()))
    assert decay_history(setup.gauge_cells).columns == (("time", "s"), ("mean", "-"), ("gauge0_value", "-"),
                                                         ("gauge1_value", "-"))
    s = DecayState(jnp.arange(8.0), **timeloop.clock(3, 4, jnp.float64))
    np.testing.assert_array_equal(decay_history(setup.gauge_cells, s).values(jnp.float64),
                                  [0.0, 3.5, *np.arange(8.0)[list(setup.gauge_cells)]])
    wrong = timeloop.Row().add_block([("a", "-"), ("b", "-")], lambda: jnp.zeros(3))
    with pytest.raises(ValueError, match=r"history entries \['a', 'b'\]: 3 values"):
        wrong.values(jnp.float64)


def test_ensemble_histories_and_grid_snapshots_are_exact(tmp_path):
    # each step multiplies by exp(-k dt): exact up to round-off (~ steps x eps)
    res = simulation.run(decay_data(sweep={"rate": [1.0, 3.0]}), tmp_path / "r")
    assert len(res.summaries) == 2 and res.summary["method"] == ["decay", "decay"]
    assert res.summary["cells"] == [8, 8] and res.summary["time"] == [0.5, 0.5]
    for k, (setup, hist) in enumerate(zip(res.setups, res.history)):
        np.testing.assert_allclose(hist["mean"], np.mean(exact(setup, hist["time"][:, None]), axis=1), rtol=1e-13)
        gauges = res.gauges[k]
        assert gauges["value"].shape == (11, 2)
        np.testing.assert_allclose(gauges["value"], exact(setup, hist["time"][:, None])[:, [2, 7]], rtol=1e-13)
        disk = read_history(tmp_path / "r" / f"history_member{k}.csv")
        np.testing.assert_array_equal(disk["gauge1_value"], hist["gauge1_value"])
    # snapshots at 0, 0.1, ..., 0.5 through the grid writer of blastfsi.io.fields, read back
    mid = res.fields(time=0.2)
    for k, setup in enumerate(res.setups):
        np.testing.assert_allclose(mid[k]["x"], 0.5 * (setup.edges[1:] + setup.edges[:-1]), rtol=1e-15)
        np.testing.assert_allclose(mid[k]["density"], exact(setup, 0.2), rtol=1e-13)
        assert mid[k]["velocity"].shape == (8, 1)
        np.testing.assert_array_equal(res.fields(time=0.5)[k]["density"], res.fields()[k]["density"])
    with pytest.raises(ValueError, match="available"):
        res.fields(time=0.25)
    assert (tmp_path / "r" / "fields" / "member1.xdmf").is_file() and (tmp_path / "r" / "plots" / "decay.txt").is_file()


def test_checkpoint_restart_of_any_state_is_bit_for_bit(tmp_path):
    data = decay_data(output__checkpoint_interval=0.1)
    full = simulation.run(data, tmp_path / "a")
    part = tmp_path / "b"
    simulation.run(data, part)
    for f in sorted((part / "checkpoints").glob("*.h5"))[2:]:
        f.unlink()  # as if the run had died after t = 0.2
    again = simulation.run(parse(data).model_dump(exclude_none=True), part, restart=True)
    assert again.summary["steps"] == full.summary["steps"]
    np.testing.assert_array_equal(np.asarray(again.state.y), np.asarray(full.state.y))
    np.testing.assert_array_equal(np.asarray(again.state.hist), np.asarray(full.state.hist))


def test_collapsing_time_step_stops_the_run():
    # stable dt = cfl (T - t): T - t shrinks by (1 - cfl) per step, so the step
    # falls below dt_min_fraction x dt0 = f cfl T exactly when T - t < f T
    T, f = 0.3, 1e-6
    with pytest.raises(simulation.SimulationError) as err:
        simulation.run(decay_data(decay__collapse_time=T, numerics__cfl=0.5))
    msg = str(err.value)
    assert msg.startswith("time step collapsed below time.dt_min_fraction x initial (1e-06 x 0.15 s)")
    t = float(msg.split("t = ")[1].split()[0])
    assert T * (1 - f) < t <= T and "cell" in msg and "no checkpoint written yet" in msg


def test_piston_squeezing_gas_against_a_wall_exits_with_code_3(tmp_path, capsys):
    # A piston at the post-shock velocity u_p drives the gas against a fixed wall:
    # the column L - u_p t, and with it the zones and the stable step, collapses at
    # t_c = L / u_p. The run must stop there with exit code 3, not run on for hours.
    ratio, length = 10.0, 0.1
    t_c = length / float(shock.incident_shock(ratio * P0, P0, RHO0).particle_velocity)
    scenario = {"name": "squeeze", "incident": {"profile": "uniform", "overpressure": ratio * P0},
                "plate": {"fixed": True}, "domain": {"length": length}, "grid": {"cells": 20},
                "time": {"end": 100 * t_c}, "output": {"fields": 0, "plots": False, "history_samples": 1001}}
    (tmp_path / "s.toml").write_text(tomli_w.dumps(scenario))
    code = cli.main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "out"), "--json"])
    out, err = capsys.readouterr()
    assert code == cli.EXIT_SIMULATION and out == "", err
    assert "time step collapsed below time.dt_min_fraction x initial" in err and "zone" in err
    t = float(err.split("t = ")[1].split()[0])
    assert 0.99 * t_c < t <= t_c
    # the history up to the fault is written (and named in the message), as the snapshots are
    history = tmp_path / "out" / "history.csv"
    assert f"history to the fault: {history}" in err
    times = np.loadtxt(history, delimiter=",", skiprows=1, usecols=0, ndmin=1)
    assert len(times) >= 9 and times[0] == 0.0 and np.all(np.diff(times) > 0.0) and times[-1] <= t  # every t_c / 10


def _logged(stable, t_stop, n_samples, sample_interval, steps=64):
    """A toy state advanced to each of the stop times ``t_stop`` (as the driver does): y[j] logs step j's
    dt / dt_stable, y[-1] a quantity linear in time (dy = 2 dt); history rows (t, y[-1], t^2)."""
    state = DecayState(jnp.zeros(steps + 1), **timeloop.clock(n_samples, 3, jnp.float64))

    def step(s, dt):
        return s._replace(y=s.y.at[s.step].set(dt / stable(s)).at[-1].add(2.0 * dt))

    for t in t_stop:
        state = timeloop.run_until(state, t, steps, sample_interval, 1e-6, stable_dt=stable, step=step,
                                   history_row=lambda s: jnp.stack([s.t, s.y[-1], s.t ** 2]))
    return state


def test_history_samples_never_shorten_a_step():
    """Samples every 0.05 and a stable step of 0.3 to 3.0: ten steps of 0.3 (samples used to be landed on,
    60 steps of 0.05); the rows at the sample times are interpolated within the steps, exact for the
    quantity linear in time, the first and the last rows exact."""
    out = _logged(lambda s: jnp.asarray(0.3), [3.0], 61, 0.05)
    assert int(out.step) == 10
    np.testing.assert_allclose(np.asarray(out.y[:10]), 1.0, rtol=1e-14)
    times = 0.05 * np.arange(61)
    hist = np.asarray(out.hist)
    np.testing.assert_allclose(hist[:, 0], times, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(hist[:, 1], 2.0 * times, rtol=1e-14, atol=1e-15)
    assert hist[0, 0] == 0.0 and hist[-1, 0] == 3.0 and hist[-1, 1] == float(out.y[-1])
    # t^2 interpolated linearly: off by at most (h/2)^2 within a step of h = 0.3, exact at the steps' ends
    err = hist[:, 2] - times ** 2
    assert -1e-13 <= err.min() and err.max() <= 0.15 ** 2 + 1e-13 and np.all(np.abs(err[::6]) < 1e-13)


def test_stop_times_are_landed_on_without_a_short_step():
    """The time left to a stop is split into the fewest equal steps no longer than the stable one: 1.0 with a
    stable step of 0.3 in four steps of 0.25 (not three of 0.3 and one of 0.1: a modulated dt pumps an
    explicit integrator's fast modes, blastfsi.timeloop); with a stable step that varies and stop times that
    are not multiples of it, every step is within [0.5, 1] of the stable one (up to its growth in a step), and
    each stop is landed on exactly."""
    out = _logged(lambda s: jnp.asarray(0.3), [1.0], 2, 1.0)
    assert int(out.step) == 4 and float(out.t) == 1.0
    np.testing.assert_allclose(np.asarray(out.y[:4]), 0.25 / 0.3, rtol=1e-14)
    stops = [0.123, 0.5, 0.77, 1.0]
    out = _logged(lambda s: 0.021 * (1.0 + s.t) ** 2, stops, 20001, 5e-5, steps=200)
    n = int(out.step)
    ratio = np.asarray(out.y[:n])
    assert float(out.t) == 1.0 and n < 40 and 0.45 <= ratio.min() and ratio.max() <= 1.0 + 1e-12
    hist = np.asarray(out.hist)
    np.testing.assert_allclose(hist[:, 1], 2.0 * hist[:, 0], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(hist[:, 0], 5e-5 * np.arange(20001), rtol=1e-13, atol=1e-15)


def test_steps_do_not_depend_on_the_history_samples():
    """Through the driver: 2001 history samples take the steps of 2 (the old landing on every sample took
    2000), and checkpoint times an ulp from snapshot times are one stop time."""
    fewest = simulation.run(decay_data(output__history_samples=2))
    many = simulation.run(decay_data(output__history_samples=2001))
    assert many.summary["steps"] == fewest.summary["steps"] < 60
    fields, ckpt, stops = simulation.stop_times(parse(decay_data(output__fields=101, output__checkpoint_interval=0.05)))
    assert set(ckpt) <= set(fields) and len(stops) == 101
