"""Fruit tissues: the differentiation rule after volume subdivision (thesis §2.4).

Tissue codes (volume attribute ``tissue``; names in :data:`TISSUES`):

====  ==========  ==================================================
code  name        cells
====  ==========  ==================================================
0     columella   the trunk (central axis, placenta)
1     pericarp    undifferentiated branch cells (no volume subdivision)
2     exocarp     skin: branch cells with a boundary face
3     mesocarp    flesh under the skin
4     endocarp    inner lining of each locule
5     septum      radial walls between locules
6     locule      locule cavities (gel)
7     seed        seeds: locule cells on the columella, rounded
====  ==========  ==================================================

The rule, ``B -> (C, e, D, m, B, n, carpels, G)`` in the thesis, works here on
radial layers.  After ``k`` volume subdivisions each branch holds
``L = 2**k`` layers of cells between the core and the skin (told apart by the
``radial`` vertex scalar).  The outer layer is exocarp, then mesocarp,
one layer of endocarp and the rest locule (for ``L = 2``: exocarp and
mesocarp; ``L = 3``: exocarp, mesocarp, locule).  Any branch cell with a
boundary face is exocarp, so the skin also covers the poles.  Around the axis,
the fruit is cut into ``carpels`` equal angular sectors; the fraction
``septum`` of each sector centred on its borders turns endocarp and locule
cells into septum.  Then ``seeds`` locule cells glued to the columella but not to the
exocarp (no two sharing a vertex) are picked at random; each is cut across its depth into gel,
seed and gel (the seed spans :data:`SEED_SPAN` of the cell's depth), and the
seeds are rounded by ``seed_smoothing`` surface subdivisions of those cells
only (their neighbours' faces follow).  The thesis relabels whole cells as
seeds; here a whole cell would be as deep as the locule, hence the cuts.

A core band (``core_low``, ``core_high``, fractions of the axis; default the whole axis)
bounds the core along the fruit: core tissues outside an oval over that band become flesh,
so an apple's core and a drupe's stone sit in the middle of the height with flesh above and
below.  ``kernel`` fills the middle of a drupe's stone with seed cells (its kernel), ``pips``
makes whole-cell pips per carpel in the middle (``seed_band``) of the core, ``pip_width`` of
the carpel's angle wide (the thesis's whole-cell seeds, large enough to show in a cut); see
:func:`_core_band`.  With the defaults nothing changes.

Thicknesses ``exocarp``, ``mesocarp`` and ``endocarp`` are *fractions of the
local pericarp depth* (core surface to skin; the locules take the rest): the
vertices between layers are moved along each radial line to these depths, as
the thesis moves the inner faces "along their incident edges".

>>> from ramure.gmap.organs.fruit import build_fruit
>>> gm = build_fruit("round_tomato", volume_levels=2, seeds=10)
>>> counts = tissue_counts(gm)
>>> counts["seed"], counts["exocarp"] > 0, counts["locule"] > 0
(10, True, True)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel import subdivide as _subdivide
from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.storage import TISSUES

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

CODES = {name: code for code, name in enumerate(TISSUES)}

#: Display colours (hex RGB) by tissue name, for renderers.
COLORS = {
    "columella": "#f4c7a1",
    "pericarp": "#e0452f",
    "exocarp": "#9e0d12",
    "mesocarp": "#e8412c",
    "endocarp": "#f0866a",
    "septum": "#d9382a",
    "locule": "#d4b843",
    "seed": "#fff8e0",
}

#: Internal-structure parameters and their defaults.
DEFAULTS = {
    "carpels": 3,
    "exocarp": 0.04,
    "mesocarp": 0.30,
    "endocarp": 0.06,
    "septum": 0.25,
    "seeds": 120,
    "seed_smoothing": 1,
    "core_low": 0.0,
    "core_high": 1.0,
    "seed_band": 1.0,
    "kernel": 0.0,
    "pips": 0,
    "pip_width": 0.6,
}

#: Tissues of the core (a pome's core and cavities, a drupe's stone) that :func:`core_band` bounds.
CORE_TISSUES = ("columella", "endocarp", "locule", "septum")


def check_params(p: Mapping[str, float]) -> None:
    """Raise :class:`~ramure.gmap.kernel.errors.ValueRefused` for out-of-range tissue parameters."""
    if not 1 <= p["carpels"] <= 64:
        raise ValueRefused(f"carpels must be in 1..64, got {p['carpels']}")
    for name in ("exocarp", "mesocarp", "endocarp"):
        if not 0 < p[name] < 1:
            raise ValueRefused(f"{name} thickness is a fraction of the pericarp depth in (0, 1), got {p[name]}")
    total = p["exocarp"] + p["mesocarp"] + p["endocarp"]
    if total >= 1:
        raise ValueRefused(f"exocarp + mesocarp + endocarp must stay below 1 (the locules take the rest), got {total:g}")
    if not 0 <= p["septum"] < 1:
        raise ValueRefused(f"septum must be a fraction of each carpel in [0, 1), got {p['septum']}")
    if p["seeds"] < 0:
        raise ValueRefused(f"seeds must be >= 0, got {p['seeds']}")
    if not 0 <= p["seed_smoothing"] <= 3:
        raise ValueRefused(f"seed_smoothing must be in 0..3, got {p['seed_smoothing']}")
    lo, hi = p.get("core_low", 0.0), p.get("core_high", 1.0)
    if not 0 <= lo < hi <= 1:
        raise ValueRefused(f"the core band needs 0 <= core_low < core_high <= 1 (fractions of the axis), got {lo}..{hi}")
    if not 0 < p.get("seed_band", 1.0) <= 1:
        raise ValueRefused(f"seed_band is a fraction of the core band in (0, 1], got {p['seed_band']}")
    if not 0 <= p.get("kernel", 0.0) <= 1:
        raise ValueRefused(f"kernel is a fraction of the core band in [0, 1], got {p['kernel']}")
    if not 0 <= p.get("pips", 0) <= 16:
        raise ValueRefused(f"pips (whole-cell pips per carpel) must be in 0..16, got {p['pips']}")
    if not 0 < p.get("pip_width", 0.6) <= 1:
        raise ValueRefused(f"pip_width is a fraction of a carpel's angle in (0, 1], got {p['pip_width']}")


def tissue_counts(gm: GMap3) -> dict[str, int]:
    """Number of volumes of each tissue, by name (all names present).

    >>> from ramure.gmap.organs.fruit import build_fruit
    >>> tissue_counts(build_fruit("round_tomato"))["pericarp"]
    100
    """
    counts = np.bincount(gm.volume_data["tissue"].astype(np.int64), minlength=len(TISSUES))
    return {name: int(counts[code]) for code, name in enumerate(TISSUES)}


def layer_tissues(layers: int) -> np.ndarray:
    """Tissue code of each radial layer, outermost first.

    >>> [TISSUES[c] for c in layer_tissues(4)]
    ['exocarp', 'mesocarp', 'endocarp', 'locule']
    """
    return _layer_plan(layers, DEFAULTS)[0]


def _layer_plan(layers, p):
    """Tissue per layer and the target depth (fraction) of each layer boundary."""
    exo, meso, endo = p["exocarp"], p["mesocarp"], p["endocarp"]
    if layers <= 1:
        return np.array([CODES["pericarp"]]), np.array([0.0, 1.0])
    if layers == 2:
        plan = [("exocarp", 1, exo), ("mesocarp", 1, 1 - exo)]
    elif layers == 3:
        plan = [("exocarp", 1, exo), ("mesocarp", 1, meso), ("locule", 1, 1 - exo - meso)]
    else:
        rest = layers - 2
        locule_share = (1 - exo - meso - endo) / (1 - exo - endo)
        n_loc = min(max(1, int(round(rest * locule_share))), rest - 1)
        plan = [
            ("exocarp", 1, exo),
            ("mesocarp", rest - n_loc, meso),
            ("endocarp", 1, endo),
            ("locule", n_loc, 1 - exo - meso - endo),
        ]
    codes = np.concatenate([[CODES[name]] * count for name, count, _ in plan])
    steps = np.concatenate([[thick / count] * count for _, count, thick in plan])
    return codes, np.concatenate([[0.0], np.cumsum(steps)])


def differentiate(
    gm: GMap3,
    carpels: int = 3,
    exocarp: float = 0.04,
    mesocarp: float = 0.30,
    endocarp: float = 0.06,
    septum: float = 0.25,
    seeds: int = 40,
    seed_smoothing: int = 1,
    core_low: float = 0.0,
    core_high: float = 1.0,
    seed_band: float = 1.0,
    kernel: float = 0.0,
    pips: int = 0,
    pip_width: float = 0.6,
    rng: int | np.random.Generator | None = None,
) -> GMap3:
    """Assign tissues to a volume-subdivided fruit and shape its layers; returns a map.

    Works on maps from :func:`ramure.gmap.organs.fruit.build_fruit` (volume attributes
    ``order``, ``ring`` and the ``radial`` vertex scalar).  With fewer than
    two radial layers (no volume subdivision) the branches stay
    ``pericarp``.  See the module docstring for the rule.
    """
    check_params(
        dict(
            carpels=carpels,
            exocarp=exocarp,
            mesocarp=mesocarp,
            endocarp=endocarp,
            septum=septum,
            seeds=seeds,
            seed_smoothing=seed_smoothing,
            core_low=core_low,
            core_high=core_high,
            seed_band=seed_band,
            kernel=kernel,
            pips=pips,
            pip_width=pip_width,
        )
    )
    rng = np.random.default_rng(rng)
    vd = gm.volume_data
    branch = vd["order"] >= 1
    rho = gm.volume_means(gm.dart_data["radial"])
    if not branch.any():
        return gm
    layers = int(round(1.0 / (2.0 * max(1.0 - rho[branch].max(), 1e-9))))
    if layers < 2:
        return gm
    params = dict(exocarp=exocarp, mesocarp=mesocarp, endocarp=endocarp)
    codes, depths = _layer_plan(layers, params)
    tissue = vd["tissue"]
    layer = np.clip(np.floor((1.0 - rho) * layers).astype(np.int64), 0, layers - 1)
    tissue[branch] = codes[layer[branch]]
    alpha = gm.alpha
    vol = gm.dart_volume
    free = alpha[3] == np.arange(gm.n_darts)
    on_skin = np.zeros(gm.n_volumes, bool)
    on_skin[vol[free]] = True
    tissue[branch & on_skin] = CODES["exocarp"]
    inner = np.isin(tissue, [CODES["endocarp"], CODES["locule"]])
    tissue[inner & _in_septum(gm, carpels, septum)] = CODES["septum"]
    allowed = None
    if (core_low, core_high, kernel, pips) != (0.0, 1.0, 0.0, 0) or seed_band < 1:
        allowed = _core_band(gm, carpels, core_low, core_high, seed_band, kernel, pips, pip_width)
    _place_layers(gm, layers, depths)
    cells, inner = _pick_seeds(gm, seeds, rng, allowed)
    return _carve_seeds(gm, cells, inner, seed_smoothing)


def axial_coordinates(gm: GMap3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each volume's centroid in the fruit's own axial coordinates: ``(s, r, theta)``.

    ``s`` is where it lies along the axis, 0 at the blossom end of the columella (the trunk),
    1 at its stem end: the length of the rings below plus the centroid's offset along its
    ring's axis (each ring's own axis, so a bent axis is followed), over the trunk's whole
    length (its vertices' furthest reach along the last ring's axis).  ``r`` is the distance
    from the ring's axis and ``theta`` the angle about it (radians, from the ring frame's L
    row towards its U row, as the septa are placed).
    """
    vd = gm.volume_data
    ring = vd["ring"].astype(np.int64)
    trunk = np.flatnonzero(vd["order"] == 0)
    n = int(ring.max()) + 1
    rings, first = np.unique(ring[trunk], return_index=True)
    origin = np.zeros((n, 3))
    frame = np.tile(np.eye(3), (n, 1, 1))
    origin[rings] = vd["origin"][trunk[first]]
    frame[rings] = vd["frame"][trunk[first]]
    axis = frame[:, 0]
    below = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(origin, axis=0), axis=1))])
    last = gm.points[np.isin(gm.dart_volume, trunk[ring[trunk] == n - 1])]
    total = below[-1] + (float(np.max((last - origin[-1]) @ axis[-1])) if len(last) else 0.0)
    rel = gm.volume_centroids() - origin[ring]
    along = np.sum(rel * axis[ring], axis=1)
    f = frame[ring]
    x, y = np.sum(rel * f[:, 1], axis=1), np.sum(rel * f[:, 2], axis=1)
    r = np.linalg.norm(rel - along[:, None] * axis[ring], axis=1)
    return (below[ring] + along) / max(total, 1e-12), r, np.arctan2(y, x)


