"""The main window: editor, constants, 3D view, regeneration panel and the docks.

:class:`MainWindow` wires widgets to the :class:`~ramure.app.desktop.controller.Controller`:
widgets emit what the user asked for, the controller runs it on the model
(in the worker when it changes the plant), and the snapshot it publishes goes
to the :class:`~ramure.app.desktop.view.presenter.PlantPresenter`, which draws
it in the 3D view, and to the docks, which show their own part of it.  The
window makes the docks, the menus and the view, connects their signals and
keeps the status bar; no drawing and no algorithm live here.
"""

from __future__ import annotations

import importlib
import pathlib
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, TypeVar


from PySide6.QtCore import QSettings, Qt, QTimer
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QDockWidget, QLabel, QMainWindow, QMessageBox, QProgressBar, QPushButton, QTabWidget

from ramure.app.desktop import state
from ramure.app.desktop.controller import Busy, Controller
from ramure.app.desktop.state import SAME_PLANT
from ramure.app.desktop.qt_fix import protect_none
from ramure.app.desktop.panels import qualifier_map
from ramure.app.desktop.panels.architecture import ArchitecturePanel
from ramure.app.desktop.panels.constants import ConstantsPanel
from ramure.app.desktop.panels.cut_graph import CutGraphView
from ramure.app.desktop.panels.defects import DefectsPanel
from ramure.app.desktop.panels.details import DetailsPanel
from ramure.app.desktop.panels.editor import GrammarEditor
from ramure.app.desktop.panels.gallery import GalleryView
from ramure.app.desktop.panels.pca_cloud import PcaCloudView
from ramure.app.desktop.panels.regen import RegenPanel
from ramure.app.desktop.panels.string_dock import StringView
from ramure.app.desktop.panels.variants import VariantsController
from ramure.app.desktop.panels.wood import WoodPanel
from ramure.app.desktop.menus.files import OPEN_TITLE, TITLE, FileActions
from ramure.app.desktop.view.plant_view import PlantView
from ramure.app.desktop.view.presenter import PlantPresenter
from ramure.app.model import Explorer
from ramure.errors import RamureError

if TYPE_CHECKING:
    from types import TracebackType
    from PySide6.QtGui import QCloseEvent, QImage
    from PySide6.QtWidgets import QWidget
    from ramure.app.desktop.panels.qualifier_map import QualifierMapView
    from ramure.app.desktop.state import Snapshot
    from ramure.app.desktop.variants import VariantSet
    from ramure.app.desktop.workers import Job

KINSHIP_HINT = (
    "Kinship colours: red = the selected leaf and its closest kin, through yellow and green, "
    "to blue = related only through the first derivation steps"
)
T = TypeVar("T")
#: The docks by task: tabs in each group (the first one raised).
DOCK_GROUPS = {
    "left": ("grammar", "constants"),
    "right": ("regeneration", "gallery", "details", "pca", "architecture", "wood", "defects"),
    "bottom": ("string", "cut"),  # side by side when both are open
}
DOCK_WIDTH = 280  # each side column at the default size: the plant keeps over half of 1400 x 880
#: Docks used less often: closed at start, opened from the View menu.
CLOSED_AT_START = ("pca", "architecture", "wood", "defects", "string", "cut")

BUSY = "Computing…"
KINSHIP_NEEDS_ONE = "Kinship colours: click exactly one branch to colour the plant by kinship to it"


def warm_up() -> None:
    """Import the optional packages the first pick needs now, not on the first click."""
    importlib.import_module("ramure.metrics")


