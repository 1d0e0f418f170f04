"""Compiled inner loops of Open-DLA (see :mod:`ramure.gmap.organs.lichen`): surface walks and neighbour tests.

numba because the walk is sequential by nature (each particle's fate depends on the ones
before it) and steps through triangles one crossing at a time; numpy cannot express it
without a Python loop per step.
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _unit(v):
    n = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return v / n if n > 0 else v


@njit(cache=True)
def _triple(ax, ay, az, bx, by, bz, n):
    """(a x b) . n without temporaries."""
    return (ay * bz - az * by) * n[0] + (az * bx - ax * bz) * n[1] + (ax * by - ay * bx) * n[2]


@njit(cache=True)
def step_on_surface(points, tris, across, normals, tri, pos, d, length):
    """Move ``length`` from ``pos`` along direction ``d`` on the surface, crossing edges
    (arrays in and out; the growth loop calls :func:`_step` on scalars).
    """
    tri, px, py, pz, dx, dy, dz = _step(points, tris, across, normals, tri, pos[0], pos[1], pos[2], d[0], d[1], d[2], length)
    return tri, np.array([px, py, pz]), np.array([dx, dy, dz])


@njit(cache=True)
def _step(points, tris, across, normals, tri, px, py, pz, dx, dy, dz, length):
    """Move ``length`` from ``(px, py, pz)`` along ``(dx, dy, dz)`` on the surface, crossing edges.

    Crossing an edge into triangle T2 unfolds the direction over the edge (its component
    along the edge kept, the rest pointing into T2): on gentle folds this is the source's
    ``t = d x n2; d = n2 x t``, and over sharp ridges (a tube's end cap) it still goes on
    into T2 instead of back out. A point that finds no way out of its triangle stays where
    it is: a walker never leaves the surface. Returns (tri, px, py, pz, dx, dy, dz): scalars,
    no array is allocated on the way.
    """
    remaining = length
    came_from = -1
    for _ in range(64):
        n = normals[tri]
        best_t, best_k, best_s = 1e300, -1, 0.5
        edge_k, edge_s = -1, 0.5  # an edge the point sits on, leaving through it (t ~ 0)
        for k in range(3):
            a = points[tris[tri, k]]
            b = points[tris[tri, (k + 1) % 3]]
            ex, ey, ez = b[0] - a[0], b[1] - a[1], b[2] - a[2]
            den = _triple(dx, dy, dz, ex, ey, ez, n)
            if abs(den) < 1e-15:
                continue
            apx, apy, apz = a[0] - px, a[1] - py, a[2] - pz
            t = _triple(apx, apy, apz, ex, ey, ez, n) / den
            s = _triple(apx, apy, apz, dx, dy, dz, n) / den
            size = np.sqrt(ex * ex + ey * ey + ez * ez)
            entry = across[tri, k] == came_from
            # the edge just crossed is at t ~ 0 behind or under the point: only a clear hit counts
            if t > (1e-9 * size if entry else 1e-12) and -1e-9 <= s <= 1 + 1e-9 and t < best_t:
                best_t, best_k, best_s = t, k, s
            elif den > 0 and -1e-5 <= s <= 1 + 1e-5 and not entry and abs(t) <= 1e-5 * size:
                edge_k, edge_s = k, s
        if best_k < 0 and edge_k >= 0:  # on an edge (or a vertex) heading out: cross it here
            best_t, best_k, best_s = 0.0, edge_k, edge_s
        if best_k < 0:  # no way out of the triangle along d (numerically off it): stay, never leave the surface
            return tri, px, py, pz, dx, dy, dz
        if best_t >= remaining:
            return tri, px + remaining * dx, py + remaining * dy, pz + remaining * dz, dx, dy, dz
        # cross at the hit point, kept off the edge's ends: a ray through a vertex would enter a
        # triangle it leaves at once (symmetric meshes do this), so it crosses just beside it
        a = points[tris[tri, best_k]]
        b = points[tris[tri, (best_k + 1) % 3]]
        s_in = min(max(best_s, 1e-6), 1 - 1e-6)
        px, py, pz = a[0] + s_in * (b[0] - a[0]), a[1] + s_in * (b[1] - a[1]), a[2] + s_in * (b[2] - a[2])
        remaining -= best_t
        came_from = tri
        tri = across[tri, best_k]
        # unfold d over the edge into T2: keep its component along the edge, the rest points
        # into T2 across the edge (a geodesic keeps its angle with the edge; projecting d on
        # T2's plane, the source's d <- n2 x (d x n2), can point back out over a sharp ridge)
        ex, ey, ez = b[0] - a[0], b[1] - a[1], b[2] - a[2]
        elen = np.sqrt(ex * ex + ey * ey + ez * ez)
        ex, ey, ez = ex / elen, ey / elen, ez / elen
        along = dx * ex + dy * ey + dz * ez
        along = min(max(along, -1.0), 1.0)
        far = points[tris[tri, 0]]
        for k in range(3):
            v = tris[tri, k]
            if v != tris[came_from, best_k] and v != tris[came_from, (best_k + 1) % 3]:
                far = points[v]
        mx, my, mz = far[0] - px, far[1] - py, far[2] - pz
        dot = mx * ex + my * ey + mz * ez
        mx, my, mz = mx - dot * ex, my - dot * ey, mz - dot * ez
        mlen = np.sqrt(mx * mx + my * my + mz * mz)
        if mlen < 1e-300:
            return tri, px, py, pz, dx, dy, dz
        cross = np.sqrt(1.0 - along * along)
        dx, dy, dz = along * ex + cross * mx / mlen, along * ey + cross * my / mlen, along * ez + cross * mz / mlen
        norm = np.sqrt(dx * dx + dy * dy + dz * dz)
        dx, dy, dz = dx / norm, dy / norm, dz / norm
    return tri, px, py, pz, dx, dy, dz


@njit(cache=True)
def _hash(ix, iy, iz, mask):
    return ((ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791)) & mask


@njit(cache=True)
def cell_key(pos, h, mask):
    """Hash of the grid cell of ``pos`` (cells of size ``h``) into ``mask + 1`` buckets."""
    return _hash(np.int64(np.floor(pos[0] / h)), np.int64(np.floor(pos[1] / h)), np.int64(np.floor(pos[2] / h)), mask)


@njit(cache=True)
def nearest(pos, head, nxt, particles, h, mask, rho):
    """(min distance, its particle, particles within ``rho``) among the particles of the 27 grid
    cells around ``pos``: exact for distances up to the cell size ``h``."""
    return _nearest(pos[0], pos[1], pos[2], head, nxt, particles, h, mask, rho)


@njit(cache=True)
def _nearest(x, y, z, head, nxt, particles, h, mask, rho):
    best2, who, within = 1e300, -1, 0
    rho2 = rho * rho
    ix = np.int64(np.floor(x / h))
    iy = np.int64(np.floor(y / h))
    iz = np.int64(np.floor(z / h))
    for dx in range(-1, 2):
        for dy in range(-1, 2):
            for dz in range(-1, 2):
                p = head[_hash(ix + dx, iy + dy, iz + dz, mask)]
                while p >= 0:
                    ex, ey, ez = particles[p, 0] - x, particles[p, 1] - y, particles[p, 2] - z
                    dist2 = ex * ex + ey * ey + ez * ez
                    if dist2 < best2:
                        best2, who = dist2, p
                    if dist2 <= rho2:
                        within += 1
                    p = nxt[p]
    return np.sqrt(best2), who, within


@njit(cache=True)
def tangent_direction(normal, angle):
    """A unit vector in the plane of ``normal`` at ``angle`` (radians) from a fixed in-plane axis."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = _unit(_cross(normal, helper))
    y = _cross(normal, x)
    return np.cos(angle) * x + np.sin(angle) * y


@njit(cache=True)
def rotate_in_plane(d, normal, angle):
    """``d`` turned by ``angle`` about ``normal`` (Rodrigues; d is in the plane)."""
    return _unit(np.cos(angle) * d + np.sin(angle) * _cross(normal, d))


@njit(cache=True)
def grow(
    points,
    tris,
    across,
    normals,
    h,
    mask,
    env,
    particles,
    tri_of,
    cluster,
    count,
    a_count,
    b_count,
    head,
    nxt,
    r,
    eps,
    step,
    turn,
    rho,
    floor,
    sigma,
    tau,
    max_steps,
    kill,
    target,
    seed,
    tests,
    a_init,
    b_init,
):
    """Grow clusters until ``target`` particles or every emitter is retired; returns the count.

    ``particles``/``tri_of``/``cluster``/``a_count``/``b_count``/``nxt`` have room for ``target``
    rows, the first ``count`` used; ``head`` (per hashed grid cell of size ``h``) and ``nxt``
    chain particles by cell. ``env`` is E(p) per vertex (interpolated at the new particle). ``tests`` (1,)
    counts distance tests.
    """
    np.random.seed(seed)
    two_r = 2.0 * r
    while count < target:
        alive = 0
        for i in range(count):
            if b_count[i] > 0:
                alive += 1
        if alive == 0:
            break
        pick = np.random.randint(alive)
        i = -1
        for k in range(count):
            if b_count[k] > 0:
                if pick == 0:
                    i = k
                    break
                pick -= 1
        d = tangent_direction(normals[tri_of[i]], np.random.random() * 2 * np.pi)
        ox, oy, oz = particles[i, 0], particles[i, 1], particles[i, 2]
        tri, px, py, pz, dx, dy, dz = _step(points, tris, across, normals, tri_of[i], ox, oy, oz, d[0], d[1], d[2], two_r + eps)
        dist, who, _ = _nearest(px, py, pz, head, nxt, particles, h, mask, rho)
        tests[0] += 1
        if dist < two_r:  # born touching the cluster: a failed attempt
            _fail(a_count, b_count, i, a_init)
            continue
        joined = False
        kill2 = kill * kill
        for _ in range(max_steps):
            dx, dy, dz = _rotate(dx, dy, dz, normals[tri], (np.random.random() * 2 - 1) * turn)
            ntri, nx, ny, nz, ndx, ndy, ndz = _step(points, tris, across, normals, tri, px, py, pz, dx, dy, dz, step)
            dist, who, within = _nearest(nx, ny, nz, head, nxt, particles, h, mask, rho)
            tests[0] += 1
            if dist < two_r:  # the step would overlap: the particle stops where it was, touching
                dist, who, within = _nearest(px, py, pz, head, nxt, particles, h, mask, rho)
                if who < 0 or cluster[who] != cluster[i] or dist > two_r + step:
                    break  # another cluster (or lost contact): destroyed
                bary_env = _env_at(points, tris, env, tri, px, py, pz)
                a_term = floor + (1.0 - floor) * np.exp(-sigma * (within - tau) ** 2)
                if np.random.random() < a_term * bary_env:
                    particles[count, 0] = px
                    particles[count, 1] = py
                    particles[count, 2] = pz
                    tri_of[count] = tri
                    cluster[count] = cluster[i]
                    a_count[count] = a_init
                    b_count[count] = b_init
                    key = _hash(np.int64(np.floor(px / h)), np.int64(np.floor(py / h)), np.int64(np.floor(pz / h)), mask)
                    nxt[count] = head[key]
                    head[key] = count
                    count += 1
                    joined = True
                break
            tri, px, py, pz, dx, dy, dz = ntri, nx, ny, nz, ndx, ndy, ndz
            ex, ey, ez = px - ox, py - oy, pz - oz
            if ex * ex + ey * ey + ez * ez > kill2:
                break  # strayed too far from the cluster: destroyed
        if not joined:
            _fail(a_count, b_count, i, a_init)
    return count


@njit(cache=True)
def _rotate(dx, dy, dz, n, angle):
    """``d`` turned by ``angle`` about ``n`` (d in the plane), on scalars."""
    c, s = np.cos(angle), np.sin(angle)
    rx = c * dx + s * (n[1] * dz - n[2] * dy)
    ry = c * dy + s * (n[2] * dx - n[0] * dz)
    rz = c * dz + s * (n[0] * dy - n[1] * dx)
    norm = np.sqrt(rx * rx + ry * ry + rz * rz)
    return rx / norm, ry / norm, rz / norm


@njit(cache=True)
def _fail(a_count, b_count, i, a_init):
    """A failed attempt of emitter ``i`` costs an ``a`` token; no ``a`` left costs a ``b`` (and
    refills ``a``); no ``b`` left retires the emitter."""
    a_count[i] -= 1
    if a_count[i] <= 0:
        b_count[i] -= 1
        a_count[i] = a_init


@njit(cache=True)
def _env_at(points, tris, env, tri, px, py, pz):
    a = points[tris[tri, 0]]
    b = points[tris[tri, 1]]
    c = points[tris[tri, 2]]
    v0x, v0y, v0z = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    v1x, v1y, v1z = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    v2x, v2y, v2z = px - a[0], py - a[1], pz - a[2]
    d00 = v0x * v0x + v0y * v0y + v0z * v0z
    d01 = v0x * v1x + v0y * v1y + v0z * v1z
    d11 = v1x * v1x + v1y * v1y + v1z * v1z
    d20 = v2x * v0x + v2y * v0y + v2z * v0z
    d21 = v2x * v1x + v2y * v1y + v2z * v1z
    den = d00 * d11 - d01 * d01
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    return (1 - v - w) * env[tris[tri, 0]] + v * env[tris[tri, 1]] + w * env[tris[tri, 2]]
