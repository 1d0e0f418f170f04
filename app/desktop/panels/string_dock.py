"""The string dock: the current string of leaves, and the modules of the selection."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import QLabel, QPlainTextEdit, QSplitter, QWidget
from PySide6.QtCore import Qt

from ramure.app.desktop.panels.common import dock_column

if TYPE_CHECKING:
    from ramure.app.desktop.state import Snapshot

MORE = " … ("  # where the string preview's "… (k more modules)" tail starts (state.string_preview)


class StringView(QWidget):
    """Read-only views of the derived string (first modules) and of the selected leaves."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        font = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont)
        self.summary = QLabel("")
        self.string = QPlainTextEdit()
        self.string.setObjectName("currentString")
        self.string.setReadOnly(True)
        self.string.setFont(font)
        self.selected = QPlainTextEdit()
        self.selected.setObjectName("selectedModules")
        self.selected.setReadOnly(True)
        self.selected.setFont(font)
        self.selected.setPlaceholderText("Selected leaves appear here (id: module).")
        split = QSplitter(Qt.Orientation.Vertical)
        split.addWidget(self.string)
        split.addWidget(self.selected)
        split.setSizes([3, 1])
        dock_column(self, self.summary).addWidget(split, 1)

    def show_snapshot(self, snap: Snapshot) -> None:
        """Show the snapshot's string.  Laying out the 5,000-module preview costs 20-50 ms, so
        an edit that leaves the shown modules as they were (most regrows, every undo of one)
        rewrites only the "… (k more modules)" tail, or nothing, and the scroll position stays."""
        self.summary.setText(f"{snap.n_modules} modules after {snap.n} steps")
        text = snap.string_preview
        shown = self.string.toPlainText()
        if text == shown:
            return
        head, cut, _ = text.rpartition(MORE)
        if cut and shown.rpartition(MORE)[0] == head:
            from PySide6.QtGui import QTextCursor

            cursor = QTextCursor(self.string.document())
            cursor.setPosition(len(head.encode("utf-16-le")) // 2)  # Qt counts UTF-16 units
            cursor.movePosition(QTextCursor.MoveOperation.End, QTextCursor.MoveMode.KeepAnchor)
            cursor.insertText(text[len(head) :])
            return
        self.string.setPlainText(text)

    def show_selection(self, lines: Iterable[str]) -> None:
        """Show the selection's modules, one per line."""
        self.selected.setPlainText("\n".join(lines))
