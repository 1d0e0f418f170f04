"""Every docstring example of every Ramure module runs, from a directory that is not the repository.

The examples open shipped grammars by name or as ``grammars/NAME.lsys``; running them
from a temporary directory proves they work for someone who installed the wheel.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import ramure

PACKAGES = [
    "ramure",
    "ramure.lsys",
    "ramure.metrics",
    "ramure.gmap",
    "ramure.studies",
    "ramure.grammars",
    "ramure.app",
    "ramure.app.commands",
    "ramure.app.jupyter",
    "ramure.app.desktop",
    "ramure.app.desktop.menus",
    "ramure.app.desktop.panels",
    "ramure.app.desktop.view",
]


def _modules():
    """Every module of the packages, sub-packages at any depth included (the rooms of
    ``ramure.lsys`` and ``ramure.gmap``: ``iter_modules`` alone stopped at the first level)."""
    names = []
    for package in PACKAGES:
        names.append(package)
        module = importlib.import_module(package)
        names += [m.name for m in pkgutil.walk_packages(module.__path__, prefix=f"{package}.")]
    return sorted(set(names))


def test_the_rooms_examples_are_collected():
    found = set(_modules())
    assert {"ramure.gmap.organs.wood", "ramure.gmap.kernel.map3", "ramure.lsys.engine.derive"} <= found


@pytest.mark.parametrize("name", _modules())
def test_docstring_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    if name.startswith("ramure.app.jupyter"):
        pytest.importorskip("ipywidgets")
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} doctest failure(s) in {name}"


def test_front_door_names_resolve():
    for name in ramure.__all__:
        assert getattr(ramure, name) is not None
