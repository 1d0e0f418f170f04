"""Convert a :class:`ramure.gmap.GMap3` to pyvista data objects (no plotting here).

:func:`to_unstructured_grid` gives one cell per volume: a hexahedron when
the volume has 6 quad faces and 8 corners, a wedge for 2 triangles, 3 quads
and 6 corners, otherwise a polyhedron whose faces are oriented outwards.
Cell data: ``volume`` (id), ``label`` (string), ``tissue`` (int code; names in
field data ``tissue_names`` and :data:`ramure.gmap.kernel.storage.TISSUES`), ``leaf_id``,
``order``, ``stage`` and any other one-value-per-volume attribute.
:func:`boundary_polydata` gives the alpha3-free faces as a surface.

>>> from ramure.gmap.organs.fruit import build_fruit
>>> grid = to_unstructured_grid(build_fruit("round_tomato"))
>>> grid.n_cells, grid.n_points, sorted(set(grid.celltypes.tolist()))
(110, 220, [12, 42])
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyvista as pv
from numpy.typing import ArrayLike

from ramure.gmap.kernel.measure import face_triangles, faces_up, turned_over
from ramure.gmap.kernel.storage import TISSUES

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

VTK_TETRA, VTK_HEXAHEDRON, VTK_WEDGE, VTK_POLYHEDRON = 10, 12, 13, 42
_SKIP = {"frame", "origin", "size", "parent"}


def face_cycles(gm: GMap3, darts: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every per-volume face ``<a0,a1>`` (or those holding ``darts``) as a vertex cycle.

    Returns ``(first, cycles, degree, volume, corner_darts)``: the face's
    smallest dart, the vertex ids padded with -1 (n_faces, max_degree), the
    degree, the owning volume and, for each corner, the face dart there that
    leads (by alpha0) to the next corner.
    """
    vid, _ = gm.cells(0)
    side, _ = gm.orbit_ids("01")
    darts = np.arange(gm.n_darts) if darts is None else np.asarray(darts, np.int64)
    _, first = np.unique(side[darts], return_index=True)
    first = darts[first]
    walk, length = gm.face_walk(first)
    corner_darts = walk[:, 0::2]
    cycles = np.where(corner_darts >= 0, vid[np.maximum(corner_darts, 0)], -1)
    return first, cycles, length // 2, gm.dart_volume[first].astype(np.int64), corner_darts


def _newell(pos, cycles, degree):
    """Face normals (not normalised) and centroids from padded vertex cycles."""
    ok = cycles >= 0
    p = pos[np.maximum(cycles, 0)]
    nxt_idx = np.arange(cycles.shape[1])[None, :] + 1
    nxt_idx = np.where(nxt_idx >= degree[:, None], 0, nxt_idx)
    q = np.take_along_axis(p, nxt_idx[:, :, None], axis=1)
    normal = np.where(ok[:, :, None], np.cross(p, q), 0.0).sum(axis=1)
    centre = np.where(ok[:, :, None], p, 0.0).sum(axis=1) / degree[:, None]
    return normal, centre


def _outward(pos, cycles, degree, cell_centre):
    """Reverse the cycles whose Newell normal points towards ``cell_centre`` (first vertex kept)."""
    normal, fcentre = _newell(pos, cycles, degree)
    inward = np.sum(normal * (fcentre - cell_centre), axis=1) < 0
    idx = np.arange(cycles.shape[1])[None, :]
    rev = np.where(idx == 0, 0, degree[:, None] - idx)
    rev = np.where(idx < degree[:, None], rev, idx)
    return np.where(inward[:, None], np.take_along_axis(cycles, rev, axis=1), cycles)


