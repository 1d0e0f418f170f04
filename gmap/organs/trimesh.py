"""A triangle mesh with adjacency, for details that live on surfaces (lichen, cracks).

:class:`TriMesh` holds ``points`` (n, 3) and ``triangles`` (t, 3) and precomputes what surface
walks need: unit normals, areas and the triangle across each edge (``across``, (t, 3): edge k
goes from corner k to corner k+1). Neighbour queries between particles use a grid, not the
mesh (see :mod:`ramure.gmap.organs.lichen`).

Triangles are oriented outward (a mesh given inside out, with a negative enclosed volume, is
flipped), so normals point out of the solid. A substrate must be a **closed 2-manifold**:
every edge shared by exactly two triangles, with opposite orientations. :func:`from_polydata`
refuses anything else with "close the model first".

>>> import pyvista as pv
>>> mesh = from_polydata(pv.Sphere(theta_resolution=16, phi_resolution=16))
>>> mesh.across.shape[1], bool((mesh.across >= 0).all()), round(mesh.area(), 2)
(3, True, 3.08)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import GMapError

if TYPE_CHECKING:
    import pyvista as pv


@dataclass
class TriMesh:
    points: np.ndarray
    triangles: np.ndarray

    def __post_init__(self) -> None:
        self.points = np.ascontiguousarray(self.points, np.float64)
        self.triangles = np.ascontiguousarray(self.triangles, np.int64)
        a, b, c = (self.points[self.triangles[:, k]] for k in range(3))
        if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() < 0:  # inside out: orient outward
            self.triangles = np.ascontiguousarray(self.triangles[:, ::-1])
            a, b, c = c, b, a
        cross = np.cross(b - a, c - a)
        double_area = np.linalg.norm(cross, axis=1)
        if len(self.triangles) == 0 or (double_area <= 1e-300).any():
            raise GMapError("the surface has no triangles or degenerate (zero-area) ones")
        self.normals: np.ndarray = cross / double_area[:, None]
        self.areas: np.ndarray = double_area / 2
        self.across: np.ndarray = _edge_neighbours(self.triangles)

    def area(self) -> float:
        return float(self.areas.sum())

    def random_points(
        self, count: int, rng: np.random.Generator, weights: ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``count`` points uniform over the surface (area-weighted), optionally times ``weights``
        per triangle; returns (triangles, points)."""
        p = self.areas if weights is None else self.areas * np.asarray(weights, np.float64)
        tri = rng.choice(len(self.triangles), size=count, p=p / p.sum())
        u, v = rng.random(count), rng.random(count)
        flip = u + v > 1
        u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
        a, b, c = (self.points[self.triangles[tri, k]] for k in range(3))
        return tri, a + u[:, None] * (b - a) + v[:, None] * (c - a)

    def closest_point(self, point: ArrayLike) -> tuple[int, np.ndarray, float]:
        """``(triangle, point on it, distance)``: the surface point nearest to ``point``."""
        p = np.asarray(point, np.float64)
        a, b, c = (self.points[self.triangles[:, k]] for k in range(3))
        inside = p - np.einsum("ij,ij->i", p - a, self.normals)[:, None] * self.normals
        bary = self.barycentric(np.arange(len(self.triangles)), inside)
        best = np.where(np.all(bary >= 0, axis=1)[:, None], inside, np.nan)
        candidates = [best]
        for s, e in ((a, b), (b, c), (c, a)):
            edge = e - s
            t = np.clip(np.einsum("ij,ij->i", p - s, edge) / np.einsum("ij,ij->i", edge, edge), 0, 1)
            candidates.append(s + t[:, None] * edge)
        stack = np.stack(candidates)  # (4, t, 3)
        dist = np.linalg.norm(stack - p, axis=2)
        dist[np.isnan(dist)] = np.inf
        which = dist.argmin(axis=0)
        per_tri = dist[which, np.arange(len(which))]
        tri = int(per_tri.argmin())
        return tri, stack[which[tri], tri].copy(), float(per_tri[tri])

    def barycentric(self, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Barycentric coordinates (m, 3) of points in their triangles (of their plane projections)."""
        a, b, c = (self.points[self.triangles[triangles, k]] for k in range(3))
        v0, v1, v2 = b - a, c - a, points - a
        d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
        d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
        den = d00 * d11 - d01 * d01
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        return np.stack([1 - v - w, v, w], axis=1)

    def interpolate(self, values: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Per-vertex ``values`` interpolated at points (barycentric)."""
        bary = self.barycentric(triangles, points)
        return (np.asarray(values, np.float64)[self.triangles[triangles]] * bary).sum(axis=1)


def _edge_neighbours(triangles: np.ndarray) -> np.ndarray:
    t = len(triangles)
    starts = triangles.ravel()
    ends = np.roll(triangles, -1, axis=1).ravel()
    key_dir = starts * (starts.max() + 1 + 1) + ends
    key_rev = ends * (starts.max() + 1 + 1) + starts
    order = np.argsort(key_dir)
    found = np.searchsorted(key_dir[order], key_rev)
    found = np.minimum(found, len(order) - 1)
    matched = key_dir[order][found] == key_rev
    undirected = np.minimum(starts, ends) * (starts.max() + 2) + np.maximum(starts, ends)
    _, counts = np.unique(undirected, return_counts=True)
    if (counts != 2).any() or not matched.all() or len(np.unique(key_dir)) != len(key_dir):
        open_edges = int((counts == 1).sum())
        raise GMapError(
            f"the surface is not a closed 2-manifold ({open_edges} open edge(s), "
            f"{int((counts > 2).sum())} edge(s) shared by more than two triangles, or "
            "inconsistent orientation): close the model first"
        )
    across = order[found] // 3
    return across.reshape(t, 3)


def from_polydata(mesh: pv.DataSet) -> TriMesh:
    """A :class:`TriMesh` from a pyvista surface (triangulated and merged first)."""
    surface = mesh.extract_surface(algorithm="dataset_surface").triangulate().clean()
    faces = np.asarray(surface.faces).reshape(-1, 4)
    if len(faces) and (faces[:, 0] != 3).any():
        raise GMapError("the surface could not be triangulated")
    return TriMesh(np.asarray(surface.points), faces[:, 1:])


def tubes_surface(
    start: ArrayLike,
    end: ArrayLike,
    base_radius: ArrayLike,
    top_radius: ArrayLike,
    parent: ArrayLike | None = None,
    sides: int = 10,
    min_radius: float = 0.0,
) -> TriMesh:
    """One closed surface around branch segments (a plant's bark): the union of a truncated
    cone per segment and a ball where a segment bends away from its ``parent`` segment by more
    than 5 degrees (without ``parent``: at every segment's start), by manifold3d's robust
    Boolean. A derived plant's tubes are open rings per segment, not a closed 2-manifold;
    this is what lichen and cracks need. Segments thinner than ``min_radius`` are drawn that
    thick; zero-length ones are left out.
    """
    import manifold3d

    start = np.asarray(start, np.float64).reshape(-1, 3)
    end = np.asarray(end, np.float64).reshape(-1, 3)
    r0 = np.maximum(np.asarray(base_radius, np.float64).reshape(-1), min_radius)
    r1 = np.maximum(np.asarray(top_radius, np.float64).reshape(-1), min_radius)
    axis = end - start
    length = np.linalg.norm(axis, axis=1)
    keep = (length > 1e-12) & (r0 > 0) & (r1 > 0)
    if not keep.any():
        raise GMapError("the plant has no branch segment with a length and a radius: no bark to grow on")
    unit = axis / np.maximum(length, 1e-300)[:, None]
    if parent is None:
        bend = np.ones(len(start), bool)
    else:
        parent = np.asarray(parent, np.int64).reshape(-1)
        has = parent >= 0
        bend = np.ones(len(start), bool)
        bend[has] = np.einsum("ij,ij->i", unit[has], unit[parent[has]]) < np.cos(np.radians(5.0))
    pieces = []
    for p, a, h, ra, rb, ball in zip(start[keep], axis[keep], length[keep], r0[keep], r1[keep], bend[keep]):
        z = a / h
        helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        frame = np.column_stack([x, y, z, p])
        pieces.append(manifold3d.Manifold.cylinder(float(h), float(ra), float(rb), sides).transform(frame))
        if ball:
            pieces.append(manifold3d.Manifold.sphere(float(ra), sides).translate(tuple(float(c) for c in p)))
    union = manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add)
    scale = float(np.ptp(np.r_[start, end], axis=0).max()) or 1.0
    union = union.simplify(1e-7 * scale)  # drop the Boolean's slivers (zero-area triangles)
    parts = union.decompose()
    if len(parts) > 1:  # and the specks it leaves (tiny closed bits where cones and balls graze)
        biggest = max(part.volume() for part in parts)
        union = manifold3d.Manifold.compose([part for part in parts if part.volume() > 1e-6 * biggest])
    out = union.to_mesh64() if hasattr(union, "to_mesh64") else union.to_mesh()
    # copies, not views: a view keeps manifold3d's mesh alive (nanobind reports it leaked at exit)
    points = np.array(out.vert_properties[:, :3], np.float64)
    tris = np.array(out.tri_verts, np.int64)
    a, b, c = (points[tris[:, k]] for k in range(3))
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if (area <= 1e-300).any():
        raise GMapError(f"the bark surface keeps {int((area <= 1e-300).sum())} zero-area triangle(s)")
    return TriMesh(points, tris)
