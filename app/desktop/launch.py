"""The ``python -m ramure.app.desktop`` command: open the window on a grammar.

``--screenshot PATH`` saves a PNG of the whole window once the plant is
drawn; ``--quit-after SECONDS`` closes it after that many seconds (both
for headless runs under Xvfb, e.g. ``make run`` without a display).
A grammar that cannot be read or parsed is reported in one line, exit 2.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import sys
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    from PySide6.QtWidgets import QApplication

DEFAULT_GRAMMAR = "grammars/honda_sympodial.lsys"
FIRST_COMPILE = (
    "ramure desktop: compiling the plant kernels (first run after an install or an upgrade, "
    "10-25 s, once; later runs load them from numba's cache)"
)


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m ramure.app.desktop``."""
    p = argparse.ArgumentParser(
        prog="python -m ramure.app.desktop", description="The Ramure desktop explorer: edit, pick, regenerate, browse variants."
    )
    p.add_argument(
        "grammar", nargs="?", default=DEFAULT_GRAMMAR, help="an .lsys grammar file or a shipped grammar's name (honda_sympodial)"
    )
    p.add_argument("-n", type=int, default=None, help="derivation steps (default: the grammar's n:)")
    p.add_argument("--seed", type=int, default=None, help="random seed (default: the grammar's #seed, else 0)")
    p.add_argument("--screenshot", metavar="PATH", help="save a PNG of the window once the plant is drawn")
    p.add_argument("--quit-after", metavar="SECONDS", type=float, default=None, help="close the window after this many seconds")
    return p


def one_malloc_arena() -> bool:
    """Ask glibc's malloc to serve every thread from one arena (``mallopt(M_ARENA_MAX, 1)``);
    False where the C library has no ``mallopt`` (not glibc), or refuses.

    The desktop makes each plant version in its worker thread and frees the version before it
    in the GUI thread.  With an arena per thread (glibc's default, up to 8 per core), what one
    thread frees is not reused by the other, so each edit mapped fresh pages.  On Honda n = 17
    (alternated, 3 runs each) the window held 645-648 MB after a regrow and its undo and
    694-698 MB after five edits; with one arena 636-642 and 680-681 MB; the edits' times to
    the frame stayed within this machine's noise.  Called before the worker and OpenGL's
    threads start; arenas made before keep serving their threads.  Same as
    ``MALLOC_ARENA_MAX=1``.
    """
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt if name else None
    except (OSError, AttributeError):
        return False
    if mallopt is None:
        return False
    M_ARENA_MAX = -8
    return bool(mallopt(M_ARENA_MAX, 1))


def make_application(argv: list[str] | None = None) -> QApplication:
    """The QApplication (created once), with the GL format pyvistaqt needs set first, and
    one malloc arena for all of its threads (:func:`one_malloc_arena`)."""
    from PySide6.QtWidgets import QApplication

    from ramure.app.desktop.qt_fix import protect_none

    protect_none()
    app = QApplication.instance()
    if app is None:
        one_malloc_arena()
        app = QApplication(list(argv or sys.argv[:1]))
        from ramure.app.desktop.view.native_view import native_windows

        if not native_windows():  # pyvistaqt's QOpenGLWidget fallback only (6-12 MB less otherwise)
            import pyvistaqt  # noqa: F401  (loaded before the first window, as before)

        app.setApplicationName("Ramure")
        app.setOrganizationName("Ramure")
    return cast("QApplication", app)  # a QApplication: this function is what creates it


def main(argv: list[str] | None = None) -> int:
    """Open the window on the grammar named in ``argv``; returns the exit code (2: a grammar that cannot be read)."""
    args = build_parser().parse_args(argv)
    import ramure.grammars
    from ramure.app.model import Explorer
    from ramure.errors import RamureError

    path = ramure.grammars.resolve(args.grammar)  # a file, or a shipped name like honda_sympodial
    if not path.is_file():
        print(
            f"ramure desktop: no grammar file or shipped grammar named {args.grammar!r} "
            "(ramure.grammars.names() lists the shipped ones)",
            file=sys.stderr,
        )
        return 2
    from ramure.jit import on_first_compile

    on_first_compile(lambda _name: print(FIRST_COMPILE, file=sys.stderr, flush=True))
    try:
        # a file named on the command line runs as `ramure derive` runs it: an .lpy's code too
        explorer = Explorer(path, n=args.n, seed=args.seed, run_code=True)
    except (OSError, RamureError) as exc:
        print(f"ramure desktop: {exc}", file=sys.stderr)
        return 2
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY") and not os.environ.get("QT_QPA_PLATFORM"):
        print("ramure desktop: no display (set DISPLAY, or run under xvfb-run)", file=sys.stderr)
        return 2
    app = make_application()
    from PySide6.QtCore import QTimer

    from ramure.app.desktop.window import MainWindow

    headless = args.screenshot is not None or args.quit_after is not None
    window = MainWindow(explorer, ask=not headless)
    screen = app.primaryScreen()
    if screen is not None:  # a small screen gets the compact layout (the 3D view keeps most room)
        area = screen.availableGeometry()
        window.fit_screen(area.width(), area.height())
    window.show()
    sys.excepthook = window.report_unexpected  # a bug in a slot shows a dialog, the window stays
    if args.screenshot:

        def shoot() -> None:
            window.controller.wait_idle()
            out = pathlib.Path(args.screenshot)
            out.parent.mkdir(parents=True, exist_ok=True)
            window.grab_window().save(str(out), "PNG")  # type: ignore[call-overload]  # PySide6's stub wants bytes; the binding refuses them, takes str
            print(f"wrote {out}")

        QTimer.singleShot(300, shoot)
    if args.quit_after is not None:
        QTimer.singleShot(int(max(args.quit_after, 0.4) * 1000), window.close)
    return app.exec()
