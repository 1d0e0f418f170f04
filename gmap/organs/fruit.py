"""Volumetric fruit after Bohl (2015): a trunk of prisms and glued radial branches.

The fruit axis is a trunk of ``precision`` prisms of order ``ph`` stacked on
their E faces; each lateral face of each trunk prism carries one radial quad
prism (a *branch*) whose O face is sewn to it and whose E face is skin; every
branch is then sewn to its neighbours around and along the axis, which closes
the pericarp.  Vertices sit at the barycentre of their volumes' corners.

Parameters keep the thesis's names (Grammar 2.7, Table 2.12):

============  ==============================================================
precision     number of trunk prisms (rings of branches)
ph            order of the trunk prisms = branches per ring
longueur, fc  trunk segment size ``longueur * max(lmin, fc(x))``, fc sampled
              over its interval (``"sin"`` on [0, pi], ``"constant"``, ...)
largeur, fb   branch length ``largeur * max(wminb, fb(x)) * fd(k)``
nbprotus      number of ribs; ``fd(k) = max(creux, |sin(k pi nbprotus / ph)|)``
              (periodic step, so C1 and C_ph are not both in a valley);
              ``fd = 1`` when ``nbprotus = 0``
creux         depth floor of the valleys between ribs (0.9 shallow .. 0.2 deep)
anglesup,     stem-end dimple: branches of the last ``nbvolangle`` rings turn
angleinf,     (about their U axis, degrees) from ``anglesup`` down to
nbvolangle    ``angleinf``; negative angles tip them towards the stem end
rotx, roty,   per-segment rotation of the trunk (bent axis, e.g. banana)
rotz
stepmax,      vertical bounding-surface constraint ``variate(x)`` (thesis
vmax,         ch. 3.1, approach 2) multiplying the branch length of ring x:
vmin_a,       a ramp from ``vmin_a`` up to ``vmax`` at ring ``stepmax``, then
vmin_b        down to ``vmin_b`` at the stem end; all three 1 (default): off
fmin, hamp    horizontal constraint ``hfunction(k) = fmin + hamp sin(k pi /
              (ph - 1))`` on sector k (the thesis's is ``hamp = 1``: small
              branches near C1, large opposite); ``hamp = 0`` (default): off
============  ==============================================================

Choices where the thesis is silent: the axiom trunk prism is sized by ``fc``
like the others; a branch's base matches its trunk face (L = segment height,
W = face width); the stem end is the last trunk prism's E face; every preset
uses ``ph = 10`` except the ribbed tomato (24, so six ribs are resolved);
the pear's profile is walked from 1.6 down to -0.6 so the neck is at the stem.

Internal structure (see :mod:`ramure.gmap.organs.tissue`) needs ``volume_levels >= 1``; its
parameters ``carpels``, ``exocarp``, ``mesocarp``, ``endocarp``, ``septum``,
``seeds`` and ``seed_smoothing`` are accepted here too.

>>> from ramure.gmap.organs.fruit import build_fruit
>>> gm = build_fruit("round_tomato")
>>> c = gm.counts()
>>> c["darts"], c["vertices"], c["faces_per_volume"], c["volumes"]
(6000, 220, 720, 110)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ramure.gmap.kernel import frames as _frames
from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel import subdivide as _subdivide
from ramure.gmap.organs import regions as _regions
from ramure.gmap.organs import species as _species
from ramure.gmap.organs import tissue as _tissue
from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.map3 import GMap3

#: A 1-D profile, mapping sample positions to values of the same shape.
Profile = Callable[[NDArray[np.float64]], NDArray[np.float64]]

#: 1-D profile functions and their sampling interval ``[binf, bsup]``, walked
#: from the blossom end (first trunk prism) to the stem end.  The pear's
#: interval [-0.6, 1.6] is walked downwards so its neck is at the stem end.
PROFILES: dict[str, tuple[Profile, float, float]] = {
    "sin": (np.sin, 0.0, np.pi),
    "constant": (np.ones_like, 0.0, 1.0),
    "circle": (lambda x: np.sqrt(np.clip(1.0 - x * x, 0.0, None)), -1.0, 1.0),
    "circle15": (lambda x: np.sqrt(np.clip(1.5 * (1.0 - x * x), 0.0, None)), -1.0, 1.0),
    "pear": (lambda x: x**3 * (1.5 - x) + 0.46, 1.6, -0.6),
}

#: Shape parameters and their defaults (Grammar 2.7).
SHAPE_DEFAULTS = {
    "precision": 10,
    "ph": 10,
    "longueur": 15.0,
    "fc": "sin",
    "lmin": 0.1,
    "largeur": 55.0,
    "fb": "circle",
    "wminb": 0.1,
    "nbprotus": 0,
    "creux": 0.5,
    "anglesup": 0.0,
    "angleinf": -30.0,
    "nbvolangle": 5,
    "rotx": 0.0,
    "roty": 0.0,
    "rotz": 0.0,
    "stepmax": 0,
    "vmax": 1.0,
    "vmin_a": 1.0,
    "vmin_b": 1.0,
    "fmin": 1.0,
    "hamp": 0.0,
}

#: Every accepted parameter with its default (shape, then internal structure).
DEFAULTS = {**SHAPE_DEFAULTS, **_tissue.DEFAULTS}

#: The six presets of Table 2.12 (values not listed take :data:`DEFAULTS`).
PRESETS = {
    "round_tomato": dict(
        precision=10,
        ph=10,
        longueur=13.0,
        fc="sin",
        largeur=55.0,
        fb="circle",
        nbvolangle=5,
        angleinf=-60.0,
        anglesup=0.0,
        carpels=3,
    ),
    "banana": dict(
        precision=10, ph=10, rotz=12.0, longueur=80.0, fc="constant", largeur=90.0, fb="circle", nbvolangle=0, carpels=3
    ),
    "cherry_tomato": dict(
        precision=20,
        ph=10,
        longueur=10.5,
        fc="constant",
        largeur=100.0,
        fb="circle15",
        nbvolangle=15,
        angleinf=-15.0,
        anglesup=0.0,
        carpels=2,
    ),
    "pear": dict(
        precision=20,
        ph=10,
        longueur=17.0,
        fc="pear",
        largeur=60.0,
        fb="pear",
        nbvolangle=0,
        carpels=5,
        seeds=0,
        pips=2,
        core_low=0.08,
        core_high=0.5,
        seed_band=0.7,
    ),
    "elongated_tomato": dict(
        precision=20,
        ph=10,
        longueur=25.0,
        fc="sin",
        largeur=60.0,
        fb="circle",
        nbvolangle=15,
        angleinf=-60.0,
        anglesup=0.0,
        carpels=2,
    ),
    "ribbed_tomato": dict(
        precision=20,
        ph=24,
        longueur=5.0,
        fc="sin",
        largeur=55.0,
        fb="circle",
        nbprotus=6,
        creux=0.5,
        nbvolangle=15,
        angleinf=-60.0,
        anglesup=0.0,
        carpels=6,
    ),
    # Not in Table 2.12 (Ramure's): an apple, round and a little flattened, dimpled at both
    # ends (nbvolangle = precision), five carpels and ten pips; a plum and a cherry (drupes):
    # one kernel in a stone (the differentiation's endocarp and locules, see
    # :mod:`ramure.gmap.organs.species`), a shallow stem cavity; the plum is oval with its
    # suture (one shallow groove: nbprotus=1, creux=0.88).
    # Inside (issue 40): the core or stone fills an oval band of the axis (core_low ..
    # core_high, chosen so the measured span over the fruit's height is what a lengthwise cut
    # shows): an apple's core the middle 0.44 of the height (a third to a half), with two
    # whole-cell pips per carpel (pips=2, ten in all, in the band's middle 60 %); a pear's
    # core the wide blossom half (0.09 .. 0.49 of the height), ten pips likewise; a plum's
    # stone 0.62 of its length (55-65 %), a cherry's 0.51 of its height (45-55 %), each with
    # a kernel filling the middle 60 % of the stone inside its shell (kernel=0.6).
    "apple": dict(
        precision=12,
        ph=12,
        longueur=12.0,
        fc="sin",
        largeur=62.0,
        fb="circle",
        nbvolangle=12,
        anglesup=25.0,
        angleinf=-45.0,
        carpels=5,
        seeds=0,
        pips=2,
        mesocarp=0.78,
        endocarp=0.06,
        core_low=0.25,
        core_high=0.8,
        seed_band=0.6,
    ),
    "plum": dict(
        precision=10,
        ph=12,
        longueur=19.0,
        fc="sin",
        largeur=50.0,
        fb="circle",
        nbprotus=1,
        creux=0.88,
        nbvolangle=3,
        angleinf=-30.0,
        anglesup=0.0,
        carpels=1,
        septum=0.0,
        seeds=0,
        mesocarp=0.8,
        endocarp=0.06,
        core_low=0.2,
        core_high=0.8,
        kernel=0.6,
    ),
    "cherry": dict(
        precision=10,
        ph=10,
        longueur=12.0,
        fc="sin",
        largeur=55.0,
        fb="circle",
        nbvolangle=4,
        angleinf=-40.0,
        anglesup=0.0,
        carpels=1,
        septum=0.0,
        seeds=0,
        mesocarp=0.8,
        endocarp=0.06,
        core_low=0.22,
        core_high=0.78,
        kernel=0.6,
    ),
}


def sample(profile: str, count: int, floor: float) -> NDArray[np.float64]:
    """Sample a named profile at ``count`` evenly spaced points of its interval, floored.

    ``x_i = binf + i dx`` with ``dx = (bsup - binf) / (count - 1)``; returns
    ``max(floor, f(x_i))``.

    >>> sample("circle", 3, 0.1).tolist()
    [0.1, 1.0, 0.1]
    """
    f, lo, hi = PROFILES[profile]
    x = np.linspace(lo, hi, count) if count > 1 else np.array([lo])
    return np.maximum(floor, f(x))


def rib_profile(ph: int, nbprotus: int, creux: float) -> NDArray[np.float64]:
    """``fd(k)`` for the ``ph`` sectors: 1 without ribs, else ``max(creux, |sin(k pi nbprotus / ph)|)``.

    >>> np.round(rib_profile(8, 2, 0.5), 3).tolist()
    [0.5, 0.707, 1.0, 0.707, 0.5, 0.707, 1.0, 0.707]
    """
    k = np.arange(ph)
    if nbprotus <= 0:
        return np.ones(ph)
    return np.maximum(creux, np.abs(np.sin(k * np.pi * nbprotus / ph)))


def dimple_angles(precision: int, nbvolangle: int, anglesup: float, angleinf: float) -> NDArray[np.float64]:
    """Branch turn angle ``fa`` per trunk stage: a ramp on the last ``nbvolangle`` stages.

    >>> dimple_angles(10, 5, 0.0, -60.0).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -15.0, -30.0, -45.0, -60.0]
    """
    fa = np.zeros(precision)
    if nbvolangle <= 0:
        return fa
    dxa = abs(anglesup - angleinf) / (nbvolangle - 1) if nbvolangle > 1 else 0.0
    start = precision - nbvolangle
    x = np.arange(start, precision)
    fa[start:] = anglesup - (x - start) * dxa
    return fa


def variate(precision: int, stepmax: int, vmax: float, vmin_a: float, vmin_b: float) -> NDArray[np.float64]:
    """Vertical constraint per ring (thesis 3.1, approach 2): up from ``vmin_a`` to ``vmax`` at
    ring ``stepmax``, then down to ``vmin_b`` at ring ``precision``.

    >>> np.round(variate(5, 2, 1.0, 0.2, 0.8), 3).tolist()
    [0.2, 0.6, 1.0, 0.933, 0.867]
    """
    x = np.arange(precision, dtype=float)
    up = vmin_a + (vmax - vmin_a) / stepmax * x if stepmax > 0 else np.full(precision, float(vmax))
    down = vmax - (vmax - vmin_b) / max(precision - stepmax, 1) * (x - stepmax)
    return np.where(x <= stepmax, up, down)


def hfunction(ph: int, fmin: float, hamp: float) -> NDArray[np.float64]:
    """Horizontal constraint per sector: ``fmin + hamp sin(k pi / (ph - 1))``, k = 0 .. ph-1.

    >>> np.round(hfunction(5, 1.0, 1.0), 3).tolist()
    [1.0, 1.707, 2.0, 1.707, 1.0]
    """
    k = np.arange(ph)
    return fmin + hamp * np.sin(k * np.pi / max(ph - 1, 1))


def resolve_params(preset: str = "round_tomato", **params: object) -> dict[str, Any]:
    """Preset values overridden by ``params``, checked and converted; a plain dict.

    Values may be strings (from the command line); they are converted to the
    default's type.  Unknown names and out-of-range values raise
    :class:`~ramure.gmap.kernel.errors.ValueRefused`.

    >>> resolve_params("banana", precision="12")["precision"]
    12
    """
    if preset not in PRESETS:
        raise ValueRefused(f"unknown fruit preset {preset!r}; choose one of {', '.join(PRESETS)}")
    out = dict(DEFAULTS)
    out.update(PRESETS[preset])
    for name, value in params.items():
        if name not in DEFAULTS:
            raise ValueRefused(f"unknown fruit parameter {name!r}; known: {', '.join(sorted(DEFAULTS))}")
        out[name] = _convert(name, value, DEFAULTS[name])
    _check(out)
    return out


def _convert(name, value, default):
    try:
        if isinstance(default, bool):
            return value if isinstance(value, bool) else str(value).lower() in ("1", "true", "yes", "on")
        if isinstance(default, int):
            as_float = float(value)
            if as_float != int(as_float):
                raise ValueError
            return int(as_float)
        if isinstance(default, float):
            return float(value)
        return str(value)
    except (TypeError, ValueError):
        kind = type(default).__name__
        raise ValueRefused(f"fruit parameter {name}={value!r} is not a valid {kind}") from None


def _check(p) -> None:
    def need(cond, message):
        if not cond:
            raise ValueRefused(message)

    need(1 <= p["precision"] <= 2000, f"precision must be in 1..2000, got {p['precision']}")
    need(3 <= p["ph"] <= 2000, f"ph (branches per ring) must be in 3..2000, got {p['ph']}")
    for name in ("longueur", "largeur"):
        need(p[name] > 0, f"{name} must be > 0, got {p[name]}")
    for name in ("lmin", "wminb"):
        need(p[name] > 0, f"{name} must be > 0 (it floors a size), got {p[name]}")
    for name in ("fc", "fb"):
        need(p[name] in PROFILES, f"{name} must be one of {', '.join(PROFILES)}, got {p[name]!r}")
    need(0 < p["creux"] <= 1, f"creux must be in (0, 1], got {p['creux']}")
    need(p["nbprotus"] >= 0, f"nbprotus must be >= 0, got {p['nbprotus']}")
    need(0 <= p["nbvolangle"] <= p["precision"], f"nbvolangle must be in 0..precision ({p['precision']}), got {p['nbvolangle']}")
    need(0 <= p["stepmax"] <= p["precision"], f"stepmax must be in 0..precision ({p['precision']}), got {p['stepmax']}")
    for name in ("vmax", "vmin_a", "vmin_b", "fmin"):
        need(p[name] > 0, f"{name} must be > 0 (it scales branch lengths), got {p[name]}")
    need(p["hamp"] >= 0, f"hamp must be >= 0, got {p['hamp']}")
    _tissue.check_params(p)


def _trunk_frames(p, base_frame):
    """Origins and frames of the trunk prisms, each on its parent's E face."""
    n = p["precision"]
    fc = p["longueur"] * sample(p["fc"], n, p["lmin"])
    origins = np.zeros((n, 3))
    frames = np.empty((n, 3, 3))
    frames[0] = base_frame
    for i in range(1, n):  # one step per trunk segment, not per dart
        frames[i] = _frames.rotate(frames[i - 1], p["rotx"], p["roty"], p["rotz"])
        origins[i] = origins[i - 1] + fc[i - 1] * frames[i - 1, 0]
    return origins, frames, fc


