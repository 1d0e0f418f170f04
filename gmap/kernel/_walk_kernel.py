"""Compiled face walk for :meth:`ramure.gmap.kernel.operations.Operations.face_walk`.

numba because the numpy walk steps all faces together, a handful of array
calls per two darts, and the wood walks a few faces at a time several
hundred times per growth (sewing, identifying, finding side faces): there
the calls, not the darts, were the cost.  Same walk, same padding.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True)
def face_walks(a0, a1, starts, n, limit):
    """``(walk, lengths, ok)``: each face ``d, a0 d, a1 a0 d, ...`` of ``starts`` as a padded row.

    ``ok`` is False (nothing else meaningful) when a dart id leaves
    ``0..n-1`` or a face does not close within ``limit`` darts; the caller
    then runs the numpy walk, which raises the error.
    """
    k = starts.size
    lengths = np.zeros(k, np.int64)
    longest = 0
    for j in range(k):
        s = starts[j]
        if s < 0 or s >= n:
            return np.zeros((0, 0), np.int64), lengths, False
        cur = s
        step = 0
        while True:
            cur = a0[cur]
            if cur < 0 or cur >= n:
                return np.zeros((0, 0), np.int64), lengths, False
            cur = a1[cur]
            if cur < 0 or cur >= n:
                return np.zeros((0, 0), np.int64), lengths, False
            step += 2
            if cur == s:
                break
            if step > limit:
                return np.zeros((0, 0), np.int64), lengths, False
        lengths[j] = step
        longest = max(longest, step)
    walk = np.full((k, longest), -1, np.int64)
    for j in range(k):
        cur = starts[j]
        for t in range(0, lengths[j], 2):
            walk[j, t] = cur
            cur = a0[cur]
            walk[j, t + 1] = cur
            cur = a1[cur]
    return walk, lengths, True
