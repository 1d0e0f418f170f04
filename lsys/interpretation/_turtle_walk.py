"""The turtle's walk in plain Python, for short strings: no numba to load.

:func:`walk` is :func:`ramure.lsys.interpretation._turtle_kernel.walk` line for line, on Python floats and
lists instead of compiled arrays, with the arithmetic written in the same order, so both give
the same arrays bit for bit (tests/lsys/test_lsys_turtle_walk.py).  A new process loads
numba and the compiled walk from its cache in about 0.2 s; this loop walks Honda's
sympodial tree at n = 10 (11,253 modules) in about 10 ms, so strings below
:data:`ramure.lsys.interpretation.turtle.KERNEL_MIN_MODULES` modules take it while numba is not loaded.

This module also holds what both walks share and that needs no numba: the action codes
(the values of :class:`ramure.lsys.interpretation.actions.TurtleAction`) and :func:`initial_state`.
"""

from __future__ import annotations

import math
from itertools import chain

import numpy as np

STATE_SIZE = 17

# Action codes: the values of ramure.lsys.interpretation.actions.TurtleAction (numba needs plain ints).
DRAW, MOVE, TURN_LEFT, TURN_RIGHT, PITCH_DOWN, PITCH_UP, ROLL_LEFT, ROLL_RIGHT = 1, 2, 3, 4, 5, 6, 7, 8
TURN_AROUND, ROLL_HORIZONTAL, PUSH, POP, WIDTH, COLOR_UP, COLOR_DOWN, ORGAN = 9, 10, 11, 12, 13, 14, 15, 16
POLY_START, POLY_END, POLY_VERTEX, POLY_MOVE, SPHERE, SURFACE, ELASTICITY = 17, 18, 19, 20, 21, 22, 23
WIDTH_UP = 24
RICH_FIRST = 25  # and after: ramure.lsys.interpretation._turtle_rich (this walk only)

# Error codes of walk's ``err`` output: (code, string position) of the first problem.
ERR_CLOSE_WITHOUT_OPEN, ERR_VERTEX_OUTSIDE, ERR_UNCLOSED = 1, 2, 3

FULL, SEEK, REGION = 0, 1, 2


def initial_state(width: float) -> np.ndarray:
    """The turtle at the origin heading up +z with L = +x, U = +y, no segment drawn yet."""
    state = np.zeros(STATE_SIZE)
    state[5] = 1.0  # H = +z
    state[6] = 1.0  # L = +x
    state[10] = 1.0  # U = +y
    state[12] = width
    state[15] = -1.0
    state[16] = np.nan
    return state


def _int64(x):
    """``np.int64(x)`` of a float as compiled code converts it (x86: out of range or NaN gives
    the smallest int64)."""
    if x != x or not -9.223372036854775808e18 <= x < 9.223372036854775808e18:
        return -(2**63)
    return int(x)


#: Whole numbers up to this size go through a float unchanged (order and segment numbers always
#: do; a colour index may not).
_EXACT = 2**53


def _rodrigues(vx, vy, vz, kx, ky, kz, c, s):
    cx, cy, cz = ky * vz - kz * vy, kz * vx - kx * vz, kx * vy - ky * vx
    kv = kx * vx + ky * vy + kz * vz
    return (vx * c + cx * s + kx * kv * (1 - c), vy * c + cy * s + ky * kv * (1 - c), vz * c + cz * s + kz * kv * (1 - c))


def _same(ax, ay, az, bx, by, bz):
    """Two vertices equal up to rounding (1e-9 relative): an outline back at its start."""
    d = abs(ax - bx) + abs(ay - by) + abs(az - bz)
    return d <= 1e-9 * (1.0 + abs(ax) + abs(ay) + abs(az))


