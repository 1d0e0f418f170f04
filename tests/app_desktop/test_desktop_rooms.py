"""The desktop's rooms (issue 41): panels, view and menus never reach back into the window.

Read from the source (ast), so no display is needed.  A module under ``panels/``, ``view/`` or
``menus/`` may not import :mod:`ramure.app.desktop.window` (not even for type hints), may not
take a parameter typed ``MainWindow``, and may not use a member of :class:`MainWindow` (its
methods, properties and the attributes it sets) through a receiver named like a window
(``window``, ``self.window``, ``self.main_window``, ``window_``...) nor through
``getattr``/``setattr``/``hasattr`` on one.  The view, the lowest room, imports neither the
panels, the menus nor the controller; the panels do not import the menus.
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
#: What each room may not import, besides the window (dotted prefixes under ramure.app.desktop).
FORBIDDEN = {
    "view": ("ramure.app.desktop.panels", "ramure.app.desktop.menus", "ramure.app.desktop.controller"),
    "panels": ("ramure.app.desktop.menus",),
    "menus": (),
}


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


def back_calls(source: str, members: set[str], room: str = "panels", package: str = "ramure.app.desktop.panels") -> list[str]:
    """What ``source`` (a module of ``room``) does that a room may not, one line each."""
    tree = ast.parse(source)
    found = []
    for module in sorted(_imported(tree, package)):
        if module.startswith("ramure.app.desktop.window"):
            found.append(f"imports {module}")
        elif module.startswith(FORBIDDEN[room]):
            found.append(f"imports {module} (the {room} room may not)")
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
        "imports ramure.app.desktop.menus (the panels room may not)",
        "imports ramure.app.desktop.menus.files (the panels room may not)",
        "imports ramure.app.desktop.window",
        "imports ramure.app.desktop.window.MainWindow",
        "line 11: self.window.report_refused",
        "line 12: self.main_window.status",
        "line 13: getattr(self.window, 'view', None)",
        "line 7: parameter window typed MainWindow",
    ]
    assert back_calls("from ramure.app.desktop import controller\n", set(), "view", "ramure.app.desktop.view") == [
        "imports ramure.app.desktop.controller (the view room may not)"
    ]
    assert back_calls("from ..panels import regen\n", set(), "view", "ramure.app.desktop.view") == [
        "imports ramure.app.desktop.panels (the view room may not)",
        "imports ramure.app.desktop.panels.regen (the view room may not)",
    ]


def test_no_room_reaches_back_into_the_window():
    bad, seen = [], 0
    for room in ROOMS:
        for path in sorted((DESKTOP / room).glob("*.py")):
            seen += 1
            package = f"ramure.app.desktop.{room}"
            bad += [f"{room}/{path.name}: {b}" for b in back_calls(path.read_text(encoding="utf-8"), MEMBERS, room, package)]
    assert seen >= 25  # the 13 panels, 7 view modules and 5 menus, with their __init__ files
    assert bad == []


def test_each_room_says_what_it_owns_and_may_import():
    for room in ROOMS:
        doc = ast.get_docstring(ast.parse((DESKTOP / room / "__init__.py").read_text(encoding="utf-8")))
        assert doc and "import" in doc and "window" in doc, room
