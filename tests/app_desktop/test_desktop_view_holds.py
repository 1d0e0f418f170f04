"""The view holds still and says what happened (issue 34, section 4): the camera stays on an
edit and an undo, Undo and Redo say what they did, sliders follow them, a stale grammar error
goes with the text an undo took back."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from desktop_helpers import STOCHASTIC, settle

pytestmark = pytest.mark.gui

CTRL = Qt.KeyboardModifier.ControlModifier
SHIFT = Qt.KeyboardModifier.ShiftModifier


def camera_state(window):
    camera = window.view.plotter.renderer.GetActiveCamera()
    return (
        np.array(camera.GetPosition()),
        np.array(camera.GetFocalPoint()),
        np.array(camera.GetViewUp()),
        camera.GetParallelScale(),
        camera.GetViewAngle(),
    )


def same_camera(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a, b))


def tips(window, count):
    snap = window.controller.snapshot
    order = np.asarray(snap.skeleton.order)
    return snap.segment_leaf[np.flatnonzero(order == order.max())[:count]]


def test_the_camera_stays_on_a_regrow_and_an_undo_and_frames_on_n_and_home(make_window, qtbot):
    w = make_window(STOCHASTIC, n=4)
    ex = w.controller.explorer
    start = camera_state(w)
    bounds = w.view.plant_bounds()
    snap = w.controller.snapshot
    top = np.argsort(-np.asarray(snap.skeleton.end)[:, 2])[:4]  # the top of the crown: its height changes
    w.controller.select(snap.segment_leaf[top])
    regrows = 0
    while w.view.plant_bounds() == bounds and regrows < 6:  # the regrown part stays selected
        qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
        settle(qtbot, w, timeout=90)  # the first regrow in a process loads the edit kernels
        regrows += 1
        assert same_camera(camera_state(w), start)  # before: framed again, the picture shifted
    assert w.view.plant_bounds() != bounds  # another plant, another size
    for _ in range(regrows):
        QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, CTRL)
        settle(qtbot, w)
        assert same_camera(camera_state(w), start)
    assert w.view.plant_bounds() == bounds
    w.constants_panel.n_box.setValue(5)  # another n: a plant of another size, framed again
    settle(qtbot, w)
    framed = camera_state(w)
    assert ex.session.n == 5 and not same_camera(framed, start)
    w.view.plotter.renderer.GetActiveCamera().Zoom(2.0)  # the user zooms in
    w.view.auto_framed = False
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Home)
    settle(qtbot, w)
    assert same_camera(camera_state(w), framed)  # Home frames the whole plant again


def test_undo_and_redo_say_what_they_did_and_the_sliders_follow(make_window, qtbot):
    w = make_window()
    row = w.constants_panel.rows["a2"]
    w.constants_panel.set_constant("a2", 45.0)
    settle(qtbot, w)
    w.controller.select(tips(w, 3))
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, CTRL)
    settle(qtbot, w)
    assert w.statusBar().currentMessage() == "Undid: regrow of 3 leaves"
    assert w.regen.note.text() == "Undid: regrow of 3 leaves"
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, CTRL)
    settle(qtbot, w)
    assert w.statusBar().currentMessage() == "Undid: a2 = 45"
    assert row.value.value() == 60.0 and row.slider.value() == row._to_step(60.0)
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, CTRL | SHIFT)
    settle(qtbot, w)
    assert w.statusBar().currentMessage() == "Redid: a2 = 45"
    assert row.value.value() == 45.0 and row.slider.value() == row._to_step(45.0)


def test_a_stale_grammar_error_goes_with_an_undo_that_fixed_the_text(make_window, qtbot):
    w = make_window()
    ex = w.controller.explorer
    w.constants_panel.set_constant("a2", 45.0)
    settle(qtbot, w)
    good = w.editor.text()
    w.editor.edit.setPlainText(good.replace("F(l)[&(a1)", "F(l*zz)[&(a1)"))
    qtbot.waitUntil(lambda: w.editor.error is not None, timeout=5000)
    settle(qtbot, w)
    assert "zz" in w.editor.message.text()
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, CTRL)  # takes back a2 = 45: the text is a good one again
    settle(qtbot, w)
    assert ex.constants["a2"] == 60.0 and ex.error is None
    assert w.editor.text() == ex.document_text() and "zz" not in w.editor.text()
    assert w.editor.error is None and w.editor.message.text() == "" and w.editor.underlined() is None
    assert not w.windowTitle().endswith("* — Ramure") and "*" not in w.windowTitle()


def pick_only(view, actor, x, y):
    """(cell, world point) of ``actor`` alone under display ``(x, y)``, or (-1, None)."""
    from vtkmodules.vtkRenderingCore import vtkCellPicker

    from ramure.app.desktop.view import plant_view as view_module

    picker = vtkCellPicker()
    picker.SetTolerance(view_module.PICK_TOLERANCE)
    picker.PickFromListOn()
    picker.AddPickList(actor)
    picker.AddLocator(view_module._locator(actor.GetMapper().GetInput()))
    if not picker.Pick(float(x), float(y), 0.0, view.plotter.renderer):
        return -1, None
    return int(picker.GetCellId()), np.array(picker.GetPickPosition())


def test_a_click_on_a_fruit_where_its_twig_crosses_it_picks_the_fruit(make_window, qtbot):
    from desktop_helpers import ROOT

    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=5)
    w.fruit_action.setChecked(True)  # volumetric fruit replace the spheres
    qtbot.waitUntil(lambda: w.view.fruit is not None, timeout=60000)
    QTest.keyClick(w.view.plotter, Qt.Key.Key_4, CTRL)  # the iso view: twigs cross their fruit
    settle(qtbot, w)
    view, ex = w.view, w.controller.explorer
    leaf = np.asarray(view.fruit.cell_data["leaf_id"])
    centres = np.asarray(view.fruit.cell_centers().points)
    kind = np.asarray(view.mesh.cell_data["kind"])
    crossings = []  # display points on a fruit where a branch inside the fruit's box is hit first
    for f in np.unique(leaf):
        box = centres[leaf == f]
        lo, hi = view.project(box).min(axis=0), view.project(box).max(axis=0)
        for fx in (0.3, 0.5, 0.7):
            for fy in (0.3, 0.5, 0.7):
                x, y = lo + (hi - lo) * (fx, fy)
                cell, point = pick_only(view, view.actor, x, y)
                if cell >= 0 and kind[cell] == 0 and (point >= box.min(axis=0)).all() and (point <= box.max(axis=0)).all():
                    if pick_only(view, view.fruit_actor, x, y)[0] >= 0:
                        crossings.append((int(f), x, y))
    assert len(crossings) >= 3
    for f, x, y in crossings:
        QTest.mouseClick(view.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, view.to_widget(x, y))
        assert ex.selection == [f]  # before: the twig's leaf
