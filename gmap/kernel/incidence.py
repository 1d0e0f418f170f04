"""Vertex editing, local cell queries and incidence as scipy sparse arrays.

Local queries walk only the orbits they ask about (breadth-first over the
involutions, cost proportional to the orbit), so an operation that needs
the cells around a few darts does not relabel the whole map.  Whole-map
tables (incidence, adjacency) are built in one vectorised pass from the
cached cell labels.

>>> from ramure.gmap import GMap3
>>> gm = GMap3(); _ = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
>>> gm.sew3(gm.face_of(0, "E"), gm.face_of(1, "O"))
>>> volume_adjacency(gm, "face").toarray().tolist()
[[0, 1], [1, 0]]
>>> vertex_volumes(gm).sum(axis=1).tolist()[:4]        # shared face vertices touch both cubes
[1, 1, 1, 1]
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.storage import CELL_INVOLUTIONS

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3


def cell_darts(gm: GMap3, dart: int, dim: int) -> np.ndarray:
    """Sorted darts of the ``dim``-cell (0 vertex .. 3 volume) holding ``dart``; orbit-proportional."""
    if dim not in CELL_INVOLUTIONS:
        raise GMapError(f"cell dimension must be 0, 1, 2 or 3, got {dim!r}")
    return gm.orbit(dart, CELL_INVOLUTIONS[dim])


def cells_around(gm: GMap3, darts: ArrayLike, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """``(members, which)``: the ``dim``-cells of several darts at once (one per distinct cell).

    Darts lying in the same cell are answered once, by the first of them;
    ``which`` gives the index in ``darts`` of the query that owns each member.
    """
    darts = np.asarray(gm.check_darts(darts))
    key = CELL_INVOLUTIONS[dim]
    members, labels = gm.orbits_from(darts, key, strict=False)
    return members, labels


def vertex_volumes_local(gm: GMap3, dart: int) -> np.ndarray:
    """Volume ids around the vertex of ``dart`` (orbit-proportional)."""
    return np.unique(gm.dart_volume[cell_darts(gm, dart, 0)])


def move_vertices(gm: GMap3, darts: ArrayLike, positions: ArrayLike) -> None:
    """Move the vertices of ``darts`` to ``positions`` (k, 3): manual embedding of those vertices.

    Every dart of each vertex gets the new point and the new default
    corner, so a later :meth:`GMap3.embed` keeps them there.  Cost is
    proportional to the vertices' orbits.  Two darts of one vertex or a
    non-finite position are refused.
    """
    darts = np.asarray(gm.check_darts(darts))
    pos = np.asarray(positions, float).reshape(-1, 3)
    if len(pos) != len(darts):
        raise GMapError(f"move_vertices needs one position per dart, got {len(pos)} for {len(darts)}")
    if not np.all(np.isfinite(pos)):
        raise GMapError("vertex positions must be finite")
    members, labels = gm.orbits_from(darts, CELL_INVOLUTIONS[0], strict=True)
    gm.points[members] = pos[labels]
    gm.corners[members] = pos[labels]
    gm.mark_changed()


def vertex_volumes(gm: GMap3) -> sparse.csr_array:
    """Vertex x volume incidence, a ``scipy.sparse.csr_array`` of 0/1 (int8)."""
    vid, nv = gm.cells(0)
    vol = gm.dart_volume.astype(np.int64)
    key = np.unique(vid.astype(np.int64) * max(gm.n_volumes, 1) + vol)
    rows, cols = key // max(gm.n_volumes, 1), key % max(gm.n_volumes, 1)
    return sparse.csr_array((np.ones(len(key), np.int8), (rows, cols)), shape=(nv, gm.n_volumes))


def volume_adjacency(gm: GMap3, by: str = "face") -> sparse.csr_array:
    """Volume x volume adjacency (``csr_array`` of 0/1, no diagonal): sharing a face or a vertex."""
    n = gm.n_volumes
    if by == "face":
        d = np.flatnonzero(gm.alpha[3] != np.arange(gm.n_darts))
        a = gm.dart_volume[d].astype(np.int64)
        b = gm.dart_volume[gm.alpha[3][d]].astype(np.int64)
    elif by == "vertex":
        inc = vertex_volumes(gm).astype(np.int32)
        co = (inc.T @ inc).tocoo()
        a, b = co.row.astype(np.int64), co.col.astype(np.int64)
    else:
        raise GMapError(f"adjacency is by 'face' or 'vertex', got {by!r}")
    keep = a != b
    key = np.unique(a[keep] * max(n, 1) + b[keep])
    return sparse.csr_array((np.ones(len(key), np.int8), (key // max(n, 1), key % max(n, 1))), shape=(n, n))
