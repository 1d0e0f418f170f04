"""Selections a script or a front end makes without a mouse: leaves by branch order and height.

A selection is a list of history-leaf ids (the ``leaf_id`` of the segments the turtle drew),
the input of :func:`ramure.lsys.regeneration.mincut.select_roots` and :meth:`ramure.lsys.regeneration.regen.Session.regrow`.

>>> import ramure
>>> sk = ramure.derive("honda_sympodial", n=5).skeleton()
>>> high = leaves_where(sk, min_order=2, min_height=2.0)
>>> len(high) > 0 and all(sk.order[sk.leaf_id == leaf].max() >= 2 for leaf in high)
True
"""

from __future__ import annotations

import numpy as np

from ..interpretation.turtle import Skeleton


def leaves_where(
    skeleton: Skeleton, min_order: int | None = None, min_height: float | None = None, max_height: float | None = None
) -> list[int]:
    """Leaves whose segments pass a branch-order / height filter (e.g. order >= 3 above height h).

    Height is the segment midpoint's z; a leaf is kept when any of its segments passes.
    Returns sorted unique leaf ids.
    """
    mask = np.ones(len(skeleton), bool)
    if min_order is not None:
        mask &= skeleton.order >= min_order
    mid_z = (skeleton.start[:, 2] + skeleton.end[:, 2]) / 2
    if min_height is not None:
        mask &= mid_z >= min_height
    if max_height is not None:
        mask &= mid_z <= max_height
    return np.unique(skeleton.leaf_id[mask]).astype(int).tolist()
