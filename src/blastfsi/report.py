"""What the terminal shows of a run: the stage lines, the progress line and the end-of-run summary table.

Pure functions of numbers and of a summary dict (the content of ``summary.json``, of which the table is
only a view); the driver (:mod:`blastfsi.simulation`) and the command line (:mod:`blastfsi.cli`) print
what they return. Quantities are shown with 4 significant digits in a unit that suits their size
(:func:`quantity`): pressures in Pa to GPa, times in ns to s, lengths in µm to m, impulses per area in
Pa·ms to MPa·ms (1 kPa·ms = 1 Pa·s). A summary key's unit is inferred from its name (:data:`UNIT_RULES`);
masses, energies, momenta and volumes are shown as plain numbers, since their unit depends on the
geometry (per metre in plane 2D, per area in 1D).
"""
from __future__ import annotations

import math
import re

# A unit family: (name, factor in the SI unit), largest first; a value is shown in the first whose factor
# does not exceed its magnitude (the last for smaller values).
SCALES = {
    "s": (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)),
    "Pa": (("GPa", 1e9), ("MPa", 1e6), ("kPa", 1e3), ("Pa", 1.0)),
    "Pa s": (("MPa·ms", 1e3), ("kPa·ms", 1.0), ("Pa·ms", 1e-3)),
    "length": (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6)),
}
DIGITS = 4  # significant digits of a quantity


def _words(*words: str) -> str:
    """A pattern of a dotted key path holding one of ``words`` as a whole word (between '_' or '.')."""
    return rf"(.*[._])?({'|'.join(words)})([._].*)?"


# (pattern, unit) of a summary key's dotted path (re.fullmatch, first match wins): "wall" a wall-clock
# duration, "%" a relative quantity (shown x 100), "" a plain number, else a family of SCALES or a unit.
UNIT_RULES = (
    (_words("wall_time", "compile_time", "loop_time", "output_time"), "wall"),
    (_words("reaction"), ""),  # a force's impulse [N s] and work, per metre or per area by geometry
    (_words("scaled_distance"), "m/kg^1/3"),
    (r".*_relative", "%"),
    (r".*_deg", "°"),
    (_words("areal_mass"), "kg/m²"),
    (_words("ratio", "coefficient", "fraction", "beta_s", "f_R"), ""),
    (_words("energy", "mass", "work", "momentum", "volume", "strain", "damage", "particles", "capacity", "cells",
            "steps", "zones", "growths"), ""),
    (_words("position", "center", "extent"), "m"),
    (_words("pressure", "overpressure"), "Pa"),
    (_words("impulse"), "Pa s"),
    (_words("time", "duration"), "s"),
    (_words("velocity", "wave_speed"), "m/s"),
    (_words("displacement", "distance", "radius", "length", "diameter", "dx", "cell_size", "zone_width", "air_zone",
            "thickness", "height"), "length"),
)
PROSE = 60  # strings longer than this are explanations: left to summary.json
RUN_KEYS = ("method", "status", "error", "time", "steps", "cells", "wall_time", "compile_time", "loop_time",
            "output_time", "pool_growths", "pool_shrinks")
NOT_SHOWN = ("warning",)  # printed by the command line on stderr


def unit_of(path: str) -> str:
    """The unit of the summary key ``path`` (dotted, e.g. "gauges.kb.peak_overpressure"), by UNIT_RULES."""
    return next((unit for pattern, unit in UNIT_RULES if re.fullmatch(pattern, path)), "")


def number(value: float) -> str:
    """A float with DIGITS significant digits (an integer-valued one without a decimal point)."""
    return f"{value:.{DIGITS}g}"