def build_shape(**params: Any) -> GMap3:
    """The fruit's 3-G-map before internal structure (all parameters resolved).

    Trunk prisms are volumes ``0 .. precision-1`` (label A, order 0, stage i);
    branch (i, k) on face C(k+1) of trunk prism i is volume
    ``precision + i * ph + k`` (label B, order 1, parent i).
    """
    p = dict(params)
    n, ph = p["precision"], p["ph"]
    base_frame = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # H = z, L = x, U = y
    origins, frames, fc = _trunk_frames(p, base_frame)
    gm = GMap3()
    gm.add_volume_data("ring", np.int32, fill=-1)
    gm.add_volume_data("sector", np.int32, fill=-1)
    sizes = np.repeat(fc[:, None], 3, axis=1)
    trunk = gm.add_prisms(
        ph,
        n,
        origins,
        frames,
        sizes,
        label="A",
        order=0,
        stage=np.arange(n),
        tissue=_tissue.CODES["columella"],
        ring=np.arange(n),
    )
    # branch frames from the default corners of each trunk lateral face
    c = _prism.corners(ph, origins, frames, sizes)  # (n, 2ph, 3)
    k = np.arange(ph)
    k1 = (k + 1) % ph
    pb, pb1, pt1, pt = c[:, k], c[:, k1], c[:, ph + k1], c[:, ph + k]  # (n, ph, 3)
    centre = 0.25 * (pb + pb1 + pt1 + pt)
    u = (pb1 - pb) + (pt1 - pt)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    down = (pb + pb1) - (pt + pt1)
    down -= np.sum(down * u, axis=-1, keepdims=True) * u
    down /= np.linalg.norm(down, axis=-1, keepdims=True)
    bframes = np.stack([np.cross(down, u), down, u], axis=-2)  # rows H (outward), L, U
    fa = dimple_angles(n, p["nbvolangle"], p["anglesup"], p["angleinf"])
    bframes = _frames.rotate(bframes, atz=np.repeat(fa[:, None], ph, axis=1))
    fb = sample(p["fb"], n, p["wminb"])
    fd = rib_profile(ph, p["nbprotus"], p["creux"]) * hfunction(ph, p["fmin"], p["hamp"])
    fb = fb * variate(n, p["stepmax"], p["vmax"], p["vmin_a"], p["vmin_b"])
    bsizes = np.stack(
        [
            p["largeur"] * fb[:, None] * fd[None, :],
            np.linalg.norm(pt - pb, axis=-1),
            np.linalg.norm(pb1 - pb, axis=-1),
        ],
        axis=-1,
    )
    ring = np.repeat(np.arange(n), ph)
    branch = gm.add_prisms(
        4,
        n * ph,
        centre.reshape(-1, 3),
        bframes.reshape(-1, 3, 3),
        bsizes.reshape(-1, 3),
        label="B",
        order=1,
        stage=0,
        parent=ring,
        parent_face=np.tile(k + 2, n),
        tissue=_tissue.CODES["pericarp"],
        ring=ring,
        sector=np.tile(k, n),
    )
    tb = _prism.template(4)
    gm.dart_data["radial"][branch[:, None] + np.arange(tb.size)] = (tb.corner >= 4)[None, :]
    bgrid = branch.reshape(n, ph)
    # glue: trunk E to next O; branch O to trunk side; branches around and along the axis
    face = gm.prism_face
    gm.sew3(face(trunk[:-1], ph, "E"), face(trunk[1:], ph, "O"))
    trunk_sides = np.repeat(trunk, ph) + 4 * ph + 8 * np.tile(k, n)  # dart 0 of C(k+1)
    a = [trunk_sides, face(bgrid, 4, "C2"), face(bgrid[:-1], 4, "C3")]  # all quads: one walk
    b = [face(branch, 4, "O"), face(bgrid[:, k1], 4, "C4", 1), face(bgrid[1:], 4, "C1", 1)]
    gm.sew3(np.concatenate([np.ravel(x) for x in a]), np.concatenate([np.ravel(x) for x in b]))
    gm.embed()
    return gm


