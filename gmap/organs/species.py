"""What each fruit preset *is*: species, real size, ripeness stages and the colours of its tissues.

The volumetric fruit has the same tissue codes for every preset (:data:`ramure.gmap.kernel.storage.TISSUES`),
but a pear has no locule gel and a plum's endocarp is a stone.  This module gives every preset a
species (:data:`SPECIES_OF`), and every species a table of ripeness stages, each a colour per
tissue name and the name shown for it in a legend (:data:`SHOWN_AS`): in a pear or an apple the
"locule" cells are the core's seed cavities, in a banana the pale central placenta, in a plum
the stone.  :func:`cell_rgb` colours cells from their tissue code, their position (an apple's
blush faces the sun, a ripe banana's brown flecks are scattered on its skin) and their damage
marks (healed cork, bruise, rot), all numpy, no plotting library.

Sizes (largest extent of the fruit, mm; :data:`SIZE_MM`), with their sources:

================ ======  ===========================================================================
preset           mm      source
================ ======  ===========================================================================
round_tomato     65      UNECE FFV-36 (2017) size code: round tomatoes sold from 35 mm; 57-67 mm
                         is the common "M" grade of the EU marketing standard (Reg. 543/2011)
cherry_tomato    25      FFV-36: "cherry" tomatoes (cocktail included) are the type under the 35 mm
                         minimum of the others; 20-30 mm is the usual fruit (Ohta 2017, J. Appl. Hort.)
elongated_tomato 75      plum/Roma types: 60-90 mm long
ribbed_tomato    90      beefsteak/ribbed types: FFV-36 minimum 35 mm, sold 80-100 mm across
pear             95      FFV-51 (2017): Class I minimum 55 mm diameter (large-fruited 60 mm); a
                         Conference or Williams pear is 85-110 mm long
banana           180     FFV-35 (bananas): minimum length 14 cm; Cavendish fingers are 15-25 cm
apple            75      FFV-50 (2017): Class I minimum 60 mm diameter for large-fruited varieties;
                         65-80 mm is the common size
plum             45      FFV-29 (plums): minimum 35 mm for large-fruited varieties; 40-55 mm usual
cherry           26      FFV-13 (cherries): Class I minimum 20 mm; sweet cherries 22-30 mm
================ ======  ===========================================================================

Choices where nothing says more: three or four stages per species, colours picked from photos
of the named stage (tomato stages after the USDA colour chart green / breaker-turning / red);
a banana's flecks and an apple's blush are fixed by the cell's position and the fruit's seed
(:func:`cell_rgb`), so a fruit is coloured the same way every time.

>>> cell_rgb([CODES["exocarp"]], species="tomato", stage="green").tolist()
[[94, 140, 50]]
>>> shown_name("pear", "locule")
'core cavity'
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.storage import TISSUES

CODES = {name: code for code, name in enumerate(TISSUES)}

#: Species of each preset.
SPECIES_OF = {
    "round_tomato": "tomato",
    "cherry_tomato": "tomato",
    "elongated_tomato": "tomato",
    "ribbed_tomato": "tomato",
    "pear": "pear",
    "banana": "banana",
    "apple": "apple",
    "plum": "plum",
    "cherry": "cherry",
}

#: Largest extent of each preset in millimetres (sources in the module docstring).
SIZE_MM = {
    "round_tomato": 65.0,
    "cherry_tomato": 25.0,
    "elongated_tomato": 75.0,
    "ribbed_tomato": 90.0,
    "pear": 95.0,
    "banana": 180.0,
    "apple": 75.0,
    "plum": 45.0,
    "cherry": 26.0,
}

#: Corky brown of healed cracks and healed hail (suberised wound periderm).
CORK = "#8a5a2b"
#: Rot: browning at the edge, water-soaked tissue, white-grey mould at the centre.
ROT = {"brown": "#6b3d1e", "soaked": "#4a3a22", "mould": "#b8bca8"}
#: A bruise under the skin darkens the flesh towards this colour.
BRUISE = "#5a2c1a"
#: Stem (stalk) and calyx.
STEM = "#6b5a2e"
CALYX = "#3f6b2a"
#: Stalks that are green, not woody brown, when the fruit is fresh: a tomato's pedicel (green
#: like its sepals) and a cherry's long stalk (UNECE FFV-13 asks for fresh stalks; a brown one
#: is an old one).  Other species keep :data:`STEM` (apple, pear: woody).
STEM_BY_SPECIES = {"tomato": "#4c7a2c", "cherry": "#6f8c34"}
#: A turning tomato's shoulders stay green longest (the USDA colour classes: the break from
#: green starts at the blossom end; "turning" is 10 to 30 % of the surface coloured).
TURNING_SHOULDER = "#a8b44c"


def _stage(skin: str, flesh: str, **inside: str) -> dict[str, str]:
    """Colours of one stage: skin (exocarp; and the undifferentiated pericarp of a fruit without
    volume subdivision, seen from outside), flesh (mesocarp, septum) and the rest."""
    out = {"exocarp": skin, "pericarp": skin, "mesocarp": flesh, "septum": flesh}
    out.update(inside)
    return out


#: Ripeness stages by species, in order, each a colour per tissue name (all names present).
STAGES: dict[str, dict[str, dict[str, str]]] = {
    "tomato": {
        "green": _stage("#5e8c32", "#a8c874", columella="#d6e4ac", endocarp="#b8d07e", locule="#c8d890", seed="#ece6c2"),
        "turning": _stage("#d8822e", "#e49a58", columella="#f0d2a0", endocarp="#e8a868", locule="#e8c070", seed="#f4ecc8"),
        "red": _stage("#b8140f", "#e2452f", columella="#f4b89a", endocarp="#ee7a5a", locule="#f0a060", seed="#f8eec0"),
    },
    "pear": {
        "green": _stage("#8fae3c", "#f2efd0", columella="#e8e2b8", endocarp="#e4dcae", locule="#ddd3a4", seed="#4a2a14"),
        "ripening": _stage("#c4c248", "#f6f0d4", columella="#ece4bc", endocarp="#e8dcae", locule="#e0d4a2", seed="#3c2210"),
        "ripe": _stage("#e0c448", "#f8f0d0", columella="#eee2b8", endocarp="#e8d8a8", locule="#e2d2a0", seed="#2e1a0c"),
    },
    "banana": {
        "green": _stage("#4e8a2c", "#f0ecd0", columella="#ece2b4", endocarp="#eee6c2", locule="#e8e0b8", seed="#3a3020"),
        "yellow": _stage("#ecd03a", "#f8f0cc", columella="#f0e4b0", endocarp="#f4eac0", locule="#eee2b4", seed="#3a3020"),
        "flecked": _stage("#e8c030", "#f6e8c0", columella="#eedcaa", endocarp="#f2e2b4", locule="#ecdcae", seed="#3a3020"),
    },
    "apple": {
        "green": _stage("#8cc43c", "#f4f2d2", columella="#ece8c0", endocarp="#e6deb2", locule="#e0d6a8", seed="#3e2412"),
        "yellow": _stage("#e8d04c", "#f8f2d0", columella="#eee6bc", endocarp="#e8dcae", locule="#e2d6a6", seed="#3e2412"),
        "bicolour": _stage("#d8c048", "#f6f2d4", columella="#eee8c0", endocarp="#e8deb0", locule="#e2d8a8", seed="#3e2412"),
        "red": _stage("#a8141c", "#f6f2d6", columella="#eee8c2", endocarp="#e8deb2", locule="#e2d8aa", seed="#3e2412"),
    },
    "plum": {
        "green": _stage("#8aa83a", "#e4e6a0", columella="#b48c5a", endocarp="#a07a4c", locule="#a07a4c", seed="#e8dcb8"),
        "turning": _stage("#a0284c", "#e8cc6a", columella="#a8804e", endocarp="#946c40", locule="#946c40", seed="#e6d6b0"),
        "ripe": _stage("#4a2a62", "#e8b84a", columella="#9c7442", endocarp="#8a6238", locule="#8a6238", seed="#e4d2a8"),
    },
    "cherry": {
        "green": _stage("#9ab84a", "#e6e8b0", columella="#c0a070", endocarp="#b89868", locule="#b89868", seed="#ece0c0"),
        "red": _stage("#c8182a", "#f0a0a0", columella="#d0b080", endocarp="#c8a878", locule="#c8a878", seed="#ece0c0"),
        "dark": _stage("#5a0a14", "#8c1c2c", columella="#c8a878", endocarp="#bea070", locule="#bea070", seed="#ece0c0"),
    },
}

#: Skin colour of an apple's sun-facing blush (bicolour) and of a ripe banana's flecks.
BLUSH = "#b8202a"
FLECK = "#4a2e14"

#: Legend name of a tissue by species (tissues not listed keep their own name).
_POME = {"exocarp": "skin", "mesocarp": "flesh", "septum": "flesh", "endocarp": "core", "locule": "core cavity"}
_DRUPE = {"exocarp": "skin", "mesocarp": "flesh", "septum": "stone", "endocarp": "stone", "locule": "stone"}
_BANANA = {"exocarp": "peel", "mesocarp": "pulp", "septum": "pulp", "endocarp": "pulp", "locule": "placenta"}
SHOWN_AS: dict[str, dict[str, str]] = {
    "tomato": {"exocarp": "skin", "mesocarp": "pericarp", "locule": "locular gel", "columella": "columella"},
    "pear": {**_POME, "columella": "core", "seed": "pips"},
    "apple": {**_POME, "columella": "core", "seed": "pips"},
    "banana": {**_BANANA, "columella": "placenta", "seed": "ovules"},
    "plum": {**_DRUPE, "columella": "stone", "seed": "kernel"},
    "cherry": {**_DRUPE, "columella": "stone", "seed": "kernel"},
}

#: Inner tissues that are stone in a drupe: the differentiation's endocarp and locules become the stone.
STONE_TISSUES = ("endocarp", "locule", "septum", "columella")


def species_of(preset: str) -> str:
    """The species of a preset (``"round_tomato"`` -> ``"tomato"``); refused for an unknown preset."""
    if preset not in SPECIES_OF:
        raise ValueRefused(f"unknown fruit preset {preset!r}; choose one of {', '.join(SPECIES_OF)}")
    return SPECIES_OF[preset]


def stages(species: str) -> list[str]:
    """The ripeness stages of a species, from unripe to ripe."""
    if species not in STAGES:
        raise ValueRefused(f"unknown species {species!r}; choose one of {', '.join(STAGES)}")
    return list(STAGES[species])


def default_stage(species: str) -> str:
    """The stage a fruit is shown at unless told: the ripe one (the last)."""
    return stages(species)[-1]


def check_stage(species: str, stage: str | None) -> str:
    """``stage`` checked against the species (``None``: the ripe stage); refusals list the stages."""
    known = stages(species)
    if stage is None:
        return known[-1]
    if stage not in known:
        raise ValueRefused(f"{species} has no ripeness stage {stage!r}; choose one of {', '.join(known)}")
    return stage


def palette(species: str, stage: str | None = None) -> dict[str, str]:
    """Hex colour per tissue name for ``species`` at ``stage`` (default ripe)."""
    return dict(STAGES[species][check_stage(species, stage)])


def shown_name(species: str, tissue: str) -> str:
    """The name a legend shows for ``tissue`` in ``species``."""
    return SHOWN_AS.get(species, {}).get(tissue, tissue)


def stem_colour(species: str) -> str:
    """Hex colour of the species' stalk: green for tomatoes and cherries, woody brown otherwise."""
    return STEM_BY_SPECIES.get(species, STEM)


