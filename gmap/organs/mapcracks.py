"""Cracks carved topologically into a 3-G-map (wood planks, fruit skins): issue 18.

:mod:`ramure.gmap.organs.cracks` carves a crack into a triangle surface with a mesh Boolean. Here
the same pattern (skeleton and profiles, growth in time) cuts a volumetric map along its
own faces, so the cracked map is still a map: it can be cut, measured, cracked again.

1. **Skin**: the map's boundary surface (its alpha3-free faces, triangulated) as a closed
   :class:`~ramure.gmap.organs.trimesh.TriMesh` whose points are the map's vertices.
2. **Projection**: the pattern is walked over the skin from an anchor and a direction
   (:func:`ramure.gmap.organs.cracks.project`), densely (samples about a third of a skin edge
   apart).
3. **Snapping**: each sample snaps to its nearest skin vertex; consecutive vertices are
   joined by shortest paths along skin edges. The crack on the skin is this set of edges.
   Each edge takes the profile (half-width ``w``, depth ``h``) of the sample it ends at.
4. **Strip**: under each crack edge the interior face (shared by two volumes) that goes
   most straight inward is chosen, then deeper ones, layer after layer, each continuing the
   previous face as straight as the cells allow, while the layer's inner edge is less than
   ``h`` below the skin (at least one layer). A face is taken only if its vertices off the
   crack are inside the solid (never on the skin): the crack never cuts through to another
   side, so a ball stays a ball (chi = 1, the skin chi = 2).
5. **Unsewing**: the strip's faces are alpha3-unsewn (:meth:`GMap3.unsew3`). The kernel's
   vertex and edge orbits then split by themselves along the crack; the strip's bottom and
   the crack's tips stay sewn (a notch, like :func:`ramure.gmap.organs.defects.crack`).
6. **Marking**: the darts of the crack's walls get the dart attribute ``crack = 1`` (rule
   copy, so later subdivisions keep it); :func:`wall_faces` lists them on the skin.
7. **Opening**: every vertex copy made by the split moves off the crack into its own side,
   by ``w`` times ``1 - depth/h`` (a V-shaped section, 0 at the bottom), capped at
   :data:`OPEN_CAP` of its shortest edge leaving the crack plane so no cell turns inside out.

**Growth**: at time ``t0`` an arc keeps the samples up to the part of its length grown by
then (:meth:`CrackPattern.progress`); growing nodes scale their profiles. Samples are those
of the fully grown crack, so a crack at a later time holds every edge of an earlier one:
its length never decreases, and from ``max(t_i + Δt_i)`` on it is the static crack.

>>> from ramure.gmap.organs.fruit import build_fruit
>>> from ramure.gmap.organs.cracks import random_pattern
>>> fruit = build_fruit("round_tomato", volume_levels=1)   # about 110 units across
>>> _, pos = fruit.vertex_positions()
>>> side = pos[pos[:, 0].argmax()]
>>> pattern = random_pattern(8, seed=2, length=8.0, width=3.0, depth=8.0)
>>> out, facts = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
>>> facts["valid"], facts["euler_after"], facts["skin_euler_after"], facts["length"] > 0
(True, 1, 2, True)
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from ramure.gmap.organs.cracks import CrackPattern, project
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.trimesh import TriMesh

if TYPE_CHECKING:
    import pyvista as pv

    from ramure.gmap.kernel.map3 import GMap3

#: A split vertex moves at most this fraction of its shortest edge leaving the crack plane.
OPEN_CAP = 0.3
#: Layers of cells a crack may go down at most.
MAX_LAYERS = 64


def _fan(surface: pv.PolyData) -> pv.PolyData:
    """Polygons split into fans over their own vertices (VTK's triangulation of a cut cell's
    polygon with collinear vertices can leave holes; a fan never does)."""
    import pyvista as pv

    faces = np.asarray(surface.faces)
    fan: list[tuple[int, int, int]] = []
    k = 0
    while k < len(faces):
        n = int(faces[k])
        cycle = faces[k + 1 : k + 1 + n]
        fan.extend((cycle[0], cycle[i], cycle[i + 1]) for i in range(1, n - 1))
        k += n + 1
    tris = np.array(fan, np.int64).reshape(-1, 3)
    return pv.PolyData(np.asarray(surface.points), np.c_[np.full(len(tris), 3), tris].ravel())


class Skin:
    """The map's boundary as triangles over the map's vertices, with its edge graph."""

    def __init__(self, gm: GMap3) -> None:
        from ramure.gmap.kernel.pyvista import boundary_polydata

        self.vid, _ = gm.cells(0)
        _, self.pos = gm.vertex_positions()
        n = gm.n_darts
        self.free = np.flatnonzero(gm.alpha[3] == np.arange(n))
        if self.free.size == 0:
            raise GMapError("the map has no boundary (no alpha3-free face): nothing to crack")
        self.used = np.unique(self.vid[self.free])
        surface = _fan(boundary_polydata(gm))
        # faces of cut cells may face the wrong way from their cell's centre: orient them by
        # their neighbours (VTK keeps the points, so they stay the map's vertices)
        surface = surface.compute_normals(
            cell_normals=False,
            point_normals=True,
            split_vertices=False,
            consistent_normals=True,
            auto_orient_normals=True,
            non_manifold_traversal=False,
        )
        faces = np.asarray(surface.faces).reshape(-1, 4)[:, 1:]
        self.mesh = TriMesh(self.pos[self.used], faces)  # refuses an open or non-manifold skin
        self.on_skin = np.zeros(len(self.pos), bool)
        self.on_skin[self.used] = True
        u, w = self.vid[self.free], self.vid[gm.alpha[0][self.free]]
        lo, hi = np.minimum(u, w), np.maximum(u, w)
        self.edge_dart: dict[tuple[int, int], int] = {}  # skin edge (a < b) -> one free dart on it
        for a, b, d in zip(lo.tolist(), hi.tolist(), self.free.tolist()):
            self.edge_dart.setdefault((a, b), d)
        keys = np.array(list(self.edge_dart), np.int64).reshape(-1, 2)
        length = np.linalg.norm(self.pos[keys[:, 0]] - self.pos[keys[:, 1]], axis=1)
        nv = len(self.pos)
        self.graph = sparse.csr_matrix(
            (np.r_[length, length], (np.r_[keys[:, 0], keys[:, 1]], np.r_[keys[:, 1], keys[:, 0]])), shape=(nv, nv)
        )
        self.mean_edge = float(length.mean())
        self.tree = cKDTree(self.pos[self.used])

    def snap(self, points: ArrayLike) -> np.ndarray:
        """Nearest skin vertex (map vertex id) of each point."""
        return self.used[self.tree.query(np.asarray(points, np.float64))[1]]

    def path(self, a: int, b: int) -> list[int]:
        """Skin vertices from ``a`` to ``b`` along skin edges (shortest)."""
        if (min(a, b), max(a, b)) in self.edge_dart:
            return [a, b]
        _, pred = dijkstra(self.graph, indices=a, return_predecessors=True)
        if pred[b] < 0:
            raise GMapError("the crack crosses from one piece of the model to another")
        out = [b]
        while out[-1] != a:
            out.append(int(pred[out[-1]]))
        return out[::-1]


#: How many times a crack too wide for its cells is halved before it is refused.
OPEN_TRIES = 4


def crack_map(
    gm: GMap3,
    pattern: CrackPattern,
    anchor: ArrayLike | None = None,
    direction: ArrayLike = (1.0, 0.0, 0.0),
    t0: float | None = None,
) -> tuple[GMap3, dict[str, Any]]:
    """Crack a 3-G-map along ``pattern`` grown until ``t0`` (default: fully grown).

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


