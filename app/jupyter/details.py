"""The Details tab: the plant's leaves through a season; lichen and a crack on the selected fruit.

The notebook counterpart of the desktop's Details dock (issue 18).  A **season** slider (0..24
steps) with heat, humidity and wind: the leaves of the explorer's plant age along the open
Markov chain of :mod:`ramure.lsys.architecture.seasons` (computed once per plant and environment; the
slider only redraws), and the picture shows the plant at that step as ``ramure autumn``
draws it: attached leaves in their state's colour, fallen ones gone from the branches and
lying on the ground.  **Lichen** and **Crack** act on the selected fruit's closed surface
(:mod:`ramure.app.details`) and show it in the same picture, with their facts.  A static
picture cannot be clicked, so *where* stands for the desktop's brush and crack tool: lichen
starts only near the fruit's top, side (-x) or bottom (a painted adhesion dab of 30 % of the
fruit's diagonal), and the crack is carved from that point.

>>> from ramure.app.jupyter.details import DetailsTab
>>> tab = DetailsTab(None)
>>> tab.season_slider.value = 3
>>> "select" in tab.facts.value or "explorer" in tab.facts.value
True
"""

from __future__ import annotations

import os
import tempfile
from typing import TYPE_CHECKING

import ipywidgets as W
import numpy as np

from ramure.app.details_history import record, selected_fruit

from ramure.app.jupyter._ui import button, on_value, png_image
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.lsys.architecture.seasons import Season

STEPS = 24
PLACES = ("anywhere", "top", "side", "bottom")  # where lichen starts / the crack begins (anywhere: top)


