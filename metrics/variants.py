"""The variant design: which constant values each variant uses, on which rule (thesis §6).

Every variant changes the chosen constants ``k`` to ``k (1 + beta * level)``
on **one rule only**; the other rules keep the grammar's values.

``mode="grid"`` (the thesis): levels in {-1, 0, +1} — every combination of
``{k(1-beta), k, k(1+beta)}`` over the m chosen constants, for each rule:
``3^m x N_rules`` variants.  Variant ``i`` applies to rule ``i // 3^m``; within
a rule the combinations run in :func:`itertools.product` order (the first
constant varies slowest, level -1 first).  The all-original combination
appears once per rule, as in the thesis.

``mode="lhs"`` / ``"sobol"`` (for large m): ``n_samples`` points per rule from
a Latin hypercube or a scrambled Sobol sequence (:mod:`scipy.stats.qmc`,
seeded), mapped to continuous levels in [-1, 1].  Same rule-major order.

Values are rounded to 12 significant digits, so a combination written to
JSON and read back derives exactly the same plant.

>>> d = variant_design({"r1": 0.9, "r2": 0.7}, n_rules=2)
>>> len(d), d.names, d.values[0].tolist(), d.combination(0)
(18, ('r1', 'r2'), [0.81, 0.63], {'rule': 0, 'constants': {'r1': 0.81, 'r2': 0.63}})
"""

from __future__ import annotations

import collections
import itertools
import warnings
from dataclasses import dataclass

from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import RamureError, ValueRefused
from ramure.lsys.engine.combination import combination

if TYPE_CHECKING:
    from ramure.lsys import LSystem
    from ramure.lsys.language.hidden import Hidden

MODES = ("grid", "lhs", "sobol")
MAX_VARIANTS = 200_000
DEFAULT_SAMPLES = 243


@dataclass(frozen=True)
class VariantDesign:
    """``names`` (m,), and per variant: ``rules`` (N,), ``levels`` (N,m) in [-1, 1], ``values`` (N,m)."""

    names: tuple
    rules: np.ndarray
    levels: np.ndarray
    values: np.ndarray
    beta: float
    mode: str
    #: The hidden constants among ``names`` (:mod:`ramure.lsys.language.hidden`): set only where changed.
    hidden: tuple = ()

    def __len__(self) -> int:
        return len(self.rules)

    def combination(self, i: int) -> dict:
        """Variant ``i`` as a parameter combination ``{"rule", "constants"}`` (:mod:`ramure.lsys.engine.combination`);
        rule -1 (an axiom literal) is ``None``: every rule, the axiom evaluated again."""
        hidden = set(self.hidden)
        values = {
            k: v
            for k, v, level in zip(self.names, self.values[i].tolist(), self.levels[i].tolist())
            if k not in hidden or level != 0
        }
        rule = int(self.rules[i])
        return combination(None if rule < 0 else rule, values)


def rule_constant_names(lsystem: LSystem) -> list[set[str]]:
    """For each rule, the set of constants its condition and successor expressions read,
    with its hidden constants (:mod:`ramure.lsys.language.hidden`: its literals, its probability);
    then one more set: the axiom's hidden constants (read when the plant is derived again).

    A name that is also one of the rule's formal parameters means the parameter.
    """
    from ramure.lsys.expr import names_used

    out: list[set[str]] = []
    for rule in lsystem.grammar.rules:
        exprs = [rule.condition] if rule.condition is not None else []
        exprs += [arg for module in rule.successor for arg in module.args]
        formals = set(rule.formals)
        out.append({name for e in exprs for name, _ in names_used(e) if name not in formals and name in lsystem.constants})
    for key, knob in getattr(lsystem, "hidden", {}).items():
        if knob.rule is not None and knob.rule < len(out):
            out[knob.rule].add(key)
    out.append({key for key, knob in getattr(lsystem, "hidden", {}).items() if knob.rule is None})
    return out


