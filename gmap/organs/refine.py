"""A region of a map refined alone, the rest byte-identical (issue 40 §6, a local precision).

:func:`refine_volumes` splits the given volumes ``levels`` times into hexahedra (x8 volumes
per level, each edge in 2) while every dart of every other volume keeps its bytes: its
position, its four involutions and its attributes.  That forbids splitting any face, edge
or vertex the region shares with the outside, so the refinement is *pillowed* (the
hexahedral meshers' name for it):

1. **Rim.**  The region's faces glued to a volume outside are its rim.  Each rim face stays
   whole, with its darts (ids, ``alpha0``, ``alpha1``, ``alpha3`` to the outside) as they
   were; only their ``alpha2`` and volume change.
2. **Core.**  A copy of the region in which every vertex on the rim is moved ``inset`` of the
   way into the region (along the region's edges leaving the rim, so inner layers keep their
   faces; a rim vertex on the skin moves along the skin) is subdivided
   ``levels`` times (:func:`ramure.gmap.kernel.subdivide.volume`), every new point linear
   (corners, edge midpoints, face and cell centroids).  The choice: the region is a finer
   mesh of the same fruit, its skin where it was; Catmull-Clark on the region's skin would
   shrink it away from the rest (by 2 to 5 % of the fruit's volume for a ring refined 2 or 3
   times) and turn thin skin cells inside out.
3. **Pillows.**  Between each rim face and its refined copy in the core, a transition cell:
   its outer face is the rim face (whole), its inner face the ``4**levels`` sub-faces of the
   core, its sides one polygon per rim edge (the rim edge, then the core's ``2**levels``
   segments): the cell where the precision changes.  Neighbouring pillows share their sides;
   a side reaching the skin is skin.

New darts take the ids of the region's darts that are not on the rim, then ids after the
last; new volumes take the region's volume ids, then ids after the last, so ids outside the
region never move.  Every new volume copies its parent's row (a fruit's ``ring``,
``sector``, tissue), so label patterns still select it, and gains ``refined`` (how many
times its parent was refined, 0 for the volumes as built) and ``sub`` (its number among its
parent's children, from 1; the pillows come after the core's children; 0 as built).  A
fruit's radial layer (Bohl's radial stage) is frozen in ``layer`` before the first
refinement, since the layer of a cell is otherwise measured from the finest cell at the skin
(:func:`ramure.gmap.organs.defects.radial_layers`).  The Euler characteristic is kept (the
region is cut into more cells, its union is the same).

>>> from ramure.gmap.organs.fruit import build_fruit
>>> from ramure.gmap.organs.regions import region_volumes
>>> gm = build_fruit("round_tomato")
>>> vols = region_volumes(gm, {"path": "(5, C3, *)"})
>>> out = refine_volumes(gm, vols)
>>> out.is_valid(), out.euler_characteristic() == gm.euler_characteristic()
(True, True)
>>> out.n_volumes - gm.n_volumes  # 8 hexahedra, 5 pillows (none on the skin face), less itself
12
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import subdivide as _subdivide
from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.kernel.prism import FACE_I

#: Most refinement levels of one region (x8 cells each).
MAX_LEVELS = 3
#: Most darts a refined map may have (as :data:`ramure.gmap.organs.fruit.MAX_DARTS`): a large
#: region refined 3 times is refused, not an out-of-memory.
MAX_DARTS = 8_000_000
#: Kind of point of the 8 children of a dart in volume subdivision (corner, edge, face, cell).
_CHILD_KIND = np.array([0, 1, 1, 2, 1, 2, 2, 3])


def _free(alpha: np.ndarray) -> np.ndarray:
    return alpha[3] == np.arange(alpha.shape[1])


def _cross(alpha: np.ndarray, darts: np.ndarray) -> np.ndarray:
    """For free (``alpha3``) ``darts``: the free dart met going round the dart's edge
    through the volumes (``alpha2``, then ``alpha3 alpha2`` until free)."""
    x = alpha[2][darts]
    todo = np.flatnonzero(alpha[3][x] != x)
    while len(todo):
        x[todo] = alpha[2][alpha[3][x[todo]]]
        todo = todo[alpha[3][x[todo]] != x[todo]]
    return x


def _pair_means(keys: np.ndarray, items: np.ndarray, values: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean of ``values`` per key over the distinct ``(key, item)`` pairs, and the pair counts."""
    big = int(items.max(initial=0)) + 1
    _, first = np.unique(keys * big + items, return_index=True)
    k = keys[first]
    n = np.bincount(k, minlength=count)
    mean = np.stack([np.bincount(k, values[first, j], minlength=count) for j in range(3)], axis=1)
    return mean / np.maximum(n, 1)[:, None], n


