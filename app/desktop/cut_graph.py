"""The cut graph dock: the derivation graph of the last regeneration and its minimum cut.

Each tree node is two vertices, ``in`` above ``out``, joined by its node
edge; rows are derivation depths.  Source-side vertices are blue, sink-side
orange, cut edges thick red; the regrown roots are ringed in red and the
selected leaves filled in red.  The layout comes from
:func:`app.desktop.state.cut_graph_layout`.
"""
from __future__ import annotations

from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QPainter, QPen
from PySide6.QtWidgets import (QGraphicsScene, QGraphicsView, QHBoxLayout, QLabel, QPushButton,
                               QVBoxLayout, QWidget)

SOURCE_COLOR = QColor("#3b6fd8")
SINK_COLOR = QColor("#e08a1e")
CUT_COLOR = QColor("#d00000")
X_STEP, Y_STEP, RADIUS = 28.0, 26.0, 5.0


class CutGraphView(QWidget):
    """A zoomable drawing of a cut graph, with a legend and a "plan for selection" button."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.scene = QGraphicsScene(self)
        self.view = QGraphicsView(self.scene)
        self.view.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.view.setDragMode(QGraphicsView.DragMode.ScrollHandDrag)
        self.title = QLabel("No cut yet: select branches, then Regrow or Prune.")
        self.title.setWordWrap(True)
        self.plan_button = QPushButton("Show the cut for the selection")
        legend = QLabel('<span style="color:#3b6fd8">● source side</span> &nbsp; '
                        '<span style="color:#e08a1e">● sink side</span> &nbsp; '
                        '<span style="color:#d00000">━ cut edge, ○ regrown root</span>')
        top = QHBoxLayout()
        top.addWidget(self.title, 1)
        top.addWidget(self.plan_button)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addLayout(top)
        layout.addWidget(legend)
        layout.addWidget(self.view, 1)
        self.layout_data = None

    def clear(self, message):
        self.scene.clear()
        self.layout_data = None
        self.title.setText(message)

    def show_layout(self, layout, title):
        """Draw a :class:`~app.desktop.state.GraphLayout`."""
        self.scene.clear()
        self.layout_data = layout
        self.title.setText(title)
        pos = {v: QPointF(x * X_STEP, y * Y_STEP) for v, (x, y) in layout.positions.items()}
        thin = QPen(QColor("#999999"), 1.0)
        cut_pen = QPen(CUT_COLOR, 3.0)
        for u, v, _cap, is_cut in layout.edges:
            if u in pos and v in pos:
                self.scene.addLine(pos[u].x(), pos[u].y(), pos[v].x(), pos[v].y(), cut_pen if is_cut else thin)
        labels = len(pos) <= 160
        for v, p in pos.items():
            terminal = v in ("s", "t")
            r = RADIUS * (1.8 if terminal else 1.0)
            color = SOURCE_COLOR if v in layout.source_side else SINK_COLOR
            node = v[0] if isinstance(v, tuple) else None
            brush = QBrush(CUT_COLOR if node in layout.selected and v[1] == "out" else color)
            pen = QPen(CUT_COLOR, 2.5) if node in layout.roots and v[1] == "in" else QPen(Qt.PenStyle.NoPen)
            self.scene.addEllipse(QRectF(p.x() - r, p.y() - r, 2 * r, 2 * r), pen, brush)
            if terminal or (labels and v[1] == "in"):
                text = self.scene.addText(v if terminal else str(node))
                font = text.font()
                font.setPointSize(7)
                text.setFont(font)
                text.setPos(p.x() + r, p.y() - 2.5 * r)
        self.view.fitInView(self.scene.itemsBoundingRect().adjusted(-10, -10, 10, 10),
                            Qt.AspectRatioMode.KeepAspectRatio)

    def resizeEvent(self, event):  # noqa: N802 (Qt API)
        super().resizeEvent(event)
        if self.layout_data is not None:
            self.view.fitInView(self.scene.itemsBoundingRect().adjusted(-10, -10, 10, 10),
                                Qt.AspectRatioMode.KeepAspectRatio)

    def wheelEvent(self, event):  # noqa: N802 (Qt API)
        factor = 1.15 if event.angleDelta().y() > 0 else 1 / 1.15
        self.view.scale(factor, factor)