class DetailsTab:
    """Season slider, heat, humidity, wind; Lichen and Crack buttons; facts and a picture."""

    def __init__(self, app: NotebookExplorer | None, size: tuple[int, int] = (420, 420)) -> None:
        from ramure.lsys.architecture.seasons import autumn_chain

        self.app = app
        self.size = size
        self.chain = autumn_chain()
        self.season: Season | None = None
        self.season_key: tuple | None = None
        self.shown: str | None = None  # "season", "lichen" or "crack"
        self.last_facts: dict | None = None
        self.last_result: dict | None = None  # the last lichen or crack (see ramure.app.details)
        self.season_slider = W.IntSlider(value=0, min=0, max=STEPS, description="season step")
        self.heat = W.BoundedFloatText(value=0.5, min=0.0, max=1.0, step=0.1, description="heat")
        self.humidity = W.BoundedFloatText(value=0.5, min=0.0, max=1.0, step=0.1, description="humidity")
        self.wind = W.BoundedFloatText(value=0.0, min=0.0, max=2.0, step=0.05, description="wind")
        self.seed = W.BoundedIntText(value=0, min=0, max=2**31 - 1, description="seed")
        for box in (self.season_slider, self.heat, self.humidity, self.wind, self.seed):
            on_value(box, lambda _v: self.show_season())
        from ramure.gmap.organs.lichen import HABITS

        self.clusters = W.BoundedIntText(value=5, min=1, max=200, description="clusters")
        self.particles = W.BoundedIntText(value=300, min=1, max=20_000, description="particles")
        self.habit = W.Dropdown(options=list(HABITS), value="crustose", description="habit")
        self.nodes = W.BoundedIntText(value=15, min=2, max=500, description="crack nodes")
        self.where = W.Dropdown(options=PLACES, value="anywhere", description="where")
        self.facts = W.HTML("<small>Move the slider to age the leaves; select a fruit for lichen or a crack.</small>")
        self.picture = png_image(width=size[0])
        self.widget = W.VBox(
            [
                W.HBox([self.season_slider, self.heat, self.humidity]),
                W.HBox([self.wind, self.seed]),
                W.HBox([self.clusters, self.particles, self.habit]),
                W.HBox(
                    [
                        self.nodes,
                        self.where,
                        button("Lichen on the fruit", self.grow_lichen),
                        button("Crack the fruit", self.carve_crack),
                    ]
                ),
                W.HBox([button("Lichen on the branches", self.grow_lichen_on_bark)]),
                self.facts,
                self.picture,
            ]
        )

    # -- season ------------------------------------------------------------------------
    def _model(self):
        model = getattr(self.app, "model", None)
        if model is None:
            raise RamureError("this tab needs an explorer's plant (DetailsTab(explorer))")
        return model

    def compute_season(self) -> Season:
        """The whole season of the plant's leaves for the current environment (cached)."""
        from ramure.lsys.architecture.seasons import age_leaves

        model = self._model()
        key = (model.version, id(model.session), self.heat.value, self.humidity.value, self.wind.value, self.seed.value)
        if self.season is None or key != self.season_key:
            self.season = age_leaves(
                model.skeleton,
                self.chain,
                steps=STEPS,
                seed=self.seed.value,
                heat=self.heat.value,
                humidity=self.humidity.value,
                wind=self.wind.value,
            )
            self.season_key = key
        return self.season

    def show_season(self) -> None:
        """Draw the plant at the slider's step (leaves in state colours, fallen ones on the ground)."""
        from ramure.app.details import season_at

        try:
            season = self.compute_season()
        except RamureError as err:
            self._refused(err)
            return
        step = self.season_slider.value
        now = season_at(season, step)
        states = now.states[-1]
        counts = ", ".join(
            f"{int((states == i).sum())} {name}" for i, name in enumerate(self.chain.states) if (states == i).any()
        )
        self.last_facts = {"step": step, "leaves": len(season.leaf_ids), "fallen_leaves": int(now.fallen.sum())}
        self.facts.value = (
            f"<small>Step {step}/{STEPS}: {len(season.leaf_ids)} leaves, {int(now.fallen.sum())} fallen; {counts}</small>"
        )
        self.shown = "season"
        self.picture.value = _png(lambda path: _render_autumn(self._model().skeleton, now, self.chain, path, self.size))

    # -- lichen and cracks ---------------------------------------------------------------
    def grow_lichen(self) -> None:
        """Grow lichen on the selected fruit (at the picked point when there is one, else all over) with the
        tab's settings, record it in the model and show the result; a refused setting is said in the
        message line.
        """
        from ramure.app.details import diagonal, facing, lichen_on_fruit, paint_adhesion

        try:
            point, poly = self._place()
            adhesion = None if point is None else paint_adhesion(poly.points, None, point, 0.3 * diagonal(poly))
            model = self._model()
            out = lichen_on_fruit(model, self.clusters.value, self.particles.value, self.habit.value, self.seed.value, adhesion)
            record(
                model,
                "lichen",
                {**self._lichen_settings(), "adhesion": None if adhesion is None else adhesion.tolist()},
                selected_fruit(model),
            )
        except RamureError as err:
            self._refused(err)
            return
        f = out["facts"]
        camera = facing(out["growth"], out["mesh"])  # the lichen's side, the whole fruit in view
        self._show(
            "lichen",
            out,
            f"Lichen ({f['habit']}): {f['particles']} particles in {f['clusters']} clusters "
            f"on {f['triangles']} triangles; old discs dark, young rims light",
            lambda path: _render_surface(out["surface"], path, self.size, out["discs"], camera=camera),
        )

    def grow_lichen_on_bark(self) -> None:
        """Lichen on the plant's bark (its branches welded into one closed surface), seen close up."""
        from ramure.app.details import close_up, lichen_on_surface, plant_bark

        try:
            poly, mesh = plant_bark(self._model().skeleton)
            out = lichen_on_surface(poly, mesh, self.clusters.value, self.particles.value, self.habit.value, self.seed.value)
            record(self._model(), "bark", self._lichen_settings())
        except RamureError as err:
            self._refused(err)
            return
        f = out["facts"]
        camera = close_up(out["growth"], out["mesh"])
        self._show(
            "bark",
            out,
            f"Lichen on the branches ({f['habit']}): {f['particles']} particles in "
            f"{f['clusters']} clusters on {f['triangles']} triangles of bark",
            lambda path: _render_surface(out["surface"], path, self.size, out["discs"], colour=(0.47, 0.41, 0.35), camera=camera),
        )

    def carve_crack(self) -> None:
        """Carve a crack into the selected fruit from the picked point (or its default start) with the tab's
        settings, record it in the model and show the result; a refused setting is said in the message
        line.
        """
        from ramure.app.details import crack_on_fruit

        try:
            point, _ = self._place()
            model = self._model()
            out = crack_on_fruit(model, self.nodes.value, self.seed.value, point)
            record(
                model,
                "crack",
                {
                    "nodes": self.nodes.value,
                    "seed": self.seed.value,
                    "anchor": None if point is None else [float(v) for v in point],
                },
                selected_fruit(model),
            )
        except RamureError as err:
            self._refused(err)
            return
        f = out["facts"]
        self._show(
            "crack",
            out,
            f"Crack: {f['nodes']} nodes, length {f['length']:.3g}, "
            f"{f['triangles_object']} → {f['triangles_result']} triangles, "
            f"{'watertight' if f['watertight'] else 'not watertight'}",
            lambda path: _render_surface(out["surface"], path, self.size),
        )

    def _lichen_settings(self) -> dict:
        """The lichen controls' values, as a detail edit records them."""
        return {
            "clusters": self.clusters.value,
            "particles": self.particles.value,
            "habit": self.habit.value,
            "seed": self.seed.value,
        }

    def _show(self, kind: str, out: dict, text: str, render) -> None:
        """Show a grown detail: its facts line and its picture; remember it as the last result."""
        self.last_facts, self.last_result, self.shown = out["facts"], out, kind
        self.facts.value = f"<small>{text}</small>"
        self.picture.value = _png(render)

    def _place(self):
        """The chosen place on the selected fruit (None: anywhere) and the fruit's surface."""
        from ramure.app.details import selected_fruit_surface

        poly, _ = selected_fruit_surface(self._model())
        if self.where.value == "anywhere":
            return None, poly
        points = np.asarray(poly.points)
        pick = {"top": np.argmax(points[:, 2]), "bottom": np.argmin(points[:, 2]), "side": np.argmin(points[:, 0])}
        return points[int(pick[self.where.value])], poly

    def _refused(self, err):
        self.facts.value = f"<small style='color:#b00020'>refused: {err}</small>"


