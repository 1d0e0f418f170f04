"""Qualifiers: the default vocabulary, qualifier regions in PCA space, and their combinations.

**Default vocabulary.**  Before any study exists, each of the thirteen
qualifiers of the thesis's collision matrix has a documented *direction* in
metric-delta space.  Variants are ranked by their projection on it, after
dividing each metric's delta by its standard deviation over the sweep (so
``small = -box_volume - total_length`` weighs both terms equally; a metric
that never varies contributes nothing).  The best-ranked variant's parameter
combination is what "make this selection <qualifier>" applies, so it works on
any grammar from day one.  ``normal`` has no direction: it ranks variants by
closeness to the base plant (the smallest standardised deltas), i.e. it
gives back the grammar's own look.

The ten metrics do not measure symmetry, roundness or realism directly, so
those directions are proxies, documented in :data:`VOCABULARY`:
``round``/``symmetric`` favour a compact box (``1.5 d_box_surface -
d_box_volume`` is the first-order change of ``S^1.5 / V``, smallest for a
cube), ``fir-like``/``asymmetric`` an elongated one, ``realistic`` sturdier
and fuller branches.  A study replaces these guesses with measured regions.

**Regions** (:class:`QualifierRegions`, thesis §5.5): from labelled variant
points per qualifier (a study's, read from the :mod:`ramure.metrics.store`), one
axis-aligned box per qualifier in PCA space, after trimming the ``trim``
share (7 % by default) of its points farthest from the qualifier's median
point (``floor(trim * k)`` of k points); the collision matrix; and the box
centre -> nearest variant -> its parameter combination.

>>> import numpy as np
>>> canonical_name("Épars"), canonical_name("sapin"), canonical_name("Fir like")
('sparse', 'fir-like', 'fir-like')
>>> deltas = np.array([[10.0, 0, 0, 0, -5, 0, 0, 0, 0, 0], [0, 0, 0, 0, 20, 0, 0, 0, 0, 0]])
>>> rank_variants("dense", deltas).tolist()
[1, 0]
"""
from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass

import numpy as np

from ramure.errors import RamureError

from .plant import METRIC_NAMES


@dataclass(frozen=True)
class Qualifier:
    """A vocabulary entry: English ``name``, ``french`` name, metric weights (None: nearest
    to the base plant) and what the direction means."""

    name: str
    french: str
    direction: dict | None
    meaning: str

    def vector(self) -> np.ndarray | None:
        """The unit direction (10,) over :data:`~ramure.metrics.plant.METRIC_NAMES`, or None."""
        if self.direction is None:
            return None
        v = np.array([self.direction.get(m, 0.0) for m in METRIC_NAMES], float)
        return v / np.linalg.norm(v)


_COMPACT = {"box_volume": 1.0, "box_surface": -1.5}
_ELONGATED = {"box_volume": -1.0, "box_surface": 1.5}

#: The default vocabulary: canonical English name -> :class:`Qualifier`.
VOCABULARY = {q.name: q for q in [
    Qualifier("small", "petit", {"box_volume": -1, "total_length": -1}, "smaller box, shorter branches"),
    Qualifier("large", "grand", {"box_volume": 1, "total_length": 1}, "bigger box, longer branches"),
    Qualifier("sparse", "épars", {"branch_density": -1, "fill_rate": -1},
              "fewer branches and less wood per unit of box volume"),
    Qualifier("dense", "dense", {"branch_density": 1}, "more branches per unit of box volume (+density)"),
    Qualifier("symmetric", "symétrique", dict(_COMPACT),
              "proxy: a more cube-like box (lower surface^1.5 / volume)"),
    Qualifier("asymmetric", "asymétrique", dict(_ELONGATED),
              "proxy: a more elongated, lopsided box (higher surface^1.5 / volume)"),
    Qualifier("realistic", "réaliste", {"mean_radius": 1, "fill_rate": 0.5, "mean_length": -0.5},
              "proxy: sturdier, shorter branches that fill their box more"),
    Qualifier("unrealistic", "irréaliste", {"mean_radius": -1, "fill_rate": -0.5, "mean_length": 0.5},
              "proxy: spindly, long branches in an emptier box"),
    Qualifier("fir-like", "sapin", {**_ELONGATED, "branch_density": 0.5},
              "an elongated box densely filled with branches (tall, narrow, busy)"),
    Qualifier("normal", "normal", None, "closest to the base plant (smallest standardised deltas)"),
    Qualifier("thin", "mince", {"mean_radius": -1, "branch_volume": -1}, "thinner branches, less wood"),
    Qualifier("thick", "gros", {"mean_radius": 1, "branch_volume": 1}, "thicker branches, more wood"),
    Qualifier("round", "rond", {**_COMPACT, "fill_rate": 0.5},
              "a compact, cube-like box well filled with wood"),
]}

