"""The 3D turtle (ABOP ch. 1): from a derived string to a :class:`Skeleton`.

The turtle keeps a position and a frame of unit vectors H (heading), L (left)
and U (up) with ``H x L = U``.  It starts at the origin heading up the z axis
(H = +z, L = +x, U = +y), so 2D grammars lie in the x-z plane.

==============  ========================================================================
``F(l)``        draw a branch segment of length l (default ``#step``)
``f(l)``        move by l without drawing
``+ -``         turn left / right about U by the parameter (default ``#angle``)
``& ^``         pitch down / up about L
``\\ /``          roll left / right about H
``|``           turn around (180 degrees about U)
``$``           roll about H so that L is horizontal (ABOP's ``$``)
``[ ]``         push / pop the whole state (position, frame, width, colour, order)
``!(w)``        set the width (diameter) to w; ``!`` alone multiplies it by 0.7
``#(w) _(w)``   set the width to w (cpfg's ``#``, L-Py's ``_``); alone they divide it by 0.7
``@v``          cpfg's roll to vertical: the same as ``$``
``'(c)``        set the colour index to c; ``'`` alone adds 1
``;(i)``        set the colour index to i: material i of the grammar's
                ``#material`` table (the same index as ``'(i)``); ``;`` alone adds 1
``,(i)``        set the colour index to i; ``,`` alone subtracts 1 (as in cpfg and L-Py)
organs          ``Leaf``, ``Fruit`` and every ``#organ`` module are recorded with
                the turtle's position and frame; their first parameter is the size
``{ . }``       polygons (``F f`` inside one record vertices, ``G`` moves without
                recording): see :mod:`ramure.lsys.interpretation.polygons`
``@O(r)``       a sphere of radius r (``@O`` alone: diameter = the width), an organ
``~name(s)``    a predefined surface scaled by s, an organ (:mod:`ramure.lsys.interpretation.surfaces`)
``@Ts(e)``      the tropism elasticity for the rest of the branch (``[`` saves it):
                bends toward ``#tropism``'s direction (``@Tp`` sets it), else -z
==============  ========================================================================

The commands of several parameters or objects (``@M``, ``@R``, ``@o``, ``@c``, ``@B``,
``@Tp``, ``@Gs``/``@Gc``/``@Ge``, L-Py's ``LineTo``, ``SetGuide``, ``Sweep`` ...) are walked by
:mod:`ramure.lsys.interpretation._turtle_rich` (its table gives their meanings); a string without them never
pays for them.

A segment's **base radius** is half the width when it is drawn, times
``#widthscale`` (default 1; ABOP widths are often in pixels, so a grammar may
scale them).  Its **top radius** is the base radius of the segment that
continues it on the same axis (the next ``F`` at the same branch order), else
the widest segment forking from its tip, else its own base radius, so the
tubes join smoothly.

Tropism (``#tropism tx ty tz e``) bends H toward T by ``e*|H x T|`` after each
``F``, as in ABOP section 2.3.

Branch order is the number of ``[`` open around a segment (the trunk is 0).

The interpreter is one loop over arrays of the string: actions, parameter
counts and first parameters; compiled (:mod:`numba`) for long strings, the
same loop in plain Python for short ones, which then need no numba
(:data:`KERNEL_MIN_MODULES`; both give the same arrays).  It
also records the turtle state at every ``[`` (a :class:`Trace`), so an edit
re-interprets only the part of the string it changed (:func:`reinterpret`).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ._turtle_rich import CPFG_CODES, RICH_FIRST, SYMBOL_CODES, Rich, recode, symbol_codes
from .actions import SYMBOL_ACTIONS, TurtleAction
from ..errors import DerivationError
from .polygons import Polygons, check_walk, from_walk

if TYPE_CHECKING:
    import pyvista as pv

    from ..engine.derive import Derivation, LSystem
    from ..language.grammar import Grammar
    from ..history.tree import DerivationTree


#: Surfaces are the modules ``~name``: every symbol starting with this prefix.
SURFACE_PREFIX = "~"


@dataclass
class Organs:
    """Organs as arrays: ``kind`` (str), ``position`` (k,3), ``frame`` (k,3,3) with rows
    H, L, U, ``size`` (k,), ``params`` (k,p), the history ``leaf_id`` (k,) and the
    colour/material index ``color`` (k,) in force where the organ was drawn.

    Spheres ``@O`` (kind ``"@O"``, size = diameter) and surfaces ``~name``
    (kind ``"~name"``, size = scale) are organs too.
    """

    kind: np.ndarray
    position: np.ndarray
    frame: np.ndarray
    size: np.ndarray
    params: np.ndarray
    leaf_id: np.ndarray
    color: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.kind)


@dataclass
class Skeleton:
    """Branch segments (truncated cones) and organs of a derived plant, as numpy arrays.

    ``start``/``end`` (s,3); ``base_radius``/``top_radius`` (s,); ``order`` (s,)
    branch order; ``leaf_id`` (s,) the history-tree leaf (module ``F``) that drew
    the segment; ``color`` (s,) colour index; ``normal`` (s,3) the turtle's L
    vector, used to orient tube rings; ``parent`` (s,) the segment this one
    grows from (-1 at the base).

    The turtle makes ``start`` and ``end`` the two halves of one (2s, 3) array
    (:meth:`ends`), so a view that draws every segment as a line hands that array
    to VTK as its points, without a copy (6 MB at Honda n = 17, for every version
    kept).
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
    #: Filled polygons (``{ . }``), see :class:`ramure.lsys.interpretation.polygons.Polygons`.
    polygons: Polygons = field(default_factory=Polygons.empty)

    def __len__(self) -> int:
        return len(self.start)

    @property
    def length(self) -> np.ndarray:
        return np.linalg.norm(self.end - self.start, axis=1)

    def midpoints(self) -> np.ndarray:
        """(s, 3) the segments' midpoints (a new array)."""
        mid = np.add(self.start, self.end)
        mid *= 0.5  # the same bits as / 2.0 (a power of two), one array fewer
        return mid

    def ends(self) -> np.ndarray:
        """(2s, 3) float64: the starts, then the ends; the array ``start`` and ``end`` are the
        halves of when the turtle made them (no copy), else a new one."""
        n = len(self.start)
        start, end = self.start, self.end
        whole = start.base
        if (
            isinstance(whole, np.ndarray)
            and whole is end.base
            and whole.shape == (2 * n, 3)
            and whole.dtype == np.float64
            and whole.flags.c_contiguous
            and start.__array_interface__["data"][0] == whole.__array_interface__["data"][0]
            and end.__array_interface__["data"][0] == whole.__array_interface__["data"][0] + 24 * n
        ):
            return whole
        return np.concatenate([np.asarray(start, np.float64).reshape(-1, 3), np.asarray(end, np.float64).reshape(-1, 3)])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned ``(min xyz, max xyz)`` of segments (with radii), organs and polygons."""
        parts = [self.start, self.end]
        if len(self.organs):
            parts.append(self.organs.position)
        if len(self.polygons):
            parts.append(self.polygons.points)
        pts = np.concatenate(parts) if any(len(p) for p in parts) else np.zeros((1, 3))
        pad = float(max(self.base_radius.max(initial=0), self.organs.size.max(initial=0)))
        return pts.min(axis=0) - pad, pts.max(axis=0) + pad

    def select(self, leaf_ids: Iterable[int]) -> np.ndarray:
        """Boolean mask of the segments drawn by the given history leaves."""
        return np.isin(self.leaf_id, np.asarray(list(leaf_ids), np.int64))

    def to_polydata(self, sides: int = 8, organ_resolution: int = 8) -> pv.PolyData:
        """All tubes and organs as one :class:`pyvista.PolyData` (see :mod:`ramure.lsys.interpretation.geometry`)."""
        from .geometry import skeleton_to_polydata

        return skeleton_to_polydata(self, sides=sides, organ_resolution=organ_resolution)


@dataclass
class Trace:
    """What a skeleton keeps of its turtle run so an edit re-interprets only what it changed.

    ``leaves`` is the string interpreted (node ids); ``acts``, ``nps`` its
    action codes and has-parameters flags (the first parameters are not kept:
    an edit reads them again from the tree, a gather as fast as splicing a
    copy, and 8 bytes per module less); ``segment_at`` / ``organ_at`` the
    string position (int32) of each segment's ``F`` / each organ; ``balanced``
    whether every bracket is matched (else edits re-interpret the whole string;
    an edit finds the new string's bracket matches itself, so none are kept:
    4 bytes per module less).  The turtle state
    at any position is found again by walking from the root and jumping over
    the branches in between (:func:`ramure.lsys.interpretation._turtle_kernel.walk`, SEEK).
    """

    leaves: np.ndarray
    acts: np.ndarray
    nps: np.ndarray
    segment_at: np.ndarray
    organ_at: np.ndarray
    balanced: bool
    #: String position of each polygon's ``{`` (empty without polygons).
    polygon_at: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))

    def nbytes(self) -> int:
        arrays = (self.acts, self.nps, self.segment_at, self.organ_at, self.polygon_at)
        return sum(a.nbytes for a in arrays)


def _settings(lsys):
    g = lsys.grammar
    trop = np.asarray(g.tropism, float) if g.tropism is not None else np.zeros(0)
    return float(g.angle), float(g.step), trop


def action_table(lsys: LSystem) -> np.ndarray:
    """The :class:`TurtleAction` of every symbol of ``lsys`` (one more entry, 0, for padding)."""
    organs = set(lsys.grammar.organs)
    rich = symbol_codes(getattr(lsys.grammar, "dialect", "") == "cpfg")

    def action(s):
        if s in SYMBOL_ACTIONS:
            return SYMBOL_ACTIONS[s]
        if s in rich:
            return rich[s]
        if s in organs:
            return TurtleAction.ORGAN
        return TurtleAction.SURFACE if s.startswith(SURFACE_PREFIX) and len(s) > 1 else TurtleAction.NONE

    return np.array([action(s) for s in lsys.symbols] + [0], np.int8)


def module_arrays(lsys: LSystem, tree: DerivationTree, leaves: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per module of ``leaves``: action code, whether it has parameters, and its first parameter."""
    acts = action_table(lsys)[tree.symbol[leaves]]
    nps = tree.nparams[leaves] > 0  # a fixed dtype whatever the tree stores (one compiled kernel)
    par = tree.params[leaves, 0]
    return acts, nps, par


