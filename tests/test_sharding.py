"""The Eulerian grid and the MPM particle pool split across devices (``numerics.devices``): results equal the
one-device run's to round-off, the compiled loop exchanges halos or nodal sums (not whole arrays), bad counts
are refused.

JAX fixes its device count at start-up, so the split runs go in one subprocess with 8 virtual CPU devices
(``XLA_FLAGS=--xla_force_host_platform_device_count=8``), which prints its measurements as JSON.
"""
import json
import os
import subprocess
import sys
import textwrap
import tomllib
from importlib.resources import files

import pytest

from blastfsi.scenario import ScenarioError, expand

# Round-off bound: the split run's arithmetic per cell is the one-device run's, except for what the
# compiler fuses or contracts (multiply-adds) differently in the partitioned program and the order of the
# few global sums (the history's totals); that is a few ulps per step, carried by a stable scheme over
# these runs' 10-20 steps: measured 2e-15 of each field's largest value. 1e-13 (~450 ulps) is that
# with room, and a wrong halo (a stale or missing ghost cell) is an O(1) relative error.
RELATIVE = 1e-13
# MPM: the nodal sums of a split pool are partial sums per device added across devices, so every nodal mass,
# momentum and force of every step is summed in another order (a few ulps each, ~1e-15 relative), and the
# particles carry that over the steps (taylor-bar, 114 steps: 1.8e-14 in velocity, 1.0e-13 in stress, where
# the plastic return and the stiff elastic update amplify velocity-gradient differences). 1e-12 is ten times
# that; a particle lost or counted twice by the split is an O(1/particles per node) ~ 10 % error.
RELATIVE_MPM = 1e-12

