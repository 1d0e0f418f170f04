"""The Defects dock: cracks, hail, shrinkage, rot and excrescences on the selected fruit (issue 17).

Pick a defect kind, edit its options (the field starts with an example), press *Add*: the
spec joins the list.  *Apply to the selected fruit* records the list on the fruit selected in
the main view, as one undoable edit (Edit > Undo takes it back; the list and the view follow).
The dock's own 3D view shows that fruit rebuilt with one volume subdivision and damaged, and
one line of facts: the defects, the volume lost and the OECD/UNECE grade with its reasons.
Selecting another fruit shows its recorded defects.  Refusals (a bad spec, no fruit
selected, a defect the fruit cannot take) are shown in the dock in one line and change
nothing.

**Regions** (issue 40 §6): in the dock's view a right-button drag draws a rubber band over
the skin (Shift adds, Ctrl removes), a right click brushes the skin cells within the
*brush* radius (mm) of the point (Shift adds, Ctrl removes); *Select* takes a label pattern
such as ``(9, C*, *)``.  The region is drawn in a light blue.  *Place defect there* adds the
defect of the kind and options fields at the region (hail and rot at its centre, a crack
along it, an excrescence on it).  *Regrow region* re-derives it
with the parameters typed beside it (``largeur=75,creux=0.4``): one undoable edit, the rest of
the fruit unchanged (:mod:`ramure.app.fruit_regions`).  The work runs in the controller's worker; the logic is
:mod:`ramure.app.fruit_defects`, shared with the Jupyter tab.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

from PySide6.QtCore import QEvent, QObject, QPoint, QRect, QSize, Qt, QTimer, Signal
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QPushButton,
    QRubberBand,
    QWidget,
)

from ramure.app.desktop.panels.common import dock_column, number_box
from ramure.app.desktop.view.lazy_view import LazyView
from ramure.app.fruit_defects import EXAMPLES
from ramure.errors import RamureError

if TYPE_CHECKING:
    from PySide6.QtGui import QShowEvent
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.workers import Job

JOB = "fruit defects"


class DefectsPanel(QWidget):
    """Kind, options, Add / Remove, the spec list, Apply; facts and a 3D view of the damaged fruit."""

    #: A message for the window's status bar (a refused defect) and how long it stays (ms).
    status = Signal(str, int)

    def __init__(
        self,
        controller: Controller,
        parent: QWidget | None = None,
        plotter_factory: Callable[[QWidget], Any] | None = None,
    ) -> None:
        super().__init__(parent)
        self.controller = controller
        self.shown_leaf = None
        self.shown_leaf_drawn = None
        self.last_facts = None
        self.kind = QComboBox()
        self.kind.setObjectName("defectsKind")
        self.kind.addItems(list(EXAMPLES))
        self.options = QLineEdit(EXAMPLES["crack"])
        self.options.setObjectName("defectsOptions")
        self.kind.currentTextChanged.connect(lambda k: self.options.setText(EXAMPLES[k]))
        self.add_button = QPushButton("Add")
        self.add_button.setObjectName("defectsAdd")
        self.add_button.clicked.connect(self.add)
        self.specs = QListWidget()
        self.specs.setObjectName("defectsList")
        self.specs.setMaximumHeight(90)
        self.remove_button = QPushButton("Remove")
        self.remove_button.setObjectName("defectsRemove")
        self.remove_button.clicked.connect(self.remove)
        self.apply_button = QPushButton("Apply to the selected fruit")
        self.apply_button.setObjectName("defectsApply")
        self.apply_button.clicked.connect(self.apply)
        self.shown_gm = None  # the fruit the view shows (a click's or a rubber band's frame)
        self.region_pattern = QLineEdit()
        self.region_pattern.setObjectName("regionPattern")
        self.region_pattern.setPlaceholderText("(5, C*, *)  or right-drag / right-click the fruit")
        self.region_select = QPushButton("Select")
        self.region_select.setObjectName("regionSelect")
        self.region_select.clicked.connect(self.select_pattern)
        self.brush = number_box(0.0, 100.0, 2, value=8.0, name="regionBrush", suffix=" mm")
        self.brush.setToolTip("Brush radius: a right click selects the skin cells this close")
        self.region_params = QLineEdit("largeur=75")
        self.region_params.setObjectName("regionParams")
        self.region_params.setToolTip(
            "Shape parameters (largeur=75, creux=0.4 ...) or a finer precision (precision=20: twice "
            "the fruit's 10), comma-separated; the rest of the fruit is not touched"
        )
        self.region_regrow = QPushButton("Regrow region")
        self.region_regrow.setObjectName("regionRegrow")
        self.region_regrow.clicked.connect(self.regrow_region)
        self.region_place = QPushButton("Place defect there")
        self.region_place.setObjectName("regionPlace")
        self.region_place.setToolTip("Add the defect kind and options above, placed in the selected region")
        self.region_place.clicked.connect(self.place_in_region)
        self.facts = QLabel("Select a fruit, add defects, press Apply.")
        self.facts.setObjectName("defectsFacts")
        self.facts.setWordWrap(True)
        row = QHBoxLayout()
        row.addWidget(self.kind)
        row.addWidget(self.options, 1)
        row.addWidget(self.add_button)
        buttons = QHBoxLayout()
        buttons.addWidget(self.remove_button)
        buttons.addWidget(self.apply_button, 1)
        regions = QHBoxLayout()
        regions.addWidget(QLabel("Region"))
        regions.addWidget(self.region_pattern, 1)
        regions.addWidget(self.region_select)
        regions.addWidget(self.brush)
        regrow = QHBoxLayout()
        regrow.addWidget(self.region_params, 1)
        regrow.addWidget(self.region_regrow)
        regrow.addWidget(self.region_place)
        layout = dock_column(self, row, self.specs, buttons, regions, regrow, self.facts)
        self.view_slot = LazyView(plotter_factory or _interactor)  # made when the dock is first shown
        layout.addWidget(self.view_slot, 1)
        controller.job_done.connect(self._job_done)
        controller.plant_changed.connect(lambda _snap: QTimer.singleShot(0, self.refresh))
        controller.selection_changed.connect(lambda _sel: QTimer.singleShot(0, self.refresh))

    @property
    def plotter(self) -> Any:
        """The dock's 3D view (made on first use if the dock was never shown)."""
        plotter = self.view_slot.plotter()
        if getattr(self, "_mouse", None) is None:
            self._mouse = _RegionMouse(self, plotter)
            plotter.interactor.installEventFilter(self._mouse)
        return plotter

    def showEvent(self, event: QShowEvent) -> None:  # noqa: N802 - Qt's name
        """Refresh the dock's fruit when it comes on screen."""
        super().showEvent(event)
        QTimer.singleShot(0, self.refresh)

    # -- the list ----------------------------------------------------------------------
    def spec_list(self) -> list[str]:
        """The specs in the list, in order."""
        return [self.specs.item(i).text() for i in range(self.specs.count())]

    def add(self) -> None:
        """Add ``kind:options`` to the list (checked now; a bad spec is refused in the dock)."""
        from ramure.app.fruit_defects import check_specs

        options = self.options.text().strip()
        spec = f"{self.kind.currentText()}:{options}" if options else self.kind.currentText()
        try:
            check_specs([spec])
        except RamureError as err:
            self._refused(err)
            return
        self.specs.addItem(spec)
        self.facts.setText(f"Added {spec}; press Apply to damage the selected fruit.")

    def remove(self) -> None:
        """Remove the selected spec (or the last one)."""
        row = self.specs.currentRow()
        self.specs.takeItem(row if row >= 0 else self.specs.count() - 1)

    # -- work ----------------------------------------------------------------------------
    def apply(self) -> Job:
        """Record the list on the selected fruit (one undoable edit) and show it damaged."""
        specs = self.spec_list()
        return self.controller.submit(JOB, lambda ex: ("applied", ex.set_fruit_defects(specs)))

    def refresh(self) -> Job | None:
        """Show the selected fruit with its recorded defects (nothing selected: say so)."""
        from ramure.app.fruit_defects import damaged_fruit

        if not self.isVisible() or self.visibleRegion().isEmpty():  # hidden, or behind another tab: shown when raised
            return None

        def run(ex):
            fruit = set(ex.fruit_ids())
            if not any(leaf in fruit for leaf in ex.selection):
                return ("none", None)
            return ("shown", _with_region(ex, damaged_fruit(ex)))

        return self.controller.submit(JOB, run, key="defects-view")

    # -- regions -------------------------------------------------------------------------
    def select_pattern(self) -> Job:
        """Select the region the label pattern names (``(9, C*, *)``) and show it."""
        text = self.region_pattern.text().strip() or self.region_pattern.placeholderText().split()[0]
        return self._select("pattern", text, mode="replace")

    def select_rectangle(self, rect: tuple[float, float, float, float], mode: str = "replace") -> Job:
        """Select the skin facing the camera inside display rectangle ``rect`` (VTK pixels)."""
        renderer = self.plotter.renderer
        camera = renderer.GetActiveCamera()
        m = camera.GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1, 1)
        matrix = [[m.GetElement(i, j) for j in range(4)] for i in range(4)]
        size = tuple(int(v) for v in renderer.GetSize())
        return self._select("rectangle", matrix, size, tuple(rect), mode=mode)

    def brush_at(self, point: Any, mode: str = "replace") -> Job:
        """Select the skin cells within the brush radius of ``point`` (the view's frame)."""
        gm = self.shown_gm
        per_mm = 1.0 / float(gm.meta.get("mm_per_unit") or 1.0) if gm is not None else 1.0
        return self._select("point", point, self.brush.value() * per_mm, mode=mode)

    def _select(self, how, *args, mode):
        from ramure.app.fruit_defects import damaged_fruit

        gm, facts, leaf = self.shown_gm, self.last_facts, self.shown_leaf

        def run(ex):
            fruit = set(ex.fruit_ids())
            if gm is None or leaf not in fruit or leaf not in ex.selection:  # the view is not the selected fruit's yet
                ex.select_fruit_region(how, *args, mode=mode)
                return ("region", _with_region(ex, damaged_fruit(ex, ex.fruit_region["leaf"])))
            ex.select_fruit_region(how, *args, mode=mode, leaf=leaf, on=gm)
            return ("region", _with_region(ex, (gm, facts)))

        return self.controller.submit(JOB, run)

    def place_in_region(self) -> Job:
        """Add the defect of the kind and options fields, placed in the selected region, to the
        fruit's recorded defects: one undoable edit."""
        options = self.options.text().strip()
        spec = f"{self.kind.currentText()}:{options}" if options else self.kind.currentText()
        return self.controller.submit(JOB, lambda ex: ("placed", _with_region(ex, ex.place_defect_in_region(spec))))

    def regrow_region(self) -> Job:
        """Regrow the selected region with the typed parameters: one undoable edit."""
        from ramure.app.fruit_regions import parse_params

        text = self.region_params.text()

        def run(ex):
            return ("regrown", _with_region(ex, ex.regrow_fruit_region(**parse_params(text))))

        return self.controller.submit(JOB, run)

    def _job_done(self, job):
        if job.name != JOB or job.stale:
            return
        if job.error is not None:
            self._refused(job.error)
            return
        if job.result is None:
            return
        what, shown = job.result
        if what == "none":
            self.shown_leaf = None
            self.facts.setText("Select a fruit in the main view: its defects show here.")
            return
        if shown is None:
            return
        if what == "applied":
            shown = (*shown, None)
        gm, facts, region = shown
        self._show(gm, facts, keep_list=(what in ("applied", "region", "regrown")), region=region)
        if what == "placed":
            self.specs.clear()
            self.specs.addItems(facts["specs"])
        if region is not None:
            from ramure.gmap.organs.regions import region_text

            verb = {"regrown": "Regrown", "placed": "Placed in"}.get(what, "Region")
            self.facts.setText(f"{verb}: {region_text(region)} of fruit {facts['leaf']}. {self.facts.text()}")

    def _show(self, gm, facts, keep_list=False, region=None):
        from ramure.app.fruit_defects import facts_text, surface
        from ramure.app.fruit_regions import highlight, region_mask

        self.last_facts = facts
        self.shown_gm = gm
        if not keep_list:
            self.specs.clear()
            self.specs.addItems(facts["specs"])
        self.shown_leaf = facts["leaf"]
        self.facts.setText(facts_text(facts))
        self.facts.setStyleSheet("")
        skin = surface(gm)
        if region is not None:
            skin = highlight(skin, region_mask(gm, region))
        same = self.shown_leaf_drawn == facts["leaf"]
        self.shown_leaf_drawn = facts["leaf"]
        self.plotter.clear_actors()
        self.plotter.add_mesh(skin, scalars="rgb", rgb=True, name="defects_fruit", reset_camera=not same)
        if not same:  # the same fruit again (a region picked): the user's view stays
            self.plotter.reset_camera()
        self.plotter.render()

    def _refused(self, err):
        text = str(err).splitlines()[0] if isinstance(err, RamureError) else f"failed: {err}"
        self.facts.setText(f"Refused: {text}")
        self.facts.setStyleSheet("color: #b00020")
        self.status.emit(f"Defects: {text}", 6000)