def _inset(core: GMap3, rim: np.ndarray, inset: float) -> None:
    """Move the core's vertices on rim faces ``inset`` of the way into the region (in place).

    A vertex moves along the region's edges that leave it off the rim (on the skin: along
    the skin's), so the layers inside (exocarp, mesocarp ...) keep their faces; with no such
    edge (a corner of the region) it moves towards the centroids of its cells, or of its
    skin faces on the skin."""
    vid, nv = core.cells(0)
    eid, ne = core.cells(1)
    side, ns = core.orbit_ids("01")
    free = _free(core.alpha)
    skin = free & ~rim
    on_rim = np.bincount(vid[rim], minlength=nv) > 0
    on_skin = np.bincount(vid[skin], minlength=nv) > 0
    edge_rim = np.bincount(eid[rim], minlength=ne) > 0
    edge_skin = np.bincount(eid[skin], minlength=ne) > 0
    pts = core.points
    step = pts[core.alpha[0]] - pts
    # fallbacks: the centroids of the cells round the vertex; on the skin, of its skin faces
    into, _ = _pair_means(vid, core.dart_volume.astype(np.int64), core.volume_centroids()[core.dart_volume] - pts, nv)
    if skin.any():
        per = np.bincount(side, minlength=ns)
        centre = np.stack([np.bincount(side, pts[:, j], minlength=ns) for j in range(3)], axis=1) / np.maximum(per, 1)[:, None]
        d = np.flatnonzero(skin)
        along, _ = _pair_means(vid[d], side[d], centre[side[d]] - pts[d], nv)
        into[on_skin] = along[on_skin]
    # along the edges off the rim (on the skin: the skin's edges off the rim)
    off = ~edge_rim[eid] & (edge_skin[eid] | ~on_skin[vid])
    d = np.flatnonzero(off)
    edges, n_edges = _pair_means(vid[d], eid[d], step[d], nv)
    into = np.where((n_edges > 0)[:, None], edges, into)
    move = on_rim[vid]
    pts[move] += inset * into[vid[move]]
    core.corners[:] = pts
    core.mark_changed()


def _subdivided(core: GMap3, levels: int) -> GMap3:
    """``core`` subdivided ``levels`` times, every new point linear (corners, edge midpoints,
    face and cell centroids: the boundary's Catmull-Clark points are replaced)."""
    for _ in range(levels):
        parent = core
        core = _subdivide.volume(parent, 1)
        rim = _free(parent.alpha)
        vid, nv = parent.cells(0)
        eid, ne = parent.cells(1)
        side, ns = parent.orbit_ids("01")
        on = [np.bincount(k[rim], minlength=c) > 0 for k, c in ((vid, nv), (eid, ne), (side, ns))]
        pts = parent.points
        per = np.bincount(side, minlength=ns)
        centre = np.stack([np.bincount(side, pts[:, j], minlength=ns) for j in range(3)], axis=1) / np.maximum(per, 1)[:, None]
        p = np.repeat(np.arange(parent.n_darts), 8)
        kind = np.tile(_CHILD_KIND, parent.n_darts)
        linear = np.zeros((core.n_darts, 3))
        touch = np.zeros(core.n_darts, bool)
        for k, key, lin in (
            (0, vid, pts),
            (1, eid, 0.5 * (pts + pts[parent.alpha[0]])),
            (2, side, centre[side]),
        ):
            sel = np.flatnonzero(kind == k)
            hit = sel[on[k][key[p[sel]]]]
            touch[hit] = True
            linear[hit] = lin[p[hit]]
        core.points[touch] = linear[touch]
        core.corners[:] = core.points
        core.mark_changed()
    return core