#: A core's or stone's outline in a lengthwise cut: cells are kept where
#: ``((s - mid) / half)**2 + (r / (CORE_ROUNDING * r_max))**2 <= 1`` (an oval whose widest part,
#: at mid-height, keeps every core cell: ``r_max`` is the core cells' largest distance from the
#: axis; a larger value gives squarer ends).  A choice, judged on the cut pictures.
CORE_ROUNDING = 1.25


def _core_band(gm, carpels, low, high, seed_band, kernel, pips, pip_width):
    """Bound the core along the axis, place a drupe's kernel and whole-cell pips.

    Returns the volumes where carved seeds may be picked.  Core tissues
    (:data:`CORE_TISSUES`) outside an oval spanning ``low .. high`` of the axis
    (:func:`axial_coordinates`, outline :data:`CORE_ROUNDING`) become flesh (mesocarp): a
    pome's core and a drupe's stone fill the middle of the fruit, not its whole height.
    The centred fraction ``kernel`` of the band (an oval as wide as the locules) turns its
    columella and locule cells into seed: a drupe's kernel, inside the stone's shell (the endocarp);
    a fruit without locules (one volume subdivision) has no shell, hence no kernel.
    ``pips`` > 0 pips per carpel, stacked along the centred fraction ``seed_band`` of the band,
    are the locule cells inside a lens ``pip_width`` of the carpel's angle wide centred on
    the carpel (the ovules sit in the middle of each locule), 0.9 of its share of the band high.
    """
    tissue = gm.volume_data["tissue"]
    s, r, theta = axial_coordinates(gm)
    mid, half = 0.5 * (low + high), 0.5 * (high - low)
    core = np.isin(tissue, [CODES[name] for name in CORE_TISSUES])
    in_band = core & (s >= low) & (s <= high)
    reach = CORE_ROUNDING * (r[in_band].max() if in_band.any() else 1.0)
    tissue[core & (((s - mid) / half) ** 2 + (r / reach) ** 2 > 1.0)] = CODES["mesocarp"]
    if kernel > 0 and (tissue == CODES["locule"]).any():  # no locules (one subdivision): no shell round it
        filling = np.isin(tissue, [CODES["columella"], CODES["locule"]])
        fill_reach = CORE_ROUNDING * (r[filling].max() if filling.any() else 1.0)
        tissue[filling & (((s - mid) / (kernel * half)) ** 2 + (r / fill_reach) ** 2 <= 1.0)] = CODES["seed"]
    if pips > 0:
        u = np.mod(theta / (2 * np.pi) * carpels, 1.0) - 0.5  # 0 at a carpel's centre
        share = 2.0 * seed_band * half / pips
        centres = mid - seed_band * half + share * (np.arange(pips) + 0.5)
        lens = ((s[:, None] - centres) / (0.45 * share)) ** 2 + (u[:, None] / (0.5 * pip_width)) ** 2
        tissue[(lens.min(axis=1) <= 1.0) & (tissue == CODES["locule"])] = CODES["seed"]
    return np.abs(s - mid) <= seed_band * half


