"""Apply a qualifier to a selection of a plant being edited (an :class:`ramure.lsys.regeneration.regen.Session`).

The thesis applies the qualifier's combination to the part of the plant the
min-cut selects.  Here the choice is checked, not assumed:

1. **Rules that read the varied constants.**  A combination changes
   constants on one rule; candidates are the variants whose rule rewrites
   inside the regrown subtrees (for the whole plant: every rule) and
   changes a constant that rule reads, ranked by
   :meth:`~ramure.metrics.qualifiers.QualifierModel.rank` (variants the
   qualifier owns on the whole plant first).
2. **The selection's part only, unless asked to climb.**  On a selection
   the qualifier regrows exactly the part a Regrow would (the cut the
   front ends preview): 3 selected tips never replace the whole plant.
   When that part cannot move (its rules read none of the varied
   constants, typically a few tips whose last step only copies
   parameters, or no candidate changes it) the result says so and why,
   and the plant stays as it was.  Only with ``max_climb`` > 0 does the
   regrowth climb: the cut's minimum ascension grows one level at a time
   (``min_ascend`` 1, 2, ... ``max_climb`` + 1) until a rule that reads
   them is regrown and the part changes; ``climbed`` says how many levels
   above the default.  (Climbing by default replaced the whole plant for
   7 of 22 qualifiers on 3 tips of a conifer, issue 34.)
   A part can answer a constant the other way from the whole plant, so
   when every candidate moves it the wrong way the antonym's best
   candidates are tried at the same level.  If they fail too, it climbs on
   too, for at most :data:`MAX_WRONG_WAY_LEVELS` such levels (a larger part
   regrown is a larger change).  A grammar none of whose variants moves the
   qualifier's metrics forward is refused at once, with the reason.
3. **Measure, then keep only a dominant try.**  Each candidate is applied
   with ``Session.regrow``; the fifteen qualifier metrics of the regrown
   part are measured before and after and scored along every qualifier's
   direction, in the unit of :class:`~ramure.metrics.qualifiers.QualifierModel`'s
   scores: each metric's change relative to its value before, divided by
   that metric's spread over the sweep, projected on each qualifier's
   direction, divided by the spread of that qualifier's scores over the
   sweep (so one qualifier's move compares with another's; values within
   1e-6 of the base plant's value of 0 count as 0, and scores below
   :data:`MIN_MOVE` as no move).  A try moves its qualifier forward only
   when the qualifier's definition holds on the measured part (the metric
   it promises moves its way, :mod:`ramure.metrics.definitions`).  A try is
   kept at once when it moves its own qualifier forward *and* no other
   qualifier (its antonym aside, and only qualifiers whose own definition
   the change keeps) more.
   At the first level the first ``tries`` candidates are tried, then the
   set widens (up to :data:`WIDEN` times ``tries``) while tries move
   forward without dominating; each level above tries ``tries`` (a higher
   level widens the set by regrowing more rules); after
   :data:`MAX_CROWDED_LEVELS` such levels it goes to the whole plant, when
   ``max_climb`` reaches the plant's ``n`` (where a variant the qualifier
   owns is dominant, the sweep having measured it so: ``climbed`` then says
   the selection grew to the whole plant).  A grammar where no variant is
   dominant for the qualifier on the whole plant (it owns none) is refused
   at once, saying which qualifiers move more.  When no try anywhere is
   dominant (or :data:`BUDGET` regrowths are spent), the plant is left as
   it was (no edit, ``regen`` None) and the result has ``improved`` False,
   a ``reason``, and a ``suggestion`` — unless some try kept the
   qualifier's definition: the best such try is then applied, with
   ``dominant`` False and the ``rival`` that moved more named.
4. **One derivation step more or less** (whole plant only).  When no
   variant serves the qualifier (no constant changes the number of
   segments, say), ``n + 1`` then ``n - 1`` are tried
   (:meth:`~ramure.lsys.regeneration.regen.Session.set_steps`), alone and with the
   variants that score the qualifier highest; ``changed`` records it.  A
   refusal names what the grammar lacks ("no constant or rule changes the
   branch radii").
   On a stochastic grammar each candidate is also tried with three more
   seeds (unless ``seed`` is given).  ``normal`` (no direction) keeps its
   first candidate: the combination closest to the base plant.

At most one edit stays in the session's history (rejected tries are undone).

>>> from ramure.lsys.regeneration.regen import Session
>>> from ramure.metrics import VariantSweep
>>> sweep = VariantSweep(n=4, n_jobs=1, cache=False).fit("honda_sympodial")
>>> s = Session("honda_sympodial", n=4)
>>> out = apply_qualifier(s, "tall", sweep)
>>> out.improved, out.own["height"]["after"] > out.own["height"]["before"], len(s.edits)
(True, True, 1)
"""

from __future__ import annotations

