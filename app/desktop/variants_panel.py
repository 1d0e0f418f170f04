"""Variants in the window: explorations, the gallery, the PCA dock, qualifiers, volumetric fruit.

:class:`VariantsController` runs the long work (the variant sweep, the 27
thumbnails, qualifier previews) as cancellable :class:`~app.desktop.workers.Task`
objects with the status bar's progress bar, and feeds the results to the
gallery, the PCA dock and the regeneration panel's qualifier drop-down.
The computations themselves are in :mod:`app.desktop.variants` and
:mod:`metrics`.
"""
from __future__ import annotations

from PySide6.QtGui import QAction, QImage
from PySide6.QtWidgets import QFileDialog

from app.desktop import variants
from app.desktop.thumbnails import placeholder_image, skeleton_image
from app.desktop.workers import Task
from lsys import LSystem
from lsys.errors import RamureError

THUMB = 150


def fruit_builder():
    """``gmap.plant.fruits_from_skeleton`` if the 3G-map layer provides it, else None."""
    try:
        from gmap.plant import fruits_from_skeleton
    except ImportError:
        return None
    return fruits_from_skeleton


class VariantsController:
    """Owns the current :class:`~app.desktop.variants.VariantSet` and the tasks that build it."""

    def __init__(self, window):
        self.window = window
        self.variant_set = None
        self.text = None  # grammar text the variant set belongs to
        self.tasks = {}
        self.show_fruit = False
        w = window
        w.gallery.pick_clicked.connect(self.apply_pick)
        w.gallery.explore_requested.connect(self.explore)
        w.gallery.open_requested.connect(self.open_exploration)
        w.regen.qualifier_chosen.connect(self.preview_qualifier)
        w.regen.apply_qualifier.connect(self.apply_qualifier)
        w.cancel_button.clicked.connect(self.cancel_all)
        reason = variants.metrics_available()
        if reason:
            w.gallery.set_unavailable(reason)
            w.gallery.explore_button.setEnabled(False)
            w.pca_view.set_unavailable(reason)
        else:
            w.gallery.set_unavailable("No exploration yet: Explore variants (a sweep of the constants "
                                      "±10 %, one rule at a time) or open an exploration folder.")

    @property
    def controller(self):
        return self.window.controller

    # -- menu -------------------------------------------------------------------
    def build_menu(self, menu):
        self.explore_action = menu.addAction("Explore variants of this grammar")
        self.explore_action.triggered.connect(self.explore)
        self.explore_action.setEnabled(variants.metrics_available() is None)
        menu.addAction("Open exploration folder…").triggered.connect(lambda: self.open_exploration())
        menu.addSeparator()
        menu.addAction("Cancel running work").triggered.connect(self.cancel_all)

    def fruit_action(self, menu):
        action = QAction("Volumetric fruit", self.window)
        action.setCheckable(True)
        builder = fruit_builder()
        action.setEnabled(builder is not None)
        action.setStatusTip("Draw fruit as 3G-map volumes" if builder else
                            "Volumetric fruit needs gmap.plant.fruits_from_skeleton (not available yet)")
        action.toggled.connect(self.set_fruit)
        menu.addAction(action)
        return action

    # -- tasks ------------------------------------------------------------------
    def run(self, kind, fn, on_done, label, progress=True):
        """Start a cancellable task (replacing a running one of the same kind)."""
        old = self.tasks.get(kind)
        if old is not None and old.running:
            old.cancel()
        task = Task(kind, fn, self.window)
        self.tasks[kind] = task
        w = self.window
        if progress:
            w.progress.setRange(0, 0)
            w.progress.setFormat(f"{label} %p%")
            w.progress.show()
            w.cancel_button.show()
            task.progressed.connect(self._progress)
        task.done.connect(lambda result: self._finished(task, on_done, result))
        task.failed.connect(lambda exc, details: self._failed(task, exc, details))
        task.was_cancelled.connect(lambda: self._finished(task, None, None, cancelled=True))
        w.status(f"{label}…", 0)
        return task.start()

    def _progress(self, done, total, text):
        bar = self.window.progress
        bar.setRange(0, max(total, 1))
        bar.setValue(done)

    def _end(self, task):
        if self.tasks.get(task.name) is task:
            del self.tasks[task.name]
        if not any(t.running for t in self.tasks.values()):
            self.window.progress.hide()
            self.window.cancel_button.hide()

    def _finished(self, task, on_done, result, cancelled=False):
        self._end(task)
        if cancelled:
            self.window.status(f"{task.name} cancelled")
            return
        self.window.status("")
        if on_done is not None and self.tasks.get(task.name) is None:
            on_done(result)

    def _failed(self, task, exc, details):
        self._end(task)
        if isinstance(exc, RamureError):
            self.window.report_refused(str(exc))
        else:
            self.window.report_crash(f"{type(exc).__name__}: {exc}", details)

    def cancel_all(self):
        for task in list(self.tasks.values()):
            task.cancel()

    def busy(self):
        return any(t.running for t in self.tasks.values())

    # -- explorations ---------------------------------------------------------------
    def explore(self, n_jobs=None):
        """Run the variant sweep on the current grammar (worker, progress, cancel)."""
        snap = self.controller.snapshot
        text, n, seed = snap.text, snap.n, snap.seed

        def work(progress, cancelled):
            ls = LSystem.from_text(text)
            return variants.explore_plant(ls, n, seed, progress=lambda d, t: progress(d, t, "variants"),
                                          cancel=cancelled, n_jobs=n_jobs)
        self.text = text
        return self.run("explore", work, self.set_variants, "Exploring variants")

    def open_exploration(self, directory=None):
        if directory is None:
            directory = QFileDialog.getExistingDirectory(self.window, "Open exploration folder")
            if not directory:
                return None
        try:
            vs = variants.load_exploration(directory)
        except RamureError as exc:
            self.window.report_refused(str(exc))
            return None
        self.text = self.controller.snapshot.text
        self.set_variants(vs)
        return vs

    def set_variants(self, vs):
        """Show a variant set: gallery (placeholders, then thumbnails), PCA cloud, qualifiers."""
        self.variant_set = vs
        w = self.window
        w.gallery.set_picks(vs.picks, [placeholder_image(THUMB, f"#{p.get('id')}", "drawing…") for p in vs.picks])
        w.pca_view.set_variants(vs)
        names = vs.qualifiers
        w.regen.set_qualifiers(names, "" if names else
                               "Qualifiers need a sweep run in this window (Variants ▸ Explore).")
        self.render_thumbnails()

    def render_thumbnails(self):
        vs = self.variant_set
        snap = self.controller.snapshot
        text, n, seed = snap.text, vs.n if vs.n is not None else snap.n, vs.seed

        def work(progress, cancelled):
            ls = LSystem.from_text(text)
            images = []
            for i, pick in enumerate(vs.picks):
                progress(i, len(vs.picks), "thumbnails")
                path = vs.image_path(pick)
                image = QImage(str(path)) if path else QImage()
                if image.isNull():
                    try:
                        sk = variants.variant_skeleton(ls, n, seed, pick.get("params"))
                        image = skeleton_image(sk, THUMB, f"#{pick.get('id')}")
                    except RamureError:
                        image = placeholder_image(THUMB, f"#{pick.get('id')}", "cannot derive")
                images.append(image)
            progress(len(vs.picks), len(vs.picks), "thumbnails")
            return images
        return self.run("thumbnails", work, self.window.gallery.set_images, "Drawing thumbnails")

    def plant_changed(self, snap):
        if self.variant_set is not None and self.text is not None and snap.text != self.text:
            self.window.gallery.note.setText("These variants were explored for another grammar text; "
                                             "explore again to update them.")
        if self.show_fruit:
            self.draw_fruit(snap)

    # -- applying -----------------------------------------------------------------
    def apply_pick(self, pick):
        """Regrow the selection (or whole plant) with a gallery pick's parameter combination."""
        self.window.dirty = True
        return self.controller.regrow(params=pick.get("params"))

    def _qualifier_params(self, name):
        rules = self.controller.read(variants.selection_rules, wait=None)
        return variants.qualifier_params(self.variant_set, name, rules)

    def apply_qualifier(self, name):
        try:
            params = self._qualifier_params(name)
        except RamureError as exc:
            self.window.report_refused(str(exc))
            return None
        self.window.dirty = True
        self.window.status(f"Applying '{name}': rule {params.get('rule')}, {params.get('constants')}")
        return self.controller.regrow(params=params)

    def preview_qualifier(self, name):
        if self.variant_set is None or self.variant_set.exploration is None:
            return None
        try:
            params = variants.qualifier_params(self.variant_set, name)
        except RamureError as exc:
            self.window.regen.qualifier_note.setText(str(exc))
            return None
        snap = self.controller.snapshot
        text, n, seed = snap.text, snap.n, snap.seed
        self.window.regen.qualifier_note.setText(
            f"rule {params.get('rule')}: " + ", ".join(f"{k}={v:g}" for k, v in params["constants"].items()))

        def work(progress, cancelled):
            sk = variants.variant_skeleton(LSystem.from_text(text), n, seed, params)
            return skeleton_image(sk, 96)
        return self.run("preview", work, self.window.regen.set_preview, "Preview", progress=False)

    # -- volumetric fruit ------------------------------------------------------------
    def set_fruit(self, on):
        self.show_fruit = bool(on)
        if on:
            self.draw_fruit(self.controller.snapshot)
        else:
            self.window.view.plotter.remove_actor("fruit", render=False)
            self.window.view.redraw()

    def draw_fruit(self, snap):
        builder = fruit_builder()
        if builder is None:
            return
        try:
            mesh = builder(snap.skeleton)
        except RamureError as exc:
            self.window.report_refused(str(exc))
            return
        if hasattr(mesh, "n_cells") and mesh.n_cells:
            self.window.view.plotter.add_mesh(mesh, color=(0.85, 0.18, 0.12), name="fruit", reset_camera=False,
                                              render=False, pickable=False)
        else:
            self.window.view.plotter.remove_actor("fruit", render=False)
        self.window.view.redraw()
