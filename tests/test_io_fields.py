"""Grid and particle snapshots + XDMF indices, read back with VTK's own XDMF reader (ParaView's engine) and meshio.

Field values are analytic functions of position that vary differently along x, y and z; every cell (point)
VTK reports is checked against the function evaluated at the cell centre (point) *VTK* computes, so a swap
of axes, a wrong origin/spacing order or a wrong memory order fails. The only tolerance is round-off in
those coordinates (a few ulp of |x| ~ 1, amplified by the field's gradients ~ 10): rtol = atol = 1e-12.
"""
import re

import matplotlib.image as mpimg
import meshio
import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import VTK_DOUBLE, VTK_FLOAT
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

from blastfsi.io import results
from blastfsi.io.fields import (read_grid_snapshot, read_particle_snapshot, write_coupled_snapshot, write_grid_mesh,
                                write_grid_series, write_grid_snapshot, write_particle_series, write_particle_snapshot)
from blastfsi.method import Coupled, Grid, Particles, Polyline
from blastfsi.plotting.fields import field_image, plot_particle_damage, plot_pressure_field

TOL = dict(rtol=1e-12, atol=1e-12)


def scalar_field(x, y, z, t):
    return 1.0 + 3.0 * x - 7.0 * y + 11.0 * z ** 2 + 1e3 * t


def vector_field(x, y, z):
    return np.stack([x + 2 * y, 5 * y - z, 0.5 * x * z], axis=-1)


def cell_centres(origin, spacing, shape):
    axes = [o + d * (np.arange(n) + 0.5) for o, d, n in zip(origin, spacing, shape)]
    return np.meshgrid(*axes, indexing="ij")


class Series:
    """An XDMF file opened with vtkXdmfReader: its time values and its dataset at a given time."""

    def __init__(self, path):
        self.reader = vtkXdmfReader()
        self.reader.SetFileName(str(path))
        self.reader.UpdateInformation()
        self.times = list(self.reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS()))

    def at(self, time):
        self.reader.UpdateTimeStep(time)
        out = self.reader.GetOutputDataObject(0)
        data = out.NewInstance()
        data.DeepCopy(out)
        return data


def vtk_cell_centres(data):
    centres = vtkCellCenters()
    centres.SetInputData(data)
    centres.Update()
    return vtk_to_numpy(centres.GetOutput().GetPoints().GetData())


def cell_array(data, name):
    return vtk_to_numpy(data.GetCellData().GetArray(name))


# ------------------------------------------------------------------------------------------------ grids
def write_series(tmp_path, origin, spacing, shape, fields_at, times, **kw):
    entries, kinds = [], None
    for n, t in enumerate(times):
        name = f"grid_{n:04d}.h5"
        kinds = write_grid_snapshot(tmp_path / name, t, origin, spacing, fields_at(t), **kw)
        entries.append((name, t))
    write_grid_series(tmp_path / "grid.xdmf", entries, shape, origin, spacing, kinds, **kw)
    return Series(tmp_path / "grid.xdmf")


def test_grid_3d_series(tmp_path):
    origin, spacing, shape = (0.5, -1.0, 2.0), (0.1, 0.2, 0.3), (5, 4, 3)
    x, y, z = cell_centres(origin, spacing, shape)
    tensor = np.zeros(shape + (3, 3))
    tensor[..., 0, 1], tensor[..., 1, 0], tensor[..., 2, 2] = x, y, z
    times = [0.0, 2.5e-4, 1.0e-3]
    series = write_series(tmp_path, origin, spacing, shape, lambda t: {
        "pressure": scalar_field(x, y, z, t), "velocity": vector_field(x, y, z), "stress": tensor}, times)
    assert series.times == times
    for t in times:
        grid = series.at(t)
        assert grid.GetNumberOfCells() == 60
        np.testing.assert_allclose(grid.GetBounds(), (0.5, 1.0, -1.0, -0.2, 2.0, 2.9), **TOL)
        c = vtk_cell_centres(grid)
        np.testing.assert_allclose(cell_array(grid, "pressure"), scalar_field(*c.T, t), **TOL)
        np.testing.assert_allclose(cell_array(grid, "velocity"), vector_field(*c.T), **TOL)
        stress = cell_array(grid, "stress")
        assert stress.shape == (60, 9)  # row-major xx xy xz yx yy yz zx zy zz
        np.testing.assert_allclose(stress[:, [1, 3, 8]], c, **TOL)
        assert np.all(stress[:, [0, 2, 4, 5, 6, 7]] == 0.0)


