"""Regions of one volumetric fruit, selected by label and regenerated alone (issue 40, §6).

A **region** names volumes of a fruit through their labels, never through dart or volume
ids, so it survives subdivision: volume subdivision keeps every cell's ``ring`` and
``sector`` (and Bohl's path of radial stages), so a region resolved on a subdivided fruit
names the children of the cells it named before.  Two kinds (plain dicts, so a session
file holds them):

``{"path": "(9, C*, *)"}``
    Bohl's label pattern (thesis §3.2; :func:`ramure.gmap.organs.excrescence.resolve_path`):
    ring 9, every sector, every radial stage.
``{"cells": [[ring, sector], ...]}``
    whole branch columns (skin to trunk), what a click, a brush or a rubber band on the
    skin picks (:func:`cells_near`, :func:`skin_cells`).

Either may be narrowed by ``"faces": "E(^b[a-z]*$)"``, Bohl's sub-label regular expression
(thesis §2.4.2, ``A_{E(F)}``): only the volumes with a face of that label (``O``, ``E``,
``Ck``) whose sub-label matches (:func:`re.search`; subdivision appends one letter per level,
``a`` top-left, ``b`` bottom-left, ``c`` bottom-right, ``d`` top-right) stay, so ``^b`` names
the bottom-left quarter of each skin face at every later level.

**Regenerating a region** (:func:`ramure.gmap.organs.fruit.regrow_region`, then
:func:`regrow_region` here) re-derives the fruit grammar with other
shape parameters (a local malformation: ``largeur``, ``creux``, ``nbprotus``, ``hamp``,
``vmax`` ..., or the tissue thicknesses) and takes from it only the vertices *inside* the
region: a vertex moves when every volume round it is in the region.  A vertex shared with
a volume outside stays where it was, so every dart of a volume outside the region keeps its
bytes (position and attributes), and the topology is untouched, so the map stays valid and
its Euler characteristic is kept.  ``blend`` (hops) fades the change in from the region's
rim: a free vertex ``h`` edges from the nearest pinned vertex moves ``min(1, h / blend)``
of the way.

**Another precision** (``precision`` = the fruit's times 2, 4 or 8: :func:`refine_levels`)
refines the region alone, 1 to 3 times, by :func:`ramure.gmap.organs.refine.refine_volumes`:
its cells are split into eight each time, and a transition cell at each face the region
shares with the outside keeps that face whole, so every dart outside keeps its bytes, the
map stays valid and its Euler characteristic is kept.  The refined cells and the transition
cells carry their parent's ring, sector and radial layer (plus ``refined`` and ``sub``), so
the region's pattern still names them.  The choice: refining, rather than deriving the
grammar again at the finer precision and splicing its cells in, keeps the fruit's shape
exactly where it was (a finer mesh of the same fruit) and needs no second build.  A
coarser precision is refused (merging cells would change the faces they share with the
outside), and so are ``ph``, the carpels, the seeds and the septum, which change the whole
fruit's cells.  Shape changes are applied first, then refinements, in the order of the
regions (a shape change moves vertices of the fruit as built; a refinement then
interpolates the moved ones).

>>> from ramure.gmap.organs.fruit import build_fruit, regrow_region
>>> gm = build_fruit("round_tomato", volume_levels=1)
>>> region = {"path": "(5, C*, *)"}
>>> len(region_volumes(gm, region)) == 10 * 8
True
>>> out = regrow_region(gm, region, {"largeur": 70.0})
>>> out.is_valid(), out.euler_characteristic() == gm.euler_characteristic()
(True, True)
>>> finer = regrow_region(gm, region, {"precision": 20})  # twice the fruit's 10
>>> len(region_volumes(finer, region)), finer.is_valid()
(760, True)
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse
from scipy.sparse import csgraph

from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.kernel.map3 import GMap3

#: Parameters a region may not change: they change the whole fruit's topology
#: (``precision`` may be made finer: :func:`refine_levels`).
TOPOLOGY_PARAMS = ("ph", "carpels", "seeds", "septum")
#: Keys of a region dict besides its selector (``path`` or ``cells``).
REGION_KEYS = ("path", "cells", "faces", "params", "blend")
_FACES = re.compile(r"^\s*(?P<label>[OoEe]|[Cc]\d+)\s*\((?P<regex>.*)\)\s*$")


def check_region(region: Mapping[str, Any]) -> dict[str, Any]:
    """A region dict checked and normalised (cells as sorted ``[ring, sector]`` pairs).

    >>> check_region({"cells": [(2, 1), (1, 3), (2, 1)]})
    {'cells': [[1, 3], [2, 1]]}
    """
    if not isinstance(region, Mapping):
        raise ValueRefused(f"a fruit region is a dict with 'path' or 'cells', got {region!r}")
    unknown = set(region) - set(REGION_KEYS)
    if unknown:
        raise ValueRefused(f"unknown fruit-region key(s) {sorted(unknown)}; known: {', '.join(REGION_KEYS)}")
    if ("path" in region) == ("cells" in region):
        raise ValueRefused("a fruit region has either a 'path' (a label pattern such as (9, C*, *)) or 'cells'")
    out: dict[str, Any] = {}
    if "faces" in region:
        m = _FACES.match(str(region["faces"]))
        if not m:
            raise ValueRefused(f"faces is a face label and a sub-label pattern, e.g. E(^b[a-z]*$), got {region['faces']!r}")
        try:
            re.compile(m.group("regex"))
        except re.error as err:
            raise ValueRefused(f"faces {region['faces']!r}: not a regular expression ({err})") from None
        out["faces"] = str(region["faces"]).strip()
    if "path" in region:
        from ramure.gmap.organs.excrescence import parse_path

        parse_path(str(region["path"]))  # a GrammarError with a caret
        out["path"] = str(region["path"]).strip()
    else:
        try:
            cells = np.asarray([[int(r), int(s)] for r, s in region["cells"]], np.int64).reshape(-1, 2)
        except (TypeError, ValueError):
            raise ValueRefused("region cells are [ring, sector] pairs of whole numbers") from None
        if not len(cells):
            raise ValueRefused("an empty fruit region: select some of the fruit's skin first")
        if (cells < 0).any():
            raise ValueRefused("region cells have rings and sectors >= 0")
        out["cells"] = np.unique(cells, axis=0).tolist()
    if "params" in region:
        out["params"] = check_params(region["params"])
    if "blend" in region:
        blend = int(region["blend"])
        if blend < 1:
            raise ValueRefused(f"blend is a number of edges >= 1, got {region['blend']}")
        out["blend"] = blend
    return out


def check_params(params: Mapping[str, Any]) -> dict[str, Any]:
    """Region parameters as a plain dict, refusing those that change the topology (their
    names and values are checked by the fruit builder, :func:`ramure.gmap.organs.fruit.regrow_region`)."""
    out = {}
    for name, value in dict(params).items():
        if name in TOPOLOGY_PARAMS:
            raise ValueRefused(
                f"a region cannot change {name}: it changes the fruit's cells, so darts outside the region "
                "would change (regrow the whole fruit for that)"
            )
        if name == "precision":
            try:
                value = int(value)
            except (TypeError, ValueError):
                raise ValueRefused(f"a region's precision is a whole number of stages, got {value!r}") from None
            if value < 1:
                raise ValueRefused(f"a region's precision is a whole number of stages >= 1, got {value}")
        out[str(name)] = value
    return out


def refine_levels(fruit_precision: int, precision: int) -> int:
    """How many times a region is refined for ``precision`` on a fruit of ``fruit_precision``:
    ``precision`` must be the fruit's times 2, 4 or 8 (1 to 3 levels; the fruit's own: 0).

    >>> refine_levels(10, 20), refine_levels(10, 80), refine_levels(10, 10)
    (1, 3, 0)
    """
    from ramure.gmap.organs.refine import MAX_LEVELS

    base, wanted = int(fruit_precision), int(precision)
    if wanted < base:
        raise ValueRefused(
            f"a region cannot be coarser than its fruit (precision {wanted} < {base}): merging its cells "
            "would change the faces it shares with the rest (regrow the whole fruit for that)"
        )
    for levels in range(MAX_LEVELS + 1):
        if wanted == base * 2**levels:
            return levels
    steps = ", ".join(str(base * 2**k) for k in range(1, MAX_LEVELS + 1))
    raise ValueRefused(
        f"a region's precision is the fruit's ({base}) times 2, 4 or 8 ({steps}), got {wanted}: "
        "a region is refined by halving its cells"
    )


def region_volumes(gm: GMap3, region: Mapping[str, Any]) -> np.ndarray:
    """Volume ids of ``gm`` the region names (sorted); a region naming no volume is refused."""
    region = check_region(region)
    vd = gm.volume_data
    if "ring" not in vd or "sector" not in vd:
        raise GMapError("fruit regions need a fruit (volumes with ring and sector attributes)")
    if "path" in region:
        from ramure.gmap.organs.excrescence import resolve_path

        vols = np.asarray(resolve_path(gm, region["path"]), np.int64)
    else:
        ring, sector = vd["ring"].astype(np.int64), vd["sector"].astype(np.int64)
        ph = int(sector.max()) + 1
        cells = np.asarray(region["cells"], np.int64)
        keep = (sector >= 0) & np.isin(ring * ph + sector, cells[:, 0] * ph + cells[:, 1])
        vols = np.flatnonzero(keep)
    if "faces" in region:
        vols = _with_faces(gm, vols, region["faces"])
    if not len(vols):
        raise ValueRefused(f"the region {region_text(region)} names no cell of this fruit")
    return np.unique(vols)


def _with_faces(gm: GMap3, vols: np.ndarray, faces: str) -> np.ndarray:
    """The volumes of ``vols`` with a face of the label whose sub-label matches the pattern."""
    from ramure.gmap.kernel.prism import face_label_code
    from ramure.gmap.kernel.storage import sublabel_name

    m = _FACES.match(faces)
    assert m is not None  # checked by check_region
    code, pattern = face_label_code(m.group("label")), re.compile(m.group("regex"))
    data = gm.dart_data
    darts = np.flatnonzero((data["face"] == code) & np.isin(gm.dart_volume, vols))
    subs = np.asarray(data["sublabel"])[darts]
    names = {int(c): bool(pattern.search(sublabel_name(int(c)))) for c in np.unique(subs)}
    hit = np.array([names[int(c)] for c in subs], bool) if len(subs) else np.zeros(0, bool)
    return np.unique(gm.dart_volume[darts[hit]]).astype(np.int64)


def region_text(region: Mapping[str, Any]) -> str:
    """A short name for a region: its pattern, or its cell count.

    >>> region_text({"cells": [[1, 2], [1, 3]]}), region_text({"path": "(9, C*, *)"})
    ('2 skin cells', '(9, C*, *)')
    """
    faces = f" {region['faces']}" if "faces" in region else ""
    if "path" in region:
        return str(region["path"]) + faces
    n = len(region.get("cells", ()))
    return f"{n} skin cell{'s' if n != 1 else ''}{faces}"


def region_darts(gm: GMap3, region: Mapping[str, Any]) -> np.ndarray:
    """Mask over darts: True for the darts of the region's volumes."""
    return np.isin(gm.dart_volume, region_volumes(gm, region))