def _in_septum(gm, carpels, septum):
    """Volumes whose angle about their ring's axis falls in a septum band."""
    vd = gm.volume_data
    ring = vd["ring"].astype(np.int64)
    trunk = np.flatnonzero(vd["order"] == 0)
    rings, first = np.unique(ring[trunk], return_index=True)
    origin = np.zeros((int(ring.max()) + 1, 3))
    frame = np.tile(np.eye(3), (int(ring.max()) + 1, 1, 1))
    origin[rings] = vd["origin"][trunk[first]]
    frame[rings] = vd["frame"][trunk[first]]
    rel = gm.volume_centroids() - origin[ring]
    f = frame[ring]
    theta = np.arctan2(np.sum(rel * f[:, 2], axis=1), np.sum(rel * f[:, 1], axis=1))
    u = np.mod(theta / (2 * np.pi) * carpels, 1.0)
    return np.minimum(u, 1.0 - u) < septum / 2.0


def _place_layers(gm, layers, depths) -> None:
    """Move vertices along radial lines so layer boundaries sit at ``depths``."""
    vid, nv = gm.cells(0)
    _, pos = gm.vertex_positions()
    rho = np.bincount(vid, gm.dart_data["radial"], minlength=nv) / np.bincount(vid, minlength=nv)
    u, w = vid, vid[gm.alpha[0]]
    eps = 1e-9

    def extreme(sign):
        order = np.lexsort((sign * rho[w], u))
        last = np.ones(len(order), bool)
        last[:-1] = u[order][1:] != u[order][:-1]
        best = np.arange(nv)
        cand_u, cand_w = u[order][last], w[order][last]
        better = sign * rho[cand_w] > sign * rho[cand_u] + eps
        best[cand_u[better]] = cand_w[better]
        for _ in range(64):  # pointer jumping to the end of the line
            nxt = best[best]
            if np.array_equal(nxt, best):
                break
            best = nxt
        return best

    skin, core = extreme(1.0), extreme(-1.0)
    span = rho[skin] - rho[core]
    move = (rho > eps) & (rho < 1 - eps) & (span > eps)
    t = (rho[skin][move] - rho[move]) / span[move]
    g = np.interp(t, np.linspace(0.0, 1.0, layers + 1), depths)
    new = pos.copy()
    new[move] = pos[skin[move]] + (pos[core[move]] - pos[skin[move]]) * g[:, None]
    gm.points[:] = new[vid]


