"""The docks share one outer column and one number box (``panels/common.py``), not copies of them."""

from __future__ import annotations

import pathlib
import re

import pytest

PANELS = pathlib.Path(__file__).resolve().parents[2] / "app" / "desktop" / "panels"
OWN_COLUMN = re.compile(r"QVBoxLayout\(self\)")
OWN_DECIMAL_BOX = re.compile(r"= QDoubleSpinBox\(\)")


def test_no_dock_builds_its_own_column_or_decimal_box():
    own = []
    for path in sorted(PANELS.glob("*.py")):
        if path.name == "common.py":
            continue
        text = path.read_text(encoding="utf-8")
        own += [f"{path.name}: column" for _ in OWN_COLUMN.finditer(text)]
        # the seed box stays its own: a whole number past 2^31, typed, never accelerated
        own += [
            f"{path.name}: {m.group(0)}"
            for m in OWN_DECIMAL_BOX.finditer(text)
            if "seed_box" not in text[m.start() - 20 : m.start()]
        ]
    assert own == []


@pytest.mark.gui
def test_the_shared_helpers_keep_each_docks_look(qtbot):
    from PySide6.QtWidgets import QLabel, QWidget

    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.panels.common import DOCK_MARGIN, dock_column, number_box
    from ramure.app.desktop.panels.editor import GrammarEditor
    from ramure.app.desktop.panels.string_dock import StringView

    make_application()
    box = number_box(0.0, 2.0, 2, value=0.4, name="wind", step=0.05)
    assert (box.objectName(), box.minimum(), box.maximum(), box.decimals()) == ("wind", 0.0, 2.0, 2)
    assert box.singleStep() == 0.05 and box.value() == 0.4 and box.keyboardTracking()
    assert number_box(0.0, 1.0, 1).singleStep() == 1.0  # no step: Qt's own
    widget = QWidget()
    column = dock_column(widget, QLabel("a"), QLabel("b"))
    assert column.count() == 2 and column.contentsMargins().left() == DOCK_MARGIN == 2
    assert StringView().layout().contentsMargins().top() == DOCK_MARGIN
    assert GrammarEditor().layout().contentsMargins().left() == 0  # the text reaches the frame