def test_grid_2d_series_with_padded_vectors(tmp_path):
    origin, spacing, shape = (-1.0, 2.0), 0.25, (6, 3)
    x, y = cell_centres(origin, (spacing, spacing), shape)
    times = [0.0, 1e-4]
    series = write_series(tmp_path, origin, spacing, shape, lambda t: {
        "pressure": scalar_field(x, y, 0.0, t), "velocity": vector_field(x, y, 0.0)[..., :2]}, times)
    assert series.times == times
    grid = series.at(times[1])
    assert grid.GetNumberOfCells() == 18
    # one cell thick in z, x shown as x
    np.testing.assert_allclose(grid.GetBounds(), (-1.0, 0.5, 2.0, 2.75, 0.0, 0.25), **TOL)
    c = vtk_cell_centres(grid)
    np.testing.assert_allclose(cell_array(grid, "pressure"), scalar_field(c[:, 0], c[:, 1], 0.0, times[1]), **TOL)
    velocity = cell_array(grid, "velocity")
    assert velocity.shape == (18, 3)
    np.testing.assert_allclose(velocity[:, :2], vector_field(c[:, 0], c[:, 1], 0.0)[:, :2], **TOL)
    assert np.all(velocity[:, 2] == 0.0)


def test_grid_1d_series(tmp_path):
    origin, spacing, shape = (3.0,), 0.5, (7,)
    (x,) = cell_centres(origin, (spacing,), shape)
    series = write_series(tmp_path, origin, spacing, shape, lambda t: {"pressure": scalar_field(x, 0, 0, t)}, [2.0])
    assert series.times == [2.0]
    grid = series.at(2.0)
    assert grid.GetNumberOfCells() == 7
    np.testing.assert_allclose(grid.GetBounds(), (3.0, 6.5, 0.0, 0.5, 0.0, 0.5), **TOL)
    c = vtk_cell_centres(grid)
    np.testing.assert_allclose(cell_array(grid, "pressure"), scalar_field(c[:, 0], 0, 0, 2.0), **TOL)


def test_grid_float32(tmp_path):
    origin, spacing, shape = (0.0, 0.0, 0.0), 0.1, (3, 4, 5)
    x, y, z = cell_centres(origin, (spacing,) * 3, shape)
    p = scalar_field(x, y, z, 0.0)
    series = write_series(tmp_path, origin, spacing, shape, lambda t: {"pressure": p}, [0.0], precision=4)
    grid = series.at(0.0)
    array = grid.GetCellData().GetArray("pressure")
    assert array.GetDataType() == VTK_FLOAT
    c = vtk_cell_centres(grid)
    # float32 storage: relative rounding 2**-24 of values ~ 10
    np.testing.assert_allclose(vtk_to_numpy(array), scalar_field(*c.T, 0.0), rtol=2 ** -23)


def test_grid_snapshot_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    fields = {"pressure": rng.random((4, 3)), "velocity": rng.random((4, 3, 2)), "stress": rng.random((4, 3, 2, 2))}
    kinds = write_grid_snapshot(tmp_path / "s.h5", 0.125, (1.0, 2.0), (0.5, 0.25), fields)
    assert kinds == {"pressure": "scalar", "velocity": "vector", "stress": "tensor"}
    snap = read_grid_snapshot(tmp_path / "s.h5")
    assert snap.time == 0.125
    np.testing.assert_array_equal(snap.origin, [1.0, 2.0])
    np.testing.assert_array_equal(snap.spacing, [0.5, 0.25])
    for name, array in fields.items():
        np.testing.assert_array_equal(snap.fields[name], array)


