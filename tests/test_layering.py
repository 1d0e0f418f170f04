"""The layers stay light: nothing below ``ramure.app`` pulls in Qt, widgets or pyplot."""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

import pytest

GUI = ("PySide6", "pyvistaqt", "ipywidgets", "matplotlib.pyplot", "trame")


def _loaded_after(code, tmp_path):
    probe = f"{code}\nimport sys\nprint(sorted(m for m in {GUI!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, cwd=tmp_path)
    return out.stdout.strip().splitlines()[-1]


def test_import_ramure_is_light(tmp_path):
    code = "import ramure\nramure.derive('honda_sympodial', n=3)\nassert 'pyvista' not in sys.modules"
    assert _loaded_after("import sys\n" + code, tmp_path) == "[]"


def test_metrics_explore_loads_no_gui(tmp_path):
    code = (
        "import ramure.metrics as m, ramure.metrics.apply, ramure.metrics.store\n"
        "m.explore('grammars/honda_sympodial.lsys', n=2, n_jobs=1, cache=False)"
    )
    assert _loaded_after(code, tmp_path) == "[]"


def test_studies_report_loads_no_gui(tmp_path):
    code = f"import ramure.studies as s\ns.write_report(s.simulate_study(participants=1, grammars=1), {str(tmp_path / 'r')!r})"
    assert _loaded_after(code, tmp_path) == "[]"


def test_jupyter_import_loads_no_qt(tmp_path):
    pytest.importorskip("ipywidgets")
    out = _loaded_after("import ramure.app.jupyter", tmp_path)
    assert "PySide6" not in out and "matplotlib.pyplot" not in out and "trame" not in out


# -- the package graph: who may import whom, lazy (function-level) imports included ------------
#
# Imports are read from the source (ast), wherever they stand in a module: at the top, inside a
# function or a method.  Only those under ``if TYPE_CHECKING:`` are left out (never run).  An
# import of a module's own package (``from ramure.gmap import GMap3`` inside ``ramure.gmap``)
# is the package's front door, not an edge.

ROOT = pathlib.Path(__file__).resolve().parents[1]
FOLDERS = {"ramure": "ramure", "lsys": "ramure.lsys", "metrics": "ramure.metrics", "gmap": "ramure.gmap"}
FOLDERS |= {"studies": "ramure.studies", "app": "ramure.app", "grammars": "ramure.grammars"}
#: The base modules of the ``ramure`` folder (errors, io, jit, lazy), below every package.
BASE = "ramure.<base>"
#: What each package may import (besides itself, numpy and the like).  ``ramure`` is the front
#: door (``ramure/__init__.py``); ``ramure.app`` stands for the CLI, desktop and Jupyter.
ALLOWED = {
    BASE: set(),
    "ramure": {BASE, "ramure.lsys"},
    "ramure.grammars": {BASE},
    "ramure.lsys": {BASE, "ramure.grammars"},
    "ramure.metrics": {BASE, "ramure.grammars", "ramure.lsys"},
    "ramure.gmap.kernel": {BASE},
    "ramure.gmap.lsystem": {BASE, "ramure.grammars", "ramure.lsys", "ramure.gmap.kernel"},
    "ramure.gmap.organs": {BASE, "ramure.lsys", "ramure.gmap.kernel", "ramure.gmap.lsystem"},
    "ramure.gmap": {"ramure.gmap.kernel", "ramure.gmap.organs"},
    "ramure.studies": {BASE, "ramure.grammars", "ramure.lsys", "ramure.metrics"},
    "ramure.app": {BASE, "ramure", "ramure.grammars", "ramure.lsys", "ramure.metrics", "ramure.studies"}
    | {"ramure.gmap", "ramure.gmap.kernel", "ramure.gmap.lsystem", "ramure.gmap.organs"},
}


