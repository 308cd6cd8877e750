"""Issue 37 item 3: the Kingery-Bulmash reference of a gauge (incident, reflected normal/oblique, surface burst),
inferred from its position or set by output.gauge_references (helpers only: no solver run)."""
import math

import numpy as np
import pytest

from blastfsi.api import example_data
from blastfsi.detonation import kb_compare as kbc
from blastfsi.exact import kingery_bulmash as kb
from blastfsi.exact import oblique_reflection as obl
from blastfsi.scenario import ScenarioError, parse

W = 1.0  # kg TNT
DX = 0.02
# a 3D box with a rigid wall at x = 4 and a symmetry plane at y = 0; the charge at (1, 1, 1)
BOX = ("cartesian", [0.0, 0.0, 0.0], [4.0, 5.0, 2.0],
       [["outflow", "wall"], ["symmetry", "outflow"], ["outflow", "outflow"]])
CENTRE = [1.0, 1.0, 1.0]


def ref_of(point, centre=CENTRE, box=BOX, burst="free-air", override="auto"):
    return kbc.infer_reference(point, centre, kbc.reflecting_faces(*box), DX, burst, override)


def test_faces_of_a_box_and_of_rz():
    names = [f["name"] for f in kbc.reflecting_faces(*BOX)]
    assert names == ["x upper wall", "y lower symmetry"]
    # r-z: the axis side is never a face; the ground z = 0 and a cylindrical wall r = R are
    faces = kbc.reflecting_faces("axisymmetric", [0.0, 0.0], [5.0, 3.0], [["axis", "wall"], ["wall", "outflow"]])
    assert [(f["name"], f["normal"].tolist()) for f in faces] == [("x upper wall", [-1.0, 0.0]),
                                                                  ("y lower wall", [0.0, 1.0])]


def test_gauge_on_a_wall_at_normal_incidence_is_kb_reflected():
    ref = ref_of([4.0, 1.0, 1.0])
    assert (ref["kind"], ref["reference"], ref["angle_of_incidence_deg"]) == ("reflected", "reflected (normal)", 0.0)
    assert ref["face"] == "x upper wall" and ref["source"] == "auto"
    values, notes = kbc.reference_values(W, 3.0, ref)
    assert not notes
    assert values["peak_overpressure"] == pytest.approx(float(kb.value("reflected_overpressure", W, 3.0)), rel=1e-12)
    assert values["impulse"] == pytest.approx(float(kb.value("reflected_impulse", W, 3.0)), rel=1e-12)
    # arrival at the slant range, the incident duration (KB has no reflected-duration fit)
    assert values["arrival_time"] == pytest.approx(float(kb.value("arrival_time", W, 3.0)), rel=1e-12)
    assert values["positive_phase_duration"] == pytest.approx(float(kb.value("positive_phase_duration", W, 3.0)))
    # within 2 cells of the wall is on it; 3 cells off is free air
    assert ref_of([4.0 - 2.0 * DX, 1.0, 1.0])["kind"] == "reflected"
    assert ref_of([4.0 - 3.0 * DX, 1.0, 1.0])["kind"] == "incident"


def test_gauge_on_a_wall_at_45_degrees_is_the_conwep_blend():
    ref = ref_of([4.0, 4.0, 1.0])  # 3 m off the normal through the charge, 3 m stand-off
    assert ref["kind"] == "reflected" and ref["angle_of_incidence_deg"] == pytest.approx(45.0)
    assert ref["reference"] == "reflected (oblique, 45 deg)"
    values, _ = kbc.reference_values(W, 3.0 * math.sqrt(2.0), ref)
    load = obl.plate_load(W, 3.0, [3.0])
    assert values["peak_overpressure"] == pytest.approx(load["peak_overpressure"][0], rel=1e-12)
    assert values["impulse"] == pytest.approx(load["impulse"][0], rel=1e-12)
    p_i = float(kb.value("incident_overpressure", W, 3.0 * math.sqrt(2.0)))
    p_r = float(kb.value("reflected_overpressure", W, 3.0 * math.sqrt(2.0)))
    assert p_i < values["peak_overpressure"] < p_r


def test_free_air_gauge_and_own_symmetry_plane_are_incident():
    ref = ref_of([2.5, 1.0, 1.0])
    assert (ref["kind"], ref["burst"], ref["reference"]) == ("incident", "free-air", "free-air incident")
    values, _ = kbc.reference_values(W, 1.5, ref)
    assert values == kbc.kb_values(W, 1.5, "free-air")[0]
    # a symmetry plane through the charge centre (a quarter model) is the charge's own: incident
    on_own_plane = ref_of([2.0, 0.0, 1.0], centre=[1.0, 0.0, 1.0])
    assert on_own_plane["kind"] == "incident"
    # a symmetry plane off the charge mirrors it like a rigid wall: reflected
    off = ref_of([1.0, 0.0, 1.0])
    assert off["kind"] == "reflected" and off["face"] == "y lower symmetry" and off["angle_of_incidence_deg"] == 0.0
    # a corner: the face of the smaller angle of incidence
    corner = ref_of([4.0, 0.0, 1.0], centre=[1.0, 2.0, 1.0])
    assert corner["face"] == "x upper wall"
    assert corner["angle_of_incidence_deg"] == pytest.approx(math.degrees(math.atan2(2.0, 3.0)))


def test_radial_wall_in_rz_is_normal_incidence():
    box = ("axisymmetric", [0.0, 0.0], [2.0, 3.0], [["axis", "wall"], ["outflow", "outflow"]])
    ref = ref_of([2.0, 1.0], centre=[0.0, 1.0], box=box)
    assert ref["kind"] == "reflected" and ref["angle_of_incidence_deg"] == pytest.approx(0.0)


