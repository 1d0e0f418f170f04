"""The turtle commands that take several parameters or objects: absolute moves and headings,
lines to points, circles, boxes, frames, cpfg's generalised cylinders, L-Py's guides, contours
and sweeps, colour interpolation and the tropism direction.

They are rare (a string with none of them is walked exactly as before, by the compiled walk
for long strings): a string that has one is walked by the plain walk
(:func:`ramure.lsys.interpretation._turtle_walk.walk`), which hands each of these modules to
:meth:`Rich.step` with all its arguments (numbers, and for an L-Py model its Python objects:
vectors, curves).  Meanings follow cpfg and L-Py (L-Py's helpcard; the cpfg 3.0 manual):

=======================  ==================================================================
``@M(x,y,z)`` MoveTo     move to (x, y, z) without drawing (a missing or NaN coordinate stays)
``MoveRel(x,y,z)``       move by (x, y, z) without drawing
``@R(h..,u..)`` SetHead  heading (hx, hy, hz) and, given, up (ux, uy, uz) (made orthogonal
                         to the heading); without up, the old up made orthogonal
``LineTo(x,y,z,d)``      draw a segment to (x, y, z), the heading kept; ``d`` the width after
``OLineTo(x,y,z,d)``     the same, the heading turned toward the point (smallest rotation)
``LineRel`` ``OLineRel``  the same to the position plus (x, y, z)
``Pinpoint(x,y,z)``      turn the heading toward the point (``PinpointRel``: position + v)
``@Tp(x,y,z)`` Tropism   the tropism direction (then bent toward by ``@Ts`` elasticity)
``@o(r)`` Circle         a disc of radius r (default half the width) across the heading (L-U
                         plane); in a cpfg file the parameter is the diameter, as cpfg has it
``@c(d)``                a disc of diameter d (default the width) in the H-L plane (cpfg)
``@B(l,r)`` Box          a box from the turtle along H, length l (default ``#step``), square
                         section of half-side r (default half the width); the turtle stays
``Frame(s)``             three arrows of length s (default 1) along H, L and U
``@Gs @Gc(n) @Ge(n)``    cpfg's generalised cylinder: between ``@Gs`` and ``@Ge`` the ``F`` of
                         the same branch only move; each control point ``@Gc``/``@Ge`` draws
                         the Hermite curve from the previous one (tangents: the headings,
                         length 1.2 times the chord, see ``@Gt``), in n segments (default 1)
``@Gt(a,b)``             cpfg's tangent coefficients at the control points that follow (turtle
                         state, kept by branches): the curve arriving at a control point has
                         a tangent ``a`` times the chord, the one leaving it ``b`` (one
                         parameter: both); cpfg >= 3.4 (``general.c``), default 1.2 and 1.2
``@Gc @Ge`` (L-Py)       StartGC / EndGC: Ramure's tubes already join (nothing to do)
``SetGuide(c,l)``        the ``F``/``f``/``nF`` that follow (in branches too, each with its own
                         copy) move along the 2D curve c rescaled to length l (x along the
                         heading, y along L), until ``EndGuide``, the end of the branch it was
                         set in, or the curve's end (then straight on)
``SetContour(c)``        the segments that follow (in branches too) are swept with the closed
                         2D curve c (in L-U, scaled by the radius) as section, as polygons
``Sweep(p,c,l,dl,r)``    ``SetGuide(p,l)``, ``SetContour(c)`` and segments of dl along l of
                         radius r (an optional radius variation function of [0,1] multiplies it)
``nF(l,dl,r,f)``          segments of dl along l (on the guide, swept by the contour, when set);
                         r sets the width, times f((k + 1/2) / count) when f is given
``InterpolateColors(i,j,a)``  the colour (1-a) i + a j: a new material index (after the
                         table's) whose colour blends materials i and j; without both in the
                         ``#material`` table, the index nearest (1-a) i + a j
``@#(n) @!(n)``          cpfg's polygons around and along a cylinder (L-Py's
``SectionResolution``    ``SectionResolution``): Ramure's meshes choose their own resolution
                         (:func:`ramure.app.model.mesh_sides`), so these change nothing drawn
=======================  ==================================================================
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

# Action codes after the plain ones (ramure.lsys.interpretation.actions.TurtleAction 0..24).
RICH_FIRST = 25
(
    MOVE_TO,
    MOVE_REL,
    SET_HEAD,
    LINE_TO,
    OLINE_TO,
    LINE_REL,
    OLINE_REL,
    PINPOINT,
    PINPOINT_REL,
    TROPISM,
    CIRCLE,
    CIRCLE_D,
    DISC_HL,
    BOX,
    FRAME,
    GC_START,
    GC_POINT,
    GC_END,
    GC_LPY,
    SET_GUIDE,
    END_GUIDE,
    SET_CONTOUR,
    SWEEP,
    INTERPOLATE,
    GUIDED_DRAW,
    GUIDED_MOVE,
    CONTOUR_DRAW,
    RESOLUTION,
    N_DRAW,
    GC_TANGENTS,
) = range(RICH_FIRST, RICH_FIRST + 30)

#: Symbols of both dialects (cpfg's ``@Gc`` and ``@o`` differ: see :func:`symbol_codes`).
SYMBOL_CODES = {
    "@M": MOVE_TO,
    "MoveTo": MOVE_TO,
    "MoveRel": MOVE_REL,
    "@R": SET_HEAD,
    "SetHead": SET_HEAD,
    "LineTo": LINE_TO,
    "OLineTo": OLINE_TO,
    "LineRel": LINE_REL,
    "OLineRel": OLINE_REL,
    "Pinpoint": PINPOINT,
    "PinpointRel": PINPOINT_REL,
    "@Tp": TROPISM,
    "Tropism": TROPISM,
    "@o": CIRCLE,
    "Circle": CIRCLE,
    "@c": DISC_HL,
    "@B": BOX,
    "Box": BOX,
    "Frame": FRAME,
    "@Gs": GC_START,
    "@Gc": GC_LPY,
    "@Ge": GC_LPY,
    "StartGC": GC_LPY,
    "EndGC": GC_LPY,
    "SetGuide": SET_GUIDE,
    "EndGuide": END_GUIDE,
    "SetContour": SET_CONTOUR,
    "Sweep": SWEEP,
    "InterpolateColors": INTERPOLATE,
    "@#": RESOLUTION,
    "@!": RESOLUTION,
    "SectionResolution": RESOLUTION,
    "nF": N_DRAW,
}
#: cpfg's meanings where they differ from L-Py's.
CPFG_CODES = {"@Gc": GC_POINT, "@Ge": GC_END, "@o": CIRCLE_D, "@Gt": GC_TANGENTS}

#: Points of a circle (``@o``, ``@c``) and of a sampled guide or contour curve.
CIRCLE_POINTS = 16
CURVE_SAMPLES = 64
#: cpfg's tangent coefficient of generalised cylinders: tangents 1.2 times the chord.
TANGENT_COEFFICIENT = 1.2


def symbol_codes(cpfg: bool) -> dict[str, int]:
    """The rich action of each symbol, for a cpfg file or any other grammar."""
    return {**SYMBOL_CODES, **CPFG_CODES} if cpfg else dict(SYMBOL_CODES)


def recode(acts: np.ndarray, match: np.ndarray) -> np.ndarray:
    """``acts`` with the ``F``/``f`` under a guide, a contour or inside a cpfg cylinder given
    their rich codes (only those of the same branch: a lateral branch is drawn as usual)."""
    from ._turtle_walk import DRAW, MOVE

    out = acts.copy()
    modes = {GC_START: "gc", SET_GUIDE: "guide", SET_CONTOUR: "contour", SWEEP: "sweep"}
    ends = {GC_END: "gc", END_GUIDE: "guide"}
    starts = np.flatnonzero(np.isin(acts, [GC_START, SET_GUIDE, SET_CONTOUR]))
    for s in starts.tolist():
        mode = modes[int(acts[s])]
        i, n, depth = s + 1, len(acts), 0
        while i < n:
            a = int(acts[i])
            if a == 11 and mode == "gc" and match[i] > i:  # PUSH: a cpfg cylinder skips the branch
                i = int(match[i]) + 1
                continue
            if a == 11:  # a guide or contour goes on in branches (L-Py's turtle state)
                depth += 1
            elif a == 12 and depth:
                depth -= 1
            elif a == 12 or (depth == 0 and (ends.get(a) == mode or modes.get(a) == mode)):
                break  # the end of its branch, its end, or a new one
            if mode == "gc" and a == DRAW:
                out[i] = MOVE
            elif mode == "guide" and a in (DRAW, MOVE, CONTOUR_DRAW):
                out[i] = GUIDED_DRAW if a != MOVE else GUIDED_MOVE
            elif mode == "contour" and a == DRAW:
                out[i] = CONTOUR_DRAW
            i += 1
    return out


def _floats(args: Sequence[Any]) -> list[float]:
    """The numbers of ``args``, vectors (L-Py's ``Vector3``, tuples) spread into their coordinates."""
    out: list[float] = []
    for a in args:
        if isinstance(a, (int, float, np.integer, np.floating)) and not isinstance(a, bool):
            out.append(float(a))
        elif hasattr(a, "__len__") and hasattr(a, "__getitem__") and 2 <= len(a) <= 4:
            try:
                out.extend(float(v) for v in a)
            except (TypeError, ValueError):
                out.append(math.nan)
        else:
            out.append(math.nan)
    return out


def _arg(values: list[float], k: int, default: float) -> float:
    v = values[k] if k < len(values) else math.nan
    return default if math.isnan(v) else v


def _unit(x: float, y: float, z: float) -> tuple[float, float, float] | None:
    n = math.sqrt(x * x + y * y + z * z)
    return None if not n > 1e-12 or not math.isfinite(n) else (x / n, y / n, z / n)


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _rotate(v, k, c, s):
    """Rodrigues: ``v`` rotated about the unit axis ``k`` by the angle of cosine c, sine s."""
    cx = _cross(k, v)
    kv = _dot(k, v)
    return tuple(v[j] * c + cx[j] * s + k[j] * kv * (1 - c) for j in range(3))


def turned_to(h, l, u, d):  # noqa: E741 - the turtle's L
    """The frame (H, L, U) turned by the smallest rotation that brings H onto the unit ``d``."""
    axis = _cross(h, d)
    s = math.sqrt(_dot(axis, axis))
    c = max(-1.0, min(1.0, _dot(h, d)))
    if s < 1e-12:
        if c > 0:
            return h, l, u
        return tuple(-x for x in h), tuple(-x for x in l), u  # turned around U
    k = (axis[0] / s, axis[1] / s, axis[2] / s)
    return tuple(d), _rotate(l, k, c, s), _rotate(u, k, c, s)


def curve_points(curve: Any, dims: int = 2) -> np.ndarray | None:
    """(m, dims) points of an L-Py curve (Ramure's small PlantGL; a 2D curve gets z = 0 when
    ``dims`` is 3), or None if it is not one."""
    points = getattr(curve, "points", None)
    if not callable(points):
        return None
    try:
        if type(curve).__name__.startswith("Polyline"):  # its corners exactly
            pts = np.array([list(p)[: getattr(curve, "dim", 2)] for p in curve.ctrlPointList], float)
        else:
            pts = np.asarray(points(CURVE_SAMPLES), float)
    except (TypeError, ValueError, IndexError):
        return None
    if pts.ndim != 2 or len(pts) < 2 or pts.shape[1] < 2 or not np.isfinite(pts).all():
        return None
    pts = pts[:, :dims]
    return np.c_[pts, np.zeros(len(pts))] if pts.shape[1] < dims else pts


class Rich:
    """The arguments of a string's rich modules and the state they keep along one walk."""

    def __init__(self, args: dict[int, tuple], cpfg: bool, materials: dict | None = None) -> None:
        self.args = args
        self.cpfg = cpfg
        self.materials = dict(materials or {})  # the grammar's #material table (index -> rgba)
        #: the materials InterpolateColors made: index -> rgba, beyond the table's indices
        self.blends: dict[int, tuple] = {}
        self._blend_of: dict[tuple, int] = {}
        #: the first module given what it cannot use: (string position, why), raised by the turtle
        self.problem: tuple[int, str] | None = None
        self.gc: tuple | None = None  # cpfg cylinder: (position, heading, width, leaving coefficient) of the last point
        self.tangents = (TANGENT_COEFFICIENT, TANGENT_COEFFICIENT)  # @Gt: arriving, leaving
        self.guide: dict | None = None
        self.contour: np.ndarray | None = None
        self.stack: list[tuple] = []  # at each '[': tropism direction, guide, contour, cylinder

    def push(self, tx: float, ty: float, tz: float) -> None:
        """A branch starts: it inherits the guide (its own copy) and the contour, and starts
        outside any cpfg cylinder (the parent's resumes at ``]``)."""
        self.stack.append((tx, ty, tz, self.guide, self.contour, self.gc, self.tangents))
        self.guide = dict(self.guide) if self.guide is not None else None
        self.gc = None

    def pop(self) -> tuple[float, float, float]:
        """A branch ends: the parent's state again; returns its tropism direction."""
        tx, ty, tz, self.guide, self.contour, self.gc, self.tangents = self.stack.pop()
        return tx, ty, tz

    # -- one module ---------------------------------------------------------------------
    def step(self, a, i, st, seg, polys, order, seek, full, seg_base, step, pstack) -> int:
        """Apply rich module ``a`` at string position ``i`` to the state list ``st``
        (position, H, L, U, width, colour, last segment, tropism x y z, elasticity); returns
        the last segment drawn (``st[14]``)."""
        raw = self.args.get(i, ())
        v = _floats(raw)
        p, h, l, u = tuple(st[0:3]), tuple(st[3:6]), tuple(st[6:9]), tuple(st[9:12])  # noqa: E741
        width = st[12]
        if a == MOVE_TO:
            st[0:3] = [_arg(v, j, p[j]) for j in range(3)]
        elif a == MOVE_REL:
            st[0:3] = [p[j] + _arg(v, j, 0.0) for j in range(3)]
        elif a == SET_HEAD:
            self._set_head(st, v, h, u)
        elif a in (LINE_TO, OLINE_TO, LINE_REL, OLINE_REL):
            rel = a in (LINE_REL, OLINE_REL)
            target = tuple(p[j] + _arg(v, j, 0.0) if rel else _arg(v, j, p[j]) for j in range(3))
            d = _unit(*(target[j] - p[j] for j in range(3)))
            if a in (OLINE_TO, OLINE_REL) and d is not None:
                st[3:12] = [*sum(turned_to(h, l, u, d), ())]
            if d is not None:
                self._segment(st, i, p, target, seg, order, seek, full, seg_base)
            st[0:3] = list(target)
            if len(v) > 3 and not math.isnan(v[3]):
                st[12] = v[3]
        elif a in (PINPOINT, PINPOINT_REL):
            rel = a == PINPOINT_REL
            target = tuple(p[j] + _arg(v, j, 0.0) if rel else _arg(v, j, 0.0) for j in range(3))
            d = _unit(*(target[j] - p[j] for j in range(3)))
            if d is not None:
                st[3:12] = [*sum(turned_to(h, l, u, d), ())]
        elif a == TROPISM:
            t = _unit(_arg(v, 0, 1.0), _arg(v, 1, 0.0), _arg(v, 2, 0.0))
            if t is not None:
                st[15:18] = list(t)
        elif a == INTERPOLATE:
            st[13] = self._blend(_arg(v, 0, st[13]), _arg(v, 1, st[13]), _arg(v, 2, 0.5))
        elif a == GC_START:
            self.gc = (p, h, width, self.tangents[1])
        elif a == GC_TANGENTS:
            if v:
                self.tangents = (v[0], _arg(v, 1, v[0]))
        elif a in (GC_POINT, GC_END):
            self._cylinder(st, i, p, h, width, int(_arg(v, 0, 1.0)), seg, order, seek, full, seg_base)
            if a == GC_END:
                self.gc = None
        elif a == SET_GUIDE:
            self._set_guide(raw, v, p, h, l, i)
        elif a == END_GUIDE:
            self.guide = None
        elif a == SET_CONTOUR:
            self.contour = self._contour(raw[0] if raw else None, i)
        elif a in (GUIDED_DRAW, GUIDED_MOVE):
            self._guided(st, i, _arg(v, 0, step), a == GUIDED_DRAW, seg, order, seek, full, seg_base, polys)
        elif a == CONTOUR_DRAW:
            forward = _arg(v, 0, step)
            end = tuple(p[j] + h[j] * forward for j in range(3))
            self._draw(st, i, p, end, seg, order, seek, full, seg_base, polys)
            st[0:3] = list(end)
        elif a == SWEEP:
            self._sweep(st, i, raw, v, step, seg, order, seek, full, seg_base, polys)
        elif a == N_DRAW:
            self._n_draw(st, i, raw, v, step, seg, order, seek, full, seg_base, polys)
        elif not seek and a in (CIRCLE, CIRCLE_D, DISC_HL, BOX, FRAME):
            self._shape(a, st, i, v, p, h, l, u, width, step, polys)
        return int(st[14])

    # -- pieces -------------------------------------------------------------------------
    def _contour(self, curve: Any, i: int) -> np.ndarray | None:
        pts = curve_points(curve)
        if pts is None and self.problem is None:
            self.problem = (i, "SetContour (and Sweep) take a 2D curve as the section (a Polyline2D, a NurbsCurve2D ...)")
        return pts

    def _blend(self, c1: float, c2: float, alpha: float) -> int:
        """The colour index of (1 - alpha) c1 + alpha c2: a new material blending the two when
        the table has both, else the nearer of the two indices' ramp."""
        i, j = int(c1), int(c2)
        if i in self.materials and j in self.materials and c1 == i and c2 == j and math.isfinite(alpha):
            key = (i, j, round(alpha, 9))
            if key not in self._blend_of:
                first = max([*self.materials, *self.blends, 0]) + 1
                a, b = self.materials[i], self.materials[j]
                self.blends[first] = tuple((1 - alpha) * x + alpha * y for x, y in zip(a, b))
                self._blend_of[key] = first
            return self._blend_of[key]
        return int(math.floor(c1 + alpha * (c2 - c1) + 0.5))

    def _set_head(self, st, v, h, u):
        head = _unit(_arg(v, 0, 0.0), _arg(v, 1, 0.0), _arg(v, 2, 1.0)) if v else _unit(0.0, 0.0, 1.0)
        if head is None:
            return
        up = (_arg(v, 3, math.nan), _arg(v, 4, math.nan), _arg(v, 5, math.nan)) if len(v) >= 6 else u
        if any(math.isnan(x) for x in up):
            up = u
        k = _dot(up, head)
        new_up = _unit(*(up[j] - k * head[j] for j in range(3)))
        if new_up is None:  # the up given (or kept) lies along the heading: any perpendicular
            other = (1.0, 0.0, 0.0) if abs(head[0]) < 0.9 else (0.0, 1.0, 0.0)
            new_up = _unit(*_cross(head, other))
        assert new_up is not None
        left = _cross(new_up, head)  # H x L = U, so L = U x H
        st[3:12] = [*head, *left, *new_up]

    def _segment(self, st, i, start, end, seg, order, seek, full, seg_base, width=None):
        """Record a drawn segment from ``start`` to ``end`` (its normal: L made perpendicular)."""
        if seek:
            st[14] = -2 - i
            return
        d = _unit(*(end[j] - start[j] for j in range(3)))
        l = tuple(st[6:9])  # noqa: E741
        normal = l
        if d is not None:
            k = _dot(l, d)
            ku = _dot(st[9:12], d)
            normal = _unit(*(l[j] - k * d[j] for j in range(3))) or _unit(*(st[9 + j] - ku * d[j] for j in range(3))) or l
        w = st[12] if width is None else width
        seg.append((i, *start, *end, w, order, st[13], *normal, st[14]))
        st[14] = seg_base + len(seg) - 1 if full else -2 - i

    def _draw(self, st, i, start, end, seg, order, seek, full, seg_base, polys):
        """A segment, swept with the contour when one is set, else a tube segment."""
        if self.contour is None or seek:
            self._segment(st, i, start, end, seg, order, seek, full, seg_base)
            return
        r = st[12] / 2.0
        ring0 = self._ring(start, st, r)
        ring1 = self._ring(end, st, r)
        color = st[13]
        m = len(ring0)
        for j in range(m - 1):
            q = polys.start(i, color, *ring0[j])
            for point in (ring0[j + 1], ring1[j + 1], ring1[j]):
                polys.vertex(q, *point)
            polys.end(q, i)

    def _ring(self, centre, st, r):
        contour = self.contour
        assert contour is not None
        l, u = st[6:9], st[9:12]  # noqa: E741
        return [tuple(centre[j] + r * (x * l[j] + y * u[j]) for j in range(3)) for x, y in contour]

    def _cylinder(self, st, i, p, h, width, pieces, seg, order, seek, full, seg_base):
        """cpfg's control point: the Hermite curve from the last control point to here."""
        if self.gc is None:
            self.gc = (p, h, width, self.tangents[1])
            return
        p0, h0, w0, leaving = self.gc
        chord = math.dist(p0, p)
        t0 = [x * chord * leaving for x in h0]
        t1 = [x * chord * self.tangents[0] for x in h]
        pieces = max(1, min(pieces, 1000))
        prev = p0
        for k in range(1, pieces + 1):
            t = k / pieces
            a0, a1 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
            b0, b1 = -2 * t**3 + 3 * t**2, t**3 - t**2
            point = tuple(a0 * p0[j] + a1 * t0[j] + b0 * p[j] + b1 * t1[j] for j in range(3))
            w = w0 + (width - w0) * (k - 1) / pieces
            if math.dist(prev, point) > 0:
                self._segment(st, i, prev, point, seg, order, seek, full, seg_base, width=w)
            prev = point
        self.gc = (p, h, width, self.tangents[1])

    def _set_guide(self, raw, v, p, h, l, i=-1):  # noqa: E741
        pts = curve_points(raw[0], 3) if raw else None
        length = _arg(v, 1, math.nan)
        if pts is None or not length > 0:
            self.guide = None
            if self.problem is None:
                self.problem = (i, "SetGuide (and Sweep) take a curve and a length > 0 (a Polyline2D, a NurbsCurve2D ...)")
            return
        pts = pts - pts[0]
        steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        total = float(steps.sum())
        if not total > 0:
            self.guide = None
            return
        along = np.concatenate([[0.0], np.cumsum(steps)]) * (length / total)
        pts = pts * (length / total)
        u = _cross(h, l)  # a 3D guide's z goes along U
        world = np.array(p) + np.outer(pts[:, 0], h) + np.outer(pts[:, 1], l) + np.outer(pts[:, 2], u)
        self.guide = {"along": along, "world": world, "s": 0.0}

    def _guided(self, st, i, d, draw, seg, order, seek, full, seg_base, polys):
        """``F``/``f`` on a guide: move by the guide's displacement over arc length d."""
        g = self.guide
        p = tuple(st[0:3])
        if g is None:
            h = st[3:6]
            end = tuple(p[j] + h[j] * d for j in range(3))
        else:
            along, world = g["along"], g["world"]
            s0, s1 = g["s"], g["s"] + d
            a = np.array([np.interp(s0, along, world[:, j]) for j in range(3)])
            stop = min(s1, along[-1])
            b = np.array([np.interp(stop, along, world[:, j]) for j in range(3)])
            k = int(np.clip(np.searchsorted(along, stop, side="left"), 1, len(along) - 1))
            tangent = _unit(*(world[k] - world[k - 1]))
            end = tuple(p[j] + b[j] - a[j] for j in range(3))
            if tangent is not None:
                st[3:12] = [*sum(turned_to(tuple(st[3:6]), tuple(st[6:9]), tuple(st[9:12]), tangent), ())]
            if s1 > along[-1]:  # past the guide's end: straight on, and the guide is done
                rest = s1 - along[-1]
                end = tuple(end[j] + st[3 + j] * rest for j in range(3))
                self.guide = None
            else:
                g["s"] = s1
        if draw:
            self._draw(st, i, p, end, seg, order, seek, full, seg_base, polys)
        st[0:3] = list(end)

    def _sweep(self, st, i, raw, v, step, seg, order, seek, full, seg_base, polys):
        length, dl = _arg(v, 2, math.nan), _arg(v, 3, step)
        if not (length > 0 and dl > 0) or len(raw) < 2:
            return
        saved_contour, saved_guide = self.contour, self.guide
        self._set_guide(raw[:1], [math.nan, length], tuple(st[0:3]), tuple(st[3:6]), tuple(st[6:9]), i)
        self.contour = self._contour(raw[1], i)
        radius = _arg(v, 4, st[12] / 2.0)
        variation = raw[5] if len(raw) > 5 and callable(raw[5]) else None
        count = max(1, min(int(math.ceil(length / dl - 1e-9)), 10_000))
        for k in range(count):
            d = min(dl, length - k * dl)
            factor = float(variation((k + 0.5) / count)) if variation is not None else 1.0
            st[12] = 2.0 * radius * factor
            self._guided(st, i, d, True, seg, order, seek, full, seg_base, polys)
        self.contour, self.guide = saved_contour, saved_guide

    def _n_draw(self, st, i, raw, v, step, seg, order, seek, full, seg_base, polys):
        """L-Py's ``nF(length, dl[, radius, variation])``: segments of dl along length (on the
        guide, with the contour, when set); a radius sets the width (times the variation)."""
        length, dl = _arg(v, 0, step), _arg(v, 1, step)
        if not (length > 0 and dl > 0):
            return
        radius = _arg(v, 2, math.nan)
        variation = raw[3] if len(raw) > 3 and callable(raw[3]) else None
        count = max(1, min(int(math.ceil(length / dl - 1e-9)), 10_000))
        for k in range(count):
            if not math.isnan(radius):
                factor = float(variation((k + 0.5) / count)) if variation is not None else 1.0
                st[12] = 2.0 * radius * factor
            d = min(dl, length - k * dl)
            if self.guide is not None:
                self._guided(st, i, d, True, seg, order, seek, full, seg_base, polys)
            else:
                p, h = tuple(st[0:3]), st[3:6]
                end = tuple(p[j] + h[j] * d for j in range(3))
                self._draw(st, i, p, end, seg, order, seek, full, seg_base, polys)
                st[0:3] = list(end)

    def _shape(self, a, st, i, v, p, h, l, u, width, step, polys):  # noqa: E741
        color = st[13]
        if a in (CIRCLE, CIRCLE_D, DISC_HL):
            r = width / 2.0 if not v or math.isnan(v[0]) else (v[0] / 2.0 if a != CIRCLE else v[0])
            e1, e2 = (l, u) if a != DISC_HL else (h, l)
            angles = [2 * math.pi * k / CIRCLE_POINTS for k in range(CIRCLE_POINTS)]
            ring = [tuple(p[j] + r * (math.cos(t) * e1[j] + math.sin(t) * e2[j]) for j in range(3)) for t in angles]
            _polygon(polys, i, color, ring)
        elif a == BOX:
            length, r = _arg(v, 0, step), _arg(v, 1, width / 2.0)

            def corner(t, x, y):
                return tuple(p[j] + t * length * h[j] + r * (x * l[j] + y * u[j]) for j in range(3))

            square = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
            _polygon(polys, i, color, [corner(0, x, y) for x, y in reversed(square)])
            _polygon(polys, i, color, [corner(1, x, y) for x, y in square])
            for k in range(4):
                (x0, y0), (x1, y1) = square[k], square[(k + 1) % 4]
                _polygon(polys, i, color, [corner(0, x0, y0), corner(0, x1, y1), corner(1, x1, y1), corner(1, x0, y0)])
        else:  # FRAME: three thin arrows
            size = _arg(v, 0, 1.0)
            for axis, side in ((h, l), (l, u), (u, h)):
                tip = tuple(p[j] + size * axis[j] for j in range(3))
                a0 = tuple(p[j] + 0.04 * size * side[j] for j in range(3))
                a1 = tuple(p[j] - 0.04 * size * side[j] for j in range(3))
                _polygon(polys, i, color, [a0, tip, a1])


def _polygon(polys, i, color, points) -> None:
    q = polys.start(i, color, *points[0])
    for point in points[1:]:
        polys.vertex(q, *point)
    polys.end(q, i)
