"""Nothing lost (issue 36): --overwrite and --out, results written as the run goes, Ctrl-C, unreadable
checkpoints, an emptied cfdmp box, and SIGKILL then --restart bit for bit for every method.

The runs are tiny versions of shipped examples. Subprocesses share one persistent compilation cache (a
temporary folder), so each method's time loop is compiled once for the whole file (a kill test's reference
and killed runs share one process).
"""
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import jax
import numpy as np
import pytest
import tomli_w

from blastfsi import api, cli, simulation
from blastfsi.io import results
from blastfsi.io.results import read_history
from test_io_fields import Series, blocks

COMMON = {"output.fields": 3, "output.history_samples": 41, "output.plots": False}
# the box's gas separates at 1.5 km/s each way from x = 0.625 m: the box (0.5 to 0.75 m) has no particle left
# by the snapshot at 0.15 ms, before the second checkpoint (0.2 ms), from which the kill test restarts
EMPTYING_BOX = {"grid.cells": 40, "mpm_region.bridge_cells": 2, "initial.diaphragm": 0.625, "time.end": 3e-4,
                "initial.left": {"material": "air", "density": 1.0, "pressure": 1e4, "velocity": -1500.0},
                "initial.right": {"material": "air", "density": 1.0, "pressure": 1e4, "velocity": 1500.0},
                "output.checkpoint_interval": 1e-4}
TINY = {  # method: (example, overrides); each with 3 snapshots and 3 or 4 checkpoints
    "lagrangian1d": ("plate1d-uniform", {"grid.cells": 60, "domain.length": 0.5, "time.end": 8e-4,
                                         "output.checkpoint_interval": 2e-4}),
    "euler": ("sod", {"grid.cells": 40, "output.checkpoint_interval": 4e-5}),
    "mpm": ("mpm-sod", {"grid.cells": 40, "output.checkpoint_interval": 4e-5}),
    "cfdmp": ("cfdmp-shock-tube", EMPTYING_BOX),
}
TIMINGS = {"wall_time", "compile_time", "loop_time", "output_time"}
# runs scenario argv[2] with the command line twice in one process (one compilation): uninterrupted into
# argv[3], then into argv[4], killed (SIGKILL) right after it writes checkpoint number argv[1]
REFERENCE_THEN_KILLED = """
import os, signal, sys
from blastfsi import cli
from blastfsi.io import results
n, scenario, reference, killed = sys.argv[1:]
assert cli.main(["run", scenario, "--out", reference, "--json"]) == 0
write = results.write_checkpoint
def write_then_die(path, index, *args):
    file = write(path, index, *args)
    if index == int(n):
        os.kill(os.getpid(), signal.SIGKILL)
    return file
results.write_checkpoint = write_then_die
cli.main(["run", scenario, "--out", killed, "--json"])
"""


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    cache = tmp_path_factory.mktemp("xla-cache")
    return {**os.environ, "JAX_COMPILATION_CACHE_DIR": str(cache), "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0"}


def tiny(method: str, checkpoints: bool = True, **more) -> dict:
    example, overrides = TINY[method]
    data = api.load(example, set={**COMMON, **overrides, **more})
    if not checkpoints:
        del data["output"]["checkpoint_interval"]
    return data


def scenario_file(tmp_path, data: dict):
    file = tmp_path / "s.toml"
    file.write_text(tomli_w.dumps(data))
    return file


def python(*args, env):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env)


def assert_same_h5(a, b):
    """Same groups, datasets (dtype and values, NaN where NaN) and attributes."""
    with h5py.File(a) as fa, h5py.File(b) as fb:
        names = []
        fa.visit(names.append)
        other = []
        fb.visit(other.append)
        assert names == other, b
        for name in ["/", *names]:
            x, y = fa[name], fb[name]
            assert x.attrs.keys() == y.attrs.keys(), name
            for key in x.attrs:
                np.testing.assert_array_equal(x.attrs[key], y.attrs[key])
            if isinstance(x, h5py.Dataset):
                assert x.dtype == y.dtype, name
                np.testing.assert_array_equal(x[()], y[()], err_msg=f"{b}: {name}")


