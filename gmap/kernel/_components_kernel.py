"""Compiled connected components (union-find) for :mod:`ramure.gmap.kernel.graphs`.

numba because scipy's public ``connected_components`` builds and validates a sparse
matrix first, which costs 2-4x the search itself on the kernel's graphs, and scipy's
compiled search is a private name. Union by the smaller node id with path halving;
components are numbered in the order of their smallest node, as scipy's undirected
search numbers them, so labels are the same whichever path ran.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


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
def _number_into(parent, labels):
    """Write each node's component number into ``labels[:n]``; return the count."""
    count = 0
    for x in range(parent.size):  # a root is its component's smallest node: it comes first
        root = _find(parent, x)
        if root == x:
            labels[x] = count
            count += 1
        else:
            labels[x] = labels[root]
    return count


@njit(cache=True)
def _numbered(parent):
    labels = np.empty(parent.size, np.int32)
    count = _number_into(parent, labels)
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
def involution_components(rows, select, out):
    """Components of the rows ``select`` of ``rows`` (k, n), checked to be involutions of ``0..n-1``.

    Labels (numbered by smallest node, as :func:`rows_components`) go to
    ``out[:n]`` (int32, at least n long: the caller's buffer, room included);
    returns ``(count, ok)``.  ``ok`` is False (``out`` partly written) when a
    link leaves ``0..n-1`` or a row is not an involution: the caller then
    takes the general path.  The check and the unions share one pass over
    the links, in the rows' own integer type (no widened copy), each link
    united once.
    """
    n = rows.shape[1]
    parent = np.empty(n, np.int32)  # half the memory of int64 (a map's dart ids are int32)
    for d in range(n):
        parent[d] = d
    for i in select:
        row = rows[i]
        for d in range(n):
            y = row[d]
            if y < 0 or y >= n or row[y] != d:
                return 0, False
            if y > d:
                _union(parent, d, y)
    return _number_into(parent, out), True


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
    path numbers them.  Returns ``(loc, n_loc, find, count, linked, ok)``:
    ``find`` maps old raw numbers, then the new ones, to today's orbits;
    ``ok`` is False (nothing else meaningful) when a counted row of the new
    darts is not an involution (the numpy path takes strong components then)
    or a new link of an old dart leaves the map.
    """
    m = local.shape[1]
    parent = np.arange(m)
    for i in range(4):
        if in_key[i]:
            row = local[i]
            for x in range(m):
                y = row[x]
                if y >= 0:
                    if row[y] != x:
                        return np.zeros(0, np.int32), 0, np.zeros(0, np.int32), 0, False, False
                    if y > x:  # an involution: each link once
                        _union(parent, x, y)
    loc, n_loc = _numbered(parent)
    nodes = np.arange(count_old + n_loc)
    linked = False
    for i in range(4):
        if in_key[i]:
            row = local[i]
            for x in range(m):
                y = row[x]
                if y < 0:
                    linked = True
                    _union(nodes, count_old + loc[x], find[raw[y + n_old]])
    for e in range(r.size):
        if in_key[r[e]]:
            linked = True
            a = d[e]
            b = alpha[r[e], a]
            if b < 0 or b >= n_old + m:  # a link out of the map: the numpy path deals with it
                return np.zeros(0, np.int32), 0, np.zeros(0, np.int32), 0, False, False
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
    return loc, n_loc, out, count, linked, True


@njit(cache=True)
def _pair_count(p, q):
    """Orbits of the two involutions ``p`` and ``q`` (arrays over the same nodes)."""
    parent = np.arange(p.size)
    for x in range(p.size):  # involutions (checked by the caller): each link once
        if p[x] > x:
            _union(parent, x, p[x])
        if q[x] > x:
            _union(parent, x, q[x])
    count = 0
    for x in range(p.size):
        if _find(parent, x) == x:
            count += 1
    return count


@njit(cache=True)
def boundary_counts(alpha, n):
    """``(vertices, edges, faces, ok)`` of the boundary surface (see ``GMap3.boundary``) in one pass.

    The surface's darts are the alpha3-free ones; its alpha0, alpha1 are the
    restrictions and its alpha2 of ``d`` turns ``alpha2 alpha3`` from
    ``alpha2(d)`` until a free dart.  ``ok`` is False when that does not
    hold up (an id outside the map, a restriction leaving the surface, a
    turn that never ends, a link that is not an involution): the caller then
    builds the surface with numpy.
    """
    local = np.empty(n, np.int32)  # surface number of each free dart (-1: not on the surface)
    m = 0
    row3 = alpha[3]
    for d in range(n):
        if row3[d] == d:
            local[d] = m
            m += 1
        else:
            local[d] = -1
    darts = np.empty(m, np.int64)  # the surface's darts only (not one slot per dart of the map)
    for d in range(n):
        if local[d] >= 0:
            darts[local[d]] = d
    b0 = np.empty(m, np.int64)
    b1 = np.empty(m, np.int64)
    b2 = np.empty(m, np.int64)
    for j in range(m):
        d = darts[j]
        x0, x1, x = alpha[0, d], alpha[1, d], alpha[2, d]
        if x0 < 0 or x0 >= n or x1 < 0 or x1 >= n or x < 0 or x >= n or local[x0] < 0 or local[x1] < 0:
            return 0, 0, 0, False
        b0[j], b1[j] = local[x0], local[x1]
        turns = 0
        while alpha[3, x] != x:
            y = alpha[3, x]
            if y < 0 or y >= n:
                return 0, 0, 0, False
            x = alpha[2, y]
            if x < 0 or x >= n:
                return 0, 0, 0, False
            turns += 1
            if turns > n:
                return 0, 0, 0, False
        b2[j] = local[x]
    for j in range(m):
        if b0[b0[j]] != j or b1[b1[j]] != j or b2[b2[j]] != j:
            return 0, 0, 0, False
    return _pair_count(b1, b2), _pair_count(b0, b2), _pair_count(b0, b1), True