# -------------------------------------------------------------------------------------------- particles
def test_particle_series_2d_with_active_mask(tmp_path):
    rng = np.random.default_rng(1)
    capacity, times = 9, [0.0, 5e-5]
    active = [rng.random(capacity) < 0.6, np.ones(capacity, dtype=bool)]
    written, entries, kinds = [], [], None
    for n, (t, mask) in enumerate(zip(times, active)):
        xy = rng.uniform(-1.0, 1.0, (capacity, 2))
        s = rng.normal(size=(capacity, 2, 2))
        fields = {"mass": 1.0 + xy[:, 0] ** 2, "velocity": 3.0 * xy[:, ::-1], "stress": s + s.transpose(0, 2, 1)}
        kinds = write_particle_snapshot(tmp_path / f"p_{n}.h5", t, xy, fields, active=mask)
        entries.append((f"p_{n}.h5", t, int(mask.sum())))
        written.append((xy[mask], {k: v[mask] for k, v in fields.items()}))
    assert kinds == {"mass": "scalar", "velocity": "vector", "stress": "tensor"}
    write_particle_series(tmp_path / "particles.xdmf", entries, kinds)
    series = Series(tmp_path / "particles.xdmf")
    assert series.times == times
    for t, (xy, fields) in zip(times, written):
        cloud = series.at(t)
        assert cloud.GetNumberOfPoints() == len(xy)
        points = vtk_to_numpy(cloud.GetPoints().GetData())
        np.testing.assert_array_equal(points, np.pad(xy, ((0, 0), (0, 1))))
        np.testing.assert_array_equal(cloud.GetBounds(), [*sum(((lo, hi) for lo, hi in zip(xy.min(0), xy.max(0))),
                                                                  ()), 0.0, 0.0])
        data = cloud.GetPointData()
        assert data.GetArray("mass").GetDataType() == VTK_DOUBLE
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("mass")), fields["mass"])
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("velocity")),
                                      np.pad(fields["velocity"], ((0, 0), (0, 1))))
        stress = vtk_to_numpy(data.GetArray("stress")).reshape(-1, 3, 3)
        np.testing.assert_array_equal(stress[:, :2, :2], fields["stress"])
        assert np.all(stress[:, 2, :] == 0.0) and np.all(stress[:, :, 2] == 0.0)
    snap = read_particle_snapshot(tmp_path / "p_0.h5")
    np.testing.assert_array_equal(snap.positions, written[0][0])
    for name, array in written[0][1].items():
        np.testing.assert_array_equal(snap.fields[name], array)


def test_particles_3d_full_tensor(tmp_path):
    rng = np.random.default_rng(2)
    xyz = rng.uniform(0.0, 2.0, (5, 3))
    stress = rng.normal(size=(5, 3, 3))
    kinds = write_particle_snapshot(tmp_path / "p.h5", 1.5, xyz, {"stress": stress})
    write_particle_series(tmp_path / "p.xdmf", [("p.h5", 1.5, 5)], kinds)
    cloud = Series(tmp_path / "p.xdmf").at(1.5)
    np.testing.assert_array_equal(vtk_to_numpy(cloud.GetPoints().GetData()), xyz)
    np.testing.assert_array_equal(vtk_to_numpy(cloud.GetPointData().GetArray("stress")), stress.reshape(5, 9))


# ------------------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("call, message", [
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0.0, 0.0), 0.0, {"p": np.zeros((2, 2))}), "spacing"),
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0, 0, 0, 0), 1.0, {"p": np.zeros(2)}), "origin"),
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0.0, 0.0), 1.0, {"p": np.zeros((2, 2)), "q": np.zeros((2, 3))}),
     "'q'"),
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0.0, 0.0), 1.0, {"v": np.zeros((2, 2, 4))}), "'v'"),
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0.0,), 1.0, {"a/b": np.zeros(2)}), "field name"),
    (lambda d: write_grid_snapshot(d / "a.h5", np.nan, (0.0,), 1.0, {"p": np.zeros(2)}), "time"),
    (lambda d: write_grid_snapshot(d / "a.h5", 0.0, (0.0,), 1.0, {"p": np.zeros(2)}, precision=2), "precision"),
    (lambda d: write_grid_series(d / "a.xdmf", [("a.h5", 0.0)], (2, 2, 2), (0.0, 0.0), 1.0, {"p": "scalar"}),
     "shape"),
    (lambda d: write_grid_series(d / "a.xdmf", [("a.h5", 0.0)], (2,), (0.0,), 1.0, {"p": "matrix"}), "kind"),
    (lambda d: write_grid_series(d / "a.xdmf", [("a.h5", 1.0), ("b.h5", 1.0)], (2,), (0.0,), 1.0,
                                 {"p": "scalar"}), "strictly increasing"),
    (lambda d: write_grid_series(d / "a.xdmf", [(str(d / "a.h5"), 0.0)], (2,), (0.0,), 1.0, {"p": "scalar"}),
     "relative"),
    (lambda d: write_particle_snapshot(d / "a.h5", 0.0, np.zeros((3, 4)), {}), "positions"),
    (lambda d: write_particle_snapshot(d / "a.h5", 0.0, np.zeros((3, 2)), {}, active=np.zeros(3, bool)),
     "at least one"),
    (lambda d: write_particle_snapshot(d / "a.h5", 0.0, np.zeros((3, 2)), {}, active=np.ones(2, bool)), "active"),
    (lambda d: write_particle_snapshot(d / "a.h5", 0.0, np.zeros((3, 2)), {"coordinates": np.zeros(3)}),
     "field name"),
    (lambda d: write_particle_series(d / "a.xdmf", [("a.h5", 0.0, 0)], {}), "particle"),
    (lambda d: write_particle_snapshot(d / "a.h5", 0.0, np.zeros((3, 2)), {"connectivity": np.zeros(3)}),
     "field name"),
    (lambda d: write_grid_mesh(d / "m.h5", (2, 0), (0.0, 0.0), 1.0), "shape"),
    (lambda d: write_grid_mesh(d / "m.h5", (2, 2), (0.0,), 1.0), "shape"),
])
def test_bad_input_names_the_parameter(tmp_path, call, message):
    with pytest.raises(ValueError, match=message):
        call(tmp_path)


