"""Cracks along a 3-G-map's own faces (the path before issue 40, kept for wood's end checks).

The pattern, walked over the skin, is snapped to skin vertices joined by shortest paths along
skin edges (:func:`ramure.gmap.organs.mapcracks.crack_edges`); under each crack edge the
interior face going most straight inward is taken, layer after layer down to the depth ``h``
(never a face touching the skin off the crack, never one whose unsewing would change chi);
the strip is unsewn and opened. On a fruit this reads as a staircase along the grid: there
:func:`ramure.gmap.organs.mapcracks.crack_map` cuts through the cells along the curve
instead. On a board the grid's sector faces are radial planes: an end check along them runs
where a real one does, from the pith out along a ray.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.cracks import CrackPattern
from ramure.gmap.organs.mapcracks import OPEN_CAP, OPEN_TRIES, Skin, crack_edges, open_copies, split_copies

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

#: Layers of cells a crack may go down at most.
MAX_LAYERS = 64


def crack_map_edges(
    gm: GMap3,
    pattern: CrackPattern,
    anchor: ArrayLike | None = None,
    direction: ArrayLike = (1.0, 0.0, 0.0),
    t0: float | None = None,
) -> tuple[GMap3, dict[str, Any]]:
    """Crack a 3-G-map along ``pattern`` grown until ``t0`` (default: fully grown), along the
    skin's own edges and the faces under them: the path :func:`ramure.gmap.organs.mapcracks.crack_map`
    took before issue 40, kept for wood, whose end checks run along the log's rays (its
    sector faces are radial planes, so there the grid's path is the crack's).

    ``anchor`` defaults to the skin's highest vertex. Returns ``(map, facts)``; the input map
    is not changed. Refused (one line each): a map without a closed skin, an anchor off the
    skin, a direction along the normal, a crack that finds no interior face to open.
    A crack whose opening would turn a cell inside out is opened half as wide, up to
    :data:`OPEN_TRIES` times (``narrowed`` in the facts: 1, 0.5, 0.25 or 0.125), so the
    command's defaults always open a crack (issue 40: they failed on the tomato).
    """
    t_start = time.perf_counter()
    skin = Skin(gm)
    if anchor is None:
        anchor = skin.pos[skin.used[np.argmax(skin.pos[skin.used, 2])]]
    edges = crack_edges(skin, pattern, anchor, direction, t0)
    out = gm.copy()
    before = (gm.euler_characteristic(), gm.boundary().euler_characteristic(), gm.cells(0)[1])
    strip, face_width, face_depth, layers = _strip(gm, out, skin, edges)
    if not strip:
        raise GMapError("the crack found no face between two cells under its path: use a finer map or a longer crack")
    from ramure.gmap.organs.defects import cell_volumes, orientation
    from ramure.gmap.kernel.measure import total_volume

    sign = orientation(out)
    before_volume = total_volume(gm)
    exposed = np.concatenate(list(strip.values()))
    if "crack" not in out.dart_data:
        out.add_dart_data("crack", np.int8, rule="copy")
    out.dart_data["crack"][exposed] = 1
    points, corners = out.points.copy(), out.corners.copy()
    narrowed = 1.0
    for _ in range(OPEN_TRIES):  # a crack too wide for its cells opens narrower, not at all
        widths = {f: w * narrowed for f, w in dict(face_width).items()}
        moved, opening = _open(out, exposed, strip, widths, face_depth, skin)
        if not (cell_volumes(out, sign) <= 0).any():
            break
        out.points[:], out.corners[:] = points, corners
        narrowed *= 0.5
    else:
        raise GMapError("the crack's opening turned a cell inside out even 8 times narrower: use a narrower crack")
    opened = [e for e, k in zip(edges, layers) if k > 0]
    length = float(sum(np.linalg.norm(skin.pos[a] - skin.pos[b]) for a, b in opened))
    facts = {
        "nodes": len(pattern),
        "skin_edges": len(edges),
        "skin_edges_opened": len(opened),
        "length": round(length, 9),
        "faces_unsewn": len(strip),
        "layers": int(max(layers, default=0)),
        "duplicated_vertices": int(out.cells(0)[1] - before[2]),
        "opened_vertices": moved,
        "opening": opening,
        "narrowed": narrowed,
        "euler_before": int(before[0]),
        "euler_after": int(out.euler_characteristic()),
        "skin_euler_before": int(before[1]),
        "skin_euler_after": int(out.boundary().euler_characteristic()),
        "valid": bool(out.is_valid()),
        "volume_before": before_volume,
        "volume_after": total_volume(out),
        "seconds": round(time.perf_counter() - t_start, 4),
    }
    facts["volume_lost"] = facts["volume_before"] - facts["volume_after"]
    return out, facts


def _face_darts(gm, dart):
    """The darts of ``dart``'s face in this volume, walking a0, a1, a0, ... from it."""
    a0, a1 = gm.alpha[0], gm.alpha[1]
    out, d = [dart], dart
    for k in range(4096):
        d = a0[d] if k % 2 == 0 else a1[d]
        if d == dart:
            return out
        out.append(int(d))
    raise GMapError("a face walk does not close: the map is not valid")


