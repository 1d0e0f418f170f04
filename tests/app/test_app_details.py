"""The shared details work (ramure.app.details): lichen on a fruit seen from where it grows."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.details import facing, lichen_on_fruit
from ramure.app.model import Explorer


def _picture(out, camera, discs):
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=(240, 240))
    try:
        plotter.set_background("white")
        plotter.add_mesh(out["fruit"], color=(0.8, 0.1, 0.1), smooth_shading=True)
        if discs:
            plotter.add_mesh(out["discs"], scalars="rgb", rgb=True, show_scalar_bar=False)
        plotter.camera_position = camera
        return plotter.screenshot(None, return_img=True).astype(int)
    finally:
        plotter.close()


@pytest.fixture(scope="module")
def lichen():
    explorer = Explorer("fruit_tree", n=5)
    explorer.select([explorer.fruit_ids()[0]])
    return lichen_on_fruit(explorer)  # the front ends' defaults: 5 clusters, 300 particles


def test_the_camera_faces_the_lichen_and_frames_the_whole_fruit(lichen):
    eye, centre, _ = (np.array(v) for v in facing(lichen["growth"], lichen["mesh"]))
    points = lichen["mesh"].points
    radius = np.linalg.norm(points.max(0) - points.min(0)) / 2
    assert 2.0 * radius < np.linalg.norm(eye - centre) < 3.5 * radius  # outside, the fruit fills the view
    towards_eye = (eye - centre) / np.linalg.norm(eye - centre)
    seen = lichen["mesh"].normals[lichen["growth"].triangle] @ towards_eye
    assert (seen > 0).mean() > 0.6  # most particles sit on the side the camera sees


def test_lichen_at_its_default_size_covers_a_visible_part_of_the_fruit(lichen):
    """Issue 40 §7: at diagonal / 120 from a fixed corner lichen took 9 % of the fruit's pixels."""
    camera = facing(lichen["growth"], lichen["mesh"])
    bare, grown = _picture(lichen, camera, False), _picture(lichen, camera, True)
    fruit = (bare != 255).any(-1).sum()
    shown = (bare != grown).any(-1).sum()
    assert fruit > 0.2 * 240 * 240
    assert shown > 0.2 * fruit
