"""Small widget helpers shared by the Jupyter panels: the message line, buttons, observers.

Every callback registered through :func:`button`, :func:`observe` or :func:`on_value` runs on the
kernel's main thread (:mod:`ramure.app.jupyter.mainthread`).  Typed leaf ids are read by
:func:`ramure.app.ids.parse_ids`, shared with the desktop.

>>> short_list(range(1, 30), limit=3)
'1, 2, 3, … (29 in all)'
"""

from __future__ import annotations

import base64
from collections.abc import Callable
import html

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
