"""The Ramure desktop explorer (PySide6 + pyvistaqt).

``python -m app.desktop grammars/honda_sympodial.lsys`` opens the window;
``--screenshot out/window.png --quit-after 1`` saves a picture of it and
quits (what ``make run`` does without a display).

Modules: :mod:`~app.desktop.window` (the main window),
:mod:`~app.desktop.controller` (the model in a worker thread),
:mod:`~app.desktop.state` (Qt-free helpers over the model),
:mod:`~app.desktop.workers`, :mod:`~app.desktop.editor`,
:mod:`~app.desktop.constants_panel`, :mod:`~app.desktop.view`,
:mod:`~app.desktop.regen_panel`, the docks (:mod:`~app.desktop.string_dock`,
:mod:`~app.desktop.cut_graph`, :mod:`~app.desktop.gallery`,
:mod:`~app.desktop.pca_cloud`), :mod:`~app.desktop.variants` and
:mod:`~app.desktop.variants_panel` (metrics), :mod:`~app.desktop.study`
(participant and analyst screens), :mod:`~app.desktop.launch` (the command).
Qt is imported only inside this package.
"""


def main(argv=None):
    """Run the desktop explorer (see :mod:`app.desktop.launch`)."""
    from app.desktop.launch import main as _main

    return _main(argv)
