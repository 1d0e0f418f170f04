"""The turtle's alphabet: what each module symbol does to the turtle.

Kept apart from :mod:`ramure.lsys.interpretation.turtle` so that the language side (the cpfg reader, the
``#surface`` directive) can name the turtle's symbols without importing the turtle.
"""

from __future__ import annotations

from enum import IntEnum


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
    COLOR_UP = 14  # ' and ;
    COLOR_DOWN = 15  # ,
    ORGAN = 16  # Leaf, Fruit and #organ modules
    POLY_START = 17  # {
    POLY_END = 18  # }
    POLY_VERTEX = 19  # .
    POLY_MOVE = 20  # G (inside a polygon)
    SPHERE = 21  # @O
    SURFACE = 22  # ~name
    ELASTICITY = 23  # @Ts
    WIDTH_UP = 24  # # (cpfg) and _ (L-Py)


#: The turtle symbols and their actions (organs come from the grammar's ``#organ``).
SYMBOL_ACTIONS = {
    "F": TurtleAction.DRAW,
    "f": TurtleAction.MOVE,
    "+": TurtleAction.TURN_LEFT,
    "-": TurtleAction.TURN_RIGHT,
    "&": TurtleAction.PITCH_DOWN,
    "^": TurtleAction.PITCH_UP,
    "\\": TurtleAction.ROLL_LEFT,
    "/": TurtleAction.ROLL_RIGHT,
    "|": TurtleAction.TURN_AROUND,
    "$": TurtleAction.ROLL_HORIZONTAL,
    "[": TurtleAction.PUSH,
    "]": TurtleAction.POP,
    "!": TurtleAction.WIDTH,
    "'": TurtleAction.COLOR_UP,
    ";": TurtleAction.COLOR_UP,  # cpfg and L-Py: ';' raises the colour index, ',' lowers it
    ",": TurtleAction.COLOR_DOWN,
    "{": TurtleAction.POLY_START,
    "}": TurtleAction.POLY_END,
    ".": TurtleAction.POLY_VERTEX,
    "G": TurtleAction.POLY_MOVE,
    "@O": TurtleAction.SPHERE,
    "@Ts": TurtleAction.ELASTICITY,
    "#": TurtleAction.WIDTH_UP,  # cpfg
    "_": TurtleAction.WIDTH_UP,  # L-Py
    "@v": TurtleAction.ROLL_HORIZONTAL,  # cpfg's roll to vertical: ABOP's $
}
