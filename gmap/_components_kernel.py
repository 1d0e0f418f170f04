"""Compiled connected components (union-find) for :mod:`ramure.gmap.graphs`.

numba because scipy's public ``connected_components`` builds and validates a sparse
matrix first, which costs 2-4x the search itself on the kernel's graphs, and scipy's
compiled search is a private name. Union by the smaller node id with path halving;
components are numbered in the order of their smallest node, as scipy's undirected
search numbers them, so labels are the same whichever path ran.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True)
def _union(parent, a, b):
    a = _find(parent, a)
    b = _find(parent, b)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b


@njit(cache=True)
def _numbered(parent):
    n = parent.size
    labels = np.empty(n, np.int32)
    count = 0
    for x in range(n):  # a root is its component's smallest node: it comes first
        root = _find(parent, x)
        if root == x:
            labels[x] = count
            count += 1
        else:
            labels[x] = labels[root]
    return labels, count


@njit(cache=True)
def rows_components(rows):
    """Components of the graph linking each node ``d`` to ``rows[i, d]`` for every row ``i``."""
    k, n = rows.shape
    parent = np.arange(n)
    for i in range(k):
        for d in range(n):
            _union(parent, d, rows[i, d])
    return _numbered(parent)


@njit(cache=True)
def edge_components(u, v, size):
    """Components of ``size`` nodes linked by the edges ``u[e] - v[e]``."""
    parent = np.arange(size)
    for e in range(u.size):
        _union(parent, u[e], v[e])
    return _numbered(parent)


@njit(cache=True)
def grown_orbits(local, in_key, n_old, raw, find, count_old, r, d, alpha):
    """One orbit labelling updated by growth, in one pass (see ``GMap3._grown_orbits``, the numpy path).

    ``local`` (4, m): alpha_i of the m new darts in local numbers, an older
    dart ``e`` as ``e - n_old`` (negative); rows with ``in_key[i]`` count.
    ``raw``, ``find``, ``count_old``: the old two-level labelling; ``r, d``:
    old darts ``d`` whose alpha_r is new.  The new darts are labelled among
    themselves (``loc``, numbered by smallest dart), then old orbits and new
    ones (nodes ``count_old + loc``) are merged along the links between them,
    a merged orbit taking its smallest node's place; numbering as the numpy
    path numbers them.  Returns ``(loc, n_loc, find, count, linked)``:
    ``find`` maps old raw numbers, then the new ones, to today's orbits.
    """
    m = local.shape[1]
    parent = np.arange(m)
    for i in range(4):
        if in_key[i]:
            for x in range(m):
                y = local[i, x]
                if y >= 0:
                    _union(parent, x, y)
    loc, n_loc = _numbered(parent)
    nodes = np.arange(count_old + n_loc)
    linked = False
    for i in range(4):
        if in_key[i]:
            for x in range(m):
                y = local[i, x]
                if y < 0:
                    linked = True
                    _union(nodes, count_old + loc[x], find[raw[y + n_old]])
    for e in range(r.size):
        if in_key[r[e]]:
            linked = True
            a = d[e]
            b = alpha[r[e], a]
            nb = find[raw[b]] if b < n_old else count_old + loc[b - n_old]
            _union(nodes, find[raw[a]], nb)
    n_raw = find.size
    out = np.empty(n_raw + n_loc, np.int32)
    if linked:
        relabel, count = _numbered(nodes)
        for k in range(n_raw):
            out[k] = relabel[find[k]]
        for j in range(n_loc):
            out[n_raw + j] = relabel[count_old + j]
    else:
        count = count_old + n_loc
        out[:n_raw] = find
        for j in range(n_loc):
            out[n_raw + j] = count_old + j
    return loc, n_loc, out, count, linked
