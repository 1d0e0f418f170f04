"""Cracks from a skeleton and a profile (Desbenoit, Galin, Akkouche 2005; thesis ch. 5).

A crack is ``F = {M, P}``: a **pattern** ``M`` — an acyclic graph whose arcs carry a length
``δ`` and a turning angle ``α`` (from the parent arc's direction) — and **profiles** ``P`` — at
each node, the crack's half-width ``w`` and depth ``h``, one per arc end meeting there. Applied
to a closed surface ``O``:

1. **skeleton**: from an anchor and a direction the pattern is walked over the surface (the
   walker turns by ``α`` in the tangent plane and crosses triangles like the lichen walker);
2. **sections**: along an arc of length ``δ_ij`` the section at arc length ``δ_ik`` is
   ``(1 − u) P_i + u P_j`` with ``u = δ_ik / δ_ij`` (the printed formula swaps the weights);
   a section is the triangle ``(−w, a), (w, a), (0, −h)`` in the frame ``(t, n)`` of the
   sample (``t = n ∧ d``), ``a = h/2`` above the surface so the cut goes through it;
3. **volume**: consecutive sections are joined into a closed generalized cylinder per arc,
   with caps; samples are resampled adaptively — merged when ``δ < r_i + r_j``, split when
   ``δ > 2(r_i + r_j)`` (``r`` the radius of a section's bounding disc; the spec's correction
   of the overlapping printed band);
4. **cracked object** ``O − V`` by a robust mesh Boolean (manifold3d), watertight and manifold.

**Growth**: node ``j`` starts at ``t_j = t_i + δ_ij / v`` and grows for ``Δt = τ``; the crack at
time ``t0`` keeps arcs that have ended, cuts the one in progress at ``(t0 − t_i)/(t_j − t_i)``
of its length, and scales a still-growing node's profile by ``(t0 − t_i)/Δt`` — so the
crack's length never decreases with ``t0``, and from ``max(t_i + Δt_i)`` on it is the static
crack. Operators: **noise** (points inserted along arcs and jittered), **smoothing** (the
change between successive turning angles is bounded) and **symmetry** (``k`` rotated copies
around the root). Patterns come from a seeded random tree or from an L-system's skeleton.

>>> import pyvista as pv
>>> from ramure.gmap.organs.trimesh import from_polydata
>>> stone = pv.Icosphere(radius=2.0, nsub=4)
>>> pattern = random_pattern(12, seed=1, length=0.25, width=0.03, depth=0.05)
>>> crack = carve(stone, pattern, anchor=(0, 0, 2.0), direction=(1, 0, 0))
>>> crack.facts()["watertight"], crack.volume_removed > 0
(True, True)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.organs import _dla_kernel as walker
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.trimesh import TriMesh, from_polydata

if TYPE_CHECKING:
    import pyvista as pv

    from ramure.lsys import Skeleton

MAX_NODES = 100_000

#: One sample of an arc walked over the surface, ``(position, direction, normal, u)``
#: with ``u`` from 0 at the parent node to 1 at the child.
Sample = tuple[np.ndarray, np.ndarray, np.ndarray, float]
#: One walked arc, ``(parent node, child node, samples)``.
Arc = tuple[int, int, list[Sample]]


@dataclass
class CrackPattern:
    """An acyclic crack pattern: ``parent`` (m,) (-1 for the root), ``length`` (m,) ``δ`` of the
    arc from the parent, ``angle`` (m,) ``α`` in degrees from the parent arc's direction,
    ``width``/``depth`` (m,) the node's profile, ``start``/``duration`` (m,) ``t_i``, ``Δt_i``.

    Nodes are listed parents first (``parent[j] < j``; the walks rely on it).  Without
    ``start``/``duration``, :meth:`timing` sets them (speed 1, ``τ`` = 0.5).
    Built from arcs with :meth:`from_arcs`, which refuses cycles (naming one) and checks that
    each node has one profile per incident arc (two for a leaf).
    """

    parent: np.ndarray
    length: np.ndarray
    angle: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    start: np.ndarray = field(default_factory=lambda: np.empty(0))
    duration: np.ndarray = field(default_factory=lambda: np.empty(0))

    def __post_init__(self) -> None:
        m = len(self.parent)
        if not 1 <= m <= MAX_NODES:
            raise GMapError(f"a crack pattern has 1..{MAX_NODES:,} nodes, not {m}")
        self.parent = np.asarray(self.parent, np.int64).reshape(m)
        if self.parent[0] != -1 or ((self.parent[1:] < 0) | (self.parent[1:] >= np.arange(1, m))).any():
            raise GMapError("a crack pattern lists each node after its parent: parent[0] = -1 and 0 <= parent[j] < j")
        for name in ("length", "angle", "width", "depth"):
            setattr(self, name, np.asarray(getattr(self, name), np.float64).reshape(m))
        if (self.length[1:] <= 0).any() or (self.width < 0).any() or (self.depth < 0).any():
            raise GMapError("arc lengths must be > 0 and profile widths and depths >= 0")
        if not all(np.isfinite(getattr(self, n)).all() for n in ("length", "angle", "width", "depth")):
            raise GMapError("a crack pattern holds finite numbers only")
        if self.start is None or not len(self.start):  # not given: the default growth timing
            self.timing()

    @classmethod
    def from_arcs(
        cls,
        arcs: Iterable[Sequence[int]],
        lengths: Sequence[float],
        angles: Sequence[float],
        profiles: Sequence[Sequence[tuple[float, float]]],
    ) -> CrackPattern:
        """Pattern from directed arcs ``(i, j)``; ``profiles[node]`` lists ``(w, h)`` per incident arc
        (two for a leaf). Refuses cycles and profile counts that do not match the node's valence."""
        arcs = [tuple(map(int, a)) for a in arcs]
        nodes = sorted({n for a in arcs for n in a} | set(range(len(profiles))))
        parent = {}
        for (i, j), _ in zip(arcs, lengths):
            if j in parent:
                raise GMapError(f"node {j} has two incoming arcs: a crack pattern is a tree")
            parent[j] = i
        for start in nodes:  # a cycle: following parents comes back to the start
            seen, n = [start], parent.get(start)
            while n is not None:
                if n == start:
                    cycle = [start, *seen[:0:-1], start]  # parents walked back: print the arcs' way
                    raise GMapError(f"the crack pattern has a cycle: {' -> '.join(map(str, cycle))}")
                if n in seen:
                    break
                seen.append(n)
                n = parent.get(n)
        valence = {n: 0 for n in nodes}
        for i, j in arcs:
            valence[i] += 1
            valence[j] += 1
        for n in nodes:
            expected = max(2, valence[n])
            if len(profiles[n]) != expected:
                raise GMapError(f"node {n} has {len(profiles[n])} profile(s) for valence {valence[n]}: expected {expected}")
        roots = [n for n in nodes if n not in parent]
        if len(roots) != 1:
            raise GMapError(f"a crack pattern has one root, not {len(roots)}")
        order = _topological(nodes, parent, roots[0])
        index = {n: k for k, n in enumerate(order)}
        by_arc = {j: (length, angle) for (i, j), length, angle in zip(arcs, lengths, angles)}
        prof = np.array([np.mean(profiles[n], axis=0) for n in order])
        return cls(
            np.array([index[parent[n]] if n in parent else -1 for n in order]),
            np.array([by_arc.get(n, (0.0, 0.0))[0] for n in order]),
            np.array([by_arc.get(n, (0.0, 0.0))[1] for n in order]),
            prof[:, 0],
            prof[:, 1],
        )

    def __len__(self) -> int:
        return len(self.parent)

    def timing(self, speed: float = 1.0, tau: float = 0.5) -> CrackPattern:
        """Set ``t_j = t_i + δ_ij / v`` and ``Δt_j = τ`` (the root starts at 0)."""
        if not (speed > 0 and tau > 0):
            raise GMapError("the growth speed and duration must be > 0")
        self.start = np.zeros(len(self))
        for j in range(1, len(self)):
            self.start[j] = self.start[self.parent[j]] + self.length[j] / speed
        self.duration = np.full(len(self), float(tau))
        return self

    def progress(self, t0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(kept, fraction, scale)`` per node at time ``t0``: the node's arc exists, the part of
        its length grown (1 once the node is reached), and its profile's scale (0..1)."""
        if not np.isfinite(t0):
            raise GMapError(f"the crack time must be finite, not {t0}")
        m = len(self)
        kept = np.zeros(m, bool)
        kept[0] = True
        fraction, scale = np.ones(m), np.ones(m)
        for j in range(1, m):  # parents come before their children
            i = self.parent[j]
            if kept[i] and self.start[i] < t0:
                kept[j] = True
                if t0 < self.start[j]:  # the arc in progress: cut, its tip a point
                    fraction[j] = (t0 - self.start[i]) / (self.start[j] - self.start[i])
                    scale[j] = 0.0
        fraction[~kept] = 0.0
        grow = (self.start < t0) & (t0 < self.start + self.duration)
        scale[grow] = np.minimum(scale[grow], (t0 - self.start[grow]) / self.duration[grow])
        if t0 <= 0:
            scale[0] = 0.0
        return kept, fraction, scale

    def at(self, t0: float) -> CrackPattern:
        """The pattern grown until ``t0``: finished arcs, the arc in progress cut, growing nodes scaled."""
        kept, fraction, scale = self.progress(t0)
        length = self.length * fraction
        length[0] = self.length[0]
        keep = np.flatnonzero(kept)
        remap = np.cumsum(kept) - 1
        parent = np.where(self.parent[keep] >= 0, remap[np.maximum(self.parent[keep], 0)], -1)
        return CrackPattern(
            parent,
            length[keep],
            self.angle[keep],
            self.width[keep] * scale[keep],
            self.depth[keep] * scale[keep],
            self.start[keep],
            self.duration[keep],
        )

    def total_length(self) -> float:
        return float(self.length[1:].sum())


def _topological(nodes: list[int], parent: dict[int, int], root: int) -> list[int]:
    children: dict[int, list[int]] = {n: [] for n in nodes}
    for j, i in parent.items():
        children[i].append(j)
    order, stack = [], [root]
    while stack:
        n = stack.pop()
        order.append(n)
        stack.extend(sorted(children[n], reverse=True))
    return order


# -- patterns --------------------------------------------------------------------------------
def random_pattern(
    nodes: int,
    seed: int = 0,
    length: float = 0.2,
    width: float = 0.02,
    depth: float = 0.04,
    branching: float = 0.3,
    spread: float = 35.0,
) -> CrackPattern:
    """A seeded random tree pattern: each new node continues an arc (probability ``1 − branching``)
    or branches off an earlier node; turning angles within ``±spread`` degrees; profiles thin
    towards the leaves."""
    rng = np.random.default_rng(seed)
    parent = np.full(nodes, -1, np.int64)
    angle = np.zeros(nodes)
    tip = 0
    for j in range(1, nodes):
        if rng.random() < branching and j > 2:
            parent[j] = rng.integers(0, j - 1)
            angle[j] = rng.choice([-1, 1]) * rng.uniform(30, 70)
        else:
            parent[j] = tip
            angle[j] = rng.uniform(-spread, spread)
        tip = j
    lengths = np.r_[0.0, length * rng.uniform(0.6, 1.4, nodes - 1)]
    depth_from_root = np.zeros(nodes)
    for j in range(1, nodes):
        depth_from_root[j] = depth_from_root[parent[j]] + 1
    fade = 1.0 / (1.0 + 0.08 * depth_from_root)
    return CrackPattern(parent, lengths, angle, width * fade, depth * fade)


def pattern_from_skeleton(skeleton: Skeleton, width: float = 0.02, depth: float = 0.04, scale: float = 1.0) -> CrackPattern:
    """A pattern from a derived plant's branching (an L-system crack): one node per segment end,
    arc lengths the segment lengths, turning angles measured in the x-z plane."""
    n = len(skeleton)
    if n == 0:
        raise GMapError("the plant has no segment to make a crack pattern from")
    seg = skeleton.end - skeleton.start
    heading = np.degrees(np.arctan2(seg[:, 0], seg[:, 2]))
    parent_seg = np.asarray(skeleton.parent, np.int64)
    angle = np.where(parent_seg >= 0, heading - heading[np.maximum(parent_seg, 0)], heading)
    parent = np.r_[-1, parent_seg + 1]
    lengths = np.r_[0.0, np.linalg.norm(seg, axis=1) * scale]
    angle = np.r_[0.0, (angle + 180) % 360 - 180]
    return CrackPattern(parent, lengths, angle, np.full(n + 1, width), np.full(n + 1, depth))


def add_noise(pattern: CrackPattern, amount: float = 10.0, inserts: int = 1, seed: int = 0) -> CrackPattern:
    """Insert ``inserts`` points along every arc and jitter every turning angle by ``±amount`` degrees."""
    rng = np.random.default_rng(seed)
    parent, length, angle = [-1], [0.0], [0.0]
    width, depth = [pattern.width[0]], [pattern.depth[0]]
    new_of = {0: 0}
    for j in range(1, len(pattern)):
        prev = new_of[pattern.parent[j]]
        pieces = inserts + 1
        for k in range(pieces):
            u = (k + 1) / pieces
            parent.append(prev)
            length.append(pattern.length[j] / pieces)
            angle.append((pattern.angle[j] if k == 0 else 0.0) + rng.uniform(-amount, amount))
            i = pattern.parent[j]
            width.append((1 - u) * pattern.width[i] + u * pattern.width[j])
            depth.append((1 - u) * pattern.depth[i] + u * pattern.depth[j])
            prev = len(parent) - 1
        new_of[j] = prev
    return CrackPattern(np.array(parent), np.array(length), np.array(angle), np.array(width), np.array(depth))


def smooth(pattern: CrackPattern, max_change: float = 10.0) -> CrackPattern:
    """Bound the change between a node's turning angle and its parent's by ``max_change`` degrees."""
    angle = pattern.angle.copy()
    for j in range(1, len(pattern)):
        i = pattern.parent[j]
        if i > 0:
            angle[j] = np.clip(angle[j], angle[i] - max_change, angle[i] + max_change)
    return CrackPattern(pattern.parent, pattern.length, angle, pattern.width, pattern.depth)


def symmetric(pattern: CrackPattern, copies: int) -> CrackPattern:
    """``copies`` copies of the pattern rotated evenly around the root (a circular crack)."""
    if copies < 1:
        raise GMapError("symmetry needs at least one copy")
    m = len(pattern)
    parent, length, angle, width, depth = [-1], [0.0], [0.0], [pattern.width[0]], [pattern.depth[0]]
    for c in range(copies):
        base = len(parent) - 1
        for j in range(1, m):
            i = pattern.parent[j]
            parent.append(0 if i == 0 else base + i)
            length.append(pattern.length[j])
            angle.append(pattern.angle[j] + (360.0 * c / copies if i == 0 else 0.0))
            width.append(pattern.width[j])
            depth.append(pattern.depth[j])
    return CrackPattern(np.array(parent), np.array(length), np.array(angle), np.array(width), np.array(depth))


# -- projection, sweep, Boolean ----------------------------------------------------------------
@dataclass
class Crack:
    """A carved object: ``result`` (pyvista PolyData), the crack volume ``volume`` (PolyData), the
    skeleton ``points`` (per node, on the surface), and counts for the thesis's Table 5.1."""

    result: pv.PolyData
    volume: pv.PolyData
    points: np.ndarray
    nodes: int
    triangles_object: int
    triangles_crack: int
    volume_removed: float
    length: float

    def facts(self) -> dict[str, Any]:
        t_o, t_f = self.triangles_object, int(self.result.n_cells)
        return {
            "nodes": self.nodes,
            "triangles_object": t_o,
            "triangles_crack": self.triangles_crack,
            "triangles_result": t_f,
            "delta_triangles_percent": round(100.0 * (t_f - t_o) / t_o, 1),
            "length": round(self.length, 6),
            "volume_removed": self.volume_removed,
            "watertight": bool(_is_watertight(self.result)),
        }


def project(
    mesh: TriMesh, pattern: CrackPattern, anchor: ArrayLike, direction: ArrayLike, samples_per_arc: int = 4
) -> tuple[np.ndarray, list[Arc]]:
    """Walk the pattern over the surface: node positions, and per arc the samples
    ``(position, direction, normal, u)`` along it (``u`` from 0 at the parent to 1)."""
    anchor = np.asarray(anchor, np.float64)
    tri, start, distance = mesh.closest_point(anchor)
    n = mesh.normals[tri]
    start += 1e-4 * (mesh.points[mesh.triangles[tri]].mean(axis=0) - start)  # off the edges and corners
    if distance > 10 * np.sqrt(mesh.areas[tri]):
        raise GMapError("the anchor is not on the surface: give a point on (or very near) the model")
    d = np.asarray(direction, np.float64)
    d = d / max(float(np.linalg.norm(d)), 1e-300)
    d = d - np.dot(d, n) * n
    if np.linalg.norm(d) < 0.05:  # within 3 degrees of the normal: no direction along the surface
        raise GMapError("the crack direction is along the surface normal: give a direction along the surface")
    d /= np.linalg.norm(d)
    m = len(pattern)
    where = [(tri, start, d)] * m  # node j's (triangle, position, direction); parents come first
    arcs: list[Arc] = []
    for j in range(1, m):
        tri, pos, d = where[pattern.parent[j]]
        d = walker.rotate_in_plane(d, mesh.normals[tri], np.radians(pattern.angle[j]))
        samples = [(pos, d, mesh.normals[tri], 0.0)]
        piece = pattern.length[j] / samples_per_arc
        for k in range(samples_per_arc):
            tri, pos, d = walker.step_on_surface(mesh.points, mesh.triangles, mesh.across, mesh.normals, tri, pos, d, piece)
            samples.append((pos, d, mesh.normals[tri], (k + 1) / samples_per_arc))
        where[j] = (tri, pos, d)
        arcs.append((int(pattern.parent[j]), j, samples))
    return np.array([w[1] for w in where]), arcs


def _sections(pattern, arcs):
    """Per arc, the list of section triangles (3, 3) after adaptive merge/split."""
    out = []
    for i, j, samples in arcs:
        pos = np.array([s[0] for s in samples])
        d = np.array([s[1] for s in samples])
        n = np.array([s[2] for s in samples])
        u = np.array([s[3] for s in samples])[:, None]
        w = (1 - u) * pattern.width[i] + u * pattern.width[j]
        h = (1 - u) * pattern.depth[i] + u * pattern.depth[j]
        t = np.cross(n, d)
        tris = np.stack([pos - w * t + 0.5 * h * n, pos + w * t + 0.5 * h * n, pos - h * n], axis=1)
        radius = np.maximum(w, h)[:, 0]
        out.append(_resample(list(zip(pos, tris, radius))))
    return out


def _resample(sections):
    """Merge samples closer than ``r_i + r_j``; split gaps wider than ``2 (r_i + r_j)``.

    The arc's end samples are kept where they are (an interior sample merges into them), so
    consecutive arcs still meet at their node.
    """
    out = [sections[0]]
    for k, (pos, tri, r) in enumerate(sections[1:], start=1):
        last = k == len(sections) - 1
        ppos, ptri, pr = out[-1]
        gap = float(np.sqrt(((pos - ppos) ** 2).sum()))
        if gap < pr + r and len(out) > 1:  # too close: the interior sample goes
            if last:
                out[-1] = (pos, tri, r)
            else:
                wsum = pr + r
                out[-1] = ((pr * ppos + r * pos) / wsum, (pr * ptri + r * tri) / wsum, max(pr, r))
            continue
        while gap > 2 * (pr + r) and (pr + r) > 0:
            mid = ((pr * ppos + r * pos) / (pr + r), (pr * ptri + r * tri) / (pr + r), (pr + r) / 2)
            out.append(mid)
            ppos, ptri, pr = mid
            gap = float(np.sqrt(((pos - ppos) ** 2).sum()))
        out.append((pos, tri, r))
    return [s[1] for s in out if s[2] > 0]


def _extend_ends(sections):
    """Push the first and last sections outward by half their size along the arc, so the tubes of
    arcs that meet at a node overlap instead of touching."""
    if len(sections) < 2:
        return sections
    out = [s.copy() for s in sections]
    for end, inner in ((0, 1), (-1, -2)):
        axis = out[end].mean(axis=0) - out[inner].mean(axis=0)
        size = np.linalg.norm(axis)
        if size > 0:
            reach = 0.5 * np.linalg.norm(out[end] - out[end].mean(axis=0), axis=1).max()
            out[end] = out[end] + axis / size * reach
    return out


def _tube(sections):
    """A closed triangular tube through the section triangles (vertices, faces)."""
    k = len(sections)
    verts = np.concatenate(sections)
    faces = []
    for s in range(k - 1):
        a, b = 3 * s, 3 * (s + 1)
        for e in range(3):
            f = (e + 1) % 3
            faces += [[a + e, b + e, b + f], [a + e, b + f, a + f]]
    faces += [[0, 1, 2], [3 * (k - 1) + 2, 3 * (k - 1) + 1, 3 * (k - 1)]]
    return verts, np.array(faces, np.int64)


def carve(
    model: TriMesh | pv.DataSet,
    pattern: CrackPattern,
    anchor: ArrayLike,
    direction: ArrayLike,
    t0: float | None = None,
    samples_per_arc: int = 4,
) -> Crack:
    """Carve ``pattern`` (grown until ``t0``; default: fully grown) into a closed surface."""
    import manifold3d
    import pyvista as pv

    mesh = model if isinstance(model, TriMesh) else from_polydata(model)
    grown = pattern if t0 is None else pattern.at(t0)
    points, arcs = project(mesh, grown, anchor, direction, samples_per_arc)
    solid = _manifold(manifold3d, mesh.points, mesh.triangles)
    pieces, crack_tris = [], 0
    for sections in _sections(grown, arcs):
        if len(sections) < 2:
            continue
        verts, faces = _tube(_extend_ends(sections))
        piece = _manifold(manifold3d, verts, faces)
        if piece.volume() < 0:
            piece = _manifold(manifold3d, verts, faces[:, ::-1])
        if not piece.is_empty() and piece.volume() > 0:
            pieces.append(piece)
            crack_tris += len(faces)
    volume = manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add) if pieces else manifold3d.Manifold()
    result = solid - volume
    out = result.to_mesh()
    faces = np.hstack([np.full((len(out.tri_verts), 1), 3), out.tri_verts]).ravel()
    carved = pv.PolyData(np.asarray(out.vert_properties[:, :3], np.float64), faces)
    vmesh = volume.to_mesh()
    vfaces = np.hstack([np.full((len(vmesh.tri_verts), 1), 3), vmesh.tri_verts]).ravel()
    vpoly = pv.PolyData(np.asarray(vmesh.vert_properties[:, :3], np.float64), vfaces) if len(vmesh.tri_verts) else pv.PolyData()
    return Crack(
        carved,
        vpoly,
        points,
        len(grown),
        len(mesh.triangles),
        crack_tris,
        float(solid.volume() - result.volume()),
        grown.total_length(),
    )


def _manifold(manifold3d, verts, faces):
    mesh = manifold3d.Mesh(vert_properties=np.asarray(verts, np.float32), tri_verts=np.asarray(faces, np.uint32))
    return manifold3d.Manifold(mesh)


def _is_watertight(poly: pv.PolyData) -> bool:
    if poly.n_cells == 0:
        return False
    edges = poly.extract_feature_edges(boundary_edges=True, non_manifold_edges=True, feature_edges=False, manifold_edges=False)
    return edges.n_cells == 0
