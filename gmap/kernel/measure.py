"""Exact volumes of a 3-G-map's cells, oriented by the darts (no VTK, no centroid heuristics).

Each face side ``<a0,a1>`` is walked from a dart of orientation class 0
(:func:`ramure.gmap.kernel.topology.orientation_parity`), fan-triangulated from
its vertex centroid, and the signed tetrahedra against the origin are
summed per volume (divergence theorem); a volume whose sum is negative was
walked inside out and takes the absolute value.  Non-planar faces are
measured with that fan, which is also how a VTK clip splits a hexahedron's
faces, so the kept volume of :func:`ramure.gmap.kernel.cut.cut_map` can be checked
against the picture cut.

>>> from ramure.gmap import GMap3
>>> gm = GMap3(); _ = gm.add_prisms(4, sizes=[[2.0, 3.0, 4.0]]); _ = gm.embed()
>>> float(round(volumes(gm)[0], 12))
24.0
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.gmap.kernel.topology import orientation_parity

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3


def volumes(gm: GMap3) -> np.ndarray:
    """Volume of every volume (n_volumes,), from the embedded vertex positions."""
    if gm.n_darts == 0:
        return np.zeros(gm.n_volumes)
    vid, pos = gm.vertex_positions()
    side, ns = gm.orbit_ids("01")
    parity = orientation_parity(gm)
    cand = np.flatnonzero(parity == 0)
    first = np.full(ns, -1, np.int64)
    first[side[cand][::-1]] = cand[::-1]
    first = first[first >= 0]
    walk, length = gm.face_walk(first)
    corners = walk[:, 0::2]
    ok = corners >= 0
    deg = length // 2
    p = np.where(ok[:, :, None], pos[vid[np.maximum(corners, 0)]], 0.0)
    c = p.sum(axis=1) / deg[:, None]
    nxt = (np.arange(corners.shape[1])[None, :] + 1) % deg[:, None]
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    ref = pos.mean(axis=0)
    tet = np.einsum("fki,fki->fk", np.cross(p - ref, q - ref), (c - ref)[:, None, :]) / 6.0
    per_face = np.where(ok, tet, 0.0).sum(axis=1)
    ids = np.where(ok, vid[np.maximum(corners, 0)], -1)
    for f in np.flatnonzero(turned_over(p, q, c, ok)):  # clipped into ears instead (see face_triangles)
        cyc = ids[f, : deg[f]]
        tri = pos[cyc[face_triangles(pos, cyc)]]
        per_face[f] = np.einsum("ki,ki->", np.cross(tri[:, 0] - ref, tri[:, 1] - ref), tri[:, 2] - ref) / 6.0
    signed = np.bincount(gm.dart_volume[first], per_face, minlength=gm.n_volumes)
    return np.abs(signed)


def faces_up(bottom: np.ndarray, top: np.ndarray) -> np.ndarray:
    """Whether each bottom face ``(n, m, 3)``, in its order, turns towards its opposite face ``top``.

    The face's normal is Newell's (the sum of its edges' cross products,
    right for a skew quad) and the direction to the top is between the two
    faces' centroids.  A test at one corner (that corner's two edges against
    its own top corner) read a long thin cone cell's side face backwards: the
    cell was written inside out and VTK measured it negative (82 of a 20-year
    pine's ring cells).
    """
    nxt = np.roll(bottom, -1, axis=1)
    normal = np.cross(bottom, nxt).sum(axis=1)
    return np.einsum("nx,nx->n", normal, top.mean(axis=1) - bottom.mean(axis=1)) >= 0


def turned_over(p: np.ndarray, q: np.ndarray, c: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Faces (rows of padded corners ``p``, next corners ``q``, centroids ``c``) whose fan from the
    vertex centroid has a triangle turned against the face's Newell normal: not convex seen from it."""
    cross = np.where(ok[:, :, None], np.cross(p - c[:, None, :], q - c[:, None, :]), 0.0)
    normal = cross.sum(axis=1)
    return np.any(np.einsum("fki,fi->fk", cross, normal) < 0, axis=1)


def face_triangles(pos: np.ndarray, cycle: np.ndarray) -> np.ndarray:
    """Triangles ``(k, 3)`` (positions in ``cycle``, in its turning sense) of a face that its vertex
    centroid does not see whole: ear-clipped in the plane of its Newell normal.

    A face of a cell curved around a round knot (or its piece after a plank
    cut) is not convex, and a fan from its centroid folds over itself.  The
    ears are clipped from the smallest vertex id in its increasing
    direction, so the two sides of a face get the same triangles and the
    kernel's volumes and the VTK tetrahedra of
    :func:`ramure.gmap.kernel.pyvista.to_unstructured_grid` agree.  The same
    area as any fan when the face is planar.
    """
    cycle = np.asarray(cycle, np.int64)
    m = len(cycle)
    start = int(np.argmin(cycle))
    order = (start + np.arange(m)) % m
    if cycle[order[1]] > cycle[order[-1]]:  # walk towards the smaller neighbour: one canonical order
        order = (start - np.arange(m)) % m
    p = pos[cycle[order]]
    centre = p.mean(axis=0)
    normal = np.cross(p - centre, np.roll(p, -1, axis=0) - centre).sum(axis=0)
    normal /= np.linalg.norm(normal) or 1.0
    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    xy = np.stack([(p - centre) @ u, (p - centre) @ np.cross(normal, u)], axis=1)
    ears = np.array(_ear_clip(xy), np.int64).reshape(-1, 3)
    out = order[ears]
    if order[1] != (start + 1) % m:  # triangles back in the cycle's own turning sense
        out = out[:, ::-1]
    return out


def _ear_clip(xy: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles of a counter-clockwise polygon ``xy`` (m, 2); the rest fanned if no ear is left."""
    idx = list(range(len(xy)))
    out = []
    while len(idx) > 3:
        n = len(idx)
        for t in range(n):
            i, j, k = idx[t - 1], idx[t], idx[(t + 1) % n]
            a, b, c = xy[i], xy[j], xy[k]
            if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0:
                continue  # a reflex or flat corner is no ear
            rest = xy[[x for x in idx if x not in (i, j, k)]]
            d1 = (b[0] - a[0]) * (rest[:, 1] - a[1]) - (b[1] - a[1]) * (rest[:, 0] - a[0])
            d2 = (c[0] - b[0]) * (rest[:, 1] - b[1]) - (c[1] - b[1]) * (rest[:, 0] - b[0])
            d3 = (a[0] - c[0]) * (rest[:, 1] - c[1]) - (a[1] - c[1]) * (rest[:, 0] - c[0])
            if not np.any((d1 >= 0) & (d2 >= 0) & (d3 >= 0)):
                out.append((i, j, k))
                idx.pop(t)
                break
        else:
            break
    out.extend((idx[0], idx[x], idx[x + 1]) for x in range(1, len(idx) - 1))
    return out


def total_volume(gm: GMap3) -> float:
    """Sum of :func:`volumes`."""
    return float(volumes(gm).sum())
