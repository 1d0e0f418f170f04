"""Ramure: explore procedural plants.

The front door for scripts; each name is loaded on first use, so ``import ramure``
stays light (no pyvista, no Qt).

>>> import ramure
>>> d = ramure.derive("honda_sympodial", n=4)
>>> d.to_string()[:6]
'!(10)F'
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

from ramure.errors import DerivationError, GrammarError, RamureError, ValueRefused
from ramure.lazy import lazy_loader

if TYPE_CHECKING:
    from ramure.lsys import Derivation, LSystem

__version__ = "0.1.0"

# name -> the module that defines it, imported on first use (ramure.lazy).
_LAZY = {
    "LSystem": "ramure.lsys",
    "Derivation": "ramure.lsys",
    "Session": "ramure.lsys.regeneration.regen",
    "regenerate": "ramure.lsys.regeneration.regen",
    "select_roots": "ramure.lsys.regeneration.mincut",
    "leaves_where": "ramure.lsys.regeneration.select",
    "apply_qualifier": "ramure.metrics.apply",
    "plant_metrics": "ramure.metrics",
    "plant_obb": "ramure.metrics",
    "explore": "ramure.metrics",
    "VariantSweep": "ramure.metrics",
    "DeltaPCA": "ramure.metrics",
    "GMap3": "ramure.gmap",
    "build_fruit": "ramure.gmap.organs.fruit",
    "Study": "ramure.studies",
}

__all__ = ["DerivationError", "GrammarError", "RamureError", "ValueRefused", "derive", "load", *sorted(_LAZY)]


def load(grammar: str | os.PathLike) -> LSystem:
    """An :class:`~ramure.lsys.LSystem` from a file path or a shipped grammar's name."""
    from ramure.lsys import LSystem

    return LSystem.from_file(grammar)


def derive(
    grammar: str | os.PathLike, n: int | None = None, seed: int = 0, constants: Mapping[str, float] | None = None
) -> Derivation:
    """Load ``grammar`` (path or shipped name) and derive it; ``n`` defaults to the grammar's."""
    return load(grammar).derive(n=n, seed=seed, constants=constants)


_load, _names = lazy_loader(__name__, _LAZY)


def __getattr__(name):
    return _load(name)


def __dir__():
    return _names()
