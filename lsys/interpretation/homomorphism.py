"""Interpretation rules (L-Py ``interpretation:``, cpfg ``homomorphism``): rewriting for drawing only.

A grammar's ``interpretation:`` section holds rules written like productions.
They are applied to the derived string only when it is drawn: the turtle is
fed the *interpreted* string, while the derived string, the derivation
history and every leaf id stay those of the productions.  Interpretation
rules are applied ``#interpretation_depth`` times at most (default **1**,
L-Py's default: a module an interpretation rule produces is not interpreted
again unless the depth is raised), stopping early when no rule applies.

Every module drawn from an interpreted module carries the history-leaf id of
the module it came from, so segments, organs and polygons drawn by an
interpretation rule are picked, selected and regrown as that module.

They may have contexts (the context is the string being interpreted),
conditions and probabilities; random draws come from a generator seeded by
the derivation's seed, so a plant always draws the same way.

This module is the one place the homomorphism is applied:
:func:`ramure.lsys.interpretation.turtle.interpret` (hence ``Derivation.skeleton()``, the
app's views and the metrics) calls :func:`interpret_derivation` when the
grammar has interpretation rules.

>>> from ramure.lsys import LSystem
>>> d = LSystem.from_text("n: 2\\nw: A\\np:\\n A -> AB\\ninterpretation:\\n B -> F[+F]").derive()
>>> d.to_string(), len(d.skeleton()), interpreted_text(d)
('ABB', 4, 'AF[+F]F[+F]')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import fields, is_dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..history.decompose import section_lsystem
from ..history.tree import DerivationTree

if TYPE_CHECKING:
    from ..engine.derive import Derivation, LSystem
    from ..language.grammar import Grammar, Rule
    from .turtle import Skeleton

#: The seed offset of interpretation rules' random draws (kept apart from the derivation's own stream).
SEED_OFFSET = 0x1A7E


def interpreter(lsystem: LSystem) -> LSystem:
    """The :class:`~ramure.lsys.LSystem` of ``lsystem``'s interpretation rules (same symbol ids), cached."""
    return section_lsystem(lsystem, "interpretation")


def interpreted(
    lsystem: LSystem, tree: DerivationTree, leaves: ArrayLike, constants: Mapping[str, float] | None = None, seed: int = 0
) -> tuple[DerivationTree, np.ndarray, np.ndarray]:
    """Apply the interpretation rules to the string ``leaves`` (node ids of ``tree``).

    Returns ``(scratch, string, source)``: a scratch :class:`DerivationTree`
    holding the interpreted modules, the interpreted string (node ids of
    ``scratch``) and, for each of its modules, the id (in ``tree``) of the
    leaf it was drawn from.  ``tree`` is never modified.
    """
    leaves = np.asarray(leaves, np.int64)
    rules = interpreter(lsystem)
    width = max(tree.max_params, rules.max_params)
    scratch = DerivationTree(width, capacity=max(2 * len(leaves), 1024))
    params = np.full((len(leaves), width), np.nan)
    params[:, : tree.max_params] = tree.params[leaves]
    # the copied modules keep their rule and slot, so errors point at the rule that wrote them
    string = scratch.append(
        tree.symbol[leaves], tree.nparams[leaves], params, -1, 0, tree.rule[leaves], tree.index_in_rule[leaves]
    )
    consts = {**lsystem.constants, **(constants or {})}
    rng = np.random.default_rng([int(seed), SEED_OFFSET])
    for depth in range(1, lsystem.grammar.interpretation_depth + 1):
        before, length = scratch.size, len(string)
        new = rules.rewrite(scratch, string, depth, rng, consts)
        if scratch.size == before and len(new) == length:
            break
        string = new
    made = scratch.size > len(leaves)
    if made:  # modules an interpretation rule wrote: rule index -2 - r (see interpretation_rule)
        written = scratch.rule[len(leaves) :].astype(np.int64)
        scratch.widen("rule", -2 - int(written.max()), -2 - int(written.min()))
        scratch.rule[len(leaves) :] = -2 - written
    return scratch, string, leaves[_roots(scratch)[string]]


def interpretation_rule(grammar: Grammar, rule: int) -> Rule | None:
    """The interpretation :class:`~ramure.lsys.language.grammar.Rule` a scratch node's ``rule`` value names, or None.

    In the scratch tree of :func:`interpreted`, a module copied from the derived
    string keeps its production rule index (>= 0, or -1 for the axiom); a module
    an interpretation rule ``r`` wrote has rule value ``-2 - r``.
    """
    r = -2 - int(rule)
    return grammar.interpretation[r] if 0 <= r < len(grammar.interpretation) else None


def _roots(scratch):
    """The root (string position at depth 0) every scratch node comes from."""
    root = np.arange(scratch.size, dtype=np.int64)
    for nodes in scratch.nodes_by_step()[1:]:
        root[nodes] = root[scratch.parent[nodes]]
    return root


def interpreted_text(derivation: Derivation, sep: str = "") -> str:
    """The interpreted string of a derivation, as text (what the turtle draws)."""
    ls = derivation.lsystem
    scratch, string, _ = interpreted(ls, derivation.tree, derivation.tree.leaves, derivation.constants, derivation.seed)
    return sep.join(ls.module_text(scratch, v) for v in string.tolist())


def interpret_derivation(derivation: Derivation, draw: Callable[[LSystem, DerivationTree, np.ndarray], Skeleton]) -> Skeleton:
    """The :class:`~ramure.lsys.interpretation.turtle.Skeleton` of a derivation drawn through its interpretation rules.

    Leaf ids in the result (segments, organs and any other part with a
    ``leaf_id``) are those of the derivation's own history tree.  The result
    carries no turtle trace, so an edit re-interprets the whole plant.
    """
    ls, tree = derivation.lsystem, derivation.tree
    scratch, string, source = interpreted(ls, tree, tree.leaves, derivation.constants, derivation.seed)
    node_source = np.zeros(scratch.size, np.int64)
    node_source[string] = source
    skeleton = draw(ls, scratch, string)
    _remap(skeleton, node_source)
    skeleton.extra.pop("trace", None)
    skeleton.extra["interpreted"] = len(string)
    return skeleton


def _remap(part, node_source, depth=0) -> None:
    """Replace every ``leaf_id`` array in ``part`` (and the dataclasses it holds) by the source leaf ids."""
    if depth > 2 or not is_dataclass(part):
        return
    for f in fields(part):
        value = getattr(part, f.name)
        if f.name == "leaf_id" and isinstance(value, np.ndarray):
            setattr(part, f.name, node_source[value] if len(value) else value.astype(np.int64))
        elif is_dataclass(value):
            _remap(value, node_source, depth + 1)
    for value in getattr(part, "extra", {}).values():
        _remap(value, node_source, depth + 1)