class _NewDarts(NamedTuple):
    """The darts a refinement makes, numbered ``0..len-1`` (core first), before ids are given."""

    alpha: np.ndarray  # (4, k): new darts by that numbering, an original dart d as -1 - d
    source: np.ndarray  # (k,): the dart each copies its columns from (core dart, or -1 - original)
    volume: np.ndarray  # (k,): local volume, the core's first then one pillow per rim face
    sides: np.ndarray  # new darts on the pillows' side faces (inner faces, label I)
    bottom: np.ndarray  # (r,): the side-face dart alpha2-glued to each rim dart
    rims: np.ndarray  # (r,): the rim darts (original ids), the pillows' outer faces
    parents: np.ndarray  # per local volume: the original volume it comes from


def refine_volumes(gm: GMap3, volumes: ArrayLike, levels: int = 1, inset: float | None = None) -> GMap3:
    """``gm`` with ``volumes`` refined ``levels`` times and pillowed at their rim (a new
    map; see the module docstring); every dart of every other volume keeps its bytes.

    ``inset``: how far rim vertices move into the region, as a fraction of the edge leaving
    the rim (default ``1 / (2 ** levels + 1)``: the pillow is as thick as the refined cells
    next to it)."""
    levels = int(levels)
    if not 1 <= levels <= MAX_LEVELS:
        raise ValueRefused(f"a region is refined 1 to {MAX_LEVELS} times (x2 to x{2**MAX_LEVELS} precision), got {levels}")
    inset = 1.0 / (2**levels + 1) if inset is None else float(inset)
    if not 0.0 < inset < 1.0:
        raise ValueRefused(f"inset is a fraction between 0 and 1, got {inset}")
    vols = np.unique(np.asarray(volumes, np.int64))
    if not len(vols) or vols[0] < 0 or vols[-1] >= gm.n_volumes:
        raise GMapError(f"refine: volume ids must be in 0..{gm.n_volumes - 1} and at least one")
    chosen = np.zeros(gm.n_volumes, bool)
    chosen[vols] = True
    inside = chosen[gm.dart_volume]
    a3 = gm.alpha[3]
    rim = inside & (a3 != np.arange(gm.n_darts)) & ~inside[a3]
    estimate = gm.n_darts + int(inside.sum()) * (8**levels - 1)
    if estimate > MAX_DARTS:
        raise ValueRefused(
            f"this region refined {levels} time(s) would give the map about {estimate:,} darts, more than the "
            f"limit of {MAX_DARTS:,}: select a smaller region or a lower precision"
        )
    core, loc = _core(gm, vols, inside, rim, levels, inset)
    return _assembled(gm, core, vols, inside, levels, _new_darts(gm, core, loc, rim, levels))


def _core(gm, vols, inside, rim, levels, inset):
    """The region alone (rim faces free, rim vertices inset) subdivided ``levels`` times, and
    each original dart's index in the region (-1 outside)."""
    region = np.flatnonzero(inside)
    m = len(region)
    loc = np.full(gm.n_darts, -1, np.int64)
    loc[region] = np.arange(m)
    alpha = gm.alpha.astype(np.int64)
    ca = loc[alpha[:, region]]
    ca[3] = np.where(inside[alpha[3, region]], ca[3], np.arange(m))
    data = gm.dart_data
    darts = {k: np.asarray(data[k])[region] for k in data}
    darts["volume"] = np.searchsorted(vols, gm.dart_volume[region]).astype(np.int32)
    darts["_src"] = region.astype(np.int64)
    darts["_rim"] = rim[region]
    vdata = {k: np.asarray(v)[vols] for k, v in gm.volume_data.items()}
    vdata["_parent"] = vols
    core = GMap3.from_arrays(ca, darts, vdata, {**gm.dart_rules(), "_src": "copy", "_rim": "copy"})
    _inset(core, rim[region], inset)
    return _subdivided(core, levels), loc


