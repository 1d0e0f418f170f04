"""Qualifiers: what each word means as metric directions, the regions of studies, and how to pick a variant.

**Meaning.**  Every default qualifier is a *direction* over the fifteen
qualifier metrics (:data:`QUALIFIER_METRICS`: the ten metrics of the
thesis, :mod:`ramure.metrics.plant`, then the five shape metrics of
:mod:`ramure.metrics.shape` — height, crown width, branch angle to the
vertical, angle spread, asymmetry).  :data:`VOCABULARY` gives each one in
English and French with a one-line meaning (``ramure qualify --list``
prints them).  Antonym pairs (:data:`ANTONYMS`) are exact opposites; no two
qualifiers share a direction.  ``normal`` has no direction: it ranks
variants by closeness to the base plant.

**Scores.**  A variant's change of each metric against the base plant
(relative %, see :func:`~ramure.metrics.plant.metric_deltas` and
:func:`~ramure.metrics.shape.shape_deltas`) is divided by that metric's
standard deviation over the sweep, so every metric weighs the same and one
that never varies counts for nothing; a qualifier's score is the
projection of that vector on its direction, divided by the standard
deviation of that projection over the sweep's variants (``weights_``).  So
every qualifier's score is in the same unit — "how many of its own typical
variations on this grammar it moved" — and "moves another qualifier more
than its own" compares like with like: a qualifier whose metrics co-move
(``large``: box volume and total length) is not favoured over one with a
single metric (``tall``), nor one whose metrics pull against each other
(``round``, ``fir-like``) penalised for moving less in absolute terms.
Antonyms keep exactly opposite scores.  The same scores judge a selection's
measured change (:mod:`ramure.metrics.apply`).

**The choice is checked** (:class:`QualifierModel`).  A variant *belongs*
to the qualifier it moves most (its highest score over the directional
qualifiers whose definition it keeps).  A variant moves a qualifier *forward* when its score is
positive and the qualifier's definition holds (the metric it promises moves
its way: :mod:`ramure.metrics.definitions`).  For a qualifier, candidates come
in three tiers: (1) variants it owns, that move it forward, best score first — so the
variant applied moves the qualifier's own metrics more than any other
candidate not rejected, and two qualifiers never pick the same one;
(2) variants that move it forward but move some other qualifier more,
smallest rival lead first; (3) variants that do not move it forward.
Failed variants and variants identical to the base plant are left out.

**Transfer.**  The directions hold for any grammar with ``#define``
constants, with no study.  When a study's regions exist for a grammar
(:class:`QualifierRegions` in PCA space), the variants nearest a region's
centre give a *learnt* direction (the mean of their standardised deltas)
that refines the default one (:func:`learn_directions`, ``refine``); those
learnt directions are plain metric weights, so regions learnt on one
grammar apply to another: ``QualifierModel(directions=learn_directions(...))``.

**Regions** (:class:`QualifierRegions`, thesis §5.5): from labelled variant
points per qualifier (a study's, read from the :mod:`ramure.metrics.store`),
one axis-aligned box per qualifier in PCA space, after trimming the ``trim``
share (7 % by default) of its points farthest from the qualifier's median
point (``floor(trim * k)`` of k points); the collision matrix; and the box
centre -> nearest variant -> its parameter combination.

>>> import numpy as np
>>> canonical_name("Épars"), canonical_name("sapin"), canonical_name("Fir like"), canonical_name("haut")
('sparse', 'fir-like', 'fir-like', 'tall')
>>> deltas = np.array([[10.0, 0, 0, 0, -5, 0, 0, 0, 0, 0], [0, 0, 0, 0, 20, 0, 0, 0, 0, 0]])
>>> rank_variants("dense", deltas).tolist()
[1, 0]
>>> VOCABULARY["tall"].describe(), VOCABULARY["short"].describe()
('+height', '-height')
"""

from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Self, cast

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

from .definitions import DEFINITIONS, definition_holds
from .estimator import ParamsMixin, check_rows
from .plant import METRIC_NAMES, metric_deltas
from .shape import SHAPE_METRIC_NAMES, shape_deltas

if TYPE_CHECKING:
    from ramure.lsys import LSystem

    from .sweep import VariantSweep

#: The metrics qualifiers are defined on: the ten metrics, then the five shape metrics.
QUALIFIER_METRICS = tuple(METRIC_NAMES) + tuple(SHAPE_METRIC_NAMES)


def _unit(weights: Mapping[str, float]) -> np.ndarray:
    unknown = set(weights) - set(QUALIFIER_METRICS)
    if unknown:
        raise ValueRefused(
            f"unknown metric(s) {', '.join(sorted(unknown))} in a qualifier direction (metrics: {', '.join(QUALIFIER_METRICS)})"
        )
    v = np.array([float(weights.get(m, 0.0)) for m in QUALIFIER_METRICS])
    norm = np.linalg.norm(v)
    if not np.isfinite(norm) or norm == 0:
        raise ValueRefused("a qualifier direction needs at least one non-zero, finite metric weight")
    return v / norm


