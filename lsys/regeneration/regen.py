"""Regrow or prune parts of a plant in place, with undo/redo and JSON sessions.

:func:`regenerate` removes each root's subtree and re-derives it from the
root's module for the remaining steps (``n - step[root]``), with a new seed,
constants scoped to that regeneration, or a parameter combination
``{"rule": r, "constants": {...}}`` from the metrics/qualifier layer.  Node
ids outside the regenerated subtrees never change: removed nodes are only
marked dead and new nodes are appended, so undo is cheap and exact.

Context-sensitive rules see only the regrown subtree while it is re-derived
(the rest of the plant is not its context) — a documented simplification.

:class:`Session` is what the front ends drive: select → regrow / prune →
undo / redo, constant changes, and ``save``/``load`` to JSON that replays to
the identical plant.

>>> from ramure.lsys import LSystem
>>> s = Session(LSystem.from_file("grammars/honda_sympodial.lsys"), n=6)
>>> before = s.derivation.to_string()
>>> leaves = s.leaves_with_symbol("F")[-4:]
>>> result = s.regrow(leaves, rho=0.5, constants={"a2": 20})
>>> s.derivation.to_string() != before, s.undo() is not None, s.derivation.to_string() == before
(True, True, True)
"""

from __future__ import annotations

import json
import os
import pathlib
import time
import weakref
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Self

import numpy as np
from numpy.typing import ArrayLike

from ramure.io import read_regular, write_text

from .mincut import FROM_AXIOM_MESSAGE, ascend, check_rho, collapse_nested, select_roots, stranded_words
from ..engine.combination import split as split_combination
from .mincut import validate_selection
from ..engine.derive import LSystem, check_constants, check_seed
from ..errors import GrammarError, RamureError, ValueRefused
from ..expr import seeded_generator

if TYPE_CHECKING:
    from .mincut import CutResult
    from ..engine.derive import Derivation
    from ..history.tree import DerivationTree

SESSION_FORMAT = "ramure-session"
#: Neighbouring modules kept as read-only context when regrowing a context-sensitive grammar.
CONTEXT_WINDOW = 256
#: The last edits in the undo history that keep both whole strings (see :class:`Change`);
#: older ones keep what they replaced only.
KEEP_STRINGS = 1
#: The largest derivation count a "steps" edit sets (as the explorers' n box).
MAX_STEPS = 30
SESSION_VERSION = 1


@dataclass
class Change:
    """One in-place change of the tree: enough to undo and redo it exactly.

    A fresh change keeps both strings (``old_leaves``, ``new_leaves``): undoing and redoing it
    swaps the very arrays, so whoever kept the plant of either string gets it back as it was.
    :meth:`compact` keeps only what the edit replaced and what it put in (``old_pieces``,
    ``new_pieces``): an older edit in the undo history then costs what it touched (a regrow of
    10 leaves of Honda n = 17 kept 11.5 MB, its whole new string; a few kB now), and undoing
    it splices the current string instead.
    """

    roots: np.ndarray
    old_children: tuple  # (child_start, child_count) of the roots before
    new_children: tuple
    removed: np.ndarray  # node ids marked dead
    added: np.ndarray  # node ids appended
    old_leaves: np.ndarray | None  # None once compacted
    new_leaves: np.ndarray | None
    removed_leaves: int = 0  # modules taken out of the string
    added_leaves: int = 0  # modules put in
    #: (k, 2) inclusive [first, last] string positions each run of regrown roots replaced in
    #: ``old_leaves`` and took in ``new_leaves`` (see :meth:`spans`); None when not known.
    old_spans: np.ndarray | None = None
    new_spans: np.ndarray | None = None
    #: Once compacted: the modules of each ``old_spans`` row in the old string, and of each
    #: ``new_spans`` row in the new one.
    old_pieces: list[np.ndarray] | None = None
    new_pieces: list[np.ndarray] | None = None
    _made: tuple | None = field(default=None, repr=False)  # (forward, weakrefs to the strings before and after)

    def compact(self) -> None:
        """Keep only the modules the edit replaced and put in, not both whole strings (nothing
        happens when the spans are not known)."""
        if not len(self.roots) and self.old_leaves is not None:  # regrew nothing (every leaf stayed)
            empty = np.zeros((0, 2), np.int64)
            self.old_spans, self.new_spans, self.old_pieces, self.new_pieces = empty, empty.copy(), [], []
            self.old_leaves = self.new_leaves = None
            return
        if self.old_leaves is None or self.new_leaves is None or self.old_spans is None or self.new_spans is None:
            return
        self.old_pieces = [self.old_leaves[a : b + 1].copy() for a, b in self.old_spans]
        self.new_pieces = [self.new_leaves[a : b + 1].copy() for a, b in self.new_spans]
        self.old_leaves = self.new_leaves = None

    def leaves_after(self, current: np.ndarray, forward: bool = True) -> np.ndarray:
        """The string after applying this change (``forward``) or undoing it to ``current`` (the
        string before that): the kept array, or ``current`` spliced."""
        kept = self.new_leaves if forward else self.old_leaves
        if kept is not None:
            return kept
        spans, pieces = (self.old_spans, self.new_pieces) if forward else (self.new_spans, self.old_pieces)
        assert spans is not None and pieces is not None
        return _replace_spans(current, spans[:, 0], spans[:, 1], pieces)

    def made(self, old: np.ndarray, new: np.ndarray, forward: bool = True) -> bool:
        """True if applying this change (``forward``) or undoing it turned the array ``old`` into
        ``new`` (the very arrays)."""
        made = self._made  # the last apply: its arrays (a spliced string is a new array)
        if made is not None and made[0] == forward and made[1]() is old and made[2]() is new:
            return True
        before, after = (self.old_leaves, self.new_leaves) if forward else (self.new_leaves, self.old_leaves)
        return before is not None and before is old and after is new

    def spans(self, forward: bool = True) -> tuple[np.ndarray, np.ndarray] | None:
        """What :func:`ramure.lsys.interpretation.turtle.changed_spans` finds between the strings before and after
        this change (``forward``) or its undo, without comparing them: touching spans merged, an
        empty span as ``last = first - 1``.  None when that cannot be told from the spans alone
        (a root that was a module of the string before, or a root without leaves)."""
        if self.old_spans is None or self.new_spans is None or not len(self.old_spans):
            return None
        a, b = (self.old_spans, self.new_spans) if forward else (self.new_spans, self.old_spans)
        return a.copy(), b.copy()

    def apply(self, tree: DerivationTree, forward: bool = True) -> None:
        kill, revive = (self.removed, self.added) if forward else (self.added, self.removed)
        sums = tree.detach_sums()  # updated under the roots only (the cut's capacities)
        tree.set_alive(kill, False)
        tree.set_alive(revive, True)
        start, count = self.new_children if forward else self.old_children
        tree.set_children(self.roots, start, count)
        before = tree.leaves
        tree.leaves = self.leaves_after(before, forward)
        self._made = (forward, weakref.ref(before), weakref.ref(tree.leaves))
        tree.changed()
        tree.attach_sums(sums, self.roots, revived=revive)


