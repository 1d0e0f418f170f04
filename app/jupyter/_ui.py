"""Small widget helpers shared by the Jupyter panels: the message line, buttons, id lists.

>>> parse_ids("3, 7-9 12")
[3, 7, 8, 9, 12]
"""
from __future__ import annotations

import base64
import html
import re

import ipywidgets as W

from ramure.errors import ValueRefused

_COLORS = {"error": "#b00020", "info": "#1b5e20", "note": "#555"}


def message_html(text, kind="error") -> str:
    """``text`` as a coloured, pre-formatted block (keeps a grammar error's caret aligned)."""
    if not text:
        return ""
    return (f"<pre style='margin:2px 0;white-space:pre-wrap;font-size:12px;color:{_COLORS[kind]}'>"
            f"{html.escape(str(text))}</pre>")


class MessageLine:
    """An HTML line showing the last error or note; ``text`` is what it shows."""

    def __init__(self):
        self.widget = W.HTML()
        self.text = ""
        self.kind = "info"

    def show(self, text, kind="info"):
        self.text, self.kind = str(text), kind
        self.widget.value = message_html(self.text, kind)

    def clear(self):
        self.show("", "info")


def button(description, handler, tooltip="", style="", width="auto", icon=""):
    """A button calling ``handler()`` (the clicked button is not passed on)."""
    b = W.Button(description=description, tooltip=tooltip or description, button_style=style, icon=icon,
                 layout=W.Layout(width=width))
    b.on_click(lambda _b: handler())
    return b


def on_value(widget, handler):
    """Call ``handler(new_value)`` whenever ``widget.value`` changes."""
    widget.observe(lambda change: handler(change["new"]), names="value")
    return widget


def parse_ids(text) -> list[int]:
    """Leaf ids typed as ``"12, 40-45 51"`` (commas or spaces, ``a-b`` ranges inclusive)."""
    ids = []
    for token in re.split(r"[\s,;]+", str(text).strip()):
        if not token:
            continue
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", token)
        if m is None:
            raise ValueRefused(f"'{token}' is not a leaf id or a range like 40-45")
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) else a
        if b < a:
            raise ValueRefused(f"range '{token}' goes backwards")
        if b - a > 100_000:
            raise ValueRefused(f"range '{token}' is too long")
        ids.extend(range(a, b + 1))
    return ids


def short_list(values, limit=12) -> str:
    """``"1, 2, 3, … (40 in all)"`` for long lists."""
    values = list(values)
    text = ", ".join(map(str, values[:limit]))
    return text + (f", … ({len(values)} in all)" if len(values) > limit else "")


def png_image(data=b"", width=None):
    """An ``ipywidgets.Image`` holding PNG bytes."""
    layout = W.Layout(width=f"{width}px") if width else W.Layout()
    return W.Image(value=data, format="png", layout=layout)


def png_tag(data, width, title="") -> str:
    """An ``<img>`` holding PNG bytes as a data URI (stays in a saved notebook)."""
    src = base64.b64encode(data).decode("ascii")
    return (f"<img title='{html.escape(str(title))}' src='data:image/png;base64,{src}' "
            f"style='width:{int(width)}px;margin:1px'>")


def side_by_side(images, captions=(), width=260):
    """PNG pictures in a row, each over its caption, as an IPython ``HTML`` object
    (e.g. a fruit before and after an edit)."""
    from IPython.display import HTML

    captions = list(captions) + [""] * (len(images) - len(captions))
    cells = "".join(f"<figure style='margin:0 6px;text-align:center'>{png_tag(data, width, text)}"
                    f"<figcaption style='font-size:12px'>{html.escape(str(text))}</figcaption></figure>"
                    for data, text in zip(images, captions) if data)
    return HTML(f"<div style='display:flex;flex-wrap:wrap;align-items:flex-end'>{cells}</div>")
