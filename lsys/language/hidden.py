"""Hidden constants: the numbers a grammar writes as literals, and its rule probabilities, as knobs.

A grammar that writes ``!(0.06)`` or ``+(70)`` in a successor gives the variant
sweep no ``#define`` to vary, so "thick" or "drooping" had nothing to turn
(issue 35).  Every non-zero numeric literal of a rule's successor arguments,
every axiom argument that is a bare number, and the probability of every
stochastic rule in a group of two or more becomes a *hidden constant*: a key
a parameter combination (:mod:`ramure.lsys.engine.combination`) may set like a
``#define`` name, with the grammar's own number as its default.  Without an
override the plant is exactly the grammar's.

Keys are not identifiers (they start with ``~``), so they never collide
with a ``#define`` name:

- ``~R.M.A.O``: the literal at offset ``O`` of argument ``A`` of successor module
  ``M`` of rule ``R`` (0-based), read by rule ``R`` only;
- ``~wM.A``: argument ``A`` of axiom module ``M``, a bare number (an axiom is
  evaluated once, so it changes only when the whole plant is derived again);
- ``~pR``: the probability of rule ``R``; the group's probabilities are
  renormalised to sum 1 after the override.

:class:`Hidden` says what each knob is in the grammar's own words
(``text(0.066)`` -> ``"!(0.066)"``), for showing what a variant changed.

>>> from ramure.lsys import LSystem
>>> ls = LSystem.from_text("n: 1\\nw: !(0.06)A(1)\\np:\\n .6 A(x) -> F(x*0.5)+(30)A(x)\\n .4 A(x) -> F(x)A(x)")
>>> sorted(ls.hidden)
['~0.0.0.2', '~0.1.0.0', '~p0', '~p1', '~w0.0', '~w1.0']
>>> ls.hidden["~0.1.0.0"].value, ls.hidden["~0.1.0.0"].text(33.0), ls.hidden["~p0"].text(0.75)
(30.0, '+(33) in rule 0 (A(x))', 'probability 0.75 of rule 0 (A(x))')
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..expr import Node

if TYPE_CHECKING:
    from .grammar import Grammar

#: A number as the tokenizer reads one (``1``, ``.5``, ``2.``, ``1e-3``).
_NUMBER = re.compile(r"(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


@dataclass(frozen=True)
class Hidden:
    """One hidden constant: ``key``, the grammar's ``value``, the ``rule`` reading it (None:
    the axiom), its ``kind`` (``"literal"``, ``"axiom"`` or ``"probability"``), and where it is
    written: the module's text and the literal's span in it (``start``, ``end``)."""

    key: str
    value: float
    rule: int | None
    kind: str
    module: str = ""
    start: int = 0
    end: int = 0
    rule_name: str = ""

    def written(self, value: float) -> str:
        """The module as written with ``value`` in place of the literal: ``"+(33)"``;
        for a probability, ``"probability 0.75"``."""
        if self.kind == "probability":
            return f"probability {value:g}"
        return f"{self.module[: self.start]}{value:g}{self.module[self.end :]}"

    def where(self) -> str:
        """``"rule 0 (A(x))"`` or ``"the axiom"``."""
        return "the axiom" if self.rule is None else f"rule {self.rule}" + (f" ({self.rule_name})" if self.rule_name else "")

    def text(self, value: float) -> str:
        """The knob at ``value`` in the grammar's words: ``"+(33) in rule 0 (A(x))"``."""
        return f"{self.written(value)} {'of' if self.kind == 'probability' else 'in'} {self.where()}"


def literal_offsets(node: Node) -> list[tuple[int, float]]:
    """``(offset, value)`` of the non-zero numeric literals of an expression tree, in text order.

    A literal whose offset repeats (a ``#function`` body inlined twice) is left out: its
    offset would not say which one.
    """
    found: list[tuple[int, float]] = []

    def walk(n: Node) -> None:
        if n.kind == "num":
            found.append((n.offset, float(n.value)))  # type: ignore[arg-type]
        for a in n.args:
            walk(a)

    walk(node)
    counts: dict[int, int] = {}
    for offset, _ in found:
        counts[offset] = counts.get(offset, 0) + 1
    return sorted((o, v) for o, v in found if counts[o] == 1 and v != 0)