import collections
import contextlib
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import RamureError
from ramure.lsys.regeneration.mincut import check_rho, collapse_nested
from ramure.lsys.regeneration.regen import MAX_STEPS

from .definitions import DEFINITIONS, definition_holds, lacks, metric_change, metric_changes, metric_value
from .plant import PlantMetrics, plant_metrics
from .qualifiers import QUALIFIER_METRICS, VOCABULARY, QualifierModel, all_deltas, canonical_name
from .shape import ShapeMetrics, plant_shape
from .variants import rule_constant_names

if TYPE_CHECKING:
    from ramure.lsys import LSystem, RegenResult, Session
    from ramure.lsys.history.tree import DerivationTree

    from .qualifiers import QualifierRegions
    from .sweep import VariantSweep


class QualifierMetrics(collections.namedtuple("QualifierMetrics", QUALIFIER_METRICS)):  # type: ignore[misc]
    """The fifteen qualifier metrics of a part of the plant: the ten metrics (as in
    :class:`~ramure.metrics.plant.PlantMetrics`, same names) then the five shape metrics."""

    __slots__ = ()

    def to_dict(self) -> dict:
        return {k: (int(v) if k == "branch_count" else float(v)) for k, v in self._asdict().items()}


@dataclass
class QualifierResult:
    """What :func:`apply_qualifier` did.

    ``own`` gives, for each of the qualifier's own metrics, ``before``,
    ``after`` and the ``direction`` (+1/-1) it should move; ``moves`` the
    score of the change along every qualifier; ``climbed`` the levels
    climbed above the default ascension (``min_ascend``); ``reason`` and
    ``suggestion`` explain a result that is not ``improved``; ``changed`` what the
    variant changed (rule and constants, with a ``text`` to show); ``definition`` the
    qualifier's defining metrics (:mod:`ramure.metrics.definitions`) before and after.
    """

    qualifier: str
    variant: int
    params: dict
    source: str  # "vocabulary", "region" or "transfer"
    roots: np.ndarray
    before: QualifierMetrics  # the ten metrics and the five shape metrics, by name
    after: QualifierMetrics
    score: float  # along the qualifier's direction (NaN without one)
    improved: bool
    tried: int
    regen: RegenResult | None
    seed: int | None = None  # the regrow seed given (None: the session's next seed)
    before_shape: ShapeMetrics | None = None
    after_shape: ShapeMetrics | None = None
    own: dict = field(default_factory=dict)
    moves: dict = field(default_factory=dict)
    dominant: bool = True
    rival: str | None = None
    min_ascend: int = 1
    climbed: int = 0
    reason: str | None = None
    suggestion: str | None = None
    changed: dict | None = None  # what the variant changed (VariantSweep.describe): rule, constants, text
    definition: dict | None = None  # the qualifier's defining metrics before/after and whether they held

    def to_dict(self) -> dict:
        return {
            "qualifier": self.qualifier,
            "variant": int(self.variant),
            "params": self.params,
            "source": self.source,
            "roots": self.roots.tolist(),
            "before": self.before.to_dict(),
            "after": self.after.to_dict(),
            "before_shape": self.before_shape.to_dict() if self.before_shape else None,
            "after_shape": self.after_shape.to_dict() if self.after_shape else None,
            "own": self.own,
            "score": None if np.isnan(self.score) else float(self.score),
            "improved": bool(self.improved),
            "dominant": bool(self.dominant),
            "rival": self.rival,
            "moves": {k: round(v, 6) for k, v in self.moves.items()},
            "min_ascend": self.min_ascend,
            "climbed": self.climbed,
            "reason": self.reason,
            "suggestion": self.suggestion,
            "tried": self.tried,
            "changed": self.changed,
            "definition": self.definition,
            "regen": self.regen.to_dict() if self.regen is not None else None,
        }


def _roots(session, selection, rho, min_ascend=1):
    """The subtrees a regrow of ``selection`` replaces (as :func:`ramure.lsys.regeneration.regen.regenerate` keeps them)."""
    tree = session.tree
    if not len(selection):  # the whole plant: every axiom module, as Session.regrow does
        return np.flatnonzero((tree.parent == -1) & tree.alive)
    roots = collapse_nested(tree, session.plan(selection, rho, min_ascend=min_ascend)[1])
    return roots[tree.child_count[roots] > 0]


def active_rules(tree: DerivationTree, roots: np.ndarray) -> set[int]:
    """Indices of the rules a regrowth of ``roots`` applies: those that produced a node below them."""
    if not len(roots):
        return set()
    nodes = np.concatenate([tree.subtree(int(r)) for r in roots])
    nodes = nodes[~np.isin(nodes, roots)]
    rules = tree.rule[nodes]
    return set(np.unique(rules[rules >= 0]).tolist())


def reading_rules(lsystem: LSystem, rules: Iterable[int], names: Collection[str]) -> set[int]:
    """The rules among ``rules`` that read at least one of the constants ``names``."""
    used = rule_constant_names(lsystem)
    return {r for r in rules if r < len(used) and used[r] & set(names)}