SCRIPT = textwrap.dedent('''
    import copy, json, pathlib, re, sys, tomllib
    from importlib.resources import files
    import h5py
    import jax
    import numpy as np
    from blastfsi import method as methods, simulation
    from blastfsi.scenario import ScenarioError

    def example(name, **over):
        data = tomllib.loads((files("blastfsi.examples") / f"{name}.toml").read_text())
        for key, value in over.items():
            table, leaf = key.split(".")
            data.setdefault(table, {})[leaf] = value
        return data

    def with_devices(data, n):
        data = copy.deepcopy(data)
        data.setdefault("numerics", {})["devices"] = n
        return data

    def fields_of(res):
        return {k: np.asarray(v) for k, v in res.fields().items() if np.asarray(v).dtype.kind == "f"}

    def worst(ref, other):  # per field: max |difference| / max |reference| over the finite cells
        out = {}
        for k, a in ref.items():
            b = other[k]
            same_nan = bool(np.array_equal(np.isfinite(a), np.isfinite(b)))
            m = np.isfinite(a)
            scale = float(np.max(np.abs(a[m]))) if m.any() else 1.0
            out[k] = float(np.max(np.abs(a[m] - b[m])) / scale) if m.any() and same_nan else (0.0 if same_nan else 1.0)
        return out

    def gauge_diff(ref, other, fields, end):
        # per quantity: max |difference| / the scale of its field (the map's largest value; time.end for times)
        scale = {"peak_overpressure": np.nanmax(np.abs(fields["peak_overpressure"])),
                 "impulse": np.nanmax(np.abs(fields["positive_impulse"])), "arrival_time": end,
                 "positive_phase_duration": end}
        worst_rel = 0.0
        for ga, gb in zip(ref["gauges"], other["gauges"]):
            for key in scale:
                a, b = ga[key], gb[key]
                if (a is None) != (b is None):
                    return 1.0
                if a is not None:
                    worst_rel = max(worst_rel, abs(a - b) / float(scale[key]))
        return worst_rel

    def op_sizes(exe, op):  # per collective ``op`` of the compiled loop: the element count of its largest array
        found = []
        for line in exe.as_text().splitlines():
            m = re.search(r"= (\\S+) " + op + r"(-start)?\\(", line)
            if m:
                found.append(max([int(np.prod([int(d) for d in dims.split(",") if d] or [1]))
                                  for dims in re.findall(r"\\[([0-9,]*)\\]", m.group(1))] or [0]))
        return found

    def hlo_facts(exe, cells, planes):
        return {"permutes": op_sizes(exe, "collective-permute"), "gathers": op_sizes(exe, "all-gather"),
                "all_to_all": len(op_sizes(exe, "all-to-all")), "cells": cells, "plane": planes}

    def cfdmp_split(data, label, counts=(1, 2)):  # particles and grid against one device's; the loop's collectives
        out, ref = {}, None
        for n in counts:
            res = simulation.run(with_devices(data, n))
            P = res.state.mpm.particles
            on = np.asarray(P.active)[0]
            state = {"x": np.asarray(P.x)[0][on], "stress": np.asarray(P.point.stress)[0][on],
                     "U": np.asarray(res.state.U)}
            v, c = np.asarray(P.v)[0][on], float(np.max(np.asarray(P.wave_speed)[0][on]))
            entry = {"devices_used": len(P.x.sharding.device_set), "steps": res.summary["steps"],
                     "pool": int(on.size), "active": int(on.sum()), "nodes": res.setups[0].grid.num_nodes,
                     "cells": int(np.prod(res.setups[0].grid.cells))}
            if ref is None:
                ref = (state, res.summary["steps"], v, c)
            else:  # velocities against the sound speed (a gas at rest has round-off velocities only)
                entry.update(fields={**worst(ref[0], state), "v": float(np.max(np.abs(v - ref[2]))) / ref[3]},
                             steps_ref=ref[1])
                exe = list(methods._EXECUTABLES.values())[-1]
                entry["hlo"] = {op: op_sizes(exe, op) for op in ("all-reduce", "all-gather", "all-to-all")}
            out[f"{label}/{n}"] = entry
        return out

    report = {"visible": len(jax.devices())}
    sedov = example("sedov-2d", **{"grid.cells": 32, "time.end": 0.1, "output.fields": 0, "output.plots": False,
                                   "output.gauges": [[0.25, 0.0], [0.0, -0.3]]})
    bar = example("taylor-bar", **{"time.end": 4e-6, "output.fields": 0, "output.plots": False})

    if sys.argv[2:] == ["slow"]:
        # he-slab-2d to 12 steps after the coupling starts
        report.update(cfdmp_split(example("he-slab-2d", **{"time.end": 1.62e-5, "output.fields": 0,
                                                          "output.plots": False}), "he-slab-2d"))
        # the same with the shock tube to 0.1 ms, and its checkpoint continued on another count
        report.update(cfdmp_split(example("cfdmp-shock-tube", **{"time.end": 1e-4, "output.fields": 0,
                                                                 "output.plots": False}), "cfdmp", (1, 2, 4, 8)))
        # in 3D: a Sod shock entering an MPM box that holds a steel block (15 mm cells, 2-cell bridge), to 14 us
        # after the shock reaches the box (the coupling's particles emitted on every device)
        report.update(cfdmp_split({
            "method": "cfdmp", "name": "cfdmp-3d", "grid": {"cells": 16},
            "domain": {"lower": [0.0, 0.0, 0.0], "upper": [0.24, 0.12, 0.12]},
            "initial": {"kind": "riemann", "diaphragm": 0.1, "left": {"density": 1.0, "pressure": 1.0e5},
                        "right": {"density": 0.125, "pressure": 1.0e4}},
            "mpm_region": {"lower": [0.12, 0.0, 0.0], "upper": [0.24, 0.12, 0.12], "bridge_cells": 2},
            "structures": [{"lower": [0.21, 0.03, 0.03], "upper": [0.24, 0.09, 0.09], "material": "elastic-steel"}],
            "time": {"end": 5e-5}, "output": {"fields": 0, "plots": False}}, "cfdmp-3d", (1, 2, 4, 8)))

        # a cfdmp checkpoint written on 2 devices, continued on 1 (the shock tube's pool, 302 slots, divides into both)
        out = pathlib.Path(sys.argv[1]) / "tube"
        tube = example("cfdmp-shock-tube", **{"time.end": 2e-4, "output.fields": 0, "output.plots": False,
                                              "output.checkpoint_interval": 1e-4})
        whole = simulation.run(with_devices(tube, 2), out=out)
        again = simulation.run(with_devices(tube, 1), out=out, restart=True)
        report["cfdmp_restart"] = {"fields": worst({"U": np.asarray(whole.state.U), "x": np.asarray(whole.state.mpm.particles.x)},
                                                   {"U": np.asarray(again.state.U), "x": np.asarray(again.state.mpm.particles.x)}),
                                   "steps": [whole.summary["steps"], again.summary["steps"]]}

        # snapshots written on 2 devices against 1: the same files, datasets, shapes and dtypes (the layout), the
        # same XDMF text, values to round-off; a grid (sedov-2d) and particles (taylor-bar)
        def snapshot_files(folder):
            return sorted(p.relative_to(folder).as_posix() for p in (folder / "fields").rglob("*") if p.is_file())

        def datasets(path):
            found = {}
            with h5py.File(path, "r") as f:
                f.visititems(lambda name, obj: found.__setitem__(name, np.asarray(obj)) if isinstance(obj, h5py.Dataset)
                             else None)
            return found

        for label, data in (("grid", sedov), ("particles", bar)):
            data = copy.deepcopy(data)
            data["output"]["fields"] = 3
            folders = [pathlib.Path(sys.argv[1]) / f"layout_{label}_{n}" for n in (1, 2)]
            for n, folder in zip((1, 2), folders):
                simulation.run(with_devices(data, n), out=folder)
            names = [snapshot_files(f) for f in folders]
            entry = {"files": len(names[0]), "same_files": names[0] == names[1], "layout": [], "values": 0.0,
                     "xdmf_same": True}
            if names[0] == names[1]:
                for name in names[0]:
                    a, b = (f / name for f in folders)
                    if name.endswith(".xdmf"):
                        entry["xdmf_same"] &= a.read_text() == b.read_text()
                        continue
                    da, db = datasets(a), datasets(b)
                    layout_a = {k: (v.shape, str(v.dtype)) for k, v in da.items()}
                    if layout_a != {k: (v.shape, str(v.dtype)) for k, v in db.items()}:
                        entry["layout"].append(name)
                        continue
                    floats = {k: v for k, v in da.items() if v.dtype.kind == "f"}
                    entry["values"] = max([entry["values"], *worst(floats, {k: db[k] for k in floats}).values()])
                    entry["datasets"] = entry.get("datasets", 0) + len(da)
            report[f"layout/{label}"] = entry

        print("REPORT" + json.dumps(report))
        sys.exit(0)

    cases = {
        "sedov-2d": (sedov, (1, 2, 4, 8), 32 * 32, 32),
        "sod": (example("sod", **{"grid.cells": 64, "output.fields": 0, "output.plots": False,
                                  "output.gauges": [0.3e-3, 0.75e-3]}), (1, 2, 4, 8), 64, 1),
        "sedov-3d": (example("sedov-3d", **{"grid.cells": 16, "time.end": 0.1, "output.fields": 0,
                                             "output.plots": False, "output.gauges": [[0.45, 0.0, 0.0]]}),
                     (1, 2, 4, 8), 16 ** 3, 16 * 16),
    }
    for name, (data, counts, cells, plane) in cases.items():
        ref = None
        for n in counts:
            res = simulation.run(with_devices(data, n))
            f, s = fields_of(res), res.summary
            entry = {"devices_used": len(res.state.U.sharding.device_set), "steps": s["steps"]}
            if ref is None:
                ref = (f, s)
            else:
                entry.update(fields=worst(ref[0], f), gauges=gauge_diff(ref[1], s, ref[0], data["time"]["end"]),
                             steps_ref=ref[1]["steps"], gauge_values=[ref[1]["gauges"], s["gauges"]])
                exe = list(methods._EXECUTABLES.values())[-1]  # (compiled by this run: its shapes are new)
                entry["hlo"] = hlo_facts(exe, cells, plane)
            report[f"{name}/{n}"] = entry

    # MPM: the particle pool split over 2, 4 and 8 devices (8: a pool of 6001 slots rounded up to 6008)
    ref = None
    for n, capacity in ((1, None), (2, None), (4, None), (8, 6001)):
        data = with_devices(bar, n)
        if capacity:
            data["numerics"]["capacity"] = capacity
        res = simulation.run(data)
        P = res.state.mpm.particles
        on = np.asarray(P.active)
        state = {"x": np.asarray(P.x)[on], "v": np.asarray(P.v)[on], "stress": np.asarray(P.point.stress)[on],
                 "plastic_strain": np.asarray(P.point.plastic_strain)[on]}
        entry = {"devices_used": len(P.x.sharding.device_set), "steps": res.summary["steps"], "pool": int(on.size),
                 "nodes": res.setups[0].grid.num_nodes}
        if ref is None:
            ref = (state, res.summary["steps"])
        else:
            entry.update(fields=worst(ref[0], state), steps_ref=ref[1])
        if n == 2:
            exe = list(methods._EXECUTABLES.values())[-1]
            entry["hlo"] = {op: op_sizes(exe, op) for op in ("all-reduce", "all-gather", "all-to-all")}
        report[f"mpm/{n}"] = entry

    # MPM in 1D (the gas of mpm-sod) and 3D (a quarter of the Taylor rod, symmetry planes x = 0 and y = 0):
    # the pool split over 2, 4 and 8 devices
    rod = copy.deepcopy(bar)
    rod["grid"] = {"lower": [0.0, 0.0, 0.0], "upper": [7.62e-3, 7.62e-3, 26.67e-3], "cells": 6,
                   "boundaries": {"x": ["slip", "free"], "y": ["slip", "free"], "z": ["slip", "free"]}}
    rod["impactor"]["particles_per_cell"] = 2
    rod["output"]["tracers"] = [[0.0, 0.0, 25.4e-3]]
    sod = example("mpm-sod", **{"time.end": 1e-5, "output.fields": 0, "output.plots": False})
    for label, data in (("mpm1d", sod), ("mpm3d", rod)):
        ref = None
        for n in (1, 2, 4, 8):
            res = simulation.run(with_devices(data, n))
            P = res.state.mpm.particles
            on = np.asarray(P.active)
            state = {"x": np.asarray(P.x)[on], "v": np.asarray(P.v)[on], "stress": np.asarray(P.point.stress)[on]}
            entry = {"devices_used": len(P.x.sharding.device_set), "steps": res.summary["steps"],
                     "particles": int(on.sum())}
            if ref is None:
                ref = (state, res.summary["steps"])
            else:
                entry.update(fields=worst(ref[0], state), steps_ref=ref[1])
            report[f"{label}/{n}"] = entry

    # a checkpoint written on 2 devices, continued on 4 and on 1 (host arrays: the layout is the run's)
    out = pathlib.Path(sys.argv[1]) / "a"
    data = copy.deepcopy(cases["sedov-2d"][0])
    data["output"]["checkpoint_interval"] = 0.06
    whole = simulation.run(with_devices(data, 2), out=out)
    for n in (4, 1):
        again = simulation.run(with_devices(data, n), out=out, restart=True)
        report[f"restart/{n}"] = {"fields": worst(fields_of(whole), fields_of(again)),
                                  "steps": [whole.summary["steps"], again.summary["steps"]]}

    # an MPM checkpoint written on 2 devices, continued on 1 (the pool, 6000 slots, divides into both)
    out = pathlib.Path(sys.argv[1]) / "bar"
    data = copy.deepcopy(bar)
    data["output"]["checkpoint_interval"] = 2e-6
    whole = simulation.run(with_devices(data, 2), out=out)
    again = simulation.run(with_devices(data, 1), out=out, restart=True)
    report["mpm_restart"] = {"fields": worst({"x": np.asarray(whole.state.mpm.particles.x)},
                                             {"x": np.asarray(again.state.mpm.particles.x)}),
                             "steps": [whole.summary["steps"], again.summary["steps"]]}

    # the Cartesian step slab by slab (shard_map, halos by hand) against the whole grid's: every scheme, every kind
    # of x boundary, 1D to 3D, on 2 and 4 devices, from a random state (waves at every slab edge and boundary)
    from blastfsi import euler as kernels
    from jax.sharding import NamedSharding, PartitionSpec
    with jax.enable_x64(True):  # (float64, as the runs above: outside a run the process computes in float32)
        rng = np.random.default_rng(7)
        from blastfsi.scenario import expand
        sc, _, member_scs = expand(example("sod", **{"grid.cells": 8}))  # (its gas: the air's ideal-gas parameters)
        kp = jax.tree_util.tree_map(lambda a: a[0], simulation.prepare(sc, member_scs)[4].kernel)
        slabs = {}
        for scheme in (kernels.LAX_WENDROFF, kernels.HLLC_MUSCL, kernels.HLLC_HANCOCK):
            for shape, bc, geometry, r0 in (
                    ((16, 12), ((0, 0), (1, 0)), 0, 0.0), ((16, 12), ((1, 1), (0, 1)), 0, 0.0),
                    ((16, 12), ((3, 3), (1, 1)), 0, 0.0), ((16, 12), ((1, 0), (3, 3)), 0, 0.0), ((16,), ((1, 1),), 0, 0.0),
                    ((8, 6, 4), ((1, 0), (0, 1), (3, 3)), 0, 0.0),  # Cartesian; then r-z on and off the axis, 1D
                    ((16, 12), ((2, 0), (0, 1)), 1, 0.0), ((16, 12), ((1, 0), (0, 0)), 1, 0.05),  # cylindrical and
                    ((16,), ((2, 0),), 1, 0.0), ((16,), ((2, 1),), 2, 0.0)):  # spherical (geometry.py: the metric)
                cfg = kernels.Config(shape=shape, dx=0.01, geometry=geometry, bc=bc, scheme=scheme, n_materials=1,
                                     origin=(r0,) + (0.0,) * (len(shape) - 1))
                U = kernels.conservative(1.0 + 0.5 * rng.random(shape), 1.0, 100.0 * rng.standard_normal((len(shape),) + shape),
                                         1e5 * (1.0 + rng.random(shape)), kp, cfg)
                dt = 0.3 * float(kernels.stable_dt(U, kp, cfg))
                steps = lambda c: jax.jit(lambda u: jax.lax.fori_loop(0, 6, lambda i, w: kernels.step(w, dt, kp, c, parity=i), u))
                ref = np.asarray(steps(cfg)(U))
                for n in (2, 4):
                    split = NamedSharding(jax.sharding.Mesh(jax.devices()[:n], ("x",)), PartitionSpec(None, "x"))
                    out = np.asarray(steps(cfg._replace(devices=n))(jax.device_put(U, split)))
                    slabs[f"{scheme} {shape} {geometry} {bc[0]} {n}"] = float(np.max(np.abs(out - ref)) / np.max(np.abs(ref)))
    report["slab_steps"] = slabs

    for label, n, cells in (("too_many", 16, 32), ("all_indivisible", "all", 36)):
        bad = with_devices(cases["sedov-2d"][0], n)
        bad["grid"]["cells"] = cells
        try:
            simulation.run(bad)
            report[label] = None
        except ScenarioError as err:
            report[label] = str(err)
    print("REPORT" + json.dumps(report))
''')


