"""A run over several hosts (``blastfsi run --hosts``, jax.distributed): two processes on this machine, each with
two virtual CPU devices (gloo collectives), step one run on the four devices together; the first writes the
results, the second writes nothing the user sees and prints nothing. The results equal a one-device run's to
round-off (the bound of tests/test_sharding.py: the split computation is the one-device arithmetic but for
the order of the few cross-device sums)."""
import dataclasses
import json
import os
import socket
import subprocess
import sys

import numpy as np
import pytest

from blastfsi import api

from test_sharding import RELATIVE, RELATIVE_MPM

CASES = {  # example, overrides, bound
    "sedov-2d": ({"grid.cells": 32, "time.end": 0.1, "output.gauges": [[0.25, 0.0]]}, RELATIVE),
    "taylor-bar": ({"time.end": 4e-6}, RELATIVE_MPM),  # the particle pool split over the four devices
}
QUIET = {"output.fields": 2, "output.plots": False}  # (snapshots at the start and the end)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _on_two_hosts(arguments: list) -> list:
    """``blastfsi run`` with ``arguments`` as two processes of two devices each; their (returncode, stdout,
    stderr)."""
    port = _free_port()
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2", "JAX_PLATFORMS": "cpu",
           "BLASTFSI_NO_CACHE": "1"}
    procs = [subprocess.Popen([sys.executable, "-m", "blastfsi.cli", "run", *arguments, "--json", "-q", "--hosts",
                               "--coordinator", f"127.0.0.1:{port}", "--processes", "2", "--process-id", str(k)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env) for k in (0, 1)]
    outputs = [p.communicate(timeout=600) for p in procs]
    return [(p.returncode, *o) for p, o in zip(procs, outputs)]


def _worst(ref: dict, other: dict) -> float:
    """Largest difference of the float fields, each relative to its field's largest value."""
    out = 0.0
    for name, a in ref.items():
        a, b = np.asarray(a), np.asarray(other[name])
        if a.dtype.kind == "f" and np.max(np.abs(a)) > 0.0:
            out = max(out, float(np.max(np.abs(a - b)) / np.max(np.abs(a))))
    return out


@pytest.mark.slow  # (two processes that each compile: ~33 s; the default suite keeps under 10 min on 2 cores)
@pytest.mark.parametrize("name", ["sedov-2d", "taylor-bar"])
def test_two_hosts_give_the_one_device_run(tmp_path, name):
    overrides, bound = CASES[name]
    out = tmp_path / "two-hosts"
    sets = [arg for k, v in {**overrides, **QUIET, "numerics.devices": 4}.items()
            for arg in ("--set", f"{k}={json.dumps(v)}")]
    (code0, stdout0, err0), (code1, stdout1, err1) = _on_two_hosts(["--example", name, *sets, "--out", str(out)])
    assert code0 == 0, err0[-3000:]
    assert code1 == 0, err1[-3000:]
    assert any(line.startswith("{") for line in stdout0.splitlines())  # the first process reports
    assert not any(line.startswith("{") for line in stdout1.splitlines())  # the second reports nothing
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete"

    one = api.run(name, out=tmp_path / "one-device", set={**overrides, **QUIET})
    assert summary["steps"] == one.summary["steps"]
    end = one.scenario.time.end
    two = dataclasses.replace(one, out_dir=out)  # (the same snapshots, read from the two hosts' results)
    worst = _worst(one.fields(time=end), two.fields(time=end))
    assert worst <= bound, worst  # measured: sedov-2d 8.1e-16, taylor-bar 1.2e-13
    for g_one, g_two in zip(one.summary.get("gauges", []), summary.get("gauges", [])):
        for key in ("peak_overpressure", "impulse"):
            assert abs(g_two[key] - g_one[key]) <= bound * abs(g_one[key]), key


@pytest.mark.slow
def test_a_checkpoint_continues_on_two_hosts(tmp_path):
    """sedov-2d on two hosts (4 devices) with a checkpoint halfway; its last checkpoint removed, the run is
    continued by two new processes (both read the checkpoint; the first writes): the one-device run's final
    fields to round-off."""
    overrides = {**CASES["sedov-2d"][0], **QUIET, "output.checkpoint_interval": 0.05}
    out = tmp_path / "run"
    sets = [arg for k, v in {**overrides, "numerics.devices": 4}.items() for arg in ("--set", f"{k}={json.dumps(v)}")]
    for code, _, err in _on_two_hosts(["--example", "sedov-2d", *sets, "--out", str(out)]):
        assert code == 0, err[-3000:]
    checkpoints = sorted((out / "checkpoints").glob("ckpt_*.h5"))
    assert len(checkpoints) == 2
    checkpoints[-1].unlink()
    for code, _, err in _on_two_hosts(["--restart", str(out)]):
        assert code == 0, err[-3000:]
    assert len(list((out / "checkpoints").glob("ckpt_*.h5"))) == 2  # the end's checkpoint written again
    one = api.run("sedov-2d", out=tmp_path / "one-device", set=overrides)
    end = one.scenario.time.end
    again = dataclasses.replace(one, out_dir=out)  # (the snapshots the continued run rewrote)
    assert _worst(one.fields(time=end), again.fields(time=end)) <= RELATIVE