# --------------------------------------------------------------------------------------------- plotting
def test_field_image_orientation_and_planes():
    origin, spacing = (1.0, -2.0, 0.0), (0.5, 0.25, 0.1)
    x, y, z = cell_centres(origin, spacing, (4, 3, 6))
    image, extent, z_plane = field_image(origin, spacing, 2.0 * x + 3.0 * y + 5.0 * z)
    assert image.shape == (3, 4)  # rows = y, columns = x
    assert extent == (1.0, 3.0, -2.0, -1.25)
    assert z_plane == pytest.approx(0.3, rel=1e-15)
    # linear in z: the mean of the two layers around the mid-plane is the value on it, exactly
    np.testing.assert_allclose(image, (2.0 * x + 3.0 * y)[:, :, 0].T + 5.0 * 0.3, **TOL)
    odd, _, z_odd = field_image(origin, spacing, z[:, :, :5])
    assert z_odd == pytest.approx(0.25, rel=1e-15)
    np.testing.assert_allclose(odd, 0.25, **TOL)
    # a chosen plane: linear in z between the two layers around it, exactly; beyond the first/last layer's
    # centre, that layer (and its centre as the plane)
    at, _, z_at = field_image(origin, spacing, 5.0 * z, 0.17)
    assert z_at == pytest.approx(0.17, rel=1e-15)
    np.testing.assert_allclose(at, 5.0 * 0.17, **TOL)
    low, _, z_low = field_image(origin, spacing, 5.0 * z, 0.0)
    assert z_low == pytest.approx(0.05, rel=1e-15)
    np.testing.assert_allclose(low, 5.0 * 0.05, **TOL)
    high, _, z_high = field_image(origin, spacing, 5.0 * z, 0.6)
    assert z_high == pytest.approx(0.55, rel=1e-15)
    np.testing.assert_allclose(high, 5.0 * 0.55, **TOL)
    flat, extent2d, none = field_image((0.0, 0.0), 1.0, x[:, :, 0])
    assert none is None and extent2d == (0.0, 4.0, 0.0, 3.0)
    np.testing.assert_array_equal(flat[1], x[:, 0, 0])  # a row runs along x


@pytest.mark.parametrize("shape", [(40,), (30, 20), (12, 10, 8)])
def test_plot_pressure_field_writes_png(tmp_path, shape):
    origin = (0.0, 0.0, 0.0)[:len(shape)]
    centres = cell_centres(origin, (0.1,) * len(shape), shape)
    pressure = 1e5 * (1.0 + np.exp(-sum((c - 1.0) ** 2 for c in centres)))
    png = tmp_path / "p.png"
    plot_pressure_field(png, origin, 0.1, pressure, title="test")
    picture = mpimg.imread(png)
    assert picture.ndim == 3 and picture.shape[0] > 300 and picture.shape[1] > 400
    colours = np.unique(picture[..., :3].reshape(-1, 3), axis=0)
    assert len(colours) > (10 if len(shape) == 1 else 100)  # a curve / a colour map, not a blank canvas


