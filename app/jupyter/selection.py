"""Selection tools: leaf ids, an order/height filter, and a derivation-tree browser.

Every tool goes through the explorer's ``select`` (with the mode chosen on the
panel: replace, add, remove or toggle), so clicks, filters and code all end
in :meth:`ramure.app.model.Explorer.select`.

>>> from ramure.app.model import Explorer
>>> m = Explorer("grammars/honda_sympodial.lsys", n=3)
>>> node_label(m, int(m.derivation.tree.leaves[1]))
'F(1) · leaf'
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import ipywidgets as W
import numpy as np

from ramure.app.ids import id_example, resolve_ids
from ramure.app.jupyter._ui import Breadcrumbs, button, observe, short_list
from ramure.app.model import SELECT_MODES

if TYPE_CHECKING:
    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.app.model import Explorer as Model

MAX_ROWS = 400  # children listed at once in the tree browser


class SelectionPanel:
    """Selection mode, leaf ids, the order/height filter, clear, and the selection summary."""

    def __init__(self, app: NotebookExplorer) -> None:
        self.app = app
        self.mode = W.ToggleButtons(
            options=SELECT_MODES,
            value="replace",
            style={"button_width": "auto"},
            tooltips=["replace the selection", "add to it", "remove from it", "toggle each leaf"],
        )
        self.ids = W.Text(placeholder="leaf ids", layout=W.Layout(width="170px"))
        self.min_order = W.BoundedIntText(
            value=0, min=0, max=99, description="order ≥", style={"description_width": "55px"}, layout=W.Layout(width="120px")
        )
        self.height = W.FloatRangeSlider(
            value=(0.0, 1.0),
            min=0.0,
            max=1.0,
            step=0.01,
            description="height",
            readout_format=".3g",
            continuous_update=False,
            style={"description_width": "55px"},
            layout=W.Layout(width="98%"),
        )
        self.summary = W.HTML()
        self._bounds: tuple[float, float] | None = None
        self.widget = W.VBox(
            [
                W.HTML("<b>Selection</b>"),
                self.mode,
                W.HBox([self.ids, button("Select ids", self.select_ids)]),
                W.HBox(
                    [
                        self.min_order,
                        button(
                            "Select where", self.select_where, "leaves of branches of at least this order within the height range"
                        ),
                    ]
                ),
                self.height,
                W.HBox([button("Clear", app.clear_selection)]),
                self.summary,
            ]
        )
        self.refresh()

    def select_ids(self) -> None:
        """Select the ids typed in the box (numbers and ranges, as ``ramure regen --select`` takes them) in the
        panel's mode.
        """
        model = self.app.model
        self.app.run(lambda: model.select(resolve_ids(self.ids.value, model.derivation.tree.leaves), self.mode.value))
        self.app.warm_up()

    def select_where(self) -> None:
        """Select by the branch-order and height filters (a height range covering the whole plant filters
        nothing) in the panel's mode.
        """
        lo, hi = self.height.value
        full = lo <= self.height.min and hi >= self.height.max
        self.app.select_where(
            min_order=self.min_order.value or None,
            min_height=None if full else lo,
            max_height=None if full else hi,
            mode=self.mode.value,
        )

    def refresh(self) -> None:
        """Follow the model: fit the height slider and the branch-order box to the plant's extent."""
        model = self.app.model
        sk = model.skeleton
        if len(sk):
            z = np.concatenate([sk.start[:, 2], sk.end[:, 2]])
            bounds = (float(z.min()), float(z.max()))
        else:
            bounds = (0.0, 1.0)
        if bounds != self._bounds:
            lo, hi = bounds[0], max(bounds[1], bounds[0] + 1e-6)
            self.height.min, self.height.max = -1e30, 1e30  # avoid clipping while both ends move
            self.height.value = (lo, hi)
            self.height.min, self.height.max = lo, hi
            self.height.step = (hi - lo) / 200
            self.min_order.max = max(int(sk.order.max()) if len(sk) else 0, 0)
            self._bounds = bounds
        # leaves of this plant (those that draw, if any), so typing the example selects
        example = id_example(sk.leaf_id) or id_example(model.derivation.tree.leaves)
        placeholder = f"leaf ids, e.g. {example}" if example else "leaf ids"
        if self.ids.placeholder != placeholder:
            self.ids.placeholder = placeholder
        sel = model.selection
        self.summary.value = (
            f"{len(sel)} selected: {short_list(sel)}" if sel else "<i>nothing selected: edits apply to the whole plant</i>"
        )


