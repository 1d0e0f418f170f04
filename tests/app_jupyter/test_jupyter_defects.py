"""The Jupyter Defects tab: defects on the selected fruit, one undoable edit (issue 17)."""

from __future__ import annotations

import io

import numpy as np
import pytest

from ramure.app.jupyter import NotebookExplorer
from jupyter_helpers import ROOT

FRUIT_TREE = str(ROOT / "grammars" / "fruit_tree.lsys")


@pytest.fixture(scope="module")
def tree():
    return NotebookExplorer(FRUIT_TREE, view="static", size=(120, 120), cache=False)


def test_defects_tab_applies_to_the_selected_fruit_and_undoes(tree):
    from PIL import Image

    ex, tab = tree, tree.defects
    tab.apply_button.click()  # nothing selected
    assert "select a fruit first" in tab.facts.value or "select a fruit first" in ex.message.text
    fruit = ex.model.fruit_ids()[2]
    ex.select([fruit])
    tab.kind.value = "crack"
    tab.options.value = "kind=transverse,sector=1,rings=3-5,depth=1,width_mm=1.5,healed=1"
    tab.add_button.click()
    tab.kind.value = "shrink"
    assert tab.options.value == "rate=0.05,steps=2"  # the kind's example
    tab.add_button.click()
    edits = len(ex.history)
    tab.apply_button.click()
    assert len(ex.history) == edits + 1 and ex.history[-1]["op"] == "fruit"
    assert (
        ex.history[-1]["settings"]["defects"]
        == tab.spec_list()
        == ["crack:kind=transverse,sector=1,rings=3-5,depth=1,width_mm=1.5,healed=1", "shrink:rate=0.05,steps=2"]
    )
    facts = tab.last_facts
    assert [d["kind"] for d in facts["defects"]] == ["crack", "shrink"]
    assert facts["volume_lost_fraction"] > 0.05 and f"Fruit {fruit}: crack, shrink" in tab.facts.value
    image = np.asarray(Image.open(io.BytesIO(tab.picture.value)).convert("RGB")).astype(int)
    assert image.std(axis=(0, 1)).max() > 10  # a fruit, not a blank frame
    ex.undo()
    assert "defects" not in ex.model.session.fruit_overrides().get(fruit, {})
    ex.select([fruit])
    tab.show_button.click()
    assert tab.spec_list() == [] and "no defects" in tab.facts.value


def test_bad_specs_are_refused_and_change_nothing(tree):
    ex, tab = tree, tree.defects
    ex.select([ex.model.fruit_ids()[0]])
    tab.specs.value = ""
    tab.kind.value = "hail"
    tab.options.value = "count=many"
    tab.add_button.click()
    assert tab.spec_list() == [] and "not a valid value" in tab.facts.value
    edits = len(ex.history)
    tab.specs.value = "excrescence:path=(3, C1, 0)"  # an inner cell: no free face
    tab.apply_button.click()
    assert len(ex.history) == edits and "free face" in ex.message.text


def test_defects_tab_selects_a_region_shows_it_and_regrows_it(tree, tmp_path):
    from PIL import Image

    ex, tab = tree, tree.defects
    fruit = ex.model.fruit_ids()[0]
    ex.select([fruit])
    tab.show()
    plain = np.asarray(Image.open(io.BytesIO(tab.picture.value)).convert("RGB"), float)
    tab.region_pattern.value = "(4, C*, *)"
    tab.region_button.click()
    assert ex.model.fruit_region == {"leaf": fruit, "region": {"path": "(4, C*, *)"}}
    lit = np.asarray(Image.open(io.BytesIO(tab.picture.value)).convert("RGB"), float)
    blue = (lit[..., 2] > lit[..., 0] + 15).sum()  # the highlight: blue over a red fruit
    assert blue > 200 and (plain[..., 2] > plain[..., 0] + 15).sum() < blue / 10
    (tmp_path / "region.png").write_bytes(tab.picture.value)
    # a brush at a skin point adds cells (a pattern is replaced by them)
    gm = ex.model.fruit_volume(fruit)
    from ramure.gmap.organs.regions import skin_cells

    centres, cells, _ = skin_cells(gm)
    found = tab.select_point(centres[len(centres) // 2], radius_mm=1.0)
    assert found is not None and found["region"]["cells"] == [cells[len(cells) // 2].tolist()]
    tab.region_pattern.value = "(3, C*, *)"
    tab.region_button.click()
    edits = len(ex.history)
    tab.region_params.value = "largeur=80"
    tab.regrow_button.click()
    assert len(ex.history) == edits + 1 and ex.history[-1]["settings"]["regions"][0]["path"] == "(3, C*, *)"
    grown = np.asarray(Image.open(io.BytesIO(tab.picture.value)).convert("RGB"), float)
    assert np.abs(grown - lit).max() > 50
    tab.region_params.value = "precision=3"
    tab.regrow_button.click()  # refused: merging cells would change the faces shared with the rest
    assert "cannot be coarser" in ex.message.text and len(ex.history) == edits + 1
    tab.region_params.value = "precision=20"  # twice the fruit's: the region alone is refined
    tab.regrow_button.click()
    assert len(ex.history) == edits + 2 and ex.history[-1]["settings"]["regions"][1]["params"] == {"precision": 20}
    finer = np.asarray(Image.open(io.BytesIO(tab.picture.value)).convert("RGB"), float)
    assert finer.std(axis=(0, 1)).max() > 10  # a fruit, not a blank picture
    (tmp_path / "region_finer.png").write_bytes(tab.picture.value)
    ex.undo()
    ex.undo()
    assert "regions" not in ex.model.session.fruit_overrides().get(fruit, {})


def test_zoom_to_fruit_frames_the_selected_fruit(tree):
    from PIL import Image

    ex = tree
    ex.view.zoom_to(None)
    whole = np.asarray(Image.open(io.BytesIO(ex.view.png())).convert("RGB"), float)
    fruit = ex.model.fruit_ids()[0]
    ex.select([fruit])
    ex.zoom_fruit.value = True  # the button
    bounds = ex.view.zoom
    assert bounds == ex.model.fruit_bounds([fruit])
    zoomed = np.asarray(Image.open(io.BytesIO(ex.view.png())).convert("RGB"), float)

    def reddish(img):  # the selected fruit is drawn red
        return ((img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)).mean()

    assert reddish(zoomed) > 4 * max(reddish(whole), 1e-4)
    ex.zoom_fruit.value = False
    assert ex.view.zoom is None
