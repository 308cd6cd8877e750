"""Concrete slab under a charge (000 Sec. 5.3): the empirical crushing diameter (Eq. 67), the face-damage
diagnostic that measures it on a run, and the constitutive models' snapshot fields it reads."""
import math

import numpy as np
import pytest

from blastfsi import constitutive, mpm
from blastfsi.constitutive import hjc, johnson_cook
from blastfsi.diagnostics import damage
from blastfsi.exact.concrete_crushing import charge_mass, crushing_diameter
from blastfsi.materials import SOLIDS


def test_eq67_reproduces_the_tests_it_was_fitted_to():
    # ERRATA 13: Eq. (67) gives ~250 mm at 4 kg and ~300 mm at 10 kg, h = 0.5 m (the tests' values)
    assert crushing_diameter(4.0, 0.5) == pytest.approx(0.250, rel=0.02)
    assert crushing_diameter(10.0, 0.5) == pytest.approx(0.300, rel=0.02)


def test_eq67_inverse_and_limits():
    for w in (0.5, 2.0, 20.0):
        assert charge_mass(crushing_diameter(w, 0.5), 0.5) == pytest.approx(w, rel=1e-12)
    # W -> 0: D -> h / 3.63; D grows with W
    assert crushing_diameter(1e-18, 0.5) == pytest.approx(0.5 / 3.63, rel=1e-6)  # exp(3.7e-7)
    assert crushing_diameter(20.0, 0.5) > crushing_diameter(2.0, 0.5)
    with pytest.raises(ValueError, match="mass"):
        crushing_diameter(-1.0, 0.5)
    with pytest.raises(ValueError, match="height"):
        crushing_diameter(4.0, math.nan)
    with pytest.raises(ValueError, match="diameter must exceed"):
        charge_mass(0.1, 0.5)


def _ring_face(radius, ring_width, spacing):
    """Particles of a slab's top layer on an r-z lattice (two rows), ring volumes 2 pi r s^2."""
    r = (np.arange(int(radius / spacing)) + 0.5) * spacing
    z = np.array([-0.5, -1.5]) * spacing
    R, Z = np.meshgrid(r, z, indexing="ij")
    x = np.stack([R.ravel(), Z.ravel()], axis=1)
    return x, 2.0 * np.pi * x[:, 0] * spacing ** 2


def test_connected_diameter_of_a_crushed_disk_ignores_damage_at_the_edge():
    s, h = 0.0025, 0.005  # particle spacing, cell (ring width)
    x, vol = _ring_face(0.75, h, s)
    crushed_radius = 0.13
    dmg = np.where(x[:, 0] < crushed_radius, 1.0, 0.1)
    dmg[x[:, 0] > 0.7] = 1.0  # the slab's edge, failed and apart from the crushed zone
    out = damage.damaged_face(x, vol, dmg, normal_axis=1, side="upper", spacing=s, rows=2,
                              load_axis=np.zeros(2), ring_width=h)
    at1 = out["by_threshold"][-1]
    # the rings are cut at multiples of h; the disk's edge falls inside one: one ring width at most
    assert at1["diameter"] == pytest.approx(2 * crushed_radius, abs=2 * h)
    disk_and_edge = math.pi * crushed_radius ** 2 + math.pi * (0.75 ** 2 - 0.7 ** 2)
    assert at1["area"] == pytest.approx(disk_and_edge, rel=0.02)
    assert at1["equivalent_diameter"] == pytest.approx(2 * math.sqrt(disk_and_edge / math.pi), rel=0.01)
    assert out["face_area"] == pytest.approx(math.pi * 0.75 ** 2, rel=1e-12)
    # threshold 0.05: everything damaged, the whole face
    low = damage.damaged_face(x, vol, dmg, normal_axis=1, side="upper", spacing=s, rows=2,
                              load_axis=np.zeros(2), ring_width=h, thresholds=(0.05,))
    assert low["by_threshold"][0]["diameter"] == pytest.approx(1.5, abs=h)


def test_face_layer_is_the_outer_rows_only_and_undamaged_axis_gives_zero():
    s, h = 0.0025, 0.005
    x, vol = _ring_face(0.3, h, s)
    deeper = x.copy()
    deeper[:, 1] -= 2 * s  # two rows below the face layer: failed, but not on the face
    xs, vols = np.concatenate([x, deeper]), np.concatenate([vol, vol])
    dmg = np.concatenate([np.zeros(len(x)), np.ones(len(x))])
    out = damage.damaged_face(xs, vols, dmg, normal_axis=1, side="upper", spacing=s, rows=2,
                              load_axis=np.zeros(2), ring_width=h)
    assert all(r["diameter"] == 0.0 and r["area"] == 0.0 for r in out["by_threshold"])
    back = damage.damaged_face(xs, vols, dmg, normal_axis=1, side="lower", spacing=s, rows=2,
                               load_axis=np.zeros(2), ring_width=h)
    assert back["by_threshold"][-1]["diameter"] == pytest.approx(0.6, abs=h)


