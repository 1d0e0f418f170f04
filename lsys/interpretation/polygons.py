"""Polygons drawn by the turtle (the ``{``, ``.``, ``}`` modules of ABOP sections 1.10.3 and 5.1) and their triangles.

Grammar symbols, as read by :mod:`ramure.lsys.interpretation.turtle`:

=========  ==========================================================
``{``      start a polygon; the turtle's position is its first vertex
``.``      record the turtle's position as a vertex
``F f``    inside a polygon: move by the step (or the parameter) without
           drawing a branch, and record the position reached as a vertex
           (ABOP fig. 1.26's ``{+f-ff-f+|+f-ff-f}`` traces its outline
           with ``f``; L-Py records ``F`` the same way)
``G``      inside a polygon: move without recording (ABOP fig. 5.5's
           ``C -> GC``); outside a polygon ``G`` means nothing
``}``      close the polygon; it is filled
=========  ==========================================================

Choices the books leave open, made here:

- Polygons have their own stack, independent of ``[ ]`` (cpfg; ABOP's
  cordate leaf ``[+A{.].C.}`` opens a polygon inside a branch and closes it
  after the ``]``).  A ``{`` inside an open polygon starts a nested one; the
  vertices recorded go to the innermost open polygon only.
- A vertex equal to the polygon's previous vertex is not stored twice (so
  ``{.`` and ``.f.`` are harmless), nor is a last vertex equal to the first
  (an outline that returns to its start).
- A polygon takes the colour index (material, ``;(i)`` or ``'(i)``) in force
  at its ``{``, and the history leaf of its ``{`` module: picking any of its
  triangles selects that module, whose ancestors are the rule applications
  that made the leaf, so a leaf or petal is selected and regrown like a branch.
- Polygons are triangulated in the plane that best fits them (Newell's
  normal): a fan when convex, ear clipping otherwise.  One compiled loop
  (:func:`triangulate`) does every polygon; a polygon with no area (all its
  vertices on a line) gives no triangle.

Bad input: a ``}`` with no open polygon, a ``.`` outside a polygon, a ``{``
never closed, or a polygon with fewer than 3 vertex records is refused with
the rule (line, column, caret) that wrote the module.  The grammar parser
refuses what it can already see (see :func:`check_grammar`).
"""

from __future__ import annotations

import sys
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..errors import DerivationError, GrammarError

if TYPE_CHECKING:
    from ..engine.derive import LSystem
    from ..language.grammar import Grammar, ModuleSpec, Rule
    from ..history.tree import DerivationTree

#: Fewest vertices a polygon is made of.
MIN_VERTICES = 3
#: Concave polygons with more vertices than this are fanned, not ear clipped (ear clipping is
#: quadratic: a generated outline of a million vertices must not stall the viewer).
MAX_EAR_CLIP = 2000
#: The polygon errors, by the kernel's error code (see :func:`check_walk`).
MESSAGES = {
    1: "'}' closes a polygon, but no polygon is open here (no '{' before it)",
    2: "'.' records a polygon vertex, but it is outside any polygon: put it between '{' and '}'",
    3: "this '{' starts a polygon that is never closed: add '}'",
    4: "this polygon has fewer than 3 vertices: record at least 3 with '.', 'f' or 'F' before '}'",
}
ERR_FEW_VERTICES = 4


@dataclass
class Polygons:
    """The filled polygons of a plant, as arrays.

    ``leaf_id`` (p,) the history leaf of each polygon's ``{``; ``color`` (p,)
    its colour/material index; ``offsets`` (p+1,) so polygon ``i``'s vertices
    are ``points[offsets[i]:offsets[i+1]]`` (in drawing order).
    """

    leaf_id: np.ndarray
    color: np.ndarray
    offsets: np.ndarray
    points: np.ndarray

    @classmethod
    def empty(cls) -> Polygons:
        return cls(np.zeros(0, np.int64), np.zeros(0, np.int32), np.zeros(1, np.int64), np.zeros((0, 3)))

    def __len__(self) -> int:
        return len(self.leaf_id)

    @property
    def sizes(self) -> np.ndarray:
        """Vertices per polygon."""
        return np.diff(self.offsets)

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """``(tris, polygon)``: triangles (t,3) as indices into :attr:`points` and each one's polygon."""
        return triangulate(self.points, self.offsets)

    def areas(self) -> np.ndarray:
        """Area of each polygon (the sum of its triangles' areas)."""
        tris, poly = self.triangles()
        return np.bincount(poly, triangle_areas(self.points, tris), minlength=len(self))

    def select(self, leaf_ids: Iterable[int]) -> np.ndarray:
        """Boolean mask of the polygons made by the given history leaves."""
        return np.isin(self.leaf_id, np.asarray(list(leaf_ids), np.int64))