def distinct_variants(design: VariantDesign, used: Sequence[Collection[str]]) -> tuple[np.ndarray, np.ndarray]:
    """Which variants really differ: ``(representative, inverse)``.

    A variant changes constants on one rule only, so constants that rule
    never reads change nothing: two variants of the same rule agreeing on the
    constants it reads derive exactly the same plant, and a variant changing
    none of them *is* the base plant.  ``used`` is :func:`rule_constant_names`.
    Returns the indices of one representative per distinct plant (the first)
    and, per variant, the position of its representative in that list, or -1
    for "the base plant".

    >>> d = variant_design({"a": 1.0, "b": 2.0}, n_rules=2)
    >>> reps, inv = distinct_variants(d, [{"a"}, {"a", "b"}])
    >>> len(reps), int((inv == -1).sum())   # rule 0: 2 plants + base; rule 1: 8 + base
    (10, 4)
    """
    rows = max(int(design.rules.max()) + 1, len(used))
    mask = np.array([[r < len(used) and name in used[r] for name in design.names] for r in range(rows)])
    mask = mask.reshape(rows, len(design.names))
    # rule -1 (axiom literals) reads the last entry of ``used`` (see rule_constant_names)
    relevant = mask[np.where(design.rules < 0, len(used) - 1, design.rules)]
    levels = np.where(relevant, design.levels, 0.0)
    base = ~np.any(levels != 0, axis=1)
    keys = np.column_stack([design.rules, levels])
    inverse = np.full(len(design), -1, np.int64)
    todo = np.flatnonzero(~base)
    if not todo.size:
        return todo, inverse
    _, first, inv = np.unique(keys[todo], axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # representatives in variant order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    inverse[todo] = rank[inv.reshape(-1)]
    return todo[np.sort(first)], inverse


def round12(values: ArrayLike) -> np.ndarray:
    """Round to 12 significant digits (``0.9 * 1.1 -> 0.99``)."""
    values = np.asarray(values, float)
    return np.array([float(f"{v:.12g}") for v in values.ravel()]).reshape(values.shape)


def choose_constants(constants: Mapping[str, float], names: str | Iterable[str] | None = None) -> tuple[str, ...]:
    """The constants to vary: ``names`` (validated) or every constant whose value is not 0.

    A constant equal to 0 cannot be varied by a percentage, so it is skipped by
    default and refused when named.
    """
    if names is None:
        chosen = tuple(k for k, v in constants.items() if v != 0)
        if not chosen:
            raise RamureError(
                "the grammar has no non-zero #define constant to vary; add #define lines or pass constants explicitly"
            )
        return chosen
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    names = tuple(names)
    if not names:
        raise RamureError("choose at least one constant to vary")
    unknown = [k for k in names if k not in constants]
    if unknown:
        raise RamureError(f"unknown constant(s) {', '.join(unknown)}: the grammar defines {', '.join(constants) or 'none'}")
    if len(set(names)) != len(names):
        raise RamureError(f"a constant is named twice in {', '.join(names)}")
    zero = [k for k in names if constants[k] == 0]
    if zero:
        raise RamureError(f"constant(s) {', '.join(zero)} equal 0 and cannot be varied by a percentage")
    return names


def check_beta(beta: float) -> float:
    try:
        beta = float(beta)
    except (TypeError, ValueError):
        raise ValueRefused(f"beta must be a number, not {beta!r}") from None
    if not 0 < beta < 1:
        raise ValueRefused(f"beta must be in (0, 1) (a fraction, e.g. 0.1 for +-10 %), not {beta}")
    return beta


def variant_design(
    constants: Mapping[str, float],
    n_rules: int,
    names: str | Iterable[str] | None = None,
    beta: float = 0.1,
    mode: str = "grid",
    n_samples: int | None = None,
    seed: int = 0,
    wide: float | None = None,
    hidden: Mapping[str, tuple[float, int | None]] | None = None,
) -> VariantDesign:
    """All variants of a grammar with ``constants`` (dict) and ``n_rules`` rules (see module doc).

    ``wide`` (e.g. 0.25) adds, per rule, ``2 m`` variants that change one constant at a
    time by ``+-wide``: a larger step for grammars where ``+-beta`` moves too little
    (levels ``+-wide / beta``, beyond [-1, 1]).

    ``hidden`` (``{key: (value, rule or None)}``, :mod:`ramure.lsys.language.hidden`) adds, after
    the constants' variants, each hidden constant alone at ``+-beta`` (and ``+-wide``) on
    its own rule (rule -1 for the axiom's), then each set of literals of one rule that
    write the same number, all together: the grammar's ``w*0.6`` four times becomes one knob
    as well as four.  A grammar with hidden constants needs no ``#define``.

    >>> d = variant_design({}, n_rules=2, hidden={"~0.1.0.0": (30.0, 0), "~0.3.0.0": (30.0, 0), "~w0.0": (0.06, None)})
    >>> len(d), d.rules.tolist(), d.combination(6)
    (8, [0, 0, 0, 0, -1, -1, 0, 0], {'rule': 0, 'constants': {'~0.1.0.0': 27.0, '~0.3.0.0': 27.0}})

    >>> d = variant_design({"r1": 0.9, "r2": 0.7}, n_rules=1, wide=0.25)
    >>> len(d), d.values[-4:].tolist()
    (13, [[0.675, 0.7], [1.125, 0.7], [0.9, 0.525], [0.9, 0.875]])
    """
    beta = check_beta(beta)
    if mode not in MODES:
        raise RamureError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
    if int(n_rules) < 1:
        raise RamureError("the grammar has no production rule to vary")
    no_constant = names is None and not any(v != 0 for v in constants.values())
    if hidden is not None and not hidden and no_constant:
        raise RamureError(
            "the grammar has no non-zero #define constant, numeric literal or rule probability to vary: "
            "its modules carry no numbers (add #define lines or parameters)"
        )
    hidden = dict(hidden or {})
    if hidden and no_constant:
        names = ()  # only hidden constants to vary
    else:
        names = choose_constants(constants, names)
    m = len(names)
    if m == 0:
        levels = np.zeros((0, 0))
    elif mode == "grid":
        per_rule = 3**m
        if per_rule * n_rules > MAX_VARIANTS:
            raise ValueRefused(
                f"a full grid of {m} constants gives 3^{m} x {n_rules} = "
                f"{per_rule * n_rules:,} variants (limit {MAX_VARIANTS:,}); choose "
                f"fewer constants or use mode 'lhs' or 'sobol' with n_samples"
            )
        if n_samples is not None:
            raise RamureError("n_samples only applies to modes 'lhs' and 'sobol'")
        levels = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=m)), float).reshape(-1, m)
    else:
        n_samples = DEFAULT_SAMPLES if n_samples is None else n_samples
        if isinstance(n_samples, bool) or int(n_samples) != n_samples or n_samples < 1:
            raise ValueRefused(f"n_samples must be a positive integer, not {n_samples!r}")
        if int(n_samples) * n_rules > MAX_VARIANTS:
            raise ValueRefused(f"{n_samples} samples x {n_rules} rules exceeds {MAX_VARIANTS:,} variants")
        levels = 2.0 * _unit_samples(mode, m, int(n_samples), seed) - 1.0
    steps = [-1.0, 1.0]
    if wide is not None:
        levels = np.vstack([levels, _one_at_a_time(m, check_beta(wide) / beta)])
        steps += [-check_beta(wide) / beta, check_beta(wide) / beta]
    rules = np.repeat(np.arange(n_rules), len(levels))
    levels = np.tile(levels, (n_rules, 1))
    keys = tuple(hidden)
    extra_rules, extra_levels = _hidden_rows(hidden, keys, steps)
    all_levels = np.zeros((len(levels) + len(extra_levels), m + len(keys)))
    all_levels[: len(levels), :m] = levels
    all_levels[len(levels) :, m:] = extra_levels
    base = np.array([constants[k] for k in names] + [hidden[k][0] for k in keys], float)
    values = round12(base * (1.0 + beta * all_levels))
    all_rules = np.concatenate([rules, extra_rules]).astype(np.int64)
    return VariantDesign(tuple(names) + keys, all_rules, all_levels, values, beta, mode, keys)


