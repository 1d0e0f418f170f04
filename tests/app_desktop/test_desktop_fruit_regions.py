"""Regions of a fruit in the Defects dock (issue 40 §6): a pattern, a rubber band drawn with
the right button, a regrow and its undo, driven by Qt events."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest

from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui
FRUIT_TREE = ROOT / "grammars" / "fruit_tree.lsys"


@pytest.fixture
def window(make_window):
    win = make_window(FRUIT_TREE, n=5)
    win.docks["defects"].show()
    win.docks["defects"].raise_()
    return win


def _wait(qtbot, window, panel, text):
    settle(qtbot, window)
    qtbot.waitUntil(lambda: text in panel.facts.text(), timeout=30000)


def _mesh(panel):
    return panel.plotter.renderer.actors["defects_fruit"].mapper.dataset


def test_select_a_region_regrow_it_and_undo(qtbot, window, artifacts):
    panel = window.docks["defects"].widget()
    ex = window.controller.explorer
    fruit = ex.fruit_ids()[1]
    window.controller.select([fruit])
    _wait(qtbot, window, panel, f"Fruit {fruit}: no defects")
    plain = np.asarray(_mesh(panel).points).copy()
    # a label pattern, typed as a user would
    panel.region_pattern.setFocus()
    qtbot.keyClicks(panel.region_pattern, "(6, C*, *)")
    qtbot.mouseClick(panel.region_select, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Region: (6, C*, *)")
    lit = np.asarray(_mesh(panel).cell_data["region"], bool)
    assert 0 < lit.sum() < len(lit)
    panel.plotter.screenshot(str(artifacts / "desktop_region_pattern.png"))
    # a rubber band drawn with the right button over the middle of the view
    widget = panel.plotter.interactor
    w, h = widget.width(), widget.height()
    QTest.mousePress(widget, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, QPoint(w // 2 - 25, h // 2 - 25))
    QTest.mouseMove(widget, QPoint(w // 2 + 25, h // 2 + 25))
    QTest.mouseRelease(widget, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, QPoint(w // 2 + 25, h // 2 + 25))
    _wait(qtbot, window, panel, "skin cells of fruit")
    region = ex.fruit_region["region"]
    assert "cells" in region and 1 <= len(region["cells"]) < 30
    banded = np.asarray(_mesh(panel).cell_data["region"], bool)
    assert 0 < banded.sum() < lit.sum() * 3
    image = panel.plotter.screenshot(str(artifacts / "desktop_region_band.png"), return_img=True)
    assert image.reshape(-1, image.shape[-1]).std(axis=0).max() > 10
    # regrow it: one undoable edit; the view shows the bulge, the rest of the fruit stays
    edits = len(ex.session.edits)
    panel.region_params.setText("largeur=80")
    qtbot.mouseClick(panel.region_regrow, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Regrown:")
    assert len(ex.session.edits) == edits + 1 and ex.session.fruit_overrides()[fruit]["regions"][0]["cells"] == region["cells"]
    # hail placed in the region from the kind and options fields: one more edit, in the list
    panel.kind.setCurrentIndex(panel.kind.findText("hail"))
    panel.options.setText("depth_mm=3")
    qtbot.mouseClick(panel.region_place, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Placed in:")
    assert panel.spec_list() == ex.session.fruit_overrides()[fruit]["defects"] and panel.spec_list()[0].startswith(
        "hail:depth_mm=3,at="
    )
    panel.plotter.screenshot(str(artifacts / "desktop_region_hail.png"))
    window.activateWindow()
    qtbot.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, window)
    window.controller.select([fruit])
    _wait(qtbot, window, panel, "skin cells of fruit")
    regrown = np.asarray(_mesh(panel).points)
    assert regrown.shape == plain.shape and np.abs(regrown - plain).max() > 0.02 * np.ptp(plain, axis=0).max()
    panel.plotter.screenshot(str(artifacts / "desktop_region_regrown.png"))
    window.activateWindow()
    qtbot.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, window)
    assert "regions" not in ex.session.fruit_overrides().get(fruit, {})
    window.controller.select([fruit])
    _wait(qtbot, window, panel, f"Fruit {fruit}: no defects")
    np.testing.assert_array_equal(np.asarray(_mesh(panel).points), plain)


def test_regrow_a_region_at_a_finer_precision_and_undo(qtbot, window, artifacts):
    """``precision=20`` typed in the regrow field: the region alone gets finer cells (the
    view's skin has more faces, the rest of its points stay), one edit, undone by Ctrl+Z."""
    panel = window.docks["defects"].widget()
    ex = window.controller.explorer
    fruit = ex.fruit_ids()[1]
    window.controller.select([fruit])
    _wait(qtbot, window, panel, f"Fruit {fruit}: no defects")
    plain = _mesh(panel)
    plain_points, plain_cells = np.asarray(plain.points).copy(), plain.n_cells
    panel.region_pattern.setFocus()
    qtbot.keyClicks(panel.region_pattern, "(5, C*, *)")
    qtbot.mouseClick(panel.region_select, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Region: (5, C*, *)")
    edits = len(ex.session.edits)
    panel.region_params.setText("precision=20")
    qtbot.mouseClick(panel.region_regrow, Qt.MouseButton.LeftButton)
    _wait(qtbot, window, panel, "Regrown:")
    assert len(ex.session.edits) == edits + 1
    assert ex.session.fruit_overrides()[fruit]["regions"][0]["params"] == {"precision": 20}
    finer = _mesh(panel)
    assert finer.n_cells > plain_cells + 3 * 10 * 4  # ring 5's skin, 4 times as many faces
    lit = np.asarray(finer.cell_data["region"], bool)
    assert 0 < lit.sum() < finer.n_cells  # the refined region is still the selection
    image = panel.plotter.screenshot(str(artifacts / "desktop_region_finer.png"), return_img=True)
    assert image.reshape(-1, image.shape[-1]).std(axis=0).max() > 10
    window.activateWindow()
    qtbot.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, window)
    assert "regions" not in ex.session.fruit_overrides().get(fruit, {})
    window.controller.select([fruit])
    _wait(qtbot, window, panel, f"Fruit {fruit}:")
    np.testing.assert_array_equal(np.asarray(_mesh(panel).points), plain_points)
