"""The desktop's rooms (issue 41): who may import whom, and no room reaches back into the window.

Read from the source (ast), so no display is needed.  Every module of ``app/desktop`` stands in
one room of :data:`ALLOWED` and imports only its own room and the rooms the table names, type
hints included.  Besides, a module under ``panels/``, ``view/`` or ``menus/`` may not take a
parameter typed ``MainWindow`` and may not use a member of :class:`MainWindow` (its methods,
properties and the attributes it sets) through a receiver named like a window (``window``,
``self.window``, ``self.main_window``, ``window_``...) nor through
``getattr``/``setattr``/``hasattr`` on one.  ``docs/images/desktop.svg`` is drawn from
:data:`ALLOWED` (``docs/images/make_architecture.py``).
"""

from __future__ import annotations

import ast
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
DESKTOP = ROOT / "app" / "desktop"
ROOMS = ("panels", "view", "menus")
WINDOWISH = re.compile(r"(^|_)window(_|$)")
TYPED = re.compile(r"\bMainWindow\b")
#: The desktop's rooms and the rooms each may import (besides itself).  ``command`` is the
#: ``python -m ramure.app.desktop`` entry (``__init__``, ``__main__``, ``launch``); ``controller``
#: the model's one owner and its job queue (``controller``, ``workers``); ``helpers`` the
#: modules without widgets (``state``, ``variants``, ``qt_fix``).
ALLOWED = {
    "command": {"window", "view", "helpers"},
    "window": {"panels", "menus", "view", "controller", "helpers"},
    "menus": {"panels", "view", "controller", "helpers"},
    "panels": {"view", "controller", "helpers"},
    "view": {"helpers"},
    "controller": {"helpers"},
    "helpers": set(),
}
#: The room of each module at the top of ``app/desktop`` (the sub-packages are rooms by name).
TOP = {"__init__": "command", "__main__": "command", "launch": "command", "window": "window"}
TOP |= {"controller": "controller", "workers": "controller", "state": "helpers", "variants": "helpers", "qt_fix": "helpers"}


def room(module: str) -> str:
    """The room of a dotted desktop module (``ramure.app.desktop.panels.regen`` -> ``panels``)."""
    parts = module.split(".")[3:] or ["__init__"]
    return parts[0] if parts[0] in ROOMS else TOP[parts[0]]


def window_members(source: str) -> set[str]:
    """Names :class:`MainWindow` defines: methods, properties and the ``self.x`` it assigns."""
    tree = ast.parse(source)
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "MainWindow"]
    names = set()
    for node in ast.walk(cls):
        if isinstance(node, ast.FunctionDef) and not node.name.startswith("__"):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            if isinstance(node.value, ast.Name) and node.value.id == "self":
                names.add(node.attr)
    return names


def _windowish(node: ast.AST) -> bool:
    """A receiver named like a window: ``window``, ``self.window``, ``self.main_window``...
    (not ``self.window()``, Qt's top-level widget, which is a call)."""
    if isinstance(node, ast.Name):
        return bool(WINDOWISH.search(node.id))
    return isinstance(node, ast.Attribute) and bool(WINDOWISH.search(node.attr))


def _imported(tree: ast.AST, package: str) -> set[str]:
    """Every module named by an import in ``tree`` (type-checking imports included)."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
            module = f"{base}.{node.module}" if node.level and node.module else (base if node.level else node.module or "")
            found |= {module} | {f"{module}.{a.name}" for a in node.names}
    return found


def _module_of(name: str) -> str | None:
    """The desktop module an imported name stands for (``...window.MainWindow`` -> ``...window``)."""
    parts = name.split(".")
    for cut in range(len(parts), 2, -1):
        module = ".".join(parts[:cut])
        if module in MODULES:
            return module
    return None


def _front_door(module: str, package: str) -> bool:
    """``module`` is a package enclosing ``package`` (``from ramure.app.desktop import state``
    names the front door of the importer's own package, not an edge)."""
    return MODULES[module].name == "__init__.py" and (package == module or package.startswith(module + "."))


def bad_imports(source: str, here: str, package: str) -> list[str]:
    """The imports of ``source`` (a module of room ``here``) that :data:`ALLOWED` does not allow."""
    found = []
    for name in sorted(_imported(ast.parse(source), package)):
        module = _module_of(name)
        if module is None or _front_door(module, package):
            continue
        if room(module) not in ALLOWED[here] | {here}:
            found.append(f"imports {name} (the {here} room may not import the {room(module)} room)")
    return found


def back_calls(source: str, members: set[str], room: str = "panels", package: str = "ramure.app.desktop.panels") -> list[str]:
    """What ``source`` (a module of ``room``) does that a room may not, one line each."""
    tree = ast.parse(source)
    found = bad_imports(source, room, package)
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Attribute) and node.attr in members and _windowish(node.value):
            found.append(f"line {line}: {ast.unparse(node)}")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("getattr", "setattr", "hasattr"):
            args = node.args
            if len(args) >= 2 and _windowish(args[0]) and isinstance(args[1], ast.Constant) and args[1].value in members:
                found.append(f"line {line}: {ast.unparse(node)}")
        elif isinstance(node, ast.arg) and node.annotation is not None and TYPED.search(ast.unparse(node.annotation)):
            found.append(f"line {line}: parameter {node.arg} typed MainWindow")
    return found