def node_ids(ids: ArrayLike) -> np.ndarray:
    """``ids`` as an integer array: a string of the tree (int32) or any int64 ids as they are (no
    copy of a 1.44 M-module string), anything else as int64."""
    ids = np.asarray(ids)
    return ids if ids.dtype in (np.int32, np.int64) else ids.astype(np.int64)


def interpret(derivation: Derivation) -> Skeleton:
    """Run the turtle over a derivation's current string and return its :class:`Skeleton`.

    A grammar with interpretation rules is drawn through them
    (:func:`ramure.lsys.interpretation.homomorphism.interpret_derivation`); leaf ids stay the derivation's.
    """
    if derivation.lsystem.grammar.interpretation:
        from .homomorphism import interpret_derivation

        return interpret_derivation(derivation, interpret_string)
    return interpret_string(derivation.lsystem, derivation.tree, derivation.tree.leaves)


#: Strings at least this long are walked by the compiled turtle (numba); shorter ones by the
#: same loop in plain Python (:mod:`._turtle_walk`: the same arrays), which spares a new
#: process loading numba and the compiled walk (about 0.2 s against 10 ms for Honda's
#: sympodial tree at n = 10, 11,253 modules).  Once numba is loaded, the compiled walk takes
#: strings from :data:`KERNEL_LOADED_MIN_MODULES` modules on.
KERNEL_MIN_MODULES = 100_000
KERNEL_LOADED_MIN_MODULES = 2_000
#: True / False force the compiled / plain walk (tests compare them); None chooses by length.
use_kernels: bool | None = None


