"""The variant gallery dock: the 27 picks as thumbnails; a click applies that variant.

The pictures are drawn in a worker (:mod:`ramure.app.desktop.thumbnails`) or read
from the exploration's image files.  Clicking a thumbnail asks the window to
regrow the selection (or the whole plant) with that pick's parameter
combination.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QIcon, QPixmap
from PySide6.QtWidgets import QHBoxLayout, QLabel, QListView, QListWidget, QListWidgetItem, QPushButton, QVBoxLayout, QWidget

if TYPE_CHECKING:
    from PySide6.QtGui import QImage

ICON = 150  # large enough to tell the picks apart


def pick_label(pick: Mapping[str, Any], base: Mapping[str, float] | None, limit: int = 2) -> str:
    r"""The thumbnail's caption: its number and the constants that differ from ``base``.

    >>> pick_label({"id": 5, "params": {"rule": 1, "constants": {"a2": 66.0, "r1": 0.9}}},
    ...            {"a2": 60.0, "r1": 0.9})
    '#5  rule 1\na2 66 (+10%)'
    """
    params = pick.get("params") or {}
    rule = params.get("rule")
    lines = [f"#{pick.get('id')}" + ("" if rule is None else f"  rule {rule}")]
    changes = []
    for name, value in (params.get("constants") or {}).items():
        old = (base or {}).get(name)
        if old is None:
            changes.append(f"{name} {float(value):.3g}")
        elif abs(float(value) - float(old)) > 1e-9 * max(1.0, abs(float(old))):
            pct = f" ({(float(value) / float(old) - 1) * 100:+.0f}%)" if float(old) else ""
            changes.append(f"{name} {float(value):.3g}{pct}")
    lines += changes[:limit] + (["…"] if len(changes) > limit else [])
    return "\n".join(lines)


class GalleryView(QWidget):
    """Thumbnails of the 27 picks."""

    pick_clicked = Signal(dict)  # the picks.json record
    explore_requested = Signal()
    open_requested = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.explore_button = QPushButton("Explore variants")
        self.explore_button.clicked.connect(self.explore_requested)
        self.open_button = QPushButton("Open exploration…")
        self.open_button.clicked.connect(self.open_requested)
        self.list = QListWidget()
        self.list.setObjectName("gallery")
        self.list.setViewMode(QListView.ViewMode.IconMode)
        self.list.setIconSize(QSize(ICON, ICON))
        self.list.setResizeMode(QListView.ResizeMode.Adjust)
        self.list.setMovement(QListView.Movement.Static)
        self.list.setSpacing(4)
        self.list.itemClicked.connect(self._clicked)
        buttons = QHBoxLayout()  # under the note: the dock stays narrow beside the plant
        buttons.addWidget(self.explore_button)
        buttons.addWidget(self.open_button)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.note)
        layout.addLayout(buttons)
        layout.addWidget(self.list, 1)
        self.picks: list[dict] = []

    def set_unavailable(self, message: str) -> None:
        self.list.clear()
        self.picks = []
        self.note.setText(message)

    def set_picks(
        self,
        picks: Iterable[dict],
        images: Sequence[QImage | None] | None = None,
        note: str = "",
        base: Mapping[str, float] | None = None,
    ) -> None:
        """Show the picks (records) with QImages (or placeholders until :meth:`set_images`),
        each captioned with the constants that differ from ``base`` (the plant's values)."""
        self.list.clear()
        self.picks = list(picks)
        for i, pick in enumerate(self.picks):
            params = pick.get("params", {})
            rule = params.get("rule")
            tip = "\n".join(f"{k} = {v:g}" for k, v in params.get("constants", {}).items())
            item = QListWidgetItem(pick_label({"id": i + 1, **pick}, base))
            item.setToolTip(
                f"pick {pick.get('id')} — variant {pick.get('variant')}"
                f"{'' if rule is None else f', rule {rule}'}\n{tip}\n(click to apply)"
            )
            item.setData(Qt.ItemDataRole.UserRole, i)
            self.list.addItem(item)
        if images is not None:
            self.set_images(images)
        self.note.setText(note or f"{len(self.picks)} picks — click one to apply it to the selection (or to the whole plant).")

    def set_images(self, images: Sequence[QImage | None]) -> None:
        for i, image in enumerate(images):
            if image is not None and i < self.list.count():
                self.list.item(i).setIcon(QIcon(QPixmap.fromImage(image)))

    def _clicked(self, item) -> None:
        index = item.data(Qt.ItemDataRole.UserRole)
        self.pick_clicked.emit(self.picks[index])