def _cell_records(gm, pos):
    """Cell types, the flat legacy cell array and each record's length, one cell per volume in volume order."""
    vid, _ = gm.cells(0)
    alpha = gm.alpha
    first, cycles, degree, fvol, cdarts = face_cycles(gm)
    nvol = gm.n_volumes
    faces_per_vol = np.bincount(fvol, minlength=nvol)
    quads = np.bincount(fvol, degree == 4, minlength=nvol)
    tris = np.bincount(fvol, degree == 3, minlength=nvol)
    pair = np.unique(gm.dart_volume.astype(np.int64) * (int(vid.max()) + 1) + vid)
    corners = np.bincount(pair // (int(vid.max()) + 1), minlength=nvol)
    is_hex = (faces_per_vol == 6) & (quads == 6) & (corners == 8)
    is_wedge = (faces_per_vol == 5) & (quads == 3) & (tris == 2) & (corners == 6)
    ctype = np.full(nvol, VTK_POLYHEDRON, np.uint8)
    ctype[is_hex] = VTK_HEXAHEDRON
    ctype[is_wedge] = VTK_WEDGE

    # faces grouped by volume (stable: faces of a volume in increasing first dart)
    order = np.argsort(fvol, kind="stable")
    fvol_s, deg_s, cyc_s, cd_s = fvol[order], degree[order], cycles[order], cdarts[order]
    cyc_o = _outward(pos, cyc_s, deg_s, gm.volume_centroids()[fvol_s])

    length = np.where(ctype == VTK_HEXAHEDRON, 9, np.where(ctype == VTK_WEDGE, 7, 0)).astype(np.int64)
    poly_len = 2 + np.bincount(fvol_s, deg_s + 1, minlength=nvol).astype(np.int64)
    length = np.where(ctype == VTK_POLYHEDRON, poly_len, length)
    start = np.concatenate([[0], np.cumsum(length)[:-1]])
    flat = np.empty(int(length.sum()), np.int64)

    # hexahedra and wedges: a bottom face, its corners, and the corner above each
    fixed = np.flatnonzero(ctype != VTK_POLYHEDRON)
    if fixed.size:
        want = np.where(ctype[fvol_s] == VTK_WEDGE, 3, 4)
        cand = (deg_s == want) & (ctype[fvol_s] != VTK_POLYHEDRON)
        # first suitable face of each fixed volume
        pick = np.full(nvol, -1, np.int64)
        idx_c = np.flatnonzero(cand)[::-1]
        pick[fvol_s[idx_c]] = idx_c
        for kind, m in ((VTK_HEXAHEDRON, 4), (VTK_WEDGE, 3)):
            vols = np.flatnonzero(ctype == kind)
            if not vols.size:
                continue
            f = pick[vols]
            darts = cd_s[f, :m]
            bottom = vid[darts]
            top = vid[alpha[0][alpha[1][alpha[2][darts]]]]
            up = faces_up(pos[bottom], pos[top])
            flip = np.concatenate([[0], np.arange(m - 1, 0, -1)])
            bottom = np.where(up[:, None], bottom, bottom[:, flip])
            top = np.where(up[:, None], top, top[:, flip])
            rows = start[vols][:, None] + np.arange(1 + 2 * m)[None, :]
            flat[rows] = np.concatenate([np.full((len(vols), 1), 2 * m), bottom, top], axis=1)

    # polyhedra: [n_items, n_faces, deg, ids..., deg, ids...]
    poly = ctype[fvol_s] == VTK_POLYHEDRON
    pv_ids = np.flatnonzero(ctype == VTK_POLYHEDRON)
    if pv_ids.size:
        flat[start[pv_ids]] = length[pv_ids] - 1
        flat[start[pv_ids] + 1] = faces_per_vol[pv_ids]
        fdeg = deg_s[poly]
        fv = fvol_s[poly]
        block = fdeg + 1
        # offset of each face block inside its volume's record
        csum = np.cumsum(block)
        vol_first = np.ones(len(fv), bool)
        vol_first[1:] = fv[1:] != fv[:-1]
        base = np.concatenate([[0], csum[:-1]])
        vol_base = np.maximum.accumulate(np.where(vol_first, base, 0))
        fstart = start[fv] + 2 + (base - vol_base)
        flat[fstart] = fdeg
        cyc = cyc_o[poly]
        ok = cyc >= 0
        pos_in = fstart[:, None] + 1 + np.arange(cyc.shape[1])[None, :]
        flat[pos_in[ok]] = cyc[ok]
    return ctype, flat, length


def _polyhedra_as_tetrahedra(gm, pos, ctype):
    """Tetrahedra ``(face centre, b, a, volume centre)`` for each edge ``a -> b`` of each polyhedron's faces.

    Returns ``(cells (n, 4), owning volume (n,), extra points)``; the extra
    points are the face centres then the volume centres, numbered after ``pos``.
    A face is fanned from its vertex centroid as :func:`ramure.gmap.kernel.measure.volumes`
    does, so the tetrahedra's volumes sum to the kernel's, convex cell or not.
    """
    first, cycles, degree, fvol, _ = face_cycles(gm)
    keep = ctype[fvol] == VTK_POLYHEDRON
    first, cycles, degree, fvol = first[keep], cycles[keep], degree[keep], fvol[keep]
    centres = gm.volume_centroids()
    cycles = _parity_oriented(gm, first, cycles, degree)
    _, fcentre = _newell(pos, cycles, degree)
    vols = np.flatnonzero(ctype == VTK_POLYHEDRON)
    centre_id = np.full(gm.n_volumes, -1, np.int64)
    centre_id[vols] = len(pos) + len(fvol) + np.arange(len(vols))
    k = np.arange(cycles.shape[1])[None, :]
    nxt = np.where(k + 1 >= degree[:, None], 0, k + 1)
    f, e = np.nonzero(k < degree[:, None])
    a, b = cycles[f, e], np.take_along_axis(cycles, nxt, axis=1)[f, e]
    cells = np.stack([len(pos) + f, b, a, centre_id[fvol[f]]], axis=1)
    owner = fvol[f]
    every = np.concatenate([pos, fcentre, centres[vols]])
    ok = k < degree[:, None]
    p = pos[np.maximum(cycles, 0)]
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    turned = np.flatnonzero(turned_over(p, q, fcentre, ok))
    if turned.size:  # ears instead of the folded fan, as the kernel measures them
        fan = ~np.isin(f, turned)
        ears = [cycles[t, : degree[t]][face_triangles(pos, cycles[t, : degree[t]])] for t in turned]
        tri = np.concatenate(ears)
        face_of = np.repeat(turned, [len(e) for e in ears])
        cells = np.concatenate([cells[fan], np.stack([tri[:, 0], tri[:, 2], tri[:, 1], centre_id[fvol[face_of]]], axis=1)])
        owner = np.concatenate([owner[fan], fvol[face_of]])
    a, b, c, d = (every[cells[:, i]] for i in range(4))
    signed = np.bincount(owner, np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a), minlength=gm.n_volumes)
    inside_out = signed[owner] < 0  # walked inside out (as the kernel's measure finds): turn them over
    cells[inside_out, 1], cells[inside_out, 2] = cells[inside_out, 2], cells[inside_out, 1].copy()
    _star_apex(every, cells, owner, centre_id)
    return cells, owner, every[len(pos) :]


