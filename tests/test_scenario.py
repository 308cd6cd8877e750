"""Bad input is rejected with a message naming the key and the allowed range (issue 2, item 7)."""
import json
import subprocess
import sys

import pytest
import tomli_w

from blastfsi.scenario import ScenarioError, parse
from conftest import uniform_data

# (override, expected fragments of the message)
MALFORMED = [
    ({"plate__beta_s": None, "plate__areal_mass": -3.0}, ["plate.areal_mass", ">= 0"]),
    ({"plate__beta_s": -1.0}, ["plate.beta_s", "> 0"]),
    ({"grid__cells": 0}, ["grid.cells", ">= 10"]),
    ({"grid__colls": 5}, ["grid.colls", "unknown key"]),
    ({"grid__cells": "many"}, ["grid.cells", "integer"]),
    ({"numerics__cfl": 1.5}, ["numerics.cfl", "<= 1"]),
    ({"time__end": 0.0}, ["time.end", "> 0"]),
    ({"time__end": -1.0}, ["time.end", "> 0"]),
    ({"incident__overpressure": -5.0}, ["incident.overpressure", "> 0"]),
    ({"incident__profile": "triangular"}, ["incident", "uniform"]),
    ({"domain": None}, ["domain", "missing"]),
    ({"plate__areal_mass": 2.0}, ["exactly one of plate.areal_mass"]),
    ({"plate__beta_s": None}, ["exactly one of plate.areal_mass"]),
    ({"gas__gamma": 0.9}, ["gas.gamma", "> 1"]),
    ({"gas__density": 0.0}, ["gas.density", "> 0"]),
    ({"output__history_samples": 1}, ["output.history_samples", ">= 2"]),
    ({"numerics__K1": -1.0}, ["numerics.K1", ">= 0"]),
]


@pytest.mark.parametrize("override,fragments", MALFORMED)
def test_malformed_scenarios_are_rejected(override, fragments):
    with pytest.raises(ScenarioError) as err:
        parse(uniform_data(**override))
    for frag in fragments:
        assert frag in str(err.value)


def test_cli_rejects_bad_files_with_exit_code_2(tmp_path):
    cases = [uniform_data(grid__cells=0), uniform_data(numerics__cfl=2.0), uniform_data(plate__mass=1.0)]
    for k, data in enumerate(cases):
        f = tmp_path / f"bad{k}.toml"
        f.write_text(tomli_w.dumps(data))
        proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", str(f), "--out", str(tmp_path / f"o{k}")],
                              capture_output=True, text=True)
        assert proc.returncode == 2, proc.stderr
        assert "invalid scenario" in proc.stderr and proc.stdout == ""
    bad_toml = tmp_path / "broken.toml"
    bad_toml.write_text("name = \n")
    proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", str(bad_toml)], capture_output=True, text=True)
    assert proc.returncode == 2 and "not valid TOML" in proc.stderr


def test_time_end_before_arrival_is_rejected():
    with pytest.raises(ScenarioError, match="arrival time"):
        from blastfsi.simulation import run

        run(uniform_data(time__end=1e-4))


def test_set_override_is_validated(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", "--example", "plate1d-uniform",
                           "--set", "grid.cells=-4", "--out", str(tmp_path / "o"), "--json"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "grid.cells" in proc.stderr and ">= 10" in proc.stderr


def test_sweep_members_are_the_cartesian_product():
    data = uniform_data(sweep={"overpressure": [1e4, 2e4], "beta_s": [0.1, 1.0, 10.0]})
    sc = parse(data)
    assert len(sc.members()) == 6
    assert json.dumps(sc.members()[0]) == json.dumps({"incident.overpressure": 1e4, "plate.beta_s": 0.1})
