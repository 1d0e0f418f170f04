"""The slow reference turtle: Ramure's original per-module Python interpreter, kept verbatim.

Extended (issue 15) with polygons ``{ . } G`` (a polygon stack apart from the
branch stack; inside a polygon F/f move and record a vertex, no tropism),
spheres ``@O``, surfaces ``~name``, ``@Ts(e)`` and ``;(i)``, written as plainly
as the rest; the polygons it records are compared too.

The fast turtle (:func:`ramure.lsys.interpretation.turtle.interpret`) must give the same
skeleton as this one to 1e-9 (tests/lsys/test_lsys_turtle*.py); the speed
benchmark also loads it to report the speed-up measured in the same run.
"""

from __future__ import annotations

import math

import numpy as np

from ramure.errors import DerivationError
from ramure.lsys.interpretation.turtle import Organs, Skeleton

_ACTIONS = {
    "F": 1,
    "f": 2,
    "+": 3,
    "-": 4,
    "&": 5,
    "^": 6,
    "\\": 7,
    "/": 8,
    "|": 9,
    "$": 10,
    "[": 11,
    "]": 12,
    "!": 13,
    "'": 14,
    ";": 14,  # cpfg and L-Py: ";" raises the colour index, "," lowers it
    ",": 15,
    "{": 17,
    "}": 18,
    ".": 19,
    "G": 20,
    "@O": 21,
    "@Ts": 23,
    "#": 24,  # cpfg: set the width, or widen it
    "_": 24,  # L-Py: the same
    "@v": 10,  # cpfg's roll to vertical: ABOP's $
}
_ORGAN = 16
_SURFACE = 22


def _rot(h, l, u, axis, deg):
    """Rotate the frame (tuples) by ``deg`` degrees about H (0), L (1) or U (2), ABOP matrices."""
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == 2:  # R_U: H' = H c - L s ; L' = H s + L c
        return (
            (h[0] * c - l[0] * s, h[1] * c - l[1] * s, h[2] * c - l[2] * s),
            (h[0] * s + l[0] * c, h[1] * s + l[1] * c, h[2] * s + l[2] * c),
            u,
        )
    if axis == 1:  # R_L: H' = H c + U s ; U' = -H s + U c
        return (
            (h[0] * c + u[0] * s, h[1] * c + u[1] * s, h[2] * c + u[2] * s),
            l,
            (u[0] * c - h[0] * s, u[1] * c - h[1] * s, u[2] * c - h[2] * s),
        )
    # R_H: L' = L c + U s ; U' = -L s + U c
    return (
        h,
        (l[0] * c + u[0] * s, l[1] * c + u[1] * s, l[2] * c + u[2] * s),
        (u[0] * c - l[0] * s, u[1] * c - l[1] * s, u[2] * c - l[2] * s),
    )


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit(v):
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n) if n > 1e-12 else None


def _roll_horizontal(h, l, u):
    """ABOP ``$``: L = (V x H)/|V x H| with V = +z; U = H x L.  No-op when H is vertical."""
    new_l = _unit(_cross((0.0, 0.0, 1.0), h))
    if new_l is None:
        return h, l, u
    return h, new_l, _cross(h, new_l)


def _tropism(h, l, u, t, e):
    axis = _cross(h, t)
    size = math.sqrt(sum(a * a for a in axis))
    if size < 1e-12:
        return h, l, u
    angle = e * size
    k = (axis[0] / size, axis[1] / size, axis[2] / size)
    return tuple(_rodrigues(v, k, angle) for v in (h, l, u))


def _rodrigues(v, k, angle):
    c, s = math.cos(angle), math.sin(angle)
    kxv = _cross(k, v)
    kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2]
    return tuple(v[i] * c + kxv[i] * s + k[i] * kv * (1 - c) for i in range(3))


