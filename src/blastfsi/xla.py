"""Helpers that steer XLA's fusion and control flow (shared by the Eulerian and MPM kernels), and
the package's backend policy: every choice that depends on the device kind is one function here
(:func:`device_control_flow`, :func:`combined_scatter`, :func:`blocked_sweeps`), and no other module
asks JAX for its backend (:func:`backend`; ``tests/test_runtime.py`` checks it).

On the CPU backend a conditional or a loop costs nothing but the boundary it puts
between fusions, which these helpers use. On a GPU each conditional's predicate and
each loop iteration's test is copied to the host before the next kernel is launched
(a round trip that leaves the device idle): there the helpers select between
computed branches and unroll short loops instead. (The he-slab-2d coupled step held ~60
such conditionals; with these forms it took 1.4 ms on an H200, the device's kernels busy
1.17 ms of it: benchmarks/results_cfdmp.json.)
"""
from __future__ import annotations

import functools
import operator

import jax
import jax.numpy as jnp
from jax.experimental import multihost_utils


def device_control_flow() -> bool:
    """True where conditionals and loops run without a host round trip (the CPU backend)."""
    return _cpu()


def combined_scatter(dim: int) -> bool:
    """True where the particle-to-grid transfer of a ``dim``-dimensional grid is best done as one scatter of
    rows of all channels, False where as scalar scatters, one per channel and stencil node
    (:func:`blastfsi.mpm.musl.particle_to_grid`; both add in the same order: the same sums, bit for bit).
    GPUs: rows. The CPU: rows up to 2D, scalars in 3D. The scalar form unrolls channels x stencil nodes into
    separate scatters, which the compiler pays for: measured on a 2-core Intel Xeon (jax 0.10.2, float64,
    first runs without the compilation cache, ``benchmarks/compile_baseline.py``), the time loop of
    he-slab-2d compiles in 18.3 s with rows against 23.4 s with scalars, steel-plate-blast in 15.0 s
    against 22.1 s and concrete-slab-blast in 16.3-16.5 s against 22.7-22.9 s; the loops take the same time
    (he-slab-2d 17.2 s, steel-plate-blast 32.6 s, the 2D MPM taylor-bar 4.9 s) or up to 5 % longer
    (concrete-slab-blast to 0.12 ms, two pairs of runs: 41.3 and 43.1 s against 38.8 and 41.2 s;
    tnt-standoff-plate to 1.6 ms: 73.2 against 70.9 s, compiled in 16.9 against 23.3 s). In 3D
    (27 stencil nodes) XLA:CPU's generic per-element loop over rows costs more than it saves: the Johnson-Cook
    block of ``benchmarks/bench_mpm.py`` (24^3 cells, 110 592 particles) steps
    2.09e6 particle-steps/s with scalars against 1.81e6 with rows."""
    return not _cpu() or dim <= 2


def blocked_sweeps() -> bool:
    """True where a large grid's directional operator is faster swept block by block, its temporaries
    kept in cache (the CPU: :mod:`blastfsi.euler.blocking`); False on a GPU, whose whole-grid kernel
    runs across all its cores and a loop of small blocks would leave most of them idle."""
    return _cpu()


def backend() -> str:
    """The backend the kernels are traced for ("cpu", "gpu", ...), which the choices above follow (a key of
    the stored traced programs, :func:`blastfsi.runtime.lowered`)."""
    return jax.default_backend()


def _cpu() -> bool:
    return backend() == "cpu"


def materialise(compute, operand, taken=None):
    """``compute(operand)`` evaluated once and kept in memory, not fused into its consumers.

    XLA:CPU fuses an elementwise producer into each of its consumers, so a value read by
    many fusions, or by one fusion at several offsets (an Eulerian face flux, read by the two
    cells beside the face; the MPM basis functions and strain increments, read by ~20
    per-channel fusions), is recomputed inside every one of them; and it strips optimization
    barriers. A conditional is a boundary fusion cannot cross. ``taken``: None (both branches
    are ``compute``, so the predicate -- a value of the operand XLA cannot fold -- does not
    change the result), or a traced boolean under which ``compute`` runs, zeros of the same
    shapes otherwise (e.g. an empty particle pool, an ideal-gas phase's JWL terms).
    Elsewhere (see :func:`device_control_flow`) ``compute`` runs unconditionally and its
    result is selected.
    """
    def zeros(a):
        return jax.tree_util.tree_map(lambda z: jnp.zeros(z.shape, z.dtype), jax.eval_shape(compute, a))

    if not device_control_flow():
        value = compute(operand)
        return value if taken is None else jax.tree_util.tree_map(lambda v: jnp.where(taken, v, 0), value)
    if taken is None:
        leaf = jax.tree_util.tree_leaves(operand)[0]
        return jax.lax.cond(leaf.ravel()[0] == leaf.ravel()[0], compute, compute, operand)
    return jax.lax.cond(taken, compute, zeros, operand)


