"""Variant thumbnails drawn side by side in one window and cut into tiles (issue 34 §5)."""

import numpy as np
import pytest
from PIL import Image

pytest.importorskip("pyvista")

from ramure.app.thumbnails import _grid_shape, _render_many  # noqa: E402
from ramure.lsys import LSystem  # noqa: E402


def _pixels(path):
    return np.asarray(Image.open(path).convert("RGB"))


def test_a_tile_of_the_grid_is_the_plant_rendered_alone(tmp_path):
    grammar = LSystem.from_file("grammars/honda_sympodial.lsys")
    plants = [grammar.derive(n=n).skeleton() for n in (3, 4, 5, 6)]
    size = (60, 90)  # not square: rows and columns cannot be swapped unnoticed
    together = _render_many(plants, [tmp_path / f"grid{k}.png" for k in range(4)], size, captions=list("abcd"))
    tiles = [_pixels(p) for p in together]
    for k, plant in enumerate(plants):
        alone = _render_many([plant], [tmp_path / f"alone{k}.png"], size, captions=["abcd"[k]])
        assert tiles[k].shape == (90, 60, 3)
        assert np.array_equal(tiles[k], _pixels(alone[0])), f"tile {k} is not plant {k}"
        assert (tiles[k] < 200).any(axis=-1).mean() > 0.01  # a drawn plant, not a blank tile
    assert all(not np.array_equal(tiles[0], t) for t in tiles[1:])


def test_the_window_stays_within_4096_pixels_a_side():
    assert _grid_shape(27, (220, 220)) == (9, 3)
    assert _grid_shape(2, (220, 220)) == (2, 1)
    cols, rows = _grid_shape(27, (1500, 1000))
    assert (cols, rows) == (2, 4) and cols * 1500 <= 4096 and rows * 1000 <= 4096
    assert _grid_shape(5, (5000, 5000)) == (1, 1)
