"""The command line, the results directory and its files read back with real readers."""
import json
import subprocess
import sys

import h5py
import meshio
import numpy as np
import pytest

from blastfsi.io.results import read_history

SUMMARY_KEYS = {"plate_velocity", "plate_displacement", "plate_impulse", "peak_overpressure", "beta_s",
                "reflection_coefficient_theory", "impulse_ratio_theory", "impulse_ratio"}


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "blastfsi.cli", *args], capture_output=True, text=True, cwd=cwd)


def test_examples_listed():
    proc = cli("examples")
    assert proc.returncode == 0
    for name in ("plate1d-uniform", "plate1d-exponential", "plate1d-sedov"):
        assert name in proc.stdout


def test_run_example_json_and_results_directory(tmp_path):
    out = tmp_path / "res"
    proc = cli("run", "--example", "plate1d-uniform", "--set", "grid.cells=300", "--set", "domain.length=1.0",
               "--set", "time.end=0.0016", "--set", "output.plots=true", "--out", str(out), "--json")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)  # nothing but one JSON object on stdout
    assert SUMMARY_KEYS <= summary.keys()
    assert summary["plate_velocity"] > 0 and summary["plate_impulse"] > 0
    for f in ("scenario.toml", "summary.json", "history.csv", "plots/plate_histories.png", "fields/member0.xdmf"):
        assert (out / f).is_file(), f
    hist = read_history(out / "history.csv")
    assert hist["time"][0] == 0.0 and abs(hist["time"][-1] - 0.0016) < 1e-15
    header = (out / "history.csv").read_text().splitlines()[0]
    assert "time [s]" in header and "plate_overpressure [Pa]" in header
    with h5py.File(out / "fields" / "snap_0010.h5", "r") as f:
        assert abs(f.attrs["time"] - 0.0016) < 1e-15
        x = f["member0/coordinates"][:, 0]
        assert x.size == 301 and np.all(np.diff(x) > 0)
        assert f["member0/pressure"].shape == (300,)
    # ParaView's XDMF index, read by meshio: the time series and the zone fields
    series = meshio.xdmf.TimeSeriesReader(str(out / "fields" / "member0.xdmf"))
    points, cells = series.read_points_cells()
    assert points.shape == (301, 3) and cells[0].type == "line" and len(cells[0].data) == 300
    assert series.num_steps == 11
    t, point_data, cell_data = series.read_data(10)
    assert t == pytest.approx(0.0016, rel=1e-15)
    with h5py.File(out / "fields" / "snap_0010.h5", "r") as f:
        np.testing.assert_array_equal(cell_data["pressure"][0], f["member0/pressure"][()])
        np.testing.assert_array_equal(point_data["velocity"], f["member0/velocity"][()])
    # a second run into the same directory is refused (exit 4), nothing overwritten
    again = cli("run", "--example", "plate1d-uniform", "--out", str(out))
    assert again.returncode == 4 and "exists" in again.stderr


def test_default_results_directory_is_never_reused(tmp_path):
    args = ("run", "--example", "plate1d-uniform", "--set", "grid.cells=100", "--set", "domain.length=0.5",
            "--set", "time.end=0.0008", "--set", "output.fields=0", "--set", "output.plots=false", "--json")
    assert cli(*args, cwd=tmp_path).returncode == 0
    assert cli(*args, cwd=tmp_path).returncode == 0
    assert (tmp_path / "results" / "plate1d-uniform" / "summary.json").is_file()
    assert (tmp_path / "results" / "plate1d-uniform-2" / "summary.json").is_file()


def test_exponential_and_sedov_examples_run(tmp_path):
    proc = cli("run", "--example", "plate1d-exponential", "--set", "grid.cells=600", "--set", "time.end=0.006",
               "--set", "output.fields=0", "--set", "output.plots=false", "--out", str(tmp_path / "e"), "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["plate_impulse"] > 0
    # the sedov example is an ensemble (2 mm and 20 mm plates): each key holds one value per member
    proc = cli("run", "--example", "plate1d-sedov", "--set", "grid.cells=640", "--set", "time.end=0.004",
               "--set", "output.fields=2", "--set", "output.plots=false", "--out", str(tmp_path / "s"), "--json")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert SUMMARY_KEYS <= summary.keys() and len(summary["plate_velocity"]) == 2
    light, heavy = summary["plate_velocity"]
    assert light > heavy > 0  # same loading, 10x the mass
    assert summary["peak_overpressure"][0] == pytest.approx(summary["peak_overpressure"][1], rel=0.05)
    for k in (0, 1):
        assert read_history(tmp_path / "s" / f"history_member{k}.csv")["time"][-1] == 0.004
        assert (tmp_path / "s" / "fields" / f"member{k}.xdmf").is_file()


@pytest.mark.parametrize("flags, message", [
    (["--processes", "2"], "--processes given without --coordinator, --process-id"),
    (["--coordinator", "127.0.0.1:1", "--process-id", "0"], "--coordinator, --process-id given without --processes"),
    (["--coordinator", "127.0.0.1:1", "--processes", "2", "--process-id", "2"],
     "--process-id 2 with --processes 2: expected --processes >= 1 and 0 <= --process-id <= 1"),
    (["--coordinator", "127.0.0.1:1", "--processes", "0", "--process-id", "0"], "expected --processes >= 1"),
])
def test_several_hosts_flags_checked_before_joining(tmp_path, flags, message):
    proc = cli("run", "--example", "sod", "--out", str(tmp_path / "r"), *flags)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr
    assert not (tmp_path / "r").exists()
