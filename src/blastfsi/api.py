"""The Python API, the same engine as the command line::

    import blastfsi

    res = blastfsi.run("plate1d-uniform", set={"grid.cells": 2000})   # example name, TOML path or dict
    res.summary["plate_velocity"]          # what `blastfsi run --json` prints
    f = res.fields()                       # final state: f["x"], f["pressure"], f["velocity"][:, 0], ...
    res.history["plate_impulse"], res.gauges

With ``out=...`` the run writes a results directory (as the CLI does) and
``res.fields(time=t)`` reads the snapshot at time t back from it.
"""
from __future__ import annotations

import copy
import tomllib
from importlib import resources
from pathlib import Path

from blastfsi import simulation
from blastfsi.io.results import OutputError
from blastfsi.scenario import ScenarioError, read_toml, set_dotted
from blastfsi.simulation import Result

__all__ = ["Result", "example_data", "example_names", "load", "restart", "run"]


def example_names() -> dict[str, str]:
    """Shipped example name -> its one-line description."""
    out = {}
    for f in sorted(resources.files("blastfsi.examples").iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            out[f.name[:-5]] = tomllib.loads(f.read_text()).get("description", "")
    return out


def example_data(name: str) -> dict:
    """The raw scenario dict of a shipped example."""
    names = example_names()
    if name not in names:
        raise ScenarioError(f"unknown example {name!r}; available: {', '.join(names)}")
    return tomllib.loads(resources.files("blastfsi.examples").joinpath(f"{name}.toml").read_text())


def load(scenario: str | Path | dict, set: dict | None = None) -> dict:
    """The raw scenario dict of an example name, a TOML file (str or Path) or a
    dict, with the dotted-key overrides ``set`` ({"grid.cells": 2000}) applied.
    Validation happens when it is run (or with :func:`blastfsi.scenario.parse`)."""
    if isinstance(scenario, dict):
        data = copy.deepcopy(scenario)
    elif isinstance(scenario, Path) or (isinstance(scenario, str) and (
            scenario.endswith(".toml") or Path(scenario).is_file())):
        data = read_toml(scenario)
    elif isinstance(scenario, str):
        if scenario not in example_names():
            raise ScenarioError(f"{scenario!r} is neither a scenario file nor a shipped example; examples: "
                                f"{', '.join(example_names())}")
        data = example_data(scenario)
    else:
        raise ScenarioError(f"a scenario is an example name, a TOML path or a dict, not {type(scenario).__name__}")
    if set is not None:
        if not isinstance(set, dict):
            raise ScenarioError(f"set: expected a dict of dotted keys to values, got {type(set).__name__}")
        for key, value in set.items():
            data = set_dotted(data, key, value)
    return data


def run(scenario: str | Path | dict, *, set: dict | None = None, out: str | Path | None = None,
        progress: bool = False, overwrite: bool = False) -> Result:
    """Run a scenario (see :func:`load`). ``out``: results directory to write
    (None: nothing written); a non-empty one is refused unless ``overwrite`` and it
    is a results directory (the earlier run's outputs are then removed). Ctrl-C
    stops a run with ``out`` cleanly (:class:`blastfsi.simulation.RunInterrupted`)."""
    return simulation.run(load(scenario, set), None if out is None else Path(out), overwrite=overwrite,
                          progress=progress)


def restart(out: str | Path, *, progress: bool = False) -> Result:
    """Continue the run in results directory ``out`` from its latest readable checkpoint."""
    out = Path(out)
    if not (out / "scenario.toml").is_file():
        raise OutputError(f"restart: {out} holds no scenario.toml")
    return simulation.run(read_toml(out / "scenario.toml"), out, progress=progress, restart=True)