def _strip(gm, out, skin, edges):
    """Choose and unsew the strip's faces (navigating ``gm``, unsewing ``out``); returns
    ``(darts of both sides per face, half-width per face, depth per face, layers per crack edge)``.

    A face is unsewn only if that keeps the solid's Euler characteristic (checked on the
    orbits of its own vertices and edges): strips of two crack edges that meet deep inside
    would make a tunnel, so the second one stops there.
    """
    a2, a3 = gm.alpha[2], gm.alpha[3]
    vid, fid = skin.vid, gm.cells(2)[0]
    centres = gm.volume_centroids()
    strip: dict[int, np.ndarray] = {}  # face id -> its darts on both sides
    width: dict[int, float] = {}
    depth: dict[int, float] = {}
    layers: list[int] = []
    for (a, b), (w, h) in edges.items():
        d = skin.edge_dart[(a, b)]
        mid = (skin.pos[a] + skin.pos[b]) / 2
        inward = _mean_centre(gm, d, centres) - mid  # from the skin into the cells at the edge
        inward /= max(np.linalg.norm(inward), 1e-300)
        around: list[int] = []
        x = int(a2[d])
        while a3[x] != x and len(around) < 64:
            around.append(x)
            x = int(a2[a3[x]])
        taken, edge, previous_dir, ends = 0, {a, b}, inward, (a, b)
        while around and taken < MAX_LAYERS:
            best = _straightest(gm, skin, around, fid, strip, edge, ends, previous_dir, 0.05 if taken == 0 else 0.3)
            if best is None:
                break
            x, darts, direction = best
            inner = _opposite(darts, vid, edge)
            if not _keeps_euler(out, x):
                break
            walk, _ = out.face_walk([x])
            face = walk[walk >= 0]
            face = np.r_[face, out.alpha[3][face]]
            out.unsew3([x])
            below = float((skin.pos[list(inner)].mean(axis=0) - mid) @ inward) if inner else np.inf
            strip[fid[x]] = face
            width[fid[x]] = w
            depth[fid[x]] = h
            taken += 1
            if inner is None or below >= h:
                break
            inner_dart = next(y for y in darts if vid[y] in inner and vid[gm.alpha[0][y]] in inner)
            edge, previous_dir, ends = set(inner), direction, tuple(inner)
            around = _faces_around(gm, inner_dart)
        layers.append(taken)
    return strip, width, depth, layers


def _straightest(gm, skin, around, fid, strip, edge, ends, previous_dir, least):
    """Among the faces ``around`` an edge, the one going on most straight (None if none has a
    cosine above ``least`` with ``previous_dir`` or each touches the skin off the crack).

    Under the skin any face going inward will do (in wood, a crack may follow a ring: a
    shake); deeper, a face must go on within about 70 degrees."""
    best, score_best = None, least
    vid = skin.vid
    start = (skin.pos[ends[0]] + skin.pos[ends[1]]) / 2
    for x in around:
        if fid[x] in strip:
            continue
        darts = _face_darts(gm, x)
        verts = {int(vid[y]) for y in darts}
        off = verts - edge
        if not off or skin.on_skin[list(off)].any():
            continue
        direction = skin.pos[list(verts)].mean(axis=0) - start
        direction /= max(np.linalg.norm(direction), 1e-300)
        score = float(direction @ previous_dir)
        if score > score_best:
            best, score_best = (x, darts, direction), score
    return best


