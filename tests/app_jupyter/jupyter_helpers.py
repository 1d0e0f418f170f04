"""Helpers for the Jupyter front-end tests (a unique module name: other test folders have a conftest too)."""

from __future__ import annotations

import io
import os
from unittest import mock
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
HONDA = str(ROOT / "grammars" / "honda_sympodial.lsys")


def red_pixels(png) -> int:
    """Pixels of the selection red (255, 0, 0 shaded) in a PNG."""
    from matplotlib.image import imread

    rgb = imread(io.BytesIO(png), format="png")[..., :3]
    return int(np.sum((rgb[..., 0] > 0.6) & (rgb[..., 1] < 0.15) & (rgb[..., 2] < 0.15)))


def execute(nb, env=None, timeout=180):
    """Run notebook ``nb`` in a fresh python3 kernel at the repository root (``env`` reaches the kernel)."""
    import nbclient

    with mock.patch.dict(os.environ, env or {}):  # the kernel inherits them; restored after
        nbclient.NotebookClient(nb, kernel_name="python3", timeout=timeout, resources={"metadata": {"path": str(ROOT)}}).execute()
    return nb