@dataclass(frozen=True)
class Qualifier:
    """A vocabulary entry: English ``name``, ``french`` name, metric weights (None: nearest
    to the base plant), what the direction means, and its ``antonym`` (or None)."""

    name: str
    french: str
    direction: dict | None
    meaning: str
    antonym: str | None = None

    def vector(self) -> np.ndarray | None:
        """The unit direction (15,) over :data:`QUALIFIER_METRICS`, or None."""
        return None if self.direction is None else _unit(self.direction)

    def metrics(self) -> tuple:
        """The metrics the qualifier reads (its own metrics), strongest first."""
        if self.direction is None:
            return ()
        direction = self.direction
        return tuple(sorted(direction, key=lambda m: -abs(direction[m])))

    def describe(self) -> str:
        """The direction in one line, e.g. ``+height -crown_width +0.5 branch_angle``."""
        if self.direction is None:
            return "(no direction)"
        parts = []
        for m in self.metrics():
            w = self.direction[m]
            sign = "+" if w > 0 else "-"
            parts.append(f"{sign}{m}" if abs(w) == 1 else f"{sign}{abs(w):g} {m}")
        return " ".join(parts)


def _neg(direction: dict) -> dict:
    return {k: -v for k, v in direction.items()}


def _pair(pos, neg, direction, pos_meaning, neg_meaning):
    """Two antonyms: ``neg``'s direction is exactly ``-direction``."""
    return [
        Qualifier(pos[0], pos[1], dict(direction), pos_meaning, neg[0]),
        Qualifier(neg[0], neg[1], _neg(direction), neg_meaning, pos[0]),
    ]


#: The default vocabulary: canonical English name -> :class:`Qualifier` (thesis's 13, then 9 more).
VOCABULARY = {
    q.name: q
    for q in [
        *_pair(
            ("small", "petit"),
            ("large", "grand"),
            {"box_volume": -1, "total_length": -1},
            "a smaller plant: smaller box and less branch length in all",
            "a bigger plant: bigger box and more branch length in all",
        ),
        *_pair(
            ("dense", "dense"),
            ("sparse", "épars"),
            {"branch_density": 1, "branch_count": 1},
            "more branches, packed closer (more per unit of box volume)",
            "fewer branches, spread through more space",
        ),
        *_pair(
            ("asymmetric", "asymétrique"),
            ("symmetric", "symétrique"),
            {"asymmetry": 1},
            "wood more on one side of the trunk's vertical (higher asymmetry)",
            "wood better balanced around the trunk's vertical (lower asymmetry)",
        ),
        *_pair(
            ("realistic", "réaliste"),
            ("unrealistic", "irréaliste"),
            {"mean_radius": 1, "mean_length": -1},
            "proxy: stouter segments, thicker and shorter (lower slenderness), as wood grows",
            "proxy: spindly segments, thinner and longer (higher slenderness)",
        ),
        Qualifier(
            "fir-like",
            "sapin",
            {"height": 1, "crown_width": -1, "branch_angle": 0.5},
            "a conical crown: taller and narrower, branches held more horizontally",
        ),
        Qualifier("normal", "normal", None, "closest to the base plant (smallest standardised changes)"),
        *_pair(
            ("thick", "gros"),
            ("thin", "mince"),
            {"mean_radius": 1, "branch_volume": 0.5},
            "thicker branches (mean radius up), more wood",
            "thinner branches (mean radius down), less wood",
        ),
        Qualifier(
            "round", "rond", {"box_volume": 1, "box_surface": -1.5}, "a compact, cube-like box (lower surface^1.5 / volume)"
        ),
        *_pair(
            ("tall", "haut"),
            ("short", "bas"),
            {"height": 1},
            "taller: larger vertical extent",
            "shorter: smaller vertical extent",
        ),
        *_pair(
            ("wide", "large"),
            ("narrow", "étroit"),
            {"crown_width": 1},
            "wider: larger horizontal extent of the crown",
            "narrower: smaller horizontal extent",
        ),
        *_pair(
            ("drooping", "retombant"),
            ("upright", "érigé"),
            {"branch_angle": 1},
            "branches lean further from the vertical (mean angle to vertical up)",
            "branches closer to the vertical (mean angle to vertical down)",
        ),
        Qualifier(
            "bushy",
            "touffu",
            {"branch_count": 1, "crown_width": 0.5, "mean_length": -0.5},
            "more and shorter branches in a wider crown",
        ),
        *_pair(
            ("irregular", "irrégulier"),
            ("regular", "régulier"),
            {"angle_spread": 1},
            "branching angles more varied (higher angle spread)",
            "branching angles more alike (lower angle spread)",
        ),
    ]
}

#: Antonym pairs (each direction is exactly minus the other).
ANTONYMS = sorted({tuple(sorted((q.name, q.antonym))) for q in VOCABULARY.values() if q.antonym})

_ALIASES = {
    "fir": "fir-like",
    "fir-tree": "fir-like",
    "conical": "fir-like",
    "denser": "dense",
    "sparser": "sparse",
    "smaller": "small",
    "larger": "large",
    "big": "large",
    "bigger": "large",
    "thinner": "thin",
    "thicker": "thick",
    "rounder": "round",
    "rounded": "round",
    "taller": "tall",
    "shorter": "short",
    "wider": "wide",
    "narrower": "narrow",
    "broad": "wide",
    "erect": "upright",
    "weeping": "drooping",
    "pendulous": "drooping",
    "bushier": "bushy",
    "balanced": "symmetric",
    "lopsided": "asymmetric",
    "plus-haut": "tall",
    "etale": "wide",
    "evase": "wide",
    "pleureur": "drooping",
    "dresse": "upright",
    "buissonnant": "bushy",
}


def _fold(text) -> str:
    text = unicodedata.normalize("NFKD", str(text))
    text = "".join(c for c in text if not unicodedata.combining(c)).lower()
    return "-".join(re.sub(r"[^0-9a-z]+", " ", text).split())


