"""Botanical architecture (AMAP): axes, annual shoots, growth units and internodes of a derivation.

Botanists describe a tree as **axes** made of **annual shoots** made of **growth units** made
of **internodes** (Blaise 2004, Figs 46-47; spec ``natural-details-and-amap.md`` B.4). A
grammar names which of its modules play these roles with ``#amap`` directives::

    #amap internode F       modules that are internodes (they carry the geometry)
    #amap uc U              a module that starts a new growth unit on its axis
    #amap shoot Y           a module that starts a new annual shoot (and a new growth unit)
    #amap axis [            modules that open a new axis (default: '[')
    #amap death D           a module that marks a dead bud (an event, no structure)
    #amap reiteration R     a module that marks a reiteration (an event, no structure)

Organs (``Leaf``, ``Fruit``, ``#organ`` modules) count as organ events.

:func:`architecture` reads the current string of a derivation, all at once with numpy, into
an :class:`Architecture`: tables of internodes, growth units, annual shoots and axes with
their **father** links (containment: internode → growth unit → annual shoot → axis) and
**bearer** links (an axis is borne by an internode of its parent axis).

Choices the sources leave open, made here:

* Structure is built from the current string: an axis is the span of one axis-opening
  module up to its matching ``]``; growth units and annual shoots are runs of internodes of
  one axis between markers. Empty units (no internode) are not listed, and an axis with no
  internode of its own is not an axis (a bud, an organ in brackets): its sub-axes hang on the
  nearest listed ancestor.
* The first internode of every axis opens a growth unit and an annual shoot.
* The bearer of an axis is the last internode of its parent axis before the axis opens; an
  axis opened before any internode of its parent is borne by the nearest ancestor axis that
  has an internode before it (and that axis is its parent), so a parent always contains the
  bearer. An axis with no such ancestor is a root axis like the trunk (order 1, no bearer).
* Events are counted from the derivation history: every module a production created
  (step >= 1) with an ``#amap``/organ role is one event of that kind. A new growth unit is a
  ``uc`` marker (an annual-shoot marker only where the grammar has no ``uc`` role, so a unit
  that opens a shoot is not counted twice); branching counts axis-opening modules.

>>> import ramure
>>> text = '''#amap internode F
... #amap uc U
... n: 3
... w: A
... p:
...   A -> U F F [ B ] F A
...   B -> U F F
... '''
>>> arch = architecture(ramure.LSystem.from_text(text).derive())
>>> arch.counts()["axes"], arch.counts()["growth_units"], arch.counts()["internodes"]
(3, 5, 13)
>>> arch.axes.order.tolist()
[1, 2, 2]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ramure.errors import GrammarError, ValueRefused
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..engine.derive import Derivation
    from ..language.grammar import Grammar

ROLES = {
    "internode": "modules that are internodes",
    "uc": "a module that starts a new growth unit",
    "shoot": "a module that starts a new annual shoot",
    "axis": "modules that open an axis (default '[')",
    "death": "a module that marks a dead bud",
    "reiteration": "a module that marks a reiteration",
}
ALIASES = {"gu": "uc", "growth_unit": "uc", "annual_shoot": "shoot", "internodes": "internode"}
EVENT_KINDS = ("growth_unit", "internode", "branching", "organ", "reiteration", "death")


def check_annotations(grammar: Grammar) -> None:
    """Refuse an unknown ``#amap`` role or a module the grammar never writes (line, column, caret)."""
    known = _written_symbols(grammar)
    for role, symbol, line, column, source, role_column in grammar.amap:
        if ALIASES.get(role, role) not in ROLES:
            raise GrammarError(
                f"unknown #amap role '{role}' (known: {', '.join(ROLES)})", line, role_column, source, filename=grammar.filename
            )
        if symbol not in known:
            raise GrammarError(
                f"#amap {role}: the grammar never writes a module '{symbol}'", line, column, source, filename=grammar.filename
            )


def _written_symbols(grammar):
    symbols = {m.symbol for m in grammar.axiom} | {"[", "]"}
    for rule in grammar.rules:
        symbols.add(rule.pred.symbol)
        symbols.update(m.symbol for m in rule.successor)
    return symbols


