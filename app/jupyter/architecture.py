"""The Architecture tab: browse a plant as axes, annual shoots, growth units and internodes.

The notebook counterpart of the desktop's Architecture dock (:mod:`ramure.lsys.amap`): a list
of the rows under the opened element, *Open* to go down, *Up* to go back, and *Select* to
select the row's internodes (an axis: itself and every axis it bears) with the selection
panel's mode, ready to regrow or prune.

>>> from ramure.app.jupyter import Explorer
>>> ex = Explorer("grammars/amap/massart.lsys", n=4, view="static")
>>> browser = ex.architecture
>>> [label for label, _ in browser.rows.options]
['Axis 1 (order 1) — 12 internodes']
>>> browser.open(("axis", 0)); browser.rows.options[0][0]
'Annual shoot 1 — 3 internodes'
>>> browser.select(("unit", 0)); len(ex.selection)
3
"""
from __future__ import annotations

import ipywidgets as W
import numpy as np

from ramure.app.jupyter._ui import button
from ramure.errors import RamureError
from ramure.lsys.amap import architecture

HOW_TO = ("this grammar names no architecture: add lines such as <code>#amap internode F</code> and "
          "<code>#amap uc U</code> (see the grammar reference)")


class ArchitectureBrowser:
    """Rows of the AMAP tables under an opened element; ``path`` is the list of opened ``(kind, row)``."""

    def __init__(self, app):
        self.app = app
        self.arch = None
        self.path = []
        self.crumbs = W.HTML()
        self.rows = W.Select(options=[], rows=12, layout=W.Layout(width="98%"))
        self.widget = W.VBox([
            self.crumbs, self.rows,
            W.HBox([button("Open ▸", self.open_selected, "show what this element is made of"),
                    button("◂ Up", self.up), button("Top", self.top),
                    button("Select", self.select_selected, "select this element's internodes", style="info")]),
        ])
        self._version = None
        self.refresh()

    # -- rows ------------------------------------------------------------------
    def children(self, tag=None) -> list:
        """``(label, (kind, row))`` pairs of the elements directly under ``tag`` (None = the plant)."""
        arch, inter = self.arch, self.arch.internodes
        kind, row = tag or ("plant", -1)
        if kind in ("plant", "axis"):
            shoots = np.flatnonzero(arch.shoots.axis == row) if kind == "axis" else []
            rows = [(f"Annual shoot {k} — {self._size('shoot', s)} internodes", ("shoot", int(s)))
                    for k, s in enumerate(shoots, start=1)]
            axes = np.flatnonzero(arch.axes.parent == row)
            rows += [(f"Axis {a + 1} (order {int(arch.axes.order[a])}) — {self._size('axis', a)} internodes",
                      ("axis", int(a))) for a in axes]
            return rows
        if kind == "shoot":
            units = np.flatnonzero(arch.growth_units.shoot == row)
            return [(f"Growth unit {k} — {int(arch.growth_units.count[u])} internodes", ("unit", int(u)))
                    for k, u in enumerate(units, start=1)]
        if kind == "unit":
            return [(f"Internode {int(inter.node[i])}", ("internode", int(i)))
                    for i in np.flatnonzero(inter.growth_unit == row)]
        return []

    def _size(self, kind, row):
        return len(self.leaves_of((kind, row))) if kind == "shoot" else int(np.count_nonzero(
            self.arch.internodes.axis == row))

    def leaves_of(self, tag) -> list[int]:
        """History-leaf ids of an element (an axis: itself and every axis it bears)."""
        kind, row = tag
        inter = self.arch.internodes
        if kind == "axis":
            return self.arch.subtree_nodes(row).tolist()
        column = {"shoot": inter.shoot, "unit": inter.growth_unit}.get(kind)
        mask = column == row if column is not None else np.arange(len(inter)) == row
        return inter.node[mask].tolist()

    # -- actions ---------------------------------------------------------------
    def open(self, tag):
        if self.arch is not None and self.children(tag):
            self.path.append(tuple(tag))
            self._fill()

    def open_selected(self):
        if self.rows.value:
            self.open(self.rows.value)

    def up(self):
        if self.path:
            self.path.pop()
            self._fill()

    def top(self):
        self.path = []
        self._fill()

    def select(self, tag):
        self.app.select(self.leaves_of(tag), self.app.selection_panel.mode.value)

    def select_selected(self):
        if not self.rows.value:
            self.app.message.show("choose a row in the architecture first", "note")
            return
        self.select(self.rows.value)

    def _fill(self):
        if self.arch is None:
            self.rows.options = []
            return
        counts = self.arch.counts()
        where = " ▸ ".join(f"{kind} {row + 1}" for kind, row in self.path) or "plant"
        self.crumbs.value = (f"<b>Architecture</b>: {where} <small>({counts['axes']} axes, "
                             f"{counts['growth_units']} growth units, {counts['internodes']} internodes)</small>")
        options = self.children(self.path[-1] if self.path else None)
        self.rows.options = options
        self.rows.value = None

    def refresh(self):
        model = self.app.model
        if model.version == self._version:
            return
        self._version = model.version
        try:
            self.arch = architecture(model.derivation)
        except RamureError:
            self.arch, self.path = None, []
            self.crumbs.value = f"<b>Architecture</b>: {HOW_TO}"
            self.rows.options = []
            return
        self.path = [(k, r) for k, r in self.path if (k == "axis" and r < len(self.arch.axes))][:1]
        self._fill()