_ALIASES = {"fir": "fir-like", "fir-tree": "fir-like", "denser": "dense", "sparser": "sparse",
            "smaller": "small", "larger": "large", "big": "large", "thinner": "thin", "thicker": "thick",
            "rounder": "round", "rounded": "round"}


def _fold(text) -> str:
    text = unicodedata.normalize("NFKD", str(text))
    text = "".join(c for c in text if not unicodedata.combining(c)).lower()
    return "-".join(re.sub(r"[^0-9a-z]+", " ", text).split())


_LOOKUP = {**{_fold(q.name): q.name for q in VOCABULARY.values()},
           **{_fold(q.french): q.name for q in VOCABULARY.values()},
           **{_fold(k): v for k, v in _ALIASES.items()}}


def canonical_name(name) -> str:
    """The canonical English name of a qualifier given in English or French (any case, accents)."""
    key = _fold(name)
    if key in _LOOKUP:
        return _LOOKUP[key]
    return key


def vocabulary_name(name) -> str:
    """Like :func:`canonical_name` but refuses names outside the default vocabulary."""
    key = canonical_name(name)
    if key not in VOCABULARY:
        known = ", ".join(f"{q.name}/{q.french}" for q in VOCABULARY.values())
        raise RamureError(f"unknown qualifier {name!r}; the vocabulary is: {known}")
    return key


def _deltas_of(source):
    deltas = getattr(source, "deltas_", source)
    deltas = np.asarray(deltas, float)
    if deltas.ndim != 2 or deltas.shape[1] != len(METRIC_NAMES):
        raise RamureError(f"expected deltas of shape (N, {len(METRIC_NAMES)}), got {deltas.shape}")
    return deltas


def metric_scale(deltas) -> np.ndarray:
    """Standard deviation of each metric's delta over valid variants (0 where it never varies)."""
    deltas = _deltas_of(deltas)
    ok = np.all(np.isfinite(deltas), axis=1)
    return deltas[ok].std(axis=0) if ok.any() else np.zeros(deltas.shape[1])


def qualifier_scores(name, deltas, scale=None) -> np.ndarray:
    """Score (N,) of each variant for qualifier ``name``; higher is better, NaN for failed variants.

    ``deltas`` (N,10) or a fitted sweep; ``scale`` (10,) the per-metric
    standardisation (default: :func:`metric_scale` of ``deltas``).
    """
    q = VOCABULARY[vocabulary_name(name)]
    deltas = _deltas_of(deltas)
    scale = metric_scale(deltas) if scale is None else np.asarray(scale, float)
    z = np.divide(deltas, scale, out=np.zeros_like(deltas), where=scale > 0)
    z[~np.isfinite(deltas)] = np.nan
    if q.direction is None:
        return -np.linalg.norm(z, axis=1)
    return z @ q.vector()


def rank_variants(name, deltas, rules=None, variant_rules=None) -> np.ndarray:
    """Variant indices, best first, for qualifier ``name`` (failed variants left out).

    With ``rules`` (a set of rule indices) and ``variant_rules`` (N,) only the
    variants acting on one of those rules are ranked — e.g. the rules that
    actually rewrite inside a selection.
    """
    scores = qualifier_scores(name, deltas)
    keep = np.isfinite(scores)
    if rules is not None:
        variant_rules = getattr(deltas, "rules_", variant_rules)
        if variant_rules is None:
            raise RamureError("ranking by rules needs each variant's rule (pass a fitted sweep)")
        keep &= np.isin(np.asarray(variant_rules), np.asarray(sorted(rules), dtype=np.int64))
    idx = np.flatnonzero(keep)
    return idx[np.argsort(-scores[idx], kind="stable")]


# -- regions --------------------------------------------------------------------
def trim_points(points, trim=0.07) -> np.ndarray:
    """Boolean mask keeping all but the ``floor(trim * k)`` points farthest from the median point."""
    points = np.asarray(points, float).reshape(-1, 3)
    drop = int(np.floor(float(trim) * len(points)))
    keep = np.ones(len(points), bool)
    if drop > 0:
        dist = np.linalg.norm(points - np.median(points, axis=0), axis=1)
        keep[np.argsort(-dist, kind="stable")[:drop]] = False
    return keep


