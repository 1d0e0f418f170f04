"""How the 3D view looks: light, background, camera presets, the ground grid, hairline twigs.

Choices the issue leaves open, stated here:

* **Light**: VTK's light kit (a key, a fill, two back lights and a head
  light, the classic three-point setup) shows the tubes' roundness; no
  image-based lighting (it needs an HDR file and a GPU).
* **Background**: a vertical gradient from a light neutral grey at the bottom
  to a soft blue-grey at the top, so bark, leaves, the red selection and the
  orange fruit all stand out, and screenshots read well on paper.
* **Anti-aliasing**: FXAA (a cheap screen-space pass that works on software
  OpenGL, where multisampling is often refused), its edge-end search cut to
  :data:`FXAA_ENDPOINT_STEPS` steps.
* **Thin branches**: every segment is also drawn as a 1.5-pixel line of its
  own colour under the tubes; a twig thinner than a pixel still shows as a
  line instead of vanishing.  Selected segments get a 3-pixel red line on
  top, so a selected hairline twig is plainly visible.  The lines are drawn
  in chunks of :data:`CHUNK_LINES`, each once the last is drawn (see
  :class:`LineChunks`: software OpenGL's memory for a frame).
* **Camera**: presets front, side, top and iso, all with Z up; the view
  orbits like a turntable (VTK's terrain style: azimuth about Z and
  elevation, never any roll).  Framing fits the plant's 8 box corners into
  90 % of the view, whatever its shape (tall plants are not cropped).
* **Draft frames** (see :mod:`ramure.app.desktop.view.plant_view`) leave out the hairlines shorter
  than :data:`DRAFT_MIN_LINE_PIXELS` on screen (chosen again when the camera moves, so
  zooming in brings them back).  Software OpenGL pays about 0.15 microseconds per line
  however short: Honda n = 17 framed whole leaves out about half of its 131k lines, about
  10 ms of a 41 ms draft frame, and 0.1 % of the pixels change (a twig's last pixel, which
  its parent's line mostly covers).  The polished frame draws them all.
* **Ground**: a grid on the plane under the plant, its spacing a round
  number (1, 2 or 5 times a power of ten) about a tenth of the plant's size,
  labelled in a corner ("grid: 0.5 units"; the grammar's units are not
  metres unless the grammar says so); its lines are opaque, in the colour a
  60 % grey line has over the lower background (see :func:`grid_color`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike
import pyvista as pv

from ramure.app.render import projection_matrix  # shared with the notebook's view

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton

BACKGROUND_BOTTOM = "#eef0f2"
BACKGROUND_TOP = "#b9c6d3"
GRID_RGB = (0.55, 0.58, 0.62)
GRID_OPACITY = 0.6
SELECTION_RGB = (255, 0, 0)
FXAA_ENDPOINT_STEPS = 4  # FXAA's edge-end search (VTK's default: 12)
LINE_WIDTH = 1.5  # pixels: the least a branch is drawn with
DRAFT_LINE_WIDTH = 1.0  # pixels: the hairlines of a draft frame (VTK's native lines, no geometry shader)
SELECTED_LINE_WIDTH = 3.0
#: A draft frame leaves out the hairlines shorter than this many pixels wherever they are (see
#: :class:`Hairlines`).
DRAFT_MIN_LINE_PIXELS = 1.5
#: ... unless that leaves out fewer than this share of them (then the draft draws them all).
DRAFT_MIN_LEFT_OUT = 0.1
VIEWS = {"front": (0.0, -1.0, 0.12), "side": (1.0, 0.0, 0.12), "top": (0.0, -1e-3, 1.0), "iso": (0.7, -0.7, 0.45)}


def apply_look(plotter: pv.BasePlotter) -> None:
    """Light kit, gradient background, FXAA and turntable orbiting on ``plotter``."""
    plotter.set_background(BACKGROUND_BOTTOM, top=BACKGROUND_TOP)  # type: ignore[arg-type]  # pyvista stubs
    plotter.enable_lightkit()
    try:
        plotter.enable_anti_aliasing("fxaa")
        # 4 endpoint steps instead of 12: 15-30 ms less per llvmpipe frame at 1000x800 and
        # no visible change (0.6 % of pixels move by more than 8/255)
        plotter.renderer.GetFXAAOptions().SetEndpointSearchIterations(FXAA_ENDPOINT_STEPS)
    except Exception:  # noqa: BLE001 - an OpenGL without the pass: plain lines, still correct
        pass
    plotter.enable_terrain_style(mouse_wheel_zooms=True, shift_pans=True)  # type: ignore[call-arg]  # pyvista stubs


def nice_step(size: float) -> float:
    """A round grid spacing (1, 2 or 5 x 10^k) close to ``size / 10``.

    >>> nice_step(10.0), nice_step(3.7), nice_step(0.8)
    (1.0, 0.5, 0.1)
    """
    target = max(float(size), 1e-9) / 10.0
    power = 10.0 ** math.floor(math.log10(target))
    for m in (1.0, 2.0, 5.0, 10.0):
        if target <= m * power * 1.5:
            return m * power
    return 10.0 * power


def fit_camera(
    plotter: pv.BasePlotter,
    bounds: Sequence[float],
    view: str = "front",
    margin: float = 0.9,
    clip_bounds: Sequence[float] | None = None,
) -> None:
    """Look at ``bounds`` from preset ``view`` (Z up) so the whole box fills ``margin`` of the view.

    ``clip_bounds``: the shown props' bounds, when the caller knows them (what VTK's
    ``ComputeVisiblePropBounds`` gives); the clipping range is then set from them without
    VTK's pass over every shown prop.
    """
    b = np.asarray(bounds, float).reshape(3, 2)
    center = b.mean(axis=1)
    size = float(np.max(b[:, 1] - b[:, 0])) or 1.0
    d = np.asarray(VIEWS[view], float)
    d /= np.linalg.norm(d)
    up = (0.0, 1.0, 0.0) if view == "top" else (0.0, 0.0, 1.0)
    renderer = plotter.renderer
    camera = renderer.GetActiveCamera()
    # VTK's own calls, what pyvista's camera_position setter does without its three clipping
    # range resets (each a bounds pass over the shown props: ~3 ms per new plant version)
    camera.SetPosition(*(center + d * size * 3.0))
    camera.SetFocalPoint(*center)
    camera.SetViewUp(*up)
    renderer.camera_set = True
    # the renderer's own reset: Plotter.reset_camera always paints a frame (0.1-0.7 s at 131k
    # segments); no clipping range yet, it is set once below
    renderer.ResetCamera(*b.ravel())
    corners = np.array(np.meshgrid(*b, indexing="ij")).reshape(3, -1).T
    for _ in range(3):  # perspective: the fit converges in a step or two
        m = camera.GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1, 1)
        matrix = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
        clip = np.c_[corners, np.ones(len(corners))] @ matrix.T
        extent = float(np.max(np.abs(clip[:, :2] / clip[:, 3:4])))
        if not np.isfinite(extent) or extent <= 0:
            break
        camera.Zoom(margin / extent)
    if clip_bounds is None:
        renderer.ResetCameraClippingRange()
    else:
        renderer.ResetCameraClippingRange(*clip_bounds)


def outside_view(plotter: pv.BasePlotter, bounds: Sequence[float], slack: float = 1.02) -> bool:
    """True if a corner of ``bounds`` projects outside the view (the plant grew out of sight)."""
    b = np.asarray(bounds, float).reshape(3, 2)
    corners = np.array(np.meshgrid(*b, indexing="ij")).reshape(3, -1).T
    clip = np.c_[corners, np.ones(len(corners))] @ projection_matrix(plotter.renderer).T
    if (clip[:, 3] <= 0).any():
        return True
    return bool(np.max(np.abs(clip[:, :2] / clip[:, 3:4])) > slack)


def segment_colors(mesh: pv.DataSet, colors: ArrayLike, count: int, sides: int = 0) -> np.ndarray:
    """Per-segment RGB from per-cell ``colors``: each segment takes its first tube cell's colour.

    ``sides``: the mesh is known to be laid out as ``count`` tubes of ``sides`` quads first
    (:func:`ramure.app.desktop.view.plant_actors.tube_layout`), so the layout is not checked again.
    """
    colors = np.asarray(colors)
    if sides:
        out = np.empty((count, 3), np.uint8)
        for c in range(3):  # a column at a time: 10x faster than gathering 3-byte rows
            out[:, c] = colors[0 : count * sides : sides, c]
        return out
    seg = np.asarray(mesh.cell_data["segment"])
    quads = int(np.count_nonzero(seg >= 0))
    sides = quads // count if count else 0
    ids = np.arange(count)
    if (
        sides
        and sides * count == quads
        and np.array_equal(seg[0:quads:sides], ids)
        and np.array_equal(seg[sides - 1 : quads : sides], ids)
    ):
        return np.ascontiguousarray(colors[0:quads:sides], np.uint8)  # tubes first, segment by segment
    on = np.flatnonzero(seg >= 0)
    out = np.zeros((count, 3), np.uint8)
    out[seg[on][::-1]] = np.asarray(colors)[on][::-1]  # reversed: the first cell wins
    return out


_COUNT = np.zeros(0, np.int32)  # 0, 1, 2, ... (read-only), kept for every line set
_EVENS = np.zeros(0, np.int32)  # 0, 2, 4, ... (read-only): line sets' offsets, a prefix of it

#: A frame draws a line set in chunks of at most this many lines, one actor each (see :class:`LineChunks`).
CHUNK_LINES = 32_768


def _counting(n: int) -> None:
    global _COUNT, _EVENS
    if len(_COUNT) < 2 * n + 1:
        _COUNT = np.arange(max(4 * n + 2, 1024), dtype=np.int32)
        _EVENS = _COUNT[: len(_COUNT) // 2] * 2
        _COUNT.flags.writeable = _EVENS.flags.writeable = False


@dataclass
class LineBuffers:
    """Memory the cells and colours of a line set of up to ``capacity`` lines are written into
    (:func:`skeleton_lines`): a new plant version's hairlines go into the buffers of the version
    dropped, so they are written into memory already touched (fresh pages cost this machine
    several ms).  The points are the skeleton's own (:meth:`ramure.lsys.interpretation.turtle.Skeleton.ends`)."""

    conn: np.ndarray  # (2 capacity,) int32
    colors: np.ndarray  # (2 capacity, 4) uint8: RGBA, alpha 255 (see point_colors)

    @classmethod
    def make(cls, n: int) -> LineBuffers:
        """Buffers for ``n`` lines and 10 % more."""
        cap = n + n // 10 + 16
        colors = np.empty((2 * cap, 4), np.uint8)
        colors[:, 3] = 255  # written once: point_colors writes the RGB only
        return cls(np.empty(2 * cap, np.int32), colors)

    @property
    def capacity(self) -> int:
        """How many lines the buffers hold."""
        return len(self.conn) // 2


