"""The explorer's 3D view: an interactive pyvista/trame view when it can run, else a PNG.

The static view is an ``ipywidgets.Image`` re-rendered off-screen (VTK, EGL
when there is no display) after every change.  The interactive view uses
pyvista's trame backend (``pip install "pyvista[jupyter]"``, i.e.
``trame-pyvista``) in server-rendering mode, where picking works: a click on
a branch selects its leaf (in trame's client mode picking does not reach
Python).  ``backend="auto"`` takes the trame server view when trame is
installed and pyvista's notebook backend is not set to ``static``
(``PYVISTA_JUPYTER_BACKEND=static``), else the PNG.  Either way :meth:`PlantView.png` gives the current picture, which is
also what a notebook shows where no widget can run (nbconvert, GitHub).

In the interactive view a click picks (:class:`ClickPicker`) and, in rectangle mode, a drag
draws a rubber band whose leaves the model finds (:class:`RectanglePicker`, the model's
``leaves_in_view``: the same as the desktop's).  The view's frame is served through Jupyter's
own port when jupyter-server-proxy is there (:func:`trame_proxy`).

>>> from ramure.app.model import Explorer
>>> png = plant_png(Explorer("grammars/honda_sympodial.lsys", n=4), size=(120, 120))
>>> png[:4] == b"\\x89PNG"
True
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.app.jupyter._ui import png_image
from ramure.app.render import FRUIT_RGB, plant_colors as base_colors
from ramure.app.render import headless_setup, frame_camera

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.app.model import Explorer as Model

CUT = (1.0, 0.6, 0.0)  # leaves the planned cut would regrow
VIEWS = ("iso", "front", "side", "top")
BACKENDS = ("auto", "static", "trame", "server", "client")
RENDER_LOCK = threading.Lock()  # one off-screen render at a time (thumbnail threads included)
#: Pixels kept free above the plant in the trame view: pyvista's trame menu is a card floating
#: over the picture, 20 px from its top and 36 px tall; the view is this much taller than the
#: explorer's ``size`` and frames the plant below it.
TOOLBAR_BAND = 64


def cut_leaves(model: Model) -> np.ndarray:
    """Leaf ids the current selection's cut would regrow (empty without a selection): the
    model's :meth:`~ramure.app.model.Explorer.preview`, the same the desktop highlights."""
    preview = model.preview()
    return np.zeros(0, np.int64) if preview is None else preview.leaves


def view_colors(model: Model, show_cut: bool = False) -> np.ndarray:
    """RGB (uint8) per mesh cell: bark/leaf/fruit (orange, as on the desktop: red always means
    selected), kinship hues for one selected leaf, the planned cut in orange (``show_cut``),
    the selection in red."""
    mesh = model.mesh
    if not mesh.n_cells:  # a plant that draws nothing (e.g. algae) may carry no cell data at all
        return np.zeros((0, 3), np.uint8)
    rgb = base_colors(mesh)
    if show_cut:
        rgb[np.isin(mesh.cell_data["leaf_id"], cut_leaves(model))] = np.multiply(CUT, 255).astype(np.uint8)
    else:
        hues = model.kinship_hues()
        if hues is not None:
            seg = np.asarray(mesh.cell_data["segment"])
            rgb[seg >= 0] = (np.asarray(hues)[seg[seg >= 0]] * 255).astype(np.uint8)
    if model.selection:
        rgb[np.isin(mesh.cell_data["leaf_id"], model.selection)] = (255, 0, 0)
    return rgb


def _screenshot(size, draw, background: str = "white") -> bytes:
    """Render off-screen (one render at a time): ``draw(plotter)`` adds the meshes and places
    the camera; returns the PNG bytes."""
    headless_setup()
    import pyvista as pv

    with RENDER_LOCK:
        plotter = pv.Plotter(off_screen=True, window_size=[int(size[0]), int(size[1])])
        try:
            plotter.set_background(background)  # type: ignore[arg-type]  # pyvista stubs: decorated method
            draw(plotter)
            buf = io.BytesIO()
            plotter.screenshot(buf)
        finally:
            plotter.close()
    return buf.getvalue()