def _png(render) -> bytes:
    """Run ``render(path)`` under the explorer's render lock and return the PNG's bytes."""
    from ramure.app.jupyter.view import RENDER_LOCK

    fd, path = tempfile.mkstemp(suffix=".png")
    os.close(fd)
    try:
        with RENDER_LOCK:
            render(path)
        with open(path, "rb") as f:
            return f.read()
    finally:
        os.unlink(path)


def _render_autumn(skeleton, season, chain, path, size):
    from ramure.app.commands.autumn import render_autumn

    render_autumn(skeleton, season, chain, path, size)


def _render_surface(surface, path, size, discs=None, colour=(0.92, 0.47, 0.16), camera=None):
    """A fruit (orange) or bark with lichen discs, or carved, seen from above and aside (or
    from ``camera``)."""
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    try:
        plotter.set_background("white", top="lightsteelblue")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        plotter.add_mesh(surface, color=colour, smooth_shading=discs is not None)
        if discs is not None:
            plotter.add_mesh(discs, scalars="rgb", rgb=True, show_scalar_bar=False)
        b = np.reshape(surface.bounds, (3, 2))
        centre, span = b.mean(axis=1), float(np.ptp(b, axis=1).max())
        if camera is None:
            plotter.camera_position = [tuple(centre + np.array([0.5, -0.7, 0.9]) * span * 2), tuple(centre), (0, 0, 1)]
            plotter.reset_camera()  # type: ignore[call-arg]  # pyvista stubs: decorated method
        else:
            plotter.camera_position = camera
        plotter.screenshot(str(path))
    finally:
        plotter.close()
