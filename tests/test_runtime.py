"""The run's JAX settings (blastfsi.runtime) and the backend policy (blastfsi.xla)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import blastfsi
from blastfsi import runtime

PACKAGE = Path(blastfsi.__file__).parent


def test_backend_is_asked_only_in_xla_py():
    asking = [str(f.relative_to(PACKAGE)) for f in PACKAGE.rglob("*.py")
              if f.name != "xla.py" and "default_backend" in f.read_text()]
    assert asking == [], "backend decisions belong in blastfsi/xla.py (one function per decision)"
    assert "default_backend" in (PACKAGE / "xla.py").read_text()


@pytest.mark.parametrize("env, expected", [
    ({"XDG_CACHE_HOME": "/x/cache"}, f"/x/cache/blastfsi/jax/{runtime.machine_key()}"),
    ({"XDG_CACHE_HOME": "/x/cache", "BLASTFSI_CACHE_DIR": "/y/jit"}, "/y/jit"),
    ({"BLASTFSI_CACHE_DIR": ""}, None),
    ({"BLASTFSI_CACHE_DIR": "/y/jit", "BLASTFSI_NO_CACHE": "1"}, None),
])
def test_cache_directory_from_the_environment(monkeypatch, env, expected):
    if sys.platform in ("win32", "darwin") and "XDG_CACHE_HOME" in env and "BLASTFSI_CACHE_DIR" not in env:
        pytest.skip("XDG_CACHE_HOME is the Linux convention")
    for key in ("XDG_CACHE_HOME", "BLASTFSI_CACHE_DIR", "BLASTFSI_NO_CACHE"):
        monkeypatch.delenv(key, raising=False)
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    got = runtime.cache_directory()
    assert (None if got is None else got.as_posix()) == expected


RUN = ("import json, jax, numpy as np, blastfsi\n"
       "hits = []\n"
       "jax.monitoring.register_event_listener("
       "lambda event, **kw: hits.append(1) if event == '/jax/compilation_cache/cache_hits' else None)\n"
       "res = blastfsi.run('sedov-2d', set={'grid.cells': 40, 'output.fields': 0, 'output.plots': False})\n"
       "state = [float(np.nansum(np.asarray(a, float))) for a in jax.tree_util.tree_leaves(res.state)]\n"
       "print(json.dumps([jax.config.jax_compilation_cache_dir, state, len(hits),\n"
       "                  jax.config.jax_persistent_cache_min_compile_time_secs]))\n")


def _run_in_a_fresh_process(env: dict) -> list:
    env = {**{k: v for k, v in os.environ.items() if not k.startswith(("BLASTFSI_", "JAX_"))}, **env,
           "JAX_PLATFORMS": "cpu"}
    out = subprocess.run([sys.executable, "-c", RUN], capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_run_stores_its_time_loop_in_the_cache_and_a_repeated_run_reads_it(tmp_path):
    cache = tmp_path / "cache"
    first = _run_in_a_fresh_process({"BLASTFSI_CACHE_DIR": str(cache)})
    # written: the run's compilations; after the run nothing more is stored (the caller's own code)
    assert first[0] == str(cache) and any(cache.iterdir()) and first[3] == float("inf")
    assert len(list((cache / "traced").iterdir())) == 1  # the time loop, traced and lowered
    second = _run_in_a_fresh_process({"BLASTFSI_CACHE_DIR": str(cache)})
    # read back (hits: also a run's repeated small programs), and the same final state to the bit
    assert second[:2] == first[:2] and second[2] > first[2]
    off = _run_in_a_fresh_process({"BLASTFSI_CACHE_DIR": str(cache), "BLASTFSI_NO_CACHE": "1"})
    assert off[:3] == [None, first[1], 0] and off[3] == 1.0  # (JAX's default threshold, untouched)
