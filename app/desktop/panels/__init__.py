"""The desktop's docks, one module per dock: grammar editor, constants, regeneration, variants
(gallery, PCA cloud, qualifier map and the :class:`~ramure.app.desktop.panels.variants.VariantsController`
behind them), wood, details, defects, architecture, string and cut graph.

A panel owns its widgets and what they show.  It reads and changes the plant only through the
:class:`~ramure.app.desktop.controller.Controller` (the shared Qt-free
:class:`~ramure.app.model.Explorer` behind one worker) and tells the window what happened with Qt
signals (``status``, ``refused``, ``select_requested``...) that the window connects.  A panel may
import Qt, the :mod:`~ramure.app.desktop.view` package (its own 3D views), the desktop's Qt-free
helpers (``controller``, ``state``, ``variants``, ``workers``), the rest of :mod:`ramure.app`
and the core packages; it never imports :mod:`~ramure.app.desktop.window` or
:mod:`~ramure.app.desktop.menus` and never calls a :class:`MainWindow` method
(``tests/app_desktop/test_desktop_rooms.py`` checks both).
"""