def segment_lines(start: ArrayLike, end: ArrayLike) -> pv.PolyData:
    """Line cells from ``start[i]`` to ``end[i]`` (points: the starts, then the ends, copied)."""
    start, end = np.asarray(start, float).reshape(-1, 3), np.asarray(end, float).reshape(-1, 3)
    return point_lines(np.concatenate([start, end]))


def skeleton_lines(skeleton: Skeleton, buffers: LineBuffers | None = None) -> pv.PolyData:
    """Every segment of ``skeleton`` as a line (:func:`point_lines`): its points are the
    skeleton's :meth:`~ramure.lsys.interpretation.turtle.Skeleton.ends`, read by VTK in place."""
    return point_lines(skeleton.ends(), buffers)


def point_lines(points: np.ndarray, buffers: LineBuffers | None = None) -> pv.PolyData:
    """Lines from ``points[i]`` to ``points[n + i]`` (``points`` (2n, 3) float64, read by VTK
    in place: the caller keeps it alive); the cell arrays are handed to VTK as they are (no
    legacy-format import: 6 ms at 131k segments), written into ``buffers`` if given (large
    enough)."""
    n = len(points) // 2
    conn = (np.empty(2 * n, np.int32) if buffers is None else buffers.conn[: 2 * n]).reshape(n, 2)
    _counting(n)
    conn[:, 0] = _COUNT[:n]
    conn[:, 1] = _COUNT[n : 2 * n]
    lines = pv.PolyData()  # points without vertex cells
    lines.SetPoints(pv.vtk_points(points, deep=False))
    lines.SetLines(line_cells(conn))
    return lines