class _Polygons:
    """The polygon lists of one walk (the kernel's ``poly_*`` and ``vtx*`` arrays)."""

    def __init__(self):
        self.at, self.close, self.color, self.records, self.first, self.last = [], [], [], [], [], []
        self.vtx: list[tuple[float, float, float]] = []
        self.tag: list[int] = []

    def start(self, i, color, px, py, pz):
        p = len(self.at)
        self.at.append(i)
        self.close.append(-1)
        self.color.append(color)
        self.records.append(0)
        self.first.append(len(self.tag))
        self.last.append(-1)
        self.vertex(p, px, py, pz)
        return p

    def vertex(self, p, px, py, pz):
        """Record the turtle position as a vertex of polygon ``p`` (a repeat of its last vertex
        is counted as a record but not stored)."""
        self.records[p] += 1
        last = self.last[p]
        if last >= 0:
            ax, ay, az = self.vtx[last]
            if _same(ax, ay, az, px, py, pz):
                return
        self.last[p] = len(self.tag)
        self.vtx.append((px, py, pz))
        self.tag.append(p)

    def end(self, q, i):
        self.close[q] = i
        f, g = self.first[q], self.last[q]
        if g > f and _same(*self.vtx[f], *self.vtx[g]):
            self.tag[g] = -1  # the outline came back to its start: not a vertex twice

    def arrays(self):
        return (
            np.array(self.at, np.int32),
            np.array(self.close, np.int64),
            np.array(self.color, np.int64),
            np.array(self.records, np.int64),
            np.array(self.vtx, float).reshape(-1, 3),
            np.array(self.tag, np.int64),
        )


