"""Shared helpers of the desktop tests (a uniquely named module: other test folders have a conftest)."""

from __future__ import annotations

import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "tests" / "artifacts"
HONDA = ROOT / "grammars" / "honda_sympodial.lsys"
STOCHASTIC = ROOT / "grammars" / "stochastic_plant.lsys"


def settle(qtbot, window, timeout=60.0):
    """Wait until every model job is delivered and the view has painted.

    A liveness bound, not a speed test: a large plant's regrow took over 20 s once in a
    clean-clone run on the 2 cores shared with two other builds (speed is benchmarked)."""
    assert window.controller.wait_idle(timeout), "a model job did not finish in time"
    qtbot.waitUntil(lambda: not window.variants.busy(), timeout=int(timeout * 1000))
    window.view.redraw(now=True)
    qtbot.wait(10)


class BarePlotter:
    """What PlantActors needs of a plotter: a renderer (never drawn here)."""

    def __init__(self) -> None:
        from vtkmodules.vtkRenderingCore import vtkRenderer

        self.renderer = vtkRenderer()


def show_model_plant(actors, ex) -> None:
    """What the view gives PlantActors: a shallow copy of the model's mesh with colours, keyed by it."""
    import numpy as np

    mesh = ex.mesh.copy(deep=False)
    mesh.cell_data["rgb"] = np.zeros((mesh.n_cells, 3), np.uint8)
    actors.show(mesh, ex.skeleton, key=ex.mesh)
