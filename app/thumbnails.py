"""Off-screen thumbnails of variants (the 27 picks) and one contact-sheet PNG.

Each thumbnail is rendered (tubes, plus every segment as a one-pixel line
so branches thinner than a pixel still show) with the camera framed on that
plant's own bounds (:func:`ramure.app.render.frame_camera`), so every plant fills its tile; the
tile's caption gives the pick id and the plant's height so sizes stay
comparable.  The tiles are drawn side by side in one off-screen window (a viewport each)
and rendered once: 27 renders of a small window cost about four times one render of all.

The contact sheet lays the 27 tiles out in three rows of nine — row k holds
ids 9k+1..9k+9, i.e. one PC1 slab per row (ids put PC1 slowest) — with each
id written on its tile.

>>> from ramure.metrics import explore
>>> import tempfile, pathlib
>>> exp = explore("grammars/honda_sympodial.lsys", n=3, n_jobs=1, cache=False)
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> images = render_picks(exp, out, size=(64, 64))
>>> images[0], contact_sheet([out / p for p in images], range(1, 28), out / "sheet.png").exists()
('thumbs/pick_01.png', True)
"""

from __future__ import annotations

import os
import pathlib
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ramure.app.render import BARK, headless_setup, frame_camera, plant_colors
from ramure.io import write_with

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton
    from ramure.metrics.exploration import Exploration
    from ramure.metrics.sweep import VariantSweep

THUMB_DIR = "thumbs"


def _segment_lines(sk):
    """Segments as 1-pixel lines, so branches thinner than a pixel still show."""
    import pyvista as pv

    s = len(sk)
    points = np.concatenate([sk.start, sk.end])
    lines = np.column_stack([np.full(s, 2), np.arange(s), np.arange(s) + s]).ravel()
    return pv.PolyData(points, lines=lines)


