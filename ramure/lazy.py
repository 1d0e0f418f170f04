"""Names a package loads on first use (a PEP 562 module ``__getattr__``).

``import ramure`` and ``import ramure.studies`` stay cheap this way: ``ramure study anova``
loads only the ANOVA module, not the report's matplotlib, metrics and scipy.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_loader(package: str, table: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(load, names)`` for ``package``: ``load(name)`` imports module ``table[name]`` (absolute,
    or relative to ``package``), keeps its attribute ``name`` in the package and returns it;
    ``names()`` lists the package's names, loaded or not.  Unknown names raise AttributeError."""
    namespace = vars(sys.modules[package])

    def load(name: str) -> Any:
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value

    def names() -> list[str]:
        return sorted(set(namespace) | set(table))

    return load, names