def walk(acts, nps, par, begin, end, match, mode, state, angle, step, trop, seg_base, pidx=None, rich=None):
    """:func:`ramure.lsys.interpretation._turtle_kernel.walk` (same arguments, same results), in plain Python.

    ``rich`` (a :class:`ramure.lsys.interpretation._turtle_rich.Rich`) walks the modules of several
    parameters too (codes from :data:`~ramure.lsys.interpretation._turtle_rich.RICH_FIRST`), which the
    compiled walk leaves to this one."""
    acts = acts.tolist()
    nps = nps.tolist()
    par = (par if pidx is None else par[pidx]).tolist()
    match = match.tolist()
    seek = mode == SEEK
    seg, org, polys = [], [], _Polygons()
    err = [-1, -1]
    px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width = state[:13].tolist()
    color, order, last = _int64(float(state[13])), _int64(float(state[14])), _int64(float(state[15]))
    tx, ty, tz, te = 0.0, 0.0, -1.0, 0.0  # @Ts without #tropism bends toward -z (gravity)
    if trop.size == 4:
        tx, ty, tz, te = trop.tolist()
    if not math.isnan(state[16]):
        te = float(state[16])
    stack: list[tuple] = []
    pstack: list[int] = []
    cos, sin, radians, sqrt = _cos, _sin, math.radians, math.sqrt
    stop = end
    i = begin
    while i < end:
        a = acts[i]
        if a == 0:
            i += 1
            continue
        k = nps[i]
        p = par[i]
        if (a == DRAW or a == MOVE) and pstack:  # in a polygon: move, record a vertex
            d = p if k else step
            px, py, pz = px + hx * d, py + hy * d, pz + hz * d
            if not seek:
                polys.vertex(pstack[-1], px, py, pz)
        elif a == DRAW or a == MOVE:
            d = p if k else step
            ex, ey, ez = px + hx * d, py + hy * d, pz + hz * d
            if a == DRAW and seek:
                last = -2 - i
            elif a == DRAW:
                seg.append((i, px, py, pz, ex, ey, ez, width, order, color, lx, ly, lz, last))
                last = seg_base + len(seg) - 1 if mode == FULL else -2 - i
            if a == DRAW and te != 0.0:
                ax, ay, az = hy * tz - hz * ty, hz * tx - hx * tz, hx * ty - hy * tx
                size = sqrt(0.0 + ax * ax + ay * ay + az * az)
                if size >= 1e-12:
                    rad = te * size
                    kx, ky, kz = ax / size, ay / size, az / size
                    c, s = cos(rad), sin(rad)
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
            rad = radians(deg)
            c, s = cos(rad), sin(rad)
            # the kernel's _pair written out: (a c + b s, b c - a s)
            if a == TURN_LEFT or a == TURN_RIGHT or a == TURN_AROUND:  # about U
                s = -s
                hx, hy, hz, lx, ly, lz = (
                    hx * c + lx * s,
                    hy * c + ly * s,
                    hz * c + lz * s,
                    lx * c - hx * s,
                    ly * c - hy * s,
                    lz * c - hz * s,
                )
            elif a == PITCH_DOWN or a == PITCH_UP:  # about L
                hx, hy, hz, ux, uy, uz = (
                    hx * c + ux * s,
                    hy * c + uy * s,
                    hz * c + uz * s,
                    ux * c - hx * s,
                    uy * c - hy * s,
                    uz * c - hz * s,
                )
            else:  # about H
                lx, ly, lz, ux, uy, uz = (
                    lx * c + ux * s,
                    ly * c + uy * s,
                    lz * c + uz * s,
                    ux * c - lx * s,
                    uy * c - ly * s,
                    uz * c - lz * s,
                )
        elif a == ROLL_HORIZONTAL:
            vx, vy, vz = 0.0 * hz - 1.0 * hy, 1.0 * hx - 0.0 * hz, 0.0 * hy - 0.0 * hx
            norm = sqrt(vx * vx + vy * vy + vz * vz)
            if norm > 1e-12:
                lx, ly, lz = vx / norm, vy / norm, vz / norm
                ux, uy, uz = hy * lz - hz * ly, hz * lx - hx * lz, hx * ly - hy * lx
        elif a == PUSH:
            if seek and match[i] > i and match[i] < end:
                i = match[i] + 1  # a whole branch before the target: the state after it is the one before
                continue
            saved = color if -_EXACT <= color <= _EXACT else _int64(float(color))  # the compiled rows are floats
            stack.append((px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width, saved, order, last, te))
            if rich is not None:  # the tropism direction @Tp sets, guides, contours
                rich.push(tx, ty, tz)
            order += 1
        elif a == POP:
            if stack:
                px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width, color, order, last, te = stack.pop()
                if rich is not None:
                    tx, ty, tz = rich.pop()
            elif mode == REGION:
                stop = i
                break
        elif a == WIDTH:
            width = p if k else width * 0.7
        elif a == WIDTH_UP:
            width = p if k else width / 0.7
        elif a == COLOR_UP:
            color = _int64(p) if k else color + 1
        elif a == COLOR_DOWN:
            color = _int64(p) if k else color - 1
        elif a == ELASTICITY:
            te = p if k else 0.0
        elif a == POLY_MOVE and pstack:
            d = p if k else step
            px, py, pz = px + hx * d, py + hy * d, pz + hz * d
        elif a == POLY_START:
            pstack.append(-1 if seek else polys.start(i, color, px, py, pz))
        elif a == POLY_END:
            if not pstack:
                if err[0] < 0 and not seek:
                    err = [ERR_CLOSE_WITHOUT_OPEN, i]
            else:
                q = pstack.pop()
                if not seek:
                    polys.end(q, i)
        elif a == POLY_VERTEX and not seek:
            if not pstack:
                if err[0] < 0:
                    err = [ERR_VERTEX_OUTSIDE, i]
            else:
                polys.vertex(pstack[-1], px, py, pz)
        elif (a == ORGAN or a == SPHERE or a == SURFACE) and not seek:
            if a == SPHERE:  # @O(r): a sphere of radius r (diameter 2r); @O alone: the width
                size = 2.0 * p if k else width
            else:
                size = p if k else 1.0
            org.append((i, px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, size, color))
        elif a >= RICH_FIRST and rich is not None:
            st = [px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width, color, last, tx, ty, tz, te]
            last = rich.step(a, i, st, seg, polys, order, seek, mode == FULL, seg_base, step, pstack)
            px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width, color, _, tx, ty, tz, te = st
        i += 1
    if pstack and not seek and err[0] < 0:
        err = [ERR_UNCLOSED, polys.at[pstack[-1]]]
    state[:13] = px, py, pz, hx, hy, hz, lx, ly, lz, ux, uy, uz, width
    state[13:] = color, order, last, te
    return stop, _segments(seg), _organs(org), polys.arrays(), np.array(err, np.int64)


