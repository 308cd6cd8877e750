"""Multi-dimensional field output that ParaView and meshio open: Eulerian grids and MPM particles.

Format: one HDF5 file per snapshot (heavy data) + XDMF 3 text indices to it. Two indices, because no one XDMF
layout is read by both ParaView and meshio:

- the *series* (``write_*_series``): one XDMF temporal collection per member, what ParaView opens as a time
  series. Grids are a structured ``3DCoRectMesh`` (no cell connectivity stored; ParaView gets image data).
  meshio cannot read it: ``meshio.read`` takes one Uniform grid only ("Unknown section 'Grid'" on a
  collection), and ``meshio.xdmf.TimeSeriesReader`` needs a mesh with explicit connectivity that does not move.
- the *snapshot* index (``write_*_xdmf``): one XDMF file per snapshot holding one Uniform grid with explicit
  cells, what ``meshio.read`` opens (ParaView too). Grids are lines / quadrilaterals / hexahedra whose points
  and connectivity are written once per member (:func:`write_grid_mesh`), so the snapshots are not
  enlarged; particles are a ``Polyvertex`` topology whose connectivity (0 .. n-1) is stored in the snapshot.

HDF5 + XDMF was chosen over VTKHDF because (a) the indices are small text files rewritten from the list of
snapshots, so a restart or a crash never corrupts earlier snapshots (a transient VTKHDF file is one growing
HDF5 file); (b) the pip ``vtk`` wheel reads the whole XDMF time series (``vtkXdmfReader``: time values
included), so the time index is checked with a real reader; (c) the snapshot files stay plain HDF5 that h5py
users read directly.

Conventions, all checked by ``tests/test_io_fields.py`` with ``vtkXdmfReader`` and ``meshio``:

- Cell fields are stored flat, one row per cell, x fastest then y then z (cell ``(i, j, k)`` is row
  ``i + nx (j + ny k)``), with the cell counts (x, y, z) in the attribute ``shape``: the row order of the
  snapshot index's cells, which meshio needs one row per cell. The series declares the same datasets with
  dimensions z, y, x, the order XDMF gives CoRectMesh dimensions, origin and spacing in (slowest to fastest),
  which both ParaView readers (``XDMF Reader`` and ``Xdmf3Reader``, VTK ``IO/Xdmf2``/``IO/Xdmf3``) reverse
  into VTK's x, y, z: ParaView shows x as x.
- In the series, 1D and 2D grids are 3D grids one cell thick in the missing directions (thickness = the cell
  size along x, origin 0 there). A ``2DCoRectMesh`` would be placed in VTK's y-z plane by both readers
  (x shown as y), and a grid one *node* thick loses its cell data in ``vtkXdmfReader``. In the snapshot index
  they are lines along x / quadrilaterals in the plane z = 0.
- Vectors are stored with 3 components (zero-padded), tensors with 9 (row-major xx, xy, xz, yx, ..., zz;
  zero-padded from 2x2 / 1x1), the widths ParaView's glyph and tensor filters expect. We store all 9
  components rather than 6-component Voigt because XDMF ``Tensor6`` (xx, xy, xz, yy, yz, zz) and VTK's
  symmetric order (xx, yy, zz, xy, yz, xz) disagree; 9 components are read the same way everywhere.
- Particles are an XDMF ``Polyvertex`` topology (one vertex cell per particle) with node-centred data;
  coordinates are padded to 3 with zeros. An index needs at least one particle: ``vtkXdmfReader`` fails on
  an empty geometry (a coupled snapshot's particles may be none: that time step then shows the grid alone,
  and the snapshot has no particle index).
- Grid + particles (a coupled Eulerian-MPM run): ONE HDF5 file per snapshot with a group ``grid`` laid out
  as a grid file and a group ``particles`` laid out as a particle file (one file, so a snapshot is written
  or missing as a whole). In the series every step is a ``Spatial`` collection of the two Uniform grids (the
  reader gives a multiblock dataset of two blocks, grid and particles, per time); the snapshot index is one
  file per part.

Each snapshot file also records, as attributes, what is needed to undo the padding (``read_*_snapshot``).
"""
from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import h5py
import numpy as np

