"""A pyvista plotter in a native window: VTK draws straight into the widget's own X window.

pyvistaqt's ``QtInteractor`` is a ``QOpenGLWidget``: each frame VTK renders into its
framebuffer, the widget blits that into its own framebuffer, Qt's compositor draws the
window's backing store and that texture into the window, and only then is the window
swapped.  On software OpenGL (llvmpipe) those extra full-window passes cost about 10 ms of
CPU per 1000x800 frame (an empty frame: 30 ms instead of 19).  :class:`NativeInteractor`
is a plain ``QWidget`` with a native window handed to VTK (``vtkRenderWindow
.SetWindowInfo``), as VTK's own ``QVTKRenderWindowInteractor`` does: a render is drawn and
swapped to the screen by VTK, synchronously, in one pass.  A camera drag renders once per
mouse move (the QOpenGLWidget renders VTK's frame, then again when Qt repaints it).

Lines wider than one pixel are the driver's wide lines here (``vtkXOpenGLRenderWindow`` has
no ``SetForceMaximumHardwareLineWidth``; the QOpenGLWidget's window forces VTK's
geometry-shader lines).  On llvmpipe that is about 30 ms less for the polished frame of a
131k-segment plant, and the 1.5-pixel hairlines read a little denser: the same picture at
1:1, 1.7 % of the pixels differ by more than 8/255 (1-pixel draft frames are identical).

It is a pyvista ``BasePlotter`` like ``QtInteractor`` (``add_mesh``, ``renderer``,
``ren_win``, ``iren``, ``screenshot``...), so the scene code does not know which one it
draws into.  Only X11 (Qt's ``xcb`` platform) gives a window VTK can draw into:
:func:`make_plotter` falls back to ``QtInteractor`` elsewhere (Wayland, ``offscreen``).

The window is torn down in VTK before Qt destroys it: the native window's
``SurfaceAboutToBeDestroyed`` event finalizes the render window, so a view deleted
without ``close()`` does not leave VTK a GL context on a dead X window; when Qt makes a
new native window (a reparented widget), the next render draws into it.

All the plotters of one window are native (:func:`make_plotter`, used by the docks too): a
``QOpenGLWidget`` turns its whole top-level window to OpenGL composition, and native child
windows in it are then drawn black (Xvfb, llvmpipe).  A ``QWidget.grab()`` of an ancestor
does not hold what VTK drew: :meth:`NativeInteractor.grab_frame` reads it back (the desktop's
window grab paints it in).
"""

from __future__ import annotations

import contextlib
import os
from typing import Any

import numpy as np
from pyvista import global_theme
from pyvista.plotting import BasePlotter
from pyvista.plotting.render_window_interactor import RenderWindowInteractor
from PySide6.QtCore import QEvent, QObject, QSize, Qt
from PySide6.QtGui import QGuiApplication, QImage, QPlatformSurfaceEvent
from PySide6.QtWidgets import QSizePolicy, QWidget
from vtkmodules.vtkRenderingCore import vtkRenderWindow
from vtkmodules.vtkRenderingUI import vtkGenericRenderWindowInteractor


@contextlib.contextmanager
def _no_plotter_init():
    """``QWidget.__init__`` continues the cooperative ``super()`` chain into
    ``BasePlotter.__init__`` with no arguments; it is called later, with them."""
    init = BasePlotter.__init__
    setattr(BasePlotter, "__init__", lambda *args, **kwargs: None)  # noqa: B010  (a method, patched on purpose)
    try:
        yield
    finally:
        setattr(BasePlotter, "__init__", init)  # noqa: B010


def native_windows() -> bool:
    """True where VTK can draw into a Qt widget's native window (X11, Qt's xcb platform) and
    the environment does not ask for pyvistaqt's QOpenGLWidget (``RAMURE_GL_WIDGET=1``)."""
    return QGuiApplication.platformName() == "xcb" and os.environ.get("RAMURE_GL_WIDGET", "") in ("", "0")


def make_plotter(parent: QWidget | None = None, **kwargs: Any) -> Any:
    """A pyvista plotter widget for the desktop window: a :class:`NativeInteractor` where
    :func:`native_windows`, else pyvistaqt's ``QtInteractor(parent, **kwargs)``.

    All the plotters of one window must be of one kind: a ``QOpenGLWidget`` switches its whole
    top-level window to OpenGL composition, and the native windows in it then show black
    (seen on Xvfb with llvmpipe).  So the docks' plotters are made here too.
    """
    if native_windows():
        return NativeInteractor(parent, multi_samples=kwargs.get("multi_samples") or 0)
    from pyvistaqt import QtInteractor

    return QtInteractor(parent, **kwargs)


