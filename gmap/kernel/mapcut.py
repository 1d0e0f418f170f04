"""Cut a 3-G-map by a plane and keep one side as a new 3-G-map (so a plank can be cut again).

The thesis's simplified co-refinement (section 2.5.1), vectorised:

1. vertices get the signed distance ``s = (p - origin) . n`` of their
   embedded position; ``|s|`` below ``1e-12`` times the model's size counts
   as on the plane (INOUT);
2. every edge from ``s < 0`` to ``s > 0`` is split at the intersection
   (one batch :meth:`GMap3.split_edge`, per-dart attributes interpolated);
3. every face with vertices on both sides is split between its two
   on-plane vertices (one batch face split, both sides of sewn faces);
4. every volume with vertices on both sides is split along the loop of
   on-plane edges between its kept and dropped faces; the two new faces
   get the label ``X`` (a cut face, code -2) and are sewn to each other;
5. volumes with a vertex in front of the plane (``s > 0``, the side the
   normal points to) are removed, which leaves the cut faces alpha3-free.

The result keeps behind the plane, as :func:`ramure.gmap.kernel.cut.plane_cut` does,
and switches to *manual* embedding (thesis): every dart's default corner is
its embedded point and no dart keeps a template corner, so embedding or
re-framing the result changes nothing.  Faces that cross the plane more than
twice (strongly non-convex after embedding) are refused; so are a zero normal
and a plane that does not cross the model (it would keep all or nothing).

The kept volume equals a VTK clip's only where the faces are planar; see
:func:`planar_faces` for a copy of any map on which it is exact.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.kernel.graphs import components, orbit_labels
from ramure.gmap.kernel.prism import FACE_CUT

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

#: Plane normals by axis name.
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def unit_normal(normal: str | ArrayLike) -> np.ndarray:
    """A plane normal as a unit 3-vector: ``'x'``, ``'y'``, ``'z'`` or any non-zero 3-vector.

    >>> unit_normal((0, 0, 2)).tolist()
    [0.0, 0.0, 1.0]
    """
    if isinstance(normal, str):
        if normal.lower() not in AXES:
            raise ValueRefused(f"normal must be x, y, z or a 3-vector, got {normal!r}")
        normal = AXES[normal.lower()]
    n = np.asarray(normal, float).reshape(3)
    length = np.linalg.norm(n)
    if length == 0:
        raise ValueRefused("the cut plane's normal must not be zero")
    return n / length


def cut_map(gm: GMap3, normal: str | ArrayLike, origin: ArrayLike | None = None) -> GMap3:
    """Return a new map: the part of ``gm`` behind the plane (``(p - origin) · normal <= 0``).

    ``normal`` is a 3-vector or ``'x'``, ``'y'``, ``'z'``; ``origin``
    defaults to the centre of the model's bounding box.  ``gm`` is not
    changed.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4, sizes=[[2.0, 1.0, 1.0]]); _ = gm.embed()
    >>> half = cut_map(gm, "x", (0.5, 0, 0))
    >>> half.counts()["volumes"], half.is_valid(), round(float(half.points[:, 0].max()), 12)
    (1, True, 0.5)
    """
    n = unit_normal(normal)
    if gm.n_darts == 0:
        raise ValueRefused("cannot cut an empty map")
    out = gm.copy()
    vid, pos = out.vertex_positions()
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    o = 0.5 * (lo + hi) if origin is None else np.asarray(origin, float).reshape(3)
    if not np.all(np.isfinite(o)):
        raise ValueRefused("the cut plane's origin must be finite")
    tol = 1e-12 * max(float(np.max(hi - lo)), 1.0)
    s = (pos - o) @ n
    s[np.abs(s) <= tol] = 0.0
    if s.max() <= 0 or s.min() >= 0:
        side = "behind" if s.max() <= 0 else "in front of"
        raise ValueRefused(f"the cut plane misses the model (the whole model lies {side} it): nothing to cut")
    sd = s[vid]
    vol = out.dart_volume
    out.reserve(out.n_darts + 4 * max(int(np.count_nonzero((sd < 0) & (sd[out.alpha[0]] > 0))), 1) * 6)
    crossing = (np.bincount(vol, sd < 0, minlength=out.n_volumes) > 0) & (np.bincount(vol, sd > 0, minlength=out.n_volumes) > 0)
    sd = _split_crossing_edges(out, sd, vid)
    for _ in range(8):  # a face crossing the plane 2k times is split k times
        sd, more = _split_crossing_faces(out, sd, crossing)
        if not more:
            break
    else:
        raise GMapError("cut_map: a face crosses the plane too many times; subdivide the model or move the plane")
    sd = split_crossing_volumes(out, sd, crossing)
    front = np.bincount(out.dart_volume, sd > 0, minlength=out.n_volumes) > 0
    out.remove_volumes(np.flatnonzero(front))
    _manual(out)
    out.meta = dict(gm.meta, cut=list(out.meta.get("cut", [])) + [{"normal": n.tolist(), "origin": o.tolist()}])
    return out


def planar_faces(gm: GMap3) -> GMap3:
    """A copy of ``gm`` whose faces are all triangles (so planar): faces split along diagonals.

    A warped face (a quad whose corners were averaged by the embedding) has
    no unique area or volume: the kernel's measure fans it from its
    centroid, VTK splits a hexahedron's faces its own way, so a map cut and
    a VTK clip of warped cells agree only up to the warp.  On this copy
    every face is a triangle, the solid is a well-defined polyhedron, and
    :func:`cut_map` (edge splits at the plane, straight splits inside planar
    faces) keeps exactly the part behind the plane: it agrees with a VTK
    clip of the same triangles' tetrahedra to round-off.  Each round
    splits every face of more than 3 corners between a vertex and the
    one half-way round (``log2`` rounds for a k-gon); no vertex moves or is
    added, so the vertex positions and the volume's topology are kept.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4); _ = gm.embed()
    >>> tri = planar_faces(gm)
    >>> tri.counts()["faces"], tri.is_valid(), tri.euler_characteristic()
    (12, True, 1)
    """
    out = gm.copy()
    for _ in range(64):
        vid, pos = out.vertex_positions()
        face, count = out.cells(2)
        first = np.full(count, -1, np.int64)
        first[face[::-1]] = np.arange(out.n_darts)[::-1]
        walk, length = out.face_walk(first)
        degree = length // 2
        big = np.flatnonzero(degree > 3)
        if not big.size:
            return out
        start, step = _diagonals(pos, vid, walk[big], degree[big])
        out.split_faces(walk[big, 2 * start], step)
    raise GMapError("planar_faces: a face did not become triangles in 64 rounds")


def _diagonals(pos, vid, walk, degree):
    """One diagonal per face, ``(start corner, corners on)``: corner 0 to the one half-way round, or,
    where that diagonal is not inside the face (a face curved in round a knot), the diagonal that
    cuts off the face's first ear (:func:`ramure.gmap.kernel.measure.face_triangles`)."""
    from ramure.gmap.kernel.measure import face_triangles

    start = np.zeros(len(degree), np.int64)
    step = degree // 2
    corners = walk[:, 0::2]
    ok = corners >= 0
    p = np.where(ok[:, :, None], pos[vid[np.maximum(corners, 0)]], 0.0)
    k = np.arange(corners.shape[1])[None, :]
    nxt = np.where(k + 1 >= degree[:, None], 0, k + 1)
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    normal = np.where(ok[:, :, None], np.cross(p, q), 0.0).sum(axis=1)
    rows = np.arange(len(degree))
    a, b = p[:, 0], p[rows, step]
    side = np.ones(len(degree), bool)  # both halves turn the face's way: the diagonal lies inside
    edges = np.where(ok[:, :, None], np.cross(p, q), 0.0)
    first_half = k < step[:, None]  # edges 0 .. step-1, closed by the diagonal back to corner 0
    for half, closing in ((first_half, np.cross(b, a)), (~first_half & ok, np.cross(a, b))):
        part = np.where(half[:, :, None], edges, 0.0).sum(axis=1) + closing
        side &= np.einsum("fi,fi->f", part, normal) > 0
    for f in np.flatnonzero(~side):
        cyc = vid[corners[f, : degree[f]]]
        i, _, j = sorted(face_triangles(pos, cyc)[0].tolist())
        if j - i == 2:
            start[f], step[f] = i, 2
        else:  # the ear wraps round corner 0
            start[f], step[f] = j, 2
    return start, step


