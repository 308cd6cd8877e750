"""Command line: ``blastfsi run``, ``blastfsi examples``."""
from __future__ import annotations

import argparse
import json
import sys
import tomllib
from importlib import resources
from pathlib import Path

from blastfsi.io.results import OutputError
from blastfsi.scenario import ScenarioError, apply_overrides, read_toml

EXIT_SCENARIO, EXIT_SIMULATION, EXIT_OUTPUT = 2, 3, 4


def example_names() -> dict[str, str]:
    """Shipped example name -> its one-line description."""
    out = {}
    for f in sorted(resources.files("blastfsi.examples").iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            out[f.name[:-5]] = tomllib.loads(f.read_text()).get("description", "")
    return out


def example_data(name: str) -> dict:
    names = example_names()
    if name not in names:
        raise ScenarioError(f"unknown example {name!r}; available: {', '.join(names)}")
    return tomllib.loads(resources.files("blastfsi.examples").joinpath(f"{name}.toml").read_text())


def _default_out(name: str) -> Path:
    base = Path("results") / name
    out, k = base, 1
    while out.exists() and any(out.iterdir()):
        k += 1
        out = base.with_name(f"{base.name}-{k}")
    return out


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="blastfsi", description="Air-blast and blast-structure interaction solvers.")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scenario")
    src = r.add_mutually_exclusive_group(required=True)
    src.add_argument("scenario", nargs="?", help="scenario TOML file")
    src.add_argument("--example", metavar="NAME", help="run a shipped example (see `blastfsi examples`)")
    src.add_argument("--restart", metavar="DIR", help="continue the run in DIR from its latest checkpoint")
    r.add_argument("--out", metavar="DIR", help="results directory (default: results/<name>, never reused)")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value by its dotted key, e.g. --set grid.cells=2000")
    r.add_argument("--json", action="store_true", help="print the summary as one JSON object on stdout")
    r.add_argument("--overwrite", action="store_true", help="allow reusing a non-empty --out directory")
    sub.add_parser("examples", help="list the shipped examples")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "examples":
        for name, text in example_names().items():
            print(f"{name:24s} {text}")
        return 0
    try:
        return _run(args)
    except ScenarioError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_SCENARIO
    except OutputError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_OUTPUT


def _run(args) -> int:
    from blastfsi import simulation

    if args.restart:
        out = Path(args.restart)
        if args.overrides:
            raise ScenarioError("--restart continues a run as it was; --set is not allowed")
        if not (out / "scenario.toml").is_file():
            raise OutputError(f"--restart: {out} holds no scenario.toml")
        data = read_toml(out / "scenario.toml")
    else:
        if args.example:
            data = example_data(args.example)
        else:
            data = read_toml(args.scenario)
        data = apply_overrides(data, args.overrides)
        name = str(data.get("name", "run"))
        out = Path(args.out) if args.out else _default_out(name)
    progress = sys.stderr.isatty() and not args.json
    try:
        res = simulation.run(data, out, overwrite=args.overwrite, progress=progress, restart=bool(args.restart))
    except simulation.SimulationError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_SIMULATION
    summary = res.summary
    if args.json:
        print(json.dumps(summary))
    else:
        for key, value in summary.items():
            if key != "members":
                print(f"{key:32s} {value}")
    print(f"results written to {out}", file=sys.stderr)
    for warning in _warnings(summary):
        print(f"warning: {warning}", file=sys.stderr)
    return 0


def _warnings(summary: dict) -> list[str]:
    w = summary.get("warning")
    if w is None:
        return []
    return sorted({x for x in w if x}) if isinstance(w, list) else [w]


if __name__ == "__main__":
    sys.exit(main())
