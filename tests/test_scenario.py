"""Bad input is rejected with a message naming the key and the allowed range (issue 2, item 7)."""
import json
import re
import subprocess
import sys

import pytest
import tomli_w

from blastfsi.scenario import ScenarioError, parse, read_toml
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


def test_set_reaches_into_lists_by_index():
    """``--set structures.0.material=...`` changes the first structure; an index past the end, or a word where
    a list needs an index, is refused naming the key and the valid range."""
    from blastfsi.scenario import set_dotted

    data = {"structures": [{"material": "steel-rha", "supports": [{"lower": [0.25, 0.1]}]}],
            "domain": {"upper": [0.3, 0.15]}, "grid": {"cells": 120}}
    changed = set_dotted(data, "structures.0.material", "steel-4340")
    assert changed["structures"][0]["material"] == "steel-4340" and data["structures"][0]["material"] == "steel-rha"
    assert set_dotted(data, "structures.0.supports.0.lower.1", 0.11)["structures"][0]["supports"][0]["lower"] == \
        [0.25, 0.11]
    assert set_dotted(data, "domain.upper.1", 0.2)["domain"]["upper"] == [0.3, 0.2]
    for key, words in (("structures.1.material", "structures is a list of 1 entries, so '1' must be an index from 0"),
                       ("structures.first.material", "'first' must be an index"),
                       ("domain.upper.2", "domain.upper is a list of 2 entries"),
                       ("grid.cells.x", "grid.cells is a value, not a table")):
        with pytest.raises(ScenarioError, match=re.escape(words)):
            set_dotted(data, key, 1)


def test_set_by_index_from_the_command_line(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", "--example", "steel-plate-blast",
                           "--set", "structures.0.material=steel-4340", "--set", "structures.0.supports.0.lower.0=2.0",
                           "--out", str(tmp_path / "o")], capture_output=True, text=True)
    # the overrides reached the first structure: its moved support is now checked (and refused) by validation
    assert proc.returncode == 2 and "structures" in proc.stderr and "is a list" not in proc.stderr, proc.stderr


def test_sweep_members_are_the_cartesian_product():
    data = uniform_data(sweep={"overpressure": [1e4, 2e4], "beta_s": [0.1, 1.0, 10.0]})
    sc = parse(data)
    assert len(sc.members()) == 6
    assert json.dumps(sc.members()[0]) == json.dumps({"incident.overpressure": 1e4, "plate.beta_s": 0.1})


# Issue 5: strict types (no string-to-bool, string-to-number, float-to-int), safe names,
# gauges inside the domain, the time-step floor's range, the method key.
STRICT = [
    ({"plate__beta_s": None, "plate__fixed": "yes"}, ["plate.fixed", "boolean", "'yes'"]),
    ({"grid__cells": 100.5}, ["grid.cells", "integer", "100.5"]),
    ({"grid__cells": 100.0}, ["grid.cells", "integer", "100.0"]),
    ({"grid__cells": True}, ["grid.cells", "integer"]),
    ({"domain__length": "8"}, ["domain.length", "number", "'8'"]),
    ({"incident__overpressure": "4e5"}, ["incident.overpressure", "number"]),
    ({"name": "../../x"}, ["name", "letters, digits", "'../../x'"]),
    ({"name": ".hidden"}, ["name", "not start with '.'"]),
    ({"name": "a/b"}, ["name", "'a/b'"]),
    ({"output__gauges": [1.0, 2.5]}, ["output.gauges[1] = 2.5 m lies outside the domain (x in [0, 2] m)"]),
    ({"output__gauges": [-0.1]}, ["output.gauges[0] = -0.1 m lies outside the domain (x in [0, 2] m)"]),
    ({"output__gauges": [[1.0, 0.5]]}, ["output.gauges[0]", "expected 1 coordinate"]),
    ({"output__gauges": ["1.0"]}, ["output.gauges[0]", "'1.0'"]),
    ({"time__dt_min_fraction": 1.0}, ["time.dt_min_fraction", "< 1"]),
    ({"time__dt_min_fraction": -1e-3}, ["time.dt_min_fraction", ">= 0"]),
    ({"method": "nope"}, ["method", "unknown method 'nope'", "lagrangian1d"]),
]


@pytest.mark.parametrize("override,fragments", STRICT)
def test_strict_types_safe_names_and_gauges(override, fragments):
    with pytest.raises(ScenarioError) as err:
        parse(uniform_data(**override))
    for frag in fragments:
        assert frag in str(err.value)


def test_integers_for_float_keys_and_safe_names_are_accepted(tmp_path):
    f = tmp_path / "ints.toml"
    f.write_text(tomli_w.dumps(uniform_data(name="case-1_b.2", domain__length=2, time__end=1,
                                            output__gauges=[0, 2])))
    sc = parse(read_toml(f))
    assert sc.method == "lagrangian1d" and sc.name == "case-1_b.2"
    assert isinstance(sc.time.end, float) and sc.time.end == 1.0 and isinstance(sc.domain.length, float)
    assert sc.output.gauges == [0.0, 2.0] and sc.time.dt_min_fraction == 1e-6


def test_cli_refuses_an_escaping_name_before_writing_anything(tmp_path, monkeypatch, capsys):
    from blastfsi import cli

    monkeypatch.chdir(tmp_path)
    f = tmp_path / "evil.toml"
    f.write_text(tomli_w.dumps(uniform_data(name="../../escaped")))
    assert cli.main(["run", str(f)]) == cli.EXIT_SCENARIO
    assert "name" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.toml"] and not (tmp_path.parent / "escaped").exists()


def test_every_shipped_example_validates():
    """The shipped scenarios parse under their method's schema (a typo in an example is caught here, not by
    the user)."""
    from blastfsi.api import example_data, example_names

    for name in example_names():
        assert parse(example_data(name)).name == name
