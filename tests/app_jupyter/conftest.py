"""Fixtures for the Jupyter front-end tests (no kernel: widgets are built and driven directly)."""

from __future__ import annotations

import pytest

pytest.importorskip("ipywidgets")

from jupyter_helpers import HONDA  # noqa: E402


@pytest.fixture
def explorer():
    from ramure.app.jupyter import NotebookExplorer

    return NotebookExplorer(HONDA, n=5, view="static", size=(200, 200), cache=False)


@pytest.fixture(autouse=True)
def no_edit_warm_up(monkeypatch):
    """The edit warm-up (a background thread at the first selection) counts as done: it would
    otherwise run beside whichever test selects first.  ``test_jupyter_widgets`` checks it."""
    import threading

    from ramure.app import model

    monkeypatch.setattr(model, "_warm_up", [threading.Thread()])
