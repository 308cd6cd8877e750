"""Pictures of the examples gallery from short runs of the cheap examples (each well under a minute on a 2-core
CPU): runs each example without field snapshots, copies one of its plots to docs/figures/examples/<name>.png and
records what was run in docs/figures/examples/pictures.json. The coupled and 3D examples, which take minutes,
are shown by the figures of the validation and verification pages instead (``reference.FIGURES``).

    python scripts/docs/example_pictures.py [NAME ...]
"""
from __future__ import annotations

import json
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

import jax

import blastfsi

OUT = Path(__file__).resolve().parents[2] / "docs" / "figures" / "examples"
NO_FIELDS = {"output.fields": 0}

# example -> (the plot shown, overrides of the run)
PICTURES = {
    "sod": ("pressure.png", {}),
    "shock-tube": ("pressure.png", {}),
    "interface-advection": ("pressure.png", {}),
    "sedov-spherical": ("pressure.png", {}),
    "sedov-2d": ("pressure.png", {}),
    "sedov-axisym": ("pressure.png", {}),
    "tnt-free-air": ("gauges.png", {}),
    "elastic-wave-1d": ("tracers.png", {}),
    "vibrating-bar": ("tracers.png", {}),
    "mpm-sod": ("particles.png", {}),
    "concrete-spall": ("damage.png", {}),
    "soil-column": ("particles.png", {}),
    "taylor-bar": ("particles.png", {}),
    "cfdmp-shock-tube": ("gauges.png", {}),
    # coarse: 4 cm cells instead of 2 cm (the shipped runs take 2-3 min)
    "tnt-free-air-axisym": ("pressure.png", {"grid.cells": 150}),
    "tnt-surface-burst": ("pressure.png", {"grid.cells": 150}),
    "tnt-height-of-burst": ("pressure.png", {"grid.cells": 125}),
}


def picture(name: str) -> dict:
    """Run one example into a temporary directory and copy its plot; what was run and how long it took."""
    plot, overrides = PICTURES[name]
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        blastfsi.run(name, set={**NO_FIELDS, **overrides}, out=Path(tmp) / name)
        wall = time.perf_counter() - start
        OUT.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(Path(tmp) / name / "plots" / plot, OUT / f"{name}.png")
    return {"plot": plot, "set": {**NO_FIELDS, **overrides}, "wall_s": round(wall, 1)}


def main(names: list[str]) -> None:
    record_path = OUT / "pictures.json"
    record = json.loads(record_path.read_text()) if record_path.is_file() else {}
    record["machine"] = f"{platform.machine()} {platform.system()}, {os.cpu_count()} cores, jax {jax.__version__}"
    runs = record.setdefault("runs", {})
    for name in names or list(PICTURES):
        runs[name] = picture(name)
        print(name, runs[name], flush=True)
        record_path.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
