"""Every example in the studies docstrings runs; the package stays free of GUI imports."""
from __future__ import annotations

import doctest
import importlib
import pkgutil
import subprocess
import sys

import pytest

import studies

MODULES = ["studies"] + sorted(f"studies.{m.name}" for m in pkgutil.iter_modules(studies.__path__))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"


def test_no_gui_imports_even_when_writing_a_report(tmp_path):
    code = ("import sys, studies\n"
            f"studies.write_report(studies.simulate_study(participants=1, grammars=1), {str(tmp_path)!r})\n"
            "print(sorted(m for m in ('PySide6', 'pyvista', 'ipywidgets', 'matplotlib.pyplot') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
