"""Volumetric wood on the 3-G-map: pith, growth rings, bark, sapwood, heartwood and knots.

After Guimberteau (2008), chapters 2-3, with the decisions of
``shared/spec/wood-3gmap.md``.  Each axis (the trunk, and every branch) is a
chain of pith prisms, one *level* per year of length growth, with a radial
*stack* of cubes on each side face.  One step is a half-year (spring, then
summer; spec decision 1); every stack gets one wood cell per step -- earlywood
in spring, latewood in summer -- and one bark cell per spring, so a stack that
has lived ``q`` half-years holds ``q`` wood cells and ``ceil(q/2)`` bark cells.
New cells are added on the free outer face of each stack (the thesis's
"add a volume on a face") and identified with their neighbours around the
axis (C2 | C4) and along it (C1 | C3) through the edge they share.

*Levels are glued by year (issue 39 (a)).*  Level ``t`` is a year younger
than level ``t - 1`` (or of the same year, a node's internode), so its
stacks hold 2 wood cells and a bark cell fewer.  Its cell ``i`` meets cell
``i + s`` below (``s`` the age difference in half-years,
:meth:`Wood.year_shift`): the cell laid in the same half-year, so a ring
runs on across the boundary and a board shows no step there.  The older
level's cells ``1..s`` (the year before level ``t`` existed) end on level
``t``'s first cell, whose bottom face is cut in ``s + 1`` pieces
(:meth:`Wood._bridge`): the apex of their growth cone, drawn in to the pith
(:meth:`Wood._tapers`), as a real year's cone closes at the top of its
shoot.  A node carrying knots is glued so too, its slot's bottom wall
meeting each knot ring by year (:meth:`Wood._sew_knots`).  So is every
branch: its knot (level 0) is its first year, the stub's level ``t`` its
year ``t + 1``, so the knot's first ring closes its cone at the knot's end
and a branch's rings run on past each of its level boundaries (issue 39), a
branch carrying sub-branches included.

*Cambium (a choice; the thesis has no bark).*  Cells are added outside, but
the cambium lies under the bark: after each step the roles are re-read from
the inside of each stack -- the ``q`` inner cells are wood, the outer ones
bark, the newest bark innermost -- so a cell made as bark becomes wood when
the cambium passes it.  A cell keeps its topology; its role, width and
colour follow its position.  Hence bark is always the outer layer (spec
decision 7: one bark layer per year with its own thickness law), sapwood is
the outer ``sapwood_rings`` rings, heartwood the rings inside once the tree is
older than ``heartwood_age`` years (younger trees are all sapwood inside).
The outer bark is shed beyond the species' live thickness, deeper in its
fissures, and branch wood carries compression or tension wood on its lower or
upper side: :mod:`ramure.gmap.organs.wood_species` (species table, sources).

*Widths.*  A wood cell's radial width is drawn in its law's bounds,
``[lo, hi] x f(c) x reaction(phi)``: ``lo, hi`` per season, ``f(c) =
max(floor, exp(-(c - 1) / decay))`` of the cambial ring number ``c`` (ring
count from the pith; juvenile rings are wider) and ``reaction(phi) = 1 + r
max(0, cos(phi - phi_r))``, thicker rings on one side (reaction wood).  The
draw mixes a per-year value (a good year is wide all round) with a per-cell
value, both seeded from the axis's seed and the cell's address, never from
volume ids, so regrowing one branch with a new seed changes only its cells.

*Embedding.*  Default corners are analytic: level frames along each axis,
corner angles ``2 pi (k - 1/2) / n``, radial boundaries at the cumulative
widths (apothems).  The kernel's :meth:`GMap3.embed` then averages the
corners of the volumes around each vertex (spec decision 3); where that
average would fold a trunk ring cell (a shed bark sliver by a whorl's knots),
its vertices are pulled in across the axis (:meth:`Wood._keep_rings_apart`).
Default corners depend only on attributes, so embedding every step or once
gives the same positions.

*Knots.*  A year with new branches grows a short *node* level (1.6 times
the branch's final base radius) under its internode.  A branch born in year
``j`` starts on the node's pith face in sector ``k`` (the trunk grows no stack
there, as in Table 3.4 ``A -> A[F]_E [B]_Ci [R1]_C*-i``): the branch's first
pith prism is sewn onto that face, then grows along the branch direction
with its own stacks; its first level spans the trunk's radius (the knot), so
the branch base has ``Y - j`` years of rings around its pith.

*The knot is sewn into its slot (a choice; the thesis only says "special
gluing between the branch cubes and the trunk cubes").*  The missing stack
leaves a tunnel whose layer ``i`` is walled by four trunk faces (C2 of the
stack at ``k - 1``, C4 at ``k + 1``, C3 below, C1 above, cell ``i`` of each).
Branches have as many sides as the trunk (``branch_sides = 16``, any
multiple of 4): a quarter of them faces each wall.  The trunk's pith face
under the knot has its edges cut in ``q = branch_sides / 4`` pieces when the
branch is sewn on; at each layer every wall face is cut in ``q`` quads
(its outer edge in ``q`` pieces, then ``q - 1`` chords,
:meth:`Wood._split_walls`), and the next cell of a wall's stack gets the
same pieces on its O face (:meth:`Wood._match_supports`).  The knot's ring
cell ``i`` is born in the same step as the walls' cell ``i``, so after
every layer the kernel's :meth:`GMap3.identify` sews each knot cell's C1
face to its piece of the wall of its layer through the edge they share
(the pith face edge for ``i = 1``, the previous layer's seam after): no
filler cell is needed, and the knot's rings continue the trunk's (one
cambium; the bark of the knot meets the trunk's bark).
The solid stays one ball (valid, chi = 1, boundary chi = 2 after every
step).  Geometrically ring ``i`` of the knot starts on layer ``i`` of the
slot: nested cups, a cone of the branch's rings opening from the pith
(:meth:`Wood._seat_knot`), round in every cut.  Knot volumes are
``exclusive`` (the thesis's ``seulPourPl``), so the seam vertices take the
knot's corners and the trunk's rings bend around the knot by a displacement
field from the seam (:meth:`Wood._push`): the trunk makes room for the
square round the knot's section, and the ring cells on the seam curve in
along its round edge, so a tangential cut shows the trunk's rings flowing
round a round knot.  The push moves a ring's corners round and along the
trunk, not out of their ring (:meth:`Wood._keep_apothem`), so the stem stays
round and tapering past a whorl (issue 39: it swelled into a bottle).  The knot's pith is an arc (:meth:`Wood.knot_bender`):
the branch leaves the trunk's pith ``KNOT_BEND`` degrees steeper than it
leaves the bark, as a conifer's branch bends in its knot.  The seam uses the law's mean
widths, so regrowing a branch with a new seed moves only that branch.  On a knot's section the
trunk's rings sag into the trunk above a rising knot (the inner rings' deflection); the outer
rings and the bark meet the knot's upper side at their own apothem instead, and the knot's end
goes out with them (:meth:`Wood._level_seam`), so no trunk bark lies inside the wood.

*Live and dead knots (a choice; the thesis has none).*  A branch dies in a
year set per branch (``Branch.death``, ``grow_wood(branch_deaths=...)``) or
by the rule ``branch_life`` (it dies that many years after its birth; the
lower branches, born first, die first).  From then on its knot stops
growing with the trunk: the branch grows no more length, its cambium stops,
and the cells its levels held at death keep the roles they had -- knot wood
inside, the branch's own bark outside (volume attribute ``dead``).  Its
stacks go on receiving one cell a half-year, sewn to the slot walls as
before: these are the trunk's later rings (trunk wood of the trunk's years,
the same year as the wall cell they meet), which encase the dead knot.  So
a dead knot meets the later wood only through a layer of bark tissue: the
boundary is sewn through bark along the stub (never knot wood to later trunk wood, a test
checks it), the solid stays one ball, and a cut shows a dark ring round a
dead knot where a live knot's rings run into the trunk's.  That bark is kept
whole, as dark as the species' bark fissures (:meth:`_kill_branches`), and the later rings
round it are trunk wood, with no reaction wood.  Inside the radius the trunk had at the death
the dead knot is intergrown, as the wood grew round a live branch (a sound knot near the
pith, a loose one outside it).  The knot's
volume stops growing from its death step on.  *Occlusion*: at death a cap level
is grown on the stub's end (:meth:`Wood._cap_stub`): a disc of cells of
the death year covers the end face, and the cap's stacks grow with the
others, so the later rings run up the stub and turn over its end on nested
cones (:meth:`Wood._cap_corners`): the dead knot is buried, no face of it
on the boundary, its length what it was at death.  Over the end face the
later wood meets the knot's wood (a stub's end has no bark); along it, the
bark lining.  What is not modelled: the stub breaking off.

*Branches on branches (a choice; the thesis only tried them, without
collision handling).*  A branch may grow on a branch (``Branch.parent``):
in the year it is born its host grows a short node (at most half a year's
``branch_length``) under the rest of that year's length, and the sub-branch
starts on the node's pith face, its knot sewn into the slot's walls exactly
as a first-order knot into the trunk's, its rings bending the host's
(:meth:`Wood._push` on the host's axis).  So the host must be growing in
length that year: a branch is a stub of ``branch_levels`` years (0: no
limit), and a sub-branch born after its host's stub stopped, or after its
host died, is refused (:func:`check_hosts`; :func:`from_skeleton` leaves it
out and counts it).  Any order: a sub-branch can host sub-branches.

>>> w = grow_wood("pine", years=2, branches=0)
>>> w.gm.n_darts == trunk_darts(16, 2), w.gm.euler_characteristic()
(True, 1)
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.lsystem.engine import mix
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.kernel.measure import faces_up
from ramure.gmap.organs import wood_species as _species

if TYPE_CHECKING:
    import pyvista as pv

    from ramure.lsys.interpretation.turtle import Skeleton

#: Wood tissues (volume attribute ``wood``).
TISSUES = ("pith", "heartwood", "sapwood", "bark", "knot")
CODES = {name: i for i, name in enumerate(TISSUES)}
EARLY, LATE = 0, 1

#: Dart offsets of a fresh cube's side faces (forward dart at corner 0), see :mod:`ramure.gmap.kernel.prism`.
_C1, _C2, _C3, _C4 = 16, 24, 32, 40

#: Fewest trunk faces between two branches of one year that :func:`from_skeleton` keeps (closer
#: knots of one node crowd the ring cells between them).
MIN_SECTOR_GAP = 3

#: Most darts a wood may have (about 450 bytes each).
MAX_DARTS = 8_000_000

#: Species presets (pine, larch, elm, oak), their sources and their bark, reaction wood and
#: texture: :mod:`ramure.gmap.organs.wood_species`.
SPECIES = _species.SPECIES

#: Parameters a user may set (``--set name=value``) with their meaning.
PARAMETERS = {
    "sides": "faces of the trunk's pith prisms (>= 3)",
    "branch_sides": "faces of a branch's pith prisms (a multiple of 4: a quarter meets each slot wall)",
    "branch_levels": "most yearly levels of a branch, its knot included (0: no limit; 2: the knot and a stub)",
    "pith_radius": "apothem of the pith (m)",
    "height": "length growth of the trunk per year (m)",
    "early_min": "earlywood width bounds at the pith (m)",
    "early_max": "",
    "late_min": "latewood width bounds at the pith (m)",
    "late_max": "",
    "decay": "rings for the width law to fall by e (juvenile wood is wider)",
    "width_floor": "lowest factor of the width law",
    "bark_min": "bark layer thickness bounds (m)",
    "bark_max": "",
    "sapwood_rings": "rings of sapwood under the bark",
    "heartwood_age": "age (years) after which inner rings are heartwood",
    "branches": "number of branches (knots)",
    "branch_start": "first year a branch may be born",
    "branch_angle": "branch insertion angle from the trunk axis (degrees)",
    "branch_length": "branch length growth per year (m)",
    "branch_scale": "branch ring widths / trunk ring widths",
    "reaction": "extra ring width on the reaction side (0 = none, 0.5 = +50 %)",
    "reaction_angle": "direction of the reaction side (degrees about the axis)",
    "height_jitter": "relative random variation of the yearly height growth",
    "branch_life": "years a branch lives before it dies and its knot is encased (0: never dies)",
    **_species.PARAMETERS,
}

#: Lengths (m) among the parameters, and the largest accepted: growth of a kilometre a year or
#: a ring a kilometre wide is a typo, and 1e308 would make coordinates that are not finite.
LENGTHS = (
    "pith_radius",
    "height",
    "early_min",
    "early_max",
    "late_min",
    "late_max",
    "bark_min",
    "bark_max",
    "bark_cap",
    "branch_length",
)
MAX_LENGTH = 1000.0
#: Most faces of the trunk's pith prisms (a round trunk needs tens, not thousands).
MAX_SIDES = 1024


#: Darts a level glued by year adds per sector: its first cells' bottom faces cut in three
#: (two edge cuts, 8 darts each, shared by two sectors; two chords of 4 darts), :meth:`Wood._bridge`.
BRIDGE_DARTS = 24
#: Darts per quarter of a knot's sides its node's gluing by year adds (its first ring's bottoms
#: facing the older level cut in three, the slot's corners), less 32: 48 q - 32 a knot.
KNOT_BRIDGE_DARTS = 48


def trunk_darts(sides: int, years: int) -> int:
    """Darts of a branch-free trunk after ``years`` years (closed form).

    Levels ``t = 0..Y-1`` (one pith ``sides``-prism each, ``12 sides`` darts);
    level ``t`` has lived ``2 (Y - t)`` half-years, so each of its ``sides``
    stacks holds ``2 (Y - t)`` wood cells and ``Y - t`` bark cells, cubes of 48
    darts; each level ``t >= 1`` is glued by year to the one below
    (:meth:`Wood._bridge`), ``BRIDGE_DARTS`` per sector:
    ``darts = 12 s Y + 48 s * 3 * Y (Y + 1) / 2 + 24 s (Y - 1)``.

    >>> trunk_darts(16, 10)
    132096
    """
    return 12 * sides * years + 48 * sides * 3 * years * (years + 1) // 2 + BRIDGE_DARTS * sides * max(years - 1, 0)


def trunk_volumes(sides: int, years: int) -> int:
    """Volumes of a branch-free trunk: ``Y + 3 s Y (Y + 1) / 2``."""
    return years + 3 * sides * years * (years + 1) // 2


def resolve_params(species: str = "pine", **params: Any) -> dict[str, Any]:
    """Species preset values overridden by ``params`` (strings converted); checked."""
    if species not in SPECIES:
        raise ValueRefused(f"unknown species {species!r}; choose one of {', '.join(SPECIES)}")
    out = dict(SPECIES[species])
    for name, value in params.items():
        if name not in PARAMETERS:
            raise ValueRefused(f"unknown wood parameter {name!r}; known: {', '.join(sorted(PARAMETERS))}")
        default = SPECIES[species][name]
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueRefused(f"wood parameter {name}={value!r} is not a number") from None
        if not math.isfinite(number):
            raise ValueRefused(f"wood parameter {name} must be a finite number, got {value!r}")
        if isinstance(default, int) and not number.is_integer():
            raise ValueRefused(f"wood parameter {name} must be a whole number, got {value!r}")
        out[name] = int(number) if isinstance(default, int) else number
    _check(out)
    return out


def _check(p) -> None:
    def need(cond, message):
        if not cond:
            raise ValueRefused(message)

    for name in (
        "pith_radius",
        "height",
        "early_min",
        "early_max",
        "late_min",
        "late_max",
        "decay",
        "width_floor",
        "bark_min",
        "bark_max",
        "branch_length",
        "branch_scale",
        "reaction",
        "reaction_angle",
        "branch_angle",
        "height_jitter",
    ):
        need(math.isfinite(p[name]), f"{name} must be a finite number, got {p[name]}")
    need(
        p["sides"] >= 3 and p["branch_sides"] >= 3,
        f"prism order must be at least 3, got sides={p['sides']}, branch_sides={p['branch_sides']}",
    )
    need(
        p["branch_sides"] % 4 == 0 and p["branch_sides"] <= MAX_SIDES,
        "branch_sides must be a multiple of 4, at most "
        f"{MAX_SIDES} (a quarter of a knot's sides meets each wall of its slot), got {p['branch_sides']}",
    )
    for lo, hi in (("early_min", "early_max"), ("late_min", "late_max"), ("bark_min", "bark_max")):
        need(p[lo] > 0 and p[hi] > 0, f"ring widths must be positive, got {lo}={p[lo]}, {hi}={p[hi]}")
        need(p[lo] <= p[hi], f"{lo} must not exceed {hi}, got {p[lo]} > {p[hi]}")
    for name in ("pith_radius", "height", "decay", "branch_length", "branch_scale"):
        need(p[name] > 0, f"{name} must be > 0, got {p[name]}")
    for name in LENGTHS:  # a wood of finite, drawable size: never 1e308 m a year
        need(p[name] <= MAX_LENGTH, f"{name} must be at most {MAX_LENGTH:g} m, got {p[name]:g}")
    need(p["sides"] <= MAX_SIDES, f"sides must be at most {MAX_SIDES}, got {p['sides']}")
    need(0 < p["width_floor"] <= 1, f"width_floor must be in (0, 1], got {p['width_floor']}")
    need(p["reaction"] >= 0, f"reaction must be >= 0, got {p['reaction']}")
    need(0 <= p["height_jitter"] < 1, f"height_jitter must be in [0, 1), got {p['height_jitter']}")
    need(0 < p["branch_angle"] < 180, f"branch_angle must be in (0, 180) degrees, got {p['branch_angle']}")
    need(
        p["branches"] >= 0
        and p["sapwood_rings"] >= 0
        and p["heartwood_age"] >= 0
        and p["branch_levels"] >= 0
        and p.get("branch_life", 0) >= 0,
        "branches, branch_levels, branch_life, sapwood_rings and heartwood_age must be >= 0",
    )
    _species.check(p)


def death_year(p: Mapping[str, Any], born: int, death: int | None = None) -> int | None:
    """The year a branch born in ``born`` dies: ``death`` if given, else ``born + branch_life``
    (``None``: it never dies, ``branch_life = 0``).

    >>> death_year({"branch_life": 4}, 3), death_year({"branch_life": 0}, 3), death_year({}, 3, 5)
    (7, None, 5)
    """
    if death is not None:
        return int(death)
    life = int(p.get("branch_life", 0))
    return born + life if life > 0 else None


def estimated_darts(
    p: Mapping[str, Any],
    years: int,
    branch_years: Sequence[int] = (),
    deaths: Sequence[int | None] | None = None,
    parents: Sequence[int] | None = None,
) -> int:
    """Darts the wood will have: the trunk's closed form plus each branch's (a branch born in
    year ``j`` is a trunk of ``branch_sides`` sides grown ``years - j`` years, of at most
    ``branch_levels`` levels);
    nodes add one pith prism and its stacks per year with branches, less one stack per branch
    (its slot); the walls of a slot are cut in ``branch_sides / 4`` pieces, one per knot cell
    facing them.  A branch that dies in year ``D`` grows no level after it (``D - j`` levels at
    most); its stacks go on (the rings that encase its knot).  ``deaths`` gives each branch's
    death year (``None``: :func:`death_year`'s rule); a branch dead before ``years`` gets a cap
    level on its stub's end (:meth:`Wood._cap_stub`).  ``parents`` gives each branch's host
    (-1: the trunk; else the index of the branch it grows on, :class:`Branch`): a branch
    carrying sub-branches grows a node of ``branch_sides`` sides in each year some are born on
    it, like the trunk's.  A branch's levels are glued by year as the
    trunk's (:meth:`Wood.year_shift`): ``BRIDGE_DARTS`` per side for each
    level past the knot (a cap has none).  Exact for :func:`grow_wood` (measured: a
    knot of 16 sides grown ``y`` years adds ``3 (28 + 144 y)`` darts of cuts)."""
    s, b = int(p["sides"]), int(p["branch_sides"])
    total = trunk_darts(s, years)
    host = [-1] * len(branch_years) if parents is None else [int(h) for h in parents]
    born = [int(y) for y in branch_years]
    for h in sorted(set(host)):  # the node levels and their stacks, less the slots
        sides = s if h < 0 else b
        mine = [y for y, hh in zip(born, host) if hh == h]
        for j in sorted(set(mine)):
            total += 12 * sides + 48 * (sides - mine.count(j)) * 3 * (years - j)
    cap = int(p.get("branch_levels", 0))
    for c, j in enumerate(branch_years):
        y = years - int(j)
        kept = y if cap == 0 else min(y, cap)  # levels t < kept, level t lived y - t years
        dies = death_year(p, int(j), None if deaths is None else deaths[c])
        if dies is not None:
            kept = min(kept, max(dies - int(j), 1))
        total += 12 * b * kept + 144 * b * (kept * y - kept * (kept - 1) // 2)
        total += BRIDGE_DARTS * b * max(kept - 1, 0)  # its levels past the knot are glued by year too
        if dies is not None and dies < years:  # the cap on the stub (Wood._cap_stub): a pith prism and
            # c = 3 (D - year of the top level) cells a stack at death, then 3 a year
            total += 12 * b + 48 * b * (3 * (dies - (int(j) + kept - 1)) + 3 * (years - dies))
        # a knot of b = 4q sides: its slot's walls are cut in q, 28 darts for the pith face and 48 per
        # layer (4 walls of 12 darts) for each extra piece, 3 layers (two of wood, one of bark) a year
        total += (b // 4 - 1) * (28 + 144 * (years - int(j)))
        if 1 <= int(j) < years:  # a node (the trunk's or a branch's) is glued by year: the knot's first ring
            total += KNOT_BRIDGE_DARTS * (b // 4) - 32  # meets three cells below (Wood._split_knot_bottoms), measured
    return total


# ---------------------------------------------------------------------- geometry helpers
def _across(rel: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The part of each offset ``rel`` (n, 3) across its axis direction ``up`` (n, 3), a unit vector."""
    return rel - np.einsum("ij,ij->i", rel, up)[:, None] * up


def _u01(*key):
    """A uniform number in [0, 1) from a key (no shared random stream)."""
    return mix(*key) / float(1 << 63)


_MIX_A, _MIX_B = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_R31, _R29, _LOW63 = np.uint64(31), np.uint64(29), np.uint64((1 << 63) - 1)


def mix_array(*columns: ArrayLike) -> np.ndarray:
    """:func:`mix` over integer arrays (broadcast), vectorised: the same values as ``mix``.

    >>> int(mix_array(np.array([1]), 2)[0]) == mix(1, 2)
    True
    """
    arrays = [np.asarray(c) for c in columns]
    h = np.full(np.broadcast(*arrays).shape, 0x9E3779B97F4A7C15, np.uint64)
    shift = np.empty_like(h)
    with np.errstate(over="ignore"):  # in place: uint64 arithmetic wraps, as mix's mask does
        for c in arrays:
            h ^= c.astype(np.int64).astype(np.uint64)
            h *= _MIX_A
            np.right_shift(h, _R31, out=shift)
            h ^= shift
            h *= _MIX_B
            np.right_shift(h, _R29, out=shift)
            h ^= shift
    h &= _LOW63
    return h.view(np.int64)


def u01_array(*columns: ArrayLike) -> np.ndarray:
    """Uniform numbers in [0, 1) from integer key arrays (vectorised :func:`_u01`)."""
    return mix_array(*columns) / float(1 << 63)


@dataclass
class Branch:
    """A branch: born in ``year`` on its host's level ``level``, sector ``sector`` (0-based).

    The host is the trunk (``parent = -1``) or the branch of index ``parent``
    (listed before it): a second-order branch's knot lies in its first-order
    branch's wood as a first-order knot lies in the trunk's.
    """

    year: int
    sector: int
    seed: int
    level: int = -1  # the trunk level (a short node) the branch grows from
    angle: float | None = None  # insertion angle from the trunk axis (degrees); None: the species'
    death: int | None = None  # the year it dies (None: the species' ``branch_life`` rule)
    parent: int = -1  # the branch it grows on (index; -1: the trunk), see :func:`check_hosts`


@dataclass
class Axis:
    """One pith chain with its stacks; ``levels[t]`` is the first dart of pith prism t."""

    index: int
    sides: int
    born_step: int
    seed: int
    address: int = 0  # seed-free address for volume keys
    parts: list = field(default_factory=list)  # (year, 'whole' | 'node' | 'internode') per level
    levels: list = field(default_factory=list)  # pith first darts
    level_step: list = field(default_factory=list)  # step each level was made
    missing: set = field(default_factory=set)  # (t, k) slots with no stack (knot holes)
    #: stacks as arrays: ``alive[t, k]`` (a stack grows there), ``count[t, k]`` cells in it and
    #: ``cells[t, k, i]`` the first dart of its cell ``i + 1`` (-1 beyond the count)
    alive: np.ndarray = None  # type: ignore[assignment]  # set by Wood before any read
    count: np.ndarray = None  # type: ignore[assignment]
    cells: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.alive = np.zeros((0, self.sides), bool)
        self.count = np.zeros((0, self.sides), np.int64)
        self.cells = np.full((0, self.sides, 4), -1, np.int64)

    def add_level(self) -> None:
        """One more level of (empty, alive) stacks."""
        self.alive = np.vstack([self.alive, np.ones((1, self.sides), bool)])
        self.count = np.vstack([self.count, np.zeros((1, self.sides), np.int64)])
        self.cells = np.concatenate([self.cells, np.full((1,) + self.cells.shape[1:], -1, np.int64)])

    def stack_darts(self, t: int, k: int) -> list[int]:
        """First darts of the cells of stack ``(t, k)``, from the pith outwards."""
        return self.cells[t, k, : self.count[t, k]].tolist()


#: codes of a trunk level's part of its year (``Axis.parts``)
_PARTS = {"whole": 0, "node": 1, "internode": 2}

#: the knot's four seam corners in slot coordinates (u, v): (-,-), (+,-), (+,+), (-,+)
_SU = np.array([-1.0, 1.0, 1.0, -1.0])
_SV = np.array([-1.0, -1.0, 1.0, 1.0])


def branch_direction(f: np.ndarray, phi: float, elev: float) -> np.ndarray:
    """Frame (rows H, L, U) of a branch leaving a level of frame ``f`` (rows H, L, U) at angle
    ``phi`` about it, ``elev`` radians above the level's cross-section (towards its H).

    The knot's side 0 faces the slot's bottom wall (the sew puts it there),
    side 1 the wall at sector ``k + 1``: L points down the host, away from H.

    >>> (np.round(branch_direction(np.eye(3)[[2, 0, 1]], 0.0, 0.0), 6) + 0.0).tolist()  # + 0.0: no -0.0
    [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    """
    radial = math.cos(phi) * f[1] + math.sin(phi) * f[2]
    d = math.cos(elev) * radial + math.sin(elev) * f[0]
    d = d / np.linalg.norm(d)
    down = -f[0] + (f[0] @ d) * d
    left = down / np.linalg.norm(down)
    d0, d1, d2 = d
    l0, l1, l2 = left  # np.cross(d, left), term for term, without its overhead
    return np.array([d, left, [d1 * l2 - d2 * l1, d2 * l0 - d0 * l2, d0 * l1 - d1 * l0]])


#: rounds of :func:`split_corners` (a knot's walls cut an edge in at most ``branch_sides / 4``
#: pieces; each round shrinks the error of a chain of ``q - 1`` cuts by ``cos(pi / q)`` at most)
SPLIT_ROUNDS = 60


def split_corners(gm: GMap3, split: np.ndarray) -> None:
    """Corners of the darts ``split`` made by edge cuts: each the mean of its edge's two
    neighbours (``alpha0`` and ``alpha0 alpha1``), solved by ``SPLIT_ROUNDS`` Jacobi rounds.

    An edge cut in ``q`` pieces has ``q - 1`` cut vertices whose neighbours
    are cut vertices too: one round of midpoints reads the table's unset
    rows for them.  Only the corners of volumes that count in the vertex
    average matter: a cut on a knot's seam (every cut, on a trunk's knots)
    meets an ``exclusive`` knot volume, which alone places it, so
    :meth:`Wood.embed` keeps one round for the others; a sub-branch's slot in
    the node next to its host's knot cuts the host's knot (exclusive too),
    whose cut darts get these rounds.  The neighbours are darts of the same
    volume (``alpha0``, ``alpha1`` stay in it), so ``split`` may be any
    volumes' cut darts.  Starts from each cut dart's volume centre.
    """
    corners = gm.corners
    a0, a1 = gm.alpha[0], gm.alpha[1]
    left, right = a0[split], a0[a1[split]]
    vol = gm.dart_volume[split].astype(np.int64)
    own = gm.dart_volume[: len(corners)]
    need = np.zeros(max(int(own.max()), int(vol.max())) + 1, bool)
    need[vol] = True
    pick = need[own]  # the darts of the split darts' volumes only (the same sums, in the same order)
    pick[split] = False
    darts = np.flatnonzero(pick)
    mine = own[darts].astype(np.int64)
    count = np.bincount(mine, minlength=len(need))
    centre = np.stack([np.bincount(mine, corners[darts, j], minlength=len(need)) for j in range(3)], axis=1)
    corners[split] = centre[vol] / np.maximum(count[vol], 1)[:, None]
    for _ in range(SPLIT_ROUNDS):
        corners[split] = 0.5 * (corners[left] + corners[right])


def _corner_blend(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``((1 + u su) (1 + v sv) / 4)`` for the four seam corners ``(su, sv)`` = (-,-), (+,-), (+,+), (-,+): (m, 4, 1).

    ``u * -1`` is exact, so ``1 + u su`` is ``1 - u`` or ``1 + u``: each factor
    is made once, and the products and the division are the ones a broadcast
    over ``_SU``, ``_SV`` would make.
    """
    out = np.empty((len(u), 4, 1))
    pu, mu, pv, mv = 1 + u, 1 - u, 1 + v, 1 - v
    for c, (a, b) in enumerate(((mu, mv), (pu, mv), (pu, pv), (mu, pv))):
        np.multiply(a, b, out=out[:, c, 0])
        out[:, c, 0] /= 4
    return out


def _put_blocks(flat: np.ndarray, rows: np.ndarray, pts: np.ndarray) -> None:
    """``flat[rows[j] + c] = pts[j, c]`` for each of the ``c < 8`` corners of cube ``j``.

    As whole 8-row blocks when every start row is a multiple of 8 (the usual
    case: prisms of even order have 2n corners), which numpy copies about 5x
    faster than 8 single rows each; the same values either way.
    """
    if len(flat) % 8 == 0 and not np.any(rows % 8):
        flat.reshape(-1, 8, 3)[rows // 8] = pts
    else:
        flat[rows[:, None] + np.arange(8)[None, :]] = pts


class Wood:
    """A growing volumetric wood: ``gm`` is the :class:`GMap3`; ``step()`` adds a half-year."""

    _radius: float  # memos of trunk_radius() and node_height() once the final year is known
    _node: float
    seconds: float  # build time, set by grow_wood / from_skeleton

    def __init__(
        self,
        params: dict[str, Any],
        seed: int = 0,
        branches: list[Branch] | None = None,
        species: str = "pine",
        trunk_frames: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
        years: int | None = None,
    ) -> None:
        self.p = params
        self.final_years = years
        #: push trunk rings out of the knots' cones (see the module docstring)
        self.bend_rings = True
        self.species = species
        self.seed = int(seed)
        self.steps = 0
        self.gm = gm = GMap3()
        for name, dtype in (
            ("axis", np.int16),
            ("level", np.int16),
            ("sector", np.int16),
            ("cell", np.int16),
            ("wood", np.int8),
            ("season", np.int8),
            ("year", np.int16),
            ("ring", np.int16),
            ("width", np.float64),
            ("born", np.int16),
            ("rule", np.int8),
            ("key", np.int64),
            ("reaction", np.int8),
            ("bark", np.int8),
        ):
            gm.add_volume_data(name, dtype, fill=-1 if dtype is not np.float64 else 0.0)
        gm.add_volume_data("dead", np.int8, fill=0)  # 1: part of a dead knot (see _kill_branches)
        self._corner = np.zeros(0, np.int16)  # template corner per dart (-1: made by a split)
        if years:  # one allocation up front instead of doublings
            listed = branches or []
            est = estimated_darts(
                params, int(years), [br.year for br in listed], [br.death for br in listed], [br.parent for br in listed]
            )
            if est <= MAX_DARTS:
                gm.reserve(est)
                self._corner = np.full(est, -1, np.int16)
        self.trunk = Axis(0, int(params["sides"]), 0, mix(self.seed, 0), address=mix(0))
        self.axes = [self.trunk]
        self.branches = list(branches or [])
        self.trunk_frames = trunk_frames
        self._sewn_layers: dict[int, int] = {}  # branch index -> slot layers sewn so far
        #: branch index -> its axis (``axes`` holds them in birth order, which need not be branch order)
        self.branch_axis: dict[int, Axis] = {}
        #: dead branch index -> (half-years each level had lived, cells each level held) at its death
        self.dead: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        #: dead branch index -> (its cap level, cells each cap stack got at death, the death year)
        self.caps: dict[int, tuple[int, int, int]] = {}

    # ------------------------------------------------------------------ growth
    @property
    def year(self) -> int:
        return self.steps // 2

    def step(self) -> None:
        """One half-year: length growth and new branches in spring, then one ring layer."""
        spring = self.steps % 2 == 0
        if spring:
            self._kill_branches()
            born = [br for br in self.branches if br.year == self.year and br.parent < 0]
            if born:  # a short node carries the new branches, then the internode
                self._grow_length(self.trunk, "node")
                for br in born:
                    br.level = len(self.trunk.levels) - 1
                self._grow_length(self.trunk, "internode")
            else:
                self._grow_length(self.trunk)
            for b, br in enumerate(self.branches):  # hosts come first: a sub-branch's node exists when it starts
                if br.year == self.year:
                    self._start_branch(b, br)
                elif br.year < self.year and self._branch_grows(b):
                    self._grow_branch(b)
        for _ in range(2 if spring else 1):
            self._add_layer()
            self._sew_knots()
        self.steps += 1
        self._sync_corner()
        self.assign_roles()

    def _grow_branch(self, b: int) -> None:
        """A year's length of branch ``b``: a node and an internode when sub-branches are born on it."""
        ax = self.branch_axis[b]
        kids = [c for c in self.branches if c.parent == b and c.year == self.year]
        if not kids:
            self._grow_length(ax)
            return
        self._grow_length(ax, "node")
        for c in kids:
            c.level = len(ax.levels) - 1
        self._grow_length(ax, "internode")

    def host(self, br: Branch) -> Axis:
        """The axis a branch grows on: the trunk, or its parent branch's axis."""
        return self.trunk if br.parent < 0 else self.branch_axis[br.parent]

    def death_year(self, b: int) -> int | None:
        """The year branch ``b`` dies (:func:`death_year`), or ``None``."""
        br = self.branches[b]
        return death_year(self.p, br.year, br.death)

    def _kill_branches(self) -> None:
        """Branches whose death year has come die: their knots stop growing with the trunk.

        A dead branch grows no more length, and its cambium stops: the cells
        each level holds at death keep the roles they had (knot wood inside,
        the branch's bark outside, :meth:`assign_roles`), and the ``dead``
        volume attribute marks them and the branch's pith.  Its stacks go on
        receiving one cell a half-year, sewn to the trunk's slot walls as
        before: they are the trunk's later rings, trunk wood of the trunk's
        years, which encase the dead knot.  So the boundary between a dead
        knot and the later wood is sewn through a layer of bark tissue (the
        knot's own bark at death), never knot wood to trunk wood: a loose,
        bark-lined knot; the solid stays one ball (chi = 1).

        *The encased bark (a choice).*  A living branch's bark is shed as the
        trunk's is (:func:`~ramure.gmap.organs.wood_species.shed_bark`: at most
        ``bark_ratio`` of the wood radius, a log's bark share [UNECE]), which
        leaves a branch of a few years under a millimetre of bark, its outer
        layers flakes 50 um thin.  From its death the branch's bark cells keep the
        widths its own bark law draws (``branch_scale`` times ``[bark_min,
        bark_max]`` a layer, one layer a year lived), none shed, and are marked
        ``BARK_ENCASED``, drawn in the species' darkest bark colour: the trunk
        encases the dead branch's whole bark, and the lumber glossaries'
        encased knot "results from a dead branch which the wood growth of the
        tree has surrounded", with "a dark ring of bark around the eye of the
        knot".  In the gallery's pine (a knot 3 years old at death) the ring
        is 1.3 mm thick (mean of its 16 stacks) where it was 0.8 mm, and dark
        where its inner layer was drawn pale; and no cell turns over any
        more: the flakes, bent round the knot's arc (``KNOT_BEND``), did
        (their straight edges crossed the bend by 0.1-0.2 mm, more than their
        thickness).
        """
        for b, ax in self.branch_axis.items():
            if b in self.dead or self.death_year(b) != self.year:
                continue
            lived = self.steps - np.asarray(ax.level_step, np.int64)
            # every level keeps the knot's depth less its year shift (the cells of the knot's outer
            # cells' years, glued by year): the stub's outer cells (born after death when the stub
            # is young) are its bark, so the knot's wood never meets later wood, and the bark
            # lining runs on across the stub's level boundaries as the rings do
            held = int(ax.count.max(initial=0)) - np.cumsum(self.year_shift(ax))
            self.dead[b] = (lived, held)
            self._cap_stub(b)

    def _cap_stub(self, b: int) -> None:
        """Close the later rings over dead branch ``b``'s stub: one cap level on its end (occlusion).

        At death the stub's end is a disc: the E face of its top pith prism
        and the C3 faces of the ``c`` cells each of its top level's stacks
        holds.  A cap level is grown on it (:meth:`_grow_length`, the pith
        prism sewn to that E face) and each cap stack gets ``c`` cells at
        once, cell ``i`` sewn (C1) to the top level's cell ``i`` and round
        its level (C2 | C4): the stub's end is covered in the step it dies,
        and its length stays what it was.  From then on the cap's stacks grow
        one cell a half-year with every other stack, cell ``i`` sewn to cell
        ``i`` of the top level: the trunk's later rings run up the stub and
        on over its end (:meth:`_cap_corners` draws them closing over it).
        Cap cells are trunk tissue (:meth:`assign_roles`), never the dead
        knot's, so no face of the dead knot stays on the boundary once the
        trunk's rings have passed its depth.
        """
        ax = self.branch_axis[b]
        top = len(ax.levels) - 1
        c = int(ax.count[top].max(initial=0))
        self._grow_length(ax)
        cap = top + 1
        self.caps[b] = (cap, c, self.year)
        k = np.arange(ax.sides)
        t = np.full(ax.sides, cap)
        for i in range(1, c + 1):
            below = ax.cells[t, k, max(i - 2, 0)]
            support = below + 8 if i > 1 else ax.levels[cap] + 4 * ax.sides + 8 * k
            self._add_layer([(ax, t, k, np.full(ax.sides, i), support.astype(np.int64))])

    def knot_counts(self) -> dict[str, int]:
        """Knots (branches born so far) that are alive and that are dead."""
        born = list(self.branch_axis)
        dead = sum(1 for b in born if b in self.dead)
        return {"live": len(born) - dead, "dead": dead}

    def knot_orders(self) -> dict[str, int]:
        """Knots (branches born so far) by order: ``"1"`` in the trunk, ``"2"`` in first-order branches..."""
        orders = branch_orders(self.branches)
        counts = Counter(orders[b] for b in self.branch_axis)
        return {str(o): counts[o] for o in sorted(counts)}

    def _frozen(self, axis: np.ndarray, level: np.ndarray, cell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per volume: whether it belongs to a dead knot, and the half-years it had lived at death.

        A dead branch's pith prisms and the cells its levels held at death
        are the dead knot; ``lived`` is -1 elsewhere.
        """
        frozen = np.zeros(len(axis), bool)
        lived = np.full(len(axis), -1, np.int64)
        for b, (q_d, n_d) in self.dead.items():
            on = np.flatnonzero((axis == b + 1) & (level >= 0) & (level < len(n_d)))
            lv = level[on]
            mine = on[cell[on] <= n_d[lv]]
            frozen[mine] = True
            lived[mine] = q_d[level[mine]]
        return frozen, lived

    def _branch_grows(self, b: int) -> bool:
        """Whether branch ``b`` still grows in length: below ``branch_levels`` levels (0: always).

        A log's branches are stubs: the knot inside the trunk and a short
        length past the bark are what planks and cuts show, and a branch of
        as many sides as the trunk grown to its full length would cost four
        times the darts of the trunk's rings (30 years, 20 branches: 9.2
        million darts against 3.6 million with stubs).
        """
        if b in self.dead:  # a dead branch grows no more
            return False
        cap = int(self.p.get("branch_levels", 0))
        return cap == 0 or len({year for year, _ in self.branch_axis[b].parts}) < cap  # years: a node is no year

    def _sync_corner(self) -> None:
        n = self.gm.n_darts
        if n > len(self._corner):  # grow by doubling: no copy per added layer
            grown = np.full(max(n, 2 * len(self._corner)), -1, np.int16)
            grown[: len(self._corner)] = self._corner
            self._corner = grown

    @property
    def corner(self) -> np.ndarray:
        """Template corner of every dart (-1 for darts made by edge splits)."""
        return self._corner[: self.gm.n_darts]

    def _new(self, n, count, axis, rule, **values):
        gm = self.gm
        first = gm.add_prisms(n, count, axis=axis, born=self.steps, rule=rule, **values)
        self._sync_corner()
        t = _prism.template(n)
        start = int(first[0]) if len(first) else 0  # add_prisms numbers the prisms' darts consecutively
        self.corner[start : start + len(first) * t.size].reshape(len(first), t.size)[:] = t.corner[None, :]
        return first

    def _grow_length(self, ax, part: str = "whole") -> None:
        """A new pith prism on the free E face of the axis's top prism (none for the trunk's first)."""
        t = len(ax.levels)
        ax.parts.append((self.year, part))
        label = "P" if ax.index == 0 else "Q"
        (first,) = self._new(
            ax.sides,
            1,
            ax.index,
            0,
            label=label,
            level=t,
            sector=-1,
            cell=0,
            exclusive=ax.index > 0 and t == 0,
            wood=CODES["pith"] if ax.index == 0 else CODES["knot"],
            key=mix(ax.address, 1, t),
        )
        if ax.levels:
            gm = self.gm
            gm.sew3([int(gm.prism_face(ax.levels[-1], ax.sides, "E"))], [int(gm.prism_face(first, ax.sides, "O"))])
        ax.levels.append(int(first))
        ax.level_step.append(self.steps)
        ax.add_level()
        for k in range(ax.sides):
            if (t, k) in ax.missing:
                ax.alive[t, k] = False

    def _start_branch(self, b, br):
        """The branch's first pith prism, its O face sewn onto its host's pith face in the slot."""
        host = self.host(br)
        if br.parent >= 0 and not (0 < br.level < len(host.levels) and host.parts[br.level] == (self.year, "node")):
            raise ValueRefused(f"branch {b}: its host branch {br.parent} grows no node in year {self.year} (see check_hosts)")
        host.missing.add((br.level, br.sector))
        if br.level < len(host.alive):
            host.alive[br.level, br.sector] = False
        ax = Axis(b + 1, int(self.p["branch_sides"]), self.steps, br.seed, address=mix(1000 + b))
        self.axes.append(ax)
        self.branch_axis[b] = ax
        self._grow_length(ax)
        gm = self.gm
        slot = self._anchors([host.levels[br.level]], f"C{br.sector + 1}")
        base = self._anchors([ax.levels[0]], "O")
        self._cut_slot(int(slot[0]), ax.sides // 4)
        gm.sew3(slot, base)
        self._sewn_layers[b] = 0

    def _cut_edges(self, darts: np.ndarray, pieces: np.ndarray) -> None:
        """Cut the edge of each dart of ``darts`` into ``pieces`` equal pieces, halving in batches.

        A cut at ``h / n`` (``h = n // 2``) leaves ``h`` pieces on the dart's
        side and ``n - h`` beyond (from ``alpha1`` of the new dart); every round
        cuts all edges at once, so four pieces take two batches, not three.
        """
        gm = self.gm
        cur, left = np.asarray(darts, np.int64), np.asarray(pieces, np.int64)
        keep = left > 1
        cur, left = cur[keep], left[keep]
        while cur.size:
            half = left // 2
            new = gm.split_edge(cur, half / left)
            beyond = gm.alpha[1][new].astype(np.int64)
            cur, left = np.concatenate([cur, beyond]), np.concatenate([half, left - half])
            keep = left > 1
            cur, left = cur[keep], left[keep]

    def _cut_slot(self, dart: int, q: int) -> None:
        """Cut each edge of the trunk's pith face under a knot (the face of ``dart``) into ``q`` pieces.

        An edge already cut (shared with the slot of a knot born beside it in
        the same year) is left as it is; corners are the darts with a
        template corner.
        """
        if q == 1:
            return
        gm = self.gm
        walk, length = gm.face_walk([dart])
        at_vertex = walk[0, 0 : length[0] : 2]
        corners = np.flatnonzero(self.corner[at_vertex] >= 0)
        pieces = np.diff(np.append(corners, len(at_vertex)))
        whole = pieces == 1  # an edge cut already (a knot beside this one) stays as it is
        self._cut_edges(at_vertex[corners[whole]], np.full(int(whole.sum()), q))

    def _anchors(self, firsts, label):
        """Anchor darts (forward, corner 0) of face ``label`` of the volumes of darts ``firsts``.

        Found by label in each volume's own darts (an orbit walk, cost
        proportional to the volumes), not by template offsets.
        """
        gm = self.gm
        firsts = np.asarray(firsts, np.int64)
        members, which = gm.orbits_from(firsts, (0, 1, 2))
        data = gm.dart_data
        labels = [label] * len(firsts) if isinstance(label, str) else label
        code = np.array([_prism.face_label_code(x) for x in labels], np.int64)
        hit = (data["face"][members] == code[which]) & data["forward"][members] & (data["fcorner"][members] == 0)
        out = np.full(len(firsts), -1, np.int64)
        out[which[hit][::-1]] = members[hit][::-1]
        if np.any(out < 0):
            raise GMapError(f"a wood volume has no face {label}")
        return out

    def _side_faces(self, firsts, labels):
        """A dart of side face ``labels[i]`` of the cell whose O face holds dart ``firsts[i]``.

        Walks each O face and looks across its edges (``alpha2``) for the
        label carried by the darts: faces by label, one face walk per cell
        instead of a volume orbit.
        """
        gm = self.gm
        walk, _ = gm.face_walk(np.asarray(firsts, np.int64))
        side = np.where(walk >= 0, gm.alpha[2][np.maximum(walk, 0)], -1)
        code = np.array([_prism.face_label_code(x) for x in labels], np.int64)
        hit = (side >= 0) & (gm.dart_data["face"][np.maximum(side, 0)] == code[:, None])
        if not hit.any(axis=1).all():
            raise GMapError(f"a wood cell has no side face {labels[int(np.argmin(hit.any(axis=1)))]}")
        return side[np.arange(len(side)), np.argmax(hit, axis=1)]

    def _sew_knots(self) -> None:
        """Identify each knot's new ring cells with the slot walls they meet (see the module docstring).

        Layer ``i`` of a slot is walled by four trunk faces: C2 of stack
        ``(t, k-1)``, C4 of ``(t, k+1)``, C3 of ``(t-1, k)`` and C1 of
        ``(t+1, k)``, cell ``i`` of each -- of the bottom wall, a year older
        and glued by year (:meth:`year_shift` ``s``), cell ``i + s``, and its
        cells ``1..s`` (whose cones end there) meet the knot's first ring
        too, in ``s`` rounds more after layer 1 (:meth:`_split_knot_bottoms`
        cut its bottom faces for them).  Its partner is the knot cell whose
        C1 face lies across the wall face's inner edge on the boundary (found
        by turning around that edge, :func:`ramure.gmap.kernel.identify.boundary_neighbour`):
        layer ``i - 1`` (or the pith face, for ``i = 1``) is sewn already, so
        the two faces share that edge and :meth:`GMap3.identify` zips them.
        Layers are done in order, one batch per layer over every slot.
        """
        from ramure.gmap.kernel.identify import boundary_neighbour

        gm = self.gm
        c1 = _prism.face_label_code("C1")
        vd = gm.volume_data
        shifts: dict[int, np.ndarray] = {}  # per host (a branch's parent): year_shift
        while True:
            walls, labels, want = [], [], []
            for b, done in self._sewn_layers.items():
                br = self.branches[b]
                host = self.host(br)  # the trunk, or the branch a sub-branch grows on
                n = host.sides
                t, k, r = br.level, br.sector, done + 1
                if br.parent not in shifts:
                    shifts[br.parent] = self.year_shift(host)
                shift = shifts[br.parent]
                s = int(shift[t]) if 0 < t < len(shift) else 0
                # round r: the knot's ring i against the walls' cells of its year; its first ring
                # meets the bottom wall's cells 1..s + 1 in s + 1 rounds (the older cones end there)
                i = 1 if r <= s + 1 else r - s
                if self.branch_axis[b].count[0].min() < i:  # the knot's ring cell i is not born yet
                    continue
                for tt, kk, label in ((t, (k - 1) % n, "C2"), (t, (k + 1) % n, "C4"), (t - 1, k, "C3"), (t + 1, k, "C1")):
                    c = (r if r <= s + 1 else i + s) if label == "C3" else i
                    if label != "C3" and i == 1 and r > 1:
                        continue  # the side and top walls' first cells are sewn in round 1
                    if 0 <= tt < len(host.levels) and host.alive[tt, kk] and host.count[tt, kk] >= c:
                        walls.append(host.cells[tt, kk, c - 1])
                        labels.append(label)
                        want.append((b, i))
            if not walls:
                return
            anchors = self._side_faces(walls, labels)
            anchors, rows = self._split_walls(anchors)
            want = [want[r] for r in rows]
            walk, _ = gm.face_walk(anchors)
            free = walk >= 0
            nb = np.full(walk.shape, -1, np.int64)
            nb[free] = boundary_neighbour(gm, walk[free])
            nv = gm.dart_volume[np.maximum(nb, 0)]
            b_of = np.array([w[0] for w in want])[:, None]
            i_of = np.array([w[1] for w in want])[:, None]
            partner = (
                (nb >= 0)
                & (gm.dart_data["face"][np.maximum(nb, 0)] == c1)
                & (vd["axis"][nv] == b_of + 1)
                & (vd["level"][nv] == 0)
                & (vd["cell"][nv] == i_of)
            )
            ok = partner.any(axis=1)
            if not ok.any():
                return
            first = np.argmax(partner, axis=1)
            a = anchors[ok]
            other = nb[np.flatnonzero(ok), first[ok]]
            gm.identify(a, other)
            for b in {w[0] for w, good in zip(want, ok) if good}:
                self._sewn_layers[b] += 1

    def _split_walls(self, anchors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Split each slot wall face of ``anchors`` into ``q = branch_sides / 4`` faces, one per knot cell.

        A wall face of layer ``i`` runs from its inner edge (shared with the
        cell's O face, already in ``q`` pieces: the previous layer's seam, or
        the pith face split when the branch was sewn) to its outer edge (on
        the E face).  The outer edge is cut into ``q`` pieces, then ``q - 1``
        chords join inner vertex ``r`` to outer vertex ``r``: ``q`` quads,
        each to be sewn to the C1 face of one knot cell.  Found by the faces'
        labels (topology), never by coordinates.  Returns one dart per
        sub-face (on its inner piece) and the row of ``anchors`` it came from;
        with ``q = 1`` (or faces already split) the anchors themselves.
        """
        gm = self.gm
        q = int(self.p["branch_sides"]) // 4
        rows = np.arange(len(anchors))
        if q == 1 or not len(anchors):
            return anchors, rows
        e_code, o_code = _prism.face_label_code("E"), _prism.face_label_code("O")
        walk, _ = gm.face_walk(anchors)
        across = gm.dart_data["face"][gm.alpha[2][np.maximum(walk, 0)]]
        outer = (walk >= 0) & (across == e_code)
        fresh = np.flatnonzero(outer.sum(axis=1) == 2)  # outer edge still whole
        if fresh.size:
            self._cut_edges(walk[fresh, np.argmax(outer[fresh], axis=1)], np.full(len(fresh), q))
        walk, length = gm.face_walk(anchors)
        across = gm.dart_data["face"][gm.alpha[2][np.maximum(walk, 0)]]
        at_vertex = np.where(walk >= 0, walk, 0)[:, 0::2]
        edge_ok = walk[:, 0::2] >= 0
        n_inner = ((across[:, 0::2] == o_code) & edge_ok).sum(axis=1)
        n_outer = ((across[:, 0::2] == e_code) & edge_ok).sum(axis=1)
        # ready: inner and outer edges in q pieces, and faces not split yet (a side wall's first
        # cell may have its bottom edge in pieces too, :meth:`_bridge`: 2q + 2 edges or more)
        ready = np.flatnonzero((n_inner == q) & (n_outer == q) & (length >= 2 * (2 * q + 2)))
        done = np.setdiff1d(rows, ready)
        out_darts, out_rows = [anchors[done]], [rows[done]]
        if not ready.size:
            return np.concatenate(out_darts), np.concatenate(out_rows)
        degrees = length[ready] // 2
        for deg in np.unique(degrees):  # faces of one degree at a time
            these = ready[degrees == deg]
            edge_darts = at_vertex[these, :deg]  # dart starting edge e, at vertex e
            inner = across[these, 0 : 2 * deg : 2] == o_code
            outer = across[these, 0 : 2 * deg : 2] == e_code
            first_inner = inner & ~np.roll(inner, 1, axis=1)
            e0 = np.argmax(first_inner, axis=1)
            pick = np.arange(len(these))
            # edges from the end of the inner run to the start of the outer run, walking on
            order = (e0[:, None] + q + np.arange(deg)[None, :]) % deg
            cross = np.argmax(outer[pick[:, None], order], axis=1)
            sub = np.stack([edge_darts[pick, (e0 + r) % deg] for r in range(q)], axis=1)
            for r in range(1, q):  # chord r: inner vertex r to outer vertex r, 2 (q - r) + cross corners on
                gm.split_faces(sub[:, r], 2 * (q - r) + cross)
            out_darts.append(sub.ravel())
            out_rows.append(np.repeat(rows[these], q))
        return np.concatenate(out_darts), np.concatenate(out_rows)

    def _near_slots(self, parts) -> np.ndarray:
        """Mask over this layer's new cells: those on a host's stack walling a knot's slot."""
        walls = {ax.index: np.zeros((len(ax.levels) + 2, ax.sides), bool) for ax, *_ in parts}
        for b in self._sewn_layers:
            br = self.branches[b]
            host = self.host(br)
            if host.index not in walls:  # the host grows no cell in this layer (a dead stub's cap alone)
                continue
            n, mask = host.sides, walls[host.index]
            t, k = br.level, br.sector
            for tt, kk in ((t, (k - 1) % n), (t, (k + 1) % n), (t - 1, k), (t + 1, k)):
                if tt >= 0:
                    mask[tt, kk] = True
        return np.concatenate([walls[ax.index][t, k] for ax, t, k, *_ in parts])

    def _match_supports(self, support: np.ndarray, first: np.ndarray) -> None:
        """Split the O edges of fresh cubes ``first`` as the edges of their ``support`` faces are split.

        A slot wall's cells have edges cut for the knot's sides (and the
        trunk's pith face under a knot likewise); the next cell stacked on
        such a face gets the same pieces on its O face so the two faces sew
        vertex to vertex.  Original corners carry a template corner
        (``corner >= 0``), split vertices do not.
        """
        gm = self.gm
        if not len(support):
            return
        walk, length = gm.face_walk(support)
        odd = np.flatnonzero(length > 8)
        if not odd.size:
            return
        corner = self.corner
        owalk, _ = gm.face_walk(first[odd])
        darts, cuts = [], []
        for row, j in enumerate(odd):
            at_vertex = walk[j, 0 : length[j] : 2]
            corners = np.flatnonzero(corner[at_vertex] >= 0)
            if len(corners) != 4 or corners[0] != 0:
                raise GMapError("a wood cell's support face has lost a corner")
            pieces = np.diff(np.append(corners, len(at_vertex)))
            for e in np.flatnonzero(pieces > 1):
                darts.append(int(owalk[row, 2 * e]))
                cuts.append(int(pieces[e]) - 1)
        self._cut_edges(np.array(darts, np.int64), np.array(cuts, np.int64) + 1)

    def _add_layer(self, only: list | None = None):
        """One new cube on the outside of every stack, then the joins around and along each axis.

        ``only``: the stacks to grow, ``[(axis, t, k, i, support)]`` (a dead stub's cap,
        :meth:`_cap_stub`); every alive stack by default.
        """
        gm = self.gm
        parts = [] if only is None else only
        for ax in self.axes if only is None else ():  # one step per axis, arrays over its stacks
            t, k = np.nonzero(ax.alive)
            i = ax.count[t, k] + 1
            # fresh template darts keep their ids and labels: E of a cube is first + 8,
            # C(k+1) of an n-prism first + 4n + 8k (forward dart at the face's corner 0)
            below = ax.cells[t, k, np.maximum(i - 2, 0)]
            pith = np.asarray(ax.levels, np.int64)[t] + 4 * ax.sides + 8 * k
            support = np.where(i > 1, below + 8, pith)
            parts.append((ax, t, k, i, support))
        n_slots = sum(len(part[1]) for part in parts)
        if not n_slots:
            return
        if gm.n_darts + 48 * n_slots > MAX_DARTS:
            raise ValueRefused(f"the wood would exceed {MAX_DARTS:,} darts")
        cat = np.concatenate
        axis = cat([np.full(len(t), ax.index) for ax, t, *_ in parts])
        address = cat([np.full(len(t), ax.address, np.int64) for ax, t, *_ in parts])
        t_all, k_all, i_all = (cat([part[j] for part in parts]) for j in (1, 2, 3))
        keys = mix_array(address, 3, t_all, k_all, i_all)
        first = self._new(
            4, n_slots, axis, 1, label="W", level=t_all, sector=k_all, cell=i_all, key=keys, exclusive=(axis > 0) & (t_all == 0)
        )
        support = cat([part[4] for part in parts])
        near = self._near_slots(parts)  # only a slot wall's stack has cut edges under its next cell
        self._match_supports(support[near], first[near].astype(np.int64))
        gm.sew3(support, first)
        start = 0
        for ax, t, k, i, _ in parts:
            mine = first[start : start + len(t)].astype(np.int64)
            start += len(t)
            if i.max() > ax.cells.shape[2]:
                grow = max(int(i.max()), 2 * ax.cells.shape[2]) - ax.cells.shape[2]
                ax.cells = np.concatenate([ax.cells, np.full(ax.cells.shape[:2] + (grow,), -1, np.int64)], 2)
            ax.cells[t, k, i - 1] = mine
            ax.count[t, k] = i
        self._join(parts, first)

    def _join(self, parts, first) -> None:
        """Identify each new cube with its neighbours through the edges they share.

        Around the axis: C2 of (t, k, i) with C4 of (t, k+1, i); along it: C1 of
        (t, k, i) with C3 of (t-1, k, i + s), the cell of the same year
        (:meth:`year_shift`; a new level's first cells through
        :meth:`_bridge`, a new knot's through :meth:`_split_knot_bottoms`).  The neighbours are found by the
        stacks' bookkeeping (same pith edge, same layer), never by coordinates;
        the two darts paired sit on the edge the faces share.
        """
        gm = self.gm
        a_parts: list[np.ndarray] = []
        b_parts: list[np.ndarray] = []
        along_a: list[np.ndarray] = [np.zeros(0, np.int64)]
        along_b: list[np.ndarray] = [np.zeros(0, np.int64)]
        bridges: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        start = 0
        for ax, t, k, i, _ in parts:
            f = first[start : start + len(t)].astype(np.int64)
            start += len(t)
            kr = (k + 1) % ax.sides  # the stack on the right, same layer
            right = ax.cells[t, kr, i - 1]
            ok = ax.alive[t, kr] & (ax.count[t, kr] >= i) & (right != f)
            a_parts.append(f[ok] + _C2)  # C2 of this cube, dart 0 ...
            b_parts.append(right[ok] + _C4 + 1)  # ... meets C4 of the next, dart 1: same edge, same vertex
            tb = np.maximum(t - 1, 0)  # the stack below, its cell of the same year
            j = i + self.year_shift(ax)[t]
            ok = (t > 0) & ax.alive[tb, k] & (ax.count[tb, k] >= j) & (j == i)
            a_parts.append(ax.cells[tb, k, j - 1][ok] + _C3)  # top of the cube below, dart 0
            b_parts.append(f[ok] + _C1 + 1)  # bottom of this one, dart 1
            later = (t > 0) & (j > i) & (i > 1)  # a level younger than the one below: by year
            later &= ax.alive[tb, k] & (ax.count[tb, k] >= j)
            along_a.append(ax.cells[tb, k, np.maximum(j - 1, 0)][later] + _C3)
            along_b.append(f[later] + _C1)
            new_level = np.flatnonzero((t > 0) & (j > i) & (i == 1))
            if new_level.size:  # one new level at a time: its shift is one number
                below = ax.cells[tb[new_level], k[new_level], : int(j[new_level].max())]
                lone = ~ax.alive[t[new_level], (k[new_level] - 1) % ax.sides]  # a knot's slot on its C4 side
                bridges.append((f[new_level], below, lone))
        a, b = np.concatenate(a_parts), np.concatenate(b_parts)
        if a.size:
            fresh = gm.alpha[3][a] == a
            gm.sew3(a[fresh], b[fresh])
        for cubes, below, lone in bridges:
            if len(cubes):
                self._bridge(cubes, below, lone)
        self._split_knot_bottoms(parts, first)
        a, b = np.concatenate(along_a), np.concatenate(along_b)
        if a.size:
            gm.identify(a, b)

    def year_shift(self, ax: Axis) -> np.ndarray:
        """Per level ``t`` of ``ax``: how many cells more the level below holds in each stack, ``0`` or ``2``.

        Level ``t`` is glued to level ``t - 1`` *by year*: its cell ``i``
        meets cell ``i + shift[t]`` below, the cell laid in the same
        half-year (issue 39: no ring ends on a level boundary).  The shift
        is the levels' age difference in half-years: 2 for a level grown a
        year after the one below it, 0 for a node's internode (same year)
        and for level 0.  Every axis is glued so, the trunk and each branch
        (a node carrying knots too: its slot's bottom wall meets the knot by
        year, :meth:`_sew_knots`).  On a branch, level 0 is the knot, the
        branch's first year (it starts on its host's pith in the spring it
        is born), and level 1 its second year's shoot, past the host's bark:
        shift 2, so the knot's first ring is the apex of its cone and closes
        at the knot's end, and ring ``i`` of the stub runs on from the
        knot's ring ``i + 1`` (a choice: the model's knot is the branch's
        first year's length).  A dead stub's cap (:meth:`_cap_stub`) has
        shift 0: its cells continue the top level's cell for cell.
        """
        shift = np.zeros(len(ax.levels), np.int64)
        if len(ax.levels) < 2:
            return shift
        steps = np.asarray(ax.level_step, np.int64)
        shift[1:] = steps[1:] - steps[:-1]
        cap = self.caps.get(ax.index - 1) if ax.index > 0 else None
        if cap is not None and cap[0] < len(shift):
            shift[cap[0]] = 0
        return shift

    def level_shifts(self, axis: ArrayLike, level: ArrayLike) -> np.ndarray:
        """:meth:`year_shift` of each ``(axis index, level)`` pair (0 for a level an axis lacks, or -1)."""
        axis, level = np.asarray(axis, np.int64), np.asarray(level, np.int64)
        width = max(len(ax.levels) for ax in self.axes) + 1
        table = np.zeros((max(ax.index for ax in self.axes) + 1, width), np.int64)
        for ax in self.axes:  # one row per axis: tens of axes, not one per volume
            table[ax.index, : len(ax.levels)] = self.year_shift(ax)
        ok = (axis >= 0) & (axis < len(table)) & (level >= 0) & (level < width)
        return np.where(ok, table[np.where(ok, axis, 0), np.where(ok, level, 0)], 0)

    def _bridge(self, cubes: np.ndarray, below: np.ndarray, lone_c4: np.ndarray | None = None) -> None:
        """Sew the first cells ``cubes`` of a new level onto cells ``below[:, 0..s]`` of the level below.

        The level below is ``s`` half-years older (``s = below.shape[1] - 1``):
        its inner cells ``1..s`` were laid before the new level existed, and
        their growth cones end at the level boundary (the apex of those
        years' cones).  The new level's cell 1 is laid in the same half-year
        as cell ``s + 1`` below.  So cell 1's bottom face (C1) is cut
        radially into ``s + 1`` quads (:meth:`_split_bottoms`) and piece
        ``j`` (from the pith out) is identified with the top face (C3) of
        cell ``j`` below.  The older inner cells end on the younger level's
        first ring cell, no ring meets a ring of another year.  ``lone_c4``
        marks the cubes whose C4 side has no stack (a knot's slot): that
        edge is theirs alone and is cut too.  Topology only (labels and
        shared edges); the embedding puts the pieces' vertices where the
        cells below end (:meth:`embed`).
        """
        cubes = np.asarray(cubes, np.int64)
        lone = np.zeros(len(cubes), bool) if lone_c4 is None else np.asarray(lone_c4, bool)
        sub = self._split_bottoms(cubes, cubes[lone], cubes, below.shape[1])
        for r, piece in enumerate(sub):  # piece r shares an edge with cell r + 1 below once piece r - 1 is sewn
            self.gm.identify(piece, below[:, r] + _C3)

    def _split_knot_bottoms(self, parts, first) -> None:
        """A new knot's first ring cells that face its slot's bottom wall: bottoms cut like :meth:`_bridge`'s.

        The slot's bottom wall is the top of the host's level under the node
        (the trunk's, or a branch's for a sub-branch), ``s`` half-years older: its cells ``1..s + 1`` meet the knot's first
        ring (the older cones end there, as under a trunk cell), its cell
        ``i + s`` the knot's ring ``i`` (:meth:`_sew_knots`).  So the C1 face
        of each of the knot's first cells that faces the bottom wall (sides
        ``0..m/4 - 1``, where the sew puts them) is cut radially into ``s + 1``
        pieces, and the edges on the slot's two bottom corners too (the side
        walls' first cells have theirs cut by :meth:`_bridge`).
        """
        start = 0
        for ax, t, k, i, _ in parts:
            f = first[start : start + len(t)].astype(np.int64)
            start += len(t)
            if ax.index == 0:
                continue
            br = self.branches[ax.index - 1]
            shift = self.year_shift(self.host(br))  # a branch host's levels are glued by year too
            s = int(shift[br.level]) if 0 < br.level < len(shift) else 0
            new = (t == 0) & (i == 1)
            if s == 0 or not new.any():
                continue
            q = ax.sides // 4
            by_sector = np.full(ax.sides, -1, np.int64)
            by_sector[k[new]] = f[new]
            if np.any(by_sector < 0):
                raise GMapError("a knot's first ring is not complete")
            bottom = by_sector[:q]
            self._split_bottoms(by_sector[np.r_[ax.sides - 1, 0:q]], np.zeros(0, np.int64), bottom, s + 1)

    def _split_bottoms(self, cut_c2: np.ndarray, cut_c4: np.ndarray, split: np.ndarray, pieces: int) -> list[np.ndarray]:
        """Cut the bottom faces (C1) of cubes ``split`` radially into ``pieces`` quads, from the O side out.

        The radial edge of C1 with C2 of each cube of ``cut_c2`` and with C4
        of each of ``cut_c4`` is cut into ``pieces`` (a cube's C2 edge is its
        right neighbour's C4 edge once they are joined: cut once, for both),
        then ``pieces - 1`` chords join the cut points across each face of
        ``split``, whose two radial edges must be cut.  Found by the faces'
        labels, never by coordinates.  Returns, per piece, one dart of it for
        each cube of ``split`` (piece 0 holds the edge shared with the O face).
        """
        gm = self.gm
        c2, c4, o_code = (_prism.face_label_code(x) for x in ("C2", "C4", "O"))
        darts = []
        for cubes, code in ((cut_c2, c2), (cut_c4, c4)):
            cubes = np.asarray(cubes, np.int64)
            if cubes.size:
                walk, _ = gm.face_walk(cubes + _C1)
                edges = walk[:, 0:8:2]
                across = gm.dart_data["face"][gm.alpha[2][edges]]
                if not np.all((across == code).any(axis=1)):
                    raise GMapError("a ring cell's bottom face has lost a radial edge")
                darts.append(edges[np.arange(len(cubes)), np.argmax(across == code, axis=1)])
        if darts:
            self._cut_edges(np.concatenate(darts), np.full(sum(len(d) for d in darts), pieces))
        split = np.asarray(split, np.int64)
        walk, length = gm.face_walk(split + _C1)
        n_edges = 2 * pieces + 2
        if not np.all(length == 2 * n_edges):
            raise GMapError("a ring cell's bottom face does not have its radial edges cut in pieces")
        edges = walk[:, 0 : 2 * n_edges : 2]
        across = gm.dart_data["face"][gm.alpha[2][edges]]
        inner = np.argmax(across == o_code, axis=1)
        rows = np.arange(len(split))
        sub = [edges[rows, inner]] + [edges[rows, (inner + 1 + r) % n_edges] for r in range(1, pieces)]
        for r in range(1, pieces):  # chord r: side vertex r to the facing vertex r on the other side
            gm.split_faces(sub[r], np.full(len(split), 2 * pieces + 1 - 2 * r))
        return sub

    # ------------------------------------------------------------------ roles
    def assign_roles(self) -> None:
        """Tissue, season, ring and width of every cell from its place in its stack (see module doc)."""
        gm, p = self.gm, self.p
        vd = gm.volume_data
        cell = vd["cell"].astype(np.int64)
        axis = vd["axis"].astype(np.int64)
        level = vd["level"].astype(np.int64)
        is_cell = cell > 0
        born_level = np.full(gm.n_volumes, 0, np.int64)
        for ax in self.axes:
            steps = np.array(ax.level_step + [0], np.int64)
            on = is_cell & (axis == ax.index)
            born_level[on] = steps[level[on]]
        disc, disc_year = self._cap_roles(axis, level, cell, born_level)
        q = self.steps - born_level  # half-years the stack has lived
        frozen, lived = self._frozen(axis, level, cell)
        sheath = (axis > 0) & is_cell & ~frozen & np.isin(axis - 1, list(self.dead))  # rings round a dead knot
        q = np.where(frozen, lived, q)  # a dead knot's cells keep the roles they had at its death
        vd["dead"][:] = frozen
        wood = is_cell & ((cell <= q) | disc)
        bark = is_cell & ~wood
        season = np.where(wood & ~disc, (cell - 1) % 2, np.where(disc, EARLY, -1))
        ring = np.where(wood, (cell + 1) // 2, -1)
        year = np.where(wood, np.where(disc, disc_year, born_level // 2 + (cell - 1) // 2), -1)
        bark_layer = np.where(bark, (q + 1) // 2 - (cell - q) + 1, -1)  # 1 = oldest, outermost
        year = np.where(bark, born_level // 2 + bark_layer - 1, year)
        vd["season"][:] = season
        vd["ring"][:] = ring
        vd["year"][:] = np.where(is_cell, year, vd["year"])
        sector = vd["sector"].astype(np.int64)
        width = self._widths(wood, bark, axis, level, sector, cell, ring, season, year, bark_layer)
        width, vd["bark"][:] = self._shed(width, wood, bark & ~frozen, axis, level, sector, cell - q - 1)
        vd["bark"][bark & frozen] = _species.BARK_ENCASED  # a dead knot's bark, kept whole (_kill_branches)
        vd["width"][:] = np.where(is_cell, width, 0.0)
        tissue = vd["wood"]
        y_now = self.year + (1 if self.steps % 2 else 0)  # years begun
        from_bark = y_now - year
        trunk = (axis == 0) | sheath  # the rings laid round a dead knot are the trunk's
        heart = trunk & wood & (from_bark > p["sapwood_rings"]) & (y_now > p["heartwood_age"])
        tissue[trunk & wood] = CODES["sapwood"]
        tissue[heart] = CODES["heartwood"]
        tissue[bark] = CODES["bark"]
        tissue[~trunk & wood] = CODES["knot"]
        for b, (cap, _, died) in self.caps.items():  # a cap's centre: wood of the death year
            old = y_now - died > p["sapwood_rings"] and y_now > p["heartwood_age"]
            tissue[gm.dart_volume[self.branch_axis[b].levels[cap]]] = CODES["heartwood" if old else "sapwood"]
        vd["label"][is_cell] = np.where(bark[is_cell], "K", np.where(season[is_cell] == EARLY, "R", "S"))
        reacts = wood & ((axis == 0) | (tissue == CODES["knot"]))  # not the later rings round a dead knot
        vd["reaction"][:] = _species.reaction_marks(p, axis, sector, reacts, self.trunk.sides)

    def _cap_roles(
        self, axis: np.ndarray, level: np.ndarray, cell: np.ndarray, born_level: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Roles of the cap cells on dead stubs (:meth:`_cap_stub`): ``(disc, year)`` per volume.

        A cap stack's cell ``i`` past the ``c`` it got at death continues
        cell ``i`` of the stub's top level (the same ring, year and role: its
        ``born_level`` is set to the top level's, in place); the ``c`` cells
        of the disc that first covers the stub's end are wood of the death
        year (``disc``; a choice: the first later wood closes the end).
        """
        disc = np.zeros(len(axis), bool)
        year = np.zeros(len(axis), np.int64)
        for b, (cap, c, died) in self.caps.items():
            ax = self.branch_axis[b]
            on = (axis == ax.index) & (level == cap) & (cell > 0)
            born_level[on] = ax.level_step[cap - 1]
            disc |= on & (cell <= c)
            year[on] = died
        return disc, year

    def _shed(self, width, wood, bark, axis, level, sector, depth):
        """Bark widths shed beyond the species' live thickness, and the ``bark`` attribute
        (:func:`ramure.gmap.organs.wood_species.shed_bark`): one id per stack, dense.

        ``bark`` flags the living bark; a dead knot's bark is left out (it keeps its width,
        :meth:`_kill_branches`), so it neither sheds nor shares a stack's layer table with the
        trunk's bark laid over it.
        """
        p = self.p
        sides = np.zeros(len(self.axes), np.int64)
        size = np.zeros(len(self.axes), np.int64)
        for i, ax in enumerate(self.axes):
            sides[i], size[i] = ax.sides, max(len(ax.levels), 1) * ax.sides
        index = np.zeros(max(ax.index for ax in self.axes) + 1, np.int64)
        index[[ax.index for ax in self.axes]] = np.arange(len(self.axes))
        cells = wood | bark
        a = index[np.where(cells, axis, 0)]
        stack = np.where(cells, (np.cumsum(size) - size)[a] + level * sides[a] + sector, 0)
        scale = np.where(axis == 0, 1.0, p["branch_scale"])
        radius = np.bincount(stack[wood], width[wood], minlength=int(size.sum()))
        radius = p["pith_radius"] * scale + radius[stack]
        seeds = np.array([ax.seed for ax in self.axes], np.int64)[a]
        fissure = _species.roughness(p, seeds, axis, level, sector)
        mark = np.full(len(width), _species.BARK_NONE, np.int8)
        kept, mark[bark] = _species.shed_bark(p, stack[bark], depth[bark], width[bark], radius[bark], fissure[bark])
        width = width.copy()
        width[bark] = kept
        return width, mark

    def law(
        self, ring: np.ndarray, season: np.ndarray, sector_angle: np.ndarray | None = None, axis: int = 0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bounds ``(lo, hi)`` of the width law for cambial ring numbers ``ring`` (arrays)."""
        p = self.p
        ring = np.asarray(ring, float)
        f = np.maximum(p["width_floor"], np.exp(-(ring - 1) / p["decay"]))
        early = np.asarray(season) == EARLY
        lo = np.where(early, p["early_min"], p["late_min"]) * f
        hi = np.where(early, p["early_max"], p["late_max"]) * f
        scale = np.where(np.asarray(axis) == 0, 1.0, p["branch_scale"])
        if sector_angle is not None:
            scale = scale * (
                1.0
                + p["reaction"]
                * np.maximum(0.0, np.cos(np.asarray(sector_angle) - math.radians(p["reaction_angle"])))
                * (np.asarray(axis) == 0)
            )
        return lo * scale, hi * scale

    def _widths(self, wood, bark, axis, level, sector, cell, ring, season, year, bark_layer):
        p = self.p
        by_index = np.zeros(max(ax.index for ax in self.axes) + 1, np.int64)
        by_index[[ax.index for ax in self.axes]] = [ax.seed for ax in self.axes]
        seeds = by_index[np.maximum(axis, 0)]
        n = np.where(axis == 0, self.trunk.sides, int(p["branch_sides"]))
        angle = 2 * np.pi * sector / n
        lo, hi = self.law(np.maximum(ring, 1), np.maximum(season, 0), angle, axis)
        u_wood = 0.6 * u01_array(seeds, 5, year, season) + 0.4 * u01_array(seeds, 6, level, sector, cell)
        u_bark = u01_array(seeds, 7, level, sector, bark_layer)
        bark_scale = np.where(axis == 0, 1.0, p["branch_scale"])
        w_bark = bark_scale * (p["bark_min"] + (p["bark_max"] - p["bark_min"]) * u_bark)
        return np.where(wood, lo + (hi - lo) * u_wood, np.where(bark, w_bark, 0.0))

    # ------------------------------------------------------------------ embedding
    def level_frames(self, ax: Axis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(origins, frames, heights)`` of the axis's levels (rows H, L, U); kept for the step."""
        key = (ax.index, len(ax.levels), self.steps)
        memo = self.__dict__.setdefault("_frames_memo", {})
        if key not in memo:
            if len(memo) > 4 * len(self.axes) + 8:
                memo.clear()
            memo[key] = self._level_frames(ax)
        return memo[key]

    def _level_frames(self, ax):
        p = self.p
        n_levels = len(ax.levels)
        if ax.index == 0:
            yo, yf, yh = self.year_frames()
            parts = ax.parts[:n_levels]
            year = np.array([y for y, _ in parts], np.int64)
            kind = np.array([_PARTS[part] for _, part in parts], np.int64)
            node = np.minimum(self.node_height(), 0.5 * yh[year])  # one row per level, all levels at once
            o, f = yo[year], yf[year]  # copies (fancy indexing)
            h = np.where(kind == 0, yh[year], np.where(kind == 1, node, yh[year] - node))
            inter = kind == 2
            o[inter] = yo[year[inter]] + node[inter, None] * yf[year[inter], 0]
            return o, f, h
        br = self.branches[ax.index - 1]
        p0, knot = self.branch_frame(br, knot=True)
        _, frame = self.branch_frame(br)
        h = np.full(n_levels, p["branch_length"])
        kind = np.array([_PARTS[part] for _, part in ax.parts[:n_levels]], np.int64)
        if np.any(kind > 0):  # a year with sub-branches: a short node, then the rest of the year's length
            short = self.branch_node_height()
            h = np.where(kind == 1, short, np.where(kind == 2, p["branch_length"] - short, h))
        if n_levels:  # the first level spans the host's final radius: the knot
            h[0] = self.knot_length(br)
        s = np.concatenate([[0.0], np.cumsum(h)[:-1]])
        origins = p0 + h[0] * knot[0] + (s - h[0])[:, None] * frame[0][None]
        bender = self.knot_bender(br)
        if bender is not None:  # the branch goes on from the bent knot's end
            end = p0 + h[0] * knot[0]
            origins += bender(end) - end
        origins[0] = p0
        frames = np.repeat(frame[None], n_levels, axis=0)
        frames[0] = knot
        return origins, frames, h

    def trunk_radius(self) -> float:
        """The trunk's radius at its base after the final year, from the law's mean widths."""
        if self.final_years is not None and "_radius" in self.__dict__:
            return self._radius
        self._radius = self._trunk_radius()
        return self._radius

    def _trunk_radius(self):
        p = self.p
        years = self.final_years or (self.year + 1)
        rings = np.arange(1, years + 1)
        lo_e, hi_e = self.law(rings, np.zeros_like(rings), None, 0)
        lo_l, hi_l = self.law(rings, np.ones_like(rings), None, 0)
        wood = p["pith_radius"] + 0.5 * (lo_e + hi_e + lo_l + hi_l).sum()
        return float(wood + _species.nominal_bark(p, years, wood))

    def year_frames(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(origins, frames, heights)`` of the trunk's yearly growth units (straight, or a plant's)."""
        if self.trunk_frames is not None:
            return self.trunk_frames
        p = self.p
        years = max(self.final_years or 0, self.year + 1)
        jit = p["height_jitter"]
        key = (years, p["height"], jit, self.trunk.seed)
        memo = self.__dict__.get("_year_frames_memo")
        if memo is not None and memo[0] == key:
            return memo[1]
        h = np.array([p["height"] * (1 + jit * (2 * _u01(self.trunk.seed, 8, y) - 1)) for y in range(years)])
        o = np.zeros((years, 3))
        o[:, 2] = np.concatenate([[0.0], np.cumsum(h)[:-1]])
        out = (o, np.repeat(np.eye(3)[[2, 0, 1]][None], years, axis=0), h)
        for a in out:  # kept (read-only) while the key holds
            a.flags.writeable = False
        self._year_frames_memo = (key, out)
        return out

    def node_height(self) -> float:
        """Height of a node carrying branches: the branches' final base diameter and a margin."""
        if not self.branches:
            return 0.0
        if self.final_years is not None and "_node" in self.__dict__:
            return self._node
        years = self.final_years or (self.year + 1)
        probe = Branch(0, 0, 0)
        self._node = 1.6 * float(self.nominal_radius(probe, np.zeros(1), years)[0])
        return self._node

    def branch_node_height(self) -> float:
        """Height of a node a branch grows in a year with sub-branches: the trunk's node height
        (:meth:`node_height`), at most half a year's ``branch_length`` (a choice: one rule for every order)."""
        return min(self.node_height(), 0.5 * float(self.p["branch_length"]))

    @staticmethod
    def sector_centre(ax: Axis, k: int) -> float:
        """Angle of the middle of sector ``k`` of an axis (see :meth:`sector_angles`)."""
        if ax.index == 0:
            return 2 * np.pi * k / ax.sides
        return 2 * np.pi * (k + 0.5 - ax.sides / 8) / ax.sides

    def pith_apothem(self, ax: Axis) -> float:
        """Apothem of an axis's pith prisms (a branch's is ``branch_scale`` times the trunk's)."""
        return float(self.p["pith_radius"] * (1.0 if ax.index == 0 else self.p["branch_scale"]))

    def branch_frame(self, br: Branch, knot: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Base point (centre of the trunk face) and frame (H along the branch) of a branch.

        With ``knot``, the frame of its first level inside the trunk: its rise
        is capped at ``KNOT_RISE`` degrees (a steep branch's knot would
        otherwise run along the trunk, far out of its node's slot); the
        branch turns to its own direction where the knot ends.  Kept while
        the trunk level it stands on keeps its frame (an embedding asks for
        each frame several times, and every step); the arrays returned are
        read-only.
        """
        p = self.p
        host = self.host(br)
        o, f, h = self.level_frames(host)
        t = br.level  # the frame reads only the host's level t: kept while that level stays as it is
        level = (o[t].tobytes(), f[t].tobytes(), float(h[t]), host.sides, host.index)
        key = (level, br.level, br.sector, br.angle, bool(knot), p["pith_radius"], p["branch_angle"], self.KNOT_RISE)
        memo = self.__dict__.setdefault("_branch_frames_memo", {})
        hit = memo.get(key)
        if hit is None:
            if len(memo) > 2 * len(self.branches) + 8:
                memo.clear()
            hit = memo[key] = self._branch_frame(br, knot)
            for a in hit:
                a.flags.writeable = False
        return hit

    def _branch_frame(self, br, knot):
        p = self.p
        host = self.host(br)
        o, f, h = self.level_frames(host)
        phi = self.sector_centre(host, br.sector)
        t = br.level
        radial = math.cos(phi) * f[t, 1] + math.sin(phi) * f[t, 2]
        p0 = o[t] + 0.5 * h[t] * f[t, 0] + self.pith_apothem(host) * radial
        elev = math.radians(90.0 - (p["branch_angle"] if br.angle is None else br.angle))
        if knot:
            elev = max(min(elev, math.radians(self.KNOT_RISE)), -math.radians(self.KNOT_RISE))
        return p0, branch_direction(f[t], phi, elev)

    def default_corners(self) -> tuple[np.ndarray, np.ndarray]:
        """Default corners of every volume, flat: ``(points (sum 2n, 3), offset per volume)``."""
        gm = self.gm
        vd = gm.volume_data
        n_corners = 2 * vd["degree"].astype(np.int64)
        offset = np.concatenate([[0], np.cumsum(n_corners)[:-1]])
        flat = np.zeros((int(n_corners.sum()), 3))
        radii = self._radii()
        profiles = self._knot_profiles(radii)
        for ax in self.axes:  # one step per axis, not per volume
            o, f, h = self.level_frames(ax)
            rp = self.p["pith_radius"] * (1.0 if ax.index == 0 else self.p["branch_scale"])
            n = ax.sides
            theta = self.sector_angles(ax)
            pith = gm.dart_volume[np.array(ax.levels, np.int64)].astype(np.int64)
            pith_pts = self._pith_points(o, f, h, theta[:n], rp, n)
            bender = self.knot_bender(self.branches[ax.index - 1]) if ax.index > 0 else None
            if ax.index > 0 and len(ax.levels):  # the knot's end keeps the trunk's apothem on its upper side
                pith_pts[0, n:] = self._level_knot_end(self.branches[ax.index - 1], pith_pts[0, n:])
            if bender is not None:  # the knot (level 0) is curved
                pith_pts[0] = bender(pith_pts[0])
            flat[offset[pith][:, None] + np.arange(2 * n)[None, :]] = pith_pts
            cells = np.flatnonzero((vd["axis"] == ax.index) & (vd["cell"] > 0))
            if not cells.size:
                continue
            t, k = vd["level"][cells].astype(int), vd["sector"][cells].astype(int)
            r_in, r_out = radii[cells] - vd["width"][cells], radii[cells]
            bottom, top = self._tapers(ax, cells, t, k, radii, rp)
            pts = self._cube_points(o, f, h, t, k, theta, r_in, r_out, n, bottom=bottom, top=top)
            if ax.index == 0 and len(self.axes) > 1 and self.bend_rings:
                pts = self._push(pts, t, profiles)
                self._close_under_knots(ax, cells, pts, radii, profiles)
            elif ax.index > 0 and self.bend_rings and any(c.parent == ax.index - 1 for c in self.branches):
                outside = t > 0  # a sub-branch's slot lies in a node past the knot: the knot is not pushed
                pts[outside] = self._push(pts[outside], t[outside], profiles, ax)
                self._close_under_knots(ax, cells, pts, radii, profiles)
            if ax.index > 0 and ax.index - 1 in profiles:
                pts = self._seat_knot(ax, cells, pts, radii, profiles[ax.index - 1])
            if ax.index > 0:
                knot = np.flatnonzero(t == 0)
                ends = [2, 3, 6, 7]
                pts[knot[:, None], ends] = self._level_knot_end(self.branches[ax.index - 1], pts[knot[:, None], ends])
            if bender is not None:
                knot = t == 0
                pts[knot] = bender(pts[knot])
            if ax.index - 1 in self.caps:  # a dead stub's cap closes over its end
                self._cap_corners(ax.index - 1, cells, t, k, pts, pith_pts)
                flat[offset[pith][:, None] + np.arange(2 * n)[None, :]] = pith_pts
            _put_blocks(flat, offset[cells], pts)
        return flat, offset

    #: radius of the channel the cap's rings leave on a dead stub's axis, over the stub's end radius
    CAP_CHANNEL = 0.1

    def _cap_corners(
        self, b: int, cells: np.ndarray, t: np.ndarray, k: np.ndarray, pts: np.ndarray, pith_pts: np.ndarray
    ) -> None:
        """Corners of dead stub ``b``'s cap (:meth:`_cap_stub`), in place in ``pts`` and ``pith_pts``.

        The cap's bottom corners are the stub's end corners (its top level's
        top corners, as drawn).  A top corner is its bottom corner lifted
        along the stub's axis: a point at radius ``r`` from the axis goes to
        height ``w + max(r - R, 0)`` over the end and radius ``rho min(r /
        R, 1)`` (``R`` the stub's radius at its end, ``w`` a mean earlywood
        width, ``rho = CAP_CHANNEL R``).  So the disc laid at death covers
        the end, and every later ring (radius ``r > R`` on the stub's side)
        turns over the end on a cone and runs in to the axis: in a cut along
        the stub the rings laid after death close over its end, nested.  A
        choice: each cap stack is one column of cells, so each ring reaches
        the boundary on a thin channel of radius ``rho`` round the axis (a
        scar over the stub) instead of closing on the axis itself.
        """
        cap, c, _ = self.caps[b]
        top = cap - 1
        n = pith_pts.shape[1] // 2
        cell = self.gm.volume_data["cell"][cells].astype(np.int64)
        end = pith_pts[top, n:]
        centre = end.mean(axis=0)
        along = centre - pith_pts[top, :n].mean(axis=0)
        along /= np.linalg.norm(along)
        on_top, on_cap = np.flatnonzero(t == top), np.flatnonzero(t == cap)
        depth = int(cell[on_cap].max(initial=0))
        if not on_cap.size or depth < 1:
            return
        table = np.zeros((n, depth + 1, 4, 3))  # the top level's top corners 3, 2, 7, 6 per (sector, cell)
        sel = on_top[cell[on_top] <= depth]
        table[k[sel], cell[sel]] = pts[sel][:, [3, 2, 7, 6]]

        def radius(points):
            rel = points - centre
            return np.linalg.norm(rel - (rel @ along)[..., None] * along, axis=-1)

        r_end = float(radius(table[:, min(c, depth), 2:]).mean()) if c > 0 else float(radius(end).mean())
        width = 0.5 * (self.p["early_min"] + self.p["early_max"])
        rho = self.CAP_CHANNEL * r_end

        def lift(points):
            rel = points - centre
            h = rel @ along
            radial = rel - h[..., None] * along
            r = np.maximum(np.linalg.norm(radial, axis=-1), 1e-300)
            up = h + width + np.maximum(r - r_end, 0.0)
            return centre + up[..., None] * along + (rho * np.minimum(r / r_end, 1.0) / r)[..., None] * radial

        bottom = table[k[on_cap], cell[on_cap]]
        pts[on_cap[:, None], [0, 1, 4, 5]] = bottom
        pts[on_cap[:, None], [3, 2, 7, 6]] = lift(bottom)
        pith_pts[cap, :n] = end
        pith_pts[cap, n:] = lift(end)

    @staticmethod
    def sector_angles(ax: Axis) -> np.ndarray:
        """Angles of the corners of an axis's sectors, ``n + 1`` values (the last closes the turn).

        The trunk's sector ``k`` spans ``2 pi (k -+ 1/2) / n``.  A branch's
        corner ``v`` is at ``2 pi v / m - pi / 4``: its corners ``0, m/4, m/2,
        3m/4`` (where the walls of its slot meet) lie on the diagonals, so
        each wall faces a quarter of the knot, centred on it (for ``m = 4``
        both rules agree).
        """
        n = ax.sides
        shift = 0.5 if ax.index == 0 else n / 8
        return 2 * np.pi * (np.arange(n + 1) - shift) / n

    def _knot_profiles(self, radii):
        """Per branch, ``(s_j, rho_j, a_j, lateral_j)``, ``j = 0..N``: where slot layer ``j`` meets the knot.

        The trunk's ring ``j`` around the slot ends at apothem ``a_j`` (mean
        over the slot's wall stacks); along the branch that is at ``s_j = (a_j
        - r_p) / cos(elevation)``; ``rho_j`` is the knot's ring ``j`` apothem
        from the law's mean widths (:meth:`_nominal_rings`), so the seam, and
        the trunk bent around it, do not depend on the branch's seed.  Two
        knots of one node ``d`` sectors apart share the ring between them:
        each keeps its width across the trunk (``lateral_j`` scales it) under
        ``KNOT_ROOM d a_j tan(pi / n)``, so their walls never cross; knots in
        adjacent sectors (no wall between) both end on their common corner
        line (``d a_j tan(pi / n)``).
        """
        gm = self.gm
        out = {}
        for b, br in enumerate(self.branches):
            if b not in self._sewn_layers:
                continue
            trunk = self.host(br)  # the trunk, or the branch a sub-branch grows on
            n = trunk.sides
            rp = self.pith_apothem(trunk)
            shift = self.year_shift(trunk)
            _, f_t, _ = self.level_frames(trunk)
            ax = self.branch_axis[b]
            t, k = br.level, br.sector
            depth = int(ax.count[0].max())
            a, used = np.zeros(depth + 1), np.zeros(depth + 1)
            s = int(shift[t]) if 0 < t < len(shift) else 0
            for tt, kk in ((t, (k - 1) % n), (t, (k + 1) % n), (t - 1, k), (t + 1, k)):
                if 0 <= tt < len(trunk.levels) and trunk.alive[tt, kk]:
                    off = s if tt == t - 1 else 0  # the bottom wall meets the knot by year
                    c = max(min(int(trunk.count[tt, kk]) - off, depth), 0)
                    a[1 : c + 1] += radii[gm.dart_volume[trunk.cells[tt, kk, off : off + c]]]
                    used[1 : c + 1] += 1
            a[0], used[0] = rp, 1
            a /= np.maximum(used, 1)
            for j in range(1, depth + 1):  # layers no wall reaches: continue outwards
                if used[j] == 0:
                    a[j] = a[j - 1] + (a[j - 1] - a[j - 2] if j > 1 else rp)
            rho = self._nominal_rings(ax, depth)
            _, f, h = self.level_frames(ax)
            phi = self.sector_centre(trunk, k)
            cos_elev = abs(f[0, 0] @ (math.cos(phi) * f_t[t, 1] + math.sin(phi) * f_t[t, 2]))
            gap = min(
                [
                    min((k - o.sector) % n, (o.sector - k) % n)
                    for c, o in enumerate(self.branches)
                    if c != b and c in self._sewn_layers and o.level == t and o.parent == br.parent
                ]
                or [n]
            )
            room = (1.0 if gap == 1 else self.KNOT_ROOM) * gap * math.tan(math.pi / n) * a  # 1: meet on the line
            lateral = np.minimum(1.0, room / np.maximum(rho, 1e-12))
            out[b] = (np.minimum(self._bent_s(br, a - rp, cos_elev), 0.95 * h[0]), rho, a, lateral)
        return out

    def _nominal_rings(self, ax, depth):
        """Apothems ``rho_0..rho_depth`` of the first level of branch axis ``ax`` from the law's means.

        Cells ``1..q`` are wood (``q`` half-years lived), the rest bark, as
        :meth:`assign_roles` reads them; no random draw is involved.  A dead
        knot's bark keeps its mean width (:meth:`_kill_branches`); the living
        bark outside it (the trunk's, over the stub) is shed on its own, its
        newest layer first: shed after the dead knot's bark, it was drawn 50
        um thin where the trunk's bark layers are about a millimetre apart,
        and its cells turned over.
        """
        p = self.p
        cell = np.arange(1, depth + 1)
        q = np.full(depth, self.steps - ax.level_step[0])
        encased = np.zeros(depth, bool)
        if ax.index - 1 in self.dead:  # a dead knot's cells keep their roles (bark stays bark)
            q_d, n_d = self.dead[ax.index - 1]
            q = np.where(cell <= n_d[0], q_d[0], q)
            encased = (cell > q) & (cell <= n_d[0])  # its bark, kept whole (_kill_branches)
        lo, hi = self.law((cell + 1) // 2, (cell - 1) % 2, None, 1)
        bark = p["branch_scale"] * 0.5 * (p["bark_min"] + p["bark_max"])
        width = np.where(cell <= q, 0.5 * (lo + hi), bark)
        wood = cell <= q  # the living bark past the species' live thickness is shed (wood_species)
        live = ~wood & ~encased
        cap = float(_species.bark_cap(p, p["pith_radius"] * p["branch_scale"] + width[wood].sum()))
        width[live] = _species.shed_profile(width[live], cap)
        return p["pith_radius"] * p["branch_scale"] + np.concatenate([[0.0], np.cumsum(width)])

    def _seat_knot(self, ax, cells, pts, radii, profile):
        """Bottom corners of a knot's ring cells: ring ``i`` starts on the slot wall's layer ``i``.

        Cell ``i``'s C1 face (sewn to wall layer ``i``) runs from ``(s_{i-1},
        rho_{i-1})`` to ``(s_i, rho_i)`` (:meth:`_knot_profiles`; its far end
        keeps the cell's own widths): nested cups, the knot a cone of the
        branch's rings.  Knot volumes are ``exclusive`` (the thesis's ``seulPourPl``),
        so the walls' vertices take these positions.
        """
        vd = self.gm.volume_data
        level0 = np.flatnonzero(vd["level"][cells] == 0)
        if not level0.size:
            return pts
        s_layer, rho_layer, lateral = profile[0], profile[1], profile[3]
        _, f, _ = self.level_frames(ax)
        p0, frame = self.branch_frame(self.branches[ax.index - 1], knot=True)
        sel = cells[level0]
        i = np.minimum(vd["cell"][sel].astype(np.int64), len(s_layer) - 1)
        m = ax.sides
        c = 1.0 / math.cos(math.pi / m)
        theta = self.sector_angles(ax)
        kk = vd["sector"][sel].astype(np.int64)
        br = self.branches[ax.index - 1]
        edge = np.arange(m + 1)
        layer = np.arange(len(s_layer))
        down = c * rho_layer[:, None] * np.cos(theta[edge])[None, :]  # (layers, edges)
        s_seat = self._level_seam(br, frame, np.repeat(s_layer[:, None], m + 1, 1), down, self._outer_weight(br, layer)[:, None])
        squeeze = np.hypot(np.cos(theta[edge])[None, :], lateral[:, None] * np.sin(theta[edge])[None, :])
        s_seat = self._clear_of_tops(br, frame, pts[level0], i, kk, s_seat, c * rho_layer[:, None] * squeeze)
        out = pts.copy()
        for corner, e, j in ((0, kk, i - 1), (1, kk + 1, i - 1), (4, kk, i), (5, kk + 1, i)):
            r = rho_layer[j]
            th = theta[e]
            radial = np.cos(th)[:, None] * f[0, 1] + (lateral[j] * np.sin(th))[:, None] * f[0, 2]
            out[level0, corner] = p0 + s_seat[j, e][:, None] * frame[0] + (c * r)[:, None] * radial
        return out

    #: the most of its room a knot ring's seat point may slide towards the level's end (``_clear_of_tops``)
    SEAT_ROOM = 0.5

    def _clear_of_tops(
        self,
        br: Branch,
        frame: np.ndarray,
        pts: np.ndarray,
        cell: np.ndarray,
        sector: np.ndarray,
        s_seat: np.ndarray,
        radius: np.ndarray,
    ) -> np.ndarray:
        """The seam's positions ``s_seat`` (layers, edges) along the knot, held so no knot ring turns over.

        A ring cell of the knot's first level runs from its seat on the slot
        wall (:meth:`_seat_knot`) to the level's end, where its radii are
        the knot's own (drawn) widths, not the nominal ``rho_j`` of the seat:
        a ring's face rises (or sinks) between the two.  On the knot's upper
        side :meth:`_level_seam` slides the seat of the outer layers along
        the knot by up to ``|down| tan(e)`` (some centimetres), ramped over
        ``LEVEL_RAMP`` layers, so each layer's seat lies millimetres past the
        one inside it while the rings are 0.2 mm apart: where the inner face
        rises towards the end, the outer seat lay under it (issue 39: 5 bark
        cells of the last ring of the lowest whorl's knot of a 30-year pine
        inside out).  A choice: from the pith out, layer ``j``'s seat may go
        at most ``SEAT_ROOM`` of the way along layer ``j - 1``'s face that
        keeps it outside that face (in the knot's straight frame, radius
        across its axis, the end's corners as :meth:`_level_knot_end` puts
        them); the seat never moves out, only back towards the pith, so the
        trunk's walls (which take the knot's positions) only fold less.
        ``pts``: the corners of the level-0 cells, with their ``cell`` and
        ``sector``; ``radius``: the seat's distance from the knot's axis (layers, edges).
        """
        p0 = self.branch_frame(br, knot=True)[0]
        n_layers, n_edges = s_seat.shape
        ends = self._level_knot_end(br, pts[:, [3, 2, 7, 6]])  # top corners: inner (kk, kk+1), outer
        rel = ends - p0
        along = rel @ frame[0]
        across = np.linalg.norm(rel - along[..., None] * frame[0], axis=-1)
        top_s = np.full((n_layers, n_edges), np.nan)
        top_r = np.full((n_layers, n_edges), np.nan)
        j = np.minimum(cell, n_layers - 1)
        for col, lay, e in ((0, j - 1, sector), (1, j - 1, sector + 1), (2, j, sector), (3, j, sector + 1)):
            top_s[lay, e], top_r[lay, e] = along[:, col], across[:, col]
        s = s_seat.copy()
        for jj in range(1, n_layers):  # outwards: each layer's bound rests on the (held) layer inside it
            rise = top_r[jj - 1] - radius[jj - 1]
            room = top_s[jj - 1] - s[jj - 1]
            gain = radius[jj] - radius[jj - 1]
            bound = s[jj - 1] + self.SEAT_ROOM * room * gain / np.where(rise > 0, rise, np.inf)
            ok = (rise > 0) & (room > 0) & np.isfinite(bound)
            s[jj] = np.where(ok, np.minimum(s[jj], np.maximum(bound, s[jj - 1])), s[jj])
        return s

    #: slot layers (half-years) over which the seam goes from following the knot's section to
    #: following the trunk's rings, under the knot's outer wood (see ``_level_seam``)
    LEVEL_RAMP = 6

    def _outer_weight(self, br: Branch, j: np.ndarray) -> np.ndarray:
        """0 for the knot's inner slot layers, 1 from its outer wood layer out (bark), linear over ``LEVEL_RAMP``.

        A dead knot keeps the ramp it had at its death (its cells keep their
        places; the rings laid round it after are all at weight 1).
        """
        b = self.branches.index(br)
        q = self.steps - self.branch_axis[b].level_step[0]  # wood layers of the knot and its node's walls
        if b in self.dead:
            q = int(self.dead[b][0][0])
        return np.clip((np.asarray(j, float) - (q - self.LEVEL_RAMP)) / self.LEVEL_RAMP, 0.0, 1.0)

    def _level_shift(self, br: Branch, frame: np.ndarray, s: np.ndarray, down: np.ndarray) -> np.ndarray:
        """How far along the knot a point ``down`` off its axis (towards the trunk's base) at ``s`` goes to
        keep the trunk apothem of its axis point: ``-down tan(e)`` on the knot's upper side (``down < 0``),
        ``e`` the knot's local elevation (the bent knot's, ``e + KNOT_BEND (1 - s / h)``); 0 below it."""
        _, f, _ = self.level_frames(self.trunk)
        e = math.asin(float(np.clip(frame[0] @ f[br.level, 0], -0.99, 0.99)))
        h0 = self.knot_length(br)
        local = e + math.radians(self.KNOT_BEND) * (1 - np.clip(np.asarray(s, float), 0.0, h0) / h0)
        return -np.minimum(np.asarray(down, float), 0.0) * np.tan(np.clip(local, 0.0, 1.2))

    def _level_seam(self, br: Branch, frame: np.ndarray, s: np.ndarray, down: np.ndarray, weight: np.ndarray) -> np.ndarray:
        """Where along the knot a seam point ``down`` off its axis (towards the trunk's base) meets its ring.

        Slot layer ``j`` is where the trunk's ring ``j`` (apothem ``a_j``)
        meets the knot, at ``s_j`` along the knot's axis.  A point off the
        axis, across a rising knot, lies nearer the trunk's pith than the
        axis point on the knot's upper side, by ``|down| sin(e)``: on a
        knot's section the trunk's ring sags into the trunk above the knot,
        which is how the inner rings deflect round a knot in a flat-sawn
        board.  The outer rings and the bark must not sag (the upper wall's
        outer bark would lie inside the wood, a wedge of bark over the knot
        in boards): with ``weight`` 1 the point goes :meth:`_level_shift`
        along the knot so the ring keeps its apothem where it meets the
        knot's upper side (a choice: ``weight`` ramps from 0 to 1 over the
        ``LEVEL_RAMP`` layers under the knot's outer wood,
        :meth:`_outer_weight`; the lower side bulges out as before, a collar,
        and is left as it is: the bottom wall's outer bark closes under it,
        :meth:`_close_under_knots`).  The knot's end is moved out with it
        (:meth:`_level_knot_end`), and a seam point goes no farther than
        the end's shift past ``0.95 h`` (the seam's old cap), so it never
        passes the end.
        """
        s = np.asarray(s, float)
        h0 = self.knot_length(br)
        end = np.maximum(s, 0.95 * h0) + self._level_shift(br, frame, np.full(s.shape, h0), down)  # the end's shift
        return s + np.minimum(self._level_shift(br, frame, s, down), end - s) * weight

    def _level_knot_end(self, br: Branch, points: np.ndarray) -> np.ndarray:
        """The knot's end corners (straight, before the bend) moved out along the knot on its upper side.

        The knot's first level ends on a section square to its axis at
        ``h`` past the trunk's final radius; on a rising knot that section's
        upper edge lies inside the trunk, and the upper wall's bark, sewn to
        the knot's bark there, would follow it in.  Each end corner goes
        :meth:`_level_shift` (at ``s = h``) along the knot, so the end's
        upper edge keeps the apothem of the knot's axis end.
        """
        p0, frame = self.branch_frame(br, knot=True)
        rel = np.asarray(points, float) - p0
        down = rel @ frame[1]
        shift = self._level_shift(br, frame, np.full(down.shape, self.knot_length(br)), down)
        return points + shift[..., None] * frame[0]

    def _radii(self):
        """Outer apothem of every cell: pith radius plus the widths of its stack up to it."""
        vd = self.gm.volume_data
        cell = vd["cell"].astype(np.int64)
        is_cell = cell > 0
        key = (vd["axis"].astype(np.int64) * 4096 + vd["level"]) * 4096 + vd["sector"]
        order = np.lexsort((cell, key))
        order = order[is_cell[order]]
        w = vd["width"][order]
        k = key[order]
        csum = np.cumsum(w)
        start = np.ones(len(k), bool)
        start[1:] = k[1:] != k[:-1]
        base = np.maximum.accumulate(np.where(start, np.arange(len(k)), 0))
        offset = csum - np.concatenate([[0.0], csum])[base]
        out = np.zeros(len(cell))
        rp = np.where(vd["axis"] == 0, self.p["pith_radius"], self.p["pith_radius"] * self.p["branch_scale"])
        out[order] = rp[order] + offset
        return out

    @staticmethod
    def _pith_points(o, f, h, theta, rp, n):
        """:meth:`_ring_points` of every level at once (same arithmetic): ``(levels, 2n, 3)``."""
        c = 1.0 / math.cos(math.pi / n)
        radial = np.cos(theta)[None, :, None] * f[:, 1][:, None, :] + np.sin(theta)[None, :, None] * f[:, 2][:, None, :]
        bottom = o[:, None, :] + (c * rp) * radial
        return np.concatenate([bottom, bottom + h[:, None, None] * f[:, 0][:, None, :]], axis=1)

    @staticmethod
    def _ring_points(o, f, h, theta, r_bottom, r_top, n):
        c = 1.0 / math.cos(math.pi / n)
        radial = np.cos(theta)[:, None] * f[1][None] + np.sin(theta)[:, None] * f[2][None]
        bottom = o[None] + (c * r_bottom)[:, None] * radial
        return np.concatenate([bottom, bottom + h * f[0][None]])

    #: how much of a stack's step is left where the stack above ends (the taper of a level's top)
    TAPER = 0.12
    #: share of the half-gap to the next knot of the same node a knot may fill across the trunk
    KNOT_ROOM = 0.8
    #: half-side of the square the trunk makes room for around a round knot, over the knot's radius
    KNOT_HULL = 1.3
    #: how much steeper (degrees) a knot leaves the pith than it meets the bark: the branch bends in it
    KNOT_BEND = 15.0
    #: steepest rise of a knot inside the trunk (degrees above the horizontal)
    KNOT_RISE = 35.0
    #: share of a knot's push reach next to its slot where the trunk's corners follow the knot's
    #: seam rather than their rings' circles (:meth:`_on_ring`)
    RING_FREE = 0.5

    def _tapers(self, ax, cells, t, k, radii, rp):
        """Radius maps for the bottom and top corners of ``cells`` (the thesis's wedges, geometrically).

        A stack holds one year's cells more than the stack above it.  Where
        the level above is glued cell to cell (:meth:`year_shift` 0), those
        are its outer cells: their top corners are drawn in towards the
        radius where the stack above ends (``R + TAPER (r - R)``), so each
        level tapers into the next and the apex closes, instead of leaving
        flat steps.  Where the level above is glued by year (shift ``s``),
        this stack's cells ``1..s`` were laid before the level above existed
        and their growth cones end at the boundary: their top corners (and
        the inner top corner of cell ``s + 1``) are drawn in to the pith,
        ``r_p + TAPER (r - r_p)`` (the cone's apex), and only the cells past
        the ``count + s`` the level above meets (its oldest bark) taper as
        before.  A year split in a node and an internode spreads its taper
        over both (:meth:`_year_spread`); other bottom corners keep their
        radii; a knot's bottom corners are set by :meth:`_seat_knot`.  Both
        maps take ``(r, outer)``, ``outer`` for a cell's outer corners.
        Topology is unchanged.
        """
        vd = self.gm.volume_data
        cell = vd["cell"][cells].astype(np.int64)
        n_levels, n = len(ax.levels), ax.sides
        count = np.zeros((n_levels + 1, n), np.int64)  # cells per stack; a slot never tapers
        count[: len(ax.count)] = np.where(ax.alive, ax.count, 10**6)
        shift = np.zeros(n_levels + 1, np.int64)
        shift[:n_levels] = self.year_shift(ax)
        s_up = np.where(count[t + 1, k] > 0, shift[t + 1], 0)
        above = count[t + 1, k] + s_up  # the cells of this stack the level above meets
        table = np.full((n_levels, n, int(cell.max()) + 1), rp)
        table[t, k, cell] = radii[cells]
        m = np.minimum(above, cell)
        base = np.where(m > 0, table[t, k, np.maximum(m, 0)], rp)
        exposed = cell > above
        # where the trunk's level above goes on, the stack's outer corner at the boundary is the
        # average of its cell m's top and the level above's outermost cell's bottom (embed): close
        # onto that.  Next to a knot's slot too (issue 39): left at its own radius there, that
        # vertex's average leant on the older level's corners (4 of 6 volumes) while the one inside
        # it had both levels' evenly, so it sank inside it by a sixth of the levels' step, more
        # than a shed bark cell is wide (50 um): 4 such cells inside out under a pine's whorl.
        up = np.minimum(t + 1, n_levels - 1)
        goes_on = (ax.index == 0) & (t + 1 < n_levels) & (count[t + 1, k] > 0) & (m > s_up)
        goes_on &= ax.alive[up, k]
        upper = table[up, k, np.clip(m - s_up, 0, table.shape[2] - 1)]
        base = np.where(exposed & goes_on, 0.5 * (base + upper), base)
        eps = self.TAPER
        apex = table[t, k, np.minimum(s_up, table.shape[2] - 1)]  # outer radius of cell s
        apex_tol = 1e-9 * np.maximum(apex, 1.0)

        spread = self._year_spread(ax, t, k, cell, table, count, shift, rp)

        def bottom(r, outer):
            return spread(r, outer, 0)

        def top(r, outer):
            r = spread(r, outer, 1)
            out = np.where(exposed, base + eps * (r - base), r)
            cone = (s_up > 0) & (r <= apex + apex_tol)  # a cone that ends here: to the pith
            return np.where(cone, rp + eps * (r - rp), out)

        return bottom, top

    def _year_spread(self, ax, t, k, cell, table, count, shift, rp):
        """Radius map ``(r, outer, end) -> r'`` that spreads a year's taper over its node and internode.

        A year that carries knots is two levels: a short node (the slot's
        height) and the internode above it, glued cell to cell (same year).
        A level boundary's vertex is the average of the corners that meet
        there (:meth:`embed`): a ring whose radius is ``r_n`` in the node
        and ``r_i`` in the internode (their widths are drawn apart), ``A`` in
        the level below (its cell ``i + s``, glued by year) and ``U`` in the
        level above the internode is at ``B0 = (A + r_n) / 2`` at the node's
        bottom and at ``B1 = (r_i + U) / 2`` at the internode's top.  Left
        alone, the node's top would sit at ``(r_n + r_i) / 2``, so the node
        would take half the year's change within its few centimetres and
        kink every ring of a flat-sawn board at each whorl.  Instead the
        node's top corners and the internode's bottom ones are both at ``B0
        + f (B1 - B0)``, ``f`` the node's share of the year's height: the
        ring runs linearly over the whole year.  ``end`` is 0 for bottom
        corners, 1 for top ones; ``outer`` tells a cell's outer corners from
        its inner ones.  Every axis (a branch carrying sub-branches has
        node years too); other levels, and stacks the levels around cannot
        match or that flank a slot, keep ``r`` (the apex of a cone that ends
        at the internode's top is drawn in by :meth:`_tapers` as before).
        """
        n_levels = len(ax.levels)
        if n_levels < 3:  # every axis: a branch carrying sub-branches grows node years too
            return lambda r, outer, end: r
        kind = np.array([_PARTS[part] for _, part in ax.parts[:n_levels]], np.int64)
        h = self.level_frames(ax)[2]
        node = np.zeros(n_levels, bool)
        node[1:-1] = (kind[1:-1] == 1) & (kind[2:] == 2) & (shift[1 : n_levels - 1] > 0) & (shift[2:n_levels] == 0)
        nodes = np.flatnonzero(node)
        first = np.full(n_levels, -1, np.int64)  # the node of the year, per level of the year
        first[nodes], first[nodes + 1] = nodes, nodes
        frac = np.zeros(n_levels)
        frac[nodes] = h[nodes] / (h[nodes] + h[nodes + 1])
        moved = np.zeros((n_levels, 2), bool)  # which end of each level's corners is moved
        moved[nodes, 1] = moved[nodes + 1, 0] = True
        y = first[t]
        f = frac[np.maximum(y, 0)]
        y = np.where(self._clear_of_slots(ax, np.maximum(y, 0), k), y, -1)  # the knots' push places those

        def radius_at(level, j, valid):  # the table's outer radius of cell j (0: the pith) where valid
            lv = np.clip(level, 0, n_levels - 1)
            inside = valid & (level >= 0) & (level < n_levels) & (j >= 0) & (j <= cell.max())
            inside &= ax.alive[lv, k] & (count[lv, k] >= j)
            return np.where(inside, table[lv, k, np.clip(j, 0, table.shape[2] - 1)], np.nan)

        s_below = shift[np.maximum(y, 0)]
        s_above = shift[np.clip(y + 2, 0, len(shift) - 1)]
        ends = {}
        for outer in (False, True):
            j = cell - (0 if outer else 1)
            a = radius_at(y - 1, j + s_below, y >= 0)
            r_node = radius_at(y, j, y >= 0)
            r_int = radius_at(y + 1, j, y >= 0)
            u = radius_at(y + 2, j - s_above, (y >= 0) & (j - s_above >= 1))
            u = np.where(np.isnan(u), r_int, u)
            b0, b1 = 0.5 * (a + r_node), 0.5 * (r_int + u)
            cone = (y >= 0) & (j <= s_above) & (y + 2 < n_levels)  # ends at the internode's top: its apex
            b1 = np.where(cone, rp + self.TAPER * (r_int - rp), b1)
            ends[outer] = b0 + f * (b1 - b0)  # NaN where a level does not match: keep r

        def spread(r, outer, end):
            target = ends[outer]
            return np.where(moved[t, end] & ~np.isnan(target), target, r)

        return spread

    @staticmethod
    def _clear_of_slots(ax: Axis, level: np.ndarray, k: np.ndarray) -> np.ndarray:
        """Whether stack ``k`` of ``level`` and the stacks either side of it are alive (no knot's slot):
        the corners of a slot's walls are placed by the knots' push (:meth:`_push`), not by the tapers."""
        n = ax.sides
        return ax.alive[level, k] & ax.alive[level, (k - 1) % n] & ax.alive[level, (k + 1) % n]

    @staticmethod
    def _cube_points(o, f, h, t, k, theta, r_in, r_out, n, bottom=None, top=None):
        """Corners (m, 8, 3) of cubes: base 0..3 = (bottom th0, bottom th1, top th1, top th0) at r_in.

        Cube ``j`` lies on level ``t[j]`` (rows of the level arrays ``o, f,
        h``) between angles ``theta[k[j]]`` and ``theta[k[j] + 1]``; the radial
        directions and level tops are computed once per (level, angle) and
        gathered.  ``bottom`` and ``top`` map the radii of the bottom and top
        corners (tapers), called as ``(r, outer)``.
        """
        c = 1.0 / math.cos(math.pi / n)
        bottom = bottom or (lambda r, outer: r)
        top = top or (lambda r, outer: r)
        radial = np.cos(theta)[None, :, None] * f[:, 1][:, None, :] + np.sin(theta)[None, :, None] * f[:, 2][:, None, :]
        r0, r1 = radial[t, k], radial[t, k + 1]
        low, high = o[t], (o + h[:, None] * f[:, 0])[t]
        out = np.empty((len(t), 8, 3))
        for base, r, outer in ((0, r_in, False), (4, r_out, True)):
            rb, rt = (c * bottom(r, outer))[:, None], (c * top(r, outer))[:, None]
            out[:, base + 0] = low + rb * r0
            out[:, base + 1] = low + rb * r1
            out[:, base + 2] = high + rt * r1
            out[:, base + 3] = high + rt * r0
        return out

    def nominal_radius(self, br: Branch, s: np.ndarray, now: int | None = None) -> np.ndarray:
        """The branch's outer radius at distance ``s`` along it, from the law's mean widths."""
        p = self.p
        now = self.year + 1 if now is None else now
        years_here = np.clip(now - br.year - np.floor(np.maximum(s - 2 * p["pith_radius"], 0) / p["branch_length"]), 0, None)
        rings = np.arange(1, max(int(years_here.max(initial=0)), 0) + 1)
        lo_e, hi_e = self.law(rings, np.zeros_like(rings), None, 1)
        lo_l, hi_l = self.law(rings, np.ones_like(rings), None, 1)
        per_year = 0.5 * (lo_e + hi_e + lo_l + hi_l)
        cum = np.concatenate([[0.0], np.cumsum(per_year)])
        wood = p["pith_radius"] * p["branch_scale"] + cum[years_here.astype(int)]
        return wood + _species.nominal_bark(p, years_here, wood, p["branch_scale"])

    def knot_length(self, br: Branch) -> float:
        """Length of the branch's first level (the knot): from the pith face past its host's final radius."""
        p = self.p
        angle = p["branch_angle"] if br.angle is None else br.angle
        radial = max(math.sin(math.radians(angle)), math.cos(math.radians(self.KNOT_RISE)))  # cos(elevation)
        bend = math.radians(self.KNOT_BEND)
        if bend > 0:  # the curved knot reaches out by (sin(e + B) - sin e) / B per unit length, not cos e
            e = math.acos(min(radial, 1.0))
            radial = (math.sin(e + bend) - math.sin(e)) / bend
        host = self.host(br)
        return max((self.host_radius(br) - self.pith_apothem(host)) / radial, p["branch_length"] * 0.25)

    def host_radius(self, br: Branch) -> float:
        """The final radius of a branch's host where it grows: the trunk's base radius, or the
        parent branch's radius at the year of the node it grows from (the law's mean widths)."""
        if br.parent < 0:
            return self.trunk_radius()
        years = self.final_years or (self.year + 1)
        probe = Branch(br.year, 0, 0)  # the host's wood there was laid down from the sub-branch's year on
        return float(self.nominal_radius(probe, np.zeros(1), years)[0])

    def knot_bender(self, br: Branch) -> Any:
        """The map from the straight knot to the bent one: a function of points ``(..., 3)``, or ``None``.

        The knot's pith is an arc: it leaves the trunk's pith ``KNOT_BEND``
        degrees steeper than its straight axis and turns at a constant rate
        until the knot's end (``knot_length``), where the branch goes on
        (a conifer's knot, seen in a quarter-sawn board, is a spike curved up
        towards the pith).  A point at distance ``s`` along the straight axis
        and offset across it goes to the arc's point at arc length ``s``, its
        offset turned with the arc; before the pith and past the knot's end
        the axis runs straight on.
        """
        bend = math.radians(self.KNOT_BEND)
        if bend <= 0:
            return None
        p0, frame = self.branch_frame(br, knot=True)
        f0, up, side = frame[0], -frame[1], frame[2]
        h0 = self.knot_length(br)
        c0, s0 = math.cos(bend), math.sin(bend)

        def bent(points: np.ndarray) -> np.ndarray:
            rel = np.asarray(points, float) - p0
            s = rel @ f0
            a_up, a_side = rel @ up, rel @ side
            alpha = bend * (1 - np.clip(s, 0.0, h0) / h0)
            before, past = np.minimum(s, 0.0), np.maximum(s - h0, 0.0)
            along = (h0 / bend) * (s0 - np.sin(alpha)) + past + before * c0 - a_up * np.sin(alpha)
            rise = (h0 / bend) * (np.cos(alpha) - c0) + before * s0 + a_up * np.cos(alpha)
            return p0 + along[..., None] * f0 + rise[..., None] * up + a_side[..., None] * side

        return bent

    def _bent_s(self, br: Branch, x: np.ndarray, cos_elev: float) -> np.ndarray:
        """Arc lengths along the bent knot where it has gone ``x`` out from the trunk's pith."""
        bend = math.radians(self.KNOT_BEND)
        if bend <= 0:
            return x / max(cos_elev, 0.2)
        e = math.acos(min(cos_elev, 1.0))
        h0 = self.knot_length(br)
        arg = np.clip(math.sin(e + bend) - bend * x / h0, -1.0, 1.0)
        return h0 * (1 - (np.arcsin(arg) - e) / bend)

    def _push(self, pts, levels, profiles, host=None):
        """Bend the trunk's rings around each knot: a displacement field from the knot's seam.

        At slot layer ``j`` each of the tunnel's four corner lines (sector
        edge ``theta_k`` or ``theta_k+1``, node bottom or top) has a seam
        vertex that the knot places (its volumes are ``exclusive``); its
        displacement is the knot corner minus the straight trunk corner.  A
        trunk corner near the slot gets the bilinear blend of the four
        displacements at its slot coordinates (clipped to the slot), at its
        fractional layer (its apothem among the layers' ``a_j``), faded out
        linearly over twice the displacement's length outside the slot, so
        the field's slope stays under 1/2 (no folded cells).  On a corner line
        it is the knot's corner: the seam vertices' volumes agree.  Where
        several knots reach a corner their fields are blended with weights
        ``1 / q^2`` (``q`` the distance outside each slot over its reach), so
        each knot's own field holds on its seam and two knots of one year do
        not push the same cells twice.  The field has no part across the trunk's rings
        (:meth:`_keep_apothem`, :meth:`_on_ring`).  ``host`` is the axis whose cells ``pts`` are (the trunk
        by default; a branch's for its sub-branches' knots, whose slots lie in its nodes).
        """
        host = self.trunk if host is None else host
        o, f, h = self.level_frames(host)
        n = host.sides
        half = math.pi / n
        levels = np.asarray(levels)
        base = pts.reshape(-1, 3)
        per = pts.shape[1]
        num = np.zeros_like(base)
        den = np.zeros(len(base))
        share = np.ones(len(base))  # how far each corner goes back onto its ring (_on_ring)
        for b, br in enumerate(self.branches):
            if b not in profiles or self.host(br) is not host:
                continue
            s_layer, rho_layer, a_layer, lateral = profiles[b]
            cells = np.flatnonzero(np.abs(levels - br.level) <= 1)  # the slot lies in its node level
            t, phi = br.level, self.sector_centre(host, br.sector)
            p0, frame = self.branch_frame(br, knot=True)
            # (4, layers, 3): the four corners (-,-), (+,-), (+,+), (-,+) at once, same arithmetic per corner
            cos_th = np.array([math.cos(phi + su * half) for su in _SU])
            sin_th = np.array([math.sin(phi + su * half) for su in _SU])
            lift = np.array([(0.5 + 0.5 * sv) * h[t] for sv in _SV])
            ring = cos_th[:, None] * f[t, 1] + sin_th[:, None] * f[t, 2]
            straight = (o[t] + lift[:, None] * f[t, 0])[:, None, :] + (a_layer / math.cos(half))[None, :, None] * ring[:, None, :]
            by_layer = straight.transpose(1, 0, 2).copy()  # (layers, 4, 3)
            seam = self._seam_map(br, p0, frame, s_layer, rho_layer, lateral, hull=True)
            ring_u = np.array([-1, 0, 1, 1, 1, 0, -1, -1], float)  # the slot's boundary, corners and mid-walls
            ring_v = np.array([-1, -1, -1, 0, 1, 1, 1, 0], float)
            blend8 = _corner_blend(ring_u, ring_v)
            n_layers = len(a_layer)
            layer = np.repeat(np.arange(n_layers), 8)
            at_ring = seam(np.tile(ring_u, n_layers), np.tile(ring_v, n_layers), layer, np.zeros(len(layer)))
            straight_ring = np.einsum("lcx,pc->lpx", by_layer, blend8[:, :, 0]).reshape(-1, 3)
            size_layer = np.linalg.norm(at_ring - straight_ring, axis=1).reshape(n_layers, 8).max(axis=1)
            rel = pts[cells].reshape(-1, 3)
            rel -= o[t]
            z = rel @ f[t, 0]
            close = np.flatnonzero(np.abs(z - 0.5 * h[t]) - 0.5 * h[t] < 2 * size_layer.max())
            rows = cells[close // per] * per + close % per
            rel, z = rel[close], z[close]  # the rest is beyond reach
            across = z[:, None] * f[t, 0]  # np.linalg.norm of rel - across, in place
            np.subtract(rel, across, out=across)
            across *= across
            r_h = across[:, 0] + across[:, 1]  # add.reduce over 3 columns: left to right
            r_h += across[:, 2]
            np.sqrt(r_h, out=r_h)
            du = (np.arctan2(rel @ f[t, 2], rel @ f[t, 1]) - phi + np.pi) % (2 * np.pi) - np.pi
            outside = np.hypot(np.maximum(np.abs(du) - half, 0) * r_h, np.maximum(np.abs(z - 0.5 * h[t]) - 0.5 * h[t], 0))
            near = np.flatnonzero(outside < 2 * size_layer.max())
            if not near.size:
                continue
            u = np.clip(du[near] / half, -1, 1)
            v = np.clip((z[near] - 0.5 * h[t]) / (0.5 * h[t]), -1, 1)
            lam = np.interp(r_h[near] * math.cos(half), a_layer, np.arange(len(a_layer)))
            lo = np.floor(lam).astype(np.int64)
            hi = np.minimum(lo + 1, len(a_layer) - 1)
            frac = (lam - lo)[:, None]
            blend = _corner_blend(u, v)
            terms = by_layer[lo]  # the straight trunk at the slot coordinates: bilinear in the corners
            terms *= 1 - frac[:, :, None]
            upper = by_layer[hi]
            upper *= frac[:, :, None]
            terms += upper
            terms *= blend
            field = seam(u, v, lo, frac[:, 0]) - terms.sum(axis=1)
            radial = rel[near] - z[near, None] * f[t, 0]  # across the trunk, of length r_h
            s_at = (1 - frac[:, 0]) * s_layer[lo] + frac[:, 0] * s_layer[hi]
            field = self._keep_apothem(br, frame, field, radial, f[t, 0], v, s_at)
            reach = np.maximum(2 * np.maximum(size_layer[lo], size_layer[hi]), 1e-12)
            q = outside[near] / reach
            fade = np.clip(1 - q, 0, 1)
            weight = np.where(fade > 0, 1.0 / (q * q + 1e-9), 0.0)  # the nearest knot's field wins
            at = rows[near]  # distinct within a branch
            field *= (weight * fade)[:, None]
            num[at] += field
            den[at] += weight
            share[at] = np.minimum(share[at], np.clip(q / self.RING_FREE, 0.0, 1.0))
        moved = np.flatnonzero(den > 0)
        out = base.copy()
        shift = num[moved]
        shift /= den[moved, None]
        out[moved] += shift
        out[moved] = self._on_ring(host, base[moved], out[moved], levels[moved // per], share[moved])
        return out.reshape(pts.shape)

    def _close_under_knots(self, host: Axis, cells: np.ndarray, pts: np.ndarray, radii: np.ndarray, profiles) -> None:
        """Top corners of the bottom wall's cells past a knot's last ring, in place in ``pts``.

        The slot's bottom wall (stack ``k`` of the level under the knot's
        node, a year older) holds ``s`` cells more than the knot's ``N``
        rings (its cone's apex, :meth:`year_shift`) and, as an older stack,
        one or more bark cells past cell ``N + s``, which no knot cell
        meets.  The first one's top face has the knot's last ring on its
        inner edge (the knot's corners round the ring's lower quarter) and
        one straight outer edge between the slot's two lower corner lines.
        The push (:meth:`_push`) left that edge at the trunk's apothem,
        inside the ring, which juts out of the trunk under a rising knot
        (``d sin(e)``), so those cells came out turned over at their top
        (issue 39: 26 of 4,000 points of a cross-cut under a pine's knot in
        two cells).  A choice: the outer edge goes onto the square round the
        knot's last ring (half-side ``r / cos(pi / m)``, the ring's own
        corners' radius), below the ring's two lower diagonal corners on the
        knot's section, so the top face lies on that section between the
        round ring and its square, never crossing it; each further cell
        stands ``TAPER`` times its radius past cell ``N + s`` out from there
        (a stack's exposed top closes so, :meth:`_tapers`), along the
        section's downward side.  The corners of the stacks either side of
        the wall at those vertices go there too, so the vertex is where all
        its volumes put it.
        """
        n = host.sides
        if not host.alive.size:
            return
        c_n = 1.0 / math.cos(math.pi / n)
        c_m = 1.0 / math.cos(math.pi / int(self.p["branch_sides"]))
        row = np.full(len(self.gm.volume_data["cell"]), -1, np.int64)
        row[cells] = np.arange(len(cells))
        shift = self.year_shift(host)
        for b, br in enumerate(self.branches):
            if b not in profiles or self.host(br) is not host or br.level < 1:
                continue
            t, k = br.level - 1, br.sector
            if host.index > 0 and t == 0:  # the bottom wall is the host's knot: placed by its seat
                continue
            s_layer, rho_layer, _, lateral = profiles[b]
            last = len(s_layer) - 1 + int(shift[br.level])  # the wall's cell meeting the knot's last ring
            if not host.alive[t, k] or host.count[t, k] <= last:
                continue
            p0, frame = self.branch_frame(br, knot=True)
            r = c_m * rho_layer[-1]
            side = np.array([-1.0, 1.0]) * (r * lateral[-1] / math.sqrt(2.0))  # under the diagonal corners
            down = np.array([r / math.sqrt(2.0), r])  # the ring's diagonal corner, the square's corner
            weight = self._outer_weight(br, np.full(2, len(s_layer) - 1))
            s_at = self._level_seam(br, frame, np.full(2, s_layer[-1]), down, weight)
            ring, square = (p0 + s_at[j] * frame[0] + down[j] * frame[1] + side[:, None] * frame[2] for j in (0, 1))
            bender = self.knot_bender(br)
            if bender is not None:
                ring, square = bender(ring), bender(square)
            out = square - ring
            out /= np.linalg.norm(out, axis=1, keepdims=True)
            # (sector, corner, line, inner) for every top corner on the lower corner lines
            for kk, corner, line, inner in (
                (k, 3, 0, True), (k, 7, 0, False), (k, 2, 1, True), (k, 6, 1, False),
                ((k - 1) % n, 2, 0, True), ((k - 1) % n, 6, 0, False),
                ((k + 1) % n, 3, 1, True), ((k + 1) % n, 7, 1, False),
            ):  # fmt: skip
                if not host.alive[t, kk]:
                    continue
                cell = np.arange(last + 1, int(host.count[t, kk]) + 1)  # cells past the knot's last ring
                depth = cell - 1 if inner else cell  # the cell whose outer radius the corner is at
                cell, depth = cell[depth > last], depth[depth > last]  # (depth == last: the knot's corner)
                if not cell.size:
                    continue
                stack = np.where(depth <= host.count[t, k], k, kk)  # the wall's radii where it reaches
                vol = self.gm.dart_volume[host.cells[t, stack, depth - 1]]
                base = self.gm.dart_volume[host.cells[t, stack, last - 1]]
                at = row[self.gm.dart_volume[host.cells[t, kk, cell - 1]]]
                keep = at >= 0
                lift = self.TAPER * c_n * (radii[vol] - radii[base])
                pts[at[keep], corner] = square[line] + lift[keep, None] * out[line]

    def _on_ring(self, host: Axis, before: np.ndarray, after: np.ndarray, levels: np.ndarray, share: np.ndarray) -> np.ndarray:
        """Corners ``after`` put back at the distance from their level's axis they had ``before`` the push.

        Each knot's field has no part across the rings (:meth:`_keep_apothem`),
        but its move round the trunk runs along the knot's tangent, off the
        ring's circle, and the blend of several knots' moves cuts inside it.
        So the corner goes back to its ring across the axis of its level,
        keeping its height and its angle round the axis, by the ``share``
        (0 to 1) given per corner: near a slot the corners keep the knot's
        seam (whose own corners lie on its flat sections, off the ring;
        bringing their neighbours onto the ring there turns cells inside
        out), from ``RING_FREE`` of the field's reach out they are on the ring.
        """
        o, f, _ = self.level_frames(host)
        up = f[levels, 0]
        rel_b, rel_a = before - o[levels], after - o[levels]
        across_b = _across(rel_b, up)
        across_a = _across(rel_a, up)
        scale = np.linalg.norm(across_b, axis=1) / np.maximum(np.linalg.norm(across_a, axis=1), 1e-300)
        return after + (share * (scale - 1.0))[:, None] * across_a

    def _keep_apothem(
        self, br: Branch, frame: np.ndarray, field: np.ndarray, radial: np.ndarray, up: np.ndarray, v: np.ndarray, s: np.ndarray
    ) -> np.ndarray:
        """The knot's push ``field`` at trunk corners with no part across the trunk's rings (issue 39).

        The seam's hull (:meth:`_seam_map`) lies off the trunk's ring
        cylinders: its lower side juts out by ``d sin(e)`` on a knot rising
        at ``e`` (its upper side sinks in as much), and its sides run on the
        knot's straight tangent, out of the ring's arc.  Faded over twice
        its size, that radial part pushed every ring and the bark out all
        round a whorl, the log a bottle (level 0 of a 15-year pine 86 mm at
        its top for 62 mm at its base, mean over its sectors).  So the
        radial part ``d_r`` of the field (``radial`` the corner's offset
        across the trunk's axis ``up``) is removed, and on the knot's lower
        and upper sides (weight ``|v|``, the slot coordinate) it is turned
        into a slide along the trunk, ``-d_r tan(e)`` with ``e`` the bent
        knot's local elevation at ``s``: the point moves as if along the
        knot, so it keeps its distance from the knot's axis (the rings stay
        clear of the knot).  The move round the trunk, along its tangent,
        is bent back onto the ring's circle after the knots' fields are
        blended (:meth:`_on_ring`).
        The corners on the seam keep the knot's own corners (its volumes
        are exclusive).
        """
        _, f, _ = self.level_frames(self.host(br))
        e = math.asin(float(np.clip(frame[0] @ f[br.level, 0], -0.99, 0.99)))
        h0 = self.knot_length(br)
        local = e + math.radians(self.KNOT_BEND) * (1 - np.clip(s, 0.0, h0) / h0)
        r_h = np.maximum(np.linalg.norm(radial, axis=1), 1e-300)
        unit = radial / r_h[:, None]
        d_r = np.einsum("ij,ij->i", field, unit)
        slide = -d_r * np.tan(np.clip(local, -1.2, 1.2)) * np.abs(v)
        return field - d_r[:, None] * unit + slide[:, None] * up[None, :]

    def _seam_map(self, br, p0, frame, s_layer, rho_layer, lateral, hull=False, level=False):
        """Where the knot's seam lies at slot coordinates ``(u, v)`` in ``[-1, 1]^2``, fractional layer ``j + w``.

        With ``hull`` (what the trunk around the knot is pushed to), the
        square circumscribing the knot's round section, of half-side ``rho /
        cos(pi / m)``: the trunk cells next to the slot make room for the whole
        knot, and their faces on the seam (placed by the knot, whose volumes
        are exclusive) curve in along its round edge without crossing their
        far sides.  Else the slot's square boundary mapped onto the round
        section itself (an elliptical grid map, ``x = u sqrt(1 - v^2 / 2)``,
        ``y = v sqrt(1 - u^2 / 2)``: the walls' corners go to the diagonals,
        the mid-walls to the axes).  A four-sided knot is its own square.
        Returns a function of arrays ``(u, v, j, w)`` giving points ``(len(u), 3)``.
        """
        m = int(self.p["branch_sides"])
        scale = 1.0 / math.cos(math.pi / m)
        last = len(s_layer) - 1
        bender = self.knot_bender(br)

        def at(u, v, j, w):
            j = np.asarray(j, np.int64)
            k = np.minimum(j + 1, last)
            w = np.asarray(w, float)
            s_at = (1 - w) * s_layer[j] + w * s_layer[k]
            r_at = scale * ((1 - w) * rho_layer[j] + w * rho_layer[k])
            lat = (1 - w) * lateral[j] + w * lateral[k]
            if m == 4:
                x, y = u / math.sqrt(2), v / math.sqrt(2)
            elif hull:
                x, y = self.KNOT_HULL * u, self.KNOT_HULL * v
            else:
                x, y = u * np.sqrt(1 - 0.5 * v * v), v * np.sqrt(1 - 0.5 * u * u)
            down = r_at * -y
            if level:
                s_at = self._level_seam(br, frame, s_at, down, self._outer_weight(br, j + w))
            straight = p0 + s_at[:, None] * frame[0] + down[:, None] * frame[1] + (r_at * x * lat)[:, None] * frame[2]
            return straight if bender is None else bender(straight)

        return at

    def embed(self) -> np.ndarray:
        """Default corners on every dart (``gm.corners``), then the kernel's per-vertex average."""
        gm = self.gm
        self._sync_corner()
        flat, offset = self.default_corners()
        tpl = self.corner
        gm.set_corners_from_tables(flat, offset, tpl)
        split = np.flatnonzero(tpl < 0)  # darts made by edge splits: edge midpoints
        if split.size:
            corners = gm.corners
            a0, a1 = gm.alpha[0], gm.alpha[1]
            corners[split] = 0.5 * (corners[a0[split]] + corners[a0[a1[split]]])
            knots = split[gm.volume_data["exclusive"][gm.dart_volume[split]]]
            if knots.size:  # cuts in a knot's own volumes (a sub-branch next to its host's knot)
                split_corners(gm, knots)
            self._bridge_corners(split)
            self._knot_bridge_corners(split)
        pos = gm.embed()
        if len(self.axes) > 1 and self.bend_rings:
            self._keep_rings_apart(pos)
        return pos

    #: least radial gap the trunk's ring cells keep between their inner and outer vertices, over their width
    RING_GAP = 0.1

    def _keep_rings_apart(self, pos: np.ndarray, sweeps: int = 8) -> None:
        """Pull embedded trunk vertices in so no ring cell is turned inside out (issue 39), in place.

        ``pos``: the vertex positions :meth:`GMap3.embed` returned (numbered
        as :meth:`GMap3.vertex_positions`), updated with the darts' points.

        The knots' push (:meth:`_push`) moves a corner round and along the
        trunk by a field that changes with the corner's radius too (its
        fractional layer among the knot's rings), and near a slot it leaves
        the corners off their rings (:meth:`_on_ring`).  The outer bark of
        an old level is shed to ``SHED_WIDTH`` (50 um) slivers, thinner than
        that change: between two knots of a pine's lowest whorl the push set
        some sliver's inner corners up to 0.2 mm outside its outer ones, and
        the kernel's average of the volumes' corners at a vertex mixes
        stacks pushed apart, so 5 trunk cells of a 20-year pine (all shed
        bark, levels 0 to 2) came out inside out.  A choice, after the
        average, on the vertices themselves (so every volume at a vertex
        agrees): along each corner line of each trunk stack (level, sector,
        corner), from the bark in, a vertex's distance from its level's axis
        is held at most its outer neighbour's less ``RING_GAP`` times the
        cell's width between them, moving it across the axis only (height
        and angle kept).  Pulled in rather than pushed out, so the bark
        stays where the push put it; a vertex of a knot (an ``exclusive``
        volume) never moves.  A few sweeps, as a vertex lies on up to four
        stacks' lines; only the folded vertices move, a fraction of a
        millimetre.  A sliver the push tilts along the trunk stays inside out
        with its layers in order across the axis: its outer vertices are put
        straight out from its inner ones after (:meth:`_square_turned_cells`).
        """
        gm = self.gm
        vd = gm.volume_data
        tpl = self.corner[: gm.n_darts]
        vol = gm.dart_volume.astype(np.int64)
        ring = (vd["axis"] == 0) & (vd["cell"] > 0)
        darts = np.flatnonzero((tpl >= 0) & ring[vol])
        if not darts.size:
            return
        slot = np.full(8 * gm.n_volumes, -1, np.int64)  # one dart per (volume, corner): any will do
        slot[vol[darts] * 8 + tpl[darts]] = darts
        key = np.flatnonzero(slot >= 0)
        darts = slot[key]
        v, c = key // 8, key % 8
        t, k, cell = (vd[name][v].astype(np.int64) for name in ("level", "sector", "cell"))
        col = np.where(c >= 4, cell, cell - 1)  # column j: the vertex past cell j (0: the pith side)
        line = (t * self.trunk.sides + k) * 4 + c % 4
        lines, row = np.unique(line, return_inverse=True)
        n_cols = int(col.max()) + 1
        gap = np.zeros((len(lines), n_cols))
        outer = c >= 4
        gap[row[outer], col[outer]] = self.RING_GAP * vd["width"][v[outer]]
        g = np.cumsum(gap, axis=1)
        vid, _ = gm.cells(0)
        point = vid[darts].astype(np.int64)
        touched = np.zeros(len(pos), bool)  # a knot's vertex stays where the knot put it
        touched[vid[vd["exclusive"][vol]]] = True
        o, f, _ = self.level_frames(self.trunk)
        up = f[t, 0]
        changed = np.zeros(len(pos), bool)
        on = np.arange(len(point))  # the entries swept: after the first sweep, the lines that moved
        for _ in range(sweeps):
            p_on, r_on, c_on, t_on = point[on], row[on], col[on], t[on]
            rel = pos[p_on] - o[t_on]
            across = _across(rel, up[on])
            dist = np.linalg.norm(across, axis=1)
            table = np.full((len(lines), n_cols), np.inf)
            table[r_on, c_on] = dist
            held = g + np.minimum.accumulate((table - g)[:, ::-1], axis=1)[:, ::-1]
            ratio = np.where(touched[p_on], 1.0, held[r_on, c_on] / np.maximum(dist, 1e-300))
            least = np.ones(len(pos))
            np.minimum.at(least, p_on, ratio)
            fold = (least < 1.0 - 1e-12)[p_on] & (ratio == least[p_on])
            if not fold.any():
                break
            pos[p_on[fold]] = (pos[p_on] + (ratio - 1.0)[:, None] * across)[fold]
            changed[p_on[fold]] = True
            moved = np.zeros(len(pos), bool)
            moved[p_on[fold]] = True
            lines_moved = np.zeros(len(lines), bool)
            lines_moved[row[moved[point]]] = True  # every line through a moved vertex
            on = np.flatnonzero(lines_moved[row])
        self._square_turned_cells(pos, v, c, point, touched, changed)
        moved = np.flatnonzero(changed[vid])
        gm.points[moved] = pos[vid[moved]]

    #: the hexahedron's faces over its default corners (0..3 inner, 4..7 outer): positive volume the right way out
    HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [3, 7, 6, 2], [0, 4, 7, 3], [1, 2, 6, 5]])

    @classmethod
    def hex_volumes(cls, corners: np.ndarray) -> np.ndarray:
        """Signed volumes of hexahedra ``corners`` (m, 8, 3) in the cube order, each face fanned from its centroid.

        A face's fan from its centroid ``c`` holds ``c . (q_k x q_k+1) / 6`` per
        edge; summed round a quad the cross products are the cross product of
        its diagonals, so each face costs one cross product, not four.
        """
        ref = corners.mean(axis=1, keepdims=True)
        quads = corners[:, cls.HEX_FACES] - ref[:, None]  # (m, 6, 4, 3)
        a, b = quads[:, :, 2] - quads[:, :, 0], quads[:, :, 3] - quads[:, :, 1]
        x, y, z = a[..., 0], a[..., 1], a[..., 2]
        u, v, w = b[..., 0], b[..., 1], b[..., 2]
        area = np.stack([y * w - z * v, z * u - x * w, x * v - y * u], axis=-1)
        return np.einsum("mfi,mfi->m", area, quads.mean(axis=2)) / 6.0

    def _square_turned_cells(
        self, pos: np.ndarray, v: np.ndarray, c: np.ndarray, point: np.ndarray, touched: np.ndarray, changed: np.ndarray
    ) -> None:
        """Outer vertices of trunk ring cells still inside out put straight out from their inner ones, in place.

        ``v, c, point``: each trunk ring cell's default corner ``c`` and its
        vertex (:meth:`_keep_rings_apart`).  A shed bark sliver (50 um) the
        knots' push tilts along the trunk by more than its width stays
        inside out with its layers in order across the axis (issue 39: a
        30-year pine's level 2, sector 13, cell 87, its outer bottom corners
        0.2 mm lower than its inner ones by a knot's push), so pulling in
        across the axis cannot fix it.  A choice: an outer vertex of such a
        cell (its 8 corners' signed volume <= 0) takes its inner vertex's
        height and angle round its level's axis, keeping its own distance
        from the axis (held past the inner one's by the ring gap): the cell's
        corner lines run straight out, so it has the width of its layer.  A
        knot's vertex never moves; a few rounds, as a moved vertex is the
        inner one of the cell outside it.
        """
        corners = np.full((self.gm.n_volumes, 8), -1, np.int64)
        corners[v, c] = point
        cells = np.flatnonzero((corners >= 0).all(axis=1))
        if not cells.size:
            return
        level = self.gm.volume_data["level"][cells].astype(np.int64)
        o, f, _ = self.level_frames(self.trunk)
        for _ in range(4):
            turned = np.flatnonzero(self.hex_volumes(pos[corners[cells]]) <= 0)
            if not turned.size:
                return
            inner = corners[cells[turned], :4].ravel()
            outer = corners[cells[turned], 4:].ravel()
            free = ~touched[outer]
            inner, outer = inner[free], outer[free]
            up = f[np.repeat(level[turned], 4)[free], 0]
            base = o[np.repeat(level[turned], 4)[free]]
            rel_i, rel_o = pos[inner] - base, pos[outer] - base
            across_i = _across(rel_i, up)
            across_o = _across(rel_o, up)
            r_i = np.linalg.norm(across_i, axis=1)
            r_o = np.maximum(np.linalg.norm(across_o, axis=1), r_i * (1 + 1e-9))
            pos[outer] = pos[inner] + ((r_o / np.maximum(r_i, 1e-300)) - 1.0)[:, None] * across_i
            changed[outer] = True

    def _knot_bridge_corners(self, split: np.ndarray) -> None:
        """Corners of the darts :meth:`_split_knot_bottoms` made: evenly along each cut edge.

        A knot's first ring cell facing the bottom wall has its bottom edges
        cut in ``s + 1`` pieces; the side faces hold each cut edge whole, so
        a cut point there is the midpoint of its two neighbours along the
        edge, solved by a few sweeps (pieces of equal length); the bottom
        pieces' darts at that point take its corner.  Knot cells are
        exclusive: the bottom wall's cells end where these put them.
        """
        gm = self.gm
        vd = gm.volume_data
        vol = gm.dart_volume[split]
        mine = split[(vd["axis"][vol] > 0) & (vd["level"][vol] == 0) & (vd["cell"][vol] == 1)]
        if not mine.size:
            return
        face = gm.dart_data["face"]
        sides = np.isin(face[mine], [_prism.face_label_code("C2"), _prism.face_label_code("C4")])
        chain = mine[sides]
        corners = gm.corners
        a0, a1, a2 = gm.alpha[0], gm.alpha[1], gm.alpha[2]
        for _ in range(64):  # Jacobi sweeps: the error halves each time, down to rounding
            corners[chain] = 0.5 * (corners[a0[chain]] + corners[a0[a1[chain]]])
        rest = mine[~sides]
        for step in (lambda d: a2[d], lambda d: a2[a1[d]]):  # a bottom dart on the edge, then on a chord
            other = step(rest).astype(np.int64)
            on_side = np.isin(other, chain)
            corners[rest[on_side]] = corners[other[on_side]]
            rest = rest[~on_side]

    def _bridge_corners(self, split: np.ndarray) -> None:
        """Corners of the darts :meth:`_bridge` made: those of the cells below at the same vertex.

        A new level's first cell has its bottom face cut where the older
        level's inner cells end; its darts there have no template corner, so
        they take the corner of the dart across the face (``alpha3``, or
        ``alpha3 alpha2`` from a side face), a template corner of the cell
        below: the vertex sits where the older cells put it.
        """
        gm = self.gm
        vd = gm.volume_data
        vol = gm.dart_volume[split]
        mine = (vd["cell"][vol] == 1) & (self.level_shifts(vd["axis"][vol], vd["level"][vol]) > 0)
        darts = split[mine]
        if not darts.size:
            return
        tpl, corners = self.corner, gm.corners
        a2, a3 = gm.alpha[2], gm.alpha[3]
        across = a3[darts].astype(np.int64)
        other = np.where(tpl[across] >= 0, across, a3[a2[darts]].astype(np.int64))
        ok = tpl[other] >= 0
        corners[darts[ok]] = corners[other[ok]]

    # ------------------------------------------------------------------ facts
    def check_topology(self) -> None:
        """Raise :class:`GMapError` unless valid, chi = 1 and boundary chi = 2."""
        from ramure.gmap.kernel.topology import assert_solid

        try:
            assert_solid(self.gm)
        except GMapError as err:
            raise GMapError(f"after step {self.steps}: {err}") from None

    def tissue_counts(self) -> dict[str, int]:
        """Volumes per wood tissue (all names present)."""
        counts = np.bincount(self.gm.volume_data["wood"].astype(np.int64), minlength=len(TISSUES))
        return {name: int(counts[i]) for i, name in enumerate(TISSUES)}

    def branch_volumes(self, b: int) -> np.ndarray:
        """Volume ids of branch ``b`` (0-based): its pith prisms and cells (the knot is level 0)."""
        return np.flatnonzero(self.gm.volume_data["axis"] == b + 1)


def place_branches(p: Mapping[str, Any], years: int, seed: int, count: int | np.integer | None = None) -> list[Branch]:
    """Branches for a trunk: birth years spread over ``branch_start..years-1``, sectors by 137.5 degrees.

    The sector is the golden-angle divergence quantised onto the trunk's
    faces, turned by a seeded offset; a branch is never born in its
    trunk's last year (it would have no rings yet).
    """
    count = int(p["branches"] if count is None else count)
    first = int(p["branch_start"])
    span = years - 1 - first
    if count <= 0 or span < 0:
        return []
    faces = (span + 1) * int(p["sides"])  # one branch per trunk face and year: checked before placing
    if count > faces:
        shown = f"{count:,}" if count < 10**9 else f"{float(count):.3g}"
        raise ValueRefused(f"{shown} branches do not fit: {span + 1} years of {p['sides']} trunk faces hold at most {faces:,}")
    if int(p.get("whorl", 1)) > 1 or p.get("divergence", 137.5) != 137.5:  # the species' pattern
        return [Branch(y, k, mix(seed, 1000 + i)) for i, (y, k) in enumerate(_species.place_whorls(p, years, seed, count))]
    n = int(p["sides"])
    turn = int(mix(seed, 11) % n)
    out = []
    for i in range(count):
        year = first + (i * (span + 1)) // count if count > span + 1 else first + round(i * span / max(count - 1, 1))
        sector = (turn + int(round(i * n * 137.5 / 360.0))) % n
        out.append(Branch(int(min(year, years - 1)), sector, mix(seed, 1000 + i)))
    return out


def grow_wood(
    species: str = "pine",
    years: int = 10,
    seed: int = 0,
    branches: int | str | Sequence[tuple[int, int]] | None = None,
    check_every_step: bool = False,
    embed_every_step: bool = False,
    branch_seeds: Mapping[int, int] | None = None,
    branch_deaths: Mapping[int, int] | None = None,
    **params: Any,
) -> Wood:
    """Grow ``years`` years (``2 * years`` half-year steps) of wood; returns the :class:`Wood`.

    ``branches``: a number (placed by :func:`place_branches`; default the
    species' ``branches``) or a list of ``(year, sector)`` pairs, or
    ``(year, sector, parent)`` triples for branches on branches (``parent``
    the index of the branch it grows on, -1 the trunk; :func:`check_hosts`).
    ``branch_seeds`` maps a branch index to its seed (regrowth).
    ``branch_deaths`` maps a branch index to the year it dies (after the
    year it is born); the others follow ``branch_life`` (0: they never die).
    """
    if isinstance(branches, str):  # from the command line (--set branches=3)
        params = {**params, "branches": branches}
        branches = None
    p = resolve_params(species, **params)
    years = check_years(years)
    if isinstance(branches, (int, np.integer)) or branches is None:
        placed = place_branches(p, years, seed, branches)
    else:
        placed = []
        for i, item in enumerate(branches):
            year, sector, parent = (*item, -1) if len(item) == 2 else item
            sides = p["sides"] if int(parent) < 0 else p["branch_sides"]
            if not 0 <= int(year) < years or not 0 <= int(sector) < sides:
                raise ValueRefused(
                    f"branch {i}: year must be in 0..{years - 1} and sector in 0..{sides - 1}, got ({year}, {sector})"
                )
            placed.append(Branch(int(year), int(sector), mix(seed, 1000 + i), parent=int(parent)))
    slots = [(b.year, b.sector) for b in placed]
    if len({(b.year, b.sector, b.parent) for b in placed}) != len(placed):
        raise ValueRefused("two branches share one face of their host (same year and sector)")
    for i, s in (branch_seeds or {}).items():
        placed[int(i)].seed = mix(int(s), 1000 + int(i))
    _set_deaths(placed, branch_deaths)
    check_hosts(p, placed, years)
    est = estimated_darts(p, years, [b.year for b in placed], [b.death for b in placed], [b.parent for b in placed])
    if est > MAX_DARTS:
        raise ValueRefused(
            f"this wood would have about {est:,} darts, more than the limit of {MAX_DARTS:,}; grow fewer years or branches"
        )
    t0 = time.perf_counter()
    wood = Wood(p, seed, placed, species, years=years)
    for _ in range(2 * years):
        wood.step()
        if check_every_step:  # first: its fresh look at what changed is then shared by the embedding's labels
            wood.check_topology()
        if embed_every_step:
            wood.embed()
    if not embed_every_step:  # else the last step's embedding stands: nothing changed since
        wood.embed()
    wood.seconds = time.perf_counter() - t0
    wood.gm.meta = {
        "species": species,
        "years": years,
        "seed": int(seed),
        "params": {k: v for k, v in p.items() if k != "colors"},
        "branches": slots,
        "deaths": [wood.death_year(b) for b in range(len(placed))],
    }
    if any(b.parent >= 0 for b in placed):
        wood.gm.meta["parents"] = [b.parent for b in placed]
    return wood


def check_hosts(p: Mapping[str, Any], branches: Sequence[Branch], years: int) -> None:
    """Refuse (:class:`ValueRefused`) a branch on a branch that its host cannot carry.

    A sub-branch born in year ``y`` on branch ``h`` (born in ``j``) sits on
    the node ``h`` grows in year ``y``: ``h`` is listed before it, ``j < y <
    years``, the node lies within the stub (``y - j < branch_levels`` when
    that is not 0: level 0 is the knot, one level a year after) and ``h`` is
    alive then (``y`` before its death year).
    """
    cap = int(p.get("branch_levels", 0))
    for i, br in enumerate(branches):
        if br.parent < 0:
            continue
        if br.parent >= i:
            raise ValueRefused(f"branch {i}: its host (branch {br.parent}) must be listed before it")
        host = branches[br.parent]
        if not host.year < br.year < years:
            raise ValueRefused(f"branch {i}: born in year {br.year}, it must come after its host's year {host.year}")
        if cap and br.year - host.year >= cap:
            raise ValueRefused(
                f"branch {i}: its host branch {br.parent} is a stub of {cap} levels (branch_levels) that ends "
                f"before year {br.year}; set branch_levels=0 for whole branches"
            )
        dies = death_year(p, host.year, host.death)
        if dies is not None and br.year >= dies:
            raise ValueRefused(f"branch {i}: its host branch {br.parent} dies in year {dies}, before it is born in {br.year}")


def _set_deaths(placed: list[Branch], deaths: Mapping[int, int] | None) -> None:
    """Set each branch's death year from ``deaths`` (branch index -> year), checked."""
    for i, year in (deaths or {}).items():
        if not 0 <= int(i) < len(placed):
            raise ValueRefused(f"branch_deaths: no branch {i} (there are {len(placed)})")
        if int(year) <= placed[int(i)].year:
            raise ValueRefused(f"branch {i} is born in year {placed[int(i)].year}: it must die later, not in year {year}")
        placed[int(i)].death = int(year)


def check_years(years: float) -> int:
    """``years`` as a whole number >= 1, else :class:`ValueRefused`."""
    try:
        y = int(years)
    except (TypeError, ValueError):
        raise ValueRefused(f"years must be a whole number, got {years!r}") from None
    if y != years or y <= 0:
        raise ValueRefused(f"years must be a whole number >= 1, got {years}")
    return y


def regrow_branch(wood: Wood, b: int, seed: int) -> Wood:
    """The same wood with branch ``b`` grown from a new seed (every other cell keeps its draws)."""
    if not 0 <= b < len(wood.branches):
        raise ValueRefused(f"branch index must be in 0..{len(wood.branches) - 1}, got {b}")
    slots = [(br.year, br.sector) for br in wood.branches]
    seeds = {i: None for i in range(len(slots))}
    new = Wood(
        wood.p,
        wood.seed,
        [Branch(y, s, br.seed, death=br.death, angle=br.angle, parent=br.parent) for (y, s), br in zip(slots, wood.branches)],
        wood.species,
        wood.trunk_frames,
        wood.final_years,
    )
    new.branches[b].seed = mix(int(seed), 1000 + b)
    del seeds
    for _ in range(wood.steps):
        new.step()
    new.embed()
    new.gm.meta = dict(wood.gm.meta)
    return new


# ---------------------------------------------------------------------- colours, grids, cuts
def _hex(c):
    return [int(c[i : i + 2], 16) for i in (1, 3, 5)]


def cell_colors(volume_data: Mapping[str, np.ndarray], species: str = "pine") -> np.ndarray:
    """uint8 RGB per volume from its wood tissue and season (the species' colours)."""
    colors = SPECIES[species]["colors"]
    tissue = np.asarray(volume_data["wood"]).astype(np.int64)
    season = np.asarray(volume_data["season"]).astype(np.int64)
    out = np.zeros((len(tissue), 3), np.uint8)
    for code, name in enumerate(TISSUES):
        value = colors[name]
        pair = value if isinstance(value, tuple) else (value, value)
        for s in (EARLY, LATE):
            out[(tissue == code) & (np.maximum(season, 0) == s)] = _hex(pair[s])
    if "reaction" in volume_data:  # compression / tension wood (wood_species)
        out = _species.reaction_rgb(out, np.asarray(volume_data["reaction"])).astype(np.uint8)
    if "bark" in volume_data:  # inner bark, plates or ridges, fissures
        marks = np.asarray(volume_data["bark"])
        is_bark = (tissue == CODES["bark"]) & (marks >= 0)
        out[is_bark] = _species.bark_rgb(species, marks[is_bark]).astype(np.uint8)
    return out


def to_grid(wood: Wood, convex: bool = True) -> pv.UnstructuredGrid:
    """The wood as a :class:`pyvista.UnstructuredGrid` (one cell per volume) with ``rgb`` cell data.

    ``convex=True`` (the default) writes polyhedra as tetrahedra (cell data
    ``volume`` names the owner), so VTK measures their volumes right and
    slices them right: the slot walls around a round knot are non-convex
    polyhedra, which VTK's polyhedron slice leaves with holes.  Hexahedra
    and wedges stay whole either way.
    """
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    grid = to_unstructured_grid(wood.gm, convex=convex)
    colors = cell_colors(wood.gm.volume_data, wood.species)
    grid.cell_data["rgb"] = colors[np.asarray(grid.cell_data["volume"])]
    return grid


#: VTK hexahedron edges in three classes of four parallel edges (points 0-3 bottom, 4-7 top)
_HEX_EDGES = np.array(
    [
        [[0, 1], [3, 2], [4, 5], [7, 6]],
        [[0, 3], [1, 2], [4, 7], [5, 6]],
        [[0, 4], [1, 5], [3, 7], [2, 6]],
    ]
)


def _vtk_order(corners: np.ndarray) -> np.ndarray:
    """The order (m, 8) that writes hexahedra of template ``corners`` (m, 8, 3) (inner quad 0..3,
    outer quad 4..7) as VTK wants them: the first quad turned towards the second, judged as the
    kernel's converter judges it (:func:`~ramure.gmap.kernel.measure.faces_up`, a Newell normal,
    not one corner's edges, which read a long thin cone cell backwards)."""
    up = faces_up(corners[:, :4], corners[:, 4:])
    return np.where(up[:, None], np.arange(8), np.array([0, 3, 2, 1, 4, 7, 6, 5]))


def bridged_as_hexahedra(wood: Wood, grid: pv.UnstructuredGrid) -> pv.UnstructuredGrid:
    """``grid`` with each ring cell :meth:`Wood._bridge` cut drawn as one hexahedron of its 8 corners.

    A level's first ring cell (the trunk's or a branch's), glued by year to
    the level below, has its bottom face cut in three, so :func:`to_grid` writes it as a polyhedron
    (tetrahedra).  Its extra vertices lie on its bottom edges (the embedding
    puts them where the older cells end, on the level's boundary plane), so
    the hexahedron of its 8 template corners has the same shape; pictures
    then round it like every other ring cell (:func:`smooth_grid`).  A
    branch's cell that also walls a sub-branch's slot (its faces cut and
    seated on the knot) is left in its pieces: its hexahedron would leave a
    hole by the knot (a trunk's is drawn whole, as before: its rounded
    neighbours meet its corners).
    """
    import pyvista as pv

    gm, vd = wood.gm, wood.gm.volume_data
    bridged = (vd["cell"] == 1) & (wood.level_shifts(vd["axis"], vd["level"]) > 0)
    # a branch's cell cut elsewhere too (a slot's wall: a sub-branch's knot seats its faces) keeps
    # its pieces: only cut points on its bottom face lie on the hexahedron's faces (the trunk's
    # stay whole: smooth_grid rounds their neighbours, which then meet the hexahedron's corners)
    tpl, face, a1, a2 = wood.corner, gm.dart_data["face"], gm.alpha[1], gm.alpha[2]
    cut = np.flatnonzero((tpl < 0) & (bridged & (vd["axis"] > 0))[gm.dart_volume[: gm.n_darts]])
    c1 = _prism.face_label_code("C1")
    off = (face[cut] != c1) & (face[a2[cut]] != c1) & (face[a2[a1[cut]]] != c1)
    bridged[gm.dart_volume[cut[off]]] = False
    owner = np.asarray(grid.cell_data["volume"])
    drop = bridged[owner] & (grid.celltypes != 12)
    vols = np.unique(owner[drop])
    if not vols.size:
        return grid
    row = np.full(gm.n_volumes, -1, np.int64)
    row[vols] = np.arange(len(vols))
    tpl = wood.corner
    darts = np.flatnonzero((row[gm.dart_volume] >= 0) & (tpl >= 0) & (tpl < 8))
    corner_dart = np.full((len(vols), 8), -1, np.int64)
    corner_dart[row[gm.dart_volume[darts]], tpl[darts]] = darts
    if np.any(corner_dart < 0):
        raise GMapError("a bridged ring cell has lost a corner")
    pts = gm.points[corner_dart]  # (m, 8, 3), VTK order: inner quad 0..3, outer quad 4..7
    order = _vtk_order(pts)
    conn = np.arange(8 * len(vols)).reshape(-1, 8)[np.arange(len(vols))[:, None], order]
    hexes = pv.UnstructuredGrid(
        np.hstack([np.full((len(vols), 1), 8), conn]).ravel(), np.full(len(vols), 12, np.uint8), pts.reshape(-1, 3)
    )
    first = np.zeros(gm.n_volumes, np.int64)
    first[owner[::-1]] = np.arange(len(owner))[::-1]  # a grid row of each volume, for its data
    for name in grid.cell_data.keys():
        hexes.cell_data[name] = np.asarray(grid.cell_data[name])[first[vols]]
    return pv.merge([grid.extract_cells(~drop), hexes], merge_points=False)


def _keys(points: ArrayLike) -> np.ndarray:
    """Points rounded to a nanometre, as integer rows (the grid's pieces are matched by position)."""
    return np.round(np.asarray(points) * 1e9).astype(np.int64)


def _hash(points: ArrayLike) -> np.ndarray:
    """One integer per point, by its position to a nanometre (:func:`_keys`): a 1-d key, so that
    matching points by position is a sort of integers, not of rows."""
    k = _keys(points)
    return (k[..., 0] * 2_654_435_761 + k[..., 1]) * 805_459_861 + k[..., 2]  # wraps round: a hash


def _find(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Row of ``table`` (k, 3) at each point of ``query`` (n, 3), matched to a nanometre; -1 where none."""
    h = _hash(table)
    order = np.argsort(h, kind="stable")
    sorted_h = h[order]
    q = _hash(query)
    at = np.minimum(np.searchsorted(sorted_h, q), max(len(h) - 1, 0))
    if not len(h):
        return np.full(len(q), -1, np.int64)
    return np.where(sorted_h[at] == q, order[at], -1)


#: the twelve edges of a VTK hexahedron, class by class as in _HEX_EDGES (edge e is in class e // 4)
_EDGE_LIST = _HEX_EDGES.reshape(-1, 2)


def seated_as_hexahedra(wood: Wood, grid: pv.UnstructuredGrid) -> pv.UnstructuredGrid:
    """``grid`` with each trunk ring cell seated on a knot drawn as a row of hexahedra (pictures only).

    A knot's slot walls (the node's ring cells on either side of the knot)
    and the ring cells over and under it have one face seated on the knot:
    two parallel edges of that face bend round the knot through extra
    vertices (three each), so :func:`to_grid` writes these cells as
    polyhedra, cut in tetrahedra.  Those tetrahedra's long skew faces break
    the rings into kinks and steep jogs where a board cuts them (a ring
    crossed a wall in two straight pieces meeting at 45 degrees), and
    :func:`smooth_grid` cannot round them (a cross-cut showed the 16-gon's
    facets beside every knot).  Here such a cell is drawn as ``n + 1``
    hexahedra across its seated edges: each piece joins two consecutive
    vertices of the seated edges to two points on the opposite parallel
    edges, which are cut in ``n + 1`` equal parts: the same shares on both
    (so the pieces cut the far face of the cell along its own bilinear
    lines and leave no gap to the neighbour there) and on every cell
    (neighbours sharing a far edge cut it at the same points).  A far edge
    along the trunk is cut straight, one round it in polar coordinates
    about the level's axis, as :func:`smooth_grid` cuts the neighbour's arc
    (three extra vertices: at its very points), or straight where a cell
    left whole holds it.  The seated vertices and faces
    are the kernel's, so the knot's cells meet the same faces as before.
    A cell whose extra vertices lie otherwise is left in its pieces.
    """
    import pyvista as pv

    gm, vd = wood.gm, wood.gm.volume_data
    owner = np.asarray(grid.cell_data["volume"])
    poly = (grid.celltypes != 12) & (vd["axis"][owner] == 0) & (vd["cell"][owner] > 0)
    vols = np.unique(owner[poly])
    if not vols.size:
        return grid
    m = len(vols)
    corners, masks, extra, extra_mask, extra_cell = _cell_points(wood, vols)
    edge_mask = masks[:, _EDGE_LIST[:, 0]] & masks[:, _EDGE_LIST[:, 1]]  # (m, 12): the two faces of each edge
    hit = edge_mask[extra_cell] == extra_mask[:, None]
    on = np.where(hit.sum(axis=1) == 1, np.argmax(hit, axis=1), -1)  # the edge each extra vertex lies on
    count = np.zeros((m, 12), np.int64)
    np.add.at(count, (extra_cell[on >= 0], on[on >= 0]), 1)
    # the seated vertices are the knot's too (a bridged cell's bottom is cut at trunk points only)
    knot = np.flatnonzero(vd["axis"][gm.dart_volume[: gm.n_darts]] > 0)
    seat = (on >= 0) & np.isin(_hash(extra), _hash(gm.points[knot]))
    seated = np.zeros((m, 12), np.int64)
    np.add.at(seated, (extra_cell[seat], on[seat]), 1)
    ok = np.isfinite(corners).all(axis=(1, 2))
    ok[extra_cell[on < 0]] = False
    held = _held_keys(grid, (grid.celltypes != 12) & ~np.isin(owner, vols), _hash(grid.points))

    def straight(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # edges a cell left whole holds
        return np.isin(_edge_keys(_hash(a), _hash(b)), held)

    pieces, rows, points = [], [], []
    base = 0
    done = np.zeros(m, bool)
    pairs = [(a, b) for a in range(12) for b in range(a + 1, 12) if a // 4 == b // 4]  # parallel edges
    for e0, e1 in pairs:
        n = count[:, e0]
        # no vertex on the class's two other edges (there go the pieces' points); one on an edge
        # across (a bridged cell's bottom face, cut where the older cells end) is drawn straight,
        # as bridged_as_hexahedra draws it
        others = count[:, 4 * (e0 // 4) : 4 * (e0 // 4) + 4].sum(axis=1) - count[:, e0] - count[:, e1]
        pick = ok & ~done & (n > 0) & (count[:, e1] == n) & (others == 0)
        pick &= (seated[:, e0] == n) & (seated[:, e1] == n)
        pick &= (edge_mask[:, e0] & edge_mask[:, e1]) != 0  # both on one face: the seated one
        for k in np.unique(n[pick]):
            g = np.flatnonzero(pick & (n == k))
            path = np.full((len(g), 2, int(k), 3), np.nan)
            for side, e in enumerate((e0, e1)):
                x = np.flatnonzero((on == e) & pick[extra_cell] & (count[extra_cell, e0] == k))
                local = np.searchsorted(g, extra_cell[x])
                a, b = corners[extra_cell[x], _EDGE_LIST[e, 0]], corners[extra_cell[x], _EDGE_LIST[e, 1]]
                t = np.einsum("ix,ix->i", extra[x] - a, b - a) / np.einsum("ix,ix->i", b - a, b - a)
                order = np.lexsort((t, local))
                path[:, side] = extra[x[order]].reshape(len(g), int(k), 3)
            cells, pts = _seated_rows(wood, vols[g], corners[g], (e0, e1), path, straight)
            pieces.append(cells + base)
            points.append(pts)
            base += len(pts)
            rows.append(np.repeat(vols[g], k + 1))
            done[g] = True
    if not pieces:
        return grid
    first = np.zeros(gm.n_volumes, np.int64)
    first[owner[::-1]] = np.arange(len(owner))[::-1]  # a grid row of each volume, for its data
    conn = np.concatenate(pieces)
    hexes = pv.UnstructuredGrid(
        np.hstack([np.full((len(conn), 1), 8), conn]).ravel(), np.full(len(conn), 12, np.uint8), np.concatenate(points)
    )
    which = first[np.concatenate(rows)]
    for name in grid.cell_data.keys():
        hexes.cell_data[name] = np.asarray(grid.cell_data[name])[which]
    keep: Any = ~np.isin(owner, vols[done])  # the grid's other rows (a boolean mask)
    return pv.merge([grid.extract_cells(keep), hexes], merge_points=False)


def _cell_points(wood: Wood, vols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The template corners of volumes ``vols`` and their other vertices, with the faces they lie on.

    Returns the corners (m, 8, 3) (NaN where missing) and their faces as
    bit masks (m, 8) (bit ``c`` for the dart label ``face == c``), then each
    extra vertex (one per volume and position): its point, face mask and
    row in ``vols``.
    """
    gm = wood.gm
    row = np.full(gm.n_volumes, -1, np.int64)
    row[vols] = np.arange(len(vols))
    darts = np.flatnonzero(row[gm.dart_volume[: gm.n_darts]] >= 0)
    tpl = wood.corner[darts]
    bit = np.left_shift(1, gm.dart_data["face"][darts].astype(np.int64))
    key = np.concatenate([row[gm.dart_volume[darts]][:, None], _keys(gm.points[darts])], axis=1)
    uniq, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    mask = np.zeros(len(uniq), np.int64)
    np.bitwise_or.at(mask, inv, bit)
    corner = np.full(len(uniq), -1, np.int64)
    corner[inv[(tpl >= 0) & (tpl < 8)]] = tpl[(tpl >= 0) & (tpl < 8)]
    cell, pts = uniq[:, 0], gm.points[darts[first]]
    corners = np.full((len(vols), 8, 3), np.nan)
    masks = np.zeros((len(vols), 8), np.int64)
    at = corner >= 0
    corners[cell[at], corner[at]] = pts[at]
    masks[cell[at], corner[at]] = mask[at]
    return corners, masks, pts[~at], mask[~at], cell[~at]


def _seated_rows(
    wood: Wood,
    vols: np.ndarray,
    corners: np.ndarray,
    seats: tuple[int, int],
    seated: np.ndarray,
    straight: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """The ``n + 1`` hexahedra of each cell ``vols`` across its seated edges (:func:`seated_as_hexahedra`).

    ``corners`` (m, 8, 3) are the cells' template corners, ``seats`` the two seated edges (of one
    class of ``_EDGE_LIST``) and ``seated`` (m, 2, n, 3) their extra vertices
    in order from the edge's first corner.  ``straight(a, b)`` tells which
    edges must stay straight.  Returns the connectivity (m (n + 1), 8), each
    piece in its cell's VTK order, and the points it indexes.
    """
    m, n = len(vols), seated.shape[2]
    cls = seats[0] // 4
    edges = _HEX_EDGES[cls]  # (4, 2): the class's four parallel edges, first corner to second
    chain = np.zeros((m, 4, n + 2, 3))  # the points along each of them
    chain[:, :, 0] = corners[:, edges[:, 0]]
    chain[:, :, -1] = corners[:, edges[:, 1]]
    for side, e in enumerate(seats):
        chain[:, e % 4, 1:-1] = seated[:, side]
    o, f, _ = wood.level_frames(wood.trunk)
    level = wood.gm.volume_data["level"][vols].astype(np.int64)
    w = np.broadcast_to(np.arange(1, n + 1) / (n + 1), (m, n))
    for s in range(4):
        if 4 * cls + s in seats:
            continue
        a, b = chain[:, s, 0], chain[:, s, -1]
        along = np.abs(np.einsum("mx,mx->m", b - a, f[level, 0])) > 0.5 * np.linalg.norm(b - a, axis=1)
        flat = along | straight(a, b)
        line = a[:, None] + w[..., None] * (b - a)[:, None]
        chain[:, s, 1:-1] = np.where(flat[:, None, None], line, _polar_lerp(a, b, w, o[level], f[level]))
    slot = np.zeros(8, np.int64)  # corner c: on the class's edge slot[c], at its first (0) or second (1) end
    end = np.zeros(8, np.int64)
    for k in range(4):
        slot[edges[k]] = k
        end[edges[k, 1]] = 1
    ids = np.arange(m * 4 * (n + 2)).reshape(m, 4, n + 2)
    cells = ids[np.arange(m)[:, None, None], slot[None, None, :], np.arange(n + 1)[None, :, None] + end[None, None, :]]
    order = _vtk_order(corners)
    cells = np.take_along_axis(cells, np.broadcast_to(order[:, None, :], cells.shape), axis=2)
    return cells.reshape(-1, 8), chain.reshape(-1, 3)


def _polar_lerp(a: np.ndarray, b: np.ndarray, w: np.ndarray, origin: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Points (m, k, 3) at shares ``w`` (m, k) from ``a`` to ``b`` (m, 3), radius, angle and height
    linear about each level's axis (``origin`` (m, 3); ``frame`` (m, 3, 3): the axis, then two across),
    the short way round: where :func:`smooth_grid` draws its arcs."""
    rel_a, rel_b = a - origin, b - origin

    def polar(rel):
        x, y = np.einsum("mx,mx->m", rel, frame[:, 1]), np.einsum("mx,mx->m", rel, frame[:, 2])
        return np.hypot(x, y), np.arctan2(y, x), np.einsum("mx,mx->m", rel, frame[:, 0])

    (ra, ta, za), (rb, tb, zb) = polar(rel_a), polar(rel_b)
    tb = ta + np.angle(np.exp(1j * (tb - ta)))
    r, t, z = (lo[:, None] + w * (hi - lo)[:, None] for lo, hi in ((ra, rb), (ta, tb), (za, zb)))
    across = np.cos(t)[..., None] * frame[:, None, 1] + np.sin(t)[..., None] * frame[:, None, 2]
    return origin[:, None] + z[..., None] * frame[:, None, 0] + r[..., None] * across


def smooth_grid(wood: Wood, grid: pv.UnstructuredGrid, parts: int = 4) -> pv.UnstructuredGrid:
    """A picture grid whose rings are round: each ring cell, the trunk's and the branches', cut in ``parts`` along its arc.

    A trunk of 16 sides shows 16-gons in a cross-cut; at 64 sides the wood
    would hold four times the darts (the 30-year, 20-branch pine: 12 million).
    For pictures only, each hexahedral ring cell is cut into ``parts``
    hexahedra across its sector, the new points interpolated in polar
    coordinates (radius, angle and height linear) about its ring's axis, so
    the rings are drawn with ``16 parts`` sides, on circles.  A trunk cell
    turns about its level's axis, and so does a branch's past its knot; a
    knot's cell turns about the centre of its own ring (:func:`_branch_arcs`:
    a knot is bent, so no level frame is its axis).  The trunk's cells bent round a knot
    are rounded too (a flat-sawn board shows arches there, not the
    16-gon's chevrons); those seated on a knot are first drawn as rows of
    hexahedra (:func:`seated_as_hexahedra`), each piece rounded the way its
    cell's pieces are rounded together (the edge class most round the trunk
    over all of them: a thin piece by the pith could pick another).

    Every edge is cut once, at points all the cells holding it share
    (:func:`_edge_points`), so no gap opens at the seam: a knot's ring
    edge that the trunk's cells seated on the knot hold follows the knot's
    arc in them too, so the knot's outline is round where it meets the
    trunk.  Over and under the knot those edges run round the trunk, and
    are cut with the rest; in a slot's wall they run along it (the pieces
    of :func:`seated_as_hexahedra` are stacked along the knot), so the
    wall's pieces are first cut in ``parts`` along them, on the knot's
    arcs, their far edges straight at the same shares (on the
    neighbour's straight edges and along its bilinear face), then round
    like the rest.  An edge stays a chord, cut at the same points, where
    a cell left whole also holds it (the pith's wedges, the tetrahedra of
    the slot walls and bridges, a dead stub's cap), where a trunk cell
    holds a knot's ring edge in neither of those ways, and where a ring's
    centre is unknown.  Other cells keep their point ids
    (:func:`_replace_cells`); the volumes are not the kernel's any more
    (arcs, not chords): measure a :func:`to_grid`.
    """
    if parts <= 1:
        return grid
    grid = bridged_as_hexahedra(wood, seated_as_hexahedra(wood, grid))
    vd = wood.gm.volume_data
    owner = np.asarray(grid.cell_data["volume"])
    hexa = (grid.celltypes == 12) & (vd["cell"][owner] > 0)
    rows = np.flatnonzero(hexa)
    if not rows.size:
        return grid
    conn = grid.cell_connectivity.reshape(-1)
    cells = conn[np.asarray(grid.cell_offsets, np.int64)[rows][:, None] + np.arange(8, dtype=np.int64)[None, :]]
    pts = np.asarray(grid.points, float)
    vols = owner[rows]
    trunk = vd["axis"][vols] == 0
    m = len(rows)
    edges = np.zeros((m, 4, 2), np.int64)  # each row's four tangential edges (its corners), 'a' end to 'b' end
    origin, frame = np.zeros((m, 4, 3)), np.zeros((m, 4, 3, 3))
    known = np.ones((m, 4), bool)  # the arc's axis is known (else the edge stays a chord)
    o, f, _ = wood.level_frames(wood.trunk)
    level = vd["level"][vols[trunk]].astype(np.int64)
    which = np.full(m, -1, np.int64)  # a trunk row's tangential class
    which[trunk] = _trunk_tangents(pts[cells[trunk]], vols[trunk], o[level], f[level])
    edges[trunk] = _HEX_EDGES[which[trunk]]
    origin[trunk], frame[trunk] = o[level][:, None], f[level][:, None]
    if np.any(~trunk):
        edges[~trunk], origin[~trunk], frame[~trunk], known[~trunk] = _branch_arcs(wood, pts[cells[~trunk]], vols[~trunk])
    h = _hash(pts)
    idx = np.arange(m)[:, None]
    ends = cells[idx, edges[:, :, 0]], cells[idx, edges[:, :, 1]]
    knot_keys = np.unique(_edge_keys(h[ends[0]], h[ends[1]])[~trunk])
    seat, off = _seats(cells, which, trunk, h, knot_keys)
    chords = np.union1d(_held_keys(grid, ~hexa, h), off)
    # every edge of the rows and the walls' edges along the knot, cut once (the walls' follow: prio 2)
    walls = np.flatnonzero(seat >= 0)
    s_edges = _HEX_EDGES[seat[walls]]
    all_cells = np.concatenate([cells, cells[walls]])
    all_edges = np.concatenate([edges, s_edges])
    prio = np.concatenate([np.broadcast_to(trunk[:, None], (m, 4)).astype(np.int64), np.full((len(walls), 4), 2)])
    inner, table = _edge_points(
        h,
        pts,
        all_cells,
        all_edges,
        np.concatenate([origin, np.zeros((len(walls), 4, 3))]),
        np.concatenate([frame, np.zeros((len(walls), 4, 3, 3))]),
        np.concatenate([known, np.ones((len(walls), 4), bool)]),
        prio,
        chords,
        parts,
        layered=np.arange(len(all_cells)) < m,
    )
    inner_walls = inner[m:]
    keep = np.ones(m, bool)
    keep[walls] = False
    source = np.concatenate([np.flatnonzero(keep), np.repeat(walls, parts)])  # each row's row before the walls' cut
    inner = inner[:m][keep]
    if walls.size:  # the walls' pieces along the knot, then cut round like the rest
        w_pts, w_cells = _cut_rows(cells[walls], s_edges, inner_walls, len(pts))
        pts = np.concatenate([pts, w_pts])
        h = np.concatenate([h, _hash(w_pts)])
        w_rows = source[len(inner) :]
        w_inner, _ = _edge_points(
            h,
            pts,
            w_cells,
            edges[w_rows],
            origin[w_rows],
            frame[w_rows],
            known[w_rows],
            np.ones((len(w_rows), 4), np.int64),
            chords,
            parts,
            fixed=table,
        )
        cells, inner = np.concatenate([cells[keep], w_cells]), np.concatenate([inner, w_inner])
    new_pts, new_cells = _cut_rows(cells, edges[source], inner, len(pts))
    rows = rows[source]
    return _replace_cells(grid, hexa, np.concatenate([pts, new_pts]), new_cells, np.repeat(rows, parts))


def _replace_cells(
    grid: pv.UnstructuredGrid, drop: np.ndarray, points: np.ndarray, hexes: np.ndarray, rows: np.ndarray
) -> pv.UnstructuredGrid:
    """``grid`` without the cells ``drop`` and with the hexahedra ``hexes`` (k, 8) on ``points`` (the
    grid's points first), each with the data of the grid's row ``rows``.  The kept cells keep their
    point ids, so cells that shared points still do (a knot's wedges and its rounded ring cells make
    one region, :func:`knot_states`); a grid of polyhedra is merged instead."""
    import pyvista as pv

    keep = np.flatnonzero(~drop)
    types = np.asarray(grid.celltypes)
    data = {
        name: np.concatenate([np.asarray(grid.cell_data[name])[keep], np.asarray(grid.cell_data[name])[rows]])
        for name in grid.cell_data.keys()
    }
    if np.any(types[keep] == 42):  # polyhedra (face streams): merge, without sharing points
        sub = pv.UnstructuredGrid(
            np.hstack([np.full((len(hexes), 1), 8), hexes]).ravel(), np.full(len(hexes), 12, np.uint8), points
        )
        mask: Any = ~drop  # a boolean mask (the stubs want one)
        out = pv.merge([grid.extract_cells(mask), sub], merge_points=False)
        for name, values in data.items():
            out.cell_data[name] = values
        return out
    offsets = np.asarray(grid.cell_offsets, np.int64)
    conn = np.asarray(grid.cell_connectivity, np.int64)
    sizes = np.diff(offsets)[keep]
    head = np.concatenate([[0], np.cumsum(sizes + 1)[:-1]])  # where each kept cell's size goes
    flat = np.empty(int((sizes + 1).sum()), np.int64)
    flat[head] = sizes
    body = np.ones(len(flat), bool)
    body[head] = False
    flat[body] = conn[np.repeat(offsets[:-1][keep] - np.cumsum(np.r_[0, sizes[:-1]]), sizes) + np.arange(int(sizes.sum()))]
    cells = np.concatenate([flat, np.hstack([np.full((len(hexes), 1), 8), hexes]).ravel()])
    out = pv.UnstructuredGrid(cells, np.concatenate([types[keep], np.full(len(hexes), 12, np.uint8)]), points)
    for name, values in data.items():
        out.cell_data[name] = values
    return out


def _trunk_tangents(corners: np.ndarray, vols: np.ndarray, origin: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """The tangential edge class (m,) of trunk hexahedra ``corners`` (m, 8, 3): the class of
    ``_HEX_EDGES`` whose edges run most round the level's axis (``origin``, ``frame`` per row), summed over
    the rows of each volume (a seated cell's pieces all cut the same way round)."""
    axis_dir = frame[:, 0]
    centre = corners.mean(axis=1)
    radial = centre - origin - np.einsum("mx,mx->m", centre - origin, axis_dir)[:, None] * axis_dir
    tangent = np.cross(axis_dir, radial)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1), 1e-300)[:, None]
    score = np.zeros((len(corners), 3))
    for c, e in enumerate(_HEX_EDGES):  # how much the class's edges run round the trunk (|cos| to the tangent)
        vec = corners[:, e[:, 1]] - corners[:, e[:, 0]]
        length = np.maximum(np.linalg.norm(vec, axis=2).sum(axis=1), 1e-300)
        score[:, c] = np.abs(np.einsum("mkx,mx->mk", vec, tangent)).sum(axis=1) / length
    vol = np.unique(vols, return_inverse=True)[1].reshape(-1)
    total = np.zeros((int(vol.max(initial=-1)) + 1, 3))
    np.add.at(total, vol, score)
    return np.argmax(total[vol], axis=1)


def _branch_arcs(wood: Wood, corners: np.ndarray, vols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Tangential edges (m, 4, 2), arc centres (m, 4, 3), frames (m, 4, 3, 3) and whether known
    (m, 4) of branch hexahedra ``corners`` (m, 8, 3), one row per volume ``vols``.

    The tangential edges are the template's (corners 0-1, 3-2, 4-5, 7-6:
    round the branch), found by matching the row's points to the volume's
    template corners.  Past the knot (levels 1 on) the branch is straight:
    each edge turns about its level's axis, the pith line, as the trunk's
    do (an eccentric ring, or one missing a sector for a sub-branch's
    slot, is drawn round the pith).  In the knot (level 0), which is bent,
    each edge turns about the centre of its own ring: the mean of the
    ring's vertices at that end of the cell (the edges' first ends, over
    the ring's sectors), the axis the normal of the ring's polygon (its
    vector area).  Those vertices are the branch's ``sides`` equally
    spaced points of one section of the knot, moved rigidly by the bend
    (:meth:`Wood.knot_bender` turns each section with the arc) and
    squeezed across where two knots share a node (an ellipse), so their
    mean is the pith's point there: a straight level frame is not the
    bent knot's axis (the ring's vertices spread by 94 % of their radius
    about it, by 7 % about the mean, on a 12-year pine's knots), and the
    pith line at the same height would need the bend's inverse.  A knot's
    ring missing a sector has no reliable mean: its edges stay chords.
    """
    vd = wood.gm.volume_data
    tpl = _template_corners(wood, vols)
    d = np.linalg.norm(corners[:, :, None, :] - tpl[:, None, :, :], axis=3)  # grid corner x template corner
    d = np.nan_to_num(d, nan=np.inf)
    at = np.argmin(d, axis=1)  # (m, 8): the grid corner at each template corner
    # a row whose points are not its template corners one to one is cut straight, in the grid's order
    matched = (np.sort(at, axis=1) == np.arange(8)).all(axis=1) & (d.min(axis=1) < 1e-9).all(axis=1)
    template = _HEX_EDGES[0]  # round the branch: bottom th0-th1, top th0-th1, inner then outer
    edges = np.where(matched[:, None, None], at[:, template], template[None])  # (m, 4, 2)
    m = len(corners)
    idx = np.arange(m)[:, None]
    a, b = corners[idx, edges[:, :, 0]], corners[idx, edges[:, :, 1]]
    axis, level, cell = (vd[k][vols].astype(np.int64) for k in ("axis", "level", "cell"))
    dims = (int(axis.max()) + 1, int(level.max()) + 1, int(cell.max()) + 1, 4)
    key = np.ravel_multi_index((axis[:, None], level[:, None], cell[:, None], np.arange(4)[None, :]), dims)
    ring_key, inv = np.unique(key, return_inverse=True)
    inv = inv.reshape(m, 4)
    ring = np.stack(np.unravel_index(ring_key, dims), axis=1)
    count = np.bincount(inv.ravel(), minlength=len(ring))
    centre = np.zeros((len(ring), 3))
    np.add.at(centre, inv.ravel(), a.reshape(-1, 3))
    centre /= np.maximum(count, 1)[:, None]
    normal = np.zeros((len(ring), 3))
    np.add.at(normal, inv.ravel(), np.cross(a - centre[inv], b - centre[inv]).reshape(-1, 3))
    size = np.linalg.norm(normal, axis=1)
    sides = np.array([ax.sides for ax in wood.axes])[ring[:, 0]]
    normal /= np.maximum(size, 1e-300)[:, None]
    ref = np.where((np.abs(normal[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(normal, ref)
    e1 /= np.maximum(np.linalg.norm(e1, axis=1), 1e-300)[:, None]
    frame = np.stack([normal, e1, np.cross(normal, e1)], axis=1)
    known = (size > 0) & (count == sides)
    centre, frame, known = centre[inv], frame[inv], known[inv]
    known &= matched[:, None]
    straight = level > 0  # past the knot the branch is straight: its level's axis is its pith
    o_all, f_all = np.zeros((m, 3)), np.zeros((m, 3, 3))
    for ax in np.unique(axis[straight]):  # one per branch
        o, f, _ = wood.level_frames(wood.axes[ax])
        sel = straight & (axis == ax)
        sel[sel] = level[sel] < len(o)  # (a level the frames do not hold keeps its ring's mean)
        o_all[sel], f_all[sel] = o[level[sel]], f[level[sel]]
        centre[sel], frame[sel], known[sel] = o_all[sel, None], f_all[sel, None], matched[sel, None]
    return edges, centre, frame, known


def _template_corners(wood: Wood, vols: np.ndarray) -> np.ndarray:
    """The template corners (m, 8, 3) of volumes ``vols`` (one row each; NaN where missing)."""
    gm = wood.gm
    row = np.full(gm.n_volumes, -1, np.int64)
    row[vols] = np.arange(len(vols))
    darts = np.flatnonzero(row[gm.dart_volume[: gm.n_darts]] >= 0)
    tpl = wood.corner[darts]
    darts, tpl = darts[(tpl >= 0) & (tpl < 8)], tpl[(tpl >= 0) & (tpl < 8)]
    out = np.full((len(vols), 8, 3), np.nan)
    out[row[gm.dart_volume[darts]], tpl] = gm.points[darts]
    return out


def _edge_keys(ha: np.ndarray, hb: np.ndarray) -> np.ndarray:
    """One integer per unordered pair of points, from their position hashes (:func:`_hash`)."""
    lo, hi = np.minimum(ha, hb), np.maximum(ha, hb)
    return lo * 1_000_003 + hi  # wraps round: a hash


def _held_keys(grid: pv.UnstructuredGrid, whole: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Sorted :func:`_edge_keys` of every pair of points one of the cells ``whole`` holds (a
    tetrahedron's six edges, a wedge's or a hexahedron's edges and diagonals); ``h`` hashes the grid's points."""
    conn = np.asarray(grid.cell_connectivity, np.int64)
    offsets = np.asarray(grid.cell_offsets, np.int64)
    sizes = np.diff(offsets)
    keys = [np.zeros(0, np.int64)]
    for size in np.unique(sizes[whole]):
        rows = np.flatnonzero(whole & (sizes == size))
        ids = h[conn[offsets[rows][:, None] + np.arange(size)]]
        i, j = np.triu_indices(int(size), 1)
        keys.append(_edge_keys(ids[:, i], ids[:, j]).reshape(-1))
    return np.unique(np.concatenate(keys))


def _seats(
    cells: np.ndarray, which: np.ndarray, trunk: np.ndarray, h: np.ndarray, knot_keys: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Where the trunk's rows ``cells`` (m, 8) hold a knot's ring edges (``knot_keys``) off their
    tangential class ``which``: the class of ``_HEX_EDGES`` holding them (a slot wall's pieces run
    along the knot: they are cut along it first), -1 elsewhere; and the keys of the knot's ring edges
    a trunk row holds in neither class (a diagonal, or a second class): chords in both."""
    seat = np.full(len(cells), -1, np.int64)
    near = np.flatnonzero(trunk & np.isin(h[cells], h[cells[~trunk]]).any(axis=1))
    if not near.size or not knot_keys.size:
        return seat, np.zeros(0, np.int64)
    hc = h[cells[near]]
    has = np.stack([np.isin(_edge_keys(hc[:, e[:, 0]], hc[:, e[:, 1]]), knot_keys).any(axis=1) for e in _HEX_EDGES], axis=1)
    has[np.arange(len(near)), which[near]] = False
    seat[near] = np.where(has.any(axis=1), np.argmax(has, axis=1), -1)
    i, j = np.triu_indices(8, 1)
    every = _edge_keys(hc[:, i], hc[:, j])  # (k, 28): every pair of the row's points
    own = [which[near]] + [np.where(seat[near] >= 0, seat[near], which[near])]
    cut = np.concatenate(
        [
            _edge_keys(
                hc[np.arange(len(near))[:, None], _HEX_EDGES[c][:, :, 0]],
                hc[np.arange(len(near))[:, None], _HEX_EDGES[c][:, :, 1]],
            )
            for c in own
        ],
        axis=1,
    )
    pairs = every[~(every[:, :, None] == cut[:, None, :]).any(axis=2)]
    return seat, np.intersect1d(pairs, knot_keys)


def _edge_points(
    h: np.ndarray,
    pts: np.ndarray,
    cells: np.ndarray,
    edges: np.ndarray,
    origin: np.ndarray,
    frame: np.ndarray,
    known: np.ndarray,
    prio: np.ndarray,
    chords: np.ndarray,
    parts: int,
    layered: np.ndarray | None = None,
    fixed: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """The ``parts - 1`` points (m, 4, parts - 1, 3) cutting each edge ``edges`` (m, 4, 2) of rows ``cells``.

    Each edge (by its ends' position hashes ``h``) is cut once, from its end
    of lower hash, and every row holding it takes those very points (in its
    own direction): no gap between cells, whichever way they hold it.  The
    row of lowest ``prio`` (m, 4) holding it gives the arc's axis
    (``origin``, ``frame`` (m, 4, 3, 3)): a knot's (0), so the trunk's
    cells seated on a knot follow the knot's arcs, then the trunk's (1);
    an edge only rows of ``prio`` 2 hold (they follow) is a chord.  An edge
    is a chord too where its key is in ``chords`` or a row holding it has
    ``known`` false; in the rows ``layered`` (all by default), under an
    outer chord (edges 2, 3) the inner edge (0, 1) stays a chord too (a
    rounded inner arc under a chord would cross a ring thinner than its
    bulge), and so on inwards.  Edges in ``fixed`` (keys, points from their
    lower end: the table this returns) keep those points.
    """
    m = len(cells)
    idx = np.arange(m)[:, None]
    pa, pb = cells[idx, edges[:, :, 0]], cells[idx, edges[:, :, 1]]
    ha, hb = h[pa], h[pb]
    edge, inv = np.unique(_edge_keys(ha, hb), return_inverse=True)
    inv = inv.reshape(m, 4)
    is_chord = np.isin(edge, chords)
    is_chord[inv[~known]] = True
    lay = inv if layered is None else inv[layered]
    while True:
        chord = is_chord[lay]
        below = chord.copy()
        below[:, :2] |= chord[:, 2:]
        if np.array_equal(below, chord):
            break
        is_chord[lay[below]] = True
    flip = (ha > hb).ravel()
    flat = inv.ravel()
    order = np.lexsort((prio.ravel(), flat))  # a knot's row first: its arc's axis
    first = order[np.r_[True, flat[order][1:] != flat[order][:-1]]]  # one row per edge, in edge order
    is_chord |= prio.ravel()[first] >= 2
    a, b = pts[pa].reshape(-1, 3), pts[pb].reshape(-1, 3)
    lo = np.where(flip[first, None], b[first], a[first])
    hi = np.where(flip[first, None], a[first], b[first])
    w = np.broadcast_to(np.arange(1, parts) / parts, (len(first), parts - 1))
    arc = _polar_lerp(lo, hi, w, origin.reshape(-1, 3)[first], frame.reshape(-1, 3, 3)[first])
    line = lo[:, None] + w[..., None] * (hi - lo)[:, None]
    points = np.where(is_chord[:, None, None], line, arc)
    if fixed is not None and len(fixed[0]):
        at = np.minimum(np.searchsorted(fixed[0], edge), len(fixed[0]) - 1)
        hit = fixed[0][at] == edge
        points[hit] = fixed[1][at[hit]]
    out = points[flat]
    out[flip] = out[flip, ::-1]
    return out.reshape(m, 4, parts - 1, 3), (edge, points)


def _cut_rows(cells: np.ndarray, edges: np.ndarray, inner: np.ndarray, base: int) -> tuple[np.ndarray, np.ndarray]:
    """Each hexahedron ``cells`` (m, 8) cut in ``parts`` across its edges ``edges`` (m, 4, 2) at the points
    ``inner`` (m, 4, parts - 1, 3), numbered from ``base``: the new points and the pieces
    (m parts, 8), row by row, each in its cell's VTK order."""
    m, parts = len(cells), inner.shape[2] + 1
    idx = np.arange(m)[:, None]
    ids = base + np.arange(m * 4 * (parts - 1)).reshape(m, 4, parts - 1)
    chain = np.concatenate([cells[idx, edges[:, :, 0]][..., None], ids, cells[idx, edges[:, :, 1]][..., None]], axis=2)
    slot = np.zeros((m, 8), np.int64)  # corner c: on the row's edge slot[c], at its 'a' (0) or 'b' (1) end
    end = np.zeros((m, 8), np.int64)
    for k in range(4):
        slot[idx[:, 0], edges[:, k, 0]] = k
        slot[idx[:, 0], edges[:, k, 1]] = k
        end[idx[:, 0], edges[:, k, 1]] = 1
    j = np.arange(parts)[None, :, None]
    pieces = chain[np.arange(m)[:, None, None], slot[:, None, :], j + end[:, None, :]]
    return inner.reshape(-1, 3), pieces.reshape(-1, 8)


def parse_plank(text: str) -> tuple[np.ndarray, float, float]:
    """``"normal=x,offset=0.3,thickness=0.02"`` -> (normal 3-vector, offset, thickness)."""
    values = {}
    for part in str(text).split(","):
        name, sep, value = part.partition("=")
        name = name.strip().lower()
        if not sep or name not in ("normal", "offset", "thickness"):
            raise ValueRefused(f"--plank expects normal=AXIS,offset=NUMBER,thickness=NUMBER, got {text!r}")
        values[name] = value.strip()
    normal = values.get("normal", "x").lower()
    axes = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
    if normal in axes:
        n = np.array(axes[normal])
    else:
        try:
            n = np.array([float(v) for v in normal.split(":")])
        except ValueError:
            raise ValueRefused(f"plank normal must be x, y, z or X:Y:Z, got {normal!r}") from None
        if n.shape != (3,) or not np.all(np.isfinite(n)) or not np.linalg.norm(n) > 0:
            raise ValueRefused(f"plank normal must be a non-zero finite 3-vector, got {normal!r}")
    try:
        offset, thickness = float(values.get("offset", 0.0)), float(values.get("thickness", 0.02))
    except ValueError:
        raise ValueRefused(f"plank offset and thickness must be numbers, got {text!r}") from None
    if not (math.isfinite(offset) and math.isfinite(thickness)) or thickness <= 0:
        raise ValueRefused(f"plank thickness must be a positive finite number and offset finite, got {text!r}")
    return n / np.linalg.norm(n), offset, thickness


def plank(grid: pv.UnstructuredGrid, normal: ArrayLike, offset: float, thickness: float) -> pv.UnstructuredGrid:
    """The slab ``offset <= n · (x - axis) <= offset + thickness`` of a wood grid (VTK clips).

    ``offset`` is measured from the trunk's axis (the line x = y = 0); an
    empty slab raises :class:`ValueRefused` naming the model's extent.
    """
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    lower = grid.clip(normal=tuple(-n), origin=tuple(offset * n), invert=True)
    slab = lower.clip(normal=tuple(n), origin=tuple((offset + thickness) * n), invert=True) if lower.n_cells else lower
    if slab.n_cells == 0:
        pts = np.asarray(grid.points)
        reach = float(np.max(pts @ n)) if len(pts) else 0.0
        raise ValueRefused(f"the plank at offset {offset:g} misses the wood (it reaches {reach:.4g} along the normal)")
    if "axis" in grid.cell_data and np.any(np.asarray(grid.cell_data["axis"]) == 0):
        if not np.any(np.asarray(slab.cell_data["axis"]) == 0):  # a sliver of branch or nothing: no board
            ids = np.flatnonzero(np.asarray(grid.cell_data["axis"]) == 0)
            trunk = np.asarray(grid.extract_cells(ids).points)  # type: ignore[arg-type]  # pyvista stubs want int64
            reach = float(np.max(trunk @ n))
            raise ValueRefused(
                f"the plank at offset {offset:g} misses the trunk (it reaches {reach:.4g} along the normal); "
                "only branch wood would be left"
            )
    return slab


PLANK_PRESETS = {"flat-sawn": 0.5, "quarter-sawn": 0.0, "rift": 0.3}
"""Plank offset from the pith as a fraction of the trunk's radius: a flat-sawn board shows arches
(rings nearly in its face), a quarter-sawn one passes the pith (rings across its face, straight
stripes), a rift one lies between (rings at 30-60 degrees over most of its width).  A quarter-sawn
board is centred on the pith (offset ``-thickness / 2``)."""


def plank_normal(degrees: float) -> np.ndarray:
    """The horizontal plank normal at ``degrees`` around the trunk axis from +x."""
    a = math.radians(float(degrees))
    return np.array([math.cos(a), math.sin(a), 0.0])


def preset_offset(grid: pv.DataSet, preset: str, thickness: float) -> float:
    """The offset of a ``preset`` plank (:data:`PLANK_PRESETS`) in a wood grid whose trunk has ``axis == 0``.

    The radius is the trunk's wood under the bark (its cells' centres)."""
    if preset not in PLANK_PRESETS:
        raise ValueRefused(f"unknown plank preset {preset!r}; choose one of {', '.join(PLANK_PRESETS)}")
    if preset == "quarter-sawn":
        return -0.5 * thickness
    axis = np.asarray(grid.cell_data["axis"]) if "axis" in grid.cell_data else np.zeros(grid.n_cells)
    wood = np.asarray(grid.cell_data["wood"]) != CODES["bark"] if "wood" in grid.cell_data else True
    centres = np.asarray(grid.cell_centers().points)[(axis <= 0) & wood]  # the trunk's wood, under the bark
    radius = float(np.max(np.hypot(centres[:, 0], centres[:, 1]))) if len(centres) else 0.0
    return PLANK_PRESETS[preset] * radius


def plank_camera(
    points: ArrayLike,
    normal: ArrayLike,
    aspect: float = 1.0,
    window: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
    upright: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(position, focal point, view up, parallel scale)`` that show a plank's face filling a view.

    The camera faces the board's inner face (the one at ``offset``, nearer the
    pith: a flat-sawn board's arches); the trunk axis (z) runs across the
    view, the board's width up, or with ``upright`` the trunk axis up (as the
    tree stood: for a view taller than wide, such as a dock); a cross-cut
    (normal z) is drawn the same either way.  ``aspect`` is width over height.  ``window`` is
    the part of the view the board fills, ``(left, bottom, right, top)`` as
    fractions of the view from its lower left corner (the rest is free for a
    title or a legend): the board's bounding box is centred in it and fills it
    but for a 2 % margin on its tighter side.
    """
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    up = np.cross(n, [0.0, 0.0, 1.0])
    if not np.linalg.norm(up) > 1e-6:  # a cross-cut plank (normal z): x across, y up
        up = np.array([0.0, 1.0, 0.0])
    elif upright:  # the trunk axis up: z less its part along the normal
        up = np.array([0.0, 0.0, 1.0]) - n[2] * n
    up = up / np.linalg.norm(up)
    right = np.cross(n, up)  # the view's right: direction of projection x view up
    pts = np.asarray(points, float)
    across, high, deep = pts @ right, pts @ up, pts @ n
    length, width = float(np.ptp(across)) or 1.0, float(np.ptp(high)) or 1.0
    x0, y0, x1, y1 = window
    scale = 0.5 * max(length / (aspect * (x1 - x0)), width / (y1 - y0)) * 1.04
    centre = right * _middle(across) + up * _middle(high) + n * _middle(deep)  # of the board's box
    focal = centre - right * (x0 + x1 - 1.0) * scale * aspect - up * (y0 + y1 - 1.0) * scale  # the window's off centre
    return focal - n * length * 3.0, focal, up, scale  # from the pith's side: the face at ``offset``


def _middle(values: np.ndarray) -> float:
    """Halfway between the least and the greatest of ``values``."""
    return 0.5 * float(values.min() + values.max())


def plank_window(slab: pv.DataSet, length: float | None = None, at: float | None = None) -> tuple[pv.DataSet, float, float]:
    """A length of a plank around a knot: ``(part, centre, length)`` along the trunk axis (z).

    ``at`` is the centre height (default: the middle of the plank's largest
    knot, else of the plank); ``length`` defaults to three times the board's
    width, so its rings show as lines once the part fills a picture.
    """
    b = np.asarray(slab.bounds, float).reshape(3, 2)
    if length is None:
        length = 3.0 * float(np.max(b[:2, 1] - b[:2, 0]))
    if not (math.isfinite(length) and length > 0):
        raise ValueRefused(f"plank length must be a positive number, got {length:g}")
    if at is None:
        at = _knot_centre(slab) if "axis" in slab.cell_data else None
        at = float(b[2].mean()) if at is None else at
    if not b[2, 0] <= at <= b[2, 1]:
        raise ValueRefused(f"plank centre z = {at:g} is off the plank (it spans {b[2, 0]:.4g}..{b[2, 1]:.4g})")
    part = slab.clip_box((b[0, 0] - 1, b[0, 1] + 1, b[1, 0] - 1, b[1, 1] + 1, at - length / 2, at + length / 2), invert=False)
    return part, float(at), float(length)


def _knot_centre(slab):
    """Height of the centre of the plank's largest knot region (``None`` without knots)."""
    ids = np.flatnonzero(np.asarray(slab.cell_data["axis"]) >= 1)
    if not ids.size:
        return None
    conn = slab.extract_cells(ids).connectivity("largest")
    return float(np.asarray(conn.cell_centers().points)[:, 2].mean())


def cut_facts(grid: pv.DataSet) -> dict[str, Any]:
    """``{"rings", "knots", "live_knots", "dead_knots"}`` of a cut or plank: distinct trunk ring
    years, knot regions, and how many of them are alive and dead (:func:`knot_states`)."""
    axis = np.asarray(grid.cell_data["axis"])
    tissue = np.asarray(grid.cell_data["wood"])
    year = np.asarray(grid.cell_data["year"])
    trunk_wood = (axis == 0) & np.isin(tissue, [CODES["sapwood"], CODES["heartwood"]])
    rings = int(len(np.unique(year[trunk_wood])))
    live, dead = knot_states(grid)
    return {"rings": rings, "knots": live + dead, "live_knots": live, "dead_knots": dead}


def _knot_cells(grid: pv.DataSet) -> np.ndarray:
    """Ids of a grid's knot cells: a branch's (``axis >= 1``) pith, wood and bark; the rings laid
    round a dead knot are trunk wood (sapwood, heartwood) and not part of it."""
    data = grid.cell_data
    knot = np.asarray(data["axis"]) >= 1
    if "wood" in data:
        knot &= ~np.isin(np.asarray(data["wood"]), [CODES["sapwood"], CODES["heartwood"]])
    return np.flatnonzero(knot)


def knot_regions(grid: pv.DataSet) -> int:
    """Number of connected regions of knot cells (branch cells but the rings round a dead knot)."""
    return sum(knot_states(grid))


def knot_states(grid: pv.DataSet) -> tuple[int, int]:
    """``(live, dead)``: the grid's knot regions, a region dead if it holds a dead knot's cell
    (cell data ``dead``; without it every knot is alive)."""
    ids = _knot_cells(grid)
    if not ids.size:
        return 0, 0
    part = grid.extract_cells(ids)
    conn = part.connectivity()
    region = np.asarray(conn.cell_data["RegionId"])
    n = int(region.max()) + 1 if region.size else 0
    if "dead" not in conn.cell_data:
        return n, 0
    dead_regions = np.unique(region[np.asarray(conn.cell_data["dead"]) > 0])
    return n - len(dead_regions), len(dead_regions)


def knot_roundness(section: pv.DataSet, normal: ArrayLike) -> list[float]:
    """Area over smallest bounding rectangle of each knot (``axis >= 1`` region) on a plane section.

    ``section`` is a slice of a wood grid (polygons in a plane of the given
    ``normal``); a round knot scores pi/4 (0.785), a square one 1.  The
    rectangle is the smallest over rotations in 1 degree steps.
    """
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    u = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    ids = np.flatnonzero(np.asarray(section.cell_data["axis"]) >= 1)
    if not ids.size:
        return []
    regions = section.extract_cells(ids).connectivity()  # type: ignore[arg-type]  # pyvista stubs want int64
    region = np.asarray(regions.cell_data["RegionId"])
    area = np.asarray(regions.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
    turn = np.radians(np.arange(90))
    out = []
    for r in np.unique(region):  # one per knot: a handful
        pts = np.asarray(regions.extract_cells(np.flatnonzero(region == r)).points)
        a, b = pts @ u, pts @ v
        x = np.outer(np.cos(turn), a) + np.outer(np.sin(turn), b)
        y = np.outer(-np.sin(turn), a) + np.outer(np.cos(turn), b)
        box = np.ptp(x, axis=1) * np.ptp(y, axis=1)
        out.append(float(area[region == r].sum() / box.min()))
    return out


# ---------------------------------------------------------------------- from a plant
def _trunk_chain(skeleton):
    """Indices of the trunk's segments, base to top: order-0 segments following parents."""
    order = np.asarray(skeleton.order)
    parent = np.asarray(skeleton.parent)
    trunk = np.flatnonzero(order == order.min(initial=0))
    if not trunk.size:
        raise ValueRefused("the plant has no segments: derive it with more steps")
    child = {int(parent[i]): int(i) for i in trunk}
    start = [int(i) for i in trunk if parent[i] < 0 or order[parent[i]] != order.min()]
    chain = [start[0]]
    while chain[-1] in child and len(chain) <= len(trunk):
        chain.append(child[chain[-1]])
    return np.array(chain)


def _subtree(parent: np.ndarray, segment: int) -> np.ndarray:
    """Mask of a segment and every segment growing from it, at any depth."""
    inside = np.zeros(len(parent), bool)
    inside[segment] = True
    for _ in range(len(parent)):
        grow = ~inside & (parent >= 0) & inside[np.maximum(parent, 0)]
        if not grow.any():
            break
        inside |= grow
    return inside


def _subtree_leaves(skeleton, segment):
    """History-leaf ids of a segment and every segment growing from it."""
    inside = _subtree(np.asarray(skeleton.parent), segment)
    return sorted(set(np.asarray(skeleton.leaf_id)[inside].tolist()))


def _continuations(skeleton) -> dict[int, int]:
    """Segment -> the segment continuing its axis (same order, growing from it)."""
    order, parent = np.asarray(skeleton.order), np.asarray(skeleton.parent)
    out: dict[int, int] = {}
    for i in np.flatnonzero((parent >= 0) & (order == order[np.maximum(parent, 0)])).tolist():
        out.setdefault(int(parent[i]), int(i))
    return out


def _axis_chain(first: int, cont: Mapping[int, int], limit: int) -> list[int]:
    """Segment ``first`` and the segments continuing its axis, base to tip."""
    chain = [int(first)]
    while chain[-1] in cont and len(chain) <= limit:
        chain.append(cont[chain[-1]])
    return chain


def skeleton_branches(
    skeleton: Skeleton,
    p: Mapping[str, Any],
    years: int,
    frames: np.ndarray,
    cuts: np.ndarray,
    arc: np.ndarray,
    chain: np.ndarray,
    seed: int = 0,
    steps: int | None = None,
    leaf_steps: ArrayLike | None = None,
    max_branches: int | None = None,
) -> tuple[list[Branch], list[int], dict[str, int]]:
    """The plant's branches of every order as :class:`Branch` es, hosts before the branches on them.

    Order by order: the first-order branches on the trunk (``chain``, cut at
    ``cuts`` along its arc ``arc``, unit frames ``frames``), then the
    second-order ones on each kept first-order branch, and so on.  A branch's
    birth year is the year of the derivation step that made the segment it
    grows from (``leaf_steps`` and ``steps`` given), else from where it grows:
    its height on the trunk, or its place along its host branch (the host
    grows from the year after its birth to the last year).  Its sector and
    insertion angle come from its direction in its host's frame (a host
    branch's frame is the one the wood gives it, :func:`branch_direction`).
    Left out, and counted in the returned ``left_out``: branches born in the
    last year (no ring yet) or on a host not yet born (``last_year``); less
    than ``MIN_SECTOR_GAP`` faces from an earlier branch of the same host
    and year (``too_close``); born on a host branch past its stub, whose
    ``branch_levels`` levels end before the year the branch is born
    (``beyond_stub``; ``branch_levels=0`` keeps whole branches) or after
    the host's death (``host_dead``); past ``max_branches`` in all
    (``over_max``).  Branches growing on a left-out branch are not in the
    wood either (``on_left_out``).  Returns the branches, the skeleton
    segment each starts at, and ``left_out``.
    """
    start, end = np.asarray(skeleton.start, float), np.asarray(skeleton.end, float)
    order, parent = np.asarray(skeleton.order), np.asarray(skeleton.parent)
    leaf_id = np.asarray(skeleton.leaf_id)
    cont = _continuations(skeleton)
    cap = int(p.get("branch_levels", 0))
    left_out = dict.fromkeys(("last_year", "too_close", "beyond_stub", "host_dead", "over_max", "on_left_out"), 0)
    branches: list[Branch] = []
    segments: list[int] = []
    host_frames: list[np.ndarray] = []  # each kept branch's frame past its knot
    # hosts: (branch index or -1, chain of segments, arc along it, sides)
    hosts = [(-1, np.asarray(chain, np.int64), np.asarray(arc, float))]
    seen = 0
    while seen < len(hosts):
        h, axis_chain, axis_arc = hosts[seen]
        seen += 1
        on = np.flatnonzero(np.isin(parent, axis_chain) & (order > order[axis_chain[0]]))
        where = {int(c): i for i, c in enumerate(axis_chain.tolist())}
        n = int(p["sides"] if h < 0 else p["branch_sides"])
        used: set[tuple[int, int]] = set()
        for i in on.tolist():
            if order[i] != order[axis_chain[0]] + 1:
                continue
            par = int(parent[i])
            at = axis_arc[where[par] + 1]
            if h < 0:
                year = int(min(np.searchsorted(cuts, at, side="right") - 1, years - 1))
                f = frames[year]
            else:
                born = branches[h].year
                share = at / axis_arc[-1] if axis_arc[-1] > 0 else 1.0
                year = born + 1 + int(share * max(years - 2 - born, 0))
                f = host_frames[h]
            if leaf_steps is not None and steps:
                step = int(np.asarray(leaf_steps)[int(leaf_id[par])])
                year = int(min(years - 1, max(0, step * years // max(int(steps), 1))))
            d = end[i] - start[i]
            if max_branches is not None and len(branches) >= max_branches:
                left_out["over_max"] += 1
                continue
            if h >= 0:
                host = branches[h]
                dies = death_year(p, host.year, host.death)
                if year <= host.year or year >= years - 1 or not np.linalg.norm(d) > 0:
                    left_out["last_year"] += 1
                    continue
                if cap and year - host.year >= cap:
                    left_out["beyond_stub"] += 1
                    continue
                if dies is not None and year >= dies:
                    left_out["host_dead"] += 1
                    continue
            elif not np.linalg.norm(d) > 0 or year >= years - 1:
                left_out["last_year"] += 1
                continue
            az = math.atan2(d @ f[2], d @ f[1])
            if h < 0:
                sector = int(round(az / (2 * np.pi / n))) % n
            else:  # a branch's sector k is centred on 2 pi (k + 1/2 - n/8) / n (Wood.sector_angles)
                sector = int(round(az * n / (2 * np.pi) - 0.5 + n / 8)) % n
            angle = float(np.clip(math.degrees(math.acos(np.clip(d @ f[0] / np.linalg.norm(d), -1, 1))), 5, 175))
            if any(y == year and min((sector - k) % n, (k - sector) % n) < MIN_SECTOR_GAP for y, k in used):
                left_out["too_close"] += 1  # the thesis's topological correction: too close
                continue
            used.add((year, sector))
            branches.append(Branch(year, sector, mix(seed, 1000 + len(branches)), angle=angle, parent=h))
            segments.append(int(i))
            centre = 2 * np.pi * sector / n if h < 0 else 2 * np.pi * (sector + 0.5 - n / 8) / n
            host_frames.append(branch_direction(f, centre, math.radians(90.0 - angle)))
            sub_chain = np.array(_axis_chain(int(i), cont, len(order)), np.int64)
            seg = np.linalg.norm(end[sub_chain] - start[sub_chain], axis=1)
            hosts.append((len(branches) - 1, sub_chain, np.concatenate([[0.0], np.cumsum(seg)])))
        for i in on.tolist():  # the branches on a left-out branch
            if order[i] == order[axis_chain[0]] + 1 and int(i) not in segments:
                left_out["on_left_out"] += _subtree_branches(order, parent, int(i))
    return branches, segments, left_out


def _subtree_branches(order: np.ndarray, parent: np.ndarray, segment: int) -> int:
    """Branches (axis starts) growing on the axis from ``segment`` and on those, at any depth."""
    inside = _subtree(parent, segment)
    starts = inside & (parent >= 0) & (order > order[np.maximum(parent, 0)])
    starts[segment] = False
    return int(starts.sum())


def from_skeleton(
    skeleton: Skeleton,
    years: int,
    species: str = "pine",
    seed: int = 0,
    steps: int | None = None,
    leaf_steps: ArrayLike | None = None,
    max_branches: int | None = None,
    **params: Any,
) -> Wood:
    """Volumetric wood of a derived Ramure plant: its trunk and its branches of every order.

    The trunk polyline (order-0 segments from the base) is cut into
    ``years`` yearly units of equal length; each unit's frame follows the
    polyline there (a bent trunk bends the pith and its rings).  Each
    first-order branch growing from the trunk becomes a knot in the trunk, and
    each branch growing on a branch a knot in that branch's wood, in a node
    its host grows in the branch's birth year, and so on
    (:func:`skeleton_branches`: birth years from the derivation, sectors and
    insertion angles from the directions).  Branches born the same year on
    the same host less than ``MIN_SECTOR_GAP`` faces from an earlier one
    (the thesis's "topological correction" refusing a branch too close to
    another: two knots of one node that near crowd the ring between them),
    or born in the last year, are left out.

    *The dart budget (a choice).*  A branch is grown as a stub of
    ``branch_levels`` yearly levels (the species' 2: its knot and one year
    past its host's bark; 0 keeps whole branches), so a sub-branch is in
    the wood only if it is born while its host's stub still grows (within
    ``branch_levels - 1`` years of the host's birth); the others are left
    out and counted (``gm.meta["left_out"]``, ``beyond_stub``).  No count
    cap: ``max_branches`` (default none) keeps at most that many knots of
    every order, in order.  The wood's darts are :func:`estimated_darts`
    (exact) and are checked before growing: over ``MAX_DARTS`` the wood is
    refused with the knots by order and what to change.
    ``gm.meta["orders"]`` gives each branch's order (1 on the trunk).
    Units are the plant's.
    """
    years = check_years(years)
    p = resolve_params(species, **params)
    start, end = np.asarray(skeleton.start, float), np.asarray(skeleton.end, float)
    chain = _trunk_chain(skeleton)
    pts = np.concatenate([start[chain[:1]], end[chain]])
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    if not arc[-1] > 0:
        raise ValueRefused("the plant's trunk has zero length")
    cuts = np.linspace(0.0, arc[-1], years + 1)
    pos = np.stack([np.interp(cuts, arc, pts[:, j]) for j in range(3)], axis=1)
    heading = np.diff(pos, axis=0)
    h = np.linalg.norm(heading, axis=1)
    from ramure.gmap.kernel.frames import frame_from

    frames = frame_from(heading, np.cross(heading, [0.0, 0.0, 1.0]) + np.array([1e-9, 1.0, 0.0]))
    frames = frame_from(heading, np.repeat(frames[:1, 1], years, axis=0))  # one turn of L for all units
    branches, segments, left_out = skeleton_branches(
        skeleton, p, years, frames, cuts, arc, chain, seed=seed, steps=steps, leaf_steps=leaf_steps, max_branches=max_branches
    )
    orders = branch_orders(branches)
    est = estimated_darts(p, years, [b.year for b in branches], None, [b.parent for b in branches])
    if est > MAX_DARTS:
        by_order = ", ".join(f"{n} of order {o}" for o, n in sorted(Counter(orders).items()))
        raise ValueRefused(
            f"this wood would have about {est:,} darts, more than the limit of {MAX_DARTS:,} "
            f"(knots: {by_order or 'none'}); grow fewer years, derive fewer steps or set branch_levels lower"
        )
    t0 = time.perf_counter()
    wood = Wood(p, seed, branches, species, trunk_frames=(pos[:-1], frames, h), years=years)
    for _ in range(2 * years):
        wood.step()
    wood.embed()
    wood.seconds = time.perf_counter() - t0
    wood.gm.meta = {
        "species": species,
        "years": years,
        "seed": int(seed),
        "from": "skeleton",
        "branches": [(b.year, b.sector) for b in branches],
        "parents": [b.parent for b in branches],
        "orders": orders,
        "left_out": left_out,
        "branch_segments": segments,  # the skeleton segment each branch starts at
        "branch_leaves": _own_leaves(skeleton, branches, segments),
    }
    return wood


def _own_leaves(skeleton, branches, segments):
    """Per branch, the history leaves of its plant branch less those of its sub-branches in the
    wood: each leaf maps to the knot of the deepest branch of the wood it grows on."""
    leaves = [set(_subtree_leaves(skeleton, i)) for i in segments]
    own = [set(x) for x in leaves]
    for b, br in enumerate(branches):
        if br.parent >= 0:
            own[br.parent] -= leaves[b]
    return [sorted(x) for x in own]


def orders_text(knots_by_order: Mapping[str, int], left_out: Mapping[str, int] | None = None) -> str:
    """The knots by order and the plant's branches left out, as words (empty for trunk knots only).

    >>> orders_text({"1": 3, "2": 2}, {"last_year": 7, "beyond_stub": 1, "too_close": 0})
    ' (by order 1: 3, 2: 2); left out: 7 last year, 1 beyond stub'
    """
    text = ""
    if knots_by_order and max(int(o) for o in knots_by_order) > 1:
        text = " (by order " + ", ".join(f"{o}: {n}" for o, n in knots_by_order.items()) + ")"
    left = {k: v for k, v in (left_out or {}).items() if v}
    if left:
        text += "; left out: " + ", ".join(f"{n} {k.replace('_', ' ')}" for k, n in left.items())
    return text


def branch_orders(branches: Sequence[Branch]) -> list[int]:
    """Each branch's order: 1 on the trunk, one more than its host's on a branch.

    >>> branch_orders([Branch(1, 0, 0), Branch(2, 3, 0, parent=0), Branch(3, 1, 0, parent=1)])
    [1, 2, 3]
    """
    out: list[int] = []
    for br in branches:
        out.append(1 if br.parent < 0 else out[br.parent] + 1)
    return out


def plank_map(gm: GMap3, normal: ArrayLike, offset: float, thickness: float) -> GMap3:
    """The plank as a 3-G-map (two kernel map cuts), so it can be cut again, textured, cracked.

    Keeps ``offset <= n . x <= offset + thickness`` like :func:`plank`; the
    new faces are labelled ``X`` and the volumes keep their attributes
    (tissue, season, axis...).  Refused by the kernel when a plane misses.
    """
    from ramure.gmap.kernel.cut import cut_map

    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    inner = cut_map(gm, -n, offset * n)
    return cut_map(inner, n, (offset + thickness) * n)
