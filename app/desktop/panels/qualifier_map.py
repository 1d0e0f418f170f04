"""The qualifier map dock: the collision matrix of the qualifiers on the grammar being explored.

A heat map (:func:`ramure.metrics.heatmap.draw_collision_matrix`) beside
the PCA cloud: row A, column B is the share of A's best variants that fall
inside B's box in PCA space, so a dark cell says "these two words pick the
same kind of plant here".  With an exploration run in this window the
regions are the default vocabulary's (:func:`ramure.metrics.qualifiers.vocabulary_regions`);
a variant set without a fitted sweep (an opened folder) shows its
qualifier boxes' overlap only when the sweep is there, and says so otherwise.

:func:`attach` adds the dock to a ``QMainWindow``
(tabified with the PCA cloud) the first time variants are shown.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QCheckBox, QDockWidget, QLabel, QScrollArea, QWidget

from ramure.app.desktop.panels.common import dock_column
from ramure.errors import RamureError

if TYPE_CHECKING:
    from PySide6.QtWidgets import QWidget
    from ramure.app.desktop.variants import VariantSet
    from PySide6.QtWidgets import QMainWindow, QMenu
    from ramure.metrics.qualifiers import QualifierRegions


#: Smallest size (pixels) the heat map is drawn at: below it the names were clipped.
MIN_WIDTH, MIN_HEIGHT = 480, 440


class QualifierMapView(QWidget):
    """The collision-matrix heat map with a one-line summary and an English/French toggle."""

    def __init__(self, parent: QWidget | None = None) -> None:
        # matplotlib (about 48 MB) is imported with the view, made when variants are first shown
        from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
        from matplotlib.figure import Figure

        super().__init__(parent)
        self.figure = Figure(figsize=(5, 4.6), dpi=90)  # fixed margins: a docked canvas can be tiny
        self.canvas = FigureCanvasQTAgg(self.figure)
        # 22 names and their values need room: a narrow dock scrolls rather than clipping the names
        self.canvas.setMinimumSize(MIN_WIDTH, MIN_HEIGHT)
        self.canvas_area = QScrollArea()
        self.canvas_area.setWidgetResizable(True)
        self.canvas_area.setWidget(self.canvas)
        self.note = QLabel("No exploration yet.")
        self.note.setWordWrap(True)
        self.french = QCheckBox("French names")
        self.french.toggled.connect(lambda _: self.redraw())
        layout = dock_column(self, self.note)
        layout.addWidget(self.canvas_area, 1)
        layout.addWidget(self.french)
        self.regions: QualifierRegions | None = None
        self.name = ""

    def set_unavailable(self, message: str) -> None:
        """Show no matrix, only ``message``."""
        self.regions = None
        self.note.setText(message)
        self.redraw()

    def set_variants(self, variant_set: VariantSet) -> None:
        """Compute the vocabulary's regions of ``variant_set``'s exploration and draw them."""
        exp = getattr(variant_set, "exploration", None)
        if exp is None or getattr(exp, "sweep", None) is None:
            self.set_unavailable("The collision matrix needs this grammar's variant sweep: Variants ▸ Explore variants.")
            return
        from ramure.metrics.qualifiers import vocabulary_regions

        try:
            self.regions = vocabulary_regions(exp.sweep, exp.points)
        except RamureError as exc:
            self.set_unavailable(f"No collision matrix: {exc}")
            return
        self.name = variant_set.name
        self.note.setText(
            f"{variant_set.name}: {len(self.regions.names_)} qualifiers, mean collision "
            f"{self.regions.mean_collision():.1f} % (the thesis's study: 66 %). Dark = two "
            "qualifiers pick the same plants."
        )
        self.redraw()

    def redraw(self) -> None:
        """Draw the collision matrix of the regions (nothing without them)."""
        from ramure.metrics.heatmap import draw_collision_matrix

        self.figure.clear()
        if self.regions is not None:
            self.figure.subplots_adjust(left=0.2, bottom=0.22, right=0.95, top=0.98)
            ax = self.figure.add_subplot()
            image = draw_collision_matrix(ax, self.regions.collision_matrix_, self.regions.names_, french=self.french.isChecked())
            self.figure.colorbar(image, ax=ax, shrink=0.75, label="% of A's variants in B's box")
        self.canvas.draw_idle()


def attach(window: QMainWindow, docks: dict[str, QDockWidget], menu: QMenu | None = None) -> QualifierMapView:
    """The qualifier map of ``window``, created on first use as ``docks["qualifier_map"]``:
    tabified with ``docks["pca"]`` (and hidden with it), its toggle added to ``menu``."""
    if "qualifier_map" in docks:
        return docks["qualifier_map"].widget()  # type: ignore[return-value]  # made below
    view = QualifierMapView()
    dock = QDockWidget("Qualifier map", window)
    dock.setObjectName("dock_qualifier_map")
    dock.setWidget(view)
    window.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, dock)
    if "pca" in docks:
        window.tabifyDockWidget(docks["pca"], dock)
        if not docks["pca"].isVisible():  # closed with the PCA cloud (the View menu opens it)
            dock.hide()
    if menu is not None:
        menu.addAction(dock.toggleViewAction())
    docks["qualifier_map"] = dock
    return view
