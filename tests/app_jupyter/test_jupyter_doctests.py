"""Every example in the app.jupyter docstrings runs; importing it pulls in no Qt and no pyplot."""
from __future__ import annotations

import doctest
import importlib
import pkgutil
import subprocess
import sys

import pytest

pytest.importorskip("ipywidgets")

import app.jupyter  # noqa: E402
from jupyter_helpers import ROOT  # noqa: E402

MODULES = ["app.jupyter"] + sorted(f"app.jupyter.{m.name}" for m in pkgutil.iter_modules(app.jupyter.__path__))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, monkeypatch):
    monkeypatch.chdir(ROOT)  # the examples open grammars/...
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"


def test_import_is_light():
    code = ("import sys, app.jupyter\n"
            "print(sorted(m for m in ('PySide6', 'matplotlib.pyplot', 'trame', 'metrics') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"
