"""Every example in the metrics docstrings runs."""
import doctest
import importlib
import pkgutil

import pytest

import metrics

MODULES = ["metrics"] + [f"metrics.{m.name}" for m in pkgutil.iter_modules(metrics.__path__)]


@pytest.mark.parametrize("name", MODULES)
def test_doctests(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"


def test_no_gui_imports():
    import subprocess
    import sys

    code = ("import sys, metrics, metrics.apply, metrics.store\n"
            "metrics.explore('grammars/honda_sympodial.lsys', n=2, n_jobs=1, cache=False)\n"
            "print(sorted(m for m in ('PySide6', 'pyvista', 'pyvistaqt', 'ipywidgets', 'matplotlib.pyplot') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