class MainWindow(QMainWindow):
    """The Ramure desktop explorer for one plant."""

    def __init__(
        self, explorer: Explorer, settings: QSettings | None = None, ask: bool = True, parent: QWidget | None = None
    ) -> None:
        protect_none()  # PySide6 6.12 on Python 3.11 leaks references to None: see qt_fix
        super().__init__(parent)
        self._ask = ask
        self.settings = settings or QSettings("Ramure", "Ramure desktop")
        self.controller = Controller(explorer, self)
        self.message_box: QMessageBox | None = None
        self.last_message: str | None = None

        self.view = PlantView(self)
        self.setCentralWidget(self.view)
        self.presenter = PlantPresenter(self.controller, self.view, self)
        self.editor = GrammarEditor()
        self.files = FileActions(self.controller, self.settings, self.editor, self.view, self, ask)
        self.constants_panel = ConstantsPanel()
        self.regen = RegenPanel()
        self.string_view = StringView()
        self.cut_view = CutGraphView(self.controller)
        self.gallery = GalleryView()
        self.pca_view = PcaCloudView()
        self.qualifier_map: QualifierMapView | None = None  # made by qualifier_map.attach when first used
        self.docks: dict[str, QDockWidget] = {}
        self.setTabPosition(Qt.DockWidgetArea.AllDockWidgetAreas, QTabWidget.TabPosition.North)
        left, right, bottom = (
            Qt.DockWidgetArea.LeftDockWidgetArea,
            Qt.DockWidgetArea.RightDockWidgetArea,
            Qt.DockWidgetArea.BottomDockWidgetArea,
        )
        self._dock("grammar", "Grammar", self.editor, left)
        self._dock("constants", "Constants", self.constants_panel, left)
        self._dock("regeneration", "Regeneration", self.regen, right)
        self._dock("gallery", "Gallery", self.gallery, right)
        self._dock("details", "Details", DetailsPanel(self.controller, self.view), right)
        self._dock("pca", "PCA cloud", self.pca_view, right)
        self._dock("architecture", "Architecture", ArchitecturePanel(self.controller), right)
        self._dock("wood", "Wood", WoodPanel(self.controller), right)
        defects = DefectsPanel(self.controller)
        defects.status.connect(self.status)
        self._dock("defects", "Defects", defects, right)
        self._dock("string", "String", self.string_view, bottom)
        self._dock("cut", "Cut graph", self.cut_view, bottom)
        self._group_docks()

        self.status_label = QLabel("")
        self.status_label.setObjectName("plantStatus")
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(220)
        self.progress.hide()
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.hide()
        self.busy_label = QLabel("")
        self.busy_label.setObjectName("busy")
        self.statusBar().addWidget(self.status_label, 1)
        self.statusBar().addPermanentWidget(self.busy_label)
        self.statusBar().addPermanentWidget(self.progress)
        self.statusBar().addPermanentWidget(self.cancel_button)

        self.variants = VariantsController(
            self.controller, self.regen, self.gallery, self.pca_view, self.view, self.progress, self.cancel_button, self
        )
        self._actions()
        self._connect()
        self.fit_size(1400, 880)
        self.compact = False
        warm_up()
        self.resizeDocks([self.docks["grammar"], self.docks["regeneration"]], [DOCK_WIDTH, DOCK_WIDTH], Qt.Orientation.Horizontal)
        self.resizeDocks([self.docks["grammar"], self.docks["constants"]], [400, 380], Qt.Orientation.Vertical)
        self.resizeDocks([self.docks["string"]], [190], Qt.Orientation.Vertical)
        self.editor.show_model_text(self.controller.snapshot.text)
        self.presenter.show_plant(self.controller.snapshot, reset_camera=True)
        self.mark_saved()
        QTimer.singleShot(0, self._full_tab_titles)  # dock tabs never read "Req…"

    def _group_docks(self) -> None:
        """The docks by task, so the plant keeps at least half of the window: writing the grammar
        on the left (the text above its constants), changing a part on the right (regrowth, the
        variant gallery, natural details, as tabs).  The docks used less often start closed, each
        in its group, and the View menu opens them: the variants' PCA cloud, architecture, wood
        and defects on the right, the module string and the cut graph below the plant."""
        group = DOCK_GROUPS["right"]  # (a group with every dock closed would leave its tab bar)
        for a, b in zip(group, group[1:]):
            self.tabifyDockWidget(self.docks[a], self.docks[b])
        for key in CLOSED_AT_START:
            self.docks[key].hide()
        self.docks["regeneration"].raise_()

    def use_compact_layout(self) -> None:
        """Small screens (under 1300 px wide, e.g. 1024x700): every dock in one right-hand column,
        two tab groups (the plant's tools above, grammar, constants and the string below), so the
        3D view keeps most of the window.  Docks can still be moved and floated."""
        if self.compact:
            return
        self.compact = True
        right = Qt.DockWidgetArea.RightDockWidgetArea
        top = ["regeneration", "pca", "architecture", "wood", "details", "defects"]
        bottom = ["grammar", "constants", "string", "cut", "gallery"]
        for key in top + bottom:
            if key in self.docks:
                self.removeDockWidget(self.docks[key])
        first = self.docks[top[0]]
        self.addDockWidget(right, first)
        lower = self.docks[bottom[0]]
        self.addDockWidget(right, lower)
        self.splitDockWidget(first, lower, Qt.Orientation.Vertical)
        for group in (top, bottom):
            for a, b in zip(group, group[1:]):
                if a in self.docks and b in self.docks:
                    self.tabifyDockWidget(self.docks[a], self.docks[b])
            for key in group:
                if key in self.docks:
                    self.docks[key].setVisible(key not in CLOSED_AT_START)  # those the View menu opens stay closed
        self.docks["regeneration"].raise_()
        self.docks["grammar"].raise_()
        self.resizeDocks([first], [340], Qt.Orientation.Horizontal)
        self.resizeDocks([first, lower], [390, 260], Qt.Orientation.Vertical)
        QTimer.singleShot(0, self._full_tab_titles)

    def _full_tab_titles(self) -> None:
        """Dock tabs show whole titles (scroll arrows when they do not fit), never "Gra…"."""
        from PySide6.QtWidgets import QTabBar

        for bar in self.findChildren(QTabBar):
            bar.setElideMode(Qt.TextElideMode.ElideNone)
            bar.setUsesScrollButtons(True)

    def fit_screen(self, width: int, height: int) -> None:
        """Size the window for a screen of ``width`` x ``height`` pixels (compact below 1300 wide)."""
        if width < 1300:
            self.use_compact_layout()
        self.fit_size(min(width, 1400), min(height, 880))

    def fit_size(self, width: int, height: int) -> None:
        """Resize to ``width`` x ``height`` as the docks stand now.  Qt keeps the window's minimum
        size from the layout's last activation: built dock by dock, before the tabs group them,
        that was the docks' heights stacked (1338 px), and ``resize`` never went below it, so the
        window came out taller than a 900- or 1080-pixel screen.  The layout is activated first."""
        layout = self.layout()
        if layout is not None:
            layout.activate()
        self.resize(width, height)

    # -- construction ----------------------------------------------------------------
    def _dock(self, key, title, widget, area):
        dock = QDockWidget(title, self)
        dock.setObjectName(f"dock_{key}")
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        self.docks[key] = dock
        return dock

    def _action(self, menu, text, slot, shortcut=None, checkable: bool = False, tip=None):
        action = QAction(text, self)
        if shortcut:
            action.setShortcut(QKeySequence(shortcut))
        action.setCheckable(checkable)
        if tip:
            action.setStatusTip(tip)
        action.triggered.connect(slot)
        menu.addAction(action)
        return action

    def _actions(self) -> None:
        bar = self.menuBar()
        f = bar.addMenu("&File")
        self._action(f, f"&{OPEN_TITLE}…", lambda: self.files.open_grammar(), QKeySequence.StandardKey.Open)
        self._action(f, "&Save grammar", lambda: self.files.save_grammar(), QKeySequence.StandardKey.Save)
        self._action(f, "Save grammar &as…", lambda: self.files.save_grammar(ask=True), QKeySequence.StandardKey.SaveAs)
        f.addSeparator()
        self._action(f, "Save session…", lambda: self.files.save_session())
        self._action(f, "Load session…", lambda: self.files.load_session())
        f.addSeparator()
        self._action(f, "Export PNG screenshot…", lambda: self.files.screenshot())
        self._action(f, "Export plant (VTK, OBJ, glTF)…", lambda: self.files.export_mesh())
        self.yup_action = self._action(
            f,
            "Export with Y up",
            self.files.set_yup,
            checkable=True,
            tip="Swap axes on export for tools that take Y as up (Blender, glTF)",
        )
        f.addSeparator()
        self.recent_menu = f.addMenu("Recent files")
        self.update_recent_menu()
        f.addSeparator()
        self._action(f, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        e = bar.addMenu("&Edit")
        self.undo_action = self._action(
            e, "&Undo", self.undo, "Ctrl+Z", tip="Undo the last change: typing, a constant, n, seed, regrow, prune"
        )
        self.redo_action = self._action(e, "&Redo", self.redo, "Ctrl+Shift+Z")
        self.redo_action.setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
        e.addSeparator()
        self._action(e, "Regrow", self._regrow, "Ctrl+R")
        self._action(e, "Prune", self._prune, "Delete")
        self.clear_action = self._action(e, "Clear selection", self._clear_selection, "Esc")
        self.clear_action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)

        v = self.view_menu = bar.addMenu("&View")
        self.rect_action = self._action(
            v,
            "Rectangle selection (left drag)",
            self.view.set_rectangle_mode,
            checkable=True,
            tip="Right drag always draws a rectangle",
        )
        self.kinship_action = self._action(
            v,
            "Kinship colours",
            self.set_kinship,
            "K",
            checkable=True,
            tip="Colour the plant by derivation kinship to one selected leaf",
        )
        self._action(v, "Frame the whole plant", lambda: self.view.reset_camera(), "Home")
        self._action(
            v,
            "Zoom to fruit",
            self.zoom_to_fruit,
            "F",
            tip="Frame the selected fruit (every fruit when none is selected); Home frames the plant again",
        )
        camera = v.addMenu("Camera")
        for name, key in (("front", "Ctrl+1"), ("side", "Ctrl+2"), ("top", "Ctrl+3"), ("iso", "Ctrl+4")):
            self._action(
                camera,
                name.capitalize(),
                lambda _=False, n=name: self.view.reset_camera(n),
                key,
                tip=f"Look at the whole plant from the {name} (Z up)",
            )
        self.ground_action = self._action(
            v,
            "Ground grid",
            self.view.ground.set_visible,
            "G",
            checkable=True,
            tip="A grid under the plant; its spacing is written bottom left",
        )
        self.ground_action.setChecked(True)
        v.addSeparator()
        for dock in self.docks.values():
            v.addAction(dock.toggleViewAction())
        self.fruit_action = self.variants.fruit_action(v)

        variants_menu = bar.addMenu("Va&riants")
        self.variants.build_menu(variants_menu)
        from ramure.app.desktop.menus.study import StudyMenu

        study_menu = bar.addMenu("&Study")
        self.study_menu = StudyMenu(study_menu, self, self.ask)
        self.study_menu.refused.connect(self.report_refused)
        from ramure.app.desktop.menus.new_study import NewStudyActions

        self.new_study = NewStudyActions(self.variants, study_menu, variants_menu, self)
        self.new_study.status.connect(self.status)
        self.new_study.refused.connect(self.report_refused)
        from ramure.app.desktop.menus.help import HelpMenu

        self.help_menu = HelpMenu(self, bar.addMenu("&Help"))

        tools = self.addToolBar("Plant")
        tools.setObjectName("plantToolbar")
        for action in (self.undo_action, self.redo_action, self.rect_action, self.kinship_action):
            tools.addAction(action)

    def _connect(self) -> None:
        c = self.controller
        c.plant_changed.connect(self.presenter.show_plant)
        c.state_changed.connect(self.show_state)
        c.selection_changed.connect(self.presenter.show_selection)
        p = self.presenter
        p.plant_shown.connect(self._plant_shown)
        p.selection_shown.connect(self.show_selection_docks)
        p.cut_message.connect(self.regen.set_cut_preview)
        c.job_done.connect(self._job_done)
        c.job_done.connect(self.variants.fruit_ready)
        c.refused.connect(self.report_refused)
        c.crashed.connect(self.report_crash)
        c.busy_changed.connect(self._busy_changed)
        c.edit_started.connect(self.view.forget_kept)
        c.replaying.connect(lambda done, total: self.status(f"Replaying the session: edit {done} of {total}"))
        self.editor.text_settled.connect(self._text_settled)
        self.constants_panel.constant_changed.connect(self._constant)
        self.constants_panel.derivation_changed.connect(self._derivation)
        self.constants_panel.range_refused.connect(lambda m: self.status(m) if m else None)
        self.view.cell_clicked.connect(self.pick_cell)
        self.view.rectangle_selected.connect(self.select_rectangle)
        self.view.escape.connect(self._clear_selection)
        r = self.regen
        r.rho_changed.connect(self._rho)
        r.regrow.connect(self._regrow)
        r.regrow_with_constants.connect(self._regrow_with_constants)
        r.prune.connect(self._prune)
        r.undo.connect(self.undo)
        r.redo.connect(self.redo)
        self.cut_view.refused.connect(self.report_refused)
        self.cut_view.to_front.connect(lambda show: self.open_dock("cut") if show else self.docks["cut"].raise_())
        v = self.variants
        v.status.connect(self.status)
        v.status_ended.connect(self._status_ended)
        v.refused.connect(self.report_refused)
        v.crashed.connect(self.report_crash)
        v.select_requested.connect(lambda leaves, mode: self.run_selection(self.controller.select, leaves, mode))
        v.variants_shown.connect(self._variants_shown)
        fa = self.files
        fa.status.connect(self.status)
        fa.refused.connect(self.report_refused)
        fa.flush_requested.connect(self.flush_edits)
        fa.recent_changed.connect(self.update_recent_menu)

    # -- the docks follow the view ----------------------------------------------------
    def _plant_shown(self, snap: Snapshot) -> None:
        """A new plant version is on screen (:class:`PlantPresenter` drew it): the docks follow."""
        self.show_selection_docks(snap.selection)
        self.string_view.show_snapshot(snap)
        self.show_state(snap)
        self.cut_view.show_snapshot(snap)
        self.variants.plant_changed(snap)

    def show_state(self, snap: Snapshot) -> None:
        """Same plant, other state: constants, undo/redo, status line, grammar error."""
        self.constants_panel.show_snapshot(snap, snap.grammar_constants)
        self.regen.show_state(snap)
        self.undo_action.setEnabled(snap.can_undo)
        self.redo_action.setEnabled(snap.can_redo)
        self.status_label.setText(snap.status)
        self.editor.follow(snap)
        name = pathlib.Path(snap.path).name if snap.path else "untitled"
        self.setWindowTitle(f"{name}{' *' if self.dirty else ''} — {TITLE}")

    def show_selection_docks(self, selection: Sequence[int]) -> None:
        """The selection in the panels: counts, status line, the string dock's modules."""
        snap = self.controller.snapshot
        self.regen.set_selection_size(len(selection))
        fruit = self.presenter.fruit_leaves
        self.regen.set_fruit_selection(self.presenter.fruit_selected(selection), len(fruit), self.variants.fruit_ok)
        if self.status_label.text() != snap.status:
            self.status_label.setText(snap.status)
        if self.presenter.kinship:  # say what the colours mean, or what they need
            self.status(KINSHIP_HINT if len(selection) == 1 else KINSHIP_NEEDS_ONE, 10000)
        try:
            self.string_view.show_selection(self.controller.selected_modules() if selection else [])
        except RamureError:
            pass

    def _variants_shown(self, vs: VariantSet) -> None:
        """A variant set on show: the gallery's picks in front of the regeneration panel, and the
        qualifier map (made on first use, tabified with the PCA cloud)."""
        self.open_dock("gallery")
        self.qualifier_map = qualifier_map.attach(self, self.docks, self.view_menu)
        self.qualifier_map.set_variants(vs)

    def open_dock(self, key: str) -> None:
        """Show dock ``key`` (perhaps closed at start) in front of its tab group."""
        self.docks[key].show()
        self.docks[key].raise_()

    def zoom_to_fruit(self) -> None:
        """Frame the selected fruit, or every fruit when none is selected (View ▸ Zoom to fruit);
        the bounds are read in the worker, which owns the explorer."""
        self.controller.submit("zoom to fruit", lambda ex: ex.fruit_bounds())

    def _zoomed(self, job) -> None:
        if job.error is not None:
            self.status(f"Zoom to fruit: {job.error}")
        elif job.result is None:
            self.status("This plant has no fruit to zoom to")
        else:
            self.view.zoom_to(job.result)

    def set_kinship(self, on: bool) -> None:
        """Colour the selection's relatives (``on``) or the selection only (the menu entry follows)."""
        self.kinship_action.setChecked(bool(on))
        self.presenter.set_kinship(on)

    # -- user actions -------------------------------------------------------------------
    def _text_settled(self, text) -> None:
        self.controller.set_text(text)

    def _constant(self, name, value, gesture=0) -> None:
        self.controller.set_constant(name, value, gesture)

    def _derivation(self, n, seed) -> None:
        self.controller.set_derivation(n, seed)

    def flush_edits(self) -> None:
        """Send what the user typed or slid but the pause has not sent yet."""
        self.editor.flush()
        self.constants_panel.flush()

    def undo(self) -> Job:
        """Undo (Ctrl+Z): typing waiting to be sent is sent first, so it is what Undo takes back."""
        self.flush_edits()
        return self.controller.undo()

    def redo(self) -> Job:
        """Redo (Ctrl+Shift+Z or Ctrl+Y)."""
        self.flush_edits()
        return self.controller.redo()

    def _rho(self, percent) -> None:
        """The slider's percent, as the fraction the model takes."""
        self.controller.set_rho(percent / 100.0)  # its preview is asked for when the ρ job is done

    def _regrow(self) -> None:
        self.controller.regrow()

    def _regrow_with_constants(self, constants) -> None:
        if not constants:
            self.status("Change a value under 'Constants for the selection' first.")
            return
        self.controller.regrow(constants=constants)

    def _prune(self) -> None:
        if not self.controller.snapshot.selection:
            self.report_refused("select the branches to prune first")
            return
        self.controller.prune()

    def _clear_selection(self) -> None:
        self.run_selection(self.controller.clear_selection)

    def run_selection(self, fn: Callable[..., T], *args: object) -> T | None:
        """Run a selection change ``fn(*args)``; a busy model or a refusal is said, not raised."""
        try:
            return fn(*args)
        except Busy as exc:
            self.status(str(exc))
        except RamureError as exc:
            self.report_refused(str(exc))
        return None

    def pick_cell(self, cell: int, mode: str = "replace") -> int | None:
        """A click landed on mesh cell ``cell`` (-1: on the background)."""
        if cell < 0:
            self.status("Nothing under the cursor")
            return None
        leaf = self.run_selection(self.controller.pick_cell, cell, mode)
        if leaf is not None:
            self.status(f"Picked leaf {leaf} ({mode})")
        return leaf

    def select_rectangle(self, rect: Sequence[float], mode: str = "replace") -> list[int] | None:
        """Select the branches whose midpoints project inside display rectangle ``rect``."""
        points = self.presenter.rectangle_points()
        if points is None:
            return None
        xy, leaves = points
        found = self.run_selection(self.controller.select_rectangle, xy, rect, mode, leaves)
        if found is not None:
            self.status(f"Rectangle: {len(found)} leaves ({mode})")
        return found

    def _job_done(self, job) -> None:
        if job.stale:
            return
        if job.name == "grammar":
            if job.error is None:
                self.editor.show_error(job.result)
                if job.result is not None:
                    self.status("Grammar error: the last good plant stays on screen")
        elif job.name in ("open grammar", "load session") and job.error is None:
            self.editor.set_text(self.controller.snapshot.text)
            self.mark_saved()
            self.view.reset_camera()
        elif job.name.startswith(("regrow", "prune")) and job.error is None:
            self.after_regrow(job)
        elif job.name == "preview" and job.error is None:
            self.presenter.set_cut_preview(job.result)
        elif job.name == "rho" and job.error is None:
            self.presenter.set_cut_preview(None)  # the preview of the old ρ: a new one follows
            if self.controller.snapshot.selection:
                # asked here, after the ρ job: a preview job queued with the keystroke could be
                # replaced into a place before a later ρ job and then be cleared by it
                self.controller.preview(inline=False)
        elif job.name in ("undo", "redo") and job.error is None:
            self.after_history(job.result)
        elif job.name == "zoom to fruit":
            self._zoomed(job)

    def after_history(self, note: str) -> None:
        """After Undo or Redo: say what it did; the editor shows the model's text again, without
        the error of text typed since (an undo took that text back)."""
        self.editor.show_undone(self.controller.snapshot)
        self.regen.set_note(note)
        self.status(note, 8000)

    def after_regrow(self, job: Job) -> None:
        """Say what the regrow did; on a deterministic grammar, say why nothing changed."""
        snap = self.controller.snapshot
        note = state.regrow_note(job.name, snap.note, self.presenter.same_as_before, len(snap.selection) > 0)
        self.regen.set_note(note)
        self.status(SAME_PLANT if note == SAME_PLANT else snap.status, 0)

    # -- messages -------------------------------------------------------------------------
    def _busy_changed(self, busy: bool) -> None:
        """Show "Computing…" in its own corner of the status bar while a job runs, so it never
        hides or erases a message (a job's result is announced just before it ends)."""
        self.busy_label.setText(BUSY if busy else "")
        self.view.set_busy(busy)  # the 3D view's polished frame waits for the next version

    def status(self, text: str, timeout: int = 4000) -> None:
        """Show ``text`` on the status bar for ``timeout`` ms (0: until replaced); empty text clears it."""
        if text:
            self.statusBar().showMessage(text, timeout)
        else:
            self.statusBar().clearMessage()

    def _status_ended(self, text: str) -> None:
        """Clear the status bar if it still shows ``text`` (a newer message stays)."""
        if self.statusBar().currentMessage() == text:
            self.status("")

    def report_refused(self, message: str) -> None:
        """A user error: the status bar and a non-blocking message box."""
        self.status(message, 8000)
        self._message(QMessageBox.Icon.Warning, "Not possible", message)

    def report_crash(self, message: str, details: str) -> None:
        """An unexpected error in a worker: a dialog; the last good plant stays."""
        self.status(f"Error: {message}", 10000)
        self._message(QMessageBox.Icon.Critical, "Unexpected error", f"{message}\n\nThe last good plant is kept.", details)

    def report_unexpected(self, kind: type[BaseException], value: BaseException, tb: TracebackType | None) -> None:
        """``sys.excepthook`` while the window runs: report, never exit."""
        import traceback

        if isinstance(value, RamureError):
            self.report_refused(str(value))
        else:
            self.report_crash(f"{kind.__name__}: {value}", "".join(traceback.format_exception(kind, value, tb)))

    def _message(self, icon, title, text, details=None) -> None:
        self.last_message = text
        if not self.ask:
            return
        box = self.message_box
        if box is None:
            box = self.message_box = QMessageBox(self)
            box.setWindowModality(Qt.WindowModality.WindowModal)
        box.setIcon(icon)
        box.setWindowTitle(title)
        box.setText(text)
        box.setDetailedText(details or "")
        box.open()

    @property
    def ask(self) -> bool:
        """False: never show modal questions (tests, ``--quit-after``); the menus follow."""
        return self._ask

    @ask.setter
    def ask(self, value: bool) -> None:
        """Set whether the window and its menus may ask questions."""
        self._ask = bool(value)
        self.files.ask = self.study_menu.ask = self._ask

    # -- files and closing ------------------------------------------------------------------
    def update_recent_menu(self) -> None:
        """Fill File > Recent files from the settings."""
        self.recent_menu.clear()
        for path in self.files.recent():
            action = self.recent_menu.addAction(path)
            action.triggered.connect(lambda _=False, p=path: self.files.open_recent(p))
        self.recent_menu.setEnabled(bool(self.recent_menu.actions()))

    def mark_saved(self) -> None:
        """Show the model's state after a save or an open (the title loses its "*")."""
        self.controller.refresh()

    @property
    def dirty(self) -> bool:
        """Unsaved changes: the model's plant differs from the file (see
        :attr:`Explorer.dirty <ramure.app.model.Explorer.dirty>`), or typing not yet sent or
        not parsed."""
        return self.files.unsaved()

    @dirty.setter
    def dirty(self, value: bool) -> None:
        """``False`` takes the plant as saved (no question on closing: tests, scripts); the model
        says when it is dirty, so ``True`` changes nothing."""
        if not value:
            self.controller.read(lambda ex: ex.mark_saved(), wait=None)
            self.controller.refresh()

    def confirm_discard(self) -> bool:
        """True if there are no unsaved changes or the user agrees to lose them (see
        :meth:`FileActions.confirm_discard <ramure.app.desktop.menus.files.FileActions.confirm_discard>`)."""
        return self.files.confirm_discard()

    def grab_window(self) -> QImage:
        """The whole window as a QImage, with the 3D view freshly painted (polished)."""
        return self.view.grab_window()

    def closeEvent(self, event: QCloseEvent) -> None:  # noqa: N802 (Qt API)
        """Close after the unsaved-changes question; stop tasks and jobs, then the view."""
        if not self.confirm_discard():
            event.ignore()
            return
        self.variants.cancel_all()
        self.controller.wait_idle(10.0)
        self.controller.jobs.wait(10000)
        self.view.close()
        event.accept()

    def run_later(self, msecs: int, fn: Callable[[], object]) -> None:
        """Call ``fn`` after ``msecs`` in the event loop."""
        QTimer.singleShot(msecs, fn)