@dataclass
class RegenResult:
    """What a regrow/prune did (JSON-able through :meth:`to_dict`)."""

    op: str
    roots: np.ndarray
    cut_roots: np.ndarray
    min_roots: np.ndarray
    removed: int  # modules (leaves) removed from the string
    added: int  # modules (leaves) added to the string
    cut_value: float | None
    seconds: float
    cut: CutResult | None = field(default=None, repr=False)
    change: Change | None = field(default=None, repr=False)
    #: A root is an axiom module: the regrowth restarts from the axiom (the whole plant).
    from_axiom: bool = False

    @property
    def warning(self) -> str | None:
        """What a status line should say about this edit, if anything (e.g. regrown from the axiom)."""
        return FROM_AXIOM_MESSAGE if self.from_axiom and self.op in ("regrow", "prune") else None

    def to_dict(self) -> dict:
        out = {
            "op": self.op,
            "roots": self.roots.tolist(),
            "cut_roots": self.cut_roots.tolist(),
            "min_roots": self.min_roots.tolist(),
            "removed_modules": self.removed,
            "added_modules": self.added,
            "cut_value": self.cut_value,
            "seconds": round(self.seconds, 6),
            "from_axiom": self.from_axiom,
        }
        if self.warning:
            out["warning"] = self.warning
        return out


def _replace_spans(old, first, last, pieces):
    """The string with each span ``old[first[i]:last[i] + 1]`` replaced by ``pieces[i]``."""
    parts, cursor = [], 0
    for i in np.argsort(first):
        parts.append(old[cursor : first[i]])
        parts.append(pieces[i])
        cursor = last[i] + 1
    parts.append(old[cursor:])
    return np.concatenate(parts, dtype=np.int32)  # the tree's string dtype: no int64 copy


def regenerate(
    derivation: Derivation,
    roots: ArrayLike,
    seed: int = 0,
    constants: Mapping[str, float] | None = None,
    params: dict | None = None,
    prune: bool = False,
    steps: int = 0,
) -> Change:
    """Regrow (or, with ``prune=True``, cut back) the subtrees under ``roots`` in place.

    ``steps`` (-1, 0 or 1) regrows the subtrees one derivation step less or more than the
    plant's ``n``: the part alone grows on (or stops a step early), the rest of the plant
    stays as it is (a qualifier's n +- 1 on a selection, issue 35).

    Roots whose leaf spans touch and that were made at the same step are
    re-derived together as one string, so context rules see each other's
    modules (regrowing the whole axiom is exactly a fresh derivation).  For
    context-sensitive grammars the current neighbours of a regrown part (up
    to :data:`CONTEXT_WINDOW` modules each side) serve as fixed context: they
    are read, never rewritten — an approximation, since during the original
    derivation those neighbours were younger.  Returns a :class:`Change`
    that :meth:`Change.apply` can undo.
    """
    tree, ls = derivation.tree, derivation.lsystem
    roots = collapse_nested(tree, roots)
    extra, rule_constants = split_combination(params)  # params: ramure.lsys.engine.combination
    constants = {**(constants or {}), **extra}
    unknown = (set(constants) | {k for v in (rule_constants or {}).values() for k in v}) - set(ls.constants) - set(ls.hidden)
    if unknown:
        raise GrammarError(f"unknown constant(s): {', '.join(sorted(unknown))}")
    consts = check_constants({**derivation.constants, **(constants or {})})
    check_seed(seed)
    if isinstance(steps, bool) or steps not in (-1, 0, 1):
        raise ValueRefused(f"a regrowth's extra steps are -1, 0 or 1, not {steps!r}")
    if steps < 0 and not prune and len(roots) and int(tree.step[roots].max()) >= derivation.n - 1:
        raise ValueRefused("one step less leaves a part made in the last step nothing to regrow")
    first, last = tree.string_spans(roots)
    order = np.argsort(first)
    roots, first, last = roots[order], first[order], last[order]
    old_leaves = tree.leaves
    old_children = (tree.child_start[roots].copy(), tree.child_count[roots].copy())
    removed = np.concatenate([tree.subtree(r) for r in roots]) if roots.size else np.zeros(0, np.int64)
    first_new = tree.size
    rng = seeded_generator(seed)
    sums = tree.detach_sums()  # kept: updated under the roots once the edit is done
    try:
        pieces, starts, ends = _rederive(derivation, roots, first, last, old_leaves, rng, consts, rule_constants, prune, steps)
    except BaseException:
        # Loses nothing: forget the half-grown nodes and point the roots at their old children.
        tree.truncate(first_new)
        tree.set_children(roots, *old_children)
        raise
    if prune:
        tree.set_children(roots, -1, 0)
    new_children = (tree.child_start[roots].copy(), tree.child_count[roots].copy())
    tree.set_alive(removed, False)
    new_leaves = _replace_spans(old_leaves, np.array(starts, np.int64), np.array(ends, np.int64), pieces)
    spans = _edit_spans(starts, ends, pieces) if (old_children[1] > 0).all() else None
    change = Change(
        roots,
        old_children,
        new_children,
        removed,
        np.arange(first_new, tree.size, dtype=np.int64),
        old_leaves,
        new_leaves,
        int((last - first + 1).sum()),
        int(sum(len(p) for p in pieces)),
        *(spans if spans is not None else (None, None)),
    )
    tree.leaves = new_leaves
    tree.changed()
    tree.attach_sums(sums, roots, new_leaves=pieces)
    return change