# ------------------------------------------------------------------------------- grid + particles (coupled)
def coupled_member(origin, spacing, shape, t, count, rng, offset=0.0):
    """A Coupled snapshot: grid fields analytic in the cell centres (scalar, vector, tensor), and ``count``
    random particles in the grid's box with their own scalar, vector and tensor fields."""
    ndim = len(shape)
    centres = cell_centres(origin, spacing, shape)
    x, y, z = (*centres, *[0.0] * (3 - ndim))
    tensor = np.zeros(shape + (ndim, ndim))
    tensor[..., 0, 1], tensor[..., 1, 0] = x, y
    edges = tuple(o + d * np.arange(n + 1) for o, d, n in zip(origin, spacing, shape))
    grid = Grid(edges=edges, cell_fields={"pressure": scalar_field(x, y, z, t) + offset,
                                          "velocity": vector_field(x, y, z)[..., :ndim], "stress": tensor})
    lo, hi = np.array(origin), np.array(origin) + np.array(spacing) * np.array(shape)
    positions = rng.uniform(lo, hi, (count, ndim))
    s = rng.normal(size=(count, ndim, ndim))
    particles = Particles(positions=positions, point_fields={
        "pressure": rng.random(count) + offset, "velocity": rng.normal(size=(count, ndim)), "stress": s + s.mT})
    return Coupled(grid=grid, particles=particles)


def blocks(multiblock):
    """{name: dataset} of the blocks vtkXdmfReader makes of a spatial collection (it appends [k] to the names
    of later time steps)."""
    return {re.sub(r"\[\d+\]$", "", multiblock.GetMetaData(b).Get(vtkCompositeDataSet.NAME())): multiblock.GetBlock(b)
            for b in range(multiblock.GetNumberOfBlocks())}


def check_coupled_series(out, written, times, member, offset=0.0):
    """Read member ``member`` (made with ``offset``) back through results.read_snapshot (exact) and through
    vtkXdmfReader."""
    for index, snap in enumerate(written):
        back = results.read_snapshot(out, "coupled", index, member)
        assert isinstance(back, Coupled)
        assert len(back.grid.edges) == len(snap.grid.edges)
        for e_back, e in zip(back.grid.edges, snap.grid.edges):  # origin + spacing * i: a few ulp of |x| ~ 1
            np.testing.assert_allclose(e_back, e, **TOL)
        np.testing.assert_array_equal(back.particles.positions, snap.particles.positions)
        for part_back, part in ((back.grid.cell_fields, snap.grid.cell_fields),
                                (back.particles.point_fields, snap.particles.point_fields)):
            assert part_back.keys() == part.keys()
            for name, array in part.items():
                assert part_back[name].shape == array.shape, name
                np.testing.assert_array_equal(part_back[name], array)
    series = Series(out / "fields" / f"member{member}.xdmf")
    assert series.times == times
    for t, snap in zip(times, written):
        parts = blocks(series.at(t))
        assert sorted(parts) == ["grid", "particles"]
        grid, cloud = parts["grid"], parts["particles"]
        g, p = snap.grid, snap.particles
        ndim, shape = len(g.edges), [len(e) - 1 for e in g.edges]
        assert grid.GetNumberOfCells() == np.prod(shape)
        bounds = np.array([(e[0], e[-1]) for e in g.edges] + [(0.0, g.edges[0][1] - g.edges[0][0])] * (3 - ndim))
        np.testing.assert_allclose(grid.GetBounds(), bounds.ravel(), **TOL)
        c = vtk_cell_centres(grid)
        x, y, z = (*c[:, :ndim].T, *[0.0] * (3 - ndim))
        np.testing.assert_allclose(cell_array(grid, "pressure"), scalar_field(x, y, z, t) + offset, **TOL)
        velocity = cell_array(grid, "velocity")
        np.testing.assert_allclose(velocity[:, :ndim], vector_field(x, y, z)[..., :ndim], **TOL)
        assert np.all(velocity[:, ndim:] == 0.0)
        stress = cell_array(grid, "stress")
        assert stress.shape == (np.prod(shape), 9)
        np.testing.assert_allclose(stress[:, [1, 3]], c[:, :2], **TOL)
        assert np.all(stress[:, [0, 2, 4, 5, 6, 7, 8]] == 0.0)
        n = len(p.positions)
        assert cloud.GetNumberOfPoints() == n and cloud.GetNumberOfCells() == n
        np.testing.assert_array_equal(vtk_to_numpy(cloud.GetPoints().GetData()),
                                      np.pad(p.positions, ((0, 0), (0, 3 - ndim))))
        data = cloud.GetPointData()
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("pressure")), p.point_fields["pressure"])
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("velocity")),
                                      np.pad(p.point_fields["velocity"], ((0, 0), (0, 3 - ndim))))
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("stress")).reshape(n, 3, 3),
                                      np.pad(p.point_fields["stress"], ((0, 0), (0, 3 - ndim), (0, 3 - ndim))))