def _grid_shape(count: int, size: tuple[int, int], columns: int = 9, max_side: int = 4096) -> tuple[int, int]:
    """Columns and rows of one off-screen window holding up to ``count`` tiles of ``size``,
    the window at most ``max_side`` pixels a side (below every OpenGL's framebuffer limit)."""
    cols = max(1, min(columns, count, max_side // max(size[0], 1)))
    rows = max(1, min(-(-count // cols), max_side // max(size[1], 1)))
    return cols, rows


def _draw_tile(plotter, sk, view: str, zoom: float, bounds=None, bar=None) -> None:
    """One plant in the current viewport, framed on its own bounds, or on ``bounds`` (one camera
    for a whole set) with a vertical scale bar ``bar`` long at their left."""
    mesh = sk.to_polydata(sides=6)
    if mesh.n_cells:
        mesh.cell_data["rgb"] = plant_colors(mesh)
        plotter.add_mesh(mesh, scalars="rgb", rgb=True, smooth_shading=False)
        plotter.add_mesh(_segment_lines(sk), color=BARK, line_width=1.0)
        if bounds is None:
            frame_camera(plotter, mesh.bounds, view)
            plotter.camera.zoom(zoom)
    if bounds is not None:
        frame_camera(plotter, bounds, view)
        plotter.camera.zoom(1.35)  # reset_camera fits the bounds' sphere: a wide margin
        if bar:
            plotter.add_mesh(_scale_bar(bounds, bar), color="black", line_width=5.0)


def _render_grid(skeletons, size, view: str, zoom: float, cols: int, bounds=None, bar=None) -> list[np.ndarray]:
    """Render skeletons side by side in one window (one viewport each, one render in all) and
    cut the picture into one RGB tile per skeleton."""
    import pyvista as pv

    rows = -(-len(skeletons) // cols)
    w, h = size
    plotter = pv.Plotter(off_screen=True, shape=(rows, cols), window_size=[w * cols, h * rows], border=False)
    try:
        plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        for k, sk in enumerate(skeletons):
            plotter.subplot(k // cols, k % cols)
            _draw_tile(plotter, sk, view, zoom, bounds, bar)
        image = np.asarray(plotter.screenshot(return_img=True))
    finally:
        plotter.close()
    return [image[(k // cols) * h : (k // cols + 1) * h, (k % cols) * w : (k % cols + 1) * w] for k in range(len(skeletons))]


def _save_tile(tile: np.ndarray, path, caption: str | None) -> None:
    from PIL import Image, ImageDraw, ImageFont

    picture = Image.fromarray(np.ascontiguousarray(tile))
    if caption:
        font = ImageFont.load_default(size=max(10, picture.height // 16))
        draw = ImageDraw.Draw(picture)
        left, top, right, bottom = draw.textbbox((0, 0), caption, font=font)
        draw.text((4, picture.height - 4 - (bottom - top) - top), caption, fill="black", font=font)
    write_with(path, lambda tmp: picture.save(tmp, format="PNG"))


def _render_many(
    skeletons, paths, size=(256, 256), view: str = "front", captions=None, zoom: float = 1.15, bounds=None, bar=None
):
    """Render skeletons to PNG files, as many as fit in one off-screen window per render
    (a render costs about the same for one tile as for 27: the tiles share it); framed on
    ``bounds`` when given (one camera for all, with a scale bar ``bar`` long), else each plant
    on its own bounds."""
    headless_setup()
    skeletons, paths = list(skeletons), list(paths)
    cols, rows = _grid_shape(len(skeletons), size)
    for start in range(0, len(skeletons), cols * rows):
        chunk = skeletons[start : start + cols * rows]
        for k, tile in enumerate(_render_grid(chunk, size, view, zoom, cols, bounds, bar), start):
            _save_tile(tile, paths[k], None if captions is None else captions[k])
    return paths


def _scale_bar(bounds, length):
    """A vertical segment ``length`` long standing on the ground at the left of ``bounds``."""
    import pyvista as pv

    b = np.asarray(bounds, float)
    x = b[0] + 0.08 * (b[1] - b[0])  # inside the room shared_bounds made on the left
    y = 0.5 * (b[2] + b[3])
    return pv.Line((x, y, b[4]), (x, y, b[4] + float(length)))


def render_framed(
    skeletons: Sequence[Skeleton],
    paths: Sequence[str | os.PathLike],
    size: tuple[int, int] = (480, 480),
    bounds: Sequence[float] | None = None,
    bar: float | None = None,
    view: str = "front",
) -> list[str | os.PathLike]:
    """Render ``skeletons`` to ``paths`` with one off-screen plotter: every plant framed on the same
    ``bounds`` with a scale bar ``bar`` long (one scale for a study's set), or, with ``bounds``
    None, each on its own bounds."""
    return _render_many(skeletons, list(paths), size, view, bounds=bounds, bar=bar)


def render_variants(
    sweep: VariantSweep,
    variants: Iterable[int],
    paths: Iterable[str | os.PathLike],
    size: tuple[int, int] = (256, 256),
    view: str = "front",
    captions: Sequence[str] | None = None,
) -> list[str | os.PathLike]:
    """Derive variants ``variants`` of a fitted sweep and render each to ``paths``."""
    skeletons = (sweep.derive(int(v)).skeleton() for v in variants)
    return _render_many(skeletons, list(paths), size, view, captions)


def render_picks(
    exploration: Exploration, directory: str | os.PathLike, size: tuple[int, int] = (256, 256), view: str = "front"
) -> list[str]:
    """Render the 27 picks to ``directory/thumbs/pick_XX.png``; returns the paths relative
    to ``directory`` (what ``picks.json`` records)."""
    directory = pathlib.Path(directory)
    (directory / THUMB_DIR).mkdir(parents=True, exist_ok=True)
    rel = [f"{THUMB_DIR}/pick_{i:02d}.png" for i in range(1, 28)]
    sweep = exploration.sweep
    skeletons = [sweep.derive(int(v)).skeleton() for v in exploration.picks.variant]
    # no caption: these images are what study participants sort, and a metric written on
    # them ("h 5.42") would bias the grouping
    _render_many(skeletons, [directory / p for p in rel], size, view)
    return rel


def contact_sheet(
    images: Sequence[str | os.PathLike],
    labels: Sequence[object],
    path: str | os.PathLike,
    columns: int = 9,
    title: str | None = None,
    pad: int = 6,
) -> pathlib.Path:
    """Tile ``images`` (paths) in a grid with ``labels`` written on them; write a PNG to ``path``."""
    from PIL import Image, ImageDraw, ImageFont

    pictures = [Image.open(p).convert("RGB") for p in images]
    texts = [str(x) for x in labels]
    if not pictures:
        raise ValueError("no image to put on the contact sheet")
    w, h = pictures[0].size
    rows = -(-len(pictures) // columns)
    head = 28 if title else 0
    sheet = Image.new("RGB", (columns * (w + pad) + pad, head + rows * (h + pad) + pad), "white")
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=max(12, h // 10))
    if title:
        draw.text((pad, 4), title, fill="black", font=ImageFont.load_default(size=18))
    for k, (img, label) in enumerate(zip(pictures, texts)):
        x = pad + (k % columns) * (w + pad)
        y = head + pad + (k // columns) * (h + pad)
        sheet.paste(img.resize((w, h)), (x, y))
        draw.rectangle([x, y, x + w - 1, y + h - 1], outline=(190, 190, 190))
        box = draw.textbbox((x + 4, y + 2), label, font=font)
        draw.rectangle(box, fill="white")
        draw.text((x + 4, y + 2), label, fill=(180, 0, 0), font=font)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_with(path, lambda tmp: sheet.save(tmp, format="PNG"))
    return path