def node_label(model: Model, node: int) -> str:
    """``"B(0.9,7.07) · 31 leaves, step 2"`` (or ``"F(1) · leaf"``) for a history node."""
    tree = model.derivation.tree
    text = model.lsystem.module_text(tree, node)
    count = int(tree.leaf_counts()[node])
    if tree.is_leaf(node):
        return f"{text} · leaf"
    return f"{text} · {count} leaves, step {int(tree.step[node])}"


class TreeBrowser(Breadcrumbs):
    """Browse the derivation history from the axiom down; select a leaf or all leaves under a node.

    ``path`` holds the opened nodes (empty = the axiom's modules).  Choose a row,
    then *Open* to go down, *Up* to go back, *Select* to select the row's leaves
    with the panel's mode.
    """

    WHAT = "derivation tree"

    def __init__(self, app: NotebookExplorer) -> None:
        self.info = W.HTML()
        super().__init__(app, "show this node's children", "select this leaf, or every leaf under this node", [self.info])
        observe(self.rows, lambda ch: self._describe())
        self.refresh()

    def children(self) -> np.ndarray:
        """The derivation-tree nodes listed now: the children of the node last opened, or the axiom's modules at
        the top.
        """
        tree = self.app.model.derivation.tree
        if self.path:
            return tree.children(self.path[-1])
        return np.flatnonzero((tree.parent == -1) & tree.alive)

    def children_with(self, symbol: str) -> list[int]:
        """The listed nodes whose module symbol is ``symbol`` (e.g. ``"B"``)."""
        model = self.app.model
        kids = self.children()
        symbols = np.asarray(model.lsystem.symbols, dtype=object)[model.derivation.tree.symbol[kids]]
        return kids[symbols == symbol].tolist()

    def can_open(self, node: int) -> bool:
        """Whether ``node`` has children; a leaf has none, and the line under the list says so."""
        if self.app.model.derivation.tree.is_leaf(node):
            self.info.value = "<i>a leaf has no children: use Select</i>"
            return False
        return True

    def open(self, node: int) -> None:
        """Show ``node``'s children (a leaf has none: nothing happens)."""
        super().open(int(node))

    def leaves_of(self, node: int) -> list[int]:
        """The leaves under ``node`` (the node itself if it is a leaf)."""
        return self.app.model.derivation.tree.leaves_under(int(node)).tolist()

    def _describe(self) -> None:
        node = self.rows.value
        if node is None:
            self.info.value = ""
            return
        tree = self.app.model.derivation.tree
        self.info.value = (
            f"node {node}: {node_label(self.app.model, node)}, rule {int(tree.rule[node])}, depth {int(tree.depth[node])}"
        )

    def fill(self) -> None:
        """Show the opened nodes' modules as the breadcrumb and list the children of the last (at most
        :data:`MAX_ROWS`)."""
        model = self.app.model
        names = [model.lsystem.module_text(model.derivation.tree, n) for n in self.path]
        self.crumbs.value = "<b>Derivation tree</b>: " + (" ▸ ".join(names) if names else "axiom")
        kids = self.children()
        options: list[tuple[str, int | None]] = [(f"{int(n)}: {node_label(model, int(n))}", int(n)) for n in kids[:MAX_ROWS]]
        if len(kids) > MAX_ROWS:
            options.append((f"… {len(kids) - MAX_ROWS} more not listed", None))
        self.rows.options = options
        self.rows.value = None

    def refresh(self) -> None:
        """Follow the model after a change of plant: keep the opened path as far as its nodes are still alive and
        inner, and list the children again.
        """
        model = self.app.model
        if model.version == self._version:
            return
        self._version = model.version
        tree = model.derivation.tree
        # keep the opened path as far as it is still alive
        keep: list[int] = []
        for n in self.path:
            if n < tree.size and tree.alive[n] and not tree.is_leaf(n) and (not keep or tree.parent[n] == keep[-1]):
                keep.append(n)
            else:
                break
        self.path = keep
        self.fill()
