"""The string dock lays its text out again only when the shown modules changed."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.gui


def snap(text, n_modules=100):
    return SimpleNamespace(string_preview=text, n_modules=n_modules, n=3)


def test_only_the_more_modules_tail_is_rewritten_when_the_shown_modules_stay(qtbot):
    from ramure.app.desktop.panels.string_dock import StringView

    view = StringView()
    qtbot.addWidget(view)
    calls = []
    real = view.string.setPlainText
    view.string.setPlainText = lambda text: calls.append(text) or real(text)
    head = "A(1) [ +(30) F 𝔸 ] B(2.5) " * 200  # a character outside the BMP: Qt counts UTF-16 units
    view.show_snapshot(snap(head + "… (5000 more modules)"))
    assert len(calls) == 1
    view.show_snapshot(snap(head + "… (5123 more modules)", 6123))  # a regrow behind the shown modules
    assert len(calls) == 1 and view.string.toPlainText() == head + "… (5123 more modules)"
    assert view.summary.text() == "6123 modules after 3 steps"
    view.show_snapshot(snap(head + "… (5123 more modules)"))  # nothing changed
    assert len(calls) == 1
    view.show_snapshot(snap("X " + head + "… (5123 more modules)"))  # a shown module changed
    assert len(calls) == 2 and view.string.toPlainText().startswith("X A(1)")
    view.show_snapshot(snap("F F F"))  # a short string: no tail
    assert len(calls) == 3 and view.string.toPlainText() == "F F F"