def _parity_oriented(gm, first, cycles, degree):
    """Vertex cycles turned the way the kernel's measure walks them (from a dart of orientation class
    0, :func:`ramure.gmap.kernel.topology.orientation_parity`): one sense per volume, by topology.

    (Turning each face by its Newell normal against the cell's centroid, as
    :func:`_outward` does, guesses wrong for a sliver cut from a cell curved
    round a knot.)
    """
    from ramure.gmap.kernel.topology import orientation_parity

    flip = orientation_parity(gm)[first] == 1
    idx = np.arange(cycles.shape[1])[None, :]
    rev = np.where(idx == 0, 0, degree[:, None] - idx)
    rev = np.where(idx < degree[:, None], rev, idx)
    return np.where(flip[:, None], np.take_along_axis(cycles, rev, axis=1), cycles)


def _star_apex(points, cells, owner, centre_id) -> None:
    """Move the apex of each cell with a tetrahedron turned inside out to the candidate with the least.

    VTK measures each tetrahedron unsigned; a cell not star-shaped from its
    centroid (curved round a knot) would measure too much.  Candidates: the
    centroid pulled a quarter, half and three quarters of the way towards each
    of its vertices.  The signed sum, the kernel's volume, is the same from any apex.
    """
    a, b, c, d = (points[cells[:, i]] for i in range(4))
    normal = np.cross(b - a, c - a)
    vol = np.einsum("ij,ij->i", normal, d - a)
    total = np.bincount(owner, vol, minlength=len(centre_id))
    sign = np.where(total < 0, -1.0, 1.0)
    inverted = np.bincount(owner, np.maximum(-vol * sign[owner], 0.0), minlength=len(centre_id))
    for v in np.flatnonzero(inverted > 1e-12 * np.abs(total)):
        rows = np.flatnonzero(owner == v)
        centre = points[centre_id[v]]
        corners = points[np.unique(cells[rows, 1:3])]
        cand = np.concatenate([[centre], *[centre + t * (corners - centre) for t in (0.25, 0.5, 0.75)]])
        signed = ((cand[:, None, :] - a[rows][None]) * normal[rows][None]).sum(axis=2) * sign[v]
        best = int(np.argmin(np.maximum(-signed, 0.0).sum(axis=1)))
        points[centre_id[v]] = cand[best]


