"""`blastfsi kb` (issue 6): KB values of a TNT charge on the command line."""
import json

import pytest

from blastfsi import cli
from blastfsi.exact import kingery_bulmash as kb


def test_kb_json_gives_the_report(capsys):
    assert cli.main(["kb", "--mass", "8", "--distance", "4", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["scaled_distance"] == pytest.approx(2.0, rel=1e-12)
    assert out["incident_overpressure"] == pytest.approx(float(kb.scaled_value("incident_overpressure", 2.0)))
    assert out["arrival_time"] == pytest.approx(2.0 * float(kb.scaled_value("arrival_time", 2.0)))
    assert out["burst"] == "free-air" and out["units"]["incident_impulse"] == "Pa*s"


def test_kb_text_and_surface_burst(capsys):
    assert cli.main(["kb", "--mass", "1", "--distance", "5", "--burst", "surface"]) == 0
    text = capsys.readouterr().out
    assert "scaled_distance" in text and "surface" in text and "Pa" in text


def test_kb_close_in_says_which_fit_does_not_hold(capsys):
    """seed 000 Sec. 5.4 case 1: 0.468 kg at 0.1 m, Z = 0.129 m/kg^(1/3), below the duration's fit only."""
    assert cli.main(["kb", "--mass", "0.468", "--distance", "0.1"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "n/a" in lines["positive_phase_duration"] and "0.147 <= Z" in lines["positive_phase_duration"]
    assert "Pa*s" in lines["reflected_impulse"] and "n/a" not in lines["reflected_impulse"]


@pytest.mark.parametrize("args,fragment", [(["--mass", "1", "--distance", "100"], "validity range"),
                                          (["--mass", "0", "--distance", "1"], "mass must be > 0"),
                                          (["--mass", "-2", "--distance", "1"], "mass must be > 0")])
def test_kb_bad_input_exits_2(capsys, args, fragment):
    assert cli.main(["kb", *args]) == 2
    assert fragment in capsys.readouterr().err
