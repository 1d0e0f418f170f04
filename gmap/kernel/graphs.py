"""Connected components for the kernel's graphs, safe against scipy's repeated-edge hang.

scipy's *strong* connected components (the fastest variant on the symmetric
graphs of involutions) loop forever on a CSR graph that repeats an edge
(scipy 1.17).  That happens where two involutions send a dart to the same
other dart (a volume sewn to itself).  :func:`orbit_labels` turns such
repeats into self-loops (same components); :func:`components` uses weak
components, which accept repeats.

Speed: the public :func:`scipy.sparse.csgraph.connected_components` builds
and validates a sparse matrix first, which costs 2-4x the search itself on
the kernel's graphs (one fixed number of links per dart).  Both functions
run a compiled union-find (:mod:`ramure.gmap.kernel._components_kernel`, numba;
4-10x faster than scipy's search on 200k darts, same labels: components
numbered by their smallest node) and fall back to the public function for
ids out of range and for strong components of maps that are not involutions.

>>> import numpy as np
>>> rows = np.array([[1, 0, 3, 2], [1, 0, 2, 3]])      # alpha_i(0) == alpha_j(0) == 1: a repeat
>>> labels, count = orbit_labels(rows)
>>> count, bool(labels[0] == labels[1]), bool(labels[2] == labels[3])
(2, True, True)
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse
from scipy.sparse.csgraph import connected_components


#: From this many nodes (darts) on, the compiled passes run even when numba is not loaded yet:
#: loading it costs about 1 s once per process, which a small map (a fruit) never earns back.
COMPILED_FROM = 50_000


def compiled_pays(n: int) -> bool:
    """Whether a compiled pass is worth it for ``n`` nodes: numba already loaded, or a large graph.

    Both paths give the same results (labels numbered alike, sums in the same order).
    """
    return n >= COMPILED_FROM or "numba" in sys.modules


def orbit_labels(
    rows: ArrayLike, involutions: bool | None = None, select: Sequence[int] | None = None, out: np.ndarray | None = None
) -> tuple[np.ndarray, int]:
    """``(labels int32, count)``: orbits of the maps ``rows`` (k, n) (``rows[i][d]`` = image of d).

    When every row is an involution (a map's alpha_i, valid or not, usually
    is) the graph is symmetric, so its out-links serve as in-links and
    scipy's undirected search labels it (about twice as fast as the strong
    search, and blind to repeated links).  Otherwise repeats are turned into
    self-loops and strong components are taken, as scipy requires.
    ``involutions=True``: the caller knows every row is an involution of
    ``0..n-1`` (the check is skipped); None checks.  ``select``: take only
    these rows of ``rows`` (a map's ``alpha`` and a cell's involutions),
    without copying them out first.  ``out``: an int32 buffer of at least n
    entries; the labels are written to ``out[:n]`` and that view is returned
    (the kernel's orbit states keep labels with room to grow: no copy).

    The compiled path checks and unites in one pass over the rows as they
    are (int32 alpha stays int32): no widened copy, no per-row temporaries.
    """
    rows = np.asarray(rows)
    if select is not None:
        select = [int(i) for i in select]
    k, n = (len(select), rows.shape[1]) if select is not None else rows.shape
    if n == 0:
        return np.zeros(0, np.int32), 0
    if compiled_pays(n):
        from ._components_kernel import involution_components

        buffer = np.empty(n, np.int32) if out is None else out
        count, ok = involution_components(rows, np.arange(rows.shape[0]) if select is None else np.array(select), buffer)
        if ok:
            return buffer[:n], int(count)
    if out is not None:
        labels, count = orbit_labels(rows, involutions, select)
        out[:n] = labels
        return out[:n], count
    if select is not None:
        rows = rows[select]
    ar = np.arange(n)
    in_range = bool(involutions) or (rows.min() >= 0 and rows.max() < n)
    if in_range and (involutions or all(np.array_equal(row[row], ar) for row in rows)):
        if not compiled_pays(n):  # symmetric graph: its weak components are the orbits
            return _scipy_components(rows.T.ravel(), np.arange(0, n * k + 1, k), n, "weak")
        from ._components_kernel import rows_components

        labels, count = rows_components(np.ascontiguousarray(rows, np.int64))
        return labels, int(count)
    copied = False
    for i in range(k):
        for j in range(i + 1, k):
            same = (rows[i] == rows[j]) & (rows[j] != ar)
            if same.any():
                if not copied:
                    rows, copied = np.array(rows), True
                rows[j] = np.where(same, ar, rows[j])
    return _scipy_components(rows.T.ravel(), np.arange(0, n * k + 1, k), n, "strong")


def _scipy_components(indices, indptr, n, connection):
    """``(labels int32, count)`` by scipy's public search over a CSR graph of ``n`` nodes."""
    graph = sparse.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))  # float: no bool copy
    count, ids = connected_components(graph, directed=True, connection=connection)
    return ids.astype(np.int32), int(count)


def _csr_arrays(u: np.ndarray, v: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``(indices, indptr)`` of the edges ``u -> v`` in CSR order."""
    # node ids below 2**16 sort as uint16: numpy's radix sort, linear time
    order = np.argsort(u.astype(np.uint16) if size <= 1 << 16 else u, kind="stable")
    indptr = np.zeros(size + 1, np.int64)
    np.cumsum(np.bincount(u, minlength=size), out=indptr[1:])
    return v[order], indptr


def components(u: ArrayLike, v: ArrayLike, size: int) -> tuple[int, np.ndarray]:
    """``(count, labels int32)``: connected components of ``size`` nodes linked by edges ``u - v``."""
    u = np.asarray(u, np.int64)
    v = np.asarray(v, np.int64)
    in_range = not u.size or (min(u.min(), v.min()) >= 0 and max(u.max(), v.max()) < size)
    if in_range and compiled_pays(size):
        from ._components_kernel import edge_components

        labels, count = edge_components(u, v, size)
        return int(count), labels
    indices, indptr = _csr_arrays(u, v, size)
    labels, count = _scipy_components(indices.astype(np.int32), indptr.astype(np.int32), size, "weak")
    return count, labels