#: The rooms of ``ramure.lsys`` (its sub-packages) and what each may import inside ``ramure.lsys``
#: besides itself; outside it, every room may import what ``ALLOWED["ramure.lsys"]`` says.
#: ``LSYS_ROOT`` stands for the modules directly in ``lsys/`` (``errors``, ``expr``: the
#: expression language), below every room; ``ramure.lsys`` itself is the front door.  Floors,
#: from the bottom: root; architecture, history; interpretation; language; engine;
#: regeneration, readers (``docs/images/lsys_rooms.py`` prints them from the source).
LSYS_ROOT = "ramure.lsys.<root>"
LSYS_ROOMS = {
    LSYS_ROOT: set(),
    "ramure.lsys.architecture": {LSYS_ROOT},
    "ramure.lsys.history": {LSYS_ROOT},
    "ramure.lsys.interpretation": {LSYS_ROOT, "ramure.lsys.history"},
    "ramure.lsys.language": {LSYS_ROOT, "ramure.lsys.architecture", "ramure.lsys.interpretation"},
    "ramure.lsys.engine": {LSYS_ROOT, "ramure.lsys.architecture", "ramure.lsys.history"}
    | {"ramure.lsys.interpretation", "ramure.lsys.language"},
    "ramure.lsys.regeneration": {LSYS_ROOT, "ramure.lsys.history", "ramure.lsys.interpretation", "ramure.lsys.engine"},
    "ramure.lsys.readers": {LSYS_ROOT, "ramure.lsys.history", "ramure.lsys.interpretation", "ramure.lsys.language"}
    | {"ramure.lsys.engine"},
}
LSYS_ROOMS["ramure.lsys"] = set(LSYS_ROOMS)


def _modules():
    """``{dotted name: path}`` of every Ramure module, as installed."""
    out = {}
    for folder, package in FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            out[".".join((package, *parts)).removesuffix(".__init__")] = path
    return out


MODULES = _modules()


def _unchecked(tree):
    """Ids of the nodes under ``if TYPE_CHECKING:``."""
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip |= {id(sub) for stmt in node.body for sub in ast.walk(stmt)}
    return skip


def _imports(name, path, front_doors=False):
    """The Ramure modules ``name`` imports, lazy imports included; an import of a package the
    module stands in (its front door) is left out unless ``front_doors``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip, found = _unchecked(tree), set()
    here = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(here.split(".")[: len(here.split(".")) - node.level + 1]) if node.level else ""
            source = ".".join(filter(None, (base, node.module)))
            found |= {source} | {f"{source}.{alias.name}" for alias in node.names}
    own_front_doors = {m for m in found if MODULES.get(m, pathlib.Path()).name == "__init__.py" and name.startswith(m + ".")}
    return {m for m in found if m in MODULES and m != name} - (set() if front_doors else own_front_doors)


def _package(module):
    if module.startswith("ramure.app"):
        return "ramure.app"
    if module.startswith("ramure.lsys"):  # its rooms are checked by LSYS_ROOMS
        return "ramure.lsys"
    if module == "ramure":
        return "ramure"
    if module.count(".") == 1 and module.startswith("ramure.") and MODULES[module].parent == ROOT / "ramure":
        return BASE
    return module if MODULES[module].name == "__init__.py" else module.rsplit(".", 1)[0]


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def _cycles(graph):
    """Strongly connected components of more than one node (Tarjan, iterative)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                    break
                if child in on:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = set()
                    while True:
                        top = stack.pop()
                        on.discard(top)
                        component.add(top)
                        if top == node:
                            break
                    if len(component) > 1:
                        out.append(component)
    return out


def test_the_graph_sees_lazy_imports():
    assert "ramure.gmap.kernel.mapcut" in GRAPH["ramure.gmap.kernel.cut"]  # a top-level import
    assert "ramure.lsys.interpretation.turtle" in GRAPH["ramure.lsys.engine.derive"]  # inside Derivation.skeleton
    assert "ramure.lsys.engine.derive" not in GRAPH["ramure.lsys.interpretation.turtle"]  # only under TYPE_CHECKING


