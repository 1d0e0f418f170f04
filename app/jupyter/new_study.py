"""The notebook's "New study…": a study made from the explorer's variants, and how to serve it.

:class:`NewStudyPanel` (under the Variants tab) asks for a folder, a title and a time budget and
calls :func:`ramure.app.new_study.new_study`, the function the desktop calls too; it then shows
the ``ramure study serve`` command to run in a terminal.  ``ex.new_study(folder)`` does the same
from code.
"""

from __future__ import annotations

import html
import os
from typing import TYPE_CHECKING

import ipywidgets as W

from ramure.app.jupyter._ui import MessageLine, button
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.app.new_study import NewStudy


class NewStudyPanel:
    """Folder, title and budget of a new study made of the explorer's 27 picks."""

    def __init__(self, app: NotebookExplorer) -> None:
        self.app = app
        self.made: NewStudy | None = None
        self.folder = W.Text(placeholder="a new folder, e.g. studies/honda", description="folder", layout=W.Layout(width="360px"))
        self.title = W.Text(placeholder="default: the folder's name", description="title", layout=W.Layout(width="300px"))
        self.minutes = W.BoundedFloatText(value=30.0, min=1.0, max=1440.0, description="minutes", layout=W.Layout(width="160px"))
        self.add_to = W.Checkbox(value=False, description="add to the study in this folder (one more part)", indent=False)
        self.create_button = button(
            "New study…", lambda: self.create(), style="info", tooltip="make a study of these 27 picks (pictures drawn once)"
        )
        self.message = MessageLine()
        self.command = W.HTML()
        self.widget = W.VBox(
            [
                W.HTML("<b>A study of these variants</b>"),
                W.HBox([self.folder, self.title, self.minutes, self.create_button]),
                self.add_to,
                self.message.widget,
                self.command,
            ]
        )

    def create(
        self, folder: str | os.PathLike | None = None, name: str | None = None, add: bool | None = None
    ) -> NewStudy | None:
        """Make the study in ``folder`` (default: the folder box), or with ``add`` add these picks to
        the study already there; a refusal is shown, not raised."""
        from ramure.app.jupyter.view import RENDER_LOCK
        from ramure.app.new_study import add_to_study, new_study

        if folder is not None:
            self.folder.value = os.fspath(folder)
        if name is not None:
            self.title.value = name
        if add is not None:
            self.add_to.value = add
        try:
            exploration = self.app.variants.exploration
            if exploration is None:
                raise RamureError("explore the variants first (Variants: Explore variants); the study is made of the 27 picks")
            if not self.folder.value.strip():
                raise RamureError("give a folder for the study")
            with RENDER_LOCK:  # the pictures are drawn off-screen, like the thumbnails
                if self.add_to.value:
                    made = add_to_study(exploration, self.folder.value.strip())
                else:
                    made = new_study(
                        exploration,
                        self.folder.value.strip(),
                        name=self.title.value.strip() or None,
                        budget_minutes=self.minutes.value,
                    )
        except (RamureError, OSError) as exc:
            self.message.show(exc, "error")
            return None
        self.made = made
        done = "added to the study" if self.add_to.value else "study created"
        self.message.show(f"{done}: {made.db} ({made.grammar}, 27 pictures)", "info")
        self.command.value = (
            "Serve it to participants from a terminal (Ctrl+C stops it):"
            f"<pre style='margin:2px 0;user-select:all'>{html.escape(made.command)}</pre>"
        )
        return made