def _edit_spans(starts, ends, pieces):
    """``(old_spans, new_spans)`` of an edit that replaced ``[starts[i], ends[i]]`` by ``pieces[i]``
    (sorted runs), spans that touch in the old string merged: the runs
    :func:`ramure.lsys.interpretation.turtle.changed_spans` finds.  None for a span without modules."""
    starts, ends = np.asarray(starts, np.int64), np.asarray(ends, np.int64)
    lengths = np.array([len(p) for p in pieces], np.int64)
    if not len(starts) or (starts < 0).any() or (ends < starts).any():
        return None
    runs = np.flatnonzero(np.r_[True, starts[1:] != ends[:-1] + 1])
    last = np.r_[runs[1:], len(starts)] - 1
    old = np.stack([starts[runs], ends[last]], axis=1)
    grown = np.add.reduceat(lengths, runs)
    delta = grown - (old[:, 1] - old[:, 0] + 1)  # each run's change of length
    first = old[:, 0] + np.cumsum(delta) - delta  # shifted by the runs before it
    return old, np.stack([first, first + grown - 1], axis=1)


def _rederive(derivation, roots, first, last, old_leaves, rng, consts, rule_constants, prune, steps=0):
    """Re-derive each run of touching roots; returns (pieces, span starts, span ends)."""
    tree, ls = derivation.tree, derivation.lsystem
    pieces, starts, ends = [], [], []
    window = CONTEXT_WINDOW if ls.has_context else 0
    for run in _runs(first, last, tree.step[roots]):
        string = roots[run]
        if not prune:  # rewrite() points each root at its new children
            left = old_leaves[max(0, first[run[0]] - window) : first[run[0]]]
            right = old_leaves[last[run[-1]] + 1 : last[run[-1]] + 1 + window]
            string = np.concatenate([left, string, right])
            for step in range(int(tree.step[roots[run[0]]]) + 1, derivation.n + 1 + steps):
                frozen = np.zeros(len(string), bool)
                frozen[: len(left)] = frozen[len(string) - len(right) :] = True
                string = ls.rewrite(tree, string, step, rng, consts, rule_constants, frozen)
            string = string[len(left) : len(string) - len(right)]
        pieces.append(string)
        starts.append(first[run[0]])
        ends.append(last[run[-1]])
    return pieces, starts, ends


def _runs(first, last, steps):
    """Split sorted root spans into runs of touching spans made at the same step."""
    if not len(first):
        return []
    breaks = np.flatnonzero((first[1:] != last[:-1] + 1) | (steps[1:] != steps[:-1])) + 1
    return np.split(np.arange(len(first)), breaks)