def roots_metrics(session: Session, roots: Iterable[int]) -> PlantMetrics:
    """The ten metrics of the segments drawn by the current leaves under ``roots``."""
    return plant_metrics(session.derivation.skeleton(), leaf_ids=_leaves(session, roots))


def _leaves(session, roots):
    tree = session.tree
    leaves = [tree.leaves_under(int(r)) for r in roots]
    return np.concatenate(leaves) if leaves else np.zeros(0, np.int64)


def _measure(session, roots):
    """``(QualifierMetrics, ShapeMetrics, (15,) vector)`` of the part under ``roots``."""
    sk = session.derivation.skeleton()
    leaves = _leaves(session, roots)
    m, s = plant_metrics(sk, leaf_ids=leaves), plant_shape(sk, leaf_ids=leaves)
    vector = np.concatenate([np.array(m, float), np.array(s, float)])
    return QualifierMetrics._make([*m, *s]), s, vector


def _stochastic(lsystem):
    return any(r.probability is not None for r in lsystem.grammar.rules)


def _seeds(session, seed, seeds_per_candidate=4):
    """Seeds to try each candidate with: the given one (or the session's next); on a stochastic
    grammar without an explicit ``seed``, a few more."""
    seeds = [seed]
    if seed is None and _stochastic(session.lsystem):
        rng = np.random.default_rng([session.seed, len(session.edits)])
        seeds += rng.integers(0, 2**31 - 1, size=seeds_per_candidate - 1).tolist()
    return seeds


def _own(key, before, after):
    q = VOCABULARY.get(key)
    if q is None or q.direction is None:
        return {}
    idx = {m: i for i, m in enumerate(QUALIFIER_METRICS)}
    return {
        m: {"before": float(before[idx[m]]), "after": float(after[idx[m]]), "direction": 1 if q.direction[m] > 0 else -1}
        for m in q.metrics()
    }


#: Levels climbed past the first where candidates moved the part the wrong way before giving up.
MAX_WRONG_WAY_LEVELS = 3
#: At the first level tried and on the whole plant, the candidate set widens up to this many
#: times ``tries`` while no try is dominant (higher levels widen it by reading more rules).
WIDEN = 3
#: Levels where tries moved forward without dominating before jumping to the whole plant.
MAX_CROWDED_LEVELS = 4
#: A score below this (in standard deviations of the sweep) is rounding noise, not a move.
MIN_MOVE = 1e-6
#: Regrowths one call may try in all (over every level) before reporting that none was dominant.
BUDGET = 60


@dataclass
class _Try:
    level: int
    variant: int
    seed: int | None
    params: dict
    score: float
    dominant: bool
    rival: str | None
    moves: dict
    changed: bool
    kind: str = "cut"  # "cut": the selection's cut at ``level``; "whole": the plant, climbing; "steps": n +- 1;
    # "part-steps": the selection's part one derivation step more or less


def _snap(values, floor):
    """Values within ``floor`` of 0 set to 0: a part whose angles all agree has an angle
    spread of 1e-14, not a value a relative change should divide by."""
    values = np.asarray(values, float)
    return np.where(np.abs(values) <= floor, 0.0, values)


def noise_floor(sweep: VariantSweep) -> np.ndarray:
    """(15,) per-metric noise floor: 1e-6 of the base plant's value (1e-12 where that is 0)."""
    base = np.concatenate(
        [
            np.asarray(getattr(sweep, "base_metrics_", np.zeros(10)), float),
            np.asarray(getattr(sweep, "base_shape_metrics_", np.zeros(5)), float),
        ]
    )
    return np.where(base != 0, 1e-6 * np.abs(base), 1e-12)


def _judge(model, key, before, after, antonym, floor: float | np.ndarray = 0.0):
    """Score a measured change along every qualifier; is ``key`` dominant, and who moved more.

    The normalisation that makes "more" comparable (documented in the
    module docstring): the change of each of the fifteen metrics, relative
    to its value before (as the sweep's deltas), divided by the standard
    deviation of that metric's change over the sweep's variants; each
    qualifier's move is that vector projected on its unit direction.  The
    antonym is no rival (its move is exactly minus ``key``'s).
    """
    deltas = all_deltas(_snap(after, floor), _snap(before, floor))
    moves = model.move_scores(deltas)
    own = moves.get(key, float("nan"))
    defined = key in DEFINITIONS and model.sources_.get(key) != "region"
    if abs(own) < MIN_MOVE or (defined and not definition_holds(key, deltas)):
        own = min(own, 0.0)  # rounding noise, or the metric it promises did not move its way: no move
    # a rival is a qualifier whose own definition this change keeps, and that it moves more
    rivals = {k: v for k, v in moves.items() if k not in (key, antonym) and (k not in DEFINITIONS or definition_holds(k, deltas))}
    rival = max(rivals, key=rivals.__getitem__) if rivals else None
    dominant = rival is None or own >= rivals[rival]
    return own, dominant, (None if dominant else rival), moves


