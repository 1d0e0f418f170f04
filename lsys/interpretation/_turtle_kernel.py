"""The turtle's compiled loop (numba): one pass over the action arrays of a string.

Kept apart from :mod:`ramure.lsys.interpretation.turtle` so that module stays readable.  The
arithmetic is written in the same order as Ramure's original Python turtle
(kept in ``tests/lsys/turtle_reference.py``) so the two agree to rounding.

The turtle state is a float vector of :data:`STATE_SIZE` values: position
(0:3), H (3:6), L (6:9), U (9:12), width (12), colour (13), branch order (14),
the last segment drawn (15, -1 for none) and the tropism elasticity (16,
``@Ts``; NaN until set: then ``#tropism``'s e applies).

Polygons (``{ . }``, see :mod:`ramure.lsys.interpretation.polygons`) have their own stack,
independent of the branch stack (cpfg, ABOP fig. 5.5: a polygon may be opened
inside a branch and closed after its ``]``), so they are not part of the state
saved by ``[``.

Why numba rather than numpy prefix products of rotations: ``$`` and tropism
depend on the world heading, so every ``$`` and (with ``#tropism``) every
``F`` breaks a prefix product into a new pass; measured on Honda n=17 the
numpy scan was several times slower than this loop, which also keeps the
original arithmetic exactly (see the commit message for the figures).
"""

from __future__ import annotations

import math

import numpy as np

from ramure.jit import njit

from ._turtle_walk import (  # shared with the plain-Python walk (no numba there)
    COLOR_DOWN,
    COLOR_UP,
    DRAW,
    ELASTICITY,
    ERR_CLOSE_WITHOUT_OPEN,
    ERR_UNCLOSED,
    ERR_VERTEX_OUTSIDE,
    FULL,
    MOVE,
    ORGAN,
    PITCH_DOWN,
    PITCH_UP,
    POLY_END,
    POLY_MOVE,
    POLY_START,
    POLY_VERTEX,
    POP,
    PUSH,
    REGION,
    ROLL_HORIZONTAL,
    ROLL_RIGHT,
    SEEK,
    SPHERE,
    STATE_SIZE,
    SURFACE,
    TURN_AROUND,
    TURN_LEFT,
    TURN_RIGHT,
    WIDTH,
    WIDTH_UP,
    initial_state,
)

__all__ = ["FULL", "REGION", "SEEK", "STATE_SIZE", "initial_state", "walk"]


@njit(cache=True, inline="always")
def _pair(ax, ay, az, bx, by, bz, c, s):
    """(a c + b s, b c - a s): a rotation of the frame pair (a, b) by (c, s)."""
    return (ax * c + bx * s, ay * c + by * s, az * c + bz * s, bx * c - ax * s, by * c - ay * s, bz * c - az * s)


@njit(cache=True, inline="always")
def _rodrigues(vx, vy, vz, kx, ky, kz, c, s):
    cx, cy, cz = ky * vz - kz * vy, kz * vx - kx * vz, kx * vy - ky * vx
    kv = kx * vx + ky * vy + kz * vz
    return (vx * c + cx * s + kx * kv * (1 - c), vy * c + cy * s + ky * kv * (1 - c), vz * c + cz * s + kz * kv * (1 - c))


@njit(cache=True, inline="always")
def _same(ax, ay, az, bx, by, bz):
    """Two vertices equal up to rounding (1e-9 relative): an outline back at its start."""
    d = abs(ax - bx) + abs(ay - by) + abs(az - bz)
    return d <= 1e-9 * (1.0 + abs(ax) + abs(ay) + abs(az))


@njit(cache=True, inline="always")
def _vertex(px, py, pz, p, vtx, vtx_poly, poly_last, poly_records, k_vtx):
    """Record the turtle position as a vertex of polygon ``p`` (a repeat of its last vertex is
    counted as a record but not stored); returns the new vertex count."""
    poly_records[p] += 1
    last = poly_last[p]
    if last >= 0 and _same(vtx[last, 0], vtx[last, 1], vtx[last, 2], px, py, pz):
        return k_vtx
    vtx[k_vtx, 0], vtx[k_vtx, 1], vtx[k_vtx, 2] = px, py, pz
    vtx_poly[k_vtx] = p
    poly_last[p] = k_vtx
    return k_vtx + 1


