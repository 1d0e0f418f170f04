"""Regrow says what it did: the regrown part stays selected, and a deterministic grammar is named."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt

from ramure.app.desktop.window import SAME_PLANT
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