def _try_level(session, model, sweep, key, selection, rho, level, order, tries, seed, before, rules=None, budget=None, widen=1):
    """Try candidates at one ascension level until one is dominant for ``key``.

    Returns ``(tries, accepted, regen)``: every try is undone except the
    accepted one (None when no try was dominant).  The first ``tries``
    candidates of ``order`` are tried, then the candidate set widens to the
    next ones (at most ``widen`` times ``tries`` in all) while some try
    moved ``key`` forward without being dominant.  A part of the plant can
    answer a constant the other way from the whole plant (a sub-branch's
    asymmetry may fall where the plant's rises): when every candidate moved
    the part the wrong way, the antonym's best candidates are tried too.
    ``budget`` caps the number of regrowths.
    """
    antonym = VOCABULARY[key].antonym if key in VOCABULARY else None
    floor = noise_floor(sweep)
    step = max(int(tries), 1)
    out: list[_Try] = []
    queue, rest = order[:step].tolist(), order[step : max(int(widen), 1) * step].tolist()
    mirrored = False
    while queue:
        variant = queue.pop(0)
        params = sweep.combination(int(variant))
        for try_seed in _seeds(session, seed):
            if budget is not None and len(out) >= budget:
                return out, None, None
            regen = _regrow(session, selection, rho, try_seed, params, level)
            after = _measure(session, _regrown(session, regen, rho))[2]
            own, dominant, rival, moves = _judge(model, key, before, after, antonym, floor)
            t = _Try(
                level,
                variant,
                try_seed,
                params,
                own,
                dominant,
                rival,
                moves,
                not np.allclose(after, before, rtol=1e-9, atol=1e-12),
            )
            out.append(t)
            if own > 0 and dominant:
                return out, t, regen
            session.undo()
        if queue:
            continue
        if rest and any(t.score > 0 for t in out):  # forward but not dominant: widen
            queue, rest = rest[:step], rest[step:]
        elif not mirrored and antonym in model.names_ and all(t.changed and t.score < 0 for t in out):
            mirrored = True
            tried = {t.variant for t in out}
            mirror = [v for v in model.rank(antonym, rules=rules).tolist() if v not in tried]
            queue = mirror[:step]
    return out, None, None


def apply_qualifier(
    session: Session,
    name: str,
    sweep: VariantSweep,
    selection: Iterable[int] = (),
    rho: float = 0.5,
    points: ArrayLike | None = None,
    regions: QualifierRegions | None = None,
    tries: int = 5,
    seed: int | None = None,
    directions: Mapping[str, Mapping[str, float]] | None = None,
    max_climb: int | None = None,
) -> QualifierResult:
    """Regrow ``selection`` (leaf ids; empty = whole plant) of ``session`` toward qualifier ``name``.

    ``sweep`` is a fitted :class:`~ramure.metrics.sweep.VariantSweep` of the same
    grammar; ``regions`` (a study's, with the sweep's PCA cloud ``points``)
    refine the directions; ``directions`` (``{qualifier: {metric: weight}}``,
    e.g. learnt on another grammar) replace them.  ``max_climb`` bounds the
    extra ascension levels above the selection's cut (default 0: the part a
    Regrow of the selection would change, nothing more; ``session.n`` or more
    lets it climb to the whole plant).  See the module docstring.
    """
    rho = check_rho(rho)  # at the door: a whole-plant refusal may never reach the cut that checks it
    model = QualifierModel(directions=directions, regions=regions).fit(sweep, points=points)
    n_before = session.n
    with _same_cut(session):
        out = _apply(session, canonical_name(name), model, sweep, [int(x) for x in selection], rho, tries, seed, max_climb)
    if "steps" in out.params:  # the selection's part, one derivation step more or less
        n_part = n_before + out.params["steps"]
        out.changed = {"steps": out.params["steps"], "text": f"n {n_before} -> {n_part} inside the selection"}
        if out.variant >= 0 and hasattr(sweep, "describe"):
            also = sweep.describe(out.variant)
            out.changed = {**also, **out.changed, "text": f"{out.changed['text']}; {also['text']}"}
    elif "n" in out.params:  # a derivation count, alone or with a sweep variant
        out.changed = {"n": [n_before, out.params["n"]], "text": f"n {n_before} -> {out.params['n']}"}
        if out.variant >= 0 and hasattr(sweep, "describe"):
            also = sweep.describe(out.variant)
            out.changed = {**also, **out.changed, "text": f"{out.changed['text']}; {also['text']}"}
    elif out.variant >= 0 and hasattr(sweep, "describe"):
        out.changed = sweep.describe(out.variant)
    out.definition = definition_record(out.qualifier, out.before, out.after)
    return out


