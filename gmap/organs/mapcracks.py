"""Cracks carved topologically into a 3-G-map (wood planks, fruit skins): issue 18.

:mod:`ramure.gmap.organs.cracks` carves a crack into a triangle surface with a mesh Boolean. Here
the same pattern (skeleton and profiles, growth in time) cuts a volumetric map along its
own faces, so the cracked map is still a map: it can be cut, measured, cracked again.

1. **Skin**: the map's boundary surface (its alpha3-free faces, triangulated) as a closed
   :class:`~ramure.gmap.organs.trimesh.TriMesh` whose points are the map's vertices.
2. **Projection**: the pattern is walked over the skin from an anchor and a direction
   (:func:`ramure.gmap.organs.cracks.project`), densely (samples an eighth of a skin edge
   apart), and split into chains rounded at the pattern's nodes (:func:`crack_curves`).
3. **Cutting** (issue 40): the cells under each chain are cut along its ribbon, the curve
   swept down the skin normals to the depth ``h``, through skin faces and the cells under
   them wherever the curve crosses them (:mod:`ramure.gmap.organs.crackcut`). The crack's
   mouth is where the ribbon meets the skin: it follows the curve, not the skin's edges (the
   crack used to be snapped to skin vertices, a staircase along the grid; :func:`crack_edges`
   still gives that old path). The cut stays under the skin (cells whose centroid is less
   than ``h`` deep), so a ball stays a ball (chi = 1, the skin chi = 2).
4. **Unsewing**: the cuts' new faces are alpha3-unsewn (:meth:`GMap3.unsew3`). The kernel's
   vertex and edge orbits then split by themselves along the crack; the cut's bottom and
   the crack's tips stay sewn (a notch, like :func:`ramure.gmap.organs.defects.crack`).
5. **Marking**: the darts of the crack's walls get the dart attribute ``crack = 1`` (rule
   copy, so later subdivisions keep it); :func:`wall_faces` lists them on the skin.
6. **Opening**: every vertex copy made by the split moves off the crack into its own side,
   by ``w`` times ``1 - depth/h`` (a V-shaped section, 0 at the bottom), capped at
   :data:`OPEN_CAP` of the crack's typical room across its plane so no cell turns inside out.

**Growth**: at time ``t0`` an arc keeps the samples up to the part of its length grown by
then (:meth:`CrackPattern.progress`); growing nodes scale their profiles. Samples are those
of the fully grown crack, so a crack at a later time runs along an earlier one and further:
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

#: A split vertex moves at most this fraction of the crack's typical room across its plane.
OPEN_CAP = 0.3
#: Corners of a cut cell nearer the crack than this fraction of their shortest edge are moved
#: onto it first (no sliver cells).
PULL = 0.15


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
        self.edge_mid = (self.pos[keys[:, 0]] + self.pos[keys[:, 1]]) / 2
        self.edge_length = length
        self.tree = cKDTree(self.pos[self.used])

    def edge_near(self, point: ArrayLike, radius: float) -> float:
        """Median length of the skin edges whose middles lie within ``radius`` of ``point`` (the
        whole skin's when none does): the skin's grain where a crack runs. A board's skin has
        long edges along its length and short ones on its end grain, so its mean says little."""
        near = np.linalg.norm(self.edge_mid - np.asarray(point, np.float64), axis=1) <= radius
        return float(np.median(self.edge_length[near] if near.any() else self.edge_length))

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


#: How many times a crack too wide for its cells is halved (1, 1/2, 1/4, 1/8).
OPEN_TRIES = 4
#: Then how many rounds the corners of the cells it still turns inside out are held in place
#: (thin cells where two chains of a crack cross), before it is refused.
HOLD_TRIES = 4


def crack_map(
    gm: GMap3,
    pattern: CrackPattern,
    anchor: ArrayLike | None = None,
    direction: ArrayLike = (1.0, 0.0, 0.0),
    t0: float | None = None,
    pull: float = PULL,
) -> tuple[GMap3, dict[str, Any]]:
    """Crack a 3-G-map along ``pattern`` grown until ``t0`` (default: fully grown).

    The crack follows its curve on the skin, cutting through the cells under it
    (:mod:`ramure.gmap.organs.crackcut`), not the skin's existing edges: its mouth is the
    polyline where its ribbon meets the skin's faces. ``anchor`` defaults to the skin's
    highest vertex. Returns ``(map, facts)``; the input map is not changed. Refused (one line
    each): a map without a closed skin, an anchor off the skin, a direction along the normal,
    a crack that finds no cell to cut. A crack whose opening would turn a cell inside out is
    opened half as wide, up to :data:`OPEN_TRIES` times (``narrowed`` in the facts: 1, 0.5,
    0.25 or 0.125), so the command's defaults always open a crack (issue 40: they failed on
    the tomato).

    ``pull``: a corner of a cut cell nearer the crack than this fraction of its shortest edge
    is moved onto it, so the cut leaves no sliver cell (0 moves none).
    The path before issue 40, along the skin's edges and the faces under them, is
    :func:`ramure.gmap.organs.edgecracks.crack_map_edges`; the command uses it on wood, whose
    grid's sector faces are the radial planes an end check runs along.
    """
    t_start = time.perf_counter()
    skin = Skin(gm)
    if anchor is None:
        anchor = skin.pos[skin.used[np.argmax(skin.pos[skin.used, 2])]]
    curves = crack_curves(skin, pattern, anchor, direction, t0)
    out, facts = crack_along(gm, curves, pull, skin)
    facts = {"nodes": len(pattern), **facts, "seconds": round(time.perf_counter() - t_start, 4)}
    return out, facts


def crack_along(gm: GMap3, curves: list, pull: float = PULL, skin: Skin | None = None) -> tuple[GMap3, dict[str, Any]]:
    """Crack a 3-G-map along the given chains on its skin (:class:`ramure.gmap.organs.crackcut.Curve`,
    e.g. from :func:`crack_curves` or :func:`ramure.gmap.organs.crackcut.ring_curve`): cut the
    cells under each, unsew the cuts' faces, open them (see :func:`crack_map`); the cells with
    a crack wall get the volume mark ``wound = 1`` (as :func:`ramure.gmap.organs.defects.crack`
    marks its fresh walls: a per-cell label in the VTU). Returns ``(map, facts)``; ``gm`` is
    not changed."""
    from ramure.gmap.organs.crackcut import SNAP, ribbon_cut
    from ramure.gmap.organs.defects import mark_volumes, cell_volumes, orientation
    from ramure.gmap.kernel.measure import total_volume

    t_start = time.perf_counter()
    skin = Skin(gm) if skin is None else skin
    out = gm.copy()
    before = (gm.euler_characteristic(), gm.boundary().euler_characteristic(), gm.cells(0)[1], gm.n_volumes)
    if "crack" not in out.dart_data:
        out.add_dart_data("crack", np.int8, rule="copy")
    old_walls = np.asarray(out.dart_data["crack"]) == 1
    for curve in curves:  # each chain's new faces are walls; later cuts split them, the mark follows
        new, seams = ribbon_cut(out, curve, SNAP * skin.mean_edge, pull)
        out.dart_data["crack"][seams] = 0
        out.dart_data["crack"][new] = 1
    mark = np.asarray(out.dart_data["crack"]) == 1
    fid, n_faces = out.cells(2)
    fresh = mark & ~np.r_[old_walls, np.zeros(out.n_darts - len(old_walls), bool)]  # not a wall of an older crack
    mark |= (np.bincount(fid, fresh, n_faces) > 0)[fid]
    out.dart_data["crack"][mark] = 1  # a wall split by a later cut is a wall all round
    walls = np.flatnonzero(mark)
    walls = walls[out.alpha[3][walls] != walls]  # new walls, still sewn
    if walls.size == 0:
        raise GMapError("the crack found no cell to cut under its path: use a finer map or a longer crack")
    old_vid, n_old = out.cells(0)
    split_volume = total_volume(out)
    walls, dropped = _unsew_chains(out, walls, curves, int(before[0]))
    if walls.size == 0:
        raise GMapError(
            "the crack cannot open here without cutting a piece off the model or a tunnel through it: "
            "move its anchor or make it shallower"
        )
    mouth = mouth_edges(out, walls)  # after unsewing: each mouth edge twice, once per lip
    _, pos = out.vertex_positions()
    length = 0.5 * float(np.linalg.norm(pos[mouth[:, 0]] - pos[mouth[:, 1]], axis=1).sum())
    faces_unsewn = len(np.unique(out.cells(2)[0][walls])) // 2
    # per-cell label for datasets (the VTU's cell data): cells with a crack wall are wounds
    mark_volumes(out, "wound", np.unique(out.dart_volume[walls]), 1.0)
    sign = orientation(out)
    points, corners = out.points.copy(), out.corners.copy()
    narrowed, held = 1.0, np.zeros(out.cells(0)[1], bool)
    for attempt in range(OPEN_TRIES + HOLD_TRIES):  # a crack too wide for its cells opens narrower
        moved, opening = _open(out, walls, old_vid, curves, narrowed, held)
        bad = cell_volumes(out, sign) <= 0
        if not bad.any():
            break
        out.points[:], out.corners[:] = points, corners
        if attempt < OPEN_TRIES - 1:
            narrowed *= 0.5
        else:  # still too wide at an eighth: the corners of the cells it turns stay where they are
            held[out.cells(0)[0][bad[out.dart_volume]]] = True
    else:
        raise GMapError("the crack's opening turned a cell inside out even 8 times narrower: use a narrower crack")
    facts = {
        "chains": len(curves),
        "chains_left_shut": dropped,
        "skin_edges": len(mouth) // 2,
        "skin_edges_opened": len(mouth) // 2,
        "length": round(length, 9),
        "faces_unsewn": faces_unsewn,
        "cells_split": int(out.n_volumes - before[3]),
        "cut_vertices": int(n_old - before[2]),
        "duplicated_vertices": int(out.cells(0)[1] - n_old),
        "opened_vertices": moved,
        "opening": opening,
        "narrowed": narrowed,
        "held_vertices": int(held.sum()),
        "euler_before": int(before[0]),
        "euler_after": int(out.euler_characteristic()),
        "skin_euler_before": int(before[1]),
        "skin_euler_after": int(out.boundary().euler_characteristic()),
        "valid": bool(out.is_valid()),
        "volume_before": total_volume(gm),
        "volume_after": total_volume(out),
        "seconds": round(time.perf_counter() - t_start, 4),
    }
    # the gap: what the opening took from the cut cells (cutting itself keeps the volume)
    facts["volume_lost"] = split_volume - facts["volume_after"]
    return out, facts


def _unsew_chains(gm: GMap3, walls: np.ndarray, curves: list, euler: int) -> tuple[np.ndarray, int]:
    """Unsew the cut faces ``walls`` chain by chain (a face goes with the chain nearest its
    centre), keeping a chain's unsewing only if the map's Euler characteristic stays ``euler``:
    a chain that meets another one twice, or itself, would cut a tunnel or a piece off (the old
    crack left out skin edges closing a loop). Its faces stay sewn and lose the ``crack`` mark.
    Returns (the wall darts unsewn, the count of chains left shut)."""
    fid, n_faces = gm.cells(2)
    faces, first = np.unique(fid[walls], return_index=True)
    centre = np.zeros((n_faces, 3))
    count = np.bincount(fid[walls], minlength=n_faces)
    for j in range(3):
        centre[:, j] = np.bincount(fid[walls], gm.points[walls, j], minlength=n_faces)
    centre = centre[faces] / count[faces, None]
    gap = np.stack([np.linalg.norm(c.nearest(centre)[2] - centre, axis=1) for c in curves])
    chain = np.full(n_faces, -1, np.int64)
    chain[faces] = gap.argmin(axis=0)
    shut = 0
    for k in range(len(curves)):
        darts = walls[chain[fid[walls]] == k]
        if not darts.size:
            continue
        walk, _ = gm.face_walk(darts)
        side = walk[walk >= 0]
        partner = gm.alpha[3][side].copy()
        gm.unsew3(darts)
        if gm.euler_characteristic() != euler:
            gm.alpha[3][side], gm.alpha[3][partner] = partner, side
            gm.mark_changed()
            gm.dart_data["crack"][np.r_[side, partner]] = 0
            shut += 1
    walls = walls[gm.alpha[3][walls] == walls]
    return walls, shut


def crack_curves(skin: Skin, pattern: CrackPattern, anchor: ArrayLike, direction: ArrayLike, t0: float | None = None) -> list:
    """The crack's chains on the skin at ``t0`` (:class:`ramure.gmap.organs.crackcut.Curve`):
    the pattern walked densely (samples an eighth of a skin edge apart, the median edge within
    the pattern's length of the anchor, at most 4096 per arc),
    each sample kept once the crack has reached it, its profile scaled by the growth, the
    chain's corners rounded over a skin edge (:meth:`~ramure.gmap.organs.crackcut.Curve.rounded`),
    its depth at most half the model's thickness under it
    (:func:`~ramure.gmap.organs.crackcut.thickness`: a crack over a board's edge does not cut
    through the board). This is the curve the crack's mouth follows."""
    from ramure.gmap.organs.crackcut import chains, thickness

    edge = skin.edge_near(anchor, max(pattern.total_length(), 1e-300))
    spacing = edge / 8
    per_arc = int(np.clip(np.ceil(pattern.length[1:].max(initial=0) / spacing), 4, 4096))
    _, arcs = project(skin.mesh, pattern, anchor, direction, samples_per_arc=per_arc)
    grown_at = float((pattern.start + pattern.duration).max()) + 1.0
    when = grown_at if t0 is None else float(t0)
    if when <= 0:
        return []
    _, _, scale = pattern.progress(when)
    times, width, depth = [], [], []
    for i, j, samples in arcs:
        u = np.array([s[3] for s in samples])
        times.append(pattern.start[i] + u * (pattern.start[j] - pattern.start[i]))
        width.append((1 - u) * pattern.width[i] * scale[i] + u * pattern.width[j] * scale[j])
        depth.append((1 - u) * pattern.depth[i] * scale[i] + u * pattern.depth[j] * scale[j])
    curves = [c.rounded(edge, skin.mesh) for c in chains(arcs, pattern.parent, times, width, depth, when)]
    for c in curves:  # never deeper than half the model there: a crack never cuts through
        c.depth = np.minimum(c.depth, 0.5 * thickness(skin.mesh, c.points, c.normal))
    return curves


def mouth_edges(gm: GMap3, walls: np.ndarray) -> np.ndarray:
    """``(k, 2)`` vertex ids of the crack's mouth: edges shared by a wall dart and a skin dart
    (alpha3-free, not a wall) of ``gm``, each once (call it before the walls are unsewn)."""
    edge, n_edges = gm.orbit_ids("023")
    is_wall = np.zeros(gm.n_darts, bool)
    is_wall[walls] = True
    free = (gm.alpha[3] == np.arange(gm.n_darts)) & ~is_wall
    on_skin = np.zeros(n_edges, bool)
    on_skin[edge[free]] = True
    at = walls[on_skin[edge[walls]]]
    _, first = np.unique(edge[at], return_index=True)
    vid, _ = gm.cells(0)
    d = at[first]
    return np.c_[vid[d], vid[gm.alpha[0][d]]]


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
    """Skin edges ``(a, b)`` (map vertex ids, a < b) of the crack at ``t0`` snapped to the skin's
    own edges, each with its profile ``(w, h)``: the path :func:`crack_map` took before issue 40
    (a staircase along the grid), kept to compare with.

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


def split_copies(gm: GMap3, old_vid: np.ndarray, darts: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
    """``(vid, nv, split)``: the map's vertex id of each dart, their count, and the vertices of
    ``darts`` that are copies of one vertex of before the unsewing (``old_vid``: each dart's
    vertex then), which an opening moves apart."""
    vid, nv = gm.cells(0)
    old = np.zeros(nv, np.int64)
    old[vid] = old_vid
    copies = np.bincount(old, minlength=int(old_vid.max()) + 1)
    ex = np.unique(vid[darts])
    return vid, nv, ex[copies[old[ex]] > 1]


def open_copies(
    gm: GMap3, vid: np.ndarray, pos: np.ndarray, split: np.ndarray, step: np.ndarray, unit: np.ndarray
) -> tuple[int, float]:
    """Move the vertices ``split`` by ``-step`` along their ``unit`` vectors (points and corners
    of their darts); returns (vertices moved, widest opening: twice the largest step)."""
    new = pos.copy()
    new[split] = pos[split] - step[:, None] * unit[split]
    take = np.isin(vid, split)
    gm.points[take] = new[vid[take]]
    gm.corners[take] = new[vid[take]]
    return int((step > 0).sum()), float(2.0 * step.max())


def _open(
    gm: GMap3, walls: np.ndarray, old_vid: np.ndarray, curves: list, narrowed: float, held: np.ndarray
) -> tuple[int, float]:
    """Move each vertex copy the unsewing made off the crack, into its own cells: along the
    ribbon's side vector at its nearest curve sample (the sign pointing from its cells to the
    walls, reversed), by the sample's half-width times ``narrowed``, tapered with depth to 0
    at ``h``, capped by :data:`OPEN_CAP` of the crack's median room across (the distance, across
    the crack plane, to a vertex's nearest neighbour off it: so the lips run even) and by half
    its own, times ``narrowed``; ``held`` vertices stay.
    Returns (copies moved, widest opening)."""
    vid, nv, split = split_copies(gm, old_vid, walls)
    if split.size == 0:
        return 0, 0.0
    _, pos = gm.vertex_positions()
    centres = gm.volume_centroids()
    points = np.concatenate([c.points for c in curves])
    side = np.concatenate([c.side for c in curves])
    normal = np.concatenate([c.normal for c in curves])
    width = np.concatenate([c.width for c in curves])
    depth = np.concatenate([c.depth for c in curves])
    near = cKDTree(points).query(pos[vid[walls]])[1]
    toward = np.sign(np.einsum("ij,ij->i", pos[vid[walls]] - centres[gm.dart_volume[walls]], side[near]))
    unit = np.zeros((nv, 3))
    np.add.at(unit, vid[walls], toward[:, None] * side[near])
    unit /= np.maximum(np.linalg.norm(unit, axis=1, keepdims=True), 1e-300)
    at = cKDTree(points).query(pos[split])[1]
    below = np.einsum("ij,ij->i", points[at] - pos[split], normal[at])
    taper = np.where(depth[at] > 0, np.clip(1.0 - below / np.maximum(depth[at], 1e-300), 0.0, 1.0), 1.0)
    reach = width[at] * taper
    u, w = vid, vid[gm.alpha[0]]
    vec = pos[w] - pos[u]
    elen = np.linalg.norm(vec, axis=1)
    rise = np.abs(np.einsum("ij,ij->i", vec, unit[u]))
    across = rise > 0.2 * elen  # edges leaving the crack plane (not along a wall)
    room = np.full(nv, np.inf)
    np.minimum.at(room, u[across], rise[across])  # how far the next vertex across lies
    own = room[split]
    typical = float(np.median(own[np.isfinite(own)])) if np.isfinite(own).any() else 0.0
    own[~np.isfinite(own)] = typical
    # one cap for the whole crack (its cells' typical room across), so the lips run even; a
    # vertex with less room (a cell the cut left thin) opens at most half of it
    step = narrowed * np.minimum(np.minimum(reach, OPEN_CAP * typical), 0.5 * own)
    step[held[split]] = 0.0
    return open_copies(gm, vid, pos, split, step, unit)