class QualifierRegions:
    """One axis-aligned box per qualifier in PCA space (configure, fit, query).

    ``fit(points)`` takes ``{qualifier: (k,3) points}`` (names in English or
    French).  Fitted: ``names_`` (canonical, sorted), ``boxes_`` ``{name: (lo, hi)}``,
    ``centres_`` ``{name: (3,)}``, ``kept_`` ``{name: (k',3) points after trimming}``,
    ``collision_matrix_`` (q,q): row A, column B = % of A's kept points inside
    B's box (the diagonal is 100 by construction).

    >>> regions = QualifierRegions(trim=0).fit({"dense": [[0, 0, 0], [2, 2, 2]], "petit": [[1, 1, 1], [5, 5, 5]]})
    >>> regions.centres_["dense"].tolist(), regions.collision_matrix_.round(1).tolist()
    ([1.0, 1.0, 1.0], [[100.0, 50.0], [50.0, 100.0]])
    """

    def __init__(self, trim=0.07):
        self.trim = trim

    def fit(self, points):
        trim = float(self.trim)
        if not 0 <= trim < 1:
            raise RamureError(f"trim must be a fraction in [0, 1), not {self.trim}")
        merged = {}
        for name, pts in dict(points).items():
            pts = np.asarray(pts, float).reshape(-1, 3)
            key = canonical_name(name)
            merged[key] = np.vstack([merged[key], pts]) if key in merged else pts
        merged = {k: v[np.all(np.isfinite(v), axis=1)] for k, v in merged.items()}
        merged = {k: v for k, v in merged.items() if len(v)}
        if not merged:
            raise RamureError("no qualifier points to build regions from")
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

    def _name(self, name):
        if not hasattr(self, "boxes_"):
            raise RamureError("these regions are not fitted yet: call fit(points) first")
        key = canonical_name(name)
        if key not in self.boxes_:
            raise RamureError(f"no region for qualifier {name!r} (known: {', '.join(self.names_)})")
        return key

    def __contains__(self, name):
        return hasattr(self, "boxes_") and canonical_name(name) in self.boxes_

    def contains(self, name, points) -> np.ndarray:
        lo, hi = self.boxes_[self._name(name)]
        points = np.asarray(points, float).reshape(-1, 3)
        return np.all((points >= lo - 1e-12) & (points <= hi + 1e-12), axis=1)

    def nearest_variants(self, name, cloud) -> np.ndarray:
        """Variant indices of ``cloud`` (N,3) by distance to the region's centre (NaN rows left out)."""
        centre = self.centres_[self._name(name)]
        cloud = np.asarray(cloud, float)
        ok = np.flatnonzero(np.all(np.isfinite(cloud), axis=1))
        return ok[np.argsort(np.linalg.norm(cloud[ok] - centre, axis=1), kind="stable")]

    def mean_collision(self) -> float:
        """Mean of the off-diagonal collision percentages (the thesis reports 66 %, 61 % trimmed)."""
        m = self.collision_matrix_
        off = ~np.eye(len(m), dtype=bool)
        return float(m[off].mean()) if off.any() else 0.0

    def to_dict(self) -> dict:
        return {"trim": float(self.trim), "names": self.names_,
                "boxes": {k: {"lo": lo.tolist(), "hi": hi.tolist()} for k, (lo, hi) in self.boxes_.items()},
                "collision_matrix": self.collision_matrix_.tolist()}


# -- the front door -------------------------------------------------------------
def ranked_variants(name, sweep, points=None, regions=None, rules=None) -> tuple:
    """``(indices best first, source)`` for qualifier ``name`` on a fitted sweep.

    If ``regions`` has a box for ``name`` and the sweep's PCA cloud ``points``
    (N,3) is given, variants are ordered by distance to the box centre
    (source ``"region"``); otherwise by the default vocabulary's direction
    (source ``"vocabulary"``).  ``rules`` restricts to variants on those rules.
    """
    if regions is not None and points is not None and name in regions:
        order = regions.nearest_variants(name, points)
        if rules is not None:
            order = order[np.isin(sweep.rules_[order], np.asarray(sorted(rules), dtype=np.int64))]
        source = "region"
    else:
        order = rank_variants(name, sweep, rules=rules)
        source = "vocabulary"
    if not len(order):
        raise RamureError(f"no variant available for qualifier {name!r}"
                          + (f" on rule(s) {sorted(rules)}" if rules is not None else ""))
    return order, source


def qualifier_combination(name, sweep, points=None, regions=None, rules=None) -> dict:
    """The parameter combination ``{"rule", "constants"}`` that qualifier ``name`` applies.

    ``sweep`` is a fitted :class:`~ramure.metrics.sweep.VariantSweep`, or a grammar
    (LSystem or file path), which is then swept with the default settings
    (cached on disk, so only the first call is slow).

    >>> from metrics import VariantSweep
    >>> sweep = VariantSweep(n=4, n_jobs=1, cache=False).fit("grammars/honda_sympodial.lsys")
    >>> combo = qualifier_combination("dense", sweep)
    >>> sorted(combo), combo["rule"] in (0, 1)
    (['constants', 'rule'], True)
    """
    if not hasattr(sweep, "deltas_"):
        from .sweep import VariantSweep

        sweep = VariantSweep().fit(sweep)
    order, _ = ranked_variants(name, sweep, points, regions, rules)
    return sweep.combination(int(order[0]))