def definition_record(name: str, before: ArrayLike, after: ArrayLike) -> dict | None:
    """``{"definition", "terms": [{metric, sign, before, after}], "holds"}`` of qualifier ``name``
    for the fifteen metrics ``before`` and ``after`` (None for a word without a definition)."""
    if name not in DEFINITIONS:
        return None
    b, a = np.asarray(before, float), np.asarray(after, float)
    terms = [
        {"metric": m, "sign": sign, "before": float(metric_value(m, b)), "after": float(metric_value(m, a))}
        for m, sign in DEFINITIONS[name].terms()
    ]
    holds = bool(definition_holds(name, metric_changes(a, b)))
    return {"definition": DEFINITIONS[name].describe(), "terms": terms, "holds": holds}


@contextlib.contextmanager
def _same_cut(session):
    """Solve each min-cut once while trying candidates.

    Every try starts from the same plant (rejected tries are undone), so the
    cut of (selection, rho, min_ascend) cannot change between tries; the
    session's :meth:`~ramure.lsys.regeneration.regen.Session.plan` is memoised for the
    duration of one :func:`apply_qualifier` call, then restored.
    """
    plan, memo = session.plan, {}

    def cached(selection, rho: float = 0.5, min_ascend=1, ascend_levels=None, flow_func=None, whole_branches=False):
        key = (tuple(int(x) for x in selection), float(rho), int(min_ascend), ascend_levels, flow_func, whole_branches)
        if key not in memo:
            memo[key] = plan(selection, rho, min_ascend, ascend_levels, flow_func, whole_branches=whole_branches)
        return memo[key]

    session.plan = cached
    try:
        yield
    finally:
        del session.plan


def _unreachable(model, key, base=None):
    """Why no variant of this grammar can be applied for ``key`` (None when one can).

    A variant can be applied when it moves ``key`` forward more than any
    other qualifier on the whole plant (``key`` *owns* it).  When none does,
    no regrowth of a part is likely to, and none of the whole plant can.
    """
    q = model.index(key)
    s = model.scores_[:, q]
    forward = model.usable_ & np.isfinite(s) & (s > MIN_MOVE) & model.holds_[:, q]
    weights = model.direction(key)
    own = ", ".join(sorted(weights, key=lambda m: -abs(weights[m]))[:4])
    if not np.any(forward):
        if key in DEFINITIONS and model.sources_.get(key) != "region":
            deltas = model.deltas_[model.usable_]
            why = lacks(key, deltas, base)
            where = "" if why.startswith("the plant") else "in this grammar "
            return f"{key} {DEFINITIONS[key].sentence()}, but {where}{why}"
        return f"no variant of this grammar moves {key}'s metrics ({own}) its way: the varied constants do not reach them"
    return None