KIND_COMPONENTS = {"scalar": 1, "vector": 3, "tensor": 9}  # components stored on disk per field kind
_DTYPES = {4: np.float32, 8: np.float64}  # XDMF Precision (bytes) -> stored dtype
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
COORDINATES = "coordinates"  # particle-snapshot dataset holding the (n, 3) positions
CONNECTIVITY = "connectivity"  # particle-snapshot dataset (n, 1): particle p is vertex cell p (snapshot index)
POINTS = "points"  # grid-mesh dataset holding the (nodes, 3) node coordinates (CONNECTIVITY: the cells' nodes)
_PARTICLE_DATASETS = (COORDINATES, CONNECTIVITY)  # a particle snapshot's datasets that are not fields
GRID_GROUP, PARTICLES_GROUP = "grid", "particles"  # the two HDF5 groups of a coupled snapshot (and XDMF grid names)


class GridSnapshot(NamedTuple):
    time: float
    origin: np.ndarray
    spacing: np.ndarray
    fields: dict[str, np.ndarray]


class ParticleSnapshot(NamedTuple):
    time: float
    positions: np.ndarray
    fields: dict[str, np.ndarray]


class CoupledSnapshot(NamedTuple):
    time: float
    grid: GridSnapshot
    particles: ParticleSnapshot


# --------------------------------------------------------------------------------------------------- checks
def grid_geometry(origin, spacing) -> tuple[np.ndarray, np.ndarray]:
    """Validated (origin, spacing) as float arrays of length ndim = len(origin) in 1..3.

    ``spacing`` is one cell size for all axes or one per axis; every value must be finite and > 0.
    """
    origin = np.atleast_1d(np.asarray(origin, dtype=float))
    if origin.ndim != 1 or not 1 <= origin.size <= 3 or not np.all(np.isfinite(origin)):
        raise ValueError(f"origin must be 1 to 3 finite coordinates (x[, y[, z]]), got {origin.tolist()}")
    spacing = np.asarray(spacing, dtype=float)
    if spacing.ndim == 0:
        spacing = np.full(origin.shape, float(spacing))
    if spacing.shape != origin.shape or not np.all(np.isfinite(spacing) & (spacing > 0)):
        raise ValueError(f"spacing must be one cell size > 0 or {origin.size} of them (one per axis), "
                         f"got {np.asarray(spacing).tolist()}")
    return origin, spacing


def _dtype(precision: int):
    if precision not in _DTYPES:
        raise ValueError(f"precision must be 4 (float32) or 8 (float64) bytes, got {precision!r}")
    return _DTYPES[precision]


def _time(time) -> float:
    time = float(time)
    if not np.isfinite(time):
        raise ValueError(f"time must be finite, got {time}")
    return time


def _check_names(names, reserved=()) -> None:
    for name in names:
        if not isinstance(name, str) or not _NAME.match(name) or name in reserved:
            raise ValueError(f"field name {name!r} must be an identifier (letters, digits, '_')"
                             + (f" other than {', '.join(reserved)}" if reserved else ""))


def _check_kinds(field_kinds: Mapping[str, str], reserved=()) -> None:
    _check_names(field_kinds, reserved)
    for name, kind in field_kinds.items():
        if kind not in KIND_COMPONENTS:
            raise ValueError(f"kind of field {name!r} must be one of {sorted(KIND_COMPONENTS)}, got {kind!r}")


def _check_snapshot_list(snapshots, layout: tuple[str, ...]) -> None:
    if not snapshots:
        raise ValueError("snapshots must list at least one snapshot")
    for entry in snapshots:
        if len(entry) != len(layout) or Path(entry[0]).is_absolute():
            raise ValueError(f"each snapshot must be ({', '.join(layout)}), got {entry!r}")
    times = np.array([_time(entry[1]) for entry in snapshots])
    if np.any(np.diff(times) <= 0):
        raise ValueError(f"snapshot times must be strictly increasing, got {times.tolist()}")


