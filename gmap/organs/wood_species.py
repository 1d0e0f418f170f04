"""Wood species: pine, larch, elm and oak -- their numbers, their bark, reaction wood and texture.

The volumetric wood (:mod:`ramure.gmap.organs.wood`) reads its species
presets from :data:`SPECIES` here.  Each species has its own ring width law
(earlywood and latewood bounds at the pith, the juvenile decay), hence its own
latewood share; its heartwood age, sapwood rings and colours; its branch
pattern (whorls or scattered branches, :func:`place_whorls`); its bark law
with shedding and a rough outer surface (:func:`shed_bark`); compression or
tension wood (:func:`reaction_marks`); and a texture for pictures: earlywood
pores of ring-porous oak and elm, elm's wavy latewood pore bands, resin canals
of pine and larch, and rays (:func:`texture_face`).

Sources of the numbers (each value is a round figure inside the range these
give; where a value is our choice the table says so):

- [WAG] Wagenführ, R. (2007) *Holzatlas*, 6th ed., Hanser: colours of
  sapwood and heartwood, ring-porous / not, ray visibility.
- [SCH] Schweingruber, F. H. (1990) *Anatomie europäischer Hölzer*,
  Haupt: pore diameters (oak earlywood vessels 0.2-0.4 mm, elm 0.15-0.3 mm),
  elm's ulmiform latewood bands, ray widths (oak's broad rays up to
  1 mm wide and several cm tall; elm up to 6 cells; pine and larch uniseriate),
  resin canals of pine and larch.
- [ZOB] Zobel, B. J. and van Buijtenen, J. P. (1989) *Wood Variation*,
  Springer: juvenile wood (wider rings near the pith: the ``decay`` of the
  law), latewood percentages (Scots pine 20-35 %, larch 30-45 %).
- [HOL] Hollstein, E. (1980) *Mitteleuropäische Eichenchronologie*: oak
  sapwood of 10-30 rings (median about 20).
- [UNECE] UNECE/FAO (2020) *Forest product conversion factors*: bark
  volume in per cent of over-bark volume, about 10-12 % for pine and elm,
  15-20 % for larch and oak.  A bark share ``v`` of the volume is a bark
  thickness ``b = R (1 / sqrt(1 - v) - 1)`` over a wood radius ``R``:
  ``bark_ratio`` below (pine v = 12 % gives 0.066, larch 17 % 0.098, oak
  16 % 0.091, elm 12 % 0.066).
- [KOZ] Kozlowski, T. T. and Pallardy, S. G. (1997) *Growth control in
  woody plants*: branching -- rhythmic whorls in pines, scattered branches
  in larch (long shoots), clusters at the end of the annual shoot in oak,
  distichous (two-ranked) branches in elm; compression wood on the lower
  side of conifer branches and leaning stems, tension wood on the upper side
  in broadleaves (also Timell 1986, *Compression wood in gymnosperms*).

Choices (ours): the ages are compressed so a 10-30 year model shows its
heartwood (pine's heartwood begins at 8 years here, about 20-30 in a forest
pine; oak keeps 10 sapwood rings, not 20); the bark's yearly layer widths
(``bark_min``, ``bark_max``) are set so shedding starts after a few years; the
colours are picked from photographs of planed, unfinished boards.

*Bark (a choice; the thesis has no bark).*  The 3G-map keeps one bark cell
per stack and year (spec decision 7); the outer ones are *shed*: the live bark
of a stack is at most ``cap = min(bark_cap, bark_ratio * R) * rough``, its
newest (innermost) layers keep their width while they fit under the cap, the
layer that crosses it is trimmed, and the outer ones shrink to
:data:`SHED_WIDTH` (the cells stay in the map, so the darts' closed forms and
chi are unchanged; they are flaked-off scales 50 um thick (thinner cells fold in a knot's seam)).  ``rough`` is
1 on a plate or ridge and ``fissure_depth`` in a fissure: pine and larch have
*plates* (stacks in fissures at random, in both directions), oak and elm
*ridges* (every other stack round the trunk, shifting by one every few
years, so ridges run up the trunk and interlace).  Young bark, thinner than
the cap, is smooth: the fissures appear as the bark starts to shed, as on a
young pine.  Pictures colour the inner bark (the newest layer), the plates
and the fissures apart.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import ValueRefused

if TYPE_CHECKING:
    import pyvista as pv

#: Radial width (m) of a shed bark cell: the scale has fallen, its cell stays in the map.
SHED_WIDTH = 5e-5

#: ``bark`` volume attribute: not bark, inner bark (the newest layer), outer bark on a plate or
#: ridge, outer bark in a fissure, shed on a plate, shed in a fissure, and the bark of a dead
#: knot that the trunk's later rings encase (``Wood.assign_roles``; drawn as dark as a fissure).
BARK_NONE, BARK_INNER, BARK_PLATE, BARK_FISSURE, SHED_PLATE, SHED_FISSURE, BARK_ENCASED = -1, 0, 1, 2, 3, 4, 5

#: ``reaction`` volume attribute: none, compression wood (softwoods), tension wood (hardwoods).
REACTION_NONE, COMPRESSION, TENSION = 0, 1, 2

#: Half-angle (degrees) of the reaction-wood sector of a branch, round its lowest (softwoods) or
#: highest (hardwoods) side: a third of the circumference (a choice; Timell 1986 shows it over
#: a quarter to a half of a conifer branch's section).
REACTION_HALF_ANGLE = 60.0

#: Share of silver-white mixed into tension wood's colour (:func:`reaction_rgb`).
TENSION_VEIL = 0.12

COMMON: dict[str, Any] = dict(
    sides=16,
    branch_sides=16,
    branch_levels=2,
    branch_angle=60.0,
    branch_length=0.15,
    branch_scale=0.5,
    branches=3,
    branch_start=1,
    reaction=0.0,
    reaction_angle=0.0,
    width_floor=0.35,
    height_jitter=0.0,
    whorl=1,
    divergence=137.5,
    fissure_depth=0.4,
    branch_life=0,
)

#: Species presets: geometry in metres, widths per half-year cell, colours as hex RGB.
#: ``kind``: softwood (compression wood) or hardwood (tension wood); ``bark_pattern``: plates or
#: ridges; ``texture``: pores, resin canals and rays for pictures (sizes in metres).
SPECIES: dict[str, dict[str, Any]] = {
    # Scots pine, Pinus sylvestris.  Latewood share 27 % [ZOB 20-35 %]; pale wide sapwood, reddish
    # heartwood [WAG]; 3 branches a whorl, one whorl a year [KOZ]; plated bark, grey-brown below
    # [WAG]; resin canals, uniseriate rays (not seen) [SCH].
    "pine": dict(
        COMMON,
        kind="softwood",
        pith_radius=0.003,
        height=0.5,
        early_min=0.0025,
        early_max=0.0045,
        late_min=0.0008,
        late_max=0.0018,
        decay=25.0,
        bark_min=0.0006,
        bark_max=0.0012,
        bark_ratio=0.066,
        bark_cap=0.03,
        bark_pattern="plates",
        fissure_depth=0.35,
        sapwood_rings=6,
        heartwood_age=8,
        branches=6,
        whorl=3,
        divergence=137.5,
        colors=dict(
            pith="#5b3b22",
            heartwood=("#d9a266", "#a65f2c"),
            sapwood=("#f3deb0", "#cf9d5c"),
            bark=("#b9825a", "#6b4a35", "#2e211a"),  # inner bark, plates, fissures
            knot=("#8a5527", "#5b3314"),
        ),
        texture=dict(resin=dict(size=0.00018, spacing=0.0022)),
    ),
    # European larch, Larix decidua.  Abrupt dark latewood, share 38 % [ZOB 30-45 %]; narrow
    # sapwood, red-brown heartwood early [WAG]; scattered branches on long shoots [KOZ]; thick,
    # deeply fissured reddish scaly bark, the largest bark share of the four [UNECE].
    "larch": dict(
        COMMON,
        kind="softwood",
        pith_radius=0.003,
        height=0.6,
        early_min=0.0018,
        early_max=0.0034,
        late_min=0.0010,
        late_max=0.0022,
        decay=20.0,
        bark_min=0.0008,
        bark_max=0.0016,
        bark_ratio=0.098,
        bark_cap=0.04,
        bark_pattern="plates",
        fissure_depth=0.3,
        sapwood_rings=4,
        heartwood_age=6,
        branch_angle=75.0,
        branches=5,
        whorl=1,
        divergence=137.5,
        colors=dict(
            pith="#5a3020",
            heartwood=("#cf8a5a", "#8c3f22"),
            sapwood=("#ecd8ae", "#c79a63"),
            bark=("#b86a4a", "#7a4a3a", "#33201a"),
            knot=("#7e3f22", "#4f2412"),
        ),
        texture=dict(resin=dict(size=0.00012, spacing=0.003)),
    ),
    # Field elm, Ulmus minor.  Ring-porous: one or two rows of earlywood pores, latewood pores
    # in wavy tangential (ulmiform) bands [SCH]; latewood share 74 %; narrow pale sapwood,
    # brown heartwood [WAG]; two-ranked branches, 180 degrees apart [KOZ]; furrowed bark with
    # interlacing ridges.
    "elm": dict(
        COMMON,
        kind="hardwood",
        pith_radius=0.0025,
        height=0.4,
        early_min=0.0007,
        early_max=0.0011,
        late_min=0.0014,
        late_max=0.0036,
        decay=30.0,
        bark_min=0.0006,
        bark_max=0.0012,
        bark_ratio=0.066,
        bark_cap=0.03,
        bark_pattern="ridges",
        fissure_depth=0.4,
        sapwood_rings=5,
        heartwood_age=8,
        branch_angle=55.0,
        branches=4,
        whorl=1,
        divergence=180.0,
        colors=dict(
            pith="#4a3020",
            heartwood=("#b27a50", "#7d4a2c"),
            sapwood=("#e6d2ab", "#c7a57a"),
            bark=("#c8a980", "#6a5d50", "#2c241e"),
            knot=("#6d4028", "#46271a"),
        ),
        texture=dict(
            pores=dict(size=0.00022, spacing=0.0005),
            waves=dict(size=0.00008, spacing=0.00025, period=0.0008, amplitude=0.0004),
            rays=dict(width=0.00008, height=0.0008, spacing=0.0012, length=0.008, lighten=0.12),
        ),
    ),
    # Pedunculate / sessile oak, Quercus robur / petraea.  Ring-porous: a band of large earlywood
    # vessels 0.2-0.4 mm [SCH]; latewood share 66 %; broad rays up to 1 mm wide, 1-4 cm tall:
    # the silver figure of quarter-sawn oak [SCH, WAG]; 10 sapwood rings (a choice, [HOL] gives
    # about 20); branches clustered at the top of each annual shoot, 2/5 phyllotaxis (144
    # degrees) [KOZ]; ridged grey bark with deep fissures.
    "oak": dict(
        COMMON,
        kind="hardwood",
        pith_radius=0.0025,
        height=0.35,
        early_min=0.0008,
        early_max=0.0012,
        late_min=0.0010,
        late_max=0.0028,
        decay=40.0,
        bark_min=0.0008,
        bark_max=0.0015,
        bark_ratio=0.091,
        bark_cap=0.04,
        bark_pattern="ridges",
        fissure_depth=0.3,
        sapwood_rings=10,
        heartwood_age=12,
        branch_angle=50.0,
        branches=4,
        whorl=2,
        divergence=144.0,
        colors=dict(
            pith="#4a3520",
            heartwood=("#bb9260", "#8a6038"),
            sapwood=("#ead6ad", "#c9a677"),
            bark=("#a98a6a", "#6f6a62", "#2f2a25"),
            knot=("#6d4a2a", "#4a2f18"),
        ),
        texture=dict(
            pores=dict(size=0.0003, spacing=0.0006),
            rays=dict(width=0.0005, height=0.025, spacing=0.0025, length=0.012, lighten=0.35),
        ),
    ),
}

#: Species parameters a user may set (``--set name=value``), on top of the wood's own.
PARAMETERS = {
    "bark_ratio": "largest live bark thickness over the wood radius under it (outer layers are shed beyond)",
    "bark_cap": "largest live bark thickness (m)",
    "fissure_depth": "live bark in a fissure over that on a plate or ridge (0, 1]",
    "whorl": "branches born together at one node (a whorl; 1: scattered)",
    "divergence": "angle (degrees) from one node's branches to the next node's",
}


def check(p: Mapping[str, Any]) -> None:
    """Refuse species parameters out of range (:class:`ValueRefused`)."""
    for name in ("bark_ratio", "bark_cap", "fissure_depth", "divergence"):
        if not math.isfinite(p[name]):
            raise ValueRefused(f"{name} must be a finite number, got {p[name]}")
    if not 0 < p["bark_ratio"] <= 1:
        raise ValueRefused(f"bark_ratio must be in (0, 1], got {p['bark_ratio']}")
    if not 0 < p["bark_cap"] <= 1:
        raise ValueRefused(f"bark_cap must be in (0, 1] m, got {p['bark_cap']}")
    if not 0 < p["fissure_depth"] <= 1:
        raise ValueRefused(f"fissure_depth must be in (0, 1], got {p['fissure_depth']}")
    if p["whorl"] < 1:
        raise ValueRefused(f"whorl must be >= 1, got {p['whorl']}")


def latewood_share(p: Mapping[str, Any]) -> float:
    """Mean latewood width over mean ring width of the species' law (the floor and decay cancel)."""
    late = p["late_min"] + p["late_max"]
    return late / (p["early_min"] + p["early_max"] + late)


