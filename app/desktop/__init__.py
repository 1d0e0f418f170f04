"""The Ramure desktop explorer (PySide6 + pyvistaqt).

``python -m ramure.app.desktop grammars/honda_sympodial.lsys`` opens the window;
``--screenshot out/window.png --quit-after 1`` saves a picture of it and
quits (what ``make run`` does without a display).

Rooms: :mod:`~ramure.app.desktop.window` (the main window, which only assembles the rest),
:mod:`~ramure.app.desktop.panels` (one module per dock),
:mod:`~ramure.app.desktop.view` (the 3D scene, its actors and picking) and
:mod:`~ramure.app.desktop.menus` (File, Help and Study menus and their windows).  Beside them
the Qt-free or model-side helpers: :mod:`~ramure.app.desktop.controller` (the model, changed by
one worker thread), :mod:`~ramure.app.desktop.state` (Qt-free helpers over the model),
:mod:`~ramure.app.desktop.variants` (Qt-free bridge to :mod:`ramure.metrics`),
:mod:`~ramure.app.desktop.workers` (job queue, cancellable tasks),
:mod:`~ramure.app.desktop.qt_fix` (a guard against a PySide6 6.12 refcount bug on Python 3.11)
and :mod:`~ramure.app.desktop.launch` (the command).  Panels, view and menus never import the
window nor call its methods: they emit Qt signals the window connects.
Qt is imported only inside this package.
"""

from ramure.app.desktop.qt_fix import skip_source_scan as _skip_source_scan

_skip_source_scan()  # before anything else is imported: PySide6 would keep every module's source


def main(argv: list[str] | None = None) -> int:
    """Run the desktop explorer (see :mod:`ramure.app.desktop.launch`)."""
    from ramure.app.desktop.launch import main as _main

    return _main(argv)