def fit_view(plotter: pv.Plotter, points: ArrayLike, fill: float = 0.9, max_points: int = 20_000, top: float = 0.0) -> None:
    """Pan and zoom the camera so ``points`` (n,3) fill ``fill`` of the picture, centred; with
    ``top``, in the part of the picture below its top ``top`` fraction (kept for a toolbar).

    :func:`ramure.app.render.frame_camera` fits the bounding *sphere*, which leaves a tall plant
    seen from above off-centre (its top near the edge, empty space below); this measures
    where the points land on screen and corrects for it.
    """
    points = np.asarray(points, float).reshape(-1, 3)
    if len(points) > max_points:
        points = points[:: len(points) // max_points + 1]
    if not len(points):
        return
    cam = plotter.camera
    width, height = plotter.window_size
    aspect = width / height
    for _ in range(3):  # a perspective view: converge in a few steps
        m = np.array(
            [[cam.GetCompositeProjectionTransformMatrix(aspect, -1, 1).GetElement(i, j) for j in range(4)] for i in range(4)]
        )
        h = np.c_[points, np.ones(len(points))] @ m.T
        ndc = h[:, :2] / h[:, 3:4]
        lo, hi = ndc.min(axis=0), ndc.max(axis=0)
        centre, extent = (lo + hi) / 2, (hi - lo) / 2
        scale = float(max(extent[0], extent[1] / (1.0 - top)))
        zoom = fill / scale if scale > 0 else 1.0
        centre[1] += top / zoom  # the band's centre, -top in NDC once zoomed (a zoom scales about 0)
        position, focal = np.array(cam.position), np.array(cam.focal_point)
        distance = np.linalg.norm(focal - position)
        half_h = distance * np.tan(np.radians(cam.view_angle) / 2)
        up = np.array(cam.up) / np.linalg.norm(cam.up)
        forward = (focal - position) / distance
        right = np.cross(forward, up)
        right /= np.linalg.norm(right) or 1.0  # a view from above has ``up`` almost along ``forward``
        up = np.cross(right, forward)
        shift = centre[0] * half_h * aspect * right + centre[1] * half_h * up
        cam.position, cam.focal_point = tuple(position + shift), tuple(focal + shift)
        if scale > 0:
            cam.zoom(zoom)
    plotter.reset_camera_clipping_range()


def mesh_png(
    mesh: pv.PolyData,
    rgb: ArrayLike | None = None,
    size: tuple[int, int] = (480, 480),
    view: str = "iso",
    background: str = "white",
    fill: float = 0.9,
    bounds: Sequence[float] | None = None,
) -> bytes:
    """PNG bytes of a plant mesh coloured by ``rgb`` per cell (default: bark/leaf/fruit),
    framed so the plant (or the box ``bounds``: a zoom to fruit) fills ``fill`` of the picture."""

    def draw(plotter) -> None:
        if mesh.n_cells:
            shown = mesh.copy(deep=False)
            shown.cell_data["rgb"] = base_colors(mesh) if rgb is None else np.asarray(rgb)
            plotter.add_mesh(shown, scalars="rgb", rgb=True)
            if bounds is not None:
                frame_camera(plotter, tuple(bounds), view)
                fit_view(plotter, _corners(bounds), fill)
                return
            frame_camera(plotter, mesh.bounds, view)
            fit_view(plotter, mesh.points, fill)

    return _screenshot(size, draw, background)


def _corners(bounds: Sequence[float]) -> np.ndarray:
    """The 8 corners of a box ``(x0, x1, y0, y1, z0, z1)``."""
    b = np.reshape(np.asarray(bounds, float), (3, 2))
    return np.array(np.meshgrid(*b, indexing="ij")).reshape(3, -1).T


def plant_png(
    model: Model,
    size: tuple[int, int] = (480, 480),
    view: str = "iso",
    show_cut: bool = False,
    bounds: Sequence[float] | None = None,
) -> bytes:
    """PNG bytes of the model's current plant as the explorer colours it (``bounds``: framed on
    that box, e.g. :meth:`ramure.app.model.Explorer.fruit_bounds`)."""
    return mesh_png(model.mesh, view_colors(model, show_cut), size, view, bounds=bounds)


def fruit_png(
    model: Model, size: tuple[int, int] = (480, 480), view: str = "front", focus: int | None = None, fill: float = 0.9
) -> bytes | None:
    """PNG of the plant's wood with its volumetric fruit (3G-maps, per-fruit edits applied) in
    orange, the selected ones in red; ``focus`` (a fruit's leaf id) shows that fruit alone with
    its faces outlined, seen from outside the crown (``view`` is then not used).
    None when the plant has no fruit or the 3G-map layer is missing."""
    surface = model.fruit_surface()
    if surface is None:
        return None
    mesh = model.mesh
    wood = mesh.extract_cells(np.asarray(mesh.cell_data["kind"]) < 2)  # type: ignore[arg-type]  # pyvista types masks as NDArray[bool], not numpy's bool dtype
    leaf = np.asarray(surface.cell_data["leaf_id"])
    colours = np.tile(np.array(FRUIT_RGB, np.uint8), (surface.n_cells, 1))
    colours[np.isin(leaf, model.selection)] = (255, 0, 0)
    surface.cell_data["rgb"] = colours
    bounds, outward = np.asarray(mesh.bounds, float), None
    if focus is not None:
        one = surface.extract_cells(leaf == int(focus))
        if one.n_cells:
            centre = np.reshape(one.bounds, (3, 2)).mean(axis=1)
            half = 0.6 * float(np.ptp(np.reshape(one.bounds, (3, 2)), axis=1).max())
            surface, wood = one, wood.extract_cells([])  # that fruit alone, its faces outlined
            bounds = np.column_stack([centre - half, centre + half]).ravel()
            # look from outside the crown: from the plant's axis out through the fruit, a little above
            axis = np.reshape(mesh.bounds, (3, 2)).mean(axis=1)
            outward = np.append(centre[:2] - axis[:2], 0.0)
            outward = outward / (np.linalg.norm(outward) or 1.0) + (0.0, 0.0, 0.35)

    def draw(plotter) -> None:
        if wood.n_cells:
            wood.cell_data["rgb"] = base_colors(wood)
            plotter.add_mesh(wood, scalars="rgb", rgb=True)
        plotter.add_mesh(surface, scalars="rgb", rgb=True, show_edges=outward is not None, edge_color="#7a3d12")
        if outward is None:
            frame_camera(plotter, bounds, view)
            fit_view(plotter, mesh.points, fill)
        else:
            plotter.camera_position = [tuple(centre + outward * 10 * half), tuple(centre), (0.0, 0.0, 1.0)]
            plotter.reset_camera(bounds=tuple(bounds))
            fit_view(plotter, surface.points, fill * 0.8)

    return _screenshot(size, draw)


def fruit_cut_png(model: Model, leaf: int, size: tuple[int, int] = (420, 420), volume_levels: int = 1) -> bytes | None:
    """PNG of fruit ``leaf`` cut open across its axis, volume cells coloured by tissue in its
    species' colours (:func:`ramure.app.fruit_look.coloured_grid`) with a legend in the
    species' words; None when ``leaf`` is not a fruit."""
    if int(leaf) not in model.fruit_ids():
        return None
    from ramure.app.fruit_look import coloured_grid, legend_entries
    from ramure.gmap.kernel.cut import plane_cut

    cells = coloured_grid(model.fruit_volume(leaf, volume_levels=volume_levels))  # that fruit only, species colours
    organs = model.skeleton.organs
    axis = np.asarray(organs.frame)[list(organs.leaf_id).index(int(leaf))][0]  # the heading
    inside = plane_cut(cells, normal=tuple(axis), origin=cells.center, mode="cells")
    entries = legend_entries(inside)
    present = [name for name, _ in entries]
    side = np.cross(axis, (0.0, 0.0, 1.0))
    look = axis + 0.6 * side / (np.linalg.norm(side) or 1.0) + (0.0, 0.0, 0.3)  # the cut face, a bit aside
    centre = np.asarray(inside.center)

    def draw(plotter) -> None:
        plotter.add_mesh(inside, scalars="rgb", rgb=True, show_edges=True, edge_color="#5d4037", line_width=0.5)
        plotter.add_legend(
            [[name, colour] for name, colour in entries],
            bcolor="white",
            border=True,
            face="rectangle",
            loc="lower right",
            size=(0.045 + 0.022 * max(map(len, present)), 0.06 * len(present)),
        )
        plotter.camera_position = [tuple(centre + look * 10), tuple(centre), (0.0, 0.0, 1.0)]
        plotter.reset_camera(bounds=tuple(inside.bounds))

    return _screenshot(size, draw)


def trame_available() -> bool:
    """True when pyvista's trame notebook backend is installed."""
    return importlib.util.find_spec("trame_pyvista") is not None


def in_kernel() -> bool:
    """True inside a Jupyter kernel (where a widget front end may be connected)."""
    from IPython import get_ipython  # ipywidgets depends on IPython

    shell = get_ipython()
    return shell is not None and getattr(shell, "kernel", None) is not None


def resolve_backend(backend: str = "auto") -> str:
    """``"static"`` or a trame mode (``"trame"``, ``"server"``, ``"client"``)."""
    if backend not in BACKENDS:
        from ramure.errors import ValueRefused

        raise ValueRefused(f"view backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
    if backend == "static" or not trame_available():
        return "static"
    if backend != "auto":
        return backend
    if not in_kernel():
        return "static"
    import pyvista as pv

    chosen = pv.global_theme.jupyter_backend
    return "server" if chosen in (None, "trame", "server", "client") else "static"


class PlantView:
    """The 3D view of an explorer ``app`` (anything with ``.model`` and ``.pick(cell_id)``)."""

    def __init__(
        self, app: NotebookExplorer, backend: str = "auto", size: tuple[int, int] = (480, 480), view: str = "iso"
    ) -> None:
        self.app = app
        width, height = size
        self.size = (width, height)
        self.view = view
        self.show_cut = True  # the cut preview, on by default (the explorer's check box)
        self.backend = resolve_backend(backend)
        self.image = png_image()
        self._shown: tuple | None = None  # the key of what the view shows
        self._png: tuple[tuple, bytes] | None = None
        self.zoom: tuple[float, ...] | None = None  # a box the view is framed on (zoom to fruit), None: the plant
        self.trame: TrameView | None = None
        self.fallback_reason: str | None = None
        if self.backend != "static":
            try:
                self.trame = TrameView(self, self.backend)
            except Exception as exc:  # noqa: BLE001 - any trame/server failure falls back to the PNG
                self.backend = "static"
                self.fallback_reason = f"interactive view unavailable ({type(exc).__name__}: {exc}); showing a picture"
        self.widget = self.trame.widget if self.trame else self.image

    @property
    def picking(self) -> bool:
        """Whether a click in the view selects leaves."""
        return self.trame is not None and self.backend != "client"

    def key(self) -> tuple:
        """What the picture depends on (model version, selection, cut, camera, size); equal keys, same picture."""
        m = self.app.model
        return (m.version, tuple(m.selection), m.rho if self.show_cut else None, self.show_cut, self.view, self.size, self.zoom)

    def png(self) -> bytes:
        """The current picture (re-rendered only when something changed)."""
        key = self.key()
        if self._png is None or self._png[0] != key:
            self._png = (key, plant_png(self.app.model, self.size, self.view, self.show_cut, self.zoom))
        return self._png[1]

    def zoom_to(self, bounds: Sequence[float] | None) -> None:
        """Frame the box ``bounds`` (a fruit), or the whole plant again (None)."""
        self.zoom = None if bounds is None else tuple(float(v) for v in bounds)
        if self.trame is not None:
            self.trame.zoom_to(self.zoom)
        self.refresh()

    def refresh(self) -> None:
        """Redraw after a change of plant, selection, camera side or cut preview."""
        key = self.key()
        if key == self._shown:
            return
        self._shown = key
        if self.trame is not None:
            self.trame.draw()
        else:
            self.image.value = self.png()


CLICK_PIXELS = 4  # a left press and release closer than this (in pixels) is a click, else a drag


class ClickPicker:
    """Select on click, rotate on drag: ``on_cell(cell_id)`` is called when the left button goes
    down and up at (nearly) the same place over the plant.  A press alone picks nothing, so a
    drag that starts on a branch rotates the view and leaves the selection as it was."""

    def __init__(self, plotter: pv.Plotter, on_cell: Callable[[int], object], actor: Any = None) -> None:
        from vtkmodules.vtkRenderingCore import vtkCellPicker  # not ``import vtk``: every VTK module, ~60 MB

        self.plotter = plotter
        self.on_cell = on_cell
        self.actor = actor  # pick only this actor's cells (None: any)
        self.down = None
        self.picker = vtkCellPicker()
        self.picker.SetTolerance(0.004)
        iren = plotter.iren
        assert iren is not None, "an on-screen or notebook plotter has an interactor"
        self.iren = iren
        iren.add_observer("LeftButtonPressEvent", self._press)
        # a desktop interactor reports the release; trame's remote view ends the gesture with
        # EndInteractionEvent (no release event reaches the interactor): either one closes it
        iren.add_observer("LeftButtonReleaseEvent", self._release)
        iren.add_observer("EndInteractionEvent", self._release)

    def _press(self, _caller, _event) -> None:
        self.down = self.iren.interactor.GetEventPosition()

    def _release(self, _caller, _event) -> None:  # the caller is the interactor or its style
        down, self.down = self.down, None
        x, y = self.iren.interactor.GetEventPosition()
        if down is None or max(abs(x - down[0]), abs(y - down[1])) > CLICK_PIXELS:
            return  # a drag: the interactor style rotated the view
        cell = self.pick(x, y)
        if cell is not None:
            self.on_cell(cell)

    def pick(self, x: int, y: int) -> int | None:
        """The plant cell under display position (x, y), or None."""
        if not self.picker.Pick(x, y, 0, self.plotter.renderer):
            return None
        if self.actor is not None and self.picker.GetActor() is not self.actor:
            return None
        cell = int(self.picker.GetCellId())
        return cell if cell >= 0 else None


class RectanglePicker:
    """Rectangle mode of the interactive view: a left drag draws a rubber band and, on release,
    ``on_rectangle((x0, y0, x1, y1))`` gets its display corners (pixels, origin bottom left, as
    VTK counts); the camera stays still.  A press and release without moving is a click:
    ``on_click(x, y)``.  Off (the default), the view turns on drag as usual.

    Its observers run before the camera's interactor style and stop the left button's events
    there (VTK's abort flag), for the interactor of a desktop window and for trame's remote
    view alike (trame hands the browser's mouse events to the same interactor)."""

    EVENTS = ("LeftButtonPressEvent", "MouseMoveEvent", "LeftButtonReleaseEvent")

    def __init__(
        self,
        plotter: pv.Plotter,
        on_rectangle: Callable[[tuple[int, int, int, int]], object],
        on_click: Callable[[int, int], object],
        on_band: Callable[[], object] | None = None,
    ) -> None:
        assert plotter.iren is not None, "an on-screen or notebook plotter has an interactor"
        self.plotter = plotter
        self.interactor = plotter.iren.interactor
        self.on_rectangle, self.on_click = on_rectangle, on_click
        self.on_band = on_band or plotter.render  # show the band as it moves (trame: send a new picture)
        self.tags: dict[str, int] = {}
        self.start: tuple[int, int] | None = None
        self.band = _band_actor()
        self.band.VisibilityOff()
        plotter.renderer.AddViewProp(self.band)

    @property
    def enabled(self) -> bool:
        """Whether the rubber band listens to the mouse."""
        return bool(self.tags)

    def enable(self, on: bool) -> None:
        """Start (``on``) or stop listening to the mouse for a rubber band; stopping hides a band half drawn."""
        if on == self.enabled:
            return
        if on:
            handlers = (self._press, self._move, self._release)
            self.tags = {e: self.interactor.AddObserver(e, h, 100.0) for e, h in zip(self.EVENTS, handlers)}
        else:
            for tag in self.tags.values():
                self.interactor.RemoveObserver(tag)
            self.tags, self.start = {}, None
            self.band.VisibilityOff()

    def _swallow(self, event: str) -> None:
        """Stop ``event`` here: the interactor style (the camera) does not see it."""
        self.interactor.GetCommand(self.tags[event]).SetAbortFlag(1)

    def _press(self, _caller, event) -> None:
        self._swallow(event)
        self.start = tuple(self.interactor.GetEventPosition())

    def _move(self, _caller, event) -> None:
        if self.start is None:
            return  # the pointer passes over the view: nothing to do
        self._swallow(event)
        _place_band(self.band, self.start, self.interactor.GetEventPosition())
        self.band.VisibilityOn()
        self.on_band()

    def _release(self, _caller, event) -> None:
        self._swallow(event)
        start, self.start = self.start, None
        self.band.VisibilityOff()
        if start is None:
            return
        x, y = self.interactor.GetEventPosition()
        if max(abs(x - start[0]), abs(y - start[1])) <= CLICK_PIXELS:
            self.on_click(x, y)
        else:
            self.on_rectangle((start[0], start[1], x, y))


def _band_actor() -> Any:
    """A red outline in display coordinates (its four corners set by :func:`_place_band`)."""
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkRenderingCore import vtkActor2D, vtkPolyDataMapper2D

    points = vtkPoints()
    points.SetNumberOfPoints(4)
    outline = vtkCellArray()
    outline.InsertNextCell(5, [0, 1, 2, 3, 0])
    data = vtkPolyData()
    data.SetPoints(points)
    data.SetLines(outline)
    mapper = vtkPolyDataMapper2D()
    mapper.SetInputData(data)
    actor = vtkActor2D()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(0.85, 0.0, 0.0)
    actor.GetProperty().SetLineWidth(1.5)
    return actor


def _place_band(actor: Any, start: Sequence[int], end: Sequence[int]) -> None:
    data = actor.GetMapper().GetInput()
    (x0, y0), (x1, y1) = start, end
    for k, (x, y) in enumerate(((x0, y0), (x1, y0), (x1, y1), (x0, y1))):
        data.GetPoints().SetPoint(k, x, y, 0.0)
    data.GetPoints().Modified()


_ABSENT = object()


@contextlib.contextmanager
def without_vtklocal() -> Iterator[None]:
    """Hide ``trame.widgets.vtklocal`` while pyvista starts its trame server.

    ``trame_pyvista.launch_server`` initialises trame-vtklocal whenever it is importable, and
    that downloads VTK's WebAssembly bundle from the internet (a 60-line traceback offline).
    Ramure's view renders on the server (where picking works) and never uses it, and Ramure
    never reaches the network on its own: for the duration of the launch the module cannot be
    imported, which pyvista treats as "not installed".
    """
    import trame.widgets as trame_widgets

    name = "trame.widgets.vtklocal"
    module, attribute = sys.modules.get(name, _ABSENT), trame_widgets.__dict__.pop("vtklocal", _ABSENT)
    sys.modules[name] = None  # type: ignore[assignment]  # None makes an import of it raise ImportError
    try:
        yield
    finally:
        if module is _ABSENT:
            sys.modules.pop(name, None)
        else:
            sys.modules[name] = module  # type: ignore[assignment]  # the module saved above
        if attribute is not _ABSENT:
            trame_widgets.vtklocal = attribute


def needs_reframe(framed: Sequence[float] | None, bounds: Sequence[float], margin: float = 0.02, shrink: float = 0.5) -> bool:
    """True when ``bounds`` (a plant's, after an edit) leave the ``framed`` bounds (grown past
    them by more than ``margin`` of their size) or shrink below ``shrink`` of their size.

    >>> needs_reframe((0, 1, 0, 1, 0, 4), (0, 1, 0, 1, 0, 4.05)), needs_reframe((0, 1, 0, 1, 0, 4), (0, 1, 0, 1, 0, 5))
    (False, True)
    """
    if framed is None:
        return True
    old, new = np.reshape(framed, (3, 2)), np.reshape(bounds, (3, 2))
    size = float(np.ptp(old, axis=1).max()) or 1.0
    grew = np.any(new[:, 0] < old[:, 0] - margin * size) or np.any(new[:, 1] > old[:, 1] + margin * size)
    return bool(grew or float(np.ptp(new, axis=1).max()) < shrink * size)


#: ``RAMURE_TRAME_PROXY``: ``1`` sends the trame view through Jupyter's own port (jupyter-server-proxy's
#: ``/proxy/PORT/``), ``0`` lets the browser reach trame's port directly; unset, the proxy is used
#: whenever jupyter-server-proxy is importable (see :func:`trame_proxy`).
PROXY_SWITCH = "RAMURE_TRAME_PROXY"


def trame_proxy() -> dict[str, Any]:
    """How the browser reaches the trame view: pyvista's ``server_proxy_enabled`` and
    ``server_proxy_prefix`` for :meth:`pyvista.Plotter.show`.

    Through the proxy the view's frame loads from ``PREFIX PORT/index.html`` on the Jupyter
    server itself (``/proxy/PORT/``; on JupyterHub pyvista puts the user's service prefix in
    front, from ``JUPYTERHUB_SERVICE_PREFIX``), so it works wherever the notebook does: on a
    hub, or through an SSH tunnel that forwards Jupyter's port only.  Without it the frame asks
    for ``http://localhost:PORT``, a port the browser reaches only on the kernel's machine.

    Chosen by :data:`PROXY_SWITCH` (``1``/``0``), else by pyvista when it was told
    (``PYVISTA_TRAME_JUPYTER_MODE``, ``PYVISTA_TRAME_SERVER_PROXY_PREFIX``, a hub), else on
    whenever ``jupyter_server_proxy`` is importable.  The prefix is always pyvista's.
    """
    import pyvista as pv

    theme = pv.global_theme.trame
    switch = os.environ.get(PROXY_SWITCH, "").strip().lower()
    if switch in ("1", "on", "yes", "true"):
        enabled = True
    elif switch in ("0", "off", "no", "false"):
        enabled = False
    elif theme.server_proxy_enabled or theme.jupyter_extension_enabled or os.environ.get("PYVISTA_TRAME_JUPYTER_MODE"):
        enabled = bool(theme.server_proxy_enabled)  # pyvista was told: its choice
    else:
        enabled = importlib.util.find_spec("jupyter_server_proxy") is not None
    return {"server_proxy_enabled": enabled, "server_proxy_prefix": theme.server_proxy_prefix}


def trame_window(size: tuple[int, int]) -> tuple[int, int]:
    """The trame view's window (and so its iframe's) size for an explorer ``size``: the toolbar
    band above a picture of that size, so the plant's top is not under the menu.

    >>> trame_window((480, 480))
    (480, 544)
    """
    return int(size[0]), int(size[1]) + TOOLBAR_BAND


class TrameView:
    """pyvista's trame view of the plant (needs ``trame-pyvista``): rotate on drag, select on click,
    re-framed when the camera side is chosen or an edit grows the plant out of the picture.

    Every call into it happens on the kernel's main thread, where the trame server renders
    (:mod:`ramure.app.jupyter.mainthread`)."""

    def __init__(self, owner: PlantView, mode: str = "trame") -> None:
        headless_setup()
        import pyvista as pv

        self.owner = owner
        self.plotter = pv.Plotter(notebook=True, window_size=list(trame_window(owner.size)))
        self.plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        self._actor: pv.Actor | None = None
        self._view: str | None = None
        self._framed: tuple[float, ...] | None = None
        self.draw(update=False)
        self.clicks = ClickPicker(self.plotter, self._picked)
        self.rectangle = RectanglePicker(self.plotter, self._rectangle, self._click_at, self._push)
        self.last_rectangle: tuple[int, int, int, int] | None = None
        with without_vtklocal():
            self.widget = self.plotter.show(jupyter_backend=mode, return_viewer=True, jupyter_kwargs=trame_proxy())

    def draw(self, update: bool = True) -> None:
        """Draw the model's plant with the view's colours, on the same actor when there is one (new arrays, no
        new GL objects), framing the camera when the view direction changed; ``update`` pushes the
        frame to the browser.
        """
        model = self.owner.app.model
        mesh = model.mesh.copy(deep=False)
        mesh.cell_data["rgb"] = view_colors(model, self.owner.show_cut)
        shown = getattr(self, "_mesh", None)
        if self._actor is not None and shown is not None:  # same actor, new arrays (no new GL objects)
            shown.copy_from(mesh, deep=False)
            shown.cell_data.active_scalars_name = "rgb"
        else:
            self._mesh = mesh
            self._actor = self.plotter.add_mesh(mesh, scalars="rgb", rgb=True, name="plant", reset_camera=False)
        if self._view != self.owner.view:
            frame_camera(self.plotter, model.mesh.bounds, self.owner.view)
            self._frame(model.mesh)
            self._view = self.owner.view
        elif model.mesh.n_cells and needs_reframe(self._framed, model.mesh.bounds):
            self.reframe(model.mesh)
        if update:
            self._push()

    def _push(self) -> None:
        """Render, and send the picture to the browser (trame's viewer) when there is one."""
        viewer = getattr(getattr(self, "widget", None), "viewer", None)
        if viewer is not None:
            viewer.update()
        else:
            self.plotter.render()

    def reframe(self, mesh: pv.PolyData) -> None:
        """Frame the whole plant again, looking from where the camera looks now (z up)."""
        cam = self.plotter.camera
        direction = np.subtract(cam.position, cam.focal_point)
        direction = direction / (np.linalg.norm(direction) or 1.0)
        b = np.reshape(mesh.bounds, (3, 2))
        centre, size = b.mean(axis=1), float(np.ptp(b, axis=1).max()) or 1.0
        self.plotter.camera_position = [tuple(centre + direction * size * 2.2), tuple(centre), (0.0, 0.0, 1.0)]
        self.plotter.reset_camera(bounds=tuple(b.ravel()))  # type: ignore[call-arg]  # pyvista stubs: decorated method
        self._frame(mesh)

    def zoom_to(self, bounds: Sequence[float] | None) -> None:
        """Frame ``bounds`` from where the camera looks now (None: the whole plant again)."""
        model = self.owner.app.model
        if bounds is None:
            self.reframe(model.mesh)
        else:
            frame_camera(self.plotter, tuple(bounds), self.owner.view)
            fit_view(self.plotter, _corners(bounds), 0.9, top=TOOLBAR_BAND / self.plotter.window_size[1])
        self._push()

    def _frame(self, mesh) -> None:
        if mesh.n_cells:
            fit_view(self.plotter, mesh.points, 0.9, top=TOOLBAR_BAND / self.plotter.window_size[1])
            self._framed = tuple(mesh.bounds)

    def _picked(self, cell) -> None:
        self.owner.app.pick(cell)

    def _click_at(self, x: int, y: int) -> None:
        cell = self.clicks.pick(x, y)
        if cell is not None:
            self._picked(cell)

    def camera(self) -> tuple[np.ndarray, tuple[int, int]]:
        """The camera's world-to-clip projection and the view's size in pixels (what a rubber
        band's display rectangle is measured against)."""
        from ramure.app.render import projection_matrix

        width, height = self.plotter.window_size
        return projection_matrix(self.plotter.renderer), (int(width), int(height))

    def _rectangle(self, rect) -> None:
        self.last_rectangle = rect  # display corners of the last band (what a test compares)
        self.owner.app.select_rectangle(rect)
