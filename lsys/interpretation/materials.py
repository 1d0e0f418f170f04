"""Materials: ``;(i)`` selects material i, ``#material i r g b [a]`` gives its colour.

The material of a branch segment, polygon or organ is the turtle's colour
index where it was drawn (``;(i)`` and ``'(i)`` set it, ``'`` adds 1, ``;``
alone subtracts 1).  A grammar's table maps indices to colours::

    #material 1 0.2 0.6 0.1        // leaves: green
    #material 2 0.95 0.9 0.3 0.8   // petals: yellow, alpha 0.8

Components are numbers from 0 to 1 (divide 0-255 values by 255); alpha
defaults to 1.  An index is a whole number from 0 to :data:`MAX_MATERIAL`.
Every mesh cell carries its index (``cell_data["material"]``) and a mesh whose
grammar has a table carries it as ``field_data["material_rgb"]`` rows
``(index, r, g, b)`` and ``field_data["material_rgba"]`` rows
``(index, r, g, b, a)`` for exporters and viewers.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from ..language.grammar import GrammarParser, SourceLine

#: The largest material index accepted.
MAX_MATERIAL = 2**31 - 1


def parse_directive(parser: GrammarParser, line: SourceLine, start: int) -> tuple[int, tuple[float, ...]]:
    """``#material i r g b [a]``: returns (index, (r, g, b, a))."""
    words = [(w.group(), start + w.start()) for w in re.finditer(r"\S+", line.text[start:])]
    if len(words) not in (4, 5):
        raise line.error(
            "#material takes an index and a colour: i r g b [a], components 0..1, e.g. '#material 1 0.2 0.6 0.1'", start + 1
        )
    values = [parser.constant(line, col, col + len(w)) for w, col in words]
    index = values[0]
    if index != int(index) or not 0 <= index <= MAX_MATERIAL:
        raise line.error(f"a material index is a whole number from 0 to {MAX_MATERIAL}, not {index:g}", words[0][1] + 1)
    for (word, col), value in zip(words[1:], values[1:]):
        if not 0.0 <= value <= 1.0:
            raise line.error(f"a colour component is a number from 0 to 1, not {value:g} (divide 0-255 values by 255)", col + 1)
    rgba = tuple(float(v) for v in values[1:]) + ((1.0,) if len(values) == 4 else ())
    return int(index), rgba


def table_arrays(materials: Mapping[int, Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """``(rgb rows (k,4): index r g b, rgba rows (k,5))`` of a ``#material`` table, sorted by index."""
    items = sorted(materials.items())
    rgba = np.array([(i, *c) for i, c in items], float).reshape(-1, 5)
    return rgba[:, :4].copy(), rgba


def colors(
    materials: Mapping[int, Sequence[float]], index: ArrayLike, default: Sequence[float] = (0.55, 0.4, 0.25, 1.0)
) -> np.ndarray:
    """RGBA (n,4) floats of material indices ``index``; indices not in the table get ``default``."""
    index = np.asarray(index, np.int64)
    out = np.tile(np.asarray(default, float), (len(index), 1))
    for i, rgba in materials.items():
        out[index == i] = rgba
    return out