def _check_cfdmp_split(entry, devices: int, gas_particles: int):
    """cfdmp on ``devices`` devices against 1: the pool split, the particles and the grid to round-off, the
    compiled loop adding the nodal and per-cell sums across devices and gathering no pool-sized array."""
    assert entry["devices_used"] == devices and entry["steps"] == entry["steps_ref"], entry
    assert entry["active"] > gas_particles, entry  # the coupling started: the box's gas is particles
    assert max(entry["fields"].values()) <= RELATIVE_MPM, entry["fields"]
    # the all-reduces: the nodal and per-cell sums (a channel each, or rows of all channels: multiples of the MPM
    # grid's nodes or cells) and short ones (the emission batch's slot ranks, scalars); no pool-sized gather
    hlo = entry["hlo"]
    assert hlo["all-reduce"] and all(size < 1000 or size % entry["nodes"] == 0 or size % entry["cells"] == 0
                                     for size in hlo["all-reduce"]), (sorted(set(hlo["all-reduce"])), entry)
    assert all(size < entry["pool"] for size in hlo["all-gather"]) and not hlo["all-to-all"], hlo


@pytest.mark.slow  # ~7 min alone on 2 cores
def test_coupled_split_and_snapshots_on_two_virtual_devices(tmp_path):
    """cfdmp with the MPM region's pool split over 2 devices, the Eulerian grid whole on each:

    * he-slab-2d (2D), cfdmp-shock-tube (1D, to 0.1 ms) and a Sod shock entering a 3D box with a steel block
      (test_cfdmp's 3D case on 15 mm cells): the one-device run's particles and grid to round-off;
      the compiled loop adds the nodal and per-cell sums across devices and gathers no pool-sized array
      (particles are emitted into free slots ranked per device, mpm.add_particles_at: one cumsum over the pool
      made the shock tube's loop all-gather its slot ranks). he-slab-2d is held to round-off for 12 steps after
      the coupling starts, not further: the bridge compares sums with thresholds (a reservoir's mass against a
      share of a particle's, coupling.feed), and the other order of the nodal sums flips one of them a few steps
      later (measured: step 115 of that run, one particle emitted a step earlier), after which the runs differ
      by that discrete event, not by round-off;
    * a cfdmp checkpoint written on 2 devices continues on 1 (cfdmp-shock-tube);
    * snapshots written on 2 devices are the one-device run's files (names, HDF5 datasets with their shapes
      and dtypes, XDMF text) with values to round-off, for a grid (sedov-2d) and for particles (taylor-bar)."""
    measured = _split_runs(tmp_path, "slow")
    _check_cfdmp_split(measured["he-slab-2d/2"], 2, gas_particles=20000)
    for n in (2, 4, 8):
        _check_cfdmp_split(measured[f"cfdmp/{n}"], n, gas_particles=100)
        _check_cfdmp_split(measured[f"cfdmp-3d/{n}"], n, gas_particles=4160)  # (4160 before the shock reaches the box)
    entry = measured["cfdmp_restart"]
    assert entry["steps"][0] == entry["steps"][1] and max(entry["fields"].values()) <= RELATIVE_MPM, entry
    for label in ("grid", "particles"):  # snapshots written on 2 devices: the one-device files, layout and values
        entry = measured[f"layout/{label}"]
        assert entry["files"] >= 4 and entry["same_files"] and entry["xdmf_same"], (label, entry)
        assert not entry["layout"] and entry["datasets"] > 0, (label, entry)
        assert entry["values"] <= RELATIVE_MPM, (label, entry)