def compiled_walk(length: int) -> bool:
    """Whether a string of ``length`` modules is walked by the compiled turtle."""
    if use_kernels is not None:
        return use_kernels
    return length >= KERNEL_MIN_MODULES or ("numba" in sys.modules and length >= KERNEL_LOADED_MIN_MODULES)


def _walker(length):
    """The ``walk`` function for a string of ``length`` modules (see :func:`compiled_walk`)."""
    if compiled_walk(length):
        from ._turtle_kernel import walk  # numba loads on first use only

        return walk
    from ._turtle_walk import walk

    return walk


def interpret_string(lsys: LSystem, tree: DerivationTree, leaves: ArrayLike) -> Skeleton:
    """The :class:`Skeleton` of the string ``leaves`` (node ids of ``tree``), with its :class:`Trace`."""
    from ._turtle_walk import FULL, initial_state

    leaves = node_ids(leaves)
    acts, nps, par = module_arrays(lsys, tree, leaves)
    angle, step, trop = _settings(lsys)
    state = initial_state(lsys.grammar.width)
    acts, rich = rich_modules(lsys, tree, leaves, acts)
    if rich is not None:  # modules of several parameters: the plain walk (see ramure.lsys.interpretation._turtle_rich)
        from ._turtle_walk import walk as plain

        _, segs, orgs, poly, err = plain(acts, nps, par, 0, len(acts), _NO_MATCH, FULL, state, angle, step, trop, 0, rich=rich)
        if rich.problem is not None:
            at, why = rich.problem
            raise DerivationError(f"{why}: not {lsys.module_text(tree, int(leaves[at]))}")
    else:
        walk = _walker(len(acts))
        _, segs, orgs, poly, err = walk(acts, nps, par, 0, len(acts), _NO_MATCH, FULL, state, angle, step, trop, 0)
    check_walk(lsys, tree, leaves, poly, err)
    trace = Trace(leaves, acts, nps, segs[0], orgs[0], _balanced(acts), poly[0])
    skeleton = _skeleton(lsys, tree, leaves, segs, orgs, trace)
    _check_color(lsys, tree, leaves[poly[0]], poly[2])  # before from_walk makes colours int32
    skeleton.polygons = _checked(lsys, tree, from_walk(leaves, poly))
    skeleton = _with_drawing(lsys, skeleton)
    if rich is not None and rich.blends:  # the materials InterpolateColors blended
        skeleton.extra["materials"] = {**skeleton.extra.get("materials", {}), **rich.blends}
    return skeleton


def rich_modules(lsys: LSystem, tree: DerivationTree, leaves: np.ndarray, acts: np.ndarray) -> tuple[np.ndarray, Rich | None]:
    """The actions to walk and, when the string has modules of several parameters (``@M``,
    ``LineTo``, ``SetGuide`` ...), their arguments (:class:`~ramure.lsys.interpretation._turtle_rich.Rich`);
    else ``acts`` unchanged and None (the fast walks)."""
    if not (acts >= RICH_FIRST).any():
        return acts, None
    match, _ = _bracket_pairs(acts)
    acts = recode(acts, match)
    where = np.flatnonzero(acts >= RICH_FIRST)
    nodes = leaves[where]
    arguments = getattr(lsys, "turtle_arguments", None)
    if arguments is not None:
        values = arguments(tree, nodes)
    else:
        counts = tree.nparams[nodes].tolist()
        rows = np.asarray(tree.params[nodes], float).tolist()
        values = [tuple(row[:k]) for row, k in zip(rows, counts)]
    cpfg = getattr(lsys.grammar, "dialect", "") == "cpfg"
    return acts, Rich(dict(zip(where.tolist(), values)), cpfg, getattr(lsys.grammar, "materials", None))