# English names first: "large" is English "large" (grand); French "large" is "wide" with language="fr".
_FRENCH = {_fold(q.french): q.name for q in VOCABULARY.values()}
_LOOKUP = {**_FRENCH, **{_fold(k): v for k, v in _ALIASES.items()}, **{_fold(q.name): q.name for q in VOCABULARY.values()}}


def canonical_name(name: str, language: str | None = None) -> str:
    """The canonical English name of a qualifier given in English or French (any case, accents).

    One word is both English and French: ``large`` (English: bigger, *grand*;
    French: wider, *wide*).  It reads as English unless ``language="fr"``.

    >>> canonical_name("large"), canonical_name("large", language="fr"), canonical_name("Érigé")
    ('large', 'wide', 'upright')
    """
    key = _fold(name)
    if language == "fr" and key in _FRENCH:
        return _FRENCH[key]
    if key not in _LOOKUP:  # "plus touffu", "more upright"; "moins dense", "less bushy": the antonym
        head, _, rest = key.partition("-")
        if rest and head in _MORE | _LESS:
            word = canonical_name(rest, language)
            if word in VOCABULARY:
                return word if head in _MORE else (VOCABULARY[word].antonym or f"{head}-{word}")
    return _LOOKUP.get(key, key)


_MORE, _LESS = {"plus", "more", "tres", "very"}, {"moins", "less"}


def accepted_words() -> list[str]:
    """Every word a qualifier box accepts, for suggestions while typing: the English and French
    names and the synonyms and comparatives (``taller``, ``touffu``, ``plus touffu`` also work).

    >>> words = accepted_words()
    >>> {"tall", "taller", "haut", "touffu"} <= set(words), canonical_name("plus touffu")
    (True, 'bushy')
    """
    words = {q.name for q in VOCABULARY.values()} | {q.french for q in VOCABULARY.values() if q.french}
    words |= {k.replace("-", " ") if k.startswith("plus-") else k for k in _ALIASES}
    return sorted(words, key=lambda w: (_fold(w), w))


def close_words(text: str, extra: Iterable[str] = (), n: int = 5) -> list[str]:
    """The accepted words (and ``extra`` ones, e.g. a study's) nearest ``text`` in spelling,
    nearest first: what a refusal suggests.

    >>> close_words("taler")[:1], close_words("plus touffuu"), close_words("xyzzy")
    (['taller'], ['touffu', 'plus touffu'], [])
    """
    import difflib

    words = {_fold(w): w for w in accepted_words()}
    words.update({_fold(w): w if w in VOCABULARY else w.replace("-", " ") for w in extra})  # "long-trunk": "long trunk"
    key = _fold(text)
    head, _, rest = key.partition("-")
    found = difflib.get_close_matches(key, list(words), n=n, cutoff=0.6)
    if rest and head in _MORE | _LESS:  # "plus touffuu": the word after "plus", with its "plus"
        found += [f"{head}-{w}" for w in difflib.get_close_matches(rest, list(words), n=n, cutoff=0.6)]
    return [words.get(k, k.replace("-", " ")) for k in dict.fromkeys(found)][:n]


def vocabulary_name(name: str, language: str | None = None, extra: Iterable[str] = ()) -> str:
    """Like :func:`canonical_name` but refuses names outside the default vocabulary (and
    ``extra`` canonical names, e.g. a study's words), suggesting the nearest words.

    >>> vocabulary_name("plus touffu"), vocabulary_name("feathery", extra=["feathery"])
    ('bushy', 'feathery')
    """
    key = canonical_name(name, language)
    extra = {canonical_name(w) for w in extra}
    if key not in VOCABULARY and key not in extra:
        near = close_words(name, extra)
        hint = f"did you mean {', '.join(near)}? " if near else ""
        raise ValueRefused(
            f"unknown qualifier {name!r}: {hint}(English or French, e.g. tall/haut, taller, plus touffu; "
            "'ramure qualify --list' lists them)"
        )
    return key


def vocabulary_table() -> list:
    """One dict per qualifier (name, french, direction, meaning, antonym): ``qualify --list``."""
    return [
        {
            "name": q.name,
            "french": q.french,
            "direction": q.describe(),
            "meaning": q.meaning,
            "antonym": q.antonym,
            "metrics": list(q.metrics()),
        }
        for q in VOCABULARY.values()
    ]


# -- scores ---------------------------------------------------------------------
def _deltas_of(source) -> np.ndarray:
    """(N,15) deltas from a fitted sweep or an (N,10) / (N,15) array (missing shape deltas: 0)."""
    if hasattr(source, "deltas_"):
        shape = getattr(source, "shape_deltas_", None)
        deltas = np.asarray(source.deltas_, float)
        if shape is None:
            shape = np.zeros((len(deltas), len(SHAPE_METRIC_NAMES)))
        return np.hstack([deltas, np.asarray(shape, float)])
    deltas = np.asarray(source, float)
    if deltas.ndim == 2 and deltas.shape[1] == len(METRIC_NAMES):
        deltas = np.hstack([deltas, np.where(np.isfinite(deltas[:, :1]), 0.0, np.nan) * np.ones((1, len(SHAPE_METRIC_NAMES)))])
    if deltas.ndim != 2 or deltas.shape[1] != len(QUALIFIER_METRICS):
        features = deltas.shape[1] if deltas.ndim == 2 else "no"
        raise ValueRefused(
            f"expected deltas of shape (N, {len(METRIC_NAMES)}) or (N, {len(QUALIFIER_METRICS)}), "
            f"got {features} feature(s) (shape {deltas.shape})"
        )
    return deltas