MEMBERS = window_members((DESKTOP / "window.py").read_text(encoding="utf-8"))
#: ``{dotted name: path}`` of every desktop module.
MODULES = {
    ".".join(("ramure.app.desktop", *p.relative_to(DESKTOP).with_suffix("").parts)).removesuffix(".__init__"): p
    for p in sorted(DESKTOP.rglob("*.py"))
}


def test_the_window_members_are_read_from_its_class():
    # the five back-calls issue 41 names are window members the check looks for
    assert {"report_refused", "run_selection", "status", "confirm_discard", "flush_edits"} <= MEMBERS
    assert {"view", "regen", "controller", "files"} <= MEMBERS  # attributes it sets count too
    assert "__init__" not in MEMBERS


def test_the_detector_finds_what_it_should():
    source = (
        "from __future__ import annotations\n"
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from ramure.app.desktop.window import MainWindow\n"
        "from ramure.app.desktop.menus import files\n"
        "class Panel:\n"
        "    def __init__(self, window: MainWindow, controller) -> None:\n"
        "        self.window = window\n"
        "        self.controller = controller\n"
        "    def go(self):\n"
        "        self.window.report_refused('no')\n"
        "        self.main_window.status('x', 1)\n"
        "        getattr(self.window, 'view', None)\n"
        "        self.controller.undo()\n"  # a controller's undo, not the window's
        "        self.window().setWindowTitle('t')\n"  # Qt's top-level widget: allowed
        "        self.status.emit('fine', 1)\n"  # its own signal
    )
    found = back_calls(source, {"report_refused", "status", "view", "undo"})
    assert sorted(found) == [
        "imports ramure.app.desktop.menus (the panels room may not import the menus room)",
        "imports ramure.app.desktop.menus.files (the panels room may not import the menus room)",
        "imports ramure.app.desktop.window (the panels room may not import the window room)",
        "imports ramure.app.desktop.window.MainWindow (the panels room may not import the window room)",
        "line 11: self.window.report_refused",
        "line 12: self.main_window.status",
        "line 13: getattr(self.window, 'view', None)",
        "line 7: parameter window typed MainWindow",
    ]
    assert back_calls("from ramure.app.desktop import controller\n", set(), "view", "ramure.app.desktop.view") == [
        "imports ramure.app.desktop.controller (the view room may not import the controller room)"
    ]
    assert back_calls("from ..panels import regen\n", set(), "view", "ramure.app.desktop.view") == [
        "imports ramure.app.desktop.panels (the view room may not import the panels room)",
        "imports ramure.app.desktop.panels.regen (the view room may not import the panels room)",
    ]
    assert back_calls("from . import plant_view, scene\n", set(), "view", "ramure.app.desktop.view") == []


def test_no_room_reaches_back_into_the_window():
    bad, seen = [], 0
    for room in ROOMS:
        for path in sorted((DESKTOP / room).glob("*.py")):
            seen += 1
            package = f"ramure.app.desktop.{room}"
            bad += [f"{room}/{path.name}: {b}" for b in back_calls(path.read_text(encoding="utf-8"), MEMBERS, room, package)]
    assert seen >= 25  # the 13 panels, 7 view modules and 5 menus, with their __init__ files
    assert bad == []


def test_every_module_stands_in_a_room_and_imports_only_what_it_may():
    assert room("ramure.app.desktop") == "command" and room("ramure.app.desktop.view.scene") == "view"
    bad = []
    for name, path in MODULES.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        bad += [f"{name}: {b}" for b in bad_imports(path.read_text(encoding="utf-8"), room(name), package)]
    assert bad == []
    assert {room(name) for name in MODULES} == set(ALLOWED)  # every room has a module, every module a room


def test_each_room_says_what_it_owns_and_may_import():
    for room in ROOMS:
        doc = ast.get_docstring(ast.parse((DESKTOP / room / "__init__.py").read_text(encoding="utf-8")))
        assert doc and "import" in doc and "window" in doc, room


#: What the 3D view draws with: the presenter (``view/presenter.py``) calls these, the window never.
DRAWING = {"set_colors", "show_plant", "set_box_for", "set_box", "set_selected_segments", "set_fruit_selection", "project"}


def view_drawing_calls(source: str) -> list[str]:
    """The calls of ``source`` on ``self.view`` that draw (one line each)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in DRAWING:
            receiver = node.func.value
            if isinstance(receiver, ast.Attribute) and receiver.attr == "view":
                found.append(f"line {node.lineno}: {ast.unparse(node.func)}")
    return found


def test_the_window_only_assembles_the_presenter_draws():
    assert view_drawing_calls("def f(self):\n    self.view.set_colors(c)\n    self.view.reset_camera()\n") == [
        "line 2: self.view.set_colors"
    ]
    assert view_drawing_calls((DESKTOP / "window.py").read_text(encoding="utf-8")) == []
    presenter = (DESKTOP / "view" / "presenter.py").read_text(encoding="utf-8")
    assert {call.split(".")[-1] for call in view_drawing_calls(presenter)} == DRAWING
    # the colour, preview and kinship state lives with the drawing, not in the window
    assert not {"base_colors", "fruit_leaves", "preview_key", "cut_leaves", "drawn_version", "kinship"} & MEMBERS
