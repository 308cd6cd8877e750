"""Everything the driver writes into a results directory.

Layout::

    .blastfsi                  marker: a results directory (what --overwrite may empty)
    scenario.toml              the resolved scenario (defaults filled in)
    summary.json               the run's summary quantities (rewritten at each output, key status)
    history.csv                (history_member<k>.csv for ensembles) SI units in the header; appended as the run goes
    fields/                    field snapshots, one FieldWriter per snapshot kind:
                               member<k>.xdmf    member k's time series (open it in ParaView)
                               member<k>_<i>.xdmf  snapshot i of member k as one mesh (meshio.read; coupled:
                                                 member<k>_<i>_grid.xdmf and, with particles, _particles.xdmf)
                               the data: 1D meshes snap_<i>.h5 (one group per member); grids, particles, and
                               grid + particles in one file (coupled; groups grid, particles)
                               (blastfsi.io.fields) member<k>_<i>.h5, with member<k>.mesh.h5 (a grid's cells)
    checkpoints/ckpt_<i>.h5    full solver state, for --restart
    plots/*.png
"""
from __future__ import annotations

import csv
import json
import re
import shutil
from pathlib import Path
from typing import Protocol

import h5py
import numpy as np
import tomli_w

from blastfsi.io import fields
from blastfsi.method import Coupled, Grid, Particles, Polyline


class OutputError(RuntimeError):
    pass


MARKER = ".blastfsi"  # the file that makes a directory a results directory
RUN_OUTPUTS = ("scenario.toml", "summary.json", "summary.json.tmp", "history*.csv", "fields", "checkpoints", "plots")
#              (glob patterns: everything a run writes besides the marker, removed by --overwrite)


def prepare_directory(path: Path, overwrite: bool) -> Path:
    """Create a fresh results directory, marked as one; never reuse a non-empty one silently: with
    ``overwrite``, only a results directory (its MARKER), whose earlier run's outputs are then removed."""
    try:
        if path.exists() and not path.is_dir():
            raise OutputError(f"results directory {path} is a file; choose another --out")
        if path.exists() and any(path.iterdir()):
            if not overwrite:
                raise OutputError(f"results directory {path} exists and is not empty; choose another --out, "
                                  "pass --overwrite, or continue it with --restart")
            if not (path / MARKER).is_file():
                raise OutputError(f"--overwrite refused: {path} is not a blastfsi results directory (it has no "
                                  f"{MARKER} marker); nothing in it was touched, choose another --out")
            _remove_outputs(path)
        for sub in ("fields", "checkpoints", "plots"):
            (path / sub).mkdir(parents=True, exist_ok=True)
        (path / MARKER).write_text("blastfsi results directory\n")
    except OSError as err:
        raise OutputError(f"results directory {path} cannot be created or emptied: {err.strerror or err}") from None
    return path


def _remove_outputs(path: Path) -> None:
    for pattern in RUN_OUTPUTS:
        for p in path.glob(pattern):
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()


def write_scenario(path: Path, scenario) -> None:
    (path / "scenario.toml").write_text(tomli_w.dumps(scenario.model_dump(exclude_none=True)))


def write_summary(path: Path, summary: dict) -> None:
    """Write atomically: a run killed while writing leaves the previous summary."""
    tmp = path / "summary.json.tmp"
    tmp.write_text(json.dumps(summary, indent=2) + "\n")
    tmp.replace(path / "summary.json")


def write_history(file: Path, columns, rows: np.ndarray) -> None:
    """The header and ``rows`` (replacing the file); :func:`append_history` adds rows as the run goes."""
    with open(file, "w", newline="") as fh:
        csv.writer(fh).writerow([f"{name} [{unit}]" for name, unit in columns])
    append_history(file, rows)


def append_history(file: Path, rows: np.ndarray) -> None:
    with open(file, "a", newline="") as fh:  # (closed, so flushed: a run killed later keeps them)
        csv.writer(fh).writerows([repr(float(v)) for v in r] for r in rows)


def read_history(file: Path) -> dict:
    with open(file) as fh:
        rows = list(csv.reader(fh))
    names = [re.sub(r"\s*\[.*\]$", "", h) for h in rows[0]]
    data = np.array(rows[1:], dtype=float).reshape(-1, len(names))
    return {n: data[:, i] for i, n in enumerate(names)}


def snapshot_name(index: int) -> str:
    return f"snap_{index:04d}.h5"