def roles(grammar: Grammar) -> dict:
    """``{role: set of symbols}`` from the grammar's ``#amap`` lines (``axis`` defaults to ``[``)."""
    out: dict[str, set[str]] = {role: set() for role in ROLES}
    for role, symbol, *_ in grammar.amap:
        out[ALIASES.get(role, role)].add(symbol)
    if not out["axis"]:
        out["axis"] = {"["}
    return out


@dataclass
class Table:
    """Columns of equal length (numpy arrays), one row per element."""

    columns: dict = field(default_factory=dict)

    def __getattr__(self, name):
        try:
            return self.__dict__["columns"][name]
        except KeyError:
            raise AttributeError(name) from None

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def equals(self, other: Table) -> bool:
        return self.columns.keys() == other.columns.keys() and all(
            np.array_equal(self.columns[k], other.columns[k]) for k in self.columns
        )


@dataclass
class Architecture:
    """The AMAP tables of one plant.

    ``internodes``: ``node`` (history-tree node id), ``axis``, ``growth_unit``, ``shoot``,
    ``rank`` (0-based place in its growth unit);
    ``growth_units``: ``axis``, ``shoot``, ``first`` (internode row), ``count``;
    ``shoots``: ``axis``, ``first`` (growth-unit row), ``count``;
    ``axes``: ``parent`` (bearer axis, -1 for the trunk), ``bearer`` (bearer internode row,
    -1 for the trunk), ``order`` (1 for the trunk), ``first`` (internode row).
    Rows are in string order; every index refers to a row of another table.
    ``events``: counts per kind of :data:`EVENT_KINDS`.
    """

    internodes: Table
    growth_units: Table
    shoots: Table
    axes: Table
    events: dict

    def counts(self) -> dict:
        return {
            "axes": len(self.axes),
            "annual_shoots": len(self.shoots),
            "growth_units": len(self.growth_units),
            "internodes": len(self.internodes),
        }

    def axes_per_order(self) -> dict:
        orders, counts = np.unique(self.axes.order, return_counts=True)
        return {int(o): int(c) for o, c in zip(orders, counts)}

    def internodes_per_growth_unit(self) -> dict:
        """Histogram: ``{k: number of growth units with k internodes}``."""
        sizes, counts = np.unique(self.growth_units.count, return_counts=True)
        return {int(s): int(c) for s, c in zip(sizes, counts)}

    def subtree_axes(self, axis: int) -> np.ndarray:
        """``axis`` and every axis borne on it, directly or not (sorted rows)."""
        keep = np.zeros(len(self.axes), bool)
        keep[axis] = True
        for a in range(axis + 1, len(self.axes)):  # parents come before children (string order)
            parent = self.axes.parent[a]
            keep[a] = parent >= 0 and keep[parent]
        return np.flatnonzero(keep)

    def subtree_nodes(self, axis: int) -> np.ndarray:
        """History-tree node ids of the internodes of ``axis`` and every axis borne on it."""
        return self.internodes.node[np.isin(self.internodes.axis, self.subtree_axes(axis))]

    def prune(self, axis: int) -> Architecture:
        """The tables without ``axis`` and every axis borne on it (rows renumbered, links kept)."""
        if axis == 0:
            raise ValueRefused("the trunk cannot be pruned from the tables; prune its branches")
        gone_axes = np.zeros(len(self.axes), bool)
        gone_axes[self.subtree_axes(axis)] = True
        keep = {
            "axes": ~gone_axes,
            "internodes": ~gone_axes[self.internodes.axis],
            "growth_units": ~gone_axes[self.growth_units.axis],
            "shoots": ~gone_axes[self.shoots.axis],
        }
        new_row = {name: np.cumsum(mask) - 1 for name, mask in keep.items()}
        links = {"axis": "axes", "parent": "axes", "bearer": "internodes", "growth_unit": "growth_units", "shoot": "shoots"}
        firsts = {"internodes": None, "growth_units": "internodes", "shoots": "growth_units", "axes": "internodes"}
        tables = {}
        for name, mask in keep.items():
            columns = {}
            for col, values in getattr(self, name).columns.items():
                values = values[mask]
                target = links.get(col) or (firsts[name] if col == "first" else None)
                if target is not None:
                    values = np.where(values >= 0, new_row[target][np.maximum(values, 0)], -1)
                columns[col] = values
            tables[name] = Table(columns)
        return Architecture(tables["internodes"], tables["growth_units"], tables["shoots"], tables["axes"], dict(self.events))

    def equals(self, other: Architecture) -> bool:
        return (
            all(getattr(self, t).equals(getattr(other, t)) for t in ("internodes", "growth_units", "shoots", "axes"))
            and self.events == other.events
        )

    def to_dict(self) -> dict:
        return {
            **self.counts(),
            "axes_per_order": self.axes_per_order(),
            "events": dict(self.events),
            "internodes_per_growth_unit": self.internodes_per_growth_unit(),
        }


