"""The 3D view in a native window (VTK draws into the widget's X window, no QOpenGLWidget):
the same picture as pyvistaqt's QOpenGLWidget view, on the screen, in window grabs, picked
the same; torn down without crashes."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.desktop import state
from ramure.app.desktop.view import scene
from ramure.app.desktop.view.native_view import NativeInteractor, native_windows
from ramure.app.model import Explorer
from desktop_helpers import HONDA

pytestmark = pytest.mark.gui


def image_array(qimage):
    qimage = qimage.convertToFormat(qimage.Format.Format_RGB888)
    w, h = qimage.width(), qimage.height()
    return np.frombuffer(qimage.constBits(), np.uint8).reshape(h, qimage.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).astype(int)


def on_screen(view):
    """What the X server shows where the view's plotter is (not what VTK or Qt hold)."""
    from PySide6.QtCore import QPoint
    from PySide6.QtGui import QGuiApplication

    corner = view.plotter.mapToGlobal(QPoint(0, 0))
    shot = QGuiApplication.primaryScreen().grabWindow(0, corner.x(), corner.y(), view.plotter.width(), view.plotter.height())
    return image_array(shot.toImage())


def differ(a, b, level=8):
    return float((np.abs(a - b).max(axis=2) > level).mean())


@pytest.fixture(scope="module")
def honda():
    ex = Explorer(str(HONDA), n=10)
    snap = state.take_snapshot(ex)
    return snap, state.cell_colors(snap.mesh, snap.selection, base=state.base_colors(snap.mesh))


@pytest.fixture
def views(qtbot, honda):
    """A native view and a QOpenGLWidget view of the same plant, side by side, 500x400 each."""
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.view.plant_view import PlantView

    make_application()
    if not native_windows():
        pytest.skip("native windows need X11 (Qt's xcb platform)")
    snap, colors = honda
    made = {}
    for x, native in ((0, True), (520, False)):
        view = PlantView(native=native)
        qtbot.addWidget(view)
        view.resize(500, 400)
        view.move(x, 0)
        view.show()
        qtbot.waitExposed(view)
        view.show_plant(snap, colors, reset_camera=True)
        view.redraw(now=True)
        made["native" if native else "gl"] = view
    qtbot.wait(50)
    yield made
    for view in made.values():
        view.close()


def test_the_native_view_is_the_default_on_x11_and_draws_what_the_gl_widget_draws(views, qtbot):
    native, gl = views["native"], views["gl"]
    assert isinstance(native.plotter, NativeInteractor) and not isinstance(gl.plotter, NativeInteractor)
    from ramure.app.desktop.view.plant_view import PlantView

    default = PlantView()
    qtbot.addWidget(default)
    assert default.native and isinstance(default.plotter, NativeInteractor)
    default.close()
    a, b = image_array(native.grab_image()), image_array(gl.grab_image())
    assert a.shape == b.shape == (400, 500, 3)
    row = a[200]
    assert len({tuple(p) for p in row[::5]}) > 5  # not blank: background, bark, grid
    # polished: 1.5-px hairlines are the driver's wide lines here, VTK's geometry shader there
    assert differ(a, b) < 0.03
    assert np.abs(a.reshape(-1, 3).mean(0) - b.reshape(-1, 3).mean(0)).max() < 2.0
    # the draft look (1-px lines, no FXAA) is drawn pixel for pixel the same
    for view in (native, gl):
        view.hairlines.set_width(scene.DRAFT_LINE_WIDTH)
        view.plotter.renderer.SetUseFXAA(False)
        view.redraw(now=True)
    a, b = image_array(native.frame_image()), image_array(gl.frame_image())
    assert differ(a, b, level=0) < 0.001


def test_vtk_draws_into_the_x_window_and_the_window_grab_holds_it(views, qtbot):
    native = views["native"]
    frame = image_array(native.grab_image())
    qtbot.wait(20)
    assert differ(on_screen(native), frame) < 0.001  # the frame is on the screen as VTK read it back
    # a grab of an ancestor (as MainWindow.grab_window does) holds the frame where the view is
    from PySide6.QtCore import QPoint

    from ramure.app.desktop.view.native_view import grab_with_frames

    grab = image_array(grab_with_frames(native))
    at = native.plotter.mapTo(native, QPoint(0, 0))
    h, w = frame.shape[:2]
    assert differ(grab[at.y() : at.y() + h, at.x() : at.x() + w], frame) < 0.001


