"""Round damage marks on a fruit's skin: hail pits and rot lesions drawn as discs, not as the
skin faces of the cells the defects marked (no Qt; pyvista meshes, numpy).

The defects mark whole cells (:mod:`ramure.gmap.organs.defects`: ``scar`` and ``bruise`` at a
hail pit, ``rot`` round a lesion); coloured per face, a mark is a square aligned with the mesh.
Here each mark becomes a :class:`Disc` found from the marked skin faces:

* a **hail pit**: centred on the hit skin vertex (the vertex whose skin faces all carry the
  full bruise), of the radius the grading uses (the half-depth radius of
  :func:`ramure.gmap.organs.defects.hail`: ``s / 2 / (1 - HAIL_RIM)``, ``s`` the mean length
  of the vertex's skin edges), healed when its faces carry the ``scar``;
* a **rot lesion**: one per connected patch of rotting skin faces, centred on the patch's
  vertex with the most rot round it, of the patch's equivalent radius (the disc of its area).

:func:`draw_round_marks` then subdivides the skin faces near each disc (midpoints, so the
shape does not move): finely where the colour changes sharply (the mark's edge, mould), less
in the soft bruise halo, not below two pixels (:func:`_levels`); and colours every face by
its centroid's distance from the disc's centre (:func:`ramure.gmap.organs.species.round_mark_rgb`).
Neighbouring faces subdivided to different levels meet at T-junctions: their midpoints lie on
the shared edge, so no gap opens (none seen in the batch's face-id pictures).
Distances are straight lines, taken only on the disc's side of the fruit (face normal within
90 degrees of the disc's): over a mark a few millimetres across on a fruit centimetres
across, this is the distance along the skin to within a percent.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pyvista as pv

#: A subdivided face's longest edge is at most this fraction of the disc's radius, by kind
#: (a rot lesion's mould colonies are a tenth of its radius across).
FINE_EDGE = {"hail": 0.08, "rot": 0.035}
#: Where a mark's colour changes softly, faces down to this fraction of its radius.
SOFT_EDGE = 0.3
#: At most this many midpoint subdivisions (each splits a triangle in four).
MAX_LEVELS = 5
#: Skin faces face outward: ``|normal . radial|`` above this (walls of a crack are below).
SKIN_COSINE = 0.7


@dataclass(frozen=True, eq=False)
class Disc:
    """A round mark: ``kind`` (``"hail"`` or ``"rot"``), centre and outward normal, radius
    (model units), healed (a hail pit's corky scar), and ``faces``: the surface's marked faces
    it was found from (their cells are the defect's); a hail pit's ``depth`` below its first
    ring of skin vertices and ``bowl``, the radius where the crater meets the untouched skin
    (twice that ring's mean distance), both model units."""

    kind: str
    centre: np.ndarray
    normal: np.ndarray
    radius: float
    healed: bool = False
    faces: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    depth: float = 0.0
    bowl: float = 0.0


def skin_faces(surface: pv.PolyData, centre: np.ndarray) -> np.ndarray:
    """Boolean per face: the skin.  An uncut fruit's outer faces are all skin but a crack's
    walls: faces of the cells a crack marked (cell data ``corky``, ``wound``) turned away from
    the direction out of ``centre`` (``|normal . radial|`` at most :data:`SKIN_COSINE`).  The
    radial test alone failed on a curved banana, whose skin is far from radial."""
    walls = np.zeros(surface.n_cells, bool)
    for name in ("corky", "wound"):
        if name in surface.cell_data:
            walls |= np.asarray(surface.cell_data[name], float) > 0
    if not walls.any():
        return np.ones(surface.n_cells, bool)
    normals = surface.compute_normals(cell_normals=True, point_normals=False, auto_orient_normals=True)
    n = np.asarray(normals.cell_data["Normals"], float)
    out = np.asarray(surface.cell_centers().points, float) - np.asarray(centre, float)
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    return ~walls | (np.abs(np.einsum("ij,ij->i", n, out)) > SKIN_COSINE)


def _faces(surface: pv.PolyData) -> tuple[np.ndarray, np.ndarray]:
    """``(point ids, face of each)`` of every face corner, in face order (any polygon sizes)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    polys = surface.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    ids = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    return ids, np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))


def _edges(ids: np.ndarray, face: np.ndarray) -> np.ndarray:
    """``(n, 2)`` point ids of each face's edges (corner to next corner round the face)."""
    first = np.r_[True, face[1:] != face[:-1]]
    start = np.maximum.accumulate(np.where(first, np.arange(len(face)), 0))
    last = np.r_[face[1:] != face[:-1], True]
    nxt = np.where(last, start, np.arange(len(face)) + 1)
    return np.stack([ids, ids[nxt]], axis=1)


def mark_discs(surface: pv.PolyData, centre: np.ndarray) -> list[Disc]:
    """The round marks of a fruit's outer surface (cell data ``bruise``, ``scar``, ``rot`` as
    :func:`ramure.app.fruit_look.coloured_grid` carries them; see the module docstring)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from ramure.gmap.organs.defects import HAIL_RIM

    if surface.n_cells == 0 or not any(k in surface.cell_data for k in ("bruise", "rot")):
        return []
    skin = skin_faces(surface, centre)
    ids, face = _faces(surface)
    pts = np.asarray(surface.points, float)
    n_pts = len(pts)
    normals = np.asarray(
        surface.compute_normals(cell_normals=True, point_normals=False, auto_orient_normals=True).cell_data["Normals"]
    )
    discs: list[Disc] = []
    on_skin = skin[face]
    all_count = np.bincount(ids[on_skin], minlength=n_pts)
    if "bruise" in surface.cell_data:
        bruise = np.asarray(surface.cell_data["bruise"], float)
        scar = np.asarray(surface.cell_data["scar"], float) if "scar" in surface.cell_data else np.zeros(surface.n_cells)
        hit = skin & (bruise >= 0.999)
        hit_count = np.bincount(ids[hit[face]], minlength=n_pts)
        centres = np.flatnonzero((hit_count >= 3) & (hit_count == all_count))
        edges = np.unique(np.sort(_edges(ids, face)[on_skin], axis=1), axis=0)  # each skin edge once
        length = np.linalg.norm(pts[edges[:, 0]] - pts[edges[:, 1]], axis=1)
        for p in centres.tolist():
            near = (edges[:, 0] == p) | (edges[:, 1] == p)
            s = float(length[near].mean()) if near.any() else 0.0
            mine = np.unique(face[(ids == p) & hit[face]])
            nrm = normals[mine].mean(axis=0)
            radius = 0.5 * s / (1.0 - HAIL_RIM)
            unit = nrm / max(np.linalg.norm(nrm), 1e-12)
            depth = _pit_depth(pts, edges, p, unit, 1.0 - HAIL_RIM)
            healed = bool(scar[mine].mean() > 0.5)
            discs.append(Disc("hail", pts[p], unit, radius, healed, mine, depth, 2.0 * s))
    if "rot" in surface.cell_data:
        rot = np.asarray(surface.cell_data["rot"], float)
        rotten = skin & (rot > 0)
        if rotten.any():
            area = np.asarray(surface.compute_cell_sizes(length=False, volume=False).cell_data["Area"], float)
            keep = rotten[face]
            inc = coo_matrix((np.ones(int(keep.sum())), (face[keep], ids[keep])), shape=(surface.n_cells, n_pts)).tocsr()
            _, label = connected_components(inc @ inc.T, directed=False)
            around = np.bincount(ids[keep], weights=rot[face[keep]], minlength=n_pts)
            for lab in np.unique(label[rotten]).tolist():
                patch = rotten & (label == lab)
                corners = np.unique(ids[patch[face]])
                p = int(corners[np.argmax(around[corners])])
                nrm = (normals[patch] * area[patch, None]).sum(axis=0)
                radius = float(np.sqrt(area[patch].sum() / np.pi))
                unit = nrm / max(np.linalg.norm(nrm), 1e-12)
                discs.append(Disc("rot", pts[p], unit, radius, False, np.flatnonzero(patch)))
    return discs


def _pit_depth(pts: np.ndarray, edges: np.ndarray, p: int, normal: np.ndarray, share: float) -> float:
    """A crater's depth at its centre ``p`` below the skin it was dug into (model units).

    The crater pushed ``p`` in by ``D`` and its first ring of skin vertices by ``(1 - share) D``
    (``share = 1 - HAIL_RIM``); the second ring did not move.  Each ring vertex's height over
    ``p`` along ``normal`` is then ``share D - k r^2 / 2`` (first ring) or ``D - k r^2 / 2``
    (second), ``r`` its distance across and ``k`` the skin's curvature: ``D`` and ``k`` by
    least squares.  0 when the rings are missing."""
    first = np.setdiff1d(edges[(edges[:, 0] == p) | (edges[:, 1] == p)].ravel(), [p])
    touch = np.isin(edges[:, 0], first) | np.isin(edges[:, 1], first)
    second = np.setdiff1d(edges[touch].ravel(), np.r_[first, p])
    if first.size == 0 or second.size == 0:
        return 0.0
    ring = np.r_[first, second]
    rel = pts[ring] - pts[p]
    height = rel @ normal
    across = np.linalg.norm(rel - np.outer(height, normal), axis=1)
    a = np.stack([np.r_[np.full(first.size, share), np.ones(second.size)], -0.5 * across**2], axis=1)
    (depth, _), *_ = np.linalg.lstsq(a, height, rcond=None)
    return max(float(depth), 0.0)


def subdivide(
    points: np.ndarray, tris: np.ndarray, levels: int, normals: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Midpoint subdivision of triangles ``levels`` times: ``(points, triangles, parent,
    normals)``; new points are appended after ``points`` (shared between neighbours),
    ``parent`` is each new triangle's row in ``tris``.  Point ``normals``, when given, are
    carried to each midpoint as the normalised mean of its edge's ends, so a subdivided patch
    shades as smoothly as the faces it replaces (flat midpoint normals made it faceted)."""
    nrm = None if normals is None else np.asarray(normals, float)
    pts = np.asarray(points, float)
    tri = np.asarray(tris, np.int64).reshape(-1, 3)
    parent = np.arange(len(tri))
    for _ in range(int(levels)):
        n = len(tri)
        e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        uniq, inv = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True)
        mid = (len(pts) + np.arange(len(uniq)))[inv.reshape(-1)].reshape(3, n).T
        pts = np.vstack([pts, 0.5 * (pts[uniq[:, 0]] + pts[uniq[:, 1]])])
        if nrm is not None:
            m = nrm[uniq[:, 0]] + nrm[uniq[:, 1]]
            nrm = np.vstack([nrm, m / np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-12)])
        a, b, c = tri.T
        m01, m12, m20 = mid.T
        tri = np.concatenate([np.stack(x, axis=1) for x in ((a, m01, m20), (m01, b, m12), (m20, m12, c), (m01, m12, m20))])
        parent = np.tile(parent, 4)
    return pts, tri, parent, nrm


def draw_round_marks(
    surface: pv.PolyData,
    centre: np.ndarray,
    seed: int = 0,
    feature_angle: float | None = None,
    discs: list[Disc] | None = None,
    pixel: float = 0.0,
) -> pv.PolyData:
    """The surface with its hail pits and rot lesions drawn round (module docstring).

    ``surface`` carries cell data ``rgb`` (drawn colours) and ``rgb_plain`` (the same without
    bruise, scar and rot; :func:`ramure.app.fruit_look.coloured_grid`).  Skin faces take
    ``rgb_plain`` with the discs painted on, other faces (a crack's walls) keep ``rgb``.
    ``discs``: those of :func:`mark_discs` (found when None).  ``pixel``: the picture's
    pixel in model units: faces are not subdivided below about two of them (a batch's small
    pictures need far fewer faces than the gallery's close-ups).

    Returned triangulated, with point ``Normals`` for smooth shading (a renderer must use
    them, not recompute them: a subdivided face's midpoints would shade flat), split where
    faces meet at more than ``feature_angle`` degrees (None: not split), and cell data
    ``rgb``, ``face`` (the face of ``surface`` each comes from) and ``mark_bits`` (bit ``k``:
    disc ``k``'s weight is at least one half there, :func:`ramure.gmap.organs.species.mark_weight`).
    The surface itself when it has no round mark.
    """
    import pyvista as pv

    from ramure.gmap.organs.species import HAIL_HALO, mark_weight, round_mark_rgb

    if discs is None:
        discs = mark_discs(surface, centre) if "rgb_plain" in surface.cell_data else []
    if not discs or "rgb_plain" not in surface.cell_data:
        return surface
    skin = skin_faces(surface, centre)
    outward = np.asarray(
        surface.compute_normals(cell_normals=True, point_normals=False, auto_orient_normals=True).cell_data["Normals"], float
    )
    base = np.where(skin[:, None], surface.cell_data["rgb_plain"], surface.cell_data["rgb"]).astype(float)
    work = pv.PolyData(surface.points, surface.faces)
    work.cell_data["face"] = np.arange(surface.n_cells)
    shaded = work.triangulate().compute_normals(
        cell_normals=False,
        point_normals=True,
        split_vertices=feature_angle is not None,
        feature_angle=30.0 if feature_angle is None else float(feature_angle),
    )
    tris = np.asarray(shaded.faces, np.int64).reshape(-1, 4)[:, 1:]
    owner = np.asarray(shaded.cell_data["face"], np.int64)
    pts = np.asarray(shaded.points, float)
    level = np.where(skin[owner], _levels(pts, tris, discs, pixel), 0)
    near = level > 0
    fine_pts, fine_nrm = pts, np.asarray(shaded.point_data["Normals"], float)
    pieces, owners = [tris[~near]], [owner[~near]]
    for lv in np.unique(level[near]).tolist():  # each level apart: a shared edge's midpoints coincide
        group = np.flatnonzero(level == lv)
        fine_pts, new, parent, nrm = subdivide(fine_pts, tris[group], lv, fine_nrm)
        assert nrm is not None  # normals in, normals out
        fine_nrm = nrm
        pieces.append(new)
        owners.append(owner[group][parent])
    for d in discs:
        if d.depth > 0 and d.bowl > 0:
            fine_nrm = _pit_normals(fine_pts, fine_nrm, d)
    all_tris = np.vstack(pieces)
    all_owner = np.concatenate(owners)
    rgb = base[all_owner]
    bits = np.zeros(len(all_tris), np.int64)
    tri_mid = fine_pts[all_tris].mean(axis=1)
    painted_skin = skin[all_owner]
    for k, d in enumerate(discs):
        rel = (tri_mid - d.centre) / d.radius
        u = np.linalg.norm(rel, axis=1)
        # only skin faces the mark reaches, and not through a thin fruit to its far side
        hit = np.flatnonzero((u < HAIL_HALO + 0.1) & painted_skin & (outward[all_owner] @ d.normal > 0))
        e1 = np.cross(d.normal, [1.0, 0.0, 0.0] if abs(d.normal[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        xy = np.stack([rel[hit] @ e1, rel[hit] @ np.cross(d.normal, e1)], axis=1)
        rgb[hit] = round_mark_rgb(rgb[hit], d.kind, u[hit], d.healed, xy, seed + k)
        bits[hit[mark_weight(u[hit]) >= 0.5]] |= np.int64(1) << min(k, 62)
    out = pv.PolyData(fine_pts, np.hstack([np.full((len(all_tris), 1), 3, np.int64), all_tris]).ravel())
    out.point_data["Normals"] = fine_nrm
    out.point_data.active_normals_name = "Normals"
    out.cell_data["rgb"] = np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
    out.cell_data["face"] = all_owner
    out.cell_data["mark_bits"] = bits
    return out


def _levels(pts: np.ndarray, tris: np.ndarray, discs: list[Disc], pixel: float) -> np.ndarray:
    """Midpoint subdivisions each triangle needs (0 to :data:`MAX_LEVELS`): where a mark's
    colour changes sharply (its edge, a rot lesion's mould) faces shrink to
    :data:`FINE_EDGE` of its radius, where it changes softly (a pit's bruise halo, the soaked
    band) to :data:`SOFT_EDGE`, never below two ``pixel``; elsewhere none.  A triangle's
    nearest and farthest distances from a disc's centre are taken over a grid of 15 points
    on it, the nearest less a tenth of its longest edge."""
    from ramure.gmap.organs.species import HAIL_HALO, MARK_EDGE

    corners = pts[tris]
    longest = np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2), axis=1)
    grid = np.array([(i, j, 4 - i - j) for i in range(5) for j in range(5 - i)], float) / 4.0
    samples = np.einsum("sk,tkd->tsd", grid, corners)
    need = np.zeros(len(tris))
    for d in discs:
        dist = np.linalg.norm(samples - d.centre, axis=2)
        lo = (dist.min(axis=1) - 0.1 * longest) / d.radius
        hi = dist.max(axis=1) / d.radius
        sharp = (lo < MARK_EDGE[1] + 0.05) & (hi > MARK_EDGE[0] - 0.05)
        soft_to = HAIL_HALO if d.kind == "hail" else MARK_EDGE[0]
        soft = (lo < soft_to) & (hi > 0.4)
        if d.kind == "rot":  # the mould colonies, out to half the radius and a colony
            sharp |= lo < 0.65
        want = np.where(sharp, FINE_EDGE[d.kind] * d.radius, np.where(soft, SOFT_EDGE * d.radius, np.inf))
        want = np.maximum(want, 2.0 * pixel)
        ratio = np.where(np.isfinite(want), longest / want, 0.0)
        need = np.maximum(need, np.ceil(np.log2(np.maximum(ratio, 1.0))))
    return np.minimum(need, MAX_LEVELS).astype(np.int64)


def _pit_normals(points: np.ndarray, normals: np.ndarray, disc: Disc) -> np.ndarray:
    """Shading normals tilted as a smooth bowl would tilt them, so the pit reads as a pit.

    The crater's mesh is a few flat faces whose smoothed normals hardly tilt; the bowl
    ``z = -depth cos^2(pi r / (2 bowl))`` (``r`` along the skin from the centre, out to
    ``bowl``) has slope ``depth pi / (2 bowl) sin(pi r / bowl)``, and each point's normal
    leans that much towards the centre.  Only the shading changes, not the geometry."""
    rel = points - disc.centre
    flat = rel - np.outer(rel @ disc.normal, disc.normal)
    r = np.linalg.norm(flat, axis=1)
    sel = (r < disc.bowl) & (r > 0) & (normals @ disc.normal > 0.5) & (np.abs(rel @ disc.normal) < disc.bowl)
    slope = disc.depth * np.pi / (2.0 * disc.bowl) * np.sin(np.pi * r[sel] / disc.bowl)
    out = normals.copy()
    tilted = normals[sel] - slope[:, None] * flat[sel] / r[sel, None]
    out[sel] = tilted / np.linalg.norm(tilted, axis=1, keepdims=True)
    return out


def mark_area(surface: pv.PolyData, disc: Disc) -> float:
    """Area (model units squared) of ``surface``'s faces (drawn by :func:`draw_round_marks`)
    where ``disc``'s weight is at least one half: the mark a viewer sees."""
    from ramure.gmap.organs.species import mark_weight

    mids = np.asarray(surface.cell_centers().points, float)
    area = np.asarray(surface.compute_cell_sizes(length=False, volume=False).cell_data["Area"], float)
    inside = mark_weight(np.linalg.norm(mids - disc.centre, axis=1) / disc.radius) >= 0.5
    return float(area[inside].sum())
