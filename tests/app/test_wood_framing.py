"""Plank and cross-cut pictures fill their frame; the legend and the title cover no wood (issue 39 §6)."""

import numpy as np
import pytest

from ramure.gmap.organs import wood as W

LEGEND_BOX = (245, 245, 240)  # add_legend_box's bcolor (0.96, 0.96, 0.94) in 8 bits


@pytest.fixture(scope="module")
def grid():
    wood = W.grow_wood("pine", years=6, height=0.12)
    return W.smooth_grid(wood, W.to_grid(wood))


def render(tmp_path, part, normal, size, **kwargs):
    from PIL import Image

    from ramure.app.commands.wood import render_plank

    out = tmp_path / "plank.png"
    render_plank(part, out, normal, size, **kwargs)
    pixels = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert pixels.shape == (size[1], size[0], 3)  # the size asked for
    return pixels


def test_cross_cut_without_legend_fills_the_picture(grid, tmp_path):
    # the bottom 40 % was kept for a legend that was not drawn: the section spanned 58 % of the height
    normal = np.array([0.0, 0.0, 1.0])
    section = W.plank(grid, normal, 0.03, 0.004)
    pixels = render(tmp_path, section, normal, (500, 400))
    wood = (pixels < 250).any(axis=2)
    rows, columns = np.flatnonzero(wood.any(axis=1)), np.flatnonzero(wood.any(axis=0))
    assert max(np.ptp(rows) / 400, np.ptp(columns) / 500) >= 0.85
    assert abs(rows.mean() - 200) < 20 and abs(columns.mean() - 250) < 20  # centred, not pushed up


def is_wood(pixels):
    """Tissue colours are warm (red well over blue); the title's text, the legend's box and text are grey."""
    return pixels[..., 0] - pixels[..., 2] > 25


def box_of(mask):
    rows, columns = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return rows.min(), rows.max(), columns.min(), columns.max()


@pytest.mark.parametrize("size", [(600, 600), (900, 600)])
def test_legend_and_title_cover_no_wood(grid, tmp_path, size):
    # a board little longer than wide filled the view's top 60 %: the legend's box, 0.42 high, touched its
    # lower edge and the title covered its upper one
    from ramure.app.commands.wood import legend_for

    normal = np.array([1.0, 0.0, 0.0])
    slab = W.plank(grid, normal, 0.01, 0.004)
    width = float(np.ptp(np.asarray(slab.points)[:, 1]))
    part = W.plank_window(slab, 1.2 * width)[0]
    pixels = render(tmp_path, part, normal, size, title="pine, a short board", legend=legend_for("pine"))
    legend = np.abs(pixels - LEGEND_BOX).max(axis=2) <= 2
    assert legend.sum() > 0.05 * size[0] * size[1]  # the legend is drawn
    top, bottom, left, right = box_of(legend)
    wood = is_wood(pixels)
    wood[top : bottom + 1, left : right + 1] = False  # the legend's swatches
    w_top, w_bottom, w_left, w_right = box_of(wood)
    gap = int(0.01 * min(size))  # no box in the board's box, and a margin between them
    assert not legend[max(w_top - gap, 0) : w_bottom + gap + 1, max(w_left - gap, 0) : w_right + gap + 1].any()
    assert w_top > 22  # the title's letters end 22 px down
    assert max((w_bottom - w_top) / size[1], (w_right - w_left) / size[0]) > 0.5  # the board is still large


def block(bounds, rgb):
    """A volume of hexahedra over ``bounds`` (x0, x1, y0, y1, z0, z1), its cells coloured ``rgb``."""
    import pyvista as pv

    x0, x1, y0, y1, z0, z1 = bounds
    image = pv.ImageData(dimensions=(2, 4, 8), origin=(x0, y0, z0), spacing=(x1 - x0, (y1 - y0) / 3, (z1 - z0) / 7))
    grid = image.cast_to_unstructured_grid()
    grid.cell_data["rgb"] = np.tile(np.asarray(rgb, np.uint8), (grid.n_cells, 1))
    return grid


def test_legend_goes_over_the_empty_corner_of_a_board_with_a_branch(tmp_path):
    # a quarter-sawn board with its branch rising from it: the legend went beside the board's box, which the
    # branch made as high as long, and the board spanned half the picture's width
    from scipy.ndimage import binary_dilation

    from ramure.app.commands.wood import legend_for

    normal = np.array([1.0, 0.0, 0.0])  # the view's right is -z, its up -y
    board = block((0.0, 0.004, -0.06, 0.0, -0.3, 0.0), (222, 184, 135))
    branch = block((0.0, 0.004, -0.3, -0.06, -0.08, -0.05), (120, 70, 30))  # rising from the board's left end
    part = board.merge(branch)
    size = (600, 600)
    pixels = render(tmp_path, part, normal, size, title="a board and its branch", legend=legend_for("pine"))
    legend = np.abs(pixels - LEGEND_BOX).max(axis=2) <= 2
    assert legend.sum() > 0.05 * size[0] * size[1]
    top, bottom, left, right = box_of(legend)
    wood = is_wood(pixels)
    wood[top : bottom + 1, left : right + 1] = False  # the legend's swatches
    w_top, w_bottom, w_left, w_right = box_of(wood)
    assert (w_right - w_left) / size[0] > 0.85 and w_top > 22  # the board nearly as long as the picture
    near_wood = binary_dilation(wood, iterations=int(0.01 * min(size)))
    assert not (near_wood & legend).any()  # the box keeps off the wood
    assert bottom < 300 < left  # in the upper right corner, over the sky beside the branch