def _checked(lsys, tree, polygons):
    """Refuse polygons whose vertices overflowed (named by their ``{`` module)."""
    ok = _usable(polygons.points).all(1)
    if not ok.all():
        owner = np.repeat(np.arange(len(polygons)), polygons.sizes)
        _check_finite(lsys, tree, polygons.leaf_id[owner], ok)
    return polygons


def _with_drawing(lsys, skeleton):
    """Attach what the mesh needs from the grammar: surface templates and the material table."""
    kinds = {k for k in set(skeleton.organs.kind.tolist()) if k.startswith(SURFACE_PREFIX)}
    if kinds:
        from .surfaces import templates

        skeleton.extra["surfaces"] = templates(lsys.grammar, lsys.constants, sorted(kinds), lsys.file_polygons)
    if getattr(lsys.grammar, "materials", None):
        skeleton.extra["materials"] = dict(lsys.grammar.materials)
    return skeleton


_NO_MATCH = np.zeros(0, np.int32)  # the dtype of the trace's matches: one compiled walk


def _balanced(acts):
    """Whether every bracket of the string (its actions) is matched."""
    return bool(_bracket_pairs(acts)[1])


def bracket_pairs(symbols: np.ndarray, open_id: int, close_id: int) -> tuple[np.ndarray, bool]:
    """For each open bracket the position of its close and vice versa (-1 elsewhere), and whether
    all are balanced: one compiled pass (numba loads on the first call).  The engine uses it to
    match ``[`` and ``]`` in a string of module ids."""
    from ._turtle_kernel import bracket_pairs as compiled

    return compiled(symbols, open_id, close_id)


def _bracket_pairs(acts):
    """(match, balanced): bracket matches of the string (int32, -1 unmatched), compiled or numpy."""
    if compiled_walk(len(acts)):
        from ._turtle_kernel import bracket_pairs32
    else:
        from ._turtle_walk import bracket_pairs32
    return bracket_pairs32(acts, int(TurtleAction.PUSH), int(TurtleAction.POP))