def _with_region(ex, shown):
    """``(map, facts)`` with the explorer's fruit region when it is on that fruit (else None)."""
    gm, facts = shown
    r = ex.fruit_region
    return gm, facts, (r["region"] if r is not None and r["leaf"] == facts["leaf"] else None)


class _RegionMouse(QObject):
    """Right-button drag: a rubber band over the skin; right click: the brush (Shift adds,
    Ctrl removes).  The left button turns the view as usual."""

    def __init__(self, panel: DefectsPanel, plotter: Any) -> None:
        super().__init__(panel)
        self.panel, self.plotter = panel, plotter
        self.start: QPoint | None = None
        self.band = QRubberBand(QRubberBand.Shape.Rectangle, plotter.interactor)

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:  # noqa: N802 - Qt's name
        kind = event.type()
        if kind not in (QEvent.Type.MouseButtonPress, QEvent.Type.MouseMove, QEvent.Type.MouseButtonRelease):
            return False
        event = cast(QMouseEvent, event)
        if kind == QEvent.Type.MouseButtonPress and event.button() == Qt.MouseButton.RightButton:
            self.start = event.position().toPoint()
            self.band.setGeometry(QRect(self.start, QSize()))
            self.band.show()
            return True
        if kind == QEvent.Type.MouseMove and self.start is not None:
            self.band.setGeometry(QRect(self.start, event.position().toPoint()).normalized())
            return True
        if kind == QEvent.Type.MouseButtonRelease and self.start is not None:
            start, end, self.start = self.start, event.position().toPoint(), None
            self.band.hide()
            mods = event.modifiers()
            ctrl, shift = Qt.KeyboardModifier.ControlModifier, Qt.KeyboardModifier.ShiftModifier
            mode = "remove" if mods & ctrl else "add" if mods & shift else "replace"
            ratio = self.plotter.interactor.devicePixelRatioF()
            height = self.plotter.renderer.GetSize()[1]

            def display(p):  # Qt widget pixels (origin top left) -> VTK display (bottom left)
                return p.x() * ratio, height - p.y() * ratio

            if (end - start).manhattanLength() > 4:
                (x0, y0), (x1, y1) = display(start), display(end)
                self.panel.select_rectangle((x0, y0, x1, y1), mode)
            else:
                point = self._pick(*display(end))
                if point is not None:
                    self.panel.brush_at(point, mode)
            return True
        return False

    def _pick(self, x: float, y: float) -> Any:
        from vtkmodules.vtkRenderingCore import vtkCellPicker

        picker = vtkCellPicker()
        picker.SetTolerance(0.005)
        if not picker.Pick(x, y, 0.0, self.plotter.renderer):
            return None
        return tuple(picker.GetPickPosition())


def _interactor(parent: QWidget) -> Any:
    """The dock's own 3D view: a white background."""
    from ramure.app.desktop.panels.common import dock_plotter

    return dock_plotter(parent, "white")