def line_cells(conn: np.ndarray) -> Any:
    """A ``vtkCellArray`` of lines between the point ids ``conn`` ((n, 2) int32, C order), read
    by VTK in place (the caller keeps ``conn`` alive)."""
    from ramure.lsys.interpretation.geometry import cell_array

    _counting(len(conn))
    return cell_array(_EVENS[: len(conn) + 1], conn.ravel())


def point_colors(rgb: np.ndarray, buffers: LineBuffers | None = None) -> np.ndarray:
    """The per-point RGBA of :func:`point_lines`' lines coloured ``rgb`` (both ends, alpha
    255), written into ``buffers`` if given.  Four bytes a point: VTK draws direct RGBA
    scalars as they are, where three-byte colours are copied to RGBA by every mapper that
    draws them (each chunk of :class:`LineChunks`)."""
    n = len(rgb)
    if buffers is None:
        both = np.empty((2 * n, 4), np.uint8)
        both[:, 3] = 255
    else:
        both = buffers.colors[: 2 * n]  # alpha 255 from LineBuffers.make
    both[:n, :3] = rgb
    both[n:, :3] = rgb
    return both


def _chunks(lines: int) -> int:
    """How many chunks of at most :data:`CHUNK_LINES` ``lines`` lines take (at least one)."""
    return max(1, -(-lines // CHUNK_LINES))


class LineChunks:
    """The actors that draw one line set, a consecutive chunk of its lines each, in order.

    Software OpenGL (llvmpipe) bins a whole frame before it rasterises it: 131k hairlines in
    one draw held about 29 MB of binned scene at each frame, most of the desktop's own share
    of its peak memory.  Here the lines are drawn :data:`CHUNK_LINES` at a time, and before
    each chunk after the first the frame waits for what was given so far to be drawn (the
    render window's ``WaitForCompletion``, a ``glFinish``, from the chunk mapper's
    ``UpdateShaderEvent``, which VTK fires just before the draw): the scene then holds one
    chunk at a time.  On Honda n = 17 (4 chunks) the desktop's peak is 20 MB lower (616 to
    596 MB); a polished frame takes about 5 ms more (75 to 80 ms, medians), a draft, whose
    shorter line list fills fewer chunks, about 2 ms more (40 to 42 ms).  The pixels are the
    same: the same lines in the same order, in one renderer (one clipping range, one FXAA
    pass).  The chunks share the line set's points and colour arrays (uploaded once: VTK
    keeps one buffer per array) and have cells of their own.  On a GPU the waits cost little
    (4 chunks: three waits a frame) and the binned scene does not exist; they are kept
    there too, one code path.
    """

    def __init__(self, renderer: Any, width: float) -> None:
        self.renderer = renderer
        self.width = float(width)
        self.actors: list[Any] = []
        self.visible = True
        self._drawn: tuple = ()  # (source, conn) the chunks were made from
        self._keep: list[np.ndarray] = []  # the chunks' cells, read by VTK in place

    def draw(self, source: pv.PolyData, conn: np.ndarray) -> None:
        """Draw the lines ``conn`` ((m, 2) int32 point ids of ``source``'s points, whose point
        data ``rgb`` colours them; every line of ``source`` or a subset) from the next frame
        on; nothing is done for the same pair.  There are as many actors as ``source``'s lines
        need chunks; a subset (a draft's) takes the first chunks it needs, the other actors
        draw nothing (and wait for nothing)."""
        if len(self._drawn) == 2 and self._drawn[0] is source and self._drawn[1] is conn:
            return
        self._drawn = (source, conn)
        count = _chunks(int(source.GetNumberOfLines()))
        while len(self.actors) < count:
            self._add_actor()
        for actor in self.actors[count:]:
            self.renderer.RemoveActor(actor)
        del self.actors[count:]
        used = _chunks(len(conn))
        bounds = np.r_[np.linspace(0, len(conn), used + 1).astype(int), np.full(count - used, len(conn))]
        self._keep = [np.ascontiguousarray(conn[a:b]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        points, colors = source.GetPoints(), source.GetPointData().GetArray("rgb")
        for actor, cells in zip(self.actors, self._keep, strict=True):
            chunk = pv.PolyData()
            chunk.SetPoints(points)
            chunk.GetPointData().SetScalars(colors)
            chunk.SetLines(line_cells(cells))
            actor.GetMapper().SetInputData(chunk)

    def _add_actor(self) -> None:
        from vtkmodules.vtkCommonCore import vtkCommand
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        mapper = vtkPolyDataMapper()
        mapper.SetColorModeToDirectScalars()
        mapper.SetScalarModeToUsePointData()
        mapper.ScalarVisibilityOn()
        if self.actors:  # what the chunks before it gave is drawn first
            mapper.AddObserver(vtkCommand.UpdateShaderEvent, self._wait)
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.LightingOff()
        prop.SetLineWidth(self.width)
        actor.PickableOff()
        actor.SetVisibility(self.visible)
        self.renderer.AddActor(actor)
        self.actors.append(actor)

    def _wait(self, *_args: Any) -> None:
        window = self.renderer.GetRenderWindow()
        if window is not None:
            window.WaitForCompletion()

    def colors_changed(self) -> None:
        """The source's colours were written in place: the next frame uploads them again.  VTK
        keeps one buffer per array and uploads it again only when the array itself is marked
        modified (four-byte colours are drawn as they are, without a mapped copy to refresh)."""
        if self._drawn:
            self._drawn[0].GetPointData().GetArray("rgb").Modified()

    def inputs(self) -> list[pv.PolyData]:
        """The chunks' line sets, in drawing order."""
        return [actor.GetMapper().GetInput() for actor in self.actors]

    def release(self) -> None:
        """Let go of the lines drawn (their points and cells); the actors stay, drawing nothing,
        for the next :meth:`draw`."""
        for actor in self.actors:
            actor.GetMapper().SetInputData(pv.PolyData())
        self._drawn = ()
        self._keep = []

    def remove(self) -> None:
        """Take the actors out of the renderer (the line set is dropped)."""
        for actor in self.actors:
            self.renderer.RemoveActor(actor)
        self.actors = []
        self._drawn = ()

    def set_visible(self, on: bool) -> None:
        """Show or hide every chunk."""
        self.visible = bool(on)
        for actor in self.actors:
            actor.SetVisibility(self.visible)

    def set_width(self, width: float) -> None:
        """The lines' width in pixels."""
        self.width = float(width)
        for actor in self.actors:
            actor.GetProperty().SetLineWidth(self.width)


@dataclass(eq=False)
class LineSet:
    """One plant version's hairlines: every segment's line, the memory they are written in, the
    actors that draw them, and the subset a draft frame draws."""

    lines: pv.PolyData  # every line: points (the starts, then the ends), point data ``rgb``, cells
    conn: np.ndarray  # (n, 2) the lines' point ids (the cells of ``lines``)
    buffers: LineBuffers
    chunks: LineChunks
    draft: DraftLines = field(default_factory=lambda: DraftLines())
    skeleton: Any = None
    sides: int = 0
    key: Any = None

    def release(self) -> None:
        """Keep only the memory and the actors (a spare's): the version's points (its
        skeleton's, read in place), skeleton and draft subset are let go."""
        self.chunks.release()
        self.lines = pv.PolyData()
        self.conn = self.buffers.conn[:0].reshape(0, 2)
        self.draft = DraftLines()
        self.skeleton = None
        self.key = None


class Hairlines:
    """Every segment as a thin line under the tubes, and the selected ones as thick red lines.

    The lines of the plant shown before the last new one are kept (their actors hidden) with
    the key they were shown with; showing that key again (an undo) shows them again without
    building or uploading anything (only their colours are refreshed if they changed).  A new
    version's lines are written into the memory and actors of the version dropped.
    """

    def __init__(self, plotter: pv.BasePlotter) -> None:
        self.plotter = plotter
        self.shown: LineSet | None = None
        self.kept: LineSet | None = None  # the plant shown before
        self.selected: pv.PolyData | None = None
        self.selected_actor: pv.Actor | None = None
        self._spare: LineSet | None = None  # a line set no longer shown, its memory and actors free
        self.width = LINE_WIDTH
        self.drafting = False  # True: frames leave out the shortest lines (see the module's notes)
        plotter.renderer.AddObserver("StartEvent", self._before_frame)

    @property
    def lines(self) -> pv.PolyData | None:
        """The shown version's line set (every line), or None."""
        return None if self.shown is None else self.shown.lines

    @property
    def skeleton(self) -> Skeleton | None:
        """The skeleton drawn, None before the first."""
        return None if self.shown is None else self.shown.skeleton

    @property
    def actors(self) -> list[Any]:
        """The actors drawing the shown version's lines ([] when none is shown)."""
        return [] if self.shown is None else self.shown.chunks.actors

    def visible(self) -> bool:
        """True when hairlines are drawn and shown."""
        return self.shown is not None and self.shown.chunks.visible

    def set_draft(self, draft: bool) -> None:
        """Draw the next frames in the draft look (True: 1-pixel lines, the shortest left out)."""
        self.drafting = bool(draft)
        self.set_width(DRAFT_LINE_WIDTH if draft else LINE_WIDTH)

    def set_width(self, width: float) -> None:
        """Draw the hairlines ``width`` pixels wide (:data:`DRAFT_LINE_WIDTH` in a draft frame)."""
        self.width = float(width)
        for line_set in (self.shown, self.kept):
            if line_set is not None:
                line_set.chunks.set_width(self.width)

    def show(self, skeleton: Skeleton | None, mesh: pv.DataSet, colors: ArrayLike, key: Any = None, sides: int = 0) -> None:
        """Lines for a new plant (``colors``: the tubes' per-cell RGB); ``key`` names the version
        (see the class notes); ``sides``: see :func:`segment_colors` (0: the layout is checked)."""
        if skeleton is not None and len(skeleton) and key is not None and self.kept is not None and self.kept.key is key:
            self._swap(mesh, colors)
            return
        self._keep(key)
        if skeleton is None or len(skeleton) == 0:
            if self.selected_actor is not None:
                self.selected_actor.SetVisibility(False)
            return
        spare, self._spare = self._spare, None
        n = len(skeleton)
        buffers = spare.buffers if spare is not None and spare.buffers.capacity >= n else LineBuffers.make(n)
        lines = skeleton_lines(skeleton, buffers)
        lines.point_data["rgb"] = point_colors(segment_colors(mesh, colors, n, sides), buffers)  # see line_colors
        chunks = spare.chunks if spare is not None else LineChunks(self.plotter.renderer, self.width)
        chunks.set_width(self.width)
        chunks.set_visible(True)
        self.shown = LineSet(lines, buffers.conn[: 2 * n].reshape(n, 2), buffers, chunks, skeleton=skeleton, sides=sides, key=key)
        chunks.draw(lines, self.shown.conn)  # every line (the actors exist, VTK knows the bounds)

    def _keep(self, key: Any) -> None:
        """Before version ``key`` is shown: keep the shown version for an undo (the one kept
        before is freed), unless it is the same key or unnamed (then it is freed itself)."""
        shown, self.shown = self.shown, None
        if shown is None:
            return
        if shown.key is None or shown.key is key:
            self._free(shown)
            return
        self._free(self.kept)
        self.kept = shown
        shown.chunks.set_visible(False)

    def forget_kept(self) -> None:
        """Drop the kept version (see :meth:`ramure.app.desktop.view.plant_view.PlantView.forget_kept`):
        its memory and actors become the spare."""
        kept, self.kept = self.kept, None
        self._free(kept)

    def _free(self, line_set: LineSet | None) -> None:
        """``line_set`` is neither shown nor kept any more: hidden, it is the spare whose memory
        and actors the next version takes (the spare before is dropped); what it drew is let go."""
        if line_set is None or line_set is self._spare:
            return
        line_set.chunks.set_visible(False)
        if self._spare is not None:
            self._spare.chunks.remove()
        line_set.release()
        self._spare = line_set

    def _swap(self, mesh: pv.DataSet, colors: ArrayLike) -> None:
        """Show the kept lines again, and keep the shown ones."""
        assert self.kept is not None
        back, shown = self.kept, self.shown
        self.kept = None
        if shown is not None and shown.key is not None:
            self.kept = shown
            shown.chunks.set_visible(False)
        else:
            self._free(shown)
        self.shown = back
        self._recolor(mesh, colors)
        back.chunks.set_width(self.width)
        back.chunks.set_visible(True)

    def set_colors(self, mesh: pv.DataSet, colors: ArrayLike) -> None:
        """Recolour the hairlines as the mesh's cells are coloured."""
        if self.shown is not None and self.shown.skeleton is not None:
            self._recolor(mesh, colors)

    def line_colors(self) -> np.ndarray:
        """Each shown hairline's RGB.  The colours are stored per point (each line has its own
        two points, both of its colour): VTK then reads no per-cell colour texture for every
        fragment, 4 ms less per draft frame at 131k lines, the same pixels."""
        assert self.shown is not None
        return np.asarray(self.shown.lines.point_data["rgb"])[: len(self.shown.skeleton), :3]

    def _recolor(self, mesh: pv.DataSet, colors: ArrayLike) -> None:
        shown = self.shown
        assert shown is not None and shown.skeleton is not None
        rgb = segment_colors(mesh, colors, len(shown.skeleton), shown.sides)
        if not np.array_equal(rgb, self.line_colors()):  # else no upload again
            both = np.asarray(shown.lines.point_data["rgb"])
            both[: len(rgb), :3] = rgb
            both[len(rgb) :, :3] = rgb
            shown.chunks.colors_changed()

    def set_selection(self, segments: ArrayLike) -> None:
        """Thick red lines over the selected ``segments`` (indices), drawn above the tubes."""
        picked = np.asarray(segments, np.int64)
        if self.skeleton is None or not len(picked):
            if self.selected_actor is not None:
                self.selected_actor.SetVisibility(False)
            return
        sk = self.skeleton
        selected = segment_lines(np.asarray(sk.start)[picked], np.asarray(sk.end)[picked])
        if self.selected_actor is None or self.selected is None:
            self.selected = selected
            self.selected_actor = self.plotter.add_mesh(
                selected,
                color=np.array(SELECTION_RGB) / 255,
                name="selected_lines",
                reset_camera=False,
                render=False,
                pickable=False,
                lighting=False,
                line_width=SELECTED_LINE_WIDTH,
            )
            mapper = self.selected_actor.GetMapper()
            # drawn a little towards the camera, so the red wins over the tube it runs inside
            mapper.SetResolveCoincidentTopologyToPolygonOffset()
            mapper.SetRelativeCoincidentTopologyLineOffsetParameters(0, -66000)
        else:
            self.selected.copy_from(selected, deep=False)
        self.selected_actor.SetVisibility(True)

    # -- draft frames ----------------------------------------------------------------
    def _before_frame(self, *_args: Any) -> None:
        """Before each frame: the shown chunks draw every line, or a draft's subset."""
        shown = self.shown
        if shown is None or shown.skeleton is None or not shown.chunks.visible:
            return
        shown.chunks.draw(shown.lines, self.draft_conn() if self.drafting else shown.conn)

    def draft_conn(self) -> np.ndarray:
        """The lines a draft frame draws now ((m, 2) point ids): those at least
        :data:`DRAFT_MIN_LINE_PIXELS` long on screen (all of them when that leaves out fewer
        than :data:`DRAFT_MIN_LEFT_OUT`).  Chosen again only when the camera or the window
        size changes, or the lines do."""
        shown = self.shown
        assert shown is not None and shown.skeleton is not None
        shown.draft.update(self.plotter.renderer, shown.lines, len(shown.skeleton))
        return shown.conn if shown.draft.conn is None else shown.draft.conn


@dataclass
class DraftLines:
    """The hairlines a draft frame draws: one line set's lines at least
    :data:`DRAFT_MIN_LINE_PIXELS` long from the camera they were chosen for."""

    view: tuple = ()  # the camera's projection (the rows that place points on screen) and viewport size
    conn: np.ndarray | None = None  # (m, 2) their point ids; None: every line
    lines: Any = None  # the line set they were chosen from

    def update(self, renderer: Any, lines: pv.PolyData, count: int) -> None:
        """Choose among the first ``count`` lines of ``lines`` (:func:`point_lines`) for
        ``renderer``'s camera, unless they were chosen for the same view and lines."""
        from ramure.app.desktop.view._lines_kernel import long_lines

        matrix = projection_matrix(renderer)
        width, height = renderer.GetSize()
        view = (*matrix[[0, 1, 3]].ravel().tolist(), width, height)  # the clipping range (row 2) does not move lines
        if view == self.view and lines is self.lines:
            return
        self.view, self.lines = view, lines
        points = np.asarray(lines.points)
        kept = long_lines(points, count, matrix, 0.5 * width, 0.5 * height, DRAFT_MIN_LINE_PIXELS)
        if count - len(kept) < DRAFT_MIN_LEFT_OUT * count:
            self.conn = None
            return
        conn = np.empty((len(kept), 2), np.int32)
        conn[:, 0] = kept
        conn[:, 1] = kept + count
        self.conn = conn


def grid_color() -> tuple[float, float, float]:
    """The grid's colour: :data:`GRID_RGB` at :data:`GRID_OPACITY` over the background's lower
    quarter, where the ground lies, drawn opaque (one translucent actor costs every frame an
    order-independent translucency pass: about 20 ms on llvmpipe)."""
    bottom, top = (np.array(pv.Color(c).float_rgb) for c in (BACKGROUND_BOTTOM, BACKGROUND_TOP))
    behind = 0.85 * bottom + 0.15 * top
    rgb = GRID_OPACITY * np.asarray(GRID_RGB) + (1 - GRID_OPACITY) * behind
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))


class Ground:
    """A grid under the plant with its spacing written in a corner."""

    def __init__(self, plotter: pv.BasePlotter) -> None:
        self.plotter = plotter
        self.grid: pv.PolyData | None = None
        self.actor: pv.Actor | None = None
        self.label: Any = None  # the corner text actor (a vtkCornerAnnotation)
        self.step: float | None = None
        self.layout: tuple | None = None  # (step, half width, centre x, centre y, z) of the drawn grid
        self.visible = True

    def show(self, bounds: Sequence[float]) -> None:
        """Lay the grid under ``bounds`` with a round step (:func:`nice_step`); the same grid as before is kept."""
        b = np.asarray(bounds, float).reshape(3, 2)
        size = float(np.max(b[:2, 1] - b[:2, 0]))
        size = max(size, float(b[2, 1] - b[2, 0]) * 0.6, 1e-6)
        step = nice_step(size)
        half = math.ceil(0.75 * size / step) * step
        cx = round(float(b[0].mean()) / step) * step
        cy = round(float(b[1].mean()) / step) * step
        z = float(b[2, 0])
        layout = (step, half, cx, cy, z)
        if layout == self.layout and self.actor is not None:  # the same grid (most edits): no new lines
            self.set_visible(self.visible)
            return
        self.layout = layout
        ticks = np.arange(-half, half + step / 2, step)
        xs = np.c_[cx + ticks, np.full(len(ticks), cy - half), cx + ticks, np.full(len(ticks), cy + half)]
        ys = np.c_[np.full(len(ticks), cx - half), cy + ticks, np.full(len(ticks), cx + half), cy + ticks]
        segs = np.concatenate([xs, ys])
        points = np.zeros((2 * len(segs), 3))
        points[0::2, :2], points[1::2, :2] = segs[:, :2], segs[:, 2:]
        points[:, 2] = z
        cells = np.c_[np.full(len(segs), 2), np.arange(0, 2 * len(segs), 2), np.arange(1, 2 * len(segs), 2)]
        grid = pv.PolyData(points, lines=cells.ravel())
        if self.actor is None or self.grid is None:
            self.grid = grid
            self.actor = self.plotter.add_mesh(
                grid,
                color=grid_color(),
                name="ground",
                reset_camera=False,
                render=False,
                pickable=False,
                lighting=False,
                line_width=1,
            )
        else:
            self.grid.copy_from(grid, deep=False)
        self.step = step
        text = f"grid: {step:g} unit{'s' if step != 1 else ''}"
        if self.label is None:
            self.label = self.plotter.add_text(
                text, position="lower_left", font_size=9, color="#3c4650", name="ground_label", render=False
            )
        elif self.label.GetText(0) != text:  # new text: a new texture drawn in the next frame
            self.label.SetText(0, text)
        self.set_visible(self.visible)

    def set_visible(self, on: bool) -> None:
        """Show or hide the grid and its label."""
        self.visible = bool(on)
        for actor in (self.actor, self.label):
            if actor is not None:
                actor.SetVisibility(self.visible)
