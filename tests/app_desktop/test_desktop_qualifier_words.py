"""Issue 35 in the desktop: the collision matrix dock, refused words with suggestions, a study's words."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest

from ramure.app.desktop.view.thumbnails import pixel_variance
from desktop_helpers import settle
from test_desktop_variants import menu_action

pytestmark = pytest.mark.gui


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path / "cache"))


def type_word(qtbot, box, text):
    """Type ``text`` in the qualifier box as a user does (the line edit, then Return)."""
    box.lineEdit().clear()
    QTest.keyClicks(box.lineEdit(), text)
    QTest.keyClick(box.lineEdit(), Qt.Key.Key_Return)


def test_the_qualifier_map_is_the_api_matrix_with_names(make_window, qtbot, tmp_path):
    from ramure.metrics.qualifiers import vocabulary_regions

    w = make_window(n=4)
    menu_action(w, "Variants", "Explore variants of this grammar").trigger()
    qtbot.waitUntil(lambda: w.variants.variant_set is not None and not w.variants.busy(), timeout=60000)
    settle(qtbot, w)
    exp = w.variants.variant_set.exploration
    api = vocabulary_regions(exp.sweep, exp.points)  # what `ramure qualify --matrix` prints
    dock, view = w.docks["qualifier_map"], w.qualifier_map
    dock.show()
    dock.raise_()
    settle(qtbot, w)
    ax = view.figure.axes[0]
    drawn = np.asarray(ax.images[0].get_array().filled(np.nan), float)
    off = ~np.eye(len(api.names_), dtype=bool)
    assert [t.get_text() for t in ax.get_yticklabels()] == api.names_
    assert np.allclose(drawn[off], api.collision_matrix_[off]) and np.isnan(np.diag(drawn)).all()
    assert f"mean collision {api.mean_collision():.1f} %" in view.note.text()
    view.canvas.draw()
    picture = view.canvas.grab().toImage()
    picture.save(str(tmp_path / "qualifier_map.png"))
    assert picture.width() >= 480 and pixel_variance(picture) > 20  # a drawn heat map, not a blank dock
    renderer = view.canvas.get_renderer()
    for label in [*ax.get_yticklabels(), *ax.get_xticklabels()]:  # every name whole, none clipped
        box = label.get_window_extent(renderer)
        assert box.x0 >= 0 and box.y0 >= 0 and box.x1 <= picture.width(), label.get_text()
    # the French names, with a click on the check box
    box = view.french
    qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=QPoint(8, box.height() // 2))
    assert box.isChecked()
    french = [t.get_text() for t in view.figure.axes[0].get_yticklabels()]
    assert "petit" in french and "haut" in french and "small" not in french
    assert menu_action(w, "View", "Qualifier map") is dock.toggleViewAction()


def test_a_study_word_joins_the_box_and_a_typo_is_refused_with_suggestions(make_window, qtbot, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QFileDialog

    path = tmp_path / "words.json"
    entry = {"direction": {"height": 1.0, "crown_width": -0.3}, "meaning": "named by 3 groups: +1 height"}
    path.write_text(json.dumps({"format": "ramure-words", "words": {"long-trunk": entry}}))
    w = make_window(n=4)
    box = w.regen.qualifier
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))
    menu_action(w, "Variants", "Load study words…").trigger()
    assert "long-trunk" in w.variants.words
    assert "long trunk" in box.completer().model().stringList() and box.findText("long trunk") >= 0
    assert "+1 height" in box.itemData(box.findText("long trunk"), Qt.ItemDataRole.ToolTipRole)
    # a typo is refused at once, naming the nearest words; nothing is explored for it
    type_word(qtbot, box, "long trnk")
    qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    assert "did you mean long trunk" in w.regen.qualifier_note.text()
    assert w.variants.variant_set is None and not w.variants.busy()
    type_word(qtbot, box, "talller")
    qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    assert "unknown qualifier 'talller'" in w.regen.qualifier_note.text() and "taller" in w.regen.qualifier_note.text()
    # the study's word, typed in any case, explores then regrows along its measured direction
    type_word(qtbot, box, "Long Trunk")
    with qtbot.waitSignal(w.controller.job_done, timeout=120000, check_params_cb=lambda job: job.name == "qualifier long-trunk"):
        qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    result = w.variants.last_qualifier
    assert result.qualifier == "long-trunk" and result.source == "transfer"
    assert w.statusBar().currentMessage().startswith("long-trunk: ")  # what it did, or why not
    if result.improved:
        assert result.moves["long-trunk"] > 0
    else:
        assert "long-trunk" in result.reason
    # a file that is not a vocabulary file is refused; the words loaded stay
    (tmp_path / "bad.json").write_text("[1]")
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(tmp_path / "bad.json"), ""))
    menu_action(w, "Variants", "Load study words…").trigger()
    assert "not a Ramure vocabulary file" in w.last_message and "long-trunk" in w.variants.words


def test_a_study_word_that_moved_nothing_says_why():
    from types import SimpleNamespace

    from ramure.app.desktop.variants import qualifier_message

    result = SimpleNamespace(
        qualifier="long-trunk", improved=False, tried=0, variant=-1, params={}, regen=None, reason="every variant moves X more"
    )
    assert qualifier_message(result) == (
        "long-trunk: no variant moved the selection that way; the plant is as it was: every variant moves X more"
    )
    result.regen, result.improved, result.variant, result.params = object(), True, 4, {"rule": 2}
    assert qualifier_message(result) == "long-trunk: applied variant 4 (rule 2)"