def architecture(derivation: Derivation) -> Architecture:
    """The :class:`Architecture` of a derivation's current string (see the module docstring)."""
    lsystem, tree = derivation.lsystem, derivation.tree
    role_sets = roles(lsystem.grammar)
    if not role_sets["internode"]:
        raise ValueRefused("the grammar names no internode: add a line such as '#amap internode F'")
    ids = {name: i for i, name in enumerate(lsystem.symbols)}

    def member(role):
        wanted = [ids[s] for s in role_sets[role] if s in ids]
        return np.isin(symbols, np.asarray(wanted, symbols.dtype))

    nodes = tree.leaves
    symbols = tree.symbol[nodes]
    opens = member("axis")
    closes = symbols == ids["]"] if "]" in ids else np.zeros(len(symbols), bool)
    axis_of, parent_of_open = _axis_spans(opens, closes)
    table = _tables(nodes, axis_of, parent_of_open, member("internode"), member("uc"), member("shoot"))
    table.events = _events(tree, lsystem, role_sets, ids)
    return table


def _axis_spans(opens, closes):
    """Axis of every position (0 = trunk, k = k-th opening module) and the parent axis of each.

    The axis of position p at bracket depth d is the last opening module at depth d before p:
    found for all positions at once by searching (depth, position) keys.
    """
    n = len(opens)
    depth = np.cumsum(opens.astype(np.int64)) - np.cumsum(closes.astype(np.int64))
    depth_at = depth + closes  # a closing module still belongs to the level it closes
    open_pos = np.flatnonzero(opens)
    keys = depth[open_pos] * (n + 1) + open_pos
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]

    def innermost(level, pos):
        found = np.searchsorted(sorted_keys, level * (n + 1) + pos, side="right") - 1
        return np.where(level > 0, order[np.maximum(found, 0)] + 1, 0)

    axis_of = innermost(depth_at, np.arange(n))
    parent_of_open = np.concatenate([[-1], innermost(depth[open_pos] - 1, open_pos)])
    return axis_of, parent_of_open


def _tables(nodes, axis_of, parent_of_open, is_internode, is_uc, is_shoot):
    n_axes = len(parent_of_open)
    marks = np.flatnonzero(is_internode | is_uc | is_shoot)
    order = marks[np.lexsort((marks, axis_of[marks]))]  # by axis, then string position
    axis = axis_of[order]
    new_axis = np.r_[True, axis[1:] != axis[:-1]]
    shoot_seq = _per_group_cumsum(is_shoot[order], new_axis)
    unit_seq = _per_group_cumsum(is_uc[order] | is_shoot[order], new_axis)
    inter = is_internode[order]
    pos, axis, shoot_seq, unit_seq = order[inter], axis[inter], shoot_seq[inter], unit_seq[inter]
    back_to_string = np.argsort(pos, kind="stable")
    pos, axis, shoot_seq, unit_seq = (
        pos[back_to_string],
        axis[back_to_string],
        shoot_seq[back_to_string],
        unit_seq[back_to_string],
    )

    kept_axes, axis_row = np.unique(axis, return_inverse=True)
    parent_row = _kept_parents(parent_of_open, kept_axes, n_axes)
    shoot_key = axis_row.astype(np.int64) << 32 | shoot_seq
    unit_key = shoot_key << 16 | unit_seq
    shoot_ids, shoot_row = _first_seen_ids(shoot_key)
    unit_ids, unit_row = _first_seen_ids(unit_key)
    rank = rank_in_group(unit_row)

    internodes = Table(
        {
            "node": nodes[pos].astype(np.int64),
            "axis": axis_row.astype(np.int64),
            "growth_unit": unit_row,
            "shoot": shoot_row,
            "rank": rank,
        }
    )
    unit_first = _first_index(unit_row)
    growth_units = Table(
        {
            "axis": axis_row[unit_first].astype(np.int64),
            "shoot": shoot_row[unit_first],
            "first": unit_first,
            "count": np.bincount(unit_row, minlength=unit_ids),
        }
    )
    shoot_first_unit = _first_index(growth_units.shoot)
    shoots = Table(
        {
            "axis": growth_units.axis[shoot_first_unit],
            "first": shoot_first_unit,
            "count": np.bincount(growth_units.shoot, minlength=shoot_ids),
        }
    )
    axes = _axes_table(kept_axes, parent_row, axis_row, pos, parent_of_open)
    return Architecture(internodes, growth_units, shoots, axes, {})


