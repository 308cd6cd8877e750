"""The JAX settings of a run: its precision, and the persistent compilation cache.

Both are chosen by the run, not by importing the package, so a user's own JAX code
in the same process keeps its settings.

* :func:`precision`: ``numerics.precision`` of the scenario, set for the run's
  duration (JAX's ``jax_enable_x64``, as a context: restored after the run).
* :func:`compilation_cache`: JAX's persistent compilation cache, so that a
  repeated run loads its compiled time loop (and the small functions of its
  set-up and output) instead of compiling them again. It lives in
  :func:`cache_directory` and is safe to delete (it is only a cache).
* :func:`lowered`: a run's time loop traced and lowered once, kept beside that
  cache, so that a repeated run skips also the tracing.
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import os
import pickle
import platform
import re
import sys
from pathlib import Path

import jax
import jaxlib.version
from jax import export

from blastfsi import xla

CACHE_DIR_ENV = "BLASTFSI_CACHE_DIR"  # a directory for the cache; empty: no cache
NO_CACHE_ENV = "BLASTFSI_NO_CACHE"  # "1": no cache
MIN_JAXLIB = (0, 10)  # older jaxlibs crash loading large cached CPU executables (Linux and macOS; reported with
#   jaxlib 0.9.2 in github.com/uwplasma/vmex pull requests 142 and 347): no cache there
_claimed: list[str] = []  # the directory this module gave JAX's cache (JAX takes one per process, at its first use)
_active: list[bool] = []  # one entry per run (nested: a charge's 1D detonation) inside compilation_cache()


def precision(name: str):
    """Context of a run computing in ``name`` ("float64" or "float32", ``numerics.precision``): JAX's
    64-bit types on for float64 and off for float32 (so that also the indices are 32-bit), the caller's
    setting restored on leaving. Everything that traces or runs the run's kernels runs inside it:
    JAX keys its compiled code on the setting, so code compiled outside is not reused inside."""
    if name not in ("float64", "float32"):
        raise ValueError(f"numerics.precision: expected 'float64' or 'float32', got {name!r}")
    return jax.enable_x64(name == "float64")


def cache_directory() -> Path | None:
    """Where the compiled time loops are kept: ``$BLASTFSI_CACHE_DIR`` if set (an empty value: nowhere),
    nowhere with ``BLASTFSI_NO_CACHE=1``, else ``blastfsi/jax`` in the user's cache directory
    (``$XDG_CACHE_HOME`` or ``~/.cache`` on Linux, ``~/Library/Caches`` on macOS,
    ``%LOCALAPPDATA%`` on Windows), in a folder of this jaxlib and CPU (:func:`machine_key`)."""
    if os.environ.get(NO_CACHE_ENV, "") not in ("", "0"):
        return None
    if CACHE_DIR_ENV in os.environ:
        value = os.environ[CACHE_DIR_ENV]
        return Path(value).expanduser() if value else None
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "blastfsi" / "jax" / machine_key()


def machine_key() -> str:
    """The jaxlib and the CPU that compiled code is for: XLA:CPU compiles for the host's instruction set
    and JAX's cache key names neither it nor a jaxlib reinstalled in place, so a cache directory shared by
    machines of different CPUs (a network home) or jaxlib builds keeps their code apart."""
    cpuinfo = Path("/proc/cpuinfo")
    lines = cpuinfo.read_text().splitlines() if cpuinfo.is_file() else []
    flags = next((ln for ln in lines if ln.startswith(("flags", "Features"))), "")  # (x86, arm Linux)
    cpu = hashlib.sha256(f"{platform.processor()} {flags}".encode()).hexdigest()[:12]
    return f"jaxlib-{jaxlib.version.__version__}-{platform.machine()}-{cpu}"


@contextlib.contextmanager
def compilation_cache():
    """Context of a run: JAX's persistent compilation cache in :func:`cache_directory`, storing every
    compilation of the run (its time loop, and the ~50-200 small functions of its set-up and output: a
    repeated 1D plate run took 6.8 s instead of 8.5 s with them stored), and nothing outside runs (the
    caller's own JAX code is not stored there). JAX's key covers the program, the jax and XLA versions, the
    device and the compile options: a changed kernel or scenario shape compiles afresh.

    Not used where the process chose a cache directory of its own (``jax_compilation_cache_dir``, e.g.
    from ``JAX_COMPILATION_CACHE_DIR``: its settings apply unchanged), where it is switched off
    (:func:`cache_directory` None) or with a jaxlib older than MIN_JAXLIB."""
    if not _claim():
        yield
        return
    before = jax.config.jax_persistent_cache_min_compile_time_secs
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    _active.append(True)
    try:
        yield
    finally:
        _active.pop()
        jax.config.update("jax_persistent_cache_min_compile_time_secs", before)  # (a nested run's: its outer's)


def _claim() -> bool:
    """Whether JAX's cache directory is :func:`cache_directory`, set here where the process has none (and
    then nothing stored outside runs). JAX reads the directory once, at its first cached compilation. Not
    on several hosts (:func:`join_hosts`): their processes would share one cache directory's files."""
    if xla.processes() > 1:
        return False
    current = jax.config.jax_compilation_cache_dir
    if current is not None:
        return current in _claimed and cache_directory() is not None
    directory = cache_directory()
    if directory is None or _version(jaxlib.version.__version__) < MIN_JAXLIB:
        return False
    jax.config.update("jax_compilation_cache_dir", str(directory))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", float("inf"))
    _claimed.append(str(directory))
    return True


