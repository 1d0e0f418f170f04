"""Zoom to fruit and a readable cut in the desktop (issue 40 §7)."""

from __future__ import annotations

import numpy as np
import pytest

from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui


def _action(w, text):
    return next(a for a in w.findChildren(type(w.variants.cut_toggle)) if a.text() == text)


def test_zoom_to_the_selected_fruit_and_a_cut_in_tissue_colours(make_window, qtbot, artifacts):
    from ramure.gmap.organs.species import cell_rgb

    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    fruit = w.controller.read(lambda ex: ex.fruit_ids(), wait=None)[0]
    w.controller.select([fruit])
    w.variants.cut_toggle.trigger()  # View > Cut fruit open
    qtbot.waitUntil(lambda: w.view.fruit is not None and w.variants.fruit_job_cut, timeout=30000)
    settle(qtbot, w)
    far = np.linalg.norm(np.subtract(w.view.plotter.camera.position, w.view.plotter.camera.focal_point))
    _action(w, "Zoom to fruit").trigger()
    settle(qtbot, w)
    bounds = w.controller.read(lambda ex: ex.fruit_bounds([fruit]), wait=None)
    centre = np.reshape(bounds, (3, 2)).mean(axis=1)
    camera = w.view.plotter.camera
    assert np.linalg.norm(np.subtract(camera.focal_point, centre)) < 1e-6 * max(1.0, far)
    near = np.linalg.norm(np.subtract(camera.position, camera.focal_point))
    assert near < far / 3  # much closer than the whole plant's frame
    # the cut reads by tissue: the fruit's cells in the species' colours, not shades of one red
    cut = w.view.fruit
    other = np.asarray(cut.cell_data["leaf_id"]) != fruit
    tissue = np.asarray(cut.cell_data["tissue"])[other]
    rgb = np.asarray(cut.cell_data["rgb"])[other]
    np.testing.assert_array_equal(rgb, np.asarray(cut.cell_data["tissue_rgb"])[other])
    expected = {int(t): tuple(cell_rgb([t], "tomato")[0]) for t in np.unique(tissue)}
    assert len(set(expected.values())) >= 3
    for t, colour in expected.items():
        assert (rgb[tissue == t] == colour).all(axis=1).mean() > 0.9
    image = w.view.grab_image()
    image.save(str(artifacts / "desktop_zoom_fruit_cut.png"))
    # nothing selected: every fruit is framed
    w.controller.select([])
    _action(w, "Zoom to fruit").trigger()
    settle(qtbot, w)
    every = w.controller.read(lambda ex: ex.fruit_bounds(), wait=None)
    assert np.allclose(w.view.plotter.camera.focal_point, np.reshape(every, (3, 2)).mean(axis=1))