def all_deltas(after: ArrayLike, before: ArrayLike) -> np.ndarray:
    """Change (15,) of the fifteen qualifier metrics from ``before`` to ``after`` (15,)."""
    k = len(METRIC_NAMES)
    after, before = np.asarray(after, float), np.asarray(before, float)
    return np.concatenate([metric_deltas(after[:k], before[:k]), shape_deltas(after[k:], before[k:])])


def metric_scale(deltas: VariantSweep | ArrayLike) -> np.ndarray:
    """Standard deviation of each metric's delta over valid variants (0 where it never varies)."""
    deltas = _deltas_of(deltas)
    ok = np.all(np.isfinite(deltas), axis=1)
    return deltas[ok].std(axis=0) if ok.any() else np.zeros(deltas.shape[1])


def standardise(deltas: ArrayLike, scale: ArrayLike) -> np.ndarray:
    """``deltas / scale`` per metric (0 where the scale is 0; NaN rows stay NaN)."""
    deltas = np.atleast_2d(np.asarray(deltas, float))
    scale = np.asarray(scale, float)
    z = np.divide(deltas, scale, out=np.zeros_like(deltas), where=scale > 0)
    z[~np.isfinite(deltas)] = np.nan
    return z


def qualifier_scores(name: str, deltas: VariantSweep | ArrayLike, scale: ArrayLike | None = None) -> np.ndarray:
    """Score (N,) of each variant along qualifier ``name``'s own direction; NaN for failed variants.

    ``deltas`` (N,10), (N,15) or a fitted sweep; ``scale`` the per-metric
    standardisation (default: :func:`metric_scale` of ``deltas``).  ``normal``
    scores minus the length of the standardised change.
    """
    q = VOCABULARY[vocabulary_name(name)]
    deltas = _deltas_of(deltas)
    scale = metric_scale(deltas) if scale is None else np.asarray(scale, float)
    if scale.shape[0] == len(METRIC_NAMES):
        scale = np.concatenate([scale, np.zeros(len(SHAPE_METRIC_NAMES))])
    z = standardise(deltas, scale)
    if q.direction is None:
        return -np.linalg.norm(z, axis=1)
    return z @ q.vector()


def rank_variants(
    name: str, deltas: VariantSweep | ArrayLike, rules: Iterable[int] | None = None, variant_rules: ArrayLike | None = None
) -> np.ndarray:
    """Variant indices, best first, for qualifier ``name`` (failed variants left out).

    The ranking of :meth:`QualifierModel.rank` with the default vocabulary.
    With ``rules`` (a set of rule indices) and ``variant_rules`` (N,) only the
    variants acting on one of those rules are ranked — e.g. the rules that
    actually rewrite inside a selection.
    """
    model = QualifierModel().fit(deltas)
    return model.rank(name, rules=rules, variant_rules=variant_rules)


# -- the model ------------------------------------------------------------------
def learn_directions(
    regions: QualifierRegions, sweep: VariantSweep | ArrayLike, points: ArrayLike, k_nearest: int = 10
) -> dict[str, dict[str, float]]:
    """Metric directions learnt from study ``regions`` on one grammar: ``{name: {metric: weight}}``.

    For each region, the ``k_nearest`` variants of ``points`` (the sweep's PCA
    cloud, (N,3)) closest to the box centre; their standardised deltas,
    averaged, give the direction (unit length; a region whose variants do not
    move any metric is left out).  The result applies to any grammar
    (``QualifierModel(directions=...)``), since it speaks of metrics, not of
    one grammar's PCA axes.
    """
    deltas = _deltas_of(sweep)
    z = standardise(deltas, metric_scale(deltas))
    out: dict[str, dict[str, float]] = {}
    for name in regions.names_:
        near = regions.nearest_variants(name, points)
        near = near[np.all(np.isfinite(z[near]), axis=1)][: max(int(k_nearest), 1)]
        if not len(near):
            continue
        v = z[near].mean(axis=0)
        norm = np.linalg.norm(v)
        if norm > 0:
            out[name] = {m: float(w) for m, w in zip(QUALIFIER_METRICS, v / norm) if w != 0}
    return out


def _score_weights(directions, z) -> np.ndarray:
    """Directions (Q,15) each divided by the standard deviation of its projection over the
    variants ``z`` (N,15), so every qualifier's score varies by 1 over the sweep."""
    ok = np.all(np.isfinite(z), axis=1)
    spread = (z[ok] @ directions.T).std(axis=0) if ok.any() else np.zeros(len(directions))
    # a qualifier no variant moves keeps its direction at unit spread: its scores over the sweep
    # are all 0 anyway, and a change measured elsewhere (n +- 1) still scores
    return directions / np.where(spread > 0, spread, 1.0)[:, None]


