"""Hierarchical embedding: a volume's frame from its parent's support face, corners from frames.

The thesis places every volume in a frame taken from the *support face* of
its filiation parent (3 angles and a translation on top), computes the
volume's default shape in that frame, then puts every vertex at the mean of
its incident volumes' corners (:meth:`GMap3.embed`).  Here:

* :func:`support_frames` -- frame of a face from its parent's **default
  corners** (never embedded points) and only its *real* corners (darts with
  a face-corner index; vertices made by edge splits are skipped, so a
  support face that a knot turned into a 7-gon still gives the quad's
  frame).  Origin: centroid of the real corners; H: outward normal
  (Newell, away from the volume); L: towards the midpoint of the edge from
  corner 0 to the next corner in the sense that is counter-clockwise about
  H; U = H x L.
* :func:`grow` -- the operator "add a volume on a face": prisms of order n
  built in those frames, their O face sewn to the support face (corner 0
  on corner 0, same rotation sense), ``parent`` / ``parent_face`` /
  ``angles`` / ``shift`` stored on the volume.
* :func:`reframe` -- recompute, parents first, every grown volume's frame
  and default corners (template corners from the frame; corners made by
  splits from their recorded supports, ``sup``/``supt``).  Embedding is a
  pure function of topology, attributes and root frames, so embedding after
  every step or once at the end gives the same positions.

>>> from ramure.gmap import GMap3
>>> gm = GMap3(); _ = gm.add_prisms(4)
>>> kids = grow(gm, gm.face_of([0, 0], ["E", "C1"]), 4, height=[1.0, 0.5], label="B")
>>> kids.tolist(), gm.volume_data["parent"].tolist(), gm.is_valid()
([1, 2], [-1, 0, 0], True)
>>> import numpy as np
>>> pos = gm.embed(); bool(np.allclose(pos.max(axis=0), [2.0, 1.0, 0.5]))
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import frames as _frames
from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.storage import NO_FACE

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3


def _real_corners(gm, anchors):
    """Padded (k, m) darts at the real corners of each face, walk order from the anchor; counts."""
    walk, length = gm.face_walk(anchors)
    cd = walk[:, 0::2]
    ok = cd >= 0
    ok &= gm.dart_data["fcorner"][np.maximum(cd, 0)] >= 0
    order = np.argsort(~ok, axis=1, kind="stable")
    cd = np.take_along_axis(cd, order, axis=1)
    count = ok.sum(axis=1)
    cd = np.where(np.arange(cd.shape[1])[None, :] < count[:, None], cd, -1)
    return cd, count


def support_frames(gm: GMap3, anchors: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(origins, frames, apothems, reverse)`` of the faces of ``anchors`` (see module docstring).

    ``apothems`` (k, 2): distances from the origin to the midpoints of the
    frame's first two edges (the L and U half-extents of a quad);
    ``reverse`` is True where the face's walk from its anchor runs
    clockwise about the outward normal.
    """
    anchors = np.asarray(anchors, np.int64).reshape(-1)
    cd, count = _real_corners(gm, anchors)
    if np.any(count < 3):
        i = int(np.flatnonzero(count < 3)[0])
        raise GMapError(f"the face of dart {int(anchors[i])} has fewer than 3 corners")
    c = gm.dart_data["corner"]
    ok = cd >= 0
    p = np.where(ok[:, :, None], c[np.maximum(cd, 0)], 0.0)
    centre = p.sum(axis=1) / count[:, None]
    nxt = (np.arange(cd.shape[1])[None, :] + 1) % count[:, None]
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    normal = np.where(ok[:, :, None], np.cross(p - centre[:, None], q - centre[:, None]), 0.0).sum(axis=1)
    cell = gm.volume_means(c)[gm.dart_volume[anchors]]
    area = np.linalg.norm(normal, axis=1)
    if np.any(area <= 0):
        raise GMapError("a support face is degenerate (zero area)")
    walk_normal = normal / area[:, None]
    outward = np.sign(np.sum(walk_normal * (centre - cell), axis=1))
    outward[outward == 0] = 1.0
    h = walk_normal * outward[:, None]
    reverse = outward < 0  # the walk turns clockwise about the outward normal
    last = np.take_along_axis(p, (count - 1)[:, None, None].repeat(3, axis=2), axis=1)[:, 0]
    mid0 = 0.5 * (p[:, 0] + np.where(reverse[:, None], last, p[:, 1]))
    mid1 = 0.5 * (
        np.where(reverse[:, None], last, p[:, 1])
        + np.where(
            reverse[:, None], np.take_along_axis(p, np.maximum(count - 2, 0)[:, None, None].repeat(3, 2), 1)[:, 0], p[:, 2]
        )
    )
    frames = _frames.frame_from(h, mid0 - centre)
    apothems = np.stack([np.linalg.norm(mid0 - centre, axis=1), np.linalg.norm(mid1 - centre, axis=1)], axis=1)
    return centre, frames, apothems, reverse


