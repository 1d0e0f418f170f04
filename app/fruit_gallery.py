"""Contact sheets of fruit for the gallery and for looking: each species at its ripeness stages,
and each defect class at a better and a worse UNECE class side by side (no Qt).

The grades under the defect pictures are computed (:func:`ramure.gmap.organs.grading.grade_unece`),
not written by hand: a pair whose better picture is not graded above the worse one shows it.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from typing import Any

#: Defect pairs: (title, preset, volume levels, better spec, worse spec).  Tomatoes tolerate no
#: crack in Class I (FFV-36), so the tomato crack pair is Class II against out of grade.
#: Shrivel: 2.1 % and 4.2 % of the volume lost (Class I up to 3 %, Class II up to 5 %,
#: :mod:`ramure.gmap.organs.grading`), creased nine times the shrink defect's default
#: (``wrinkle=9``: 0.42 and 0.84 mm deep on a 75 mm apple; the default's 0.05 and 0.09 mm do
#: not show) in 6 mm waves (fine shrivel, still 2.4 skin faces a wave when twice subdivided;
#: the default, a seventh of the fruit, reads as dents), under a raking light (:data:`RAKING`).
DEFECT_PAIRS: list[tuple[str, str, int, str, str]] = [
    ("healed crack (apple)", "apple", 1, "crack:healed=1,rings=8-9,sector=2", "crack:healed=1,rings=7-10,sector=2"),
    (
        "stem-scar crack (tomato)",
        "round_tomato",
        1,
        "crack:kind=transverse,healed=1,rings=7-8,width_mm=2",
        "crack:kind=concentric",
    ),
    ("hail (tomato)", "round_tomato", 2, "hail:count=1,depth_mm=0.8,healed=1,vertex=-1", "hail:count=3,depth_mm=1.8,healed=1"),
    ("shrivel (apple)", "apple", 2, "shrink:rate=0.0025,wrinkle=9,wave_mm=6", "shrink:rate=0.005,wrinkle=9,wave_mm=6"),
    (
        "excrescence (tomato)",
        "round_tomato",
        1,
        "excrescence:path=(6,C3,*),height_mm=1.5,taper=0.8",
        "excrescence:path=(6,C3,*),segments=3,taper=0.8",
    ),
    ("rot (pear)", "pear", 1, "rot:at=ring8/sector3,coefficients=2.5", "rot:at=ring8/sector3"),
]


#: Defect kinds the sheet draws under a raking light (:func:`ramure.app.fruit_look.raking_lights`):
#: shallow relief (shrivel creases) that a frontal light flattens.
RAKING = ("shrink",)


def sheet_light(spec: str) -> str:
    """The light the defect sheet draws ``spec`` under: ``"raking"`` for :data:`RAKING` kinds."""
    return "raking" if spec.split(":", 1)[0].strip() in RAKING else "front"


#: Presets whose skin pattern is finer than a once-subdivided cell: a ripe banana's sugar spots
#: are a few millimetres across, its once-subdivided peel faces about 9.5 mm (4.7 mm twice), so
#: a fleck one face wide read as a black patch; the sheets draw these presets twice subdivided.
FINE_SKIN = ("banana",)


def sheet_levels(preset: str, levels: int) -> int:
    """The volume levels a sheet draws ``preset`` at: ``levels``, at least 2 for :data:`FINE_SKIN`."""
    return max(levels, 2) if preset in FINE_SKIN else levels


def species_sheet(path: str | os.PathLike, tile: int = 300, levels: int = 1, cut: bool = False) -> str:
    """Every species at three ripeness stages (apples at their four colours), one row each
    (``levels`` volume levels, :func:`sheet_levels`)."""
    from ramure.gmap.organs.fruit import build_fruit
    from ramure.gmap.organs.species import SPECIES_OF, stages

    from ramure.app.fruit_look import render_png

    rows: list[list[tuple[str, str]]] = []
    with tempfile.TemporaryDirectory() as folder:
        for preset in ("round_tomato", "cherry_tomato", "apple", "pear", "banana", "plum", "cherry"):
            species = SPECIES_OF[preset]
            row = []
            for stage in stages(species) if species == "apple" else stages(species)[-3:]:
                gm = build_fruit(preset, volume_levels=2 if cut else sheet_levels(preset, levels), ripeness=stage)
                out = os.path.join(folder, f"{preset}_{stage}.png")
                render_png(gm, out, size=(tile, tile), cut=((1, 0.08, 0), (0, 0, 0)) if cut else None, legend=cut)
                row.append((out, f"{preset.replace('_', ' ')}, {stage}, {gm.meta['size_mm']:g} mm"))
            rows.append(row)
        return _compose(path, rows, tile)


def inside_sheet(path: str | os.PathLike, tile: int = 300) -> str:
    """Every species ripe, cut along its axis (twice subdivided: skin, flesh, core or locules,
    seeds or stone), with a legend in the species' words."""
    from ramure.gmap.organs.fruit import build_fruit

    from ramure.app.fruit_look import render_png

    presets = ("round_tomato", "apple", "pear", "banana", "plum", "cherry")
    row = []
    with tempfile.TemporaryDirectory() as folder:
        for preset in presets:
            gm = build_fruit(preset, volume_levels=2)
            out = os.path.join(folder, f"{preset}.png")
            render_png(gm, out, size=(tile, tile), cut=((1, 0.08, 0), (0, 0, 0)))
            row.append((out, f"{preset.replace('_', ' ')}, cut"))
        return _compose(path, [row[:3], row[3:]], tile)


