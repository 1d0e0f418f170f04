"""Meshes of a :class:`~ramure.lsys.turtle.Skeleton`, built for all segments at once.

Each segment becomes a frustum of ``sides`` quads (no caps: neighbouring
segments close the tube); leaves are flat diamonds in the turtle's H-L plane;
fruit and other organs are low-poly spheres.  Every cell carries:

``leaf_id``  the history-tree leaf that made it (picking maps a cell to it)
``segment``  the segment index (-1 for organs)
``organ``    the organ index (-1 for branches)
``kind``     0 branch, 1 leaf, 2 fruit, 3 other organ
``order``    branch order (organs: -1)

>>> from ramure.lsys import LSystem
>>> mesh = LSystem.from_text("n: 1\\nw: F\\np: F -> F[+F]F").derive().skeleton().to_polydata(sides=6)
>>> mesh.n_cells, sorted(set(mesh.cell_data["segment"].tolist()))
(18, [0, 1, 2])
"""
from __future__ import annotations

import numpy as np

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


def tube_arrays(skeleton, sides=8):
    """Points (2·s·k, 3) and quad indices (s·k, 4) of all frustums."""
    s = len(skeleton)
    a, b = _ring_basis(skeleton.end - skeleton.start, skeleton.normal)
    theta = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.cos(theta)[None, :, None] * a[:, None, :] + np.sin(theta)[None, :, None] * b[:, None, :]
    bottom = skeleton.start[:, None, :] + skeleton.base_radius[:, None, None] * ring
    top = skeleton.end[:, None, :] + skeleton.top_radius[:, None, None] * ring
    points = np.concatenate([bottom.reshape(-1, 3), top.reshape(-1, 3)])
    j = np.arange(sides)
    base = (np.arange(s) * sides)[:, None]
    b0, b1 = base + j, base + (j + 1) % sides
    t0, t1 = b0 + s * sides, b1 + s * sides
    quads = np.stack([b0, b1, t1, t0], axis=-1).reshape(-1, 4)
    return points, quads


def _sphere_template(resolution):
    """A UV sphere of unit radius: points (m,3) and triangles (t,3)."""
    rings = max(resolution // 2, 2)
    phi = np.linspace(0, np.pi, rings + 1)[1:-1]
    theta = np.linspace(0, 2 * np.pi, resolution, endpoint=False)
    pts = np.stack([np.outer(np.sin(phi), np.cos(theta)).ravel(),
                    np.outer(np.sin(phi), np.sin(theta)).ravel(),
                    np.repeat(np.cos(phi), resolution)], axis=1)
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


def organ_arrays(organs, resolution=8):
    """Points, triangles and per-triangle organ index / kind of all organs."""
    if not len(organs):
        return np.zeros((0, 3)), np.zeros((0, 3), int), np.zeros(0, int), np.zeros(0, int)
    is_leaf = np.array([k == "Leaf" for k in organs.kind])
    kinds = np.where(is_leaf, KIND_LEAF,
                     np.where(np.array([k == "Fruit" for k in organs.kind]), KIND_FRUIT, KIND_ORGAN))
    out_pts, out_tris, out_idx = [], [], []
    offset = 0
    # Leaves: a diamond of length = size.  Other organs: a sphere of diameter = size,
    # centred on the turtle position.
    for mask, (tpts, ttris), scale in ((is_leaf, _leaf_template(), 1.0),
                                       (~is_leaf, _sphere_template(resolution), 0.5)):
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


def skeleton_to_polydata(skeleton, sides=8, organ_resolution=8):
    """One :class:`pyvista.PolyData` with tubes and organs and the cell data above."""
    import pyvista as pv

    tpts, quads = tube_arrays(skeleton, sides)
    opts, tris, organ_idx, organ_kind = organ_arrays(skeleton.organs, organ_resolution)
    points = np.vstack([tpts, opts]) if len(opts) else tpts
    tris = tris + len(tpts)
    faces = np.concatenate([
        np.hstack([np.full((len(quads), 1), 4), quads]).ravel(),
        np.hstack([np.full((len(tris), 1), 3), tris]).ravel(),
    ]).astype(np.int64)
    mesh = pv.PolyData(points, faces) if len(points) else pv.PolyData()
    nseg = len(skeleton)
    seg = np.repeat(np.arange(nseg), sides)
    mesh.cell_data["leaf_id"] = np.concatenate([skeleton.leaf_id[seg], skeleton.organs.leaf_id[organ_idx]])
    mesh.cell_data["segment"] = np.concatenate([seg, np.full(len(tris), -1)])
    mesh.cell_data["organ"] = np.concatenate([np.full(len(seg), -1), organ_idx])
    mesh.cell_data["kind"] = np.concatenate([np.full(len(seg), KIND_BRANCH), organ_kind]).astype(np.int8)
    mesh.cell_data["order"] = np.concatenate([skeleton.order[seg], np.full(len(tris), -1)]).astype(np.int32)
    return mesh
