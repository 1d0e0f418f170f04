"""The ten plant metrics of the thesis (§5.2), for a whole plant or a selection.

=====  ==================  ======================================================
#      name                definition (b base radius, t top radius, h length)
=====  ==================  ======================================================
1      ``box_volume``      OBB volume ``l w h`` (covariance box, see :mod:`ramure.metrics.obb`)
2      ``box_surface``     OBB surface ``2(lw + lh + wh)``
3      ``branch_surface``  lateral area ``sum pi (b + t) sqrt((b - t)^2 + h^2)``
4      ``branch_volume``   ``sum 1/3 pi (b^2 + b t + t^2) h``
5      ``branch_density``  ``branch_count / box_volume``
6      ``branch_count``    number of drawn segments (modules ``F``)
7      ``fill_rate``       ``branch_volume / box_volume`` (the thesis gives no formula;
                           we choose the share of the box filled with wood)
8      ``total_length``    ``sum h``
9      ``mean_length``     ``total_length / branch_count``
10     ``mean_radius``     ``(sum t + sum b) / (2 branch_count)``
=====  ==================  ======================================================

Only branch segments count; organs (leaves, fruit) are ignored, as in the
thesis.  Conventions for degenerate inputs: a selection that draws no segment
has every metric 0; a flat box (volume 0, e.g. zero-width 2D segments) has
``branch_density`` and ``fill_rate`` 0 rather than infinite.

>>> from ramure.lsys import LSystem
>>> sk = LSystem.from_text("n: 0\\nw: !(2)F(3)").derive().skeleton()   # one cylinder r=1, h=3
>>> m = plant_metrics(sk)
>>> m.branch_count, round(m.branch_volume, 6), round(m.branch_surface, 6), round(m.box_volume, 6)
(1, 9.424778, 18.849556, 12.0)
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import RamureError

from .obb import obb_from_frustums

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton

    from .obb import OrientedBox

METRIC_NAMES = (
    "box_volume",
    "box_surface",
    "branch_surface",
    "branch_volume",
    "branch_density",
    "branch_count",
    "fill_rate",
    "total_length",
    "mean_length",
    "mean_radius",
)
#: The thesis's abbreviations (Table 3.2), in the same order.
METRIC_SHORT = ("Vobb", "Sobb", "Sb", "Vb", "Db", "Nb", "Remp", "Lb", "Ml", "Mr")


class PlantMetrics(NamedTuple):
    """The ten metrics as a named record (``np.array(m)`` gives the vector in this order)."""

    box_volume: float
    box_surface: float
    branch_surface: float
    branch_volume: float
    branch_density: float
    branch_count: int
    fill_rate: float
    total_length: float
    mean_length: float
    mean_radius: float

    def to_dict(self) -> dict:
        return {k: (int(v) if k == "branch_count" else float(v)) for k, v in self._asdict().items()}


def metrics_from_arrays(
    start: np.ndarray, end: np.ndarray, base_radius: np.ndarray, top_radius: np.ndarray, box: OrientedBox | None = None
) -> np.ndarray:
    """The ten metrics (10,) of frustums given as arrays — the sweep's hot path.

    ``box`` is an :class:`~ramure.metrics.obb.OrientedBox` to use instead of the
    covariance OBB of the segments (e.g. a tight box).
    """
    count = len(start)
    if count == 0:
        return np.zeros(len(METRIC_NAMES))
    if box is None:
        box = obb_from_frustums(start, end, base_radius, top_radius)
    b, t = base_radius, top_radius
    h = np.linalg.norm(end - start, axis=1)
    surface = float(np.sum(np.pi * (b + t) * np.sqrt((b - t) ** 2 + h**2)))
    volume = float(np.sum(np.pi / 3.0 * (b * b + b * t + t * t) * h))
    total = float(h.sum())
    bv = box.volume
    density = count / bv if bv > 0 else 0.0
    fill = volume / bv if bv > 0 else 0.0
    return np.array(
        [
            bv,
            box.surface,
            surface,
            volume,
            density,
            count,
            fill,
            total,
            total / count,
            (float(t.sum()) + float(b.sum())) / (2.0 * count),
        ]
    )


def selection_mask(
    skeleton: Skeleton, leaf_ids: Iterable[int] | None = None, segments: Iterable[int] | None = None
) -> np.ndarray:
    """Boolean mask of the segments chosen by history leaves and/or segment indices.

    ``None`` for both means the whole plant; given both, their union.
    """
    n = len(skeleton)
    if leaf_ids is None and segments is None:
        return np.ones(n, bool)
    mask = np.zeros(n, bool)
    if leaf_ids is not None:
        mask |= skeleton.select(np.asarray(list(leaf_ids), np.int64).reshape(-1))
    if segments is not None:
        seg = np.asarray(list(segments), np.int64).reshape(-1)
        bad = seg[(seg < 0) | (seg >= n)]
        if bad.size:
            raise RamureError(f"segment index {int(bad[0])} is out of range: the plant has {n} segments (0 to {n - 1})")
        mask[seg] = True
    return mask


def plant_obb(
    skeleton: Skeleton, leaf_ids: Iterable[int] | None = None, segments: Iterable[int] | None = None, tight: bool = False
) -> OrientedBox:
    """The OBB of a plant or of a selection (see :func:`selection_mask`).

    >>> from lsys import LSystem
    >>> sk = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=3).skeleton()
    >>> plant_obb(sk).corners().shape
    (8, 3)
    """
    m = selection_mask(skeleton, leaf_ids, segments)
    return obb_from_frustums(skeleton.start[m], skeleton.end[m], skeleton.base_radius[m], skeleton.top_radius[m], tight=tight)


def plant_metrics(
    skeleton: Skeleton, leaf_ids: Iterable[int] | None = None, segments: Iterable[int] | None = None, tight: bool = False
) -> PlantMetrics:
    """The ten metrics of a plant, or of the segments drawn by ``leaf_ids`` / ``segments``.

    ``tight=True`` measures the box with the refined (smaller) OBB instead of
    the thesis's covariance box.
    """
    m = selection_mask(skeleton, leaf_ids, segments)
    args = (skeleton.start[m], skeleton.end[m], skeleton.base_radius[m], skeleton.top_radius[m])
    box = obb_from_frustums(*args, tight=True) if tight and m.any() else None
    values = metrics_from_arrays(*args, box=box)
    row = values.tolist()  # Python floats
    row[5] = int(row[5])  # branch_count
    return PlantMetrics(*row)


def metric_deltas(variant: ArrayLike, base: ArrayLike) -> np.ndarray:
    """``delta = 100 (mu' / mu - 1)`` per metric, rows of ``variant`` (..., 10) against ``base`` (10,).

    A metric whose base value is 0 has no relative change: its delta is 0
    (documented choice; the thesis does not handle mu = 0).  Non-finite
    variant values (failed variants) stay NaN.

    >>> metric_deltas(np.array([[2.0, 0.0, 3.0]]), np.array([1.0, 0.0, 4.0])).tolist()
    [[100.0, 0.0, -25.0]]
    """
    variant = np.asarray(variant, float)
    base = np.asarray(base, float)
    ok = base != 0
    out = np.zeros(np.broadcast(variant, base).shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(variant, np.where(ok, base, 1.0), out=out, where=ok)
    out = np.where(ok, 100.0 * (out - 1.0), 0.0)
    out[~np.isfinite(variant)] = np.nan
    return out
