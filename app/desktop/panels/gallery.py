"""The variant gallery dock: the 27 picks as thumbnails; a click applies that variant.

The pictures are drawn in a worker (:mod:`ramure.app.desktop.view.thumbnails`) or read
from the exploration's image files.  Clicking a thumbnail asks the window to
regrow the selection (or the whole plant) with that pick's parameter
combination.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QIcon, QPixmap
from PySide6.QtWidgets import QCheckBox, QHBoxLayout, QLabel, QListView, QListWidget, QListWidgetItem, QPushButton, QWidget

from ramure.app.desktop.panels.common import dock_column, number_box

if TYPE_CHECKING:
    from PySide6.QtGui import QImage, QResizeEvent

ICON = 150  # the largest thumbnail (a wide dock)
MIN_ICON = 100  # two columns in a 280-pixel dock rather than one of 150
CAPTION_LINES = 4  # pick_label's most: the number, two constants and "…"


def pick_label(pick: Mapping[str, Any], base: Mapping[str, float] | None, limit: int = 6, first: Sequence[str] = ()) -> str:
    r"""The thumbnail's caption: its number and every constant that differs from ``base`` (at
    most ``limit``, then "…"), two a line, as the change in percent (the value where ``base``
    has none or 0), those named in ``first`` (the ones that tell the picks apart) first.
    The constants a pick leaves as they are are not named: the caption says how it differs.

    >>> pick_label({"id": 5, "params": {"rule": 1, "constants": {"a2": 66.0, "r1": 0.9}}},
    ...            {"a2": 60.0, "r1": 0.9})
    '#5  rule 1\na2+10%'
    >>> pick_label({"id": 2, "params": {"constants": {"r1": 0.99, "r2": 0.77, "a2": 54.0, "s": 2}}},
    ...            {"r1": 0.9, "r2": 0.7, "a2": 60.0}, first=["a2"])
    '#2\na2-10% r1+10%\nr2+10% s=2'
    """
    params = pick.get("params") or {}
    rule = params.get("rule")
    changes = []
    constants = params.get("constants") or {}
    order = list(first)
    for name in sorted(constants, key=lambda k: order.index(k) if k in order else len(order)):
        value, old = float(constants[name]), (base or {}).get(name)
        if old is None or not float(old):
            changes.append(f"{name}={value:.3g}")
        elif abs(value - float(old)) > 1e-9 * max(1.0, abs(float(old))):
            changes.append(f"{name}{(value / float(old) - 1) * 100:+.0f}%")
    shown = changes[:limit] + (["…"] if len(changes) > limit else [])
    lines = [f"#{pick.get('id')}" + ("" if rule is None else f"  rule {rule}")]
    lines += [" ".join(shown[i : i + 2]) for i in range(0, len(shown), 2)]
    return "\n".join(lines)


def varying_constants(picks: Iterable[Mapping[str, Any]]) -> list[str]:
    """The constants whose values differ between ``picks``, the most varied first: what a
    caption shows to tell the picks apart (one all picks share says nothing)."""
    values: dict[str, set] = {}
    for pick in picks:
        for name, value in ((pick.get("params") or {}).get("constants") or {}).items():
            values.setdefault(name, set()).add(round(float(value), 9))
    varied = [name for name, seen in values.items() if len(seen) > 1]
    return sorted(varied, key=lambda name: -len(values[name]))


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
        # issue 35's larger space, off by default: the default PCA cloud and its count stay the thesis's
        self.hidden_box = QCheckBox("Hidden constants")
        self.hidden_box.setToolTip("Also vary the numeric literals and rule probabilities (ramure explore --hidden)")
        self.wide_box = number_box(0.0, 0.9, 2, step=0.05)
        self.wide_box.setPrefix("wide ±")
        self.wide_box.setSpecialValueText("no wide step")
        self.wide_box.setToolTip("A larger step added one constant at a time, e.g. 0.25 (ramure explore --wide 0.25)")
        self.open_button = QPushButton("Open exploration…")
        self.open_button.clicked.connect(self.open_requested)
        self.list = QListWidget()
        self.list.setObjectName("gallery")
        self.list.setViewMode(QListView.ViewMode.IconMode)
        self.list.setIconSize(QSize(ICON, ICON))
        self.list.setResizeMode(QListView.ResizeMode.Adjust)
        self.list.setMovement(QListView.Movement.Static)
        self.list.setSpacing(4)
        self.list.setWordWrap(True)
        self.list.setUniformItemSizes(True)
        self.list.itemClicked.connect(self._clicked)
        buttons = QHBoxLayout()  # under the note: the dock stays narrow beside the plant
        buttons.addWidget(self.explore_button)
        buttons.addWidget(self.open_button)
        options = QHBoxLayout()
        options.addWidget(self.hidden_box)
        options.addWidget(self.wide_box)
        dock_column(self, self.note, buttons, options).addWidget(self.list, 1)
        self.picks: list[dict] = []

    def sweep_options(self) -> dict[str, Any]:
        """``{"hidden": bool, "wide": float or None}``: the larger space of variants the boxes ask for."""
        wide = round(float(self.wide_box.value()), 2)
        return {"hidden": self.hidden_box.isChecked(), "wide": wide or None}

    def resizeEvent(self, event: QResizeEvent) -> None:  # noqa: N802 (Qt API)
        """Fit the thumbnails to the dock's new width."""
        super().resizeEvent(event)
        self.fit_thumbnails()

    def fit_thumbnails(self) -> None:
        """Thumbnails as large as the dock's width allows (at most :data:`ICON`), in as many
        columns as fit at :data:`MIN_ICON`, each with room for its whole caption."""
        pad = 2 * self.list.spacing() + 8
        scrollbar = self.list.verticalScrollBar().sizeHint().width()  # shown or not: the same columns
        width = self.list.width() - 2 * self.list.frameWidth() - scrollbar - 2 * self.list.spacing() - 2
        columns = max(1, width // (MIN_ICON + pad))
        icon = max(48, min(ICON, width // columns - pad))
        lines = self.list.fontMetrics().lineSpacing() * CAPTION_LINES
        self.list.setIconSize(QSize(icon, icon))
        self.list.setGridSize(QSize(icon + pad, icon + lines + pad))
        self.list.doItemsLayout()  # the rows again, for this width

    def set_unavailable(self, message: str) -> None:
        """Show no picks, only ``message``."""
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
        varying = varying_constants(self.picks)
        for i, pick in enumerate(self.picks):
            params = pick.get("params", {})
            rule = params.get("rule")
            tip = "\n".join(f"{k} = {v:g}" for k, v in params.get("constants", {}).items())
            item = QListWidgetItem(pick_label({"id": i + 1, **pick}, base, first=varying))
            item.setToolTip(
                f"pick {pick.get('id')} — variant {pick.get('variant')}"
                f"{'' if rule is None else f', rule {rule}'}\n{tip}\n(click to apply)"
            )
            item.setData(Qt.ItemDataRole.UserRole, i)
            self.list.addItem(item)
        if images is not None:
            self.set_images(images)
        self.fit_thumbnails()
        self.note.setText(note or f"{len(self.picks)} picks — click one to apply it to the selection (or to the whole plant).")

    def set_images(self, images: Sequence[QImage | None]) -> None:
        """Put the drawn thumbnails on the picks (None: that one is not drawn yet)."""
        for i, image in enumerate(images):
            if image is not None and i < self.list.count():
                self.list.item(i).setIcon(QIcon(QPixmap.fromImage(image)))

    def _clicked(self, item) -> None:
        index = item.data(Qt.ItemDataRole.UserRole)
        self.pick_clicked.emit(self.picks[index])
