"""The cut graph dock: the derivation graph of the last regeneration and its minimum cut.

Each tree node is two vertices, ``in`` above ``out``, joined by its node
edge; rows are derivation depths and each subtree is a block under its
parent (:func:`ramure.app.desktop.state.cut_graph_layout`).  Source-side vertices
are blue, sink-side orange, cut edges thick red; the regrown roots are
ringed in red and the selected leaves filled in red.

A wide graph is fitted to the view's height (scroll across it) rather than
shrunk to a line.  Node numbers keep a fixed on-screen size and each shows
only when its row neighbours are far enough apart to read it: zoom in with
the wheel to see more.  Hovering a node always tells its number, symbol and
role.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from PySide6.QtCore import QEvent, QObject, QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QFontMetrics, QPainter, QPen, QWheelEvent
from PySide6.QtWidgets import QGraphicsItem, QGraphicsScene, QGraphicsView, QHBoxLayout, QLabel, QPushButton, QWidget

from ramure.app.desktop import state
from ramure.app.desktop.panels.common import dock_column
from ramure.errors import RamureError

if TYPE_CHECKING:
    from PySide6.QtWidgets import QGraphicsSimpleTextItem
    from PySide6.QtGui import QResizeEvent
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.state import GraphLayout, Snapshot

SOURCE_COLOR = QColor("#3b6fd8")
SINK_COLOR = QColor("#e08a1e")
CUT_COLOR = QColor("#d00000")
X_STEP, Y_STEP, RADIUS = 30.0, 18.0, 5.0
LABEL_POINTS = 8


class CutGraphView(QWidget):
    """A zoomable drawing of a cut graph, with a legend and a "plan for selection" button.

    Given a ``controller``, the button plans the selection's cut (:meth:`plan`); a refusal is
    emitted as :attr:`refused`, and :attr:`to_front` asks for the dock in front of its tabs
    (True: opened too, it may be closed)."""

    refused = Signal(str)
    to_front = Signal(bool)

    def __init__(self, controller: Controller | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.scene = QGraphicsScene(self)
        self.view = QGraphicsView(self.scene)
        self.view.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.view.setDragMode(QGraphicsView.DragMode.ScrollHandDrag)
        self.view.setTransformationAnchor(QGraphicsView.ViewportAnchor.AnchorUnderMouse)
        self.view.viewport().installEventFilter(self)
        self.title = QLabel("No cut yet: select branches, then Regrow or Prune.")
        self.title.setWordWrap(True)
        self.plan_button = QPushButton("Show the cut for the selection")
        if controller is not None:
            self.plan_button.clicked.connect(self.plan)
        legend = QLabel(
            '<span style="color:#3b6fd8">● source side</span> &nbsp; '
            '<span style="color:#e08a1e">● sink side</span> &nbsp; '
            '<span style="color:#d00000">━ cut edge, ○ regrown root</span>'
        )
        self.hint = QLabel("")
        self.hint.setStyleSheet("color: #666;")
        top = QHBoxLayout()
        top.addWidget(self.title, 1)
        top.addWidget(self.plan_button)
        bottom = QHBoxLayout()
        bottom.addWidget(legend)
        bottom.addStretch(1)
        bottom.addWidget(self.hint)
        dock_column(self, top, bottom).addWidget(self.view, 1)
        self.layout_data: GraphLayout | None = None
        self.labels: list[QGraphicsSimpleTextItem] = []
        self.label_width = 0.0
        self.label_font = QFont()
        self.label_font.setPointSize(LABEL_POINTS)

    def show_snapshot(self, snap: Snapshot) -> None:
        """Show the last regrow's cut graph (nothing before the first edit)."""
        result = snap.last_result
        if result is None:
            return
        if snap.cut_layout is None:
            cut = result.cut
            words = state.edit_words(result)
            self.clear(
                f"Last edit: {words}. {state.cut_too_large_words(cut)}"
                if cut is not None
                else f"Last {result.op}: the whole plant (no cut)."
            )
            return
        self.show_layout(snap.cut_layout, f"Last edit: {state.edit_words(result)}; cut capacity {result.cut_value:g}")

    def plan(self) -> None:
        """Show the cut a regrow of the selection would make (the Plan button)."""

        def plan(ex):
            cut = ex.plan()
            return cut, (
                state.cut_graph_layout(cut, ex.derivation.tree, cut.roots, ex.lsystem.symbols)
                if state.drawable_cut(cut)
                else None
            )

        assert self.controller is not None  # the button is connected only with one
        try:
            cut, layout = self.controller.read(plan, wait=2.0)
        except RamureError as exc:
            self.refused.emit(str(exc))
            return
        if cut is None:
            self.clear("Select branches first: the cut is planned for the selection.")
            return
        if layout is None:
            self.clear(f"Planned cut for the selection, cut value {cut.cut_value:g}. {state.cut_too_large_words(cut)}")
            self.to_front.emit(False)
            return
        self.show_layout(layout, f"Planned cut for the selection: roots {cut.roots.tolist()[:12]}, cut value {cut.cut_value:g}")
        self.to_front.emit(True)

    def clear(self, message: str) -> None:
        """Show no graph, only ``message``."""
        self.scene.clear()
        self.labels = []
        self.layout_data = None
        self.title.setText(message)
        self.hint.setText("")

    def show_layout(self, layout: GraphLayout, title: str) -> None:
        """Draw a :class:`~ramure.app.desktop.state.GraphLayout`."""
        self.scene.clear()
        self.labels = []
        self.layout_data = layout
        self.title.setText(title)
        pos = {v: QPointF(x * X_STEP, y * Y_STEP) for v, (x, y) in layout.positions.items()}
        thin = QPen(QColor("#999999"), 1.0)
        cut_pen = QPen(CUT_COLOR, 3.0)
        for u, v, _cap, is_cut in layout.edges:
            if u in pos and v in pos:
                line = self.scene.addLine(pos[u].x(), pos[u].y(), pos[v].x(), pos[v].y(), cut_pen if is_cut else thin)
                if is_cut:
                    line.setZValue(1)
        widest = ""
        rows: dict[float, list[float]] = {}
        for v, p in pos.items():
            if isinstance(v, tuple) and v[1] == "in":
                rows.setdefault(p.y(), []).append(p.x())
        gaps, below = {}, {}  # labels alternate above / below their row: twice the room
        for y, xs in rows.items():
            xs.sort()
            for i, x in enumerate(xs):
                left = x - xs[i - 2] if i > 1 else float("inf")
                right = xs[i + 2] - x if i + 2 < len(xs) else float("inf")
                gaps[x, y] = min(left, right)
                below[x, y] = i % 2 == 1
        for v, p in pos.items():
            terminal = v in ("s", "t")
            r = RADIUS * (1.8 if terminal else 1.0)
            source = v in layout.source_side
            color = SOURCE_COLOR if source else SINK_COLOR
            node = v[0] if isinstance(v, tuple) else None
            brush = QBrush(CUT_COLOR if node in layout.selected and v[1] == "out" else color)
            pen = QPen(CUT_COLOR, 2.5) if node in layout.roots and v[1] == "in" else QPen(Qt.PenStyle.NoPen)
            item = self.scene.addEllipse(QRectF(p.x() - r, p.y() - r, 2 * r, 2 * r), pen, brush)
            item.setZValue(2)
            item.setToolTip(self._tooltip(layout, v, source))
            if terminal or v[1] == "in":
                text = self.scene.addSimpleText(v if terminal else str(node), self.label_font)
                text.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)
                low = not terminal and below[p.x(), p.y()]
                width = QFontMetrics(self.label_font).horizontalAdvance(text.text())
                # ignores the view's scale: placed by its top-left corner, centred by hand in fit()
                text.anchor = (  # type: ignore[attr-defined]  # a Python attribute on the Qt item
                    p,
                    -width / 2,
                    0.8 * Y_STEP + r if low else -r - 2 * LABEL_POINTS,
                )
                text.setPos(p.x() + r, p.y() - 2.5 * r) if terminal else None
                text.setZValue(3)
                text.setToolTip(item.toolTip())
                if not terminal:
                    text.gap = gaps[p.x(), p.y()]  # type: ignore[attr-defined]  # scene distance to the labels beside it
                    self.labels.append(text)
                    widest = max(widest, str(node), key=len)
        self.label_width = QFontMetrics(self.label_font).horizontalAdvance(widest + "0")
        self.scene.setSceneRect(self.scene.itemsBoundingRect().adjusted(-10, -10, 10, 10))  # not the old graph's
        self.fit()

    @staticmethod
    def _tooltip(layout, v, source):
        if v in ("s", "t"):
            return "source (the kept plant)" if v == "s" else "sink (what is regrown)"
        node, end = v
        roles = ["source side" if source else "sink side"]
        if node in layout.roots:
            roles.append("regrown root")
        if node in layout.selected:
            roles.append("selected leaf")
        name = layout.names.get(node)
        depth = layout.depths.get(node)
        what = f"node {node}" + (f" ({name})" if name else "") + (f", depth {depth}" if depth is not None else "")
        return f"{what} — {end} vertex, {', '.join(roles)}"

    def fit(self) -> None:
        """Fit the whole graph in the view, then show or hide the node numbers."""
        if self.layout_data is None:
            return
        rect = self.scene.itemsBoundingRect().adjusted(-10, -10, 10, 10)
        port = self.view.viewport().size()
        fit_w = port.width() / max(rect.width(), 1.0)
        fit_h = port.height() / max(rect.height(), 1.0)
        readable = (self.label_width + 4) / X_STEP  # columns a label apart
        scale = min(fit_h, max(fit_w, readable), 2.0)
        self.view.resetTransform()
        self.view.scale(scale, scale)
        self.view.centerOn(rect.center())
        self.update_labels()

    def update_labels(self) -> None:
        """Node numbers only where neighbouring columns are at least a label apart on screen."""
        scale = self.view.transform().m11()
        hidden = 0
        for text in self.labels:
            p, dx, dy = text.anchor  # type: ignore[attr-defined]  # a Python attribute set on the Qt item in show_layout
            text.setPos(p.x() + dx / scale, p.y() + dy / scale if dy < 0 else p.y() + dy)
            readable = text.gap * scale >= self.label_width  # type: ignore[attr-defined]  # a Python attribute set on the Qt item in show_layout
            text.setVisible(readable)
            hidden += not readable
        across = self.view.horizontalScrollBar().maximum() > 0
        if hidden:
            self.hint.setText(
                f"{hidden} of {len(self.labels)} node numbers hidden: zoom in (wheel) to read them, or hover a node"
            )
        else:
            self.hint.setText(f"{len(self.labels)} nodes; hover one for details" + (" — drag to scroll across" if across else ""))

    def labels_shown(self) -> int:
        """How many node numbers are visible."""
        return sum(text.isVisible() for text in self.labels)

    def zoom(self, factor: float) -> None:
        """Scale the graph by ``factor`` (labels follow)."""
        self.view.scale(factor, factor)
        self.update_labels()

    def resizeEvent(self, event: QResizeEvent) -> None:  # noqa: N802 (Qt API)
        """Keep the graph fitted in the dock."""
        super().resizeEvent(event)
        self.fit()

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt API)
        """The mouse wheel zooms instead of scrolling."""
        if obj is self.view.viewport() and isinstance(event, QWheelEvent):
            self.zoom(1.15 if event.angleDelta().y() > 0 else 1 / 1.15)
            return True
        return super().eventFilter(obj, event)
