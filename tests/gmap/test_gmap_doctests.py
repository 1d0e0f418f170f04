"""Every example in gmap's docstrings runs."""
import doctest
import importlib
import pkgutil

import pytest

import gmap

MODULES = sorted(m.name for m in pkgutil.iter_modules(gmap.__path__, "gmap."))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} doctest failure(s) in {name}"
