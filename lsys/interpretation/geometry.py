"""Meshes of a :class:`~ramure.lsys.interpretation.turtle.Skeleton`, built for all segments at once.

Each segment becomes a frustum of ``sides`` quads (no caps: neighbouring
segments close the tube); leaves are flat diamonds in the turtle's H-L plane;
surfaces ``~name`` are their template (:mod:`ramure.lsys.interpretation.surfaces`); fruit,
spheres ``@O`` and other organs are low-poly spheres; polygons ``{ . }`` are
their triangles (:mod:`ramure.lsys.interpretation.polygons`).  Every cell carries:

============  =======================================================================
``leaf_id``   the history-tree leaf that made it (picking maps a cell to it;
              a polygon's is its ``{`` module's)
``segment``   the segment index (-1 elsewhere)
``organ``     the organ index (-1 elsewhere)
``polygon``   the polygon index (-1 elsewhere)
``kind``      0 branch, 1 leaf (``Leaf``, polygons, surfaces), 2 fruit, 3 other organ
``order``     branch order (organs and polygons: -1)
``material``  the colour/material index in force where it was drawn
============  =======================================================================

Cells come in this order: tube quads, organ triangles, polygon triangles.
``leaf_id`` and ``segment`` are int32: history-tree ids and counts stay below
2^31 (the tree refuses more nodes).  ``organ``, ``polygon``, ``order`` and
``material`` take the smallest of int8, int16, int32 that holds their values
(:func:`value_dtype`; ``kind`` is int8): a plant without organs or polygons, a
dozen branch orders and a few materials stores them in a byte each, 4.7 MB
less for Honda n = 17's 393k cells.  Points are float64 unless ``points_dtype`` asks for float32 (the
explorer's on-screen mesh does: OpenGL draws float32 anyway, and a
1.44 M-module plant's tubes take 9 MB less; every point is the float64 value
rounded once, so a patched mesh equals a full rebuild bit for bit).
A grammar's ``#material`` table rides along as ``field_data["material_rgb"]``
/ ``["material_rgba"]`` (see :mod:`ramure.lsys.interpretation.materials`).

>>> from ramure.lsys import LSystem
>>> mesh = LSystem.from_text("n: 1\\nw: F\\np: F -> F[+F]F").derive().skeleton().to_polydata(sides=6)
>>> mesh.n_cells, sorted(set(mesh.cell_data["segment"].tolist()))
(18, [0, 1, 2])
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pyvista as pv

    from .turtle import Organs, Skeleton

KIND_BRANCH, KIND_LEAF, KIND_FRUIT, KIND_ORGAN = 0, 1, 2, 3


def _ring_basis(direction, normal):
    """Two unit vectors perpendicular to each direction, the first close to ``normal``."""
    d = direction / np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-12)
    a = normal - (normal * d).sum(1, keepdims=True) * d
    bad = np.linalg.norm(a, axis=1) < 1e-9
    if bad.any():  # normal parallel to the segment: use any perpendicular
        helper = np.where(np.abs(d[bad, 0:1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        a[bad] = np.cross(d[bad], helper)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(d, a)
    return a, b


#: Segments computed at once by :func:`tube_points` (bounds its float64 temporaries to a few MB).
TUBE_CHUNK = 16_384


def tube_points(
    start: np.ndarray,
    end: np.ndarray,
    normal: np.ndarray,
    base_radius: np.ndarray,
    top_radius: np.ndarray,
    sides: int = 8,
    dtype: type = np.float64,
) -> np.ndarray:
    """Points (s, 2·sides, 3) of frustums: each segment's bottom ring then its top ring.

    Each segment's points are contiguous, so an edit can replace the rings of
    some segments and keep the others' bytes as they are.  Computed in float64
    by blocks of :data:`TUBE_CHUNK` segments and stored as ``dtype`` (float32:
    each value rounded once, the same whatever the block).
    """
    theta = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    cos, sin = np.cos(theta)[None, :, None], np.sin(theta)[None, :, None]
    pts: np.ndarray = np.empty((len(start), 2 * sides, 3), dtype)
    for lo in range(0, len(start), TUBE_CHUNK):
        part = slice(lo, lo + TUBE_CHUNK)
        pts[part] = _frustums(start[part], end[part], normal[part], base_radius[part], top_radius[part], cos, sin)
    return pts


def _frustums(start, end, normal, base_radius, top_radius, cos, sin):
    a, b = _ring_basis(end - start, normal)
    ring = cos * a[:, None, :]
    ring += sin * b[:, None, :]
    sides = ring.shape[1]
    pts = np.empty((len(start), 2 * sides, 3))
    np.multiply(base_radius[:, None, None], ring, out=pts[:, :sides])
    pts[:, :sides] += start[:, None, :]
    np.multiply(top_radius[:, None, None], ring, out=pts[:, sides:])
    pts[:, sides:] += end[:, None, :]
    return pts


_QUADS: dict[int, np.ndarray] = {}  # sides -> the quads of the largest plant so far (a smaller plant's are a prefix)


def tube_quads(count: int, sides: int = 8) -> np.ndarray:
    """Quad indices (count·sides, 4) of ``count`` frustums laid out as :func:`tube_points`."""
    cached = _QUADS.get(sides)
    if cached is None or len(cached) < count * sides:
        _QUADS[sides] = cached = _make_quads(_with_headroom(count), sides)
    return cached[: count * sides]


def _with_headroom(count: int) -> int:
    """A cached index array's length for ``count``: an eighth more, so that an edit that adds a
    few segments (a stochastic regrow) shares the array with the version before instead of
    holding a second one (7.9 MB of quads and offsets for Honda n = 17)."""
    return count + count // 8


_OFFSETS: list[np.ndarray] = []  # the quad offsets 0, 4, 8 ... of the largest plant so far


def _quad_offsets(quads: int) -> np.ndarray:
    """Read-only cell offsets (quads + 1,) of ``quads`` quads (a prefix of a cached array)."""
    if not _OFFSETS or len(_OFFSETS[0]) < quads + 1:
        room = _with_headroom(quads)
        offsets: np.ndarray = np.arange(0, 4 * room + 1, 4, dtype=id_dtype(4 * room))
        offsets.flags.writeable = False
        _OFFSETS[:] = [offsets]
    return _OFFSETS[0][: quads + 1]


_TUBE_CELLS: dict[tuple[str, int], np.ndarray] = {}  # (name, sides) -> the largest plant's so far


def _tube_cells(name: str, segments: int, sides: int) -> np.ndarray:
    """Read-only per-cell ``name`` ("segment", "organ", "polygon" or "kind") of a mesh of only
    ``segments`` tubes of ``sides`` quads (a prefix of a cached array, as :func:`tube_quads`):
    cell ``i`` is segment ``i // sides``'s, no organ (-1), no polygon (-1), a branch.  Every
    version of a plant shares them instead of holding its own (2.8 MB at Honda n = 17)."""
    cached = _TUBE_CELLS.get((name, sides))
    if cached is None or len(cached) < segments * sides:
        count = _with_headroom(segments)
        if name == "segment":
            cached = np.repeat(np.arange(count, dtype=np.int32), sides)
        else:
            cached = np.full(count * sides, KIND_BRANCH if name == "kind" else -1, np.int8)
        cached.flags.writeable = False
        _TUBE_CELLS[(name, sides)] = cached
    return cached[: segments * sides]


def _make_quads(count, sides):
    dtype = id_dtype(2 * sides * count)
    j = np.arange(sides, dtype=dtype)
    template = np.stack([j, (j + 1) % sides, (j + 1) % sides + sides, j + sides], axis=-1)
    base = (np.arange(count, dtype=dtype) * dtype(2 * sides))[:, None, None]
    quads = (template[None] + base).reshape(-1, 4)
    quads.flags.writeable = False  # shared by meshes (their cells wrap it) and callers
    return quads


def id_dtype(largest: int) -> type:
    """The dtype of point ids and cell offsets up to ``largest``: int32 (VTK keeps 32-bit cell
    arrays as they are, half the bytes: 7.9 MB less for Honda n = 17's 393k quads), int64 past
    2^31 - 1."""
    return np.int32 if largest < 2**31 - 1 else np.int64


def value_dtype(low: int, high: int) -> type:
    """The smallest of int8, int16 and int32 that holds every value from ``low`` to ``high``
    (cell data whose range is known only at run time: organ and polygon indices, branch orders,
    material indices).

    >>> value_dtype(-1, 12).__name__, value_dtype(-1, 1000).__name__, value_dtype(0, 70_000).__name__
    ('int8', 'int16', 'int32')
    """
    for dtype in (np.int8, np.int16):
        info = np.iinfo(dtype)
        if info.min <= low and high <= info.max:
            return dtype
    return np.int32


def _dtype_holding(*arrays):
    """:func:`value_dtype` of the values in ``arrays`` (int8 when there are none)."""
    full = [a for a in arrays if len(a)]
    if not full:
        return np.int8
    return value_dtype(min(int(a.min()) for a in full), max(int(a.max()) for a in full))


def cell_array(offsets: np.ndarray, conn: np.ndarray) -> Any:
    """A ``vtkCellArray`` reading ``offsets`` and ``conn`` (contiguous, both int32 or both int64)
    in place: the caller keeps the arrays alive."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonDataModel import vtkCellArray

    cells = vtkCellArray()
    if offsets.dtype == np.int32 and conn.dtype == np.int32:
        cells.SetData(numpy_to_vtk(offsets, deep=False), numpy_to_vtk(conn, deep=False))
    else:
        as64 = (np.ascontiguousarray(a, np.int64) for a in (offsets, conn))
        cells.SetData(*(numpy_to_vtkIdTypeArray(a, deep=False) for a in as64))
    return cells


def tube_arrays(skeleton: Skeleton, sides: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Points (2·s·k, 3) and quad indices (s·k, 4) of all frustums."""
    sk = skeleton
    points = tube_points(sk.start, sk.end, sk.normal, sk.base_radius, sk.top_radius, sides)
    return points.reshape(-1, 3), tube_quads(len(sk), sides)


def _sphere_template(resolution):
    """A UV sphere of unit radius: points (m,3) and triangles (t,3)."""
    rings = max(resolution // 2, 2)
    phi = np.linspace(0, np.pi, rings + 1)[1:-1]
    theta = np.linspace(0, 2 * np.pi, resolution, endpoint=False)
    pts = np.stack(
        [
            np.outer(np.sin(phi), np.cos(theta)).ravel(),
            np.outer(np.sin(phi), np.sin(theta)).ravel(),
            np.repeat(np.cos(phi), resolution),
        ],
        axis=1,
    )
    pts = np.vstack([[0, 0, 1.0], pts, [0, 0, -1.0]])
    tris = []
    j = np.arange(resolution)
    jn = (j + 1) % resolution
    tris.append(np.stack([np.zeros(resolution, int), 1 + j, 1 + jn], 1))
    for r in range(rings - 2):
        a, b = 1 + r * resolution, 1 + (r + 1) * resolution
        tris.append(np.stack([a + j, b + j, b + jn], 1))
        tris.append(np.stack([a + j, b + jn, a + jn], 1))
    last = 1 + (rings - 2) * resolution
    tris.append(np.stack([last + j, np.full(resolution, len(pts) - 1), last + jn], 1))
    return pts, np.vstack(tris)


def _leaf_template():
    """A diamond in the H-L plane: base at the origin, tip at H=1."""
    pts = np.array([[0, 0, 0], [0.45, 0.3, 0], [1.0, 0, 0], [0.45, -0.3, 0]], float)  # (h, l, u)
    return pts, np.array([[0, 1, 2], [0, 2, 3]])


def organ_arrays(
    organs: Organs, resolution: int = 8, surfaces: Mapping[str, tuple] | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points, triangles and per-triangle organ index / kind of all organs.

    ``surfaces`` maps a surface organ kind (``"~leaf"``) to its template
    (points in (h, l, u), triangles), see :func:`ramure.lsys.interpretation.surfaces.templates`.
    """
    if not len(organs):
        return np.zeros((0, 3)), np.zeros((0, 3), int), np.zeros(0, int), np.zeros(0, int)
    surfaces = surfaces or {}
    kind_names = np.asarray(organs.kind, dtype=object)
    is_leaf = kind_names == "Leaf"
    is_surface = np.array([k in surfaces for k in kind_names], bool)
    kinds = np.where(is_leaf | is_surface, KIND_LEAF, np.where(kind_names == "Fruit", KIND_FRUIT, KIND_ORGAN))
    out_pts, out_tris, out_idx = [], [], []
    offset = 0
    # Leaves: a diamond of length = size.  Surfaces: their template scaled by size.  Other
    # organs: a sphere of diameter = size, centred on the turtle position.
    groups = [(is_leaf, _leaf_template(), 1.0), (~is_leaf & ~is_surface, _sphere_template(resolution), 0.5)]
    groups += [(kind_names == k, template, 1.0) for k, template in surfaces.items()]
    for mask, (tpts, ttris), scale in groups:
        idx = np.flatnonzero(mask)
        if not idx.size:
            continue
        frame = organs.frame[idx]  # (k, 3, 3) rows H, L, U
        size = organs.size[idx][:, None, None]
        local = tpts[None] * size * scale
        world = organs.position[idx][:, None, :] + np.einsum("kpi,kij->kpj", local, frame)
        out_pts.append(world.reshape(-1, 3))
        tris = ttris[None] + (offset + np.arange(idx.size) * len(tpts))[:, None, None]
        out_tris.append(tris.reshape(-1, 3))
        out_idx.append(np.repeat(idx, len(ttris)))
        offset += idx.size * len(tpts)
    organ_idx = np.concatenate(out_idx)
    return np.vstack(out_pts), np.vstack(out_tris), organ_idx, kinds[organ_idx]


def skeleton_to_polydata(
    skeleton: Skeleton, sides: int = 8, organ_resolution: int = 8, points_dtype: type = np.float64
) -> pv.PolyData:
    """One :class:`pyvista.PolyData` with tubes and organs and the cell data above.

    Cells: the tubes' quads segment by segment (``sides`` per segment), then
    the organs' triangles; points likewise (2·``sides`` per segment first).
    ``points_dtype`` float32 halves the points (for drawing, see the module notes).
    """
    sk = skeleton
    tpts = tube_points(sk.start, sk.end, sk.normal, sk.base_radius, sk.top_radius, sides, points_dtype).reshape(-1, 3)
    return polydata_from_parts(skeleton, tpts, sides, organ_resolution)


def polydata_from_parts(skeleton: Skeleton, tube_pts: np.ndarray, sides: int = 8, organ_resolution: int = 8) -> pv.PolyData:
    """The plant's PolyData from already computed tube points (see :func:`tube_points`); the
    points keep ``tube_pts``' dtype."""
    import pyvista as pv

    organs = skeleton.organs
    opts, otris, organ_idx, organ_kind = organ_arrays(organs, organ_resolution, skeleton.extra.get("surfaces"))
    polygons = getattr(skeleton, "polygons", None)
    if polygons is not None and len(polygons):
        ptris, poly_idx = polygons.triangles()
        ppts = polygons.points
    else:
        ptris, poly_idx, ppts = np.zeros((0, 3), np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    nseg = len(skeleton)
    no, npoly = len(otris), len(ptris)
    nq, nt = nseg * sides, no + npoly
    points = np.concatenate([tube_pts, opts, ppts], dtype=tube_pts.dtype) if len(opts) or len(ppts) else tube_pts
    mesh = pv.PolyData()
    if not len(points):
        return mesh
    if nt:
        dtype = id_dtype(max(len(points), 4 * nq + 3 * nt))
        conn: np.ndarray = np.empty(4 * nq + 3 * nt, dtype)
        conn[: 4 * nq] = tube_quads(nseg, sides).ravel()
        conn[4 * nq : 4 * nq + 3 * no] = (otris + len(tube_pts)).ravel()
        conn[4 * nq + 3 * no :] = (ptris + len(tube_pts) + len(opts)).ravel()
        offsets = np.concatenate([np.arange(0, 4 * nq + 1, 4, dtype=dtype), 4 * nq + 3 * np.arange(1, nt + 1, dtype=dtype)])
    else:  # tubes only: read-only views of the cached quads, shared by every such mesh (no copy)
        conn = tube_quads(nseg, sides).ravel()
        offsets = _quad_offsets(nq)
    mesh.points = points
    # VTK wraps the arrays (numpy_support keeps them alive): no copy of the 1.6 M indices
    mesh.SetPolys(cell_array(offsets, conn))
    poly_leaf = polygons.leaf_id[poly_idx] if polygons is not None and npoly else np.zeros(0, np.int32)
    i32 = np.int32  # ids below 2^31 (the tree's node limit): half the bytes of int64

    def per_cell(per_segment, dtype, *rest):  # each segment's value on its `sides` quads, then organs, polygons
        if dtype is None:  # the smallest that holds the values (see the module notes)
            dtype = _dtype_holding(np.atleast_1d(per_segment) if nq else rest[0][:0], *rest)
        out = np.empty(nq + nt, dtype)
        if np.ndim(per_segment):
            quads = out[:nq].reshape(nseg, sides)
            for j in range(sides):  # a column at a time: faster than one broadcast over rows of `sides`
                quads[:, j] = per_segment
        else:
            out[:nq] = per_segment
        if nt:
            out[nq:] = np.concatenate(rest)
        return out

    mesh.cell_data["leaf_id"] = per_cell(skeleton.leaf_id, i32, organs.leaf_id[organ_idx], poly_leaf)
    if nt:
        mesh.cell_data["segment"] = per_cell(np.arange(nseg), i32, np.full(nt, -1))
        mesh.cell_data["organ"] = per_cell(-1, None, organ_idx, np.full(npoly, -1))
        mesh.cell_data["polygon"] = per_cell(-1, None, np.full(no, -1), poly_idx)
        mesh.cell_data["kind"] = per_cell(KIND_BRANCH, np.int8, organ_kind, np.full(npoly, KIND_LEAF))
    else:  # tubes only: the same values for every plant of as many segments (shared, see _tube_cells)
        for name in ("segment", "organ", "polygon", "kind"):
            mesh.cell_data[name] = _tube_cells(name, nseg, sides)
    mesh.cell_data["order"] = per_cell(skeleton.order, None, np.full(nt, -1))
    organ_color = organs.color if organs.color is not None else np.zeros(len(organs), np.int32)
    poly_color = polygons.color[poly_idx] if polygons is not None and npoly else np.zeros(0, np.int32)
    mesh.cell_data["material"] = per_cell(skeleton.color, None, organ_color[organ_idx], poly_color)
    materials = skeleton.extra.get("materials")
    if materials:
        from .materials import table_arrays

        mesh.field_data["material_rgb"], mesh.field_data["material_rgba"] = table_arrays(materials)
    return mesh


def patch_polydata(old_mesh: pv.PolyData | None, skeleton: Skeleton, sides: int = 8, organ_resolution: int = 8) -> pv.PolyData:
    """The mesh of ``skeleton`` made from ``old_mesh``, recomputing only the tubes that changed.

    ``skeleton`` comes from :func:`ramure.lsys.interpretation.turtle.reinterpret`, whose
    ``extra["reuse"]`` = ``(new, old)`` names the segments whose tube is the
    same as in ``old_mesh`` (built with the same ``sides``): their points are
    copied, only the other tubes are computed.  Organs are rebuilt (a few
    vectorised passes).  Without ``reuse`` this is :func:`skeleton_to_polydata`.
    """
    reuse = skeleton.extra.get("reuse")
    if reuse is None or old_mesh is None or old_mesh.n_points == 0:
        return skeleton_to_polydata(skeleton, sides, organ_resolution)
    new, old = reuse
    k = 2 * sides
    old_pts = np.asarray(old_mesh.points)
    n_old = int(old.max(initial=-1)) + 1
    if n_old * k > len(old_pts):
        return skeleton_to_polydata(skeleton, sides, organ_resolution)
    pts = np.empty((len(skeleton), k, 3), old_pts.dtype)  # the old mesh's precision (see the module notes)
    old_tubes = old_pts[: len(old_pts) - len(old_pts) % k].reshape(-1, k, 3)
    breaks = np.flatnonzero((np.diff(new) != 1) | (np.diff(old) != 1)) + 1
    runs = zip(np.r_[0, breaks], np.r_[breaks, len(new)]) if len(new) else ()  # nothing kept: no run
    for a, b in runs:  # runs of kept tubes: block copies
        pts[new[a] : new[a] + b - a] = old_tubes[old[a] : old[a] + b - a]
    todo = np.ones(len(skeleton), bool)
    todo[new] = False
    todo = np.flatnonzero(todo)  # the few new tubes: gathered by index, not by a mask over all
    sk = skeleton
    if todo.size:
        fresh = (sk.start[todo], sk.end[todo], sk.normal[todo], sk.base_radius[todo], sk.top_radius[todo])
        pts[todo] = tube_points(*fresh, sides, pts.dtype)
    return polydata_from_parts(skeleton, pts.reshape(-1, 3), sides, organ_resolution)