class Session:
    """A plant being edited: derivation + edit log with undo/redo, saved as JSON.

    Every edit is a dict in :attr:`edits` (``op`` = ``regrow``, ``prune``,
    ``constants``, ``steps`` or ``fruit``) holding everything needed to replay it, including the seed
    actually used, so :meth:`load` rebuilds the identical plant.
    """

    def __init__(
        self,
        lsystem: LSystem | str | pathlib.Path,
        n: int | None = None,
        seed: int | None = None,
        constants: Mapping[str, float] | None = None,
        filename: str | None = None,
    ) -> None:
        if isinstance(lsystem, (str, pathlib.Path)):
            filename = filename or str(lsystem)
            lsystem = LSystem.from_file(lsystem)
        self.lsystem = lsystem
        self.filename = filename
        self.n = lsystem.n if n is None else int(n)
        self.base_n = self.n  # the n the edits replay from (a "steps" edit changes self.n)
        self.seed = lsystem.seed if seed is None else int(seed)  # default: the grammar's #seed
        self.base_constants = {**lsystem.constants, **(constants or {})}
        self.constants = dict(self.base_constants)
        self.derivation = lsystem.derive(n=self.n, seed=self.seed, constants=self.constants)
        self.edits: list[dict] = []  # applied edits, oldest first
        self._undo: list[tuple] = []  # (edit, how to undo)
        self._redo: list[tuple] = []
        self.last_result: RegenResult | None = None

    # -- queries -----------------------------------------------------------
    @property
    def tree(self) -> DerivationTree:
        return self.derivation.tree

    def leaves_with_symbol(self, symbol: str) -> np.ndarray:
        """Current leaf ids whose module symbol is ``symbol`` (e.g. all ``F``)."""
        if symbol not in self.lsystem.symbols:
            return np.zeros(0, np.int64)
        sid = self.lsystem.symbols.index(symbol)
        return self.tree.leaves[self.tree.symbol[self.tree.leaves] == sid]

    def plan(
        self,
        selection: Iterable[int],
        rho: float = 0.5,
        min_ascend: int = 1,
        ascend_levels: int | None = None,
        flow_func: Callable | None = None,
        whole_branches: bool = False,
    ) -> tuple[CutResult | None, np.ndarray, np.ndarray, np.ndarray]:
        """The cut for a selection, without changing anything (``whole_branches``: see
        :func:`ramure.lsys.regeneration.mincut.minimum_ascension`)."""
        if ascend_levels is not None:
            levels = ascend_levels
            if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
                raise ValueRefused(f"ascend levels must be a whole number >= 0, not {levels!r}")
            sel = validate_selection(self.tree, selection)
            roots = collapse_nested(self.tree, [ascend(self.tree, leaf, ascend_levels) for leaf in sel])
            return None, roots, roots, np.zeros(0, np.int64)
        cut = select_roots(
            self.tree, selection, rho=rho, n=self.n, min_ascend=min_ascend, flow_func=flow_func, whole_branches=whole_branches
        )
        return cut, cut.roots, cut.cut_roots, cut.min_roots

    # -- edits -------------------------------------------------------------
    def regrow(
        self,
        selection: Iterable[int] = (),
        rho: float = 0.5,
        seed: int | None = None,
        constants: Mapping[str, float] | None = None,
        params: dict | None = None,
        min_ascend: int = 1,
        ascend_levels: int | None = None,
        refuse_empty: bool = False,
        steps: int = 0,
    ) -> RegenResult:
        """Regrow the selection's cut subtrees (or the whole plant if ``selection`` is empty).

        ``seed`` None draws the next seed of this session (recorded in the edit);
        ``constants`` apply to this regeneration only; ``params`` is a
        parameter combination ``{"rule": r or None, "constants": {...}}``.
        ``refuse_empty``: a selection whose cut regrows nothing (every selected leaf
        stays) is refused with :class:`ValueRefused` instead of making an empty edit.
        ``steps`` 1 (or -1) regrows the cut's part one derivation step more (less) than the
        plant's ``n``; the rest of the plant is unchanged (:func:`regenerate`).
        """
        if isinstance(steps, bool) or steps not in (-1, 0, 1):
            raise ValueRefused(f"a regrowth's extra steps are -1, 0 or 1, not {steps!r}")
        edit = {
            "op": "regrow",
            "selection": [int(x) for x in selection],
            "rho": check_rho(rho),
            "seed": self._next_seed() if seed is None else check_seed(seed),
            "constants": dict(constants or {}),
            "params": _check_params(params, self.lsystem),
            "min_ascend": int(min_ascend),
            "ascend": ascend_levels,
            "whole_branches": False,
        }
        if steps:  # recorded only when used, so older readers see the edits they know
            edit["steps"] = int(steps)
        return self._apply(edit, refuse_empty)

    def prune(
        self,
        selection: Iterable[int],
        rho: float = 0.5,
        min_ascend: int = 1,
        ascend_levels: int | None = None,
        refuse_empty: bool = False,
    ) -> RegenResult:
        """Delete the cut subtrees without regrowing them (their roots become leaves);
        ``refuse_empty`` as for :meth:`regrow`."""
        edit = {
            "op": "prune",
            "selection": [int(x) for x in selection],
            "rho": check_rho(rho),
            "seed": 0,
            "constants": {},
            "params": None,
            "min_ascend": int(min_ascend),
            "ascend": ascend_levels,
            "whole_branches": False,
        }
        return self._apply(edit, refuse_empty)

    def regrow_fruit(self, leaf_ids: Iterable[int], seed: int | None = None, **settings: Any) -> RegenResult:
        """Give selected ``Fruit`` organs new volumetric-fruit settings (an undoable edit).

        ``settings`` are recorded as given (``preset``, ``size`` and fruit
        parameters, checked by the volumetric layer that applies them, see
        :func:`ramure.gmap.organs.plant.fruits_from_skeleton`); ``seed`` None draws a new one.
        :meth:`fruit_overrides` gives what applies to the current plant.
        """
        leaves = [int(x) for x in leaf_ids]
        tree = self.tree
        organs = {self.lsystem.symbols.index(o) for o in self.lsystem.grammar.organs if o in self.lsystem.symbols}
        in_string = self._in_string(leaves)
        bad = [x for x in leaves if x not in in_string or int(tree.symbol[x]) not in organs]
        if not leaves or bad:
            raise ValueRefused(f"select fruit to regrow; {bad[0] if bad else 'nothing'} is not a fruit of the current plant")
        size = settings.get("size")
        if size is not None and not (np.isfinite(float(size)) and float(size) > 0):
            raise ValueRefused(f"fruit size must be a positive number, not {size}")
        edit = {
            "op": "fruit",
            "leaves": leaves,
            "settings": {**settings, "seed": self._next_seed() if seed is None else int(seed)},
        }
        return self._apply(edit)

    def add_detail(self, kind: str, settings: Mapping[str, Any], leaves: Iterable[int] = ()) -> RegenResult:
        """Record a natural detail (issue 18) as an undoable edit that sessions save: ``kind``
        one of :data:`DETAIL_KINDS` (lichen or a crack on a fruit, lichen on the bark), its
        ``settings`` (names to numbers, text, booleans or lists of numbers: the seed, counts,
        an anchor, painted adhesion) and the ``leaves`` it sits on (a fruit). Data only: the
        plant does not change; :meth:`details` lists the details and the app layer grows them
        again from their settings (they are seeded, so they come out the same)."""
        if kind not in DETAIL_KINDS:
            raise ValueRefused(f"a detail is one of {', '.join(DETAIL_KINDS)}, not {kind!r}")
        leaves = [int(x) for x in leaves]
        present = np.isin(np.asarray(leaves, np.int64), self.tree.leaves)
        if not present.all():
            raise ValueRefused(f"{leaves[int(np.argmin(present))]} is not a leaf of the current plant")
        edit = {"op": "detail", "kind": kind, "leaves": leaves, "settings": _check_detail_settings(settings)}
        return self._apply(edit)

    def _in_string(self, ids: Iterable[int]) -> set[int]:
        """Which of ``ids`` are modules of the current string.  Checked with numpy: a Python set
        of the whole string is about 120 bytes per module (170 MB at 1.44 M modules)."""
        ids = np.unique(np.fromiter((int(x) for x in ids), np.int64))
        ids = ids[(ids >= 0) & (ids < len(self.tree))]
        return set(ids[np.isin(ids, self.tree.leaves)].tolist()) if ids.size else set()

    def details(self) -> list[dict]:
        """The detail edits (see :meth:`add_detail`) whose leaves are still in the plant, oldest first."""
        edits = [e for e in self.edits if e["op"] == "detail"]
        present = self._in_string(x for e in edits for x in e["leaves"])
        return [e for e in edits if all(x in present for x in e["leaves"])]

    def fruit_overrides(self) -> dict[int, dict]:
        """``{leaf_id: settings}`` from the fruit edits, for fruit still in the plant."""
        present = self._in_string(x for e in self.edits if e["op"] == "fruit" for x in e["leaves"])
        out: dict[int, dict] = {}
        for edit in self.edits:
            if edit["op"] == "fruit":
                for leaf in edit["leaves"]:
                    if leaf in present:
                        out.setdefault(leaf, {}).update(edit["settings"])
        return out

    def set_constants(self, values: Mapping[str, float]) -> RegenResult:
        """Change global constants: the whole plant is re-derived (an undoable edit)."""
        edit = {"op": "constants", "values": _check_values(values, self.lsystem)}
        return self._apply(edit)

    def set_steps(self, n: int, params: dict | None = None) -> RegenResult:
        """Derive the whole plant again with ``n`` derivation steps (an undoable edit; a
        qualifier's n +- 1 when no constant moves the plant its way); ``params`` a parameter
        combination this derivation applies (as a whole-plant :meth:`regrow`'s)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 0 <= n <= MAX_STEPS:
            raise ValueRefused(f"the derivation count must be a whole number from 0 to {MAX_STEPS}, not {n!r}")
        return self._apply({"op": "steps", "n": int(n), "params": _check_params(params, self.lsystem)})

    def current_lsystem(self) -> LSystem:
        """The grammar with this session's current constants: what a variant sweep should vary.

        The session's own :attr:`lsystem` keeps the file's values; this copy carries the
        values set since (sliders, :meth:`set_constants`), so exploring or qualifying a
        session starts from the plant on screen.
        """
        current = self.lsystem.copy()
        current.constants.update(self.constants)
        return current

    def _next_seed(self):
        return self.seed * 1_000_003 + len(self.edits) + 1

    def _apply(self, edit, refuse_empty=False):
        t0 = time.perf_counter()
        undo: tuple[Any, ...]
        if edit["op"] in ("fruit", "detail"):  # data only: read by fruit_overrides() / details()
            undo = ("none",)
            result = RegenResult(
                edit["op"],
                np.array(edit["leaves"], np.int64),
                *(np.zeros(0, np.int64),) * 2,
                0,
                0,
                None,
                time.perf_counter() - t0,
            )
        elif edit["op"] in ("constants", "steps"):
            undo = ("derivation", self.derivation, dict(self.constants), self.n)
            constants = {**self.constants, **edit.get("values", {})}
            n = int(edit.get("n", self.n))
            derivation = self.lsystem.derive(n=n, seed=self.seed, constants=constants, params=edit.get("params"))
            # Only now that the plant re-derived: a refused value changes nothing.
            self.derivation, self.constants, self.n = derivation, constants, n
            result = RegenResult(
                edit["op"], *(np.zeros(0, np.int64),) * 3, len(undo[1]), len(self.derivation), None, time.perf_counter() - t0
            )
        else:
            result = self._regrow_or_prune(edit, t0, refuse_empty)
            undo = ("change", result.change)
        self.edits.append(edit)
        self._undo.append((edit, undo))
        self._redo.clear()
        if len(self._undo) > KEEP_STRINGS:
            how = self._undo[-KEEP_STRINGS - 1][1]
            if how[0] == "change":
                how[1].compact()
        self.last_result = result
        return result

    def _regrow_or_prune(self, edit, t0, refuse_empty=False):
        tree = self.tree
        if edit["selection"]:
            # a session saved before issue 34 has no "whole_branches": its minimum ascension took them
            whole = edit.get("whole_branches", True)
            cut, roots, cut_roots, min_roots = self.plan(
                edit["selection"], edit["rho"], edit["min_ascend"], edit["ascend"], whole_branches=whole
            )
            if refuse_empty and not len(roots):
                raise ValueRefused(f"nothing regrows: {stranded_words(len(edit['selection']))}")
        else:  # the whole plant: regrow from every axiom module
            cut = None
            roots = np.flatnonzero((tree.parent == -1) & tree.alive)
            cut_roots, min_roots = roots, np.zeros(0, np.int64)
        change = regenerate(
            self.derivation,
            roots,
            seed=edit["seed"],
            constants=edit["constants"],
            params=edit["params"],
            prune=edit["op"] == "prune",
            steps=edit.get("steps", 0),
        )
        return RegenResult(  # the roots in the plan's order (ascending ids), not the string order
            edit["op"],  # regenerate re-derives them in: a result names the part the preview showed
            np.sort(change.roots),
            cut_roots,
            min_roots,
            change.removed_leaves,
            change.added_leaves,
            cut.cut_value if cut else None,
            time.perf_counter() - t0,
            cut,
            change,
            from_axiom=bool(edit["selection"]) and bool(change.roots.size and (tree.parent[change.roots] < 0).any()),
        )

    def edit_spans(self, old: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The spans (as :func:`ramure.lsys.interpretation.turtle.changed_spans` gives them) of the regrow, prune,
        undo or redo that made the string ``new`` (the tree's leaves array itself) from ``old``
        (the very array before it), or None when the last edit did not (then compare the strings)."""
        for stack, forward in ((self._undo, True), (self._redo, False)):
            if stack and stack[-1][1][0] == "change":
                change = stack[-1][1][1]
                if change.made(old, new, forward):
                    return change.spans(forward)
        return None

    def undo(self) -> dict | None:
        """Undo the last edit; returns it (None when there is nothing to undo)."""
        return self._travel(self._undo, self._redo, forward=False)

    def redo(self) -> dict | None:
        """Redo the last undone edit; returns it (None when there is nothing to redo)."""
        return self._travel(self._redo, self._undo, forward=True)

    def _travel(self, take, give, forward):
        if not take:
            return None
        edit, how = take.pop()
        if how[0] == "derivation":  # swap whole derivations (a constants or steps edit)
            current = ("derivation", self.derivation, dict(self.constants), self.n)
            self.derivation, self.constants, self.n = how[1], how[2], how[3]
            how = current
        elif how[0] == "change":
            how[1].apply(self.tree, forward=forward)
        if forward:
            self.edits.append(edit)
        else:
            self.edits.pop()
        give.append((edit, how))
        return edit

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)

    # -- persistence -------------------------------------------------------
    def to_dict(self) -> dict:
        return {
            "format": SESSION_FORMAT,
            "version": SESSION_VERSION,
            "grammar": self.lsystem.text,
            "filename": self.filename,
            "reader": _reader(self.lsystem, self.filename),
            "n": self.base_n,
            "seed": self.seed,
            "constants": self.base_constants,
            "edits": self.edits,
        }

    def save(self, path: str | os.PathLike) -> pathlib.Path:
        """Write the session as JSON (atomically: a crash never leaves half a file)."""
        path = pathlib.Path(path)
        if path.is_dir():
            raise RamureError(f"cannot save the session to {path}: it is a directory")
        try:
            write_text(path, json.dumps(self.to_dict(), indent=1))
        except RamureError as exc:
            raise RamureError(f"cannot save the session: {exc}") from None
        return path

    @classmethod
    def from_dict(
        cls,
        data: dict,
        where: str = "session",
        folder: str | os.PathLike | None = None,
        progress: Callable[[int, int], None] | None = None,
    ) -> Self:
        """The session ``data`` describes (edits replayed; ``progress(done, total)`` is called
        after each edit).  A session of more than :data:`MAX_SESSION_EDITS` edits is refused
        before any is replayed (each edit regrows part of the plant: thousands take seconds).

        The stored ``"filename"`` is metadata only, never where files are read from: the
        grammar is parsed as if it stood, under that file's name, in ``folder`` (the session
        file's folder, see :meth:`load`), so its ``#include`` and ``#surface`` files are read
        from that folder and below only; with no ``folder`` it reads no file at all."""
        if not isinstance(data, dict) or data.get("format") != SESSION_FORMAT:
            raise RamureError(f'{where} is not a Ramure session (no \'"format": "{SESSION_FORMAT}"\')')
        if data.get("version") != SESSION_VERSION:
            raise RamureError(f"{where} has session version {data.get('version')!r}; this Ramure reads version {SESSION_VERSION}")
        missing = [k for k in ("grammar", "n", "seed", "constants", "edits") if k not in data]
        if missing:
            raise RamureError(f"{where} is incomplete: missing {', '.join(missing)}")
        _check_session_fields(data, where)
        try:
            name = _beside(folder, data.get("filename"), data.get("reader"))
            ls = LSystem.from_text(data["grammar"], filename=name)
            session = cls(ls, n=data["n"], seed=data["seed"], constants=data["constants"], filename=data.get("filename"))
            for i, edit in enumerate(data["edits"]):
                session._apply(_check_edit(edit, i, session))
                if progress is not None:
                    progress(i + 1, len(data["edits"]))
        except RamureError as exc:
            raise RamureError(f"{where} cannot be replayed: {exc}") from None
        except (KeyError, TypeError, ValueError, OverflowError, RecursionError) as exc:
            raise RamureError(f"{where} is a corrupt session file: {type(exc).__name__}") from None
        session._undo.clear()  # a loaded session starts a fresh undo history
        return session

    @classmethod
    def load(cls, path: str | os.PathLike, progress: Callable[[int, int], None] | None = None) -> Self:
        """Read a session file; a corrupt or truncated file raises RamureError, nothing else changes
        (``progress``: see :meth:`from_dict`)."""
        path = pathlib.Path(path)
        try:
            data = json.loads(read_regular(path, MAX_SESSION_BYTES, "session file").decode("utf-8"))
        except json.JSONDecodeError as exc:
            raise RamureError(
                f"{path} is not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg}); is the file truncated?"
            ) from None
        except UnicodeDecodeError:
            raise RamureError(f"{path} is not a text file") from None
        except RecursionError:
            raise RamureError(f"{path} is a corrupt session file (nested too deeply)") from None
        except ValueError as exc:  # e.g. an integer of thousands of digits
            raise RamureError(f"{path} is a corrupt session file ({exc})") from None
        except OSError as exc:
            raise RamureError(f"cannot read {path}: {exc.strerror or exc}") from None
        return cls.from_dict(data, where=str(path), folder=path.absolute().parent, progress=progress)


