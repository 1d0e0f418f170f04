"""The grammar dock follows the model's text by itself (the window only hands it snapshots)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.gui


def _editor():
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.panels.editor import GrammarEditor

    make_application()
    editor = GrammarEditor()
    editor.show_model_text("n = 3\nA --> B\n")
    return editor


def test_the_editor_follows_the_model_but_not_over_typing(qtbot):
    editor = _editor()
    assert editor.shown_text == editor.text() == "n = 3\nA --> B\n"
    editor.follow(SimpleNamespace(text="n = 4\nA --> B\n", job="set constant"))  # a slider moved
    assert editor.text() == "n = 4\nA --> B\n" and editor.shown_text == editor.text()
    editor.follow(SimpleNamespace(text="n = 30\nA --> B\n", job="grammar"))  # the user's own "30."
    assert editor.text() == "n = 4\nA --> B\n" and editor.shown_text == "n = 30\nA --> B\n"
    editor.edit.setPlainText("n = 5\nA --> BB\n")  # typing, still in its pause
    assert editor.pending()
    editor.follow(SimpleNamespace(text="n = 6\nA --> B\n", job="set constant"))
    assert editor.text() == "n = 5\nA --> BB\n"  # the typing stays


def test_undo_takes_the_typed_text_and_its_error_back(qtbot):
    from ramure.lsys import GrammarError

    editor = _editor()
    editor.edit.setPlainText("A --> (\n")
    editor.timer.stop()
    editor.show_error(GrammarError("unbalanced", line=1, column=7))
    editor.show_undone(SimpleNamespace(text="n = 3\nA --> B\n", error=None))
    assert editor.text() == "n = 3\nA --> B\n" and editor.error is None and editor.shown_text == editor.text()
    editor.show_error(GrammarError("still bad", line=1, column=1))
    editor.show_undone(SimpleNamespace(text="n = 2\n", error="refused"))  # the model keeps an error
    assert editor.text() == "n = 3\nA --> B\n" and editor.error is not None
