"""The Details dock: leaves that age and fall, lichen and cracks on a fruit (issue 18).

* **Season**: a slider over the time steps of :func:`ramure.lsys.architecture.seasons.age_leaves` with the
  heat, humidity and wind it runs in.  The whole season (every step) is computed once per
  plant and environment, in the controller's worker; moving the slider then only recolours:
  each attached leaf takes its Markov state's colour (:attr:`LeafChain.colors`) in the main
  view, through the view's public :meth:`~ramure.app.desktop.view.plant_view.PlantView.set_colors`.
  A **fallen leaf's cells are hidden** on the branches
  (:meth:`~ramure.app.desktop.view.plant_view.PlantView.set_hidden_cells`; their colour is set to the
  background's, :data:`FALLEN_RGB`, as well) and the leaf is drawn again as a disc in its
  state's colour where it landed on the ground (an overlay actor named ``details_fallen``).
  Step 0 gives the plant its own colours back.  The selection stays red on top of the season
  colours.
* **Lichen** and **Crack** act on the selected fruit's closed surface (the volumetric fruit
  of :meth:`ramure.app.model.Explorer.fruit_surface`, subdivided once so a crack has
  triangles to cut): Open-DLA lichen discs coloured by age class
  (:func:`ramure.gmap.organs.lichen.grow_lichen`), or a random crack pattern carved from the top of
  the fruit (:func:`ramure.gmap.organs.cracks.carve`).  Both run in the worker and are shown in the
  dock's own 3D view, with their facts.  Without a selected fruit, or on a surface that is not
  closed, the action is refused with one line in the dock (and the window's usual message).
  **Lichen on the branches** grows on the plant's bark instead: the branches welded into one
  closed surface (:func:`ramure.app.details.plant_bark`).

The work itself (fruit surface, lichen, crack, their sizes) is :mod:`ramure.app.details`, shared
with the Jupyter tab; the crack's dock view looks down on the fruit's top, where the crack starts.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import (
    QComboBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QScrollArea,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from ramure.app.desktop.panels.common import dock_column, number_box
from ramure.app.desktop import state
from ramure.app.desktop.view.lazy_view import LazyView
from ramure.app.details import crack_on_fruit, diagonal, lichen_on_fruit, paint_adhesion, selected_fruit_surface
from ramure.app.details_history import grow_again, last_detail, record, selected_fruit
from ramure.errors import RamureError

if TYPE_CHECKING:
    import pyvista as pv
    from numpy.typing import ArrayLike
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.view.plant_view import PlantView
    from ramure.app.desktop.workers import Job
    from ramure.lsys.architecture.seasons import LeafChain, Season

#: The lichen habits of :data:`ramure.gmap.organs.lichen.HABITS`, listed without loading gmap.
HABIT_NAMES = ("crustose", "foliose", "fruticose")

SEASON_STEPS = 24
FALLEN_RGB = (211, 219, 226)  # the sky behind the plant: a fallen leaf's cells fade into it
SELECTED_RGB = (255, 0, 0)
FRUIT_RGB = (235, 120, 40)
PAINT_RGB = (60, 150, 60)  # painted adhesion on the fruit
STONE_RGB = (190, 184, 173)
BARK_RGB = (120, 104, 88)
KIND_LEAF = 1
TOOLS = ("turn the view", "paint where lichen may start", "place the crack")
BRUSH = 0.15  # brush radius, a fraction of the fruit's diagonal


# -- pure helpers (tested without widgets) ---------------------------------------------------
def season_cell_colors(
    mesh: pv.DataSet, season: Season, chain: LeafChain, step: int, base: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Per-cell RGB (uint8) at ``step``: leaf cells in their state's colour, fallen ones ground-coloured.

    Returns ``(rgb, fallen_cells)``; ``base`` is the plant's own colours (copied).
    """
    rgb = np.array(base, np.uint8, copy=True)
    ids = np.asarray(mesh.cell_data["leaf_id"], np.int64)
    leaf_cells = np.flatnonzero(np.asarray(mesh.cell_data["kind"]) == KIND_LEAF)
    order = np.argsort(season.leaf_ids, kind="stable")
    sorted_ids = season.leaf_ids[order]
    at = np.searchsorted(sorted_ids, ids[leaf_cells])
    found = at < len(sorted_ids)
    found[found] = sorted_ids[at[found]] == ids[leaf_cells][found]
    cells, leaf = leaf_cells[found], order[at[found]]
    colours = np.round(chain.colors[season.states[step][leaf]] * 255).astype(np.uint8)
    rgb[cells] = colours
    down = fallen_by(season, step)[leaf]
    rgb[cells[down]] = FALLEN_RGB
    fallen_cells = np.zeros(mesh.n_cells, bool)
    fallen_cells[cells[down]] = True
    return rgb, fallen_cells