def _beside(folder, stored, reader=None):
    """Where a session's grammar is parsed from: its stored file name, in ``folder``.

    ``reader`` (the suffix of the reader the grammar text needs, see :func:`_reader`) replaces
    the name's suffix.  With no ``folder`` it is None (no file is read), except for an L-Py
    model: a bare ``session.lpy`` then names its reader."""
    name = stored.replace("\\", "/").rsplit("/", 1)[-1] if stored else ""
    if isinstance(reader, str) and reader in _READERS:
        name = str(pathlib.PurePath(name or "session").with_suffix(reader))
    elif folder is None:
        return None
    if folder is None:  # no file is read: an .lpy name only says which reader parses the text
        return name if reader == ".lpy" else None
    return str(pathlib.Path(folder) / (name or "session.lsys"))


#: The readers a session names: an L-Py model's Python, and a grammar an MTG became.
_READERS = (".lpy", ".lsys")


def _reader(lsystem, filename):
    """The suffix whose reader parses ``lsystem``'s text when the file name would not say it:
    ``.lpy`` for an L-Py model, ``.lsys`` for the grammar an MTG file became; else None."""
    if getattr(lsystem, "READER", None) == ".lpy":  # an L-Py model (ramure.lsys.readers.lpy), read by name
        return ".lpy"
    if filename and str(filename).lower().endswith(".mtg"):
        return ".lsys"
    return None


