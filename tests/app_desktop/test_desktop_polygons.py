"""A real click on a polygon leaf in the desktop view selects it; regrow draws new polygon leaves."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from desktop_helpers import settle

pytestmark = pytest.mark.gui

LEAVES = """#module plant leaf
#angle 30
n: 4
w: plant
p:
  plant -> F[+leaf]F[-leaf]plant
  .5 leaf -> ['{+f-ff-f+|+f-ff-f}]
  .5 leaf -> [''{+f(2)-f|+f-f(2)}]
"""


def polygon_centres(polygons):
    sizes = polygons.sizes
    owner = np.repeat(np.arange(len(polygons)), sizes)
    return np.stack([np.bincount(owner, polygons.points[:, k]) / sizes for k in range(3)], axis=1)


def test_a_real_click_on_a_polygon_leaf_selects_it_and_regrow_redraws_leaves(make_window, qtbot, artifacts):
    w = make_window(LEAVES, n=4, seed=1)
    ex = w.controller.explorer
    polygons = ex.skeleton.polygons
    xy = w.view.project(polygon_centres(polygons))
    segments = w.view.project(w.controller.snapshot.midpoints)
    # the leaf whose centre is farthest from every branch and every other leaf on screen
    gaps = [
        min(np.min(np.linalg.norm(segments - p, axis=1)), np.min(np.linalg.norm(np.delete(xy, k, axis=0) - p, axis=1)))
        for k, p in enumerate(xy)
    ]
    k = int(np.argmax(gaps))
    QTest.mouseClick(w.view.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, w.view.to_widget(*xy[k]))
    leaf = int(polygons.leaf_id[k])
    assert ex.selection == [leaf]
    rgb = np.asarray(w.view.mesh.cell_data["rgb"])
    red = np.asarray(w.view.mesh.cell_data["leaf_id"]) == leaf
    assert red.sum() == len(polygons.triangles()[0][polygons.triangles()[1] == k])  # its triangles
    assert (rgb[red] == [255, 0, 0]).all()
    w.view.redraw(now=True)
    image = w.view.plotter.screenshot(str(artifacts / "desktop-polygon-leaf-picked.png"), return_img=True)
    r, g, b = (image[..., c].astype(int) for c in range(3))
    assert ((r > 120) & (g < 40) & (b < 40)).sum() > 100  # the picked leaf shows red (shaded)
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    after = ex.skeleton.polygons
    assert len(after) == len(polygons) and leaf not in after.leaf_id.tolist()
    fresh = set(after.leaf_id.tolist()) - set(polygons.leaf_id.tolist())
    assert fresh and fresh <= set(ex.selection)  # the regrown leaf stays selected (and highlighted)
    red = np.isin(np.asarray(w.view.mesh.cell_data["leaf_id"]), list(fresh))
    assert red.any() and (np.asarray(w.view.mesh.cell_data["rgb"])[red] == [255, 0, 0]).all()


def test_thumbnails_fill_polygon_leaves(qtbot):
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.view.thumbnails import skeleton_image
    from ramure.lsys import LSystem

    make_application()

    def leaf_pixels(axiom):
        image = skeleton_image(LSystem.from_text(f"#angle 90\nn: 0\nw: {axiom}").derive().skeleton(), 100)
        rgba = np.frombuffer(image.constBits(), np.uint8).reshape(100, 100, 4)  # B G R A
        return int(((rgba[..., 1] > 120) & (rgba[..., 2] < 120)).sum())

    assert leaf_pixels("F(0.2){f(4)+f(4)+f(4)+f(4)}") > 3000  # a filled square over most of the tile
    assert leaf_pixels("F(0.2)f(4)+f(4)+f(4)+f(4)") == 0  # the same moves without braces: nothing
