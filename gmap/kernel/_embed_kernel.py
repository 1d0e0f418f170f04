"""Compiled embedding pass for :meth:`ramure.gmap.kernel.map3.GMap3.embed`.

numba because the numpy version made seven passes over every dart per embedding (one
``bincount`` per coordinate and for the weights, one ``take`` per coordinate back): the
wood embeds after every growth step, and these passes were the kernel's largest cost
there. The sums run in dart order, as ``np.bincount`` runs them, so positions are the same.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True)
def inverse_orbit_sizes(raw, find, count):
    """``1 / size`` of each dart's orbit (``find[raw[d]]``, two-level labels), as float64.

    The same doubles as ``1.0 / np.bincount(ids).astype(float)[ids]`` (an
    exact integer divided once): :meth:`GMap3.embed` weighs each corner's
    darts with them without keeping per-dart sizes between calls.
    """
    sizes = np.zeros(count, np.int64)
    for d in range(raw.size):
        sizes[find[raw[d]]] += 1
    out = np.empty(raw.size)
    for d in range(raw.size):
        out[d] = 1.0 / np.float64(sizes[find[raw[d]]])
    return out


@njit(cache=True)
def weighted_sums(raw, find, weight, corners, count):
    """``(sums (count, 3), total (count,))``: weighted corner sums and weights per vertex.

    Dart ``d``'s vertex is ``find[raw[d]]`` (the kernel's two-level labels, so
    they need not be gathered first; pass ``find = arange`` for plain ids).
    """
    sums = np.zeros((count, 3))
    total = np.zeros(count)
    for d in range(raw.size):
        v = find[raw[d]]
        w = weight[d]
        total[v] += w
        sums[v, 0] += w * corners[d, 0]
        sums[v, 1] += w * corners[d, 1]
        sums[v, 2] += w * corners[d, 2]
    return sums, total


@njit(cache=True)
def exclusive_sums(raw, find, weight, corners, count, vol, exclusive):
    """:func:`weighted_sums` where a vertex touching an ``exclusive`` volume counts only those volumes.

    ``vol`` is each dart's volume, ``exclusive`` a flag per volume.  The darts
    left out would add a weight of 0 (the numpy path zeroes them), so the sums
    are the same, in the same order.  ``ok`` is False (sums unset) when a
    dart's volume is not a volume.
    """
    at_exclusive = np.zeros(count, np.bool_)
    sums = np.zeros((count, 3))
    total = np.zeros(count)
    for d in range(raw.size):
        v = vol[d]
        if v < 0 or v >= exclusive.size:
            return sums, total, False
        if exclusive[v]:
            at_exclusive[find[raw[d]]] = True
    for d in range(raw.size):
        v = find[raw[d]]
        if at_exclusive[v] and not exclusive[vol[d]]:
            continue
        w = weight[d]
        total[v] += w
        sums[v, 0] += w * corners[d, 0]
        sums[v, 1] += w * corners[d, 1]
        sums[v, 2] += w * corners[d, 2]
    return sums, total, True


@njit(cache=True)
def scatter(points, pos, raw, find):
    """``points[d] = pos[find[raw[d]]]`` for every dart, in place."""
    for d in range(raw.size):
        v = find[raw[d]]
        points[d, 0] = pos[v, 0]
        points[d, 1] = pos[v, 1]
        points[d, 2] = pos[v, 2]


@njit(cache=True)
def gather_corners(table, offset, vol, corner, out):
    """``out[d] = table[offset[vol[d]] + corner[d]]`` (index clipped to the table), dart by dart.

    Returns False (``out`` partly written) when a dart's volume has no offset.
    """
    last = table.shape[0] - 1
    for d in range(vol.size):
        v = vol[d]
        if v < 0 or v >= offset.size:
            return False
        k = offset[v] + corner[d]
        if k < 0:
            k = 0
        elif k > last:
            k = last
        out[d, 0] = table[k, 0]
        out[d, 1] = table[k, 1]
        out[d, 2] = table[k, 2]
    return True