def _new_darts(gm, core, loc, rim, levels) -> _NewDarts:
    """The refined core's darts, then the pillows': a mirror of each core dart under a rim
    face (their inner faces), and their side faces (one polygon per rim edge: the rim edge,
    two lateral edges, the core's segments along the inset edge)."""
    alpha = gm.alpha.astype(np.int64)
    M = core.n_darts
    kc = core.alpha.astype(np.int64)
    face_rim = _free(kc) & core.dart_data["_rim"]
    side0, _ = gm.orbit_ids("01")
    src = core.dart_data["_src"].astype(np.int64)
    tops = np.flatnonzero(face_rim)  # core darts under a pillow's inner face
    q = len(tops)
    cross = _cross(kc, tops)
    same = face_rim[cross] & (side0[src[cross]] == side0[src[tops]])
    edge = tops[~same]  # core darts along the pillow's side faces
    b = len(edge)
    rims = np.flatnonzero(rim)  # original darts of the pillows' outer faces
    r = len(rims)
    corner = loc[rims] * 8**levels  # the core dart at the inset corner, along the same edge
    # numbering: core (M), top (q), u (b), bottom side (r), lateral (r), lateral top (r)
    o_top, o_u, o_bot = M, M + q, M + q + b
    o_lat, o_latt = o_bot + r, o_bot + 2 * r
    total = o_bot + 3 * r
    top_of = np.full(M, -1, np.int64)
    top_of[tops] = o_top + np.arange(q)
    u_of = np.full(M, -1, np.int64)
    u_of[edge] = o_u + np.arange(b)
    side_of = np.full(gm.n_darts, -1, np.int64)  # rim dart -> its index among rims
    side_of[rims] = np.arange(r)
    rim_at = np.full(M, -1, np.int64)  # core corner dart -> rim index
    rim_at[corner] = np.arange(r)
    if not face_rim[corner].all() or (side_of[src[tops]] < 0).any():
        raise GMapError("refine: a rim face lost its place in the core (internal error)")

    A = np.empty((4, total), np.int64)
    A[:, :M] = kc
    A[3, tops] = top_of[tops]
    t = top_of[tops]
    A[0, t], A[1, t], A[3, t] = top_of[kc[0, tops]], top_of[kc[1, tops]], tops
    A[2, t] = np.where(same, top_of[cross], u_of[tops])
    u = u_of[edge]
    xe = cross[~same]
    A[0, u] = u_of[kc[0, edge]]
    A[2, u] = top_of[edge]
    A[3, u] = np.where(face_rim[xe], u_of[xe], u)
    y = kc[1, edge]  # along the sub-face's other edge at the same corner
    yc = _cross(kc, y)
    inner = face_rim[yc] & (side0[src[yc]] == side0[src[y]])
    k_r = rim_at[edge[~inner]]
    if (k_r < 0).any():
        raise GMapError("refine: a side face's corner is not a rim corner (internal error)")
    A[1, u] = np.where(inner, u_of[kc[1, yc]], -1)
    A[1, u[~inner]] = o_latt + k_r
    bot, lat, latt = o_bot + np.arange(r), o_lat + np.arange(r), o_latt + np.arange(r)
    A[0, bot] = o_bot + side_of[alpha[0, rims]]
    A[1, bot] = lat
    A[2, bot] = -1 - rims
    A[0, lat], A[0, latt] = latt, lat
    A[1, lat], A[1, latt] = bot, u_of[corner]
    A[2, lat] = o_lat + side_of[alpha[1, rims]]
    A[2, latt] = o_latt + side_of[alpha[1, rims]]
    z = cross[np.searchsorted(tops, corner)]  # round the inset corner's edge in the core
    other = np.where(face_rim[z], rim_at[z], -1)
    if (face_rim[z] & (other < 0)).any():
        raise GMapError("refine: two pillows meet off a rim corner (internal error)")
    for base in (o_bot, o_lat, o_latt):
        A[3, base + np.arange(r)] = np.where(other >= 0, base + other, base + np.arange(r))

    faces, face_idx = np.unique(side0[rims], return_inverse=True)
    pillow = core.n_volumes + face_idx  # per rim dart
    volume = np.empty(total, np.int64)
    volume[:M] = core.dart_volume
    volume[t], volume[u] = pillow[side_of[src[tops]]], pillow[side_of[src[edge]]]
    volume[o_bot:] = np.tile(pillow, 3)
    source = np.empty(total, np.int64)
    source[:M] = np.arange(M)
    source[t], source[u] = tops, edge
    source[bot], source[lat], source[latt] = -1 - rims, -1 - rims, corner
    first = np.unique(face_idx, return_index=True)[1]
    parents = np.concatenate([core.volume_data["_parent"].astype(np.int64), gm.dart_volume[rims[first]].astype(np.int64)])
    return _NewDarts(A, source, volume, np.concatenate([u, bot, lat, latt]), bot, rims, parents)