def grab_with_frames(window: QWidget) -> QImage:
    """``window.grab()`` as a ``QImage``, with the frame of each shown :class:`NativeInteractor`
    in it rendered and painted where the plotter is (Qt's grab cannot read what VTK drew
    into a native window; QOpenGLWidgets are in the grab already)."""
    from PySide6.QtCore import QPoint
    from PySide6.QtGui import QPainter

    image = window.grab().toImage()
    plotters = [p for p in window.findChildren(NativeInteractor) if p.isVisible() and p.ren_win is not None]
    if isinstance(window, NativeInteractor) and window.ren_win is not None:
        plotters.append(window)
    if plotters:
        painter = QPainter(image)
        for plotter in plotters:
            plotter.render()
            frame = plotter.grab_frame()
            frame.setDevicePixelRatio(image.devicePixelRatio())
            painter.drawImage(plotter.mapTo(window, QPoint(0, 0)) if plotter is not window else QPoint(0, 0), frame)
        painter.end()
    return image


class _SurfaceWatch(QObject):
    """Follows the native window under the render window: VTK's context is released just before
    Qt destroys the window (Qt makes a new one when the widget is reparented, or when a
    QOpenGLWidget joins the top-level window), and VTK is pointed at the new one."""

    def __init__(self, render_window: Any) -> None:
        super().__init__()
        self.render_window = render_window
        self.window_id = 0  # the X window VTK draws into
        self.alive = False  # True while the native window exists
        self.handle: Any = None  # the QWindow watched

    def attach(self, widget: QWidget) -> None:
        """Point VTK at ``widget``'s native window and watch it."""
        wid = int(widget.winId())
        self.alive = True
        if self.render_window is not None and wid != self.window_id:
            self.render_window.SetWindowInfo(str(wid))
            self.window_id = wid
        handle = widget.windowHandle()
        if handle is not None and handle is not self.handle:
            handle.installEventFilter(self)
            self.handle = handle

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt API)
        if event.type() == QEvent.Type.PlatformSurface and isinstance(event, QPlatformSurfaceEvent):
            kind = event.surfaceEventType()
            if kind == QPlatformSurfaceEvent.SurfaceEventType.SurfaceAboutToBeDestroyed:
                if self.render_window is not None:
                    self.render_window.Finalize()  # a new context is made on the next window
                self.alive, self.window_id = False, 0
            elif kind == QPlatformSurfaceEvent.SurfaceEventType.SurfaceCreated:
                self.alive = True
        return False


_BUTTON_NAMES = {Qt.MouseButton.LeftButton: "Left", Qt.MouseButton.RightButton: "Right", Qt.MouseButton.MiddleButton: "Middle"}