@njit(cache=True, nogil=True)
def walk(acts, nps, par, begin, end, match, mode, state, angle, step, trop, seg_base, pidx=None):
    """Interpret ``acts[begin:end]`` from ``state`` (updated in place); returns where it stopped.

    Module ``i``'s first parameter is ``par[i]``, or ``par[pidx[i]]`` with ``pidx`` (the string's
    node ids and the tree's parameter column: no gathered copy of the string's parameters).

    ``mode`` FULL draws everything (a ``]`` with nothing to pop is ignored);
    SEEK only moves the turtle to ``end`` (no output), jumping over every
    ``[ ... ]`` that closes before ``end`` (``match``: bracket matches), so it
    costs the modules on the path from the root, not the whole string before
    ``end``; REGION draws like FULL but stops at the first ``]`` that closes a
    branch opened before ``begin`` (the end of the part an edit changed).
    ``trop`` is (tx, ty, tz, e) or empty.  FULL numbers the segments from
    ``seg_base`` (their parent links); SEEK and REGION cannot know the final
    numbering, so there a parent link (and the state's last segment) is
    ``-2 - p``, p the string position of the parent's ``F``.

    Inside a polygon (``{`` ... ``}``) ``F`` and ``f`` move without drawing
    and record the position reached as a vertex, ``G`` moves without
    recording, ``.`` records; ``{`` records the start.  Spheres (``@O``) and
    surfaces (``~name``) are recorded with the organs.

    Returns (stop, segment arrays, organ arrays, polygon arrays, err), see
    the code; ``err`` is (code, position) of the first polygon error, (-1, -1)
    when none (codes ``ERR_*``).
    """
    seek = mode == SEEK
    n_draw = n_org = depth = max_depth = n_poly = n_vtx = pdepth = 0
    for i in range(begin, begin if seek else end):  # SEEK draws nothing; its stack grows as needed
        a = acts[i]
        if a == DRAW or a == MOVE:
            n_draw += a == DRAW
            n_vtx += pdepth > 0
        elif a == ORGAN or a == SPHERE or a == SURFACE:
            n_org += 1
        elif a == POLY_START:
            n_poly += 1
            n_vtx += 1
            pdepth += 1
        elif a == POLY_END:
            pdepth -= pdepth > 0
        elif a == POLY_VERTEX:
            n_vtx += 1
        elif a == PUSH:
            depth += 1
            max_depth = max(depth, max_depth)
        elif a == POP:
            if depth > 0:
                depth -= 1
            elif mode == REGION:
                break
    if seek:
        n_draw = n_org = 0
    seg_at = np.empty(n_draw, np.int32)  # string positions: < 2^31 (the tree's node limit)
    seg_start = np.empty((n_draw, 3))
    seg_end = np.empty((n_draw, 3))
    seg_width = np.empty(n_draw)
    seg_order = np.empty(n_draw, np.int32)
    seg_color = np.empty(n_draw, np.int64)
    seg_normal = np.empty((n_draw, 3))
    seg_parent = np.empty(n_draw, np.int64)
    org_at = np.empty(n_org, np.int32)
    org_pos = np.empty((n_org, 3))
    org_frame = np.empty((n_org, 3, 3))
    org_size = np.empty(n_org)
    org_color = np.empty(n_org, np.int64)
    poly_at = np.empty(n_poly, np.int32)
    poly_close = np.full(n_poly, -1, np.int64)
    poly_color = np.empty(n_poly, np.int64)
    poly_records = np.zeros(n_poly, np.int64)
    poly_first = np.full(n_poly, -1, np.int64)
    poly_last = np.full(n_poly, -1, np.int64)
    vtx = np.empty((n_vtx, 3))
    vtx_poly = np.empty(n_vtx, np.int64)
    pstack = np.empty(n_poly + 1, np.int64)
    err = np.full(2, -1, np.int64)
    stack = np.empty((max_depth + 8, STATE_SIZE))

    px, py, pz = state[0], state[1], state[2]
    hx, hy, hz = state[3], state[4], state[5]
    lx, ly, lz = state[6], state[7], state[8]
    ux, uy, uz = state[9], state[10], state[11]
    width = state[12]
    color = np.int64(state[13])
    order = np.int64(state[14])
    last = np.int64(state[15])
    tx, ty, tz, te = 0.0, 0.0, -1.0, 0.0  # @Ts without #tropism bends toward -z (gravity)
    if trop.size == 4:
        tx, ty, tz, te = trop[0], trop[1], trop[2], trop[3]
    if not math.isnan(state[16]):
        te = state[16]
    top = k_seg = k_org = k_poly = k_vtx = 0
    pdepth = 0
    stop = end
    i = begin
    while i < end:
        a = acts[i]
        if a == 0:
            i += 1
            continue
        k = nps[i]
        p = par[i] if pidx is None else par[pidx[i]]
        if (a == DRAW or a == MOVE) and pdepth > 0:  # in a polygon: move, record a vertex
            d = p if k else step
            px, py, pz = px + hx * d, py + hy * d, pz + hz * d
            if not seek:
                k_vtx = _vertex(px, py, pz, pstack[pdepth - 1], vtx, vtx_poly, poly_last, poly_records, k_vtx)
        elif a == DRAW or a == MOVE:
            d = p if k else step
            ex, ey, ez = px + hx * d, py + hy * d, pz + hz * d
            if a == DRAW and seek:
                last = -2 - i
            elif a == DRAW:
                seg_at[k_seg] = i
                seg_start[k_seg, 0], seg_start[k_seg, 1], seg_start[k_seg, 2] = px, py, pz
                seg_end[k_seg, 0], seg_end[k_seg, 1], seg_end[k_seg, 2] = ex, ey, ez
                seg_width[k_seg] = width
                seg_order[k_seg] = order
                seg_color[k_seg] = color
                seg_normal[k_seg, 0], seg_normal[k_seg, 1], seg_normal[k_seg, 2] = lx, ly, lz
                seg_parent[k_seg] = last
                last = seg_base + k_seg if mode == FULL else -2 - i
                k_seg += 1
            if a == DRAW and te != 0.0:
                ax, ay, az = hy * tz - hz * ty, hz * tx - hx * tz, hx * ty - hy * tx
                size = math.sqrt(0.0 + ax * ax + ay * ay + az * az)
                if size >= 1e-12:
                    rad = te * size
                    kx, ky, kz = ax / size, ay / size, az / size
                    c, s = math.cos(rad), math.sin(rad)
                    hx, hy, hz = _rodrigues(hx, hy, hz, kx, ky, kz, c, s)
                    lx, ly, lz = _rodrigues(lx, ly, lz, kx, ky, kz, c, s)
                    ux, uy, uz = _rodrigues(ux, uy, uz, kx, ky, kz, c, s)
            px, py, pz = ex, ey, ez
        elif a <= TURN_AROUND:
            deg = p if k else angle
            if a == TURN_RIGHT or a == PITCH_UP or a == ROLL_RIGHT:
                deg = -deg
            elif a == TURN_AROUND:
                deg = 180.0
            c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
            if a == TURN_LEFT or a == TURN_RIGHT or a == TURN_AROUND:  # about U
                hx, hy, hz, lx, ly, lz = _pair(hx, hy, hz, lx, ly, lz, c, -s)
            elif a == PITCH_DOWN or a == PITCH_UP:  # about L
                hx, hy, hz, ux, uy, uz = _pair(hx, hy, hz, ux, uy, uz, c, s)
            else:  # about H
                lx, ly, lz, ux, uy, uz = _pair(lx, ly, lz, ux, uy, uz, c, s)
        elif a == ROLL_HORIZONTAL:
            vx, vy, vz = 0.0 * hz - 1.0 * hy, 1.0 * hx - 0.0 * hz, 0.0 * hy - 0.0 * hx
            norm = math.sqrt(vx * vx + vy * vy + vz * vz)
            if norm > 1e-12:
                lx, ly, lz = vx / norm, vy / norm, vz / norm
                ux, uy, uz = hy * lz - hz * ly, hz * lx - hx * lz, hx * ly - hy * lx
        elif a == PUSH:
            if seek and match[i] > i and match[i] < end:
                i = match[i] + 1  # a whole branch before the target: the state after it is the one before
                continue
            if top == len(stack):
                bigger = np.empty((2 * len(stack), STATE_SIZE))
                bigger[:top] = stack
                stack = bigger
            row = stack[top]
            row[0], row[1], row[2], row[3], row[4], row[5] = px, py, pz, hx, hy, hz
            row[6], row[7], row[8], row[9], row[10], row[11] = lx, ly, lz, ux, uy, uz
            row[12], row[13], row[14], row[15], row[16] = width, color, order, last, te
            top += 1
            order += 1
        elif a == POP:
            if top > 0:
                top -= 1
                row = stack[top]
                px, py, pz, hx, hy, hz = row[0], row[1], row[2], row[3], row[4], row[5]
                lx, ly, lz, ux, uy, uz = row[6], row[7], row[8], row[9], row[10], row[11]
                width, color, order, last = row[12], np.int64(row[13]), np.int64(row[14]), np.int64(row[15])
                te = row[16]
            elif mode == REGION:
                stop = i
                break
        elif a == WIDTH:
            width = p if k else width * 0.7
        elif a == WIDTH_UP:
            width = p if k else width / 0.7
        elif a == COLOR_UP:
            color = np.int64(p) if k else color + 1
        elif a == COLOR_DOWN:
            color = np.int64(p) if k else color - 1
        elif a == ELASTICITY:
            te = p if k else 0.0
        elif a == POLY_MOVE and pdepth > 0:
            d = p if k else step
            px, py, pz = px + hx * d, py + hy * d, pz + hz * d
        elif a == POLY_START:
            if not seek:
                poly_at[k_poly] = i
                poly_color[k_poly] = color
                pstack[pdepth] = k_poly
                poly_first[k_poly] = k_vtx
                k_vtx = _vertex(px, py, pz, k_poly, vtx, vtx_poly, poly_last, poly_records, k_vtx)
                k_poly += 1
            pdepth += 1
        elif a == POLY_END:
            if pdepth == 0:
                if err[0] < 0 and not seek:
                    err[0], err[1] = ERR_CLOSE_WITHOUT_OPEN, i
            else:
                pdepth -= 1
                if not seek:
                    q = pstack[pdepth]
                    poly_close[q] = i
                    f, g = poly_first[q], poly_last[q]
                    if g > f and _same(vtx[f, 0], vtx[f, 1], vtx[f, 2], vtx[g, 0], vtx[g, 1], vtx[g, 2]):
                        vtx_poly[g] = -1  # the outline came back to its start: not a vertex twice
        elif a == POLY_VERTEX and not seek:
            if pdepth == 0:
                if err[0] < 0:
                    err[0], err[1] = ERR_VERTEX_OUTSIDE, i
            else:
                k_vtx = _vertex(px, py, pz, pstack[pdepth - 1], vtx, vtx_poly, poly_last, poly_records, k_vtx)
        elif (a == ORGAN or a == SPHERE or a == SURFACE) and not seek:
            org_at[k_org] = i
            org_pos[k_org, 0], org_pos[k_org, 1], org_pos[k_org, 2] = px, py, pz
            org_frame[k_org, 0, 0], org_frame[k_org, 0, 1], org_frame[k_org, 0, 2] = hx, hy, hz
            org_frame[k_org, 1, 0], org_frame[k_org, 1, 1], org_frame[k_org, 1, 2] = lx, ly, lz
            org_frame[k_org, 2, 0], org_frame[k_org, 2, 1], org_frame[k_org, 2, 2] = ux, uy, uz
            if a == SPHERE:  # @O(r): a sphere of radius r (diameter 2r); @O alone: the width
                org_size[k_org] = 2.0 * p if k else width
            else:
                org_size[k_org] = p if k else 1.0
            org_color[k_org] = color
            k_org += 1
        i += 1
    if pdepth > 0 and not seek and err[0] < 0:
        err[0], err[1] = ERR_UNCLOSED, poly_at[pstack[pdepth - 1]]
    state[0], state[1], state[2], state[3], state[4], state[5] = px, py, pz, hx, hy, hz
    state[6], state[7], state[8], state[9], state[10], state[11] = lx, ly, lz, ux, uy, uz
    state[12], state[13], state[14], state[15] = width, color, order, last
    state[16] = te
    seg = (
        seg_at[:k_seg],
        seg_start[:k_seg],
        seg_end[:k_seg],
        seg_width[:k_seg],
        seg_order[:k_seg],
        seg_color[:k_seg],
        seg_normal[:k_seg],
        seg_parent[:k_seg],
    )
    org = (org_at[:k_org], org_pos[:k_org], org_frame[:k_org], org_size[:k_org], org_color[:k_org])
    poly = (poly_at[:k_poly], poly_close[:k_poly], poly_color[:k_poly], poly_records[:k_poly], vtx[:k_vtx], vtx_poly[:k_vtx])
    return stop, seg, org, poly, err