def _apply(session, key, model, sweep, selection, rho, tries, seed, max_climb):
    source = model.sources_.get(key, "vocabulary")
    if key == "normal" or key not in model.names_:
        return _apply_first(session, model, sweep, key, selection, rho, seed, source)
    varied = list(getattr(sweep, "names_", []))
    base = None
    if hasattr(sweep, "base_shape_metrics_"):
        base = np.concatenate([sweep.base_metrics_, sweep.base_shape_metrics_])
    unreachable = _unreachable(model, key, base)
    if unreachable:  # no constant can: one derivation step more or less may
        if not selection:
            stepped, tries_n = _try_steps(session, model, sweep, key, source, 0, tries)
        else:  # inside the selection only: the rest of the plant stays as it is
            stepped, tries_n = _try_part_steps(session, model, sweep, key, source, selection, rho, seed, tries, 0)
        kept = stepped or _best_held(session, key, source, tries_n, selection, rho)
        if kept is not None:
            return kept
        if tries_n or not selection:
            unreachable += f"; {_steps_reason(key, tries_n, bool(selection))}"
        return _not_improved(session, model, key, source, selection, rho, [], [unreachable], varied)
    climb = 0 if max_climb is None else max(int(max_climb), 0)
    top = 1 + climb
    levels = [1] if not selection else range(1, top + 1)
    tried: list[_Try] = []
    last_roots: np.ndarray | None = None
    reasons: list[str] = []
    wrong_way = crowded = 0
    for level in levels:
        roots = _roots(session, selection, rho, level)
        if last_roots is not None and np.array_equal(roots, last_roots):
            continue
        last_roots = roots
        rules: set[int] | None = None
        if selection:
            regrown = active_rules(session.tree, roots)
            rules = reading_rules(session.lsystem, regrown, varied)
            if not rules:
                reasons.append(f"ascension {level}: rule(s) {sorted(regrown)} read none of {', '.join(varied)}")
                continue
        order = model.rank(key, rules=rules)
        if not len(order):
            of_rules = "" if rules is None else f"of rule(s) {sorted(rules)} "
            reasons.append(f"ascension {level}: no variant {of_rules}changes the plant")
            continue
        m0, s0, before = _measure(session, roots)
        level_tries, accepted, regen = _try_level(
            session,
            model,
            sweep,
            key,
            selection,
            rho,
            level,
            order,
            tries,
            seed,
            before,
            rules,
            BUDGET - len(tried),
            WIDEN if not tried else 1,
        )
        tried += level_tries
        if accepted is not None:
            return _result(session, key, source, accepted, regen, m0, s0, before, len(tried), level, True)
        reasons.append(_level_reason(key, level, level_tries, session.n - int(session.tree.step[roots].min())))
        if level_tries and not any(t.score > 0 for t in level_tries) and any(t.changed for t in level_tries):
            wrong_way += 1
        elif level_tries:
            crowded += 1
        if wrong_way >= MAX_WRONG_WAY_LEVELS or crowded >= MAX_CROWDED_LEVELS or len(tried) >= BUDGET:
            break
    if selection and len(tried) < BUDGET:  # one derivation step more or less, inside the selection
        stepped, tries_p = _try_part_steps(session, model, sweep, key, source, selection, rho, seed, tries, len(tried))
        if stepped is not None:
            return stepped
        tried += tries_p
        if tries_p:
            reasons.append(_steps_reason(key, tries_p, True))
    whole = _roots(session, [], rho)
    tried_whole = last_roots is not None and np.array_equal(last_roots, whole)
    if selection and climb >= session.n and not tried_whole:
        # the last level: the whole plant, where a variant the qualifier owns is dominant by construction
        m0, s0, before = _measure(session, whole)
        level_tries, accepted, regen = _try_level(
            session, model, sweep, key, (), rho, 1, model.rank(key), tries, seed, before, None, WIDEN * max(int(tries), 1), WIDEN
        )
        for t in level_tries:
            t.kind = "whole"
        tried += level_tries
        if accepted is not None:
            accepted.level = top
            return _result(session, key, source, accepted, regen, m0, s0, before, len(tried), top, True)
        reasons.append(_level_reason(key, top, level_tries).replace(f"ascension {top}", "whole plant"))
    if not selection:
        stepped, tries_n = _try_steps(session, model, sweep, key, source, len(tried), tries)
        if stepped is not None:
            return stepped
        tried += tries_n
        reasons.append(_steps_reason(key, tries_n))
    kept = _best_held(session, key, source, tried, selection, rho)
    if kept is not None:
        return kept
    return _not_improved(session, model, key, source, selection, rho, tried, reasons, varied)


def _best_held(session, key, source, tried, selection, rho):
    """No try was dominant: apply again the one that moved ``key`` most among those that kept its
    definition (score > 0), flagged ``dominant`` False with the ``rival`` that moved more (the
    word's own metric moved its way, which is what it promises).  None when no try kept it, or
    when ``key`` has no definition to keep (a word of a study, or a direction its regions gave)."""
    held = [t for t in tried if t.score > 0 and t.changed and t.kind != "whole"]
    if not held or key not in DEFINITIONS or source == "region":
        return None
    t = max(held, key=lambda t: t.score)
    if t.kind == "steps":
        m0, s0, before = _measure(session, _roots(session, [], rho))
        regen = session.set_steps(t.params["n"], t.params["combination"])
    elif t.kind == "part-steps":
        m0, s0, before = _measure(session, _roots(session, selection, rho, 1))
        regen = session.regrow(selection, rho=rho, seed=t.seed, params=t.params["combination"], steps=t.params["steps"])
    else:
        m0, s0, before = _measure(session, _roots(session, selection, rho, t.level))
        regen = _regrow(session, selection, rho, t.seed, t.params, t.level)
    reason = f"no try moved {key} more than every other qualifier: this one keeps {key}'s definition but moves {t.rival} more"
    return _result(session, key, source, t, regen, m0, s0, before, len(tried), t.level, True, reason)


def _try_steps(session, model, sweep, key, source, tried_before=0, tries=3):
    """Whole plant: one derivation step more, then one less (:meth:`Session.set_steps`), alone
    and with each of the ``tries`` variants that score ``key`` highest (a step adds or removes
    segments; a constant then packs or spreads them).  Keeps the first that keeps ``key``'s
    definition and moves it more than any other qualifier.  Returns ``(result or None, tries)``."""
    antonym = VOCABULARY[key].antonym if key in VOCABULARY else None
    m0, s0, before = _measure(session, _roots(session, [], 0.5))
    s = model.scores_[:, model.index(key)]
    best = np.flatnonzero(model.usable_ & np.isfinite(s))
    best = best[np.argsort(-s[best], kind="stable")][: max(int(tries), 0)].tolist()
    out: list[_Try] = []
    for n in (session.n + 1, session.n - 1):
        if not 0 <= n <= MAX_STEPS:
            continue
        for variant in [-1, *best]:
            combo = sweep.combination(variant) if variant >= 0 else None
            try:
                regen = session.set_steps(n, combo)
            except RamureError:  # too large a plant, or a turtle error: not a candidate
                continue
            after = _measure(session, _roots(session, [], 0.5))[2]
            own, dominant, rival, moves = _judge(model, key, before, after, antonym, noise_floor(sweep))
            changed = not np.allclose(after, before, rtol=1e-9, atol=1e-12)
            t = _Try(1, variant, None, {"n": n, "combination": combo}, own, dominant, rival, moves, changed, "steps")
            out.append(t)
            if own > 0 and dominant:
                return _result(session, key, source, t, regen, m0, s0, before, tried_before + len(out), 1, True), out
            session.undo()
    return None, out


