"""Apply a qualifier to a selection of a plant being edited (an :class:`ramure.lsys.regen.Session`).

The thesis applies the qualifier's combination to the part of the plant the
min-cut selects.  Two refinements make "make this selection <qualifier>"
dependable on any grammar:

1. **Only rules that act there.**  A combination changes constants on one
   rule; if that rule never rewrites inside the cut subtrees, nothing
   changes.  Candidates are therefore restricted to variants whose rule
   produced a node under the cut roots (for the whole plant: every rule).
2. **Check, then keep.**  The candidates are tried best first (at most
   ``tries``).  Each is applied with ``Session.regrow``; the selection's ten
   metrics are measured before and after (the segments drawn by the leaves
   under the cut roots) and scored along the qualifier's direction
   (:func:`~ramure.metrics.qualifiers.qualifier_scores` with the sweep's scale).
   The first candidate that moves the selection the right way is kept; if
   none does, the best tried is kept and ``improved`` is False.  On a
   stochastic grammar the regrown part is a new random draw, so each
   candidate is also tried with three more seeds (unless ``seed`` is given).  ``normal``
   (no direction) and study regions without a vocabulary direction keep the
   first candidate.

Only one edit stays in the session's history (rejected tries are undone).

>>> from ramure.lsys.regen import Session
>>> from ramure.metrics import VariantSweep
>>> sweep = VariantSweep(n=4, n_jobs=1, cache=False).fit("grammars/honda_sympodial.lsys")
>>> s = Session("grammars/honda_sympodial.lsys", n=4)
>>> out = apply_qualifier(s, "dense", sweep)
>>> out.improved, out.after.branch_density > out.before.branch_density, len(s.edits)
(True, True, 1)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ramure.lsys.cut import collapse_nested

from .plant import PlantMetrics, metric_deltas, plant_metrics
from .qualifiers import VOCABULARY, canonical_name, metric_scale, qualifier_scores, ranked_variants


@dataclass
class QualifierResult:
    """What :func:`apply_qualifier` did."""

    qualifier: str
    variant: int
    params: dict
    source: str  # "vocabulary" or "region"
    roots: np.ndarray
    before: PlantMetrics
    after: PlantMetrics
    score: float  # along the qualifier's direction (NaN without one)
    improved: bool
    tried: int
    regen: object
    seed: int | None = None  # the regrow seed given (None: the session's next seed)

    def to_dict(self) -> dict:
        return {"qualifier": self.qualifier, "variant": int(self.variant), "params": self.params,
                "source": self.source, "roots": self.roots.tolist(), "before": self.before.to_dict(),
                "after": self.after.to_dict(), "score": None if np.isnan(self.score) else float(self.score),
                "improved": bool(self.improved), "tried": self.tried,
                "regen": self.regen.to_dict() if self.regen is not None else None}


def _roots(session, selection, rho):
    """The subtrees a regrow of ``selection`` replaces (as :func:`ramure.lsys.regen.regenerate` keeps them)."""
    tree = session.tree
    if not len(selection):  # the whole plant: every axiom module, as Session.regrow does
        return np.flatnonzero((tree.parent == -1) & tree.alive)
    roots = collapse_nested(tree, session.plan(selection, rho)[1])
    return roots[tree.child_count[roots] > 0]


def active_rules(tree, roots) -> set:
    """Indices of the rules that produced a node under ``roots``."""
    if not len(roots):
        return set()
    nodes = np.concatenate([tree.subtree(int(r)) for r in roots])
    return set(np.unique(tree.rule[nodes][tree.rule[nodes] >= 0]).tolist())


def roots_metrics(session, roots) -> PlantMetrics:
    """The ten metrics of the segments drawn by the current leaves under ``roots``."""
    tree = session.tree
    leaves = [tree.leaves_under(int(r)) for r in roots]
    leaves = np.concatenate(leaves) if leaves else np.zeros(0, np.int64)
    return plant_metrics(session.derivation.skeleton(), leaf_ids=leaves)


def _stochastic(lsystem):
    return any(r.probability is not None for r in lsystem.grammar.rules)


def _attempts(session, order, tries, seed, seeds_per_candidate=4):
    """(variant, seed) pairs to try: the ``tries`` best variants; on a stochastic grammar
    (without an explicit ``seed``) each with the session's next seed and a few more."""
    seeds = [seed]
    if seed is None and _stochastic(session.lsystem):
        rng = np.random.default_rng([session.seed, len(session.edits)])
        seeds += rng.integers(0, 2**31 - 1, size=seeds_per_candidate - 1).tolist()
    return [(v, s) for v in order[:max(int(tries), 1)].tolist() for s in seeds]


def apply_qualifier(session, name, sweep, selection=(), rho=0.5, points=None, regions=None, tries=5,
                    seed=None) -> QualifierResult:
    """Regrow ``selection`` (leaf ids; empty = whole plant) of ``session`` toward qualifier ``name``.

    ``sweep`` is a fitted :class:`~ramure.metrics.sweep.VariantSweep` of the same
    grammar; with ``regions`` (e.g. from a study) and the sweep's PCA cloud
    ``points``, the region's centre chooses the candidates instead of the
    default direction.  See the module docstring for the procedure.
    """
    key = canonical_name(name)
    selection = [int(x) for x in selection]
    roots = _roots(session, selection, rho)
    rules = active_rules(session.tree, roots) if len(selection) else None
    order, source = ranked_variants(key, sweep, points, regions, rules)
    before = roots_metrics(session, roots)
    direction = VOCABULARY.get(key)
    checks = direction is not None and direction.direction is not None
    scale = metric_scale(sweep) if checks else None
    best = None
    tried = 0
    for variant, try_seed in _attempts(session, order, tries, seed):
        tried += 1
        params = sweep.combination(variant)
        regen = session.regrow(selection, rho=rho, seed=try_seed, params=params)
        after = roots_metrics(session, regen.roots)
        score = float("nan")
        if checks:
            delta = metric_deltas(np.array(after, float), np.array(before, float))
            score = float(qualifier_scores(key, delta[None], scale)[0])
        result = QualifierResult(key, variant, params, source, regen.roots, before, after, score,
                                 checks and score > 0, tried, regen, try_seed)
        if not checks or result.improved:
            return result
        if best is None or score > best.score:
            best = result
        session.undo()
    # nothing improved: keep the best candidate tried
    regen = session.regrow(selection, rho=rho, seed=best.seed, params=best.params)
    best.regen, best.tried = regen, tried
    best.after = roots_metrics(session, regen.roots)
    return best