def _per_group_cumsum(flags, starts):
    """Running count of ``flags`` restarting at each ``starts`` (counts the start's own flag)."""
    total = np.cumsum(flags.astype(np.int64))
    base = total - flags
    group = np.cumsum(starts) - 1
    return total - base[np.flatnonzero(starts)][group]


def _first_seen_ids(keys):
    """Dense ids 0..k-1 numbered in order of first appearance, and the id of every key."""
    uniq, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    rank = np.empty(len(uniq), np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(uniq))
    return len(uniq), rank[inverse]


def rank_in_group(groups: np.ndarray) -> np.ndarray:
    """0-based place of each element among the elements of its group (in array order)."""
    by_group = np.argsort(groups, kind="stable")
    sorted_groups = groups[by_group]
    starts = np.r_[True, sorted_groups[1:] != sorted_groups[:-1]]
    run_start = np.maximum.accumulate(np.where(starts, np.arange(len(groups)), 0))
    rank = np.empty(len(groups), np.int64)
    rank[by_group] = np.arange(len(groups)) - run_start
    return rank


def _first_index(rows):
    """For dense ids ``rows`` (appearing in increasing order), the first index of each id."""
    first = np.full(int(rows.max()) + 1 if len(rows) else 0, -1, np.int64)
    first[rows[::-1]] = np.arange(len(rows))[::-1]
    return first


def _kept_parents(parent_of_open, kept_axes, n_axes):
    """Parent row of every kept axis: the nearest kept ancestor (an empty axis is skipped)."""
    row_of = np.full(n_axes, -1, np.int64)
    row_of[kept_axes] = np.arange(len(kept_axes))
    parent = np.full(len(kept_axes), -1, np.int64)
    for row, a in enumerate(kept_axes.tolist()):
        p = parent_of_open[a]
        while p >= 0 and row_of[p] < 0:
            p = parent_of_open[p]
        parent[row] = row_of[p] if p >= 0 else -1
    return parent


def _axes_table(kept_axes, parent_row, axis_row, pos, parent_of_open):
    """Order, bearer internode and first internode of each kept axis."""
    first = _first_index(axis_row)
    start = pos[first]  # string position of each axis's first internode
    span = int(pos.max()) + 2 if len(pos) else 1
    by_axis = np.lexsort((pos, axis_row))  # internode rows sorted by (axis, position)
    keys = axis_row[by_axis].astype(np.int64) * span + pos[by_axis]
    bearer = np.full(len(kept_axes), -1, np.int64)
    order = np.ones(len(kept_axes), np.int64)
    parent_row = parent_row.copy()
    for row in range(len(kept_axes)):  # parents come first in string order
        p = parent_row[row]
        while p >= 0:  # the last internode of p before this axis starts, else climb to p's parent
            found = np.searchsorted(keys, p * span + start[row]) - 1
            hit = by_axis[found] if found >= 0 else -1
            if hit >= 0 and axis_row[hit] == p:
                bearer[row] = hit
                break
            p = parent_row[p]
        parent_row[row] = p
        order[row] = order[p] + 1 if p >= 0 else 1
    return Table({"parent": parent_row, "bearer": bearer, "order": order, "first": first})


