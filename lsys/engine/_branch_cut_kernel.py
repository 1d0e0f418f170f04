"""The compiled pass of :mod:`ramure.lsys.engine.branch_cut` (numba), in its own module so that
importing :mod:`ramure.lsys` does not load numba (about 65 MB): only a string with a ``%``
needs it."""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True, nogil=True)
def keep_after_cuts(symbols, cut_id, open_id, close_id, limit):
    """Which modules stay: each ``%`` drops itself and what follows up to its branch's ``]``."""
    n = len(symbols)
    keep = np.ones(n, np.bool_)
    i = 0
    while i < limit:
        if symbols[i] != cut_id:
            i += 1
            continue
        depth = 0
        while i < limit:
            s = symbols[i]
            if s == open_id:
                depth += 1
            elif s == close_id:
                if depth == 0:
                    break
                depth -= 1
            keep[i] = False
            i += 1
    return keep