# ----------------------------------------------------------------------------------------- components
def _padded(name: str, array: np.ndarray, lead_shape: tuple[int, ...], ndim: int) -> tuple[str, np.ndarray, tuple]:
    """(kind, array with its value axes padded to 1, 3 or 9 stored components, value shape as given).

    The value shape is what follows ``lead_shape``: () scalar, (d,) vector, (d, d) tensor, d = ndim or 3.
    """
    lead = len(lead_shape)
    if array.shape[:lead] != lead_shape:
        raise ValueError(f"field {name!r} has shape {array.shape}; its leading axes must be {lead_shape}")
    value_shape = array.shape[lead:]
    if value_shape == ():
        return "scalar", array, value_shape
    d = value_shape[0]
    if d not in (ndim, 3) or value_shape not in ((d,), (d, d)):
        raise ValueError(f"field {name!r} has shape {array.shape}: after the leading axes {lead_shape} allowed "
                         f"are () scalar, ({ndim},) or (3,) vector, ({ndim}, {ndim}) or (3, 3) tensor")
    pad = [(0, 0)] * lead + [(0, 3 - d)] * len(value_shape)
    padded = np.pad(array, pad)
    if len(value_shape) == 1:
        return "vector", padded, value_shape
    return "tensor", padded.reshape(lead_shape + (9,)), value_shape


def _unpadded(stored: np.ndarray, lead: int, value_shape: tuple[int, ...]) -> np.ndarray:
    if value_shape == ():
        return stored
    d = value_shape[0]
    if len(value_shape) == 1:
        return stored[..., :d]
    return stored.reshape(stored.shape[:lead] + (3, 3))[..., :d, :d]


def _to_rows(array: np.ndarray, ndim: int) -> np.ndarray:
    """Spatial axes (x[, y[, z]]) -> one row per cell, x fastest; the value axis (if any) kept last."""
    order = tuple(reversed(range(ndim))) + tuple(range(ndim, array.ndim))
    return np.ascontiguousarray(np.transpose(array, order)).reshape((-1,) + array.shape[ndim:])