def _split_runs(folder, *args):
    """The report of the 8-device subprocess (SCRIPT; ``args`` after the folder)."""
    script = folder / "split_runs.py"
    script.write_text(SCRIPT)
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=8", "JAX_PLATFORMS": "cpu",
           "BLASTFSI_NO_CACHE": "1"}
    proc = subprocess.run([sys.executable, str(script), str(folder), *args], capture_output=True, text=True,
                          env=env, timeout=1500)
    assert proc.returncode == 0, proc.stderr[-4000:]
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("REPORT"))
    return json.loads(line[len("REPORT"):])


@pytest.mark.slow  # default-suite time (131 s on 2 cores): the device checks below stay
def test_split_runs_on_eight_virtual_devices(tmp_path):
    """One subprocess with 8 virtual CPU devices runs every split case (one test, so that one worker pays
    for it):

    * the split grid gives the one-device run's fields, gauges and steps to round-off on 2, 4 and 8 devices in
      1D (sod), 2D (sedov-2d) and 3D (sedov-3d, 16^3), and the final state lies on N devices; a one-device run
      is not split;
    * the split loop's optimised HLO (each of those runs): the stencils' neighbour cells come from
      collective permutes of a few planes of cells (the halo: at most 2 ghost planes per side, of at most 8
      rows), at most 6 of them (the rows stacked: one exchange per side and exchange point), and no all-gather
      or all-to-all moves a grid-sized array; the slab-by-slab step equals the whole grid's to round-off for
      every scheme and kind of x boundary (outflow, wall, periodic, axis, mixed) in 1D, 2D and 3D, Cartesian,
      r-z and spherical, on 2 and 4 devices. The one-device-shaped program would
      instead need every device to see the whole grid; a partitioner that fell back to gathering would show
      up here as an all-gather of the grid's cell count (as it did for a concatenated zero ghost cell on a
      1D grid before boundaries.extend_coefficient selected it instead);
    * a checkpoint written on 2 devices continues on 4 and on 1 with the uninterrupted run's steps and fields;
    * MPM (taylor-bar, 4 us): the particle pool split over 2, 4 and 8 devices gives the one-device run's
      particles and steps to round-off, as it does in 1D (mpm-sod) and 3D (a quarter of the Taylor rod); a
      pool of 6001 slots is rounded up to 6008 on 8; the compiled loop adds the nodal sums across devices
      (all-reduces of node-sized arrays) and moves no pool-sized array between devices;
      a checkpoint written on 2 devices continues on 1;
    * cfdmp, and snapshots written on 2 devices: test_coupled_split_and_snapshots_on_two_virtual_devices;
    * more devices than visible, and "all" not dividing the cells, are refused naming the key."""
    measured = _split_runs(tmp_path)
    assert measured["visible"] == 8
    split_grids = [f"{name}/{n}" for name in ("sod", "sedov-2d", "sedov-3d") for n in (2, 4, 8)]
    for case in split_grids:
        entry = measured[case]
        assert entry["devices_used"] == int(case.split("/")[1]), case  # the final state really lies on N devices
        assert entry["steps"] == entry["steps_ref"], case
        assert max(entry["fields"].values()) <= RELATIVE, (case, entry["fields"])
        assert entry["gauges"] <= RELATIVE, case
        assert all(g["arrival_time"] is not None for g in entry["gauge_values"][0]), case  # the gauges saw the blast
    assert measured["sedov-2d/1"]["devices_used"] == 1
    for case in split_grids:
        hlo = measured[case]["hlo"]
        assert hlo["permutes"], f"{case}: no collective-permute: the split loop exchanges no halos"
        assert max(hlo["permutes"]) <= 2 * 8 * hlo["plane"], case
        # halos by hand (euler.step._slab_by_slab): one stacked exchange per side and exchange point (HLLC-MUSCL: 2
        # in its loop body, one stage; Lax-Wendroff: 6); the compiler's partitioning made 34-76, a row and stencil
        # shift each
        assert len(hlo["permutes"]) <= 6, (case, hlo["permutes"])
        assert all(size < hlo["cells"] for size in hlo["gathers"]), (case, hlo["gathers"])
        assert hlo["all_to_all"] == 0, case
    assert len(measured["slab_steps"]) == 60 and max(measured["slab_steps"].values()) <= RELATIVE, measured["slab_steps"]
    for n in (4, 1):
        entry = measured[f"restart/{n}"]
        assert entry["steps"][0] == entry["steps"][1], n
        assert max(entry["fields"].values()) <= RELATIVE, (n, entry["fields"])
    for n in (2, 4, 8):  # MPM: the pool split over the devices
        entry = measured[f"mpm/{n}"]
        assert entry["devices_used"] == n and entry["steps"] == entry["steps_ref"], (n, entry)
        assert max(entry["fields"].values()) <= RELATIVE_MPM, (n, entry["fields"])
    for case in (f"{label}/{n}" for label in ("mpm1d", "mpm3d") for n in (2, 4, 8)):  # MPM in 1D and 3D
        entry = measured[case]
        assert entry["devices_used"] == int(case.split("/")[1]) and entry["steps"] == entry["steps_ref"], entry
        assert entry["particles"] > 500, entry
        assert max(entry["fields"].values()) <= RELATIVE_MPM, (case, entry["fields"])
    assert measured["mpm/8"]["pool"] == 6008  # numerics.capacity 6001 rounded up to equal parts
    hlo = measured["mpm/2"]["hlo"]
    pool, nodes = measured["mpm/2"]["pool"], measured["mpm/2"]["nodes"]
    # the nodal sums, added across devices: node-sized arrays (a channel each, or rows of all channels), not the
    # pool's; and no array of the pool's particles is gathered or exchanged (they stay on their device)
    assert hlo["all-reduce"] and all(size < 100 or size % nodes == 0 for size in hlo["all-reduce"]), (hlo, nodes)
    assert all(size < pool for size in hlo["all-gather"]) and not hlo["all-to-all"], hlo
    entry = measured["mpm_restart"]
    assert entry["steps"][0] == entry["steps"][1] and max(entry["fields"].values()) <= RELATIVE_MPM, entry
    message = measured["too_many"]
    assert message is not None and "numerics.devices = 16" in message and "only 8 device(s) visible" in message
    message = measured["all_indivisible"]
    assert message is not None and 'numerics.devices = "all" is 8 devices' in message
    assert "grid.cells = 36 is not divisible by 8" in message