class QualifierModel(ParamsMixin):
    """Qualifier directions fitted on one grammar's sweep: scores, owners and rankings.

    Parameters (stored as given, checked by :meth:`fit`):

    directions
        ``{qualifier: {metric: weight}}`` replacing or adding directions —
        e.g. :func:`learn_directions` of another grammar's study (transfer).
    regions
        fitted :class:`QualifierRegions` of *this* grammar (a study's); with
        ``points`` given to :meth:`fit`, each region refines its qualifier's direction.
    refine
        weight in [0, 1] of a region's learnt direction against the default one.
    k_nearest
        variants nearest a region's centre used to learn its direction.

    Fitted: ``names_`` (directional qualifiers, sorted), ``directions_`` (Q,15) (unit length),
    ``weights_`` (Q,15) (the directions divided by the spread of their scores: see
    *Scores* in the module docstring), ``sources_`` ``{name: "vocabulary" | "transfer" | "region"}``, ``scale_`` (15,),
    ``scores_`` (N,Q), ``normal_scores_`` (N,), ``owner_`` (N,) (index into
    ``names_`` of the qualifier each variant moves most; -1 for none),
    ``usable_`` (N,) (finite and not the base plant), ``deltas_`` (N,15), ``holds_`` (N,Q) (the variant keeps the
    qualifier's definition, :mod:`ramure.metrics.definitions`), ``rules_`` (N,) or None,
    ``picks_`` ``{name: variant}`` (whole-plant picks, pairwise distinct), ``n_features_in_`` (10 or 15).

    A scikit-learn estimator (``fit(X, y=None)``, tags, ``NotFittedError`` before ``fit``);
    ``check_estimator``'s checks that fit on other than 10 or 15 columns do not apply
    (tests/metrics/test_estimator_contract.py names them).
    """

    _fitted_attribute = "scores_"

    def __init__(
        self,
        directions: Mapping[str, Mapping[str, float]] | None = None,
        regions: QualifierRegions | None = None,
        refine: float = 0.5,
        k_nearest: int = 10,
    ) -> None:
        self.directions = directions
        self.regions = regions
        self.refine = refine
        self.k_nearest = k_nearest

    def fit(self, X: VariantSweep | ArrayLike, y: object = None, *, points: ArrayLike | None = None) -> Self:
        """Fit on a fitted sweep or a delta array ``X`` (N,10)/(N,15); ``points`` is the sweep's PCA
        cloud (N,3) (for ``regions``); ``y`` is ignored (scikit-learn's signature)."""
        refine = float(self.refine)
        if not 0 <= refine <= 1:
            raise ValueRefused(f"refine must be in [0, 1], not {self.refine!r}")
        sweep = X if hasattr(X, "deltas_") else check_rows(self, X, fitting=True)
        deltas = _deltas_of(sweep)
        if sweep is X:
            self.n_features_in_ = np.asarray(X.deltas_).shape[1]  # type: ignore[union-attr]
        # a metric no variant moves gets unit scale (1 % = 1): its sweep values are all 0 whatever
        # the scale, and a change measured elsewhere (one derivation step more) still counts
        scale = metric_scale(deltas)
        self.scale_ = np.where(scale > 0, scale, 1.0)
        dirs = {n: q.vector() for n, q in VOCABULARY.items() if q.direction is not None}
        sources = dict.fromkeys(dirs, "vocabulary")
        for name, weights in (self.directions or {}).items():
            key = canonical_name(name)
            dirs[key], sources[key] = _unit(weights), "transfer"
        if self.regions is not None and points is not None:
            for name, weights in learn_directions(self.regions, sweep, points, self.k_nearest).items():
                learnt = _unit(weights)
                mixed = learnt if name not in dirs else (1 - refine) * dirs[name] + refine * learnt
                if np.linalg.norm(mixed) > 0:
                    dirs[name], sources[name] = mixed / np.linalg.norm(mixed), "region"
        self.names_ = sorted(dirs)
        self.directions_ = np.array([dirs[n] for n in self.names_]).reshape(-1, len(QUALIFIER_METRICS))
        self.sources_ = {n: sources[n] for n in self.names_}
        z = standardise(deltas, self.scale_)
        self.weights_ = _score_weights(self.directions_, standardise(deltas, self.scale_))
        self.scores_ = z @ self.weights_.T
        self.normal_scores_ = -np.linalg.norm(z, axis=1)
        finite = np.all(np.isfinite(z), axis=1)
        changes = getattr(sweep, "changes_", None)
        moved = np.any(z != 0, axis=1) if changes is None else np.asarray(changes, bool)
        self.usable_ = finite & moved
        self.deltas_ = deltas
        self.holds_ = _holds(self.names_, deltas, self.scores_, self.sources_)
        filled = np.where(np.isfinite(self.scores_) & self.holds_, self.scores_, -np.inf)
        self.owner_ = np.where(filled.max(axis=1, initial=-np.inf) > 0, filled.argmax(axis=1), -1)
        self.rules_ = getattr(sweep, "rules_", None)
        self.n_variants_ = len(deltas)
        self.picks_ = self._assign()
        return self

    def _fitted(self):
        self._check_fitted()

    def index(self, name: str) -> int:
        """Position of qualifier ``name`` in ``names_`` (refuses unknown and direction-less names)."""
        self._fitted()
        key = canonical_name(name)
        if key not in self.names_:
            if key in VOCABULARY:
                raise ValueRefused(f"qualifier {key!r} has no metric direction")
            vocabulary_name(name)
        return self.names_.index(key)

    def direction(self, name: str) -> dict[str, float]:
        """``{metric: weight}`` of qualifier ``name``'s unit direction (non-zero weights)."""
        row = self.directions_[self.index(name)]
        return {m: float(w) for m, w in zip(QUALIFIER_METRICS, row) if w != 0}

    def scores(self, name: str) -> np.ndarray:
        """Scores (N,) of every variant along ``name`` (``normal``: minus the change's length)."""
        self._fitted()
        if canonical_name(name) == "normal":
            return self.normal_scores_
        return self.scores_[:, self.index(name)]

    def _tiers(self, q, keep):
        """Candidate tiers for directional qualifier ``q`` among ``keep`` (module docstring)."""
        s = self.scores_[:, q]
        keep = keep & self.usable_ & np.isfinite(s)
        forward = (s > 0) & self.holds_[:, q]
        owned = keep & forward & (self.owner_ == q)
        return owned, keep & forward & ~owned, keep & ~forward

    def _assign(self):
        """One whole-plant pick per directional qualifier, never shared (``picks_``).

        Owners take their best owned variant; a qualifier owning none takes
        its best forward variant not taken yet (strongest claims first).
        """
        everything = np.ones(self.n_variants_, bool)
        picks, claims = {}, []
        for q, name in enumerate(self.names_):
            owned, second, _ = self._tiers(q, everything)
            s = self.scores_[:, q]
            if owned.any():
                picks[name] = int(np.flatnonzero(owned)[np.argmax(s[owned])])
            elif second.any():
                claims.append((-float(s[second].max()), name))
        taken = set(picks.values())
        for _, name in sorted(claims):
            q = self.names_.index(name)
            s = self.scores_[:, q]
            idx = np.flatnonzero(self._tiers(q, everything)[1])
            idx = idx[np.argsort(-s[idx], kind="stable")]
            free = [int(v) for v in idx if int(v) not in taken]
            if free:
                picks[name] = free[0]
                taken.add(free[0])
        return picks

    def rank(self, name: str, rules: Iterable[int] | None = None, variant_rules: ArrayLike | None = None) -> np.ndarray:
        """Candidate variants for ``name``, best first (see the module docstring for the tiers).

        Within a tier, variants are ordered by the qualifier's own score; the
        whole-plant picks of *other* qualifiers (``picks_``) go last in their
        tier.  ``rules``: keep only variants on those rules (``variant_rules``
        (N,) when the model was fitted on a plain array).
        """
        self._fitted()
        keep = np.ones(self.n_variants_, bool)
        if rules is not None:
            variant_rules = self.rules_ if variant_rules is None else variant_rules
            if variant_rules is None:
                raise ValueRefused("ranking by rules needs each variant's rule (pass a fitted sweep)")
            keep &= np.isin(np.asarray(variant_rules), np.asarray(sorted(rules), dtype=np.int64))
        if canonical_name(name) == "normal":
            s = self.normal_scores_
            idx = np.flatnonzero(keep & np.isfinite(s))
            return idx[np.argsort(-s[idx], kind="stable")]
        q = self.index(name)
        s = self.scores_[:, q]
        others = np.zeros(self.n_variants_, bool)
        others[[v for n, v in self.picks_.items() if n != self.names_[q]]] = True
        out = []
        for tier in self._tiers(q, keep):
            idx = np.flatnonzero(tier)
            out.append(idx[np.lexsort((-s[idx], others[idx]))])
        return np.concatenate(out)

    def picks(self) -> dict:
        """``{name: variant}`` applied to the whole plant: distinct for distinct qualifiers."""
        self._fitted()
        return dict(self.picks_)

    def move_scores(self, deltas: ArrayLike) -> dict[str, float]:
        """``{name: score}`` of one measured change (15,) (e.g. a selection before/after)."""
        self._fitted()
        z = standardise(np.asarray(deltas, float)[None], self.scale_)[0]
        return dict(zip(self.names_, (self.weights_ @ np.nan_to_num(z)).tolist()))

    def to_dict(self) -> dict:
        """JSON-able directions: ``{"metrics", "directions": {name: {metric: weight}}, "sources"}``."""
        self._fitted()
        return {
            "metrics": list(QUALIFIER_METRICS),
            "directions": {n: self.direction(n) for n in self.names_},
            "sources": self.sources_,
        }