# ---------------------------------------------------------------------- bark
def bark_cap(p: Mapping[str, Any], wood_radius: ArrayLike) -> np.ndarray:
    """Largest live bark thickness over a wood radius: ``min(bark_cap, bark_ratio * R)``."""
    return np.minimum(p["bark_cap"], p["bark_ratio"] * np.asarray(wood_radius, float))


def shed_profile(widths: ArrayLike, cap: float) -> np.ndarray:
    """Widths of one stack's bark layers, innermost (newest) first, after shedding beyond ``cap``."""
    w = np.asarray(widths, float)
    before = np.concatenate([[0.0], np.cumsum(w)[:-1]])
    return np.maximum(np.minimum(w, cap - before), SHED_WIDTH)


def u01(*columns: ArrayLike) -> np.ndarray:
    """Uniform numbers in [0, 1) from integer key arrays: splitmix64 steps, the values of
    ``ramure.gmap.organs.wood.u01_array`` (which this module must not import: wood imports it)."""
    arrays = [np.asarray(c) for c in columns]
    h = np.full(np.broadcast(*arrays).shape, 0x9E3779B97F4A7C15, np.uint64)
    with np.errstate(over="ignore"):
        for c in arrays:
            h ^= c.astype(np.int64).astype(np.uint64)
            h *= np.uint64(0xBF58476D1CE4E5B9)
            h ^= h >> np.uint64(31)
            h *= np.uint64(0x94D049BB133111EB)
            h ^= h >> np.uint64(29)
    h &= np.uint64((1 << 63) - 1)
    return h.view(np.int64) / float(1 << 63)