def _keeps_euler(gm, dart) -> bool:
    """Would unsewing ``dart``'s face keep V - E + F - C? (Local: only the orbits of the face's
    vertices and edges can change; the face itself becomes two.)"""
    walk, _ = gm.face_walk([dart])
    darts = walk[walk >= 0]
    partners = gm.alpha[3][darts]
    cut = set(darts.tolist()) | set(partners.tolist())
    seeds = list(cut)
    change = 1  # the face becomes two
    for involutions, sign in (((1, 2, 3), 1), ((0, 2, 3), -1)):
        change += sign * (_components(gm, seeds, involutions, cut) - _components(gm, seeds, involutions, set()))
    return change == 0


def _components(gm, seeds, involutions, cut):
    """Orbits (under ``involutions``) through ``seeds``, with alpha3 of the darts in ``cut`` freed."""
    alpha = gm.alpha
    seen, count = set(), 0
    for s in seeds:
        if s in seen:
            continue
        count += 1
        stack = [s]
        seen.add(s)
        while stack:
            d = stack.pop()
            for i in involutions:
                e = d if (i == 3 and d in cut) else int(alpha[i][d])
                if e not in seen:
                    seen.add(e)
                    stack.append(e)
    return count


def _mean_centre(gm, dart, centres):
    """Mean centre of the volumes around the edge of a skin ``dart``."""
    a2, a3 = gm.alpha[2], gm.alpha[3]
    vols, x = [int(gm.dart_volume[dart])], int(a2[dart])
    while a3[x] != x and len(vols) < 64:
        x = int(a3[x])
        vols.append(int(gm.dart_volume[x]))
        x = int(a2[x])
    return centres[vols].mean(axis=0)


def _opposite(darts, vid, edge):
    """The face's edge that touches none of ``edge``'s vertices (None for a triangle)."""
    verts = [int(vid[y]) for y in darts[0::2]]
    k = len(verts)
    for i in range(k):
        p, q = verts[i], verts[(i + 1) % k]
        if p not in edge and q not in edge:
            return (p, q)
    return None


def _faces_around(gm, dart):
    """One dart per face around the (interior) edge of ``dart``, all on that edge."""
    a2, a3 = gm.alpha[2], gm.alpha[3]
    out, x = [], int(dart)
    for _ in range(128):
        x = int(a2[x])
        if a3[x] == x:
            return []  # the edge reaches the skin elsewhere: stop here
        out.append(x)
        x = int(a3[x])
        if x == dart or a2[x] == dart:
            break
    return out


def _open(gm, exposed, strip, face_width, face_depth, skin):
    """Move each vertex copy the split made off the crack, into its own side: along the mean
    normal of its crack faces (pointing out of their cells), by the faces' half-width tapered
    with depth, capped by :data:`OPEN_CAP` of its shortest edge leaving the crack plane."""
    vid, nv, split = split_copies(gm, skin.vid, exposed)
    if split.size == 0:
        return 0, 0.0
    _, pos = gm.vertex_positions()
    centres = gm.volume_centroids()
    normal = np.zeros((nv, 3))
    reach = np.zeros(nv)
    for f, darts in strip.items():
        half = len(darts) // 2
        for side in (darts[:half], darts[half:]):  # the face as seen from each of its two cells
            corners = vid[side[0::2]]
            p = pos[corners]
            n = np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)  # Newell
            if n @ (p.mean(axis=0) - centres[gm.dart_volume[side[0]]]) < 0:
                n = -n
            n /= max(np.linalg.norm(n), 1e-300)
            np.add.at(normal, np.unique(corners), n)
        w, h = face_width[f], face_depth[f]
        for v in np.unique(vid[darts]):
            below = float(skin.tree.query(pos[v])[0])
            taper = 1.0 if h <= 0 else max(0.0, 1.0 - below / h)
            reach[v] = max(reach[v], w * taper)
    unit = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    u, w = vid, vid[gm.alpha[0]]
    vec = pos[w] - pos[u]
    elen = np.linalg.norm(vec, axis=1)
    across = np.abs(np.einsum("ij,ij->i", vec, unit[u])) > 0.5 * elen
    shortest = np.full(nv, np.inf)
    np.minimum.at(shortest, u[across], elen[across])
    step = np.minimum(reach[split], OPEN_CAP * shortest[split])
    step[~np.isfinite(step)] = 0.0
    return open_copies(gm, vid, pos, split, step, unit)