def test_quarter_model_mirrors_to_the_full_disk():
    s = 0.01
    g = (np.arange(60) + 0.5) * s
    X, Y = np.meshgrid(g, g, indexing="ij")
    x = np.stack([X.ravel(), Y.ravel(), np.full(X.size, -0.5 * s)], axis=1)
    dmg = (np.hypot(x[:, 0], x[:, 1]) < 0.2).astype(float)
    out = damage.damaged_face(x, np.full(len(x), s ** 3), dmg, normal_axis=2, side="upper", spacing=s, rows=1,
                              load_axis=np.zeros(3), ring_width=s, mirror=4.0)
    at1 = out["by_threshold"][-1]
    assert at1["equivalent_diameter"] == pytest.approx(0.4, rel=0.03)  # the lattice's staircase of the circle
    assert at1["diameter"] == pytest.approx(0.4, abs=2 * s)


def test_model_output_fields_split_the_damages_and_give_nan_elsewhere():
    concrete = hjc.params_from(SOLIDS["concrete-25mpa"])
    steel = johnson_cook.params_from(SOLIDS["steel-rha"])
    models = (constitutive.get("hjc"), constitutive.get("johnson-cook"))
    history = np.zeros((4, 4))
    history[0] = [0.01, 0.002, 0.3, 0.0]  # HJC: D = 0.3, L = 0 (virgin tensile damage D_t0)
    history[1] = [0.01, 0.002, 1.0, 50.0]  # HJC: crushed, L large: D_t -> 1
    history[2, 0] = 12.5  # JC temperature rise [K]
    material = np.array([0, 0, 1, 1])
    out = mpm.model_output_fields(material, history, models, (concrete, steel))
    assert out["compressive_damage"][:2].tolist() == [0.3, 1.0]
    assert out["tensile_damage"][0] == pytest.approx(SOLIDS["concrete-25mpa"].initial_tensile_damage, rel=1e-12)
    assert out["tensile_damage"][1] == pytest.approx(1.0, abs=1e-12)
    assert out["temperature"][2:].tolist() == [steel.room_temperature + 12.5, steel.room_temperature]
    assert np.isnan(out["compressive_damage"][2:]).all() and np.isnan(out["temperature"][:2]).all()


def test_breach_diameter_is_where_half_the_thickness_failed():
    s, h = 0.0025, 0.005
    r = (np.arange(200) + 0.5) * s
    z = -(np.arange(8) + 0.5) * s  # 8 rows through the thickness
    R, Z = np.meshgrid(r, z, indexing="ij")
    x = np.stack([R.ravel(), Z.ravel()], axis=1)
    vol = 2.0 * np.pi * x[:, 0] * s ** 2
    # failed through the whole thickness for r < 0.1, through the lower 3 rows (3/8 < 1/2) beyond
    dmg = np.where((x[:, 0] < 0.1) | (x[:, 1] < -4.5 * s), 1.0, 0.2)
    d = damage.breach_diameter(x, vol, dmg, normal_axis=1, load_axis=np.zeros(2), ring_width=h)
    assert d == pytest.approx(0.2, abs=2 * h)


def test_annulus_zone_is_measured_from_its_inner_edge():
    s, h = 0.0025, 0.005
    x, vol = _ring_face(0.75, h, s)
    ring = x[:, 0] >= 0.1  # the body around a defect of radius 0.1 m
    x, vol = x[ring], vol[ring]
    dmg = np.where(x[:, 0] < 0.2, 1.0, 0.0)
    out = damage.damaged_face(x, vol, dmg, normal_axis=1, side="upper", spacing=s, rows=2,
                              load_axis=np.zeros(2), ring_width=h)
    assert out["by_threshold"][-1]["diameter"] == pytest.approx(0.4, abs=2 * h)
    undamaged_edge = damage.damaged_face(x, vol, np.where(x[:, 0] > 0.3, 1.0, 0.0), normal_axis=1, side="upper",
                                         spacing=s, rows=2, load_axis=np.zeros(2), ring_width=h)
    assert undamaged_edge["by_threshold"][-1]["diameter"] == 0.0


def test_sides_toward_the_load():
    z = np.array([-0.15, -0.1, 0.0])
    assert damage.sides_toward(0.5, z) == ("upper", "lower")
    assert damage.sides_toward(-1.0, z) == ("lower", "upper")
    assert damage.sides_toward(-0.05, z) is None
