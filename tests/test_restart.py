"""Checkpoint/restart reproduces an uninterrupted run bit for bit (CPU)."""
import json
import subprocess
import sys

import numpy as np
import pytest
import tomli_w

from blastfsi.io.results import read_history
from conftest import uniform_data


@pytest.mark.slow  # default-suite time (< 10 min on 2 cores)
def test_restart_is_bit_for_bit(tmp_path):
    data = uniform_data(grid__cells=200, output__checkpoint_interval=0.0007, output__fields=4)
    scenario = tmp_path / "s.toml"
    scenario.write_text(tomli_w.dumps(data))
    a, b = tmp_path / "a", tmp_path / "b"
    for out in (a, b):
        proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", str(scenario), "--out", str(out), "--json"],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
    ckpts = sorted((b / "checkpoints").glob("ckpt_*.h5"))
    assert len(ckpts) == 4
    for f in ckpts[2:]:  # pretend the run died after the second checkpoint
        f.unlink()
    (b / "history.csv").unlink()
    (b / "summary.json").unlink()
    proc = subprocess.run([sys.executable, "-m", "blastfsi.cli", "run", "--restart", str(b), "--json"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    ha, hb = read_history(a / "history.csv"), read_history(b / "history.csv")
    for key in ha:
        np.testing.assert_array_equal(ha[key], hb[key])
    sa, sb = json.loads((a / "summary.json").read_text()), json.loads((b / "summary.json").read_text())
    for key in ("plate_velocity", "plate_displacement", "plate_impulse", "peak_overpressure", "steps"):
        assert sa[key] == sb[key]
    for f in sorted((a / "checkpoints").glob("*.h5")):
        import h5py

        with h5py.File(f) as fa, h5py.File(b / "checkpoints" / f.name) as fb:
            for name in fa:
                np.testing.assert_array_equal(fa[name][()], fb[name][()])
