"""Surface and volume subdivision of a :class:`ramure.gmap.GMap3` (Catmull-Clark geometry).

``surface(gm, levels)``
    Every face (n corners) becomes n quads, one per corner; volumes are kept.
    Each child face keeps its parent's face label and appends one sub-label
    letter.  For a quad parent the letters follow the thesis layout (Fig. 2.31,
    read with the face's corner 0 at the bottom left): ``b`` bottom-left,
    ``c`` bottom-right, ``d`` top-right, ``a`` top-left; for an n-gon the child
    at corner k gets the k-th letter (``a``, ``b``, ...; the thesis leaves this
    open).  With ``volumes=None`` the whole model is one volume for the
    geometry (thesis case 2): Catmull-Clark moves the boundary surface, inner
    face points are centroids, inner edge points midpoints and inner vertices
    stay.  With ``volumes=`` (ids or a mask) only those volumes are subdivided
    (cases 1 and 3): each is smoothed on its own surface, vertices shared by
    several of them are averaged, and the faces of other volumes glued to them
    are split too and follow them, so the map stays conforming.

``volume(gm, levels)``
    Every cell with V corners becomes V hexahedra (cell centre, face centres,
    edge midpoints, corner), 8 darts per dart; only boundary vertices are
    moved by Catmull-Clark.  Outer child faces keep the label and gain a
    letter; the new inner faces are labelled ``I``.  Child volumes copy their
    parent's attributes, with ``degree`` 4.

>>> from ramure.gmap import GMap3
>>> from ramure.gmap.kernel import subdivide
>>> gm = GMap3(); _ = gm.add_prisms(4)
>>> s = subdivide.surface(gm, 1)
>>> s.n_darts, s.counts()["faces"], s.is_valid()
(192, 24, True)
>>> v = subdivide.volume(gm, 1)
>>> v.n_darts, v.counts()["volumes"], v.is_valid()
(384, 8, True)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import attributes as _attributes
from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.kernel.storage import SUBLABEL_BASE
from ramure.gmap.kernel.prism import FACE_I

#: letters (1 = a) of the children of a quad at its corners 0, 1, 2, 3
QUAD_LETTERS = np.array([2, 3, 4, 1])
_BIG = np.iinfo(np.int64).max // 4


def _group_mean(keys, values, count):
    """Mean of ``values`` (n, ...) per key in ``0..count-1``."""
    values = np.asarray(values, float)
    flat = values.reshape(len(values), -1)
    out: np.ndarray = np.stack([np.bincount(keys, flat[:, j], minlength=count) for j in range(flat.shape[1])], axis=1)
    n = np.bincount(keys, minlength=count)
    out /= np.maximum(n, 1)[:, None]
    return out.reshape((count,) + values.shape[1:])


def _compact(keys):
    uniq, inverse = np.unique(keys, return_inverse=True)
    return uniq, inverse, len(uniq)


def catmull_clark(
    points: ArrayLike, vertex: ArrayLike, edge: ArrayLike, face: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Catmull-Clark points of a closed surface given per-dart keys.

    ``points`` (m, 3) is the position of each surface dart's vertex;
    ``vertex``, ``edge``, ``face`` are the dart's vertex, edge and face keys
    (any integers; a face's darts are its ``<a0,a1>`` orbit).  Returns
    ``(vertex_keys, vertex_points, edge_keys, edge_points)``, sorted by key:
    face points are centroids, edge points ``(v1 + v2 + f1 + f2) / 4`` and
    vertex points ``(F + 2R + (n - 3) P) / n``.

    >>> import numpy as np
    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4, sizes=[[2.0, 2.0, 2.0]])
    >>> vid, pos = gm.vertex_positions()
    >>> _, new, _, _ = catmull_clark(pos[vid], vid, gm.cells(1)[0], gm.orbit_ids("01")[0])
    >>> centre = np.array([1.0, 0.0, 0.0])    # corners end 5/9 of the way out from it
    >>> np.round(np.abs(new[0] - centre), 4).tolist()
    [0.5556, 0.5556, 0.5556]
    """
    vk, vi, nv = _compact(vertex)
    ek, ei, ne = _compact(edge)
    _, fi, nf = _compact(face)
    p = np.asarray(points, float)
    fp = _group_mean(fi, p, nf)
    mid = _group_mean(ei, p, ne)
    ep = 0.5 * (mid + _group_mean(ei, fp[fi], ne))
    f_avg = _group_mean(vi, fp[fi], nv)
    r_avg = _group_mean(vi, mid[ei], nv)
    valence = np.bincount(vi, minlength=nv) / 2.0
    own = _group_mean(vi, p, nv)
    new = (f_avg + 2 * r_avg + (valence - 3)[:, None] * own) / valence[:, None]
    return vk, new, ek, ep


