"""Predefined surfaces ``~name(scale)``: leaves, petals and sepals placed by the turtle.

A surface is a small triangle mesh in the turtle's local frame, coordinates
``(h, l, u)`` along its heading, left and up vectors: the base at the origin,
the tip at ``h = 1``.  ``~name(s)`` draws it scaled by ``s`` (``~name``
alone: 1) at the turtle's position and orientation, in the colour/material
in force, as an organ of kind ``"~name"`` (so it is picked, selected and
regrown through its module's history leaf like any organ).

Shipped (:data:`LIBRARY`): ``leaf`` (lanceolate, folded along the midrib and
arched), ``petal`` (obovate, cupped), ``sepal`` (narrow, pointed, slightly
cupped), ``disc`` (a flat round disc, for flower centres); ``l`` is ``leaf`` under the name
cpfg and L-Py give their predefined leaf (``~l``).

A grammar defines its own with ``#surface`` (its name may shadow a shipped one):

``#surface NAME MODULES``
    a turtle string of polygon modules, drawn from the origin heading along
    +h: e.g. ``#surface heart {.-(40)f(.5).+(80)f(.5).+(60)f(.4).}``.  Its
    parameters are constant expressions (``#define`` constants may be used).
``#surface NAME "FILE"``
    the polygons of another grammar file (relative to this one), derived with
    its own ``n:`` — a leaf made by a polygon sub-grammar such as ABOP's
    cordate leaf (fig. 5.5).  The sub-grammar's turtle starts at the origin
    heading up +z, with L = +x and U = +y, which become h, l and u.

A surface name used but neither shipped nor defined is a :class:`GrammarError`
with line, column and caret when the grammar is read.
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable, Iterable, Mapping
from functools import cache, lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..errors import GrammarError

if TYPE_CHECKING:
    from ..language.grammar import Grammar, GrammarParser, ModuleSpec, SourceLine
    from .polygons import Polygons

#: Grid of the shipped surfaces: points along the length and across the width.
_ALONG, _ACROSS = 12, 7


def _blade(width, cup, arch, fold: float = 0.0):
    """A surface as a grid over (t along, s across): half-width ``width(t)``, ``u`` from cupping
    (``cup`` times s²), an arch along the length and a fold along the midrib (``fold`` times |s|)."""
    t = np.linspace(0.0, 1.0, _ALONG)
    s = np.linspace(-1.0, 1.0, _ACROSS)
    T, S = np.meshgrid(t, s, indexing="ij")
    w = width(T)
    pts = np.stack([T, S * w, cup * (S * w) ** 2 + fold * np.abs(S) * w - arch * T**2], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(_ALONG - 1), np.arange(_ACROSS - 1), indexing="ij")
    a = (i * _ACROSS + j).ravel()
    b, c, d = a + 1, a + _ACROSS, a + _ACROSS + 1
    tris = np.concatenate([np.stack([a, c, d], 1), np.stack([a, d, b], 1)])
    area = 0.5 * np.linalg.norm(np.cross(pts[tris[:, 1]] - pts[tris[:, 0]], pts[tris[:, 2]] - pts[tris[:, 0]]), axis=1)
    return pts, tris[area > 1e-12]  # no slivers where the outline meets the midrib at base and tip


def _leaf():
    return _blade(lambda t: 0.22 * np.sin(np.pi * t) ** 0.9 * (1.15 - 0.3 * t), cup=0.0, arch=0.12, fold=0.25)


def _petal():
    return _blade(lambda t: 0.36 * np.sin(np.pi * np.sqrt(t) * 0.98) * np.sqrt(t), cup=1.2, arch=0.05)


def _sepal():
    return _blade(lambda t: 0.16 * np.sin(np.pi * t) ** 0.6 * (1.0 - 0.6 * t), cup=0.8, arch=0.03)


def _disc():
    k = 24
    a = np.linspace(0, 2 * np.pi, k, endpoint=False)
    pts = np.vstack([[0.5, 0.0, 0.0], np.stack([0.5 + 0.5 * np.cos(a), 0.5 * np.sin(a), np.zeros(k)], 1)])
    j = np.arange(k)
    return pts, np.stack([np.zeros(k, int), 1 + j, 1 + (j + 1) % k], 1)


#: The shipped surfaces: name -> function returning (points (m,3) in (h,l,u), triangles (t,3)).
LIBRARY = {"leaf": _leaf, "petal": _petal, "sepal": _sepal, "disc": _disc, "l": _leaf}


@cache
def shipped(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Points and triangles of a shipped surface (read-only arrays)."""
    pts, tris = LIBRARY[name]()
    pts.flags.writeable = tris.flags.writeable = False
    return pts, tris