def _check_params(params, lsystem):
    if params is None:
        return None
    if not isinstance(params, dict) or not isinstance(params.get("constants"), dict):
        raise ValueRefused("a parameter combination is {'rule': index or None, 'constants': {...}}")
    rule = params.get("rule")
    if rule is not None and not (_is_whole(rule) and rule < len(lsystem.grammar.rules)):
        raise ValueRefused(f"rule {rule!r} does not exist (the grammar has {len(lsystem.grammar.rules)} rules, numbered from 0)")
    return {
        "rule": None if rule is None else int(rule),
        "constants": _check_values(params["constants"], lsystem, " in the combination"),
    }


def _check_values(values, lsystem, where: str = ""):
    """Constant overrides: known names, finite numbers (returned as floats)."""
    if not isinstance(values, dict):
        raise ValueRefused(f"constant values must be a mapping of name to number, not {values!r}")
    unknown = set(values) - set(lsystem.constants) - set(getattr(lsystem, "hidden", {}))
    if unknown:
        raise ValueRefused(f"unknown constant(s){where}: {', '.join(sorted(map(str, unknown)))}")
    check_constants(values)
    return {k: float(v) for k, v in values.items()}


#: Largest whole number a session file may hold (ids, seeds, n): node ids are int64.
MAX_WHOLE = 2**63 - 1
#: The largest session file read (a session of a thousand edits is well under 1 MB).
MAX_SESSION_BYTES = 64 * 2**20
#: The most edits a session file may hold: each is replayed on load (about 1.6 ms each on a
#: small plant, more on a large one), so 2,000 took 3-4 s; 1,000 bound it to about 2 s.
MAX_SESSION_EDITS = 1000