#: Most darts a fruit may have (about 450 bytes each once built): absurd parameters
#: such as precision=2000 with two volume subdivisions are refused, not an out-of-memory.
MAX_DARTS = 8_000_000


def estimated_darts(p: Mapping[str, Any], volume_levels: int = 0, surface_levels: int = 0) -> float:
    """Darts of the fruit ``build_fruit`` would make: 60 per trunk branch, x8 per volume
    subdivision (plus about 20 % for tissues), x4 per surface subdivision."""
    darts = 60 * int(p["precision"]) * int(p["ph"]) * 8 ** int(volume_levels) * 4 ** int(surface_levels)
    return darts * (1.2 if volume_levels else 1.0)


def build_fruit(
    preset: str = "round_tomato",
    *,
    seed: int = 0,
    volume_levels: int = 0,
    surface_levels: int = 0,
    tissues: bool = True,
    size: float | None = None,
    origin: ArrayLike | None = None,
    frame: ArrayLike | None = None,
    anchor: str = "center",
    ripeness: str | None = None,
    size_mm: float | None = None,
    regions: Sequence[Mapping[str, Any]] = (),
    **params: object,
) -> GMap3:
    """Build a volumetric fruit from a preset and parameter overrides.

    Steps: shape (trunk, branches, gluing, embedding); ``volume_levels``
    volume subdivisions; internal tissues when ``tissues`` and
    ``volume_levels >= 1`` (random seeds from ``seed``); ``surface_levels``
    surface subdivisions; placement.  Placement puts the ``anchor``
    (``"center"``: bounding-box centre, ``"stem"``: centre of the stem-end
    face of the axis) at ``origin``, scales uniformly so that the largest
    extent of the fruit's own bounding box (before turning) is ``size`` (when given) and turns the fruit so its
    axis (blossom end to stem end, local +z) follows ``frame[0]`` (rows H,
    L, U; local x goes to L).  Provenance is stored in ``gm.meta``, with the
    species, the ``ripeness`` stage (default the ripe one, see
    :mod:`ramure.gmap.organs.species`) and the real size ``size_mm`` (the
    preset's, :data:`ramure.gmap.organs.species.SIZE_MM`, unless given): the
    millimetres of the defects and of the pictures.

    ``regions`` (see :mod:`ramure.gmap.organs.regions`): parts of the fruit, named by
    label, re-derived with their own shape parameters after the rest is built; the
    placement (centre, size) is that of the fruit without them, so a region never moves
    the rest of the fruit.

    >>> gm = build_fruit("banana", precision=6, ph=6)
    >>> gm.counts()["volumes"], gm.is_valid()
    (42, True)
    """
    p = resolve_params(preset, **params)
    species = _species.species_of(preset)
    stage = _species.check_stage(species, ripeness)
    if size_mm is not None and not (np.isfinite(size_mm) and size_mm > 0):
        raise ValueRefused(f"size_mm must be a finite number of millimetres > 0, got {size_mm}")
    levels = [int(volume_levels), int(surface_levels)]
    if min(levels) < 0:
        raise ValueRefused(f"subdivision levels must be >= 0, got volume={levels[0]}, surface={levels[1]}")
    if anchor not in ("center", "stem"):
        raise ValueRefused(f"anchor must be 'center' or 'stem', got {anchor!r}")
    darts = estimated_darts(p, *levels)
    if darts > MAX_DARTS:
        raise ValueRefused(
            f"this fruit would have about {darts:,.0f} darts, more than the limit of {MAX_DARTS:,} "
            f"(precision={p['precision']}, ph={p['ph']}, volume levels {levels[0]}, surface levels "
            f"{levels[1]}): lower precision or ph, or subdivide fewer times"
        )
    t0 = time.perf_counter()
    gm, stem = built_unplaced(p, seed, volume_levels, surface_levels, tissues)
    _, before = gm.vertex_positions()
    if regions:

        def build(changes):
            return built_unplaced(resolve_params(preset, **{**p, **changes}), seed, levels[0], levels[1], tissues)[0]

        gm = _regions.apply_regions(gm, regions, build, int(p["precision"]))
    _place(gm, stem, anchor, size, origin, frame, before)
    placed = gm.meta
    gm.meta = {
        "preset": preset,
        "species": species,
        "ripeness": stage,
        "size_mm": _species.SIZE_MM[preset] if size_mm is None else float(size_mm),
        "mm_per_unit": 0.0,
        "params": p,
        "seed": int(seed),
        "volume_levels": int(volume_levels),
        "surface_levels": int(surface_levels),
        "seconds": time.perf_counter() - t0,
        "placement": placed["placement"],
        "_scale": placed["_scale"],
    }
    if regions:
        gm.meta["regions"] = [dict(r) for r in regions]
    scale = gm.meta.pop("_scale")
    if regions:  # measured without them: a region never rescales the fruit
        extent = float((before.max(axis=0) - before.min(axis=0)).max()) * scale
    else:  # measured on the placed fruit, to the last bit as before regions existed
        _, pos = gm.vertex_positions()
        extent = float((pos.max(axis=0) - pos.min(axis=0)).max())
    gm.meta["extent"] = extent  # without its regions: what sizes and placements use
    gm.meta["mm_per_unit"] = gm.meta["size_mm"] / max(extent, 1e-12)
    return gm


