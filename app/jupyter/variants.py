"""Variant exploration in the notebook: sweep with a progress bar, 27-thumbnail gallery,
PCA scatter with qualifier boxes, and the qualifier choices.

The work is done by :mod:`ramure.metrics` (sweep, PCA, picks, qualifier regions and
combinations); this panel only runs it and shows it.  A sweep started from
the button runs in a thread and *Stop* cancels it; a sweep started from code
(:meth:`VariantPanel.explore`) blocks, updates the same bar, and stops on a
kernel interrupt.  Before a sweep the panels say what to press.

Sweeps start from the session's current constants
(:meth:`ramure.app.model.Explorer.variant_lsystem`), not the file's ``#define``
values.  Applying a pick regrows the selection's cut (the whole plant when
nothing is selected) with that variant's parameter combination
(:meth:`ramure.app.model.Explorer.regrow`); applying a qualifier goes through
:meth:`ramure.app.model.Explorer.apply_qualifier`, which tries candidates until the
selection's metrics move the qualifier's way and keeps one undoable edit.  The
qualifier is a typed word (English or French, synonyms, comparatives, a
study's words from :meth:`VariantPanel.load_words`), read by
:func:`ramure.metrics.qualifiers.vocabulary_name` as in every front end.  The
*PCA & qualifiers* tab also shows the qualifiers' collision matrix as a heat map
(:func:`collision_png`).

>>> from types import SimpleNamespace as NS
>>> m = NS(branch_density=1772.5, branch_count=3)
>>> qualifier_summary(NS(qualifier="dense", improved=True, before=m, after=NS(branch_density=2137.5, branch_count=3),
...                      params={}, tried=1))
'denser: density 1772 → 2138, branches 3 → 3'
"""

from __future__ import annotations

import base64
import os
import pathlib
import tempfile
import threading
from typing import TYPE_CHECKING, Any

import ipywidgets as W
import numpy as np

from ramure.app.jupyter._ui import Fallback, button, message_html, observe, png_image, png_tag
from ramure.app.jupyter.mainthread import is_main_thread, kernel_loop, on_main
from ramure.app.jupyter.scatter import pca_png
from ramure.app.jupyter.view import RENDER_LOCK
from ramure.errors import RamureError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.metrics.apply import QualifierResult
    from ramure.metrics.exploration import Exploration
    from ramure.metrics.sweep import VariantSweep
    from ramure.metrics.qualifiers import Qualifier, QualifierRegions
    from ramure.metrics.store import QualifierStore

N_PICKS = 27


def qualifier_tools() -> tuple[dict[str, Qualifier], type[QualifierStore]]:
    """``(VOCABULARY, QualifierStore)``: the qualifier words and the store of study regions."""
    from ramure.metrics.qualifiers import VOCABULARY
    from ramure.metrics.store import QualifierStore

    return VOCABULARY, QualifierStore


#: How the message line words a qualifier that worked ("denser: density 1772 → 2172").
COMPARATIVES = {
    "small": "smaller",
    "large": "larger",
    "sparse": "sparser",
    "dense": "denser",
    "thin": "thinner",
    "thick": "thicker",
    "round": "rounder",
}


def _metric_label(metric) -> str:
    return metric.removeprefix("branch_").replace("_", " ") if metric != "branch_count" else "branches"


def qualifier_summary(result: QualifierResult) -> str:
    """One line on what applying a qualifier did to the selection: the metrics its direction
    weighs most, before → after, and whether they moved its way."""
    name = result.qualifier
    entry = qualifier_tools()[0].get(name)
    weights = (entry.direction or {}) if entry is not None else {}
    shown = sorted(weights, key=lambda m: -abs(weights[m]))[:2]
    moves = ", ".join(f"{_metric_label(m)} {getattr(result.before, m):.4g} → {getattr(result.after, m):.4g}" for m in shown)
    why = f": {result.reason}" if getattr(result, "reason", None) else ""
    if not shown and getattr(result, "regen", True) is None:  # a study's word that moved nothing: say why
        return f"'{name}' did not move the selection its way after {result.tried} tries; the plant is as it was{why}"
    if not shown:  # no vocabulary direction (normal, a study's word): say what was applied
        return f"'{name}': applied {result.params}"
    if result.improved:
        word = COMPARATIVES.get(name, f"more {name}")
        return f"{word}: {moves}"
    return f"'{name}' did not move the selection its way after {result.tried} tries ({moves}); the plant is as it was{why}"