#: Where a seed sits inside its locule cell: fractions of the cell's depth from its inner face.
SEED_SPAN = (0.2, 0.45)


def _pick_seeds(gm, count, rng, allowed=None):
    """Up to ``count`` random locule cells glued to the columella, not to the exocarp, sharing no vertex
    (and, when ``allowed`` is given, among the volumes it marks).

    Returns ``(volumes, inner_darts)``: each cell and a dart of its face on the columella.
    """
    tissue = gm.volume_data["tissue"]
    alpha = gm.alpha
    vol = gm.dart_volume
    sewn = np.flatnonzero(alpha[3] != np.arange(gm.n_darts))
    here, there = tissue[vol[sewn]], tissue[vol[alpha[3][sewn]]]
    touch = sewn[(here == CODES["locule"]) & (there == CODES["columella"])]
    near_skin = np.unique(vol[sewn[there == CODES["exocarp"]]])
    touch = touch[~np.isin(vol[touch], near_skin)]
    if allowed is not None:
        touch = touch[allowed[vol[touch]]]
    cells, first = np.unique(vol[touch], return_index=True)
    if not count or cells.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    inner = touch[first]
    vid, _ = gm.cells(0)
    by_vol = np.argsort(vol, kind="stable")
    bounds = np.searchsorted(vol[by_vol], np.arange(gm.n_volumes + 1))
    used = np.zeros(int(vid.max()) + 1, bool)
    chosen = []
    for i in rng.permutation(len(cells)):  # one step per candidate cell, not per dart
        c = cells[i]
        verts = vid[by_vol[bounds[c] : bounds[c + 1]]]
        if used[verts].any():
            continue
        used[verts] = True
        chosen.append(i)
        if len(chosen) == count:
            break
    picked = np.array(chosen, np.int64)
    return cells[picked], inner[picked]