def _split_polyhedra(gm, pos, ctype, flat, length):
    """The legacy cell records with each polyhedron replaced by tetrahedra (after the other cells)."""
    fixed = ctype != VTK_POLYHEDRON
    kept = flat[np.repeat(fixed, length)]
    cells, owner, extra = _polyhedra_as_tetrahedra(gm, pos, ctype)
    tets = np.concatenate([np.full((len(cells), 1), 4), cells], axis=1).ravel()
    types = np.concatenate([ctype[fixed], np.full(len(cells), VTK_TETRA, np.uint8)])
    owners = np.concatenate([np.flatnonzero(fixed), owner])
    return np.concatenate([kept, tets]), types, np.concatenate([pos, extra]), owners


def to_unstructured_grid(gm: GMap3, convex: bool = False) -> pv.UnstructuredGrid:
    """A :class:`pyvista.UnstructuredGrid` with one cell per volume and cell data per volume.

    With ``convex=True`` every polyhedron (a volume that is not a hexahedron
    or a wedge, often non-convex after a cut or a knot) is written as
    tetrahedra instead, each carrying its volume's cell data and id
    (``volume``): VTK measures a non-convex polyhedron cell short (12-35 %
    on a cut plank), tetrahedra exactly.

    >>> from ramure.gmap import GMap3
    >>> gm = GMap3(); _ = gm.add_prisms(4); _ = gm.add_prisms(3)
    >>> g = to_unstructured_grid(gm)
    >>> g.celltypes.tolist(), g.cell_data["label"].tolist()
    ([12, 13], ['A', 'A'])
    >>> [round(v, 6) for v in g.compute_cell_sizes()["Volume"].tolist()]
    [1.0, 1.299038]
    """
    vid, pos = gm.vertex_positions()
    ctype, flat, length = _cell_records(gm, pos)
    owner = np.arange(gm.n_volumes)
    if convex and np.any(ctype == VTK_POLYHEDRON):
        flat, ctype, pos, owner = _split_polyhedra(gm, pos, ctype, flat, length)
    grid = pv.UnstructuredGrid(flat, ctype, pos)
    grid.cell_data["volume"] = owner
    for name, arr in gm.volume_data.items():
        if name in _SKIP or np.ndim(arr) != 1:
            continue
        grid.cell_data[name] = np.asarray(arr)[owner]
    grid.field_data["tissue_names"] = np.array(TISSUES)
    return grid


def boundary_polydata(gm: GMap3) -> pv.PolyData:
    """The boundary surface (alpha3-free faces) as :class:`pyvista.PolyData`.

    Cell data: ``face`` (label code), ``sublabel`` (code), ``volume``,
    ``tissue`` and ``label`` of the volume each face belongs to.

    >>> from ramure.gmap.organs.fruit import build_fruit
    >>> surf = boundary_polydata(build_fruit("round_tomato"))
    >>> surf.n_cells, surf.is_manifold
    (122, True)
    """
    _, pos = gm.vertex_positions()
    free = np.flatnonzero(gm.alpha[3] == np.arange(gm.n_darts))
    first, cycles, degree, vol, _ = face_cycles(gm, free)
    cycles = _outward(pos, cycles, degree, gm.volume_centroids()[vol])
    used = np.unique(cycles[cycles >= 0])
    remap = np.full(len(pos), -1, np.int64)
    remap[used] = np.arange(len(used))
    cycles = np.where(cycles >= 0, remap[np.maximum(cycles, 0)], -1)
    block = np.concatenate([degree[:, None], cycles], axis=1)
    faces = block[np.concatenate([np.ones((len(block), 1), bool), cycles >= 0], axis=1)]
    surf = pv.PolyData(pos[used], faces=faces)
    data = gm.dart_data
    surf.cell_data["face"] = data["face"][first]
    surf.cell_data["sublabel"] = data["sublabel"][first]
    surf.cell_data["volume"] = vol
    surf.cell_data["tissue"] = gm.volume_data["tissue"][vol]
    surf.cell_data["label"] = gm.volume_data["label"][vol]
    return surf