def pad_new_darts(sd: np.ndarray, gm: GMap3) -> np.ndarray:
    """``sd`` extended with zeros for the darts made since (every new dart lies on the plane)."""
    return np.concatenate([sd, np.zeros(gm.n_darts - len(sd))])


def _split_crossing_edges(gm, sd, vid):
    """Split every edge from s < 0 to s > 0 at the plane; one dart per edge (by its edge orbit: two
    edges may join the same two vertices, e.g. a diagonal along cut points that lie on a line)."""
    a0 = gm.alpha[0]
    d = np.flatnonzero((sd < 0) & (sd[a0] > 0))
    if d.size:
        edge, _ = gm.cells(1)
        _, first = np.unique(edge[d], return_index=True)
        d = d[first]
        gm.split_edge(d, sd[d] / (sd[d] - sd[a0[d]]))
    return pad_new_darts(sd, gm)


def _band_sides(gm: GMap3, crossing: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Face sides ``<a0,a1>`` of the darts of the crossing volumes, labelled locally."""
    darts = np.flatnonzero(crossing[gm.dart_volume])
    nb = np.stack([np.searchsorted(darts, gm.alpha[0][darts]), np.searchsorted(darts, gm.alpha[1][darts])], 1)
    labels, count = orbit_labels(nb.T)  # repeated edges made harmless (scipy hangs on them)
    return darts, labels, count


def _band_signs(labels: np.ndarray, count: int, sd_band: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per label ``0..count-1``: whether any of its darts lies below, and above, the plane."""
    neg = np.bincount(labels, sd_band < 0, minlength=count) > 0
    pos = np.bincount(labels, sd_band > 0, minlength=count) > 0
    return neg, pos


def crossed_faces(gm: GMap3, sd: np.ndarray, crossing: np.ndarray) -> np.ndarray | None:
    """One dart of each face of the ``crossing`` volumes with corners on both sides of the
    plane (signed distances ``sd``), one side of a sewn face only; None if there is none."""
    darts, labels, count = _band_sides(gm, crossing)
    neg, pos = _band_signs(labels, count, sd[darts])
    both = neg & pos
    if not both.any():
        return None
    rep = np.full(count, -1, np.int64)
    rep[labels[::-1]] = darts[::-1]  # smallest dart of each side
    cand = np.flatnonzero(both)  # their partners' volumes hold both signs too
    at = np.minimum(np.searchsorted(darts, gm.alpha[3][rep[cand]]), len(darts) - 1)
    partner = np.where(darts[at] == gm.alpha[3][rep[cand]], labels[at], cand)
    return rep[cand[cand <= partner]]


def on_plane_runs(zero: np.ndarray, nz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per face (rows of ``zero``: its corners on the plane, in walk order; ``nz`` their count),
    the corners ``a < b`` to split between: two on-plane corners consecutive in walk order with
    a run of corners between them (all on one side), else the run that wraps round.  A face
    crossing more than twice (non-convex after embedding) keeps its other crossings for the
    next round."""
    k = np.argsort(~zero, axis=1, kind="stable")  # on-plane corners first, in walk order
    rows = np.arange(len(zero))
    gap = np.diff(k, axis=1)
    gap = np.where(np.arange(gap.shape[1])[None, :] < (nz - 1)[:, None], gap, 0)
    first = np.argmax(gap >= 2, axis=1)  # two on-plane corners with a run between
    has = gap[rows, first] >= 2
    a = np.where(has, k[rows, first], k[:, 0])
    b = np.where(has, k[rows, first + 1], k[rows, np.maximum(nz - 1, 0)])
    return a, b


def _split_crossing_faces(gm, sd, crossing):
    faces = crossed_faces(gm, sd, crossing)
    if faces is None:
        return sd, False
    walk, _ = gm.face_walk(faces)
    corners = walk[:, 0::2]
    ok = corners >= 0
    zero = ok & (sd[np.maximum(corners, 0)] == 0)
    nz = zero.sum(axis=1)
    if np.any(nz < 2) or np.any(nz % 2):
        raise GMapError("cut_map: a face touches the plane without crossing it cleanly; move the plane")
    a, b = on_plane_runs(zero, nz)
    rows = np.arange(len(faces))
    if np.any(b - a < 2):
        raise GMapError("cut_map: a face lies along the plane without crossing it; move the plane")
    gm.split_faces(corners[rows, a], b - a)
    return pad_new_darts(sd, gm), bool(np.any(nz > 2))


def split_crossing_volumes(gm: GMap3, sd: np.ndarray, crossing: np.ndarray) -> np.ndarray:
    """Split the crossing volumes along their on-plane loops, one loop per volume per round.

    A warped volume can meet the plane in several loops (its faces crossing
    it more than twice); each round splits one loop of every volume, the
    others end up in one of the two parts and are split by later rounds.
    """
    for _ in range(16):
        darts, labels, count = _band_sides(gm, crossing)
        neg, pos = _band_signs(labels, count, sd[darts])
        a0, a2 = gm.alpha[0], gm.alpha[2]
        other = labels[np.searchsorted(darts, a2[darts])]
        on_plane = (sd[darts] == 0) & (sd[a0[darts]] == 0)
        path = darts[on_plane & neg[labels] & pos[other] & (darts < a0[darts])]
        if not path.size:
            return sd
        path, more = _one_loop_per_volume(gm, path)
        gm.split_volumes(path, (FACE_CUT, FACE_CUT), many=True)
        sd = pad_new_darts(sd, gm)
        crossing = np.concatenate([crossing, np.ones(gm.n_volumes - len(crossing), bool)])
        if not more:
            return sd
    raise GMapError("cut_map: a volume meets the plane in too many loops; subdivide the model or move the plane")


def _one_loop_per_volume(gm, path):
    """The path edges of one loop in each volume, and whether other loops were left out."""
    a0, a1, a2 = gm.alpha[0], gm.alpha[1], gm.alpha[2]
    both = np.concatenate([path, a0[path]])
    edge = np.concatenate([np.arange(len(path))] * 2)
    order = np.argsort(both)
    both, edge = both[order], edge[order]

    def find(x):
        at = np.minimum(np.searchsorted(both, x), len(both) - 1)
        return np.where(both[at] == x, at, -1)

    y = a1[both].astype(np.int64)
    at = find(y)
    for _ in range(gm.n_darts):  # next path edge around each end (as split_volume walks)
        todo = at < 0
        if not todo.any():
            break
        y[todo] = a1[a2[y[todo]]]
        at[todo] = find(y[todo])
    count, loop = components(edge, edge[at], len(path))
    vol = gm.dart_volume[path].astype(np.int64)
    first = np.full(gm.n_volumes, np.iinfo(np.int64).max)
    np.minimum.at(first, vol, loop)
    keep = loop == first[vol]
    return path[keep], bool(not keep.all())


def _manual(gm) -> None:
    data = gm.dart_data
    data["corner"][:] = data["point"]
    data["vcorner"][:] = -1
    data["sup"][:] = -1
    vd = gm.volume_data
    vd["fit"][:] = False
    vd["parent_face"][:] = -2