def built_unplaced(
    p: Mapping[str, Any], seed: int, volume_levels: int, surface_levels: int, tissues: bool = True
) -> tuple[GMap3, np.ndarray]:
    """The fruit of resolved parameters ``p`` in its own frame (before placement), and its
    stem point: shape, volume subdivisions, tissues, surface subdivisions."""
    gm = build_shape(**p)
    stem = _stem_point(gm, p)
    if volume_levels:
        gm = _subdivide.volume(gm, volume_levels)
        if tissues:
            gm = _tissue.differentiate(gm, rng=np.random.default_rng(seed), **{k: p[k] for k in _tissue.DEFAULTS})
    if surface_levels:
        gm = _subdivide.surface(gm, surface_levels)
    return gm, stem


def _stem_point(gm, p):
    """Centre of the last trunk prism's E face (the stem end)."""
    last = p["precision"] - 1
    data = gm.dart_data
    mask = (gm.dart_volume == last) & (data["face"] == _prism.FACE_E)
    return gm.points[mask].mean(axis=0)


def _place(gm, stem, anchor, size, origin, frame, pos):
    """Move, scale and turn ``gm`` as :func:`build_fruit` says, by the vertex positions ``pos``
    of the fruit without regions; the scale is left in ``gm.meta["_scale"]``."""
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    ref = 0.5 * (lo + hi) if anchor == "center" else stem
    scale = 1.0
    if size is not None:
        if not float(size) > 0:
            raise ValueRefused(f"fruit size must be > 0, got {size}")
        scale = float(size) / max(float((hi - lo).max()), 1e-12)
    rot = np.eye(3)
    if frame is not None:
        f = np.asarray(frame, float).reshape(3, 3)
        rot = np.stack([f[1], f[2], f[0]])  # local x -> L, y -> U, z (axis) -> H
    off = np.zeros(3) if origin is None else np.asarray(origin, float).reshape(3)
    gm.transform(rotation=rot, scale=scale, offset=off - scale * ref @ rot)
    gm.meta = {**(gm.meta or {}), "_scale": scale, "placement": {"rotation": rot.tolist(), "scale": scale}}


