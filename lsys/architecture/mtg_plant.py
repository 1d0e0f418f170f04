"""An MTG as a plant Ramure can show, select and measure: a grammar whose axiom draws it.

The plant is drawn at the MTG's finest scale, one ``F`` per entity, a ``+`` edge as a branch
``[ ... ]`` (as in :mod:`ramure.lsys.interpretation.turtle`):

* **geometry features** where present (OpenAlea's PlantFrame conventions): ``XX``, ``YY``,
  ``ZZ`` are the coordinates of the entity's *top*; its base is its parent's top (a first
  entity starts at the nearest complex that has coordinates, else at the origin).  The turtle
  turns toward the top (``+`` then ``&``) and draws ``F`` of that length;
* otherwise ``Length`` (or ``Len``) gives the length, else :data:`DEFAULT_LENGTH`; an entity
  that follows (``<``) keeps its parent's heading, one that branches (``+``) rolls by
  :data:`DIVERGENCE` degrees per branch on its bearer and leans :data:`BRANCH_ANGLE` degrees
  away from it; plants without coordinates stand :data:`PLANT_SPACING` apart along x;
* ``TopDia`` / ``TopDiameter`` is the entity's top diameter and ``BotDia`` /
  ``BottomDiameter`` its base diameter (default: its parent's top diameter), written as the
  turtle's width ``!(w)`` in the file's units (``#widthscale`` rescales them).

``AA``/``BB``/``CC`` (Euler angles) orient organs in PlantFrame; the drawn axes here follow
the coordinates, so they are not needed and are left out.

>>> from ramure.lsys.architecture.mtg_graph import parse_mtg_graph
>>> from ramure.lsys import LSystem
>>> g = parse_mtg_graph('''CLASSES:
... SYMBOL SCALE DECOMPOSITION INDEXATION DEFINITION
... P 1 FREE FREE IMPLICIT
... E 2 FREE FREE IMPLICIT
... FEATURES:
... NAME TYPE
... XX REAL
... YY REAL
... ZZ REAL
... MTG:
... ENTITY-CODE\\t\\tXX\\tYY\\tZZ
... /P1/E1\\t\\t0\\t0\\t2
... ^<E2\\t\\t3\\t0\\t6''')
>>> skeleton = LSystem.from_text(mtg_grammar_text(g)).derive().skeleton()
>>> skeleton.end.round(6).tolist()
[[0.0, 0.0, 2.0], [3.0, 0.0, 6.0]]
"""

from __future__ import annotations

import math

import numpy as np

from .mtg_graph import MTGGraph

#: The length of an entity with neither coordinates nor a ``Length`` feature.
DEFAULT_LENGTH = 1.0
#: Degrees a branch leans away from its bearer when the file gives no coordinates.
BRANCH_ANGLE = 45.0
#: Degrees of roll between successive branches of one bearer (the golden angle).
DIVERGENCE = 137.5
#: Distance between plants that have no coordinates (along x).
PLANT_SPACING = 10.0
LENGTH_NAMES = ("Length", "Len")
TOP_NAMES = ("TopDia", "TopDiameter")
BOTTOM_NAMES = ("BotDia", "BottomDiameter")


def mtg_grammar_text(graph: MTGGraph, scale: int | None = None, where: str = "the MTG") -> str:
    """A Ramure grammar (``n: 0``) whose axiom draws ``graph`` at ``scale`` (default: the finest)."""
    scale = int(graph.scale.max()) if scale is None else scale
    drawer = _Drawer(graph, scale)
    axiom = drawer.axiom()
    counts = graph.vertices_per_scale()
    return (
        f"/* {where}: {counts.get(scale, 0)} entities of scale {scale} drawn "
        f"({'coordinates XX YY ZZ' if drawer.has_points else 'no coordinates: default geometry'}) */\n"
        f"n: 0\nw: {axiom}\n"
    )


def _feature(graph, names):
    """The first of ``names`` the graph declares, as a float array (nan where absent)."""
    for name in names:
        if name in graph.features:
            return np.array([np.nan if v is None else float(v) for v in graph.features[name]])
    return np.full(len(graph), np.nan)


