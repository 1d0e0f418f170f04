"""Small widget helpers shared by the Jupyter panels: the message line, buttons, observers.

Every callback registered through :func:`button`, :func:`observe` or :func:`on_value` runs on the
kernel's main thread (:mod:`ramure.app.jupyter.mainthread`).  Typed leaf ids are read by
:func:`ramure.app.ids.parse_ids`, shared with the desktop.

>>> short_list(range(1, 30), limit=3)
'1, 2, 3, … (29 in all)'
"""

from __future__ import annotations

import base64
from collections.abc import Callable, Sequence
import html
from typing import Any

import ipywidgets as W

from ramure.app.jupyter.mainthread import main_thread_callback, on_main

_COLORS = {"error": "#b00020", "info": "#1b5e20", "note": "#555"}


def message_html(text, kind: str = "error") -> str:
    """``text`` as a coloured, pre-formatted block (keeps a grammar error's caret aligned)."""
    if not text:
        return ""
    return f"<pre style='margin:2px 0;white-space:pre-wrap;font-size:12px;color:{_COLORS[kind]}'>{html.escape(str(text))}</pre>"


class MessageLine:
    """An HTML line showing the last error or note; ``text`` is what it shows."""

    def __init__(self) -> None:
        self.widget = W.HTML()
        self.text = ""
        self.kind = "info"

    def show(self, text, kind: str = "info") -> None:
        self.text, self.kind = str(text), kind
        self.widget.value = message_html(self.text, kind)

    def clear(self) -> None:
        self.show("", "info")


def button(description, handler, tooltip: str = "", style: str = "", width: str = "auto", icon: str = ""):
    """A button calling ``handler()`` on the kernel's main thread (the clicked button is not passed on)."""
    b = W.Button(
        description=description, tooltip=tooltip or description, button_style=style, icon=icon, layout=W.Layout(width=width)
    )
    b.on_click(lambda _b: on_main(handler))
    return b


def observe(widget, handler, names: str = "value"):
    """Call ``handler(change)`` on the kernel's main thread whenever ``widget``'s trait ``names`` changes
    (:mod:`ramure.app.jupyter.mainthread`: widget messages may arrive on a subshell thread)."""
    widget.observe(main_thread_callback(handler), names=names)
    return widget


def on_value(widget, handler):
    """Call ``handler(new_value)`` on the kernel's main thread whenever ``widget.value`` changes."""
    return observe(widget, lambda change: handler(change["new"]))


class Breadcrumbs:
    """A list of the rows under an opened element, with a breadcrumb above it: *Open* goes down
    into the chosen row, *Up* back one level, *Top* to the start, *Select* selects the row's
    leaves with the selection panel's mode.  The derivation-tree and the architecture browsers
    are two of them.

    :attr:`path` holds the opened rows (empty: the top).  A subclass says what a row is:
    :meth:`can_open` (whether it has rows under it), :meth:`leaves_of` (what *Select* selects)
    and :meth:`fill` (the breadcrumb and the rows under :attr:`path`); :attr:`WHAT` names the
    list in its messages.
    """

    WHAT = "list"

    def __init__(self, app: Any, open_help: str, select_help: str, below: Sequence[W.Widget] = ()) -> None:
        self.app = app
        self.path: list = []
        self.crumbs = W.HTML()
        self.rows = W.Select(options=[], rows=12, layout=W.Layout(width="98%"))
        self.buttons = [
            button("Open ▸", self.open_selected, open_help),
            button("◂ Up", self.up),
            button("Top", self.top),
            button("Select", self.select_selected, select_help, style="info"),
        ]
        self.widget = W.VBox([self.crumbs, self.rows, W.HBox(self.buttons), *below])
        self._version: int | None = None

    def can_open(self, row: Any) -> bool:
        """Whether ``row`` has rows under it."""
        raise NotImplementedError

    def leaves_of(self, row: Any) -> list[int]:
        """The history leaves *Select* selects for ``row``."""
        raise NotImplementedError

    def fill(self) -> None:
        """Show the breadcrumb of :attr:`path` and list the rows under its end."""
        raise NotImplementedError

    def open(self, row: Any) -> None:
        """Go down into ``row`` when it has rows under it: the breadcrumb grows by one."""
        if self.can_open(row):
            self.path.append(row)
            self.fill()

    def open_selected(self) -> None:
        """Open the row chosen in the list (the Open button)."""
        if self.rows.value is not None:
            self.open(self.rows.value)

    def up(self) -> None:
        """Go back up one level of the breadcrumb."""
        if self.path:
            self.path.pop()
            self.fill()

    def top(self) -> None:
        """Go back to the top of the breadcrumb."""
        self.path = []
        self.fill()

    def select(self, row: Any) -> None:
        """Select :meth:`leaves_of` ``row`` in the selection panel's mode (replace, add...)."""
        self.app.select(self.leaves_of(row), self.app.selection_panel.mode.value)

    def select_selected(self) -> None:
        """Select the row chosen in the list (the Select button); without one, the message line
        says to choose one."""
        if self.rows.value is None:
            self.app.message.show(f"choose a row in the {self.WHAT} first", "note")
            return
        self.select(self.rows.value)