def _holds(names, deltas, scores, sources) -> np.ndarray:
    """(N,Q): each variant keeps each qualifier's definition (:mod:`ramure.metrics.definitions`);
    a word without one, or whose direction this grammar's study regions gave (its meaning is
    then what the participants chose), holds where its score is positive."""
    out = np.asarray(scores, float) > 0
    for q, name in enumerate(names):
        if name in DEFINITIONS and sources.get(name) != "region":
            out[:, q] = definition_holds(name, deltas)
    return out


# -- regions --------------------------------------------------------------------
def _rows(points: ArrayLike, dim: int = 3) -> np.ndarray:
    """Points as rows: a 2-D array as it is (any dimension), anything else as rows of ``dim``."""
    points = np.asarray(points, float)
    return points if points.ndim == 2 else points.reshape(-1, dim)


def trim_points(points: ArrayLike, trim: float = 0.07) -> np.ndarray:
    """Boolean mask keeping all but the ``floor(trim * k)`` points farthest from the median point."""
    points = _rows(points)
    drop = int(np.floor(float(trim) * len(points)))
    keep = np.ones(len(points), bool)
    if drop > 0:
        dist = np.linalg.norm(points - np.median(points, axis=0), axis=1)
        keep[np.argsort(-dist, kind="stable")[:drop]] = False
    return keep