Pair = tuple[str, str, int, str, str]


def defect_sheet(path: str | os.PathLike, tile: int = 320, pairs: Sequence[Pair] | None = None) -> list[dict[str, Any]]:
    """Each defect class at a better and a worse grade side by side; returns the grades shown."""
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit

    from ramure.app.fruit_look import render_png

    rows, shown = [], []
    with tempfile.TemporaryDirectory() as folder:
        for i, (title, preset, levels, better, worse) in enumerate(pairs or DEFECT_PAIRS):
            gm = build_fruit(preset, volume_levels=levels)
            row = []
            for j, spec in enumerate((better, worse)):
                spec = _first_site(gm, spec)
                damaged, facts = apply_defects(gm, [spec])
                grade = facts["unece"]["grade"] or "not tabulated"
                out = os.path.join(folder, f"{i}_{j}.png")
                render_png(damaged, out, size=(tile, tile), view="defect", legend=False, light=sheet_light(spec))
                row.append((out, f"{title}: {grade}"))
                shown.append({"defect": title, "spec": spec, "grade": grade, "reasons": facts["unece"]["reasons"]})
            rows.append(row)
        _compose(path, rows, tile)
    return shown


def _first_site(gm, spec):
    """``vertex=-1`` in a hail spec: the hail site nearest the fruit's equator, facing the camera."""
    if "vertex=-1" not in spec:
        return spec
    import numpy as np

    from ramure.gmap.organs.defects import hail_sites

    sites = hail_sites(gm)
    pos = gm.vertex_positions()[1][sites]
    mid = pos.mean(axis=0)
    score = np.abs(pos[:, 2] - mid[2]) - 0.2 * (pos[:, 0] - mid[0])
    return spec.replace("count=1,", "").replace("vertex=-1", f"vertex={int(sites[np.argmin(score)])}")


def _compose(path, rows, tile):
    """Paste the pictures in rows with a caption under each; write ``path`` atomically."""
    from PIL import Image, ImageDraw

    from ramure.io import write_with

    caption = 22
    cols = max(len(r) for r in rows)
    sheet = Image.new("RGB", (tile * cols, (tile + caption) * len(rows)), "white")
    draw = ImageDraw.Draw(sheet)
    for r, row in enumerate(rows):
        for c, (picture, text) in enumerate(row):
            with Image.open(picture) as im:
                sheet.paste(im.convert("RGB"), (c * tile, r * (tile + caption)))
            draw.text((c * tile + 6, r * (tile + caption) + tile + 4), text, fill=(0, 0, 0))
    write_with(path, lambda tmp: sheet.save(os.fspath(tmp), format="PNG"))
    return os.fspath(path)