def names(grammar: Grammar | None = None) -> list[str]:
    """Every surface name a grammar can use: shipped ones and its ``#surface`` ones."""
    return sorted(set(LIBRARY) | set(getattr(grammar, "surfaces", {}) or {}))


def check_grammar(grammar: Grammar) -> None:
    """Refuse a ``~name`` that is neither shipped nor defined by ``#surface`` (line, column, caret)."""
    known = set(names(grammar))
    from .polygons import all_rules

    written = list(grammar.axiom) + [m for r in all_rules(grammar) for m in r.successor]
    for spec in written:
        if spec.symbol.startswith("~") and spec.symbol[1:] not in known:
            line = spec.line
            raise GrammarError(
                f"unknown surface '{spec.symbol[1:]}' in {spec.symbol}: known surfaces are "
                f"{', '.join(names(grammar))} (define one with #surface)",
                line.number,
                spec.column,
                line.original,
                filename=line.filename,
            )
        if spec.symbol.startswith("~") and len(spec.args) > 1:
            line = spec.line
            raise GrammarError(
                f"{spec.symbol} takes one parameter, its scale", line.number, spec.column, line.original, filename=line.filename
            )


def templates(
    grammar: Grammar, constants: Mapping[str, float], kinds: Iterable[str], draw_file: Callable[[str], Polygons] | None = None
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{kind: (points, triangles)}`` for the surface organ kinds ``"~name"`` among ``kinds``.

    ``draw_file(path)`` derives and draws a ``#surface "file.lsys"`` (the turtle passes
    :meth:`ramure.lsys.engine.derive.LSystem.file_polygons`, so this module imports no engine).
    """
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for kind in kinds:
        name = str(kind)[1:]
        defined = (getattr(grammar, "surfaces", None) or {}).get(name)
        if defined is not None:
            out[kind] = _defined(grammar, defined, constants, draw_file)
        elif name in LIBRARY:
            out[kind] = shipped(name)
    return out


def _defined(grammar, definition, constants, draw_file):
    """Points and triangles of a ``#surface`` (a module string or a grammar file)."""
    if definition.path is not None:
        path = pathlib.Path(definition.path)
        stamp = path.stat().st_mtime_ns if path.exists() else 0
        if draw_file is None:
            raise GrammarError(f"#surface {definition.name}: drawing the grammar file {path} needs a drawing function")
        return _from_file(str(path), stamp, draw_file)  # an edited sub-grammar file is read again
    key = (id(definition), tuple(sorted((k, float(v)) for k, v in constants.items())))
    cached = _CACHE.get(key)
    if cached is None:
        cached = _CACHE[key] = _from_modules(grammar, definition, constants)
    return cached


_CACHE: dict = {}


def _from_modules(grammar, definition, constants):
    """Run the turtle over a ``#surface``'s module string (no derivation)."""
    from ._turtle_walk import FULL, initial_state, walk  # a few modules: the plain walk, no numba
    from ..expr import evaluate_constant
    from .polygons import from_walk
    from .actions import SYMBOL_ACTIONS, TurtleAction

    specs = definition.modules
    acts = np.array([SYMBOL_ACTIONS.get(m.symbol, TurtleAction.NONE) for m in specs], np.int8)
    nps = np.array([len(m.args) > 0 for m in specs], np.bool_)
    par = np.array([evaluate_constant(m.args[0], constants) if m.args else np.nan for m in specs], float)
    trop = np.zeros(0)
    state = initial_state(grammar.width)
    _, _, _, poly, err = walk(
        acts, nps, par, 0, len(acts), np.zeros(0, np.int64), FULL, state, float(grammar.angle), float(grammar.step), trop, 0
    )
    code, at = int(err[0]), int(err[1])
    if code < 0 and (poly[3] < 3).any():
        code, at = 4, int(poly[0][np.argmax(poly[3] < 3)])
    if code >= 0:
        from .polygons import MESSAGES

        spec = specs[at]
        raise GrammarError(
            f"#surface {definition.name}: {MESSAGES[code]}",
            spec.line.number,
            spec.column,
            spec.line.original,
            filename=spec.line.filename,
        )
    polygons = from_walk(np.arange(len(specs)), poly)
    if not len(polygons):
        line = definition.line
        raise GrammarError(
            f"#surface {definition.name} draws no polygon: write it with {{ . }}",
            line.number,
            definition.column,
            line.original,
            filename=line.filename,
        )
    return _local(polygons)


