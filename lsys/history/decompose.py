"""Decomposition rules (L-Py ``decomposition:``, cpfg ``decomposition``), applied after each step.

A grammar's ``decomposition:`` section holds rules written like productions.
After every production step (and once on the axiom, before the first step)
they rewrite the modules that step made, again and again, until no rule
applies or ``#decomposition_depth`` rounds (default 1, as in L-Py) have run;
the next production step sees the decomposed string.

As in L-Py and cpfg the rules apply to the whole string, so a module that
no production rewrote is decomposed too if a decomposition rule matches it.
Decomposition rules may have contexts (the whole current string),
conditions and probabilities.

**How decomposition enters the history tree.**  The history stays the
history of productions: the modules a decomposition makes are recorded as
the children of the *production* that made the decomposed module, in its
place, at the same step and with the same rule index (``index_in_rule`` is
the position, in that rule's successor, of the module they came from).  The
intermediate module (the ``B`` of ``B -> C D``) is not kept.  A module that
no production rewrote this step but a decomposition rule did (an identity
production followed by a decomposition) gets its decomposed modules as
children at this step, with rule index -1.  So every current leaf is a node
of a production step, every id outside a regrown part keeps its meaning,
and :func:`ramure.lsys.regeneration.regen.regenerate` and the min-cut work unchanged: a
regrown subtree is re-derived with the same decomposition (it runs inside
:meth:`ramure.lsys.LSystem.rewrite`), and a regrowth's context neighbours
are never decomposed.  The axiom is decomposed once before the first step
(its modules stay roots, step 0).

>>> from ramure.lsys import LSystem
>>> text = "n: 2\\nw: A\\np:\\n A -> AB\\n C -> X\\ndecomposition:\\n B -> CC"
>>> LSystem.from_text(text).derive().to_string()     # C is made by decomposition, then rewritten
'ACCXX'
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..engine.derive import LSystem
    from .tree import DerivationTree


def section_lsystem(lsystem: LSystem, section: str) -> LSystem:
    """An :class:`~ramure.lsys.LSystem` whose productions are ``lsystem``'s ``section`` rules
    (``"decomposition"`` or ``"interpretation"``), same symbol ids; cached on ``lsystem``."""
    key = f"_{section}_lsystem"
    cached = lsystem.__dict__.get(key)
    if cached is None:
        grammar = lsystem.grammar
        sub = replace(grammar, rules=list(getattr(grammar, section)), decomposition=[], interpretation=[])
        cached = type(lsystem)(sub)
        lsystem.__dict__[key] = cached
    return cached


def decomposer(lsystem: LSystem) -> LSystem:
    """The :class:`~ramure.lsys.LSystem` of ``lsystem``'s decomposition rules (same symbol ids), cached."""
    cached = section_lsystem(lsystem, "decomposition")
    for limit in ("max_modules", "max_history", "max_values"):
        setattr(cached, limit, getattr(lsystem, limit))
    return cached


def decompose(
    lsystem: LSystem,
    tree: DerivationTree,
    string: np.ndarray,
    first_new: int,
    step: int,
    rng: np.random.Generator,
    constants: Mapping[str, float],
    frozen: np.ndarray | None = None,
) -> np.ndarray:
    """Apply the decomposition rules to ``string`` after production step ``step``.

    ``first_new`` is the first node id the production step made; ``frozen``
    the node ids that serve only as context (a regrowth's neighbours), never
    decomposed.  Returns the new string; the tree then records the decomposed
    modules as described in the module docstring.
    """
    grammar = lsystem.grammar
    if not grammar.decomposition:
        return string
    rules = decomposer(lsystem)
    made = tree.size  # nodes from first_new to here were made by the production step
    work, changed = string, False
    for _ in range(grammar.decomposition_depth):
        before, length = tree.size, len(work)
        fixed = None if frozen is None or not len(frozen) else np.isin(work, frozen)
        work_next = rules.rewrite(tree, work, step, rng, constants, None, fixed)
        if tree.size == before and len(work_next) == length:
            break  # no rule applied
        work, changed = work_next, True
    if not changed:
        return string
    return _record(tree, string, work, first_new, made, step)


def _record(tree, string, final, first_new, made, step):
    """Re-append the decomposed modules as children of productions; the new string.

    A module the production step made (id >= ``first_new``) is replaced, in
    its producer's block of children, by what it decomposed into.  An older
    module that a decomposition rule rewrote (no production did) gets its
    decomposed modules as children at this step, with rule -1.
    """
    origin = final.copy()  # the module (made by a production, or older) each module comes from
    deep = origin >= made
    while deep.any():
        origin[deep] = tree.parent[origin[deep]]
        deep = origin >= made
    moved = np.flatnonzero((origin >= first_new) | (final != origin))
    keys = origin[moved]
    if len(keys) > 1 and (keys[1:] < keys[:-1]).any():  # group by origin, string order within
        moved = moved[np.argsort(keys, kind="stable")]
    order = moved
    src, org = final[order], origin[order]
    old = org < first_new  # products of an older module
    scratch_parents = tree.parent[made:]
    touched = np.concatenate([_runs(tree.parent[first_new:made]), _runs(scratch_parents[scratch_parents < first_new])])
    symbol, nparams, params = tree.symbol[src], tree.nparams[src], tree.params[src]  # copies (fancy indexing)
    parent = tree.parent[org]
    rule, index = tree.rule[org], tree.index_in_rule[org]
    if old.any():
        parent[old], rule[old], index[old] = org[old], -1, _rank(org[old])
    tree.truncate(first_new)
    ids = tree.append(symbol, nparams, params, parent, step, rule, index)
    touched = touched[touched >= 0]
    tree.set_children(touched, -1, 0)  # a module whose successors all decomposed to nothing
    has = parent >= 0
    kids, fathers = ids[has], parent[has]
    if len(fathers):
        starts = np.flatnonzero(np.r_[True, fathers[1:] != fathers[:-1]])  # each parent's children: one run
        tree.set_children(fathers[starts], kids[starts], np.diff(np.r_[starts, len(fathers)]))
    out = final.copy()
    out[order] = ids
    return out


def _runs(values):
    """``values`` without consecutive repeats (a parent's children are one contiguous run)."""
    if len(values) < 2:
        return values
    return values[np.r_[True, values[1:] != values[:-1]]]


def _rank(groups):
    """0, 1, 2, ... within each run of equal values of the sorted array ``groups``."""
    if not len(groups):
        return groups
    starts = np.r_[0, np.flatnonzero(groups[1:] != groups[:-1]) + 1]
    return np.arange(len(groups)) - np.repeat(starts, np.diff(np.r_[starts, len(groups)]))
