"""Every example in the studies docstrings runs."""
from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import studies

MODULES = sorted(m.name for m in pkgutil.iter_modules(studies.__path__))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(f"studies.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in studies.{name}"