# ------------------------------------------------------------------------------------- --out and --overwrite
def test_overwrite_refuses_a_directory_that_is_not_a_results_directory(tmp_path, capsys):
    mine = tmp_path / "mine"
    (mine / "fields").mkdir(parents=True)
    (mine / "fields" / "keep.dat").write_text("a user's file")
    (mine / "scenario.toml").write_text("name = 'mine'")
    file = scenario_file(tmp_path, tiny("lagrangian1d"))
    assert cli.main(["run", str(file), "--out", str(mine), "--overwrite", "--quiet"]) == cli.EXIT_OUTPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{mine} is not a blastfsi results directory" in err
    assert (mine / "fields" / "keep.dat").read_text() == "a user's file"
    assert sorted(p.name for p in mine.rglob("*")) == ["fields", "keep.dat", "scenario.toml"]


def test_overwrite_leaves_nothing_of_the_earlier_run(tmp_path, capsys):
    out = tmp_path / "out"
    # an earlier run: an ensemble of two (history_member<k>.csv), 3 snapshots, 4 checkpoints
    api.run(tiny("lagrangian1d", **{"sweep.beta_s": [1.0, 2.0]}), out=out)
    (out / "fields" / "sub").mkdir()  # (a folder inside fields/ is removed, not a traceback)
    (out / "fields" / "sub" / "x.txt").write_text("x")
    file = scenario_file(tmp_path, tiny("lagrangian1d", checkpoints=False, **{"output.fields": 1}))
    assert cli.main(["run", str(file), "--out", str(out), "--overwrite", "--json"]) == 0, capsys.readouterr().err
    left = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert left == [".blastfsi", "checkpoints", "fields", "fields/member0.xdmf", "fields/member0_0000.xdmf",
                    "fields/snap_0000.h5", "history.csv",
                    "plots", "scenario.toml", "summary.json"]


@pytest.mark.parametrize("where", ["a file", "under a file"])
def test_out_that_cannot_be_a_directory_is_one_line_exit_4(tmp_path, capsys, where):
    (tmp_path / "f").write_text("not a directory")
    out = tmp_path / "f" if where == "a file" else tmp_path / "f" / "out"
    file = scenario_file(tmp_path, tiny("lagrangian1d"))
    assert cli.main(["run", str(file), "--out", str(out), "--quiet"]) == cli.EXIT_OUTPUT
    err = capsys.readouterr().err
    assert err.startswith(f"error: results directory {out} ") and err.count("\n") == 1
    assert (tmp_path / "f").read_text() == "not a directory"


def test_default_results_directory_skips_a_file_of_its_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "plate1d-uniform").write_text("a file")
    file = scenario_file(tmp_path, tiny("lagrangian1d", checkpoints=False))
    assert cli.main(["run", str(file), "--json"]) == 0
    assert "results written to results/plate1d-uniform-2" in capsys.readouterr().err


# ----------------------------------------------------------------------------------- unreadable checkpoints
def test_restart_falls_back_to_the_newest_readable_checkpoint(tmp_path, capsys):
    out = tmp_path / "out"
    api.run(tiny("lagrangian1d"), out=out)
    history = (out / "history.csv").read_bytes()
    ckpt = out / "checkpoints"
    assert sorted(p.name for p in ckpt.iterdir()) == [f"ckpt_000{k}.h5" for k in (1, 2, 3, 4)]
    (ckpt / "ckpt_0004.h5").write_bytes(b"")  # zero bytes
    (ckpt / "ckpt_0003.h5").write_bytes((ckpt / "ckpt_0003.h5").read_bytes()[:5000])  # truncated
    (ckpt / "ckpt_0005.h5").mkdir()  # a directory named like a checkpoint
    (ckpt / "ckpt_0006.h5").write_bytes(np.random.default_rng(0).bytes(3000))  # garbage
    (out / "history.csv").unlink()
    (out / "summary.json").unlink()
    assert cli.main(["run", "--restart", str(out), "--json"]) == 0
    err = capsys.readouterr().err
    for k in (3, 4, 5, 6):
        assert f"unreadable checkpoint skipped: {ckpt / f'ckpt_000{k}.h5'}" in err
    assert f"continuing from {ckpt / 'ckpt_0002.h5'}" in err
    assert (out / "history.csv").read_bytes() == history
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"
    # none readable: exit 4 naming them
    for f in ckpt.glob("ckpt_*.h5"):
        if f.is_file():
            f.write_bytes(b"garbage")
    assert cli.main(["run", "--restart", str(out), "--quiet"]) == cli.EXIT_OUTPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: --restart: no readable checkpoint in {ckpt}")
    assert all(f"ckpt_000{k}.h5" in err for k in range(1, 7))


