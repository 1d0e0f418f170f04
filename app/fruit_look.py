"""How a volumetric fruit looks: species colours, damage marks, stem and calyx, smooth shading,
pictures at a physical scale (no Qt; pyvista off-screen).

Every picture of a fruit goes through :func:`render_png`: the CLI's ``ramure fruit -o x.png``,
the defects panel and the gallery.  Choices:

* **Colours** come from :func:`ramure.gmap.organs.species.cell_rgb`: the species and ripeness
  stored in ``gm.meta`` by :func:`ramure.gmap.organs.fruit.build_fruit` (a map without them is
  a red tomato), the damage marks the defects write (corky healed walls, wet fresh wounds,
  bruises under hail pits, rot browning, water-soaking and mould).  Hail pits and rot lesions
  are drawn round on a locally subdivided skin (:mod:`ramure.app.fruit_marks`), not as the
  square skin faces of their cells; a cut picture keeps them per cell.
* **Stem and calyx** are surface decorations (:func:`stem_and_calyx`), not cells: a stalk along
  the axis at the stem scar, and for tomatoes five sepals laid on the shoulder (each sepal point
  is dropped onto the skin by a ray, so they follow any shape).  Sizes in millimetres per
  species (:data:`STEMS`); colour per species
  (:func:`ramure.gmap.organs.species.stem_colour`: green for tomatoes and cherries).
* **Smooth shading** with sharp edges split (a cut face stays flat), a little specular gloss,
  none to speak of on a plum (:data:`GLOSS`): its skin is "practically covered with bloom"
  (UNECE FFV-29 asks that of Extra plums, "according to the variety"), a matte waxy dust.
* **Physical scale.**  The camera is orthographic and its frame is fixed by the fruit's real
  size (``gm.meta["size_mm"]`` times :data:`FRAME_MARGIN`), never refitted to what is left:
  a shrivelled fruit is smaller in the picture than the fresh one.  The PNG carries text
  chunks ``ramure:mm_per_pixel``, ``ramure:species`` and ``ramure:ripeness``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pyvista as pv
    from ramure.gmap.kernel.map3 import GMap3

#: The picture's frame is the fruit's real size times this.
FRAME_MARGIN = 1.35
#: Stem (length mm, radius mm, bend) and number of sepals by species (0: no calyx drawn).
STEMS = {
    "tomato": (9.0, 1.6, 0.2, 5),
    "pear": (32.0, 1.5, 0.35, 0),
    "apple": (18.0, 1.4, 0.25, 0),
    "banana": (22.0, 5.0, 0.15, 0),
    "plum": (9.0, 0.9, 0.2, 0),
    "cherry": (38.0, 0.8, 0.4, 0),
}


#: Specular strength of the skin by species (others: ``"default"``); a plum's bloom is matte.
GLOSS = {"default": 0.3, "plum": 0.05}


def species_of(gm: GMap3) -> tuple[str, str]:
    """``(species, ripeness)`` of a fruit from its provenance (a red tomato when it has none)."""
    from ramure.gmap.organs.species import check_stage

    species = str(gm.meta.get("species", "tomato"))
    return species, check_stage(species, gm.meta.get("ripeness"))


def coloured_grid(gm: GMap3, stage: str | None = None, seed: int = 0, round_marks: bool = False) -> pv.UnstructuredGrid:
    """The fruit's cells as an UnstructuredGrid with cell data ``rgb`` (species colours and damage)
    and field data ``materials`` (JSON: one material per tissue, see
    :func:`ramure.gmap.organs.species.materials`), ``species``, ``ripeness`` and ``mm_per_unit``.

    ``round_marks``: also ``rgb_plain``, the colours without the hail and rot marks (scar,
    bruise, rot) nor a crack's, when the fruit has any, for
    :func:`ramure.app.fruit_marks.draw_round_marks` to paint them round."""
    from ramure.gmap.kernel.pyvista import to_unstructured_grid
    from ramure.gmap.organs.species import CODES, MARKS, cell_rgb, check_stage, materials

    species, ripe = species_of(gm)
    stage = check_stage(species, stage or ripe)
    grid = to_unstructured_grid(gm)
    marks = {k: np.asarray(grid.cell_data[k]) for k in MARKS if k in grid.cell_data}
    centres = grid.cell_centers().points
    tissue = np.asarray(grid.cell_data["tissue"])
    grid.cell_data["rgb"] = cell_rgb(tissue, species, stage, centres, marks, seed)
    if "corky" in marks or "wound" in marks:  # crack walls: coloured_surface keeps the mark on the walls only
        plain = {k: v for k, v in marks.items() if k not in ("corky", "wound")}
        grid.cell_data["rgb_skin"] = cell_rgb(tissue, species, stage, centres, plain, seed)
    if round_marks and any(k in marks for k in ("scar", "bruise", "rot")):
        plain = {k: v for k, v in marks.items() if k not in ("corky", "wound", "scar", "bruise", "rot")}
        grid.cell_data["rgb_plain"] = cell_rgb(tissue, species, stage, centres, plain, seed)
    whole = tissue == CODES["pericarp"]
    if whole.any():  # a fruit not subdivided: skin outside, flesh on a cut (cut_in_flesh)
        inner = np.where(whole, CODES["mesocarp"], tissue)
        grid.cell_data["rgb_cut"] = cell_rgb(inner, species, stage, centres, marks, seed)
    grid.field_data["materials"] = np.array([json.dumps(materials(species, stage))])
    grid.field_data["species"] = np.array([species])
    grid.field_data["ripeness"] = np.array([stage])
    grid.field_data["mm_per_unit"] = np.array([float(gm.meta.get("mm_per_unit", 0.0) or 0.0)])
    return grid


def coloured_surface(grid: pv.UnstructuredGrid) -> pv.PolyData:
    """The grid's outer faces with cell data ``rgb``; a crack's marks (corky, wound) stay on its
    walls (faces turned more than about 45 degrees from the outward direction), while the skin
    faces of the same cells keep the skin colour: a healed crack is a narrow corky line, not a
    band two cells wide."""
    surface = grid.extract_surface(algorithm="dataset_surface")
    if "rgb_skin" not in surface.cell_data or surface.n_cells == 0:
        return surface
    normals = surface.compute_normals(cell_normals=True, point_normals=False, auto_orient_normals=True)
    n = np.asarray(normals.cell_data["Normals"], float)
    centres = np.asarray(surface.cell_centers().points, float)
    out = centres - np.asarray(grid.center, float)
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    skin_face = np.abs(np.einsum("ij,ij->i", n, out)) > 0.7
    rgb = np.asarray(surface.cell_data["rgb"]).copy()
    rgb[skin_face] = np.asarray(surface.cell_data["rgb_skin"])[skin_face]
    surface.cell_data["rgb"] = rgb
    return surface


def cut_in_flesh(surface: pv.PolyData, normal: Any, origin: Any) -> pv.PolyData:
    """Colour the faces a plane cut made (on the plane, facing along its normal) with ``rgb_cut``
    where the grid had it: a fruit that is not subdivided is one pericarp tissue, skin-coloured,
    and its cut shows the flesh."""
    if "rgb_cut" not in surface.cell_data or surface.n_cells == 0:
        return surface
    n = np.asarray(normal, float) / max(float(np.linalg.norm(normal)), 1e-12)
    centres = np.asarray(surface.cell_centers().points, float)
    b = np.asarray(surface.bounds, float).reshape(3, 2)
    tol = 1e-6 * max(float(np.max(b[:, 1] - b[:, 0])), 1e-12)
    on_plane = np.abs((centres - np.asarray(origin, float)) @ n) < tol
    rgb = np.asarray(surface.cell_data["rgb"]).copy()
    rgb[on_plane] = np.asarray(surface.cell_data["rgb_cut"])[on_plane]
    surface.cell_data["rgb"] = rgb
    return surface


def stem_point(gm: GMap3) -> tuple[np.ndarray, np.ndarray]:
    """The stem scar's centre and the outward axis direction there (unit)."""
    vd = gm.volume_data
    trunk = vd["order"] == 0
    last = trunk & (vd["ring"] == vd["ring"][trunk].max())
    free = gm.alpha[3] == np.arange(gm.n_darts)
    darts = free & last[gm.dart_volume]
    if not darts.any():  # no free face on the trunk (should not happen): the top of the bounds
        _, pos = gm.vertex_positions()
        top = pos[np.argmax(pos[:, 2])]
        return top, np.array([0.0, 0.0, 1.0])
    point = gm.points[darts].mean(axis=0)
    inner = gm.points[last[gm.dart_volume]].mean(axis=0)
    direction = point - inner
    norm = np.linalg.norm(direction)
    return point, (direction / norm if norm > 0 else np.array([0.0, 0.0, 1.0]))


