"""The cut symbol ``%``: after each derivation step, ``%`` and the rest of its branch leave the string.

As in cpfg and L-Py: a ``%`` removes itself and every module after it up to
(not including) the ``]`` that closes the branch it stands in; at the top
level (outside any branch) it removes the rest of the string.  The cut runs
after each production step (after decomposition rules, if any) and on the
axiom, so the next step never sees the cut modules.  The derivation history
keeps them as nodes that are simply no longer in the string (like modules
an empty successor deleted): node ids elsewhere do not change, regrowing
and undo work as before.

In a regrow (:mod:`ramure.lsys.regeneration.regen`) the cut stops at the end of the
regrown part: the modules after it belong to other parts of the history and
are not removed by re-deriving this one.

>>> from ramure.lsys import LSystem
>>> LSystem.from_text("n: 1\\nw: A\\np:\\n A -> F[+F%F[-F]F]F%FF").derive().to_string()
'F[+F]F'
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .derive import LSystem
    from ..history.tree import DerivationTree

CUT_SYMBOL = "%"


def cut_string(lsys: LSystem, tree: DerivationTree, string: np.ndarray, frozen: np.ndarray | None = None) -> np.ndarray:
    """``string`` (node ids) without the parts ``%`` cuts; ``frozen`` marks the input positions
    of a regrow's read-only context (its trailing part is never cut)."""
    if CUT_SYMBOL not in lsys.symbols or not len(string):
        return string
    cut_id = lsys.symbols.index(CUT_SYMBOL)
    symbols = tree.symbol[string]
    if not (symbols == cut_id).any():
        return string
    tail = 0
    if frozen is not None and len(frozen) and frozen[-1]:
        tail = len(frozen) - int(np.flatnonzero(~frozen)[-1]) - 1 if (~frozen).any() else len(frozen)
    open_id, close_id = (-1 if b is None else b for b in lsys.bracket_ids)
    from ._branch_cut_kernel import keep_after_cuts  # numba loads on the first '%' cut, not on import

    keep = keep_after_cuts(symbols.astype(np.int64), cut_id, open_id, close_id, len(string) - tail)
    return string[keep]
