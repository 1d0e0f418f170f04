"""Regions of the selected fruit: selected, shown and regrown (the work behind the desktop's
Defects dock and the Jupyter Defects tab; no Qt, no widgets).

A region is selected on the selected fruit of the plant (:func:`ramure.app.fruit_defects.selected_fruit`)
by a label pattern (Bohl's ``(9, C*, *)``), a click or brush on the skin (a point and a
radius) or a rubber band (a screen rectangle: the skin cells whose face centres project
inside it, through :func:`ramure.app.model.project_to_display` and
:func:`ramure.app.model.leaves_in_rectangle`, the helpers the plant's rubber band uses).
Every selection is stored as labels (the pattern, or ``[ring, sector]`` cells), so it names
the same part of the fruit in the plant's coarse fruit and in the Defects view's subdivided
one.  The selection is state of the explorer (:attr:`ramure.app.model.Explorer.fruit_region`),
not an edit; regrowing it is one undoable edit (:meth:`ramure.app.model.Explorer.regrow_fruit_region`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.model import Explorer
    from ramure.gmap.kernel.map3 import GMap3

#: The colour a selected region is drawn in (mixed with the fruit's own: HIGHLIGHT_MIX of it).
HIGHLIGHT_RGB = (40, 200, 255)
HIGHLIGHT_MIX = 0.55
#: Selection modes of a region (as the plant's selection).
MODES = ("replace", "add", "remove")


def _fruit(ex: Explorer, leaf: int | None, on: GMap3 | None = None) -> tuple[int, GMap3]:
    """The fruit's leaf id and the map a click was made on: ``on`` (the Defects view's
    fruit) or the plant's fruit."""
    from ramure.app.fruit_defects import selected_fruit

    leaf = selected_fruit(ex) if leaf is None else int(leaf)
    return leaf, ex.fruit_volume(leaf) if on is None else on


def combine(old: Mapping[str, Any] | None, new: Mapping[str, Any], mode: str) -> dict[str, Any]:
    """``new`` region combined with ``old`` (same fruit) by ``mode``: cells add and remove;
    a pattern replaces (it is a selection of its own).

    >>> combine({"cells": [[1, 1]]}, {"cells": [[2, 2]]}, "add")
    {'cells': [[1, 1], [2, 2]]}
    """
    from ramure.gmap.organs.regions import check_region

    if mode not in MODES:
        raise ValueRefused(f"region mode is one of {', '.join(MODES)}, not {mode!r}")
    checked = check_region(new)
    if mode == "replace" or old is None or "cells" not in old or "cells" not in checked:
        if mode == "remove":
            raise ValueRefused("nothing to remove from: the region is a pattern or empty")
        return checked
    have = {tuple(c) for c in old["cells"]}
    got = {tuple(c) for c in checked["cells"]}
    cells = have | got if mode == "add" else have - got
    if not cells:
        raise ValueRefused("that would leave the region empty")
    return check_region({"cells": sorted(cells)})


def parse_params(text: str) -> dict[str, Any]:
    """``"largeur=75, creux=0.4"`` -> ``{"largeur": "75", "creux": "0.4"}`` (converted and
    checked by the fruit builder); refused when empty or not ``name=value``.

    >>> parse_params("largeur=75, creux=0.4")
    {'largeur': '75', 'creux': '0.4'}
    """
    out = {}
    for item in filter(None, (x.strip() for x in str(text).split(","))):
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ValueRefused(f"region parameters are name=value, separated by commas; got '{item}'")
        out[name.strip()] = value.strip()
    if not out:
        raise ValueRefused("give the region new parameters, e.g. largeur=75")
    return out


def split_pattern(text: str) -> dict[str, str]:
    """A typed pattern as a region: the path, and the sub-label pattern after it if any.

    >>> split_pattern("(5, C*, *) E(^b)"), split_pattern("(9, C*, *)")
    ({'path': '(5, C*, *)', 'faces': 'E(^b)'}, {'path': '(9, C*, *)'})
    """
    text = str(text).strip()
    close = text.find(")") if text.startswith("(") else -1
    if close < 0 or not text[close + 1 :].strip():
        return {"path": text}
    return {"path": text[: close + 1], "faces": text[close + 1 :].strip()}