def _assembled(gm, core, vols, inside, levels, new: _NewDarts) -> GMap3:
    """The refined map: the new darts take the region's non-rim dart ids then ids after the
    last, the new volumes the region's volume ids then ids after the last."""
    n = gm.n_darts
    total = len(new.source)
    free_ids = np.flatnonzero(inside)
    free_ids = free_ids[~np.isin(free_ids, new.rims)]
    if total < len(free_ids):
        raise GMapError("refine: fewer darts than the region had (internal error)")
    new_id = np.concatenate([free_ids, n + np.arange(total - len(free_ids))])
    N = n + total - len(free_ids)
    out_alpha = np.empty((4, N), np.int64)
    out_alpha[:, :n] = gm.alpha
    out_alpha[:, new_id] = np.where(new.alpha < 0, -1 - new.alpha, new_id[np.maximum(new.alpha, 0)])
    out_alpha[2, new.rims] = new_id[new.bottom]

    n_new = len(new.parents)
    vol_id = np.concatenate([vols, gm.n_volumes + np.arange(max(n_new - len(vols), 0))])[:n_new]
    data, cdata = gm.dart_data, core.dart_data
    from_core = new.source >= 0
    out_darts = {}
    for name in data:
        col = np.asarray(data[name])
        column = np.empty((N,) + col.shape[1:], col.dtype)
        column[:n] = col
        vals = np.empty((total,) + col.shape[1:], col.dtype)
        vals[from_core] = np.asarray(cdata[name])[new.source[from_core]]
        vals[~from_core] = col[-1 - new.source[~from_core]]
        column[new_id] = vals
        out_darts[name] = column
    out_darts["volume"][new_id] = vol_id[new.volume]
    out_darts["volume"][new.rims] = vol_id[new.volume[new.bottom]]
    sides = new_id[new.sides]
    out_darts["face"][sides] = FACE_I
    out_darts["sublabel"][sides] = 0
    out_darts["fcorner"][sides] = -1
    out_darts["forward"][sides] = False
    out_darts["sup"][new_id] = -1
    out_darts["corner"][new_id] = out_darts["point"][new_id]
    out = GMap3.from_arrays(out_alpha, out_darts, _volume_rows(gm, vol_id, new.parents, levels), gm.dart_rules())
    out.meta = dict(gm.meta)
    return out


def _volume_rows(gm: GMap3, vol_id: np.ndarray, parents: np.ndarray, levels: int) -> dict[str, np.ndarray]:
    """Volume columns: each new volume ``vol_id[i]`` copies ``parents[i]``'s row, with
    ``refined`` (+ levels), ``sub`` (1.. among its parent's children) and a fruit's ``layer``."""
    vd = gm.volume_data
    V = max(gm.n_volumes, int(vol_id.max()) + 1)
    out = {}
    for name in vd:
        col = np.asarray(vd[name])
        rows = np.empty((V,) + col.shape[1:], col.dtype)
        rows[: gm.n_volumes] = col
        rows[vol_id] = col[parents]
        out[name] = rows
    if "parent" in out:
        out["parent"][vol_id] = -1
    if "refined" not in out:
        out["refined"] = np.zeros(V, np.int16)
    out["refined"][vol_id] = (np.asarray(vd["refined"])[parents] if "refined" in vd else 0) + levels
    order = np.argsort(parents, kind="stable")
    sub = np.empty(len(parents), np.int32)
    sub[order] = np.arange(len(parents)) - np.searchsorted(parents[order], parents[order]) + 1
    if "sub" not in out:
        out["sub"] = np.zeros(V, np.int32)
    out["sub"][vol_id] = sub
    if "ring" in vd and "layer" not in vd:  # a fruit's radial layers, frozen before its cells change
        from ramure.gmap.organs.defects import radial_layers

        _, layer = radial_layers(gm)
        out["layer"] = np.full(V, -1, np.int16)
        out["layer"][: gm.n_volumes] = layer
        out["layer"][vol_id] = layer[parents]
    return out
