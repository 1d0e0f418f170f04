"""The Wood dock: volumetric wood (3G-map) of a species or of the current plant, with a live cut.

Choose a species and a number of years and press *Grow*: the wood (pith,
earlywood/latewood rings, heartwood, sapwood, bark and knots, see
:mod:`ramure.gmap.organs.wood`) appears in the dock's own 3D view, clipped by a
plane widget you drag and turn (VTK clip, re-cut live).  *From the current
plant* grows the wood of the plant shown in the main window: its trunk and
branches of every order (a branch's branches are knots in its wood), with
their ages from the derivation steps.  Selecting a branch of that plant in
the main view paints its knot red in the cut.

Growth runs in the GUI thread (a 10-year trunk takes about a second; the
dock shows a busy cursor); the refusal of bad input is shown in the dock.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QWidget,
)

from ramure.app.desktop.panels.common import dock_column, dock_plotter, number_box
from ramure.app.desktop.view.lazy_view import LazyView
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.app.desktop.controller import Controller
    import pyvista as pv
    from ramure.gmap.organs.wood import Wood

SELECTED_RGB = (220, 30, 30)
PRESETS = ("flat-sawn", "quarter-sawn", "rift")  # as ramure.gmap.organs.wood.PLANK_PRESETS (gmap loads late)


class WoodPanel(QWidget):
    """Species, years, *from the current plant*, Grow; a 3D view with a cut-plane widget."""

    def __init__(
        self,
        controller: Controller | None = None,
        parent: QWidget | None = None,
        plotter_factory: Callable[[QWidget], Any] | None = None,
    ) -> None:
        super().__init__(parent)
        self.controller = controller
        self.wood: Wood | None = None
        self.grid: pv.UnstructuredGrid | None = None
        self.branch_leaves: list[list[int]] = []  # per knot, the history leaves of its plant branch
        self.species = QComboBox()
        self.species.setObjectName("woodSpecies")
        self.species_listed = False  # filled by list_species(), when the dock is first shown
        self.years = QSpinBox()
        self.years.setObjectName("woodYears")
        self.years.setRange(1, 40)
        self.years.setValue(10)
        self.from_plant = QCheckBox("From the current plant")
        self.from_plant.setObjectName("woodFromPlant")
        self.grow_button = QPushButton("Grow")
        self.grow_button.setObjectName("woodGrow")
        self.grow_button.clicked.connect(self.grow)
        self.facts = QLabel("Press Grow to build the wood.")
        self.facts.setObjectName("woodFacts")
        self.facts.setWordWrap(True)
        form = QFormLayout()
        form.addRow("Species", self.species)
        form.addRow("Years", self.years)
        row = QHBoxLayout()
        row.addWidget(self.from_plant)
        row.addWidget(self.grow_button)
        layout = dock_column(self, form, row, self.plank_controls(), self.facts)
        # the view and the species list: when the dock is first on screen (see lazy_view)
        self.view_slot = LazyView(plotter_factory or dock_plotter, setup=lambda _plotter: self.list_species())
        layout.addWidget(self.view_slot, 1)
        if controller is not None and hasattr(controller, "selection_changed"):
            controller.selection_changed.connect(self.highlight_selection)

    def plank_controls(self) -> QFormLayout:
        """Plank: a preset, its direction around the trunk, offset from the pith, thickness; Saw."""
        self.plank_preset = QComboBox()
        self.plank_preset.setObjectName("woodPlankPreset")
        self.plank_preset.addItems(PRESETS)
        self.plank_preset.currentIndexChanged.connect(lambda _i: self.apply_preset())
        self.plank_direction = number_box(0.0, 359.0, 0, value=0.0, name="woodPlankDirection", suffix=" deg")
        self.plank_offset = number_box(-2000.0, 2000.0, 1, value=10.0, name="woodPlankOffset", suffix=" mm")
        self.plank_thickness = number_box(0.1, 500.0, 1, value=20.0, name="woodPlankThickness", suffix=" mm")
        self.plank_button = QPushButton("Saw plank")
        self.plank_button.setObjectName("woodPlank")
        self.plank_button.clicked.connect(self.show_plank)
        form = QFormLayout()
        form.addRow("Plank", self.plank_preset)
        form.addRow("Direction", self.plank_direction)
        form.addRow("Offset", self.plank_offset)
        form.addRow("Thickness", self.plank_thickness)
        form.addRow(self.plank_button)
        return form

    def apply_preset(self) -> None:
        """Set the offset of the chosen preset for the grown wood's trunk (the pith's offset before Grow)."""
        from ramure.gmap.organs.wood import preset_offset

        thickness = self.plank_thickness.value() / 1000.0
        if self.grid is None:
            offset = -0.5 * thickness if self.plank_preset.currentText() == "quarter-sawn" else 0.0
        else:
            offset = preset_offset(self.grid, self.plank_preset.currentText(), thickness)
        self.plank_offset.setValue(1000.0 * offset)

    def add_texture(self, part: Any, normal: Any, pixel: float, up: Any) -> None:
        """The species' pores, resin canals and rays on the board's face, one point a pixel
        (:func:`ramure.gmap.organs.wood_species.texture_face`), as ``ramure wood --plank`` draws them."""
        from ramure.gmap.organs import wood as W
        from ramure.gmap.organs.wood_species import texture_face

        species = self.species.currentText()
        if species not in W.SPECIES or not all(k in part.cell_data for k in ("wood", "season")):
            return
        face = texture_face(part, normal, species, pixel=max(pixel, 1e-5), codes=W.CODES, up=up)
        if face.n_points:
            self.plotter.add_mesh(face, scalars="rgb", rgb=True, lighting=False, name="texture")

    def show_plank(self) -> Any:
        """Saw the plank the controls describe and show a length of it around a knot, face-on, filling the view."""
        from ramure.gmap.organs import wood as W

        if self.grid is None:
            self.facts.setText("Grow the wood first, then saw a plank.")
            return None
        normal = W.plank_normal(self.plank_direction.value())
        offset, thickness = self.plank_offset.value() / 1000.0, self.plank_thickness.value() / 1000.0
        try:
            slab = W.plank(self.grid, normal, offset, thickness)
            part, at, length = W.plank_window(slab)
        except RamureError as err:
            self.facts.setText(f"Refused: {err}")
            return None
        facts = W.cut_facts(slab)
        p = self.plotter
        p.clear()
        p.add_mesh(part.extract_surface(algorithm="dataset_surface"), scalars="rgb", rgb=True, lighting=False, name="plank")
        w, h = p.window_size
        aspect = w / h if w > 0 and h > 0 else 1.0
        position, focal, up, scale = W.plank_camera(part.points, normal, aspect, upright=aspect < 1.0)  # a tall dock: as it grew
        self.add_texture(part, normal, 2.0 * scale / max(h, 1), up)
        p.enable_parallel_projection()
        p.camera_position = [tuple(position), tuple(focal), tuple(up)]
        p.camera.parallel_scale = scale
        p.reset_camera_clipping_range()
        if hasattr(p, "render"):
            p.render()
        self.facts.setText(
            f"Plank {self.plank_preset.currentText()}: {facts['rings']} rings, {facts['knots']} knot(s) "
            f"({facts['live_knots']} live, {facts['dead_knots']} dead); "
            f"{length:.3g} m shown around z = {at:.3g} m, seen from the pith's side."
        )
        return part

    def list_species(self) -> None:
        """Put the species into their list (once).  They come from ramure.gmap.organs.wood: gmap loads
        (with scipy.sparse, about 25 MB) when the dock is first on screen or grown, not with the window."""
        if self.species_listed:
            return
        from ramure.gmap.organs.wood import SPECIES

        chosen = self.species.currentText()
        self.species.addItems([name for name in sorted(SPECIES) if self.species.findText(name) < 0])
        if chosen:
            self.species.setCurrentText(chosen)
        self.species_listed = True

    @property
    def plotter(self) -> Any:
        """The dock's 3D view (made on first use if the dock was never shown)."""
        return self.view_slot.plotter()

    # -- growth ------------------------------------------------------------------------
    def grow(self) -> Wood | None:
        """Grow the wood from the widgets' values and show it with a cut plane."""
        from ramure.gmap.organs import wood as W

        self.list_species()
        QGuiApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            species, years = self.species.currentText(), int(self.years.value())
            if self.from_plant.isChecked() and self.controller is not None:
                skeleton, leaf_steps, steps = self.controller.read(
                    lambda ex: (ex.skeleton, ex.derivation.tree.step.copy(), ex.derivation.n), wait=5.0
                )
                wood = W.from_skeleton(skeleton, years, species=species, leaf_steps=leaf_steps, steps=steps)
                self.branch_leaves = list(wood.gm.meta.get("branch_leaves", []))
            else:
                wood = W.grow_wood(species, years)
                self.branch_leaves = []
        except RamureError as err:
            self.facts.setText(f"Refused: {err}")
            return None
        finally:
            QGuiApplication.restoreOverrideCursor()
        self.wood, self.grid = wood, W.smooth_grid(wood, W.to_grid(wood))  # round rings in the picture
        self.show_grid()
        counts, knots = wood.tissue_counts(), wood.knot_counts()
        gm = wood.gm
        self.facts.setText(
            f"{gm.n_darts:,} darts, {gm.n_volumes:,} volumes; "
            + ", ".join(f"{v} {k}" for k, v in counts.items() if v)
            + f"; knots: {knots['live']} live, {knots['dead']} dead"
            + W.orders_text(wood.knot_orders(), gm.meta.get("left_out"))
            + ". Drag the plane to cut."
        )
        return wood

    def show_grid(self) -> None:
        """Show the grid clipped by a plane widget (horizontal cut through the trunk at first)."""
        if self.grid is None:
            return
        p = self.plotter
        p.clear()
        p.disable_parallel_projection()  # a plank was shown face-on
        b = np.asarray(self.grid.bounds, float).reshape(3, 2)
        origin = (0.0, 0.0, float(b[2, 0] + 0.3 * (b[2, 1] - b[2, 0])))
        p.add_mesh_clip_plane(
            self.grid,
            normal="z",
            origin=origin,
            invert=True,
            scalars="rgb",
            rgb=True,
            name="wood",
            show_scalar_bar=False,
            crinkle=False,
        )
        p.view_isometric()
        p.reset_camera()
        if hasattr(p, "render"):
            p.render()

    # -- selection -------------------------------------------------------------------
    def knot_mask(self, selection: Iterable[int]) -> np.ndarray:
        """Cells of the knots whose plant branch is in ``selection`` (history-leaf ids)."""
        if self.grid is None or not self.branch_leaves:
            return np.zeros(0 if self.grid is None else self.grid.n_cells, bool)
        selected = set(int(s) for s in selection)
        knots = [b + 1 for b, leaves in enumerate(self.branch_leaves) if selected & set(leaves)]
        return np.isin(np.asarray(self.grid.cell_data["axis"]), knots)

    def highlight_selection(self, selection: Iterable[int]) -> None:
        """Paint the selected branches' knots red (the clip widget re-cuts the recoloured grid)."""
        if self.grid is None or self.wood is None:
            return
        from ramure.gmap.organs.wood import cell_colors

        rgb = cell_colors(self.wood.gm.volume_data, self.wood.species)[np.asarray(self.grid.cell_data["volume"])]
        rgb[self.knot_mask(selection)] = SELECTED_RGB  # the grid's cells: pieces of volumes (round rings, tetrahedra)
        self.grid.cell_data["rgb"] = rgb
        self.show_grid()
