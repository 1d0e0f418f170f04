"""One derivation step's string and history nodes in one pass over the string (numba).

Used by :meth:`ramure.lsys.engine.derive.LSystem._assemble` for long strings; short
ones take the numpy path there, so a small derivation never loads numba.
Both give the same arrays (tests/lsys/test_lsys_derive_assemble.py).
"""

from __future__ import annotations

from ramure.jit import njit


@njit(cache=True, nogil=True)
def assemble(
    string,
    chosen,
    length,
    offset,
    succ_symbol,
    succ_nparams,
    base,
    out,
    symbol,
    nparams,
    parent,
    rule,
    index,
    child_start,
    child_count,
):
    """Write the new string into ``out`` and the new nodes into the tree's arrays.

    ``chosen[i]`` is the rule rewriting position i (-1: kept); rule r's
    successor is ``succ_*[offset[r]:offset[r] + length[r]]``.  New node ids
    are grouped by rule, then by string position: rule r's first new node is
    ``base[r]``.  ``symbol`` ... ``child_count`` are the tree's arrays (node
    ids index them); the rewritten nodes get their children recorded.
    """
    cursor = base.copy()
    o = 0
    for i in range(len(string)):
        r = chosen[i]
        if r < 0:
            out[o] = string[i]
            o += 1
            continue
        node = string[i]
        k = length[r]
        if k == 0:
            child_start[node] = -1
            child_count[node] = 0
            continue
        first = cursor[r]
        cursor[r] += k
        child_start[node] = first
        child_count[node] = k
        f = offset[r]
        for j in range(k):
            v = first + j
            symbol[v] = succ_symbol[f + j]
            nparams[v] = succ_nparams[f + j]
            parent[v] = node
            rule[v] = r
            index[v] = j
            out[o] = v
            o += 1
    return o