def _carve_seeds(gm, cells, inner, smoothing):
    """Cut each cell into gel | seed | gel across its depth, then round the seeds.

    All seeds at once (two :meth:`split_prisms` calls): the seed cells share no vertex, so
    the batch cuts what one split per seed cut, 2-3 times faster on a twice-subdivided
    tomato (it was half of the fruit's build).  Which part of a split keeps the cell's id
    is not assumed: the parts are paired through their shared face.
    """
    t0, t1 = SEED_SPAN
    cells, inner = np.asarray(cells, np.int64), np.asarray(inner, np.int64)
    if cells.size == 0:
        return gm
    halves = _sewn_partner(gm, cells, gm.split_prisms(cells, t0, faces=inner, labels=("I", "I")))
    vol = gm.dart_volume.astype(np.int64)
    gel = vol[inner]  # the part on the columella
    outer = np.where(gel == cells, halves, cells)
    faces = _face_towards(gm, outer, np.where(gel == cells, cells, halves))
    gm.split_prisms(outer, (t1 - t0) / (1.0 - t0), faces=faces, labels=("I", "I"))
    seed_ids = gm.dart_volume.astype(np.int64)[faces]  # the slab next to the gel
    gm.volume_data["tissue"][seed_ids] = CODES["seed"]
    if smoothing:
        gm = _subdivide.surface(gm, smoothing, volumes=seed_ids)
    return gm


