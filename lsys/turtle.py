"""The 3D turtle (ABOP ch. 1): from a derived string to a :class:`Skeleton`.

The turtle keeps a position and a frame of unit vectors H (heading), L (left)
and U (up) with ``H x L = U``.  It starts at the origin heading up the z axis
(H = +z, L = +x, U = +y), so 2D grammars lie in the x-z plane.

=========  ==========================================================
``F(l)``   draw a branch segment of length l (default ``#step``)
``f(l)``   move by l without drawing
``+ -``    turn left / right about U by the parameter (default ``#angle``)
``& ^``    pitch down / up about L
``\\ /``    roll left / right about H
``|``      turn around (180 degrees about U)
``$``      roll about H so that L is horizontal (ABOP's ``$``)
``[ ]``    push / pop the whole state (position, frame, width, colour, order)
``!(w)``   set the width (diameter) to w; ``!`` alone multiplies it by 0.7
``'(c)``   set the colour index to c; ``'`` alone adds 1 (``;`` subtracts 1)
organs     ``Leaf``, ``Fruit`` and every ``#organ`` module are recorded with
           the turtle's position and frame; their first parameter is the size
=========  ==========================================================

A segment's **base radius** is half the width when it is drawn, times
``#widthscale`` (default 1; ABOP widths are often in pixels, so a grammar may
scale them).  Its **top radius** is the base radius of the segment that
continues it on the same axis (the next ``F`` at the same branch order), else
the widest segment forking from its tip, else its own base radius, so the
tubes join smoothly.

Tropism (``#tropism tx ty tz e``) bends H toward T by ``e*|H x T|`` after each
``F``, as in ABOP section 2.3.

Branch order is the number of ``[`` open around a segment (the trunk is 0).

The interpreter is one compiled loop (:mod:`numba`, see :func:`_walk`) over
arrays of the string: actions, parameter counts and first parameters.  It
also records the turtle state at every ``[`` (a :class:`Trace`), so an edit
re-interprets only the part of the string it changed (:func:`reinterpret`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from .errors import DerivationError


class TurtleAction(IntEnum):
    """What a module does to the turtle (the compiled loop dispatches on these values)."""

    NONE = 0  # no turtle meaning (skipped)
    DRAW = 1  # F
    MOVE = 2  # f
    TURN_LEFT = 3  # +
    TURN_RIGHT = 4  # -
    PITCH_DOWN = 5  # &
    PITCH_UP = 6  # ^
    ROLL_LEFT = 7  # \\
    ROLL_RIGHT = 8  # /
    TURN_AROUND = 9  # |
    ROLL_HORIZONTAL = 10  # $
    PUSH = 11  # [
    POP = 12  # ]
    WIDTH = 13  # !
    COLOR_UP = 14  # '
    COLOR_DOWN = 15  # ;
    ORGAN = 16  # Leaf, Fruit and #organ modules


#: The turtle symbols and their actions (organs come from the grammar's ``#organ``).
SYMBOL_ACTIONS = {
    "F": TurtleAction.DRAW, "f": TurtleAction.MOVE, "+": TurtleAction.TURN_LEFT,
    "-": TurtleAction.TURN_RIGHT, "&": TurtleAction.PITCH_DOWN, "^": TurtleAction.PITCH_UP,
    "\\": TurtleAction.ROLL_LEFT, "/": TurtleAction.ROLL_RIGHT, "|": TurtleAction.TURN_AROUND,
    "$": TurtleAction.ROLL_HORIZONTAL, "[": TurtleAction.PUSH, "]": TurtleAction.POP,
    "!": TurtleAction.WIDTH, "'": TurtleAction.COLOR_UP, ";": TurtleAction.COLOR_DOWN,
}


@dataclass
class Organs:
    """Organs as arrays: ``kind`` (str), ``position`` (k,3), ``frame`` (k,3,3) with rows
    H, L, U, ``size`` (k,), ``params`` (k,p) and the history ``leaf_id`` (k,)."""

    kind: np.ndarray
    position: np.ndarray
    frame: np.ndarray
    size: np.ndarray
    params: np.ndarray
    leaf_id: np.ndarray

    def __len__(self):
        return len(self.kind)


@dataclass
class Skeleton:
    """Branch segments (truncated cones) and organs of a derived plant, as numpy arrays.

    ``start``/``end`` (s,3); ``base_radius``/``top_radius`` (s,); ``order`` (s,)
    branch order; ``leaf_id`` (s,) the history-tree leaf (module ``F``) that drew
    the segment; ``color`` (s,) colour index; ``normal`` (s,3) the turtle's L
    vector, used to orient tube rings; ``parent`` (s,) the segment this one
    grows from (-1 at the base).
    """

    start: np.ndarray
    end: np.ndarray
    base_radius: np.ndarray
    top_radius: np.ndarray
    order: np.ndarray
    leaf_id: np.ndarray
    color: np.ndarray
    normal: np.ndarray
    parent: np.ndarray
    organs: Organs
    extra: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.start)

    @property
    def length(self):
        return np.linalg.norm(self.end - self.start, axis=1)

    def bounds(self):
        """Axis-aligned ``(min xyz, max xyz)`` of segments (with radii) and organs."""
        pts = [self.start, self.end]
        if len(self.organs):
            pts.append(self.organs.position)
        pts = np.concatenate(pts) if any(len(p) for p in pts) else np.zeros((1, 3))
        pad = float(max(self.base_radius.max(initial=0), self.organs.size.max(initial=0)))
        return pts.min(axis=0) - pad, pts.max(axis=0) + pad

    def select(self, leaf_ids):
        """Boolean mask of the segments drawn by the given history leaves."""
        return np.isin(self.leaf_id, np.asarray(list(leaf_ids), np.int64))

    def to_polydata(self, sides=8, organ_resolution=8):
        """All tubes and organs as one :class:`pyvista.PolyData` (see :mod:`ramure.lsys.geometry`)."""
        from .geometry import skeleton_to_polydata

        return skeleton_to_polydata(self, sides=sides, organ_resolution=organ_resolution)


@dataclass
class Trace:
    """What a skeleton keeps of its turtle run so an edit re-interprets only what it changed.

    ``leaves`` is the string interpreted (node ids); ``acts``, ``nps``,
    ``par`` its action codes, parameter counts and first parameters;
    ``segment_at`` / ``organ_at`` the string position of each segment's ``F``
    / each organ; ``match`` the bracket matches (None when some bracket is
    unmatched: edits then re-interpret the whole string).  The turtle state
    at any position is found again by walking from the root and jumping over
    the branches in between (:func:`ramure.lsys._turtle_kernel.walk`, SEEK).
    """

    leaves: np.ndarray
    acts: np.ndarray
    nps: np.ndarray
    par: np.ndarray
    segment_at: np.ndarray
    organ_at: np.ndarray
    match: np.ndarray | None

    def nbytes(self) -> int:
        arrays = (self.acts, self.nps, self.par, self.segment_at, self.organ_at, self.match)
        return sum(a.nbytes for a in arrays if a is not None)


def _settings(lsys):
    g = lsys.grammar
    trop = np.asarray(g.tropism, float) if g.tropism is not None else np.zeros(0)
    return float(g.angle), float(g.step), trop


def action_table(lsys):
    """The :class:`TurtleAction` of every symbol of ``lsys`` (one more entry, 0, for padding)."""
    organs = set(lsys.grammar.organs)
    return np.array([SYMBOL_ACTIONS.get(s, TurtleAction.ORGAN if s in organs else TurtleAction.NONE)
                     for s in lsys.symbols] + [0], np.int8)


def module_arrays(lsys, tree, leaves):
    """Per module of ``leaves``: action code, parameter count and first parameter."""
    acts = action_table(lsys)[tree.symbol[leaves]]
    nps = tree.nparams[leaves]
    par = tree.params[leaves, 0]
    return acts, nps, par


def interpret(derivation):
    """Run the turtle over a derivation's current string and return its :class:`Skeleton`."""
    return interpret_string(derivation.lsystem, derivation.tree, derivation.tree.leaves)


