"""Modules use each other's public names only.

A cross-module import of an underscore name (``from ramure.lsys.history.tree import _thing``) or an
attribute access ``module._thing`` on an imported Ramure module couples two modules through
a private detail; this test walks every module's source and fails on either.  Private
*modules* (``ramure.app.jupyter._ui``) may be imported inside their own package.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
FOLDERS = {
    "ramure": "ramure",
    "lsys": "ramure.lsys",
    "metrics": "ramure.metrics",
    "gmap": "ramure.gmap",
    "studies": "ramure.studies",
    "app": "ramure.app",
    "grammars": "ramure.grammars",
}


def _sources():
    for folder, package in FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            name = ".".join((package, *parts)).removesuffix(".__init__")
            yield name, path


def _absolute(module, node):
    if not node.level:
        return node.module or ""
    base = module.split(".")[: -node.level] if not module.endswith("__init__") else module.split(".")
    return ".".join(base + ([node.module] if node.module else []))


def _package(module):
    return module.rsplit(".", 1)[0]


def _violations(name, path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_package = path.name == "__init__.py"
    here = name if is_package else _package(name)
    bad = []
    imported_modules = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            source = _absolute(name if not is_package else name + ".__init__", node)
            if not source.startswith("ramure"):
                continue
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__"):
                    target = f"{source}.{alias.name}"
                    # a private module of one's own package is fine; a private name of another module is not
                    if not (_package(target) == here and _is_module(target)):
                        bad.append(f"line {node.lineno}: from {source} import {alias.name}")
                else:
                    imported_modules[alias.asname or alias.name] = f"{source}.{alias.name}"
            private = [p for p in source.split(".") if p.startswith("_") and p != "__init__"]
            if private and not source.startswith(here):
                bad.append(f"line {node.lineno}: imports the private module {source} from outside its package")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("ramure"):
                    imported_modules[alias.asname or alias.name.split(".")[0]] = alias.name
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and isinstance(node.value, ast.Name)
            and node.value.id in imported_modules
            and _is_module(imported_modules[node.value.id])
        ):
            bad.append(f"line {node.lineno}: {node.value.id}.{node.attr}")
    bad += _foreign_private_attributes(tree)
    return bad


def _own_private_names(tree):
    """Underscore names this module defines: functions, classes, assignments, ``self._x = ...``."""
    own = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            own.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            own.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            own.add(node.id)
        elif isinstance(node, ast.arg):
            own.add(node.arg)
    return own


# namedtuple's documented API: underscored only so as not to clash with field names
NAMEDTUPLE_API = {"_make", "_asdict", "_replace", "_fields", "_field_defaults"}


def _private(name):
    """``_x`` is private; ``__x__``, protocol names such as ``_repr_png_`` and namedtuple's
    ``_make``/``_asdict``/``_replace``/``_fields`` are not."""
    return name.startswith("_") and not name.startswith("__") and not name.endswith("_") and name not in NAMEDTUPLE_API


def _foreign_private_attributes(tree):
    """``obj._x`` where ``obj`` is not ``self``/``cls`` and this module defines no ``_x``:
    reading another module's object through its private attributes."""
    own = _own_private_names(tree)
    bad = []
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and _private(node.attr)
            and node.attr not in own
            and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls", "super"))
        ):
            bad.append(f"line {node.lineno}: .{node.attr} (a private attribute of another module's object)")
    return bad


def _is_module(dotted):
    return dotted in MODULES


MODULES = {name for name, _ in _sources()}


# Known debt, to be paid down (a ratchet): uses of another module's private names that were
# already there when this test was written. Anything not listed fails; a listed entry that is
# gone must be removed from the file (the test says so).
BASELINE = ROOT / "tests" / "public_api_baseline.txt"


def _baseline():
    lines = BASELINE.read_text(encoding="utf-8").splitlines() if BASELINE.exists() else []
    return {line.strip() for line in lines if line.strip() and not line.startswith("#")}


def _entries(name, path):
    return {f"{name}: {v.split(': ', 1)[1].split(' (')[0]}" for v in _violations(name, path)}


@pytest.mark.parametrize("name,path", list(_sources()), ids=[n for n, _ in _sources()])
def test_no_private_names_across_modules(name, path):
    known = {e for e in _baseline() if e.startswith(name + ": ")}
    found = _entries(name, path)
    assert found - known == set(), "new uses of another module's private names"
    assert known - found == set(), "paid-down debt: remove these lines from tests/public_api_baseline.txt"
