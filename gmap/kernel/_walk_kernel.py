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


@njit(cache=True)
def _grown(a, m, cap):
    """A copy of ``a[:m]`` with room for ``cap`` entries."""
    out = np.empty(cap, a.dtype)
    out[:m] = a[:m]
    return out


@njit(cache=True)
def orbit_members(alpha, key, starts, mark):
    """``(members, labels, status)``: the orbits under ``alpha[key]`` of distinct ``starts``, breadth first.

    ``labels[t]`` is the index in ``starts`` of the orbit holding
    ``members[t]`` (members unsorted).  ``mark`` is a per-dart scratch of
    -1 (int32), left as it was.  ``status`` 0: done; 1: two starts lie in
    one orbit; 2: a link leaves ``0..n-1`` (the caller's numpy walk deals
    with it).  The numpy walk of ``GMap3.orbits_from`` costs a dozen array
    calls per ring of the search; split_edge calls it twice per split.
    """
    n = alpha.shape[1]
    cap = max(16, 8 * starts.size)
    members = np.empty(cap, np.int64)
    labels = np.empty(cap, np.int64)
    m = 0
    status = 0
    for j in range(starts.size):
        s = starts[j]
        if mark[s] >= 0:
            status = 1
            break
        mark[s] = j
        head = m
        if m == cap:  # room for more: double
            cap *= 2
            members, labels = _grown(members, m, cap), _grown(labels, m, cap)
        members[m] = s
        labels[m] = j
        m += 1
        while head < m and status == 0:
            d = members[head]
            head += 1
            for i in key:
                y = alpha[i, d]
                if y < 0 or y >= n:
                    status = 2
                    break
                if mark[y] < 0:
                    mark[y] = j
                    if m == cap:
                        cap *= 2
                        members, labels = _grown(members, m, cap), _grown(labels, m, cap)
                    members[m] = y
                    labels[m] = j
                    m += 1
                elif mark[y] != j:
                    status = 1
        if status != 0:
            break
    for t in range(m):
        mark[members[t]] = -1
    return members[:m], labels[:m], status