def test_every_package_imports_only_what_it_may():
    bad = []
    for name, targets in GRAPH.items():
        here = _package(name)
        assert here in ALLOWED, f"{here} ({name}) is a new package: say what it may import in ALLOWED"
        bad += [f"{name} imports {t}" for t in sorted(targets) if _package(t) not in ALLOWED[here] | {here}]
    assert bad == []


def test_no_core_package_imports_the_front_ends():
    core = {n: ts for n, ts in GRAPH.items() if not n.startswith("ramure.app")}
    bad = [f"{n} imports {t}" for n, ts in core.items() for t in ts if t.startswith("ramure.app")]
    assert bad == []


def test_the_package_graph_is_acyclic():
    packages: dict[str, set[str]] = {}
    for name, targets in GRAPH.items():
        packages.setdefault(_package(name), set()).update(_package(t) for t in targets if _package(t) != _package(name))
    assert _cycles(packages) == []
    assert all(set(ALLOWED[p]) >= imported for p, imported in packages.items())


def test_no_module_imports_itself_back():
    # the seven cycles of issue 41 (lsys around grammar/derive/turtle, polygons, cut/mapcut,
    # defects/excrescence, plant/wood, fruit/fruit_dataset, session/storage) are gone
    assert _cycles(GRAPH) == []


def test_the_cycle_finder_finds_a_lazy_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [{"a", "b", "c"}]
    assert _cycles({"a": {"b"}, "b": set()}) == []


# -- the rooms of ramure.lsys -----------------------------------------------------------------------


def _room(module):
    """The lsys room of an lsys module: its sub-package, LSYS_ROOT or the front door."""
    if module == "ramure.lsys":
        return module
    if MODULES[module].parent == ROOT / "lsys" and MODULES[module].name != "__init__.py":
        return LSYS_ROOT
    return ".".join(module.split(".")[:3])


LSYS_GRAPH = {name: _imports(name, path, front_doors=True) for name, path in MODULES.items() if name.startswith("ramure.lsys")}


def test_every_lsys_room_is_in_the_table():
    rooms = {f"ramure.lsys.{p.parent.name}" for p in (ROOT / "lsys").glob("*/__init__.py")}
    assert rooms == set(LSYS_ROOMS) - {LSYS_ROOT, "ramure.lsys"}
    assert {_room(name) for name in LSYS_GRAPH} == set(LSYS_ROOMS)


def test_every_lsys_room_imports_only_what_it_may():
    bad = []
    for name, targets in LSYS_GRAPH.items():
        here = _room(name)
        inside = sorted(t for t in targets if t.startswith("ramure.lsys"))
        bad += [f"{name} imports {t}" for t in inside if _room(t) not in LSYS_ROOMS[here] | {here}]
    assert bad == []


def test_the_lsys_rooms_are_acyclic():
    assert _cycles(LSYS_ROOMS) == []
    rooms: dict[str, set[str]] = {}
    for name, targets in LSYS_GRAPH.items():
        here = _room(name)
        rooms.setdefault(here, set()).update(_room(t) for t in targets if t.startswith("ramure.lsys") and _room(t) != here)
    assert _cycles(rooms) == []
    assert all(LSYS_ROOMS[r] >= imported for r, imported in rooms.items())


def test_the_room_check_sees_a_lazy_upward_import():
    # derive (engine) imports the turtle (interpretation) inside a function: allowed downward;
    # the same import the other way round would be refused
    assert "ramure.lsys.interpretation.turtle" in LSYS_GRAPH["ramure.lsys.engine.derive"]
    assert "ramure.lsys.engine" not in LSYS_ROOMS["ramure.lsys.interpretation"]
    assert _room("ramure.lsys.expr") == LSYS_ROOT and _room("ramure.lsys") == "ramure.lsys"
