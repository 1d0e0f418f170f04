"""The Details dock: the season slider recolours leaves; lichen and cracks on the selected fruit."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from PySide6.QtCore import Qt

from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui
FRUIT_TREE = ROOT / "grammars" / "fruit_tree.lsys"


@pytest.fixture
def window(make_window):
    win = make_window(FRUIT_TREE, n=5)
    win.docks["details"].show()
    win.docks["details"].raise_()
    return win


def _panel(window):
    return window.docks["details"].widget()


def _wait(qtbot, window, panel, text):
    settle(qtbot, window)
    qtbot.waitUntil(lambda: text in panel.season_label.text() or text in panel.fruit_label.text(), timeout=20000)


def test_the_season_slider_paints_leaves_in_their_state_colours_and_grounds_fallen_ones(qtbot, window):
    from ramure.lsys.architecture.seasons import age_leaves, autumn_chain

    panel = _panel(window)
    panel.slider.setFocus()
    qtbot.keyClick(panel.slider, Qt.Key.Key_End)  # the last step, as a user would
    _wait(qtbot, window, panel, "Step 24/24")
    mesh = window.view.mesh
    expected = age_leaves(
        window.controller.explorer.skeleton.organs, autumn_chain(), steps=24, seed=0, heat=0.5, humidity=0.5, wind=0.0
    )
    rgb = np.asarray(mesh.cell_data["rgb"])
    ids, kind = np.asarray(mesh.cell_data["leaf_id"]), np.asarray(mesh.cell_data["kind"])
    chain = autumn_chain()
    attached = fallen = 0
    for leaf, st, down in zip(expected.leaf_ids, expected.states[-1], expected.fallen):
        cells = np.flatnonzero((ids == leaf) & (kind == 1))
        assert len(cells)
        want = (211, 219, 226) if down else tuple(np.round(chain.colors[st] * 255).astype(int))
        assert (rgb[cells] == want).all(), (leaf, st, down)
        attached, fallen = attached + (not down), fallen + bool(down)
    assert fallen == int(expected.fallen.sum()) and 0 < fallen < len(expected.leaf_ids)
    assert f"{len(expected.leaf_ids)} leaves, {fallen} fallen" in panel.season_label.text()
    # the fallen leaves lie on the ground as discs, one per leaf
    assert panel.fallen_actor is not None
    # and are gone from the branches: their cells have no area left, attached leaves and bark keep theirs
    area = np.asarray(mesh.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
    down_ids = expected.leaf_ids[expected.fallen]
    gone = np.isin(ids, down_ids) & (kind == 1)
    assert gone.any() and np.abs(area[gone]).max() < 1e-12
    kept = np.isin(ids, expected.leaf_ids[~expected.fallen]) & (kind == 1)
    assert (area[kept] > 0).mean() > 0.99 and (area[kind == 0] > 0).mean() > 0.99
    assert window.view.hidden_cells is not None and int(window.view.hidden_cells.sum()) == int(gone.sum())
    # bark keeps its colour
    bark = np.flatnonzero(kind == 0)
    assert (rgb[bark] == rgb[bark[0]]).all()
    # back to step 0: the plant's own colours, no discs
    panel.slider.setValue(0)  # (Home is the window's "frame the plant" shortcut)
    settle(qtbot, window)
    assert panel.season_label.text().startswith("Step 0")
    from ramure.app.desktop.state import base_colors

    assert (np.asarray(window.view.mesh.cell_data["rgb"]) == base_colors(mesh)).all()
    assert panel.fallen_actor is None
    assert window.view.hidden_cells is None
    area = np.asarray(window.view.mesh.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
    assert (area[gone] > 0).mean() > 0.99  # the leaves are back


def test_heat_changes_the_season_and_wind_makes_more_leaves_fall(qtbot, window):
    panel = _panel(window)
    panel.slider.setValue(10)
    _wait(qtbot, window, panel, "Step 10/24")
    still = int(panel.season.fallen.sum())
    panel.wind.setValue(1.5)
    qtbot.waitUntil(lambda: panel.season is not None and panel.season_key[3] == 1.5, timeout=20000)
    _wait(qtbot, window, panel, "Step 10/24")
    assert int(panel.season.fallen.sum()) > still
    before = panel.season.states[10].copy()
    panel.heat.setValue(1.0)
    qtbot.waitUntil(lambda: panel.season_key[1] == 1.0, timeout=20000)
    assert not np.array_equal(before, panel.season.states[10])


def test_lichen_without_a_selected_fruit_is_refused_in_one_line(qtbot, window):
    panel = _panel(window)
    qtbot.mouseClick(panel.lichen_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Refused")
    assert "select a fruit first" in panel.fruit_label.text()
    assert panel.shown is None


def test_lichen_and_crack_on_the_selected_fruit(qtbot, window, artifacts):
    panel = _panel(window)
    fruit = window.controller.explorer.fruit_ids()[0]
    window.controller.select([fruit])
    panel.particles.setValue(200)
    panel.clusters.setValue(4)
    qtbot.mouseClick(panel.lichen_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "particles in")
    facts = panel.last_facts
    assert panel.shown == "lichen" and facts["clusters"] == 4 and facts["particles"] == 200
    assert "200 particles in 4 clusters" in panel.fruit_label.text()
    panel.plotter.render()
    image = panel.plotter.screenshot(return_img=True)
    assert image.reshape(-1, image.shape[-1]).std(axis=0).max() > 10  # not blank: a fruit with discs
    panel.plotter.screenshot(str(artifacts / "details-lichen.png"))

    qtbot.mouseClick(panel.crack_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Crack:")
    facts = panel.last_facts
    assert panel.shown == "crack" and facts["nodes"] == 15 and facts["watertight"]
    assert facts["triangles_result"] > facts["triangles_object"] and facts["volume_removed"] > 0
    panel.plotter.render()
    panel.plotter.screenshot(str(artifacts / "details-crack.png"))
    panel.slider.setValue(20)
    _wait(qtbot, window, panel, "Step 20/24")
    window.view.redraw(now=True)
    path = artifacts / "details-window.png"
    window.grab_window().save(str(path))
    assert path.stat().st_size > 10_000
    notes = ROOT.parent / "notes"
    if notes.is_dir():
        for name in ("details-window.png", "details-lichen.png", "details-crack.png"):
            shutil.copy(artifacts / name, notes / name)


def test_the_brush_paints_where_lichen_starts_and_a_click_places_the_crack(qtbot, window, artifacts):
    panel = _panel(window)
    fruit = window.controller.explorer.fruit_ids()[0]
    window.controller.select([fruit])
    panel.tool.setCurrentText("paint where lichen may start")
    assert panel.clicked_at((0.0, 0.0, 0.0)) is None and "show a fruit first" in panel.fruit_label.text()
    qtbot.mouseClick(panel.show_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Fruit:")
    points = np.asarray(panel.fruit.points)
    top = points[np.argmax(points[:, 2])]
    adhesion = panel.clicked_at(top + (0.0, 0.0, 0.001))  # a click just above the top vertex
    assert adhesion[np.argmax(points[:, 2])] == 1.0
    radius = 0.15 * np.linalg.norm(np.ptp(points, axis=0))
    far = np.linalg.norm(points - top, axis=1) >= radius
    assert far.any() and (adhesion[far] == 0).all() and 0 < (adhesion > 0).sum() < len(points)
    panel.particles.setValue(120)
    panel.clusters.setValue(2)
    qtbot.mouseClick(panel.lichen_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "particles in")
    assert panel.last_facts["painted"] and panel.last_facts["particles"] == 120
    panel.plotter.render()
    panel.plotter.screenshot(str(artifacts / "details-painted-lichen.png"))

    panel.tool.setCurrentText("place the crack")
    side = points[np.argmin(points[:, 0])]  # the fruit's -x side, not its top
    panel.clicked_at(side)
    _wait(qtbot, window, panel, "Crack:")
    assert panel.shown == "crack" and panel.last_facts["watertight"]
    panel.plotter.render()
    panel.plotter.screenshot(str(artifacts / "details-placed-crack.png"))
    carved = np.asarray(
        window.docks["details"].widget().plotter.renderer.actors["details_surface"].GetMapper().GetInput().GetPoints().GetData()
    )
    new = carved[np.linalg.norm(carved[:, None, :] - points[None, :, :], axis=2).min(axis=1) > 1e-6]
    assert len(new) and np.linalg.norm(new.mean(axis=0) - side) < np.linalg.norm(new.mean(axis=0) - top)
    notes = ROOT.parent / "notes"
    if notes.is_dir():
        for name in ("details-painted-lichen.png", "details-placed-crack.png"):
            shutil.copy(artifacts / name, notes / name)


def test_a_real_left_click_on_the_fruit_paints_it(qtbot, window):
    panel = _panel(window)
    window.controller.select([window.controller.explorer.fruit_ids()[0]])
    panel.tool.setCurrentText("paint where lichen may start")
    qtbot.mouseClick(panel.show_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Fruit:")
    widget = panel.plotter
    widget.render()
    centre = widget.rect().center()
    qtbot.mousePress(widget, Qt.MouseButton.LeftButton, pos=centre)
    qtbot.mouseRelease(widget, Qt.MouseButton.LeftButton, pos=centre)
    qtbot.waitUntil(lambda: panel.adhesion is not None, timeout=3000)
    assert 0 < (panel.adhesion > 0).sum() < panel.fruit.n_points
    assert "Painted" in panel.fruit_label.text()


def test_lichen_on_the_branches_grows_on_the_welded_bark(qtbot, window, artifacts):
    panel = _panel(window)
    panel.particles.setValue(300)
    panel.clusters.setValue(5)
    qtbot.mouseClick(panel.bark_button, Qt.MouseButton.LeftButton)  # no fruit needed
    _wait(qtbot, window, panel, "on the branches (")
    facts = panel.last_facts
    assert panel.shown == "bark" and facts["particles"] == 300 and facts["clusters"] == 5
    assert facts["triangles"] > 500 and 0 < facts["r"] < 0.05
    import pyvista as pv

    discs = pv.wrap(panel.plotter.actors["details_discs"].GetMapper().GetInput())
    bark = pv.wrap(panel.plotter.actors["details_surface"].GetMapper().GetInput())
    # every disc lies on the bark: its centre point is within a disc radius of the surface
    centres = discs.cell_centers().points
    _, closest = bark.find_closest_cell(centres, return_closest_point=True)
    assert np.linalg.norm(centres - closest, axis=1).max() < facts["r"]
    panel.plotter.render()
    image = panel.plotter.screenshot(return_img=True)
    assert image.reshape(-1, image.shape[-1]).std(axis=0).max() > 10
    panel.plotter.screenshot(str(artifacts / "details-bark-lichen.png"))


def test_lichen_and_a_crack_are_kept_in_the_session_undone_and_redone(qtbot, window):
    panel = _panel(window)
    ex = window.controller.explorer
    window.controller.select([ex.fruit_ids()[0]])
    settle(qtbot, window)
    panel.particles.setValue(150)
    panel.clusters.setValue(3)
    qtbot.mouseClick(panel.lichen_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "particles in")
    lichen = dict(panel.last_facts)
    qtbot.mouseClick(panel.crack_button, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Crack:")
    assert [d["kind"] for d in ex.session.details()] == ["lichen", "crack"]
    assert window.undo_action.isEnabled()
    window.undo_action.trigger()  # the window's own Undo: the crack goes, the lichen is shown again
    qtbot.waitUntil(lambda: panel.shown == "lichen", timeout=30000)
    settle(qtbot, window)
    assert panel.last_facts == lichen and [d["kind"] for d in ex.session.details()] == ["lichen"]
    window.undo_action.trigger()
    qtbot.waitUntil(lambda: panel.shown is None, timeout=30000)
    assert "undone" in panel.fruit_label.text() and ex.session.details() == []
    window.redo_action.trigger()
    qtbot.waitUntil(lambda: panel.shown == "lichen", timeout=30000)
    settle(qtbot, window)
    assert panel.last_facts == lichen


def _shot(panel, **visible):
    for name, on in visible.items():
        panel.plotter.actors[name].SetVisibility(on)
    panel.plotter.render()
    return panel.plotter.screenshot(return_img=True).astype(int)


def test_lichen_at_its_default_size_shows_in_the_dock(qtbot, window):
    """Issue 40 §7: at its default size, seen from a fixed corner, lichen covered a few pixels."""
    panel = _panel(window)
    window.controller.select([window.controller.explorer.fruit_ids()[0]])
    qtbot.mouseClick(panel.lichen_button, Qt.MouseButton.LeftButton)  # the dock's defaults
    _wait(qtbot, window, panel, "particles in")
    lichen = _shot(panel, details_surface=True, details_discs=True)
    fruit = _shot(panel, details_surface=True, details_discs=False)
    empty = _shot(panel, details_surface=False, details_discs=False)
    on_fruit = (fruit != empty).any(-1).sum()
    shown = (lichen != fruit).any(-1).sum()
    assert on_fruit > 0.1 * fruit.shape[0] * fruit.shape[1]  # the fruit fills the view
    assert shown > 0.15 * on_fruit  # and the lichen a good part of the fruit
