"""What the terminal shows: the stage lines and the progress on stderr, the summary table on stdout (or one
JSON object with --json), and `blastfsi schema`."""
import json
import logging
import math
import os
import pty
import re
import subprocess
import sys
import threading

import jsonschema
import pytest
import tomli_w

import blastfsi.method
from blastfsi import cli, report, simulation
from blastfsi.api import example_data, example_names
from blastfsi.scenario import parse

# a charge in a 1D spherical euler domain: the 1D detonation to the remap, the euler loop (cheap to compile)
CHARGE = {"method": "euler", "name": "t-charge",
          "domain": {"geometry": "spherical", "lower": [0.0], "upper": [0.6]},
          "boundaries": {"x": ["axis", "outflow"]}, "grid": {"cells": 120},
          "initial": {"kind": "charge", "mass": 0.1, "cells": 30, "remap_time": 2e-5},
          "time": {"end": 1e-4}, "output": {"history_samples": 5, "fields": 0, "plots": False, "gauges": [0.5]}}
PLATE = ["--example", "plate1d-uniform", "--set", "grid.cells=100", "--set", "domain.length=0.5", "--set",
         "time.end=8e-4", "--set", "output.fields=0", "--set", "output.plots=false"]
STAGE = re.compile(r"\[ *[0-9][0-9 .minhs]*\] (.*)")  # report.stage_line


# ------------------------------------------------------------------------------------- report: pure functions
@pytest.mark.parametrize("value, unit, text", [
    (3.722e6, "Pa", "3.722 MPa"), (935.4e3, "Pa", "935.4 kPa"), (20.98e9, "Pa", "20.98 GPa"), (0.0, "Pa", "0 Pa"),
    (140.3e-6, "s", "140.3 µs"), (0.0115, "s", "11.5 ms"), (2.5, "s", "2.5 s"),
    (141.1, "Pa s", "141.1 kPa·ms"), (33438.7, "Pa s", "33.44 MPa·ms"),  # 1 Pa s = 1 kPa ms
    (0.07009, "length", "70.09 mm"), (2.0, "length", "2 m"), (-0.02614, "%", "-2.614 %"),
    ([1.0, 0.0], "m", "(1, 0) m"), ([-0.00201, 0.1986], "", "(-0.00201, 0.1986)"),
    (None, "Pa", "-"), (6000, "", "6000"), (True, "", "true"), ("free-air incident", "", "free-air incident"),
])
def test_quantity_is_shown_in_a_unit_that_suits_its_size(value, unit, text):
    assert report.quantity(value, unit) == text


@pytest.mark.parametrize("path, unit", [
    ("positive_phase_duration", "s"),  # ("duration" holds "ratio": whole words only)
    ("burn_front_pressure_ratio", ""), ("energy_pressure_transfer", ""), ("cj_pressure", "Pa"),
    ("gauges.kb.peak_overpressure", "Pa"), ("plate_impulse_max", "Pa s"), ("budget.reaction.impulse", ""),
    ("mass_change_relative", "%"), ("compile_time", "wall"), ("arrival_time", "s"), ("one_d_air_zone", "length"),
    ("scaled_distance", "m/kg^1/3"), ("charge_mass", ""), ("position", "m"),
])
def test_unit_of_a_summary_key(path, unit):
    assert report.unit_of(path) == unit


def test_duration_and_stage_line():
    assert [report.duration(s) for s in (0.42, 12.34, 75.0, 7380.0, None)] == \
        ["0.42 s", "12.3 s", "1 min 15 s", "2 h 03 min", "-"]
    assert STAGE.fullmatch(report.stage_line(75.0, "compiling")).group(1) == "compiling"


def test_eta_rate_is_a_wall_clock_weighted_average():
    # a steady rate r is returned whatever the calls' durations
    totals, r = (0.0, 0.0), 3e-4
    for wall in (0.01, 1.0, 0.3, 7.0, 0.02):
        totals = (report.decayed(totals[0], r * wall, wall), report.decayed(totals[1], wall, wall))
    assert totals[0] / totals[1] == pytest.approx(r, rel=1e-12)
    # a slow first call (0.1 s at r / 100: compiling-time effects) weighs by its 0.1 s against the next 5 s
    # at r, so the estimate is within 0.1 / 5.1 = 2 % of r (decay makes the old weigh less still)
    sim, wall = r / 100 * 0.1, 0.1
    for _ in range(10):
        sim, wall = report.decayed(sim, r * 0.5, 0.5), report.decayed(wall, 0.5, 0.5)
    assert 1.0 - 0.1 / 5.1 <= (sim / wall) / r < 1.0
    assert report.remaining(0.25, 1.0, 0.5) == 1.5 and report.remaining(0.5, 1.0, None) is None