def fori(n: int, body, init):
    """``lax.fori_loop(0, n, body, init)`` (the body compiled once) where loops are free; elsewhere
    the n bodies unrolled, each called with its Python int index."""
    if device_control_flow():
        return jax.lax.fori_loop(0, n, body, init)
    for i in range(n):
        init = body(i, init)
    return init


def row_sum(a):
    """Sum over the short trailing axis of an (n, k) array as k - 1 elementwise adds.

    XLA:CPU (jax 0.10) sends such reductions to its YNNPACK library kernels, which took 60-90 ns
    per row here (a 38 000-particle von Mises sum 3.4 ms); the adds fuse into their neighbours.
    """
    return functools.reduce(operator.add, [a[..., k] for k in range(a.shape[-1])])


SPLIT_AXIS = "x"  # the mesh axis an array is split along (split_sharding: a grid's x, a particle pool)


def processes() -> int:
    """How many processes share the devices: 1, or the hosts joined by :func:`blastfsi.runtime.join_hosts`."""
    return jax.process_count() if jax.distributed.is_initialized() else 1


def writes_results() -> bool:
    """Whether this process writes a run's results: the only one, or the first of several hosts (the others
    compute their part of every step and write nothing the user sees)."""
    return processes() == 1 or jax.process_index() == 0


def to_host(tree):
    """``tree`` as NumPy arrays in this process. Where several processes share the devices, an array split
    over devices of other hosts is gathered from all of them (every process must then call this at the same
    point: it is a collective); arrays this process holds whole are copied as they are."""
    def one(a):
        if isinstance(a, jax.Array) and not a.is_fully_addressable:
            return multihost_utils.process_allgather(a, tiled=True)
        return jax.device_get(a)
    return jax.tree_util.tree_map(one, tree)


def visible_devices() -> int:
    """How many devices JAX sees (of the default backend: GPUs, or the CPU's, one unless
    ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` was set before JAX started)."""
    return len(jax.devices())


def device_count(requested, key: str = "numerics.devices") -> int:
    """``requested`` (an int >= 1 or "all") as a number of devices, checked against the visible ones:
    ValueError naming ``key`` where more are asked for than JAX sees."""
    visible = visible_devices()
    if requested == "all":
        return visible
    n = int(requested)
    if n > visible:
        raise ValueError(f"{key} = {n}: only {visible} device(s) visible to JAX ({jax.devices()[0].platform}); "
                         f"give at most {visible}, or \"all\" (on a CPU, XLA_FLAGS="
                         "--xla_force_host_platform_device_count=N set before starting makes N virtual devices)")
    return n


def equal_parts(count: int, n_devices: int) -> int:
    """``count`` rounded up to a multiple of ``n_devices``: an array axis that splits into equal parts (a particle
    pool's slots, :func:`split_sharding`)."""
    return -(-count // n_devices) * n_devices


def split_sharding(n_devices: int, ndim: int, axis: int = 0):
    """The placement of an array of ``ndim`` axes split along ``axis`` in ``n_devices`` equal parts over the
    first ``n_devices`` devices (a 1D mesh, axis SPLIT_AXIS), the other axes whole; None for one device (the
    default placement). Under ``jit`` a computation on such arrays runs SPMD: each device computes its part,
    and the compiler adds the communication the computation needs: an Eulerian grid split along x exchanges
    the halo cells its stencils read (collective permutes); a particle pool split along its slots adds the
    per-device nodal sums of a particle-to-grid transfer (all-reduces)."""
    if n_devices <= 1:
        return None
    mesh = jax.sharding.Mesh(jax.devices()[:n_devices], (SPLIT_AXIS,))
    spec = [None] * ndim
    spec[axis] = SPLIT_AXIS
    return jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec(*spec))