def _placed(origins, frames, angles, shift):
    f = _frames.rotate(frames, angles[:, 0], angles[:, 1], angles[:, 2])
    return origins + shift[:, None] * frames[:, 0], f


def grow(
    gm: GMap3,
    faces: ArrayLike,
    n: int,
    height: ArrayLike,
    width: ArrayLike | None = None,
    label: str = "A",
    angles: ArrayLike | None = None,
    shift: ArrayLike = 0.0,
    **volume_values: Any,
) -> np.ndarray:
    """Add a prism of order ``n`` on each free face of ``faces`` (anchor darts); return volume ids.

    ``height`` (per face or one value) is the size along H; ``width``
    (k, 2) the L and W sizes, default the support face's (twice its first
    two apothems, and :func:`reframe` keeps fitting them: volume column
    ``fit``).  ``angles`` (k, 3) degrees roll / pitch / turn the frame
    (:func:`ramure.gmap.kernel.frames.rotate`), ``shift`` moves the origin along
    the support normal.  The O face is sewn to the support face, corner 0
    on the anchor; faces of other degrees are matched as
    :meth:`GMap3.identify` does.  Refused, map unchanged: a face that is not
    alpha3-free, the same face twice.
    """
    faces = np.asarray(gm.check_darts(faces))
    k = len(faces)
    walk, _ = gm.face_walk(faces)
    used = walk[walk >= 0]
    if len(np.unique(used)) != len(used):
        raise GMapError("grow: the same face is given twice")
    w = np.maximum(walk, 0)
    free = np.all((walk < 0) | (gm.alpha[3][w] == w), axis=1)
    if not free.all():
        d = int(faces[~free][0])
        v = int(gm.dart_volume[d])
        raise GMapError(
            f"cannot add a volume on face {_prism.face_label_name(gm.dart_data['face'][d])} "
            f"of volume {v} ({gm.volume_data['label'][v]}): it is sewn already"
        )
    origins, frames, apothems, reverse = support_frames(gm, faces)
    height = np.broadcast_to(np.asarray(height, float), (k,))
    fit = width is None
    width = 2 * apothems if width is None else np.broadcast_to(np.asarray(width, float), (k, 2))
    angles = np.zeros((k, 3)) if angles is None else np.broadcast_to(np.asarray(angles, float), (k, 3))
    shift = np.broadcast_to(np.asarray(shift, float), (k,))
    if not (np.all(np.isfinite(height)) and np.all(height > 0) and np.all(np.isfinite(width)) and np.all(width > 0)):
        raise GMapError("grow: heights and widths must be finite and > 0")
    o, f = _placed(origins, frames, angles, shift)
    parent = gm.dart_volume[faces]
    with gm.atomic(gm.edge_zone(walk.ravel())):
        first = gm.add_prisms(
            n,
            k,
            o,
            f,
            np.column_stack([height, width]),
            label=label,
            parent=parent,
            parent_face=gm.dart_data["face"][faces],
            angles=angles,
            shift=shift,
            fit=fit,
            **volume_values,
        )
        vols = gm.dart_volume[first].astype(np.int64)
        child = first  # the O face's dart at corner 0, towards corner 1
        target = np.where(reverse, gm.alpha[1][faces], faces)
        _sew_matched(gm, child, target)
    return vols