def quantity(value, unit: str = "") -> str:
    """``value`` (SI) as text in ``unit``: a family of SCALES scaled to its size, "%" as a percentage,
    "wall" as a :func:`duration`; None as "-", lists element by element."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)):
        if value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value) \
                and unit not in ("", "wall", "%"):  # a vector: one unit for its components
            name, factor = _scale(max(abs(v) for v in value), unit) if unit in SCALES else (unit, 1.0)
            return f"({', '.join(number(v / factor) for v in value)}) {name}"
        return "(" + ", ".join(quantity(v, unit) for v in value) + ")"
    if isinstance(value, int):
        return str(value)
    if not math.isfinite(value):
        return str(value)
    if unit == "wall":
        return duration(value)
    if unit == "%":
        return f"{number(100.0 * value)} %"
    if unit in SCALES:
        name, factor = _scale(abs(value), unit)
        return f"{number(value / factor)} {name}"
    return f"{number(value)} {unit}".rstrip()


def _scale(magnitude: float, unit: str) -> tuple[str, float]:
    """The (name, factor) of family ``unit`` for a magnitude: the base unit for 0."""
    family = SCALES[unit]
    if magnitude == 0.0:
        return next((n, f) for n, f in family if f == 1.0)
    return next(((n, f) for n, f in family if magnitude >= f * (1.0 - 1e-12)), family[-1])


def duration(seconds: float | None) -> str:
    """Wall-clock seconds as text: "0.42 s", "12.3 s", "4 min 05 s", "2 h 03 min"; None as "-"."""
    if seconds is None or not math.isfinite(seconds):
        return "-"
    if seconds < 10.0:
        return f"{seconds:.2f} s"
    if seconds < 60.0:
        return f"{seconds:.1f} s"
    s = int(round(seconds))
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {(s % 3600) // 60:02d} min"


def stage_line(elapsed: float, message: str) -> str:
    """A line saying what a run is doing, after the wall-clock seconds since it started."""
    return f"[{duration(elapsed):>10}] {message}"


# ------------------------------------------------------------------------------------------- progress
SMOOTHING = 20.0  # wall-clock seconds over which the rates behind the ETA are averaged (exponentially)


def decayed(total: float, amount: float, wall_seconds: float, tau: float = SMOOTHING) -> float:
    """A running total that forgets exponentially in wall-clock time: ``total`` decayed by
    exp(-wall_seconds / tau), plus ``amount``. The ratio of two such totals (simulated time, steps over
    wall-clock time) is a rate averaged over about the last ``tau`` seconds, each call weighted by its
    duration."""
    return total * math.exp(-max(wall_seconds, 0.0) / tau) + amount


def remaining(t: float, end: float, rate: float | None) -> float | None:
    """Wall-clock seconds left at the simulated-time ``rate`` [simulated s per wall s]; None if unknown."""
    if rate is None or not rate > 0.0:
        return None
    return max(end - t, 0.0) / rate


def shown_step(previous: float | None, advanced: float, steps: int) -> float | None:
    """The time step to show after a chunk of ``steps`` steps that advanced ``advanced`` seconds: their
    mean, the stable step (the time loop splits the time to an output into equal steps of at least about
    half the stable one); a chunk of one step, which may be a step that only lands on an output time, keeps
    the ``previous`` value."""
    if steps >= 2 or (steps == 1 and previous is None):
        return advanced / steps
    return previous


def progress_parts(t: float, end: float, step: int, dt: float | None, steps_per_second: float | None,
                   eta: float | None) -> tuple[str, str]:
    """(head, tail) of the progress line: the simulated time, and step, dt, steps/s and ETA."""
    head = f"t = {quantity(t, 's')} of {quantity(end, 's')}"
    rate = "-" if steps_per_second is None else number(steps_per_second)
    tail = f"step {step}  dt = {quantity(dt, 's')}  {rate} steps/s  ETA {duration(eta)}"
    return head, tail


def progress_line(t: float, end: float, step: int, dt: float | None, steps_per_second: float | None,
                  eta: float | None) -> str:
    """The progress as one plain line (a log without a terminal)."""
    head, tail = progress_parts(t, end, step, dt, steps_per_second, eta)
    return f"{head} ({100.0 * t / end:.0f} %)  {tail}"


PLAIN_EVERY = 60.0  # wall-clock seconds between plain progress lines at most ...
PLAIN_TENTHS = 10  # ... and one at each tenth of the simulated time


def plain_due(fraction: float, last_fraction: float, since_last: float) -> bool:
    """Whether a plain progress line is due, the last one (or the start) at ``last_fraction`` of the run
    ``since_last`` seconds ago: a new tenth of the run reached, or PLAIN_EVERY seconds gone by."""
    if since_last >= PLAIN_EVERY:
        return True
    return math.floor(fraction * PLAIN_TENTHS + 1e-9) > math.floor(last_fraction * PLAIN_TENTHS + 1e-9)


# ------------------------------------------------------------------------------------ the summary table
def summary_table(summary: dict) -> str:
    """The summary as text tables: the run (status, time, steps, timings), the results, the gauges and a
    section per nested table (budget, structures, ...); an ensemble (a ``members`` key, each other key
    a list over the members) member by member."""
    if "members" not in summary:
        return "\n".join(_member_lines(summary))
    lines = []
    for k, overrides in enumerate(summary["members"]):
        one = {key: values[k] for key, values in summary.items() if key != "members"}
        said = ", ".join(f"{key} = {quantity(v, unit_of(key.split('.')[-1]))}" for key, v in overrides.items())
        lines += [f"member {k}" + (f": {said}" if said else ""), *("  " + line for line in _member_lines(one)), ""]
    return "\n".join(lines[:-1])


def _member_lines(summary: dict) -> list[str]:
    lines = ["run", *_pairs(_run_rows(summary))]
    scalars, tables, records = [], [], []
    for key, value in summary.items():
        if key in RUN_KEYS or key in NOT_SHOWN or _prose(value):
            continue
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            records.append((key, value))
        else:
            scalars.append((key, quantity(value, unit_of(key))))
    if scalars:
        lines += ["results", *_pairs(scalars)]
    for key, value in records:
        lines += [key, *_grid(*(_gauge_columns(value) if key == "gauges" else _record_columns(value)))]
    for key, value in tables:
        rows = [(path, quantity(v, unit_of(f"{key}.{path}"))) for path, v in _leaves(value)]
        if rows:
            lines += [key, *_pairs(rows)]
    return lines


def _run_rows(s: dict) -> list[tuple[str, str]]:
    rows = [(k, str(s[k])) for k in ("method", "status", "error") if s.get(k) is not None]
    if "time" in s:
        rows.append(("simulated time", quantity(s["time"], "s")))
    rows += [(k, str(s[k])) for k in ("steps", "cells", "pool_growths", "pool_shrinks") if k in s]
    if "wall_time" in s:
        parts = [f"{k.split('_')[0]} {duration(s[k])}" for k in ("loop_time", "output_time") if k in s]
        rows.append(("wall time", duration(s["wall_time"]) + (f" ({', '.join(parts)})" if parts else "")))
    if "compile_time" in s:
        rows.append(("compile time", duration(s["compile_time"])))
    return rows


def _prose(value) -> bool:
    return isinstance(value, str) and len(value) > PROSE


def _leaves(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    """(dotted path, value) of the non-table entries of a nested table, prose left out."""
    out = []
    for key, value in table.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            out += _leaves(value, path + ".")
        elif not _prose(value):
            out.append((path, value))
    return out


def _pairs(rows: list[tuple[str, str]]) -> list[str]:
    width = max(len(k) for k, _ in rows)
    return [f"  {k:<{width}}  {v}" for k, v in rows]


def _grid(headers: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
    return ["  " + "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip() for cells in [headers, *rows]]


def _record_columns(records: list[dict], prefix: str = "") -> tuple[list[str], list[list[str]]]:
    """(headers, rows) of a list of tables: one column per dotted path found in any of them."""
    paths = list(dict.fromkeys(p for r in records for p, _ in _leaves(r)))
    rows = []
    for r in records:
        values = dict(_leaves(r))
        rows.append([quantity(values.get(p), unit_of(f"{prefix}{p}")) for p in paths])
    return ["#", *paths], [[str(k), *row] for k, row in enumerate(rows)]


# the gauge table: (header, dotted path in a gauge's table, unit path); KB = Kingery-Bulmash
GAUGE_COLUMNS = (
    ("position", "position", "position"),
    ("region", "region", "region"),
    ("Z [m/kg^1/3]", "scaled_distance", ""),
    ("peak overpressure", "peak_overpressure", "peak_overpressure"),
    ("impulse", "impulse", "impulse"),
    ("arrival", "arrival_time", "arrival_time"),
    ("duration", "positive_phase_duration", "positive_phase_duration"),
    ("peak/KB", "ratio.peak_overpressure", ""),
    ("impulse/KB", "ratio.impulse", ""),
    ("KB reference", "kb.reference", ""),
)


def _gauge_columns(gauges: list[dict]) -> tuple[list[str], list[list[str]]]:
    """(headers, rows) of the gauges: the columns of GAUGE_COLUMNS that any gauge has (the Kingery-Bulmash
    ones only where a reference is given), and ``distance`` where the position is a point in 2D or 3D."""
    flat = [dict(_leaves(g)) for g in gauges]
    columns = [c for c in GAUGE_COLUMNS if any(f.get(c[1]) is not None for f in flat)]
    points = [f.get("position") for f in flat]
    if any(isinstance(p, list) and len(p) > 1 for p in points) and any("distance" in f for f in flat):
        columns.insert(1, ("distance", "distance", "distance"))
    rows = [[str(k), *(quantity(f.get(path), unit_of(unit)) for _, path, unit in columns)]
            for k, f in enumerate(flat)]
    return ["#", *(c[0] for c in columns)], rows