def triangle_areas(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Area of each triangle (t,)."""
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def from_walk(leaves: np.ndarray, poly: tuple) -> Polygons:
    """The :class:`Polygons` of one turtle walk (see :func:`ramure.lsys.interpretation._turtle_kernel.walk`)."""
    poly_at, _close, color, _records, vtx, tag = poly
    if "numba" in sys.modules and len(tag) >= GATHER_KERNEL_MIN:
        from ._polygon_kernel import gather  # numba loads on first use only

        offsets, points = gather(vtx, tag, len(poly_at))
    else:
        offsets, points = _gather(vtx, tag, len(poly_at))
    return Polygons(leaves[poly_at].astype(np.int64), color.astype(np.int32), offsets, points)  # ids handed out: int64


#: Walks with at least this many vertices (and numba loaded) gather them in one compiled pass.
GATHER_KERNEL_MIN = 100_000


def _gather(vtx, tag, n_poly):
    """What :func:`ramure.lsys.interpretation._polygon_kernel.gather` does, with a stable sort (no numba)."""
    kept = np.flatnonzero(tag >= 0)
    owner = tag[kept]
    order = np.argsort(owner, kind="stable")
    offsets = np.zeros(n_poly + 1, np.int64)
    np.cumsum(np.bincount(owner, minlength=n_poly), out=offsets[1:])
    return offsets, vtx[kept[order]].reshape(-1, 3)


def concatenate(parts: Iterable[Polygons]) -> Polygons:
    """One :class:`Polygons` from several, in order."""
    parts = [p for p in parts if len(p)]
    if not parts:
        return Polygons.empty()
    sizes = np.concatenate([p.sizes for p in parts])
    offsets = np.zeros(len(sizes) + 1, np.int64)
    np.cumsum(sizes, out=offsets[1:])
    return Polygons(
        np.concatenate([p.leaf_id for p in parts]),
        np.concatenate([p.color for p in parts]),
        offsets,
        np.concatenate([p.points for p in parts]),
    )


def take(polygons: Polygons, index: ArrayLike) -> Polygons:
    """The polygons ``index`` (an integer array, in that order)."""
    index = np.asarray(index, np.int64)
    sizes = polygons.sizes[index]
    offsets = np.zeros(len(index) + 1, np.int64)
    np.cumsum(sizes, out=offsets[1:])
    starts = polygons.offsets[index]
    rows = np.repeat(starts - offsets[:-1], sizes) + np.arange(offsets[-1])
    return Polygons(polygons.leaf_id[index], polygons.color[index], offsets, polygons.points[rows])


def polygon_depths(acts: np.ndarray, push: int, pop: int, start: int, end: int, at: np.ndarray) -> tuple[bool, np.ndarray]:
    """(local, depth): whether every polygon closes in the branch that opened it (and every
    ``}`` has its ``{``), and the number of open polygons before each position of ``at``
    (sorted; ``len(acts)`` means after the last module).  One compiled pass."""
    from ._polygon_kernel import polygon_depths as depths  # numba loads on first use only

    local, depth = depths(acts, push, pop, start, end, at)
    return bool(local), depth


# -- errors -----------------------------------------------------------------------------
def check_walk(lsys: LSystem, tree: DerivationTree, leaves: np.ndarray, poly: tuple, err: np.ndarray) -> None:
    """Raise the polygon error a walk found (``err``), or for a polygon with < 3 vertex records."""
    code, at = int(err[0]), int(err[1])
    poly_at, _close, _color, records = poly[:4]
    few = np.flatnonzero(records < MIN_VERTICES)
    if few.size and (code < 0 or poly_at[few[0]] < at):
        code, at = ERR_FEW_VERTICES, int(poly_at[few[0]])
    if code < 0:
        return
    raise located_error(lsys, tree, int(leaves[at]), MESSAGES[code])


def located_error(lsys: LSystem, tree: DerivationTree, node: int, message: str) -> DerivationError:
    """A :class:`DerivationError` naming module ``node`` and, with a caret, where its rule (or the
    axiom) wrote it."""
    rule, slot = int(tree.rule[node]), int(tree.index_in_rule[node])
    g = lsys.grammar
    if rule <= -2 and -2 - rule < len(getattr(g, "interpretation", [])):  # an interpretation rule wrote it
        specs, where = g.interpretation[-2 - rule].successor, f"interpretation rule {-1 - rule}"
    elif rule < 0:
        specs, where = g.axiom, "the axiom"
    else:
        specs, where = g.rules[rule].successor, f"rule {rule + 1}"
    module = lsys.module_text(tree, node)
    if 0 <= slot < len(specs) and specs[slot].line is not None:
        spec = specs[slot]
        err = DerivationError(
            f"{message} (module {module}, written by {where})",
            spec.line.number,
            spec.column,
            spec.line.original,
            filename=spec.line.filename,
        )
        return err
    return DerivationError(f"{message} (module {module}, written by {where})")


# -- parse-time checks ------------------------------------------------------------------
def check_grammar(grammar: Grammar) -> None:
    """Refuse at parse time the polygon mistakes that no derivation can repair.

    When no rule rewrites ``{``, ``}`` or ``.`` and every successor opens as many
    polygons as it closes (true of ABOP's grammars, including the rose leaf
    whose successors close a polygon before opening the next), every derived
    string has the axiom's polygon balance: so an axiom with a ``}`` before any
    ``{``, an unclosed ``{`` or a ``.`` outside every polygon is refused with
    line, column and caret.  A polygon written whole in one successor or the
    axiom, with nothing inside it that a rule rewrites, is refused when it
    cannot reach 3 points (its start and one per move ``F f G``).  The rest is
    checked on the derived string.
    """
    marks = {"{", "}", "."}
    rules = all_rules(grammar)
    rewritten = {r.pred.symbol for r in rules}
    for specs in [grammar.axiom] + [r.successor for r in rules]:
        check_written_polygons(specs, rewritten)
    if marks & rewritten:
        return
    if any(_balance(r.successor) != 0 for r in rules):
        return
    depth, opened = 0, []
    for spec in grammar.axiom:
        if spec.symbol == "{":
            depth += 1
            opened.append(spec)
        elif spec.symbol == "}":
            if not depth:
                raise _spec_error(spec, MESSAGES[1])
            depth -= 1
            opened.pop()
        elif spec.symbol == "." and not depth:
            raise _spec_error(spec, MESSAGES[2])
    if opened:
        raise _spec_error(opened[-1], MESSAGES[3])


def all_rules(grammar: Grammar) -> list[Rule]:
    """Production, decomposition and interpretation rules of a grammar."""
    return [*grammar.rules, *getattr(grammar, "decomposition", []), *getattr(grammar, "interpretation", [])]


def _balance(specs):
    return sum((s.symbol == "{") - (s.symbol == "}") for s in specs)


_MOVES = {"F", "f", "G"}


def check_written_polygons(specs: Iterable[ModuleSpec], rewritten: Collection[str]) -> None:
    """A polygon (``{`` to ``}``) written whole that cannot reach 3 points (and nothing inside that a rule rewrites)."""
    stack: list[list] = []  # (spec of '{', records, has rewritten modules)
    for spec in specs:
        if spec.symbol == "{":
            stack.append([spec, 1, spec.symbol in rewritten])
        elif spec.symbol == "}" and stack:
            start, records, unsure = stack.pop()
            if not unsure and records < MIN_VERTICES:
                raise _spec_error(start, MESSAGES[ERR_FEW_VERTICES])
        elif stack:
            top = stack[-1]
            top[1] += spec.symbol in _MOVES
            top[2] = top[2] or spec.symbol in rewritten or spec.symbol.startswith("~")


def _spec_error(spec, message):
    line = spec.line
    return GrammarError(message, line.number, spec.column, line.original, filename=line.filename)


# -- triangulation ----------------------------------------------------------------------
def triangulate(points: ArrayLike, offsets: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of every polygon: ``(tris (t,3) indices into points, polygon index (t,))``.

    A convex polygon is a fan from its first vertex; a non-convex one is ear
    clipped (up to :data:`MAX_EAR_CLIP` vertices; a fan beyond, which may
    overlap itself); one with no area gives nothing.  Each polygon is first projected
    on the coordinate plane most perpendicular to its Newell normal.
    """
    points = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
    offsets = np.ascontiguousarray(offsets, np.int64)
    from ._polygon_kernel import triangulate as compiled  # numba loads on first use only

    return compiled(points, offsets, MAX_EAR_CLIP)
