"""The Ramure desktop explorer (PySide6 + pyvistaqt).

``python -m ramure.app.desktop grammars/honda_sympodial.lsys`` opens the window;
``--screenshot out/window.png --quit-after 1`` saves a picture of it and
quits (what ``make run`` does without a display).

Modules: :mod:`~ramure.app.desktop.window` (the main window),
:mod:`~ramure.app.desktop.controller` (the model, changed by one worker thread),
:mod:`~ramure.app.desktop.state` (Qt-free helpers over the model),
:mod:`~ramure.app.desktop.workers` (job queue, cancellable tasks),
:mod:`~ramure.app.desktop.editor`, :mod:`~ramure.app.desktop.constants_panel`,
:mod:`~ramure.app.desktop.view` (3D view and picking), :mod:`~ramure.app.desktop.regen_panel`,
:mod:`~ramure.app.desktop.files` (File menu), the docks (:mod:`~ramure.app.desktop.string_dock`,
:mod:`~ramure.app.desktop.cut_graph`, :mod:`~ramure.app.desktop.gallery`,
:mod:`~ramure.app.desktop.pca_cloud`), :mod:`~ramure.app.desktop.variants` (Qt-free bridge to
:mod:`ramure.metrics`) and :mod:`~ramure.app.desktop.variants_panel`, :mod:`~ramure.app.desktop.thumbnails`,
:mod:`~ramure.app.desktop.study` (participant screens) and :mod:`~ramure.app.desktop.analyst`,
:mod:`~ramure.app.desktop.qt_fix` (a guard against a PySide6 6.12 refcount bug on
Python 3.11) and :mod:`~ramure.app.desktop.launch` (the command).
Qt is imported only inside this package.
"""

from ramure.app.desktop.qt_fix import skip_source_scan as _skip_source_scan

_skip_source_scan()  # before anything else is imported: PySide6 would keep every module's source


def main(argv: list[str] | None = None) -> int:
    """Run the desktop explorer (see :mod:`ramure.app.desktop.launch`)."""
    from ramure.app.desktop.launch import main as _main

    return _main(argv)