class NativeInteractor(QWidget, BasePlotter):  # type: ignore[misc]  # both define update()
    """A pyvista plotter drawn by VTK into this widget's native window (see the module's notes).

    Rendering (``render()``, a Qt paint, the interactor's camera moves) draws and swaps the
    frame before it returns.  ``grab_frame()`` reads the last frame back as a ``QImage``.
    """

    def __init__(self, parent: QWidget | None = None, multi_samples: int = 0, auto_update: object = False, **kwargs: Any) -> None:
        # only this widget and its ancestors get native windows, not every sibling on the way up
        # (the docks and their widgets stay Qt-drawn)
        QGuiApplication.setAttribute(Qt.ApplicationAttribute.AA_DontCreateNativeWidgetSiblings)
        with _no_plotter_init():
            QWidget.__init__(self, parent)
        self.setAttribute(Qt.WidgetAttribute.WA_NativeWindow)
        self.setAttribute(Qt.WidgetAttribute.WA_PaintOnScreen)  # VTK paints; Qt's backing store does not
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setAttribute(Qt.WidgetAttribute.WA_NoSystemBackground)
        self.setMouseTracking(True)
        self.setFocusPolicy(Qt.FocusPolicy.WheelFocus)
        self.setSizePolicy(QSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding))
        self._RenderWindow = vtkRenderWindow()
        self._watch = _SurfaceWatch(self._RenderWindow)
        self._watch.attach(self)
        self._Iren: Any = vtkGenericRenderWindowInteractor()
        self._Iren.SetRenderWindow(self._RenderWindow)
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        BasePlotter.__init__(self, **kwargs)
        self.interactor = self
        self.ren_win = self._RenderWindow
        self.ren_win.SetMultiSamples(multi_samples)
        # VTK's default (BlitToHardware) also copies the depth buffer into the window through a
        # full-window shader pass, for drawing after VTK; nothing draws into this window but VTK
        # (about 3 ms less per 1000x800 frame on llvmpipe)
        blit = getattr(self.ren_win, "SetFrameBlitModeToBlitToCurrent", None)  # OpenGL render windows
        if blit is not None:
            blit()
        for renderer in self.renderers:
            renderer.view_isometric()
            self.ren_win.AddRenderer(renderer)
        self.background_color = global_theme.background
        self._off_screen = False
        self.iren = RenderWindowInteractor(self, interactor=self._Iren)
        self.iren.interactor.RemoveObservers("MouseMoveEvent")
        self.iren.initialize()
        self.enable_trackball_style()  # type: ignore[call-arg]  # pyvista's decorator hides self
        self._first_time = False  # BasePlotter renders only once this is False

    # -- pyvista --------------------------------------------------------------------
    def render(self) -> None:  # type: ignore[override]  # pyvista's render, not QWidget.render
        """Draw the frame and put it on screen now."""
        if self._window_ready():
            BasePlotter.render(self)

    def GetRenderWindow(self) -> Any:  # noqa: N802 (VTK's name, as QtInteractor has it)
        """The VTK render window (as pyvistaqt's QtInteractor names it)."""
        return self._RenderWindow

    def grab_frame(self) -> QImage:
        """The last frame as an RGB ``QImage`` (read back from VTK; call ``render()`` first)."""
        rw = self.ren_win
        assert rw is not None, "the view is closed"
        w, h = rw.GetSize()
        from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
        from vtkmodules.util.numpy_support import vtk_to_numpy

        data = vtkUnsignedCharArray()
        rw.GetPixelData(0, 0, w - 1, h - 1, 0, data, 0)
        rgb = np.ascontiguousarray(vtk_to_numpy(data).reshape(h, w, 3)[::-1])
        return QImage(rgb.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy()

    def _window_ready(self) -> bool:
        """True if VTK has a live native window to draw into (pointed at a new one if Qt made one)."""
        if self.ren_win is None or getattr(self, "_closed", False) or self._watch.render_window is None:
            return False
        handle = self.windowHandle()
        if handle is None or (handle is self._watch.handle and not self._watch.alive):
            return False  # the native window is being destroyed, or not made again yet
        self._watch.attach(self)
        return True

    def _finalize(self, *_args: Any) -> None:
        rw = self._RenderWindow
        if rw is not None and self._watch.render_window is not None:
            self._watch.render_window = None
            rw.Finalize()

    def close(self) -> bool:  # type: ignore[override]
        """Release VTK's window and GL context, then close the widget."""
        if not getattr(self, "_closed", True):
            BasePlotter.close(self)  # finalizes the render window
        self._finalize()
        self._Iren = None
        return QWidget.close(self)

    # -- Qt -------------------------------------------------------------------------
    def paintEngine(self) -> None:  # type: ignore[override]  # noqa: N802 (Qt API): VTK paints this widget
        """None: VTK paints this widget, not Qt."""
        return None

    def paintEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Render the VTK window once it is ready."""
        rw = self.ren_win
        if rw is not None and self._window_ready():
            rw.Render()

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Resize the VTK window to the widget (in device pixels)."""
        scale = self.devicePixelRatioF()
        w, h = max(1, round(self.width() * scale)), max(1, round(self.height() * scale))
        rw = self._RenderWindow
        if rw is not None and self._Iren is not None:
            rw.SetDPI(round(72 * scale))
            vtkRenderWindow.SetSize(rw, w, h)
            self._Iren.SetSize(w, h)
            self._Iren.ConfigureEvent()
        self.update()

    def sizeHint(self) -> QSize:  # noqa: N802 (Qt API)
        """400 x 400, as pyvistaqt's interactor."""
        return QSize(400, 400)

    def closeEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Finalize the VTK window (the next render, if any, makes it again)."""
        if self.ren_win is not None:
            self.ren_win.Finalize()  # made again by the next render, if any
        super().closeEvent(event)

    # -- mouse to VTK ----------------------------------------------------------------
    def _event_info(self, event: Any, repeat: int = 0) -> None:
        scale = self.devicePixelRatioF()
        pos = event.position()
        mods = event.modifiers()
        ctrl = bool(mods & Qt.KeyboardModifier.ControlModifier)
        shift = bool(mods & Qt.KeyboardModifier.ShiftModifier)
        if self._Iren is not None:
            self._Iren.SetEventInformation(
                round(pos.x() * scale), round((self.height() - pos.y() - 1) * scale), ctrl, shift, "\0", repeat
            )

    def mousePressEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Forward a press (or double click) to the VTK interactor."""
        if self._Iren is None:
            return
        self._event_info(event, int(event.type() == QEvent.Type.MouseButtonDblClick))
        self._button = event.button()
        self._button_event("Press")

    def mouseReleaseEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Forward a release to the VTK interactor."""
        if self._Iren is None:
            return
        self._event_info(event)
        self._button_event("Release")

    def _button_event(self, kind: str) -> None:
        """VTK's ``<Left|Right|Middle>Button<kind>Event`` for the button last pressed (others: none)."""
        side = _BUTTON_NAMES.get(self._button)
        if side is not None and self._Iren is not None:
            getattr(self._Iren, f"{side}Button{kind}Event")()

    def mouseMoveEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Forward a move to the VTK interactor."""
        if self._Iren is None:
            return
        self._event_info(event)
        self._Iren.MouseMoveEvent()

    def wheelEvent(self, event: Any) -> None:  # noqa: N802 (Qt API)
        """Forward the wheel to the VTK interactor, one step per notch (120 eighths of a degree)."""
        if self._Iren is None:
            return
        self._wheel += event.angleDelta().y()
        if self._wheel >= 120:
            self._Iren.MouseWheelForwardEvent()
            self._wheel = 0
        elif self._wheel <= -120:
            self._Iren.MouseWheelBackwardEvent()
            self._wheel = 0
