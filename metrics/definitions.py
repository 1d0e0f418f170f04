"""One definition per qualifier: the metric it moves and which way (issue 35).

A qualifier's *direction* (:data:`ramure.metrics.qualifiers.VOCABULARY`)
ranks variants; its *definition* here is the promise a user can check with
a ruler: the metric that must move, and its sign.  A variant or a regrown
part is applied for a qualifier only when its definition holds
(:func:`definition_holds`): the ``metric`` moves ``sign``-wards and so does
every metric in ``also``, each by more than :data:`TOLERANCE` (relative).

===============  ====================================  ==============================
qualifier        moves                                 and also
===============  ====================================  ==============================
small / large    ``box_volume`` down / up              ``height`` down / up
dense / sparse   ``branch_count`` up / down            ``branch_density`` up / down
bushy            ``branch_count`` up                   ``crown_width`` up
asymmetric /     ``asymmetry`` up / down
symmetric
realistic /      ``slenderness`` down / up
unrealistic
fir-like         ``crown_ratio`` up
thick / thin     ``mean_radius`` up / down
round            ``sphericity`` up
tall / short     ``height`` up / down
wide / narrow    ``crown_width`` up / down
drooping /       ``branch_angle`` up / down
upright
irregular /      ``angle_spread`` up / down
regular
===============  ====================================  ==============================

Three metrics are ratios of the fifteen qualifier metrics (:data:`DERIVED_METRICS`):
``sphericity`` of the box, ``pi^(1/3) (6 V)^(2/3) / S`` (1 for a sphere,
0.806 for a cube, lower for a flat or long box), ``slenderness``
``mean_length / mean_radius`` and ``crown_ratio`` ``height / crown_width``.
Their relative change follows from the fifteen relative changes, so a
definition is checked on a sweep's deltas as well as on measured values.

>>> import numpy as np
>>> DEFINITIONS["round"].describe(), DEFINITIONS["small"].describe()
('+sphericity', '-box_volume -height')
>>> before = np.ones(15); after = before.copy(); after[0] = 8.0; after[1] = 4.0   # box volume x8, surface x4
>>> round(float(metric_value("sphericity", after) / metric_value("sphericity", before)), 6)
1.0
>>> bool(definition_holds("large", metric_changes(after, before))), bool(definition_holds("tall", metric_changes(after, before)))
(False, False)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

from .plant import METRIC_NAMES, metric_deltas
from .shape import SHAPE_METRIC_NAMES, shape_deltas

#: The fifteen metrics definitions read (as :data:`ramure.metrics.qualifiers.QUALIFIER_METRICS`).
BASE_METRICS = tuple(METRIC_NAMES) + tuple(SHAPE_METRIC_NAMES)
#: Ratios of the fifteen: ``{name: {metric: power}}`` (constant factors left out).
DERIVED_METRICS = {
    "sphericity": {"box_volume": 2.0 / 3.0, "box_surface": -1.0},
    "slenderness": {"mean_length": 1.0, "mean_radius": -1.0},
    "crown_ratio": {"height": 1.0, "crown_width": -1.0},
}
_SPHERE = np.pi ** (1.0 / 3.0) * 6.0 ** (2.0 / 3.0)
#: A change smaller than this (relative: 1e-6, here in %) is no move.
TOLERANCE = 1e-4

#: What a user reads: the metric in words.
LABELS = {
    "box_volume": "box volume",
    "box_surface": "box surface",
    "branch_surface": "wood surface",
    "branch_volume": "wood volume",
    "branch_density": "branches per unit of box volume",
    "branch_count": "number of branch segments",
    "fill_rate": "share of the box filled with wood",
    "total_length": "total branch length",
    "mean_length": "segment length",
    "mean_radius": "branch radii",
    "height": "height",
    "crown_width": "crown width",
    "branch_angle": "branch angles to the vertical",
    "angle_spread": "spread of the branching angles",
    "asymmetry": "one-sidedness around the trunk",
    "sphericity": "roundness of the box",
    "slenderness": "slenderness of the segments",
    "crown_ratio": "height over crown width",
}


@dataclass(frozen=True)
class Definition:
    """``metric`` moves ``sign`` (+1 up, -1 down), and so does each ``(metric, sign)`` of ``also``."""

    metric: str
    sign: int
    also: tuple[tuple[str, int], ...] = ()

    def terms(self) -> tuple[tuple[str, int], ...]:
        """Every ``(metric, sign)`` that must hold, the defining metric first."""
        return ((self.metric, self.sign), *self.also)

    def describe(self) -> str:
        """``-box_volume -height``: each metric with the sign it must move."""
        return " ".join(f"{'+' if s > 0 else '-'}{m}" for m, s in self.terms())

    def sentence(self) -> str:
        """In words: ``raises the height``."""
        return " and ".join(f"{'raises' if s > 0 else 'lowers'} the {LABELS[m]}" for m, s in self.terms())


def _pair(pos: str, neg: str, metric: str, also: tuple = ()) -> dict[str, Definition]:
    return {
        pos: Definition(metric, 1, tuple((m, s) for m, s in also)),
        neg: Definition(metric, -1, tuple((m, -s) for m, s in also)),
    }


#: The table of the module docstring: qualifier -> :class:`Definition`.
DEFINITIONS: dict[str, Definition] = {
    **_pair("large", "small", "box_volume", (("height", 1),)),
    **_pair("dense", "sparse", "branch_count", (("branch_density", 1),)),
    "bushy": Definition("branch_count", 1, (("crown_width", 1),)),
    **_pair("asymmetric", "symmetric", "asymmetry"),
    **_pair("unrealistic", "realistic", "slenderness"),
    "fir-like": Definition("crown_ratio", 1),
    **_pair("thick", "thin", "mean_radius"),
    "round": Definition("sphericity", 1),
    **_pair("tall", "short", "height"),
    **_pair("wide", "narrow", "crown_width"),
    **_pair("drooping", "upright", "branch_angle"),
    **_pair("irregular", "regular", "angle_spread"),
}


def _check(metric: str) -> None:
    if metric not in BASE_METRICS and metric not in DERIVED_METRICS:
        known = ", ".join([*BASE_METRICS, *DERIVED_METRICS])
        raise ValueRefused(f"unknown metric {metric!r} (known: {known})")


def metric_value(metric: str, values: ArrayLike) -> np.ndarray:
    """The value of ``metric`` (one of the fifteen or a derived ratio) for values (..., 15)."""
    _check(metric)
    values = np.asarray(values, float)
    if metric in BASE_METRICS:
        return values[..., BASE_METRICS.index(metric)]
    out = np.ones(values.shape[:-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        for m, power in DERIVED_METRICS[metric].items():
            out = out * values[..., BASE_METRICS.index(m)] ** power
    if metric == "sphericity":
        out = _SPHERE * out
    return np.where(np.isfinite(out), out, 0.0)


def metric_changes(after: ArrayLike, before: ArrayLike) -> np.ndarray:
    """Relative changes (..., 15) in % of the fifteen metrics, as a sweep's deltas."""
    after, before = np.asarray(after, float), np.asarray(before, float)
    k = len(METRIC_NAMES)
    return np.concatenate([metric_deltas(after[..., :k], before[:k]), shape_deltas(after[..., k:], before[k:])], axis=-1)


