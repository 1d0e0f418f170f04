"""Shape metrics the ten metrics of the thesis cannot give: height, width, posture, regularity, balance.

The ten metrics (:mod:`ramure.metrics.plant`) measure size, wood and
density but not *where* the wood goes: "tall", "wide", "upright",
"regular" or "symmetric" need these five (``z`` is up, as the turtle
starts heading up the z axis):

=================  ==========================================================
``height``         vertical extent ``max z - min z`` of the segments' end points
``crown_width``    horizontal extent: the largest spread of the end points
                   projected on 32 evenly spaced compass directions (the
                   horizontal diameter to within ``1 - cos(pi/64)`` = 0.12 %)
``branch_angle``   length-weighted mean angle, in degrees, between each
                   segment and the vertical (0 upright, 90 horizontal, 180 hanging)
``angle_spread``   standard deviation, in degrees, of the branching angles:
                   the angle between a lateral segment (one whose branch
                   order is higher than its parent segment's) and its parent
                   segment; 0 when every branch leaves at the same angle
``asymmetry``      horizontal distance from the vertical through the lowest
                   segment start to the length-weighted centroid of the
                   segments, over half the crown width (0 balanced, 1 all
                   on one side)
=================  ==========================================================

Choices the issue leaves open: the plant's base for a selection is the
lowest start point of its segments; segments of length 0 carry no weight
and no angle; a selection with no lateral segment has ``angle_spread`` 0;
a lateral segment's parent may lie outside the selection (its geometry is
the plant's).  Organs are ignored, as in the ten metrics.

>>> import numpy as np
>>> start = np.array([[0, 0, 0], [0, 0, 2], [0, 0, 2.0]])
>>> end = np.array([[0, 0, 2], [1, 0, 3], [-1, 0, 3.0]])
>>> shape_from_arrays(start, end, parent=np.array([-1, 0, 0]), order=np.array([0, 1, 1])).round(3).tolist()
[3.0, 2.0, 26.36, 0.0, 0.0]
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton

SHAPE_METRIC_NAMES = ("height", "crown_width", "branch_angle", "angle_spread", "asymmetry")

_COMPASS = np.linspace(0.0, np.pi, 32, endpoint=False)
_DIRECTIONS = np.stack([np.cos(_COMPASS), np.sin(_COMPASS)])  # (2, 32)


class ShapeMetrics(NamedTuple):
    """The five shape metrics as a named record (``np.array(m)`` gives them in order)."""

    height: float
    crown_width: float
    branch_angle: float
    angle_spread: float
    asymmetry: float

    def to_dict(self) -> dict:
        return {k: float(v) for k, v in self._asdict().items()}


def _unit(v):
    norm = np.linalg.norm(v, axis=1)
    out = np.zeros_like(v)
    np.divide(v, norm[:, None], out=out, where=norm[:, None] > 0)
    return out, norm


def crown_width(points: ArrayLike) -> float:
    """Largest horizontal extent of ``points`` (m,3) over 32 compass directions."""
    points = np.asarray(points, float)
    if not len(points):
        return 0.0
    proj = points[:, :2] @ _DIRECTIONS
    return float(np.max(proj.max(axis=0) - proj.min(axis=0)))


def branching_angles(
    start: np.ndarray, end: np.ndarray, parent: ArrayLike, order: ArrayLike, mask: ArrayLike | None = None
) -> np.ndarray:
    """Angles (degrees) between each lateral segment in ``mask`` and its parent segment."""
    parent = np.asarray(parent, np.int64)
    order = np.asarray(order)
    mask = np.ones(len(parent), bool) if mask is None else np.asarray(mask, bool)
    has = mask & (parent >= 0)
    idx = np.flatnonzero(has)
    idx = idx[order[idx] > order[parent[idx]]]
    if not len(idx):
        return np.zeros(0)
    u, nu = _unit(end[idx] - start[idx])
    p, npar = _unit(end[parent[idx]] - start[parent[idx]])
    ok = (nu > 0) & (npar > 0)
    cos = np.clip(np.einsum("ij,ij->i", u[ok], p[ok]), -1.0, 1.0)
    return np.degrees(np.arccos(cos))


def shape_from_arrays(
    start: ArrayLike,
    end: ArrayLike,
    parent: ArrayLike | None = None,
    order: ArrayLike | None = None,
    mask: ArrayLike | None = None,
) -> np.ndarray:
    """The five shape metrics (5,) of the segments in ``mask`` (default all).

    ``start``/``end`` (s,3), ``parent`` (s,) and ``order`` (s,) are the whole
    plant's arrays (a lateral's parent may lie outside ``mask``); without
    ``parent``/``order`` the angle spread is 0.
    """
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    mask = np.ones(len(start), bool) if mask is None else np.asarray(mask, bool)
    s, e = start[mask], end[mask]
    if not len(s):
        return np.zeros(len(SHAPE_METRIC_NAMES))
    pts = np.concatenate([s, e])
    height = float(pts[:, 2].max() - pts[:, 2].min())
    width = crown_width(pts)
    u, h = _unit(e - s)
    total = float(h.sum())
    tilt = np.degrees(np.arccos(np.clip(u[:, 2], -1.0, 1.0)))
    angle = float((tilt * h).sum() / total) if total > 0 else 0.0
    spread = 0.0
    if parent is not None and order is not None:
        angles = branching_angles(start, end, parent, order, mask)
        spread = float(angles.std()) if len(angles) else 0.0
    asym = 0.0
    if total > 0 and width > 0:
        base = s[np.argmin(s[:, 2]), :2]
        centroid = (((s + e) / 2.0)[:, :2] * h[:, None]).sum(axis=0) / total
        asym = float(np.linalg.norm(centroid - base) / (width / 2.0))
    return np.array([height, width, angle, spread, asym])


def plant_shape(skeleton: Skeleton, leaf_ids: Iterable[int] | None = None, segments: Iterable[int] | None = None) -> ShapeMetrics:
    """The shape metrics of a plant, or of the segments drawn by ``leaf_ids`` / ``segments``.

    >>> from ramure.lsys import LSystem
    >>> sk = LSystem.from_text("n: 0\\nw: F(2)[+(90)F(1)]").derive().skeleton()
    >>> m = plant_shape(sk)
    >>> round(m.height, 6), round(m.crown_width, 6), round(m.branch_angle, 6), m.angle_spread
    (2.0, 1.0, 30.0, 0.0)
    """
    from .plant import selection_mask

    mask = selection_mask(skeleton, leaf_ids, segments)
    return ShapeMetrics(
        *(float(v) for v in shape_from_arrays(skeleton.start, skeleton.end, skeleton.parent, skeleton.order, mask))
    )


#: A shape metric's base value this close to 0 (metres, degrees) is rounding noise.
ZERO = 1e-9


def shape_deltas(variant: ArrayLike, base: ArrayLike) -> np.ndarray:
    """Change of shape metrics, rows of ``variant`` (..., k) against ``base`` (k,).

    ``100 (v / b - 1)`` like :func:`~ramure.metrics.plant.metric_deltas` where
    ``b != 0``; where the base value is 0 (e.g. a plant whose branches all
    leave at one angle has ``angle_spread`` 0) the plain difference ``v - b``,
    so a change away from 0 still counts.  A base value within :data:`ZERO` of 0 is
    rounding noise (a symmetric plant's asymmetry of 1e-17 m) and counts as 0: a
    change of 1e-17 is no move, not -50 %.  Non-finite values stay NaN.

    >>> shape_deltas(np.array([[2.0, 3.0, 0.5]]), np.array([1.0, 0.0, 1e-17])).tolist()
    [[100.0, 3.0, 0.5]]
    """
    variant = np.asarray(variant, float)
    base = np.asarray(base, float)
    ok = np.abs(base) > ZERO
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = 100.0 * (variant - base) / np.where(ok, np.abs(base), 1.0)
    out = np.where(ok, rel, variant - base)
    out[~np.isfinite(variant)] = np.nan
    return out