def hex_rgb(color: str) -> tuple[int, int, int]:
    """``"#a0b1c2"`` -> ``(160, 177, 194)``."""
    return int(color[1:3], 16), int(color[3:5], 16), int(color[5:7], 16)


def table(species: str, stage: str | None = None) -> np.ndarray:
    """uint8 RGB per tissue code (rows in :data:`TISSUES` order)."""
    colours = palette(species, stage)
    return np.array([hex_rgb(colours[name]) for name in TISSUES], np.uint8)


def _hash01(ids: np.ndarray, seed: int) -> np.ndarray:
    """A fixed pseudo-random number in [0, 1) per id (no global state)."""
    x = (ids.astype(np.uint64) * np.uint64(2654435761) + np.uint64(seed * 97 + 13)) % np.uint64(2**32)
    x ^= x >> np.uint64(15)
    x = (x * np.uint64(2246822519)) % np.uint64(2**32)
    x ^= x >> np.uint64(13)
    return (x % np.uint64(10007)).astype(float) / 10007.0


def _mix(rgb: np.ndarray, colour: str, t: ArrayLike) -> np.ndarray:
    w = np.clip(np.asarray(t, float), 0.0, 1.0)[:, None]
    return rgb * (1.0 - w) + np.array(hex_rgb(colour), float) * w


