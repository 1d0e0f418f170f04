"""The grammar editor: syntax highlighting, debounced parsing, errors underlined in place.

:class:`GrammarEditor` emits :attr:`~GrammarEditor.text_settled` a moment
after the user stops typing (``DEBOUNCE_MS``); the window then asks the model
to parse and derive the text in the worker and calls
:meth:`~GrammarEditor.show_error` with the result.  An error is drawn as a red
wavy underline from its column to the end of the word, with the message in a
line under the editor; the plant on screen does not change.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from PySide6.QtCore import QEvent, QObject, Qt, QTimer, Signal
from PySide6.QtGui import (
    QColor,
    QFont,
    QFontDatabase,
    QKeySequence,
    QSyntaxHighlighter,
    QTextCharFormat,
    QTextCursor,
    QTextOption,
)
from PySide6.QtWidgets import QLabel, QPlainTextEdit, QTextEdit, QWidget

from ramure.app.desktop.panels.common import dock_column
from ramure.lsys.language.grammar import starts_line_comment

if TYPE_CHECKING:
    from ramure.lsys import GrammarError
    from ramure.app.desktop.state import Snapshot

DEBOUNCE_MS = 350


def _format(color, bold: bool = False, italic: bool = False):
    fmt = QTextCharFormat()
    fmt.setForeground(QColor(color))
    if bold:
        fmt.setFontWeight(QFont.Weight.Bold)
    fmt.setFontItalic(italic)
    return fmt


class GrammarHighlighter(QSyntaxHighlighter):
    """Colours directives, the n:/w:/p: sections, arrows, brackets, numbers and comments."""

    RULES = [
        (re.compile(r"^\s*#\w+:?"), _format("#7b2d8b", bold=True)),  # #define, #ignore: ...
        (re.compile(r"^\s*[nwp]\s*:"), _format("#1f4e9c", bold=True)),  # n: w: p:
        (re.compile(r"->|<|>|:\s*\*"), _format("#b35900", bold=True)),
        (re.compile(r"[\[\]]"), _format("#2b7a2b", bold=True)),
        (re.compile(r"(?<![A-Za-z_])\d+\.?\d*|\.\d+"), _format("#0a7f8c")),
        (re.compile(r"\b(Leaf|Fruit)\b"), _format("#a0522d", bold=True)),
    ]
    COMMENT = _format("#808080", italic=True)

    def highlightBlock(self, text: str) -> None:  # noqa: N802 (Qt API)
        """Colour one line: keywords, numbers, modules, then comments (a ``/* */`` may span lines)."""
        for pattern, fmt in self.RULES:
            for m in pattern.finditer(text):
                self.setFormat(m.start(), m.end() - m.start(), fmt)
        # comments last, so they win; /* ... */ may span lines (block state 1 = inside one)
        inside = self.previousBlockState() == 1
        self.setCurrentBlockState(0)
        pos = 0
        while True:
            if inside:
                end = text.find("*/", pos)
                if end < 0:
                    self.setFormat(pos, len(text) - pos, self.COMMENT)
                    self.setCurrentBlockState(1)
                    return
                self.setFormat(pos, end + 2 - pos, self.COMMENT)
                pos, inside = end + 2, False
                continue
            block, line = text.find("/*", pos), text.find("//", pos)
            if line >= 0 and (block < 0 or line < block) and starts_line_comment(text, line):
                self.setFormat(line, len(text) - line, self.COMMENT)
                return
            if block < 0:
                return
            self.setFormat(block, 2, self.COMMENT)
            pos, inside = block + 2, True


class _WindowUndo(QObject):
    """Lets Ctrl+Z, Ctrl+Shift+Z and Ctrl+Y reach the window's Undo and Redo from the editor.

    The editor keeps no undo history of its own: typing, sliders, regrowing and
    the derivation count are one history (the window's), so Undo in the editor
    also takes back a slider move made after the typing, in order.
    """

    KEYS = (QKeySequence.StandardKey.Undo, QKeySequence.StandardKey.Redo)

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt API)
        if event.type() == QEvent.Type.ShortcutOverride:
            combo = event.keyCombination().toCombined()
            ctrl_y = QKeySequence("Ctrl+Y")[0]  # type: ignore[index]  # PySide6 stubs: a sequence of key combinations
            if any(event.matches(k) for k in self.KEYS) or combo == ctrl_y.toCombined():
                event.ignore()  # not ours: the window's shortcut fires
                return True
        return False


class GrammarEditor(QWidget):
    """A plain-text grammar editor with an error line under it."""

    text_settled = Signal(str)  # emitted DEBOUNCE_MS after the last keystroke

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.edit = QPlainTextEdit(self)
        self.edit.setObjectName("grammarText")
        font = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont)
        font.setPointSize(max(font.pointSize(), 10))
        self.edit.setFont(font)
        # long lines wrap at the dock's width: the whole grammar reads without scrolling sideways
        self.edit.setLineWrapMode(QPlainTextEdit.LineWrapMode.WidgetWidth)
        self.edit.setWordWrapMode(QTextOption.WrapMode.WrapAtWordBoundaryOrAnywhere)
        self.edit.setTabStopDistance(4 * self.edit.fontMetrics().horizontalAdvance(" "))
        self.edit.setUndoRedoEnabled(False)  # one history: the window's (see _WindowUndo)
        self._undo_keys = _WindowUndo(self)
        self.edit.installEventFilter(self._undo_keys)
        self.highlighter = GrammarHighlighter(self.edit.document())
        self.message = QLabel("", self)
        self.message.setObjectName("grammarError")
        self.message.setWordWrap(True)
        self.message.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.message.setStyleSheet("color: #b00020;")
        layout = dock_column(self, margin=0)  # the text reaches the dock's frame
        layout.addWidget(self.edit, 1)
        layout.addWidget(self.message)
        self.timer = QTimer(self)
        self.timer.setSingleShot(True)
        self.timer.setInterval(DEBOUNCE_MS)
        self.timer.timeout.connect(lambda: self.text_settled.emit(self.text()))
        self.edit.textChanged.connect(self.timer.start)
        self.error: GrammarError | None = None
        self.shown_text = ""  # the model's grammar text the editor last showed

    def show_model_text(self, text: str) -> None:
        """Show the model's ``text`` as it stands (the window's first plant)."""
        self.set_text(text)
        self.shown_text = text

    def follow(self, snap: Snapshot) -> None:
        """Show the model's grammar text when something other than typing changed it (a slider,
        Undo, Redo, a file): the editor and the constants are one state."""
        if snap.text == self.shown_text:
            return
        self.shown_text = snap.text
        if snap.job == "grammar" or self.pending():
            return  # the editor's own text (perhaps "30." for 30), or the user is typing
        self.replace_text(snap.text)

    def show_undone(self, snap: Snapshot) -> None:
        """After Undo or Redo: the model's text again, without the error of text typed since (an
        undo took that text back); typing still in its pause, or a refused text, stays."""
        if snap.error is None and not self.pending():
            self.shown_text = snap.text
            self.replace_text(snap.text)
            self.show_error(None)

    def text(self) -> str:
        """The editor's text."""
        return self.edit.toPlainText()

    def set_text(self, text: str) -> None:
        """Replace the text without emitting :attr:`text_settled` (e.g. after opening a file)."""
        if text == self.text():
            return
        self.edit.blockSignals(True)
        self.edit.setPlainText(text)
        self.edit.blockSignals(False)
        self.edit.document().setModified(False)
        self.timer.stop()
        self.show_error(None)

    def pending(self) -> bool:
        """True while typing has not yet been sent (the debounce pause is running)."""
        return self.timer.isActive()

    def flush(self) -> None:
        """Send typed text now instead of after the pause (before Undo, Save...)."""
        if self.timer.isActive():
            self.timer.stop()
            self.text_settled.emit(self.text())

    def replace_text(self, text: str) -> None:
        """Show ``text`` (a slider, Undo or Redo changed it) by editing only the lines that differ,
        so the cursor and the scroll position stay where they were; emits nothing."""
        old = self.text()
        if text == old:
            return
        if any(ord(c) > 0xFFFF for c in old + text):  # Qt positions are UTF-16 units
            self.set_text(text)
            return
        start = 0
        limit = min(len(old), len(text))
        while start < limit and old[start] == text[start]:
            start += 1
        end = 0
        while end < limit - start and old[-1 - end] == text[-1 - end]:
            end += 1
        cursor = QTextCursor(self.edit.document())
        cursor.setPosition(start)
        cursor.setPosition(len(old) - end, QTextCursor.MoveMode.KeepAnchor)
        self.edit.blockSignals(True)
        cursor.insertText(text[start : len(text) - end])
        self.edit.blockSignals(False)
        self.timer.stop()

    def show_error(self, error: GrammarError | None) -> None:
        """Underline ``error`` (a GrammarError with ``line``/``column``) or clear it."""
        self.error = error
        if error is None:
            self.message.setText("")
            self.edit.setExtraSelections([])
            return
        where = f"line {error.line}, column {error.column}: " if error.line else ""
        self.message.setText(where + getattr(error, "message", str(error)))
        if not error.line:
            self.edit.setExtraSelections([])
            return
        block = self.edit.document().findBlockByNumber(int(error.line) - 1)
        if not block.isValid():
            self.edit.setExtraSelections([])
            return
        text = block.text()
        col = max(int(error.column or 1) - 1, 0)
        col = min(col, max(len(text) - 1, 0))
        end = col + 1
        while end < len(text) and (text[end].isalnum() or text[end] in "_."):
            end += 1
        if not text:  # an empty line: mark the line itself
            col, end = 0, 0
        cursor = QTextCursor(block)
        cursor.setPosition(block.position() + col)
        cursor.setPosition(block.position() + max(end, col + (1 if text else 0)), QTextCursor.MoveMode.KeepAnchor)
        selection = QTextEdit.ExtraSelection()
        fmt = QTextCharFormat()
        fmt.setUnderlineStyle(QTextCharFormat.UnderlineStyle.WaveUnderline)
        fmt.setUnderlineColor(QColor("#d00000"))
        fmt.setBackground(QColor(255, 220, 220))
        selection.format = fmt
        selection.cursor = cursor
        self.edit.setExtraSelections([selection])

    def underlined(self) -> tuple[int, int] | None:
        """``(line, column)`` (1-based) of the underlined error, or None (for tests)."""
        sels = self.edit.extraSelections()
        if not sels:
            return None
        cursor = sels[0].cursor
        block = self.edit.document().findBlock(cursor.selectionStart())
        return block.blockNumber() + 1, cursor.selectionStart() - block.position() + 1
