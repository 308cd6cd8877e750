"""Precision is chosen per run (numerics.precision), never by importing the package."""
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np

from blastfsi import simulation
from conftest import uniform_data

SMALL = dict(grid__cells=100, output__fields=0, output__history_samples=11)


def test_import_and_a_run_leave_the_process_precision_alone():
    # a fresh interpreter: this test process has float64 on (conftest)
    code = ("import jax, jax.numpy as jnp\n"
            "before = jax.config.jax_enable_x64\n"
            "import blastfsi\n"
            "after_import = jax.config.jax_enable_x64\n"
            "res = blastfsi.run('plate1d-uniform', set={'grid.cells': 100, 'output.fields': 0,"
            " 'output.history_samples': 11, 'output.plots': False})\n"
            "print(before, after_import, jax.config.jax_enable_x64, res.state.x.dtype, jnp.ones(1).dtype,"
            " res.fields()['pressure'].dtype)\n")
    env = {"PATH": "/usr/bin:/bin", "BLASTFSI_NO_CACHE": "1", "JAX_PLATFORMS": "cpu"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    # JAX's default (32-bit) before and after import and after a float64 run; the run's state float64
    assert out.stdout.split() == ["False", "False", "False", "float64", "float32", "float64"]


def test_float32_run_computes_in_float32_and_restores_the_setting():
    assert jax.config.jax_enable_x64  # (conftest)
    res = simulation.run(uniform_data(**SMALL, numerics={"precision": "float32"}))
    assert res.state.x.dtype == jnp.float32 and res.state.hist.dtype == jnp.float32
    assert res.state.step.dtype == jnp.int32
    assert res.fields()["pressure"].dtype == np.float32
    assert jax.config.jax_enable_x64 and jnp.ones(1).dtype == jnp.float64


def test_float64_run_inside_32_bit_code_computes_in_float64():
    with jax.enable_x64(False):
        res = simulation.run(uniform_data(**SMALL))
        assert not jax.config.jax_enable_x64 and jnp.ones(1).dtype == jnp.float32
        assert res.fields()["pressure"].dtype == np.float64
    assert res.state.x.dtype == jnp.float64 and res.state.hist.dtype == jnp.float64
    # the same scenario from 64-bit code: the same numbers (the setting selects the types, nothing else)
    again = simulation.run(uniform_data(**SMALL))
    np.testing.assert_array_equal(np.asarray(res.state.x), np.asarray(again.state.x))
