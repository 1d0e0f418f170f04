"""The PCA dock: the variant cloud in 3D, the 27 picks, qualifier boxes toggled by check boxes.

Drawn with matplotlib's 3D axes on a Qt canvas (drag to rotate).  The base
plant is the origin (all deltas zero).  The canvas is made when the first
variants come: until then the dock says there is no exploration, and the
desktop does not import matplotlib (about 48 MB of memory).
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QColor, QIcon, QPixmap
from PySide6.QtWidgets import QLabel, QListWidget, QListWidgetItem, QSplitter, QWidget

from ramure.app.desktop.panels.common import dock_column

if TYPE_CHECKING:
    from PySide6.QtGui import QResizeEvent
    from ramure.app.desktop.variants import VariantSet

BOX_COLORS = [
    "#e41a1c",
    "#377eb8",
    "#4daf4a",
    "#984ea3",
    "#ff7f00",
    "#a65628",
    "#f781bf",
    "#999999",
    "#1b9e77",
    "#d95f02",
    "#7570b3",
    "#e7298a",
    "#66a61e",
]


def box_edges(lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """The 12 edges ((12, 2, 3)) of the axis-aligned box [lo, hi]."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i, j, k in itertools.product((0, 1), repeat=3)])
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    return corners[np.array(edges)]


def explained_ratios(variant_set: VariantSet) -> list[float] | None:
    """The share of variance of PC1-3 (None when unknown, e.g. an opened exploration folder)."""
    exploration = getattr(variant_set, "exploration", None)
    ratio = getattr(getattr(exploration, "pca", None), "explained_variance_ratio_", None)
    return None if ratio is None else [float(r) for r in ratio[:3]]


