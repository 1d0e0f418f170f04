"""The 3D view frames the whole plant, offers Z-up presets, a ground grid, and shows hairline twigs."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from ramure.app.desktop.view import scene
from desktop_helpers import settle

pytestmark = pytest.mark.gui


def image_array(qimage):
    qimage = qimage.convertToFormat(qimage.Format.Format_RGB888)
    w, h = qimage.width(), qimage.height()
    return np.frombuffer(qimage.constBits(), np.uint8).reshape(h, qimage.bytesPerLine())[:, : 3 * w].reshape(h, w, 3)


def test_a_tall_plant_is_framed_at_1024x700_and_presets_keep_z_up(make_window, qtbot, artifacts):
    w = make_window(n=10)
    w.fit_screen(1024, 700)
    settle(qtbot, w)
    qtbot.wait(50)
    view = w.view.size()
    assert view.width() * view.height() > 0.5 * w.width() * w.height()  # the 3D view gets most
    editor = w.editor.edit
    assert not editor.horizontalScrollBar().isVisible()  # the grammar reads without side scrolling
    qtbot.wait(50)
    bounds = w.view.mesh.bounds
    assert not scene.outside_view(w.view.plotter, bounds, slack=1.0)  # every box corner on screen
    for key, name in ((Qt.Key.Key_2, "side"), (Qt.Key.Key_3, "top"), (Qt.Key.Key_4, "iso")):
        QTest.keyClick(w.view.plotter, key, Qt.KeyboardModifier.ControlModifier)
        settle(qtbot, w)
        assert w.view.view_name == name and not scene.outside_view(w.view.plotter, bounds, slack=1.0)
        up = np.asarray(w.view.plotter.camera.up)
        assert name == "top" or abs(up[2]) > 0.9  # Z up, no roll
    w.view.grab_image().save(str(artifacts / "desktop_iso.png"))
    assert w.view.ground.actor.GetVisibility() and w.view.ground.step > 0
    QTest.keyClick(w.view.plotter, Qt.Key.Key_1, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, w)
    w.grab_window().save(str(artifacts / "desktop_1024x700.png"))


@pytest.mark.parametrize("screen", [(1400, 900), (1920, 1080)])
def test_the_window_takes_the_size_asked_for_within_the_screen(make_window, qtbot, screen):
    w = make_window(n=6)
    assert (w.width(), w.height()) == (1200, 800)  # make_window's size: not the docks stacked (1338 px)
    w.fit_screen(*screen)
    settle(qtbot, w)
    assert (w.width(), w.height()) == (1400, 880)
    assert w.height() <= screen[1] and w.view.height() > 400


def test_a_selected_hairline_twig_shows_red(make_window, qtbot, artifacts):
    w = make_window(n=10)
    snap = w.controller.snapshot
    radius = np.asarray(snap.skeleton.base_radius)
    twig = int(np.argmin(radius))
    w.controller.select([int(snap.segment_leaf[twig])])
    settle(qtbot, w)
    assert w.view.hairlines.selected_actor.GetVisibility()
    x, y = w.view.project(snap.midpoints[[twig]])[0]
    pixels = image_array(w.view.grab_image())
    scale = w.view.plotter.devicePixelRatioF()
    row, col = int(round(pixels.shape[0] - 1 - y / scale)), int(round(x / scale))
    patch = pixels[max(row - 3, 0) : row + 4, max(col - 3, 0) : col + 4].reshape(-1, 3).astype(int)
    reddish = (patch[:, 0] > 180) & (patch[:, 1] < 90) & (patch[:, 2] < 90)
    assert reddish.any()  # the selection is visible on a twig far thinner than a pixel
    w.view.grab_image().save(str(artifacts / "desktop_hairline_selection.png"))


def test_f1_opens_the_mouse_and_key_reference_and_help_has_the_grammar(make_window, qtbot, artifacts):
    w = make_window(n=5)
    QTest.keyClick(w.view.plotter, Qt.Key.Key_F1)
    qtbot.waitUntil(lambda: w.help_menu.dialog is not None and w.help_menu.dialog.isVisible(), timeout=3000)
    text = w.help_menu.browser.toPlainText()
    assert "Ctrl+Y" in text and "Right drag" in text and w.help_menu.shown == "Mouse and keys"
    help_top = next(a for a in w.menuBar().actions() if a.text() == "&Help")
    titles = [a.text() for a in help_top.menu().actions()]
    assert titles == ["Mouse and keys", "Grammar reference", "About Ramure"]
    help_top.menu().actions()[1].trigger()
    assert "#define" in w.help_menu.browser.toPlainText()
    w.help_menu.dialog.close()
