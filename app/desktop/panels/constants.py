"""The constants panel: one slider and spin box per ``#define``, derivation count and seed.

Rows are rebuilt when the grammar's constant names change.  Each slider
covers a range inferred from the grammar's value
(:func:`ramure.app.desktop.state.constant_range`); "Edit ranges" shows min/max boxes
to change it, and typing a value outside the range widens it.  A change is
emitted (:attr:`ConstantsPanel.constant_changed`) after a short pause so a
slider drag re-derives a few times, not at every pixel; the changes of one
drag carry the same non-zero gesture number, and the last one is sent at
once on release, so the drag makes one undo step.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QDoubleSpinBox,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QScrollArea,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from ramure.app.desktop.panels.common import dock_column, number_box
from ramure.app.desktop.state import constant_range

if TYPE_CHECKING:
    from ramure.app.desktop.state import Snapshot

SLIDER_STEPS = 1000
SETTLE_MS = 60
LIMIT = 1e9
ROWS_SHOWN = 8  # constants shown without scrolling
SEED_LIMIT = 2.0**53  # the largest whole number a double holds exactly


def _spin(width: int = 96) -> QDoubleSpinBox:
    """A constant's value, min or max box: sent when typing ends, accelerated when held."""
    return number_box(-LIMIT, LIMIT, 4, width=width, live=False)


class ConstantRow:
    """The widgets of one constant: label, slider, value box and (hidden) min/max boxes."""

    def __init__(self, panel: ConstantsPanel, name: str, value: float) -> None:
        self.panel, self.name = panel, name
        self.label = QLabel(name)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, SLIDER_STEPS)
        self.slider.setObjectName(f"slider_{name}")
        self.slider.setMinimumWidth(90)
        self.value = _spin()
        self.value.setObjectName(f"value_{name}")
        self.low, self.high = _spin(width=80), _spin(width=80)
        self.lo, self.hi = constant_range(value)
        self.low.setValue(self.lo)
        self.high.setValue(self.hi)
        self.set_value(value)
        self.slider.valueChanged.connect(self._slid)
        self.slider.sliderPressed.connect(lambda: panel._begin_drag(name))
        self.slider.sliderReleased.connect(panel._end_drag)
        self.value.valueChanged.connect(self._typed)
        self.low.valueChanged.connect(self._range_typed)
        self.high.valueChanged.connect(self._range_typed)

    def widgets(self) -> list[QWidget]:
        """The row's widgets in grid order: name, slider, value, min, max."""
        return [self.label, self.slider, self.value, self.low, self.high]

    def set_value(self, value: float) -> None:
        """Show ``value`` without emitting anything (widening the range if needed)."""
        value = float(value)
        if value < self.lo or value > self.hi:
            self.set_range(min(self.lo, value), max(self.hi, value))
        for w in (self.slider, self.value):
            w.blockSignals(True)
        self.value.setValue(value)
        self.slider.setValue(self._to_step(value))
        for w in (self.slider, self.value):
            w.blockSignals(False)

    def set_range(self, lo: float, hi: float) -> None:
        """The slider's range ``[lo, hi]``; ValueError unless ``hi > lo``."""
        lo, hi = float(lo), float(hi)
        if not hi > lo:
            raise ValueError(f"{self.name}: the range maximum must be above its minimum ({lo:g} .. {hi:g})")
        self.lo, self.hi = lo, hi
        for box, v in ((self.low, lo), (self.high, hi)):
            box.blockSignals(True)
            box.setValue(v)
            box.blockSignals(False)
        self.slider.blockSignals(True)
        self.slider.setValue(self._to_step(self.value.value()))
        self.slider.blockSignals(False)

    def _to_step(self, value):
        return int(round((value - self.lo) / (self.hi - self.lo) * SLIDER_STEPS))

    def _slid(self, step) -> None:
        value = self.lo + (self.hi - self.lo) * step / SLIDER_STEPS
        value = float(f"{value:.6g}")
        self.value.blockSignals(True)
        self.value.setValue(value)
        self.value.blockSignals(False)
        self.panel._changed(self.name, value)

    def _typed(self, value) -> None:
        if value < self.lo or value > self.hi:
            self.set_range(min(self.lo, value), max(self.hi, value))
        self.slider.blockSignals(True)
        self.slider.setValue(self._to_step(value))
        self.slider.blockSignals(False)
        self.panel._changed(self.name, value)

    def _range_typed(self, _) -> None:
        lo, hi = self.low.value(), self.high.value()
        if hi > lo:
            self.set_range(lo, hi)
            self.panel.range_refused.emit("")
        else:
            self.set_range(self.lo, self.hi)  # put the boxes back
            self.panel.range_refused.emit(f"{self.name}: the maximum must be above the minimum")


