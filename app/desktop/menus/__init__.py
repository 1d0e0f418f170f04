"""The desktop's menus and the windows they open: File (:mod:`~ramure.app.desktop.menus.files`),
Help, Study (participant screens, the analyst view, a new study from this exploration).

A menu module owns its actions, dialogs and windows.  It works on the plant through the
:class:`~ramure.app.desktop.controller.Controller` and on the docks it is handed (the editor, the
variants controller, the view), and tells the window what happened with Qt signals (``status``,
``refused``, ``saved``...) that the window connects.  It may import Qt, the
:mod:`~ramure.app.desktop.view` and :mod:`~ramure.app.desktop.panels` packages, the desktop's
Qt-free helpers, the rest of :mod:`ramure.app` and the core packages; it never imports
:mod:`~ramure.app.desktop.window` and never calls a :class:`MainWindow` method
(``tests/app_desktop/test_desktop_rooms.py`` checks both).
"""
