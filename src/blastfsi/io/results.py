"""Everything the driver writes into a results directory.

Layout::

    scenario.toml              the resolved scenario (defaults filled in)
    summary.json               the run's summary quantities
    history.csv                (history_member<k>.csv for ensembles) SI units in the header
    fields/snap_<i>.h5         node/zone fields per snapshot, one group per member
    fields/member<k>.xdmf      ParaView time series over the snapshots
    checkpoints/ckpt_<i>.h5    full solver state, for --restart
    plots/*.png
"""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import h5py
import numpy as np
import tomli_w


class OutputError(RuntimeError):
    pass


def prepare_directory(path: Path, overwrite: bool) -> Path:
    """Create a fresh results directory; never reuse a non-empty one silently."""
    if path.exists() and any(path.iterdir()):
        if not overwrite:
            raise OutputError(f"results directory {path} exists and is not empty; choose another --out, "
                              "pass --overwrite, or continue it with --restart")
        for sub in ("fields", "checkpoints", "plots"):
            for f in (path / sub).glob("*"):
                f.unlink()
    for sub in ("fields", "checkpoints", "plots"):
        (path / sub).mkdir(parents=True, exist_ok=True)
    return path


def write_scenario(path: Path, scenario) -> None:
    (path / "scenario.toml").write_text(tomli_w.dumps(scenario.model_dump(exclude_none=True)))


def write_summary(path: Path, summary: dict) -> None:
    (path / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


def write_history(file: Path, columns, rows: np.ndarray) -> None:
    with open(file, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([f"{name} [{unit}]" for name, unit in columns])
        for r in rows:
            w.writerow([repr(float(v)) for v in r])


def read_history(file: Path) -> dict:
    with open(file) as fh:
        rows = list(csv.reader(fh))
    names = [re.sub(r"\s*\[.*\]$", "", h) for h in rows[0]]
    data = np.array(rows[1:], dtype=float).reshape(-1, len(names))
    return {n: data[:, i] for i, n in enumerate(names)}


def snapshot_name(index: int) -> str:
    return f"snap_{index:04d}.h5"


def write_snapshot(path: Path, index: int, time: float, members: list[dict]) -> None:
    """One HDF5 file per snapshot: /member<k>/{coordinates, node/*, zone/*}, attribute time."""
    with h5py.File(path / "fields" / snapshot_name(index), "w") as f:
        f.attrs["time"] = time
        for k, fields in enumerate(members):
            grp = f.create_group(f"member{k}")
            x = fields["x"]
            grp.create_dataset("coordinates", data=np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1))
            grp.create_dataset("connectivity", data=np.stack([np.arange(x.size - 1), np.arange(1, x.size)], axis=1))
            for name, arr in fields.items():
                if name != "x":
                    grp.create_dataset(name, data=arr)


def write_xdmf(path: Path, member: int, snapshots: list[tuple[int, float]], node_fields, zone_fields, n_nodes) -> None:
    """XDMF 3 temporal collection so ParaView opens the snapshots as a time series."""
    n_zones = n_nodes - 1
    grids = []
    for index, time in snapshots:
        h5 = f"{snapshot_name(index)}:/member{member}"
        attrs = "".join(
            f'<Attribute Name="{name}" Center="{center}"><DataItem Dimensions="{n}" NumberType="Float" '
            f'Precision="8" Format="HDF">{h5}/{name}</DataItem></Attribute>'
            for names, center, n in ((node_fields, "Node", n_nodes), (zone_fields, "Cell", n_zones))
            for name in names)
        grids.append(
            f'<Grid Name="t{index}" GridType="Uniform"><Time Value="{float(time)!r}"/>'
            f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{n_zones}">'
            f'<DataItem Dimensions="{n_zones} 2" NumberType="Int" Precision="8" Format="HDF">{h5}/connectivity'
            f'</DataItem></Topology><Geometry GeometryType="XYZ"><DataItem Dimensions="{n_nodes} 3" '
            f'NumberType="Float" Precision="8" Format="HDF">{h5}/coordinates</DataItem></Geometry>{attrs}</Grid>')
    text = ('<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain><Grid Name="fields" GridType="Collection" '
            f'CollectionType="Temporal">{"".join(grids)}</Grid></Domain></Xdmf>\n')
    (path / "fields" / f"member{member}.xdmf").write_text(text)


def list_snapshots(path: Path) -> list[tuple[int, float]]:
    out = []
    for f in sorted((path / "fields").glob("snap_*.h5")):
        with h5py.File(f, "r") as h:
            out.append((int(f.stem.split("_")[1]), float(h.attrs["time"])))
    return out


def write_checkpoint(path: Path, index: int, leaves: dict, meta: dict) -> Path:
    """Write atomically (temporary file, then rename) so a crash never leaves a half checkpoint."""
    file = path / "checkpoints" / f"ckpt_{index:04d}.h5"
    tmp = file.with_suffix(".tmp")
    with h5py.File(tmp, "w") as f:
        for k, v in meta.items():
            f.attrs[k] = v
        for name, arr in leaves.items():
            f.create_dataset(name, data=np.asarray(arr))
    tmp.replace(file)
    return file


def latest_checkpoint(path: Path) -> Path | None:
    files = sorted((path / "checkpoints").glob("ckpt_*.h5"))
    return files[-1] if files else None


def read_checkpoint(file: Path) -> tuple[dict, dict]:
    with h5py.File(file, "r") as f:
        return {k: f[k][()] for k in f.keys()}, dict(f.attrs)