def by_pattern(ex: Explorer, pattern: str, leaf: int | None = None, on: GMap3 | None = None) -> tuple[int, dict]:
    """The region a label pattern names on the selected fruit (checked: it names cells): a
    path, optionally followed by a sub-label pattern, ``(5, C*, *) E(^b[a-z]*$)``."""
    from ramure.gmap.organs.regions import region_volumes

    region = split_pattern(pattern)
    if on is None and "faces" in region:  # sub-labels exist once subdivided: check on the Defects view's fruit
        from ramure.app.fruit_defects import damaged_fruit, selected_fruit

        leaf = selected_fruit(ex) if leaf is None else int(leaf)
        on = damaged_fruit(ex, leaf, specs=[])[0]
    leaf, gm = _fruit(ex, leaf, on)
    region_volumes(gm, region)
    return leaf, region


def by_cells(ex: Explorer, cells: Sequence[Sequence[int]], leaf: int | None = None, on: GMap3 | None = None) -> tuple[int, dict]:
    """The region of the given ``[ring, sector]`` skin cells (checked: they are the fruit's)."""
    from ramure.gmap.organs.regions import region_volumes

    leaf, gm = _fruit(ex, leaf, on)
    region = {"cells": [[int(r), int(s)] for r, s in cells]}
    region_volumes(gm, region)
    return leaf, region


def at_point(
    ex: Explorer, point: ArrayLike, radius: float = 0.0, leaf: int | None = None, on: GMap3 | None = None
) -> tuple[int, dict]:
    """The skin cells within ``radius`` of a picked ``point`` (units and frame of the map
    clicked on: ``on``, else the plant's fruit), the nearest always."""
    from ramure.gmap.organs.regions import cells_near

    if not float(radius) >= 0:
        raise ValueRefused(f"brush radius must be >= 0, got {radius}")
    leaf, gm = _fruit(ex, leaf, on)
    return leaf, {"cells": cells_near(gm, point, float(radius))}


def facing_cells(ex: Explorer, matrix: ArrayLike, leaf: int | None = None, on: GMap3 | None = None) -> tuple[int, dict]:
    """What a rubber band on the fruit selects by: the centres of the skin faces facing the
    camera (``centres``), a key per face (``keys`` = ring * ph + sector) and ``ph``.  The far
    side of the fruit is left out: a rubber band drawn on the skin one sees selects that skin
    (:meth:`ramure.app.model.Explorer.select_fruit_region` projects them as
    :meth:`ramure.app.model.Explorer.leaves_in_view` projects the plant's points)."""
    from ramure.gmap.organs.regions import skin_cells

    leaf, gm = _fruit(ex, leaf, on)
    centres, cells, outward = skin_cells(gm)
    ph = int(cells[:, 1].max()) + 1
    front = np.einsum("ij,j->i", outward, view_direction(matrix)) < 0
    return leaf, {"centres": centres[front], "keys": (cells[:, 0] * ph + cells[:, 1])[front], "ph": ph}