class QualifierRegions(ParamsMixin):
    """One axis-aligned box per qualifier in PCA space (configure, fit, query).

    ``fit(points)`` takes ``{qualifier: (k,d) points}`` (d = 3 in PCA space; names in English or
    French).  Fitted: ``names_`` (canonical, sorted), ``boxes_`` ``{name: (lo, hi)}``,
    ``centres_`` ``{name: (3,)}``, ``kept_`` ``{name: (k',3) points after trimming}``,
    ``collision_matrix_`` (q,q): row A, column B = % of A's kept points inside
    B's box (the diagonal is 100 by construction), ``n_features_in_`` (d).  In scikit-learn's
    form ``fit(X, y)`` takes the points ``X`` (n,d) and their qualifier names ``y`` (n,).

    >>> regions = QualifierRegions(trim=0).fit({"dense": [[0, 0, 0], [2, 2, 2]], "petit": [[1, 1, 1], [5, 5, 5]]})
    >>> regions.centres_["dense"].tolist(), regions.collision_matrix_.round(1).tolist()
    ([1.0, 1.0, 1.0], [[100.0, 50.0], [50.0, 100.0]])
    """

    _fitted_attribute = "boxes_"
    _y_required = True

    def __init__(self, trim: float = 0.07) -> None:
        self.trim = trim

    def fit(self, X: Mapping[str, ArrayLike] | ArrayLike, y: ArrayLike | None = None) -> Self:
        """Fit one box per qualifier: ``X`` is ``{qualifier: (k,d) points}``, or scikit-learn's form,
        points ``X`` (n,d) with their qualifier names ``y`` (n,).  Non-finite points are left out."""
        trim = float(self.trim)
        if not 0 <= trim < 1:
            raise ValueRefused(f"trim must be a fraction in [0, 1), not {self.trim}")
        merged: dict[str, np.ndarray] = {}
        for name, pts in self._groups(X, y):
            key = canonical_name(name)
            merged[key] = np.vstack([merged[key], pts]) if key in merged else pts
        merged = {k: v[np.all(np.isfinite(v), axis=1)] for k, v in merged.items()}
        merged = {k: v for k, v in merged.items() if len(v)}
        if not merged:
            raise ValueRefused("no qualifier points to build regions from")
        self.names_ = sorted(merged)
        self.kept_ = {k: v[trim_points(v, trim)] for k, v in merged.items()}
        self.boxes_ = {k: (v.min(axis=0), v.max(axis=0)) for k, v in self.kept_.items()}
        self.centres_ = {k: (lo + hi) / 2.0 for k, (lo, hi) in self.boxes_.items()}
        q = len(self.names_)
        matrix = np.zeros((q, q))
        for i, a in enumerate(self.names_):
            for j, b in enumerate(self.names_):
                matrix[i, j] = 100.0 * self.contains(b, self.kept_[a]).mean()
        self.collision_matrix_ = matrix
        return self

    def _groups(self, X, y) -> list[tuple[str, np.ndarray]]:
        """``(name, (k,d) points)`` pairs from a mapping, or from points and labels."""
        if isinstance(X, Mapping) and not hasattr(X, "toarray"):  # scipy's dok arrays are dicts
            if y is not None:
                raise ValueRefused("give the qualifier names either as the mapping's keys or as y, not both")
            groups = [(str(name), _rows(pts)) for name, pts in X.items()]
            if groups:
                self.n_features_in_ = groups[0][1].shape[1]
            return groups
        if y is None:
            raise ValueRefused(
                "QualifierRegions requires y to be passed, but the target y is None (y: the qualifier name of each point in X)"
            )
        X = check_rows(self, X, fitting=True)
        labels = np.asarray(y)
        if labels.shape != (len(X),):
            raise ValueRefused(f"y must hold one qualifier name per point: {len(X)} names, got shape {labels.shape}")
        return [(str(label), X[labels == label]) for label in dict.fromkeys(labels.tolist())]

    def _name(self, name):
        self._check_fitted()
        key = canonical_name(name)
        if key not in self.boxes_:
            raise ValueRefused(f"no region for qualifier {name!r} (known: {', '.join(self.names_)})")
        return key

    def __contains__(self, name) -> bool:
        return hasattr(self, "boxes_") and canonical_name(name) in self.boxes_

    def contains(self, name: str, points: ArrayLike) -> np.ndarray:
        key = self._name(name)
        lo, hi = self.boxes_[key]
        points = _rows(points, len(lo))
        return np.all((points >= lo - 1e-12) & (points <= hi + 1e-12), axis=1)

    def nearest_variants(self, name: str, cloud: ArrayLike) -> np.ndarray:
        """Variant indices of ``cloud`` (N,3) by distance to the region's centre (NaN rows left out)."""
        key = self._name(name)
        centre = self.centres_[key]
        cloud = np.asarray(cloud, float)
        ok = np.flatnonzero(np.all(np.isfinite(cloud), axis=1))
        return ok[np.argsort(np.linalg.norm(cloud[ok] - centre, axis=1), kind="stable")]

    def mean_collision(self) -> float:
        """Mean of the off-diagonal collision percentages (the thesis reports 66 %, 61 % trimmed)."""
        m = self.collision_matrix_
        off = ~np.eye(len(m), dtype=bool)
        return float(m[off].mean()) if off.any() else 0.0

    def to_dict(self) -> dict:
        return {
            "trim": float(self.trim),
            "names": self.names_,
            "boxes": {k: {"lo": lo.tolist(), "hi": hi.tolist()} for k, (lo, hi) in self.boxes_.items()},
            "collision_matrix": self.collision_matrix_.tolist(),
        }


# -- the front door -------------------------------------------------------------
def ranked_variants(
    name: str,
    sweep: VariantSweep | ArrayLike,
    points: ArrayLike | None = None,
    regions: QualifierRegions | None = None,
    rules: Iterable[int] | None = None,
    directions: Mapping[str, Mapping[str, float]] | None = None,
) -> tuple[np.ndarray, str]:
    """``(indices best first, source)`` for qualifier ``name`` on a fitted sweep.

    A :class:`QualifierModel` ranks the variants; with study ``regions`` and
    the sweep's PCA cloud ``points`` the regions refine the directions
    (source ``"region"``), with ``directions`` from another grammar they
    replace them (``"transfer"``), otherwise the default vocabulary's
    (``"vocabulary"``).  ``rules`` restricts to variants on those rules.
    """
    model = QualifierModel(directions=directions, regions=regions).fit(sweep, points=points)
    key = canonical_name(name)
    order = model.rank(key, rules=rules)
    source = model.sources_.get(key, "vocabulary")
    if not len(order):
        raise ValueRefused(
            f"no variant available for qualifier {name!r}" + (f" on rule(s) {sorted(rules)}" if rules is not None else "")
        )
    return order, source