def test_picking_finds_the_same_cells_in_both_views(views):
    native, gl = views["native"], views["gl"]
    w, h = native.display_size()
    points = [(x, y) for x in range(20, w, 23) for y in range(20, h, 19)]
    picked = [native.pick(x, y) for x, y in points]
    assert sum(c >= 0 for c in picked) > 10  # the plant is hit
    assert picked == [gl.pick(x, y) for x, y in points]


def test_the_rubber_band_shows_over_the_native_window(views, qtbot):
    from PySide6.QtCore import QPoint, QRect, QSize

    native = views["native"]
    before = on_screen(native)
    native.band.setGeometry(QRect(QPoint(50, 60), QSize(200, 100)))
    native.band.show()
    qtbot.wait(50)
    during = on_screen(native)
    native.band.hide()
    moved = np.abs(during - before).max(axis=2) > 8
    assert moved[60:160, 50:250].mean() > 0.5 and moved[200:, 300:].mean() < 0.01


def test_a_camera_drag_draws_one_frame_per_move(views, qtbot):
    """The native window renders once per mouse move (the QOpenGLWidget renders VTK's frame,
    then again when Qt repaints the widget)."""
    from PySide6.QtCore import QPoint, Qt
    from PySide6.QtTest import QTest

    native = views["native"]
    QTest.mousePress(native.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(250, 200))
    before, camera = native.frames, native.plotter.camera_position
    for k in range(1, 6):
        QTest.mouseMove(native.plotter, QPoint(250 + 10 * k, 200))
    qtbot.wait(20)
    drawn = native.frames - before
    QTest.mouseRelease(native.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(300, 200))
    assert native.plotter.camera_position != camera  # the drag turned the view
    assert 1 <= drawn <= 6


def test_views_deleted_without_close_do_not_crash(qtbot, honda):
    """Qt destroys the native window under VTK's context; the view releases it first."""
    import gc

    from PySide6.QtWidgets import QMainWindow

    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.view.plant_view import PlantView

    make_application()
    if not native_windows():
        pytest.skip("native windows need X11 (Qt's xcb platform)")
    snap, colors = honda
    for k in range(4):
        window = QMainWindow()
        view = PlantView()
        window.setCentralWidget(view)
        window.resize(300, 240)
        window.show()
        qtbot.waitExposed(window)
        view.show_plant(snap, colors, reset_camera=True)
        view.redraw(now=True)
        if k % 2:
            window.deleteLater()
        else:
            del view
            window.close()
            window.deleteLater()
        qtbot.wait(20)
        gc.collect()
    fresh = PlantView()
    qtbot.addWidget(fresh)
    fresh.resize(300, 240)
    fresh.show()
    qtbot.waitExposed(fresh)
    fresh.show_plant(snap, colors, reset_camera=True)
    image = image_array(fresh.grab_image())
    assert len({tuple(p) for p in image[120, ::5]}) > 3
    fresh.close()


def test_the_window_grab_holds_the_plant_and_no_window_is_drawn_black(make_window, qtbot):
    """grab_window paints the native frames in; a dock's plotter is native too (a QOpenGLWidget
    in the window would turn its composition to OpenGL and the native views black)."""
    from PySide6.QtCore import QPoint

    w = make_window(n=8)
    if not w.view.native:
        pytest.skip("native windows need X11 (Qt's xcb platform)")
    dock = w.docks["wood"]
    dock.show()
    dock.raise_()
    qtbot.waitUntil(lambda: dock.widget().view_slot.made, timeout=5000)
    wood = dock.widget().view_slot.plotter()
    assert isinstance(wood, NativeInteractor)
    wood.set_background("white")
    qtbot.wait(50)
    image = image_array(w.grab_window())
    frame = image_array(w.view.frame_image())
    at = w.view.plotter.mapTo(w, QPoint(0, 0))
    h, width = frame.shape[:2]
    assert differ(image[at.y() : at.y() + h, at.x() : at.x() + width], frame) < 0.001
    assert len({tuple(p) for p in frame[h // 2, ::5]}) > 5  # the plant, not a blank frame
    at = wood.mapTo(w, QPoint(0, 0))
    patch = image[at.y() + 5 : at.y() + wood.height() - 5, at.x() + 5 : at.x() + wood.width() - 5]
    assert patch.size and (patch > 240).all(axis=2).mean() > 0.9  # the wood view's white background
    # what the screen shows where the plant view is: VTK's frame, not black (the rows on the
    # screen: the window may be taller than Xvfb's screen)
    from PySide6.QtGui import QGuiApplication

    rows = QGuiApplication.primaryScreen().geometry().height() - w.view.plotter.mapToGlobal(QPoint(0, 0)).y()
    assert rows > 100
    assert differ(on_screen(w.view)[:rows], frame[:rows]) < 0.01
