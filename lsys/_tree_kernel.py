"""Whole-tree passes of :class:`ramure.lsys.tree.DerivationTree` in one loop each (numba).

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
def _sum_children(v, start, k, alive, count, weight):
    """``count[v]`` and ``weight[v]`` from children ``start .. start + k - 1`` that share ``v``'s
    liveness (all of them when ``v`` is dead)."""
    c = 0
    w = np.int64(0)
    for u in range(start, start + k):
        if alive[u] or not alive[v]:
            c += count[u]
            w += weight[u]
    count[v] = c
    weight[v] = 2 * w


@njit(cache=True, nogil=True)
def leaf_sums(child_start, child_count, alive, flag, lo, hi, count, weight):
    """Current-string leaves below nodes ``lo .. hi - 1`` (``count``) and ``sum(2**(depth(leaf) -
    depth(v)))`` over them (``weight``), from their children, in reverse id order (children have
    larger ids).  A childless node takes its in-string flag ``flag[v - lo]``; a node sums the children
    that share its liveness (an alive node its alive children, a dead one as if it were alive)."""
    for v in range(hi - 1, lo - 1, -1):
        k = child_count[v]
        if k == 0:
            count[v] = flag[v - lo]
            weight[v] = flag[v - lo]
            continue
        _sum_children(v, child_start[v], k, alive, count, weight)


@njit(cache=True, nogil=True)
def resum(nodes, child_start, child_count, alive, count, weight):
    """:func:`leaf_sums` again for ``nodes`` (in decreasing id order, so children come first),
    each from its children; childless nodes keep theirs."""
    for v in nodes:
        k = child_count[v]
        if k == 0:
            continue
        _sum_children(v, child_start[v], k, alive, count, weight)
