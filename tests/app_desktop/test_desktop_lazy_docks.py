"""The Wood, Details and Defects docks make their 3D view (an OpenGL context) when first shown (issue 14).

Built hidden behind other tabs, they hold no view (and the Wood dock no gmap
list of species; the Details dock's habit list is filled from the start, without
gmap); raised, each makes its view, and that view draws the dock's result: a
picture that differs from the empty view's in many pixels.
"""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt

from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui
FRUIT_TREE = ROOT / "grammars" / "fruit_tree.lsys"
LAZY = ("wood", "details", "defects")


@pytest.fixture
def window(make_window):
    return make_window(FRUIT_TREE, n=5)


def _open(qtbot, window, key):
    """Raise the dock as a click on its tab would; returns its panel, whose view now exists."""
    dock = window.docks[key]
    dock.show()
    dock.raise_()
    settle(qtbot, window)
    panel = dock.widget()
    qtbot.waitUntil(lambda: panel.view_slot.made, timeout=5000)
    return panel


def _picture(plotter):
    plotter.render()
    return np.asarray(plotter.screenshot(return_img=True), dtype=int)


def _changed(before, after):
    """Share of pixels that changed by more than 30 in some channel."""
    assert before.shape == after.shape
    return float((np.abs(after - before).max(axis=-1) > 30).mean())


def test_each_dock_makes_its_view_when_first_shown_and_draws_in_it(qtbot, window):
    """One window (each test window costs seconds): the docks are opened one after the other."""
    for key in LAZY:
        assert not window.docks[key].widget().view_slot.made, key
    assert window.docks["wood"].widget().species.count() == 0
    habit = window.docks["details"].widget().habit
    assert [habit.itemText(i) for i in range(habit.count())] == ["crustose", "foliose", "fruticose"]  # from the start
    fruit = window.controller.explorer.fruit_ids()[0]
    window.controller.select([fruit])
    settle(qtbot, window)
    assert not window.docks["defects"].widget().view_slot.made  # a selection while hidden makes no view

    # Wood: Grow draws the wood and its cut plane
    panel = _open(qtbot, window, "wood")
    assert panel.plotter.isVisible() and not window.docks["details"].widget().view_slot.made
    species = [panel.species.itemText(i) for i in range(panel.species.count())]
    assert species == ["elm", "larch", "oak", "pine"] and panel.species.currentText() == "elm"
    empty = _picture(panel.plotter)
    panel.years.setValue(3)
    qtbot.mouseClick(panel.grow_button, Qt.MouseButton.LeftButton)
    assert panel.wood is not None and "darts" in panel.facts.text()
    # a thin trunk, its clip plane and the plane widget's outline in a tall narrow dock
    assert _changed(empty, _picture(panel.plotter)) > 0.004

    # Details: Show the fruit draws the selected fruit
    panel = _open(qtbot, window, "details")
    assert panel.habit.count() >= 3 and panel.habit.currentText() == "crustose"
    empty = _picture(panel.plotter)
    qtbot.mouseClick(panel.show_button, Qt.MouseButton.LeftButton)
    settle(qtbot, window)
    qtbot.waitUntil(lambda: panel.fruit_label.text().startswith("Fruit:"), timeout=20000)
    assert panel.shown == "fruit"
    assert _changed(empty, _picture(panel.plotter)) > 0.02

    # Defects: raised, it shows the selected fruit with its (no) defects
    panel = _open(qtbot, window, "defects")
    qtbot.waitUntil(lambda: f"Fruit {fruit}" in panel.facts.text(), timeout=30000)
    settle(qtbot, window)
    shown = _picture(panel.plotter)
    panel.plotter.clear_actors()
    assert _changed(_picture(panel.plotter), shown) > 0.02


def test_the_habit_names_listed_at_start_are_the_gmap_habits():
    from ramure.app.desktop.panels.details import HABIT_NAMES
    from ramure.gmap.organs.lichen import HABITS

    assert list(HABIT_NAMES) == list(HABITS)
