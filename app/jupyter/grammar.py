"""The grammar side of the explorer: text area with inline errors, n and seed, constant sliders.

A slider per ``#define`` constant spans 0 to twice its value.  With *live* on,
releasing a slider re-derives the whole plant (one undoable edit); otherwise
the sliders only stage values for *Apply constants* (whole plant) or *Regrow
with constants* (the selection's cut only).

>>> slider_range(60.0), slider_range(0.0), slider_range(-2.0)
((0.0, 120.0), (-1.0, 1.0), (-4.0, 0.0))
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import ipywidgets as W

from ramure.app.jupyter._ui import button, message_html, observe, on_value

if TYPE_CHECKING:
    from ramure.app.jupyter.explorer import NotebookExplorer


def slider_range(value: float) -> tuple[float, float]:
    """(min, max) of a constant's slider: 0..2·value (sign kept), -1..1 for zero."""
    value = float(value)
    if value == 0:
        return (-1.0, 1.0)
    return (min(0.0, 2 * value), max(0.0, 2 * value))


def constant_slider(name: str, value: float) -> W.FloatSlider:
    """A slider for the constant ``name`` over :func:`slider_range` of ``value`` in 400 steps,
    which sends its value when released."""
    lo, hi = slider_range(value)
    return W.FloatSlider(
        value=float(value),
        min=lo,
        max=hi,
        step=(hi - lo) / 400,
        description=name,
        continuous_update=False,
        readout_format=".4g",
        style={"description_width": "50px"},
        layout=W.Layout(width="98%"),
    )


class GrammarPanel:
    """Text area, parse error (line/column with a caret), n, seed and constant sliders."""

    def __init__(self, app: NotebookExplorer, text: str | None = None) -> None:
        self.app = app
        model = app.model
        self.text = W.Textarea(
            value=model.document_text() if text is None else text, rows=14, continuous_update=False, layout=W.Layout(width="98%")
        )
        self.text.add_class("ramure-grammar")
        self.error = W.HTML()
        self.apply_text = button(
            "Parse & derive",
            lambda: app.set_text(self.text.value),
            "re-read the grammar text (also done when the text area loses focus)",
        )
        self._quiet = False
        observe(self.text, lambda change: None if self._quiet else app.set_text(change["new"]))
        self.n = W.BoundedIntText(
            value=model.session.n,
            min=0,
            max=30,
            description="n",
            style={"description_width": "20px"},
            layout=W.Layout(width="110px"),
        )
        self.seed = W.IntText(
            value=model.session.seed, description="seed", style={"description_width": "35px"}, layout=W.Layout(width="140px")
        )
        on_value(self.n, lambda v: app.set_derivation(n=v))
        on_value(self.seed, lambda v: app.set_derivation(seed=v))
        self.live = W.Checkbox(
            value=False,
            description="live: re-derive on slider release",
            indent=False,
            tooltip="re-derive the whole plant when a slider is released (one undoable edit)",
            style={"description_width": "initial"},
            layout=W.Layout(width="auto"),
        )
        self.sliders: dict[str, W.FloatSlider] = {}
        self.slider_box = W.VBox()
        self.apply_constants = button(
            "Apply constants", app.apply_constants, "set the staged slider values on the whole plant (undoable)"
        )
        self.reset = button("Reset sliders", self.reset_sliders, "back to the plant's current constants")
        self._synced = None
        self.widget = W.VBox(
            [
                W.HTML("<style>.ramure-grammar textarea{font-family:monospace;font-size:12px}</style><b>Grammar</b>"),
                self.text,
                self.error,
                self.apply_text,
                W.HBox([self.n, self.seed]),
                W.HTML("<b>Constants</b> (<code>#define</code>)"),
                self.slider_box,
                self.live,
                W.HBox([self.apply_constants, self.reset]),
            ],
            layout=W.Layout(width="100%"),
        )
        self.refresh()

    def show_text(self, text: str) -> None:
        """Show ``text`` in the text area without parsing it again."""
        self._quiet = True
        try:
            self.text.value = text
        finally:
            self._quiet = False

    # -- constants ---------------------------------------------------------
    def _build_sliders(self, constants) -> None:
        self.sliders = {}
        for name, value in constants.items():
            s = constant_slider(name, value)
            observe(s, lambda change, name=name: self._slider_moved(name, change["new"]))
            self.sliders[name] = s
        self.slider_box.children = list(self.sliders.values()) or [W.HTML("<i>no #define constants</i>")]

    def _slider_moved(self, name, value) -> None:
        if self.live.value and not self._syncing:
            self.app.set_constant(name, value)

    _syncing = False

    def reset_sliders(self) -> None:
        """Put every slider back to the plant's current value."""
        self._syncing = True
        try:
            for name, value in self.app.model.constants.items():
                if name in self.sliders:
                    s = self.sliders[name]
                    lo, hi = slider_range(value)
                    s.min, s.max = min(s.min, lo), max(s.max, hi)
                    s.value = float(value)
        finally:
            self._syncing = False
        self._synced = self.app.model.constants

    def staged(self) -> dict:
        """Slider values that differ from the plant's current constants."""
        current = self.app.model.constants
        return {
            name: s.value
            for name, s in self.sliders.items()
            if name in current and not math.isclose(s.value, current[name], rel_tol=1e-9, abs_tol=1e-12)
        }

    # -- refresh -----------------------------------------------------------
    def refresh(self) -> None:
        """Follow the model: its grammar error, its text (after a session load or a gallery pick), ``n``, seed
        and the constants' sliders.
        """
        model = self.app.model
        err = model.error
        self.error.value = message_html(err) if err is not None else ""
        shown = model.document_text()  # the text with the plant's n, seed and constants: what Save writes
        if err is None and self.text.value != shown:
            self.show_text(shown)  # e.g. after loading a session, a gallery pick
        for w, v in ((self.n, model.session.n), (self.seed, model.session.seed)):
            if w.value != v:
                w.value = v
        constants = model.constants
        if set(constants) != set(self.sliders):
            self._build_sliders(constants)
            self._synced = constants
        elif constants != self._synced:  # the plant's constants changed (edit, undo): follow them
            self.reset_sliders()
