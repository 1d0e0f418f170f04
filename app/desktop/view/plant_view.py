"""The 3D view: the plant in a pyvista plotter widget, click and rubber-band picking.

The plotter is a :class:`~ramure.app.desktop.view.native_view.NativeInteractor` on X11: VTK
draws and swaps each frame straight into the widget's own X window, without the
QOpenGLWidget's copies and Qt's OpenGL composition of pyvistaqt's ``QtInteractor``
(about 10 ms of CPU less per frame on llvmpipe, 40 ms less for the polished frame, whose
1.5-pixel hairlines are then the driver's wide lines; see that module).  Elsewhere
(Wayland, Qt's offscreen platform, or ``RAMURE_GL_WIDGET=1``) it is the ``QtInteractor``.

Mouse:

* left drag rotates (VTK trackball), wheel zooms, middle drag pans;
* a click (press and release without moving) picks the branch or organ
  under the cursor: plain click replaces the selection, Ctrl+click toggles,
  Shift+click adds;
* a right-button drag (or a left drag in rectangle mode, key R) draws a
  rubber band: the branches whose midpoints fall inside are selected
  (Shift adds, Ctrl removes);
* Esc clears the selection.

The view only measures where the user clicked: it emits
:attr:`PlantView.cell_clicked` (a mesh cell id, found with a
:class:`vtkCellPicker`) or :attr:`PlantView.rectangle_selected` (display
coordinates), and the window asks the model which leaves those are.
Display coordinates follow VTK: pixels, origin at the bottom left.

Draft and polished frames (as ParaView and VTK draw interactive and still
renders): on software OpenGL a large plant's full frame costs about 140 ms of
CPU, most of it the 1.5-pixel hairlines (VTK draws wide lines with a geometry
shader) and FXAA over a picture full of edges.  So the frame right after an
edit (a new plant version, new colours, hidden cells) or during a camera drag
is a *draft*: the same plant, geometry and colours, with 1-pixel hairlines, no
FXAA, and no hairline shorter than 1.5 pixels on screen (see
:data:`~ramure.app.desktop.view.scene.DRAFT_MIN_LINE_PIXELS`; about 30 % of the cost).  When the user pauses for :data:`POLISH_MS`
(a single-shot timer that each further edit restarts) the full-quality frame
follows.  Plants under :data:`~ramure.app.desktop.view.plant_actors.LOD_SEGMENTS`
segments are always drawn polished (their frames are cheap).  Pictures taken
with :meth:`PlantView.grab_image` are always polished.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, QPoint, QRect, QSize, Qt, QTimer, Signal
from PySide6.QtWidgets import QRubberBand, QVBoxLayout, QWidget

from ramure.app.desktop.view.native_view import NativeInteractor, native_windows
from ramure.app.desktop.view.plant_actors import PlantActors
from ramure.app.desktop import state
from ramure.app.desktop.state import FRUIT_SELECTED, points_without_fruit, project_to_display
from ramure.app.render import FRUIT_RGB
from ramure.errors import RamureError
from ramure.app.desktop.view import scene

if TYPE_CHECKING:
    from PySide6.QtGui import QImage, QKeyEvent, QResizeEvent
    from pyvistaqt import QtInteractor
    from ramure.app.desktop.state import Snapshot

CLICK_SLOP = 4  # pixels a click may move and still be a click
#: Selections of more leaves than this get their OBB after the recoloured plant is painted.
BOX_LATER_LEAVES = 5_000
PICK_TOLERANCE = 0.002
#: Quiet time (ms) after an edit or a camera move before the full-quality frame is drawn.
POLISH_MS = 250
#: The same while the model computes (:meth:`PlantView.set_busy`): its next version is coming.
BUSY_POLISH_MS = 1000


def selection_mode(modifiers: Qt.KeyboardModifier, rectangle: bool = False) -> str:
    """The selection mode for Qt keyboard modifiers: replace, add, remove or toggle."""
    ctrl = bool(modifiers & Qt.KeyboardModifier.ControlModifier)
    shift = bool(modifiers & Qt.KeyboardModifier.ShiftModifier)
    if rectangle:
        return "remove" if ctrl else "add" if shift else "replace"
    return "toggle" if ctrl else "add" if shift else "replace"


class _MouseFilter(QObject):
    """Turns mouse events on the interactor into clicks and rubber bands."""

    def __init__(self, view) -> None:
        super().__init__(view)
        self.view = view
        self.press: tuple | None = None  # (QPoint, button, band?)

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt API)
        kind = event.type()
        view = getattr(self, "view", None)
        if view is None:  # events while Qt builds or tears the filter down
            return False
        if kind == QEvent.Type.Wheel:
            view.auto_framed = False  # the user zooms: keep their view
            view.draft(camera=True)  # the zoom's frame is a draft, polished when the wheel rests
        if kind == QEvent.Type.MouseButtonPress:
            pos = event.position().toPoint()
            button = event.button()
            band = button == Qt.MouseButton.RightButton or (button == Qt.MouseButton.LeftButton and view.rectangle_mode)
            self.press = (pos, button, band)
            if not band:
                view.set_moving(True)  # large plants: fewer tubes, draft look while the camera moves
            if band:
                view.band.setGeometry(QRect(pos, QSize()))
                view.band.show()
                return True
            return False
        if kind == QEvent.Type.MouseMove and self.press is not None and not self.press[2]:
            view.auto_framed = False  # the user turns or pans the view: keep it
            view.camera_dragged()
        if kind == QEvent.Type.MouseMove and self.press is not None and self.press[2]:
            view.band.setGeometry(QRect(self.press[0], event.position().toPoint()).normalized())
            return True
        if kind == QEvent.Type.MouseButtonRelease and self.press is not None:
            start, button, band = self.press
            self.press = None
            pos = event.position().toPoint()
            moved = (pos - start).manhattanLength() > CLICK_SLOP
            if band:
                view.band.hide()
                if moved:
                    view.rectangle_from_widget(start, pos, selection_mode(event.modifiers(), True))
                elif button == Qt.MouseButton.LeftButton:
                    view.click_from_widget(pos, selection_mode(event.modifiers()))
                return True
            view.set_moving(False)
            view.redraw()
            if button == Qt.MouseButton.LeftButton and not moved:
                view.click_from_widget(pos, selection_mode(event.modifiers()))
            return False
        if kind in (QEvent.Type.KeyPress, QEvent.Type.KeyRelease):
            # VTK/pyvista key bindings ('q' closes, 'w' wireframe...) are not wanted here.
            if kind == QEvent.Type.KeyPress:
                view.key_pressed(event)
            return True
        return False


def _collapse_cells(mesh, points, hidden):
    """``points`` (default: the mesh's) with each hidden cell's own points moved onto its first
    point: the cell has no area left. Points a shown cell also uses stay where they are."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    polys = mesh.GetPolys()
    conn = vtk_to_numpy(polys.GetConnectivityArray())
    offsets = vtk_to_numpy(polys.GetOffsetsArray())
    n_verts = mesh.GetNumberOfVerts() + mesh.GetNumberOfLines()  # polys come after verts and lines
    cell = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets)) + n_verts
    out = np.array(mesh.points if points is None else points, copy=True)
    gone = hidden[cell]
    shown_use = np.zeros(len(out), bool)
    shown_use[conn[~gone]] = True
    first = conn[offsets[:-1]]
    target = first[cell[gone] - n_verts]
    movable = ~shown_use[conn[gone]]
    out[conn[gone][movable]] = out[target[movable]]
    return out