class ConstantsPanel(QWidget):
    """Sliders for the grammar's constants plus the derivation count and seed."""

    constant_changed = Signal(str, float, int)  # name, value, drag gesture (0: a single change)
    derivation_changed = Signal(int, object)  # n, seed (a Python int: seeds go past 2^31)
    range_refused = Signal(str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.rows: dict[str, ConstantRow] = {}
        self._pending: dict[str, tuple[float, int]] = {}  # name -> (value, gesture)
        self._gesture = 0  # the slider drag in progress (0: none)
        self._gestures = 0
        self._dragged = None
        self.settle = QTimer(self)
        self.settle.setSingleShot(True)
        self.settle.setInterval(SETTLE_MS)
        self.settle.timeout.connect(self._flush)

        self.n_box = QSpinBox()
        self.n_box.setObjectName("derivationCount")
        self.n_box.setRange(0, 30)
        self.n_box.setKeyboardTracking(False)
        self.seed_box = QDoubleSpinBox()  # a whole number, but beyond a QSpinBox's 2^31 (a regrow's seed)
        self.seed_box.setObjectName("seed")
        self.seed_box.setDecimals(0)
        self.seed_box.setRange(0, SEED_LIMIT)
        self.seed_box.setKeyboardTracking(False)
        self.seed_box.setMinimumWidth(70)  # its hint fits 2^53: the dock would be 40 px wider
        self.n_box.valueChanged.connect(self._derivation)
        self.seed_box.valueChanged.connect(self._derivation)
        derivation = QGroupBox("Derivation")
        row = QHBoxLayout(derivation)
        row.setContentsMargins(6, 2, 6, 2)
        row.addWidget(QLabel("Steps n"))
        row.addWidget(self.n_box, 1)
        row.addWidget(QLabel("Seed"))
        row.addWidget(self.seed_box, 2)

        self.edit_ranges = QCheckBox("Edit ranges")
        self.edit_ranges.toggled.connect(self._show_ranges)
        self.grid_host = QWidget()
        self.grid = QGridLayout(self.grid_host)
        self.grid.setColumnStretch(1, 1)
        self.empty = QLabel("The grammar has no #define constants.")
        self.empty.setWordWrap(True)
        scroll = self.list_area = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(self.grid_host)
        consts = QGroupBox("Constants (#define)")
        box = QVBoxLayout(consts)
        box.addWidget(self.edit_ranges)
        box.addWidget(self.empty)
        box.addWidget(scroll, 1)
        dock_column(self, derivation).addWidget(consts, 1)

    # -- from the model --------------------------------------------------------
    def show_snapshot(self, snap: Snapshot, grammar_constants: Mapping[str, float]) -> None:
        """Show the values of ``snap``; rebuild the rows if the constant names changed."""
        names = list(grammar_constants)
        if names != list(self.rows):
            self._rebuild(grammar_constants)
        for name, row in self.rows.items():
            if name not in self._pending and not row.slider.isSliderDown():  # never under the cursor
                row.set_value(snap.constants.get(name, grammar_constants[name]))
        for box, v in ((self.n_box, snap.n), (self.seed_box, snap.seed)):
            box.blockSignals(True)
            box.setValue(int(v))
            box.blockSignals(False)

    def _rebuild(self, constants) -> None:
        while self.grid.count():
            item = self.grid.takeAt(0)
            widget = item.widget() if item is not None else None
            if widget is not None:
                widget.deleteLater()
        self.rows = {}
        for col, title in enumerate(("", "", "value", "min", "max")):
            if title:
                label = QLabel(title)
                label.setProperty("rangeHeader", col >= 3)
                self.grid.addWidget(label, 0, col)
        for i, (name, value) in enumerate(constants.items(), start=1):
            row = ConstantRow(self, name, value)
            self.rows[name] = row
            for col, w in enumerate(row.widgets()):
                self.grid.addWidget(w, i, col)
        self.grid.setRowStretch(len(constants) + 1, 1)
        self.empty.setVisible(not constants)
        self._show_ranges(self.edit_ranges.isChecked())
        self._fit_rows()

    def _fit_rows(self) -> None:
        """The list is tall enough for its header and :data:`ROWS_SHOWN` rows (a longer list
        scrolls): the last constant is never cut off by a dock squeezed below it."""
        grid = self.grid
        height = 0
        for r in range(min(len(self.rows), ROWS_SHOWN) + 1):
            items = [grid.itemAtPosition(r, c) for c in range(3)]
            height += max((i.sizeHint().height() for i in items if i is not None), default=0) + grid.verticalSpacing()
        margins = grid.contentsMargins()
        frame = 2 * self.list_area.frameWidth()
        self.list_area.setMinimumHeight(height + margins.top() + margins.bottom() + frame)

    def _show_ranges(self, on) -> None:
        for row in self.rows.values():
            row.low.setVisible(on)
            row.high.setVisible(on)
        for i in range(self.grid.count()):
            item = self.grid.itemAt(i)
            w = item.widget() if item is not None else None
            if w is not None and w.property("rangeHeader"):
                w.setVisible(on)

    # -- to the model ----------------------------------------------------------
    def _begin_drag(self, name) -> None:
        self._gestures += 1
        self._gesture, self._dragged = self._gestures, name

    def _end_drag(self) -> None:
        """Release: send the final value now; the drag's changes were one gesture."""
        self.settle.stop()
        self._flush()
        self._gesture, self._dragged = 0, None

    def _changed(self, name, value) -> None:
        self._pending[name] = (float(value), self._gesture if name == self._dragged else 0)
        self.settle.start()

    def _flush(self) -> None:
        pending, self._pending = self._pending, {}
        for name, (value, gesture) in pending.items():
            self.constant_changed.emit(name, value, gesture)

    def flush(self) -> None:
        """Send a change still waiting for the pause (before Undo or Save)."""
        if self._pending:
            self.settle.stop()
            self._flush()

    def _derivation(self, _) -> None:
        self.derivation_changed.emit(self.n_box.value(), int(self.seed_box.value()))

    # -- for tests and scripting ------------------------------------------------
    def set_constant(self, name: str, value: float, now: bool = True) -> None:
        """Type ``value`` into ``name``'s box (as a user would); ``now`` skips the pause."""
        self.rows[name].value.setValue(float(value))
        if now:
            self.settle.stop()
            self._flush()

    def values(self) -> dict[str, float]:
        """Each constant's value as shown."""
        return {name: row.value.value() for name, row in self.rows.items()}