def regrow_region(gm: GMap3, region: Mapping[str, Any], params: Mapping[str, Any], blend: int | None = None) -> GMap3:
    """``gm`` (a fruit :func:`build_fruit` made) with ``region`` re-derived with shape
    ``params``: the fruit is built again from ``gm.meta``'s recipe, as is and with the
    changes, in ``gm``'s frame, and the region's own vertices move by the difference (see
    :mod:`ramure.gmap.organs.regions`); every dart outside the region keeps its bytes.
    A finer ``precision`` (the fruit's times 2, 4 or 8) then refines the region
    (:func:`ramure.gmap.organs.refine.refine_volumes`); a coarser one is refused.

    >>> gm = build_fruit("round_tomato", volume_levels=1)
    >>> out = regrow_region(gm, {"cells": [[4, 2], [4, 3]]}, {"largeur": 70.0})
    >>> out.is_valid(), bool((out.points != gm.points).any())
    (True, True)
    """
    meta = gm.meta or {}
    if "preset" not in meta or "params" not in meta:
        raise ValueRefused("this map does not say how it was built (meta preset and params): build it with build_fruit")
    changes = _regions.check_params(params)
    wanted = changes.pop("precision", None)
    if wanted is not None:
        _regions.refine_levels(int(meta["params"]["precision"]), wanted)  # refused before any work
    if changes:
        gm = _shape_regrown(gm, meta, region, changes, blend)
    if wanted is not None:
        gm = _regions.refine_region(gm, region, wanted, int(meta["params"]["precision"]))
    return gm


def _shape_regrown(gm, meta, region, changes, blend):
    """``gm`` with the region's own vertices moved to the fruit built with shape ``changes``."""
    levels = (int(meta.get("volume_levels", 0)), int(meta.get("surface_levels", 0)))
    place = meta.get("placement") or {"rotation": np.eye(3).tolist(), "scale": 1.0}
    pair = []
    for p in (resolve_params(meta["preset"], **meta["params"]), resolve_params(meta["preset"], **{**meta["params"], **changes})):
        built, _ = built_unplaced(p, int(meta.get("seed", 0)), *levels)
        built.transform(rotation=np.asarray(place["rotation"], float), scale=float(place["scale"]))
        pair.append(built)
    return _regions.regrow_region(gm, region, pair[0], pair[1], blend=blend)
