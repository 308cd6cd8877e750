"""The import structure of the package, read from the source with ``ast`` (nothing is imported).

* (a) The module-level import graph of ``blastfsi`` has no cycle: every method owns its scenario
  builder (``euler/problem.py``, ``mpm/problem.py``, ``cfdmp/problem.py``,
  ``lagrangian1d/plate_problem.py``, ``lagrangian1d/charge_problem.py``) and nothing imports back.
* (b) A blastfsi import inside a function is allowed only where :data:`FUNCTION_IMPORTS` says why,
  so an import hidden in a function to dodge a cycle fails here.
* (c) Layering (:data:`LAYERS`): library < scenario < methods < driver; a module imports only its own
  layer or lower ones, so the physics library and the methods never import the driver
  (exceptions: :data:`LAYER_EXCEPTIONS`).
"""
from __future__ import annotations

import ast
import functools
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
ROOT = "blastfsi"


def module_files(src: Path = SRC) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` under ``src/blastfsi`` (a package is its ``__init__``)."""
    out = {}
    for path in sorted((src / ROOT).rglob("*.py")):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _resolve(node: ast.Import | ast.ImportFrom, module: str, is_package: bool, modules) -> list[str]:
    """The blastfsi modules an import statement loads: ``from blastfsi.x import y`` is ``blastfsi.x.y``
    where that is a module, else ``blastfsi.x``."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name == ROOT or a.name.startswith(ROOT + ".")]
    base = node.module or ""
    if node.level:  # relative import
        pkg = module.split(".") if is_package else module.split(".")[:-1]
        pkg = pkg[: len(pkg) - (node.level - 1)]
        base = ".".join(pkg + ([base] if base else []))
    if base != ROOT and not base.startswith(ROOT + "."):
        return []
    out = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        out.append(sub if sub in modules else base)
    return out


def imports_of(path: Path, module: str, modules) -> tuple[set[str], set[str]]:
    """(module-level, function-level) blastfsi imports of one file. Module level includes class bodies and
    ``if``/``try`` blocks (they run on import); imports under ``if TYPE_CHECKING:`` are not counted."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_package = path.name == "__init__.py"
    top, inner = set(), set()

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                for c in child.orelse:
                    visit_stmt(c, in_function)
                continue
            visit_stmt(child, in_function)

    def visit_stmt(child, in_function):
        if isinstance(child, (ast.Import, ast.ImportFrom)):
            (inner if in_function else top).update(_resolve(child, module, is_package, modules))
        visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    visit(tree, False)
    top.discard(module)
    inner.discard(module)
    return top, inner


@functools.lru_cache(maxsize=None)
def import_graph(src: Path = SRC):
    """(module-level graph, function-level graph): module -> set of blastfsi modules it imports."""
    modules = module_files(src)
    top, inner = {}, {}
    for name, path in modules.items():
        top[name], inner[name] = imports_of(path, name, modules)
    return top, inner


def without_own_submodules(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The graph less the edges from a package's ``__init__`` to its own submodules (re-exports are fine)."""
    return {m: {t for t in targets if not t.startswith(m + ".")} for m, targets in graph.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as ``[a, b, ..., a]``, or None when it is acyclic (iterative DFS)."""
    WHITE, GREY, BLACK = 0, 1, 2
    colour = {n: WHITE for n in graph}
    for targets in graph.values():
        for t in targets:
            colour.setdefault(t, WHITE)
    for start in sorted(colour):
        if colour[start] != WHITE:
            continue
        path = [start]
        stack = [iter(sorted(graph.get(start, ())))]
        colour[start] = GREY
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                colour[path.pop()] = BLACK
                stack.pop()
            elif colour[nxt] == GREY:
                return path[path.index(nxt):] + [nxt]
            elif colour[nxt] == WHITE:
                colour[nxt] = GREY
                path.append(nxt)
                stack.append(iter(sorted(graph.get(nxt, ()))))
    return None


# (b) Every blastfsi import made inside a function, with its reason. Key: (importing module, imported module).
PLOTTING = "plotting: matplotlib is imported only when plots are drawn"
FUNCTION_IMPORTS = {
    ("blastfsi.cfdmp.method", "blastfsi.plotting.fields"): PLOTTING,
    ("blastfsi.cfdmp.method", "blastfsi.plotting.histories"): PLOTTING,
    ("blastfsi.cfdmp.method", "blastfsi.plotting.units"): PLOTTING,
    ("blastfsi.euler.method", "blastfsi.plotting.fields"): PLOTTING,
    ("blastfsi.euler.method", "blastfsi.plotting.histories"): PLOTTING,
    ("blastfsi.euler.method", "blastfsi.plotting.kb"): PLOTTING,
    ("blastfsi.euler.method", "blastfsi.plotting.units"): PLOTTING,
    ("blastfsi.lagrangian1d.method", "blastfsi.plotting"): PLOTTING,
    ("blastfsi.lagrangian1d.method", "blastfsi.plotting.kb"): PLOTTING,
    ("blastfsi.mpm.method", "blastfsi.plotting.common"): PLOTTING,
    ("blastfsi.mpm.method", "blastfsi.plotting.fields"): PLOTTING,
    ("blastfsi.mpm.method", "blastfsi.plotting.histories"): PLOTTING,
    ("blastfsi.mpm.method", "blastfsi.plotting.units"): PLOTTING,
    ("blastfsi.cli", "blastfsi.exact.kingery_bulmash"): "cli start-up: loaded by the `kb` subcommand only",
    ("blastfsi.cli", "blastfsi.schema"): "cli start-up: loaded by the `schema` subcommand only",
}

# (c) Layers, lowest first. A module imports (at module level or inside a function) only modules of its own
# layer or of lower ones, except the pairs in LAYER_EXCEPTIONS: the physics library never imports a method,
# and neither imports the driver. Every module of the package belongs to one layer.
LAYERS = {
    # physics and numerics with no notion of a scenario or a run: EOS, materials, exact solutions, constitutive
    # models, diagnostics, the XLA helpers, JAX's settings and compilation cache, and the shared compiled time
    # loop (a leaf: it imports only JAX)
    "library": ("blastfsi.eos", "blastfsi.materials", "blastfsi.exact", "blastfsi.constitutive",
                "blastfsi.diagnostics", "blastfsi.xla", "blastfsi.runtime", "blastfsi.timeloop"),
    # the shared scenario model, the method registry and its state kinds, result files, the shipped examples
    "scenario": ("blastfsi.scenario", "blastfsi.method", "blastfsi.io", "blastfsi.examples"),
    # the methods, each with its scenario builder; the detonation (1D charge -> 2D/3D remap); the plots
    "methods": ("blastfsi.euler", "blastfsi.mpm", "blastfsi.cfdmp", "blastfsi.lagrangian1d", "blastfsi.detonation",
                "blastfsi.plotting"),
    # the driver: runs a scenario (terminal report), the schema, the Python API, the CLI
    "driver": ("blastfsi.simulation", "blastfsi.report", "blastfsi.schema", "blastfsi.api",
               "blastfsi.cli", "blastfsi"),
}
LAYER_EXCEPTIONS: dict[tuple[str, str], str] = {}  # none: a charge's 1D detonation runs on lagrangian1d's own face


def layer_of(module: str) -> int:
    """Index in LAYERS of the longest prefix matching ``module`` (``blastfsi`` stands for the package root only)."""
    best, length = None, -1
    for i, prefixes in enumerate(LAYERS.values()):
        for p in prefixes:
            hit = module == p or (p != ROOT and module.startswith(p + "."))
            if hit and len(p) > length:
                best, length = i, len(p)
    if best is None:
        raise KeyError(f"{module} is in no layer of LAYERS: add it to one")
    return best


def test_find_cycle_on_synthetic_graphs():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None
    assert find_cycle({"a": {"b", "c"}, "b": {"d"}, "c": {"d"}, "d": set()}) is None  # a diamond is no cycle
    assert find_cycle({"a": {"a"}}) == ["a", "a"]
    cycle = find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set()})
    assert cycle is not None and cycle[0] == cycle[-1] and set(cycle) == {"a", "b", "c"}
    cycle = find_cycle({"x": {"y"}, "y": set(), "p": {"q"}, "q": {"r"}, "r": {"q"}})
    assert cycle == ["q", "r", "q"]
    # a package re-exporting its submodules is not a cycle; a submodule cycle through the package is
    graph = {"pkg": {"pkg.sub"}, "pkg.sub": {"pkg"}}
    assert find_cycle(without_own_submodules(graph)) is None
    assert find_cycle(without_own_submodules({**graph, "pkg.sub": {"other"}, "other": {"pkg.sub"}})) is not None


def test_resolution_of_from_imports(tmp_path):
    pkg = tmp_path / ROOT
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from blastfsi.sub import thing\n")
    (pkg / "sub" / "__init__.py").write_text("thing = 1\n")
    (pkg / "sub" / "mod.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "from blastfsi import sub\n"
        "from blastfsi.sub import mod2, thing\n"
        "from . import mod2 as m2\n"
        "if TYPE_CHECKING:\n"
        "    import blastfsi.other\n"
        "def f():\n"
        "    import blastfsi.other\n"
        "class C:\n"
        "    from blastfsi.sub.mod2 import name\n")
    (pkg / "sub" / "mod2.py").write_text("name = 2\n")
    (pkg / "other.py").write_text("")
    top, inner = import_graph(tmp_path)
    assert top["blastfsi"] == {"blastfsi.sub"}
    assert top["blastfsi.sub.mod"] == {"blastfsi.sub", "blastfsi.sub.mod2"}
    assert inner["blastfsi.sub.mod"] == {"blastfsi.other"}


def test_no_module_level_import_cycle():
    top, _ = import_graph()
    assert len(top) > 50, sorted(top)  # the walk found the package
    cycle = find_cycle(without_own_submodules(top))
    assert cycle is None, "module-level import cycle: " + " -> ".join(cycle)


def test_function_level_imports_are_allowed():
    _, inner = import_graph()
    found = {(m, t) for m, targets in inner.items() for t in targets}
    hidden = sorted(found - set(FUNCTION_IMPORTS))
    assert not hidden, ("blastfsi imports inside functions that are not in FUNCTION_IMPORTS (move them to the "
                        "top of the module; if that makes a cycle, fix the layering): "
                        + ", ".join(f"{m} imports {t}" for m, t in hidden))
    stale = sorted(set(FUNCTION_IMPORTS) - found)
    assert not stale, f"FUNCTION_IMPORTS entries no longer in the source: {stale}"


def test_layers_import_only_downward():
    top, inner = import_graph()
    names = list(LAYERS)
    for m in top:
        layer_of(m)  # every module is in a layer
    found = {(m, t) for graph in (top, inner) for m, targets in graph.items() for t in targets
             if layer_of(t) > layer_of(m)}
    bad = sorted(found - set(LAYER_EXCEPTIONS))
    assert not bad, "imports of a higher layer: " + ", ".join(
        f"{m} ({names[layer_of(m)]}) -> {t} ({names[layer_of(t)]})" for m, t in bad)
    stale = sorted(set(LAYER_EXCEPTIONS) - found)
    assert not stale, f"LAYER_EXCEPTIONS entries no longer in the source: {stale}"


def test_layer_of():
    assert layer_of("blastfsi.eos.jwl") < layer_of("blastfsi.method") < layer_of("blastfsi.euler.problem")
    assert layer_of("blastfsi.euler.problem") < layer_of("blastfsi.simulation") == layer_of("blastfsi")
    for outside in ("blastfsi.newpackage", "blastfsi_other"):
        try:
            layer_of(outside)
        except KeyError:
            continue
        raise AssertionError(f"{outside} is in no layer and must be refused")