def _is_whole(value, low=0, high=MAX_WHOLE):
    """A whole number in [low, high] (``high=None``: unbounded, e.g. a min_ascend clamped later)."""
    return (
        isinstance(value, (int, np.integer)) and not isinstance(value, bool) and low <= value and (high is None or value <= high)
    )


def _check_session_fields(data, where):
    problems = []
    if not isinstance(data["grammar"], str):
        problems.append("'grammar' must be the grammar text")
    if data.get("filename") is not None and not isinstance(data["filename"], str):
        problems.append("'filename' must be a string or null")
    if not _is_whole(data["n"]):
        problems.append(f"'n' must be a whole number >= 0, not {data['n']!r}")
    if not _is_whole(data["seed"]):
        problems.append(f"'seed' must be a whole number >= 0, not {data['seed']!r}")
    if not isinstance(data["constants"], dict):
        problems.append("'constants' must be a mapping of name to number")
    if not isinstance(data["edits"], list):
        problems.append("'edits' must be a list")
    elif len(data["edits"]) > MAX_SESSION_EDITS:
        problems.append(f"it holds {len(data['edits']):,} edits; a session replays at most {MAX_SESSION_EDITS:,}")
    if problems:
        raise RamureError(f"{where} is corrupt: {'; '.join(problems)}")