def free_vertices(gm: GMap3, volumes: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(vid, free)``: vertex id per dart and, per vertex, True when every volume round it
    is one of ``volumes`` (the vertices a region may move)."""
    vid, nv = gm.vertex_ids()
    inside = np.isin(gm.dart_volume, np.asarray(volumes, np.int64))
    outside_at = np.bincount(vid[~inside], minlength=nv) > 0
    inside_at = np.bincount(vid[inside], minlength=nv) > 0
    return vid, inside_at & ~outside_at


def _hops_from_pinned(gm: GMap3, vid: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Edges from every vertex to the nearest pinned (not free) vertex."""
    nv = len(free)
    u, w = vid, vid[gm.alpha[0]]
    graph = sparse.csr_matrix((np.ones(len(u), np.int8), (u, w)), shape=(nv, nv))
    pinned = np.flatnonzero(~free)
    if not len(pinned):
        return np.full(nv, np.inf)
    dist = csgraph.dijkstra(graph, directed=False, indices=pinned, unweighted=True, min_only=True)
    return np.asarray(dist, float)


def regrow_region(
    gm: GMap3,
    region: Mapping[str, Any],
    reference: GMap3,
    regrown: GMap3,
    blend: int | None = None,
    strict: bool = True,
) -> GMap3:
    """``gm`` with the free vertices of ``region`` moved by ``regrown - reference`` (a new map).

    ``reference`` is the fruit as built and ``regrown`` the fruit built with the region's
    parameters, both in ``gm``'s frame and with ``gm``'s topology
    (:func:`ramure.gmap.organs.fruit.regrow_region` builds them from ``gm.meta``).  Adding
    the displacement keeps what earlier regions did.  A free vertex ``h`` edges from the
    nearest pinned one moves ``min(1, h / blend)`` of it.  A region with no vertex of its own
    (one ring of a coarse fruit: every corner is shared with the next ring or the trunk) is
    refused, or leaves ``gm`` as it is when not ``strict`` (the plant's coarse fruit: the
    region shows on the subdivided fruit of the Defects view).
    """
    region = check_region(region)
    blend = int(region.get("blend", 1) if blend is None else blend)
    if blend < 1:
        raise ValueRefused(f"blend is a number of edges >= 1, got {blend}")
    if reference.n_darts != gm.n_darts or regrown.n_darts != gm.n_darts or not np.array_equal(regrown.alpha, gm.alpha):
        raise GMapError("a region is regrown on the fruit as built (its cells changed since: regrow regions first)")
    vols = region_volumes(gm, region)
    vid, free = free_vertices(gm, vols)
    if not free.any():
        if not strict:
            return gm
        raise ValueRefused(
            f"the region {region_text(region)} has no vertex of its own (every corner touches a cell outside): "
            "select more cells, or subdivide the fruit"
        )
    weight = np.clip(_hops_from_pinned(gm, vid, free) / blend, 0.0, 1.0) * free
    out = gm.copy()
    moved = weight[vid] > 0
    delta = (regrown.points - reference.points)[moved]
    out.points[moved] = gm.points[moved] + weight[vid[moved], None] * delta
    out.mark_changed()
    return out


def apply_regions(
    gm: GMap3, regions: Iterable[Mapping[str, Any]], build: Callable[[dict], GMap3], precision: int | None = None
) -> GMap3:
    """Every region with ``params`` regrown in turn on ``gm`` (``build(params)``: the fruit
    built with those parameters in ``gm``'s frame; a region with no vertex of its own at
    this level is skipped, see :func:`regrow_region`), then every region with a finer
    ``precision`` than the fruit's (``precision``) refined, in order (:func:`refine_levels`)."""
    reference = gm
    finer = []
    for region in regions:
        region = check_region(region)
        shape = dict(region.get("params", {}))
        if "precision" in shape:
            finer.append((region, shape.pop("precision")))
        if shape:
            gm = regrow_region(gm, region, reference, build(shape), strict=False)
    for region, wanted in finer:
        gm = refine_region(gm, region, wanted, precision, strict=False)
    return gm


def refine_region(gm: GMap3, region: Mapping[str, Any], wanted: int, precision: int | None, strict: bool = True) -> GMap3:
    """``gm`` with ``region`` refined to ``wanted`` stages on a fruit of ``precision`` stages
    (default ``gm.meta["params"]["precision"]``; see :func:`refine_levels`).  A region naming
    no cell of ``gm`` is refused, or leaves ``gm`` as it is when not ``strict`` (a sub-label
    pattern on the plant's coarse fruit, whose faces have no sub-labels yet)."""
    from ramure.gmap.organs.refine import refine_volumes

    if precision is None:
        precision = (gm.meta or {}).get("params", {}).get("precision")
    if precision is None:
        raise ValueRefused("this map does not say its precision (meta params): build it with build_fruit")
    levels = refine_levels(int(precision), int(wanted))
    if not levels:
        return gm
    try:
        vols = region_volumes(gm, region)
    except ValueRefused:
        if strict:
            raise
        return gm
    return refine_volumes(gm, vols, levels)


def skin_cells(gm: GMap3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(centres (k, 3), cells (k, 2), outward (k, 3))``: the centre of every skin face of a
    branch cell, its ``[ring, sector]`` and its outward direction (unit, from the cell's
    centroid to the face's centre): what a click or a rubber band on the skin selects by."""
    vd = gm.volume_data
    vol = gm.dart_volume.astype(np.int64)
    sector = vd["sector"].astype(np.int64)
    skin = (gm.alpha[3] == np.arange(gm.n_darts)) & (sector[vol] >= 0)
    side, _ = gm.orbit_ids("01")
    skin_darts = np.flatnonzero(skin)
    faces, first, idx = np.unique(side[skin_darts], return_index=True, return_inverse=True)
    per = np.bincount(idx, minlength=len(faces))
    pts = gm.points[skin_darts]
    centres = np.stack([np.bincount(idx, pts[:, j], minlength=len(faces)) for j in range(3)], axis=1) / per[:, None]
    v = vol[skin_darts[first]]
    out = centres - gm.volume_centroids()[v]
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-300)
    return centres, np.stack([vd["ring"].astype(np.int64)[v], sector[v]], axis=1), out


def cells_near(gm: GMap3, point: ArrayLike, radius: float) -> list[list[int]]:
    """The ``[ring, sector]`` cells whose skin faces' centres lie within ``radius`` of
    ``point`` (a picked skin point), the nearest cell always included: a click and a brush."""
    centres, cells, _ = skin_cells(gm)
    if not len(cells):
        raise GMapError("this map has no skin cells to select")
    d = np.linalg.norm(centres - np.asarray(point, float).reshape(1, 3), axis=1)
    keep = (d <= float(radius)) | (d == d.min())
    return np.unique(cells[keep], axis=0).tolist()


def cell_mask(gm: GMap3, cells: Sequence[Sequence[int]] | np.ndarray) -> np.ndarray:
    """Mask over volumes in the given ``[ring, sector]`` cells."""
    return np.isin(np.arange(gm.n_volumes), region_volumes(gm, {"cells": [list(c) for c in cells]}))