def paired(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``start`` and ``end`` for ``n`` segments: the halves of one new (2n, 3) array (see
    :meth:`Skeleton.ends`)."""
    whole = np.empty((2 * n, 3))
    return whole[:n], whole[n:]


def _skeleton(lsys, tree, leaves, segs, orgs, trace):
    seg_at, walked_start, walked_end, width, order, color, normal, parent = segs
    start, end = paired(len(walked_start))
    start[:], end[:] = walked_start, walked_end
    base = width * (lsys.grammar.width_scale / 2.0)
    leaf = leaves[seg_at].astype(np.int64)  # the string is int32; the ids a skeleton hands out int64
    _check_finite(lsys, tree, leaf, _usable(start).all(1) & _usable(end).all(1) & _usable(base))
    _check_color(lsys, tree, leaf, color)
    organs = _organs(lsys, tree, leaves, orgs)
    return Skeleton(
        start,
        end,
        base,
        top_radius(base, order, parent),
        order.astype(np.int32),
        leaf,
        color.astype(np.int32),
        normal,
        parent,
        organs,
        {"trace": trace},
    )


def top_radius(base: np.ndarray, order: np.ndarray, parent: np.ndarray) -> np.ndarray:
    """Each segment's top radius: its continuation's base radius, else its widest fork's, else its own."""
    kids = np.flatnonzero(parent >= 0)
    return _tops(base.copy(), base, order, parent, kids, parent[kids])


def _tops(top, base, order, parent, kids, at):
    """:func:`top_radius` of some segments, written over ``top`` (their own base radii): ``kids``
    are all their child segments, ``kids[j]`` a child of the segment at ``top[at[j]]``."""
    # Without a continuation, taper to the widest child segment (a fork), if any.
    widest = np.full(len(top), -1.0)
    np.maximum.at(widest, at, base[kids])
    fork = widest >= 0
    top[fork] = widest[fork]
    # A segment's continuation: the first child segment on the same branch order.
    cont = order[kids] == order[parent[kids]]
    first = np.full(len(top), len(base), np.int64)
    np.minimum.at(first, at[cont], kids[cont])  # the earliest continuing child wins
    has = first < len(base)
    top[has] = base[first[has]]
    return top


#: Turtle coordinates and radii beyond this magnitude are refused: the lengths, volumes and
#: moments computed from them (metrics, bounds) would overflow floating point.
MAX_COORDINATE = 1e30


def _usable(values):
    """Finite and within ±:data:`MAX_COORDINATE`."""
    return np.isfinite(values) & (np.abs(values) <= MAX_COORDINATE)


def _check_finite(lsys, tree, leaf, ok):
    """Refuse a plant whose turtle overflowed (e.g. F(1e308)F(1e308) or F+f(1e308)F): checked on the
    turtle's output arrays, the first bad point names the module that drew it."""
    if ok.all():
        return
    module = lsys.module_text(tree, int(leaf[int(np.argmin(ok))]))
    raise DerivationError(
        f"the turtle geometry is not finite at module {module} (or beyond ±{MAX_COORDINATE:g}: "
        "a length, width or move too large to measure): use smaller values"
    )


def _check_color(lsys, tree, leaf, color):
    """Colour indices are stored as int32: refuse ``'(c)`` with |c| >= 2^31 instead of wrapping it."""
    bad = np.flatnonzero((color >= 2**31) | (color <= -(2**31)))  # abs() would wrap INT64_MIN
    if bad.size:
        module = lsys.module_text(tree, int(leaf[bad[0]]))
        raise DerivationError(
            f"the colour index of the segment drawn by {module} is {int(color[bad[0]])}, "
            "out of range: a colour index is a whole number below 2^31 in size"
        )


def _organs(lsys, tree, leaves, orgs):
    org_at, position, frame, size, color = orgs
    leaf_id = leaves[org_at].astype(np.int64)
    kind = np.array(lsys.symbols, dtype=object)[tree.symbol[leaf_id]] if len(leaf_id) else np.array([], dtype=object)
    _check_finite(lsys, tree, leaf_id, _usable(position).all(1) & _usable(size))
    _check_color(lsys, tree, leaf_id, color)
    return Organs(kind, position, frame, size, tree.params[leaf_id], leaf_id, color.astype(np.int32))


# -- edits: re-interpret only what changed -------------------------------------------
def changed_spans(old: ArrayLike, new: ArrayLike, size: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Spans of ``old`` replaced in ``new`` (two node-id strings of one tree with ``size`` nodes).

    Modules present in both strings are kept; the runs of the others pair up
    by the number of kept modules before them.  Returns ``(old_spans,
    new_spans)`` as (k, 2) arrays of inclusive ``[first, last]`` (``last =
    first - 1`` for an empty span), or None when the kept modules are not in
    the same order in both strings.
    """
    old, new = node_ids(old), node_ids(new)
    if compiled_walk(max(len(old), len(new))):
        from ._turtle_kernel import kept_modules
    else:
        from ._turtle_walk import kept_modules
    keep_old, keep_new, same_order = kept_modules(old, new, int(size))
    if not same_order:
        return None
    spans_old, spans_new = _gaps(keep_old), _gaps(keep_new)
    keys = np.union1d(spans_old[2], spans_new[2])
    return _paired(spans_old, keep_old, keys), _paired(spans_new, keep_new, keys)


def _gaps(keep):
    """Runs of False in ``keep``: (starts, ends, kept count before each run, total length of
    the runs before each run and of all of them); no array as long as the string but the mask's
    edges (the kept counts come from the few runs, not a cumulative sum of the string)."""
    edges = np.flatnonzero(np.diff(np.r_[False, ~keep, False].view(np.int8)))
    starts, ends = edges[0::2], edges[1::2] - 1
    gone_before = np.zeros(len(starts) + 1, np.int64)
    np.cumsum(ends - starts + 1, out=gone_before[1:])
    return starts, ends, starts - gone_before[:-1], gone_before


def _paired(gaps, keep, keys):
    """One span per key (kept count before it); an empty span where this string has none."""
    starts, ends, counts, gone_before = gaps
    where = np.searchsorted(counts, keys)
    has = (
        (where < len(counts)) & (counts[np.minimum(where, max(len(counts) - 1, 0))] == keys)
        if len(counts)
        else np.zeros(len(keys), bool)
    )
    # just after the keys-th kept module: keys - 1 kept and the runs that come before it
    first = np.where(keys > 0, keys + gone_before[np.searchsorted(counts, keys, side="left")], 0)
    out = np.stack([first, first - 1], axis=1)
    out[has] = np.stack([starts[where[has]], ends[where[has]]], axis=1)
    return out


def reinterpret(
    lsys: LSystem, tree: DerivationTree, skeleton: Skeleton, leaves: np.ndarray, old_spans: np.ndarray, new_spans: np.ndarray
) -> Skeleton:
    """The :class:`Skeleton` of ``leaves`` after an edit, re-interpreting only what changed.

    ``skeleton`` is the old string's (it carries its :class:`Trace`); the edit
    replaced each ``old_spans`` row (inclusive positions in that string) by
    the matching ``new_spans`` row of ``leaves``.  A change moves what follows
    it up to the end of its branch, so each changed span is re-interpreted from
    its first module to the ``]`` that closes the branch it is in (a region);
    the turtle state at a region's start is found by walking from the root
    and jumping over the branches in between.  The rest keeps its arrays.

    The result's ``extra["reuse"]`` is ``(new, old)``: segments whose tube is
    unchanged (same geometry, same radii), for :func:`ramure.lsys.interpretation.geometry.patch_polydata`;
    ``extra["reuse_of"]`` is ``id(skeleton)``, the skeleton ``old`` indexes (a holder of it can
    tell that it is the one).
    Falls back to a full interpretation (no ``reuse``) when the strings do not
    allow it (unbalanced brackets, no trace).
    """
    from ._turtle_walk import REGION, SEEK, initial_state

    trace = skeleton.extra.get("trace")
    leaves = node_ids(leaves)
    old_spans = np.asarray(old_spans, np.int64).reshape(-1, 2)
    new_spans = np.asarray(new_spans, np.int64).reshape(-1, 2)
    if trace is None or not trace.balanced or not len(old_spans) or (trace.acts >= RICH_FIRST).any():
        return interpret_string(lsys, tree, leaves)
    order = np.argsort(old_spans[:, 0], kind="stable")
    old_spans, new_spans = old_spans[order], new_spans[order]
    pieces = [module_arrays(lsys, tree, leaves[a : b + 1]) for a, b in new_spans]
    acts, nps = (_splice(old, old_spans, [p[k] for p in pieces]) for k, old in enumerate((trace.acts, trace.nps)))
    par = tree.params[:, 0]  # read through the string's node ids (not kept in the trace, not gathered)
    match, balanced = _bracket_pairs(acts)
    if len(acts) != len(leaves) or not balanced:
        return interpret_string(lsys, tree, leaves)
    # whether the string has polygon actions: an edit of a string without any only looks at its new pieces
    drawn = any(_has_polygons(p[0]) for p in pieces) if skeleton.extra.get("polygon_acts") is False else _has_polygons(acts)
    if (len(trace.polygon_at) or drawn) and not _polygons_allow(trace.acts, acts, old_spans, new_spans):
        return interpret_string(lsys, tree, leaves)  # a polygon crosses a branch or an edit: drawn whole
    angle, step, trop = _settings(lsys)
    start_state = initial_state(lsys.grammar.width)
    walk = _walker(len(acts))
    delta = np.cumsum((new_spans[:, 1] - new_spans[:, 0]) - (old_spans[:, 1] - old_spans[:, 0]))
    regions: list[list] = []  # (old start, old stop, segment arrays, organ arrays)
    for i, (a, b) in enumerate(new_spans):
        if regions and a < regions[-1][4]:
            if b >= regions[-1][4]:
                return interpret_string(lsys, tree, leaves)
            regions[-1][1] = regions[-1][4] - delta[i]  # merged: the old stop shifts by this span too
            continue
        state = start_state.copy()
        walk(acts, nps, par, 0, a, match, SEEK, state, angle, step, trop, 0, leaves)
        stop, segs, orgs, poly, err = walk(acts, nps, par, a, len(acts), match, REGION, state, angle, step, trop, 0, leaves)
        if stop <= b:
            return interpret_string(lsys, tree, leaves)
        check_walk(lsys, tree, leaves, poly, err)
        regions.append([old_spans[i, 0], stop - delta[i], segs, orgs, stop, poly])
    out = _patched(lsys, tree, skeleton, trace, leaves, (acts, nps), regions, old_spans, delta)
    out.extra["polygon_acts"] = drawn
    return out


def _has_polygons(acts):
    return bool(((acts >= TurtleAction.POLY_START) & (acts <= TurtleAction.POLY_VERTEX)).any())


def _polygons_allow(old_acts, new_acts, old_spans, new_spans) -> bool:
    """Whether an edit may re-interpret only its regions although the strings have polygons: every
    polygon stays inside the branch that opened it (in both strings), and no edited span starts or
    ends inside an open polygon, so each region holds whole polygons."""
    from .polygons import polygon_depths

    codes = (int(TurtleAction.PUSH), int(TurtleAction.POP), int(TurtleAction.POLY_START), int(TurtleAction.POLY_END))
    for acts, spans in ((old_acts, old_spans), (new_acts, new_spans)):
        local, depth = polygon_depths(acts, *codes, np.sort(np.concatenate([spans[:, 0], spans[:, 1] + 1])))
        if not local or depth.any():
            return False
    return True


def _splice(old, spans, parts):
    out, cursor = [], 0
    for (a, b), part in zip(spans, parts):
        out += [old[cursor:a], part]
        cursor = b + 1
    out.append(old[cursor:])
    return np.concatenate(out)


def _shift(positions, old_spans, delta):
    """New string positions of kept old positions (each span before them changed the length)."""
    k = np.searchsorted(old_spans[:, 1], positions, side="left")
    return positions + np.r_[0, delta][k]


def _pieces(at, regions, slot):
    """Kept old rows (index ranges) between the regions, and each region's new arrays (``slot``)."""
    kept, new, cursor = [], [], 0
    for r in regions:
        lo, hi = np.searchsorted(at, np.array([r[0], r[1]], at.dtype))  # at's dtype: no int64 copy of it
        kept.append(np.arange(cursor, lo))
        new.append(r[slot])
        cursor = hi
    kept.append(np.arange(cursor, len(at)))
    return kept, new


def _interleave(old, kept, new, out=None):
    """Kept old rows and new rows in turn (string order), written into ``out`` if given."""
    parts = []
    for i, idx in enumerate(kept):
        parts.append(old[idx[0] : idx[-1] + 1] if len(idx) else old[:0])  # a range: a slice, no gather
        if i < len(new):
            parts.append(new[i])
    return np.concatenate(parts, out=out)


def _interleave_shifted(old, kept, new, old_spans, delta):
    """``_interleave(_shift(old, old_spans, delta), kept, new)``: the kept rows between two regions
    all move by the same amount, so each kept run is shifted by one constant (no search per row)."""
    out = []
    for i, idx in enumerate(kept):
        run = old[idx[0] : idx[-1] + 1] if len(idx) else old[:0]
        out.append(run.astype(np.int64) + (_shift(run[:1], old_spans, delta) - run[:1]).sum())
        if i < len(new):
            out.append(new[i])
    return np.concatenate(out)


def _patched(lsys, tree, skeleton, trace, leaves, arrays, regions, old_spans, delta):
    sk, scale = skeleton, lsys.grammar.width_scale / 2.0
    kept, new = _pieces(trace.segment_at, regions, 2)

    def field(old, k, convert=None, out=None):
        return _interleave(old, kept, [p[k] if convert is None else convert(p[k]) for p in new], out)

    seg_at = _interleave_shifted(trace.segment_at, kept, [p[0] for p in new], old_spans, delta)
    start, end = paired(len(seg_at))
    field(sk.start, 1, out=start)
    field(sk.end, 2, out=end)
    order, color, normal = (field(old, k) for old, k in ((sk.order, 4), (sk.color, 5), (sk.normal, 6)))
    base = field(sk.base_radius, 3, lambda w: w * scale)
    is_kept = field(np.ones(len(sk), bool), 0, lambda a: np.zeros(len(a), bool))
    old_index = np.concatenate(kept)
    new_index = np.full(len(sk) + 1, -1, np.int64)  # the extra -1 maps parent -1 to -1
    new_index[old_index] = np.flatnonzero(is_kept)
    parent = field(new_index[sk.parent], 7)
    coded = parent <= -2  # a parent given by its string position (see _turtle_kernel.walk)
    parent[coded] = np.searchsorted(seg_at, -2 - parent[coded])
    leaf = field(sk.leaf_id, 0, lambda a: leaves[a].astype(np.int64))  # a kept segment's module is the same node
    drawn = [np.concatenate([p[k] for p in new]) if new else old[:0] for k, old in enumerate((seg_at, start, end, base))]
    fresh_leaf = leaves[drawn[0]]
    _check_finite(lsys, tree, fresh_leaf, _usable(drawn[1]).all(1) & _usable(drawn[2]).all(1) & _usable(drawn[3] * scale))
    _check_color(lsys, tree, fresh_leaf, np.concatenate([p[5] for p in new]) if new else color[:0])
    top = _patched_top(sk, base, order, parent, is_kept, old_index, new_index)
    same = is_kept.copy()
    same[is_kept] = top[is_kept] == sk.top_radius[old_index]
    okept, onew = _pieces(trace.organ_at, regions, 3)
    org = sk.organs
    org_at = _interleave(_shift(trace.organ_at, old_spans, delta), okept, [p[0] for p in onew])
    old_color = org.color if org.color is not None else np.zeros(len(org), np.int64)
    position, frame, size, ocolor = (
        _interleave(old, okept, [p[k] for p in onew])
        for k, old in ((1, org.position), (2, org.frame), (3, org.size), (4, old_color))
    )
    organs = _organs(lsys, tree, leaves, (org_at, position, frame, size, ocolor))
    polygon_at, polygons = _spliced_polygons(lsys, tree, skeleton, trace, leaves, regions, old_spans, delta)
    acts, nps = arrays
    new_trace = Trace(leaves, acts, nps, seg_at.astype(np.int32), org_at.astype(np.int32), True, polygon_at)
    reuse = (np.flatnonzero(same), old_index[same[is_kept]])
    return _with_drawing(
        lsys,
        Skeleton(
            start,
            end,
            base,
            top,
            order.astype(np.int32),
            leaf,
            color.astype(np.int32),
            normal,
            parent,
            organs,
            {"trace": new_trace, "reuse": reuse, "reuse_of": id(skeleton)},
            polygons,
        ),
    )


def _patched_top(old, base, order, parent, is_kept, old_index, new_index):
    """:func:`top_radius` after an edit from the old skeleton's: computed again only for the new
    segments and the kept ones that gained or lost a child (the others keep theirs)."""
    top = np.empty(len(base), base.dtype)
    top[is_kept] = old.top_radius[old_index]
    gone = np.ones(len(old), bool)
    gone[old_index] = False
    fresh = np.flatnonzero(~is_kept)
    targets = np.unique(np.concatenate([fresh, parent[fresh], new_index[old.parent[gone]]]))
    targets = targets[targets >= 0]
    mark = np.zeros(len(base), bool)
    mark[targets] = True
    kids = np.flatnonzero((parent >= 0) & mark[np.maximum(parent, 0)])
    top[targets] = _tops(base[targets], base, order, parent, kids, np.searchsorted(targets, parent[kids]))
    return top


def _spliced_polygons(lsys, tree, skeleton, trace, leaves, regions, old_spans, delta):
    """The polygons after an edit: the old ones outside the regions, each region's new ones."""
    from .polygons import concatenate, take

    kept, new = _pieces(trace.polygon_at, regions, 5)
    if not len(trace.polygon_at) and not any(len(p[0]) for p in new):
        return np.zeros(0, np.int32), Polygons.empty()
    shifted = _shift(trace.polygon_at, old_spans, delta)
    parts, where = [], []
    for i, idx in enumerate(kept):
        parts.append(take(skeleton.polygons, idx))
        where.append(shifted[idx])
        if i < len(new):
            _check_color(lsys, tree, leaves[new[i][0]], new[i][2])
            parts.append(_checked(lsys, tree, from_walk(leaves, new[i])))
            where.append(new[i][0])
    return np.concatenate(where).astype(np.int32), concatenate(parts)


def undrawn_symbols(grammar: Grammar) -> list[str]:
    """Module symbols a grammar writes that nothing draws: no turtle meaning (``F``, ``+``, an
    organ, a surface ``~name`` ...), no rule of any section rewrites or interprets them, and no
    ``#amap`` annotation names them.
    ``ramure check`` notes them (a misspelt or foreign turtle command is silently skipped).

    >>> from ramure.lsys.language.grammar import parse_grammar
    >>> undrawn_symbols(parse_grammar("n: 1\\nw: A\\np:\\n A -> F[+A]Q@X(2)@c(2)Leaf"))
    ['@', 'Q', 'X']
    """
    rules = [*grammar.rules, *grammar.decomposition, *grammar.interpretation]
    written = {m.symbol for m in grammar.axiom} | {m.symbol for r in rules for m in r.successor}
    rewritten = {p.symbol for r in rules for p in r.strict}  # cpfg: a predecessor of several modules
    special = {"%", "*", "?E", *QUERIES}  # the branch cut, ABOP's any-context, the query modules
    marks = {entry[1] for entry in grammar.amap}  # '#amap' markers mean architecture, not drawing
    return sorted(
        s
        for s in written - rewritten - special - marks - set(grammar.organs)
        if s not in SYMBOL_ACTIONS and s not in SYMBOL_CODES and s not in CPFG_CODES and not s.startswith(SURFACE_PREFIX)
    )


#: cpfg commands read but not drawn (``ramure check`` notes them with the others nothing draws):
#: symbol -> what it would have done.
NOT_DRAWN = {"@Tx": "a texture (Ramure draws colours and materials, not textures)"}

#: Query modules (cpfg, L-Py): symbol -> the columns of :func:`turtle_states` they receive.
QUERIES = {"?P": slice(0, 3), "?H": slice(3, 6), "?L": slice(6, 9), "?U": slice(9, 12)}


def turtle_states(lsys: LSystem, tree: DerivationTree, leaves: ArrayLike, positions: ArrayLike) -> np.ndarray:
    """(q, 12) the turtle's position, H, L and U just before each of ``positions`` of the string
    ``leaves`` (node ids of ``tree``), walked as :func:`interpret_string` walks it (interpretation
    rules are not applied)."""
    from ._turtle_walk import SEEK, initial_state

    leaves = node_ids(leaves)
    acts, nps, par = module_arrays(lsys, tree, leaves)
    match, _ = _bracket_pairs(acts)
    angle, step, trop = _settings(lsys)
    walk = _walker(len(acts))
    acts, rich = rich_modules(lsys, tree, leaves, acts)
    positions = np.asarray(positions, np.int64)
    out = np.zeros((len(positions), 12))
    for k, a in enumerate(positions.tolist()):
        state = initial_state(lsys.grammar.width)
        if rich is not None:
            from ._turtle_walk import walk as plain

            rich.gc = rich.guide = rich.contour = None
            rich.stack = []
            plain(acts, nps, par, 0, a, match, SEEK, state, angle, step, trop, 0, rich=rich)
        else:
            walk(acts, nps, par, 0, a, match, SEEK, state, angle, step, trop, 0)
        out[k] = state[:12]
    return out


def _answer_environment(lsys, tree, string, symbol, first_new) -> None:
    """Answer the ``?E`` modules with the grammar's built-in environment
    (:mod:`ramure.lsys.interpretation.environment`): every ``?E`` of the string is a query, the
    ones the last step wrote get the answer in their first parameter (as ``?P``)."""
    from .environment import honda81

    settings = getattr(lsys.grammar, "environment", {}) or {}
    where = np.flatnonzero((tree.symbol[string] == symbol) & (tree.nparams[string] > 0))
    if settings.get("program") != "honda81" or not where.size:
        return
    nodes = string[where]
    states = turtle_states(lsys, tree, string, where)
    params = np.asarray(tree.params[nodes], float)
    index = np.where(tree.nparams[nodes] > 1, params[:, 1] if params.shape[1] > 1 else 0.0, 0.0)
    answers = honda81(states[:, 0:3], params[:, 0], index, float(settings["radius"]), bool(settings["3d"]))
    new = nodes >= first_new
    if new.any():
        start = int(nodes[new].min())
        block = np.asarray(tree.params[start:], float).copy()  # written back whole, as answer_queries does
        block[nodes[new] - start, 0] = answers[new]
        tree.params[start:] = block


def answer_queries(lsys: LSystem, tree: DerivationTree, string: np.ndarray, first_new: int = 0) -> None:
    """Set the parameters of the query modules ``?P ?H ?L ?U`` of ``string`` written by the last
    step (node ids from ``first_new``) to the turtle's position, heading, left and up vectors
    where they stand, as cpfg and L-Py do after each step; a module keeps as many parameters as
    it was written with (at most 3).  A query module no rule rewrites keeps the values of the
    step that wrote it (the history tree keeps each node's parameters): rewrite it by itself
    (``?P(x,y,z) --> ?P(x,y,z)``) to have it refreshed every step."""
    ids = {s: i for i, s in enumerate(lsys.symbols)}
    if "?E" in ids:
        _answer_environment(lsys, tree, string, ids["?E"], first_new)
    wanted = {ids[s]: cols for s, cols in QUERIES.items() if s in ids}
    if not wanted:
        return
    symbols = tree.symbol[string]
    where = np.flatnonzero(np.isin(symbols, list(wanted)) & (string >= first_new))
    if not where.size:
        return
    states = turtle_states(lsys, tree, string, where)
    start = int(string[where].min())
    block = np.asarray(tree.params[start:], float).copy()
    for k, position in enumerate(where.tolist()):
        node = int(string[position])
        count = min(3, int(tree.nparams[node]))
        block[node - start, :count] = states[k, wanted[int(symbols[position])]][:count]
    tree.params[start:] = block