class _Drawer:
    """Walks the finest-scale tree depth first, keeping the turtle's state as the turtle does."""

    def __init__(self, graph: MTGGraph, scale: int) -> None:
        self.graph = graph
        self.points = np.stack([_feature(graph, (name,)) for name in ("XX", "YY", "ZZ")], axis=1)
        self.has_points = bool(np.isfinite(self.points).all(axis=1).any())
        self.length = _feature(graph, LENGTH_NAMES)
        self.top = _feature(graph, TOP_NAMES)
        self.bottom = _feature(graph, BOTTOM_NAMES)
        self.drawn = np.flatnonzero(graph.scale == scale)
        self.children: dict[int, list[int]] = {}
        for v in self.drawn.tolist():
            self.children.setdefault(int(graph.parent[v]), []).append(v)
        self.out: list[str] = []

    def axiom(self) -> str:
        """The plants one after the other, each from its base with the turtle's first frame
        (no brackets around them, so the trunks keep branch order 0)."""
        plant_of = self._plants()
        state = _State()
        for root in self.children.get(-1, []):
            base = self._point_of_complex(root)
            if base is None:
                base = np.array([0.0 if self.has_points else PLANT_SPACING * plant_of[root], 0.0, 0.0])
            if np.linalg.norm(base - state.position) > 0:
                state = self._move(state, base, "f")
            state = self._upright(state)
            state = self._subtree(root, state)
        return "".join(self.out)

    def _upright(self, state):
        """Turn the turtle back to its first frame (H up the z axis, L along x)."""
        h, left, up = state.frame @ [0.0, 0.0, 1.0]
        turn = math.degrees(math.atan2(-left, h))
        pitch = math.degrees(math.atan2(up, math.hypot(h, left)))
        state = state.turn(turn).pitch(pitch)
        roll = math.degrees(math.atan2(state.frame[2, 0], state.frame[1, 0]))
        self.out.append(_rotation("+", turn) + _rotation("&", pitch) + _rotation("\\", roll))
        return _State(state.position, _State().frame)

    def _plants(self):
        """Root vertex -> rank of its scale-1 plant."""
        graph = self.graph
        plant_of: dict[int, int] = {}
        ranks: dict[int, int] = {}
        for root in self.children.get(-1, []):
            top = root
            while graph.scale[top] > 1 and graph.complex[top] > 0:
                top = int(graph.complex[top])
            plant_of[root] = ranks.setdefault(top, len(ranks))
        return plant_of

    def _point_of_complex(self, vertex):
        c = int(self.graph.complex[vertex])
        while c > 0:
            if np.isfinite(self.points[c]).all():
                return self.points[c]
            c = int(self.graph.complex[c])
        return None

    def _subtree(self, root, state):
        """Draw ``root`` and what it bears; the turtle's state after its own axis."""
        after = state
        stack = [(root, state, 0, 0)]  # vertex (-1: close a branch), state, branch rank, depth
        while stack:
            vertex, state, branch, depth = stack.pop()
            if vertex < 0:
                self.out.append("]")
                continue
            if branch:
                self.out.append("[")
            end = self._draw(vertex, state, branch)
            after = end if depth == 0 else after
            kids = self.children.get(vertex, [])
            follow = [k for k in kids if self.graph.edge[k] == "<"][:1]
            branches = [k for k in kids if k not in follow]
            for k in follow:
                stack.append((k, end, 0, depth))
            for rank, k in reversed(list(enumerate(branches))):
                stack.append((-1, end, 0, depth))
                stack.append((k, end, rank + 1, depth + 1))
        return after

    def _draw(self, vertex, state, branch):
        g = self.graph
        width = self.bottom[vertex]
        if not np.isfinite(width) and g.parent[vertex] >= 0:
            width = self.top[g.parent[vertex]]
        if not np.isfinite(width):
            width = self.top[vertex]
        if np.isfinite(width):
            self.out.append(f"!({_num(width)})")
        if np.isfinite(self.points[vertex]).all():
            return self._move(state, self.points[vertex], "F")
        if branch:
            state = state.roll(-DIVERGENCE * branch).pitch(BRANCH_ANGLE)
            self.out.append(f"/({_num(DIVERGENCE * branch)})&({_num(BRANCH_ANGLE)})")
        length = self.length[vertex] if np.isfinite(self.length[vertex]) else DEFAULT_LENGTH
        self.out.append(f"F({_num(length)})")
        return state.forward(length)

    def _move(self, state, target, symbol):
        """Turn toward ``target`` (``+`` then ``&``) and draw or move there."""
        d = np.asarray(target, float) - state.position
        distance = float(np.linalg.norm(d))
        if distance == 0:
            self.out.append(f"{symbol}(0)")
            return state
        h, left, up = state.frame @ d / distance
        turn = _angle(math.degrees(math.atan2(-left, h)))
        pitch = _angle(math.degrees(math.atan2(up, math.hypot(h, left))))
        moved = state.turn(turn).pitch(pitch)
        self.out.append(_rotation("+", turn) + _rotation("&", pitch) + f"{symbol}({_num(distance)})")
        return moved.forward(distance)


class _State:
    """The turtle's position and frame (rows H, L, U), rotated exactly as the turtle does."""

    def __init__(self, position=None, frame=None) -> None:
        self.position = np.zeros(3) if position is None else position
        self.frame = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]) if frame is None else frame

    def _rotated(self, i, j, degrees):
        """Rows i, j -> (i c + j s, j c - i s), the turtle's rotation of a pair of axes."""
        c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
        frame = self.frame.copy()
        frame[i], frame[j] = self.frame[i] * c + self.frame[j] * s, self.frame[j] * c - self.frame[i] * s
        return _State(self.position, frame)

    def turn(self, degrees):  # + : about U
        return self._rotated(0, 1, -degrees)

    def pitch(self, degrees):  # & : about L
        return self._rotated(0, 2, degrees)

    def roll(self, degrees):  # \\ : about H
        return self._rotated(1, 2, degrees)

    def forward(self, length):
        return _State(self.position + length * self.frame[0], self.frame)


def _num(x):
    return f"{float(x):.9g}"


#: Turns below this many degrees are not written (the file's coordinates are rounded anyway).
MIN_TURN = 1e-4


def _angle(degrees):
    return 0.0 if abs(degrees) < MIN_TURN else degrees


def _rotation(symbol, degrees):
    return f"{symbol}({_num(degrees)})" if degrees else ""
