"""VTK draws on the kernel's main thread only; clicks select, drags rotate; no network at start.

JupyterLab's comms over subshells deliver widget messages on kernel threads: a callback arriving
there must be queued on the main thread's loop, not run (and draw) on the subshell thread.
"""

from __future__ import annotations

import asyncio
import socket
import threading

import numpy as np
import pytest

from jupyter_helpers import HONDA
from ramure.app.jupyter import NotebookExplorer
from ramure.app.jupyter import mainthread
from ramure.app.jupyter import view as view_module


@pytest.fixture
def kernel_loop(monkeypatch):
    """A tornado IOLoop on this (the main) thread standing in for the kernel's ``io_loop``."""
    from tornado.ioloop import IOLoop

    asyncio.set_event_loop(asyncio.new_event_loop())
    loop = IOLoop.current()
    monkeypatch.setattr(mainthread, "kernel_loop", lambda: loop)
    yield loop
    loop.close(all_fds=False)
    asyncio.set_event_loop(None)


def _from_subshell(action):
    """Run ``action()`` on another thread, as a comm message on a kernel subshell is."""
    worker = threading.Thread(target=action, name="subshell")
    worker.start()
    worker.join()


def test_widget_callbacks_from_a_subshell_draw_on_the_main_thread(kernel_loop, monkeypatch):
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(64, 64))
    drawn_on = []
    real = view_module.plant_png

    def recording_png(*args, **kwargs):
        drawn_on.append(threading.current_thread().name)
        return real(*args, **kwargs)

    monkeypatch.setattr(view_module, "plant_png", recording_png)
    leaf = int(ex.skeleton.leaf_id[-1])
    _from_subshell(lambda: setattr(ex.camera, "value", "top"))  # the view drop-down
    _from_subshell(lambda: ex.selection_panel.ids.set_trait("value", str(leaf)))
    _from_subshell(lambda: ex.selection_panel.widget.children[2].children[1].click())  # Select ids
    assert drawn_on == [] and ex.view.view == "iso" and ex.selection == []  # queued, nothing ran there
    kernel_loop.run_sync(lambda: asyncio.sleep(0.05))  # the main loop runs the queue in order
    assert ex.view.view == "top" and ex.selection == [leaf]
    assert drawn_on and set(drawn_on) == {threading.main_thread().name}


def test_a_failing_queued_callback_is_reported_and_the_loop_goes_on(kernel_loop, capsys):
    done = []

    def broken():
        raise RuntimeError("boom")

    _from_subshell(lambda: mainthread.on_main(broken))
    _from_subshell(lambda: mainthread.on_main(done.append, 1))
    kernel_loop.run_sync(lambda: asyncio.sleep(0.05))
    assert done == [1] and "RuntimeError: boom" in capsys.readouterr().err


def test_on_the_main_thread_or_outside_a_kernel_callbacks_run_at_once():
    calls = []
    mainthread.on_main(calls.append, "main")
    _from_subshell(lambda: mainthread.on_main(calls.append, "no kernel"))  # no loop to queue on
    assert calls == ["main", "no kernel"]


class _Plotter:
    """An off-screen plotter of the plant, its camera framed, for driving interactor events."""

    def __init__(self, ex):
        import pyvista as pv

        from ramure.app.render import frame_camera

        self.pl = pv.Plotter(off_screen=True, window_size=[300, 300])
        self.pl.add_mesh(ex.model.mesh)
        frame_camera(self.pl, ex.model.mesh.bounds, "front")
        self.pl.render()

    def display_point(self, world):
        ren = self.pl.renderer
        ren.SetWorldPoint(*world, 1.0)
        ren.WorldToDisplay()
        x, y, _ = ren.GetDisplayPoint()
        return int(round(x)), int(round(y))

    def event(self, name, x, y):
        iren = self.pl.iren.interactor
        iren.SetEventInformation(x, y)
        iren.InvokeEvent(name)


