"""The Architecture tab: browse a plant as axes, annual shoots, growth units and internodes.

The notebook counterpart of the desktop's Architecture dock (:mod:`ramure.lsys.architecture.amap`): a list
of the rows under the opened element, *Open* to go down, *Up* to go back, and *Select* to
select the row's internodes (an axis: itself and every axis it bears) with the selection
panel's mode, ready to regrow or prune.

>>> from ramure.app.jupyter import NotebookExplorer
>>> ex = NotebookExplorer("grammars/amap/massart.lsys", n=4, view="static")
>>> browser = ex.architecture
>>> [label for label, _ in browser.rows.options]
['Axis 1 (order 1) — 12 internodes']
>>> browser.open(("axis", 0)); browser.rows.options[0][0]
'Annual shoot 1 — 3 internodes'
>>> browser.select(("unit", 0)); len(ex.selection)
3
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.app.jupyter._ui import Breadcrumbs
from ramure.errors import RamureError
from ramure.lsys.architecture.amap import architecture

if TYPE_CHECKING:
    from ramure.lsys.architecture.amap import Architecture
    from ramure.app.jupyter.explorer import NotebookExplorer

HOW_TO = (
    "this grammar names no architecture: add lines such as <code>#amap internode F</code> and "
    "<code>#amap uc U</code> (see the grammar reference)"
)


class ArchitectureBrowser(Breadcrumbs):
    """Rows of the AMAP tables under an opened element; ``path`` is the list of opened ``(kind, row)``."""

    WHAT = "architecture"

    def __init__(self, app: NotebookExplorer) -> None:
        super().__init__(app, "show what this element is made of", "select this element's internodes")
        self.arch: Architecture | None = None
        self.refresh()

    # -- rows ------------------------------------------------------------------
    def children(self, tag: tuple[str, int] | None = None) -> list[tuple[str, tuple[str, int]]]:
        """``(label, (kind, row))`` pairs of the elements directly under ``tag`` (None = the plant)."""
        arch = self._built()
        inter = arch.internodes
        kind, row = tag or ("plant", -1)
        if kind in ("plant", "axis"):
            shoots = np.flatnonzero(arch.shoots.axis == row) if kind == "axis" else np.zeros(0, np.int64)
            rows = [
                (f"Annual shoot {k} — {self._size('shoot', s)} internodes", ("shoot", int(s)))
                for k, s in enumerate(shoots, start=1)
            ]
            axes = np.flatnonzero(arch.axes.parent == row)
            rows += [
                (f"Axis {a + 1} (order {int(arch.axes.order[a])}) — {self._size('axis', a)} internodes", ("axis", int(a)))
                for a in axes
            ]
            return rows
        if kind == "shoot":
            units = np.flatnonzero(arch.growth_units.shoot == row)
            return [
                (f"Growth unit {k} — {int(arch.growth_units.count[u])} internodes", ("unit", int(u)))
                for k, u in enumerate(units, start=1)
            ]
        if kind == "unit":
            return [(f"Internode {int(inter.node[i])}", ("internode", int(i))) for i in np.flatnonzero(inter.growth_unit == row)]
        return []

    def _size(self, kind, row):
        return (
            len(self.leaves_of((kind, row))) if kind == "shoot" else int(np.count_nonzero(self._built().internodes.axis == row))
        )

    def _built(self) -> Architecture:
        """The plant's architecture (the browser lists nothing before :meth:`refresh` built it)."""
        if self.arch is None:
            raise RamureError(HOW_TO)
        return self.arch

    def leaves_of(self, tag: tuple[str, int]) -> list[int]:
        """History-leaf ids of an element (an axis: itself and every axis it bears)."""
        kind, row = tag
        arch = self._built()
        inter = arch.internodes
        if kind == "axis":
            return arch.subtree_nodes(row).tolist()
        column = {"shoot": inter.shoot, "unit": inter.growth_unit}.get(kind)
        mask = column == row if column is not None else np.arange(len(inter)) == row
        return inter.node[mask].tolist()

    # -- actions ---------------------------------------------------------------
    def can_open(self, tag: tuple[str, int]) -> bool:
        """Whether the element ``tag`` = ``(kind, row)`` (an axis, a growth unit...) has parts."""
        return self.arch is not None and bool(self.children(tag))

    def open(self, tag: tuple[str, int]) -> None:
        """Go down into the element ``tag`` = ``(kind, row)`` when it has parts."""
        kind, row = tag
        super().open((kind, row))

    def _enable(self, on: bool) -> None:
        """The rows and buttons work only for a grammar that names its architecture (``#amap``)."""
        self.rows.disabled = not on
        for b in self.buttons:
            b.disabled = not on

    def fill(self) -> None:
        """Show the opened elements as the breadcrumb, with the plant's counts, and list the parts of the last."""
        if self.arch is None:
            self.rows.options = []
            return
        counts = self.arch.counts()
        where = " ▸ ".join(f"{kind} {row + 1}" for kind, row in self.path) or "plant"
        self.crumbs.value = (
            f"<b>Architecture</b>: {where} <small>({counts['axes']} axes, "
            f"{counts['growth_units']} growth units, {counts['internodes']} internodes)</small>"
        )
        options = self.children(self.path[-1] if self.path else None)
        self.rows.options = options
        self.rows.value = None

    def refresh(self) -> None:
        """Follow the model after a change of plant: recompute the architecture, keep the opened axis while it
        still exists, and disable the browser (saying why) when the grammar has no ``#amap``
        annotations.
        """
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
            self._enable(False)
            return
        self._enable(True)
        self.path = [(k, r) for k, r in self.path if (k == "axis" and r < len(self.arch.axes))][:1]
        self.fill()
