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

The result keeps behind the plane, as :func:`ramure.gmap.cut.plane_cut` does,
and switches to *manual* embedding (thesis): every dart's default corner is
its embedded point and no dart keeps a template corner, so embedding or
re-framing the result changes nothing.  Faces that cross the plane more than
twice (strongly non-convex after embedding) are refused; so are a zero normal
and a plane that does not cross the model (it would keep all or nothing).
"""
from __future__ import annotations

import numpy as np

from ramure.gmap.errors import GMapError, ValueRefused
from ramure.gmap.prism import FACE_CUT


def _normal(normal):
    from ramure.gmap.cut import _normal as parse
    return parse(normal)


def cut_map(gm, normal, origin=None):
    """Return a new map: the part of ``gm`` behind the plane (``(p - origin) . normal <= 0``).

    ``normal`` is a 3-vector or ``'x'``, ``'y'``, ``'z'``; ``origin``
    defaults to the centre of the model's bounding box.  ``gm`` is not
    changed.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4, sizes=[[2.0, 1.0, 1.0]]); _ = gm.embed()
    >>> half = cut_map(gm, "x", (0.5, 0, 0))
    >>> half.counts()["volumes"], half.is_valid(), round(float(half.points[:, 0].max()), 12)
    (1, True, 0.5)
    """
    n = _normal(normal)
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
    _split_crossing_edges(out, s[vid])
    _split_crossing_faces(out, tol, n, o)
    _split_crossing_volumes(out, tol, n, o)
    _drop_front(out, tol, n, o)
    _manual(out)
    out.meta = dict(gm.meta, cut=list(out.meta.get("cut", [])) + [{"normal": n.tolist(), "origin": o.tolist()}])
    return out


def _signed(gm, tol, n, o):
    vid, pos = gm.vertex_positions()
    s = (pos - o) @ n
    s[np.abs(s) <= tol] = 0.0
    return s[vid]


def _split_crossing_edges(gm, sd):
    a0 = gm.alpha[0]
    cross = (sd < 0) & (sd[a0] > 0)                    # one dart per (edge, face side), the negative end
    d = np.flatnonzero(cross)
    if d.size == 0:
        return
    eid, _ = gm.cells(1)
    _, first = np.unique(eid[d], return_index=True)
    d = d[first]
    t = sd[d] / (sd[d] - sd[a0[d]])
    gm.split_edge(d, t)


def _face_signs(gm, sd, side, ns):
    neg = np.bincount(side, sd < 0, minlength=ns) > 0
    pos = np.bincount(side, sd > 0, minlength=ns) > 0
    return neg, pos


def _split_crossing_faces(gm, tol, n, o):
    sd = _signed(gm, tol, n, o)
    side, ns = gm.orbit_ids("01")
    neg, pos = _face_signs(gm, sd, side, ns)
    both = neg & pos
    if not both.any():
        return
    # one face side per 2-cell: the side whose id is not larger than its alpha3 partner's
    reps = np.full(ns, -1, np.int64)
    reps[side[::-1]] = np.arange(gm.n_darts)[::-1]      # smallest dart of each side
    partner = side[gm.alpha[3][reps]]
    todo = np.flatnonzero(both & (np.arange(ns) <= partner))
    walk, length = gm.face_walk(reps[todo])
    corners = walk[:, 0::2]
    ok = corners >= 0
    zero = ok & (sd[np.maximum(corners, 0)] == 0)
    count = zero.sum(axis=1)
    if np.any(count != 2):
        raise GMapError("cut_map: a face crosses the plane more than twice (a strongly non-convex face); "
                        "subdivide the model or move the plane")
    k = np.argsort(~zero, axis=1, kind="stable")[:, :2]   # the two on-plane corners, in walk order
    rows = np.arange(len(todo))
    d1 = corners[rows, k[:, 0]]
    k2 = k[:, 1] - k[:, 0]
    gm._split_faces(d1, k2)


def _split_crossing_volumes(gm, tol, n, o):
    sd = _signed(gm, tol, n, o)
    side, ns = gm.orbit_ids("01")
    neg, pos = _face_signs(gm, sd, side, ns)
    a0, a2 = gm.alpha[0], gm.alpha[2]
    d = np.arange(gm.n_darts)
    on_plane = (sd == 0) & (sd[a0] == 0)
    path = on_plane & neg[side] & pos[side[a2]] & (d < a0)
    p = np.flatnonzero(path)
    if p.size == 0:
        return
    gm._split_volume(p, (FACE_CUT, FACE_CUT), many=True)


def _drop_front(gm, tol, n, o):
    sd = _signed(gm, tol, n, o)
    vol = gm.dart_volume
    front = np.bincount(vol, sd > 0, minlength=gm.n_volumes) > 0
    if front.all():
        raise ValueRefused("the cut keeps nothing")
    gm.remove_volumes(np.flatnonzero(front))


def _manual(gm):
    data = gm.dart_data
    data["corner"][:] = data["point"]
    data["vcorner"][:] = -1
    data["sup"][:] = -1
    vd = gm.volume_data
    vd["fit"][:] = False
    vd["parent_face"][:] = -2
