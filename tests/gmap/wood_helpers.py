"""Shared helpers of the wood tests (a uniquely named module: the test folders have no package)."""

from __future__ import annotations

import numpy as np


def contacts(wood) -> tuple[np.ndarray, np.ndarray]:
    """Volume pairs ``(a, b)`` of a wood's map sewn face to face by alpha3 (both directions)."""
    gm = wood.gm
    d = np.arange(gm.n_darts)
    a3 = gm.alpha[3][: gm.n_darts]
    sewn = a3 != d
    return gm.dart_volume[d[sewn]].astype(np.int64), gm.dart_volume[a3[sewn]].astype(np.int64)


def triangle_hits(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """How many of ``triangles`` (t, 3, 2) hold each of ``points`` (n, 2), edges included."""
    count = np.zeros(len(points), np.int64)
    for i in range(0, len(triangles), 2000):
        t = triangles[i : i + 2000]
        v0, v1, v2 = t[:, 0], t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
        det = v1[:, 0] * v2[:, 1] - v1[:, 1] * v2[:, 0]
        ok = np.abs(det) > 1e-20
        det = np.where(ok, det, 1.0)[:, None]
        w = points[None] - v0[:, None]
        s = (w[..., 0] * v2[:, None, 1] - w[..., 1] * v2[:, None, 0]) / det
        u = (v1[:, None, 0] * w[..., 1] - v1[:, None, 1] * w[..., 0]) / det
        count += (ok[:, None] & (s >= 0) & (u >= 0) & (s + u <= 1)).sum(axis=0)
    return count