def _sedov(devices, cells=32):
    data = tomllib.loads((files("blastfsi.examples") / "sedov-2d.toml").read_text())
    data["grid"]["cells"] = cells
    data["numerics"]["devices"] = devices
    return data


def test_devices_must_divide_the_cells():
    with pytest.raises(ScenarioError, match=r"numerics.devices = 3.*grid.cells = 32 is not divisible.*\[1, 2, 4, 8, "
                                            r"16, 32\]"):
        expand(_sedov(3))
    for bad in (0, -1, "some", 2.0):
        with pytest.raises(ScenarioError, match="numerics.devices"):
            expand(_sedov(bad))
    expand(_sedov("all"))
    expand(_sedov(4))


def test_more_devices_than_this_process_sees_refused_before_the_run():
    from blastfsi.simulation import run
    import jax

    visible = len(jax.devices())
    with pytest.raises(ScenarioError, match=rf"numerics.devices = {visible + 1}: only {visible} device"):
        run(_sedov(visible + 1, cells=32 * (visible + 1)))


def test_cfdmp_devices_checked_naming_the_key():
    from blastfsi.simulation import run
    import jax

    data = tomllib.loads((files("blastfsi.examples") / "cfdmp-shock-tube.toml").read_text())
    for bad in (0, -1, "some", 2.0):
        data.setdefault("numerics", {})["devices"] = bad
        with pytest.raises(ScenarioError, match="numerics.devices"):
            expand(data)
    visible = len(jax.devices())
    data["numerics"]["devices"] = visible + 1
    with pytest.raises(ScenarioError, match=rf"numerics.devices = {visible + 1}: only {visible} device"):
        run(data)