@pytest.mark.parametrize("end", ["LeftButtonReleaseEvent", "EndInteractionEvent"])
def test_click_selects_drag_does_not(end):
    ex = NotebookExplorer(HONDA, n=5, view="static", size=(64, 64))
    scene = _Plotter(ex)
    picked = []
    view_module.ClickPicker(scene.pl, picked.append)
    sk = ex.skeleton
    trunk = int(np.argmin(sk.order * 100 + sk.start[:, 2]))  # the trunk's first segment
    x, y = scene.display_point((sk.start[trunk] + sk.end[trunk]) / 2)
    scene.event("LeftButtonPressEvent", x, y)
    scene.event(end, x + 2, y)  # a click (within CLICK_PIXELS)
    assert len(picked) == 1 and ex.model.leaf_of_cell(picked[0]) == int(sk.leaf_id[trunk])
    scene.event("LeftButtonPressEvent", x, y)
    scene.event(end, x + 40, y + 10)  # a drag from the same branch: the view turns, nothing picked
    assert len(picked) == 1
    scene.event(end, x, y)  # a release without a press (the end of a rotation) picks nothing
    assert len(picked) == 1
    scene.event("LeftButtonPressEvent", 2, 2)
    scene.event(end, 2, 2)  # a click on the background
    assert len(picked) == 1
    scene.pl.close()


def test_reframe_when_a_regrow_grows_the_plant():
    small = (0, 1, 0, 1, 0, 4)
    assert not view_module.needs_reframe(small, (0.01, 0.99, 0, 1, 0, 4.02))
    assert view_module.needs_reframe(small, (0, 1, 0, 1, 0, 6))  # taller: the top would be cut off
    assert view_module.needs_reframe(small, (-1, 1, 0, 1, 0, 4))  # wider
    assert view_module.needs_reframe(small, (0, 0.5, 0, 0.5, 0, 1.5))  # much smaller
    assert view_module.needs_reframe(None, small)


def test_starting_the_interactive_view_reaches_no_network(monkeypatch):
    """trame-vtklocal, when importable, downloads VTK's WebAssembly bundle as pyvista starts its
    trame server: Ramure hides it for that moment and looks up no host but this one."""
    pytest.importorskip("trame_pyvista")
    looked_up = []
    real = socket.getaddrinfo

    def recording(host, *args, **kwargs):
        looked_up.append(host)
        if host not in ("127.0.0.1", "localhost", "::1", "0.0.0.0", None):
            raise OSError(f"network refused in this test: {host}")
        return real(host, *args, **kwargs)

    monkeypatch.setattr(socket, "getaddrinfo", recording)
    monkeypatch.setattr(view_module, "resolve_backend", lambda backend: "server")
    import trame.widgets as trame_widgets

    before = "vtklocal" in trame_widgets.__dict__
    ex = NotebookExplorer(HONDA, n=3, size=(120, 120))
    assert ex.view.backend == "server" and ex.view.fallback_reason is None, ex.message.text
    remote = [h for h in looked_up if h not in ("127.0.0.1", "localhost", "::1", "0.0.0.0", None)]
    assert remote == []
    assert ("vtklocal" in trame_widgets.__dict__) == before  # the module is given back afterwards


def test_the_interactive_view_reframes_when_the_plant_grows():
    """After an edit that makes the plant taller the whole plant is in the picture again."""
    pytest.importorskip("trame_pyvista")
    ex = NotebookExplorer(HONDA, n=3, view="server", size=(200, 200))
    assert ex.view.backend == "server", ex.message.text

    def outside():
        cam = ex.view.trame.plotter.camera
        m = np.array(
            [[cam.GetCompositeProjectionTransformMatrix(1.0, -1, 1).GetElement(i, j) for j in range(4)] for i in range(4)]
        )
        pts = np.asarray(ex.model.mesh.points)
        h = np.c_[pts, np.ones(len(pts))] @ m.T
        return float(np.max(np.abs(h[:, :2] / h[:, 3:4])))

    assert outside() <= 1.0
    ex.set_derivation(n=7)  # a much bigger plant
    assert outside() <= 1.0
