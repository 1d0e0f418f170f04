"""The Architecture dock: the plant as axes, annual shoots, growth units and internodes.

For a grammar with ``#amap`` annotations (see :mod:`ramure.lsys.architecture.amap`), the dock shows a tree
Plant → Axis (order, bearer) → Annual shoot → Growth unit → Internode. Clicking a row selects
its internodes in the 3D view (an axis selects itself and every axis it bears), ready to be
regrown or pruned like any selection. A grammar without annotations says how to add them.
The tables are rebuilt after every new plant, in the GUI thread under the model lock (they
cost milliseconds: numpy over the string).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QHeaderView, QLabel, QTreeWidget, QTreeWidgetItem, QWidget

from ramure.app.desktop.panels.common import dock_column
from ramure.errors import RamureError
from ramure.lsys.architecture.amap import Architecture, architecture

if TYPE_CHECKING:
    from ramure.app.desktop.controller import Controller

LEAF_ROLE = Qt.ItemDataRole.UserRole
MAX_INTERNODE_ROWS = 20_000  # beyond this, growth units are listed without their internodes


class ArchitecturePanel(QWidget):
    """Tree of the architecture tables; a click selects the row's internodes."""

    def __init__(self, controller: Controller, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.arch: Architecture | None = None
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self.tree = QTreeWidget()
        self.tree.setObjectName("architectureTree")
        self.tree.setHeaderLabels(["element", "internodes"])
        header = self.tree.header()
        header.setStretchLastSection(False)
        header.setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        header.setSectionResizeMode(1, QHeaderView.ResizeMode.ResizeToContents)
        self.tree.itemClicked.connect(self._select_item)
        dock_column(self, self.summary).addWidget(self.tree, 1)
        controller.plant_changed.connect(lambda _snap: self.rebuild())
        self.rebuild()

    def rebuild(self) -> None:
        """Recompute the tables from the model's current plant and refill the tree."""
        try:
            self.arch = self.controller.read(lambda ex: architecture(ex.derivation), wait=2.0)
        except RamureError as err:
            self.arch = None
            self.tree.clear()
            self.summary.setText(
                f"No architecture: {err}. Name the roles in the grammar, e.g. "
                "'#amap internode F' and '#amap uc U' (see the grammar reference)."
            )
            return
        self._fill(self.arch)

    def _fill(self, arch: Architecture) -> None:
        counts = arch.counts()
        orders = ", ".join(f"order {o}: {c}" for o, c in arch.axes_per_order().items())
        self.summary.setText(
            f"{counts['axes']} axes ({orders}), {counts['annual_shoots']} annual shoots, "
            f"{counts['growth_units']} growth units, {counts['internodes']} internodes"
        )
        self.tree.clear()
        plant = QTreeWidgetItem(["Plant", str(counts["internodes"])])
        plant.setData(0, LEAF_ROLE, ("plant", 0))
        self.tree.addTopLevelItem(plant)
        items: dict[int, QTreeWidgetItem] = {}
        with_internodes = counts["internodes"] <= MAX_INTERNODE_ROWS
        for a in range(len(arch.axes)):
            parent = items.get(int(arch.axes.parent[a]), plant)
            n = int(np.count_nonzero(arch.internodes.axis == a))
            item = QTreeWidgetItem([f"Axis {a + 1} (order {int(arch.axes.order[a])})", str(n)])
            item.setData(0, LEAF_ROLE, ("axis", a))
            parent.addChild(item)
            items[a] = item
            self._fill_axis(arch, a, item, with_internodes)
        plant.setExpanded(True)

    def _fill_axis(self, arch, axis, item, with_internodes) -> None:
        shoots = np.flatnonzero(arch.shoots.axis == axis)
        for k, s in enumerate(shoots.tolist(), start=1):
            shoot = QTreeWidgetItem([f"Annual shoot {k}", ""])
            shoot.setData(0, LEAF_ROLE, ("shoot", s))
            item.addChild(shoot)
            units = np.flatnonzero(arch.growth_units.shoot == s)
            total = 0
            for j, u in enumerate(units.tolist(), start=1):
                count = int(arch.growth_units.count[u])
                total += count
                unit = QTreeWidgetItem([f"Growth unit {j}", str(count)])
                unit.setData(0, LEAF_ROLE, ("unit", u))
                shoot.addChild(unit)
                if with_internodes:
                    for row in np.flatnonzero(arch.internodes.growth_unit == u).tolist():
                        leaf = QTreeWidgetItem([f"Internode {int(arch.internodes.node[row])}", "1"])
                        leaf.setData(0, LEAF_ROLE, ("internode", row))
                        unit.addChild(leaf)
            shoot.setText(1, str(total))

    def leaves_of(self, kind: str, row: int) -> list[int]:
        """History-leaf ids a row stands for (an axis: itself and every axis it bears)."""
        arch = self.arch
        if arch is None:  # the grammar names no architecture: no rows
            return []
        inter = arch.internodes
        if kind == "plant":
            mask = np.ones(len(inter), bool)
        elif kind == "axis":
            return arch.subtree_nodes(row).tolist()
        elif kind == "shoot":
            mask = inter.shoot == row
        elif kind == "unit":
            mask = inter.growth_unit == row
        else:
            mask = np.arange(len(inter)) == row
        return inter.node[mask].tolist()

    def _select_item(self, item, _column=0) -> None:
        tag = item.data(0, LEAF_ROLE)
        if self.arch is None or tag is None:
            return
        try:
            self.controller.select(self.leaves_of(*tag))
        except RamureError as err:
            self.summary.setText(str(err))
