"""Compiled validity pass for :meth:`ramure.gmap.kernel.map3.GMap3.validity_problems`.

numba because the numpy check gathers about forty arrays per call (one per
condition and involution); the wood checks after every growth step, where
that was the largest part of the check.  The conditions and counts are those
of :func:`ramure.gmap.kernel.storage._validity_problems`, dart by dart; an id outside
``0..n-1`` met on the way stops the pass (the caller then runs the full numpy
check, which names that problem).
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit

#: rows of the counts :func:`problem_counts` returns
INVOLUTION, FIXED, PAIR, VOLUME_RANGE, VOLUME_MIX, FACE_MIX, OUT_OF_RANGE = 0, 4, 7, 10, 11, 12, 13
#: the pairs ``(i, j)`` whose product alpha_i alpha_j must be an involution
PAIRS = ((0, 2), (0, 3), (1, 3))


@njit(cache=True)
def mark_reach(alpha, seeds, mask):
    """Set ``mask`` on ``a_i s``, ``a_j a_i s`` and ``a_j a_i a_j s`` of every seed (pairs as :data:`PAIRS`).

    Returns False (mask partly set) when a step leaves ``0..n-1``.
    """
    n = alpha.shape[1]
    for s in seeds:
        for i in range(4):
            x = alpha[i, s]
            if x < 0 or x >= n:
                return False
            mask[x] = True
        for p in range(3):
            i, j = PAIRS[p]
            y = alpha[j, alpha[i, s]]
            if y < 0 or y >= n:
                return False
            mask[y] = True
            z = alpha[i, alpha[j, s]]
            if z < 0 or z >= n:
                return False
            w = alpha[j, z]
            if w < 0 or w >= n:
                return False
            mask[w] = True
    return True


@njit(cache=True)
def problem_counts(alpha, vol, face, n_volumes, darts, every):
    """Darts failing each condition (rows as the module constants), over ``darts`` or all darts (``every``)."""
    n = alpha.shape[1]
    out = np.zeros(14, np.int64)
    m = n if every else darts.size
    for k in range(m):
        d = k if every else darts[k]
        for i in range(4):
            x = alpha[i, d]
            if x < 0 or x >= n:
                out[OUT_OF_RANGE] = 1
                return out
            if alpha[i, x] != d:
                out[INVOLUTION + i] += 1
            if i < 3 and x == d:
                out[FIXED + i] += 1
        for p in range(3):
            i, j = PAIRS[p]
            c = alpha[i, alpha[j, d]]
            if c < 0 or c >= n:
                out[OUT_OF_RANGE] = 1
                return out
            e = alpha[j, c]
            if e < 0 or e >= n:
                out[OUT_OF_RANGE] = 1
                return out
            if alpha[i, e] != d:
                out[PAIR + p] += 1
        v = vol[d]
        if v < 0 or v >= n_volumes:
            out[VOLUME_RANGE] += 1
        if vol[alpha[0, d]] != v or vol[alpha[1, d]] != v or vol[alpha[2, d]] != v:
            out[VOLUME_MIX] += 1
        f = face[d]
        if face[alpha[0, d]] != f or face[alpha[1, d]] != f:
            out[FACE_MIX] += 1
    return out