def test_coupled_2d_ensemble_series_varying_particle_count(tmp_path):
    rng = np.random.default_rng(3)
    origin, spacing, shape = (0.5, -1.0), (0.1, 0.2), (5, 3)
    times, counts = [0.0, 2.5e-4, 1.0e-3], [(4, 6), (7, 1), (2, 9)]  # particles of (member 0, member 1)
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    written = [[], []]
    for index, (t, per_member) in enumerate(zip(times, counts)):
        members = [coupled_member(origin, spacing, shape, t, n, rng, offset=10.0 * k)
                   for k, n in enumerate(per_member)]
        results.write_snapshot(out, index, t, members)
        for k, snap in enumerate(members):
            written[k].append(snap)
    for k in range(2):
        results.write_series(out, k, list(enumerate(times)), written[k][-1])
        check_coupled_series(out, written[k], times, k, offset=10.0 * k)
    # one HDF5 file per member and snapshot, one series per member, one meshio index per snapshot part, one
    # file of grid cells per member
    assert sorted(f.name for f in (out / "fields").iterdir()) == sorted(
        [f"member{k}_{i:04d}{part}" for k in range(2) for i in range(3)
         for part in (".h5", "_grid.xdmf", "_particles.xdmf")] + [f"member{k}{end}" for k in range(2)
                                                                 for end in (".xdmf", ".mesh.h5")])
    # the API's field dict: the grid's entries and the particles' prefixed particle_
    snap = results.read_snapshot(out, "coupled", 1, 1)
    f = snap.as_fields()
    assert f.keys() == {"x", "y", "pressure", "velocity", "stress", "particle_x", "particle_y",
                        "particle_pressure", "particle_velocity", "particle_stress"}
    assert f["x"].shape == shape and f["velocity"].shape == shape + (2,) and f["particle_x"].shape == (1,)
    np.testing.assert_array_equal(f["particle_y"], written[1][1].particles.positions[:, 1])
    np.testing.assert_array_equal(f["particle_stress"], written[1][1].particles.point_fields["stress"])
    np.testing.assert_array_equal(f["pressure"], written[1][1].grid.cell_fields["pressure"])


def test_coupled_3d_series(tmp_path):
    rng = np.random.default_rng(4)
    origin, spacing, shape = (0.0, 1.0, -0.5), (0.25, 0.5, 0.125), (4, 3, 2)
    times, counts = [1e-4, 3e-4], [5, 8]
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    written = [coupled_member(origin, spacing, shape, t, n, rng) for t, n in zip(times, counts)]
    for index, (t, snap) in enumerate(zip(times, written)):
        results.write_snapshot(out, index, t, [snap])
    results.write_series(out, 0, list(enumerate(times)), written[-1])
    check_coupled_series(out, written, times, 0)
    assert set(written[0].as_fields()) >= {"z", "particle_z"}


def test_coupled_snapshot_needs_particles_of_the_grid_dimension(tmp_path):
    with pytest.raises(ValueError, match="positions must have the grid's 2 coordinates"):
        write_coupled_snapshot(tmp_path / "a.h5", 0.0, (0.0, 0.0), 1.0, {"p": np.zeros((2, 2))}, np.zeros((3, 3)),
                               {})


@pytest.mark.parametrize("ndim", [1, 2, 3])
def test_plot_particle_damage_writes_png(tmp_path, ndim):
    rng = np.random.default_rng(0)
    positions = rng.uniform(0.0, 1.0, (2000, ndim))
    damage = positions[:, 0]  # a ramp: the picture must carry many colours (or a spread of points in 1D)
    png = tmp_path / "d.png"
    plot_particle_damage(png, positions, damage, cell_size=0.1, title="test", z_plane=0.5 if ndim == 3 else None)
    picture = mpimg.imread(png)
    assert picture.ndim == 3 and picture.shape[0] > 300 and picture.shape[1] > 400
    assert len(np.unique(picture[..., :3].reshape(-1, 3), axis=0)) > (10 if ndim == 1 else 100)
    with pytest.raises(ValueError, match="positions must be"):
        plot_particle_damage(png, positions, damage[:-1], cell_size=0.1)


