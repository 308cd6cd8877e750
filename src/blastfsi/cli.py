"""Command line: ``blastfsi run``, ``blastfsi examples``, ``blastfsi kb``, ``blastfsi schema`` (a thin layer over
:mod:`blastfsi.api`).

``run`` says on stderr what it is doing (the stages before the first step, then the progress: a bar on a
terminal, plain lines in a log; ``--quiet``: nothing but errors and warnings) and prints the summary on
stdout as tables (:func:`blastfsi.report.summary_table`), or with ``--json`` as one JSON object and nothing
else. On several hosts (``--hosts``) every host runs the same command and the first reports and writes."""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from blastfsi import api, report, runtime, xla
from blastfsi.api import example_data, example_names
from blastfsi.io.results import OutputError
from blastfsi.scenario import ScenarioError, apply_overrides, parse, read_toml
from blastfsi.simulation import RunInterrupted, SimulationError

EXIT_SCENARIO, EXIT_SIMULATION, EXIT_OUTPUT, EXIT_INTERRUPTED = 2, 3, 4, 130


def _default_out(name: str) -> Path:
    base = Path("results") / name
    out, k = base, 1
    while out.exists() and (not out.is_dir() or any(out.iterdir())):
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
    r.add_argument("-q", "--quiet", action="store_true",
                   help="say nothing on stderr but errors and warnings (no stages, no progress)")
    r.add_argument("--overwrite", action="store_true",
                   help="replace the results of an earlier run in --out (a blastfsi results directory only)")
    hosts = r.add_argument_group("several hosts", "run this command in one process per host, each with the same "
                                 "arguments but --process-id; numerics.devices then counts the devices of all "
                                 "hosts, and the first process writes the results")
    hosts.add_argument("--hosts", action="store_true",
                       help="join the other hosts' processes (jax.distributed), as the cluster (SLURM, Open MPI) "
                            "says, or as the next three options say")
    hosts.add_argument("--coordinator", metavar="HOST:PORT", help="address of the first process (--process-id 0)")
    hosts.add_argument("--processes", type=int, metavar="N", help="number of processes")
    hosts.add_argument("--process-id", type=int, metavar="I", help="this process's number, 0 to N - 1")
    sub.add_parser("examples", help="list the shipped examples")
    kb = sub.add_parser("kb", help="Kingery-Bulmash blast parameters of a TNT charge")
    kb.add_argument("--mass", type=float, required=True, metavar="KG", help="TNT mass [kg]")
    kb.add_argument("--distance", type=float, required=True, metavar="M", help="distance from the charge [m]")
    kb.add_argument("--burst", choices=("free-air", "surface"), default="free-air",
                    help="spherical free-air burst or hemispherical surface burst")
    kb.add_argument("--json", action="store_true", help="print one JSON object (SI units)")
    sc = sub.add_parser("schema", help="print the JSON Schema of a scenario file (editor completion and validation)")
    sc.add_argument("method", nargs="?", metavar="METHOD",
                    help="the scenario method (lagrangian1d, euler, mpm, cfdmp); without it: any method")
    return p


def _kb(args) -> int:
    from blastfsi.exact.kingery_bulmash import kb_report

    try:
        report = kb_report(args.mass, args.distance, args.burst)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_SCENARIO
    if args.json:
        print(json.dumps(report))
        return 0
    units, outside = report.pop("units"), report.pop("out_of_range")
    for key, value in report.items():
        if key in outside:
            lo, hi = outside[key]
            print(f"{key:28s} n/a (Kingery-Bulmash fit valid for {lo:g} <= Z <= {hi:g} m/kg^(1/3))")
        else:
            print(f"{key:28s} {value:.6g} {units.get(key, '')}" if isinstance(value, float) else f"{key:28s} {value}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "examples":
        for name, text in example_names().items():
            print(f"{name:24s} {text}")
        return 0
    if args.command == "kb":
        return _kb(args)
    if args.command == "schema":
        return _schema(args)
    try:
        if _joins_hosts(args):
            runtime.join_hosts(args.coordinator, args.processes, args.process_id)
        return _run(args)
    except ScenarioError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_SCENARIO
    except OutputError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_OUTPUT


def _joins_hosts(args) -> bool:
    """Whether ``run`` joins other hosts' processes; ScenarioError naming the flags where the three explicit
    ones are not given together or the process number is out of range."""
    explicit = {"--coordinator": args.coordinator, "--processes": args.processes, "--process-id": args.process_id}
    given = [flag for flag, value in explicit.items() if value is not None]
    if given and len(given) < 3:
        missing = [flag for flag in explicit if flag not in given]
        raise ScenarioError(f"{', '.join(given)} given without {', '.join(missing)}: the three go together (or "
                            "none of them, with --hosts alone under SLURM or Open MPI)")
    if given and not (args.processes >= 1 and 0 <= args.process_id < args.processes):
        raise ScenarioError(f"--process-id {args.process_id} with --processes {args.processes}: expected "
                            f"--processes >= 1 and 0 <= --process-id <= {args.processes - 1}")
    return args.hosts or bool(given)


def _run(args) -> int:
    progress = not args.quiet
    try:
        if args.restart:
            if args.overrides:
                raise ScenarioError("--restart continues a run as it was; --set is not allowed")
            out = Path(args.restart)
            res = api.restart(out, progress=progress)
        else:
            data = example_data(args.example) if args.example else read_toml(args.scenario)
            data = apply_overrides(data, args.overrides)
            out = Path(args.out) if args.out else _default_out(parse(data).name)
            res = api.run(data, out=out, overwrite=args.overwrite, progress=progress)
    except SimulationError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_SIMULATION
    except RunInterrupted as stop:
        print(f"{stop}; continue with: blastfsi run --restart {shlex.quote(str(out))}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except KeyboardInterrupt:  # before the time loop, or a second Ctrl-C
        print("interrupted at once: nothing more written", file=sys.stderr)
        return EXIT_INTERRUPTED
    if not xla.writes_results():  # (another host's process: the first one reports)
        return 0
    summary = res.summary
    print(json.dumps(summary) if args.json else report.summary_table(summary))
    print(f"results written to {out}", file=sys.stderr)
    for warning in _warnings(summary):
        print(f"warning: {warning}", file=sys.stderr)
    return 0


def _schema(args) -> int:
    from blastfsi.schema import scenario_schema

    try:
        schema = scenario_schema(args.method)
    except KeyError as err:
        print(f"error: {err.args[0]}", file=sys.stderr)
        return EXIT_SCENARIO
    print(json.dumps(schema, indent=2))
    return 0


def _warnings(summary: dict) -> list[str]:
    w = summary.get("warning")
    if w is None:
        return []
    return sorted({x for x in w if x}) if isinstance(w, list) else [w]


if __name__ == "__main__":
    sys.exit(main())