def _columns(rows, width):
    """The tuples ``rows`` as one float array (n, width)."""
    return np.fromiter(chain.from_iterable(rows), float, len(rows) * width).reshape(-1, width)


def _colors(rows, column):
    """Column ``column`` of ``rows`` as int64 (colour indices: whole numbers a float may not hold)."""
    return np.fromiter((r[column] for r in rows), np.int64, len(rows))


def _segments(rows):
    """The kernel's segment arrays from the rows (position, start, end, width, order, colour,
    normal, parent); positions, orders and parents are exact as floats (below 2^53)."""
    table = _columns(rows, 14)
    return (
        table[:, 0].astype(np.int32),
        table[:, 1:4].copy(),
        table[:, 4:7].copy(),
        table[:, 7].copy(),
        table[:, 8].astype(np.int32),
        _colors(rows, 9),
        table[:, 10:13].copy(),
        table[:, 13].astype(np.int64),
    )


def _organs(rows):
    table = _columns(rows, 15)
    return (
        table[:, 0].astype(np.int32),
        table[:, 1:4].copy(),
        table[:, 4:13].reshape(-1, 3, 3).copy(),
        table[:, 13].copy(),
        _colors(rows, 14),
    )


def bracket_pairs32(symbols, open_id, close_id):
    """:func:`ramure.lsys.interpretation._turtle_kernel.bracket_pairs32` (same results) in numpy steps.

    A ``]`` that would take the nesting below 0 is unmatched (as with the kernel's stack);
    among the others, each bracket has a level (the nesting inside an ``[``, before a ``]``),
    and the brackets of one level, in string order, alternate ``[ ] [ ] ...``, possibly ending
    with an unmatched ``[``: consecutive ones pair up."""
    n = len(symbols)
    opens, closes = symbols == open_id, symbols == close_id
    match = np.full(n, -1, np.int32)
    raw = np.cumsum(opens.view(np.int8) - closes.view(np.int8), dtype=np.int64)
    floor = np.minimum.accumulate(np.minimum(raw, 0)) if n else raw
    unmatched = closes & (floor < np.r_[0, floor[:-1]])  # a new low: nothing open to close
    depth = raw - floor  # the stack's size after each position
    at = np.flatnonzero(opens | (closes & ~unmatched))
    level = depth[at] + closes[at]
    at = at[np.argsort(level * (n + 1) + at, kind="stable")]
    level = depth[at] + closes[at]
    pair = opens[at[:-1]] & closes[at[1:]] & (level[:-1] == level[1:])
    first, second = at[:-1][pair], at[1:][pair]
    match[first], match[second] = second, first
    balanced = not unmatched.any() and (not n or depth[-1] == 0)
    return match, balanced


def kept_modules(old, new, size):
    """:func:`ramure.lsys.interpretation._turtle_kernel.kept_modules` (same results) in numpy steps."""
    in_old = np.zeros(size, np.bool_)
    in_new = np.zeros(size, np.bool_)
    in_old[old] = True
    in_new[new] = True
    keep_old, keep_new = in_new[old], in_old[new]
    return keep_old, keep_new, bool(np.array_equal(old[keep_old], new[keep_new]))


def _cos(rad: float) -> float:
    """``math.cos``, but NaN for an infinite angle (math raises), as the compiled walk gives it:
    the plant's points are then refused as not finite, whichever walk drew them."""
    return math.cos(rad) if math.isfinite(rad) else math.nan


def _sin(rad: float) -> float:
    return math.sin(rad) if math.isfinite(rad) else math.nan
