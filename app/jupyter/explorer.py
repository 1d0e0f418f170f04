"""The notebook explorer: edit, select, regenerate and browse variants of one plant.

:class:`NotebookExplorer` is a thin ipywidgets front end over the explorer,
:class:`ramure.app.model.Explorer` (``ex.model``), the GUI-free state the desktop window
also uses (the one class named ``Explorer``).  Every button
and every method below goes through the model; a refused input (a
:class:`~ramure.lsys.errors.RamureError`) is shown on the explorer's message line —
never as a traceback — and leaves the plant as it was.  Code and clicks mix
freely: ``ex.plant``, ``ex.selection``, ``ex.history`` and ``ex.session`` are
the live state.

>>> ex = NotebookExplorer("grammars/honda_sympodial.lsys", n=5, view="static")
>>> _ = ex.select_where(min_order=2)
>>> before = ex.plant.to_string()
>>> result = ex.regrow(constants={"a2": 25})
>>> ex.plant.to_string() != before, len(ex.selection) > 0, len(ex.history)  # the regrown part stays selected
(True, True, 1)
>>> ex.select([10**9]) is None, ex.error
(True, '1000000000 is not a leaf of the current plant')
"""

from __future__ import annotations

import base64
import html
import os
import pathlib
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

import ipywidgets as W

from ramure.app.jupyter.architecture import ArchitectureBrowser
from ramure.app.jupyter.wood import WoodTab
from ramure.app.jupyter.details import DetailsTab
from ramure.app.jupyter.defects import DefectsTab
from ramure.app.jupyter._ui import Fallback, MessageLine, button, on_value, png_tag
from ramure.app.jupyter.grammar import GrammarPanel
from ramure.app.jupyter.new_study import NewStudyPanel
from ramure.app.jupyter.selection import SelectionPanel, TreeBrowser
from ramure.app.jupyter.variants import VariantPanel, qualifier_summary
from ramure.app.jupyter.view import VIEWS, PlantView, fruit_cut_png, fruit_png
from ramure.app.document import CodeNotAllowed, runs_code, session_runs_code
from ramure.app.model import Explorer as Model
from ramure.app.model import source_path
from ramure.app.model import finite_number as _number  # a finite number or a refusal naming it
from ramure.app.model import warm_up_in_background
from ramure.errors import GrammarError, RamureError, ValueRefused

if TYPE_CHECKING:
    from IPython.display import Image
    from ramure.lsys import Derivation
    from ramure.lsys.regeneration.regen import RegenResult, Session
    from ramure.lsys.interpretation.turtle import Skeleton
    from ramure.metrics.apply import QualifierResult
    from ramure.app.new_study import NewStudy
    from ramure.metrics.exploration import Exploration
    from ramure.metrics.qualifiers import QualifierRegions

T = TypeVar("T")

PLACEHOLDER = "n: 0\nw: F"  # the plant shown while the given grammar does not parse
#: Why the rectangle cannot be used: the picture view has no camera a drag could be measured in.
NO_RECTANGLE = (
    'rectangle selection needs the interactive 3D view (pip install "pyvista[jupyter]"); '
    "select with the tools on the right or the derivation tree"
)


def _open_model(source, n, seed, run_code=False):
    """The model for ``source``; a grammar that does not parse gives a one-segment
    placeholder plant, the error and the text to show in the editor.  An ``.lpy`` model is
    refused (:class:`~ramure.app.document.CodeNotAllowed`) unless ``run_code``."""
    path = source_path(source)
    if path is not None:
        source = path
    if path is not None and not path.is_file():
        raise RamureError(f"{source}: no such grammar file")
    if path is not None and runs_code(path) and not run_code:
        raise CodeNotAllowed(path, how="pass run_code=True to Explorer(...) if you would run it as a script")
    try:
        return Model(source, n=n, seed=seed, run_code=run_code), None
    except GrammarError as err:
        text = path.read_text(encoding="utf-8", errors="replace") if path is not None else str(source)
        model = Model(PLACEHOLDER, seed=seed)
        model.error = err
        return model, text