class FieldWriter(Protocol):
    """Writes one kind of :data:`blastfsi.method.Snapshot` under ``out/fields``."""

    def write(self, out: Path, index: int, time: float, members: list) -> None:
        """Snapshot number ``index`` at ``time`` of every ensemble member."""

    def write_series(self, out: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
        """The ParaView time-series index of one member over (index, time) pairs;
        ``template`` is a snapshot of that member (names and sizes of the fields)."""

    def read(self, out: Path, index: int, member: int):
        """Snapshot ``index`` of ``member`` back as a Snapshot of this kind."""


WRITERS: dict[str, FieldWriter] = {}


def register_writer(kind: str, writer: FieldWriter) -> None:
    WRITERS[kind] = writer


def writer(kind: str) -> FieldWriter:
    if kind not in WRITERS:
        raise OutputError(f"no field writer for snapshot kind {kind!r}; known: {sorted(WRITERS)}")
    return WRITERS[kind]


def write_snapshot(path: Path, index: int, time: float, members: list) -> None:
    writer(members[0].kind).write(path, index, time, members)


def write_series(path: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
    writer(template.kind).write_series(path, member, snapshots, template)


def read_snapshot(path: Path, kind: str, index: int, member: int):
    return writer(kind).read(path, index, member)


class PolylineWriter:
    """1D meshes (:class:`blastfsi.method.Polyline`): one HDF5 file per snapshot,
    /member<k>/{coordinates, connectivity, node and zone fields}, attribute
    time; an XDMF 3 temporal collection per member opens them in ParaView."""

    def write(self, path: Path, index: int, time: float, members: list) -> None:
        with h5py.File(path / "fields" / snapshot_name(index), "w") as f:
            f.attrs["time"] = time
            for k, snap in enumerate(members):
                grp = f.create_group(f"member{k}")
                x = np.asarray(snap.nodes)
                grp.create_dataset("coordinates", data=np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1))
                grp.create_dataset("connectivity",
                                   data=np.stack([np.arange(x.size - 1), np.arange(1, x.size)], axis=1))
                grp.attrs["node_fields"] = list(snap.node_fields)
                grp.attrs["cell_fields"] = list(snap.cell_fields)
                for name, arr in {**snap.node_fields, **snap.cell_fields}.items():
                    grp.create_dataset(name, data=np.asarray(arr, np.float64))  # the XDMF index says Precision 8
        for k, snap in enumerate(members):
            (path / "fields" / _index_file(index, k)).write_text(_xdmf(_polyline_grid(
                index, k, list(snap.node_fields), list(snap.cell_fields), np.asarray(snap.nodes).size)))

    def write_series(self, path: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
        write_xdmf(path, member, snapshots, list(template.node_fields), list(template.cell_fields),
                   np.asarray(template.nodes).size)

    def read(self, path: Path, index: int, member: int):
        with h5py.File(path / "fields" / snapshot_name(index), "r") as f:
            grp = f[f"member{member}"]
            return Polyline(nodes=grp["coordinates"][:, 0],
                            node_fields={n: grp[n][()] for n in grp.attrs["node_fields"]},
                            cell_fields={n: grp[n][()] for n in grp.attrs["cell_fields"]})


def _member_file(index: int, member: int) -> str:
    return f"member{member}_{index:04d}.h5"


def _index_file(index: int, member: int, part: str = "") -> str:
    """The meshio-readable XDMF of one snapshot (``part``: grid or particles of a coupled one)."""
    return f"member{member}_{index:04d}{'_' + part if part else ''}.xdmf"


def _mesh_file(member: int) -> str:
    return f"member{member}.mesh.h5"


def _write_grid_index(path: Path, index: int, member: int, grid: Grid, kinds: dict, part: str = "") -> None:
    """The snapshot's meshio-readable index, and the member's grid cells (written once)."""
    shape, origin, spacing, _ = _grid_series_args(grid)
    mesh = path / "fields" / _mesh_file(member)
    if not mesh.is_file():
        fields.write_grid_mesh(mesh, shape, origin, spacing)
    fields.write_grid_xdmf(path / "fields" / _index_file(index, member, part), _member_file(index, member),
                           mesh.name, shape, kinds, group=part)


def _uniform(edges) -> tuple[list[float], list[float]]:
    """(origin, spacing) of a uniform rectilinear grid given by its cell edges."""
    origin, spacing = [], []
    for axis, e in zip("xyz", edges):
        d = np.diff(np.asarray(e, float))
        if not np.allclose(d, d[0], rtol=1e-9, atol=0.0):
            raise OutputError(f"field output needs a uniform grid; the cell sizes along {axis} vary "
                              f"({d.min():.6g} to {d.max():.6g} m)")
        origin.append(float(e[0]))
        spacing.append(float(d[0]))
    return origin, spacing


def _value_kinds(arrays: dict, lead: int) -> dict[str, str]:
    return {n: ("scalar", "vector", "tensor")[np.ndim(a) - lead] for n, a in arrays.items()}


def _grid_series_args(grid: Grid) -> tuple[list[int], list[float], list[float], dict[str, str]]:
    """(cells per axis, origin, spacing, {field: kind}) of a uniform grid snapshot."""
    shape = [len(e) - 1 for e in grid.edges]
    return (shape, *_uniform(grid.edges), _value_kinds(grid.cell_fields, len(shape)))


def _grid(snap: fields.GridSnapshot) -> Grid:
    shape = np.shape(next(iter(snap.fields.values())))[:snap.origin.size]
    return Grid(edges=tuple(o + d * np.arange(n + 1) for o, d, n in zip(snap.origin, snap.spacing, shape)),
                cell_fields=snap.fields)


def _particles(snap: fields.ParticleSnapshot) -> Particles:
    return Particles(positions=snap.positions, point_fields=snap.fields)


class GridWriter:
    """Rectilinear grids (:class:`blastfsi.method.Grid`) through :mod:`blastfsi.io.fields`:
    fields/member<k>_<i>.h5 per member and snapshot, fields/member<k>.xdmf."""

    def write(self, path: Path, index: int, time: float, members: list) -> None:
        for k, snap in enumerate(members):
            origin, spacing = _uniform(snap.edges)
            kinds = fields.write_grid_snapshot(path / "fields" / _member_file(index, k), time, origin, spacing,
                                               snap.cell_fields)
            _write_grid_index(path, index, k, snap, kinds)

    def write_series(self, path: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
        shape, origin, spacing, kinds = _grid_series_args(template)
        fields.write_grid_series(path / "fields" / f"member{member}.xdmf",
                                 [(_member_file(i, member), t) for i, t in snapshots], shape, origin, spacing, kinds)

    def read(self, path: Path, index: int, member: int):
        return _grid(fields.read_grid_snapshot(path / "fields" / _member_file(index, member)))


class ParticleWriter:
    """Point clouds (:class:`blastfsi.method.Particles`) through :mod:`blastfsi.io.fields`:
    fields/member<k>_<i>.h5 per member and snapshot, fields/member<k>.xdmf."""

    def write(self, path: Path, index: int, time: float, members: list) -> None:
        for k, snap in enumerate(members):
            kinds = fields.write_particle_snapshot(path / "fields" / _member_file(index, k), time, snap.positions,
                                                   snap.point_fields)
            fields.write_particle_xdmf(path / "fields" / _index_file(index, k), _member_file(index, k),
                                       len(snap.positions), kinds)

    def write_series(self, path: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
        entries = [(_member_file(i, member), t, fields.particle_count(path / "fields" / _member_file(i, member)))
                   for i, t in snapshots]
        fields.write_particle_series(path / "fields" / f"member{member}.xdmf", entries,
                                     _value_kinds(template.point_fields, 1))

    def read(self, path: Path, index: int, member: int):
        return _particles(fields.read_particle_snapshot(path / "fields" / _member_file(index, member)))


class CoupledWriter:
    """A grid plus particles (:class:`blastfsi.method.Coupled`) through :mod:`blastfsi.io.fields`: ONE file
    fields/member<k>_<i>.h5 per member and snapshot (groups ``grid`` and ``particles``), and
    fields/member<k>.xdmf, a time series of spatial collections (grid, particles)."""

    def write(self, path: Path, index: int, time: float, members: list) -> None:
        for k, snap in enumerate(members):
            origin, spacing = _uniform(snap.grid.edges)
            grid_kinds, particle_kinds = fields.write_coupled_snapshot(
                path / "fields" / _member_file(index, k), time, origin, spacing, snap.grid.cell_fields,
                snap.particles.positions, snap.particles.point_fields)
            _write_grid_index(path, index, k, snap.grid, grid_kinds, fields.GRID_GROUP)
            if len(snap.particles.positions):
                fields.write_particle_xdmf(path / "fields" / _index_file(index, k, fields.PARTICLES_GROUP),
                                           _member_file(index, k), len(snap.particles.positions), particle_kinds,
                                           group=fields.PARTICLES_GROUP)

    def write_series(self, path: Path, member: int, snapshots: list[tuple[int, float]], template) -> None:
        shape, origin, spacing, grid_kinds = _grid_series_args(template.grid)
        entries = [(_member_file(i, member), t,
                    fields.particle_count(path / "fields" / _member_file(i, member), fields.PARTICLES_GROUP))
                   for i, t in snapshots]
        fields.write_coupled_series(path / "fields" / f"member{member}.xdmf", entries, shape, origin, spacing,
                                    grid_kinds, _value_kinds(template.particles.point_fields, 1))

    def read(self, path: Path, index: int, member: int):
        snap = fields.read_coupled_snapshot(path / "fields" / _member_file(index, member))
        return Coupled(grid=_grid(snap.grid), particles=_particles(snap.particles))


register_writer("polyline", PolylineWriter())
register_writer("grid", GridWriter())
register_writer("particles", ParticleWriter())
register_writer("coupled", CoupledWriter())


def _polyline_grid(index: int, member: int, node_fields, zone_fields, n_nodes: int, time=None) -> str:
    """XDMF Uniform grid of member ``member`` of 1D snapshot ``index`` (``time``: that of a series step)."""
    n_zones = n_nodes - 1
    h5 = f"{snapshot_name(index)}:/member{member}"
    attrs = "".join(
        f'<Attribute Name="{name}" Center="{center}"><DataItem Dimensions="{n}" NumberType="Float" '
        f'Precision="8" Format="HDF">{h5}/{name}</DataItem></Attribute>'
        for names, center, n in ((node_fields, "Node", n_nodes), (zone_fields, "Cell", n_zones))
        for name in names)
    stamp = "" if time is None else f'<Time Value="{float(time)!r}"/>'
    return (f'<Grid Name="t{index}" GridType="Uniform">{stamp}'
            f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{n_zones}">'
            f'<DataItem Dimensions="{n_zones} 2" NumberType="Int" Precision="8" Format="HDF">{h5}/connectivity'
            f'</DataItem></Topology><Geometry GeometryType="XYZ"><DataItem Dimensions="{n_nodes} 3" '
            f'NumberType="Float" Precision="8" Format="HDF">{h5}/coordinates</DataItem></Geometry>{attrs}</Grid>')


def _xdmf(grid: str) -> str:
    return f'<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain>{grid}</Domain></Xdmf>\n'


def write_xdmf(path: Path, member: int, snapshots: list[tuple[int, float]], node_fields, zone_fields, n_nodes) -> None:
    """XDMF 3 temporal collection so ParaView opens the snapshots as a time series."""
    grids = "".join(_polyline_grid(index, member, node_fields, zone_fields, n_nodes, time) for index, time in snapshots)
    (path / "fields" / f"member{member}.xdmf").write_text(_xdmf(
        f'<Grid Name="fields" GridType="Collection" CollectionType="Temporal">{grids}</Grid>'))


def write_checkpoint(path: Path, index: int, leaves: dict, meta: dict, suffix: str = "") -> Path:
    """Write ``checkpoints/ckpt_<index><suffix>.h5`` atomically (temporary file, then rename) so a crash never
    leaves a half checkpoint. (An interruption's checkpoint after scheduled one <index> has a suffix that sorts
    it between that one and the next.)"""
    file = path / "checkpoints" / f"ckpt_{index:04d}{suffix}.h5"
    tmp = file.with_suffix(".tmp")
    with h5py.File(tmp, "w") as f:
        for k, v in meta.items():
            f.attrs[k] = v
        for name, arr in leaves.items():
            f.create_dataset(name, data=np.asarray(arr))
    tmp.replace(file)
    return file


def read_latest_checkpoint(path: Path) -> tuple[Path, dict, list[str]]:
    """(file, leaves, skipped) of the newest checkpoint in ``path`` that reads back whole; ``skipped`` says
    why each newer one does not (truncated, empty, not HDF5, a directory). OutputError naming them all when
    none does."""
    files = sorted((path / "checkpoints").glob("ckpt_*.h5"), reverse=True)
    if not files:
        raise OutputError(f"--restart: no checkpoint in {path / 'checkpoints'}")
    skipped = []
    for file in files:
        try:
            return file, read_checkpoint(file)[0], skipped
        except (OSError, KeyError) as err:  # (h5py: OSError for a file it cannot open or read)
            skipped.append(f"{file}: a directory" if file.is_dir()
                           else f"{file} ({file.stat().st_size} bytes): {str(err).splitlines()[0]}")
    raise OutputError(f"--restart: no readable checkpoint in {path / 'checkpoints'}: {'; '.join(skipped)}")


def read_checkpoint(file: Path) -> tuple[dict, dict]:
    with h5py.File(file, "r") as f:
        return {k: f[k][()] for k in f.keys()}, dict(f.attrs)