def test_shown_step_is_the_stable_step_not_a_landing_step():
    assert report.shown_step(None, 1e-3, 100) == pytest.approx(1e-5)
    assert report.shown_step(1e-5, 1e-20, 1) == 1e-5  # a lone step that lands on an output time
    assert report.shown_step(None, 4e-6, 1) == 4e-6  # (the first call, nothing better known)


def test_plain_progress_lines_at_each_tenth_and_every_minute():
    assert not report.plain_due(0.15, 0.11, 5.0)
    assert report.plain_due(0.21, 0.19, 0.1)
    assert report.plain_due(0.12, 0.11, report.PLAIN_EVERY)
    assert report.plain_due(1.0, 0.95, 0.01)


def test_time_loop_calls_aim_at_a_second():
    assert simulation.next_chunk(10, 1e-3, 20_000) == 40  # grows at most 4-fold per call
    assert simulation.next_chunk(4000, 2.0, 20_000) == 2000  # 2 s for 4000 steps: 2000 in a second
    assert simulation.next_chunk(20_000, 0.1, 20_000) == 20_000  # the cap
    assert simulation.next_chunk(5, 100.0, 20_000) == 1  # a step longer than a second: one per call
    assert simulation.next_chunk(3, 1e-4, 20_000, 100) == 400  # a call planned for 100, cut to 3 (an output time)


# ------------------------------------------------------------------------------------ the command line
@pytest.fixture(scope="module")
def charge_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("charge")
    (folder / "c.toml").write_text(tomli_w.dumps(CHARGE))
    proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", str(folder / "c.toml"), "--out",
                           str(folder / "out"), "--json"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return proc, folder / "out"


def test_a_charge_set_up_logs_its_1d_detonation(caplog):
    """Without a progress report (the Python API's default) the set-up's stage goes to the ``blastfsi``
    logger; the driver shows the same line as a stage when it reports (next test)."""
    with caplog.at_level(logging.INFO, logger="blastfsi"):
        blastfsi.method.get("euler").build(parse(CHARGE))
    assert [(r.name, r.getMessage()) for r in caplog.records] == [
        ("blastfsi.detonation.charge", "1D detonation of 0.1 kg TNT to t = 0.02 ms (30 zones across the charge radius)")]


def test_charge_run_says_what_it_does_in_order_on_stderr(charge_run):
    proc, out = charge_run
    stages = [STAGE.fullmatch(line).group(1) for line in proc.stderr.splitlines() if STAGE.fullmatch(line)]
    expected = ["validating the scenario", "building the euler set-up",
                "1D detonation of 0.1 kg TNT to t = 0.02 ms (30 zones across the charge radius)",
                "compiling the time loop (120 cells)", "compiled in ", "t = "]
    at = [next(i for i, s in enumerate(stages) if s.startswith(e)) for e in expected]
    assert at == sorted(at), stages
    assert proc.stderr.splitlines()[-1] == f"results written to {out}"
    # the progress lines: the last at the end, the time step each shows the mean of its call's steps (each
    # at least about half the stable step, which changes by less than 2x in this short run), never a step
    # that only lands on an output time
    summary = json.loads((out / "summary.json").read_text())
    progress = [s for s in stages if s.startswith("t = ")]
    assert progress[-1].startswith("t = 100 µs of 100 µs (100 %)")
    mean = (summary["time"] - CHARGE["initial"]["remap_time"]) / summary["steps"]
    for line in progress:
        value, unit = re.search(r"dt = ([0-9.e+-]+) (\S+)", line).groups()
        assert 0.5 * mean < float(value) * {"µs": 1e-6, "ns": 1e-9}[unit] < 2.0 * mean, line


def test_json_keeps_stdout_one_json_object(charge_run):
    proc, out = charge_run
    assert proc.stdout.count("\n") == 1 and json.loads(proc.stdout) == json.loads((out / "summary.json").read_text())


