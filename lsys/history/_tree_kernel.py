"""Whole-tree passes of :class:`ramure.lsys.history.tree.DerivationTree` in one loop each (numba).

A child's id is always larger than its parent's, so one pass in id order
(depth) or in reverse id order (leaf spans) sees every parent before (after)
its children.  Used for large trees; small ones keep the numpy passes by step.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True, nogil=True)
def depth(parent, alive):
    """Depth of every alive node (roots 0); dead nodes 0."""
    n = len(parent)
    out = np.zeros(n, np.int32)
    for v in range(n):
        p = parent[v]
        if alive[v] and p >= 0:
            out[v] = out[p] + 1
    return out


@njit(cache=True, nogil=True)
def leaf_spans(parent, alive, leaves):
    """(first, last) leaf positions under every node; -1 for nodes without leaves."""
    n = len(parent)
    first = np.full(n, np.iinfo(np.int64).max, np.int64)
    last = np.full(n, -1, np.int64)
    for i in range(len(leaves)):
        first[leaves[i]] = i
        last[leaves[i]] = i
    for v in range(n - 1, -1, -1):
        p = parent[v]
        if alive[v] and p >= 0:
            if first[v] < first[p]:
                first[p] = first[v]
            if last[v] > last[p]:
                last[p] = last[v]
    for v in range(n):
        if last[v] < 0:
            first[v] = -1
    return first, last


@njit(cache=True, nogil=True)
def leaf_weight_prefix(depth, leaves):
    """Prefix sums of ``2**depth`` over the string (int64; the caller checks it cannot overflow)."""
    out = np.zeros(len(leaves) + 1, np.int64)
    total = np.int64(0)
    for i in range(len(leaves)):
        total += np.int64(1) << np.int64(depth[leaves[i]])
        out[i + 1] = total
    return out


@njit(cache=True, nogil=True)
def _first_at_least(sorted_ids, x):
    """The first position in ``sorted_ids`` whose id is at least ``x`` (a binary search written
    out: numba's ``np.searchsorted`` costs about 11 MB more each time a process loads it)."""
    lo, hi = 0, len(sorted_ids)
    while lo < hi:
        mid = (lo + hi) // 2
        if sorted_ids[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def _sum_entries(first, stop, q, child_start, child_count, alive, flag, inner, count, weight):
    """``count[i]`` and ``weight[i]`` for the entries ``i`` from ``stop - 1`` down to ``first``
    (node ``inner[i]``), from each node's children that share its liveness (all of them when it
    is dead): a childless child counts its flag, an inner one its entry.  The entries are found
    by walking ``inner`` from position ``q`` (a derivation's nodes have their children in id
    order, so each walk is a few steps).  False, when a child with children has no entry (the
    sums are then made again)."""
    n = len(inner)
    for i in range(stop - 1, first - 1, -1):
        v = inner[i]
        dead = not alive[v]
        c = 0
        w = np.int64(0)
        start = child_start[v]
        for u in range(start, start + child_count[v]):
            if dead or alive[u]:
                if child_count[u] == 0:
                    f = flag[u]
                    c += f
                    w += f
                else:
                    while q > 0 and inner[q - 1] >= u:
                        q -= 1
                    while q < n and inner[q] < u:
                        q += 1
                    if q == n or inner[q] != u:
                        return False
                    c += count[q]
                    w += weight[q]
        count[i] = c
        weight[i] = 2 * w
    return True


@njit(cache=True, nogil=True)
def leaf_sums(child_start, child_count, alive, lo, hi, flag, inner, count, weight):
    """Current-string leaves below nodes ``lo .. hi - 1`` (``count``) and ``sum(2**(depth(leaf) -
    depth(v)))`` over them (``weight``), from their children, in reverse id order (children have
    larger ids), for the nodes with children: their entries are the last ones of ``inner``
    (ascending ids).  Childless nodes hold their in-string flags already; a node sums the
    children that share its liveness (an alive node its alive children, a dead one as if it were
    alive).  False when an entry is missing (see :func:`_sum_entries`)."""
    n = len(inner)
    return _sum_entries(_first_at_least(inner, lo), n, n, child_start, child_count, alive, flag, inner, count, weight)


@njit(cache=True, nogil=True)
def resum(nodes, child_start, child_count, alive, flag, inner, count, weight):
    """:func:`leaf_sums` again for ``nodes`` (with children, in decreasing id order, so children
    come first), each from its children.  False when an entry is missing."""
    for v in nodes:
        i = _first_at_least(inner, v)
        if i == len(inner) or inner[i] != v:
            return False
        q = _first_at_least(inner, child_start[v])
        if not _sum_entries(i, i + 1, q, child_start, child_count, alive, flag, inner, count, weight):
            return False
    return True
