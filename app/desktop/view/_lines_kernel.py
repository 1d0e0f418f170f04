"""The compiled pass of the draft frame's hairlines (:class:`ramure.app.desktop.view.scene.DraftLines`):
which lines are at least so many pixels long on screen.  numba: numpy's projection of 262k
points takes 10 ms (strided columns) where one pass over them takes well under one."""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True, nogil=True)
def long_lines(points, count, matrix, half_width, half_height, limit):
    """Indices of the lines ``points[i]``-``points[count + i]`` (i < ``count``) at least ``limit``
    pixels long on screen through the 4x4 composite projection ``matrix`` (world to clip), the
    viewport ``2 half_width`` by ``2 half_height`` pixels; a line with an end behind the
    camera counts as long."""
    out = np.empty(count, np.int64)
    kept = 0
    limit2 = limit * limit
    m = matrix
    for i in range(count):
        ax, ay, az = points[i, 0], points[i, 1], points[i, 2]
        bx, by, bz = points[count + i, 0], points[count + i, 1], points[count + i, 2]
        wa = m[3, 0] * ax + m[3, 1] * ay + m[3, 2] * az + m[3, 3]
        wb = m[3, 0] * bx + m[3, 1] * by + m[3, 2] * bz + m[3, 3]
        if wa <= 0.0 or wb <= 0.0:
            out[kept] = i
            kept += 1
            continue
        dx = (m[0, 0] * bx + m[0, 1] * by + m[0, 2] * bz + m[0, 3]) / wb
        dx -= (m[0, 0] * ax + m[0, 1] * ay + m[0, 2] * az + m[0, 3]) / wa
        dy = (m[1, 0] * bx + m[1, 1] * by + m[1, 2] * bz + m[1, 3]) / wb
        dy -= (m[1, 0] * ax + m[1, 1] * ay + m[1, 2] * az + m[1, 3]) / wa
        dx *= half_width
        dy *= half_height
        if dx * dx + dy * dy >= limit2:
            out[kept] = i
            kept += 1
    return out[:kept]
