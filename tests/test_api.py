"""The Python API (blastfsi.run) is the CLI's engine: inputs, overrides, summary, fields, histories."""
import json

import numpy as np
import pytest
import tomli_w

import blastfsi
from blastfsi import cli
from blastfsi.exact import shock
from blastfsi.scenario import ScenarioError
from conftest import P0, RHO0, uniform_data

COMMON_KEYS = {"method", "time", "steps", "cells", "wall_time", "compile_time", "loop_time", "output_time"}
TIMES = {"wall_time", "compile_time", "loop_time", "output_time"}
# every single-member run here has 200 zones, 201 history samples and 2 gauges: compiled once
SMALL = {"grid.cells": 200, "domain.length": 1.0, "time.end": 0.0016, "output.plots": False,
         "output.history_samples": 201, "output.gauges": [0.25, 0.75]}


def test_dict_input_summary_fields_and_histories():
    res = blastfsi.run(uniform_data(output__gauges=[0.5, 1.5]), set={"grid.cells": 200})
    summ = res.summary
    assert COMMON_KEYS <= summ.keys() and {"plate_velocity", "plate_impulse", "gauge_impulse"} <= summ.keys()
    assert summ["method"] == "lagrangian1d" and summ["cells"] == 200
    assert summ["time"] == pytest.approx(uniform_data()["time"]["end"], rel=1e-15) and summ["steps"] > 0
    assert summ["compile_time"] >= 0.0 and summ["wall_time"] > 0.0
    f = res.fields()
    for name in ("x", "density", "pressure", "internal_energy", "viscous_pressure"):
        assert f[name].shape == (200,), name
    assert f["velocity"].shape == (200, 1) and f["node_x"].shape == (201,) and f["node_velocity"].shape == (201,)
    np.testing.assert_allclose(f["x"], 0.5 * (f["node_x"][1:] + f["node_x"][:-1]))
    # the zone masses are rho0 dx0 and never change: density x width recovers them
    np.testing.assert_allclose(f["density"] * np.diff(f["node_x"]), RHO0 * 2.0 / 200, rtol=1e-12)
    hist = res.history
    assert hist["time"].shape == (201,) and hist["plate_impulse"][-1] == pytest.approx(summ["plate_impulse"])
    g = res.gauges
    assert g["overpressure"].shape == (201, 2) and list(g["position"]) == [0.5, 1.5]
    np.testing.assert_array_equal(g["overpressure"][:, 1], hist["gauge1_overpressure"])
    # behind the incident shock the gauge at 1.5 m reads p_s (jump conditions; smeared front excluded)
    s = shock.incident_shock(4.49 * P0, P0, RHO0)
    late = (hist["time"] > 1.5 / s.shock_speed + 2e-4) & (hist["time"] < 2.0 / s.shock_speed)
    np.testing.assert_allclose(g["overpressure"][late, 1], 4.49 * P0, rtol=5e-3)


def test_example_name_with_overrides_matches_the_cli_json(capsys, tmp_path):
    res = blastfsi.run("plate1d-uniform", set=SMALL)
    assert res.summary["cells"] == 200 and res.scenario.name == "plate1d-uniform"
    code = cli.main(["run", "--example", "plate1d-uniform", *[a for k, v in SMALL.items()
                                                              for a in ("--set", f"{k}={json.dumps(v)}")],
                     "--out", str(tmp_path / "o"), "--json"])
    printed = json.loads(capsys.readouterr().out)
    assert code == 0 and printed.keys() == res.summary.keys()
    assert printed["compile_time"] == 0.0  # the same engine: the executable compiled for the API run is reused
    for key in printed.keys() - TIMES:
        assert printed[key] == res.summary[key], key


def test_path_input_writes_results_and_reads_snapshots_back(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(uniform_data(grid__cells=200, output__fields=3, output__gauges=[0.5, 1.5])))
    out = tmp_path / "results"
    res = blastfsi.run(str(path), out=out)
    end = res.summary["time"]
    assert json.loads((out / "summary.json").read_text()) == res.summary
    summ = res.summary  # 3 snapshots written inside the time loop: their time is its output part
    assert summ["output_time"] > 0.0 and summ["loop_time"] > 0.0
    assert summ["loop_time"] + summ["output_time"] <= summ["wall_time"]
    final = res.fields(time=end)
    for name, values in res.fields().items():
        np.testing.assert_array_equal(final[name], values)
    start = res.fields(time=0.0)  # gas at rest at p0, rho0
    np.testing.assert_allclose(start["pressure"], P0, rtol=1e-12)
    np.testing.assert_allclose(start["density"], RHO0, rtol=1e-12)
    with pytest.raises(ValueError, match=r"no field snapshot at time 0.001 s; available: \[0.0, "):
        res.fields(time=1e-3)
    again = blastfsi.run(path, set={"output.fields": 0})  # a Path; out=None: nothing written
    assert again.out_dir is None and again.fields(time=end)["pressure"].shape == (200,)
    assert again.summary["output_time"] == 0.0
    with pytest.raises(ValueError, match="out=None"):
        again.fields(time=1e-3)


def test_ensemble_gives_lists_per_member():
    res = blastfsi.run(uniform_data(sweep={"beta_s": [0.5, 5.0]}, grid__cells=200, output__fields=0))
    assert len(res.history) == 2 and len(res.fields()) == 2 and len(res.gauges) == 2
    assert res.summary["cells"] == [200, 200] and res.fields()[1]["velocity"].shape == (200, 1)
    heavy, light = res.summary["plate_velocity"]  # beta_s is inversely proportional to the plate mass
    assert light > heavy > 0


@pytest.mark.parametrize("scenario,kwargs,fragment", [
    ("no-such-example", {}, "neither a scenario file nor a shipped example"),
    ("missing.toml", {}, "scenario file not found"),
    (42, {}, "not int"),
    (uniform_data(), {"set": ["grid.cells=10"]}, "set: expected a dict"),
    (uniform_data(), {"set": {"grid.cells": 100.5}}, "grid.cells"),
    (uniform_data(), {"set": {"name": "../../x"}}, "name"),
])
def test_bad_api_input_is_a_scenario_error(scenario, kwargs, fragment):
    with pytest.raises(ScenarioError) as err:
        blastfsi.run(scenario, **kwargs)
    assert fragment in str(err.value)