def _steps_reason(key, tries, part=False) -> str:
    """Why neither n + 1 nor n - 1 was kept (one clause); ``part``: inside the selection."""
    if not tries:
        return "no other derivation count could be derived"
    where = " inside the selection" if part else ""
    if part:  # one step more (+1) or less (-1) of the selection's part
        tries = [_Try(**{**t.__dict__, "params": {"n": f"{t.params['steps']:+d}"}}) for t in tries]
    forward = [t for t in tries if t.score > 0]
    if forward:
        best = max(forward, key=lambda t: t.score)
        return f"n {best.params['n']}{where} moves {key} but moves {best.rival} more"
    what = DEFINITIONS[key].sentence() if key in DEFINITIONS else f"move {key}"
    ns = [str(n) for n in sorted({t.params["n"] for t in tries}, key=lambda n: int(n), reverse=True)]
    if len(ns) > 1:
        return f"neither n {' nor n '.join(ns)}{where} {what}"
    return f"n {ns[0]}{where} also fails: nothing there {what}"


def _step_partners(model, key, rules, count) -> list[int]:
    """Variants to try with one derivation step more or less: the best that move ``key``
    forward, then the best that move its definition's other terms their way (for "dense", a
    step adds the segments and a variant packs them: branches per unit of box volume up)."""
    q = model.index(key)
    order = model.rank(key, rules=rules)
    best = [int(v) for v in order if model.scores_[v, q] > 0][:count]
    terms = DEFINITIONS[key].terms()[1:] if key in DEFINITIONS else ()
    if terms:
        usable = np.flatnonzero(model.usable_ & (np.isin(model.rules_, sorted(rules)) if model.rules_ is not None else True))
        push = sum(sign * np.nan_to_num(metric_change(m, model.deltas_[usable])) for m, sign in terms)
        ahead = usable[np.argsort(-push, kind="stable")][np.sort(-push) < 0]
        best += [int(v) for v in ahead if int(v) not in best][:count]
    return best


def _try_part_steps(session, model, sweep, key, source, selection, rho, seed, tries=3, tried_before=0):
    """A selection's part regrown one derivation step more, then one less, than the plant
    (:meth:`Session.regrow` with ``steps``; the rest of the plant unchanged), alone and with the
    best candidates of the rules it regrows that move ``key`` forward on the whole plant (a step
    adds or removes segments: "dense" or "sparse" for a part).  Keeps the first try that moves
    ``key`` forward more than any other qualifier.  Returns ``(result or None, tries)``."""
    roots = _roots(session, selection, rho, 1)
    if not len(roots):
        return None, []
    antonym = VOCABULARY[key].antonym if key in VOCABULARY else None
    m0, s0, before = _measure(session, roots)
    rules = reading_rules(session.lsystem, active_rules(session.tree, roots), list(getattr(sweep, "names_", [])))
    best = _step_partners(model, key, rules, max(min(int(tries), 3), 0))
    out: list[_Try] = []
    for extra in (1, -1):
        for variant in [-1, *best]:
            combo = sweep.combination(variant) if variant >= 0 else None
            for try_seed in _seeds(session, seed):
                if len(out) >= BUDGET:
                    return None, out
                try:
                    regen = session.regrow(selection, rho=rho, seed=try_seed, params=combo, steps=extra)
                except RamureError:  # one step less of a part made in the last step, or too large
                    break
                after = _measure(session, regen.roots)[2]
                own, dominant, rival, moves = _judge(model, key, before, after, antonym, noise_floor(sweep))
                changed = not np.allclose(after, before, rtol=1e-9, atol=1e-12)
                params = {"steps": extra, "combination": combo}
                t = _Try(1, variant, try_seed, params, own, dominant, rival, moves, changed, "part-steps")
                out.append(t)
                if own > 0 and dominant:
                    return _result(session, key, source, t, regen, m0, s0, before, tried_before + len(out), 1, True), out
                session.undo()
    return None, out


