"""Fixtures for the desktop window tests: a display (Xvfb if needed), a window, helpers.

GUI tests are skipped only when no display can be had: no ``DISPLAY`` and no
``Xvfb`` to start one.  Screenshots go to ``tests/artifacts/`` (git-ignored).
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess

import pytest

from desktop_helpers import ARTIFACTS, HONDA, ROOT, settle


def _start_xvfb():
    """Start a private Xvfb and point DISPLAY at it; returns False if impossible."""
    xvfb = shutil.which("Xvfb")
    if not xvfb:
        return False
    read, write = os.pipe()
    proc = subprocess.Popen(
        [xvfb, "-displayfd", str(write), "-screen", "0", "1400x900x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    with os.fdopen(read) as f:
        number = f.readline().strip()
    if not number:
        proc.kill()
        return False
    os.environ["DISPLAY"] = f":{number}"
    atexit.register(proc.terminate)
    return True


HAVE_DISPLAY = bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) or _start_xvfb()
os.environ.setdefault("QT_QPA_PLATFORM", "xcb" if os.environ.get("DISPLAY") else "offscreen")


def pytest_collection_modifyitems(config, items):
    if HAVE_DISPLAY:
        return
    skip = pytest.mark.skip(reason="no display and no Xvfb: GUI tests need one")
    for item in items:
        if "gui" in item.keywords and str(ROOT / "tests" / "app_desktop") in str(item.fspath):
            item.add_marker(skip)


@pytest.fixture(autouse=True)
def no_edit_warm_up(monkeypatch):
    """The edit warm-up (a background thread at the first selection) counts as done: it would
    otherwise run beside whichever test selects first, reading what that test patches.
    ``test_desktop_regrow`` checks it with this undone."""
    import threading

    from ramure.app import model

    monkeypatch.setattr(model, "_warm_up", [threading.Thread()])


@pytest.fixture(scope="session")
def artifacts():
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS


@pytest.fixture
def make_window(qtbot, tmp_path):
    """``make_window(source=HONDA, n=6)`` -> a shown MainWindow with its plant drawn."""
    from PySide6.QtCore import QSettings

    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.window import MainWindow
    from ramure.app.model import Explorer

    make_application()
    windows = []

    def make(source=HONDA, n=6, seed=0):
        settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
        window = MainWindow(Explorer(str(source), n=n, seed=seed), settings=settings, ask=False)
        qtbot.addWidget(window)
        window.resize(1200, 800)
        window.show()
        qtbot.waitExposed(window)
        window.activateWindow()
        qtbot.waitUntil(window.isActiveWindow, timeout=3000)
        settle(qtbot, window)
        windows.append(window)
        return window

    yield make
    for window in windows:
        window.dirty = False
        window.close()