def _span(module_text: str, arg_texts: list[str], arg: int, offset: int) -> tuple[int, int] | None:
    """Where the literal at ``offset`` of argument ``arg`` lies in the module's text."""
    start = len(module_text.split("(", 1)[0]) + 1 + sum(len(t) + 1 for t in arg_texts[:arg])
    m = _NUMBER.match(module_text, start + offset)
    return None if m is None else (m.start(), m.end())


def grammar_hidden(grammar: Grammar) -> dict[str, Hidden]:
    """Every hidden constant of ``grammar`` (see the module docstring), keyed, in rule order."""
    out: dict[str, Hidden] = {}
    for rule in grammar.rules:
        if rule.blocks is not None:  # cpfg statement blocks compute their own arguments
            continue
        name = str(rule.pred)
        for m, spec in enumerate(rule.successor):
            out.update(_module_hidden(spec, f"~{rule.index}.{m}.", rule.index, name))
    for m, spec in enumerate(grammar.axiom):
        for a, arg in enumerate(spec.args):
            node = getattr(arg, "node", None)
            if node is not None and node.kind == "num" and float(node.value) != 0:
                module, texts = _module_text(spec)
                span = _span(module, texts, a, node.offset)
                if span is not None:
                    key = f"~w{m}.{a}"
                    out[key] = Hidden(key, float(node.value), None, "axiom", module, *span)
    groups: dict[tuple, list] = {}
    for rule in grammar.rules:
        groups.setdefault(rule.group_key(), []).append(rule)
    for members in groups.values():
        if len(members) > 1 and all(r.probability is not None and 0 < r.probability < 1 for r in members):
            for r in members:
                key = f"~p{r.index}"
                out[key] = Hidden(key, float(r.probability), r.index, "probability", rule_name=str(r.pred))
    return out


def _module_text(spec) -> tuple[str, list[str]]:  # noqa: ANN001 - a ModuleSpec
    texts = [a.text for a in spec.args]
    return spec.symbol + (f"({','.join(texts)})" if texts else ""), texts


def _module_hidden(spec, prefix: str, rule: int, rule_name: str) -> dict[str, Hidden]:  # noqa: ANN001
    out = {}
    module, texts = _module_text(spec)
    for a, arg in enumerate(spec.args):
        node = getattr(arg, "node", None)
        if node is None:
            continue
        for offset, value in literal_offsets(node):
            span = _span(module, texts, a, offset)
            if span is None or float(module[span[0] : span[1]]) != value:
                continue  # not written where the tree says (an inlined #function): no knob
            key = f"{prefix}{a}.{offset}"
            out[key] = Hidden(key, value, rule, "literal", module, *span, rule_name=rule_name)
    return out


def literal_keys(hidden: dict[str, Hidden], rule: int, module: int, arg: int) -> dict[int, str]:
    """``{offset: key}`` of the literals of one successor argument (for compiling it)."""
    prefix = f"~{rule}.{module}.{arg}."
    return {int(k[len(prefix) :]): k for k in hidden if k.startswith(prefix)}


def probabilities(members: list[int], probs: list[float], overrides: dict | None) -> list[float] | None:
    """A stochastic group's probabilities with ``overrides`` (``{rule: {key: value}}``)
    applied and renormalised; None when no member's probability is overridden.

    >>> probabilities([3, 4], [0.5, 0.5], {3: {"~p3": 0.75}})
    [0.6, 0.4]
    """
    if not overrides:
        return None
    new = [float(overrides.get(r, {}).get(f"~p{r}", p)) for r, p in zip(members, probs)]
    if new == list(probs):
        return None
    total = sum(max(p, 0.0) for p in new)
    if total <= 0:
        return None
    return [max(p, 0.0) / total for p in new]