def _from_rows(stored: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Inverse of :func:`_to_rows` for a grid of ``shape`` cells (x[, y[, z]])."""
    ndim = len(shape)
    out = stored.reshape(tuple(reversed(shape)) + stored.shape[1:])
    return np.transpose(out, tuple(reversed(range(ndim))) + tuple(range(ndim, out.ndim)))


# --------------------------------------------------------------------------------------------- XDMF text
def _data_item(dims, reference: str, precision: int, number_type: str = "Float") -> str:
    return (f'<DataItem Dimensions="{" ".join(str(int(n)) for n in dims)}" NumberType="{number_type}" '
            f'Precision="{precision}" Format="HDF">{reference}</DataItem>')


def _index_dtype(largest: int):
    """Integer type of connectivity whose largest entry is ``largest``: int32 while it fits, else int64."""
    return np.int32 if largest < 2 ** 31 else np.int64


def _index_item(dims, reference: str, largest: int) -> str:
    return _data_item(dims, reference, np.dtype(_index_dtype(largest)).itemsize, "Int")


def _h5_location(h5_name, group: str = "") -> str:
    """``file.h5:`` (datasets at the root) or ``file.h5:/group``: a dataset ``name`` is at ``<location>/name``."""
    return f"{_xml_file_name(h5_name)}:" + (f"/{group}" if group else "")


def _attributes(location: str, field_kinds: Mapping[str, str], lead_dims, center: str, precision: int) -> str:
    parts = []
    for name, kind in field_kinds.items():
        width = KIND_COMPONENTS[kind]
        dims = tuple(lead_dims) + ((width,) if width > 1 else ())
        parts.append(f'<Attribute Name="{name}" AttributeType="{kind.capitalize()}" Center="{center}">'
                     f'{_data_item(dims, f"{location}/{name}", precision)}</Attribute>')
    return "".join(parts)


def _time_element(time) -> str:
    return f'<Time Value="{float(time)!r}"/>'


def _uniform(name: str, body: str, time=None) -> str:
    """An XDMF Uniform grid; ``time`` None leaves the time to the enclosing collection."""
    return f'<Grid Name="{name}" GridType="Uniform">{"" if time is None else _time_element(time)}{body}</Grid>'


def _write_domain(xdmf_path, grid: str) -> None:
    """Write an XDMF file of one top-level grid atomically (ParaView may be reading the previous one)."""
    xdmf_path = Path(xdmf_path)
    tmp = xdmf_path.with_name(xdmf_path.name + ".tmp")
    tmp.write_text(f'<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain>{grid}</Domain></Xdmf>\n')
    tmp.replace(xdmf_path)


def _write_collection(xdmf_path, grids: list[str]) -> None:
    """The temporal collection of ``grids`` (the series)."""
    steps = "".join(f"{grid}\n" for grid in grids)
    _write_domain(xdmf_path, f'<Grid Name="series" GridType="Collection" CollectionType="Temporal">\n{steps}</Grid>')


def _xml_file_name(name) -> str:
    return str(name).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


class _GridLayout(NamedTuple):
    """What every step of a grid series shares: cell counts (z, y, x) and the topology + geometry XML."""
    cells_zyx: tuple[int, int, int]
    mesh: str


def _grid_layout(shape: Sequence[int], origin, spacing) -> _GridLayout:
    """Validated uniform-grid mesh of ``shape`` cells (x[, y[, z]]) as a 3DCoRectMesh (see the module notes)."""
    origin, spacing = grid_geometry(origin, spacing)
    ndim = origin.size
    shape = tuple(int(n) for n in shape)
    if len(shape) != ndim or min(shape) < 1:
        raise ValueError(f"shape must give >= 1 cell along each of the {ndim} axes of origin, got {shape}")
    cells_zyx = (1,) * (3 - ndim) + shape[::-1]
    origin_zyx = np.concatenate([np.zeros(3 - ndim), origin[::-1]])
    spacing_zyx = np.concatenate([np.full(3 - ndim, spacing[0]), spacing[::-1]])
    geometry = "".join(f'<DataItem Dimensions="3" NumberType="Float" Precision="8" Format="XML">'
                       f'{" ".join(repr(float(v)) for v in values)}</DataItem>' for values in (origin_zyx, spacing_zyx))
    mesh = (f'<Topology TopologyType="3DCoRectMesh" Dimensions="{" ".join(str(n + 1) for n in cells_zyx)}"/>'
            f'<Geometry GeometryType="ORIGIN_DXDYDZ">{geometry}</Geometry>')
    return _GridLayout(cells_zyx, mesh)


def _grid_body(location: str, layout: _GridLayout, field_kinds: Mapping[str, str], precision: int) -> str:
    return layout.mesh + _attributes(location, field_kinds, layout.cells_zyx, "Cell", precision)


_CELL_TOPOLOGY = {1: ("Polyline", 2), 2: ("Quadrilateral", 4), 3: ("Hexahedron", 8)}  # ndim -> (XDMF type, nodes)


def _cell_shape(shape: Sequence[int]) -> tuple[int, ...]:
    shape = tuple(int(n) for n in shape)
    if not 1 <= len(shape) <= 3 or min(shape) < 1:
        raise ValueError(f"shape must give >= 1 cell along each of 1 to 3 axes (x[, y[, z]]), got {shape}")
    return shape


def _mesh_body(mesh_name, shape: tuple[int, ...]) -> str:
    """Topology + geometry of the cells of a :func:`write_grid_mesh` file."""
    cell_type, corners = _CELL_TOPOLOGY[len(shape)]
    cells, nodes = int(np.prod(shape)), int(np.prod([n + 1 for n in shape]))
    location = _h5_location(mesh_name)
    return (f'<Topology TopologyType="{cell_type}" NodesPerElement="{corners}" NumberOfElements="{cells}">'
            f'{_index_item((cells, corners), f"{location}/{CONNECTIVITY}", nodes - 1)}</Topology>'
            f'<Geometry GeometryType="XYZ">{_data_item((nodes, 3), f"{location}/{POINTS}", 8)}</Geometry>')


def _particle_count(h5_name, count) -> int:
    count = int(count)
    if count < 1:
        raise ValueError(f"snapshot {h5_name!r} must hold >= 1 particle, got {count}")
    return count


def _particle_body(location: str, count: int, field_kinds: Mapping[str, str], precision: int) -> str:
    return (f'<Topology TopologyType="Polyvertex" NodesPerElement="1" NumberOfElements="{count}">'
            f'{_index_item((count, 1), f"{location}/{CONNECTIVITY}", count - 1)}</Topology>'
            f'<Geometry GeometryType="XYZ">{_data_item((count, 3), f"{location}/{COORDINATES}", precision)}'
            f'</Geometry>{_attributes(location, field_kinds, (count,), "Node", precision)}')


# ------------------------------------------------------------------------------------------------ grids
def _write_grid(group: h5py.Group, time, origin, spacing, fields: Mapping[str, np.ndarray],
                precision: int) -> dict[str, str]:
    """The grid datasets and attributes of :func:`write_grid_snapshot` into an open HDF5 group."""
    origin, spacing = grid_geometry(origin, spacing)
    ndim = origin.size
    dtype = _dtype(precision)
    if not fields:
        raise ValueError("fields must hold at least one array")
    _check_names(fields)
    arrays = {name: np.asarray(a) for name, a in fields.items()}
    shape = next(iter(arrays.values())).shape[:ndim]
    if len(shape) != ndim or min(shape) < 1:
        raise ValueError(f"fields of a {ndim}D grid need {ndim} spatial axes with >= 1 cell, got shape {shape}")
    kinds = {}
    group.attrs.update(time=_time(time), origin=origin, spacing=spacing, shape=np.array(shape))
    for name, array in arrays.items():
        kind, padded, value_shape = _padded(name, array, shape, ndim)
        ds = group.create_dataset(name, data=_to_rows(padded.astype(dtype), ndim))
        ds.attrs.update(kind=kind, value_shape=np.array(value_shape, dtype=int))
        kinds[name] = kind
    return kinds


def _read_grid(group: h5py.Group) -> GridSnapshot:
    origin, spacing = np.array(group.attrs["origin"]), np.array(group.attrs["spacing"])
    shape = tuple(int(n) for n in group.attrs["shape"])
    fields = {name: _unpadded(_from_rows(ds[()], shape), len(shape), tuple(ds.attrs["value_shape"]))
              for name, ds in group.items()}
    return GridSnapshot(float(group.attrs["time"]), origin, spacing, fields)


def write_grid_snapshot(h5_path, time, origin, spacing, fields: Mapping[str, np.ndarray], *,
                        precision: int = 8) -> dict[str, str]:
    """Write cell-centred fields of a uniform grid (1D, 2D or 3D) to one HDF5 file.

    ``origin`` is the lower corner (x[, y[, z]]), ``spacing`` the cell size (one, or one per axis). Each
    field is indexed ``[i(, j(, k))]`` = (x, y, z) with an optional value shape (d,) or (d, d), d = ndim or 3.
    Returns ``{name: kind}`` for :func:`write_grid_series`.
    """
    with h5py.File(h5_path, "w") as f:
        return _write_grid(f, time, origin, spacing, fields, precision)


def read_grid_snapshot(h5_path) -> GridSnapshot:
    """Read a file of :func:`write_grid_snapshot` back into arrays indexed (x, y, z) as they were given."""
    with h5py.File(h5_path, "r") as f:
        return _read_grid(f)


def write_grid_series(xdmf_path, snapshots: Sequence[tuple[str, float]], shape: Sequence[int], origin, spacing,
                      field_kinds: Mapping[str, str], *, precision: int = 8) -> None:
    """XDMF temporal collection over grid snapshots: ``snapshots`` = [(h5 file relative to the XDMF, time)].

    ``field_kinds`` maps each field name to "scalar", "vector" or "tensor" (what
    :func:`write_grid_snapshot` returns); ``shape`` is the number of cells along x[, y[, z]].
    """
    layout = _grid_layout(shape, origin, spacing)
    _dtype(precision)
    _check_kinds(field_kinds)
    _check_snapshot_list(snapshots, ("h5 file name relative to the XDMF file", "time"))
    _write_collection(xdmf_path, [_uniform(f"step{index}", _grid_body(_h5_location(h5_name), layout, field_kinds,
                                                                       precision), time)
                                  for index, (h5_name, time) in enumerate(snapshots)])


def write_grid_mesh(h5_path, shape: Sequence[int], origin, spacing) -> None:
    """Write the cells of a uniform grid as explicit lines (1D), quadrilaterals (2D) or hexahedra (3D) to one
    HDF5 file, for the snapshot indices of :func:`write_grid_xdmf`: ``points`` (nodes, 3), x fastest, then y,
    then z, padded with zeros to 3 coordinates; ``connectivity`` (cells, 2 / 4 / 8) in the cell order of the
    snapshot files, each cell's nodes in VTK's order (counter-clockwise seen from +z, the lower face first).
    """
    shape = _cell_shape(shape)
    origin, spacing = grid_geometry(origin, spacing)
    ndim = len(shape)
    if origin.size != ndim:
        raise ValueError(f"shape must give >= 1 cell along each of the {origin.size} axes of origin, got {shape}")
    nodes = [n + 1 for n in shape]
    coordinates = [o + d * np.arange(n) for o, d, n in zip(origin, spacing, nodes)]
    grids = np.meshgrid(*coordinates[::-1], indexing="ij")  # (z, y, x) order: x fastest when raveled
    points = np.zeros((int(np.prod(nodes)), 3))
    for axis in range(ndim):
        points[:, axis] = grids[ndim - 1 - axis].ravel()
    stride = np.cumprod([1] + nodes[:-1])  # node-index step along x, y, z
    corner = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                       (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)])[:_CELL_TOPOLOGY[ndim][1], :ndim] @ stride
    lower = np.meshgrid(*[np.arange(n) * s for n, s in zip(shape[::-1], stride[::-1])], indexing="ij")
    first = np.sum(lower, axis=0).ravel()  # each cell's lowest node, cells x fastest
    h5_path = Path(h5_path)
    tmp = h5_path.with_name(h5_path.name + ".tmp")  # (written once per run: never left half written)
    with h5py.File(tmp, "w") as f:
        f.attrs.update(origin=origin, spacing=spacing, shape=np.array(shape))
        f.create_dataset(POINTS, data=points)
        f.create_dataset(CONNECTIVITY, data=(first[:, None] + corner).astype(_index_dtype(len(points) - 1)))
    tmp.replace(h5_path)


def write_grid_xdmf(xdmf_path, h5_name, mesh_name, shape: Sequence[int], field_kinds: Mapping[str, str], *,
                    group: str = "", precision: int = 8) -> None:
    """XDMF index of ONE grid snapshot with explicit cells, what ``meshio.read`` opens: the cells of
    ``mesh_name`` (a :func:`write_grid_mesh` file) and the cell fields of ``h5_name`` (a
    :func:`write_grid_snapshot` file, or the group ``group`` of a :func:`write_coupled_snapshot` file); both
    names relative to the XDMF file. ``shape`` and ``field_kinds`` as for :func:`write_grid_series`.
    """
    shape = _cell_shape(shape)
    _dtype(precision)
    _check_kinds(field_kinds)
    location = _h5_location(h5_name, group)
    _write_domain(xdmf_path, _uniform(group or "grid", _mesh_body(mesh_name, shape) + _attributes(
        location, field_kinds, (int(np.prod(shape)),), "Cell", precision)))


# -------------------------------------------------------------------------------------------- particles
def _write_particles(group: h5py.Group, time, positions, fields: Mapping[str, np.ndarray], active,
                     precision: int, allow_empty: bool = False) -> dict[str, str]:
    """The particle datasets and attributes of :func:`write_particle_snapshot` into an open HDF5 group
    (with ``allow_empty``, also of no particle)."""
    dtype = _dtype(precision)
    positions = np.asarray(positions)
    if positions.ndim != 2 or not 1 <= positions.shape[1] <= 3:
        raise ValueError(f"positions must have shape (n, ndim) with ndim 1..3, got {positions.shape}")
    n, ndim = positions.shape
    keep = np.ones(n, dtype=bool) if active is None else np.asarray(active)
    if keep.shape != (n,) or keep.dtype != bool:
        raise ValueError(f"active must be a boolean array of shape ({n},), got {keep.dtype} {keep.shape}")
    count = int(keep.sum())
    if count == 0 and not allow_empty:
        raise ValueError("a particle snapshot needs at least one (active) particle; ParaView's XDMF readers fail "
                         "on an empty geometry, so skip this snapshot")
    _check_names(fields, reserved=_PARTICLE_DATASETS)
    kinds = {}
    group.attrs.update(time=_time(time), n_points=count, ndim=ndim)
    group.create_dataset(COORDINATES, data=np.pad(positions[keep], ((0, 0), (0, 3 - ndim))).astype(dtype))
    group.create_dataset(CONNECTIVITY, data=np.arange(count, dtype=_index_dtype(count - 1)).reshape(count, 1))
    for name, array in fields.items():
        kind, padded, value_shape = _padded(name, np.asarray(array), (n,), ndim)
        ds = group.create_dataset(name, data=padded[keep].astype(dtype))
        ds.attrs.update(kind=kind, value_shape=np.array(value_shape, dtype=int))
        kinds[name] = kind
    return kinds


def _read_particles(group: h5py.Group) -> ParticleSnapshot:
    ndim = int(group.attrs["ndim"])
    fields = {name: _unpadded(ds[()], 1, tuple(ds.attrs["value_shape"]))
              for name, ds in group.items() if name not in _PARTICLE_DATASETS}
    return ParticleSnapshot(float(group.attrs["time"]), group[COORDINATES][:, :ndim], fields)


def write_particle_snapshot(h5_path, time, positions, fields: Mapping[str, np.ndarray], *, active=None,
                            precision: int = 8) -> dict[str, str]:
    """Write particles (positions (n, ndim), ndim 1..3) and their data to one HDF5 file.

    Fields are (n,) scalars, (n, d) vectors or (n, d, d) tensors, d = ndim or 3. ``active`` (bool (n,)) keeps
    only the active entries of a fixed-capacity pool. Returns ``{name: kind}`` for
    :func:`write_particle_series`; the number of particles written is ``active.sum()`` (or n),
    :func:`particle_count`.
    """
    with h5py.File(h5_path, "w") as f:
        return _write_particles(f, time, positions, fields, active, precision)


def read_particle_snapshot(h5_path) -> ParticleSnapshot:
    """Read a file of :func:`write_particle_snapshot` back: positions (n, ndim) and fields as given."""
    with h5py.File(h5_path, "r") as f:
        return _read_particles(f)


def particle_count(h5_path, group: str = "") -> int:
    """Number of particles in a file of :func:`write_particle_snapshot` (``group`` "") or of
    :func:`write_coupled_snapshot` (``group`` :data:`PARTICLES_GROUP`)."""
    with h5py.File(h5_path, "r") as f:
        return int(f[group or "/"].attrs["n_points"])


def write_particle_series(xdmf_path, snapshots: Sequence[tuple[str, float, int]], field_kinds: Mapping[str, str],
                          *, precision: int = 8) -> None:
    """XDMF temporal collection over particle snapshots: ``snapshots`` = [(h5 file relative to the XDMF, time,
    number of particles in it)]; ``field_kinds`` as returned by :func:`write_particle_snapshot`."""
    _dtype(precision)
    _check_kinds(field_kinds, reserved=_PARTICLE_DATASETS)
    _check_snapshot_list(snapshots, ("h5 file name relative to the XDMF file", "time", "particles"))
    _write_collection(xdmf_path, [_uniform(f"step{index}", _particle_body(_h5_location(h5_name),
                                                                           _particle_count(h5_name, count),
                                                                           field_kinds, precision), time)
                                  for index, (h5_name, time, count) in enumerate(snapshots)])


def write_particle_xdmf(xdmf_path, h5_name, count: int, field_kinds: Mapping[str, str], *, group: str = "",
                        precision: int = 8) -> None:
    """XDMF index of ONE particle snapshot, what ``meshio.read`` opens: ``h5_name`` (relative to the XDMF
    file) a :func:`write_particle_snapshot` file of ``count`` >= 1 particles, or the group ``group`` of a
    :func:`write_coupled_snapshot` file; ``field_kinds`` as returned by the snapshot writer."""
    _dtype(precision)
    _check_kinds(field_kinds, reserved=_PARTICLE_DATASETS)
    _write_domain(xdmf_path, _uniform(group or "particles", _particle_body(
        _h5_location(h5_name, group), _particle_count(h5_name, count), field_kinds, precision)))


# ----------------------------------------------------------------------------------- grid + particles
def write_coupled_snapshot(h5_path, time, origin, spacing, grid_fields: Mapping[str, np.ndarray], positions,
                           particle_fields: Mapping[str, np.ndarray], *, active=None,
                           precision: int = 8) -> tuple[dict[str, str], dict[str, str]]:
    """Write a uniform grid and a particle cloud of the same dimension to one HDF5 file: the group
    :data:`GRID_GROUP` as :func:`write_grid_snapshot` writes a file, the group :data:`PARTICLES_GROUP` as
    :func:`write_particle_snapshot` does (arguments as there, but the particles may be none: an MPM box
    whose gas has all left), and the attribute ``time`` at the root.
    Returns the ``{name: kind}`` of the grid fields and of the particle fields for :func:`write_coupled_series`.
    """
    ndim, particle_ndim = np.atleast_1d(origin).size, np.shape(positions)[-1]
    if particle_ndim != ndim:
        raise ValueError(f"positions must have the grid's {ndim} coordinates per particle, got {particle_ndim}")
    with h5py.File(h5_path, "w") as f:
        f.attrs["time"] = _time(time)
        grid_kinds = _write_grid(f.create_group(GRID_GROUP), time, origin, spacing, grid_fields, precision)
        particle_kinds = _write_particles(f.create_group(PARTICLES_GROUP), time, positions, particle_fields, active,
                                          precision, allow_empty=True)
    return grid_kinds, particle_kinds


def read_coupled_snapshot(h5_path) -> CoupledSnapshot:
    """Read a file of :func:`write_coupled_snapshot` back (as :func:`read_grid_snapshot` and
    :func:`read_particle_snapshot` do)."""
    with h5py.File(h5_path, "r") as f:
        return CoupledSnapshot(float(f.attrs["time"]), _read_grid(f[GRID_GROUP]), _read_particles(f[PARTICLES_GROUP]))


def write_coupled_series(xdmf_path, snapshots: Sequence[tuple[str, float, int]], shape: Sequence[int], origin,
                         spacing, grid_kinds: Mapping[str, str], particle_kinds: Mapping[str, str], *,
                         precision: int = 8) -> None:
    """XDMF temporal collection over files of :func:`write_coupled_snapshot`, each time step a Spatial collection
    of the grid (named "grid", as in :func:`write_grid_series`) and the particles (named "particles", as in
    :func:`write_particle_series`; left out of a step with no particle). ``snapshots`` = [(h5 file relative to
    the XDMF, time, number of particles in it)]; ``shape``, ``origin``, ``spacing`` describe the grid; the kinds
    are what the snapshot writer returns.
    """
    layout = _grid_layout(shape, origin, spacing)
    _dtype(precision)
    _check_kinds(grid_kinds)
    _check_kinds(particle_kinds, reserved=_PARTICLE_DATASETS)
    _check_snapshot_list(snapshots, ("h5 file name relative to the XDMF file", "time", "particles"))
    steps = []
    for index, (h5_name, time, count) in enumerate(snapshots):
        grid = _uniform(GRID_GROUP, _grid_body(_h5_location(h5_name, GRID_GROUP), layout, grid_kinds, precision))
        cloud = "" if count == 0 else _uniform(PARTICLES_GROUP, _particle_body(
            _h5_location(h5_name, PARTICLES_GROUP), _particle_count(h5_name, count), particle_kinds, precision))
        steps.append(f'<Grid Name="step{index}" GridType="Collection" CollectionType="Spatial">'
                     f'{_time_element(time)}{grid}{cloud}</Grid>')
    _write_collection(xdmf_path, steps)
