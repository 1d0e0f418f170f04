"""L-systems with derivation history: grammar language, derivation, turtle, regeneration.

The package is split into rooms by purpose, each a sub-package whose docstring says what it
owns and may import (``tests/test_layering.py``, ``LSYS_ROOMS``, enforces it), from the
bottom floor up: :mod:`~ramure.lsys.architecture` (AMAP, MTG, seasons) and
:mod:`~ramure.lsys.history` (the derivation-history tree); :mod:`~ramure.lsys.interpretation`
(the turtle, polygons, surfaces, meshes); :mod:`~ramure.lsys.language` (the ``.lsys`` and
cpfg grammars); :mod:`~ramure.lsys.engine` (derivation); :mod:`~ramure.lsys.regeneration`
(minimum cut, regrowth) and :mod:`~ramure.lsys.readers` (L-Py).  :mod:`ramure.lsys.errors` and
:mod:`ramure.lsys.expr` (the expression language) stand below them all.  The names below are
the package's front door.

>>> from ramure.lsys import LSystem
>>> d = LSystem.from_text("n: 2\\nw: A(1)\\np:\\n A(x) -> A(x+1)B(x+1)C(1)\\n B(y) -> B(y+3)").derive()
>>> d.to_string()
'A(3)B(3)C(1)B(5)C(1)'
"""

from .regeneration.mincut import CutResult, select_roots
from .engine.derive import Derivation, LSystem
from .errors import DerivationError, GrammarError, RamureError, ValueRefused
from .language.grammar import Grammar, parse_grammar
from .readers.lpy import LpyLSystem  # registers the .lpy reader
from .regeneration.regen import RegenResult, Session, regenerate
from .regeneration.select import leaves_where
from .history.tree import DerivationTree
from .interpretation.turtle import Organs, Skeleton

__all__ = [
    "CutResult",
    "Derivation",
    "DerivationError",
    "DerivationTree",
    "Grammar",
    "GrammarError",
    "LSystem",
    "LpyLSystem",
    "Organs",
    "RamureError",
    "RegenResult",
    "Session",
    "Skeleton",
    "ValueRefused",
    "leaves_where",
    "parse_grammar",
    "regenerate",
    "load_kernels",
    "select_roots",
]

#: The compiled kernels of this package (numba), loaded on first use only.
KERNEL_MODULES = (
    "engine._branch_cut_kernel",
    "engine._context_kernel",
    "engine._derive_kernel",
    "interpretation._polygon_kernel",
    "history._tree_kernel",
    "interpretation._turtle_kernel",
)


def load_kernels() -> None:
    """Load numba and the compiled kernels' modules now (about 0.2 s in a new process).

    A small plant is derived and drawn without them (numpy and plain-Python passes give the
    same arrays); once numba is loaded, the compiled passes take over from a few thousand
    modules.  A long-lived front end calls this in a background thread before the edits
    whose kernels it wants warm (:func:`ramure.app.model.warm_up_edits`)."""
    import importlib

    for name in KERNEL_MODULES:
        importlib.import_module(f"{__name__}.{name}")