MEMBERS_SCRIPT = textwrap.dedent('''
    import copy, json, pathlib, re, sys, tomllib
    from importlib.resources import files
    import jax
    import numpy as np
    from blastfsi import method as methods, simulation
    from blastfsi.scenario import ScenarioError

    data = tomllib.loads((files("blastfsi.examples") / "plate1d-uniform.toml").read_text())
    data["grid"]["cells"] = 200
    data["time"]["end"] = 0.0155
    data["output"].update({"fields": 0, "plots": False, "history_samples": 101})
    data["sweep"] = {"overpressure": [4e5, 8e5], "beta_s": [0.5, 1.0, 2.0, 4.0]}  # 8 members

    def with_devices(d, n):
        d = copy.deepcopy(d)
        d.setdefault("numerics", {})["devices"] = n
        return d

    def leaves(res):
        return {k: np.asarray(v) for k, v in res.state._asdict().items() if np.asarray(v).dtype.kind == "f"}

    def collectives(exe):  # per kind, the shapes of the compiled loop's collectives
        found = {}
        for line in exe.as_text().splitlines():
            m = re.search(r"= (\\S+) (all-gather|all-reduce|collective-permute|all-to-all|reduce-scatter)(-start)?\\(",
                          line)
            if m:
                found.setdefault(m.group(2), []).append(m.group(1))
        return found

    report, ref = {"visible": len(jax.devices())}, None
    for n in (1, 2, 8):
        res = simulation.run(with_devices(data, n))
        got = leaves(res)
        entry = {"devices_used": len(res.state.x.sharding.device_set), "steps": np.asarray(res.state.step).tolist(),
                 "summaries": [{k: m[k] for k in ("plate_velocity", "plate_impulse", "peak_overpressure")}
                               for m in res.summaries]}
        if ref is None:
            ref = got
        else:
            entry["differs"] = sorted(k for k in ref if not np.array_equal(ref[k], got[k], equal_nan=True))
            entry["collectives"] = collectives(list(methods._EXECUTABLES.values())[-1])
        report[f"members/{n}"] = entry

    # a checkpoint written on 2 devices, continued on 4 and on 1
    out = pathlib.Path(sys.argv[1]) / "sweep"
    ckpt = dict(data, output=dict(data["output"], checkpoint_interval=0.008))
    whole = simulation.run(with_devices(ckpt, 2), out=out)
    for n in (4, 1):
        again = simulation.run(with_devices(ckpt, n), out=out, restart=True)
        report[f"restart/{n}"] = {"differs": sorted(k for k, v in leaves(whole).items()
                                                    if not np.array_equal(v, leaves(again)[k], equal_nan=True)),
                                  "devices_used": len(again.state.x.sharding.device_set)}

    def refused(d):
        try:
            simulation.run(d)
        except ScenarioError as err:
            return str(err)
        return None

    report["three_for_eight"] = refused(with_devices(data, 3))
    single = copy.deepcopy(data)
    del single["sweep"]
    report["two_for_one"] = refused(with_devices(single, 2))
    print("REPORT" + json.dumps(report))
''')