#: A pick ray's candidate cells come within this many pick tolerances of it (any number
#: above 1 finds the same cells; the margin covers rounding).
NEAR_REACH = 2.0


def _near_bins(mesh: pv.PolyData | None) -> tuple[int, int, int] | None:
    """The bins (divisions along x, y, z) a ``vtkStaticCellLocator`` over the whole of ``mesh``
    takes, if a locator given them over some of its cells (and all its points) bins those
    cells alike: its box is then the same.  None when ``mesh`` has cells other than polygons,
    or a side too thin for VTK's box to be the mesh's bounds (:class:`_NearCells` is not used)."""
    from vtkmodules.vtkCommonDataModel import vtkBoundingBox, vtkStaticCellLocator

    if mesh is None or mesh.GetNumberOfVerts() or mesh.GetNumberOfLines() or mesh.GetNumberOfStrips():
        return None
    bounds = list(mesh.GetBounds())
    probe = vtkStaticCellLocator()
    bins = min(int(float(mesh.GetNumberOfCells()) / float(probe.GetNumberOfCellsPerNode())), probe.GetMaxNumberOfBuckets())
    automatic, divisions = [0.0] * 6, [0, 0, 0]
    vtkBoundingBox(bounds).ComputeDivisions(bins, automatic, divisions)  # what BuildLocator computes
    given = vtkBoundingBox(bounds)
    given.Inflate()  # what BuildLocator does with given divisions
    inflated = [0.0] * 6
    given.GetBounds(inflated)
    return (divisions[0], divisions[1], divisions[2]) if automatic == bounds == inflated else None


def _locator(data: Any, divisions: tuple[int, int, int] | None = None) -> Any:
    """A built ``vtkStaticCellLocator`` over ``data`` (with these bins, else VTK's choice)."""
    from vtkmodules.vtkCommonDataModel import vtkStaticCellLocator

    locator = vtkStaticCellLocator()
    if divisions is not None:
        locator.AutomaticOff()
        locator.SetDivisions(*divisions)
    locator.SetDataSet(data)
    locator.BuildLocator()
    return locator


