"""The compiled passes of :mod:`ramure.lsys.interpretation.polygons` (numba), in their own module so that
importing :mod:`ramure.lsys` does not load numba (about 65 MB): only a plant that is drawn
(the turtle) or has polygons needs them."""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True, nogil=True)
def gather(vtx, tag, n_poly):
    """Vertices grouped by polygon (tag -1: dropped), in recording order: (offsets, points)."""
    offsets = np.zeros(n_poly + 1, np.int64)
    for t in tag:
        if t >= 0:
            offsets[t + 1] += 1
    for p in range(n_poly):
        offsets[p + 1] += offsets[p]
    fill = offsets[:-1].copy()
    points = np.empty((offsets[-1], 3))
    for i in range(len(tag)):
        t = tag[i]
        if t >= 0:
            k = fill[t]
            points[k, 0], points[k, 1], points[k, 2] = vtx[i, 0], vtx[i, 1], vtx[i, 2]
            fill[t] = k + 1
    return offsets, points


@njit(cache=True, nogil=True)
def polygon_depths(acts: np.ndarray, push: int, pop: int, start: int, end: int, at: np.ndarray) -> tuple[bool, np.ndarray]:
    """(local, depth): whether every polygon closes in the branch that opened it (and every
    ``}`` has its ``{``), and the number of open polygons before each position of ``at``
    (sorted; ``len(acts)`` means after the last module)."""
    n = len(acts)
    depth = np.zeros(len(at), np.int32)
    opened_at = np.empty(n + 1, np.int64)  # branch depth where each open polygon started
    branch = top = q = 0
    local = True
    for i in range(n):
        while q < len(at) and at[q] == i:
            depth[q] = top
            q += 1
        a = acts[i]
        if a == push:
            branch += 1
        elif a == pop:
            branch -= 1
            if top > 0 and branch < opened_at[top - 1]:
                local = False
        elif a == start:
            opened_at[top] = branch
            top += 1
        elif a == end:
            if top == 0 or opened_at[top - 1] != branch:
                local = False
            top = max(top - 1, 0)
    while q < len(at):
        depth[q] = top
        q += 1
    return local and top == 0, depth


@njit(cache=True, nogil=True)
def triangulate(points, offsets, max_ear_clip):
    n_poly = len(offsets) - 1
    total = 0
    for p in range(n_poly):
        total += max(offsets[p + 1] - offsets[p] - 2, 0)
    tris = np.empty((total, 3), np.int64)
    owner = np.empty(total, np.int64)
    k = 0
    biggest = 0
    for p in range(n_poly):
        biggest = max(biggest, offsets[p + 1] - offsets[p])
    xs = np.empty(biggest)
    ys = np.empty(biggest)
    nxt = np.empty(biggest, np.int64)
    prv = np.empty(biggest, np.int64)
    for p in range(n_poly):
        a, b = offsets[p], offsets[p + 1]
        n = b - a
        if n < 3:
            continue
        nx = ny = nz = 0.0  # Newell's normal
        for i in range(n):
            j = i + 1 if i + 1 < n else 0
            x0, y0, z0 = points[a + i, 0], points[a + i, 1], points[a + i, 2]
            x1, y1, z1 = points[a + j, 0], points[a + j, 1], points[a + j, 2]
            nx += (y0 - y1) * (z0 + z1)
            ny += (z0 - z1) * (x0 + x1)
            nz += (x0 - x1) * (y0 + y1)
        ax, ay, az = abs(nx), abs(ny), abs(nz)
        size = max(ax, ay, az)
        scale = 0.0
        for i in range(n):
            for c in range(3):
                scale = max(scale, abs(points[a + i, c] - points[a, c]))
        if size <= 1e-12 * scale * scale or size == 0.0:
            continue  # no area
        # drop the dominant axis; flip so the outline runs counter-clockwise
        if az >= ax and az >= ay:
            u, v, sign = 0, 1, nz
        elif ax >= ay:
            u, v, sign = 1, 2, nx
        else:
            u, v, sign = 2, 0, ny
        flip = sign < 0
        for i in range(n):
            xs[i] = points[a + i, u]
            ys[i] = -points[a + i, v] if flip else points[a + i, v]
        convex = True
        for i in range(n):
            i0 = i - 1 if i > 0 else n - 1
            i2 = i + 1 if i + 1 < n else 0
            if _cross(xs[i0], ys[i0], xs[i], ys[i], xs[i2], ys[i2]) < 0:
                convex = False
                break
        if convex or n > max_ear_clip:  # a huge concave outline gets a fan too: never a long stall
            for i in range(1, n - 1):
                tris[k, 0], tris[k, 1], tris[k, 2] = a, a + i, a + i + 1
                owner[k] = p
                k += 1
            continue
        k = _ear_clip(xs, ys, nxt, prv, n, a, p, tris, owner, k)
    return tris[:k], owner[:k]


@njit(cache=True, inline="always")
def _cross(x0, y0, x1, y1, x2, y2):
    return (x1 - x0) * (y2 - y1) - (y1 - y0) * (x2 - x1)


@njit(cache=True)
def _inside(px, py, x0, y0, x1, y1, x2, y2):
    """Point in the closed counter-clockwise triangle."""
    return _cross(x0, y0, x1, y1, px, py) >= 0 and _cross(x1, y1, x2, y2, px, py) >= 0 and _cross(x2, y2, x0, y0, px, py) >= 0


@njit(cache=True)
def _ear_clip(xs, ys, nxt, prv, n, a, p, tris, owner, k):
    """Ear clipping of one counter-clockwise polygon (O(n^2)); writes n - 2 triangles at ``k``."""
    for i in range(n):
        nxt[i] = i + 1 if i + 1 < n else 0
        prv[i] = i - 1 if i > 0 else n - 1
    left = n
    i = 0
    misses = 0
    while left > 3:
        i0, i2 = prv[i], nxt[i]
        ear = _cross(xs[i0], ys[i0], xs[i], ys[i], xs[i2], ys[i2]) > 0
        if ear:
            j = nxt[i2]
            while j != i0:
                same = (
                    (xs[j] == xs[i0] and ys[j] == ys[i0])
                    or (xs[j] == xs[i] and ys[j] == ys[i])
                    or (xs[j] == xs[i2] and ys[j] == ys[i2])
                )
                if not same and _inside(xs[j], ys[j], xs[i0], ys[i0], xs[i], ys[i], xs[i2], ys[i2]):
                    ear = False
                    break
                j = nxt[j]
        if ear or misses > left:  # no ear found in a whole turn (self-crossing outline): clip anyway
            tris[k, 0], tris[k, 1], tris[k, 2] = a + i0, a + i, a + i2
            owner[k] = p
            k += 1
            nxt[i0], prv[i2] = i2, i0
            left -= 1
            misses = 0
            i = i0
        else:
            misses += 1
            i = i2
    i0, i2 = prv[i], nxt[i]
    tris[k, 0], tris[k, 1], tris[k, 2] = a + i0, a + i, a + i2
    owner[k] = p
    return k + 1
