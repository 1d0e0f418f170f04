"""The Defects tab: cracks, hail, shrinkage, rot and excrescences on the selected fruit (issue 17).

The notebook counterpart of the desktop's Defects dock (:mod:`ramure.app.fruit_defects`):
pick a kind, edit its options (an example is filled in), press *Add* (the spec joins the list,
one spec per line, which can also be edited by hand), then *Apply to the selected fruit*: the
list is recorded on the fruit selected in the explorer as one undoable edit (the explorer's
Undo takes it back) and the picture shows that fruit rebuilt with one volume subdivision and
damaged, with one line of facts (defects, volume lost, grade and reasons).  *Show* draws the
selected fruit with its recorded defects.  Refusals are shown in the explorer's message line
and change nothing.

Regions (issue 40 §6): *Select region* takes a label pattern such as ``(9, C*, *)``; the
explorer's :meth:`~ramure.app.jupyter.explorer.NotebookExplorer.select_fruit_rectangle` takes a
rubber band drawn over the 3D view (the skin facing the camera) and
:meth:`select_point` a skin point and a brush radius.  The picture draws the region in light
blue; *Regrow region* re-derives it with the parameters typed beside it (``largeur=75``): one
undoable edit, the rest of the fruit unchanged (:mod:`ramure.app.fruit_regions`).

>>> from ramure.app.jupyter.defects import DefectsTab
>>> tab = DefectsTab(None)
>>> tab.kind.value = "hail"; tab.add()
>>> tab.specs.value
'hail:count=3,depth_mm=1..3'
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import ipywidgets as W
import numpy as np

from ramure.app.fruit_defects import EXAMPLES
from ramure.app.jupyter._ui import button, on_value, png_image
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.app.model import Explorer
    from ramure.app.jupyter.explorer import NotebookExplorer
    from ramure.gmap.kernel.map3 import GMap3


class DefectsTab:
    """Kind, options, Add; the spec list; Apply and Show; facts and a picture."""

    def __init__(self, app: NotebookExplorer | None, size: tuple[int, int] = (420, 420)) -> None:
        self.app = app
        self.size = size
        self.last_facts = None
        self.kind = W.Dropdown(options=list(EXAMPLES), value="crack", description="defect")
        self.options = W.Text(value=EXAMPLES["crack"], description="options", layout=W.Layout(width="460px"))
        on_value(self.kind, lambda k: setattr(self.options, "value", EXAMPLES[k]))
        self.specs = W.Textarea(
            value="", placeholder="one spec per line, e.g. hail:count=3", layout=W.Layout(width="560px", height="80px")
        )
        self.facts = W.HTML("<small>Select a fruit, add defects, press Apply.</small>")
        self.picture = png_image(width=size[0])
        self.add_button = button("Add", self.add)
        self.apply_button = button("Apply to the selected fruit", self.apply)
        self.show_button = button("Show", self.show)
        self.region_pattern = W.Text(value="", placeholder="(5, C*, *)", description="region")
        self.region_params = W.Text(
            value="largeur=75",
            description="regrow with",
            tooltip="shape parameters (largeur=75, creux=0.4) or a finer precision (precision=20: twice the fruit's)",
        )
        self.region_button = button("Select region", self.select_region)
        self.regrow_button = button("Regrow region", self.regrow_region)
        self.place_button = button("Place defect in region", self.place_in_region)
        self.widget = W.VBox(
            [
                W.HBox([self.kind, self.options, self.add_button]),
                self.specs,
                W.HBox([self.apply_button, self.show_button, button("Clear", self.clear)]),
                W.HBox([self.region_pattern, self.region_button]),
                W.HBox([self.region_params, self.regrow_button, self.place_button]),
                self.facts,
                self.picture,
            ]
        )

    def spec_list(self) -> list[str]:
        """The specs, one per non-empty line."""
        return [line.strip() for line in self.specs.value.splitlines() if line.strip()]

    def add(self) -> None:
        """Append ``kind:options`` (checked now; a bad spec is refused and not added)."""
        from ramure.app.fruit_defects import check_specs

        options = self.options.value.strip()
        spec = f"{self.kind.value}:{options}" if options else self.kind.value
        try:
            check_specs([spec])
        except RamureError as err:
            self._refused(err)
            return
        self.specs.value = "\n".join([*self.spec_list(), spec])

    def clear(self) -> None:
        """Empty the list (Apply then removes the fruit's defects, undoably)."""
        self.specs.value = ""

    def apply(self) -> tuple[GMap3, dict] | None:
        """Record the list on the selected fruit (one undoable edit) and draw it damaged."""
        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        specs, model = self.spec_list(), self.app.model
        shown = self.app.run(
            lambda: model.set_fruit_defects(specs),
            note=f"{len(specs)} defect(s) recorded on the selected fruit; Undo takes them back",
        )
        if shown is not None:
            self._draw(*shown)
        return shown

    def show(self) -> tuple[GMap3, dict] | None:
        """Draw the selected fruit with its recorded defects."""
        from ramure.app.fruit_defects import damaged_fruit

        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        try:
            gm, facts = damaged_fruit(self.app.model)
        except RamureError as err:
            return self._refused(err)
        self.specs.value = "\n".join(facts["specs"])
        self._draw(gm, facts)
        return gm, facts

    def select_region(self, pattern: str | None = None) -> dict | None:
        """Select the region a label pattern names on the selected fruit and draw it."""
        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        text = (pattern if pattern is not None else self.region_pattern.value).strip() or "(5, C*, *)"
        self.region_pattern.value = text
        return self.select_with(lambda model: model.select_fruit_region("pattern", text))

    def select_point(self, point: Sequence[float], radius_mm: float = 8.0, mode: str = "replace") -> dict | None:
        """Brush: the skin cells within ``radius_mm`` of ``point`` (the plant's frame)."""
        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")

        def pick(model):
            from ramure.app.fruit_defects import selected_fruit

            gm = model.fruit_volume(selected_fruit(model))
            _, pos = gm.vertex_positions()
            per_mm = float(np.ptp(pos, axis=0).max()) / float(gm.meta.get("size_mm") or 65.0)
            return model.select_fruit_region("point", point, radius_mm * per_mm, mode=mode)

        return self.select_with(pick)

    def select_with(self, select: Callable[[Explorer], dict]) -> dict | None:
        """Run ``select(model)`` (a region selection), say what it selected and draw it."""
        from ramure.gmap.organs.regions import region_text

        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        model = self.app.model
        found = self.app.run(lambda: select(model), note=lambda: f"region: {region_text(model.fruit_region['region'])}")
        if found is not None:
            self.show()
        return found

    def place_in_region(self, spec: str | None = None) -> tuple[GMap3, dict] | None:
        """Add a defect (default: the kind and options fields) placed in the selected region to
        the fruit's recorded defects: one undoable edit."""
        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        options = self.options.value.strip()
        spec = spec if spec is not None else (f"{self.kind.value}:{options}" if options else self.kind.value)
        model = self.app.model
        shown = self.app.run(lambda: model.place_defect_in_region(spec), note="defect placed in the region; Undo takes it back")
        if shown is not None:
            self.specs.value = "\n".join(shown[1]["specs"])
            self._draw(*shown)
        return shown

    def regrow_region(self, params: str | None = None) -> tuple[GMap3, dict] | None:
        """Regrow the selected region with ``params`` (text ``largeur=75,creux=0.4``, default
        the field's): one undoable edit; the picture shows the fruit regrown there."""
        from ramure.app.fruit_regions import parse_params

        if self.app is None:
            return self._refused("this tab needs an explorer (DefectsTab(explorer))")
        text = self.region_params.value if params is None else params
        model = self.app.model
        shown = self.app.run(
            lambda: model.regrow_fruit_region(**parse_params(text)),
            note="region regrown; Undo takes it back",
        )
        if shown is not None:
            self._draw(*shown)
        return shown

    def _draw(self, gm, facts):
        from ramure.app.fruit_defects import facts_text, png_of_surface, surface
        from ramure.app.fruit_regions import highlight, region_mask

        self.last_facts = facts
        skin = surface(gm)
        text = facts_text(facts)
        r = self.app.model.fruit_region if self.app is not None else None
        if r is not None and r["leaf"] == facts["leaf"]:
            from ramure.gmap.organs.regions import region_text

            skin = highlight(skin, region_mask(gm, r["region"]))
            text = f"Region {region_text(r['region'])} in blue. {text}"
        self.facts.value = f"<small>{text}</small>"
        self.picture.value = png_of_surface(skin, self.size)

    def _refused(self, err):
        text = str(err).splitlines()[0]
        self.facts.value = f"<small style='color:#b00020'>refused: {text}</small>"
        if self.app is not None and hasattr(self.app, "message"):
            self.app.message.show(f"refused: {text}", "error")
        return None
