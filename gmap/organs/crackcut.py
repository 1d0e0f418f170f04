"""Cut a crack through a 3-G-map's cells along its curve on the skin (issue 40, item 2).

:mod:`ramure.gmap.organs.mapcracks` used to snap a crack to the skin's existing edges, so on
a picture it was a staircase along the mesh grid. Here the crack follows its own curve:

1. **Curves**: the pattern walked over the skin (:func:`ramure.gmap.organs.cracks.project`,
   densely) is split into chains (an arc continues its parent's chain when it is the parent's
   first child, else it starts a chain of its own), each a polyline on the skin with, per
   sample, the skin normal ``n``, the side vector ``b = d x n`` and the profile ``(w, h)``.
2. **Ribbon**: under a chain the crack is the ruled surface swept by the normals through the
   curve, down to the depth ``h``. Its field at a point ``p`` is ``s(p) = (p - q) . b(q)``,
   ``q`` the point of the polyline nearest ``p`` and ``b`` interpolated along it: zero on the
   ribbon, continuous across the chain's corners (``b`` is shared at a sample).
3. **Cells**: a cell is cut when its corners hold both signs of ``s``, its centroid lies
   under the chain (nearest point strictly inside it), less than ``h`` deep and within the
   cell's own radius of the ribbon. The chain's two ends are first cut square (a plane
   through the end, across the curve) in the cells astride them, so the crack stops where
   its curve stops, not where a cell happens to end.
4. **Splitting** (the plane cut of :func:`ramure.gmap.kernel.mapcut.cut_map`, with the
   ribbon's field for the plane's distance and only the chosen cells): edges crossing the
   ribbon are split where ``s`` is zero (linear in ``s`` along the edge), then the faces
   between their new vertices (both sides of sewn faces, so a neighbour's face gets the new
   edge too), then the cells along the loops of new edges; the two new faces of a split cell
   are sewn to each other. A corner with ``|s|`` below :data:`SNAP` times the mean skin
   edge counts as just off the ribbon (on its ``+`` side), so no face merely touches it; a
   corner nearer than ``pull`` (a fraction of its shortest edge) is first moved onto it.

:func:`ribbon_cut` returns the new faces; :func:`ramure.gmap.organs.mapcracks.crack_map`
unsews them and opens the crack. The crack's mouth on the skin is then the polyline where
the ribbon meets the skin's faces: it follows the curve to within the error of a straight
edge split in a curved field (a few hundredths of a cell), where the old snapped crack was
off by up to half a cell.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.mapcut import crossed_faces, on_plane_runs, pad_new_darts, split_crossing_volumes

#: A cut's field at points: ``(value, unit gradient)``.
Field = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3
    from ramure.gmap.organs.trimesh import TriMesh

#: Corners closer to the ribbon than this fraction of a skin edge are moved to its ``+`` side
#: (in ``s`` only, not in space): a face never merely touches the ribbon at a corner.
SNAP = 1e-6
#: An edge along a curved cut whose middle is off it by more than this fraction of its length
#: is split there, the new vertex put on the cut.
BEND = 0.02


@dataclass
class Curve:
    """One chain of a crack on the skin: ``points`` (k, 3) along it, per point the skin
    ``normal`` and the ``side`` vector ``b = d x n`` (unit), the profile ``width``/``depth``,
    and ``length`` (k,) the arc length from the chain's start."""

    points: np.ndarray
    normal: np.ndarray
    side: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    starts_free: bool = True

    def _tree(self) -> cKDTree:
        """A k-d tree of the points, built once (the points never change)."""
        if getattr(self, "_kd", None) is None:
            self._kd = cKDTree(self.points)
        return self._kd

    @property
    def length(self) -> np.ndarray:
        steps = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        return np.r_[0.0, np.cumsum(steps)]

    def nearest(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For points ``p`` (n, 3): ``(segment, t, q)``, the nearest point ``q`` of the polyline,
        on segment ``segment`` at fraction ``t`` (0..1)."""
        a, b = self.points[:-1], self.points[1:]
        k = len(a)
        near = self._tree().query(p)[1]
        best_d = np.full(len(p), np.inf)
        seg = np.zeros(len(p), np.int64)
        frac = np.zeros(len(p))
        for offset in (-1, 0):  # the two segments at the nearest sample
            s = np.clip(near + offset, 0, k - 1)
            edge = b[s] - a[s]
            t = np.clip(np.einsum("ij,ij->i", p - a[s], edge) / np.maximum(np.einsum("ij,ij->i", edge, edge), 1e-300), 0, 1)
            d = np.linalg.norm(a[s] + t[:, None] * edge - p, axis=1)
            better = d < best_d
            best_d[better], seg[better], frac[better] = d[better], s[better], t[better]
        q = self.points[seg] + frac[:, None] * (self.points[seg + 1] - self.points[seg])
        return seg, frac, q

    def field(self, p: np.ndarray) -> dict[str, np.ndarray]:
        """The ribbon's field at points ``p``: ``s`` (signed distance across the ribbon), ``along``
        (arc length of the nearest point), ``depth`` (below the curve along its normal), the
        profile ``w``, ``h`` there, and ``inside`` (the nearest point is not an end of the chain)."""
        p = np.asarray(p, np.float64).reshape(-1, 3)
        seg, t, q = self.nearest(p)
        mix = t[:, None]

        def at(values):
            w = mix if values.ndim == 2 else t
            return (1 - w) * values[seg] + w * values[seg + 1]

        side, normal = at(self.side), at(self.normal)
        side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-300)
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        along = at(self.length)
        total = self.length[-1]
        return {
            "s": np.einsum("ij,ij->i", p - q, side),
            "side": side,
            "along": along,
            "depth": np.einsum("ij,ij->i", q - p, normal),
            "w": at(self.width),
            "h": at(self.depth),
            "inside": (along > 1e-9 * total) & (along < total * (1 - 1e-9)),
        }

    def rounded(self, radius: float, mesh: TriMesh) -> Curve:
        """The chain with its corners rounded over about ``radius`` of arc length (a moving
        average of its points, the ends held by odd reflection), put back on ``mesh``'s
        surface; each point takes the normal of the triangle it lands on. A crack's chain turns
        at the pattern's nodes by up to 70 degrees: a corner inside a cell cannot be followed by
        the one straight edge a cut puts across a face, a curve bent over a cell can."""
        steps = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        k = int(min(round(radius / max(float(np.median(steps)), 1e-300)), len(self.points) - 1))
        if k < 1:
            return self
        p = self.points
        padded = np.concatenate([2 * p[0] - p[k:0:-1], p, 2 * p[-1] - p[-2 : -k - 2 : -1]])
        kernel = np.ones(2 * k + 1) / (2 * k + 1)
        smooth = np.stack([np.convolve(padded[:, j], kernel, mode="valid") for j in range(3)], axis=1)
        smooth[0], smooth[-1] = p[0], p[-1]
        points, normal = onto(mesh, smooth)
        d = np.gradient(points, axis=0)
        side = np.cross(d, normal)
        side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-300)
        return Curve(points, normal, side, self.width, self.depth, self.starts_free)

    def values(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(s, side)`` of :meth:`field` at points ``p``: the ribbon's value and unit gradient."""
        f = self.field(p)
        return f["s"], f["side"]

    def end_plane(self, end: int) -> tuple[np.ndarray, np.ndarray]:
        """``(point, unit normal)`` of the plane across the chain at its ``end`` (0 or -1), the
        normal pointing out of the chain."""
        if end == 0:
            p, d = self.points[0], self.points[0] - self.points[1]
        else:
            p, d = self.points[-1], self.points[-1] - self.points[-2]
        n = self.normal[end]
        d = d - (d @ n) * n  # across the curve, along the normal: the end is cut square
        return p, d / max(float(np.linalg.norm(d)), 1e-300)


def onto(mesh: TriMesh, points: np.ndarray, candidates: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) near ``mesh`` moved to its surface: ``(points on it, normal of their
    triangle)``, among the ``candidates`` triangles whose centres are nearest each point (the
    points lie within a triangle's size of the surface: a curve rounded on it)."""
    points = np.asarray(points, np.float64)
    tris = mesh.points[mesh.triangles]  # (t, 3, 3)
    k = min(candidates, len(tris))
    cand = cKDTree(tris.mean(axis=1)).query(points, k=k)[1].reshape(len(points), k)
    a, b, c = (tris[cand, j] for j in range(3))  # (n, k, 3)
    p = points[:, None, :]
    n = mesh.normals[cand]
    inside = p - np.einsum("nkj,nkj->nk", p - a, n)[..., None] * n
    v0, v1, v2 = b - a, c - a, inside - a
    d00, d01, d11 = (v0 * v0).sum(-1), (v0 * v1).sum(-1), (v1 * v1).sum(-1)
    d20, d21 = (v2 * v0).sum(-1), (v2 * v1).sum(-1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    v, w = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
    within = (v >= 0) & (w >= 0) & (v + w <= 1)
    options = [np.where(within[..., None], inside, np.inf)]
    for s, e in ((a, b), (b, c), (c, a)):
        edge = e - s
        t = np.clip(np.einsum("nkj,nkj->nk", p - s, edge) / np.maximum((edge * edge).sum(-1), 1e-300), 0, 1)
        options.append(s + t[..., None] * edge)
    stack = np.stack(options)  # (4, n, k, 3)
    dist = np.linalg.norm(stack - p[None], axis=-1)
    dist[~np.isfinite(dist)] = np.inf
    flat = dist.transpose(1, 0, 2).reshape(len(points), -1)  # (n, 4 k)
    best = flat.argmin(axis=1)
    option, slot = best // k, best % k
    rows = np.arange(len(points))
    return stack[option, rows, slot], mesh.normals[cand[rows, slot]]


def thickness(mesh: TriMesh, points: np.ndarray, normals: np.ndarray, chunk: int = 64) -> np.ndarray:
    """Distance from each skin point inward (along ``-normal``) to the skin's other side: the
    nearest hit of the ray beyond a thousandth of the mesh's size (Moeller-Trumbore, in chunks of
    ``chunk`` rays against every triangle); ``inf`` where the ray leaves without a hit."""
    tris = mesh.points[mesh.triangles]
    a = tris[:, 0]
    e1, e2 = tris[:, 1] - a, tris[:, 2] - a
    skip = 1e-3 * float(np.ptp(mesh.points, axis=0).max())
    out = np.full(len(points), np.inf)
    for lo in range(0, len(points), chunk):
        o = np.asarray(points[lo : lo + chunk], np.float64)[:, None, :]
        d = -np.asarray(normals[lo : lo + chunk], np.float64)[:, None, :]
        h = np.cross(d, e2[None])
        det = np.einsum("rtj,tj->rt", h, e1)
        ok = np.abs(det) > 1e-300
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        sv = o - a[None]
        u = np.einsum("rtj,rtj->rt", sv, h) * inv
        q = np.cross(sv, e1[None])
        v = np.einsum("rtj,rtj->rt", d, q) * inv
        t = np.einsum("tj,rtj->rt", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > skip)
        out[lo : lo + chunk] = np.where(hit, t, np.inf).min(axis=1)
    return out


def chains(arcs: list, parent: np.ndarray, times: list[np.ndarray], width: list, depth: list, until: float) -> list[Curve]:
    """Chains of the walked pattern's ``arcs`` (``(i, j, samples)`` as from
    :func:`ramure.gmap.organs.cracks.project`), each sample kept while its time (``times``, per
    arc) is at most ``until``; ``width``/``depth`` per arc per sample. An arc continues its
    parent's chain when it is the parent's first child, else it starts a chain at the parent
    (a branch: ``starts_free`` False, its start is not cut square, it opens on the other chain)."""
    first_child: dict[int, int] = {}
    for i, j, _ in arcs:
        first_child.setdefault(i, j)
    open_chain: dict[int, int] = {}  # node -> index of the chain ending there
    parts: list[list[tuple]] = []
    nodes: list[set[int]] = []  # per chain, the pattern nodes it passes
    branch: list[bool] = []  # per chain, does it start on an earlier chain
    for (i, j, samples), tk, wk, hk in zip(arcs, times, width, depth):
        rows = [(s[0], s[1], s[2], w, h) for s, t, w, h in zip(samples, tk, wk, hk) if t <= until]
        if len(rows) < 2:
            continue
        if first_child[i] == j and i in open_chain:
            c = open_chain.pop(i)
            parts[c].extend(rows[1:])
        else:  # a branch (or the root's first chain): it starts on another chain's path unless at the root
            c = len(parts)
            parts.append(list(rows))
            branch.append(bool(parts[:-1]) and any(i in seen for seen in nodes))
            nodes.append(set())
        nodes[c].update((i, j))
        open_chain[j] = c
    out = []
    for rows, starts_on_chain in zip(parts, branch):
        pos = np.array([r[0] for r in rows])
        keep = np.r_[True, np.linalg.norm(np.diff(pos, axis=0), axis=1) > 1e-9]
        rows = [r for r, k in zip(rows, keep) if k]
        if len(rows) < 2:
            continue
        pos = np.array([r[0] for r in rows])
        d = np.array([r[1] for r in rows])
        n = np.array([r[2] for r in rows])
        side = np.cross(d, n)
        side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-300)
        out.append(Curve(pos, n, side, np.array([r[3] for r in rows]), np.array([r[4] for r in rows]), not starts_on_chain))
    return out


def split_cells(
    gm: GMap3,
    s: np.ndarray,
    grad: np.ndarray,
    cells: np.ndarray,
    snap: float,
    field: Field | None = None,
    pull: float = 0.15,
) -> np.ndarray:
    """Split the volumes ``cells`` (mask) of ``gm`` in place along the zero set of ``s`` (one
    value per vertex id of ``gm.cells(0)``, ``grad`` its unit gradient there); returns the
    darts of the new faces (both sides).

    A corner of a chosen cell nearer the zero set than ``pull`` times its shortest edge is
    first moved onto it (by ``-s grad``), so no cut leaves a sliver cell that any opening would
    turn inside out. Then edges of the chosen cells from ``s < 0`` to ``s > 0`` are split at
    ``s = 0``, their faces, then the cells (:func:`ramure.gmap.kernel.mapcut.cut_map`'s steps).
    Other values within ``snap`` of 0 count as ``+snap``. With ``field`` (points -> ``s``; a
    curved cut, not a plane) the moved corners are put back on the zero set by two more
    Newton steps, edges left along the cut are bent onto it (:func:`_bend`), and each edge
    is split where ``field`` changes sign along it (bisection), not where the straight line
    between its end values says."""
    vid, nv = gm.cells(0)
    in_cell = cells[gm.dart_volume]
    _, pos = gm.vertex_positions()
    elen = np.linalg.norm(pos[vid[gm.alpha[0]]] - pos[vid], axis=1)
    shortest = np.full(nv, np.inf)
    np.minimum.at(shortest, vid[in_cell], elen[in_cell])
    close = np.isfinite(shortest) & (np.abs(s) < pull * shortest)
    s = np.where(np.abs(s) < snap, snap, s)
    if close.any():
        moved = pos[close] - s[close, None] * grad[close]
        if field is not None:
            for _ in range(2):
                moved -= field(moved)[0][:, None] * grad[close]
        take = close[vid]
        gm.points[take] = moved[np.searchsorted(np.flatnonzero(close), vid[take])]
        gm.corners[take] = gm.points[take]
        s = np.where(close, 0.0, s)
    sd = s[vid]
    if field is not None:
        sd = _bend(gm, sd, cells, field)
        vid, _ = gm.cells(0)
    _, pos = gm.vertex_positions()
    crossing = cells & (np.bincount(gm.dart_volume, sd < 0, minlength=gm.n_volumes) > 0)
    crossing &= np.bincount(gm.dart_volume, sd > 0, minlength=gm.n_volumes) > 0
    if not crossing.any():
        return np.empty(0, np.int64)
    a0 = gm.alpha[0]
    d = np.flatnonzero(crossing[gm.dart_volume] & (sd < 0) & (sd[a0] > 0))
    gm.reserve(gm.n_darts + 48 * len(d) + 64)
    if d.size:
        key = vid[d].astype(np.int64) * (int(vid.max()) + 1) + vid[a0[d]]
        _, first = np.unique(key, return_index=True)
        d = d[first]
        t = sd[d] / (sd[d] - sd[a0[d]])
        if field is not None:
            t = _root(field, pos[vid[d]], pos[vid[a0[d]]])
        gm.split_edge(d, t)
    sd = np.r_[sd, np.zeros(gm.n_darts - len(sd))]
    for _ in range(8):
        sd, more = _split_faces(gm, sd, crossing)
        if not more:
            break
    else:
        raise GMapError("the crack crosses a face too many times: use a finer map")
    if field is not None:  # the new edges across faces are chords of the cut: bend them too
        sd = _bend(gm, sd, crossing, field)
    before = gm.n_darts
    split_crossing_volumes(gm, sd, crossing)
    return np.arange(before, gm.n_darts)


def _bend(gm: GMap3, sd: np.ndarray, cells: np.ndarray, field: Field) -> np.ndarray:
    """Edges of the chosen ``cells`` with both ends on a curved cut (moved there) but their
    middle off it by more than :data:`BEND` of their length are split in the middle, the new
    vertex moved onto the cut (a crack's wall follows its curve, not the chord): up to three
    rounds. ``sd``: per dart; ``field``: points -> (value, unit gradient); returns ``sd`` grown
    for the new darts (0: on the cut)."""
    for _ in range(3):
        vid, _ = gm.cells(0)
        _, pos = gm.vertex_positions()
        a0 = gm.alpha[0]
        d = np.flatnonzero(cells[gm.dart_volume] & (sd == 0) & (sd[a0] == 0) & (vid < vid[a0]))
        if not d.size:
            break
        _, first = np.unique(vid[d].astype(np.int64) * (int(vid.max()) + 1) + vid[a0[d]], return_index=True)
        d = d[first]
        p, q = pos[vid[d]], pos[vid[a0[d]]]
        mid = 0.5 * (p + q)
        off = np.abs(field(mid)[0]) > BEND * np.linalg.norm(q - p, axis=1)
        d, mid = d[off], mid[off]
        if not d.size:
            break
        for _ in range(3):
            value, g = field(mid)
            mid = mid - value[:, None] * g
        n_before = gm.n_darts
        new = gm.split_edge(d, 0.5)
        vid, _ = gm.cells(0)
        slot = np.full(int(vid.max()) + 1, -1, np.int64)
        slot[vid[new]] = np.arange(len(new))
        added = np.arange(n_before, gm.n_darts)
        at = slot[vid[added]]
        gm.points[added] = mid[at]
        gm.corners[added] = mid[at]
        sd = np.r_[sd, np.zeros(len(added))]
    return sd


def _root(field: Field, p: np.ndarray, q: np.ndarray, steps: int = 30) -> np.ndarray:
    """Fraction ``t`` along each segment ``p -> q`` (``field`` < 0 at ``p``, > 0 at ``q``) where
    ``field`` changes sign (bisection, ``steps`` halvings), kept strictly inside (0, 1)."""
    lo, hi = np.zeros(len(p)), np.ones(len(p))
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        negative = field(p + mid[:, None] * (q - p))[0] < 0
        lo, hi = np.where(negative, mid, lo), np.where(negative, hi, mid)
    return np.clip(0.5 * (lo + hi), 1e-9, 1 - 1e-9)


def _split_faces(gm: GMap3, sd: np.ndarray, crossing: np.ndarray) -> tuple[np.ndarray, bool]:
    """:func:`ramure.gmap.kernel.mapcut.cut_map`'s face step, where a corner moved onto the
    cut that only touches it in a face (its two neighbours in the face on one side) is not a
    crossing of that face, and a face the cut does not cross cleanly takes its cells out of
    ``crossing`` (changed in place) instead of refusing the whole crack."""
    faces = crossed_faces(gm, sd, crossing)
    if faces is None:
        return sd, False
    walk, length = gm.face_walk(faces)
    corners = walk[:, 0::2]
    ok = corners >= 0
    degree = (length // 2)[:, None]
    value = np.where(ok, sd[np.maximum(corners, 0)], np.nan)
    k = np.arange(corners.shape[1])[None, :]
    rows = np.arange(len(faces))[:, None]
    before = np.sign(value[rows, (k - 1) % degree])
    after = np.sign(value[rows, (k + 1) % degree])
    zero = ok & (value == 0) & ~(before * after > 0)
    nz = zero.sum(axis=1)
    a, b = on_plane_runs(zero, nz)
    rows = np.arange(len(faces))
    # a face the cut meets at an odd count of corners, or along one of its edges, is left whole
    # and its cells uncut (the crack ends at them, as at a tip)
    bad = (nz < 2) | (nz % 2 == 1) | (b - a < 2)
    if bad.any():
        left = faces[bad]
        crossing[gm.dart_volume[np.r_[left, gm.alpha[3][left]]]] = False
        keep = ~bad
        corners, a, b, nz, rows = corners[keep], a[keep], b[keep], nz[keep], np.arange(int(keep.sum()))
    if len(rows):
        gm.split_faces(corners[rows, a], b - a)
    return pad_new_darts(sd, gm), bool(np.any(nz > 2))


def ribbon_cut(gm: GMap3, curve: Curve, snap: float, pull: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """Cut ``gm`` in place along ``curve``'s ribbon (ends cut square first); returns the darts
    of the ribbon's new faces (both sides; to be unsewn) and of the ends' new faces (to stay
    sewn; they copied their attributes from the faces round them, which may be walls of an
    earlier chain). ``pull``: see :func:`split_cells`. See the module's steps 3 and 4."""
    ends = []
    for end in (0, -1):
        if end == 0 and not curve.starts_free:
            continue
        point, normal = curve.end_plane(end)
        _, pos = gm.vertex_positions()
        chosen = _chosen(gm, curve, gm.volume_centroids(), pos, end)
        ends.append(split_cells(gm, (pos - point) @ normal, np.broadcast_to(normal, pos.shape), chosen, snap, pull=pull))
    _, pos = gm.vertex_positions()
    chosen = _chosen(gm, curve, gm.volume_centroids(), pos)
    f = curve.field(pos)
    ribbon = split_cells(gm, f["s"], f["side"], chosen, snap, curve.values, pull)
    return ribbon, np.concatenate(ends) if ends else np.empty(0, np.int64)


def _chosen(gm: GMap3, curve: Curve, centres: np.ndarray, pos: np.ndarray, end: int | None = None) -> np.ndarray:
    """Cells under the chain: the centroid less than ``h`` deep and within the cell's radius of
    the ribbon, its nearest point inside the chain (``end`` 0 or -1: instead, within the
    cell's radius of that end of the chain, for its square cut)."""
    vid, _ = gm.cells(0)
    reach = np.zeros(gm.n_volumes)
    np.maximum.at(reach, gm.dart_volume, np.linalg.norm(pos[vid] - centres[gm.dart_volume], axis=1))
    f = curve.field(centres)
    near = (np.abs(f["s"]) < reach) & (f["depth"] < f["h"]) & (f["depth"] > -reach)
    if end is None:
        return near & f["inside"]
    tip = curve.points[end]
    return near & (np.linalg.norm(centres - tip, axis=1) < 2 * reach + curve.depth[end])


def ring_curve(
    mesh: TriMesh,
    height: float,
    arc: float = 360.0,
    start: float = 0.0,
    width: float = 1.0,
    depth: float = 1.0,
    axis: tuple[float, float] = (0.0, 0.0),
    spacing: float | None = None,
) -> Curve:
    """A concentric crack's curve: the skin's section by the plane ``z = height`` (the outer
    loop round the vertical axis through ``axis``), from ``start`` degrees (from +x, counter-
    clockwise seen from above) over ``arc`` degrees, ``width``/``depth`` all along.

    A tomato's concentric (growth) cracks circle the stem scar: this is that circle on the true
    skin, not a walk. A closed ring (``arc`` 360) is refused: unsewn all round, the cap round the
    stem would come off (use at most 350 degrees). Points are ``spacing`` apart (default an
    eighth of the skin's mean triangle edge)."""
    import pyvista as pv

    if not (np.isfinite(arc) and 0 < arc <= 350):
        raise GMapError(f"a concentric crack runs over 0 < arc <= 350 degrees (a closed ring would cut the cap off), not {arc}")
    tris = np.c_[np.full(len(mesh.triangles), 3), mesh.triangles].ravel()
    surface = pv.PolyData(mesh.points, tris)
    section = surface.slice(normal=(0.0, 0.0, 1.0), origin=(axis[0], axis[1], float(height)))
    if section.n_points < 3:
        raise GMapError(f"the plane z = {height:g} misses the skin: no concentric crack there")
    loops = section.connectivity()
    region = np.asarray(loops.point_data["RegionId"])
    p = np.asarray(loops.points)
    rho = np.hypot(p[:, 0] - axis[0], p[:, 1] - axis[1])
    outer = max(np.unique(region), key=lambda r: rho[region == r].mean())
    p = p[region == outer]
    theta = np.degrees(np.arctan2(p[:, 1] - axis[1], p[:, 0] - axis[0]))
    turn = (theta - start) % 360.0
    order = np.argsort(turn)
    p, turn = p[order], turn[order]
    p, turn = np.r_[p[-1:], p, p[:1]], np.r_[turn[-1] - 360.0, turn, turn[0] + 360.0]  # closed round
    inside = (turn > 0) & (turn < arc)
    ends = [np.array([np.interp(x, turn, p[:, j]) for j in range(3)]) for x in (0.0, arc)]
    p = np.vstack([ends[0], p[inside], ends[1]])  # from exactly ``start`` to ``start + arc``
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    along = np.r_[0.0, np.cumsum(steps)]
    edge = float(np.linalg.norm(mesh.points[mesh.triangles[:, 0]] - mesh.points[mesh.triangles[:, 1]], axis=1).mean())
    step = edge / 8 if spacing is None else float(spacing)
    at = np.linspace(0.0, along[-1], max(int(np.ceil(along[-1] / step)) + 1, 2))
    points = np.stack([np.interp(at, along, p[:, j]) for j in range(3)], axis=1)
    points, normal = onto(mesh, points)
    side = np.cross(np.gradient(points, axis=0), normal)
    side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-300)
    k = len(points)
    return Curve(points, normal, side, np.full(k, float(width)), np.full(k, float(depth)))