def metric_change(metric: str, deltas: ArrayLike) -> np.ndarray:
    """The relative change in % of ``metric`` from the fifteen relative changes ``deltas`` (..., 15)."""
    _check(metric)
    deltas = np.asarray(deltas, float)
    if metric in BASE_METRICS:
        return deltas[..., BASE_METRICS.index(metric)]
    ratio = np.ones(deltas.shape[:-1])
    with np.errstate(invalid="ignore", divide="ignore"):  # a metric falling to 0 under a negative power: inf
        for m, power in DERIVED_METRICS[metric].items():
            ratio = ratio * np.maximum(1.0 + deltas[..., BASE_METRICS.index(m)] / 100.0, 0.0) ** power
    return 100.0 * (ratio - 1.0)


def definition_holds(name: str, deltas: ArrayLike) -> np.ndarray:
    """Whether qualifier ``name``'s definition holds for relative changes ``deltas`` (..., 15).

    Every term must move its way by more than :data:`TOLERANCE`; NaN (a failed variant) never holds.
    """
    if name not in DEFINITIONS:
        raise ValueRefused(f"qualifier {name!r} has no definition (defined: {', '.join(DEFINITIONS)})")
    deltas = np.asarray(deltas, float)
    ok = np.ones(deltas.shape[:-1], bool)
    for metric, sign in DEFINITIONS[name].terms():
        change = metric_change(metric, deltas)
        ok &= np.isfinite(change) & (sign * change > TOLERANCE)
    return ok


def lacks(name: str, deltas: ArrayLike, base: ArrayLike | None = None) -> str:
    """Why no change in ``deltas`` (N, 15) satisfies ``name``'s definition, in the user's words.

    ``"no constant or rule changes the branch angles to the vertical"`` when no variant moves
    a term at all; otherwise which way the variants move it.  With the plant's fifteen
    ``base`` values, a term that must fall from 0 says so: ``"the plant's one-sidedness around
    the trunk is already 0"`` (a symmetric plant cannot be made more symmetric).

    >>> lacks("symmetric", np.zeros((2, 15)), base=np.r_[np.ones(14), 0.0])
    "the plant's one-sidedness around the trunk is already 0 (nothing can lower it)"
    """
    deltas = np.asarray(deltas, float).reshape(-1, len(BASE_METRICS))
    deltas = deltas[np.all(np.isfinite(deltas), axis=1)]
    for metric, sign in DEFINITIONS[name].terms():
        change = metric_change(metric, deltas)
        label = LABELS[metric]
        if base is not None and sign < 0 and abs(float(metric_value(metric, base))) <= 1e-9:
            return f"the plant's {label} is already 0 (nothing can lower it)"
        if not np.any(np.abs(change) > TOLERANCE):
            return f"no constant or rule changes the {label}"
        if not np.any(sign * change > TOLERANCE):
            way = "raises" if sign > 0 else "lowers"
            return f"no constant or rule {way} the {label} (the variants only move it the other way)"
    terms = DEFINITIONS[name].terms()
    words = " and ".join(f"{'raises' if s > 0 else 'lowers'} the {LABELS[m]}" for m, s in terms)
    if len(terms) == 1:  # the moves it sees are rounding noise around 0, or score nothing
        return f"no constant or rule {words} measurably"
    return f"no constant or rule {words} at once"


def definition_table() -> list[dict]:
    """One dict per defined qualifier: ``name``, ``metric``, ``sign``, ``also``, ``definition``, ``sentence``."""
    return [
        {
            "name": name,
            "metric": d.metric,
            "sign": d.sign,
            "also": [list(t) for t in d.also],
            "definition": d.describe(),
            "sentence": d.sentence(),
        }
        for name, d in DEFINITIONS.items()
    ]