def cells_of_keys(keys: Sequence[int], ph: int) -> dict:
    """The region of the skin cells with ``keys`` (ring * ph + sector); refused when empty.

    >>> cells_of_keys([23, 5], 10)
    {'cells': [[2, 3], [0, 5]]}
    """
    if not len(keys):
        raise ValueRefused("the rectangle holds none of the fruit's skin: draw it over the selected fruit")
    return {"cells": [[int(k) // ph, int(k) % ph] for k in keys]}


def view_direction(matrix: ArrayLike) -> np.ndarray:
    """The camera's viewing direction (world, unit) read from a world-to-clip matrix: the
    gradient of clip ``w`` (perspective) or of clip depth (parallel projection).

    >>> view_direction(np.diag([1.0, 1.0, -1.0, 1.0])).tolist()
    [0.0, 0.0, -1.0]
    """
    m = np.asarray(matrix, float).reshape(4, 4)
    d = m[3, :3] if np.linalg.norm(m[3, :3]) > 1e-12 else m[2, :3]
    return d / max(float(np.linalg.norm(d)), 1e-300)


def region_mask(gm: GMap3, region: Mapping[str, Any], leaf: int | None = None) -> np.ndarray:
    """Mask over ``gm``'s volumes: the region's (only fruit ``leaf``'s when ``gm`` holds several)."""
    from ramure.gmap.organs.regions import region_volumes

    keep = np.zeros(gm.n_volumes, bool)
    keep[region_volumes(gm, region)] = True
    if leaf is not None and "leaf_id" in gm.volume_data:
        keep &= np.asarray(gm.volume_data["leaf_id"]) == int(leaf)
    return keep


def highlight(surface: pv.PolyData, mask: np.ndarray, scalars: str = "rgb") -> pv.PolyData:
    """``surface`` (cell data ``volume`` and ``rgb``, or none) with the cells of the volumes in
    ``mask`` drawn in the highlight colour; a new mesh."""
    out = surface.copy()
    vol = np.asarray(out.cell_data["volume"], np.int64)
    if scalars in out.cell_data:
        rgb = np.asarray(out.cell_data[scalars], float).reshape(-1, 3)
    else:
        rgb = np.full((out.n_cells, 3), 200.0)
    on = mask[vol]
    rgb[on] = (1 - HIGHLIGHT_MIX) * rgb[on] + HIGHLIGHT_MIX * np.asarray(HIGHLIGHT_RGB, float)
    out.cell_data[scalars] = np.clip(np.round(rgb), 0, 255).astype(np.uint8)
    out.cell_data["region"] = on
    return out


def shown(ex: Explorer) -> tuple[GMap3, pv.PolyData]:
    """The selected fruit as the Defects view shows it (subdivided, damaged) and its coloured
    skin with the current region highlighted."""
    from ramure.app.fruit_defects import damaged_fruit, surface

    if ex.fruit_region is None:
        raise ValueRefused("select a region of the fruit first (a pattern, a click or a rubber band)")
    gm, _ = damaged_fruit(ex, ex.fruit_region["leaf"])
    return gm, highlight(surface(gm), region_mask(gm, ex.fruit_region["region"]))


def png_bytes(ex: Explorer, size: tuple[int, int] = (420, 420)) -> bytes:
    """An off-screen PNG of the selected fruit with its region highlighted."""
    from ramure.app.fruit_defects import png_of_surface

    _, skin = shown(ex)
    return png_of_surface(skin, size)


#: Options that say where a defect is; placing it in a region replaces them.
PLACE_OPTIONS = ("at", "vertex", "sector", "rings", "path", "count")


def centre_cell(gm: GMap3, region: Mapping[str, Any]) -> tuple[int, int]:
    """The region's skin cell nearest the middle of its skin (``(ring, sector)``)."""
    from ramure.gmap.organs.regions import region_volumes, skin_cells

    vols = region_volumes(gm, region)
    vd = gm.volume_data
    keys = {(int(vd["ring"][v]), int(vd["sector"][v])) for v in vols if vd["sector"][v] >= 0}
    centres, cells, _ = skin_cells(gm)
    mine = np.array([(int(r), int(s)) in keys for r, s in cells], bool)
    if not mine.any():
        raise ValueRefused("the region has no skin: a defect is placed on the skin (select skin cells)")
    at = centres[mine]
    best = int(np.argmin(np.linalg.norm(at - at.mean(axis=0), axis=1)))
    r, s = cells[mine][best]
    return int(r), int(s)


def defect_here(gm: GMap3, region: Mapping[str, Any], spec: str) -> str:
    """Defect ``spec`` (``"hail:depth_mm=2"``, options as the Defects list takes them) placed in
    the region: hail and rot at its centre cell (``at=ringR/sectorS``), a crack along the
    centre sector over the region's rings, an excrescence on the region's pattern (or its
    centre cell).  The place options the spec had are replaced (so moving a defect is placing
    it again).  Shrinkage is the whole fruit's and is refused.

    >>> from ramure.gmap.organs.fruit import build_fruit
    >>> defect_here(build_fruit("round_tomato"), {"cells": [[4, 2], [5, 2], [6, 2]]}, "crack:depth=1")
    'crack:depth=1,sector=2,rings=4-6'
    """
    kind, _, rest = str(spec).partition(":")
    kind = kind.strip().lower()
    kept = [x.strip() for x in _split(rest) if x.strip() and x.split("=")[0].strip() not in PLACE_OPTIONS]
    r, s = centre_cell(gm, region)
    if kind in ("hail", "rot"):
        place = [f"at=ring{r}/sector{s}"]
    elif kind == "crack":
        vd = gm.volume_data
        from ramure.gmap.organs.regions import region_volumes

        vols = region_volumes(gm, region)
        rings = vd["ring"][vols][vd["sector"][vols] == s]
        place = [f"sector={s}", f"rings={int(rings.min())}-{int(rings.max())}"]
    elif kind == "excrescence":
        place = [f"path={region['path']}" if "path" in region else f"path=({r}, C{s + 1}, *)"]
    else:
        raise ValueRefused(f"a {kind or 'defect'} is not placed in a region (shrinkage is the whole fruit's)")
    return f"{kind}:{','.join(kept + place)}"


def _split(text: str) -> list[str]:
    """Options split on the commas outside parentheses (a path holds commas).

    >>> _split("path=(3, C1, *),height_mm=2")
    ['path=(3, C1, *)', 'height_mm=2']
    """
    items, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            items.append(text[start:i])
            start = i + 1
    items.append(text[start:])
    return items
