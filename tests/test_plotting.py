"""Plots fit their event: units chosen from the data, every axis labelled with its unit, no offset or exponent
text, r-z plots labelled r and z, one panel per gauge, 1D damage as profiles."""
import numpy as np
import pytest

from blastfsi.plotting.fields import particle_damage_figure, pressure_field_figure
from blastfsi.plotting.histories import gauge_histories_figure, plate_histories_figure, tracer_histories_figure
from blastfsi.plotting.kb import kb_gauge_histories_figure
from blastfsi.plotting.units import scale, text


@pytest.mark.parametrize("values, quantity, factor, unit", [
    ([3.0e7], "pressure", 1e6, "MPa"),          # not "30000 kPa"
    ([-2.0e4, 1.5e5], "pressure", 1e3, "kPa"),  # the largest magnitude decides
    ([2.5e9], "pressure", 1e9, "GPa"),
    ([999.0], "pressure", 1.0, "Pa"),
    ([1.75e-5], "time", 1e-6, "µs"),            # not "0.0175 ms"
    ([0.015], "time", 1e-3, "ms"),
    ([3.0], "time", 1.0, "s"),
    ([4e-10], "time", 1e-9, "ns"),              # below the smallest prefix: the smallest
    ([0.5], "length", 1e-3, "mm"),
    ([2.15], "length", 1.0, "m"),
    ([1200.0], "length", 1.0, "m"),             # no km: the largest offered
    ([5e4], "energy", 1e3, "kJ"),
    ([0.0, np.nan], "pressure", 1.0, "Pa"),     # nothing finite and non-zero: the base unit
    ([np.inf, 2e6], "pressure", 1e6, "MPa"),    # non-finite values ignored
])
def test_scale_point_values(values, quantity, factor, unit):
    s = scale(values, quantity)
    assert s.factor == pytest.approx(factor, rel=1e-15) and s.unit == unit
    assert s.label("p") == f"p [{unit}]"


def test_scale_keeps_axis_numbers_between_1_and_1000():
    # within the prefixes offered (1 Pa to < 1000 GPa, 1 ns to < 1000 s) every magnitude reads 1 to < 1000
    for quantity, lowest, highest in (("pressure", 0.0, 11.99), ("time", -9.0, 2.99)):
        for v in np.logspace(lowest, highest, 97):
            assert 1.0 <= v / scale([v], quantity).factor < 1000.0, (quantity, v)


def test_text_and_bad_quantity():
    assert text(1.75e-5, "time") == "17.5 µs"
    assert text(3.0e7, "pressure") == "30 MPa"
    with pytest.raises(ValueError, match="quantity must be one of"):
        scale([1.0], "speed")


def offsets(fig) -> list[str]:
    """The offset / exponent text of every axis of a drawn figure ("" where there is none)."""
    fig.canvas.draw()
    return [axis.get_offset_text().get_text() for ax in fig.axes for axis in (ax.xaxis, ax.yaxis)]


def close(fig):
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_microsecond_event_gauges_in_us_and_mpa_one_panel_each():
    t = np.linspace(0.0, 20e-6, 201)  # a close-in event: 20 µs
    near = 3.0e7 * np.exp(-((t - 5e-6) / 1e-6) ** 2)  # 30 MPa
    far = 4.0e4 * np.exp(-((t - 15e-6) / 2e-6) ** 2)  # 40 kPa
    fig = gauge_histories_figure([{"time": t, "gauge0_overpressure": near, "gauge1_overpressure": far}],
                                 [[0.0, 0.05], [0.0, 0.2]])
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.lines]
    assert len(panels) == 2  # one panel per gauge
    assert panels[0].get_ylabel() == "overpressure [MPa]" and panels[1].get_ylabel() == "overpressure [kPa]"
    assert panels[-1].get_xlabel() == "time [µs]"
    assert np.max(panels[0].lines[0].get_ydata()) == pytest.approx(30.0, rel=1e-2)
    assert np.max(panels[0].lines[0].get_xdata()) == pytest.approx(20.0, rel=1e-12)
    assert "50 mm" in panels[0].get_title() or "(0, 50) mm" in panels[0].get_title()
    assert set(offsets(fig)) == {""}
    close(fig)