def lowered(fn, args: tuple, key: tuple, donate_argnums: tuple = ()):
    """``jax.jit(fn, donate_argnums=...).lower(*args)``, the tracing done once: inside a run using this
    module's compilation cache (:func:`compilation_cache`), the traced and lowered program is kept there
    (``traced/``, as a serialised :func:`jax.export.export`) under a digest of ``key`` (what the program
    depends on besides the arguments' types and this package's code: e.g. a method's name and static
    configuration, which must pickle), the arguments' types, the package's source, jax and its settings; a
    repeated run reads it back and lowers it instead of tracing again (he-slab-2d's time loop: about 1 s
    against 17-37 s of tracing and lowering on a loaded 2-core CPU). The program is the same either way,
    as is the compiled code. Elsewhere, or where ``key`` or the arguments cannot be keyed or serialised (a
    pytree node other than a NamedTuple, tuple, list or dict), the usual tracing."""
    digest = _digest(key, args) if _active and importlib.util.find_spec("flatbuffers") else None  # (serialisation's)
    program = None if digest is None or not _exportable(args) else _traced(fn, args, digest)
    if program is None:
        return jax.jit(fn, donate_argnums=donate_argnums).lower(*args)
    return jax.jit(program.call, donate_argnums=donate_argnums).lower(*args)


def _traced(fn, args: tuple, digest: str):
    """The stored :class:`jax.export.Exported` of ``fn`` at ``args`` (``digest``: :func:`_digest`), exported
    and stored now if it is not there or cannot be read back; None where jax.export cannot carry the program
    (e.g. a custom call without a stability guarantee: then traced as usual, which also raises any error
    of the program itself), or does not call it as the run does (a program over several devices, a grid
    split by ``numerics.devices``: it is traced as usual, twice where the cache is on)."""
    file = Path(_claimed[0]) / "traced" / f"{digest}.exported"
    if file.is_file():
        try:
            return export.deserialize(bytearray(file.read_bytes()))
        except Exception:  # noqa: BLE001  (an unreadable entry is replaced below)
            pass
    try:
        program = export.export(jax.jit(fn))(*args)
        if program.nr_devices > 1:  # (a grid split across devices: its program, called with arguments on one
            return None             # device, is refused by jax.export; traced as usual, and not stored)
        blob = program.serialize()
    except Exception:  # noqa: BLE001  (see the docstring)
        return None
    file.parent.mkdir(parents=True, exist_ok=True)
    partial = file.with_suffix(f".{os.getpid()}.partial")  # (renamed into place: never read half written)
    partial.write_bytes(blob)
    os.replace(partial, file)
    return program


def _digest(key: tuple, args: tuple) -> str | None:
    """sha256 of what decides a traced program, or None where ``key`` does not pickle."""
    leaves, tree = jax.tree_util.tree_flatten(args)
    settings = sorted((k, repr(v)) for k, v in jax.config.values.items() if "cache" not in k and "log" not in k)
    try:
        blob = pickle.dumps((key, str(tree), [(type(x).__name__, str(jax.typeof(x))) for x in leaves], settings,
                             xla.backend(), jax.__version__, jaxlib.version.__version__, _source_digest()))
    except (pickle.PicklingError, TypeError, AttributeError):
        return None
    return hashlib.sha256(blob).hexdigest()


@functools.cache
def _source_digest() -> str:
    """sha256 of this package's Python source (a changed line traces afresh)."""
    root = Path(__file__).parent
    digest = hashlib.sha256()
    for file in sorted(root.rglob("*.py")):
        digest.update(str(file.relative_to(root)).encode() + b"\0" + file.read_bytes())
    return digest.hexdigest()


_SERIALISED: set = set()  # the NamedTuple types registered for jax.export's serialisation


def _exportable(args) -> bool:
    """Whether the pytree ``args`` is made of NamedTuples (registered here), tuples, lists and dicts only."""
    def walk(tree) -> bool:
        kind = tree.node_data()
        node = None if kind is None else kind[0]
        if node is not None and node not in (tuple, list, dict, type(None)):
            if not (issubclass(node, tuple) and hasattr(node, "_fields")):
                return False
            if node not in _SERIALISED:
                export.register_namedtuple_serialization(node, serialized_name=f"{node.__module__}.{node.__qualname__}")
                _SERIALISED.add(node)
        return all(walk(child) for child in tree.children())
    return walk(jax.tree_util.tree_structure(args))


def _version(text: str) -> tuple[int, ...]:
    """(major, minor) of a version string ("0.10.2", "0.11.0rc1")."""
    return tuple(int(part) for part in re.findall(r"\d+", text)[:2])


def join_hosts(coordinator: str | None = None, processes: int | None = None, process_id: int | None = None):
    """Join this process to a run over several hosts (``jax.distributed``): call it in every process, before
    anything else uses JAX. Then ``numerics.devices`` counts the devices of all hosts, each process steps its
    devices' part of the split grid or particle pool, and the first process writes the results (the others
    run the same program and write nothing the user sees). ``coordinator``: "host:port" of the first
    process, ``processes`` their number, ``process_id`` this one's (0 for the first); all None where the
    cluster says them (SLURM, Open MPI: see ``jax.distributed.initialize``). CPU devices exchange their
    data through gloo."""
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator, processes, process_id)