# -------------------------------------------------------------------------------------------------- Ctrl-C
def test_ctrl_c_stops_cleanly_with_checkpoint_history_and_summary(tmp_path, env):
    # the tiny euler run made long (~2.5e5 steps, ~10 s; the euler kill test's loop, compiled once): Ctrl-C
    # once its first checkpoint is on disk
    out = tmp_path / "out"
    file = scenario_file(tmp_path, tiny("euler", **{"time.end": 2.5, "output.checkpoint_interval": 0.01}))
    run = subprocess.Popen([sys.executable, "-m", "blastfsi.cli", "run", str(file), "--out", str(out), "--json"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    while not (out / "checkpoints" / "ckpt_0001.h5").exists() and run.poll() is None:
        time.sleep(0.01)
    run.send_signal(signal.SIGINT)
    stdout, stderr = run.communicate(timeout=60)
    assert run.returncode == 130 and stdout == "" and "Traceback" not in stderr, stderr
    assert stderr.endswith(f"; continue with: blastfsi run --restart {out}\n")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and 0.01 <= summary["time"] < 2.5
    newest = sorted((out / "checkpoints").glob("ckpt_*.h5"))[-1]
    assert f"checkpoint {newest}" in stderr
    leaves, meta = results.read_checkpoint(newest)
    assert meta["time"] == summary["time"] == leaves["t"][0] and leaves["step"][0] == summary["steps"]
    hist = read_history(out / "history.csv")
    assert hist["time"][0] == 0.0 and hist["time"][-1] <= summary["time"] < hist["time"][-1] + 2.5 / 40


def test_interrupted_mid_chunk_then_restarted_is_bit_for_bit(tmp_path, monkeypatch):
    data = tiny("lagrangian1d")
    full = simulation.run(data, tmp_path / "full", chunk_steps=50)
    out = tmp_path / "out"
    update, handler = simulation._Progress.update, signal.getsignal(signal.SIGINT)

    def ctrl_c_while_running(self, t, step):  # (between chunks, the first Python the signal can run in)
        if 2.5e-4 < t < 4e-4:
            signal.raise_signal(signal.SIGINT)
        update(self, t, step)

    monkeypatch.setattr(simulation._Progress, "update", ctrl_c_while_running)
    with pytest.raises(simulation.RunInterrupted, match=r"interrupted at t = .*ckpt_0001_interrupted\.h5"):
        simulation.run(data, out, chunk_steps=50)
    monkeypatch.undo()
    assert signal.getsignal(signal.SIGINT) is handler
    summary = json.loads((out / "summary.json").read_text())
    leaves, meta = results.read_checkpoint(out / "checkpoints" / "ckpt_0001_interrupted.h5")
    assert summary["status"] == "interrupted" and 2.5e-4 < meta["time"] == summary["time"] < 4e-4
    again = simulation.run(data, out, restart=True, chunk_steps=50)
    assert (out / "history.csv").read_bytes() == (tmp_path / "full" / "history.csv").read_bytes()
    for a, b in zip(jax.tree_util.tree_leaves(full.state), jax.tree_util.tree_leaves(again.state)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    for f in (tmp_path / "full" / "fields").glob("*.h5"):
        assert_same_h5(f, out / "fields" / f.name)


# -------------------------------------------------------------------------------------------------- a fault
def test_fault_keeps_the_history_and_marks_the_summary_failed(tmp_path):
    """A run stopped on a non-physical state keeps its history to the fault, marks the summary failed and writes
    the faulted state's fields as the last snapshot of the series (where it went wrong, for ParaView)."""
    # no artificial viscosity: the captured shock rings until an energy goes negative (0.65 ms), after 3 checkpoints
    data = tiny("lagrangian1d", **{"numerics.K1": 0.0, "numerics.K2": 0.0, "numerics.cfl": 1.0,
                                   "time.dt_min_fraction": 0.0})
    with pytest.raises(simulation.SimulationError) as err:
        simulation.run(data, tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "failed" and f"{summary['error']}; history to the fault" in str(err.value)
    t_fault = float(str(err.value).split("t = ")[1].split()[0])
    hist = read_history(tmp_path / "history.csv")
    assert 0.0 < summary["time"] <= hist["time"][-1] <= t_fault
    written = str(err.value).split("fields at the fault (t = ")[1].split(")")[0]
    assert float(written.split()[0]) == pytest.approx(t_fault, rel=1e-8)
    times = Series(tmp_path / "fields" / "member0.xdmf").times
    assert times[-1] == pytest.approx(t_fault, rel=1e-8) and times[-2] < times[-1]
    snapshot = str(err.value).split("s): ")[1].split(";")[0]
    with h5py.File(snapshot) as f:  # the faulted state: a non-positive energy or a non-finite value somewhere
        fields = f["member0"]
        assert "pressure" in fields and not np.all(np.isfinite(fields["pressure"][()]) &
                                                   (fields["internal_energy"][()] > 0.0))


# ------------------------------------------------------------------------- SIGKILL, then --restart: bit for bit
@pytest.mark.parametrize("method", list(TINY))
def test_killed_run_keeps_its_results_and_restarts_bit_for_bit(tmp_path, env, method):
    file = scenario_file(tmp_path, tiny(method))
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    proc = python("-c", REFERENCE_THEN_KILLED, "2", str(file), str(ref), str(killed), env=env)
    assert proc.returncode == -signal.SIGKILL, proc.stderr

    # what the killed run leaves: everything up to its output before the second checkpoint
    summary = json.loads((killed / "summary.json").read_text())
    assert summary["status"] == "running" and 0.0 < summary["time"] < 2 * tiny(method)["output"]["checkpoint_interval"]
    hist = read_history(killed / "history.csv")
    assert len(hist["time"]) > 1 and hist["time"][-1] <= summary["time"]
    times = Series(killed / "fields" / "member0.xdmf").times
    assert times[0] == 0.0 and times[-1] <= summary["time"]

    proc = python("-m", "blastfsi.cli", "run", "--restart", str(killed), "--json", env=env)
    assert proc.returncode == 0, proc.stderr
    assert (killed / "history.csv").read_bytes() == (ref / "history.csv").read_bytes()
    snapshots = sorted(p.name for p in (ref / "fields").iterdir())
    assert sorted(p.name for p in (killed / "fields").iterdir()) == snapshots
    for name in snapshots:
        if name.endswith(".h5"):
            assert_same_h5(ref / "fields" / name, killed / "fields" / name)
        else:
            assert (ref / "fields" / name).read_text() == (killed / "fields" / name).read_text()
    a, b = (json.loads((d / "summary.json").read_text()) for d in (ref, killed))
    assert {k: v for k, v in a.items() if k not in TIMINGS} == {k: v for k, v in b.items() if k not in TIMINGS}
    if method == "cfdmp":  # the box emptied: snapshots without particles, the series shows the grid alone then
        assert a["particles"] == 0
        with h5py.File(ref / "fields" / "member0_0001.h5") as f:
            assert f["particles"].attrs["n_points"] == 0 and f["particles/coordinates"].shape == (0, 3)
        series = Series(ref / "fields" / "member0.xdmf")
        assert [sorted(blocks(series.at(t))) for t in series.times] == [["grid", "particles"], ["grid"], ["grid"]]