def fruit_presets() -> list:
    """The volumetric fruit presets (:data:`ramure.gmap.organs.fruit.PRESETS`)."""
    from ramure.gmap.organs.fruit import PRESETS

    return list(PRESETS)


class EditPanel:
    """ρ, Regrow, Regrow with constants, the qualifier drop-down, Regrow fruit, Prune, Undo, Redo, files."""

    def __init__(self, app: NotebookExplorer) -> None:
        self.app = app
        self.rho = W.IntSlider(
            value=round(app.model.rho * 100),
            min=1,
            max=100,
            description="ρ %",
            continuous_update=False,
            style={"description_width": "30px"},
            layout=W.Layout(width="98%"),
        )
        on_value(self.rho, app.set_rho)
        self.regrow = button(
            "Regrow", app.regrow, "regrow the selection's cut (whole plant if nothing selected)", style="success"
        )
        self.regrow_constants = button(
            "Regrow with constants", app.regrow_with_constants, "regrow the cut with the slider values (only there)"
        )
        self.prune = button("Prune", app.prune, "delete the cut subtrees", style="danger")
        self.undo = button("Undo", app.undo, icon="undo")
        self.redo = button("Redo", app.redo, icon="repeat")
        # the words people type, with suggestions: English, French, synonyms, comparatives, a study's words
        self.qualifier = W.Combobox(
            options=[],
            value="",
            placeholder="taller, denser, plus touffu…",
            ensure_option=False,
            description="qualifier",
            style={"description_width": "60px"},
            layout=W.Layout(width="230px"),
        )
        self.apply_qualifier = button(
            "Apply",
            lambda: app.apply_qualifier(self.qualifier.value),
            "regrow the cut toward this qualifier (tries variants until the selection's metrics move its way)",
        )
        self.fruit_preset = W.Dropdown(
            options=[("same kind", "")] + [(p.replace("_", " "), p) for p in fruit_presets()],
            value="",
            description="fruit",
            style={"description_width": "35px"},
            layout=W.Layout(width="170px"),
        )
        self.fruit_size = W.BoundedFloatText(
            value=0.0,
            min=0.0,
            max=1e6,
            step=0.01,
            description="size",
            tooltip="0: keep the organ's size",
            style={"description_width": "30px"},
            layout=W.Layout(width="110px"),
        )
        self.regrow_fruit = button(
            "Regrow fruit",
            lambda: app.regrow_fruit(preset=self.fruit_preset.value or None, size=self.fruit_size.value or None),
            "new volumetric fruit for the selected fruit (new seed; the kind and size chosen here)",
        )
        self.path = W.Text(value="plant_session.json", layout=W.Layout(width="170px"))
        self.widget = W.VBox(
            [
                W.HTML("<b>Regenerate</b>"),
                self.rho,
                W.HBox([self.regrow, self.regrow_constants]),
                W.HBox([self.qualifier, self.apply_qualifier]),
                W.HBox([self.fruit_preset, self.fruit_size]),
                W.HBox([self.regrow_fruit]),
                W.HBox([self.prune, self.undo, self.redo]),
                W.HBox(
                    [
                        self.path,
                        button(
                            "Save",
                            lambda: app.save(self.path.value),
                            ".json: the session; .lsys: the grammar; .glb/.gltf/.obj/.vtp/.ply/.stl: the mesh",
                        ),
                    ]
                ),
            ]
        )

    def refresh(self) -> None:
        """Enable the buttons for what the model can do now (undo, redo, prune a selection, regrow selected
        fruit) and offer the qualifier words known.
        """
        model = self.app.model
        self.undo.disabled = not model.can_undo
        self.redo.disabled = not model.can_redo
        self.prune.disabled = not model.selection
        has_fruit = bool(model.selection) and bool(set(model.selection) & set(model.fruit_ids()))
        self.regrow_fruit.disabled = not has_fruit or not fruit_presets()
        words = self.app.variants.qualifier_words()
        if list(self.qualifier.options) != words:
            self.qualifier.options = words  # suggestions only: any word may be typed
        self.qualifier.tooltip = (
            "the first use explores the variants (a few seconds)"
            if self.app.variants.exploration is None
            else "the constants changed: the next use explores again"
            if self.app.variants.stale()
            else ""
        )
        rho = round(model.rho * 100)
        if self.rho.value != rho:
            self.rho.value = rho


