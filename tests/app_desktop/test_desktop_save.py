"""Save writes what is on screen (issue 34, section 1), driven by real key and mouse events:
n, seed and constants reach the file and come back on reopening; typing keeps n; the "*"
follows the file on disk; local edits ask for a session; Undo does not cross Open."""

from __future__ import annotations

import shutil

import pytest
from PySide6.QtCore import Qt
from PySide6.QtGui import QTextCursor
from PySide6.QtTest import QTest

from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui

CTRL = Qt.KeyboardModifier.ControlModifier


def type_into(qtbot, box, value):
    """Select the box's text, type ``value`` and press Enter, as a user does."""
    box.setFocus()
    box.selectAll()
    QTest.keyClicks(box, str(value))
    QTest.keyClick(box, Qt.Key.Key_Return)


def keys(w, key, modifiers=CTRL):
    QTest.keyClick(w.view.plotter, key, modifiers)


def starred(w):
    return "*" in w.windowTitle()


@pytest.fixture
def honda(tmp_path):
    path = tmp_path / "honda.lsys"
    shutil.copy(ROOT / "grammars" / "honda_sympodial.lsys", path)
    return path


def test_ctrl_s_writes_n_seed_and_constants_and_reopening_shows_them(make_window, qtbot, honda):
    w = make_window(honda, n=6)
    panel = w.constants_panel
    assert not starred(w)
    type_into(qtbot, panel.n_box, 8)
    settle(qtbot, w)
    type_into(qtbot, panel.seed_box, 7)
    settle(qtbot, w)
    type_into(qtbot, panel.rows["a2"].value, 33)
    settle(qtbot, w)
    assert starred(w) and "#seed 7" in w.editor.text()  # the editor shows what Save writes
    keys(w, Qt.Key.Key_S)
    settle(qtbot, w)
    assert not starred(w)
    text = honda.read_text()
    assert "#seed 7\nn:      8\n" in text and "#define a2 33 " in text  # before: n: 10 and no seed
    w.files.open_grammar(ROOT / "grammars" / "ternary_branching.lsys")
    settle(qtbot, w)
    w.files.open_grammar(honda)
    settle(qtbot, w)
    ex = w.controller.explorer
    assert (ex.session.n, ex.session.seed, ex.constants["a2"]) == (8, 7, 33.0)
    assert (panel.n_box.value(), panel.seed_box.value(), panel.values()["a2"]) == (8, 7, 33.0)
    assert not starred(w)


def test_typing_a_comment_keeps_n(make_window, qtbot):
    w = make_window(n=6)
    type_into(qtbot, w.constants_panel.n_box, 7)
    settle(qtbot, w)
    edit = w.editor.edit
    edit.setFocus()
    edit.moveCursor(QTextCursor.MoveOperation.End)
    QTest.keyClick(edit, Qt.Key.Key_Return)
    QTest.keyClicks(edit, "// note")
    qtbot.waitUntil(lambda: not w.editor.pending(), timeout=3000)
    settle(qtbot, w)
    ex = w.controller.explorer
    assert "// note" in ex.text and ex.session.n == 7  # before: n fell back to the text's 10
    assert w.constants_panel.n_box.value() == 7


def test_star_follows_undo_past_the_save_point(make_window, qtbot, honda):
    w = make_window(honda, n=6)
    type_into(qtbot, w.constants_panel.n_box, 5)
    settle(qtbot, w)
    keys(w, Qt.Key.Key_S)
    settle(qtbot, w)
    assert not starred(w)
    keys(w, Qt.Key.Key_Z)
    settle(qtbot, w)
    assert w.controller.explorer.session.n == 6 and starred(w)  # before: clean after the undo
    keys(w, Qt.Key.Key_Y)
    settle(qtbot, w)
    assert not starred(w)


def test_save_grammar_with_a_regrown_part_asks_for_a_session(make_window, qtbot, honda):
    w = make_window(honda, n=6)
    before = honda.read_text()
    w.controller.select(w.controller.snapshot.segment_leaf[-3:])
    keys(w, Qt.Key.Key_R)  # Regrow
    settle(qtbot, w)
    keys(w, Qt.Key.Key_S)
    settle(qtbot, w)
    assert "Save session" in (w.last_message or "") and honda.read_text() == before
    assert starred(w)  # before: the title lost its "*" and the regrown part was lost on disk
    session = w.files.save_session(honda.with_suffix(".json"))
    assert session.is_file() and not starred(w)


def test_undo_does_not_cross_open(make_window, qtbot):
    w = make_window(n=6)
    w.constants_panel.set_constant("a2", 30.0)
    settle(qtbot, w)
    w.dirty = False  # the question on opening is answered "discard"
    w.files.open_grammar(ROOT / "grammars" / "ternary_branching.lsys")
    settle(qtbot, w)
    assert not w.undo_action.isEnabled() and not starred(w)
    keys(w, Qt.Key.Key_Z)
    settle(qtbot, w)
    ex = w.controller.explorer
    assert ex.path.name == "ternary_branching.lsys" and "a2" not in ex.constants  # before: Honda came back
    assert w.windowTitle().startswith("ternary_branching.lsys — ")


def test_whole_plant_pick_shows_its_constants_and_save_writes_them(make_window, qtbot, honda):
    w = make_window(honda, n=6)
    w.variants.apply_pick({"params": {"rule": None, "constants": {"a2": 41.0}}})  # a gallery click
    settle(qtbot, w)
    assert w.constants_panel.values()["a2"] == 41.0 and "#define a2 41 " in w.editor.text()
    keys(w, Qt.Key.Key_S)
    settle(qtbot, w)
    assert "#define a2 41 " in honda.read_text() and not starred(w)


def test_rho_slider_minimum_is_one_percent(make_window, qtbot):
    w = make_window(n=6)
    slider = w.regen.rho
    slider.setFocus()
    for _ in range(6):  # (Home is the window's "frame the plant")
        QTest.keyClick(slider, Qt.Key.Key_PageDown)
    settle(qtbot, w)
    assert slider.value() == 1 and w.controller.explorer.rho == pytest.approx(0.01)  # before: 1.0
    for _ in range(11):
        QTest.keyClick(slider, Qt.Key.Key_PageUp)
    settle(qtbot, w)
    assert w.controller.explorer.rho == pytest.approx(1.0)