def collision_figure(regions: QualifierRegions, french: bool = False, title: str | None = None) -> Figure:
    """The collision matrix of ``regions`` as a heat map with the qualifier names (English or
    French) and a colour bar, on a matplotlib figure of its own (no pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ramure.metrics.heatmap import draw_collision_matrix

    fig = Figure(figsize=(6.4, 5.6), dpi=90)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=0.2, bottom=0.22, right=0.95, top=0.93 if title else 0.98)
    ax = fig.add_subplot()
    image = draw_collision_matrix(ax, regions.collision_matrix_, regions.names_, title=title, french=french)
    fig.colorbar(image, ax=ax, shrink=0.75, label="% of A's variants in B's box")
    return fig


def collision_png(figure: Figure) -> bytes:
    """PNG bytes of a figure made by :func:`collision_figure`."""
    import io

    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()


class Stopped(RamureError):
    """The exploration was stopped before it finished."""


class VariantPanel:
    """Explore the current grammar's variants, browse the 27 picks, apply one."""

    def __init__(self, app: NotebookExplorer, thumb_size: int = 110, cache: bool = True) -> None:
        self.app = app
        self.thumb_size = thumb_size
        self.cache = cache
        self.exploration: Exploration | None = None
        self.thumbnails: list[bytes | None] = [None] * N_PICKS
        self.regions: QualifierRegions | None = None  # from a study, if loaded
        self.defaults: QualifierRegions | None = None  # regions of the default vocabulary (its best-ranked variants)
        self.collisions: QualifierRegions | None = None  # what the collision matrix shows (study or vocabulary)
        self.matrix_figure: Figure | None = None
        self._matrix_key: tuple | None = None  # (regions, French names) the heat map shows
        self.words: dict[str, dict[str, float]] = {}  # a study's words: {word: direction} (load_words)
        self.chosen: np.ndarray | None = None  # PCA point of the last applied pick/qualifier
        self.running: threading.Thread | None = None  # the worker thread of a button-started sweep
        self._sweep: VariantSweep | None = None
        self._stop = threading.Event()
        self._pending: tuple[Any, Any] | None = None  # (exploration, grammar) whose thumbnails the main thread renders
        model = app.model
        self.n = W.BoundedIntText(
            value=min(model.session.n, 5),
            min=0,
            max=30,
            description="n",
            style={"description_width": "20px"},
            layout=W.Layout(width="100px"),
        )
        self.beta = W.BoundedFloatText(
            value=0.1,
            min=0.001,
            max=0.999,
            step=0.01,
            description="β",
            style={"description_width": "20px"},
            layout=W.Layout(width="110px"),
        )
        self.jobs = W.BoundedIntText(
            value=1, min=1, max=64, description="workers", style={"description_width": "55px"}, layout=W.Layout(width="130px")
        )
        # issue 35's larger space, off by default: the default PCA cloud (486 variants on Honda) stays
        self.hidden = W.Checkbox(
            value=False,
            description="hidden constants",
            indent=False,
            tooltip="also vary the numeric literals and rule probabilities (VariantSweep hidden=True)",
            layout=W.Layout(width="140px"),
        )
        self.wide = W.BoundedFloatText(
            value=0.0,
            min=0.0,
            max=0.9,
            step=0.05,
            description="wide",
            tooltip="a larger step (0.25: +-25 %) added one constant at a time; 0: none",
            style={"description_width": "35px"},
            layout=W.Layout(width="110px"),
        )
        self.start = button(
            "Explore variants",
            lambda: self.explore(wait=False),
            style="primary",
            tooltip="derive and measure every ±β variant, PCA, pick 27 (runs in the background)",
        )
        self.stop_button = button("Stop", self.stop, style="warning", tooltip="cancel the running exploration")
        self.stop_button.disabled = True
        self.bar = W.IntProgress(value=0, min=0, max=1, layout=W.Layout(width="260px"))
        self.progress_text = W.Label("")
        self.note = W.HTML()
        # The thumbnails are the buttons' backgrounds (a style sheet in an HTML widget), so a
        # click on the image applies the pick; without the style a button still reads "#k".
        self._css_class = f"ramure-pick-{id(self):x}"
        self.thumb_css = W.HTML()
        self.cards = []
        for pid in range(1, N_PICKS + 1):
            pick = button(
                f"#{pid}",
                lambda pid=pid: self.app.apply_pick(pid),
                width=f"{thumb_size}px",
                tooltip=f"#{pid}: regrow the selection (or the plant) with this variant's parameters",
            )
            pick.layout.height = f"{thumb_size}px"
            pick.add_class(self._css_class)
            pick.add_class(f"{self._css_class}-{pid}")
            self.cards.append(pick)
        self.gallery = W.GridBox(
            self.cards, layout=W.Layout(grid_template_columns=f"repeat(9, {thumb_size + 4}px)", grid_gap="2px")
        )
        self.scatter = png_image()
        self.box_toggles = W.VBox()
        self.widget = W.VBox(
            [
                W.HBox([self.n, self.beta, self.jobs, self.hidden, self.wide, self.start, self.stop_button]),
                W.HBox([self.bar, self.progress_text]),
                self.note,
                self.thumb_css,
                self.gallery,
            ]
        )
        self.matrix = png_image()
        self.matrix_note = W.HTML()
        self.matrix_french = W.Checkbox(value=False, description="French names", indent=False)
        observe(self.matrix_french, lambda _c: self._draw_matrix())
        self.words_path = W.Text(placeholder="words.json", description="study words", layout=W.Layout(width="260px"))
        self.load_words_button = button(
            "Load",
            lambda: self.app.load_words(self.words_path.value),
            "accept the words of a vocabulary file ('ramure study words') as qualifiers",
        )
        self.pca_widget = W.VBox(
            [
                W.HBox([self.scatter, W.VBox([W.HTML("<b>Qualifier boxes</b>"), self.box_toggles])]),
                W.HTML("<b>Collision matrix</b>"),
                self.matrix_note,
                self.matrix,
                self.matrix_french,
                W.HBox([self.words_path, self.load_words_button]),
            ]
        )
        self.refresh()

    # -- running -----------------------------------------------------------
    def _progress(self, done, total, what: str = "variants") -> None:
        self.bar.max = max(int(total), 1)
        self.bar.value = int(done)
        self.progress_text.value = f"{what} {done}/{total}"

    def explore(
        self,
        n: int | None = None,
        beta: float | None = None,
        n_jobs: int | None = None,
        wait: bool = True,
        thumbnails: bool = True,
        hidden: bool | None = None,
        wide: float | None = None,
    ) -> Exploration | threading.Thread:
        """Sweep the current grammar, run the PCA, pick 27 and render their thumbnails.

        With ``wait`` (the default from code) this blocks and returns the
        exploration; otherwise it starts a thread and returns it.  ``hidden``
        and ``wide`` (0: none) set the tab's boxes: the grammar's hidden
        constants and a larger step (e.g. 0.25), as ``ramure explore --hidden
        --wide 0.25``; both off by default so the default cloud stays the thesis's.
        """
        if self.running is not None and self.running.is_alive():
            raise RamureError("an exploration is already running: stop it first")
        from ramure.metrics import VariantSweep

        for widget, value in ((self.n, n), (self.beta, beta), (self.jobs, n_jobs), (self.hidden, hidden), (self.wide, wide)):
            if value is not None:
                widget.value = value
        # a kernel always runs threads, so worker processes are started by a fork server, not forked
        sweep = VariantSweep(
            n=self.n.value,
            beta=self.beta.value,
            n_jobs=self.jobs.value,
            cache=self.cache,
            hidden=bool(self.hidden.value),
            wide=float(self.wide.value) or None,
            mp_context="forkserver" if self.jobs.value > 1 else None,
        )
        self._sweep = sweep
        self._stop.clear()
        lsystem = self.app.model.variant_lsystem()
        if wait:
            return self._run(sweep, lsystem, thumbnails)
        self.running = threading.Thread(
            target=self._run_reported, args=(sweep, lsystem, thumbnails), name="ramure-explore", daemon=True
        )
        self.running.start()
        return self.running

    def _run_reported(self, sweep, lsystem, thumbnails) -> None:
        try:
            self._run(sweep, lsystem, thumbnails)
        except Stopped as err:
            self.app.message.show(err, "note")
        except RamureError as err:
            self.app.message.show(err, "error")

    def _run(self, sweep, lsystem, thumbnails):
        from ramure.metrics import SweepCancelled, explore

        self.start.disabled, self.stop_button.disabled = True, False
        self.note.value = message_html("exploring…", "note")
        try:
            exp = explore(lsystem, sweep=sweep, progress=self._progress, cancel=self._stop)
        except (SweepCancelled, Stopped, KeyboardInterrupt):
            self._stopped(sweep)
        if thumbnails and not is_main_thread() and kernel_loop() is not None:
            # VTK draws on the kernel's main thread only: the thumbnails are rendered there
            self._pending = (exp, lsystem)
            on_main(self._finish_pending)
            return exp
        return self._finish(exp, lsystem, thumbnails)

    def _stopped(self, sweep):
        sweep.cancel()
        self.start.disabled, self.stop_button.disabled = False, True
        self.note.value = message_html("exploration stopped; the previous results are kept", "note")
        raise Stopped("the exploration was stopped") from None

    def _finish_pending(self) -> None:
        """Render the thumbnails of a sweep a worker thread finished (on the main thread)."""
        pending, self._pending = self._pending, None
        if pending is None:
            return
        try:
            self._finish(*pending, thumbnails=True)
        except RamureError as err:
            self.app.message.show(err, "note" if isinstance(err, Stopped) else "error")

    def _finish(self, exp, lsystem, thumbnails):
        """Thumbnails (optional), then show the exploration — unless the grammar changed meanwhile."""
        try:
            images = self._render_thumbnails(exp) if thumbnails else [None] * N_PICKS
        except (Stopped, KeyboardInterrupt):
            self._stopped(exp.sweep)
        self.start.disabled, self.stop_button.disabled = False, True
        if self.app.model.lsystem.text != lsystem.text:
            self.note.value = message_html(
                "the grammar changed during the exploration: its results were set aside; explore again", "note"
            )
            return exp
        self.exploration, self.thumbnails, self.chosen = exp, images, None
        self.defaults = self.collisions = None
        self.refresh()
        self.app.edits.refresh()  # the qualifier choices
        return exp

    def _render_thumbnails(self, exp, batch=9):
        """The 27 pick thumbnails (PNG bytes) by :mod:`ramure.app.thumbnails`, a row of nine at a time
        (one render each) so the bar moves and *Stop* is honoured between rows."""
        from ramure.app.thumbnails import render_variants

        size = (self.thumb_size * 2, self.thumb_size * 2)
        images = []
        variants = exp.picks.variant.tolist()
        with tempfile.TemporaryDirectory() as tmp:
            for start in range(0, N_PICKS, batch):
                if self._stop.is_set():
                    raise Stopped("stopped")
                ids = range(start + 1, min(start + batch, N_PICKS) + 1)
                paths = [pathlib.Path(tmp) / f"pick_{pid:02d}.png" for pid in ids]
                with RENDER_LOCK:
                    render_variants(
                        exp.sweep, variants[start : start + len(paths)], paths, size, captions=[f"#{pid}" for pid in ids]
                    )
                images += [p.read_bytes() for p in paths]
                self._progress(len(images), N_PICKS, "thumbnails")
        return images

    def forget(self) -> None:
        """Drop the exploration (e.g. the grammar changed): the panels go back to empty."""
        self.exploration, self.thumbnails, self.regions, self.defaults, self.chosen = (None, [None] * N_PICKS, None, None, None)
        self.collisions = None
        self.refresh()

    def stop(self) -> None:
        """Cancel a running exploration (the button; safe to call when none runs)."""
        self._stop.set()
        if self._sweep is not None:
            self._sweep.cancel()

    def wait(self, timeout: float | None = None) -> None:
        """Wait for a button-started exploration to end (its thumbnails included)."""
        if self.running is not None:
            self.running.join(timeout)
        if not (self.running is not None and self.running.is_alive()) and is_main_thread():
            self._finish_pending()  # the main loop cannot run it while this cell waits

    # -- queries -----------------------------------------------------------
    def _need(self) -> Exploration:
        if self.exploration is None:
            raise RamureError("explore the variants first (Variants ▸ Explore variants)")
        return self.exploration

    def _pick_index(self, pick_id) -> int:
        """``pick_id`` (1-27) as a 0-based index, or a refusal naming the bad value."""
        self._need()
        try:
            index = int(str(pick_id).strip()) - 1
        except ValueError:
            index = -1
        if not 0 <= index < N_PICKS:
            raise RamureError(f"pick {pick_id!r} is not a number 1-{N_PICKS}")
        return index

    def pick_params(self, pick_id: int) -> dict:
        """The parameter combination ``{"rule", "constants"}`` of pick ``pick_id`` (1-27)."""
        index = self._pick_index(pick_id)
        exp = self._need()
        return exp.sweep.combination(int(exp.picks.variant[index]))

    def pick_point(self, pick_id: int) -> np.ndarray:
        return self._need().picks.points[self._pick_index(pick_id)]

    def qualifier_options(self) -> list:
        """``(label, name)`` of the qualifiers offered: study regions first (marked), then the
        default vocabulary, each with its French name (applying one explores first if needed)."""
        vocabulary = qualifier_tools()[0]
        study: list[str] = list(self.regions.names_) if self.regions is not None else []
        names = study + [name for name in vocabulary if name not in study]

        def label(name):
            french = vocabulary[name].french if name in vocabulary else None
            text = f"{name} ({french})" if french and french != name else name
            return f"{text} · study" if name in study else text

        return [(label(name), name) for name in names]

    def qualifier_words(self) -> list[str]:
        """What the qualifier box suggests: study regions first, then every accepted word
        (English, French, synonyms, comparatives) and the loaded study words."""
        from ramure.metrics.words import typed_words

        study = list(self.regions.names_) if self.regions is not None else []
        return study + [w for w in typed_words(self.words) if w not in study]

    def qualifier_name(self, text: str) -> str:
        """The canonical qualifier a typed ``text`` names ("plus touffu" -> bushy), or a refusal
        naming the nearest accepted words."""
        from ramure.metrics.qualifiers import vocabulary_name

        study = list(self.regions.names_) if self.regions is not None else []
        return vocabulary_name(text, extra=[*self.words, *study])

    def load_words(self, path: str | os.PathLike) -> dict[str, dict[str, float]]:
        """Accept the words of vocabulary file ``path`` (``ramure study words``) as qualifiers,
        with their measured directions; returns ``{word: direction}``."""
        from ramure.metrics.words import read_words

        self.words = read_words(path)
        return self.words

    def stale(self) -> bool:
        """True when the exploration was swept from other constant values than the plant's."""
        exp = self.exploration
        return exp is not None and dict(exp.sweep.base_constants_) != self.app.model.constants

    def apply_qualifier(self, name: str) -> QualifierResult:
        """Regrow the model's selection (or whole plant) toward qualifier ``name`` through
        :meth:`ramure.app.model.Explorer.apply_qualifier`, with the study regions when loaded.
        Without an exploration of the current constants, one is run first (blocking)."""
        key = self.qualifier_name(name)  # an unknown word is refused before any exploration
        if self.exploration is None or self.stale():
            self.explore(wait=True)
        exp = self._need()
        result = self.app.model.apply_qualifier(key, exp.sweep, points=exp.points, regions=self.regions, directions=self.words)
        self.mark_applied(exp.points[int(result.variant)] if result.regen is not None else None)
        return result

    def mark_applied(self, point: np.ndarray | None) -> None:
        """Show ``point`` (a variant's PCA point) as the applied one in the scatter."""
        self.chosen = point if point is not None and np.all(np.isfinite(point)) else None
        self._draw_scatter()

    def load_regions(self, store: str | os.PathLike, grammar: str | None = None) -> QualifierRegions:
        """Use the qualifier regions of ``grammar`` (default: the explored grammar) from a
        qualifier store (a path, e.g. written by ``ramure study export-qualifiers``)."""
        exp = self._need()
        tools = qualifier_tools()
        if not pathlib.Path(store).is_file():
            raise RamureError(f"{store}: no such qualifier store")
        with tools[1](store) as qs:  # a file that is not a store is refused there
            regions = qs.regions(grammar or exp.name)
        if regions is None:  # refused: the regions loaded before stay
            raise RamureError(f"{store}: no qualifier points for grammar '{grammar or exp.name}'")
        self.regions, self.collisions = regions, None
        self.refresh()
        return self.regions

    def boxes(self) -> dict:
        """``{name: (lo, hi)}`` to draw: study regions, else the default vocabulary's boxes."""
        if self.regions is not None:
            return dict(self.regions.boxes_)
        tools = qualifier_tools()
        if self.exploration is None:
            return {}
        if self.defaults is None:
            with tools[1](":memory:") as qs:
                qs.write_default(self.exploration)
                self.defaults = qs.regions(self.exploration.name)
        return dict(self.defaults.boxes_) if self.defaults is not None else {}

    # -- files -------------------------------------------------------------
    def save(self, directory: str | os.PathLike) -> dict:
        """Write the exploration (``variants.csv``, ``pca.json``, ``picks.json``) and the
        thumbnails (``thumbs/pick_NN.png``) to ``directory``: what a study reads."""
        from ramure.metrics import write_exploration

        exp = self._need()
        out = pathlib.Path(directory)
        (out / "thumbs").mkdir(parents=True, exist_ok=True)
        images: list[str] | None = None
        thumbs = [t for t in self.thumbnails if t is not None]
        if len(thumbs) == len(self.thumbnails):
            images = []
            for pid, data in enumerate(thumbs, start=1):
                rel = f"thumbs/pick_{pid:02d}.png"
                (out / rel).write_bytes(data)
                images.append(rel)
        return write_exploration(exp, out, images=images)

    # -- display -----------------------------------------------------------
    def gallery_html(self) -> str:
        """The 27 thumbnails as one HTML grid (what a saved notebook shows without widgets)."""
        cells = [png_tag(data, self.thumb_size, f"#{pid}") for pid, data in enumerate(self.thumbnails, start=1) if data]
        if not cells:
            return "<i>no variants explored yet</i>"
        return f"<div style='display:grid;grid-template-columns:repeat(9,{self.thumb_size + 4}px)'>{''.join(cells)}</div>"

    def _ipython_display_(self) -> None:
        """The panel, then the gallery as pictures (what a notebook reopened without a kernel shows)."""
        Fallback(self.widget, lambda: (self.gallery_html(), None), "<Ramure variants>")._ipython_display_()

    @property
    def pca(self) -> Fallback:
        """The *PCA & qualifiers* view for display in a cell, with its picture as the fallback."""
        return Fallback(
            self.pca_widget,
            lambda: (png_tag(self.scatter.value, 480, "PCA") if self.scatter.value else "", self.scatter.value or None),
            "<Ramure PCA view>",
        )

    def refresh_note(self) -> None:
        """The line over the gallery: what was explored, or why nothing is (cheap: called after
        every change of the plant, so it says when the constants moved since the sweep)."""
        exp = self.exploration
        if exp is None:
            note = message_html(
                "No variants yet: press “Explore variants” (or call ex.explore_variants()) to fill the gallery and the PCA view.",
                "note",
            )
        elif self.stale():
            note = message_html(
                "These variants were swept from other constant values than the plant's: "
                "explore again (a qualifier does so by itself).",
                "note",
            )
        else:
            s = exp.sweep
            note = message_html(
                f"{s.n_variants_} variants of '{exp.name}' (n={s.n_}, β={s.design_.beta:g}, "
                f"{int(s.failed_.sum())} failed), PCA explains "
                f"{100 * float(np.sum(exp.pca.explained_variance_ratio_)):.0f}% — click a pick to apply it.",
                "info",
            )
        if self.note.value != note:
            self.note.value = note

    def refresh(self) -> None:
        exp = self.exploration
        self.refresh_note()
        css = self.thumbnail_css() if exp is not None else ""
        if self.thumb_css.value != css:
            self.thumb_css.value = css
        for pick in self.cards:
            pick.disabled = exp is None
        self._draw_scatter()
        self._draw_matrix()

    def collision_regions(self) -> QualifierRegions | None:
        """The regions whose collision matrix is shown: the study's when loaded, else the default
        vocabulary's on this exploration (:func:`ramure.metrics.qualifiers.vocabulary_regions`)."""
        from ramure.metrics.qualifiers import vocabulary_regions

        if self.collisions is None and self.regions is not None:
            self.collisions = self.regions
        elif self.collisions is None and self.exploration is not None:
            self.collisions = vocabulary_regions(self.exploration.sweep, self.exploration.points)
        return self.collisions

    def _draw_matrix(self) -> None:
        try:
            regions = self.collision_regions()
        except RamureError as err:
            regions, why = None, f"no collision matrix: {err}"
        else:
            why = "explore the variants first" if regions is None else ""
        if regions is None:
            self.matrix_figure, self.matrix.value = None, b""
            self.matrix_note.value = f"<i>{why}</i>"
            return
        french = bool(self.matrix_french.value)
        drawn = self._matrix_key
        if self.matrix_figure is not None and drawn is not None and drawn[0] is regions and drawn[1] == french:
            return  # drawn already (about a second: 462 annotated cells)
        self._matrix_key = (regions, french)
        source = "the study's regions" if regions is self.regions else "the vocabulary's best variants"
        self.matrix_note.value = (
            f"<small>{len(regions.names_)} qualifiers ({source}); row A, column B: % of A's points inside "
            f"B's box; mean {regions.mean_collision():.1f} % (the thesis's study: 66 %). Dark = two words pick "
            "the same plants here.</small>"
        )
        self.matrix_figure = collision_figure(regions, french=french)
        self.matrix.value = collision_png(self.matrix_figure)

    def thumbnail_css(self) -> str:
        """The style sheet that puts each thumbnail on its button."""
        rules = [f".{self._css_class}:hover{{outline:2px solid #1976d2}}"]
        for pid, data in enumerate(self.thumbnails, start=1):
            if data:
                src = base64.b64encode(data).decode("ascii")
                rules.append(
                    f".{self._css_class}-{pid}{{background-image:url(data:image/png;base64,{src})"
                    " !important;background-size:cover !important;background-position:center;"
                    "color:transparent !important}"
                )
        return f"<style>{''.join(rules)}</style>"

    def _draw_scatter(self) -> None:
        exp = self.exploration
        if exp is None:
            self.box_toggles.children = [W.HTML("<i>explore the variants first</i>")]
            self.scatter.value = b""
            return
        boxes = self.boxes()
        known = {cb.description: cb.value for cb in self.box_toggles.children if isinstance(cb, W.Checkbox)}
        if set(known) != set(boxes):
            toggles = []
            for name in boxes:
                cb = W.Checkbox(
                    value=known.get(name, name in ("small", "large", "dense", "sparse")), description=name, indent=False
                )
                observe(cb, lambda _c: self._draw_scatter())
                toggles.append(cb)
            self.box_toggles.children = toggles or [W.HTML("<i>no qualifier regions</i>")]
        shown = {cb.description for cb in self.box_toggles.children if isinstance(cb, W.Checkbox) and cb.value}
        self.scatter.value = pca_png(
            exp.points, exp.picks.points, exp.picks.ids, {k: v for k, v in boxes.items() if k in shown}, self.chosen
        )
