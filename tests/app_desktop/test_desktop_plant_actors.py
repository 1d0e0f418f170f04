"""The plant drawn by thickness groups: sub-pixel tubes left to the hairlines, the same picture,
picking and colours on the whole mesh, a regrow rebuilding only what is drawn."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.desktop.view import plant_actors
from ramure.app.desktop.view.plant_actors import tube_layout
from desktop_helpers import HONDA, settle

pytestmark = pytest.mark.gui


def image_array(qimage):
    qimage = qimage.convertToFormat(qimage.Format.Format_RGB888)
    w, h = qimage.width(), qimage.height()
    return np.frombuffer(qimage.constBits(), np.uint8).reshape(h, qimage.bytesPerLine())[:, : 3 * w].reshape(h, w, 3)


def group_cells(plant, g):
    """Full-mesh cell ids of group ``g``."""
    if g.segments is None:
        return np.arange(plant.mesh.n_cells - g.count, plant.mesh.n_cells)
    return (g.segments[:, None] * plant.sides + np.arange(plant.sides)).ravel()


def test_tube_layout_is_recognised_and_other_meshes_are_drawn_whole():
    import pyvista as pv
    from ramure.app.model import Explorer

    ex = Explorer(str(HONDA), n=6)
    assert tube_layout(ex.mesh, len(ex.skeleton)) == ex.mesh.n_cells // len(ex.skeleton)
    assert tube_layout(ex.mesh, len(ex.skeleton) + 1) == 0
    assert tube_layout(pv.Sphere(), 10) == 0


def test_groups_partition_the_mesh_and_carry_its_colours(make_window, qtbot):
    w = make_window(n=14)
    plant = w.view.plant
    mesh = w.view.mesh
    assert plant.sides >= 3 and len(plant.groups) >= 3
    cells = np.concatenate([group_cells(plant, g) for g in plant.groups])
    assert len(cells) == mesh.n_cells and len(np.unique(cells)) == mesh.n_cells  # each cell once
    sk = w.controller.snapshot.skeleton
    radius = np.maximum(np.asarray(sk.base_radius), np.asarray(sk.top_radius))
    for g in plant.groups:  # a class spans at most a factor 2 (the last one: everything thinner)
        r = radius[g.segments]
        assert r.max() == pytest.approx(g.radius)
        assert g is plant.groups[-1] or r.min() >= g.radius / 2 - 1e-12
    # Selection colours: every group, once drawn, shows the mesh's own rgb for its cells.
    snap = w.controller.snapshot
    w.controller.select([int(snap.segment_leaf[-1]), int(snap.segment_leaf[0])])
    settle(qtbot, w)
    for g in plant.groups:
        plant._refresh(g)  # what a frame does for a group it draws
        rgb = np.asarray(g.poly.cell_data["rgb"])
        assert (rgb == np.asarray(mesh.cell_data["rgb"])[group_cells(plant, g)]).all()
        pts = np.asarray(g.poly.points).reshape(-1, 3)
        if g.segments is not None:
            full = np.asarray(mesh.points)[: len(snap.skeleton) * 2 * plant.sides].reshape(-1, 2 * plant.sides, 3)
            assert np.array_equal(pts.reshape(-1, 2 * plant.sides, 3), full[g.segments])


def test_thin_tubes_are_left_to_the_hairlines_until_the_camera_comes_close(make_window, qtbot, artifacts):
    w = make_window(n=14)
    view, plant = w.view, w.view.plant
    view.redraw(now=True)
    drawn = plant.drawn()
    assert 0 < len(drawn) < len(plant.groups)  # the thickest drawn, the thinnest not
    assert plant.groups[drawn[0]].radius == max(g.radius for g in plant.groups)
    lod = image_array(view.grab_image()).astype(int)
    # The same frame with every tube drawn: the picture is the same but for a few pixels.
    saved = plant_actors.MIN_PIXELS
    plant_actors.MIN_PIXELS = 0.0
    try:
        full = image_array(view.grab_image()).astype(int)
        assert plant.drawn() == list(range(len(plant.groups)))
    finally:
        plant_actors.MIN_PIXELS = saved
    changed = (np.abs(lod - full).max(axis=2) > 40).mean()
    assert lod.std() > 5 and changed < 0.01, changed
    # Closer: a thinner class is drawn too (full tubes near).
    camera = view.plotter.renderer.GetActiveCamera()
    thin = plant.groups[-1]
    centre = thin.corners.mean(axis=0)
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*(centre + np.array([0.0, -1.0, 0.0]) * thin.radius * 50))
    view.plotter.renderer.ResetCameraClippingRange()
    view.redraw(now=True)
    assert len(plant.drawn()) > len(drawn) and plant.groups.index(thin) in plant.drawn()


def test_a_click_picks_a_cell_of_the_whole_mesh_even_where_no_tube_is_drawn(make_window, qtbot):
    w = make_window(n=14)
    view, plant = w.view, w.view.plant
    view.redraw(now=True)
    hidden = [g for i, g in enumerate(plant.groups) if i not in plant.drawn() and g.segments is not None]
    assert hidden
    sk = w.controller.snapshot.skeleton
    mid = (np.asarray(sk.start) + np.asarray(sk.end)) / 2
    hits = 0
    for seg in hidden[0].segments[:: max(len(hidden[0].segments) // 40, 1)]:
        x, y = view.project(mid[seg][None])[0]
        cell = view.pick(x, y)
        if cell >= 0:
            hits += 1
            assert 0 <= cell < view.mesh.n_cells
    assert hits > 0  # thin twigs stay clickable: the picker sees the whole mesh
    thick = plant.groups[0].segments[0]
    x, y = view.project(mid[thick][None])[0]
    cell = view.pick(x, y)
    assert cell >= 0 and int(view.mesh.cell_data["segment"][cell]) >= 0


def test_while_the_camera_moves_a_large_plant_draws_within_the_budget(make_window, qtbot, monkeypatch):
    w = make_window(n=14)
    plant = w.view.plant
    monkeypatch.setattr(plant_actors, "MOTION_CELLS", plant.groups[0].count + plant.groups[1].count)
    plant.large = True
    saved = plant_actors.MIN_PIXELS
    plant_actors.MIN_PIXELS = 0.0  # everything would be drawn
    try:
        plant.set_moving(True)
        w.view.redraw(now=True)
        assert plant.drawn() == [0, 1]
        plant.set_moving(False)
        w.view.redraw(now=True)
        assert plant.drawn() == list(range(len(plant.groups)))
    finally:
        plant_actors.MIN_PIXELS = saved


def test_a_regrow_rebuilds_only_the_drawn_groups(make_window, qtbot):
    w = make_window(n=14)
    plant = w.view.plant
    snap = w.controller.snapshot
    w.controller.select([int(v) for v in snap.segment_leaf[len(snap.segment_leaf) // 2 :][:5]])
    settle(qtbot, w)
    w.controller.regrow(seed=3)
    settle(qtbot, w)
    drawn = set(plant.drawn())
    for i, g in enumerate(plant.groups):
        assert g.stale_geometry == (i not in drawn)  # hidden groups wait for the camera
    assert w.view.mesh.n_cells == w.controller.snapshot.mesh.n_cells