def _sewn_partner(gm, volumes, candidates):
    """For each of ``volumes``, the one of ``candidates`` sewn to it (-1 if none)."""
    vol = gm.dart_volume.astype(np.int64)
    allowed = np.zeros(gm.n_volumes, bool)
    allowed[candidates] = True
    darts = np.flatnonzero(np.isin(vol, volumes))
    other = vol[gm.alpha[3][darts]]
    keep = allowed[other] & (other != vol[darts])
    partner = np.full(gm.n_volumes, -1, np.int64)
    partner[vol[darts][keep]] = other[keep]
    return partner[volumes]


def _face_towards(gm, volumes, neighbours):
    """For each of ``volumes``, its first dart (lowest id) on the face sewn to its ``neighbours`` entry."""
    vol = gm.dart_volume.astype(np.int64)
    wanted = np.full(gm.n_volumes, -1, np.int64)
    wanted[volumes] = neighbours
    darts = np.flatnonzero(wanted[vol] >= 0)
    darts = darts[vol[gm.alpha[3][darts]] == wanted[vol[darts]]]
    found, first = np.unique(vol[darts], return_index=True)
    return darts[first][np.searchsorted(found, volumes)]


def tissue_rgb(tissue: ArrayLike) -> np.ndarray:
    """uint8 RGB per cell from tissue codes (colours of :data:`COLORS`).

    >>> tissue_rgb([CODES["seed"], CODES["pericarp"]]).tolist()
    [[255, 248, 224], [224, 69, 47]]
    """
    table = np.array([[int(COLORS[n][i : i + 2], 16) for i in (1, 3, 5)] for n in TISSUES], np.uint8)
    return table[np.asarray(tissue, np.int64)]