def _hidden_rows(hidden, keys, steps):
    """Rules (k,) and levels (k, h) of the hidden constants' variants: each alone, then each
    set of one rule's literals writing the same number together (see :func:`variant_design`)."""
    sets = [[j] for j in range(len(keys))]
    same: dict[tuple, list[int]] = {}
    for j, key in enumerate(keys):
        value, rule = hidden[key]
        if not key.startswith(("~p", "~w")):  # literals of one rule writing the same number
            same.setdefault((rule, float(value)), []).append(j)
    sets += [js for js in same.values() if len(js) > 1]
    rules, levels = [], np.zeros((len(sets) * len(steps), len(keys)))
    for s, js in enumerate(sets):
        rule = hidden[keys[js[0]]][1]
        for t, step in enumerate(steps):
            levels[s * len(steps) + t, js] = step
            rules.append(-1 if rule is None else int(rule))
    return np.array(rules, np.int64), levels


def _one_at_a_time(m, level):
    """(2m, m) levels: each constant alone at ``-level`` then ``+level``."""
    out = np.zeros((2 * m, m))
    out[0::2][np.arange(m), np.arange(m)] = -level
    out[1::2][np.arange(m), np.arange(m)] = level
    return out


def describe_variant(
    design: VariantDesign,
    i: int,
    base: Mapping[str, float],
    rule_names: Sequence[str] = (),
    hidden: Mapping[str, Hidden] | None = None,
) -> dict:
    """What variant ``i`` changed: ``{"rule", "predecessor", "constants": {name: [before, after]},
    "written": [...], "text"}``.

    Only the constants whose value differs from ``base`` are listed; ``rule_names`` (the
    rules' predecessors) names the rule in ``text``, e.g. ``"rule 0 (S): ls 0.8 -> 0.88"``.
    A hidden constant (``hidden``: the grammar's :attr:`~ramure.lsys.LSystem.hidden`) is
    shown as written in the grammar, ``"rule 1 (L(l)): +(40) -> +(44)"``; literals changed
    together and written alike are shown once with their count; ``written`` lists those texts.

    >>> d = variant_design({"a": 10.0, "b": 2.0}, n_rules=2)
    >>> describe_variant(d, 10, {"a": 10.0, "b": 2.0}, ["A", "B"])["text"]
    'rule 1 (B): a 10 -> 9'
    """
    hidden = dict(hidden or {})
    rule = int(design.rules[i])
    before = {**{k: h.value for k, h in hidden.items()}, **base}
    changed = {
        k: [float(before[k]), float(v)]
        for k, v in zip(design.names, design.values[i].tolist())
        if k in before and float(before[k]) != float(v)
    }
    pred = rule_names[rule] if 0 <= rule < len(rule_names) else None
    head = "the axiom (the plant derived again)" if rule < 0 else f"rule {rule}" + (f" ({pred})" if pred else "")
    plain = [f"{k} {a:g} -> {b:g}" for k, (a, b) in changed.items() if k not in hidden]
    written = [f"{hidden[k].written(a)} -> {hidden[k].written(b)}" for k, (a, b) in changed.items() if k in hidden]
    counts = collections.Counter(written)
    shown = [w if counts[w] == 1 else f"{w} (x{counts[w]})" for w in dict.fromkeys(written)]
    body = ", ".join(plain + shown) or "no constant changed"
    return {
        "rule": None if rule < 0 else rule,
        "predecessor": pred,
        "constants": changed,
        "written": written,
        "text": f"{head}: {body}",
    }


def _unit_samples(mode, m, count, seed):
    from scipy.stats import qmc

    if mode == "lhs":
        return qmc.LatinHypercube(d=m, seed=seed).random(count)
    with warnings.catch_warnings():  # Sobol prefers powers of two; any count is fine here
        warnings.simplefilter("ignore", UserWarning)
        return qmc.Sobol(d=m, scramble=True, seed=seed).random(count)