def _events(tree, lsystem, role_sets, ids):
    created = tree.symbol[np.flatnonzero(tree.step[: tree.size] >= 1)]

    def count(names):
        wanted = np.asarray([ids[s] for s in names if s in ids], created.dtype)
        return int(np.count_nonzero(np.isin(created, wanted)))

    return {
        "internode": count(role_sets["internode"]),
        "growth_unit": count(role_sets["uc"] or role_sets["shoot"]),
        "branching": count(role_sets["axis"]),
        "organ": count(set(lsystem.grammar.organs)),
        "reiteration": count(role_sets["reiteration"]),
        "death": count(role_sets["death"]),
    }


def growth_events(derivation: Derivation, arch: Architecture) -> dict:
    """The growth of ``arch`` as dated events (the scheduler's input), from the history.

    Dates are in years from the start (one derivation step = one year): a growth unit made at
    step ``s`` starts at ``s - 1``, and its ``c`` internodes appear through that year, the
    ``k``-th (0-based) at ``s - 1 + (k + 1) / c`` (AMAP's internode events inside a growth
    unit); an axis branches when its first growth unit starts; an organ appears in the middle
    of the year its module was made. Returns arrays ``date``, ``kind`` (names of
    :data:`ramure.lsys.architecture.schedule.KINDS`), ``order`` (branching order) and ``node`` (history-tree
    node ids: the internode, the unit's first internode, the axis's first internode, the organ).
    """
    tree, inter, units, axes = derivation.tree, arch.internodes, arch.growth_units, arch.axes
    step = tree.step[inter.node].astype(np.float64)
    count = units.count[inter.growth_unit]
    internode_date = step - 1 + (inter.rank + 1) / count
    unit_node = inter.node[units.first]
    unit_date = tree.step[unit_node] - 1.0
    axis_node = inter.node[axes.first[1:]]
    organs = _organ_nodes(derivation)
    organ_order = np.ones(len(organs), np.int64)
    parts = [
        ("internode", internode_date, axes.order[inter.axis], inter.node),
        ("growth_unit", unit_date, axes.order[units.axis], unit_node),
        ("branching", tree.step[axis_node] - 1.0, axes.order[1:], axis_node),
        ("organ", tree.step[organs] - 0.5, organ_order, organs),
    ]
    return {
        "date": np.concatenate([p[1] for p in parts]).astype(np.float64),
        "kind": np.concatenate([np.full(len(p[1]), p[0], dtype=object) for p in parts]),
        "order": np.concatenate([p[2] for p in parts]).astype(np.int64),
        "node": np.concatenate([p[3] for p in parts]).astype(np.int64),
    }


def _organ_nodes(derivation):
    lsystem, tree = derivation.lsystem, derivation.tree
    wanted = [i for i, name in enumerate(lsystem.symbols) if name in lsystem.grammar.organs]
    leaves = tree.leaves
    return leaves[np.isin(tree.symbol[leaves], wanted)]


def grown_by(derivation: Derivation, arch: Architecture, date: float, seed: int = 0) -> dict:
    """Replay the growth through the event scheduler up to ``date`` (years, inclusive).

    Returns ``{"internodes": node ids in the order the scheduler handed them out, "events": counts
    per kind}``: tick by tick, the four lists, each ascending by branching order with ties in
    a seeded order (see :class:`ramure.lsys.architecture.schedule.EventScheduler`).
    """
    from .schedule import KINDS, EventScheduler

    if not np.isfinite(date) or date < 0:
        raise ValueRefused(f"a date must be finite and >= 0, not {date}")
    events = growth_events(derivation, arch)
    keep = events["date"] <= date
    scheduler = EventScheduler(seed=seed)
    scheduler.add(events["date"][keep], events["kind"][keep], events["order"][keep], events["node"][keep])
    grown, counts = [], dict.fromkeys(KINDS, 0)
    for _tick, kind, nodes, _dates in scheduler.run():
        counts[kind] += len(nodes)
        if kind == "internode":
            grown.append(nodes)
    return {"internodes": np.concatenate(grown) if grown else np.zeros(0, np.int64), "events": counts}