def short_list(values, limit=12) -> str:
    """``"1, 2, 3, … (40 in all)"`` for long lists."""
    values = list(values)
    text = ", ".join(map(str, values[:limit]))
    return text + (f", … ({len(values)} in all)" if len(values) > limit else "")


def png_image(data=b"", width=None):
    """An ``ipywidgets.Image`` holding PNG bytes, hidden while it holds none (an empty image
    shows the browser's broken-image icon).

    >>> image = png_image(); image.layout.display
    'none'
    >>> image.value = b"\\x89PNG"; image.layout.display is None
    True
    """
    layout = W.Layout(width=f"{width}px") if width else W.Layout()
    image = W.Image(value=data, format="png", layout=layout)

    def show_when_filled(change=None) -> None:
        image.layout.display = None if image.value else "none"

    show_when_filled()
    image.observe(show_when_filled, names="value")  # a layout only: no need for the main thread
    return image


def png_tag(data, width, title: str = "") -> str:
    """An ``<img>`` holding PNG bytes as a data URI (stays in a saved notebook)."""
    src = base64.b64encode(data).decode("ascii")
    return f"<img title='{html.escape(str(title))}' src='data:image/png;base64,{src}' style='width:{int(width)}px;margin:1px'>"


def side_by_side(images, captions=(), width=260):
    """PNG pictures in a row, each over its caption, as an IPython ``HTML`` object
    (e.g. a fruit before and after an edit)."""
    from IPython.display import HTML

    captions = list(captions) + [""] * (len(images) - len(captions))
    cells = "".join(
        f"<figure style='margin:0 6px;text-align:center'>{png_tag(data, width, text)}"
        f"<figcaption style='font-size:12px'>{html.escape(str(text))}</figcaption></figure>"
        for data, text in zip(images, captions)
        if data
    )
    return HTML(f"<div style='display:flex;flex-wrap:wrap;align-items:flex-end'>{cells}</div>")


#: Shown with a widget so that a saved notebook reopened without a kernel shows a picture:
#: JupyterLab then has no widget model and writes "Error displaying widget: model not found".
#: The rules hide this fallback while the widget above it is live, and hide that error line
#: (the widget output in its error state) when the picture is all there is to show.
FALLBACK_CSS = (
    ".jp-OutputArea-child:has(.widget-box) + .jp-OutputArea-child:has(.ramure-fallback){display:none}"
    ".jp-OutputArea-child:has(> .jp-OutputArea-output.jupyter-widgets)"
    ":has(+ .jp-OutputArea-child .ramure-fallback){display:none}"
)


def fallback_bundle(html_body: str, png: bytes | None = None) -> dict:
    """The mime bundle of a static fallback: ``html_body`` (pictures as data URIs) in a
    ``ramure-fallback`` block with :data:`FALLBACK_CSS`, and ``png`` for viewers without HTML."""
    bundle = {"text/html": f"<div class='ramure-fallback'><style>{FALLBACK_CSS}</style>{html_body}</div>"}
    if png:
        bundle["image/png"] = base64.b64encode(png).decode("ascii")
    return bundle


class Fallback:
    """A widget shown with a static fallback output right after it (see :data:`FALLBACK_CSS`).

    ``picture()`` returns ``(html_body, png)``; :meth:`update` re-sends it into the same
    output (a ``display_id``), so a notebook saved later keeps the latest picture.
    """

    def __init__(
        self, widget: W.Widget, picture: Callable[[], tuple[str, bytes | None]], text: str | Callable[[], str] = ""
    ) -> None:
        self.widget = widget
        self.picture = picture
        self.text = text
        self.handle = None

    def _ipython_display_(self) -> None:
        from IPython.display import display

        plain = self.text() if callable(self.text) else self.text
        display({**self.widget._repr_mimebundle_(), "text/plain": plain}, raw=True)
        self.handle = display(fallback_bundle(*self.picture()), raw=True, display_id=True)

    def update(self) -> None:
        """Send the current picture to the fallback output (nothing before it is displayed)."""
        if self.handle is not None:
            self.handle.update(fallback_bundle(*self.picture()), raw=True)