class PcaCloudView(QWidget):
    """A 3D scatter of the variant cloud with toggleable qualifier boxes; a click on a pick
    emits :attr:`pick_clicked` (the window applies it, as a gallery click does)."""

    pick_clicked = Signal(dict)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.figure: Any = None  # the matplotlib figure, its canvas and 3D axes: made by _plot()
        self.canvas: Any = None
        self.axes: Any = None
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.boxes_list = QListWidget()
        self.boxes_list.setObjectName("qualifierBoxes")
        self.boxes_list.itemChanged.connect(lambda _: self.redraw())
        self.boxes_list.setToolTip("Tick a qualifier to draw its box: where its best variants lie in PCA space")
        self.split = split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(QWidget())  # the canvas's place
        split.addWidget(self.boxes_list)
        split.setStretchFactor(0, 1)
        split.setStretchFactor(1, 0)
        dock_column(self, self.note).addWidget(split, 1)
        self._arrange()
        self.variant_set: VariantSet | None = None
        self.pick_artist = None
        self.set_unavailable("No exploration yet (Variants ▸ Explore).")

    def _plot(self) -> Any:
        """The 3D axes, with the figure and its canvas made (and matplotlib imported) the first time."""
        if self.axes is None:
            from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
            from matplotlib.figure import Figure

            self.figure = Figure(figsize=(4, 3), dpi=90)
            self.canvas = FigureCanvasQTAgg(self.figure)
            self.canvas.setMinimumSize(180, 180)
            self.axes = self.figure.add_subplot(projection="3d")
            self.figure.subplots_adjust(left=0.02, right=0.92, bottom=0.06, top=0.98)
            self.canvas.mpl_connect("pick_event", self._picked)
            placeholder = self.split.replaceWidget(0, self.canvas)
            if placeholder is not None:
                placeholder.deleteLater()
        return self.axes

    def resizeEvent(self, event: QResizeEvent) -> None:  # noqa: N802 (Qt API)
        """Lay the plot and the box list out for the dock's new size."""
        super().resizeEvent(event)
        self._arrange()

    def _arrange(self) -> None:
        """The box list beside the cloud in a wide dock, under it in a tall one (no blank half)."""
        tall = self.height() > 1.2 * self.width()
        orientation = Qt.Orientation.Vertical if tall else Qt.Orientation.Horizontal
        if self.split.orientation() != orientation:
            self.split.setOrientation(orientation)
            self.boxes_list.setMaximumSize(16777215 if tall else 160, 170 if tall else 16777215)
            self.boxes_list.setFlow(QListWidget.Flow.LeftToRight if tall else QListWidget.Flow.TopToBottom)
            self.boxes_list.setWrapping(tall)

    def set_unavailable(self, message: str) -> None:
        """Show no cloud, only ``message``."""
        self.variant_set = None
        self.boxes_list.clear()
        self.note.setText(message)
        if self.axes is not None:
            self.axes.cla()
            self.canvas.draw_idle()

    def set_variants(self, variant_set: VariantSet) -> None:
        """Show ``variant_set``: its cloud, its 27 picks and one check box per qualifier box."""
        self.variant_set = variant_set
        self.boxes_list.blockSignals(True)
        self.boxes_list.clear()
        for i, name in enumerate(sorted(variant_set.boxes)):
            item = QListWidgetItem(name)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(Qt.CheckState.Unchecked)
            item.setForeground(Qt.GlobalColor.black)
            color = BOX_COLORS[i % len(BOX_COLORS)]
            item.setData(Qt.ItemDataRole.UserRole, color)
            swatch = QPixmap(12, 12)
            swatch.fill(QColor(color))
            item.setIcon(QIcon(swatch))  # the colour its box is drawn in
            self.boxes_list.addItem(item)
        self.boxes_list.blockSignals(False)
        count = 0 if variant_set.points is None else int(np.isfinite(variant_set.points[:, 0]).sum())
        self.note.setText(
            f"{variant_set.name}: {count} variants, 27 picks" + ("" if variant_set.boxes else " — no qualifier boxes")
        )
        self.redraw()

    def checked_boxes(self) -> list[str]:
        """The names of the qualifier boxes checked."""
        return [
            self.boxes_list.item(i).text()
            for i in range(self.boxes_list.count())
            if self.boxes_list.item(i).checkState() == Qt.CheckState.Checked
        ]

    def set_box_checked(self, name: str, on: bool = True) -> None:
        """Check (or uncheck) the qualifier box ``name``."""
        for i in range(self.boxes_list.count()):
            item = self.boxes_list.item(i)
            if item.text() == name:
                item.setCheckState(Qt.CheckState.Checked if on else Qt.CheckState.Unchecked)

    def _picked(self, event) -> None:
        """A click on a pick's dot: apply that pick (to the selection or the whole plant)."""
        if event.artist is not self.pick_artist or self.variant_set is None or not len(event.ind):
            return
        ind = np.asarray(event.ind, int)
        shown = self.axes.transData.transform(np.asarray(self.pick_artist.get_offsets())[ind])
        mouse = np.array([event.mouseevent.x, event.mouseevent.y], float)
        nearest = int(ind[np.argmin(np.linalg.norm(shown - mouse, axis=1))])  # dots may overlap
        self.pick_clicked.emit(self.variant_set.picks[nearest])

    def redraw(self) -> None:
        """Draw the cloud, the picks and the checked boxes again."""
        vs = self.variant_set
        if vs is None:
            if self.axes is not None:
                self.axes.cla()
                self.canvas.draw_idle()
            return
        ax = self._plot()
        ax.cla()
        if vs.points is not None:
            ok = np.all(np.isfinite(vs.points), axis=1)
            ax.scatter(*vs.points[ok].T, s=3, c="#9a9a9a", alpha=0.4, depthshade=False)
        picks = np.array([p.get("pca", [np.nan] * 3) for p in vs.picks], float)
        self.pick_artist = None
        if len(picks):
            self.pick_artist = ax.scatter(*picks.T, s=30, c=np.arange(len(picks)), cmap="viridis", depthshade=False, picker=5)
            for p, rec in zip(picks, vs.picks):
                ax.text(*p, f" {rec.get('id', '')}", fontsize=8)
        ax.scatter([0], [0], [0], marker="x", s=40, c="black")
        colors = {
            self.boxes_list.item(i).text(): self.boxes_list.item(i).data(Qt.ItemDataRole.UserRole)
            for i in range(self.boxes_list.count())
        }
        for name in self.checked_boxes():
            lo, hi = vs.boxes[name]
            for a, b in box_edges(lo, hi):
                ax.plot(*np.c_[a, b], color=colors[name], linewidth=1.2)
            ax.text(*hi, name, color=colors[name], fontsize=7)
        ratios = explained_ratios(vs)
        for axis, k in ((ax.set_xlabel, 0), (ax.set_ylabel, 1), (ax.set_zlabel, 2)):
            axis(f"PC{k + 1}" + (f" ({ratios[k]:.0%})" if ratios else ""), fontsize=9)
        ax.tick_params(labelsize=7)
        self.canvas.draw_idle()
