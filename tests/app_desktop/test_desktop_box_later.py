"""A large selection is recoloured and painted first; its OBB follows in the next event-loop turn."""

import numpy as np

from ramure.app.desktop import state
from ramure.app.desktop.view import plant_view as view_module


def test_a_large_selection_gets_its_box_after_the_paint(make_window, qtbot, monkeypatch):
    monkeypatch.setattr(view_module, "BOX_LATER_LEAVES", 3)  # Honda n=6 counts as large
    w = make_window()
    xy = w.view.project(w.controller.snapshot.midpoints)
    lo, hi = np.nanmin(xy, axis=0) - 5, np.nanmax(xy, axis=0) + 5
    w.view.rectangle_at((*lo, *hi))
    qtbot.waitUntil(lambda: len(w.controller.explorer.selection) > 3, timeout=5000)
    qtbot.waitUntil(w.view.has_box, timeout=5000)
    snap = w.controller.snapshot
    expected = state.selection_box_lines(snap.skeleton, snap.selection).reshape(-1, 3)
    np.testing.assert_allclose(np.asarray(w.view.box.points), expected)


def test_a_newer_box_request_drops_the_pending_one(make_window, qtbot):
    w = make_window()
    corners = np.zeros((12, 2, 3))
    corners[:, 1] = 1.0
    w.view.set_box_for(lambda: corners, view_module.BOX_LATER_LEAVES + 1)  # deferred
    assert not w.view.has_box()
    w.view.set_box_for(None, 0)  # selection cleared before the box came
    qtbot.wait(50)
    assert not w.view.has_box()
    w.view.set_box_for(lambda: corners, 1)  # small: drawn at once
    assert w.view.has_box()
