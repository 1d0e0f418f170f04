"""The regeneration panel: ρ, Regrow, Regrow with constants, qualifiers, fruit, Prune, Undo/Redo.

The panel only collects the user's choices and emits them; the window turns
them into model jobs.  "Regrow with constants" sends the values typed in the
panel's own constant boxes that differ from the plant's current constants:
they apply to the selection's regrown subtrees only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QPixmap
from PySide6.QtWidgets import (
    QComboBox,
    QCompleter,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QScrollArea,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from ramure.app.desktop.panels.common import dock_column, number_box
from ramure.app.desktop.state import changed_constants

if TYPE_CHECKING:
    from PySide6.QtGui import QImage
    from ramure.app.desktop.state import Snapshot

THUMB = 96


def _fruit_presets():
    from ramure.gmap.organs.fruit import PRESETS

    return list(PRESETS)


class RegenPanel(QWidget):
    """Buttons and values for regrowing or pruning the selection."""

    rho_changed = Signal(int)  # 1..100
    regrow = Signal()
    regrow_with_constants = Signal(dict)
    qualifier_chosen = Signal(str)  # the qualifier in the drop-down changed (preview)
    apply_qualifier = Signal(str)
    regrow_fruit = Signal(str)  # a gmap.fruit preset name, or "" to keep each fruit's preset
    prune = Signal()
    undo = Signal()
    redo = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.boxes: dict[str, QDoubleSpinBox] = {}
        self._current: dict[str, float] = {}
        rho_row = self._rho_row()
        buttons = self._edit_buttons()
        self._notes()
        self.constants_box = self._constants_group()
        qual = self._qualifier_group()
        self.fruit_box = self._fruit_group()
        layout = dock_column(self, rho_row, buttons, self.cut_preview, self.note, qual, self.fruit_box)
        layout.addWidget(self.constants_box, 1)
        self.set_qualifiers([], "Qualifiers need a variant exploration (Variants ▸ Explore).")
        self.set_fruit_selection(0, 0)

    def _rho_row(self) -> QHBoxLayout:
        """The ρ slider and its value."""
        self.rho = QSlider(Qt.Orientation.Horizontal)
        self.rho.setObjectName("rho")
        self.rho.setRange(1, 100)
        self.rho.setValue(50)
        self.rho_label = QLabel("ρ = 50")
        self.rho.setToolTip(
            "ρ: a parent is regrown whole when more than ρ % of its leaves are selected — "
            "lower ρ regrows larger parts, higher ρ stays closer to the selection"
        )
        self.rho.valueChanged.connect(self._rho)
        rho_row = QHBoxLayout()
        rho_row.addWidget(QLabel("ρ"))
        rho_row.addWidget(self.rho, 1)
        rho_row.addWidget(self.rho_label)
        return rho_row

    def _edit_buttons(self) -> QGridLayout:
        """Regrow, Prune, Undo, Redo."""
        self.regrow_button = QPushButton("Regrow")
        self.regrow_button.setToolTip(
            "Regrow the selection's cut subtrees with a new seed (the whole plant when nothing is selected)"
        )
        self.regrow_button.clicked.connect(self.regrow)
        self.prune_button = QPushButton("Prune")
        self.prune_button.setToolTip("Delete the selection's cut subtrees")
        self.prune_button.clicked.connect(self.prune)
        self.undo_button = QPushButton("Undo")
        self.undo_button.clicked.connect(self.undo)
        self.redo_button = QPushButton("Redo")
        self.redo_button.clicked.connect(self.redo)
        buttons = QGridLayout()
        buttons.addWidget(self.regrow_button, 0, 0)
        buttons.addWidget(self.prune_button, 0, 1)
        buttons.addWidget(self.undo_button, 1, 0)
        buttons.addWidget(self.redo_button, 1, 1)
        return buttons

    def _notes(self) -> None:
        """The regrow's note (why nothing changed...) and the cut preview's line, hidden until used."""
        self.note = QLabel("")
        self.note.setObjectName("regrowNote")
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #7a4d00;")
        self.note.hide()
        self.cut_preview = QLabel("")  # what a regrow of the selection would change (orange in the view)
        self.cut_preview.setObjectName("cutPreview")
        self.cut_preview.setWordWrap(True)
        self.cut_preview.setStyleSheet("color: #a05000;")
        self.cut_preview.hide()

    def _constants_group(self) -> QGroupBox:
        """Constants for the selection: one box per constant, Regrow with constants, Reset."""
        box = QGroupBox("Constants for the selection")
        self.constants_form = QFormLayout()
        host = QWidget()
        host.setLayout(self.constants_form)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(host)
        scroll.setMinimumHeight(90)
        self.with_constants_button = QPushButton("Regrow with constants")
        self.with_constants_button.setToolTip("Regrow the selection using the values above (only for the regrown parts)")
        self.with_constants_button.clicked.connect(self._with_constants)
        self.reset_constants_button = QPushButton("Reset values")
        self.reset_constants_button.clicked.connect(lambda: self.show_constants(self._current, force=True))
        cbox = QVBoxLayout(box)
        cbox.addWidget(scroll, 1)
        row = QHBoxLayout()
        row.addWidget(self.with_constants_button)
        row.addWidget(self.reset_constants_button)
        cbox.addLayout(row)
        return box

    def _qualifier_group(self) -> QGroupBox:
        """The qualifier box (typed or chosen), its preview picture and Apply."""
        qual = QGroupBox("Qualifier")
        self.qualifier = QComboBox()
        self.qualifier.setObjectName("qualifier")
        # the words people type: "taller", "plus touffu", French names (the model reads them all)
        self.qualifier.setEditable(True)
        self.qualifier.setInsertPolicy(QComboBox.InsertPolicy.NoInsert)
        typed = self.qualifier.lineEdit()
        assert typed is not None  # an editable combo box has its line edit
        typed.setPlaceholderText("a word: taller, denser, plus touffu…")
        typed.returnPressed.connect(lambda: self._qualifier_changed(self.qualifier.currentText()))
        self.qualifier.textActivated.connect(self._qualifier_changed)  # chosen from the list
        self.preview = QLabel()
        self.preview.setFixedSize(THUMB, THUMB)
        self.preview.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.preview.setStyleSheet("border: 1px solid #bbb; background: white; color: #888;")
        self.preview.setToolTip("The whole plant with the qualifier's best-ranked variant")
        self.apply_button = QPushButton("Apply qualifier")
        self.apply_button.clicked.connect(lambda: self.apply_qualifier.emit(self.qualifier.currentText()))
        self.qualifier_note = QLabel("")
        self.qualifier_note.setWordWrap(True)
        qgrid = QGridLayout(qual)
        qgrid.addWidget(self.qualifier, 0, 0)
        qgrid.addWidget(self.apply_button, 1, 0)
        qgrid.addWidget(self.qualifier_note, 2, 0)
        qgrid.addWidget(self.preview, 0, 1, 3, 1)
        return qual

    def _fruit_group(self) -> QGroupBox:
        """Fruit: a shape preset and Regrow fruit, with a note on the selection."""
        box = QGroupBox("Fruit")
        self.fruit_preset = QComboBox()
        self.fruit_preset.setObjectName("fruitPreset")
        self.fruit_preset.addItem("same shape, new seed", "")  # the presets: once the plant has fruit
        self.regrow_fruit_button = QPushButton("Regrow fruit")
        self.regrow_fruit_button.setObjectName("regrowFruit")
        self.regrow_fruit_button.clicked.connect(lambda: self.regrow_fruit.emit(self.fruit_preset.currentData() or ""))
        self.fruit_note = QLabel("")
        self.fruit_note.setWordWrap(True)
        fgrid = QGridLayout(box)
        fgrid.addWidget(self.fruit_preset, 0, 0)
        fgrid.addWidget(self.regrow_fruit_button, 0, 1)
        fgrid.addWidget(self.fruit_note, 1, 0, 1, 2)
        return box

    def _rho(self, value) -> None:
        self.rho_label.setText(f"ρ = {value}")
        self.rho_changed.emit(value)

    def set_rho(self, percent: float) -> None:
        """Show ρ at ``percent`` without emitting :attr:`rho_changed`."""
        self.rho.blockSignals(True)
        self.rho.setValue(int(round(percent)))
        self.rho_label.setText(f"ρ = {self.rho.value()}")
        self.rho.blockSignals(False)

    def show_state(self, snap: Snapshot) -> None:
        """The snapshot's part of the panel: the part's constants, ρ (not while the slider is
        held: the user's own value) and what Undo and Redo can do."""
        self.show_constants(snap.constants)
        if not self.rho.isSliderDown():
            self.set_rho(snap.rho * 100)
        self.set_history(snap.can_undo, snap.can_redo)

    def set_note(self, text: str) -> None:
        """A word under the buttons about the last regrow (hidden when empty)."""
        self.note.setText(text)
        self.note.setVisible(bool(text))

    def set_cut_preview(self, text: str) -> None:
        """The cut preview's sentence ("12 of 693 modules (1.7 %) will change ..."); hidden when empty."""
        self.cut_preview.setText(text)
        self.cut_preview.setVisible(bool(text))

    def set_history(self, can_undo: bool, can_redo: bool) -> None:
        """Enable Undo and Redo as the history allows."""
        self.undo_button.setEnabled(can_undo)
        self.redo_button.setEnabled(can_redo)

    def set_selection_size(self, count: int) -> None:
        """Say on Regrow what it regrows (``count`` selected, or the whole plant); Prune needs a selection."""
        self.prune_button.setEnabled(count > 0)
        target = f"{count} selected" if count else "whole plant"
        text = f"Regrow ({target})"
        if self.regrow_button.text() != text:
            self.regrow_button.setText(text)

    def set_fruit_selection(self, selected: int, total: int, available: bool = True) -> None:
        """``selected`` of the plant's ``total`` fruit are in the selection."""
        self.fruit_box.setVisible(total > 0)
        if total > 0 and self.fruit_preset.count() == 1:
            # Named shapes from ramure.gmap.organs.fruit: gmap (with scipy.sparse, about 25 MB) loads for a
            # plant with fruit, not with every window.
            for name in _fruit_presets():
                self.fruit_preset.addItem(name.replace("_", " "), name)
        ok = available and selected > 0
        self.regrow_fruit_button.setEnabled(ok)
        self.fruit_preset.setEnabled(ok)
        if not available:
            note = "Volumetric fruit need gmap (not available)."
        elif selected:
            note = f"{selected} of {total} fruit selected: new seed or shape, drawn as volumes."
        else:
            note = f"Select fruit (click one, or a rectangle) to regrow them; {total} on the plant."
        self.fruit_note.setText(note)

    # -- constants for the selection -----------------------------------------------
    def show_constants(self, constants: Mapping[str, float], force: bool = False) -> None:
        """Offer ``constants`` (the plant's current values); keeps typed values unless ``force``."""
        changed_names = list(constants) != list(self.boxes)
        typed = changed_constants(self.values(), self._current) if not force else {}
        self._current = dict(constants)
        if changed_names:
            while self.constants_form.rowCount():
                self.constants_form.removeRow(0)
            self.boxes = {}
            for name in constants:
                box = number_box(-1e9, 1e9, 4, name=f"regen_{name}")
                self.boxes[name] = box
                self.constants_form.addRow(name, box)
        for name, box in self.boxes.items():
            box.setValue(typed.get(name, constants[name]))
        self.with_constants_button.setEnabled(bool(self.boxes))

    def values(self) -> dict[str, float]:
        """The values in the panel's own constant boxes."""
        return {name: box.value() for name, box in self.boxes.items()}

    def _with_constants(self) -> None:
        self.regrow_with_constants.emit(changed_constants(self.values(), self._current))

    # -- qualifiers ---------------------------------------------------------------
    def set_qualifiers(
        self, names: Sequence[str], note: str = "", tips: Mapping[str, str] | None = None, words: Sequence[str] = ()
    ) -> None:
        """Offer the qualifiers ``names`` in the list; ``words``: every word typing may complete
        to (synonyms, comparatives, French), which the model resolves."""
        self.qualifier.blockSignals(True)
        self.qualifier.clear()
        self.qualifier.addItems(list(names))
        completer = QCompleter(sorted(set(names) | set(words)), self.qualifier)
        completer.setCaseSensitivity(Qt.CaseSensitivity.CaseInsensitive)
        completer.setFilterMode(Qt.MatchFlag.MatchContains)
        self.qualifier.setCompleter(completer)
        for i, name in enumerate(names):
            if tips and name in tips:
                self.qualifier.setItemData(i, tips[name], Qt.ItemDataRole.ToolTipRole)
        self.qualifier.blockSignals(False)
        self.qualifier.setEnabled(bool(names))
        self.apply_button.setEnabled(bool(names))
        self.qualifier_note.setText(note)
        self.set_preview(None)
        if names:
            self._qualifier_changed(self.qualifier.currentText())

    def _qualifier_changed(self, name) -> None:
        if name:
            self.qualifier_chosen.emit(name)

    def set_preview(self, image: QImage | None) -> None:
        """Show a QImage (or None) as the qualifier's preview thumbnail."""
        if image is None:
            self.preview.clear()
            self.preview.setText("preview\nafter the\nexploration")
            return
        self.preview.setPixmap(
            QPixmap.fromImage(image).scaled(
                THUMB, THUMB, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation
            )
        )