def test_table_of_a_charge_run_summary(charge_run):
    _, out = charge_run
    summary = json.loads((out / "summary.json").read_text())
    table = report.summary_table(summary)
    lines = table.splitlines()
    assert lines[:3] == ["run", "  method          euler", "  status          complete"]
    assert "{" not in table and max(map(len, lines)) < 160 and len(table) < 3000  # no dict dumps
    gauge = summary["gauges"][0]
    header = lines.index("gauges") + 1
    assert lines[header].split()[:4] == ["#", "position", "Z", "[m/kg^1/3]"]
    row = lines[header + 1]
    for value, unit in ((gauge["peak_overpressure"], "Pa"), (gauge["impulse"], "Pa s"),
                        (gauge["arrival_time"], "s")):
        assert report.quantity(value, unit) in row
    assert report.number(gauge["ratio"]["peak_overpressure"]) in row and gauge["kb"]["reference"] in row
    assert "  mass_change_relative" in table and "%" in table.split("mass_change_relative")[1].splitlines()[0]


def test_table_of_an_ensemble_is_member_by_member(charge_run):
    _, out = charge_run
    one = json.loads((out / "summary.json").read_text())
    members = [{"initial.mass": 0.1}, {"initial.mass": 0.2}]
    lines = report.summary_table(simulation._combined([one, one], members)).splitlines()  # (summary.json's form)
    single = ["  " + line for line in report.summary_table(one).splitlines()]
    assert lines == ["member 0: initial.mass = 0.1", *single, "", "member 1: initial.mass = 0.2", *single]


def test_table_on_stdout_and_quiet(tmp_path, capsys):
    assert cli.main(["run", *PLATE, "--out", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("run\n  method          lagrangian1d\n") and "plate_velocity" in out
    assert "validating the scenario" in err and "compiling the time loop" in err
    assert cli.main(["run", *PLATE, "--out", str(tmp_path / "b"), "--quiet"]) == 0
    assert capsys.readouterr().err == f"results written to {tmp_path / 'b'}\n"


def test_progress_bar_on_a_terminal(tmp_path, monkeypatch):
    parent, child = pty.openpty()
    shown = []

    def read():  # (the terminal's buffer is small: read as it is written)
        while True:
            try:
                chunk = os.read(parent, 65536)
            except OSError:  # closed
                return
            if not chunk:
                return
            shown.append(chunk)

    reader = threading.Thread(target=read)
    reader.start()
    terminal = os.fdopen(child, "w", encoding="utf-8")
    monkeypatch.setattr(sys, "stderr", terminal)
    assert cli.main(["run", *PLATE, "--out", str(tmp_path / "a")]) == 0
    terminal.close()
    reader.join(timeout=10)
    os.close(parent)
    text = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", b"".join(shown).decode())
    assert "compiling the time loop" in text and "ETA" in text and "steps/s" in text
    assert "t = 800 µs of 800 µs" in text and "100 %" in text
    assert not re.search(r"\] t = ", text)  # no plain progress lines on a terminal


# -------------------------------------------------------------------------------------------- schema
def test_schema_validates_every_example_and_rejects_a_misspelt_key(capsys):
    schemas = {}
    for method in (None, "lagrangian1d", "euler", "mpm", "cfdmp"):
        assert cli.main(["schema", *([method] if method else [])]) == 0
        schemas[method] = json.loads(capsys.readouterr().out)
        jsonschema.Draft202012Validator.check_schema(schemas[method])
    check = {m: jsonschema.Draft202012Validator(s) for m, s in schemas.items()}
    for name in example_names():
        data = example_data(name)
        misspelt = {**data, "grid": {**data["grid"], "cels": 10}}
        for validator in (check[None], check[data.get("method", "lagrangian1d")]):
            validator.validate(data)
            with pytest.raises(jsonschema.ValidationError):
                validator.validate(misspelt)
    # a file without `method` is a lagrangian1d scenario: an euler example without it is not valid
    with pytest.raises(jsonschema.ValidationError):
        check[None].validate({k: v for k, v in example_data("sedov-2d").items() if k != "method"})
    assert cli.main(["schema", "nope"]) == cli.EXIT_SCENARIO
    assert "unknown method 'nope'" in capsys.readouterr().err


def test_schema_keeps_the_ranges_and_descriptions():
    from blastfsi.schema import scenario_schema

    time = scenario_schema("euler")["$defs"]["Time"]["properties"]["end"]
    assert time["exclusiveMinimum"] == 0.0 and "simulated time" in time["description"]
    assert math.isclose(time["maximum"], 1e4)