def _mean_onto(keys, values):
    """Average ``values`` by key; return (unique keys, means)."""
    ids, inv = np.unique(keys, return_inverse=True)
    return ids, _group_mean(inv, values, len(ids))


def _old_geometry(gm, volumes=None):
    """Cells and new points of the old map, computed before any topology change.

    Returns vertex/edge/face-side ids per dart, the old vertex positions, the
    new vertex positions, edge points and face points (see module docstring).
    Points have 4 columns: x, y, z and the ``radial`` vertex scalar, which is
    interpolated linearly and never smoothed.
    """
    vid, nv = gm.cells(0)
    eid, ne = gm.cells(1)
    side, ns = gm.orbit_ids("01")
    _, pos = gm.vertex_positions()
    radial = _group_mean(vid, gm.dart_data["radial"], nv)
    pos = np.concatenate([pos, radial[:, None]], axis=1)  # the vertex scalar rides along
    new_pos = pos.copy()
    edge_pt = _group_mean(eid, pos[vid], ne)  # midpoints
    face_pt = _group_mean(side, pos[vid], ns)  # centroids
    if volumes is None:
        surf = np.flatnonzero(gm.alpha[3] == np.arange(gm.n_darts))
        v_key, e_key = vid[surf], eid[surf]
    else:
        vol = gm.dart_volume.astype(np.int64)
        surf = np.flatnonzero(volumes[vol])
        v_key = vol[surf] * nv + vid[surf]
        e_key = vol[surf] * ne + eid[surf]
    if surf.size:
        vk, vp, ek, ep = catmull_clark(pos[vid[surf], :3], v_key, e_key, side[surf])
        ids, means = _mean_onto(vk % nv, vp)
        new_pos[ids, :3] = means
        ids, means = _mean_onto(ek % ne, ep)
        edge_pt[ids, :3] = means
    return vid, eid, side, pos, new_pos, edge_pt, face_pt