@pytest.mark.slow  # default-suite time (32 s; the suite at 515-616 s on 2 cores), as the other split runs
def test_sweep_members_spread_over_virtual_devices(tmp_path):
    """lagrangian1d's numerics.devices spreads the members of a sweep over the devices (each chain whole on one
    device): on 2 and 8 virtual CPU devices an 8-member plate sweep gives the one-device run's state bit for
    bit, lies on that many devices, and its compiled loop moves no member's data between devices (the only
    collectives are the scalar all-reduces of the loop's condition: every member done, none faulted); a
    checkpoint written on 2 devices continues on 4 and on 1 to the uninterrupted run's state; a device count
    that does not divide the members is refused naming the key."""
    script = tmp_path / "members.py"
    script.write_text(MEMBERS_SCRIPT)
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=8", "JAX_PLATFORMS": "cpu",
           "BLASTFSI_NO_CACHE": "1"}
    proc = subprocess.run([sys.executable, str(script), str(tmp_path)], capture_output=True, text=True, env=env,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    measured = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("REPORT"))[len("REPORT"):])
    assert measured["visible"] == 8
    one = measured["members/1"]
    assert one["devices_used"] == 1 and min(one["steps"]) > 500  # the plates were loaded (arrival ~14 ms)
    for n in (2, 8):
        entry = measured[f"members/{n}"]
        assert entry["devices_used"] == n and entry["steps"] == one["steps"], (n, entry)
        assert entry["differs"] == [] and entry["summaries"] == one["summaries"], (n, entry)
        kinds = entry["collectives"]
        assert set(kinds) <= {"all-reduce"}, (n, kinds)  # no halo, gather or reshuffle of member data
        assert all(shape.startswith("pred[]") for shape in kinds.get("all-reduce", [])), (n, kinds)
    for n in (4, 1):
        assert measured[f"restart/{n}"] == {"differs": [], "devices_used": n}, measured[f"restart/{n}"]
    assert "numerics.devices = 3" in measured["three_for_eight"] and "8 member(s)" in measured["three_for_eight"]
    assert "numerics.devices = 2" in measured["two_for_one"] and "1 member(s)" in measured["two_for_one"]