def _sew_matched(gm, child, target):
    from ramure.gmap.kernel.identify import match_degrees

    wa, la = gm.face_walk(child)
    wb, lb = gm.face_walk(target)
    for i in np.flatnonzero(la != lb):
        match_degrees(gm, int(child[i]), int(target[i]))
    wa, la = gm.face_walk(child)
    wb, lb = gm.face_walk(target)
    if np.any(la != lb):
        raise GMapError("grow: cannot match the degree of a new volume's O face to its support face")
    gm.check_sewable(wa, wb)
    gm.sew_walks(wa, wb)


def _depths(parent):
    depth = np.zeros(len(parent), np.int64)
    cur = parent.copy()
    for _ in range(len(parent) + 1):
        has = cur >= 0
        if not has.any():
            return depth
        depth[has] += 1
        cur[has] = parent[cur[has]]
    raise GMapError("the filiation (parent) links form a cycle")


def reframe(gm: GMap3, embed: bool = True) -> np.ndarray | None:
    """Recompute grown volumes' frames (parents first) and every default corner; then embed.

    A volume is re-framed when it has a parent and a ``parent_face`` label:
    its support is that face of the parent (:meth:`GMap3.face_of`), placed by
    its ``angles`` and ``shift``.  Template corners (``vcorner``) follow
    the volume's frame and size; corners made by splits follow their
    supports.  Corners with neither (manual embedding, e.g. after
    subdivision) are kept.  Returns the vertex positions when ``embed``.
    """
    vd = gm.volume_data
    parent = vd["parent"].astype(np.int64)
    pface = vd["parent_face"].astype(np.int64)
    grown = (parent >= 0) & (pface != NO_FACE)
    depth = _depths(np.where(grown, parent, -1))
    data = gm.dart_data
    vc = data["vcorner"].astype(np.int64)
    vol = gm.dart_volume.astype(np.int64)
    by_level = [np.flatnonzero(grown & (depth == d)) for d in range(1, int(depth.max(initial=0)) + 1)]
    _template_corners(gm, np.flatnonzero(depth == 0), vc, vol)
    for level in by_level:
        anchors = np.asarray(gm.face_of(parent[level], pface[level], missing="ignore"))
        ok = anchors >= 0
        level, anchors = level[ok], anchors[ok]
        if level.size:
            origins, frames, apothems, _ = support_frames(gm, anchors)
            o, f = _placed(origins, frames, vd["angles"][level], vd["shift"][level])
            vd["origin"][level] = o
            vd["frame"][level] = f
            fit = vd["fit"][level]
            vd["size"][level[fit], 1:] = 2 * apothems[fit]
        _template_corners(gm, level, vc, vol)
    return gm.embed() if embed else None


def _template_corners(gm, volumes, vc, vol) -> None:
    """Default corners of ``volumes``: template darts from frames, then split darts from supports."""
    if len(volumes) == 0:
        return
    vd = gm.volume_data
    data = gm.dart_data
    mine = np.zeros(gm.n_volumes, bool)
    mine[volumes] = True
    darts = np.flatnonzero(mine[vol])
    corner = data["corner"]
    tpl = darts[vc[darts] >= 0]
    deg = vd["degree"].astype(np.int64)
    for n in np.unique(deg[vol[tpl]]):
        if n < 3:
            continue
        sel = tpl[deg[vol[tpl]] == n]
        v = vol[sel]
        uv, inv = np.unique(v, return_inverse=True)
        c = _prism.corners(int(n), vd["origin"][uv], vd["frame"][uv], vd["size"][uv])
        corner[sel] = c[inv, vc[sel]]
    sup = data["sup"]
    derived = darts[(vc[darts] < 0) & (sup[darts, 0] >= 0)]
    if derived.size == 0:
        return
    order = np.sort(derived)  # supports are older darts: one pass in id order per depth
    t = data["supt"][order][:, None]
    for _ in range(len(order) + 1):
        new = (1 - t) * corner[sup[order, 0]] + t * corner[sup[order, 1]]
        if np.array_equal(new, corner[order]):
            return
        corner[order] = new