def test_far_gauges_readable_and_unreached_gauge_not_magnified():
    t = np.linspace(0.0, 0.03, 301)
    hist = {"time": t}
    for k, peak in enumerate([3.4e6, 9.0e5, 1.7e5, 3.0e4]):
        hist[f"gauge{k}_overpressure"] = peak * np.exp(-((t - 0.004 * (k + 1)) / 1e-3) ** 2)
    hist["gauge4_overpressure"] = 1e-11 * np.sin(1e4 * t)  # not reached: round-off only
    fig = gauge_histories_figure([hist], [0.5, 1.0, 2.0, 5.0, 10.0])
    panels = [ax for ax in fig.axes if ax.lines]
    assert len(panels) == 5
    assert [ax.get_ylabel() for ax in panels] == ["overpressure [MPa]"] + ["overpressure [kPa]"] * 3 + \
        ["overpressure [Pa]"]
    for ax, peak in zip(panels[:4], (3.4, 900.0, 170.0, 30.0)):  # each far gauge fills its own panel
        assert ax.get_ylim()[1] == pytest.approx(peak, rel=0.15)
    assert panels[4].get_ylim() == (-1.0, 1.0)
    assert all(ax.get_xlabel() in ("", "time [ms]") for ax in panels)
    assert sum(ax.get_xlabel() == "time [ms]" for ax in panels) == 2  # the lowest panel of each column
    assert set(offsets(fig)) == {""}
    close(fig)


def test_pressure_field_colour_bar_has_no_offset_and_r_z_labels():
    r, z = np.meshgrid(np.arange(30) + 0.5, np.arange(20) + 0.5, indexing="ij")
    p = 101325.0 + 5.0 * r + z  # a narrow range about 1 atm: matplotlib would write "+1.013e2" over the bar
    fig = pressure_field_figure((0.0, 0.0), 0.002, p, axis_labels=("r", "z"), title="t")
    ax, bar = fig.axes
    assert ax.get_xlabel() == "r [mm]" and ax.get_ylabel() == "z [mm]"
    assert bar.get_ylabel() == "pressure [kPa]"
    assert ax.get_xlim() == pytest.approx((0.0, 60.0)) and ax.get_ylim() == pytest.approx((0.0, 40.0))
    assert set(offsets(fig)) == {""}
    close(fig)
    fig = pressure_field_figure((0.0, 0.0, 0.0), 1.0, np.full((4, 5, 6), 3e7), z_plane=2.0)
    assert fig.axes[0].get_xlabel() == "x [m]" and fig.axes[1].get_ylabel() == "pressure [MPa]"
    assert "z = 2 m" in fig.axes[0].get_title()
    close(fig)


def test_one_d_damage_profiles():
    x = np.linspace(0.0, 0.03, 300)[:, None]
    tensile = np.where(np.abs(x[:, 0] - 0.02) < 0.001, 1.0, 0.1)  # a spall plane at 20 mm
    fig = particle_damage_figure(x, tensile, cell_size=1e-4, profiles={"tensile damage": tensile,
                                                                       "compressive damage": 0.0 * tensile})
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel() == "damage [-]"
    assert [line.get_label() for line in ax.lines] == ["damage", "tensile damage", "compressive damage"]
    peak = ax.lines[1].get_xdata()[np.argmax(ax.lines[1].get_ydata())]
    assert abs(peak - 20.0) < 1.0
    close(fig)


def test_plate_tracer_and_kb_histories_units():
    t = np.linspace(0.0, 2e-3, 101)
    hist = {"time": t, "plate_overpressure": 2e6 * np.exp(-t / 2e-4), "plate_impulse": 400.0 * (1 - np.exp(-t / 2e-4)),
            "plate_displacement": 0.03 * t / t[-1], "plate_velocity": 15.0 * np.ones_like(t),
            "tracer0_displacement_r": 0.0 * t, "tracer0_displacement_z": -0.004 * t / t[-1],
            "gauge0_overpressure": 2e5 * np.exp(-((t - 1e-3) / 1e-4) ** 2)}
    fig = plate_histories_figure([hist], [{}])
    assert [ax.get_ylabel() for ax in fig.axes] == ["overpressure on plate [MPa]", "transmitted impulse [Pa s]",
                                                     "plate displacement [mm]", "plate velocity [m/s]"]
    assert fig.axes[2].get_xlabel() == "time [ms]" and set(offsets(fig)) == {""}
    close(fig)
    fig = tracer_histories_figure([hist], [[0.0, 0.105]], ("r", "z"))
    assert fig.axes[0].get_ylabel() == "displacement [mm]" and fig.axes[0].get_xlabel() == "time [ms]"
    assert fig.axes[0].lines[1].get_label() == "(0, 105) mm, z"
    close(fig)
    # an r-z cfdmp history names its columns x and y: the legend still says r and z
    xy = {"time": t, "tracer0_displacement_x": hist["tracer0_displacement_r"],
          "tracer0_displacement_y": hist["tracer0_displacement_z"]}
    fig = tracer_histories_figure([xy], [[0.0, 0.105]], ("x", "y"), labels=("r", "z"))
    assert [line.get_label() for line in fig.axes[0].lines] == ["(0, 105) mm, r", "(0, 105) mm, z"]
    close(fig)
    fig = kb_gauge_histories_figure(hist, [2.0], 1.0)
    assert fig.axes[0].get_xlabel() == "time [ms]" and fig.axes[0].get_ylabel() == "overpressure [kPa]"
    assert set(offsets(fig)) == {""}
    close(fig)