def test_tracer_histories_plot(tmp_path):
    from blastfsi.plotting.histories import tracer_histories

    t = np.linspace(0.0, 1e-3, 101)
    hist = {"time": t, "tracer0_displacement_x": 0.0 * t, "tracer0_displacement_y": 0.02 * np.sin(3e3 * t)}
    png = tmp_path / "tracers.png"
    tracer_histories(png, [hist], [[0.0, 0.105]], ("x", "y"))
    picture = mpimg.imread(png)
    assert picture.ndim == 3 and picture.shape[0] > 300 and picture.shape[1] > 400
    with pytest.raises(KeyError, match="tracer1"):
        tracer_histories(png, [hist], [[0.0, 0.105], [0.1, 0.105]], ("x", "y"))


# ----------------------------------------------------------------------- meshio: every snapshot, every kind
def read_mesh(out, index, part=""):
    """meshio's reading of snapshot ``index`` of member 0 (its own XDMF index)."""
    return meshio.read(out / "fields" / f"member0_{index:04d}{'_' + part if part else ''}.xdmf")


def check_meshio_grid(mesh, grid: Grid, t):
    """Cells of the right type and number, each cell's fields = the analytic ones at its centroid (computed
    from meshio's points and connectivity, so a wrong node or cell order fails)."""
    ndim, shape = len(grid.edges), [len(e) - 1 for e in grid.edges]
    (block,) = mesh.cells
    assert block.type == ("line", "quad", "hexahedron")[ndim - 1] and block.data.shape == (np.prod(shape), 2 ** ndim)
    assert len(mesh.points) == np.prod([n + 1 for n in shape])
    corners = mesh.points[block.data]
    np.testing.assert_allclose(np.ptp(corners, axis=1)[:, :ndim], np.broadcast_to(
        [e[1] - e[0] for e in grid.edges], (len(corners), ndim)), **TOL)  # every cell one cell wide along each axis
    c = corners.mean(axis=1)
    x, y, z = (*c[:, :ndim].T, *[np.zeros(len(c))] * (3 - ndim))
    np.testing.assert_allclose(mesh.cell_data["pressure"][0], scalar_field(x, y, z, t), **TOL)
    velocity = mesh.cell_data["velocity"][0]
    assert velocity.shape == (len(c), 3)
    np.testing.assert_allclose(velocity[:, :ndim], vector_field(x, y, z)[:, :ndim], **TOL)


def grid_member(origin, spacing, shape, t):
    centres = cell_centres(origin, spacing, shape)
    x, y, z = (*centres, *[np.zeros(shape)] * (3 - len(shape)))
    edges = tuple(o + d * np.arange(n + 1) for o, d, n in zip(origin, spacing, shape))
    return Grid(edges=edges, cell_fields={"pressure": scalar_field(x, y, z, t),
                                          "velocity": vector_field(x, y, z)[..., :len(shape)]})


@pytest.mark.parametrize("origin, spacing, shape", [((3.0,), (0.5,), (7,)), ((-1.0, 2.0), (0.25, 0.125), (6, 3)),
                                                    ((0.5, -1.0, 2.0), (0.1, 0.2, 0.3), (5, 4, 3))])
def test_meshio_reads_grid_time_series(tmp_path, origin, spacing, shape):
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    times = [0.0, 2.5e-4, 1.0e-3]
    written = [grid_member(origin, spacing, shape, t) for t in times]
    for index, (t, grid) in enumerate(zip(times, written)):
        results.write_snapshot(out, index, t, [grid])
    results.write_series(out, 0, list(enumerate(times)), written[-1])
    assert Series(out / "fields" / "member0.xdmf").times == times  # the ParaView series is still whole
    for index, (t, grid) in enumerate(zip(times, written)):
        check_meshio_grid(read_mesh(out, index), grid, t)
        back = results.read_snapshot(out, "grid", index, 0)  # the flat storage reads back as written
        np.testing.assert_array_equal(back.cell_fields["pressure"], grid.cell_fields["pressure"])
    if len(shape) == 3:  # ParaView opens a snapshot's own index too (an unstructured grid of hexahedra)
        reader = vtkXdmfReader()
        reader.SetFileName(str(out / "fields" / "member0_0001.xdmf"))
        reader.Update()
        data = reader.GetOutputDataObject(0)
        c = vtk_cell_centres(data)
        np.testing.assert_allclose(cell_array(data, "pressure"), scalar_field(*c.T, times[1]), **TOL)


