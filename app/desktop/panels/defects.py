"""The Defects dock: cracks, hail, shrinkage, rot and excrescences on the selected fruit (issue 17).

Pick a defect kind, edit its options (the field starts with an example), press *Add*: the
spec joins the list.  *Apply to the selected fruit* records the list on the fruit selected in
the main view, as one undoable edit (Edit > Undo takes it back; the list and the view follow).
The dock's own 3D view shows that fruit rebuilt with one volume subdivision and damaged, and
one line of facts: the defects, the volume lost and the OECD/UNECE grade with its reasons.
Selecting another fruit shows its recorded defects.  Refusals (a bad spec, no fruit
selected, a defect the fruit cannot take) are shown in the dock in one line and change
nothing.  The work runs in the controller's worker; the logic is
:mod:`ramure.app.fruit_defects`, shared with the Jupyter tab.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QTimer, Signal
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QLineEdit, QListWidget, QPushButton, QWidget

from ramure.app.desktop.panels.common import dock_column
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
        layout = dock_column(self, row, self.specs, buttons, self.facts)
        self.view_slot = LazyView(plotter_factory or _interactor)  # made when the dock is first shown
        layout.addWidget(self.view_slot, 1)
        controller.job_done.connect(self._job_done)
        controller.plant_changed.connect(lambda _snap: QTimer.singleShot(0, self.refresh))
        controller.selection_changed.connect(lambda _sel: QTimer.singleShot(0, self.refresh))

    @property
    def plotter(self) -> Any:
        """The dock's 3D view (made on first use if the dock was never shown)."""
        return self.view_slot.plotter()

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
            return ("shown", damaged_fruit(ex))

        return self.controller.submit(JOB, run, key="defects-view")

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
        gm, facts = shown
        self._show(gm, facts, keep_list=(what == "applied"))

    def _show(self, gm, facts, keep_list=False):
        from ramure.app.fruit_defects import facts_text, surface

        self.last_facts = facts
        if not keep_list:
            self.specs.clear()
            self.specs.addItems(facts["specs"])
        self.shown_leaf = facts["leaf"]
        self.facts.setText(facts_text(facts))
        self.facts.setStyleSheet("")
        skin = surface(gm)
        self.plotter.clear_actors()
        self.plotter.add_mesh(skin, scalars="rgb", rgb=True, name="defects_fruit", reset_camera=True)
        self.plotter.reset_camera()
        self.plotter.render()

    def _refused(self, err):
        text = str(err).splitlines()[0] if isinstance(err, RamureError) else f"failed: {err}"
        self.facts.setText(f"Refused: {text}")
        self.facts.setStyleSheet("color: #b00020")
        self.status.emit(f"Defects: {text}", 6000)


def _interactor(parent: QWidget) -> Any:
    """The dock's own 3D view: a white background."""
    from ramure.app.desktop.panels.common import dock_plotter

    return dock_plotter(parent, "white")
