"""Defects on the selected fruit of a plant: the work behind the desktop's Defects dock and the
Jupyter Defects tab (no Qt, no widgets; each function takes a :class:`ramure.app.model.Explorer`).

A plant's fruit are coarse volumetric fruit (110 cells for a round tomato), too coarse for
layered defects (a crack opens radial layers, hail stops at a tissue), so the defects of a
fruit are recorded on it as fruit settings (``defects``: a list of specs such as
``"crack:kind=longitudinal,sector=3,rings=3-6"``; one undoable edit of the session, see
:meth:`ramure.app.model.Explorer.set_fruit_defects`) and shown on that fruit rebuilt with
:data:`LEVELS` volume subdivisions (same preset, seed and parameters; exocarp, mesocarp and
columella), in the panel's own view.  The plant's main view keeps its coarse fruit.  The
specs are checked by applying them before the edit is recorded, so a refused defect leaves
the plant and its history unchanged.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

from ramure.errors import ValueRefused

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.app.model import Explorer
    from ramure.gmap.kernel.map3 import GMap3

#: Volume subdivisions of the fruit the defects are shown on.
LEVELS = 1
#: One example spec per defect kind (placeholders in the panels).
EXAMPLES = {
    "crack": "kind=longitudinal,sector=3,rings=3-6,depth=1,width_mm=1,healed=1",
    "hail": "count=3,depth_mm=1..3",
    "shrink": "rate=0.05,steps=2",
    "rot": "rate=0.05",
    "excrescence": "path=(0),height_mm=5,segments=2",
}


def check_specs(specs: Iterable[object]) -> list[str]:
    """Parse every spec (``"kind:options"``); returns them as strings, refusing bad ones."""
    from ramure.gmap.organs.defect_specs import parse_defect

    out = []
    for spec in specs:
        text = str(spec).strip()
        parse_defect(text)
        out.append(text)
    return out


def selected_fruit(ex: Explorer) -> int:
    """The first selected fruit's leaf id; refusals name the fix."""
    fruit = ex.fruit_ids()
    if not fruit:
        raise ValueRefused("this plant has no fruit: defects apply to a fruit (try grammars/fruit_tree.lsys)")
    chosen = [leaf for leaf in ex.selection if leaf in set(fruit)]
    if not chosen:
        raise ValueRefused("select a fruit first (click one): defects apply to the selected fruit")
    return int(chosen[0])


def fruit_settings(ex: Explorer, leaf: int) -> dict:
    """Preset, seed, size, parameters and recorded defects of fruit ``leaf``."""
    meta = ex.fruit_volumes().meta["fruits"]
    spec = next(f for f in meta if f["leaf_id"] == leaf)
    defects = ex.session.fruit_overrides().get(leaf, {}).get("defects", [])
    return {
        "preset": spec["preset"],
        "seed": int(spec["seed"]),
        "size": float(spec["size"]),
        "params": dict(spec["params"]),
        "defects": list(defects),
        "regions": list(ex.session.fruit_overrides().get(leaf, {}).get("regions", [])),
    }


def damaged_fruit(
    ex: Explorer,
    leaf: int | None = None,
    specs: Iterable[object] | None = None,
    size_mm: float | None = None,
    regions: Iterable[Mapping[str, Any]] | None = None,
) -> tuple[GMap3, dict]:
    """Fruit ``leaf`` (default: the selected one) rebuilt with its ``regions`` (default: its
    recorded ones, see :mod:`ramure.app.fruit_regions`) and damaged by ``specs`` (default: its
    recorded defects); returns ``(map, facts)``.  ``size_mm`` None: the preset's real size."""
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit

    leaf = selected_fruit(ex) if leaf is None else leaf
    s = fruit_settings(ex, leaf)
    specs = s["defects"] if specs is None else check_specs(specs)
    if regions is not None:
        s["regions"] = list(regions)
    gm = build_fruit(s["preset"], seed=s["seed"], volume_levels=LEVELS, size_mm=size_mm, regions=s["regions"], **s["params"])
    gm, facts = apply_defects(gm, specs, seed=s["seed"])
    return gm, {**facts, "leaf": leaf, "specs": list(specs)}


def surface(gm: GMap3) -> pv.PolyData:
    """The damaged fruit's skin as PolyData with per-cell ``rgb``: the species' colours at its
    ripeness, healed crack walls corky brown, fresh ones wet flesh, hail scars, bruises and rot
    (:func:`ramure.app.fruit_look.coloured_surface`)."""
    from ramure.app.fruit_look import coloured_grid, coloured_surface

    return coloured_surface(coloured_grid(gm))


def facts_text(facts: Mapping[str, Any]) -> str:
    """One line: the defects, the volume lost and the grade with its reasons."""
    kinds = ", ".join(d["kind"] for d in facts["defects"]) or "no defects"
    g = facts["grade"]
    why = f" ({'; '.join(g['reasons'])})" if g["reasons"] else ""
    unece = facts.get("unece") or {}
    cls = f"; UNECE {unece['grade']}" if unece.get("grade") else ""
    return f"Fruit {facts['leaf']}: {kinds}; volume lost {100 * facts['volume_lost_fraction']:.1f} %; {g['grade']}{why}{cls}"


def png_bytes(gm: GMap3, size: tuple[int, int] = (420, 420)) -> bytes:
    """An off-screen PNG of the damaged fruit (tissue colours), seen from the side and above."""
    return png_of_surface(surface(gm), size)


def png_of_surface(skin: pv.PolyData, size: tuple[int, int] = (420, 420)) -> bytes:
    """An off-screen PNG of a fruit's coloured skin (cell data ``rgb``), seen from the side and above."""
    import os
    import tempfile

    from ramure.app.render import headless_setup

    headless_setup()
    import numpy as np
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    try:
        plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        plotter.add_mesh(skin, scalars="rgb", rgb=True, render=False, smooth_shading=True, split_sharp_edges=True)
        b = np.asarray(skin.bounds, float).reshape(3, 2)
        centre, extent = b.mean(axis=1), float(np.max(b[:, 1] - b[:, 0])) or 1.0
        look = np.array([0.55, -0.75, 0.55]) / np.linalg.norm([0.55, -0.75, 0.55])
        plotter.camera_position = [tuple(centre + look * extent * 2.5), tuple(centre), (0.0, 0.0, 1.0)]
        plotter.reset_camera(render=False, bounds=tuple(b.ravel()))  # type: ignore[call-arg]  # pyvista stubs
        fd, path = tempfile.mkstemp(suffix=".png")
        os.close(fd)
        try:
            plotter.screenshot(path)
            with open(path, "rb") as fh:
                return fh.read()
        finally:
            os.unlink(path)
    finally:
        plotter.close()