def roughness(p: Mapping[str, Any], seed: ArrayLike, axis: ArrayLike, level: ArrayLike, sector: ArrayLike) -> np.ndarray:
    """True where a stack lies in a bark fissure: plates at random, or ridges that interlace."""
    seed, axis, level, sector = (np.asarray(a, np.int64) for a in (seed, axis, level, sector))
    if p.get("bark_pattern") == "ridges":
        shift = np.floor(2.0 * u01(seed, 32, level // 3)).astype(np.int64)
        return (sector + shift) % 2 == 0
    return u01(seed, 31, level, sector) < 0.4


def shed_bark(
    p: Mapping[str, Any],
    stack: np.ndarray,
    depth: np.ndarray,
    widths: np.ndarray,
    wood_radius: np.ndarray,
    fissure: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Bark cell widths after shedding, and their ``bark`` attribute (see module doc).

    Per bark cell: ``stack``, a dense stack id (``0 .. stacks - 1``);
    ``depth``, its place in the stack's bark (0 = innermost, the newest
    layer); ``widths``, its drawn width; ``wood_radius`` and ``fissure``, its
    stack's wood radius and fissure flag.  No sort: the layers go into a
    dense ``stacks x layers`` table whose row sums give each layer the bark
    inside it.
    """
    widths = np.asarray(widths, float)
    if stack.size == 0:
        return widths, np.zeros(0, np.int8)
    cap = bark_cap(p, wood_radius) * np.where(fissure, p["fissure_depth"], 1.0)
    table = np.zeros((int(stack.max()) + 1, int(depth.max()) + 1))
    table[stack, depth] = widths
    before = (np.cumsum(table, axis=1) - table)[stack, depth]
    kept = np.maximum(np.minimum(widths, cap - before), SHED_WIDTH)
    shed = kept < widths - 1e-12
    mark = np.where(fissure, BARK_FISSURE, BARK_PLATE) + np.where(shed, 2, 0)
    mark = np.where((depth == 0) & ~shed, BARK_INNER, mark)
    return kept, mark.astype(np.int8)


def nominal_bark(p: Mapping[str, Any], years: ArrayLike, wood_radius: ArrayLike, scale: float = 1.0) -> np.ndarray:
    """Live bark thickness from the law's mean layer width, ``years`` layers, shed beyond the cap."""
    mean = scale * 0.5 * (p["bark_min"] + p["bark_max"]) * np.asarray(years, float)
    return np.minimum(mean, bark_cap(p, wood_radius))


# ---------------------------------------------------------------------- branches and reaction wood
def place_whorls(p: Mapping[str, Any], years: int, seed: int, count: int) -> list[tuple[int, int]]:
    """``(year, sector)`` of ``count`` branches: nodes of ``whorl`` branches, one node a year at most.

    Nodes are spread over ``branch_start .. years - 1``; a node's branches
    are evenly spaced round the trunk; the next node is turned by
    ``divergence`` degrees (quantised onto the trunk's faces).  If the
    branches do not fit in whorls of ``whorl``, the nodes take more (at most
    one per trunk face; the caller refuses more).
    """
    from ramure.gmap.lsystem.engine import mix

    n = int(p["sides"])
    first = int(p["branch_start"])
    span = years - 1 - first
    per = max(int(p["whorl"]), -(-count // (span + 1)))
    nodes = -(-count // per)
    turn = int(mix(seed, 11) % n)
    out = []
    for i in range(nodes):
        year = first + (round(i * span / max(nodes - 1, 1)) if nodes > 1 else 0)
        members = min(per, count - i * per)
        base = turn + round(i * n * p["divergence"] / 360.0)
        out += [(int(year), int((base + round(j * n / members)) % n)) for j in range(members)]
    return out


def reaction_marks(p: Mapping[str, Any], axis: np.ndarray, sector: np.ndarray, wood: np.ndarray, trunk_sides: int) -> np.ndarray:
    """``reaction`` attribute of every volume: compression wood (softwoods) on the lower side of
    every branch, tension wood (hardwoods) on its upper side; in the trunk, on the wide side set
    by ``reaction`` and ``reaction_angle`` (a leaning stem's lower side for softwoods, upper for
    hardwoods), when ``reaction > 0``.  ``wood`` flags the volumes that may react: the caller
    leaves out the trunk's later rings round a dead knot (on a branch's axis, but trunk wood
    laid after the branch died, which no branch's weight bends).

    A branch's sectors are numbered from its knot's side on the slot's
    bottom wall (``Wood.branch_frame``: sectors ``0 .. m/4 - 1`` face it),
    so its lowest side is sector ``m/8 - 1/2`` and sector ``k`` faces
    ``2 pi (k - m/8 + 1/2) / m`` from straight down (checked on the
    embedded cells by the tests).
    """
    kind = COMPRESSION if p.get("kind", "softwood") == "softwood" else TENSION
    half = math.cos(math.radians(REACTION_HALF_ANGLE))
    m = int(p["branch_sides"])
    on_branch = (axis > 0) & wood
    c = np.cos(2 * np.pi * (sector - m / 8 + 0.5) / m)
    side = c > half if kind == COMPRESSION else c < -half
    marks = np.where(on_branch & side, kind, REACTION_NONE)
    if p["reaction"] > 0:
        wide = np.cos(2 * np.pi * sector / trunk_sides - math.radians(p["reaction_angle"])) > half
        marks = np.where((axis == 0) & wood & wide, kind, marks)
    return marks.astype(np.int8)


# ---------------------------------------------------------------------- colours
def _rgb(c: str) -> np.ndarray:
    return np.array([int(c[i : i + 2], 16) for i in (1, 3, 5)], float)


def reaction_rgb(rgb: np.ndarray, marks: np.ndarray) -> np.ndarray:
    """Compression wood darker and redder (the German *Rotholz*), tension wood a little paler and silvery.

    Tension wood is drawn as a light silvery veil (:data:`TENSION_VEIL` of the colour): in
    the literature it is lighter than normal wood but often hard to tell without a microscope,
    while compression wood is plainly darker and reddish-brown.  A stronger veil (0.35) drew
    the upper half of every oak and elm knot pale grey, a knot that read as a hole.
    """
    out = np.asarray(rgb, float).copy()
    comp, tens = marks == COMPRESSION, marks == TENSION
    out[comp] = out[comp] * np.array([0.80, 0.66, 0.58])
    out[tens] = (1 - TENSION_VEIL) * out[tens] + TENSION_VEIL * np.array([236.0, 230.0, 214.0])
    return np.clip(out, 0, 255)


def bark_rgb(species: str, marks: np.ndarray) -> np.ndarray:
    """Bark colours by ``bark`` attribute: inner bark, plates (or ridges), fissures.

    A dead knot's encased bark (:data:`BARK_ENCASED`) takes the fissure colour, the species'
    darkest: the dead bark round an encased knot is "a dark ring of bark around the eye of the
    knot" in the lumber glossaries, with no pale living inner bark left in it.
    """
    inner, plate, fissure = (_rgb(c) for c in SPECIES[species]["colors"]["bark"])
    table = np.array([inner, plate, fissure, plate, fissure, fissure])
    return table[np.clip(marks, 0, BARK_ENCASED)]


# ---------------------------------------------------------------------- texture
def _hash(*cols: ArrayLike) -> np.ndarray:
    return u01(*(np.asarray(c, np.int64) for c in cols))


def _speckle(s, r, z, size, spacing, key, z_len=0.006):
    """Vessels or canals: tubes along the grain, ``size`` across, about one per ``spacing``
    square in the cross-section (a dot there, a short streak on a long-grain face)."""
    i, j, kz = np.floor(s / spacing), np.floor(r / spacing), np.floor(z / z_len)
    cs = (i + 0.2 + 0.6 * _hash(key, i, j, kz)) * spacing
    cr = (j + 0.2 + 0.6 * _hash(key + 1, i, j, kz)) * spacing
    there = _hash(key + 2, i, j, kz) < 0.7
    return there & ((s - cs) ** 2 + (r - cr) ** 2 < (0.5 * size) ** 2)


def _rays(s_phi, r, z, rays):
    """Rays: ribbons ``width`` across (tangential), ``height`` tall (axial) and ``length`` long
    (radial), about one per ``spacing`` round the trunk; lens-shaped on a flat-sawn face, a
    fleck on a quarter-sawn face, a radial line on a cross-cut."""
    phi, length = s_phi
    band = np.floor(r / rays["length"])
    r_band = (band + 0.5) * rays["length"]
    s = phi * r_band  # the ray keeps its angle along its radial length
    i = np.floor(s / rays["spacing"])
    shift = _hash(41, i, band)  # rays of one column are staggered along the grain
    kz = np.floor(z / (1.5 * rays["height"]) + shift)
    cs = (i + 0.5 + 0.3 * (_hash(42, i, band, kz) - 0.5)) * rays["spacing"]
    cz = (kz + 0.5 - shift) * 1.5 * rays["height"]
    w = 0.5 * rays["width"] * (0.5 + _hash(43, i, band, kz))
    along = np.clip(1.0 - ((z - cz) / (0.5 * rays["height"])) ** 2, 0.0, 1.0)
    return np.abs(s - cs) * r / np.maximum(r_band, 1e-9) < w * np.sqrt(along)


#: Seasons of the ``season`` volume attribute (as in :mod:`ramure.gmap.organs.wood`).
EARLY, LATE = 0, 1


def texture_rgb(species: str, points: np.ndarray, rgb: np.ndarray, wood: np.ndarray, season: np.ndarray) -> np.ndarray:
    """Colours of points on a cut face of a species' trunk wood with its pores, resin canals and rays.

    The trunk's pith is the z axis (a species' wood grows straight up);
    ``wood`` flags the trunk's wood (sapwood or heartwood): knots, pith and
    bark keep their colours.  Ring-porous earlywood gets
    dark pores, elm's latewood wavy bands of small pores, pine and larch's
    latewood resin canals; rays are paler ribbons (oak's broad, elm's fine).
    """
    tex = SPECIES[species].get("texture", {})
    out = np.asarray(rgb, float).copy()
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    r = np.hypot(x, y)
    phi = np.arctan2(y, x) + np.pi
    s = phi * r
    wood = np.asarray(wood, bool)
    early, late = wood & (season == EARLY), wood & (season == LATE)
    if "rays" in tex:
        ray = wood & _rays((phi, None), r, z, tex["rays"])
        out[ray] = (1 - tex["rays"]["lighten"]) * out[ray] + tex["rays"]["lighten"] * 250.0
    if "pores" in tex:
        pore = early & _speckle(s, r, z, tex["pores"]["size"], tex["pores"]["spacing"], 51)
        out[pore] *= 0.42
    if "waves" in tex:
        wv = tex["waves"]
        wave = np.mod(r + wv["amplitude"] * np.sin(s / wv["period"]), 3 * wv["spacing"]) < wv["spacing"]
        pore = late & wave & _speckle(s, r, z, wv["size"] * 2.5, wv["size"] * 3.0, 61)
        out[pore] *= 0.55
    if "resin" in tex:
        canal = late & _speckle(s, r, z, tex["resin"]["size"], tex["resin"]["spacing"], 71, z_len=0.02)
        out[canal] = 0.5 * out[canal] + 0.5 * np.array([120.0, 70.0, 30.0])
    return np.clip(out, 0, 255).astype(np.uint8)


def texture_face(
    part: pv.DataSet,
    normal: ArrayLike,
    species: str,
    pixel: float,
    codes: Mapping[str, int],
    up: ArrayLike | None = None,
) -> pv.PolyData:
    """A textured plane over the face of ``part`` seen from ``-normal`` (the face nearer the pith
    of a plank): points ``pixel`` apart, point data ``rgb``.

    The plane lies a hair in front of the face and samples the cells a hair
    behind it (``rgb``, ``wood``, ``season``), then :func:`texture_rgb` adds
    pores and rays to the trunk's sapwood and heartwood (``codes``: the
    wood's tissue codes), wherever they lie: the trunk's rings laid round a
    dead knot and over its stub's end (on the branch's axis) are trunk wood
    too, and look it.  Points outside the part are dropped.
    """
    import pyvista as pv

    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    along = np.array([0.0, 0.0, 1.0]) if up is None or abs(n[2]) < 0.5 else np.asarray(up, float)
    if abs(n @ along) > 0.9:
        along = np.array([1.0, 0.0, 0.0])
    along = along - (along @ n) * n
    along /= np.linalg.norm(along)
    side = np.cross(n, along)
    pts = np.asarray(part.points, float)
    depth = float((pts @ n).min())
    a, b = pts @ along, pts @ side
    ni = max(2, min(int(np.ptp(a) / pixel) + 1, 4000))
    nj = max(2, min(int(np.ptp(b) / pixel) + 1, 4000))
    ga, gb = np.meshgrid(np.linspace(a.min(), a.max(), ni), np.linspace(b.min(), b.max(), nj), indexing="ij")
    eps = 1e-4 * max(float(np.ptp(a)), float(np.ptp(b)), 1e-6)
    flat = ga.ravel()[:, None] * along + gb.ravel()[:, None] * side
    probe = pv.PolyData(flat + (depth + eps) * n)
    sampled = probe.sample(part)
    valid = np.asarray(sampled.point_data["vtkValidPointMask"]).astype(bool)
    data = {k: np.asarray(sampled.point_data[k]) for k in ("rgb", "wood", "season")}
    wood = np.isin(data["wood"], [codes["sapwood"], codes["heartwood"]])
    rgb = texture_rgb(species, np.asarray(probe.points), data["rgb"], wood, data["season"])
    grid = pv.StructuredGrid(*(flat + (depth - eps) * n).T.reshape(3, ni, nj, 1))
    grid.point_data["rgb"] = rgb.reshape(ni, nj, 3).transpose(1, 0, 2).reshape(-1, 3)
    grid.point_data["valid"] = valid.reshape(ni, nj).T.ravel().astype(np.uint8)
    surface = grid.extract_surface(algorithm="dataset_surface")
    return surface.threshold(0.5, scalars="valid", preference="point", all_scalars=True).extract_surface(
        algorithm="dataset_surface"
    )


# ---------------------------------------------------------------------- facts
def bark_and_reaction_facts(volume_data: Mapping[str, np.ndarray], trunk_bark: np.ndarray) -> dict[str, Any]:
    """Facts for ``ramure wood --json``: the trunk's thickest and mean bark (mm, flakes included,
    over its stacks), the shed bark cells, and the reaction-wood volumes by kind.

    ``trunk_bark`` flags the trunk's bark volumes (the caller knows the tissue codes).
    """
    level = np.asarray(volume_data["level"], np.int64)[trunk_bark]
    sector = np.asarray(volume_data["sector"], np.int64)[trunk_bark]
    width = np.asarray(volume_data["width"], float)[trunk_bark]
    marks = np.asarray(volume_data["bark"])
    reaction = np.asarray(volume_data["reaction"])
    stacks = np.unique(level * (int(sector.max(initial=0)) + 1) + sector, return_inverse=True)[1]
    per_stack = np.bincount(stacks, width) if width.size else np.zeros(1)
    return {
        "bark_mm": {"max": round(1000 * float(per_stack.max()), 3), "mean": round(1000 * float(per_stack.mean()), 3)},
        "bark_shed": int(np.isin(marks, (SHED_PLATE, SHED_FISSURE)).sum()),
        "reaction": {"compression": int((reaction == COMPRESSION).sum()), "tension": int((reaction == TENSION).sum())},
    }