def wall_faces(gm: GMap3) -> np.ndarray:
    """Per face of :func:`ramure.gmap.kernel.pyvista.boundary_polydata` (same order): is it a crack's wall?"""
    from ramure.gmap.kernel.pyvista import face_cycles

    free = np.flatnonzero(gm.alpha[3] == np.arange(gm.n_darts))
    first = face_cycles(gm, free)[0]
    if "crack" not in gm.dart_data:
        return np.zeros(len(first), bool)
    return np.asarray(gm.dart_data["crack"])[first] == 1


def crack_edges(
    skin: Skin, pattern: CrackPattern, anchor: ArrayLike, direction: ArrayLike, t0: float | None = None
) -> dict[tuple[int, int], tuple[float, float]]:
    """Skin edges ``(a, b)`` (map vertex ids, a < b) of the crack at ``t0``, each with its
    profile ``(w, h)``.

    Every sample of the fully grown crack gets the time the crack reaches it; the edges of the
    snapped paths are taken in that order and an edge that would close a loop is left out, so
    the crack on the skin is a tree and the crack at ``t0`` is a prefix of the grown one.
    """
    spacing = skin.mean_edge / 3
    per_arc = int(np.clip(np.ceil(pattern.length[1:].max(initial=0) / spacing), 4, 4096))
    _, arcs = project(skin.mesh, pattern, anchor, direction, samples_per_arc=per_arc)
    grown_at = float((pattern.start + pattern.duration).max()) + 1.0
    when = grown_at if t0 is None else float(t0)
    _, _, scale = pattern.progress(when)
    candidates: list[tuple[float, int, int, int, float, float]] = []  # (time, order, a, b, w, h)
    for i, j, samples in arcs:
        u = np.array([s[3] for s in samples])
        times = pattern.start[i] + u * (pattern.start[j] - pattern.start[i])
        width = (1 - u) * pattern.width[i] * scale[i] + u * pattern.width[j] * scale[j]
        depth = (1 - u) * pattern.depth[i] * scale[i] + u * pattern.depth[j] * scale[j]
        vertices = skin.snap(np.array([s[0] for s in samples]))
        for k in range(1, len(vertices)):
            if vertices[k] == vertices[k - 1]:
                continue
            route = skin.path(int(vertices[k - 1]), int(vertices[k]))
            for a, b in zip(route[:-1], route[1:]):
                candidates.append((float(times[k]), len(candidates), a, b, float(width[k]), float(depth[k])))
    candidates.sort()
    root: dict[int, int] = {}

    def find(v: int) -> int:
        while root.get(v, v) != v:
            root[v] = root.get(root[v], root[v])
            v = root[v]
        return v

    edges: dict[tuple[int, int], tuple[float, float]] = {}
    for time_k, _, a, b, w, h in candidates:
        if time_k > when or when <= 0:
            break
        key = (min(a, b), max(a, b))
        if key in edges:
            old = edges[key]
            edges[key] = (max(old[0], w), max(old[1], h))
            continue
        ra, rb = find(a), find(b)
        if ra == rb:
            continue  # would close a loop on the skin
        root[ra] = rb
        edges[key] = (w, h)
    return edges


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
    vid, nv = gm.cells(0)
    old = np.zeros(nv, np.int64)
    old[vid] = skin.vid
    copies = np.bincount(old, minlength=len(skin.pos))
    ex = np.unique(vid[exposed])
    split = ex[copies[old[ex]] > 1]
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
    new = pos.copy()
    new[split] = pos[split] - step[:, None] * unit[split]
    take = np.isin(vid, split)
    gm.points[take] = new[vid[take]]
    gm.corners[take] = new[vid[take]]
    return int((step > 0).sum()), float(2.0 * step.max())
