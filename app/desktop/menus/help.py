"""The Help menu: mouse and key reference (F1), grammar reference, about.

Each page opens in one non-modal window (it can stay open beside the plant).
The grammar reference is the grammar module's own documentation, so it never
drifts from what the parser accepts.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QDialog, QDialogButtonBox, QTextBrowser, QVBoxLayout

if TYPE_CHECKING:
    from PySide6.QtWidgets import QMenu, QWidget

KEYS = [
    ("Mouse", ""),
    ("Left drag", "turn the plant (turntable, Z stays up)"),
    ("Shift + left drag, middle drag", "pan"),
    ("Wheel", "zoom"),
    ("Click a branch", "select it (Ctrl+click toggles, Shift+click adds)"),
    ("Right drag", "select the branches and fruit inside a rectangle (Shift adds, Ctrl removes)"),
    ("Keys", ""),
    ("R", "left drag draws rectangles instead of turning"),
    ("Esc", "clear the selection"),
    ("Ctrl+R", "regrow the selection (the whole plant when nothing is selected)"),
    ("Delete", "prune the selection"),
    ("Ctrl+Z", "undo: typing, a constant, n, seed, regrow, prune"),
    ("Ctrl+Shift+Z, Ctrl+Y", "redo"),
    ("Home", "frame the whole plant (an edit leaves the camera where it is)"),
    ("Ctrl+1 / 2 / 3 / 4", "front, side, top, iso view"),
    ("G", "ground grid on or off"),
    ("K", "kinship colours (select one branch)"),
    ("Ctrl+O / Ctrl+S", "open / save the grammar"),
    ("F1", "this page"),
]

ABOUT = (
    "<h3>Ramure</h3><p>An explorer for procedural plants: L-systems with a derivation "
    "history, selective regeneration by minimum cut, variants and qualifiers, volumetric "
    "wood and fruit, user studies.</p><p>BSD-3-Clause licence.</p>"
)


def keys_html() -> str:
    """The mouse and key reference as an HTML table."""
    rows = []
    for key, what in KEYS:
        if not what:
            rows.append(f"<tr><td colspan=2><h4>{html.escape(key)}</h4></td></tr>")
        else:
            rows.append(f"<tr><td><b>{html.escape(key)}</b>&nbsp;&nbsp;</td><td>{html.escape(what)}</td></tr>")
    return "<table cellpadding=2>" + "".join(rows) + "</table>"


def grammar_html() -> str:
    """The grammar reference (the parser module's documentation) as preformatted text."""
    from ramure.lsys.language import grammar

    return "<h3>Grammar reference</h3><pre>" + html.escape(grammar.__doc__ or "") + "</pre>"


class HelpMenu:
    """Fills ``menu`` with the help pages of ``window``."""

    def __init__(self, window: QWidget, menu: QMenu) -> None:
        self.window = window
        self.dialog: QDialog | None = None
        self.shown: str | None = None  # the title of the page last opened (tests)
        for title, key, make in (
            ("Mouse and keys", "F1", keys_html),
            ("Grammar reference", None, grammar_html),
            ("About Ramure", None, lambda: ABOUT),
        ):
            action = QAction(title, window)
            if key:
                action.setShortcut(QKeySequence(key))
                action.setShortcutContext(Qt.ShortcutContext.ApplicationShortcut)
            action.triggered.connect(lambda _=False, t=title, m=make: self.show(t, m()))
            menu.addAction(action)

    def show(self, title: str, text: str) -> None:
        """Show ``text`` (HTML) under ``title`` in the one help window."""
        dialog = self.dialog
        if dialog is None:
            dialog = self.dialog = QDialog(self.window)
            dialog.resize(640, 520)
            self.browser = QTextBrowser(dialog)
            buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
            buttons.rejected.connect(dialog.close)
            layout = QVBoxLayout(dialog)
            layout.addWidget(self.browser)
            layout.addWidget(buttons)
        dialog.setWindowTitle(f"{title} — Ramure")
        self.browser.setHtml(text)
        self.shown = title
        dialog.show()
        dialog.raise_()
