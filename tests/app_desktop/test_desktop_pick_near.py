"""Picking from the cells near the pick ray: the same cells as a picker over the whole mesh,
without that mesh's cell locator (its cell bounds and bins: 28 MB at 393k cells)."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.desktop import state
from ramure.app.desktop.view import plant_view as view_module
from desktop_helpers import HONDA, settle

pytestmark = pytest.mark.gui


def whole_mesh_pick(view, x, y):
    """What the view's picker answered before: a vtkCellPicker with a locator over the whole mesh."""
    from vtkmodules.vtkRenderingCore import vtkCellPicker

    picker = vtkCellPicker()
    picker.SetTolerance(view_module.PICK_TOLERANCE)
    picker.PickFromListOn()
    picker.AddPickList(view.actor)
    picker.AddLocator(view_module._locator(view.mesh))
    if not picker.Pick(float(x), float(y), 0.0, view.plotter.renderer):
        return -1
    return int(picker.GetCellId())


def clicks(view, snap, rng, count=120):
    """Display points on and near segment midpoints, and anywhere in the view."""
    w, h = view.display_size()
    xy = view.project(snap.midpoints[rng.integers(0, len(snap.midpoints), count)])
    xy = np.r_[xy + rng.normal(0, 2, xy.shape), rng.random((count // 4, 2)) * [w, h]]
    return xy[(xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)]


@pytest.mark.parametrize("zoom", [1.0, 6.0])
def test_a_pick_finds_the_whole_mesh_pickers_cell_without_its_locator(make_window, qtbot, zoom):
    w = make_window(n=14)
    view = w.view
    view.reset_camera()
    view.plotter.renderer.GetActiveCamera().Zoom(zoom)
    view.redraw(now=True)
    rng = np.random.default_rng(7)
    points = clicks(view, w.controller.snapshot, rng)
    picked = [view.pick(x, y) for x, y in points]
    assert picked == [whole_mesh_pick(view, x, y) for x, y in points]
    assert sum(c >= 0 for c in picked) > len(points) // 2  # most clicks hit a branch
    # no locator over the plant's mesh: only the cells near the last ray have one
    view.pick(*points[picked.index(max(picked))])
    assert not view._locators
    assert 0 < view._near.locator.GetDataSet().GetNumberOfCells() < view.mesh.n_cells // 10


def test_a_mesh_whose_box_the_near_locator_cannot_share_is_picked_whole(make_window, qtbot, monkeypatch):
    """Where :func:`_near_bins` gives no bins (a flat side, other cells, cells hidden), the
    plant's mesh gets its own whole locator, made once for its points: the same cells."""
    w = make_window(n=12)
    view = w.view
    rng = np.random.default_rng(5)
    points = clicks(view, w.controller.snapshot, rng, 60)
    near = [view.pick(x, y) for x, y in points]
    monkeypatch.setattr(view_module, "_near_bins", lambda mesh: None)
    made = []
    real = view_module._locator
    monkeypatch.setattr(view_module, "_locator", lambda *a: made.append(1) or real(*a))
    whole = [view.pick(x, y) for x, y in points]
    assert whole == near == [whole_mesh_pick(view, x, y) for x, y in points]
    assert sum(c >= 0 for c in whole) > len(points) // 2
    assert len(view._locators) == 1 and len(made) == 1 + len(points)  # the view's one, then the reference's
    # hidden cells (a whole tube: its own points collapse): a new whole locator, and they are
    # not picked
    cell = next(c for c in whole if c >= 0)
    segment = np.asarray(view.mesh.cell_data["segment"])
    hidden = segment == segment[cell]
    view.set_hidden_cells(hidden)
    x, y = points[whole.index(cell)]
    assert view.pick(x, y) != cell and view.pick(x, y) == whole_mesh_pick(view, x, y)
    assert len(view._locators) == 1


def test_fruit_plants_pick_their_organs_and_volumetric_fruit_as_before(make_window, qtbot):
    from ramure.app.desktop.state import fruit_surface

    w = make_window(HONDA.parent / "fruit_tree.lsys", n=6)
    view = w.view
    view.set_fruit(fruit_surface(w.controller.explorer))
    settle(qtbot, w)
    rng = np.random.default_rng(3)
    points = clicks(view, w.controller.snapshot, rng, 80)
    organs = w.controller.snapshot.organ_points
    points = np.r_[points, view.project(organs[:: max(len(organs) // 40, 1)])]
    for x, y in points:
        kind, cell = view.pick_any(x, y)
        if kind == "fruit":
            continue  # the fruit's own locator, as before
        assert cell == whole_mesh_pick(view, x, y)


def test_cells_near_line_hold_every_cell_the_line_passes_within_reach():
    rng = np.random.default_rng(0)
    centres = rng.random((300, 3)) * 10
    tri = centres[:, None, :] + rng.normal(0, 0.3, (300, 3, 3))
    points = tri.reshape(-1, 3)
    offsets, conn = np.arange(0, 901, 3), np.arange(900)
    origin, direction, reach = np.array([5.0, 5.0, -5.0]), np.array([0.1, -0.05, 1.0]), 0.4
    near = state.cells_near_line(points, offsets, conn, origin, direction, reach)
    # brute force: distance from the line to points sampled densely on each triangle
    u = direction / np.linalg.norm(direction)
    a, b = rng.random((2, 400, 1, 1))
    flip = a + b > 1
    a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
    samples = tri[None, :, 0] + a * (tri[None, :, 1] - tri[None, :, 0]) + b * (tri[None, :, 2] - tri[None, :, 0])
    rel = samples - origin
    dist = np.linalg.norm(rel - (rel @ u)[..., None] * u, axis=-1).min(axis=0)
    assert set(np.flatnonzero(dist <= reach)) <= set(near.tolist())
    assert len(near) < 300  # and not everything


def test_tube_layout_and_polygon_reading_find_the_same_cells():
    from ramure.app.model import Explorer
    from ramure.app.desktop.view.plant_actors import tube_layout
    from vtkmodules.util.numpy_support import vtk_to_numpy

    ex = Explorer(str(HONDA), n=10)
    mesh, count = ex.mesh, len(ex.skeleton)
    sides = tube_layout(mesh, count)
    polys = mesh.GetPolys()
    offsets, conn = vtk_to_numpy(polys.GetOffsetsArray()), vtk_to_numpy(polys.GetConnectivityArray())
    points = np.asarray(mesh.points)
    line = (np.asarray(mesh.center), np.array([0.3, -1.0, 0.2]), 0.05)
    as_polygons = state.cells_near_line(points, offsets, conn, *line)
    as_tubes = state.cells_near_line(points, offsets, conn, *line, tubes=(count, sides))
    assert len(as_polygons) and set(as_polygons.tolist()) <= set(as_tubes.tolist())
    sub_offsets, sub_conn = state.cell_subset(offsets, conn, as_tubes)
    again = np.split(sub_conn, sub_offsets[1:-1])
    assert all((conn[offsets[c] : offsets[c + 1]] == cell).all() for c, cell in zip(as_tubes, again))
