"""What the docks share: their outer column, their number boxes and their own 3D views.

Each dock used to build these by hand (the Wood, Constants and Details docks each had a
spin-box builder, three docks each a plotter maker, eleven docks their own margins); one
spelling here keeps their look the same.
"""

from __future__ import annotations

from typing import Any

from PySide6.QtWidgets import QDoubleSpinBox, QLayout, QVBoxLayout, QWidget

#: The docks' margin (pixels) around their contents: tight, the dock's title bar frames them.
DOCK_MARGIN = 2


def dock_column(widget: QWidget, *parts: QWidget | QLayout, margin: int = DOCK_MARGIN) -> QVBoxLayout:
    """The dock's outer column on ``widget`` with the docks' margin, holding ``parts`` in order
    (the caller adds what stretches)."""
    layout = QVBoxLayout(widget)
    layout.setContentsMargins(margin, margin, margin, margin)
    for part in parts:
        if isinstance(part, QLayout):
            layout.addLayout(part)
        else:
            layout.addWidget(part)
    return layout


def number_box(
    low: float,
    high: float,
    decimals: int,
    *,
    value: float | None = None,
    name: str = "",
    suffix: str = "",
    step: float = 0.0,
    width: int = 0,
    live: bool = True,
) -> QDoubleSpinBox:
    """A spin box for a decimal number in ``[low, high]``.

    ``name`` is its Qt object name (tests and style sheets find it), ``step`` what an arrow
    adds (0: Qt's 1), ``width`` a maximum width (0: none).  ``live=False`` sends a value only
    when typing ends (no keyboard tracking) and speeds up a held arrow: the constants' boxes,
    where each value re-derives the plant."""
    box = QDoubleSpinBox()
    if name:
        box.setObjectName(name)
    if width:
        box.setMaximumWidth(width)
    box.setRange(low, high)
    if step:
        box.setSingleStep(step)
    box.setDecimals(decimals)
    if value is not None:
        box.setValue(value)
    if suffix:
        box.setSuffix(suffix)
    if not live:
        box.setKeyboardTracking(False)
        box.setAccelerated(True)
    return box


def dock_plotter(parent: QWidget, look: str = "plain") -> Any:
    """A dock's own 3D view (a native window on X11, see
    :func:`~ramure.app.desktop.view.native_view.make_plotter`).

    ``look``: ``"plain"`` (no anti-aliasing, renders only when asked: the Wood dock's large
    grids), ``"scene"`` (the same, lit and framed like the main view) or ``"white"`` (VTK's
    defaults on a white background: one small fruit).  VTK loads here, when the dock is first
    on screen, not with the window."""
    from ramure.app.desktop.view.native_view import make_plotter

    if look == "white":
        plotter = make_plotter(parent)
        plotter.set_background("white")
        return plotter
    if look not in ("plain", "scene"):
        raise ValueError(f"unknown dock look {look!r}: plain, scene or white")
    plotter = make_plotter(parent, auto_update=False, multi_samples=0)
    if look == "scene":
        from ramure.app.desktop.view import scene

        scene.apply_look(plotter)
    return plotter