def cell_rgb(
    tissue: ArrayLike,
    species: str = "tomato",
    stage: str | None = None,
    centres: ArrayLike | None = None,
    marks: Mapping[str, ArrayLike] | None = None,
    seed: int = 0,
) -> np.ndarray:
    """uint8 RGB per cell: the species' colour for the cell's tissue at ``stage``, then its marks.

    ``centres`` (cell centres, the fruit's axis along +z, the stem end up) place an apple's
    blush (``bicolour``: skin cells facing +x, up to 70 % red), a turning tomato's green
    shoulders (``turning``: the skin turns up to 60 % yellow-green :data:`TURNING_SHOULDER` towards the
    stem end, none at the blossom end, where colour breaks first) and a banana's brown flecks
    (``flecked``: about one skin cell in nine, fixed by the cell's number and ``seed``).  ``marks`` are per-cell
    columns in [0, 1] written by the defects (:mod:`ramure.gmap.organs.defects`):

    - ``corky``: a healed crack's wall: corky brown :data:`CORK` (whole weight; a renderer
      colours the walls only, :func:`ramure.app.fruit_look.coloured_surface`);
    - ``wound``: a fresh wound's wall: the flesh colour, wet and lighter than the skin;
    - ``scar``: a healed hail pit: corky brown on the skin;
    - ``bruise``: under a hail pit: the flesh darkens towards :data:`BRUISE` (up to 60 %);
    - ``rot``: rot intensity: browning (rot > 0), water-soaked dark (> 0.5), a grey-green
      mould fuzz at the centre (> 0.8);
    - ``organ``: 1 = stem, 2 = calyx.
    """
    codes = np.asarray(tissue, np.int64)
    rgb = table(species, stage)[codes].astype(float)
    stage = check_stage(species, stage)
    ids = np.arange(len(codes))
    skin = (codes == CODES["exocarp"]) | (codes == CODES["pericarp"])  # a fruit not subdivided is skin outside
    if centres is not None and len(codes):
        c = np.asarray(centres, float).reshape(-1, 3)
        mid = 0.5 * (c.min(axis=0) + c.max(axis=0))
        rel = c - mid
        radial = np.hypot(rel[:, 0], rel[:, 1]) + 1e-12
        if species == "apple" and stage == "bicolour":
            facing = np.clip(rel[:, 0] / radial, -1.0, 1.0)
            streak = 0.06 * _hash01(ids, seed)
            rgb[skin] = _mix(rgb[skin], BLUSH, (0.7 * (0.5 + 0.5 * facing) + streak)[skin])
        if species == "tomato" and stage == "turning":
            half = max(0.5 * float(np.ptp(c[:, 2])), 1e-12)
            up = np.clip(rel[:, 2] / half, -1.0, 1.0)  # -1 blossom end .. +1 stem end
            rgb[skin] = _mix(rgb[skin], TURNING_SHOULDER, (0.6 * np.clip((up + 0.6) / 1.6, 0.0, 1.0) ** 1.5)[skin])
    if species == "banana" and stage == "flecked":
        fleck = skin & (_hash01(ids, seed + 1) < 0.11)
        rgb[fleck] = _mix(rgb[fleck], FLECK, 0.85 * np.ones(int(fleck.sum())))
    marks = marks or {}
    n = len(codes)

    def mark(name):
        if name not in marks:
            return np.zeros(n)
        return np.clip(np.asarray(marks[name], float).reshape(n), 0.0, 1.0)

    flesh = table(species, stage)[CODES["mesocarp"]].astype(float)
    wound = mark("wound")
    rgb = rgb * (1 - wound[:, None]) + (0.85 * flesh + 0.15 * 255.0) * wound[:, None]
    rgb = _mix(rgb, BRUISE, 0.6 * mark("bruise"))
    rot = mark("rot")
    rgb = _mix(rgb, ROT["brown"], np.clip(rot * 1.6, 0, 0.85) * (rot > 0))
    rgb = _mix(rgb, ROT["soaked"], np.clip((rot - 0.5) * 2.0, 0, 0.7))
    mould = rot > 0.8
    rgb[mould] = _mix(rgb[mould], ROT["mould"], 0.35 + 0.3 * _hash01(ids[mould], seed + 2))
    rgb = _mix(rgb, CORK, np.maximum(mark("corky"), mark("scar")))
    organ = np.asarray(marks.get("organ", np.zeros(n)), np.int64).reshape(n)
    rgb[organ == 1] = hex_rgb(stem_colour(species))
    rgb[organ == 2] = hex_rgb(CALYX)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def _unit_circle(angle: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(angle), np.sin(angle)], axis=1)


