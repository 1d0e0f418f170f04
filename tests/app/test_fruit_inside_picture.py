"""A lengthwise cut of an apple shows its pips, of a cherry its kernel (issue 40, item 1)."""

import numpy as np
from PIL import Image

from ramure.app import fruit_look as L
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.species import hex_rgb, palette

#: The gallery's cut sheet plane (:func:`ramure.app.fruit_gallery.inside_sheet`).
CUT = ((1, 0.08, 0), (0, 0, 0))


def _share_of(path, species, tissue):
    """Share of the fruit's pixels whose hue (chromaticity, so shading does not count) is
    nearest ``tissue``'s among the species' tissue colours."""
    img = np.asarray(Image.open(path).convert("RGB")).astype(float)
    px = img[np.abs(img - 255).sum(axis=2) > 30]
    colours = palette(species)
    names = sorted(set(colours.values()))
    table = np.array([hex_rgb(c) for c in names], float)
    chroma = px / np.maximum(px.sum(axis=1, keepdims=True), 1.0)
    ref = table / table.sum(axis=1, keepdims=True)
    nearest = np.argmin(((chroma[:, None, :] - ref[None]) ** 2).sum(axis=2), axis=1)
    return float((nearest == names.index(colours[tissue])).mean())


def test_lengthwise_cut_shows_apple_pips_and_cherry_kernel(tmp_path):
    apple = build_fruit("apple", volume_levels=2)
    L.render_png(apple, tmp_path / "apple.png", size=(240, 240), cut=CUT, legend=False, decorations=False)
    assert _share_of(tmp_path / "apple.png", "apple", "seed") > 0.003  # pips: 0.008 of the fruit (0 before)
    cherry = build_fruit("cherry", volume_levels=2)
    L.render_png(cherry, tmp_path / "cherry.png", size=(240, 240), cut=CUT, legend=False, decorations=False)
    assert _share_of(tmp_path / "cherry.png", "cherry", "seed") > 0.04  # kernel: 0.072 (0.018 before: pale stone)