class NotebookExplorer:
    """The Jupyter front end of the explorer (:class:`ramure.app.model.Explorer`) for a grammar:
    a file path, a shipped grammar's name (``"honda_sympodial"``, as :func:`ramure.load`) or text.

    The file may be a Ramure ``.lsys``, an L-studio/cpfg ``.l``, an OpenAlea ``.mtg`` (its
    plant becomes an unsaved grammar) or an L-Py ``.lpy`` model.  **An ``.lpy`` is a Python
    program**: opening it runs its code, so it is refused unless ``run_code=True`` says you
    would run it as a script (docs/security.md); :meth:`load_session` takes the same
    argument for a session of an L-Py model.

    ``view``: ``"auto"`` (interactive trame view when installed, else a
    picture), ``"static"`` or a trame mode.  ``size``: the 3D view in pixels.
    ``cache``: let variant sweeps use the on-disk cache.
    """

    def __init__(
        self,
        source: str | os.PathLike,
        n: int | None = None,
        seed: int = 0,
        view: str = "auto",
        size: tuple[int, int] = (480, 480),
        cache: bool = True,
        run_code: bool = False,
    ) -> None:
        self.model, text = _open_model(source, n, seed, run_code)
        self.error: str | None = None
        self.message = MessageLine()
        self.title = W.HTML()
        self.status_line = W.HTML()
        self.grammar = GrammarPanel(self, text)
        self.variants = VariantPanel(self, cache=cache)
        self.study_maker = NewStudyPanel(self)
        self.view = PlantView(self, backend=view, size=size)
        self.selection_panel = SelectionPanel(self)
        self.tree = TreeBrowser(self)
        self.architecture = ArchitectureBrowser(self)
        self.edits = EditPanel(self)
        self.camera = W.Dropdown(
            options=VIEWS,
            value=self.view.view,
            description="view",
            style={"description_width": "35px"},
            layout=W.Layout(width="130px"),
        )
        on_value(self.camera, self.set_view)
        # the cut preview is on by default: what a regrow would change is orange, and said
        self.show_cut = W.Checkbox(value=True, description="preview the cut (orange)", indent=False)
        on_value(self.show_cut, self.set_show_cut)
        self.preview_line = W.HTML()
        # rectangle mode: a drag in the view selects what it encloses (the desktop's rubber band)
        self.rectangle = W.ToggleButton(
            value=False,
            description="▭ rectangle",
            tooltip="drag a rectangle in the view to select the branches in it (the mode on the right applies)",
            disabled=not self.view.picking,
            layout=W.Layout(width="110px"),
        )
        on_value(self.rectangle, self.set_rectangle_mode)
        self.zoom_fruit = W.ToggleButton(
            value=False,
            description="zoom to fruit",
            tooltip="frame the selected fruit (every fruit when none is selected); again: the whole plant",
            layout=W.Layout(width="120px"),
        )
        on_value(self.zoom_fruit, lambda on: self.zoom_to_fruit(bool(on)))
        picking = (
            "click a branch to select it; ▭ rectangle: drag to select the branches inside"
            if self.view.picking
            else "picture view: select with the tools on the right or the derivation tree"
        )
        centre = W.VBox(
            [
                self.view.widget,
                W.HBox([self.camera, self.show_cut, self.rectangle, self.zoom_fruit]),
                self.preview_line,
                W.HTML(f"<small>{picking}</small>"),
            ]
        )
        side = W.VBox([self.selection_panel.widget, self.edits.widget], layout=W.Layout(width="30%", min_width="320px"))
        left = W.VBox([self.grammar.widget], layout=W.Layout(width="30%", min_width="280px"))
        self.wood = WoodTab(self)
        self.details = DetailsTab(self)
        self.defects = DefectsTab(self)
        self.tabs = W.Tab(
            children=[
                self.tree.widget,
                self.architecture.widget,
                W.VBox([self.variants.widget, self.study_maker.widget]),
                self.variants.pca_widget,
                self.wood.widget,
                self.details.widget,
                self.defects.widget,
            ],
            titles=("Derivation tree", "Architecture", "Variants", "PCA & qualifiers", "Wood", "Details", "Defects"),
        )
        self.widget = W.VBox(
            [
                self.title,
                self.status_line,
                self.message.widget,
                W.HBox([left, centre, side], layout=W.Layout(flex_flow="row wrap", align_items="flex-start")),
                self.tabs,
            ]
        )
        self.fallback = Fallback(self.widget, self._picture, lambda: f"<Ramure Explorer: {self.model.status()}>")
        self._fallback_key: tuple | None = None  # the view's key when the fallback picture was sent
        if self.view.fallback_reason:
            self.message.show(self.view.fallback_reason, "note")
        if self.model.error is not None:
            self._refused(self.model.error, "the grammar does not parse; fix it in the text area")
        self.refresh()

    # -- live state ----------------------------------------------------------
    @property
    def plant(self) -> Derivation:
        """The current :class:`~ramure.lsys.Derivation` (its string, tree and ``skeleton()``)."""
        return self.model.derivation

    @property
    def skeleton(self) -> Skeleton:
        """The turtle's skeleton of the plant shown (the model's :attr:`~ramure.app.model.Explorer.skeleton`)."""
        return self.model.skeleton

    @property
    def session(self) -> Session:
        """The editing :class:`~ramure.lsys.regeneration.regen.Session` (``save``, ``edits``, ``derivation``)."""
        return self.model.session

    @property
    def history(self) -> list[dict]:
        """The applied edits, oldest first (each a dict that replays the edit)."""
        return self.model.session.edits

    @property
    def selection(self) -> list[int]:
        """Selected leaf ids (sorted); assign a list to replace it."""
        return list(self.model.selection)

    @selection.setter
    def selection(self, leaf_ids: int | Iterable[int]) -> None:
        """Select ``leaf_ids`` in place of the current selection (as :meth:`select` with ``replace``)."""
        self.select(leaf_ids, "replace")

    def status(self) -> str:
        """The model's one-line status: modules, segments, the selection and the last edit."""
        return self.model.status()

    # -- running actions -------------------------------------------------------
    def run(self, action: Callable[[], T], note: str | Callable[[], str] | None = None) -> T | None:
        """Run ``action()`` against the model; a RamureError is shown inline and None returned.
        ``note``: the message shown after it (a callable: read once the action has run)."""
        try:
            result = action()
        except RamureError as err:
            self._refused(err)
            self.refresh()
            return None
        except OSError as err:  # a file that cannot be read or written
            self._refused(f"{err.filename or 'file'}: {err.strerror or err}")
            self.refresh()
            return None
        self.error = None
        self.message.show((note() if callable(note) else note) or self.model.status(), "info")
        self.refresh()
        return result

    def _refused(self, err, note=None) -> None:
        self.error = str(err)
        self.message.show(note or err, "error")

    def refresh(self) -> None:
        """Bring every panel up to date with the model (called after each action)."""
        model = self.model
        name = model.path.name if model.path else "grammar text"
        self.title.value = f"<h3 style='margin:4px 0'>Ramure explorer — {name}</h3>"
        self.status_line.value = f"<small>{model.status()}</small>"
        self.preview_line.value = self._preview_html()
        for panel in (self.grammar, self.view, self.selection_panel, self.tree, self.architecture, self.edits):
            panel.refresh()
        self.variants.refresh_note()
        if self.fallback.handle is not None and self._fallback_key != self.view.key():
            self._fallback_key = self.view.key()
            self.fallback.update()  # a saved notebook shows the plant as it is now

    def _preview_html(self) -> str:
        """The cut preview's sentence ("12 of 693 modules (1.7 %) will change ..."), orange when
        the view shows the cut, empty without a selection."""
        try:
            preview = self.model.preview()
        except RamureError as err:
            return f"<small>{html.escape(str(err))}</small>"
        if preview is None:
            return ""
        colour = "#c06000" if self.view.show_cut else "#444"
        return f"<small style='color:{colour}'>{html.escape(preview.message)}</small>"

    # -- grammar and constants ---------------------------------------------------
    def set_text(self, text: str) -> GrammarError | None:
        """Parse new grammar text; a parse error is shown at its line and column."""
        model = self.model
        if text in (model.text, model.document_text()) and model.error is None:
            return None  # the text shown: nothing to re-derive (regrown parts stay)
        self.grammar.show_text(text)
        err = model.set_text(text)
        if err is not None:
            self._refused(
                err,
                f"grammar not applied (line {err.line}, column {err.column}); the plant on screen is the last one that parsed",
            )
            self.refresh()
            return err
        self.variants.forget()  # the variants were of the old grammar
        self.run(lambda: None)
        return None

    def set_constant(self, name: str, value: float) -> None:
        """Change one ``#define`` (an undoable edit that re-derives the plant); a refused value is said in the
        message line.
        """
        self.run(lambda: self.model.set_constant(name, value))

    def apply_constants(self, values: Mapping[str, float] | None = None) -> None:
        """Set constants on the whole plant (default: the staged slider values)."""
        values = self.grammar.staged() if values is None else dict(values)
        if not values:
            self.message.show("no constant differs from the plant's: move a slider first", "note")
            return None

        def apply():
            checked = {name: _number(value, name) for name, value in values.items()}  # all or none
            unknown = sorted(set(checked) - set(self.model.constants))
            if unknown:
                raise ValueRefused(f"the grammar has no constant '{unknown[0]}'")
            for name, value in checked.items():
                self.model.set_constant(name, value)

        self.run(apply)

    def set_derivation(self, n: float | None = None, seed: float | None = None) -> None:
        """Re-derive with another derivation count ``n`` or ``seed`` (None keeps it; the same values do nothing);
        a refused value is said in the message line.
        """

        def apply():
            count = None if n is None else _number(n, "the derivation count")
            start = None if seed is None else _number(seed, "the seed")
            s = self.model.session
            if (count is None or count == s.n) and (start is None or start == s.seed):
                return None
            return self.model.set_derivation(count, start)

        self.run(apply)

    def set_rho(self, percent: float) -> None:
        """ρ as a percentage (1-100, the slider's unit); the model takes the fraction."""

        def apply():
            value = _number(percent, "ρ %")
            if not 0 < value <= 100:
                raise ValueRefused(f"rho must be in (0, 100] %, not {value:g}")
            self.model.set_rho(value / 100.0)

        self.run(apply, note=f"ρ = {percent} %")

    # -- selection -------------------------------------------------------------------
    def select(self, leaf_ids: int | Iterable[int], mode: str = "replace") -> None:
        """Change the selection (``mode`` is replace, add, remove or toggle) and prepare the next edit in the
        background.
        """
        self.run(lambda: self.model.select(leaf_ids, mode))
        self.warm_up()

    def warm_up(self) -> None:
        """Prepare the first edit once something is selected (a regrow usually follows): see
        :func:`ramure.app.model.warm_up_in_background`."""
        if self.model.selection:
            warm_up_in_background(self.model.text, self.model.session.n)

    def select_where(
        self,
        min_order: int | None = None,
        min_height: float | None = None,
        max_height: float | None = None,
        mode: str = "replace",
    ) -> None:
        """Select by branch order and height, e.g. every branch of order ≥ 3 above height h."""
        self.run(lambda: self.model.select(self.model.leaves_where(min_order, min_height, max_height), mode))
        self.warm_up()

    def clear_selection(self) -> None:
        """Select nothing (a Regrow then regrows the whole plant)."""
        self.run(self.model.clear_selection)

    def set_rectangle_mode(self, on: bool) -> None:
        """Rectangle mode (the ▭ button): a drag in the 3D view selects the branches it encloses
        instead of turning the view.  Needs the interactive view."""
        if self.rectangle.value != bool(on):
            self.rectangle.value = bool(on)  # the button's observer comes back here
            return
        if self.view.trame is None or not self.view.picking:
            if on:
                self.message.show(NO_RECTANGLE, "error")
                self.rectangle.value = False
            return
        self.view.trame.rectangle.enable(bool(on))

    def select_rectangle(self, rect: Sequence[float], mode: str | None = None) -> list[int] | None:
        """Select the leaves whose branch midpoints (and leaf and fruit centres) fall inside
        ``rect`` = (x0, y0, x1, y1), pixels of the 3D view with the origin at its bottom left
        (what a drag in rectangle mode gives): the model's
        :meth:`~ramure.app.model.Explorer.leaves_in_view`, as the desktop's rubber band."""
        if self.view.trame is None:
            self.message.show(NO_RECTANGLE, "error")
            return None
        matrix, size = self.view.trame.camera()
        mode = mode or self.selection_panel.mode.value
        found: list[int] = []

        def apply() -> None:
            found.extend(self.model.leaves_in_view(matrix, size, rect))
            self.model.select(found, mode)

        self.run(apply, note=lambda: f"rectangle: {len(found)} leaves ({mode}); {self.model.status()}")
        self.warm_up()
        return found

    def select_fruit_rectangle(self, rect: Sequence[float], mode: str = "replace") -> dict | None:
        """Select the region of the selected fruit whose skin, facing the camera, falls inside
        ``rect`` (pixels of the 3D view, origin bottom left, as :meth:`select_rectangle`); the
        Defects tab draws it (:meth:`~ramure.app.model.Explorer.select_fruit_region`)."""
        if self.view.trame is None:
            self.message.show(NO_RECTANGLE, "error")
            return None
        matrix, size = self.view.trame.camera()
        return self.defects.select_with(lambda model: model.select_fruit_region("rectangle", matrix, size, rect, mode=mode))

    def zoom_to_fruit(self, on: bool = True) -> tuple[float, ...] | None:
        """Frame the selected fruit (every fruit when none is selected) in the 3D view, or the
        whole plant again (``on=False``); returns the box framed (the desktop's View ▸ Zoom to fruit)."""
        bounds = self.run(self.model.fruit_bounds) if on else None
        if on and bounds is None:
            self.message.show("this plant has no fruit to zoom to", "note")
            return None
        self.view.zoom_to(bounds)
        return bounds

    def pick(self, cell_id: int, mode: str | None = None) -> None:
        """Select the leaf that drew mesh cell ``cell_id`` (what a click in the 3D view does)."""
        mode = mode or self.selection_panel.mode.value
        self.run(lambda: self.model.select([self.model.leaf_of_cell(cell_id)], mode))
        self.warm_up()

    # -- edits --------------------------------------------------------------------------
    def regrow(
        self, seed: int | None = None, constants: Mapping[str, float] | None = None, params: Mapping[str, float] | None = None
    ) -> RegenResult | None:
        """Regrow the selection's cut (the whole plant when nothing is selected)."""
        return self.run(lambda: self.model.regrow(seed=seed, constants=constants, params=params))

    def regrow_with_constants(self, constants: Mapping[str, float] | None = None) -> RegenResult | None:
        """Regrow the cut with new constant values, there only (default: the staged sliders)."""
        constants = self.grammar.staged() if constants is None else constants
        if not constants:
            self.message.show("move a constant slider first: its new value is used for the regrown part", "note")
            return None
        return self.regrow(constants=constants)

    def apply_pick(self, pick_id: int) -> RegenResult | None:
        """Regrow the cut with the parameters of variant pick ``pick_id`` (1-27)."""
        params = self.run(lambda: self.variants.pick_params(pick_id))
        if params is None:
            return None
        result = self.regrow(params=params)
        if result is not None:
            self.variants.mark_applied(self.variants.pick_point(pick_id))
            self.message.show(f"applied pick #{pick_id} {params} — {self.model.status()}", "info")
        return result

    def apply_qualifier(self, name: str) -> QualifierResult | None:
        """Regrow the cut toward qualifier ``name`` ("dense", "rond", …): candidates are tried
        until the selection's metrics move its way (:meth:`ramure.app.model.Explorer.apply_qualifier`);
        the message line says whether they did, e.g. "denser: density 1772 → 2172"."""
        if not str(name or "").strip():
            self.message.show("type or choose a qualifier first (e.g. taller, denser, plus touffu)", "note")
            return None
        result = self.run(lambda: self.variants.apply_qualifier(name))
        if result is not None:
            self.message.show(f"{qualifier_summary(result)} — {self.model.status()}", "info" if result.improved else "note")
        return result

    def regrow_fruit(self, seed: int | None = None, preset: str | None = None, size: float | None = None) -> RegenResult | None:
        """New volumetric fruit for the selected fruit: a new seed (or ``seed``), and optionally
        another ``preset`` (:data:`ramure.gmap.organs.fruit.PRESETS`, e.g. ``"pear"``) and ``size``."""

        def apply():
            settings: dict[str, Any] = {}
            if preset:
                settings["preset"] = str(preset)
            if size is not None:
                settings["size"] = _positive(size, "fruit size")
            return self.model.regrow_fruit(seed=seed, **settings)

        fruit = len(set(self.model.selection) & set(self.model.fruit_ids()))
        result = self.run(apply)
        if result is not None:
            kind = f" as {str(preset).replace('_', ' ')}" if preset else ""
            self.message.show(
                f"regrew {fruit} fruit{kind} (seed {self.history[-1]['settings']['seed']}); Undo brings the previous one back",
                "info",
            )
        return result

    def fruit_png(
        self, size: tuple[int, int] = (480, 480), view: str = "front", focus: int | None = None, fill: float = 0.9
    ) -> bytes | None:
        """PNG of the plant with its volumetric fruit (per-fruit edits applied; ``focus``: a
        fruit's leaf id to frame), or None when the plant has no fruit."""
        return fruit_png(self.model, size=size, view=view, focus=focus, fill=fill)

    def fruit_cut_png(self, leaf: int, size: tuple[int, int] = (420, 420)) -> bytes | None:
        """PNG of fruit ``leaf`` cut open across its axis, coloured by tissue (None without fruit)."""
        return fruit_cut_png(self.model, leaf, size=size)

    def prune(self) -> RegenResult | None:
        """Delete the selection's cut subtrees without regrowing them; None, with the reason in the message line,
        when nothing is selected.
        """
        return self.run(self.model.prune)

    def undo(self) -> dict | None:
        """Undo the last change; the message line says what was undone ("Undid: a2 = 45")."""
        return self.run(self.model.undo, note=lambda: self.model.history_note)

    def redo(self) -> dict | None:
        """Redo what Undo took back; the message line says what ("Redid: regrow of 3 leaves")."""
        return self.run(self.model.redo, note=lambda: self.model.history_note)

    # -- variants -----------------------------------------------------------------------
    def explore_variants(
        self, n: int | None = None, beta: float | None = None, n_jobs: int | None = None, wait: bool = True
    ) -> Exploration | threading.Thread | None:
        """Sweep the grammar's variants (progress bar; interrupt the kernel or press Stop)."""
        result = self.run(lambda: self.variants.explore(n, beta, n_jobs, wait=wait), note="exploring in the background…")
        if wait and result is not None and not isinstance(result, threading.Thread):
            self.message.show(
                f"{result.sweep.n_variants_} variants explored in {result.seconds:.1f} s: "
                "27 picks in the Variants tab, the cloud in PCA & qualifiers",
                "info",
            )
        return result

    def new_study(self, folder: str | os.PathLike, name: str | None = None, add: bool = False) -> NewStudy | None:
        """Make a study of the 27 picks in ``folder`` (:func:`ramure.app.new_study.new_study`; with
        ``add``, add them to the study there) and show the command that serves it; a refusal is
        shown on the panel and None returned."""
        return self.study_maker.create(folder, name, add)

    def load_qualifiers(self, store: str | os.PathLike, grammar: str | None = None) -> QualifierRegions | None:
        """Use qualifier regions from a study's qualifier store (SQLite path)."""
        return self.run(lambda: self.variants.load_regions(store, grammar))

    def load_words(self, path: str | os.PathLike) -> dict[str, dict[str, float]] | None:
        """Accept a study's words (a vocabulary file written by ``ramure study words``) as
        qualifiers, each with its measured direction; the qualifier box suggests them."""
        words = self.run(lambda: self.variants.load_words(path))
        if words is not None:
            self.message.show(f"{len(words)} study words accepted as qualifiers: {', '.join(sorted(words)[:8])}", "info")
        return words

    # -- view ----------------------------------------------------------------------------
    def set_view(self, view: str) -> None:
        """Camera side: ``iso``, ``front``, ``side`` or ``top``."""
        if view not in VIEWS:
            self.message.show(f"view must be one of {', '.join(VIEWS)}", "error")
            return
        if self.camera.value != view:
            self.camera.value = view  # the drop-down's observer comes back here
            return
        self.view.view = view
        self.refresh()

    def set_show_cut(self, on: bool) -> None:
        """Colour what a regrow would replace (the selection's cut) in orange."""
        if self.show_cut.value != bool(on):
            self.show_cut.value = bool(on)  # the check box's observer comes back here
            return
        self.view.show_cut = bool(on)
        self.refresh()

    def png(self) -> bytes:
        """The current picture of the plant (PNG bytes)."""
        return self.view.png()

    def snapshot(self) -> Image:
        """The current picture as an IPython image (stays in a saved notebook)."""
        from IPython.display import Image

        return Image(data=self.png(), format="png")

    # -- files -----------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> pathlib.Path | None:
        """Save by suffix: ``.json`` session, ``.lsys`` (``.lpy``) grammar, else the mesh (``.vtp``, ``.obj``, …)."""
        path = pathlib.Path(path)
        suffix = path.suffix.lower()
        if suffix == ".json":
            return self.run(lambda: self.model.save_session(path), note=f"session saved to {path}")
        if suffix in (".lsys", ".lpy"):
            return self.run(lambda: self.model.save_grammar(path), note=f"grammar saved to {path}")
        return self.run(lambda: self.model.export(path), note=f"mesh exported to {path}")

    def load_session(self, path: str | os.PathLike, run_code: bool = False) -> None:
        """Open a session file (the grammar and its local edits) as a fresh document; the message line
        follows the replay of its edits, and says why a file is refused.  A session of an L-Py
        model replays its Python code: only with ``run_code=True``.
        """

        def load() -> None:
            if not run_code and session_runs_code(path):
                raise CodeNotAllowed(path, how="pass run_code=True to load_session(...) if you would run it as a script")
            self.model.load_session(path, progress=self._replaying, run_code=True)

        self.run(load)

    def _replaying(self, done: int, total: int) -> None:
        if done == 1 or done == total or done % 50 == 0:  # a few updates, not one per edit
            self.message.show(f"replaying the session: edit {done} of {total}", "info")

    # -- display ---------------------------------------------------------------------------
    def _picture(self):
        """The explorer's static fallback: the plant's picture and a caption."""
        png = self.png()
        name = self.model.path.name if self.model.path else "grammar text"
        caption = (
            f"<div style='font-size:12px;color:#555'>Ramure explorer — {html.escape(name)}: "
            f"{html.escape(self.model.status())} (a picture; run the cell for the explorer)</div>"
        )
        return png_tag(png, self.view.size[0], name) + caption, png

    def _ipython_display_(self) -> None:
        """The widget, then a picture of the plant in its own output: what a notebook saved and
        reopened without a kernel shows (:class:`ramure.app.jupyter._ui.Fallback`)."""
        self._fallback_key = self.view.key()
        self.fallback._ipython_display_()

    def _repr_mimebundle_(self, **kwargs):
        """The widget, plus a PNG of the plant for viewers that cannot run widgets."""
        bundle = self.widget._repr_mimebundle_(**kwargs) or {}
        bundle = dict(bundle[0]) if isinstance(bundle, tuple) else dict(bundle)
        bundle["image/png"] = base64.b64encode(self.png()).decode("ascii")
        bundle["text/plain"] = f"<Ramure Explorer: {self.model.status()}>"
        return bundle


def _positive(value, name) -> float:
    number = _number(value, name)
    if number <= 0:
        raise ValueRefused(f"{name} must be a positive number, not {value!r}")
    return number
