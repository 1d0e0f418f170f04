"""Variants in the window: explorations, the gallery, the PCA dock, qualifiers, volumetric fruit.

:class:`VariantsController` runs the long work (the variant sweep, the 27
thumbnails, qualifier previews) as cancellable :class:`~ramure.app.desktop.workers.Task`
objects with the status bar's progress bar, and feeds the results to the
gallery, the PCA dock and the regeneration panel's qualifier drop-down.
The computations themselves are in :mod:`ramure.app.desktop.variants` and
:mod:`ramure.metrics`.  It is handed the docks it feeds and never calls the window: messages,
refusals, crashes, a fruit click's selection and a newly shown variant set leave as signals.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QAction, QImage
from PySide6.QtWidgets import QFileDialog

from ramure.app.desktop import variants
from ramure.app.desktop.view.thumbnails import placeholder_image, same_segments, skeleton_image
from ramure.app.desktop.workers import Task
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.metrics.apply import QualifierResult
    from ramure.lsys import LSystem
    from ramure.lsys.interpretation.turtle import Skeleton
    from PySide6.QtWidgets import QMenu, QProgressBar, QPushButton, QWidget
    from ramure.app.desktop.panels.gallery import GalleryView
    from ramure.app.desktop.panels.pca_cloud import PcaCloudView
    from ramure.app.desktop.panels.regen import RegenPanel
    from ramure.app.desktop.view.plant_view import PlantView
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.state import Snapshot
    from ramure.app.desktop.variants import VariantSet
    from ramure.app.desktop.workers import Job

THUMB = 150


def fruit_available() -> bool:
    """True: the 3G-map layer (part of Ramure) builds volumetric fruit."""
    return True


class VariantsController(QObject):
    """Owns the current :class:`~ramure.app.desktop.variants.VariantSet` and the tasks that build it.

    It feeds the docks it is handed (``regen``, ``gallery``, ``pca_view``, the main ``view``) and
    shows its tasks' progress on ``progress`` with ``cancel``; ``parent`` is the widget its
    dialogs open over.
    """

    #: A message for the status bar and how long it stays (ms; 0: until replaced).
    status = Signal(str, int)
    #: A task's own message is no longer true: clear the status bar if it still shows it.
    status_ended = Signal(str)
    #: A user error (an exploration folder that cannot be read...): the window reports it.
    refused = Signal(str)
    #: An unexpected error in a task: its message and traceback.
    crashed = Signal(str, str)
    #: A click on a fruit volume: select these leaves (``mode``: replace, add, toggle).
    select_requested = Signal(list, str)
    #: A variant set is on show (the window brings the gallery forward, fills the qualifier map).
    variants_shown = Signal(object)

    def __init__(
        self,
        controller: Controller,
        regen: RegenPanel,
        gallery: GalleryView,
        pca_view: PcaCloudView,
        view: PlantView,
        progress: QProgressBar,
        cancel: QPushButton,
        parent: QWidget,
    ) -> None:
        super().__init__(parent)
        self.controller = controller
        self.regen, self.gallery, self.pca_view, self.view = regen, gallery, pca_view, view
        self.progress, self.cancel_button, self.parent_widget = progress, cancel, parent
        self.variant_set: VariantSet | None = None
        self.text: str | None = None  # grammar text the variant set belongs to
        self.constants: dict[str, float] | None = None  # the session's constants the variants were swept from
        self.lsystem: LSystem | None = None  # that grammar with those constants (thumbnails and previews derive it)
        self.last_qualifier: QualifierResult | None = None
        self.words: dict[str, dict] = {}  # a study's words ({word: entry with its direction}), see load_words
        self.tasks: dict[str, Task] = {}
        self.show_fruit = False
        self.cut_fruit = False  # fruit drawn cut open (a plane through each fruit, facing the viewer)
        self.fruit_job_cut = False
        self.fruit_ok = fruit_available()
        self._connect()
        reason = variants.metrics_available()
        if reason:
            gallery.set_unavailable(reason)
            gallery.explore_button.setEnabled(False)
            pca_view.set_unavailable(reason)
        else:
            gallery.set_unavailable(
                "No exploration yet: Explore variants (a sweep of the constants "
                "±10 %, one rule at a time) or open an exploration folder."
            )
        self.offer_qualifiers("The first qualifier explores the grammar's variants (once; cached).")

    def _connect(self) -> None:
        """The docks' requests to this controller."""
        self.gallery.pick_clicked.connect(self.apply_pick)
        self.pca_view.pick_clicked.connect(self.apply_pick)
        self.gallery.explore_requested.connect(self.explore)
        self.gallery.open_requested.connect(self.open_exploration)
        self.regen.qualifier_chosen.connect(self.preview_qualifier)
        self.regen.apply_qualifier.connect(self.apply_qualifier)
        self.regen.regrow_fruit.connect(self.regrow_fruit)
        self.cancel_button.clicked.connect(self.cancel_all)
        self.view.leaf_clicked.connect(self.fruit_clicked)
        self.controller.job_done.connect(self.qualifier_done)

    def _say(self, text: str, timeout: int = 4000) -> None:
        """Put ``text`` on the window's status bar (through :attr:`status`)."""
        self.status.emit(text, timeout)

    def offer_qualifiers(self, note: str) -> None:
        """The qualifier box's list (the vocabulary, then a study's words) and its suggestions."""
        from ramure.metrics.words import word_label

        names = variants.vocabulary_names() + [word_label(w) for w in self.words]
        tips = {**variants.qualifier_meanings(), **{word_label(w): str(e.get("meaning", w)) for w, e in self.words.items()}}
        self.regen.set_qualifiers(names, note, tips, variants.accepted_words(self.words))

    def load_words(self, path: str | os.PathLike | None = None) -> dict[str, dict] | None:
        """Accept a study's words (a vocabulary file from ``ramure study words``) as qualifiers,
        each with its measured direction: they join the qualifier list and its suggestions."""
        if path is None:
            path, _ = QFileDialog.getOpenFileName(self.parent_widget, "Load study words", "", "Vocabulary files (*.json)")
            if not path:
                return None
        try:
            self.words = variants.read_study_words(path)
        except RamureError as exc:
            self.refused.emit(str(exc))
            return None
        self.offer_qualifiers(f"{len(self.words)} study words accepted: {', '.join(sorted(self.words)[:6])}.")
        self._say(f"Loaded {len(self.words)} study words from {os.path.basename(path)}", 8000)
        return self.words

    def directions(self) -> dict[str, dict[str, float]]:
        """``{word: {metric: weight}}`` of the study's words, for the qualifier model."""
        return {w: e["direction"] for w, e in self.words.items()}

    def _qualifier_key(self, name: str) -> str | None:
        """The canonical qualifier typed as ``name``, or None after saying why it is refused."""
        try:
            return variants.qualifier_key(name, self.words)
        except RamureError as exc:
            self.regen.qualifier_note.setText(str(exc))
            self._say(str(exc), 15000)
            return None

    # -- menu -------------------------------------------------------------------
    def build_menu(self, menu: QMenu) -> None:
        """Fill the Variants menu: explore, open an exploration folder, load study words, cancel."""
        self.explore_action = menu.addAction("Explore variants of this grammar")
        self.explore_action.triggered.connect(lambda: self.explore())  # not explore(checked)
        self.explore_action.setEnabled(variants.metrics_available() is None)
        menu.addAction("Open exploration folder…").triggered.connect(lambda: self.open_exploration())
        menu.addAction("Load study words…").triggered.connect(lambda: self.load_words())
        menu.addSeparator()
        menu.addAction("Cancel running work").triggered.connect(self.cancel_all)

    def fruit_action(self, menu: QMenu) -> QAction:
        """The checkable Volumetric fruit action (and Cut fruit open) added to ``menu``."""
        action = QAction("Volumetric fruit", self.parent_widget)
        action.setCheckable(True)
        action.setEnabled(self.fruit_ok)
        action.setStatusTip(
            "Draw fruit as 3G-map volumes"
            if self.fruit_ok
            else "Volumetric fruit needs gmap.plant and gmap.pyvista (not available)"
        )
        action.toggled.connect(self.set_fruit)
        menu.addAction(action)
        self.fruit_toggle = action
        cut = QAction("Cut fruit open", self.parent_widget)
        cut.setCheckable(True)
        cut.setStatusTip(
            "Halve every fruit with a plane facing you (turn the view, then toggle again to cut along the new direction)"
        )
        cut.toggled.connect(self.set_cut)
        menu.addAction(cut)
        self.cut_toggle = cut
        return action

    # -- tasks ------------------------------------------------------------------
    def run(
        self,
        kind: str,
        fn: Callable[[Callable[..., None], Callable[[], bool]], Any],
        on_done: Callable[[Any], object],
        label: str,
        progress: bool = True,
    ) -> Task:
        """Start a cancellable task (replacing a running one of the same kind)."""
        old = self.tasks.get(kind)
        if old is not None and old.running:
            old.cancel()
        task = Task(kind, fn, self.parent_widget)
        self.tasks[kind] = task
        if progress:
            self.progress.setRange(0, 0)
            self.progress.setFormat(f"{label} %p%")
            self.progress.show()
            self.cancel_button.show()
            task.progressed.connect(self._progress)
        task.done.connect(lambda result: self._finished(task, on_done, result))
        task.failed.connect(lambda exc, details: self._failed(task, exc, details))
        task.was_cancelled.connect(lambda: self._finished(task, None, None, cancelled=True))
        task.quiet = not progress  # a quiet task (a preview) leaves the status bar alone
        task.label = f"{label}…"
        if progress:
            self._say(task.label, 0)
        return task.start()

    def _progress(self, done, total, text) -> None:
        bar = self.progress
        bar.setRange(0, max(total, 1))
        bar.setValue(done)

    def _end(self, task: Task) -> None:
        name = task.name
        if self.tasks.get(name) is task:
            del self.tasks[name]
        if not any(t.running for t in self.tasks.values()):
            self.progress.hide()
            self.cancel_button.hide()

    def _finished(self, task, on_done, result, cancelled: bool = False) -> None:
        self._end(task)
        if cancelled:
            if not task.quiet:
                self._say(f"{task.name} cancelled")
            return
        if not task.quiet:
            self.status_ended.emit(task.label)  # only our own message: a newer one (a qualifier's result) stays
        if on_done is not None and self.tasks.get(task.name) is None:
            on_done(result)

    def _failed(self, task, exc, details) -> None:
        self._end(task)
        if isinstance(exc, RamureError):
            self.refused.emit(str(exc))
        else:
            self.crashed.emit(f"{type(exc).__name__}: {exc}", details)

    def cancel_all(self) -> None:
        """Cancel every running task."""
        for task in list(self.tasks.values()):
            task.cancel()

    def busy(self) -> bool:
        """True while a task runs."""
        return any(t.running for t in self.tasks.values())

    # -- explorations ---------------------------------------------------------------
    def _variant_lsystem(self):
        """The grammar with the session's current constants (what sweeps and previews vary)."""
        return self.controller.read(lambda ex: ex.variant_lsystem(), wait=None)

    def explore(self, n_jobs: int | None = None, then: Callable[[], object] | None = None) -> Task:
        """Sweep the current grammar's variants around the session's current constants
        (worker, progress, cancel); then ``then()``."""
        snap = self.controller.snapshot
        text, constants, n, seed = snap.text, dict(snap.constants), snap.n, snap.seed
        ls = self._variant_lsystem()
        options = self.gallery.sweep_options()  # hidden constants, wide step: the dock's boxes

        def work(progress, cancelled):
            return variants.explore_plant(
                ls, n, seed, progress=lambda d, t: progress(d, t, "variants"), cancel=cancelled, n_jobs=n_jobs, **options
            )

        def done(vs) -> None:
            self.text, self.constants, self.lsystem = text, constants, ls
            self.set_variants(vs)
            if then is not None:
                then()

        return self.run("explore", work, done, "Exploring variants")

    def explored(self) -> bool:
        """True if the variant set is a sweep of the grammar text and constants on screen."""
        vs = self.variant_set
        snap = self.controller.snapshot
        return vs is not None and vs.exploration is not None and self.text == snap.text and self.constants == snap.constants

    def open_exploration(self, directory: str | os.PathLike | None = None) -> VariantSet | None:
        """Show the exploration saved in ``directory`` (asked for when None); None after saying why not."""
        if directory is None:
            directory = QFileDialog.getExistingDirectory(self.parent_widget, "Open exploration folder")
            if not directory:
                return None
        try:
            vs = variants.load_exploration(directory)
        except RamureError as exc:
            self.refused.emit(str(exc))
            return None
        self.text, self.constants = self.controller.snapshot.text, dict(self.controller.snapshot.constants)
        self.lsystem = self._variant_lsystem()
        self.set_variants(vs)
        return vs

    def set_variants(self, vs: VariantSet) -> None:
        """Show a variant set: gallery (placeholders, then thumbnails), PCA cloud, qualifiers."""
        self.variant_set = vs
        self.gallery.set_picks(
            vs.picks, [placeholder_image(THUMB, f"#{p.get('id')}", "drawing…") for p in vs.picks], base=self.constants
        )
        self.pca_view.set_variants(vs)
        self.variants_shown.emit(vs)  # the gallery in front of the regeneration panel, the qualifier map
        self.regen.qualifier_note.setText(
            "" if vs.exploration is not None else "A qualifier explores this grammar's variants first."
        )
        if vs.exploration is not None and self.regen.qualifier.currentText():
            self.preview_qualifier(self.regen.qualifier.currentText())
        self.render_thumbnails()

    def render_thumbnails(self) -> Task:
        """Draw the 27 picks' thumbnails in a task (each pick's plant, beside the base plant)."""
        vs = self.variant_set
        assert vs is not None, "set_variants() comes first"
        snap = self.controller.snapshot
        ls, n, seed = self.lsystem, vs.n if vs.n is not None else snap.n, vs.seed
        assert ls is not None  # a grammar is loaded before variants are drawn

        def work(progress, cancelled):
            images = []
            base = _base_skeleton(ls, n, seed)
            for i, pick in enumerate(vs.picks):
                progress(i, len(vs.picks), "thumbnails")
                path = vs.image_path(pick)
                image = QImage(str(path)) if path and base is None else QImage()
                if image.isNull():
                    try:
                        sk = variants.variant_skeleton(ls, n, seed, pick.get("params"))
                        # what the pick shares with the plant pale: the part that differs stands out
                        image = skeleton_image(sk, THUMB, same=None if base is None else same_segments(sk, base))
                    except RamureError:
                        image = placeholder_image(THUMB, f"#{pick.get('id')}", "cannot derive")
                images.append(image)
            progress(len(vs.picks), len(vs.picks), "thumbnails")
            return images

        return self.run("thumbnails", work, self.gallery.set_images, "Drawing thumbnails")

    def plant_changed(self, snap: Snapshot) -> None:
        """A new plant: say when the variants belong to another text or constants; redraw the fruit volumes."""
        if self.variant_set is not None and self.text is not None and snap.text != self.text:
            self.gallery.note.setText("These variants were explored for another grammar text; explore again to update them.")
        elif self.variant_set is not None and self.constants is not None and snap.constants != self.constants:
            self.gallery.note.setText(
                "The constants changed since these variants were explored; a qualifier explores again around the new values."
            )
        if self.show_fruit:
            self.draw_fruit(snap)

    # -- applying -----------------------------------------------------------------
    def apply_pick(self, pick: Mapping[str, Any]) -> Job:
        """Regrow the selection (or whole plant) with a gallery pick's parameter combination."""
        return self.controller.regrow(params=pick.get("params"))

    def apply_qualifier(self, name: str) -> Job | Task | None:
        """Regrow the selection (or plant) toward qualifier ``name`` (explores first if needed).

        :meth:`ramure.app.model.Explorer.apply_qualifier` tries the best variants until
        the selection's metrics move the qualifier's way; one undoable edit.  A word
        nobody knows is refused at once, with the nearest words (None).
        """
        key = self._qualifier_key(name)
        if key is None:
            return None
        name = key
        if not self.explored():
            self._say(f"Exploring the variants before applying '{name}'…", 0)
            return self.explore(then=lambda: self.apply_qualifier(name))
        assert self.variant_set is not None and self.variant_set.exploration is not None  # explored()
        sweep = self.variant_set.exploration.sweep
        directions = self.directions()
        job = self.controller.submit(f"qualifier {name}", lambda ex: ex.apply_qualifier(name, sweep, directions=directions))
        self._say(
            f"Applying '{name}': trying the best variants on the "  # after "Computing…"
            f"{'selection' if self.controller.snapshot.selection else 'whole plant'}…",
            0,
        )
        return job

    def qualifier_done(self, job: Job) -> None:
        """A qualifier job ended: keep its result and say what it did."""
        if job.name.startswith("qualifier ") and not job.stale and job.error is None:
            self.last_qualifier = job.result
            self._say(variants.qualifier_message(job.result), 15000)

    def preview_qualifier(self, name: str) -> Task | None:
        """Draw the whole plant with the qualifier's best-ranked variant (a thumbnail, in a task)."""
        if not self.explored():
            self.regen.set_preview(None)
            return None
        from ramure.metrics.qualifiers import qualifier_combination

        assert self.variant_set is not None and self.variant_set.exploration is not None  # explored()
        key = self._qualifier_key(name)
        if key is None:
            self.regen.set_preview(None)
            return None
        try:
            params = qualifier_combination(key, self.variant_set.exploration.sweep, directions=self.directions() or None)
        except RamureError as exc:
            self.regen.qualifier_note.setText(str(exc))
            return None
        snap = self.controller.snapshot
        ls, n, seed = self.lsystem, snap.n, snap.seed
        assert ls is not None  # a grammar is loaded before variants are drawn
        self.regen.qualifier_note.setText(
            f"Best variant: rule {params.get('rule')}, "
            + ", ".join(f"{k}={v:g}" for k, v in params["constants"].items())
            + ". Applying tries the best few on the selection."
        )

        def work(progress, cancelled):
            return skeleton_image(variants.variant_skeleton(ls, n, seed, params), 96)

        return self.run("preview", work, self.regen.set_preview, "Preview", progress=False)

    # -- volumetric fruit ------------------------------------------------------------
    def set_fruit(self, on: bool) -> None:
        """Volumetric fruit on/off: the volumes replace the plant's fruit spheres."""
        self.show_fruit = bool(on)
        self.view.set_fruit_spheres_hidden(self.show_fruit)
        if on:
            self.draw_fruit(self.controller.snapshot)
        else:
            self.view.set_fruit(None)

    def draw_fruit(self, snap: Snapshot) -> None:
        """Build the fruit volumes in the worker (the model caches them) and draw their surface."""
        from ramure.app.desktop.state import fruit_cut_surface, fruit_surface

        if self.cut_fruit:
            camera = self.view.plotter.camera
            normal = np.subtract(camera.position, camera.focal_point)
            job = self.controller.submit("fruit", lambda ex: fruit_cut_surface(ex, normal), key="fruit")
        else:
            job = self.controller.submit("fruit", fruit_surface, key="fruit")
        self.fruit_job = job.id

    def set_cut(self, on: bool) -> None:
        """Cut every fruit open (the volumes are shown, halved facing the viewer), or close them."""
        self.cut_fruit = bool(on)
        if self.cut_fruit and not self.show_fruit:
            self.fruit_toggle.setChecked(True)  # draws the (cut) volumes
        elif self.show_fruit:
            self.draw_fruit(self.controller.snapshot)

    def fruit_ready(self, job: Job) -> None:
        """The fruit volumes of the current plant are built: draw them (if still wanted)."""
        if job.name != "fruit" or job.stale or job.error is not None or not self.show_fruit:
            return
        self.view.set_fruit(job.result, self.controller.snapshot.selection)
        self.fruit_job_cut = self.cut_fruit  # what is on screen (tests)
        if job.result is None:
            self._say("This plant has no fruit")

    def fruit_clicked(self, leaf: int, mode: str) -> None:
        """A click on a fruit volume asks for that leaf to be selected (:attr:`select_requested`)."""
        self.select_requested.emit([leaf], mode)

    def regrow_fruit(self, preset: str = "") -> Job:
        """New seed (and ``preset`` shape, if given) for the selected fruit; shows the volumes."""
        job = self.controller.submit("regrow fruit", lambda ex: ex.regrow_fruit(preset=preset) if preset else ex.regrow_fruit())
        if not self.show_fruit:
            self.fruit_toggle.setChecked(True)  # fruit settings show on the volumes
            self._say("Volumetric fruit shown: fruit shapes and seeds apply to the volumes", 6000)
        return job


def _base_skeleton(lsystem: LSystem, n: int | None, seed: int) -> Skeleton | None:
    """The plant the variants are compared with (no pick applied), None if it cannot derive."""
    try:
        return variants.variant_skeleton(lsystem, n, seed, None)
    except RamureError:
        return None