_REALISING: set = set()  # surface files being derived now: a file that draws itself is a cycle


@lru_cache(maxsize=32)
def _from_file(path, stamp, draw_file):
    if path in _REALISING:
        raise GrammarError(f"#surface cycle: {path} draws a surface made from itself")
    _REALISING.add(path)
    try:
        polygons = draw_file(path)
    finally:
        _REALISING.discard(path)
    if not len(polygons):
        raise GrammarError(f"#surface: the grammar {path} draws no polygon")
    return _local(polygons)


def _local(polygons):
    """World turtle coordinates (x = L, y = U, z = H at the start) to surface (h, l, u)."""
    tris, _ = polygons.triangles()
    pts = polygons.points[:, [2, 0, 1]].copy()
    pts.flags.writeable = False
    return pts, tris


_CHECKING: set = set()  # surface files being parsed now: a file that names itself is checked once


def _check_file(parser: GrammarParser, line: SourceLine, at: int, name: str, path: pathlib.Path) -> None:
    """Parse a ``#surface`` grammar file when the directive is read, so an error in it is
    reported at once (line, column of the directive), not after the plant is derived.  A file
    that names itself is left to the drawing, which reports the cycle."""
    key = str(path)
    if key in _CHECKING:
        return
    _CHECKING.add(key)
    try:
        parser.check_file(path)
    except GrammarError as err:
        where = f"line {err.line}: " if err.line else ""
        raise line.error(f"#surface {name}: {path.name}, {where}{err.message}", at + 1) from None
    finally:
        _CHECKING.discard(key)


class SurfaceDefinition:
    """One ``#surface`` directive: a module string (``modules``) or a grammar file (``path``)."""

    def __init__(
        self, name: str, line: SourceLine, column: int, modules: list[ModuleSpec] | None = None, path: pathlib.Path | None = None
    ) -> None:
        self.name, self.line, self.column = name, line, column
        self.modules, self.path = modules, path

    def __repr__(self) -> str:
        return f"SurfaceDefinition({self.name!r}, {'file ' + str(self.path) if self.path else 'modules'})"


def parse_directive(parser: GrammarParser, line: SourceLine, start: int) -> SurfaceDefinition:
    """``#surface NAME MODULES`` or ``#surface NAME "FILE"`` (called by the grammar parser)."""
    import re

    text = line.text
    m = re.match(r"\s*([A-Za-z_][A-Za-z_0-9]*)", text[start:])
    if not m:
        raise line.error("#surface needs a name and a definition, e.g. #surface blade {.f.+f.}", start + 1)
    name, rest = m.group(1), start + m.end()
    body = text[rest:].strip()
    if not body:
        raise line.error(f'#surface {name} has no definition: a module string {{ . }} or a "file.lsys"', rest + 1)
    at = rest + len(text[rest:]) - len(text[rest:].lstrip())
    if body[0] in "\"'" and len(body) >= 2 and body[-1] == body[0]:
        path = parser.confined(line, at, f"#surface {name}", body[1:-1], line.filename or parser.filename)
        if not path.is_file():
            raise line.error(f"#surface {name}: no grammar file {body[1:-1]} ({path})", at + 1)
        _check_file(parser, line, at, name, path)
        return SurfaceDefinition(name, line, at + 1, path=path)
    modules = parser.modules_at(line, at, None, formal=False)
    from .polygons import check_written_polygons

    check_written_polygons(modules, set())
    for spec in modules:
        for arg in spec.args:
            from ..expr import evaluate_constant

            evaluate_constant(arg, parser.constants)  # constants only: refused here with a caret
    return SurfaceDefinition(name, line, at + 1, modules=modules)
