"""A dock's 3D view made when the dock is first on screen, not when the window is built.

Each pyvistaqt ``QtInteractor`` is an OpenGL context with its frame buffers,
shaders and VTK renderer: about 7 MB under software OpenGL (llvmpipe) for
each of the Wood, Details and Defects docks, which sit in tabs many users
never open.  :class:`LazyView` takes the interactor's place in the dock's
layout and makes it when it is first on screen: at a ``showEvent`` (the
dock's tab raised), checked once the event loop has run, because the
window's first show shows every dock before the tab bars hide all but the
front one.  A panel that asks for :meth:`LazyView.plotter` earlier (a result
arriving for a dock still hidden) gets it made then: the panel's code is the
same either way.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QVBoxLayout, QWidget

if TYPE_CHECKING:
    from PySide6.QtGui import QShowEvent


class LazyView(QWidget):
    """Holds the view ``factory(parent)`` returns, made on first show or first use.

    ``setup(plotter)`` runs once, right after the view is made (e.g. click
    tracking).  ``factory`` may return the widget itself or an object whose
    ``interactor`` attribute is the widget (a pyvistaqt plotter, a test fake).
    """

    def __init__(
        self,
        factory: Callable[[QWidget], Any],
        setup: Callable[[Any], None] | None = None,
        min_height: int = 60,
        parent: QWidget | None = None,
    ) -> None:
        super().__init__(parent)
        self.box = QVBoxLayout(self)
        self.box.setContentsMargins(0, 0, 0, 0)
        self.setMinimumHeight(min_height)
        self._factory = factory
        self._setup = setup
        self._plotter: Any = None

    @property
    def made(self) -> bool:
        """Whether the view (and its OpenGL context) exists yet."""
        return self._plotter is not None

    def plotter(self) -> Any:
        """The view, made now if it was not yet."""
        if self._plotter is None:
            plotter = self._factory(self)
            self.box.addWidget(getattr(plotter, "interactor", plotter))
            self._plotter = plotter
            if self._setup is not None:
                self._setup(plotter)
        return self._plotter

    def showEvent(self, event: QShowEvent) -> None:  # noqa: N802 - Qt's name
        """First on screen: make the plotter once this show's events are done."""
        super().showEvent(event)
        if self._plotter is None:  # decide once the events of this show are done (see above)
            QTimer.singleShot(0, self, self._make_if_shown)

    def _make_if_shown(self) -> None:
        if self.isVisible() and not self.visibleRegion().isEmpty():
            self.plotter()