def test_meshio_reads_moving_particles(tmp_path):
    rng = np.random.default_rng(5)
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    times, counts = [0.0, 1e-4], [4, 9]  # the cloud moves and grows
    written = []
    for index, (t, n) in enumerate(zip(times, counts)):
        xy = rng.uniform(-1.0, 1.0, (n, 2))
        s = rng.normal(size=(n, 2, 2))
        snap = Particles(positions=xy, point_fields={"mass": 1.0 + xy[:, 0] ** 2, "velocity": 3.0 * xy[:, ::-1],
                                                     "stress": s})
        results.write_snapshot(out, index, t, [snap])
        written.append(snap)
    results.write_series(out, 0, list(enumerate(times)), written[-1])
    assert Series(out / "fields" / "member0.xdmf").times == times
    for index, snap in enumerate(written):
        mesh = read_mesh(out, index)
        n = len(snap.positions)
        assert mesh.cells[0].type == "vertex" and mesh.cells[0].data.ravel().tolist() == list(range(n))
        np.testing.assert_array_equal(mesh.points, np.pad(snap.positions, ((0, 0), (0, 1))))
        np.testing.assert_array_equal(mesh.point_data["mass"], snap.point_fields["mass"])
        np.testing.assert_array_equal(mesh.point_data["velocity"][:, :2], snap.point_fields["velocity"])
        stress = mesh.point_data["stress"].reshape(n, 3, 3)
        np.testing.assert_array_equal(stress[:, :2, :2], snap.point_fields["stress"])


def test_meshio_reads_coupled_grid_and_particles(tmp_path):
    rng = np.random.default_rng(6)
    origin, spacing, shape = (0.0, 1.0, -0.5), (0.25, 0.5, 0.125), (4, 3, 2)
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    times, counts = [1e-4, 3e-4], [5, 0]  # the second snapshot without particles
    written = [coupled_member(origin, spacing, shape, t, n, rng) for t, n in zip(times, counts)]
    for index, (t, snap) in enumerate(zip(times, written)):
        results.write_snapshot(out, index, t, [snap])
    results.write_series(out, 0, list(enumerate(times)), written[-1])
    mesh = read_mesh(out, 0, "grid")
    c = mesh.points[mesh.cells[0].data].mean(axis=1)
    np.testing.assert_allclose(mesh.cell_data["pressure"][0], scalar_field(*c.T, times[0]), **TOL)
    np.testing.assert_allclose(mesh.cell_data["stress"][0][:, [1, 3]], c[:, :2], **TOL)
    cloud = read_mesh(out, 0, "particles")
    np.testing.assert_array_equal(cloud.points, written[0].particles.positions)
    np.testing.assert_array_equal(cloud.point_data["pressure"], written[0].particles.point_fields["pressure"])
    check_meshio_grid(read_mesh(out, 1, "grid"), Grid(written[1].grid.edges, {
        "pressure": written[1].grid.cell_fields["pressure"], "velocity": written[1].grid.cell_fields["velocity"]}),
        times[1])
    assert not (out / "fields" / "member0_0001_particles.xdmf").exists()  # no particle: no particle index


def test_meshio_reads_moving_1d_mesh(tmp_path):
    out = results.prepare_directory(tmp_path / "out", overwrite=False)
    times = [0.0, 1e-3]
    written = []
    for index, t in enumerate(times):
        nodes = np.linspace(0.0, 1.0, 6) * (1.0 + 10.0 * t) ** np.linspace(1.0, 2.0, 6)  # the Lagrangian mesh moves
        snap = Polyline(nodes=nodes, node_fields={"velocity": 2.0 * nodes},
                        cell_fields={"pressure": 1e5 * (1.0 + np.diff(nodes))})
        results.write_snapshot(out, index, t, [snap])
        written.append(snap)
    results.write_series(out, 0, list(enumerate(times)), written[-1])
    for index, snap in enumerate(written):
        mesh = read_mesh(out, index)
        assert mesh.cells[0].type == "line" and len(mesh.cells[0].data) == 5
        np.testing.assert_array_equal(mesh.points[:, 0], snap.nodes)  # this snapshot's node positions
        np.testing.assert_array_equal(mesh.point_data["velocity"], snap.node_fields["velocity"])
        np.testing.assert_array_equal(mesh.cell_data["pressure"][0], snap.cell_fields["pressure"])