def _level_reason(key, level, tries, steps_left=None) -> str:
    """Why no try at one level was kept (one clause); ``steps_left``: the derivation steps that
    regrow the part (1: it was made in the last step)."""
    forward = [t for t in tries if t.score > 0]
    if forward:
        best = max(forward, key=lambda t: t.score)
        rival = best.moves.get(best.rival, float("nan"))
        return (
            f"ascension {level}: {len(forward)} of {len(tries)} tries moved {key} forward but each moved "
            f"another qualifier more (best: {key} {best.score:.2g}, {best.rival} {rival:.2g})"
        )
    if any(t.changed for t in tries):
        return f"ascension {level}: {len(tries)} tries moved it the other way"
    if steps_left == 1:
        return (
            f"ascension {level}: none of {len(tries)} tries changed the part regrown: it was made in the last "
            "derivation step, so the varied constants reach only modules that no later step rewrites"
        )
    return f"ascension {level}: none of {len(tries)} tries changed the part regrown"


def _regrow(session, selection, rho, seed, params, level):
    """Apply a candidate: regrow the selection's cut (:meth:`Session.regrow`); on the whole
    plant, a combination for every rule (``rule`` None: an axiom literal, :mod:`ramure.lsys.language.hidden`)
    derives the plant again (:meth:`Session.set_steps` at the same ``n``), since a regrowth
    keeps the axiom's values."""
    if not selection and params.get("rule", 0) is None:
        return session.set_steps(session.n, params)
    return session.regrow(selection, rho=rho, seed=seed, params=params, min_ascend=level)


def _regrown(session, regen, rho):
    """The roots to measure after ``regen``: its own, or the whole plant's after a re-derivation."""
    return regen.roots if len(regen.roots) else _roots(session, [], rho)


def _result(session, key, source, t, regen, m0, s0, before, tried, level, improved, reason=None, suggestion=None):
    m1, s1, after = _measure(session, _regrown(session, regen, 0.5))
    improved = improved and t.score > 0
    return QualifierResult(
        key,
        t.variant,
        t.params,
        source,
        regen.roots,
        m0,
        m1,
        float(t.score),
        improved,
        tried,
        regen,
        t.seed,
        s0,
        s1,
        _own(key, before, after),
        t.moves,
        t.dominant,
        t.rival,
        level,
        level - 1,
        reason,
        suggestion,
    )


def _not_improved(session, model, key, source, selection, rho, tried, reasons, varied):
    """Nothing moved the qualifier forward: leave the plant as it was and say why.

    ``variant``/``params``/``score`` describe the best candidate tried (-1 /
    {} / NaN when none could be); ``after`` equals ``before`` and ``regen``
    is None, since no edit is kept.
    """
    suggestion = (
        "select a larger part (the branch that carries the selection), lower rho (e.g. --rho 0.1), "
        f"let the qualifier climb above the selection (--climb), or vary constants the selected rules read "
        f"(varied now: {', '.join(varied) or 'none'})"
    )
    roots = _roots(session, selection, rho)
    m0, s0, before = _measure(session, roots)
    if not tried:
        reason = "; ".join(reasons) or "no candidate variant"
        return QualifierResult(
            key,
            -1,
            {},
            source,
            roots,
            m0,
            m0,
            float("nan"),
            False,
            0,
            None,
            None,
            s0,
            s0,
            _own(key, before, before),
            {},
            True,
            None,
            1,
            0,
            reason,
            suggestion,
        )
    best = max(tried, key=lambda t: t.score)
    if best.score > 0:
        head = f"none of the {len(tried)} tries moved {key} more than every other qualifier, so the plant is left as it was: "
    elif any(t.changed for t in tried):
        head = (
            f"the {len(tried)} tries moved {key}'s own metrics the other way (best score {best.score:.3g}), "
            "so the plant is left as it was: "
        )
    else:
        head = f"none of the {len(tried)} tries changed the part regrown: "
    reason = head + "; ".join(reasons)
    return QualifierResult(
        key,
        best.variant,
        best.params,
        source,
        roots,
        m0,
        m0,
        float(best.score),
        False,
        len(tried),
        None,
        best.seed,
        s0,
        s0,
        _own(key, before, before),
        best.moves,
        best.dominant,
        best.rival,
        best.level,
        best.level - 1,
        reason,
        suggestion,
    )


def _apply_first(session, model, sweep, key, selection, rho, seed, source):
    """``normal`` (or a name without direction): apply the first candidate, no check."""
    order = model.rank(key)
    roots = _roots(session, selection, rho)
    m0, s0, before = _measure(session, roots)
    variant = int(order[0])
    params = sweep.combination(variant)
    regen = _regrow(session, selection, rho, seed, params, 1)
    m1, s1, after = _measure(session, _regrown(session, regen, rho))
    return QualifierResult(
        key,
        variant,
        params,
        source,
        regen.roots,
        m0,
        m1,
        float("nan"),
        False,
        1,
        regen,
        seed,
        s0,
        s1,
        {},
        {},
        True,
        None,
        1,
        0,
        "normal has no metric direction: the combination closest to the base plant",
        None,
    )
