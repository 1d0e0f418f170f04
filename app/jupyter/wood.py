"""The Wood tab: volumetric wood of a species or of the explorer's plant, with a cut picture.

The notebook counterpart of the desktop's Wood dock (:mod:`ramure.gmap.organs.wood`): choose a
species and years, tick *from the plant* to grow the wood of the plant shown above (its trunk
and branches of every order, ages from the derivation steps), press *Grow*; the picture shows the wood
cut across at the chosen height (a VTK slice, seen from above), with pith, rings, heartwood, sapwood, bark and
knots in their colours.  Moving the height re-cuts the grown wood without growing it again.

>>> from ramure.app.jupyter.wood import WoodTab
>>> tab = WoodTab(None)
>>> tab.years.value = 3; tab.grow()
>>> tab.facts.value.startswith("<small>")
True
"""

from __future__ import annotations

import os
import tempfile
from typing import TYPE_CHECKING

import ipywidgets as W

from ramure.app.jupyter._ui import button, on_value, png_image
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.gmap.organs.wood import Wood
    import pyvista as pv
    from ramure.app.jupyter.explorer import NotebookExplorer


class WoodTab:
    """Species, years, *from the plant*, Grow, a cut height and the cut picture."""

    def __init__(self, app: NotebookExplorer, size: tuple[int, int] = (420, 420)) -> None:
        from ramure.gmap.organs.wood import SPECIES

        self.app = app
        self.size = size
        self.wood: Wood | None = None
        self.grid: pv.UnstructuredGrid | None = None
        self.species = W.Dropdown(options=sorted(SPECIES), value="pine", description="species")
        self.years = W.BoundedIntText(value=8, min=1, max=40, description="years")
        self.from_plant = W.Checkbox(value=False, description="from the plant", indent=False)
        self.height = W.FloatSlider(value=0.3, min=0.0, max=1.0, step=0.01, description="cut at", readout_format=".0%")
        on_value(self.height, lambda _v: self.show_cut())
        self.facts = W.HTML("<small>Choose a species and years, press Grow: the cut appears here.</small>")
        self.picture = png_image(width=size[0])
        self.widget = W.VBox(
            [
                W.HBox([self.species, self.years, self.from_plant, button("Grow", self.grow)]),
                self.height,
                self.facts,
                self.picture,
            ]
        )

    def grow(self) -> None:
        """Grow the wood from the widgets' values, then cut it."""
        from ramure.gmap.organs import wood as W_

        try:
            if self.from_plant.value and self.app is not None:
                model = self.app.model
                d = model.derivation
                self.wood = W_.from_skeleton(
                    model.skeleton, self.years.value, species=self.species.value, leaf_steps=d.tree.step, steps=d.n
                )
            else:
                self.wood = W_.grow_wood(self.species.value, self.years.value)
        except RamureError as err:
            self.facts.value = f"<small style='color:#b00020'>refused: {err}</small>"
            return
        self.grid = W_.smooth_grid(self.wood, W_.to_grid(self.wood))  # round rings in the picture
        gm = self.wood.gm
        counts = ", ".join(f"{v} {k}" for k, v in self.wood.tissue_counts().items() if v)
        knots = self.wood.knot_counts()
        self.facts.value = (
            f"<small>{gm.n_darts:,} darts, {gm.n_volumes:,} volumes ({counts}); "
            f"knots: {knots['live']} live, {knots['dead']} dead"
            f"{W_.orders_text(self.wood.knot_orders(), gm.meta.get('left_out'))}</small>"
        )
        self.show_cut()

    def cut(self) -> tuple[pv.DataSet, float, dict]:
        """The cross-section of the grown wood at the chosen height, and its rings and knots."""
        from ramure.gmap.organs.wood import cut_facts

        if self.grid is None:
            raise RamureError("grow a wood first")
        lo, hi = self.grid.bounds[4], self.grid.bounds[5]
        z = lo + self.height.value * (hi - lo)
        part = self.grid.slice(normal="z", origin=(0.0, 0.0, z))
        empty = {"rings": 0, "knots": 0, "live_knots": 0, "dead_knots": 0}
        return part, z, (cut_facts(part) if part.n_cells else empty)

    def show_cut(self) -> None:
        """Render the cut to the picture (off-screen)."""
        if self.grid is None:
            return
        from ramure.app.commands.wood import render_wood

        part, z, facts = self.cut()
        if part.n_cells == 0:
            self.picture.value = b""
            return
        fd, path = tempfile.mkstemp(suffix=".png")
        os.close(fd)
        try:
            render_wood(
                part,
                path,
                size=self.size,
                look=(0.0, -0.02, 1.0),
                title=f"z = {z:.3g}: {facts['rings']} rings, {facts['knots']} knots",
            )
            with open(path, "rb") as f:
                self.picture.value = f.read()
        finally:
            os.unlink(path)