@njit(cache=True, nogil=True)
def bracket_pairs(symbols, open_id, close_id):
    """For each open bracket the position of its close and vice versa (-1 elsewhere), one pass.

    Returns (match, balanced); an unmatched bracket keeps -1 and makes ``balanced`` False.
    """
    match = np.empty(len(symbols), np.int64)
    return match, fill_bracket_pairs(symbols, open_id, close_id, match)


@njit(cache=True, nogil=True)
def bracket_pairs32(symbols, open_id, close_id):
    """:func:`bracket_pairs` as int32 positions (half the bytes; the turtle's strings are shorter
    than 2^31 modules, as the history tree refuses more nodes than that)."""
    match = np.empty(len(symbols), np.int32)
    return match, fill_bracket_pairs(symbols, open_id, close_id, match)


@njit(cache=True, nogil=True)
def fill_bracket_pairs(symbols, open_id, close_id, match):
    """Write :func:`bracket_pairs`' matches into ``match`` (any integer dtype); returns ``balanced``."""
    n = len(symbols)
    match[:] = -1
    stack = np.empty(n + 1, match.dtype)  # only the deepest nesting is ever touched
    top = 0
    balanced = True
    for i in range(n):
        s = symbols[i]
        if s == open_id:
            stack[top] = i
            top += 1
        elif s == close_id:
            if top > 0:
                top -= 1
                match[stack[top]] = i
                match[i] = stack[top]
            else:
                balanced = False
    return balanced and top == 0


@njit(cache=True, nogil=True)
def kept_modules(old, new, size):
    """(keep_old, keep_new, same_order): modules of each string present in the other, and
    whether the kept modules come in the same order in both (one pass each)."""
    in_old = np.zeros(size, np.bool_)
    in_new = np.zeros(size, np.bool_)
    for v in old:
        in_old[v] = True
    for v in new:
        in_new[v] = True
    keep_old = np.empty(len(old), np.bool_)
    keep_new = np.empty(len(new), np.bool_)
    for i in range(len(old)):
        keep_old[i] = in_new[old[i]]
    for i in range(len(new)):
        keep_new[i] = in_old[new[i]]
    j = 0
    for i in range(len(old)):
        if keep_old[i]:
            while not keep_new[j]:
                j += 1
            if new[j] != old[i]:
                return keep_old, keep_new, False
            j += 1
    return keep_old, keep_new, True