class _NearCells:
    """The plant's cells near one pick ray, as a data set a ``vtkCellPicker`` picks from.

    A picker with a cell locator over the whole mesh keeps 48 bytes of cell bounds per cell
    and its bins (28 MB at 393k cells) from the first click on.  The cells whose boxes'
    spheres come within :data:`NEAR_REACH` pick tolerances of the ray
    (:func:`~ramure.app.desktop.state.cells_near_line`) hold every cell the picker can hit.
    Their locator is given the whole mesh's points and bins (:func:`_near_bins`), so it meets
    them in the same order along the ray and the picker answers the same cell as with the
    whole mesh's locator (where several cells lie within the tolerance too).  Their ids in the
    mesh are :attr:`cells`; the points are the mesh's own (no copy).
    """

    def __init__(self) -> None:
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        self.mapper = vtkPolyDataMapper()
        self.actor = vtkActor()  # never added to a renderer: picking only
        self.actor.SetMapper(self.mapper)
        self.cells = np.zeros(0, np.int64)
        self.locator: Any = None
        self.keep: tuple = ()  # the cell arrays VTK reads in place

    def gather(
        self, mesh: pv.PolyData, line: tuple[np.ndarray, np.ndarray, float], bins: tuple[int, int, int], tubes: tuple[int, int]
    ) -> Any:
        """Take ``mesh``'s cells near ``line`` (two world points and the pick tolerance in world
        units; ``tubes``: see :func:`~ramure.app.desktop.state.cells_near_line`); returns the
        locator over them (``bins``: :func:`_near_bins`) for the picker, None if there are none."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from ramure.lsys.interpretation.geometry import cell_array

        start, end, tolerance = line
        polys = mesh.GetPolys()
        offsets, conn = vtk_to_numpy(polys.GetOffsetsArray()), vtk_to_numpy(polys.GetConnectivityArray())
        points = np.asarray(mesh.points)
        self.cells = state.cells_near_line(points, offsets, conn, start, end - start, NEAR_REACH * tolerance, tubes)
        self.keep = state.cell_subset(offsets, conn, self.cells)
        part = pv.PolyData()
        part.SetPoints(mesh.GetPoints())
        part.SetPolys(cell_array(*self.keep))
        self.mapper.SetInputData(part)
        self.locator = _locator(part, bins) if len(self.cells) else None
        return self.locator


class PlantView(QWidget):
    """The plant, its selection in red, the selection's OBB as a red wireframe.

    ``native``: VTK in a native window (True), pyvistaqt's QOpenGLWidget (False), or as
    :func:`~ramure.app.desktop.view.native_view.native_windows` says (None, the default).
    """

    cell_clicked = Signal(int, str)  # cell id (-1: nothing under the cursor), mode
    leaf_clicked = Signal(int, str)  # a volumetric fruit's history leaf, mode
    rectangle_selected = Signal(object, str)  # (x0, y0, x1, y1) display coords, mode
    escape = Signal()

    def __init__(self, parent: QWidget | None = None, native: bool | None = None) -> None:
        super().__init__(parent)
        self.native = native_windows() if native is None else bool(native)
        self.plotter: NativeInteractor | QtInteractor
        if self.native:
            self.plotter = NativeInteractor(self)
        else:  # pyvistaqt only in this fallback (Wayland, offscreen): 6-12 MB not loaded otherwise
            from pyvistaqt import QtInteractor

            self.plotter = QtInteractor(self, auto_update=False, multi_samples=0)
        scene.apply_look(self.plotter)  # light kit, gradient, FXAA, turntable orbit (Z up)
        if self.plotter.iren is not None:
            self.plotter.iren.clear_key_event_callbacks()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plotter)
        self.band = QRubberBand(QRubberBand.Shape.Rectangle, self.plotter)
        self.rectangle_mode = False
        self._filter = _MouseFilter(self)
        self.plotter.installEventFilter(self._filter)
        self.mesh: pv.PolyData | None = None  # the whole plant as shown (``rgb`` colours); drawn by ``plant``
        self.actor: Any = None  # the plant's pick actor (never drawn), None without a plant
        self.snapshot: Snapshot | None = None
        self.picker: Any = None  # a vtkCellPicker over the plant and fruit, built on the first pick
        #: The picker's cell locators over whole data sets (the fruit; the plant's mesh only when
        #: its cells cannot be picked near the ray), by actor: (the data set's state, locator).
        self._locators: dict[int, tuple[tuple, Any]] = {}
        self._near = _NearCells()  # the plant's cells near the last pick ray
        self.box: pv.PolyData | None = None
        self.box_actor: pv.Actor | None = None
        self.fruit: pv.PolyData | None = None
        self.fruit_actor: pv.Actor | None = None
        self.hide_fruit_spheres = False  # True while volumetric fruit replace the spheres
        self.hidden_cells: np.ndarray | None = None  # bool per mesh cell, or None: cells drawn as nothing
        self.plant = PlantActors(self.plotter)  # tubes grouped by thickness, level of detail
        # No frustum culler: it asked every shown prop for its bounds before each frame, so a
        # new version's 131k hairlines paid VTK's pass over their cells (~3 ms) although the
        # view knows their bounds; the plant's groups are culled by level of detail, and a
        # prop outside the frustum draws nothing either way (the same pixels).
        self.plotter.renderer.GetCullers().RemoveAllItems()
        self._diag: float | None = None
        self.view_name = "front"  # the camera preset Home returns to
        self.auto_framed = True  # False once the user moves the camera
        self.hairlines = scene.Hairlines(self.plotter)
        self.ground = scene.Ground(self.plotter)
        self.drafting = False  # True: frames are drawn in the draft look (see the module's notes)
        self._fxaa = bool(self.plotter.renderer.GetUseFXAA())
        self._polish_timer = QTimer(self)
        self._polish_timer.setSingleShot(True)
        self._polish_timer.setInterval(POLISH_MS)
        self._polish_timer.timeout.connect(self.polish)
        self.busy = False
        self.frames = 0  # frames the renderer has drawn (redraw(now=True) checks one was)
        self.plotter.renderer.AddObserver("EndEvent", self._frame_drawn)

    # -- draft and polished frames ---------------------------------------------
    def draft(self, camera: bool = False) -> None:
        """Draw the next frames in the draft look (a large plant only, or any plant when the
        ``camera`` moves under the mouse) and the polished frame once nothing happened for
        :data:`POLISH_MS` (a further call restarts the wait)."""
        if not self.plant.large and not camera:
            self.polish()
            return
        if not self.drafting:
            self.drafting = True
            self._set_look(draft=True)
        self._polish_timer.start(BUSY_POLISH_MS if self.busy else POLISH_MS)

    def set_busy(self, busy: bool) -> None:
        """The model is computing (True: a new version is likely coming, so a polished frame now
        would compete with it for the CPU and soon be replaced; the polish waits up to
        :data:`BUSY_POLISH_MS`) or is idle again (False: the usual pause)."""
        self.busy = bool(busy)
        if self.drafting and self._polish_timer.isActive():
            self._polish_timer.start(BUSY_POLISH_MS if self.busy else POLISH_MS)

    def polish(self) -> None:
        """Back to the full-quality look now, and repaint if the last frames were drafts."""
        self._polish_timer.stop()
        if self.drafting:
            self.drafting = False
            self._set_look(draft=False)
            self.redraw()

    def camera_dragged(self) -> None:
        """The mouse turns or pans the camera: every plant is drawn in the draft look until the
        release (a small plant's polished frame costs about three drafts on software OpenGL,
        most of it FXAA: a drag at 50 frames a second rather than 17)."""
        self.draft(camera=True)
        self._polish_timer.stop()  # polished once the drag is over

    def set_moving(self, moving: bool) -> None:
        """The camera is dragged (True: fewer tubes, draft look) or was released (False)."""
        self.plant.set_moving(moving)
        self.draft()
        if moving:
            self._polish_timer.stop()  # polished only once the drag is over

    def _set_look(self, draft: bool) -> None:
        if self._fxaa:
            self.plotter.renderer.SetUseFXAA(not draft)
        self.hairlines.set_draft(draft)

    # -- drawing ---------------------------------------------------------------
    def forget_kept(self) -> None:
        """Drop what is kept of the plant shown before this one (for an instant undo): an edit
        is under way, after which Undo comes back to the plant shown now.  Its memory is free
        for the edit's new version (Honda n = 17: a mesh, hairlines and their skeleton, about
        35 MB that an edit otherwise held on top of two versions).  An undo of an edit that was
        refused draws that plant again as a new one."""
        self.plant.forget_kept()
        self.hairlines.forget_kept()

    def show_plant(self, snap: Snapshot, colors: np.ndarray, reset_camera: bool | None = None) -> None:
        """Draw ``snap``'s mesh with per-cell ``colors`` (uint8 RGB); ``reset_camera``: frame the
        whole plant (else the camera stays where it is, except for the first plant)."""
        if snap is not self.snapshot:
            self.hidden_cells = None  # another plant version: other cells
        self.snapshot = snap
        mesh = snap.mesh.copy(deep=False)
        if mesh.n_cells == 0:
            self.plant.show(None, None)
            self.mesh, self.actor = None, None
            self.hairlines.show(None, mesh, colors)
            self.redraw()
            return
        mesh.cell_data["rgb"] = colors
        self.mesh = mesh
        self._apply_hidden()
        # The plant's actors keep their mappers and shaders; only the groups drawn in the next
        # frame gather their cells and go to the GPU again (see plant_actors).
        self.plant.show(mesh, snap.skeleton, key=snap.mesh)  # an undo: the kept actors again
        self.actor = self.plant.pick_actor
        self.hairlines.show(snap.skeleton, self.mesh, colors, key=snap.mesh, sides=self.plant.sides)
        bounds = self.plant_bounds()
        self.ground.show(bounds)
        self.picker = None
        # The camera holds still on an edit, so the plant before and after can be compared; it
        # frames the plant only when asked (Home, an opened file, a change of n) or the first time.
        if reset_camera or self._diag is None:
            self.reset_camera()
        else:  # the same camera sees the whole new plant: nothing of it clipped away
            self.reset_clipping()
        self.draft()
        self.redraw()

    def plant_bounds(self) -> tuple[float, ...]:
        """The shown mesh's bounds (VTK's order): the plant actors' own (patched after an edit,
        see :mod:`~ramure.app.desktop.view.plant_actors`) while the mesh shows the model's points,
        else VTK's."""
        assert self.mesh is not None
        known = self.plant.bounds
        if known is not None and self.snapshot is not None and self.mesh.GetPoints() is self.snapshot.mesh.GetPoints():
            return known
        return tuple(self.mesh.bounds)

    def shown_bounds(self) -> tuple[float, ...] | None:
        """What VTK's ``ComputeVisiblePropBounds`` gives, with the hairlines' bounds taken from
        the plant actors instead of a pass over their cells; None when they are unknown."""
        lines = self.hairlines.shown
        known = self.plant.segment_bounds
        shown = self.snapshot.skeleton if self.snapshot is not None else None
        if lines is None or known is None or not lines.chunks.visible or lines.skeleton is not shown:
            return None
        lines.chunks.set_visible(False)  # the other props' bounds: a few small ones, cached by VTK
        try:
            others = self.plotter.renderer.ComputeVisiblePropBounds()
        finally:
            lines.chunks.set_visible(True)
        lo = np.minimum(np.array(others[0::2]), known[0::2])
        hi = np.maximum(np.array(others[1::2]), known[1::2])
        return tuple(float(v) for v in np.c_[lo, hi].ravel())

    def reset_camera(self, view: str | None = None) -> None:
        """Frame the whole plant from preset ``view`` (front, side, top, iso; default: the last)."""
        self.view_name = view or self.view_name
        if self.mesh is not None:
            bounds = self.plant_bounds()
            scene.fit_camera(self.plotter, bounds, self.view_name, clip_bounds=self.shown_bounds())
            self._diag = float(np.linalg.norm(np.subtract(*np.reshape(bounds, (3, 2)).T)))
        self.auto_framed = True
        self.redraw()

    def zoom_to(self, bounds: Sequence[float] | None) -> None:
        """Frame ``bounds`` (x0, x1, y0, y1, z0, z1: a fruit, see
        :meth:`ramure.app.model.Explorer.fruit_bounds`) from the current view direction; the
        plant is no longer refitted on a resize (the user chose this view)."""
        if bounds is None:
            return
        scene.fit_camera(self.plotter, bounds, self.view_name, clip_bounds=self.shown_bounds())
        self.auto_framed = False
        self.redraw()

    def reset_clipping(self) -> None:
        """The camera's near and far planes around everything shown (the camera does not move)."""
        clip = self.shown_bounds()
        if clip is None:
            self.plotter.renderer.ResetCameraClippingRange()
        else:
            self.plotter.renderer.ResetCameraClippingRange(*clip)

    def resizeEvent(self, event: QResizeEvent) -> None:  # noqa: N802 (Qt API)
        """A new size (the window's first layout, a dock moved): keep the plant framed until the
        user moves the camera."""
        super().resizeEvent(event)
        if self.auto_framed and self.mesh is not None:
            self.reset_camera()

    def set_selected_segments(self, segments: ArrayLike) -> None:
        """Thick red lines over the selected segments (visible on hairline twigs)."""
        self.hairlines.set_selection(segments)
        self.redraw()

    def set_colors(self, colors: np.ndarray) -> None:
        """Recolour the plant in place (selection or kinship changed); the same colours again
        (the window recolours every new version it has just shown) cost nothing."""
        if self.mesh is None:
            return
        rgb = np.asarray(self.mesh.cell_data["rgb"])
        if rgb.shape == np.shape(colors) and np.array_equal(rgb, colors):
            return
        self.mesh.cell_data["rgb"][:] = colors  # type: ignore[index]  # pyvista stubs
        self.mesh.Modified()
        self.plant.colors_changed()
        self.hairlines.set_colors(self.mesh, colors)
        self.draft()
        self.redraw()

    def set_box(self, lines: ArrayLike | None) -> None:
        """Draw the selection's OBB edges ((12, 2, 3) segments) in red, or hide it (None).

        One actor is kept and its points moved, so a new selection costs no new GL objects.
        """
        if lines is None:
            if self.box_actor is not None and self.box_actor.GetVisibility():
                self.box_actor.SetVisibility(False)
                self.redraw()
            return
        pts = np.asarray(lines, float).reshape(-1, 3)
        if self.box is None or self.box_actor is None or self.box.n_points != len(pts):
            cells = np.c_[np.full(len(pts) // 2, 2), np.arange(len(pts)).reshape(-1, 2)].ravel()
            self.box = pv.PolyData(pts.copy(), lines=cells)
            self.box_actor = self.plotter.add_mesh(
                self.box, color="red", line_width=2, name="obb", reset_camera=False, pickable=False, render=False, lighting=False
            )
        else:
            self.box.points[:] = pts  # type: ignore[index]  # pyvista stubs
            self.box.Modified()
        self.box_actor.SetVisibility(True)
        self.redraw()

    def set_box_for(self, make: Callable[[], ArrayLike | None] | None, leaves: int) -> None:
        """``set_box(make())`` (``make`` None: no box); for a selection of many ``leaves`` the
        recoloured plant is painted first and the box (an OBB over every selected segment,
        70-100 ms at 131k) follows in the next turn of the event loop, unless another box came."""
        self._box_generation = getattr(self, "_box_generation", 0) + 1
        if make is None or leaves <= BOX_LATER_LEAVES:
            self.set_box(make() if make is not None else None)
            return
        generation = self._box_generation
        if self.box_actor is not None:
            self.box_actor.SetVisibility(False)  # the old box does not belong to this selection
        self.redraw(now=True)

        def later() -> None:
            if generation == self._box_generation:
                try:
                    self.set_box(make())
                except RamureError:
                    self.set_box(None)

        QTimer.singleShot(0, later)

    def redraw(self, now: bool = False) -> None:
        """Schedule a repaint (``now``: paint before returning, e.g. for a benchmark or screenshot).

        The native view's frame is on the screen when ``redraw(now=True)`` returns.  Qt's
        ``repaint`` now and then returns without painting the ``QOpenGLWidget``; the
        renderer's frame count tells, and the frame is then rendered directly (Qt composes
        the QOpenGLWidget's frame into the window later, in the event loop)."""
        if not now:
            self.plotter.update()
            return
        before = self.frames
        self.plotter.repaint()
        if self.frames == before and self.plotter.ren_win is not None:
            self.plotter.render()

    def _frame_drawn(self, *_args) -> None:
        self.frames += 1

    def set_fruit_spheres_hidden(self, hidden: bool) -> None:
        """Hide the plant mesh's fruit spheres (so they do not show inside volumetric fruit)."""
        self.hide_fruit_spheres = bool(hidden)
        self._apply_hidden()
        self.draft()
        self.redraw()

    def set_hidden_cells(self, hidden: ArrayLike | None) -> None:
        """Draw the cells where ``hidden`` (bool per mesh cell) is True as nothing; None shows all.

        Cell ids, colours and the other cells stay as they are (the points used only by hidden
        cells collapse onto one point per cell). A mask of another length is ignored, and the
        mask is dropped when a new plant version comes (its cells differ).
        """
        mask = None if hidden is None else np.asarray(hidden, bool)
        if mask is not None and (self.mesh is None or len(mask) != self.mesh.n_cells or not mask.any()):
            mask = None
        self.hidden_cells = mask
        self._apply_hidden()
        self.draft()
        self.redraw()

    def _apply_hidden(self) -> None:
        if self.mesh is None or self.snapshot is None:
            return
        if self.hidden_cells is not None and len(self.hidden_cells) != self.mesh.n_cells:
            self.hidden_cells = None
        if not self.hide_fruit_spheres and self.hidden_cells is None and self.mesh.GetPoints() is self.snapshot.mesh.GetPoints():
            return  # shown as derived: nothing to do (the usual case)
        points = points_without_fruit(self.mesh) if self.hide_fruit_spheres else None
        if self.hidden_cells is not None:
            points = _collapse_cells(self.snapshot.mesh, points, self.hidden_cells)
        # new vtkPoints: the snapshot's mesh (shared, shallow copy) keeps its own
        self.mesh.SetPoints(pv.vtk_points(points, deep=False) if points is not None else self.snapshot.mesh.GetPoints())
        self.mesh.Modified()
        self.plant.points_changed()

    def set_fruit(self, surface: pv.PolyData | None, selection: Collection[int] = ()) -> None:
        """Draw volumetric fruit (a surface with ``leaf_id`` cells), or remove them (None)."""
        self.picker = None
        if surface is None or surface.n_cells == 0:
            if self.fruit_actor is not None:
                self.plotter.remove_actor("fruit", render=False)  # type: ignore[arg-type]  # pyvista stubs
            self.fruit, self.fruit_actor = None, None
            self.redraw()
            return
        self.fruit = surface.copy(deep=False)
        self.fruit.cell_data["rgb"] = self.fruit_colors(selection)
        self.fruit_actor = self.plotter.add_mesh(
            self.fruit,
            scalars="rgb",
            rgb=True,
            name="fruit",
            reset_camera=False,
            render=False,
            pickable=True,
            show_scalar_bar=False,
        )
        self.redraw()

    def fruit_colors(self, selection: Collection[int]) -> np.ndarray:
        """The fruit volumes' cell colours, the selected fruit in the selection colour."""
        from ramure.app.desktop.state import leaf_mask

        if self.fruit is None:
            return np.zeros((0, 3), np.uint8)
        rgb = np.empty((self.fruit.n_cells, 3), np.uint8)
        rgb[:] = FRUIT_RGB
        selected = leaf_mask(self.fruit.cell_data["leaf_id"], selection)
        if "tissue_rgb" in self.fruit.cell_data:  # a cut fruit: every tissue in its species' colour
            rgb[:] = np.asarray(self.fruit.cell_data["tissue_rgb"], np.uint8)
            tint = 0.8 * rgb[selected] + 0.2 * np.asarray(FRUIT_SELECTED, float)  # selected: tinted, still readable
            rgb[selected] = np.clip(np.round(tint), 0, 255).astype(np.uint8)
            return rgb
        rgb[selected] = FRUIT_SELECTED
        return rgb

    def set_fruit_selection(self, selection: Collection[int]) -> None:
        """Recolour the fruit volumes for ``selection``."""
        if self.fruit is not None:
            self.fruit.cell_data["rgb"][:] = self.fruit_colors(selection)  # type: ignore[index]  # pyvista stubs
            self.fruit.Modified()

    def has_box(self) -> bool:
        """True when the rubber-band box is on screen."""
        return self.box_actor is not None and bool(self.box_actor.GetVisibility())

    # -- coordinates -------------------------------------------------------------
    def display_size(self) -> tuple[int, ...]:
        """The render window's size in display pixels."""
        ren_win = self.plotter.ren_win
        assert ren_win is not None, "the view is closed"
        return tuple(ren_win.GetSize())

    def to_display(self, qpoint: QPoint) -> tuple[float, float]:
        """VTK display coordinates of a point in widget (Qt) coordinates."""
        scale = self.plotter.devicePixelRatioF()
        return qpoint.x() * scale, (self.plotter.height() - qpoint.y() - 1) * scale

    def to_widget(self, x: float, y: float) -> QPoint:
        """Widget (Qt) coordinates of VTK display coordinates."""
        scale = self.plotter.devicePixelRatioF()
        return QPoint(int(round(x / scale)), int(round(self.plotter.height() - 1 - y / scale)))

    def projection_matrix(self) -> np.ndarray:
        """The renderer's world-to-display projection (see :func:`ramure.app.render.projection_matrix`)."""
        return scene.projection_matrix(self.plotter.renderer)

    def project(self, points: ArrayLike) -> np.ndarray:
        """Display coordinates (k, 2) of world points (vectorised: one matrix, no VTK call per point)."""
        x0, y0, x1, y1 = self.plotter.renderer.GetViewport()
        w, h = self.display_size()
        xy = project_to_display(self.projection_matrix(), points, ((x1 - x0) * w, (y1 - y0) * h))
        return xy + np.array([x0 * w, y0 * h])

    # -- picking -----------------------------------------------------------------
    def _picker(self):
        if self.picker is None:
            # the two classes only: ``import vtk`` loads every VTK module (about 60 MB)
            from vtkmodules.vtkRenderingCore import vtkCellPicker

            picker = vtkCellPicker()
            picker.SetTolerance(PICK_TOLERANCE)
            picker.PickFromListOn()
            self._locators = {}
            self.picker = picker
        return self.picker

    def _whole_locator(self, actor: Any) -> Any:
        """A locator over the whole of ``actor``'s data set, made again only when it changed."""
        data = actor.GetMapper().GetInput()
        points = data.GetPoints()
        stamp = (data.__this__, points.__this__ if points is not None else None, data.GetMTime())  # C++ objects
        known = self._locators.get(id(actor))
        if known is None or known[0] != stamp:
            known = self._locators[id(actor)] = (stamp, _locator(data))
        return known[1]

    def pick_any(self, x: float, y: float) -> tuple[str | None, int]:
        """``("plant" | "fruit", cell id)`` under display ``(x, y)``, or ``(None, -1)``.

        The plant's cells are picked from those near the pick ray (:class:`_NearCells`): the
        cell a picker over the whole mesh finds, without that mesh's locator.  A mesh whose box
        that locator could not share (:func:`_near_bins` None: cells other than polygons, or a
        side too thin, e.g. after cells were hidden) is picked with its own whole locator,
        made once for its points."""
        if self.actor is None or self.mesh is None:
            return None, -1
        picker = self._picker()
        picker.InitializePickList()
        picker.RemoveAllLocators()
        bins = _near_bins(self.mesh)  # this mesh's points now (cells hidden since?)
        if bins is not None:
            tubes = (self.plant.segment_count, self.plant.sides) if self.plant.sides else (0, 0)
            locator = self._near.gather(self.mesh, self._pick_ray(x, y), bins, tubes)
            picker.AddPickList(self._near.actor)
            if locator is not None:
                picker.AddLocator(locator)
        else:
            picker.AddPickList(self.actor)
            picker.AddLocator(self._whole_locator(self.actor))
        if self.fruit_actor is not None:  # after the plant: the plant wins a tie
            picker.AddPickList(self.fruit_actor)
            picker.AddLocator(self._whole_locator(self.fruit_actor))
        found = picker.Pick(float(x), float(y), 0.0, self.plotter.renderer)
        picker.RemoveAllLocators()
        if not found:
            return None, -1
        hit = picker.GetActor()
        cell = int(picker.GetCellId())
        if self.fruit_actor is not None and hit is self.fruit_actor:
            return "fruit", cell
        cell = int(self._near.cells[cell]) if hit is self._near.actor and cell >= 0 else cell
        fruit = self._fruit_behind_twig(x, y, np.array(picker.GetPickPosition()), cell)
        return ("fruit", fruit) if fruit >= 0 else ("plant", cell)

    def _fruit_behind_twig(self, x: float, y: float, point: np.ndarray, cell: int) -> int:
        """The volumetric fruit cell under display ``(x, y)`` when the branch cell ``cell`` hit at
        ``point`` lies within that fruit's radius in front of it (its stalk or the twig it hangs
        on, crossing the fruit on screen): a click in the fruit's middle means the fruit.  -1 when
        the plant's cell is a leaf, or the branch is well in front of the fruit."""
        if self.fruit is None or self.fruit_actor is None or cell < 0 or self.mesh is None:
            return -1
        if int(self.mesh.cell_data["kind"][cell]) != 0:  # a leaf lying on the fruit: the leaf
            return -1
        from vtkmodules.vtkRenderingCore import vtkCellPicker

        picker = vtkCellPicker()
        picker.SetTolerance(PICK_TOLERANCE)
        picker.PickFromListOn()
        picker.AddPickList(self.fruit_actor)
        picker.AddLocator(self._whole_locator(self.fruit_actor))
        found = picker.Pick(float(x), float(y), 0.0, self.plotter.renderer)
        picker.RemoveAllLocators()
        if not found:
            return -1
        fruit_cell = int(picker.GetCellId())
        leaf = np.asarray(self.fruit.cell_data["leaf_id"])
        points = np.asarray(self.fruit.cell_centers().points)[leaf == leaf[fruit_cell]]
        radius = float(np.max(points.max(axis=0) - points.min(axis=0))) / 2
        eye = np.array(self.plotter.renderer.GetActiveCamera().GetPosition())
        gap = np.linalg.norm(np.array(picker.GetPickPosition()) - eye) - np.linalg.norm(point - eye)
        return fruit_cell if gap <= radius else -1

    def _pick_ray(self, x: float, y: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Two world points on the line through display ``(x, y)`` and the pick tolerance in
        world units, as :class:`vtkPicker` computes it: the view's diagonal at the focal
        point's depth times :data:`PICK_TOLERANCE`."""
        renderer = self.plotter.renderer
        renderer.SetWorldPoint(*renderer.GetActiveCamera().GetFocalPoint(), 1.0)
        renderer.WorldToDisplay()
        depth = renderer.GetDisplayPoint()[2]

        def world(dx: float, dy: float, dz: float) -> np.ndarray:
            renderer.SetDisplayPoint(dx, dy, dz)
            renderer.DisplayToWorld()
            return np.array(renderer.GetWorldPoint()[:3])

        w, h = self.display_size()
        x0, y0, x1, y1 = renderer.GetViewport()
        diagonal = np.linalg.norm(world(x1 * w, y1 * h, depth) - world(x0 * w, y0 * h, depth))
        return world(x, y, 0.0), world(x, y, 1.0), PICK_TOLERANCE * float(diagonal)

    def pick(self, x: float, y: float) -> int:
        """The plant's mesh cell at display ``(x, y)``, or -1 (volumetric fruit are not plant cells)."""
        kind, cell = self.pick_any(x, y)
        return cell if kind == "plant" else -1

    def click_at(self, x: float, y: float, mode: str = "replace") -> int:
        """Pick at display ``(x, y)`` and emit :attr:`cell_clicked` or :attr:`leaf_clicked`."""
        kind, cell = self.pick_any(x, y)
        if kind == "fruit" and self.fruit is not None:
            leaf = int(self.fruit.cell_data["leaf_id"][cell])
            self.leaf_clicked.emit(leaf, mode)
            return cell
        self.cell_clicked.emit(cell, mode)
        return cell

    def click_from_widget(self, qpoint: QPoint, mode: str) -> int:
        """A click at widget point ``qpoint``: pick there (see :meth:`click_at`)."""
        return self.click_at(*self.to_display(qpoint), mode)

    def rectangle_at(self, rect: Sequence[float], mode: str = "replace") -> None:
        """Emit :attr:`rectangle_selected` for display rectangle ``(x0, y0, x1, y1)``."""
        self.rectangle_selected.emit(tuple(float(v) for v in rect), mode)

    def rectangle_from_widget(self, a: QPoint, b: QPoint, mode: str) -> None:
        """A rubber band from ``a`` to ``b`` (widget points): select inside it."""
        self.rectangle_at((*self.to_display(a), *self.to_display(b)), mode)

    def key_pressed(self, event: QKeyEvent) -> None:
        """Escape clears the selection, R toggles rectangle selection."""
        if event.key() == Qt.Key.Key_Escape:
            self.escape.emit()
        elif event.key() == Qt.Key.Key_R and not event.modifiers():
            self.set_rectangle_mode(not self.rectangle_mode)
        elif event.key() == Qt.Key.Key_Home:
            self.reset_camera()

    def set_rectangle_mode(self, on: bool) -> None:
        """Drag draws a selection rectangle (``on``) or turns the camera."""
        self.rectangle_mode = bool(on)
        self.plotter.setCursor(Qt.CursorShape.CrossCursor if on else Qt.CursorShape.ArrowCursor)

    # -- images -------------------------------------------------------------------
    def grab_image(self) -> QImage:
        """The 3D view as a QImage (what is on screen, polished)."""
        self.polish()
        self.redraw(now=True)
        return self.frame_image()

    def grab_window(self) -> QImage:
        """The whole top-level window holding this view as a QImage, the 3D view freshly
        painted (polished) and VTK's native windows painted in."""
        self.polish()
        self.redraw(now=True)
        from ramure.app.desktop.view.native_view import grab_with_frames

        return grab_with_frames(self.window())

    def frame_image(self) -> QImage:
        """The last frame drawn, in whatever look (:meth:`grab_image` polishes first)."""
        if isinstance(self.plotter, NativeInteractor):
            return self.plotter.grab_frame()
        return self.plotter.grabFramebuffer()

    def close(self) -> bool:
        """Stop the polish timer and close the plotter."""
        self._polish_timer.stop()
        self.plotter.close()
        return super().close()