def stem_and_calyx(gm: GMap3, skin: pv.PolyData | None = None) -> pv.PolyData:
    """Stem (a bent tube) and, for tomatoes, a calyx of sepals on the skin; cell data ``rgb``."""
    import pyvista as pv

    from ramure.gmap.organs.species import CALYX, hex_rgb, stem_colour

    species, _ = species_of(gm)
    length, radius, bend, sepals = STEMS.get(species, STEMS["tomato"])
    if species == "tomato":  # a cherry tomato's stalk is finer than a beefsteak's
        scale = min(1.0, float(gm.meta.get("size_mm", 65.0)) / 65.0) ** 0.6
        length, radius = length * scale, radius * scale
    mpu = float(gm.meta.get("mm_per_unit", 0.0) or 0.0) or 1.0
    base, axis = stem_point(gm)
    side = np.cross(axis, [1.0, 0.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.cross(axis, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    t = np.linspace(0.0, 1.0, 12)
    path = base + (length / mpu) * (t[:, None] * axis + bend * t[:, None] ** 2 * side) - 0.15 * (length / mpu) * axis
    stem = pv.Spline(path, 24).tube(radius=radius / mpu, n_sides=12, capping=True).triangulate()
    stem.cell_data["rgb"] = np.tile(np.array(hex_rgb(stem_colour(species)), np.uint8), (stem.n_cells, 1))
    parts = [stem]
    if sepals and skin is not None:
        parts.append(_calyx(skin, base, axis, side, sepals, 0.28 * float(gm.meta.get("size_mm", 65.0)) / mpu, hex_rgb(CALYX)))
    return pv.merge(parts, merge_points=False) if len(parts) > 1 else parts[0]


def _calyx(skin, base, axis, side, count, reach, colour):
    """``count`` pointed sepals from the stem scar outward, each point dropped onto the skin."""
    import pyvista as pv

    other = np.cross(axis, side)
    centre = np.asarray(skin.center)
    points: list[np.ndarray] = []
    faces: list[int] = []
    for k in range(count):
        a = 2 * np.pi * (k + 0.3) / count
        out = np.cos(a) * side + np.sin(a) * other
        across = np.cross(axis, out)
        ring = []
        for s in np.linspace(0.0, 1.0, 7):
            half = 0.12 * reach * np.sin(np.pi * min(s * 1.15, 1.0)) * (1 - s) ** 0.3
            for w in (-half, half):
                guess = base + s * reach * out + w * across
                hit = _onto_skin(skin, guess, centre)
                ring.append(hit + 0.02 * reach * (hit - centre) / max(np.linalg.norm(hit - centre), 1e-12))
        start = len(points)
        points += ring
        for i in range(6):
            a0, b0, a1, b1 = start + 2 * i, start + 2 * i + 1, start + 2 * i + 2, start + 2 * i + 3
            faces += [3, a0, b0, b1, 3, a0, b1, a1]
    mesh = pv.PolyData(np.array(points), np.array(faces))
    mesh.cell_data["rgb"] = np.tile(np.array(colour, np.uint8), (mesh.n_cells, 1))
    return mesh


def _onto_skin(skin, point, centre):
    """The skin point on the ray from far outside ``point`` towards the fruit's centre."""
    direction = point - centre
    norm = np.linalg.norm(direction)
    if norm == 0:
        return point
    far = centre + direction / norm * (2.0 * skin.length)
    hits, _ = skin.ray_trace(far, centre, first_point=True)
    return np.asarray(hits, float).reshape(3) if len(hits) else point


def legend_entries(grid: pv.DataSet) -> list[tuple[str, str]]:
    """(name, hex colour) for each tissue present, named as the species names it."""
    from ramure.gmap.kernel.storage import TISSUES
    from ramure.gmap.organs.species import palette, shown_name

    species = str(grid.field_data["species"][0]) if "species" in grid.field_data else "tomato"
    stage = str(grid.field_data["ripeness"][0]) if "ripeness" in grid.field_data else None
    colours = palette(species, stage)
    seen: dict[str, str] = {}
    for code in np.unique(np.asarray(grid.cell_data["tissue"])):
        name = TISSUES[int(code)]
        seen.setdefault(shown_name(species, name), colours[name])
    return list(seen.items())


def render_png(
    gm: GMap3,
    path: str | os.PathLike,
    size: tuple[int, int] = (800, 800),
    cut: tuple[Any, Any] | None = None,
    view: str | tuple[float, float, float] = "side",
    title: str | None = None,
    legend: bool = True,
    stage: str | None = None,
    frame_mm: float | None = None,
    decorations: bool = True,
    light: str = "front",
) -> dict[str, Any]:
    """Render a fruit map to a PNG at a physical scale; returns the picture's metadata.

    ``cut`` = ``(normal, origin)`` keeps what lies behind that plane (cells clipped flat).
    ``view``: ``"side"`` (from the side, a little above), ``"top"`` (down the axis onto the stem
    scar), ``"bottom"``, ``"defect"`` (facing the damaged cells, :func:`defect_direction`) or a
    direction.  ``frame_mm``: the frame's width in millimetres (default
    the fruit's real size times :data:`FRAME_MARGIN`).  ``light``: ``"front"`` (pyvista's light
    kit, soft and from about the camera) or ``"raking"`` (:func:`raking_lights`: a low light from
    the side, so shallow relief such as shrivel wrinkles casts shading).  Metadata: ``mm_per_pixel``, ``species``,
    ``ripeness``, written into the PNG as text chunks too.
    """
    from ramure.app.render import headless_setup
    from ramure.gmap.kernel.cut import plane_cut

    if light not in ("front", "raking"):
        from ramure.errors import ValueRefused

        raise ValueRefused(f"light must be front or raking, got {light!r}")
    headless_setup()
    import pyvista as pv

    grid = coloured_grid(gm, stage, round_marks=cut is None)
    species, ripe = str(grid.field_data["species"][0]), str(grid.field_data["ripeness"][0])
    mpu = float(gm.meta.get("mm_per_unit", 0.0) or 0.0)
    real = float(gm.meta.get("size_mm", 65.0))
    if mpu <= 0:  # no provenance: frame the fruit as it is
        b = np.asarray(grid.bounds, float).reshape(3, 2)
        mpu = real / max(float(np.max(b[:, 1] - b[:, 0])), 1e-12)
    frame = (frame_mm or real * FRAME_MARGIN) / mpu
    whole = grid.extract_surface(algorithm="dataset_surface")
    shown = grid if cut is None else plane_cut(grid, normal=cut[0], origin=cut[1], mode="clip")
    surface = coloured_surface(shown)
    if cut is not None:
        surface = cut_in_flesh(surface, cut[0], cut[1])
    else:  # hail pits and rot lesions round, not the square skin faces of their cells (a cut keeps them per cell)
        from ramure.app.fruit_marks import draw_round_marks

        surface = draw_round_marks(surface, np.asarray(grid.center, float), pixel=frame / size[1])
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    try:
        plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        plotter.add_mesh(
            surface,
            scalars="rgb",
            rgb=True,
            smooth_shading=True,
            split_sharp_edges=cut is not None,  # a cut face stays flat; the skin is smooth everywhere
            ambient=0.4 if cut is not None else 0.28,
            diffuse=0.65 if cut is not None else 0.8,
            specular=GLOSS.get(species, GLOSS["default"]),
            specular_power=18,
        )
        if decorations:
            extra = stem_and_calyx(gm, whole)
            if cut is not None:
                extra = extra.clip(normal=tuple(np.asarray(cut[0], float)), origin=tuple(cut[1]), invert=True)
            if extra.n_cells:
                plotter.add_mesh(extra, scalars="rgb", rgb=True, smooth_shading=True, specular=0.2)
        if legend:
            entries = legend_entries(shown)
            if cut is None:  # the outside is skin only
                entries = [e for e in entries if e[0] in ("skin", "peel")] or entries[:1]
            _legend(plotter, entries, size)
        centre = np.asarray(whole.center, float)
        look = _direction(defect_direction(whole_marked(grid), centre) if view == "defect" else view, cut)
        up = (0.0, 0.0, 1.0) if abs(look[2]) < 0.9 else (0.0, 1.0, 0.0)
        plotter.camera_position = [tuple(centre + look * frame * 4.0), tuple(centre), up]
        if light == "raking":
            plotter.remove_all_lights()
            for lamp in raking_lights(look, up):
                plotter.add_light(lamp)
        plotter.enable_parallel_projection()  # type: ignore[call-arg]  # pyvista stubs: decorated method
        plotter.camera.parallel_scale = 0.5 * frame
        plotter.camera.clipping_range = (frame * 0.5, frame * 8.0)
        if title:
            plotter.add_text(title, font_size=11, color="black")
        image = np.asarray(plotter.screenshot(return_img=True))
    finally:
        plotter.close()
    meta = {"mm_per_pixel": frame * mpu / size[1], "species": species, "ripeness": ripe, "size_mm": real}
    _write_png(path, image, meta)
    return meta


#: Raking light: its angle from the line of sight (degrees; 90 grazes the skin facing the
#: camera) and the strength of the frontal fill that keeps the shadowed side readable.
RAKING_ANGLE = 80.0
RAKING_FILL = 0.2


def raking_lights(look: Any, up: Any) -> list[pv.Light]:
    """A low light from the picture's left, :data:`RAKING_ANGLE` degrees off the line of sight
    (``look``, from the fruit towards the camera), plus a weak frontal fill
    (:data:`RAKING_FILL`).  Both are camera-independent directional lights: a crease facing the
    lamp is lit, the one behind it is in shade, as a grower tilts a fruit to the window."""
    import pyvista as pv

    look = np.asarray(look, float) / np.linalg.norm(look)
    up = np.asarray(up, float)
    left = np.cross(look, up)  # the picture's left as seen from the camera
    left /= max(float(np.linalg.norm(left)), 1e-12)
    a = np.radians(RAKING_ANGLE)
    towards = np.cos(a) * look + np.sin(a) * (left)
    lamp = pv.Light(position=tuple(towards), focal_point=(0.0, 0.0, 0.0), intensity=1.0 - RAKING_FILL * 0.5)
    fill = pv.Light(position=tuple(look), focal_point=(0.0, 0.0, 0.0), intensity=RAKING_FILL)
    for light in (lamp, fill):
        light.positional = False
    return [lamp, fill]


def _legend(plotter, entries, size):
    """Tissue names in black beside a square of their colour, bottom right, inside the picture."""
    font = max(8, int(size[1] / 50))
    line = int(font * 1.9)
    width = max(len(name) for name, _ in entries) * int(font * 0.95) + 3 * font
    x0 = size[0] - width - font
    for i, (name, colour) in enumerate(reversed(entries)):
        y = font + i * line
        swatch = plotter.add_text("  ", position=(x0, y), font_size=font, color=colour)
        prop = swatch.GetTextProperty()
        prop.SetBackgroundColor(*(int(colour[i : i + 2], 16) / 255.0 for i in (1, 3, 5)))
        prop.SetBackgroundOpacity(1.0)
        plotter.add_text(name, position=(x0 + int(1.8 * font), y), font_size=font, color="black")


def whole_marked(grid: pv.UnstructuredGrid) -> pv.PolyData:
    """The grid's outer faces with their cells' data (marks included): what a camera sees."""
    return grid.extract_surface(algorithm="dataset_surface")


def defect_direction(grid: pv.DataSet, centre: np.ndarray) -> tuple[float, float, float]:
    """From the fruit's centre towards its marked cells (corky, wound, scar, bruise, rot; pass the
    outer surface so inner cells do not pull), tipped up a little; the side view when nothing
    is marked."""
    from ramure.gmap.organs.species import MARKS

    weight = np.zeros(grid.n_cells)
    for name in MARKS[:5]:
        if name in grid.cell_data:
            weight = np.maximum(weight, np.asarray(grid.cell_data[name], float))
    if "excrescence" in grid.cell_data:
        weight = np.maximum(weight, (np.asarray(grid.cell_data["excrescence"]) > 0).astype(float))
    if not weight.any():
        return (0.55, -0.75, 0.35)
    pts = grid.cell_centers().points
    d = (pts * weight[:, None]).sum(axis=0) / weight.sum() - centre
    d = d / max(np.linalg.norm(d), 1e-12)
    return (float(d[0]), float(d[1]), float(d[2] + 0.25))


def _direction(view, cut):
    if cut is not None and view == "side":  # face the cut, turned a little to show depth
        n = np.asarray(cut[0], float)
        n = n / np.linalg.norm(n)
        side = np.cross(n, [0.0, 0.0, 1.0])
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-6 else np.array([0.0, -1.0, 0.0])
        look = n + 0.35 * side + 0.25 * np.array([0.0, 0.0, 1.0])
    elif isinstance(view, str):
        table = {"side": (0.55, -0.75, 0.35), "top": (0.05, -0.1, 1.0), "bottom": (0.05, -0.1, -1.0)}
        if view not in table:
            from ramure.errors import ValueRefused

            raise ValueRefused(f"view must be side, top, bottom or a direction, got {view!r}")
        look = np.array(table[view])
    else:
        look = np.asarray(view, float)
    return look / np.linalg.norm(look)


def _write_png(path, image: np.ndarray, meta: Mapping[str, Any]) -> None:
    """The picture with ``ramure:*`` text chunks (Pillow)."""
    from PIL import Image, PngImagePlugin

    info = PngImagePlugin.PngInfo()
    for key, value in meta.items():
        info.add_text(f"ramure:{key}", str(value))
    Image.fromarray(np.asarray(image, np.uint8)).save(os.fspath(path), format="PNG", pnginfo=info)


def read_png_meta(path: str | os.PathLike) -> dict[str, str]:
    """The ``ramure:*`` text chunks of a PNG written by :func:`render_png`."""
    from PIL import Image

    with Image.open(os.fspath(path)) as im:
        text = dict(getattr(im, "text", {}))
    return {k.split(":", 1)[1]: v for k, v in text.items() if k.startswith("ramure:")}