def interpret_string(lsys, tree, leaves) -> Skeleton:
    """The :class:`Skeleton` of the string ``leaves`` (node ids of ``tree``), with its :class:`Trace`."""
    from ._turtle_kernel import FULL, initial_state, walk  # numba loads on first use only

    leaves = np.asarray(leaves, np.int64)
    acts, nps, par = module_arrays(lsys, tree, leaves)
    angle, step, trop = _settings(lsys)
    state = initial_state(lsys.grammar.width)
    _, segs, orgs = walk(acts, nps, par, 0, len(acts), _NO_MATCH, FULL, state, angle, step, trop, 0)
    trace = Trace(leaves, acts, nps, par, segs[0], orgs[0], _matches(acts))
    return _skeleton(lsys, tree, leaves, segs, orgs, trace)


_NO_MATCH = np.zeros(0, np.int64)


def _matches(acts):
    """Bracket matches of the string from its actions; None if some bracket is unmatched."""
    from ._turtle_kernel import bracket_pairs

    match, balanced = bracket_pairs(acts, int(TurtleAction.PUSH), int(TurtleAction.POP))
    return match if balanced else None


def _skeleton(lsys, tree, leaves, segs, orgs, trace):
    seg_at, start, end, width, order, color, normal, parent = segs
    base = width * (lsys.grammar.width_scale / 2.0)
    leaf = leaves[seg_at]
    _check_finite(lsys, tree, leaf, np.isfinite(start).all(1) & np.isfinite(end).all(1) & np.isfinite(base))
    organs = _organs(lsys, tree, leaves, orgs)
    return Skeleton(start, end, base, top_radius(base, order, parent), order.astype(np.int32), leaf,
                    color.astype(np.int32), normal, parent, organs, {"trace": trace})


def top_radius(base, order, parent):
    """Each segment's top radius: its continuation's base radius, else its widest fork's, else its own."""
    s = len(base)
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
    return top


def _check_finite(lsys, tree, leaf, ok):
    """Refuse a plant whose turtle overflowed (e.g. F(1e308)F(1e308)): no inf/NaN geometry."""
    if ok.all():
        return
    module = lsys.module_text(tree, int(leaf[int(np.argmin(ok))]))
    raise DerivationError(f"the turtle geometry is not finite at module {module} (a length, width or "
                          "angle too large for floating point): use smaller values")


def _organs(lsys, tree, leaves, orgs):
    org_at, position, frame, size = orgs
    leaf_id = leaves[org_at]
    kind = np.array(lsys.symbols, dtype=object)[tree.symbol[leaf_id]] if len(leaf_id) else \
        np.array([], dtype=object)
    _check_finite(lsys, tree, leaf_id, np.isfinite(position).all(1) & np.isfinite(size))
    return Organs(kind, position, frame, size, tree.params[leaf_id], leaf_id)