def fallen_by(season: Season, step: int) -> np.ndarray:
    """Leaves (season order) that have fallen at or before ``step``."""
    return season.fallen & (season.fall_step <= step)


def season_text(season: Season, chain: LeafChain, step: int) -> str:
    """One line of facts: leaves, fallen by this step, leaves per state."""
    states = season.states[step]
    down = int(fallen_by(season, step).sum())
    counts = ", ".join(f"{int((states == i).sum())} {name}" for i, name in enumerate(chain.states) if (states == i).any())
    return f"Step {step}/{len(season.states) - 1}: {len(season.leaf_ids)} leaves, {down} fallen; {counts}"


# -- the dock ------------------------------------------------------------------------------
class DetailsPanel(QWidget):
    """Season slider with heat, humidity and wind; Lichen and Crack buttons on the selected fruit."""

    def __init__(
        self,
        controller: Controller,
        view: PlantView | None = None,
        parent: QWidget | None = None,
        plotter_factory: Callable[[QWidget], Any] | None = None,
    ) -> None:
        super().__init__(parent)
        from ramure.lsys.architecture.seasons import autumn_chain

        self.controller = controller
        self.main_view = view  # the main 3D view the season recolours (None: none, tests)
        self.chain = autumn_chain()
        self.season: Season | None = None
        self.season_rgb: np.ndarray | None = None
        self.season_key: tuple | None = None  # (plant version, heat, humidity, wind, seed) the season was run for
        self.fallen_actor = None
        self.shown: str | None = None  # "lichen" or "crack": what the dock's view shows
        self.last_facts: dict[str, Any] | None = None
        self.fruit: pv.PolyData | None = None  # the selected fruit's surface shown below (uncarved), for the tools
        self.adhesion: np.ndarray | None = None  # painted per fruit vertex, or None (lichen may start anywhere)
        self.shown_detail: dict[str, Any] | None = None  # the session's detail edit the dock's view shows (None: none)
        self.habits_listed = False  # the habit list is filled by list_habits(), when the dock is first shown
        self._build()
        # the 3D view is made when the dock is first shown (or first used): see lazy_view
        self.view_slot = LazyView(plotter_factory or _interactor, setup=self._view_made)
        self.box.addWidget(self.view_slot, 1)
        controller.job_done.connect(self._job_done)
        controller.plant_changed.connect(self._plant_changed)
        controller.selection_changed.connect(lambda _sel: QTimer.singleShot(0, self._reapply))

    @property
    def plotter(self) -> Any:
        """The dock's 3D view (made on first use if the dock was never shown)."""
        return self.view_slot.plotter()

    def list_habits(self) -> None:
        """Add any lichen habit :data:`HABIT_NAMES` lacks to the list (once).  The habits come
        from ramure.gmap.organs.lichen: gmap loads (with scipy.sparse, about 25 MB) when the dock is
        first on screen, not with the window."""
        if self.habits_listed:
            return
        from ramure.gmap.organs.lichen import HABITS

        self.habit.addItems([name for name in HABITS if self.habit.findText(name) < 0])
        self.habits_listed = True

    def _view_made(self, plotter: Any) -> None:
        """The dock is on screen for the first time (see lazy_view): its view and habit list."""
        self.list_habits()
        if hasattr(plotter, "track_click_position"):
            plotter.track_click_position(self.clicked_at, side="left")

    def _build(self):
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setObjectName("detailsSeason")
        self.slider.setRange(0, SEASON_STEPS)
        self.slider.valueChanged.connect(self.show_step)
        self.heat, self.humidity = _unit_box("detailsHeat", 0.5), _unit_box("detailsHumidity", 0.5)
        self.wind = number_box(0.0, 2.0, 2, name="detailsWind", step=0.05)
        self.wind.setToolTip("wind strength along x, in plant units per step (leaves fall and drift)")
        self.seed = QSpinBox()
        self.seed.setObjectName("detailsSeed")
        self.seed.setRange(0, 2**31 - 1)
        for box in (self.heat, self.humidity, self.wind, self.seed):
            box.valueChanged.connect(self._environment_changed)
        self.season_label = QLabel("Move the slider to age the leaves (step 0: as grown).")
        self.season_label.setObjectName("detailsSeasonFacts")
        self.season_label.setWordWrap(True)
        season = QGroupBox("Season")
        form = QFormLayout(season)
        form.addRow("Step", self.slider)
        form.addRow("Heat", self.heat)
        form.addRow("Humidity", self.humidity)
        form.addRow("Wind", self.wind)
        form.addRow("Seed", self.seed)
        form.addRow(self.season_label)

        self.clusters, self.particles = _count_box("detailsClusters", 1, 200, 5), _count_box("detailsParticles", 1, 20_000, 300)
        self.habit = QComboBox()
        self.habit.setObjectName("detailsHabit")
        self.habit.addItems(HABIT_NAMES)  # filled from the start; list_habits adds any other
        self.nodes = _count_box("detailsNodes", 2, 500, 15)
        self.lichen_button = QPushButton("Lichen on the fruit")
        self.lichen_button.setObjectName("detailsLichen")
        self.lichen_button.clicked.connect(self.grow_lichen)
        self.bark_button = QPushButton("Lichen on the branches")
        self.bark_button.setObjectName("detailsLichenBark")
        self.bark_button.setToolTip(
            "grow lichen on the plant's bark: its branches welded into one closed surface "
            "(twigs under a tenth of the trunk's radius left out)"
        )
        self.bark_button.clicked.connect(self.grow_lichen_on_bark)
        self.crack_button = QPushButton("Crack the fruit")
        self.crack_button.setObjectName("detailsCrack")
        self.crack_button.clicked.connect(lambda: self.carve_crack())
        self.show_button = QPushButton("Show the fruit")
        self.show_button.setObjectName("detailsShowFruit")
        self.show_button.clicked.connect(self.load_fruit)
        self.tool = QComboBox()
        self.tool.setObjectName("detailsTool")
        self.tool.addItems(list(TOOLS))
        self.tool.setToolTip(
            "what a left click on the fruit below does: the lichen brush paints adhesion "
            "(clusters start only where painted), the crack tool carves a crack from the click"
        )
        self.clear_button = QPushButton("Clear paint")
        self.clear_button.setObjectName("detailsClearPaint")
        self.clear_button.clicked.connect(self.clear_paint)
        self.fruit_label = QLabel("Select a fruit, then grow lichen on it or crack it.")
        self.fruit_label.setObjectName("detailsFruitFacts")
        self.fruit_label.setWordWrap(True)
        fruit = QGroupBox("On the selected fruit")
        ff = QFormLayout(fruit)
        ff.addRow("Lichen clusters", self.clusters)
        ff.addRow("Particles", self.particles)
        ff.addRow("Habit", self.habit)
        ff.addRow("Crack nodes", self.nodes)
        buttons = QHBoxLayout()
        buttons.addWidget(self.lichen_button)
        buttons.addWidget(self.crack_button)
        ff.addRow(buttons)
        ff.addRow(self.bark_button)
        ff.addRow("A click", self.tool)
        tools = QHBoxLayout()
        tools.addWidget(self.show_button)
        tools.addWidget(self.clear_button)
        ff.addRow(tools)
        ff.addRow(self.fruit_label)
        controls = QWidget()
        inner = QVBoxLayout(controls)
        inner.setContentsMargins(0, 0, 0, 0)
        inner.addWidget(season)
        inner.addWidget(fruit)
        self.controls = QScrollArea()  # scrolls on small screens: the dock never forces the window taller
        self.controls.setWidgetResizable(True)
        self.controls.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.controls.setWidget(controls)
        self.controls.setMinimumHeight(60)
        self.box = dock_column(self)
        self.box.addWidget(self.controls, 2)

    # -- season ----------------------------------------------------------------------------
    def _key(self):
        return (
            self.controller.snapshot.version,
            round(self.heat.value(), 4),
            round(self.humidity.value(), 4),
            round(self.wind.value(), 4),
            int(self.seed.value()),
        )

    def compute_season(self) -> Job:
        """Age the plant's leaves over every step in the worker; the slider then shows a step."""
        from ramure.lsys.architecture.seasons import age_leaves

        key, chain = self._key(), self.chain
        _, heat, humidity, wind, seed = key

        def run(ex):
            return key, age_leaves(ex.skeleton, chain, steps=SEASON_STEPS, seed=seed, heat=heat, humidity=humidity, wind=wind)

        return self.controller.submit("details season", run, key="details-season")

    def show_step(self, step: int | None = None) -> None:
        """Colour the plant for the slider's step (computing the season first if needed)."""
        step = self.slider.value() if step is None else int(step)
        if step == 0:
            self._restore()
            self.season_label.setText("Step 0: the leaves as grown.")
            return
        if self.season is None or self.season_key != self._key():
            self.season_label.setText("Ageing the leaves…")
            self.compute_season()
            return
        self._paint(step)

    def _paint(self, step):
        view, snap = self._view(), self.controller.snapshot
        if snap.mesh is None or snap.mesh.n_cells == 0:
            return
        assert self.season is not None  # computed first (show_step)
        base = state.base_colors(snap.mesh)
        rgb, fallen = season_cell_colors(snap.mesh, self.season, self.chain, step, base)
        if len(snap.selection):
            rgb[state.leaf_mask(snap.mesh.cell_data["leaf_id"], snap.selection)] = SELECTED_RGB
        self.season_rgb = rgb
        if view is not None:
            view.set_colors(rgb)
            view.set_hidden_cells(fallen)
            self._show_fallen(view, step)
        self.season_label.setText(season_text(self.season, self.chain, step))

    def _show_fallen(self, view, step):
        from ramure.app.details import litter_polydata

        assert self.season is not None  # painted from _paint only
        down = fallen_by(self.season, step)
        if not down.any():
            if self.fallen_actor is not None:
                view.plotter.remove_actor("details_fallen", render=False)
                self.fallen_actor = None
            view.redraw()
            return
        size = 0.024 * diagonal(self.controller.snapshot.mesh)
        leaves = litter_polydata(self.season, self.chain.colors, step, size)
        self.fallen_actor = view.plotter.add_mesh(
            leaves,
            scalars="rgb",
            rgb=True,
            name="details_fallen",
            reset_camera=False,
            render=False,
            pickable=False,
            show_scalar_bar=False,
        )
        view.redraw()

    def _restore(self):
        view, snap = self._view(), self.controller.snapshot
        self.season_rgb = None
        if view is None or snap.mesh is None or snap.mesh.n_cells == 0:
            return
        if self.fallen_actor is not None:
            view.plotter.remove_actor("details_fallen", render=False)
            self.fallen_actor = None
        view.set_hidden_cells(None)
        view.set_colors(state.cell_colors(snap.mesh, snap.selection, base=state.base_colors(snap.mesh)))

    def _environment_changed(self, *_):
        if self.slider.value() > 0:
            self.show_step()

    def _plant_changed(self, _snap):
        self.season = None
        if self.slider.value() > 0:
            QTimer.singleShot(0, self.show_step)  # after the window has drawn the new plant
        QTimer.singleShot(0, self.replay_details)  # an undone or redone detail, a loaded session

    def _reapply(self):
        """A new selection recoloured the plant: put the season colours back under it."""
        if self.slider.value() > 0 and self.season is not None and self.season_key == self._key():
            self._paint(self.slider.value())

    def _view(self) -> PlantView | None:
        return self.main_view

    # -- lichen and cracks -----------------------------------------------------------------
    def grow_lichen(self) -> Job:
        """Grow lichen on the selected fruit (clusters, particles, habit and seed from the dock), as a job."""
        self.list_habits()
        clusters, particles = int(self.clusters.value()), int(self.particles.value())
        habit, seed = self.habit.currentText(), int(self.seed.value())
        self.fruit_label.setText("Growing lichen…")
        adhesion = None if self.adhesion is None else self.adhesion.copy()

        def run(ex):
            out = lichen_on_fruit(ex, clusters, particles, habit, seed, adhesion)
            settings = {
                "clusters": clusters,
                "particles": particles,
                "habit": habit,
                "seed": seed,
                "adhesion": None if adhesion is None else adhesion.tolist(),
            }
            return {**out, "detail": record(ex, "lichen", settings, selected_fruit(ex))}

        return self.controller.submit("details lichen", run, key="details-fruit")

    def grow_lichen_on_bark(self) -> Job:
        """Grow lichen on the plant's branches (clusters, particles, habit and seed from the dock)."""
        from ramure.app.details import lichen_on_surface, plant_bark

        self.list_habits()
        clusters, particles = int(self.clusters.value()), int(self.particles.value())
        habit, seed = self.habit.currentText(), int(self.seed.value())
        self.fruit_label.setText("Growing lichen on the branches…")

        def run(ex):
            poly, mesh = plant_bark(ex.skeleton)
            out = lichen_on_surface(poly, mesh, clusters, particles, habit, seed)
            settings = {"clusters": clusters, "particles": particles, "habit": habit, "seed": seed}
            return {**out, "detail": record(ex, "bark", settings)}

        return self.controller.submit("details bark", run, key="details-fruit")

    def carve_crack(self, anchor: ArrayLike | None = None) -> Job:
        """Carve a crack from ``anchor`` (a point on the fruit; default: the fruit's top)."""
        nodes, seed = int(self.nodes.value()), int(self.seed.value())
        self.fruit_label.setText("Carving the crack…")

        def run(ex):
            out = crack_on_fruit(ex, nodes, seed, anchor)
            settings = {"nodes": nodes, "seed": seed, "anchor": None if anchor is None else np.asarray(anchor, float).tolist()}
            return {**out, "detail": record(ex, "crack", settings, selected_fruit(ex))}

        return self.controller.submit("details crack", run, key="details-fruit")

    def replay_details(self) -> Job:
        """Show the session's last detail (after an undo, a redo, a load or a regrow): grown again
        from its settings, or nothing when the session has none."""
        shown = self.shown_detail

        def run(ex):
            last = last_detail(ex)
            if last == shown:
                return {"unchanged": True}
            return {"detail": None} if last is None else {**grow_again(ex, last), "detail": last}

        return self.controller.submit("details replay", run, key="details-replay")

    def load_fruit(self) -> Job:
        """Show the selected fruit below, ready for the brush or the crack tool."""
        self.fruit_label.setText("Loading the fruit…")
        return self.controller.submit("details fruit", lambda ex: {"fruit": selected_fruit_surface(ex)[0]}, key="details-fruit")

    def clicked_at(self, point: ArrayLike | None) -> Job | np.ndarray | None:
        """A left click on the dock's view at world ``point``: paint adhesion or place the crack."""
        tool = self.tool.currentText()
        if tool == TOOLS[0] or point is None:
            return None
        if self.fruit is None:
            self.fruit_label.setText("Refused: show a fruit first (select one, press 'Show the fruit')")
            return None
        points = np.asarray(self.fruit.points)
        nearest = points[int(np.argmin(np.linalg.norm(points - np.asarray(point, float), axis=1)))]
        if tool == TOOLS[2]:
            return self.carve_crack(tuple(nearest))
        self.adhesion = paint_adhesion(points, self.adhesion, nearest, BRUSH * diagonal(self.fruit))
        painted = int((self.adhesion > 0).sum())
        self.fruit_label.setText(
            f"Painted {painted} of {len(points)} vertices: lichen clusters start there (press 'Lichen on the fruit')."
        )
        self._show_fruit()
        return self.adhesion

    def clear_paint(self) -> None:
        """Forget the painted adhesion: lichen may start anywhere on the fruit."""
        self.adhesion = None
        if self.fruit is not None:
            self._show_fruit()
        self.fruit_label.setText("Paint cleared: lichen may start anywhere on the fruit.")

    def _show_fruit(self):
        """The fruit in its colour, painted adhesion in green."""
        assert self.fruit is not None  # shown once a fruit was grown
        rgb = np.tile(np.array(FRUIT_RGB, float), (self.fruit.n_points, 1))
        if self.adhesion is not None:
            rgb += self.adhesion[:, None] * (np.array(PAINT_RGB, float) - rgb)
        shown = self.fruit.copy(deep=False)
        shown.point_data["rgb"] = rgb.astype(np.uint8)
        self._show_result(shown, None, scalars="rgb", keep_camera=self.shown == "fruit")
        self.shown = "fruit"

    # -- results ---------------------------------------------------------------------------
    def _job_done(self, job):
        if not job.name.startswith("details ") or job.stale:
            return
        label = self.season_label if job.name == "details season" else self.fruit_label
        if job.error is not None:
            text = str(job.error) if isinstance(job.error, RamureError) else f"{type(job.error).__name__}: {job.error}"
            label.setText(f"Refused: {text}")
            return
        if job.name == "details season":
            self.season_key, self.season = job.result
            if self.season_key == self._key() and self.slider.value() > 0:
                self._paint(self.slider.value())
            elif self.slider.value() > 0:
                self.show_step()
            return
        if job.name == "details replay":
            if job.result.get("unchanged"):
                return
            detail = job.result["detail"]
            if detail is None:
                self.shown_detail = None
                self._clear_result()
                return
            name = {"lichen": "details lichen", "crack": "details crack", "bark": "details bark"}[detail["kind"]]
            self._show_job(name, job.result)
            return
        self._show_job(job.name, job.result)

    def _show_job(self, name, result):
        """Show a lichen, crack, bark or fruit result (a job's, or a detail grown again)."""
        if "detail" in result:
            self.shown_detail = result["detail"]
        if name == "details bark":
            self.shown, self.last_facts = "bark", result["facts"]
            self._show_result(result["surface"], BARK_RGB, result["discs"])
            from ramure.app.details import close_up

            self.plotter.camera_position = close_up(result["growth"], result["mesh"])
            if hasattr(self.plotter, "render"):
                self.plotter.render()
            f = result["facts"]
            self.fruit_label.setText(
                f"Lichen on the branches ({f['habit']}): {f['particles']} particles in "
                f"{f['clusters']} clusters on {f['triangles']} triangles of bark, "
                f"r = {f['r']:.3g}, {f['intersection_tests']:,} distance tests."
            )
            return
        fruit = result["fruit"]
        if self.fruit is None or self.fruit.n_points != fruit.n_points or not np.allclose(self.fruit.bounds, fruit.bounds):
            self.adhesion = None  # another fruit: the paint was for the old one
        self.fruit = fruit
        if name == "details fruit":
            self.shown = None
            self._show_fruit()
            self.fruit_label.setText(f"Fruit: {fruit.n_cells} triangles. Choose what a click does, then click on it.")
            return
        self.last_facts = result["facts"]
        if name == "details lichen":
            from ramure.app.details import facing

            self.shown = "lichen"
            self._show_result(result["surface"], FRUIT_RGB, result["discs"])
            self.plotter.camera_position = facing(result["growth"], result["mesh"])  # the lichen's side
            if hasattr(self.plotter, "render"):
                self.plotter.render()
            f = result["facts"]
            self.fruit_label.setText(
                f"Lichen ({f['habit']}): {f['particles']} particles in {f['clusters']} "
                f"clusters on {f['triangles']} triangles, {f['intersection_tests']:,} "
                "distance tests. Old discs dark, young rims light."
            )
        else:
            self.shown = "crack"
            self._show_result(result["surface"], FRUIT_RGB, look_at=result["points"])
            f = result["facts"]
            self.fruit_label.setText(
                f"Crack: {f['nodes']} nodes, length {f['length']:.3g}, "
                f"{f['triangles_object']} -> {f['triangles_result']} triangles, "
                f"{'watertight' if f['watertight'] else 'NOT watertight'}."
            )

    def _clear_result(self):
        """Nothing to show (the last detail was undone)."""
        for name in ("details_surface", "details_discs"):
            self.plotter.remove_actor(name, render=False)
        self.shown, self.last_facts = None, None
        self.fruit_label.setText("No lichen or crack in the session now (undone).")
        if hasattr(self.plotter, "render"):
            self.plotter.render()

    def _show_result(self, surface, colour, discs=None, scalars=None, keep_camera=False, look_at=None):
        p = self.plotter
        for name in ("details_surface", "details_discs"):  # not clear(): that removes the light kit too
            p.remove_actor(name, render=False)
        if scalars is not None:
            p.add_mesh(surface, scalars=scalars, rgb=True, smooth_shading=True, name="details_surface", show_scalar_bar=False)
        else:
            p.add_mesh(surface, color=np.array(colour) / 255, smooth_shading=discs is not None, name="details_surface")
        if discs is not None:
            p.add_mesh(discs, scalars="rgb", rgb=True, name="details_discs", show_scalar_bar=False)
        if keep_camera:  # painting: the camera stays where the user turned it
            pass
        elif discs is not None or scalars is not None:
            p.view_isometric()
        else:  # from outside the crack (its nodes' mean), a little aside
            b = np.reshape(surface.bounds, (3, 2))
            centre, size = b.mean(axis=1), float(np.ptp(b, axis=1).max())
            out = np.mean(look_at, axis=0) - centre if look_at is not None and len(look_at) else np.array([0, 0, 1.0])
            out = out / max(np.linalg.norm(out), 1e-12)
            aside = np.cross(out, (0, 0, 1.0)) if abs(out[2]) < 0.9 else np.array([0.3, -0.5, 0.0])
            up = (0, 0, 1.0) if abs(out[2]) < 0.9 else (0, 1.0, 0)
            p.camera_position = [tuple(centre + (out + 0.3 * aside) * size * 2), tuple(centre), up]
        if not keep_camera:
            p.reset_camera()
        if hasattr(p, "render"):
            p.render()


def _unit_box(name, value):
    return number_box(0.0, 1.0, 2, value=value, name=name, step=0.1)


def _count_box(name, low, high, value):
    box = QSpinBox()
    box.setObjectName(name)
    box.setRange(low, high)
    box.setValue(value)
    return box


def _interactor(parent: QWidget) -> Any:
    """The dock's own 3D view: lit and framed like the main view."""
    from ramure.app.desktop.panels.common import dock_plotter

    return dock_plotter(parent, "scene")