def qualifier_combination(
    name: str,
    sweep: VariantSweep | LSystem | str | os.PathLike,
    points: ArrayLike | None = None,
    regions: QualifierRegions | None = None,
    rules: Iterable[int] | None = None,
    directions: Mapping[str, Mapping[str, float]] | None = None,
) -> dict:
    """The parameter combination ``{"rule", "constants"}`` that qualifier ``name`` applies.

    ``sweep`` is a fitted :class:`~ramure.metrics.sweep.VariantSweep`, or a grammar
    (LSystem or file path), which is then swept with the default settings
    (cached on disk, so only the first call is slow).

    >>> from ramure.metrics import VariantSweep
    >>> sweep = VariantSweep(n=4, n_jobs=1, cache=False).fit("honda_sympodial")
    >>> combo = qualifier_combination("dense", sweep)
    >>> sorted(combo), combo["rule"] in (0, 1)
    (['constants', 'rule'], True)
    """
    if not hasattr(sweep, "deltas_"):
        from .sweep import VariantSweep

        sweep = VariantSweep().fit(sweep)
    fitted = cast("VariantSweep", sweep)  # fitted from here on (duck-typed on deltas_)
    order, _ = ranked_variants(name, fitted, points, regions, rules, directions)
    return fitted.combination(int(order[0]))


def qualifier_space(sweep: VariantSweep | ArrayLike) -> np.ndarray:
    """The variants (N,15) in the space the qualifiers are defined in: each of the fifteen
    metrics' change divided by its spread over the sweep (NaN rows for failed variants)."""
    deltas = _deltas_of(sweep)
    return standardise(deltas, metric_scale(deltas))


#: Candidates a vocabulary region surrounds: as many as a qualifier tries first
#: (:func:`ramure.metrics.apply.apply_qualifier`'s ``tries``).
REGION_CANDIDATES = 5


def vocabulary_regions(
    sweep: VariantSweep | ArrayLike,
    points: ArrayLike | None = None,
    per_qualifier: int = REGION_CANDIDATES,
    trim: float = 0.0,
) -> QualifierRegions:
    """Regions of the default vocabulary on one grammar, before any study.

    Each directional qualifier's box surrounds its ``per_qualifier`` best
    candidates that it owns (tier 1 of :meth:`QualifierModel.rank`): the ones
    applying it tries first (5 by default; 10 made a box of every variant a word
    owns far from its best, and on the shrub 4 pairs overlapped where 2 do now) in
    ``points``: by default the fifteen-metric :func:`qualifier_space` (the
    ten-metric PCA cloud of an exploration lacks height, width and angles, so
    there "regular" and "irregular" fall in one box), or a PCA cloud (N,3);
    the collision matrix then tells how far the qualifiers' choices overlap.
    """
    model = QualifierModel().fit(sweep)
    points = qualifier_space(sweep) if points is None else np.asarray(points, float)
    boxes: dict[str, np.ndarray] = {}
    for name in model.names_:
        q = model.index(name)
        order = model.rank(name)
        order = order[(model.owner_[order] == q) & (model.scores_[order, q] > 0)][:per_qualifier]
        pts = points[order]
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        if len(pts):
            boxes[name] = pts
    return QualifierRegions(trim=trim).fit(boxes)


#: A region lying more than this share (%) inside another's box does not separate from it.
SEPARATION = 25.0


def synonyms(regions: QualifierRegions, threshold: float = SEPARATION) -> list[tuple[str, str, float]]:
    """Pairs ``(a, b, percent)`` whose regions do not separate on this plant: more than
    ``threshold`` % of ``a``'s points lie inside ``b``'s box, or the other way (``percent`` is
    the larger share).  The data cannot tell these words apart here: they are synonyms for
    this plant.

    >>> regions = QualifierRegions(trim=0).fit({"tall": [[0, 0, 0], [2, 2, 2]], "large": [[1, 1, 1], [5, 5, 5]],
    ...                                          "wide": [[9, 9, 9], [10, 10, 10]]})
    >>> synonyms(regions)
    [('large', 'tall', 50.0)]
    """
    m = regions.collision_matrix_
    names = regions.names_
    out = []
    for i, a in enumerate(names):
        for j in range(i + 1, len(names)):
            share = float(max(m[i, j], m[j, i]))
            if share > threshold:
                out.append((a, names[j], round(share, 1)))
    return sorted(out, key=lambda t: (-t[2], t[0], t[1]))


def matrix_table(regions: QualifierRegions) -> str:
    """The collision matrix as a text table (row A, column B: % of A's points in B's box)."""
    names = regions.names_
    width = max(6, max(len(n) for n in names))
    head = " " * width + " " + " ".join(f"{n[:6]:>6}" for n in names)
    rows = [head]
    for i, a in enumerate(names):
        cells = " ".join("     ." if i == j else f"{regions.collision_matrix_[i, j]:6.1f}" for j in range(len(names)))
        rows.append(f"{a:>{width}} {cells}")
    rows.append(f"mean off-diagonal collision: {regions.mean_collision():.1f} %")
    pairs = synonyms(regions)
    if pairs:
        said = ", ".join(f"{a} ~ {b} ({share:.0f} %)" for a, b, share in pairs)
        rows.append(f"synonyms for this plant (regions more than {SEPARATION:.0f} % inside each other): {said}")
    return "\n".join(rows)