def test_height_of_burst_ground_gauges_are_reflected_free_air_ones_incident():
    sc = parse(example_data("tnt-height-of-burst"))
    refs = kbc.scenario_references(sc, [0.0, 1.0], "free-air", 0.02)
    # ground gauges at r = 0, 1, 2, 3 m under a charge 1 m up: 0, 45, 63.4, 71.6 deg
    assert [r["kind"] for r in refs] == ["reflected"] * 4 + ["incident"] * 2
    theta = [r["angle_of_incidence_deg"] for r in refs[:4]]
    assert theta == pytest.approx([0.0, 45.0, math.degrees(math.atan(2.0)), math.degrees(math.atan(3.0))])
    assert refs[0]["reference"] == "reflected (normal)" and refs[2]["reference"] == "reflected (oblique, 63 deg)"
    gauges = [{"position": list(p), "peak_overpressure": 1e5, "impulse": 50.0, "arrival_time": 1e-3}
              for p in sc.output.gauges]
    r = kbc.distances(sc.output.gauges, [0.0, 1.0])
    out = kbc.compare(gauges, r, 1.0, "free-air", refs)
    assert out[0]["kb"]["reference"] == "reflected (normal)"
    assert out[0]["kb"]["peak_overpressure"] == pytest.approx(float(kb.value("reflected_overpressure", 1.0, 1.0)))
    assert out[0]["ratio"]["peak_overpressure"] == pytest.approx(1e5 / out[0]["kb"]["peak_overpressure"])
    assert set(out[0]["ratio"]) == {"peak_overpressure", "impulse", "arrival_time"}
    assert out[4]["kb"]["reference"] == "free-air incident"


def test_surface_burst_ground_gauges_are_surface_incident():
    sc = parse(example_data("tnt-surface-burst"))
    refs = kbc.scenario_references(sc, [0.0, 0.0], "surface", 0.02)
    assert [(r["kind"], r["burst"]) for r in refs] == [("incident", "surface")] * 3
    assert refs[0]["reference"] == "surface-burst incident (hemispherical)"
    values, _ = kbc.reference_values(1.0, 2.0, refs[1])
    assert values == kbc.kb_values(1.0, 2.0, "surface")[0]


def test_explicit_reference_wins():
    data = example_data("tnt-height-of-burst")
    data["output"]["gauge_references"] = ["incident", "surface-incident", "auto", "auto", "reflected", "auto"]
    sc = parse(data)
    refs = kbc.scenario_references(sc, [0.0, 1.0], "free-air", 0.02)
    assert (refs[0]["kind"], refs[0]["burst"], refs[0]["source"]) == ("incident", "free-air", "set")
    assert (refs[1]["kind"], refs[1]["burst"]) == ("incident", "surface")
    assert refs[2]["kind"] == "reflected" and refs[2]["source"] == "auto"
    # reflected in free air: as if the gauge faced the charge (normal incidence)
    assert (refs[4]["kind"], refs[4]["angle_of_incidence_deg"], refs[4]["source"]) == ("reflected", 0.0, "set")
    assert refs[5]["kind"] == "incident"
    with pytest.raises(ValueError, match="gauge reference"):
        ref_of([2.5, 1.0, 1.0], override="side-on")


@pytest.mark.parametrize("refs, match", [
    (["auto", "incident", "bogus", "auto", "auto", "auto"], r"output\.gauge_references\[2\]"),
    (["auto", "incident"], r"output\.gauge_references: 2 entries for 6 gauges"),
    ("reflected", r"output\.gauge_references"),
])
def test_bad_gauge_references_are_rejected_naming_the_key(refs, match):
    data = example_data("tnt-height-of-burst")
    data["output"]["gauge_references"] = refs
    with pytest.raises(ScenarioError, match=match):
        parse(data)


def test_gauge_references_need_a_charge_and_are_euler_only():
    data = example_data("sedov-axisym")
    data["output"]["gauges"] = data["output"].get("gauges") or [[0.1, 0.1]]
    data["output"]["gauge_references"] = ["auto"] * len(data["output"]["gauges"])
    with pytest.raises(ScenarioError, match=r"output\.gauge_references"):
        parse(data)
    cfdmp = example_data("he-slab-2d")
    cfdmp.setdefault("output", {})["gauge_references"] = []
    with pytest.raises(ScenarioError, match=r"output\.gauge_references: unknown key"):
        parse(cfdmp)


def test_one_d_free_air_comparison_is_unchanged_and_named():
    gauges = [{"position": 2.0, "peak_overpressure": 1e5, "impulse": 50.0, "arrival_time": 1e-3}]
    out = kbc.compare(gauges, [2.0], 1.0, "free-air")[0]
    assert out["kb"]["reference"] == "free-air incident" and out["kb"]["kind"] == "incident"
    for key, value in kbc.kb_values(1.0, 2.0, "free-air")[0].items():
        assert out["kb"][key] == value


def test_kb_plot_labels_the_reference(tmp_path):
    from blastfsi.plotting.kb import kb_gauge_histories

    t = np.linspace(0.0, 5e-3, 50)
    hist = {"time": t, "gauge0_overpressure": np.full_like(t, 1e5), "gauge1_overpressure": np.full_like(t, 1e4)}
    refs = [kbc.reflected_reference(0.0), kbc.incident_reference()]
    kb_gauge_histories(tmp_path / "kb.png", hist, [[0.0, 0.0], [2.0, 1.0]], 1.0, "free-air", centre=[0.0, 1.0],
                       references=refs)
    assert (tmp_path / "kb.png").stat().st_size > 0