def interpret(derivation):
    """The turtle of Ramure 0.1, one module at a time (the reference the fast turtle must equal)."""
    lsys = derivation.lsystem
    g = lsys.grammar
    tree = derivation.tree
    leaves = tree.leaves
    organs = set(g.organs)
    action_of = np.array(
        [_ACTIONS.get(s, _ORGAN if s in organs else _SURFACE if s.startswith("~") else 0) for s in lsys.symbols] + [0], np.int8
    )
    actions = action_of[tree.symbol[leaves]]
    keep = np.flatnonzero(actions)  # modules with no turtle meaning are skipped up front
    acts = actions[keep].tolist()
    nps = tree.nparams[leaves[keep]].tolist()
    first = tree.params[leaves[keep], 0].tolist()
    nodes = leaves[keep].tolist()
    syms = tree.symbol[leaves[keep]].tolist()
    angle, step = g.angle, g.step
    tropism = g.tropism

    pos, h, l, u = (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    width, color, order, last_seg = g.width, 0, 0, -1
    stack = []
    elasticity = tropism[3] if tropism is not None else 0.0
    direction = tropism[:3] if tropism is not None else (0.0, 0.0, -1.0)
    polygons, open_polygons = [], []  # polygons: [leaf of '{', colour, vertices]
    seg_start, seg_end, seg_width, seg_order, seg_leaf, seg_color, seg_normal, seg_parent = ([], [], [], [], [], [], [], [])
    org = []
    for a, k, p, node, sym in zip(acts, nps, first, nodes, syms):
        if (a == 1 or a == 2 or a == 20) and open_polygons:
            d = p if k else step
            pos = (pos[0] + h[0] * d, pos[1] + h[1] * d, pos[2] + h[2] * d)
            if a != 20:
                _record(open_polygons[-1], pos)
        elif a == 20:
            pass
        elif a == 17:
            open_polygons.append([node, color, [], 0])
            _record(open_polygons[-1], pos)
        elif a == 18:
            done = open_polygons.pop()
            if len(done[2]) > 1 and _same(done[2][0], done[2][-1]):
                done[2].pop()
            polygons.append(done)
        elif a == 19:
            _record(open_polygons[-1], pos)
        elif a == 23:
            elasticity = p if k else 0.0
        elif a == 1 or a == 2:
            d = p if k else step
            end = (pos[0] + h[0] * d, pos[1] + h[1] * d, pos[2] + h[2] * d)
            if a == 1:
                seg_start.append(pos)
                seg_end.append(end)
                seg_width.append(width)
                seg_order.append(order)
                seg_leaf.append(node)
                seg_color.append(color)
                seg_normal.append(l)
                seg_parent.append(last_seg)
                last_seg = len(seg_start) - 1
                if elasticity != 0.0:
                    h, l, u = _tropism(h, l, u, direction, elasticity)
            pos = end
        elif a <= 9:
            deg = p if k else angle
            if a == 3:
                h, l, u = _rot(h, l, u, 2, deg)
            elif a == 4:
                h, l, u = _rot(h, l, u, 2, -deg)
            elif a == 5:
                h, l, u = _rot(h, l, u, 1, deg)
            elif a == 6:
                h, l, u = _rot(h, l, u, 1, -deg)
            elif a == 7:
                h, l, u = _rot(h, l, u, 0, deg)
            elif a == 8:
                h, l, u = _rot(h, l, u, 0, -deg)
            else:
                h, l, u = _rot(h, l, u, 2, 180.0)
        elif a == 10:
            h, l, u = _roll_horizontal(h, l, u)
        elif a == 11:
            stack.append((pos, h, l, u, width, color, order, last_seg, elasticity))
            order += 1
        elif a == 12:
            if stack:
                pos, h, l, u, width, color, order, last_seg, elasticity = stack.pop()
        elif a == 13:
            width = p if k else width * 0.7
        elif a == 24:
            width = p if k else width / 0.7
        elif a == 14:
            color = int(p) if k else color + 1
        elif a == 15:
            color = int(p) if k else color - 1
        elif a == 21:
            org.append((sym, pos, h, l, u, 2 * p if k else width, node, color))
        else:
            org.append((sym, pos, h, l, u, p if k else 1.0, node, color))
    skeleton = _build(lsys, tree, seg_start, seg_end, seg_width, seg_order, seg_leaf, seg_color, seg_normal, seg_parent, org)
    polygons.sort(key=lambda q: q[3])
    skeleton.extra["polygons"] = [(q[0], q[1], np.array(q[2], float).reshape(-1, 3)) for q in polygons]
    return skeleton


def _same(a, b):
    return sum(abs(x - y) for x, y in zip(a, b)) <= 1e-9 * (1.0 + sum(abs(x) for x in a))


_opened = [0]


def _record(polygon, pos):
    """Add a vertex unless it repeats the polygon's last one; number polygons in '{' order."""
    if not polygon[2]:
        _opened[0] += 1
        polygon[3] = _opened[0]
    if not polygon[2] or not _same(polygon[2][-1], pos):
        polygon[2].append(pos)


def _build(lsys, tree, start, end, width, order, leaf, color, normal, parent, org):
    s = len(start)
    start = np.array(start, float).reshape(s, 3)
    end = np.array(end, float).reshape(s, 3)
    base = np.array(width, float) * (lsys.grammar.width_scale / 2.0)
    _check_finite(lsys, tree, leaf, np.isfinite(start).all(1) & np.isfinite(end).all(1) & np.isfinite(base))
    order = np.array(order, np.int32)
    parent = np.array(parent, np.int64)
    top = base.copy()
    # Without a continuation, taper to the widest child segment (a fork), if any.
    child = np.flatnonzero(parent >= 0)
    if child.size:
        widest = np.full(s, -1.0)
        np.maximum.at(widest, parent[child], base[child])
        fork = widest >= 0
        top[fork] = widest[fork]
    # A segment's continuation: the first child segment on the same branch order.
    cont = np.flatnonzero((parent >= 0) & (order == order[np.maximum(parent, 0)]))
    if cont.size:
        par = parent[cont]
        first_child = np.full(s, s, np.int64)
        np.minimum.at(first_child, par, cont)  # the earliest continuing child wins
        has = first_child < s
        top[has] = base[first_child[has]]
    organs = _organs(lsys, tree, org)
    return Skeleton(
        start,
        end,
        base,
        top,
        order,
        np.array(leaf, np.int64),
        np.array(color, np.int32),
        np.array(normal, float).reshape(s, 3),
        parent,
        organs,
    )


def _check_finite(lsys, tree, leaf, ok):
    """Refuse a plant whose turtle overflowed (e.g. F(1e308)F(1e308)): no inf/NaN geometry."""
    if ok.all():
        return
    module = lsys.module_text(tree, int(leaf[int(np.argmin(ok))]))
    raise DerivationError(
        f"the turtle geometry is not finite at module {module} (a length, width or "
        "angle too large for floating point): use smaller values"
    )


def _organs(lsys, tree, org):
    k = len(org)
    if not k:
        return Organs(
            np.array([], dtype=object),
            np.zeros((0, 3)),
            np.zeros((0, 3, 3)),
            np.zeros(0),
            np.zeros((0, tree.max_params)),
            np.zeros(0, np.int64),
        )
    kind = np.array([lsys.symbols[o[0]] for o in org], dtype=object)
    position = np.array([o[1] for o in org], float)
    frame = np.array([(o[2], o[3], o[4]) for o in org], float)
    size = np.array([o[5] for o in org], float)
    leaf_id = np.array([o[6] for o in org], np.int64)
    _check_finite(lsys, tree, leaf_id, np.isfinite(position).all(1) & np.isfinite(size))
    color = np.array([o[7] for o in org], np.int32)
    return Organs(kind, position, frame, size, tree.params[leaf_id], leaf_id, color)
