"""Face-level operators of the 3Gmap L-systems: add a volume on a free face, identify two faces.

These work on any :class:`~ramure.gmap.kernel.map3.GMap3` through its public API.
Faces are found by label (the per-dart ``face`` column), never by template
offsets, and two faces are identified through the edge they share, never by
coordinates (spec decisions 4 and 5).

*Shared edge.*  On the boundary of a manifold solid, a free dart ``a`` has
one boundary neighbour across its edge: walk ``x = alpha2(a)`` and, while
``x`` is sewn, ``x = alpha2(alpha3(x))``.  The dart reached lies on the same
edge and at the same vertex as ``a``, in the next free face around that edge
(this is the alpha2 of :meth:`GMap3.boundary`).  Two free faces share an edge
exactly when some dart of one has its boundary neighbour in the other; that
pair gives the start darts and the rotation sense of the identification.

>>> from ramure.gmap import GMap3
>>> gm = GMap3()
>>> a, b = gm.add_prisms(4, 2)
>>> gm.sew3(gm.prism_face(a, 4, "C2"), gm.prism_face(b, 4, "C4", 1))
>>> pairs = shared_edge_pairs(gm, face_darts(gm, [0], "C3"), face_darts(gm, [1], "C3"))
>>> len(pairs[0])      # the two C3 faces meet along one edge: its two darts pair up
2
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import prism as _prism

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3


def boundary_neighbour(gm: GMap3, darts: ArrayLike) -> np.ndarray:
    """For alpha3-free ``darts``, the free dart across their edge (same edge, same vertex).

    The kernel's :func:`ramure.gmap.kernel.identify.boundary_neighbour`.
    """
    from ramure.gmap.kernel.identify import boundary_neighbour as kernel_neighbour

    return np.asarray(kernel_neighbour(gm, np.asarray(darts, np.int64)), np.int64)


def face_starts(gm: GMap3, volumes: ArrayLike, label: str) -> np.ndarray:
    """One dart per face ``label`` ('O', 'E', 'Ck') of each volume (-1 when it has none).

    The dart is the face's forward dart at its corner 0 when the face still
    has it, else its smallest dart; works on faces that were split or sewn.
    """
    volumes = np.asarray(volumes, np.int64)
    code = _prism.face_label_code(label)
    data = gm.dart_data
    mask = (data["face"] == code) & np.isin(gm.dart_volume, volumes)
    darts = np.flatnonzero(mask)
    vol = gm.dart_volume[darts]
    rank = ~((data["fcorner"][darts] == 0) & data["forward"][darts])  # preferred first
    order = np.lexsort((darts, rank, vol))
    darts, vol = darts[order], vol[order]
    first = np.ones(len(darts), bool)
    first[1:] = vol[1:] != vol[:-1]
    out = np.full(len(volumes), -1, np.int64)
    sorter = np.argsort(volumes)
    pos = np.searchsorted(volumes, vol[first], sorter=sorter)
    out[sorter[pos]] = darts[first]
    return out


def face_darts(gm: GMap3, volumes: ArrayLike, label: str) -> np.ndarray:
    """All darts of face ``label`` of each volume, as one sorted array."""
    code = _prism.face_label_code(label)
    return np.flatnonzero((gm.dart_data["face"] == code) & np.isin(gm.dart_volume, np.asarray(volumes)))


def face_is_free(gm: GMap3, starts: ArrayLike) -> np.ndarray:
    """True where the whole face ``<a0,a1>`` of each start dart is alpha3-free."""
    walk, _ = gm.face_walk(starts)
    d = np.where(walk >= 0, walk, 0)
    free = (gm.alpha[3][d] == d) | (walk < 0)
    return free.all(axis=1)


def shared_edge_pairs(gm: GMap3, darts_a: ArrayLike, darts_b: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Pairs ``(a, b)``: ``a`` in ``darts_a``, ``b`` in ``darts_b``, same edge and vertex, both free.

    ``b`` is ``a``'s boundary neighbour (see the module docstring).
    """
    darts_a = np.asarray(darts_a, np.int64)
    alpha = gm.alpha
    a = darts_a[alpha[3][darts_a] == darts_a]
    if not a.size:
        return a, a
    b = boundary_neighbour(gm, a)
    keep = np.isin(b, np.asarray(darts_b, np.int64)) & (gm.dart_volume[b] != gm.dart_volume[a])
    return a[keep], b[keep]


def identify(gm: GMap3, a: ArrayLike, b: ArrayLike) -> None:
    """Identify the free faces of darts ``a`` and ``b`` through the edge they share.

    The kernel's :meth:`GMap3.identify` (start darts and rotation sense from
    the shared edge, degree mismatches split along runs; refusals name both
    faces and leave the map unchanged).
    """
    gm.identify(np.atleast_1d(np.asarray(a, np.int64)), np.atleast_1d(np.asarray(b, np.int64)))


def sew_pairs(gm: GMap3, a: np.ndarray, b: np.ndarray) -> None:
    """``sew3`` many face pairs: equal degrees in one batch, the others one by one."""
    if not len(a):
        return
    _, la = gm.face_walk(a)
    _, lb = gm.face_walk(b)
    same = la == lb
    if same.any():
        gm.sew3(a[same], b[same])
    for x, y in zip(a[~same], b[~same]):  # degree mismatch: edge splits, one pair at a time
        gm.sew3([int(x)], [int(y)])
