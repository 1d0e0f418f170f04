"""Regrow says what it did: the regrown part stays selected, and a deterministic grammar is named."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt

from ramure.app.desktop.state import SAME_PLANT
from desktop_helpers import STOCHASTIC, settle

pytestmark = pytest.mark.gui


def tips(window, count):
    snap = window.controller.snapshot
    order = np.asarray(snap.skeleton.order)
    return snap.segment_leaf[np.flatnonzero(order == order.max())[:count]]


def test_regrow_on_a_deterministic_grammar_says_why_nothing_changed(make_window, qtbot):
    w = make_window(n=6)  # Honda: no probabilities, no random draws
    w.controller.select(tips(w, 4))
    before = w.controller.explorer.derivation.to_string()
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    assert w.controller.explorer.derivation.to_string() == before
    assert w.regen.note.isVisible() and w.regen.note.text() == SAME_PLANT
    assert "deterministic" in w.statusBar().currentMessage()
    assert "Regrow with constants" in SAME_PLANT and "qualifier" in SAME_PLANT


def test_the_regrown_part_stays_selected_and_again_regrows_it(make_window, qtbot):
    w = make_window(STOCHASTIC, n=4)
    ex = w.controller.explorer
    w.controller.select(tips(w, 5))
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    first = w.controller.snapshot.last_result
    regrown = list(ex.selection)
    added = np.asarray(first.change.added)
    assert regrown and set(regrown) <= set(added.tolist())  # selected = what grew back
    assert w.regen.note.text().startswith("The regrown part stays selected")
    rgb = np.asarray(w.view.mesh.cell_data["rgb"])
    red = np.isin(np.asarray(w.view.mesh.cell_data["leaf_id"]), regrown)
    assert red.any() and (rgb[red] == [255, 0, 0]).all()  # highlighted
    assert "whole plant" not in w.regen.regrow_button.text()
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)  # "again, another seed"
    settle(qtbot, w)
    second = ex.session.edits[-1]
    assert second["selection"] == regrown and second["seed"] != ex.session.edits[-2]["seed"]
    assert len(w.controller.snapshot.last_result.roots) <= len(first.roots) + 1  # not the whole plant


def test_the_first_selection_warms_up_edits_once_in_the_background(make_window, monkeypatch):
    import threading

    from ramure.app import model

    started = []
    monkeypatch.setattr(model, "_warm_up", [])
    monkeypatch.setattr(model, "warm_up_edits", lambda text, n: started.append((text, n, threading.current_thread().name)))
    w = make_window(n=5)
    w.controller.clear_selection()
    assert started == [] and model._warm_up == []  # nothing selected: no edit to prepare for
    w.controller.select(tips(w, 2))
    model._warm_up[0].join(10)
    ex = w.controller.explorer
    assert started == [(ex.text, 5, "ramure-warm-up")]
    w.controller.select(tips(w, 3))
    assert len(model._warm_up) == 1 and len(started) == 1  # once per process


def test_quarter_regrow_then_delete_a_regrown_branch_then_a_constant(make_window, qtbot, monkeypatch):
    """Issue 34 §3 with real events on a smaller Honda: rubber-band a quarter (right drag),
    Regrow, click one regrown branch, Delete, type a2 = 45.  The constant used to crash the
    worker's snapshot (IndexError: the prune's cut drawn on the re-derived, smaller tree).  A
    cut larger than the dock draws is said, not drawn (the limit lowered here to this plant)."""
    from PySide6.QtTest import QTest

    from ramure.app.desktop import state

    monkeypatch.setattr(state, "CUT_GRAPH_MAX_NODES", 10)
    w = make_window(n=9)
    crashes = []
    w.controller.crashed.connect(lambda message, _details: crashes.append(message))
    ex = w.controller.explorer
    first_size = ex.derivation.tree.size
    xy = w.view.project(w.controller.snapshot.midpoints)
    lo, hi = np.nanmin(xy, axis=0), np.nanmax(xy, axis=0)
    mid = (lo + hi) / 2
    plotter = w.view.plotter
    a, b = w.view.to_widget(mid[0], mid[1]), w.view.to_widget(hi[0] + 5, hi[1] + 5)  # the upper right
    QTest.mousePress(plotter, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, a)
    QTest.mouseMove(plotter, (a + b) / 2)
    QTest.mouseRelease(plotter, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, b)
    assert len(ex.selection) > 10
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    cut = w.controller.snapshot.last_result.cut
    assert not cut.from_axiom and cut.graph_size > 10 and w.cut_view.layout_data is None
    assert f"spans {cut.graph_size:,} nodes" in w.cut_view.title.text()
    snap = w.controller.snapshot
    regrown = np.flatnonzero(np.isin(snap.segment_leaf, snap.selection))
    tree = ex.derivation.tree

    def tip(i):  # a click on a tip prunes it; a lone segment that carries branches is kept
        p = int(tree.parent[int(snap.segment_leaf[i])])
        kids = np.arange(tree.child_start[p], tree.child_start[p] + tree.child_count[p])
        return bool((tree.child_count[kids] == 0).all())

    regrown = np.array([i for i in regrown if tip(i)])
    xy = w.view.project(snap.midpoints)
    gaps = [np.min(np.linalg.norm(np.delete(xy, i, axis=0) - xy[i], axis=1)) for i in regrown]
    segment = int(regrown[int(np.argmax(gaps))])  # the regrown tip farthest from the others
    QTest.mouseClick(plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, w.view.to_widget(*xy[segment]))
    assert ex.selection == [int(snap.segment_leaf[segment])] and ex.selection[0] >= first_size
    QTest.keyClick(plotter, Qt.Key.Key_Delete)
    settle(qtbot, w)
    assert w.controller.snapshot.last_result.op == "prune"
    box = w.constants_panel.rows["a2"].value
    box.setFocus()
    box.selectAll()
    QTest.keyClicks(box, "45")
    QTest.keyClick(box, Qt.Key.Key_Return)
    qtbot.waitUntil(lambda: ex.constants["a2"] == 45.0, timeout=10_000)
    settle(qtbot, w)
    assert crashes == []
    assert ex.derivation.tree.size == first_size and w.presenter.drawn_version == w.controller.snapshot.version
    assert "constants changed, whole plant re-derived" in w.status_label.text()
    assert w.view.mesh.n_cells == w.controller.snapshot.mesh.n_cells > 0
