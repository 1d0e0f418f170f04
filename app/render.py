"""Off-screen rendering of plants to PNG (pyvista), shared by the CLI and thumbnails.

With no X display VTK renders through EGL; we select that window class up
front so no "bad X server connection" warning is printed.
"""

from __future__ import annotations

import os
from collections.abc import Collection
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.io import write_with

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.lsys.interpretation.turtle import Skeleton

BARK = (0.45, 0.32, 0.2)
LEAF = (0.3, 0.62, 0.22)
FRUIT_RGB = (240, 120, 40)  # orange, so red always means "selected"
FRUIT = tuple(c / 255 for c in FRUIT_RGB)
SELECTED = (1.0, 0.0, 0.0)


def headless_setup() -> None:
    """Off-screen rendering without a display: ask VTK for an EGL window (no X needed).

    Also tells pyvista plotting is allowed: its first ``Plotter`` otherwise probes the
    system (runs ``xset -q``, then opens and renders a test window, about 0.1-0.3 s)
    only to decide whether to warn that no X server runs, a warning that never fires
    here (a display is set, or VTK was just asked for EGL)."""
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    os.environ.setdefault("ALLOW_PLOTTING", "true")


def plant_colors(mesh: pv.DataSet, selected: Collection[int] = ()) -> np.ndarray:
    """RGB per cell: bark, leaf or fruit by ``kind``, or the colour of the cell's ``material`` when
    the grammar's ``#material`` table has it; selected leaves in red."""
    kind = np.asarray(mesh.cell_data["kind"])
    rgb = np.empty((mesh.n_cells, 3))
    rgb[:] = BARK
    rgb[kind == 1] = LEAF
    rgb[kind >= 2] = FRUIT
    if "material" in mesh.cell_data and "material_rgb" in mesh.field_data:
        material = np.asarray(mesh.cell_data["material"])
        for row in np.atleast_2d(np.asarray(mesh.field_data["material_rgb"], float)):
            rgb[material == int(row[0])] = row[1:4]
    if len(selected):
        rgb[np.isin(mesh.cell_data["leaf_id"], np.asarray(list(selected)))] = SELECTED
    return (rgb * 255).astype(np.uint8)


def frame_camera(plotter: pv.BasePlotter, bounds: ArrayLike, view: str = "front") -> None:
    """Frame the camera on ``bounds`` (xmin, xmax, ymin, ymax, zmin, zmax), z up."""
    b = np.asarray(bounds, float).reshape(3, 2)
    center = b.mean(axis=1)
    size = float(np.max(b[:, 1] - b[:, 0])) or 1.0
    direction = {"front": (0.0, -1.0, 0.15), "side": (1.0, 0.0, 0.15), "top": (0.0, -0.05, 1.0), "iso": (0.7, -0.7, 0.45)}[view]
    d = np.asarray(direction) / np.linalg.norm(direction)
    plotter.camera_position = [tuple(center + d * size * 2.2), tuple(center), (0.0, 0.0, 1.0)]
    plotter.reset_camera(bounds=tuple(b.ravel()))  # type: ignore[call-arg]  # pyvista stubs: decorated method


def projection_matrix(renderer: Any) -> np.ndarray:
    """The 4x4 matrix from world to clip coordinates of ``renderer``'s camera (VTK's composite
    projection for the renderer's aspect ratio)."""
    m = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1, 1)
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])


def render_mesh(
    mesh: pv.PolyData,
    path: str | os.PathLike,
    size: tuple[int, int] = (800, 800),
    selected: Collection[int] = (),
    view: str = "front",
    background: str = "white",
    title: str | None = None,
) -> str | os.PathLike:
    """Render a plant mesh (cell data ``kind``/``leaf_id``) to a PNG file; returns the path."""
    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background(background)  # type: ignore[arg-type]  # pyvista stubs: decorated method
    if mesh.n_cells:
        mesh = mesh.copy(deep=False)
        mesh.cell_data["rgb"] = plant_colors(mesh, selected)
        plotter.add_mesh(mesh, scalars="rgb", rgb=True, smooth_shading=False)
        frame_camera(plotter, mesh.bounds, view)
    if title:
        plotter.add_text(title, font_size=10, color="black")
    write_with(path, lambda tmp: plotter.screenshot(tmp))
    plotter.close()
    return path


def render_plant(skeleton: Skeleton, path: str | os.PathLike, **kwargs: Any) -> str | os.PathLike:
    """Render a :class:`ramure.lsys.Skeleton` to PNG."""
    return render_mesh(skeleton.to_polydata(), path, **kwargs)