#: Natural details a session records (issue 18), see :meth:`Session.add_detail`.
DETAIL_KINDS = ("lichen", "crack", "bark")


def _check_detail_settings(settings):
    """A detail's settings: a mapping of names to finite numbers, text, booleans, None or
    lists of finite numbers (at most 1,000,000 in all); returns a plain JSON-ready copy."""
    if not isinstance(settings, dict):
        raise ValueRefused("a detail's settings must be a mapping of names to values")
    out: dict[str, Any] = {}
    count = 0
    for name, value in settings.items():
        if not isinstance(name, str):
            raise ValueRefused(f"a detail setting's name must be text, not {name!r}")
        if isinstance(value, (list, tuple, np.ndarray)):
            try:
                values = np.asarray(value, np.float64).ravel() if len(value) else np.zeros(0)
            except (TypeError, ValueError):
                raise ValueRefused(f"detail setting {name!r} must be a list of numbers") from None
            if not np.isfinite(values).all():
                raise ValueRefused(f"detail setting {name!r} must hold finite numbers")
            count += len(values)
            out[name] = values.tolist()
        elif value is None or isinstance(value, (bool, str)):
            out[name] = value
        elif isinstance(value, (int, float, np.integer, np.floating)) and np.isfinite(float(value)):
            out[name] = value.item() if isinstance(value, np.generic) else value
        else:
            raise ValueRefused(f"detail setting {name!r} must be a finite number, text, a boolean or a list, not {value!r}")
    if count > 1_000_000:
        raise ValueRefused("a detail's settings hold more than 1,000,000 numbers")
    return out


def _check_edit(edit, i, session):
    """Check one saved edit before replaying it on ``session`` (ids must be current leaves)."""
    if not isinstance(edit, dict) or edit.get("op") not in ("regrow", "prune", "constants", "steps", "fruit", "detail"):
        raise RamureError(f"edit {i + 1} has no valid 'op'")
    what = f"edit {i + 1} ({edit['op']})"
    if edit["op"] == "steps":
        if not _is_whole(edit.get("n"), high=MAX_STEPS):
            raise RamureError(f"{what}: 'n' must be a whole number from 0 to {MAX_STEPS}")
        try:
            return {**edit, "params": _check_params(edit.get("params"), session.lsystem)}
        except ValueRefused as exc:
            raise RamureError(f"{what}: {exc}") from None
    if edit["op"] == "detail":
        leaves = edit.get("leaves")
        if edit.get("kind") not in DETAIL_KINDS or not isinstance(leaves, list) or not all(_is_whole(x) for x in leaves):
            raise RamureError(f"{what} needs a 'kind' ({', '.join(DETAIL_KINDS)}) and 'leaves' (leaf ids)")
        if not np.isin(np.asarray(leaves, np.int64), session.tree.leaves).all():
            raise RamureError(f"{what}: a leaf of it is not in the plant")
        try:
            return {**edit, "settings": _check_detail_settings(edit.get("settings"))}
        except ValueRefused as exc:
            raise RamureError(f"{what}: {exc}") from None
    if edit["op"] == "fruit":
        leaves, settings = edit.get("leaves"), edit.get("settings")
        if not isinstance(leaves, list) or not isinstance(settings, dict) or not all(_is_whole(x) for x in leaves):
            raise RamureError(f"{what} needs 'leaves' (leaf ids) and 'settings'")
        in_string = np.isin(np.asarray(leaves, np.int64), session.tree.leaves)
        if not in_string.all():
            raise RamureError(f"{what}: {leaves[int(np.argmin(in_string))]} is not a leaf of the plant")
        return edit
    if edit["op"] == "constants":
        try:
            return {**edit, "values": _check_values(edit.get("values"), session.lsystem)}
        except ValueRefused as exc:
            raise RamureError(f"{what}: {exc}") from None
    for key in ("selection", "rho", "seed", "constants", "min_ascend"):
        if key not in edit:
            raise RamureError(f"{what} is missing '{key}'")
    selection = edit["selection"]
    if not isinstance(selection, list) or not all(_is_whole(x) for x in selection):
        raise RamureError(f"{what}: 'selection' must be a list of leaf ids")
    if not _is_whole(edit["seed"]) or not _is_whole(edit["min_ascend"], high=None):
        raise RamureError(f"{what}: 'seed' and 'min_ascend' must be whole numbers >= 0")
    ascend_levels = edit.get("ascend")
    if ascend_levels is not None and not _is_whole(ascend_levels, high=None):
        raise RamureError(f"{what}: 'ascend' must be null or a whole number >= 0")
    if not isinstance(edit.get("whole_branches", True), bool):
        raise RamureError(f"{what}: 'whole_branches' must be true or false")
    if edit.get("steps", 0) not in (-1, 0, 1) or isinstance(edit.get("steps"), bool):
        raise RamureError(f"{what}: 'steps' must be -1, 0 or 1")
    try:
        constants = _check_values(edit["constants"], session.lsystem)
        params = _check_params(edit.get("params"), session.lsystem)
    except (ValueRefused, TypeError, ValueError) as exc:
        raise RamureError(f"{what}: {exc}") from None
    return {**edit, "constants": constants, "params": params, "ascend": ascend_levels}