def _smoothstep(lo: float, hi: float, x: ArrayLike) -> np.ndarray:
    t = np.clip((np.asarray(x, float) - lo) / (hi - lo), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


#: A round mark's edge: its weight falls from 1 to 0 between these fractions of its radius
#: (0.5 at the radius itself, so the mark's area at weight 0.5 is the disc's).
MARK_EDGE = (0.85, 1.15)
#: A hail pit's bruise shows through the skin round the pit out to this many radii.
HAIL_HALO = 1.7


def mark_weight(u: ArrayLike) -> np.ndarray:
    """Weight of a round mark at ``u`` = distance from its centre over its radius: 1 inside,
    a smoothstep down to 0 across :data:`MARK_EDGE`, exactly 0.5 at ``u = 1``."""
    return 1.0 - _smoothstep(MARK_EDGE[0], MARK_EDGE[1], u)


#: Mould colonies on a rot lesion: how many, and their radius range (fractions of the lesion's).
MOULD_SPOTS = (16, 0.05, 0.11)


def round_mark_rgb(
    rgb: ArrayLike, kind: str, u: ArrayLike, healed: bool = False, xy: ArrayLike | None = None, seed: int = 0
) -> np.ndarray:
    """Skin colours (float RGB per face, 0..255) with one round mark painted on.

    ``u`` is each face's distance from the mark's centre along the skin over the mark's
    radius (:func:`mark_weight` gives the mark's extent); ``xy`` the same offset in the skin's
    tangent plane, in radii (``(n, 2)``; places the mould, fixed by ``seed``).  ``kind``:

    - ``"hail"``: a pit.  Healed (``healed``): a corky brown :data:`CORK` scar filling the pit,
      fresh: the flesh's :data:`BRUISE` showing dark through the skin; either way a soft
      bruise round it fading out at :data:`HAIL_HALO` radii.
    - ``"rot"``: a lesion: browning :data:`ROT` ``brown`` all over, a darker water-soaked band
      towards the rim, and :data:`MOULD_SPOTS` round grey-white mould colonies scattered over
      its inner half (none drawn without ``xy``).
    """
    out = np.asarray(rgb, float).reshape(-1, 3).copy()
    u = np.asarray(u, float).reshape(-1)
    w = mark_weight(u)
    if kind == "hail":
        halo = 1.0 - _smoothstep(0.9, HAIL_HALO, u)
        out = _mix(out, BRUISE, 0.35 * halo)
        out = _mix(out, CORK, 0.92 * w) if healed else _mix(out, BRUISE, 0.55 * w)
        return out
    if kind == "rot":
        out = _mix(out, ROT["brown"], 0.85 * w)
        band = _smoothstep(0.45, 0.8, u) * w
        out = _mix(out, ROT["soaked"], 0.75 * band)
        if xy is not None:
            count, small, large = MOULD_SPOTS
            rng = np.random.default_rng(seed)
            at = np.sqrt(rng.uniform(0.0, 0.5**2, count))[:, None] * _unit_circle(rng.uniform(0, 2 * np.pi, count))
            size = rng.uniform(small, large, count)
            inner = np.flatnonzero(u < 0.5 + large)  # where colonies can be
            p = np.asarray(xy, float).reshape(-1, 2)[inner]
            spot = np.zeros(len(p))
            for c, r in zip(at, size):  # a few colonies: one array pass each
                spot = np.maximum(spot, 1.0 - _smoothstep(0.6 * r, r, np.linalg.norm(p - c, axis=1)))
            out[inner] = _mix(out[inner], ROT["mould"], 0.75 * spot * w[inner])
        return out
    raise ValueRefused(f"round marks are hail or rot, got {kind!r}")


#: Damage and organ columns :func:`cell_rgb` reads from a grid's cell data.
MARKS = ("corky", "wound", "scar", "bruise", "rot", "organ")


def materials(species: str, stage: str | None = None) -> list[dict[str, object]]:
    """Per-tissue materials for exports: name, shown name and sRGB colour (0..1), one per tissue,
    then the damage materials (cork, rot, bruise) and the stem and calyx."""
    colours = palette(species, stage)
    out: list[dict[str, object]] = [
        {"name": f"{species}_{name}", "tissue": name, "shown_as": shown_name(species, name), "rgb": _unit(colours[name])}
        for name in TISSUES
    ]
    extra = {"cork": CORK, "bruise": BRUISE, "stem": stem_colour(species), "calyx": CALYX}
    extra.update({f"rot_{k}": v for k, v in ROT.items()})
    out += [{"name": name, "tissue": None, "shown_as": name.replace("_", " "), "rgb": _unit(c)} for name, c in extra.items()]
    return out


def _unit(color: str) -> list[float]:
    return [round(v / 255.0, 4) for v in hex_rgb(color)]
