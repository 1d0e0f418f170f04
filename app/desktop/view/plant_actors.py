"""The plant's tubes on screen, grouped by thickness and drawn only where they show.

Software OpenGL (llvmpipe: Ramure never needs a GPU) pays for every triangle
it is given, whether it covers a pixel or not.  Honda sympodial n = 17 has
131,000 segments (393,000 tube quads); framed whole in the desktop view, all
but about 500 of them are thinner than a pixel, and a repaint of every tube
took about 150 ms.  Every segment is also drawn as a hairline
(:class:`ramure.app.desktop.view.scene.Hairlines`), which is all a sub-pixel tube
shows as anyway.  Choices, stated here:

* **Groups by radius.**  Tube segments fall in classes a factor 2 apart below
  the thickest (:data:`MAX_CLASSES` at most; the last takes everything
  thinner); each class is one actor.  Organs and polygons (every cell after
  the tubes) are one more actor.
* **Level of detail.**  Before each frame (the renderer's ``StartEvent``, so
  camera moves by the mouse count too) a class is drawn only if its thickest
  tube is at least :data:`MIN_PIXELS` wide at the class's nearest point to the
  camera (depth along the view direction, perspective or parallel).  Zooming
  in brings the thin classes back, full tubes near, hairlines far.
* **Edits cost what is drawn.**  A class's polydata (its tubes' points and
  quads, colours) is gathered from the full mesh only when it is drawn and out
  of date: a regrow rebuilds and uploads the drawn classes; a hidden class
  waits until the camera comes close.
* **While the camera moves** (:meth:`PlantActors.set_moving`), plants of
  :data:`LOD_SEGMENTS` segments or more draw the visible groups, thickest
  first, while they fit in :data:`MOTION_CELLS` cells; the hairlines carry the rest.
* **Picking** uses the full mesh through an actor that is never drawn
  (:attr:`PlantActors.pick_actor`, for a picker's pick list), so a cell id is
  the full mesh's whatever is drawn, and maps to its history leaf as before.
* **Undo and redo draw what was drawn.**  The groups of the plant shown before
  the last new one are kept with their actors (hidden), keyed by the model's
  mesh; showing that mesh again (an undo, or a redo after it) brings them back
  as they were, their GPU buffers included, instead of sorting and uploading
  the plant again.  Only their colours are refreshed if they changed.
* Shading is flat, as before (the tubes' facets show; no point normals are
  computed: flat interpolation ignores them).

A mesh whose cells are not laid out as :func:`ramure.lsys.interpretation.geometry.polydata_from_parts`
lays them out (tube quads segment by segment, then triangles) is drawn as one
actor, as it is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.lsys.interpretation.turtle import Skeleton

#: A tube class is drawn when its thickest tube is at least this many pixels wide.
MIN_PIXELS = 0.5
#: Radius classes (factor 2 apart); the last holds every thinner tube.
MAX_CLASSES = 12
#: Plants with at least this many segments draw at most MOTION_CELLS cells while the view moves.
LOD_SEGMENTS = 30_000
MOTION_CELLS = 60_000


@dataclass(eq=False)
class _Group:
    """Cells of the full mesh drawn by one actor."""

    count: int  # cells
    radius: float  # the thickest tube (inf: organs, drawn at any distance)
    corners: np.ndarray  # (8, 3) corners of the group's box
    segments: np.ndarray | None = None  # tube groups: the segments, ascending
    actor: Any = None
    poly: Any = None
    stale_geometry: bool = True
    stale_colors: bool = True
    keep: list = field(default_factory=list)  # numpy arrays VTK reads without a copy


#: Which end (0: lo, 1: hi) of x, y and z each box corner takes, in ``np.meshgrid(..., indexing="ij")`` order.
_CORNER_ENDS = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)])


def pixels_per_unit(renderer: Any, corners: np.ndarray) -> float:
    """The most pixels one unit of length spans anywhere in the box with ``corners`` ((8, 3)),
    seen from ``renderer``'s camera: at the box's nearest depth along the view direction
    (perspective), or everywhere alike (parallel projection); inf when the box reaches the
    camera's plane."""
    camera = renderer.GetActiveCamera()
    height = max(int(renderer.GetSize()[1]), 1)
    if camera.GetParallelProjection():
        return height / (2.0 * max(camera.GetParallelScale(), 1e-300))
    depth = float(((corners - np.array(camera.GetPosition())) @ np.array(camera.GetDirectionOfProjection())).min())
    if depth <= 1e-12:
        return float("inf")
    return float(height / (2.0 * depth * np.tan(np.radians(camera.GetViewAngle()) / 2)))


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(8, 3) corners of the box ``lo``-``hi`` (as a meshgrid of its ends, without one)."""
    return np.c_[lo, hi][np.arange(3), _CORNER_ENDS]


def tube_layout(mesh: pv.PolyData, segments: int) -> int:
    """Sides per tube if ``mesh``'s cells are ``segments`` tubes' quads, segment by segment,
    then only triangles (the layout of :func:`ramure.lsys.interpretation.geometry.polydata_from_parts`); else 0."""
    if segments == 0 or mesh.GetNumberOfVerts() or mesh.GetNumberOfLines() or mesh.GetNumberOfStrips():
        return 0
    if "segment" not in mesh.cell_data:
        return 0
    seg = np.asarray(mesh.cell_data["segment"])
    quads = int(np.count_nonzero(seg >= 0))
    sides = quads // segments
    if sides < 3 or sides * segments != quads or (seg[quads:] >= 0).any():
        return 0
    ids = np.arange(segments)
    if not (np.array_equal(seg[0:quads:sides], ids) and np.array_equal(seg[sides - 1 : quads : sides], ids)):
        return 0
    if mesh.n_points < quads * 2:
        return 0
    return sides


class PlantActors:
    """The plant mesh drawn as a few actors with level of detail (see the module's notes)."""

    def __init__(self, plotter: pv.BasePlotter) -> None:
        # the two classes only: ``import vtk`` loads every VTK module (about 60 MB)
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        self.plotter = plotter
        self.renderer = plotter.renderer
        self.mesh: pv.PolyData | None = None
        self.groups: list[_Group] = []
        self.sides = 0
        self.segment_count = 0
        self.moving = False
        self.large = False
        self.key: Any = None  # what the shown version was drawn from (the model's mesh)
        self.kept: dict | None = None  # the version shown before, its actors hidden
        self._classes: dict | None = None  # the last skeleton's radius classes and their boxes
        self.bounds: tuple | None = None  # the model mesh's bounds (VTK's order), known without VTK
        self.segment_bounds: tuple | None = None  # the bounds of the shown skeleton's segment ends (its hairlines)
        self._spare: list = []  # actors free for the next version's groups
        self.pick_mapper = vtkPolyDataMapper()
        self.pick_actor = vtkActor()  # never added to the renderer: picking only
        self.pick_actor.SetMapper(self.pick_mapper)
        self.renderer.AddObserver("StartEvent", self._before_frame)

    # -- content -------------------------------------------------------------------
    _STATE = ("key", "mesh", "groups", "sides", "segment_count", "large", "_classes", "bounds", "segment_bounds")

    def show(self, mesh: pv.PolyData | None, skeleton: Skeleton | None, key: Any = None) -> None:
        """Draw ``mesh`` (cell data ``rgb``; tubes of ``skeleton``'s segments first).

        ``key`` names the version (the model's mesh ``mesh`` is a shallow copy of): the
        version shown before is kept, and showing its key again brings its groups back.
        """
        if key is not None and self.kept is not None and self.kept["key"] is key and mesh is not None:
            self._swap(mesh)
            return
        last = self._classes
        self._keep(key)
        self.key = key
        self.mesh = mesh
        self.bounds = self.segment_bounds = None
        if mesh is None or mesh.n_cells == 0:
            self._set_groups([])
            self.pick_mapper.RemoveAllInputs()
            return
        self.pick_mapper.SetInputData(mesh)
        count = 0 if skeleton is None else len(skeleton)
        self.segment_count = count
        self.sides = tube_layout(mesh, count)
        self.large = count >= LOD_SEGMENTS
        if not self.sides:
            b = np.reshape(mesh.bounds, (3, 2))
            self._set_groups([_Group(mesh.n_cells, np.inf, box_corners(b[:, 0], b[:, 1]))])
            return
        assert skeleton is not None
        groups = self._tube_groups(skeleton, last)
        quads = count * self.sides
        source = key if hasattr(key, "GetPoints") and key.n_points == mesh.n_points else mesh
        tube_lo, tube_hi = self._tube_bounds(np.asarray(source.points), skeleton, last)
        lo, hi = tube_lo, tube_hi
        if mesh.n_cells > quads:
            b = np.reshape(_bounds(np.asarray(mesh.points)[quads * 2 :]), (3, 2))
            groups.append(_Group(mesh.n_cells - quads, np.inf, box_corners(b[:, 0], b[:, 1])))
            if source is not mesh:
                b = np.reshape(_bounds(np.asarray(source.points)[quads * 2 :]), (3, 2))
            lo, hi = np.minimum(lo, b[:, 0]), np.maximum(hi, b[:, 1])
        self.bounds = _as_bounds(lo, hi)
        self._set_groups(groups)

    def _tube_bounds(self, points: np.ndarray, sk: Skeleton, last: dict | None) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest tube point of the mesh whose ``points`` are given: patched from
        ``last`` (the version ``sk`` was re-interpreted from, drawn with as many sides) as its
        classes are; computed again when a removed tube touched the old box."""
        k = 2 * self.sides
        tubes = points[: len(sk) * k].reshape(-1, k, 3)
        reuse = sk.extra.get("reuse")
        lo = hi = None
        if (
            last is not None
            and reuse is not None
            and sk.extra.get("reuse_of") == id(last["skeleton"])
            and last.get("sides") == self.sides
            and last["points"].dtype == points.dtype
        ):
            new, old = reuse
            lo, hi = last["tube_lo"], last["tube_hi"]
            gone = _others(old, len(last["skeleton"]))
            if gone.size:
                g = last["points"][: len(last["skeleton"]) * k].reshape(-1, k, 3)[gone]
                if (g.min(axis=(0, 1)) <= lo).any() or (g.max(axis=(0, 1)) >= hi).any():
                    lo = hi = None  # a removed tube was on the box: computed again
            added = tubes[_others(new, len(sk))]
            if lo is not None and hi is not None and len(added):
                lo, hi = np.minimum(lo, added.min(axis=(0, 1))), np.maximum(hi, added.max(axis=(0, 1)))
        if lo is None or hi is None:
            import pyvista as pv

            b = np.reshape(pv.vtk_points(np.ascontiguousarray(tubes.reshape(-1, 3)), deep=False).GetBounds(), (3, 2))
            lo, hi = b[:, 0].copy(), b[:, 1].copy()
        assert self._classes is not None
        self._classes.update(sides=self.sides, points=points, tube_lo=lo, tube_hi=hi)
        return lo, hi

    def _tube_groups(self, sk: Skeleton, last: dict | None) -> list[_Group]:
        """The radius classes of ``sk`` (patched from ``last``, the classes of the version
        shown before, when ``sk`` was re-interpreted from it)."""
        radius = np.maximum(np.asarray(sk.base_radius, float), np.asarray(sk.top_radius, float))
        top = float(radius.max(initial=0.0))
        reuse = sk.extra.get("reuse")
        if last is not None and reuse is not None and sk.extra.get("reuse_of") == id(last["skeleton"]) and top == last["top"]:
            level, lo, hi = _classes_after_edit(last, sk, radius, top, reuse)
        else:
            level = _levels(radius, top)
            lo, hi = _class_boxes(sk, level, np.arange(MAX_CLASSES))
        self._classes = {"skeleton": sk, "top": top, "level": level, "lo": lo, "hi": hi}
        if len(sk):  # the segment ends' bounds: the classes' boxes together
            self.segment_bounds = _as_bounds(lo.min(axis=0), hi.max(axis=0))
        order = np.argsort(level, kind="stable")  # int8: a radix sort, ascending segment ids per class
        starts = np.searchsorted(level[order], np.arange(MAX_CLASSES + 1))
        present = np.flatnonzero(np.diff(starts))
        biggest = np.maximum.reduceat(np.take(radius, order), starts[present])
        groups = []
        for j, k in enumerate(present):
            segs = order[starts[k] : starts[k + 1]]
            r = float(biggest[j])
            groups.append(_Group(len(segs) * self.sides, r, box_corners(lo[k] - r, hi[k] + r), segments=segs))
        return groups

    def _keep(self, key: Any) -> None:
        """Before version ``key`` is shown: keep the shown version (its groups and actors,
        hidden) for an undo, and free the actors of the version kept before.  The shown
        version drawn again (the same key) or unnamed (no key) is not kept: its actors are
        reused."""
        if self.key is None or self.key is key:
            spare = [g.actor for g in self.groups]
        else:
            spare = [] if self.kept is None else [g.actor for g in self.kept["groups"]]
            self.kept = {name: getattr(self, name) for name in self._STATE}
            for g in self.groups:
                g.actor.SetVisibility(False)
        self.groups = []
        self._spare += spare

    def forget_kept(self) -> None:
        """Drop the kept version: its actors become spares, their cells and points let go."""
        if self.kept is None:
            return
        for g in self.kept["groups"]:
            if g.poly is not None:
                g.poly.Initialize()
            g.keep = []
        self._spare += [g.actor for g in self.kept["groups"]]
        self.kept = None

    def _swap(self, mesh: pv.PolyData) -> None:
        """Show the kept version again (``mesh``: its shallow copy with this frame's colours)."""
        kept = self.kept
        assert kept is not None
        old_mesh = kept["mesh"]
        current = {name: getattr(self, name) for name in self._STATE}
        for g in self.groups:
            g.actor.SetVisibility(False)
        for name, value in kept.items():
            setattr(self, name, value)
        self.kept = current if current["key"] is not None else None
        if self.kept is None:
            self._spare += [g.actor for g in current["groups"]]
        self.mesh = mesh
        self.pick_mapper.SetInputData(mesh)
        if mesh.GetPoints() is not old_mesh.GetPoints():  # fruit spheres or cells hidden since
            for g in self.groups:
                g.stale_geometry = True
        if not np.array_equal(np.asarray(mesh.cell_data["rgb"]), np.asarray(old_mesh.cell_data["rgb"])):
            self.colors_changed()

    def _set_groups(self, groups: list[_Group]) -> None:
        """New groups; the actors of old groups are reused in order (no new GL objects)."""
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        actors = self._spare + [g.actor for g in self.groups]
        self._spare = []
        for actor in actors[len(groups) :]:
            self.renderer.RemoveActor(actor)
        for i, group in enumerate(groups):
            if i < len(actors):
                group.actor = actors[i]
                group.poly = actors[i].GetMapper().GetInput()
                group.poly.Initialize()  # the last version's cells go (rebuilt when drawn)
            else:
                import pyvista as pv

                group.poly = pv.PolyData()
                mapper = vtkPolyDataMapper()
                mapper.SetInputData(group.poly)
                mapper.SetScalarModeToUseCellFieldData()
                mapper.SelectColorArray("rgb")
                mapper.SetColorModeToDirectScalars()
                mapper.ScalarVisibilityOn()
                group.actor = vtkActor()
                group.actor.SetMapper(mapper)
                prop = group.actor.GetProperty()
                prop.SetInterpolationToFlat()
                prop.SetAmbient(0.0)
                prop.SetDiffuse(1.0)
                prop.SetSpecular(0.0)
                group.actor.PickableOff()
                self.renderer.AddActor(group.actor)
            group.actor.SetVisibility(False)
        self.groups = groups

    def colors_changed(self) -> None:
        """The full mesh's ``rgb`` changed: drawn groups take it before the next frame."""
        for g in self.groups:
            g.stale_colors = True

    def points_changed(self) -> None:
        """The full mesh's points changed (hidden cells, hidden fruit spheres)."""
        for g in self.groups:
            g.stale_geometry = True
        if self.mesh is not None:
            self.pick_mapper.SetInputData(self.mesh)
            self.pick_mapper.Modified()

    def set_moving(self, moving: bool) -> None:
        """The camera is being dragged (True) or has stopped (False); the caller repaints."""
        self.moving = bool(moving)

    def drawn(self) -> list[int]:
        """Indices of the groups drawn in the last frame."""
        return [i for i, g in enumerate(self.groups) if g.actor.GetVisibility()]

    # -- per frame -------------------------------------------------------------------
    def visible_groups(self) -> list[int]:
        """The groups to draw from the renderer's camera now."""
        if not self.groups:
            return []
        shown = [
            i
            for i, g in enumerate(self.groups)
            if not np.isfinite(g.radius) or 2.0 * g.radius * pixels_per_unit(self.renderer, g.corners) >= MIN_PIXELS
        ]
        if self.moving and self.large:
            shown = self._within_budget(shown)
        return shown

    def _within_budget(self, shown: list[int]) -> list[int]:
        kept: list[int] = []
        cells = 0
        for i in sorted(shown, key=lambda i: -self.groups[i].radius if np.isfinite(self.groups[i].radius) else 0):
            cells += self.groups[i].count
            if cells > MOTION_CELLS and kept:
                break
            kept.append(i)
        return sorted(kept)

    def _before_frame(self, *_args) -> None:
        shown = set(self.visible_groups())
        for i, g in enumerate(self.groups):
            on = i in shown
            if on:
                self._refresh(g)
            if bool(g.actor.GetVisibility()) != on:
                g.actor.SetVisibility(on)

    def _refresh(self, g: _Group) -> None:
        mesh = self.mesh
        if mesh is None or not (g.stale_geometry or g.stale_colors):
            return
        if g.stale_geometry:
            self._build(g)
        rgb = np.asarray(mesh.cell_data["rgb"])
        if g.count == mesh.n_cells:
            colors = rgb
        elif g.segments is None:  # organs and polygons: every cell after the tubes
            colors = rgb[mesh.n_cells - g.count :]
        else:
            tubes = rgb[: self.segment_count * self.sides].reshape(-1, self.sides * 3)
            colors = tubes.take(g.segments, axis=0).reshape(-1, 3)  # whole rows: 4x faster than [segments]
        g.poly.cell_data["rgb"] = colors
        g.poly.Modified()
        g.stale_geometry = g.stale_colors = False

    def _build(self, g: _Group) -> None:
        """``g``'s points and cells gathered from the full mesh."""
        from ramure.lsys.interpretation.geometry import cell_array, tube_quads
        import pyvista as pv

        mesh = self.mesh
        assert mesh is not None
        poly = g.poly
        if g.count == mesh.n_cells:  # one group: the mesh as it is
            poly.ShallowCopy(mesh)
            return
        points = np.asarray(mesh.points)
        k = 2 * self.sides
        if g.segments is not None:
            count = len(g.segments)
            pts = points[: self.segment_count * k].reshape(-1, k * 3).take(g.segments, axis=0).reshape(-1, 3)
            conn = tube_quads(count, self.sides).ravel()
            offsets = np.arange(0, len(conn) + 1, 4, dtype=conn.dtype)
        else:
            quads = mesh.n_cells - g.count
            polys = mesh.GetPolys()
            from vtkmodules.util.numpy_support import vtk_to_numpy

            all_offsets = vtk_to_numpy(polys.GetOffsetsArray())
            all_conn = vtk_to_numpy(polys.GetConnectivityArray())
            first = int(all_offsets[quads])
            conn = all_conn[first:] - 2 * quads
            offsets = all_offsets[quads:] - first
            pts = points[2 * quads :]
        conn = np.ascontiguousarray(conn)
        offsets = np.ascontiguousarray(offsets, dtype=conn.dtype)  # the full mesh's ids: int32 (see geometry.id_dtype)
        g.keep = [conn, offsets]
        poly.SetPoints(pv.vtk_points(np.ascontiguousarray(pts), deep=False))
        poly.SetPolys(cell_array(offsets, conn))


def _levels(radius: np.ndarray, top: float) -> np.ndarray:
    """Each segment's radius class: floor(log2(top / r)), at most MAX_CLASSES - 1 (int8)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ratio = top / radius if top > 0 else np.ones(len(radius))
    # floor(log2(top / r)) from the float's exponent; r = 0 (inf) and nan go to the last class
    level = np.where(np.isfinite(ratio), np.frexp(ratio)[1] - 1, MAX_CLASSES - 1)
    return np.clip(level, 0, MAX_CLASSES - 1).astype(np.int8)


def _class_boxes(sk: Skeleton | _Ends, level: np.ndarray, classes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(MAX_CLASSES, 3) lowest and highest segment end per class (inf / -inf for an empty one),
    computed for ``classes`` only (the other rows are inf / -inf)."""
    lo, hi = np.full((MAX_CLASSES, 3), np.inf), np.full((MAX_CLASSES, 3), -np.inf)
    if not len(classes) or not len(level):
        return lo, hi
    if len(classes) < MAX_CLASSES:
        members = np.flatnonzero(np.isin(level, classes))
        level = level[members]
    else:
        members = np.arange(len(level))
    by_level = np.argsort(level, kind="stable")
    order, sorted_level = members[by_level], level[by_level]
    starts = np.searchsorted(sorted_level, np.arange(MAX_CLASSES + 1))
    present = np.flatnonzero(np.diff(starts))
    start = np.take(np.asarray(sk.start, float), order, axis=0)
    end = np.take(np.asarray(sk.end, float), order, axis=0)
    lo[present] = np.minimum.reduceat(np.minimum(start, end), starts[present])
    hi[present] = np.maximum.reduceat(np.maximum(start, end), starts[present])
    return lo, hi


def _classes_after_edit(last: dict, sk: Skeleton, radius: np.ndarray, top: float, reuse: tuple) -> tuple:
    """Levels and class boxes of ``sk``, patched from ``last`` (the skeleton it was edited from,
    with the same thickest radius): reused segments keep their class; a class box grows by the
    new segments and is computed again only if a removed segment touched it."""
    new, old = reuse
    before = last["skeleton"]
    level = np.empty(len(radius), np.int8)
    level[new] = last["level"][old]
    added = _others(new, len(radius))
    level[added] = _levels(radius[added], top)
    gone = _others(old, len(before))
    lo, hi = last["lo"].copy(), last["hi"].copy()
    g_lo, g_hi = _class_boxes(_Ends(before, gone), last["level"][gone], np.arange(MAX_CLASSES))
    touched = ((g_lo <= lo) | (g_hi >= hi)).any(axis=1)  # a removed end on the box: recompute it
    a_lo, a_hi = _class_boxes(_Ends(sk, added), level[added], np.arange(MAX_CLASSES))
    lo, hi = np.minimum(lo, a_lo), np.maximum(hi, a_hi)
    redo = np.flatnonzero(touched)
    if redo.size:
        r_lo, r_hi = _class_boxes(sk, level, redo)
        lo[redo], hi[redo] = r_lo[redo], r_hi[redo]
    return level, lo, hi


class _Ends:
    """The ``start`` and ``end`` rows ``rows`` of a skeleton (what :func:`_class_boxes` reads)."""

    def __init__(self, sk: Skeleton, rows: np.ndarray) -> None:
        self.start, self.end = np.asarray(sk.start)[rows], np.asarray(sk.end)[rows]


def _others(rows: np.ndarray, count: int) -> np.ndarray:
    """The indices below ``count`` that are not in ``rows``."""
    keep = np.ones(count, bool)
    keep[rows] = False
    return np.flatnonzero(keep)


def _as_bounds(lo: np.ndarray, hi: np.ndarray) -> tuple[float, ...]:
    """VTK's bounds order (xmin, xmax, ymin, ymax, zmin, zmax) as Python floats."""
    return tuple(float(v) for v in np.c_[lo, hi].ravel())


def _bounds(points: np.ndarray) -> list[float]:
    if not len(points):
        return [0.0] * 6
    lo, hi = points.min(0), points.max(0)
    return [lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]]
