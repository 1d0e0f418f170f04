"""The Architecture dock: clicking a row of the AMAP tree selects that part of the plant."""

from __future__ import annotations

import pytest
from PySide6.QtCore import Qt

from desktop_helpers import ROOT

pytestmark = pytest.mark.gui
MASSART = ROOT / "grammars" / "amap" / "massart.lsys"


@pytest.fixture
def panel(qtbot):
    from ramure.app.desktop.panels.architecture import ArchitecturePanel
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.launch import make_application
    from ramure.app.model import Explorer

    make_application()
    controller = Controller(Explorer(str(MASSART), n=5))
    widget = ArchitecturePanel(controller)
    qtbot.addWidget(widget)
    widget.resize(420, 600)
    widget.show()
    qtbot.waitExposed(widget)
    return widget


def _click(qtbot, panel, item):
    panel.tree.scrollToItem(item)
    rect = panel.tree.visualItemRect(item)
    qtbot.mouseClick(panel.tree.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())


def test_clicking_an_axis_selects_its_internodes_and_its_branches(qtbot, panel):
    plant = panel.tree.topLevelItem(0)
    trunk = plant.child(0)
    branch = trunk.child(trunk.childCount() - 1)  # axes hang below their parent, after its shoots
    assert trunk.text(0).startswith("Axis 1 (order 1)") and branch.text(0).startswith("Axis")
    _click(qtbot, panel, branch)
    kind, row = branch.data(0, Qt.ItemDataRole.UserRole)
    expected = sorted(panel.arch.subtree_nodes(row).tolist())
    assert sorted(panel.controller.snapshot.selection) == expected and expected


def test_a_growth_unit_row_selects_exactly_its_internodes(qtbot, panel):
    trunk = panel.tree.topLevelItem(0).child(0)
    unit = trunk.child(0).child(0)  # first annual shoot, first growth unit
    _click(qtbot, panel, unit)
    assert len(panel.controller.snapshot.selection) == int(unit.text(1)) == 3


def test_the_tree_follows_the_plant_and_explains_missing_annotations(qtbot, panel):
    before = panel.arch.counts()["growth_units"]
    panel.controller.set_derivation(n=6)
    panel.controller.wait_idle()
    assert panel.arch.counts()["growth_units"] > before
    panel.controller.set_text("n: 2\nw: F\np:\n  F -> F[+F]F\n")
    panel.controller.wait_idle()
    qtbot.waitUntil(lambda: panel.arch is None, timeout=10000)  # the rebuild is a queued slot
    assert "#amap internode F" in panel.summary.text()


def test_the_window_has_an_architecture_dock(make_window):
    window = make_window(MASSART, n=4)
    dock = window.docks["architecture"]
    assert dock.widget().arch.counts()["axes"] == 1 + 3 * 3  # the trunk and three tiers of three