def face_corners(gm: GMap3, side: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Corner index of every dart in its face and the face's degree.

    Each face is walked from its anchor: the forward dart with the smallest
    stored corner index (new darts, whose index is unknown, come last; ties
    go to the smaller dart).
    """
    if side is None:
        side, _ = gm.orbit_ids("01")
    fc = gm.dart_data["fcorner"].astype(np.int64)
    fw = gm.dart_data["forward"]
    key = np.where(fw, np.where(fc >= 0, fc, _BIG), 2 * _BIG)
    order = np.lexsort((np.arange(gm.n_darts), key, side))
    first = np.ones(len(order), bool)
    first[1:] = side[order][1:] != side[order][:-1]
    anchors = order[first]
    walk, length = gm.face_walk(anchors)
    degree = length // 2
    pos = np.arange(walk.shape[1])[None, :]
    corner_of = ((pos + 1) // 2) % np.maximum(degree, 1)[:, None]
    ok = walk >= 0
    corner = np.empty(gm.n_darts, np.int64)
    deg = np.empty(gm.n_darts, np.int64)
    corner[walk[ok]] = np.broadcast_to(corner_of, walk.shape)[ok]
    deg[walk[ok]] = np.broadcast_to(degree[:, None], walk.shape)[ok]
    return corner, deg


def _child_faces(gm, corner, degree, darts):
    """Sub-labels, corner indices and directions of the 4 child darts (n0..n3) of ``darts``."""
    data = gm.dart_data
    k = corner[darts]
    quad = degree[darts] == 4
    letter = np.where(quad, QUAD_LETTERS[k % 4], np.minimum(k + 1, 26))
    sub = data["sublabel"][darts] * SUBLABEL_BASE + letter
    cv = np.where(quad, k, 0)
    fw = data["forward"][darts]
    ce = np.where(fw, cv + 1, cv + 3) % 4
    fcorner = np.stack([cv, ce, ce, (cv + 2) % 4], axis=1)
    forward = np.stack([fw, ~fw, fw, ~fw], axis=1)
    return sub, fcorner, forward


def _check_levels(levels):
    levels = int(levels)
    if levels < 0:
        raise ValueRefused(f"subdivision levels must be 0 or more, got {levels}")
    return levels


def _volume_mask(gm, volumes):
    if volumes is None:
        return None
    volumes = np.asarray(volumes)
    if volumes.dtype == bool:
        if volumes.shape != (gm.n_volumes,):
            raise ValueRefused(f"volume mask must have {gm.n_volumes} entries, got {volumes.shape}")
        return volumes.copy()
    volumes = volumes.astype(np.int64)
    if volumes.size and (volumes.min() < 0 or volumes.max() >= gm.n_volumes):
        raise ValueRefused(f"volume ids must be in 0..{gm.n_volumes - 1}")
    mask = np.zeros(gm.n_volumes, bool)
    mask[volumes] = True
    return mask


def surface(gm: GMap3, levels: int = 1, volumes: ArrayLike | None = None) -> GMap3:
    """Return ``gm`` with its faces Catmull-Clark subdivided ``levels`` times (a new map).

    See the module docstring.  ``volumes`` (ids or a boolean mask over
    volumes) restricts the subdivision to those volumes.
    """
    levels = _check_levels(levels)
    mask = _volume_mask(gm, volumes)
    for _ in range(levels):
        gm = _surface_once(gm, mask)
    return gm


def _surface_once(gm, mask):
    n = gm.n_darts
    alpha = gm.alpha.astype(np.int64)
    vid, eid, side, _, new_pos, edge_pt, face_pt = _old_geometry(gm, mask)
    if mask is None:
        split_face = np.ones(n, bool)
        split_edge = np.ones(n, bool)
    else:
        fid, nf = gm.cells(2)
        face_hit = np.zeros(nf, bool)
        face_hit[fid[mask[gm.dart_volume]]] = True
        split_face = face_hit[fid]
        edge_hit = np.zeros(int(eid.max()) + 1 if n else 0, bool)
        edge_hit[eid[split_face]] = True
        split_edge = edge_hit[eid]
    # children per dart: n0 always, n1 on split edges, n2 n3 on split faces
    count = 1 + split_edge + 2 * split_face
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    total = int(count.sum())
    n0 = start
    n1 = np.where(split_edge, start + 1, -1)
    n2 = np.where(split_face, start + 2, -1)
    n3 = np.where(split_face, start + 3, -1)
    a = np.empty((4, total), np.int64)
    d = np.arange(n)
    a[0, n0] = np.where(split_edge, n1, n0[alpha[0]])
    a[1, n0] = n0[alpha[1]]
    a[2, n0] = n0[alpha[2]]
    a[3, n0] = n0[alpha[3]]
    e = d[split_edge]
    a[0, n1[e]] = n0[e]
    a[1, n1[e]] = np.where(split_face[e], n2[e], n1[alpha[0][e]])
    a[2, n1[e]] = n1[alpha[2][e]]
    a[3, n1[e]] = n1[alpha[3][e]]
    f = d[split_face]
    a[0, n2[f]] = n3[f]
    a[1, n2[f]] = n1[f]
    a[2, n2[f]] = n2[alpha[0][f]]
    a[3, n2[f]] = n2[alpha[3][f]]
    a[0, n3[f]] = n2[f]
    a[1, n3[f]] = n3[alpha[1][f]]
    a[2, n3[f]] = n3[alpha[0][f]]
    a[3, n3[f]] = n3[alpha[3][f]]

    old = gm.dart_data
    src = np.repeat(d, count)
    darts = {
        "volume": old["volume"][src],
        "face": old["face"][src],
        "sublabel": old["sublabel"][src].copy(),
        "fcorner": old["fcorner"][src].copy(),
        "forward": old["forward"][src].copy(),
    }
    pts = np.empty((total, 4))
    pts[n0] = new_pos[vid]
    pts[n1[e]] = edge_pt[eid[e]]
    darts["fcorner"][n1[e]] = -1
    darts["forward"][n1[e]] = ~old["forward"][e]
    if f.size:
        corner, degree = face_corners(gm, side)
        sub, fcorner, forward = _child_faces(gm, corner, degree, f)
        kids = np.stack([n0[f], n1[f], n2[f], n3[f]], axis=1)
        darts["sublabel"][kids] = sub[:, None]
        darts["fcorner"][kids] = fcorner
        darts["forward"][kids] = forward
        pts[n2[f]] = edge_pt[eid[f]]
        pts[n3[f]] = face_pt[side[f]]
    darts["point"], darts["radial"] = pts[:, :3], pts[:, 3]
    kind = np.zeros(total, np.int64)  # per-dart attributes: n1, n2 edge points, n3 face point
    kind[n1[e]] = _attributes.EDGE
    if f.size:
        kind[n2[f]] = _attributes.EDGE
        kind[n3[f]] = _attributes.FACE
    darts.update(_attributes.carried(gm, src, kind))
    return _rebuilt(gm, a, darts, dict(gm.volume_data))


def _rebuilt(gm, alpha, darts, volumes):
    out = GMap3.from_arrays(alpha, darts, volumes, gm.dart_rules())
    out.meta = dict(gm.meta)
    return out


def volume(gm: GMap3, levels: int = 1) -> GMap3:
    """Return ``gm`` with every cell split into hexahedra ``levels`` times (a new map)."""
    levels = _check_levels(levels)
    for _ in range(levels):
        gm = _volume_once(gm)
    return gm


def _volume_once(gm):
    n = gm.n_darts
    alpha = gm.alpha.astype(np.int64)
    vid, eid, side, pos, new_pos, edge_pt, face_pt = _old_geometry(gm, None)
    nv = int(vid.max()) + 1 if n else 0
    vol = gm.dart_volume.astype(np.int64)
    # one child hexahedron per (volume, vertex); cell centre = mean of the distinct corners
    pair_key = vol * max(nv, 1) + vid
    pairs, pair_of, per_pair = np.unique(pair_key, return_inverse=True, return_counts=True)
    weight = 1.0 / per_pair[pair_of]
    nvol = gm.n_volumes
    cell_pt: np.ndarray = np.stack([np.bincount(vol, weight * pos[vid][:, j], minlength=nvol) for j in range(4)], axis=1)
    cell_pt /= np.maximum(np.bincount(vol, weight, minlength=nvol), 1e-300)[:, None]

    base = 8 * np.arange(n)
    N = [base + k for k in range(4)]
    M = [base + 4 + k for k in range(4)]
    total = 8 * n
    a = np.empty((4, total), np.int64)
    a0, a1, a2, a3 = alpha
    # outer sub-faces (as in surface subdivision)
    a[0, N[0]], a[1, N[0]], a[2, N[0]], a[3, N[0]] = N[1], N[0][a1], N[0][a2], N[0][a3]
    a[0, N[1]], a[1, N[1]], a[2, N[1]], a[3, N[1]] = N[0], N[2], N[1][a2], N[1][a3]
    a[0, N[2]], a[1, N[2]], a[2, N[2]], a[3, N[2]] = N[3], N[1], M[0], N[2][a3]
    a[0, N[3]], a[1, N[3]], a[2, N[3]], a[3, N[3]] = N[2], N[3][a1], M[1], N[3][a3]
    # inner faces, one per (corner, edge) of each cell, sewn to the next hexahedron along the edge
    a[0, M[0]], a[1, M[0]], a[2, M[0]], a[3, M[0]] = M[1], M[0][a2], N[2], M[0][a0]
    a[0, M[1]], a[1, M[1]], a[2, M[1]], a[3, M[1]] = M[0], M[2], N[3], M[1][a0]
    a[0, M[2]], a[1, M[2]], a[2, M[2]], a[3, M[2]] = M[3], M[1], M[2][a1], M[2][a0]
    a[0, M[3]], a[1, M[3]], a[2, M[3]], a[3, M[3]] = M[2], M[3][a2], M[3][a1], M[3][a0]

    old = gm.dart_data
    corner, degree = face_corners(gm, side)
    sub, fcorner, forward = _child_faces(gm, corner, degree, np.arange(n))
    s = np.arange(n) < a2
    new_vol = np.repeat(pair_of, 8)
    face = np.repeat(old["face"], 8).reshape(n, 8)
    face[:, 4:] = FACE_I
    sublabel = np.zeros((n, 8), np.int64)
    sublabel[:, :4] = sub[:, None]
    fc = np.empty((n, 8), np.int16)
    fc[:, :4] = fcorner
    fc[:, 4] = 0
    fc[:, 5] = fc[:, 6] = np.where(s, 1, 3)
    fc[:, 7] = 2
    fw = np.empty((n, 8), bool)
    fw[:, :4] = forward
    fw[:, 4], fw[:, 5], fw[:, 6], fw[:, 7] = s, ~s, s, ~s
    pts = np.empty((n, 8, 4))
    pts[:, 0] = new_pos[vid]
    pts[:, 1] = pts[:, 2] = pts[:, 4] = edge_pt[eid]
    pts[:, 3] = pts[:, 5] = pts[:, 6] = face_pt[side]
    pts[:, 7] = cell_pt[vol]
    darts = {
        "volume": new_vol,
        "face": face.ravel(),
        "sublabel": sublabel.ravel(),
        "fcorner": fc.ravel(),
        "forward": fw.ravel(),
        "point": pts[:, :, :3].reshape(-1, 3),
        "radial": pts[:, :, 3].ravel(),
    }
    kind = np.tile(np.array([0, 1, 1, 2, 1, 2, 2, 3]), n)  # matches the points above
    darts.update(_attributes.carried(gm, np.repeat(np.arange(n), 8), kind))
    parent_vol = pairs // max(nv, 1)
    volumes = {name: arr[parent_vol] for name, arr in gm.volume_data.items()}
    volumes["degree"] = np.full(len(pairs), 4, np.int16)
    volumes["parent"] = np.full(len(pairs), -1, np.int32)
    return _rebuilt(gm, a, darts, volumes)
