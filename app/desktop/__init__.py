"""The Ramure desktop explorer (PySide6 + pyvistaqt).

``python -m app.desktop grammars/honda_sympodial.lsys`` opens the window;
``--screenshot out/window.png --quit-after 1`` saves a picture of it and
quits (what ``make run`` does without a display).

Modules: :mod:`~app.desktop.window` (the main window),
:mod:`~app.desktop.controller` (the model, changed by one worker thread),
:mod:`~app.desktop.state` (Qt-free helpers over the model),
:mod:`~app.desktop.workers` (job queue, cancellable tasks),
:mod:`~app.desktop.editor`, :mod:`~app.desktop.constants_panel`,
:mod:`~app.desktop.view` (3D view and picking), :mod:`~app.desktop.regen_panel`,
:mod:`~app.desktop.files` (File menu), the docks (:mod:`~app.desktop.string_dock`,
:mod:`~app.desktop.cut_graph`, :mod:`~app.desktop.gallery`,
:mod:`~app.desktop.pca_cloud`), :mod:`~app.desktop.variants` (Qt-free bridge to
:mod:`metrics`) and :mod:`~app.desktop.variants_panel`, :mod:`~app.desktop.thumbnails`,
:mod:`~app.desktop.study` (participant screens) and :mod:`~app.desktop.analyst`,
:mod:`~app.desktop.qt_fix` (a guard against a PySide6 6.12 refcount bug on
Python 3.11) and :mod:`~app.desktop.launch` (the command).
Qt is imported only inside this package.
"""


def main(argv=None):
    """Run the desktop explorer (see :mod:`app.desktop.launch`)."""
    from app.desktop.launch import main as _main

    return _main(argv)
