"""The Jupyter Details tab: the season slider redraws the plant; lichen and a crack on a fruit."""

from __future__ import annotations

import io

import numpy as np
import pytest

from jupyter_helpers import ROOT

FRUIT_TREE = str(ROOT / "grammars" / "fruit_tree.lsys")


@pytest.fixture
def explorer():
    from ramure.app.jupyter import NotebookExplorer

    return NotebookExplorer(FRUIT_TREE, n=5, view="static", size=(200, 200), cache=False)


def _rgb(png):
    from matplotlib.image import imread

    return imread(io.BytesIO(png), format="png")[..., :3]


def _near(rgb, colour, tol=0.1):
    """Pixels within ``tol`` of an RGB colour in [0, 1] (shading darkens, so a loose match)."""
    return int(np.sum(np.abs(rgb - np.asarray(colour)).max(axis=2) < tol))


def test_the_season_slider_ages_the_leaves_and_redraws(explorer):
    from ramure.lsys.architecture.seasons import age_leaves, autumn_chain

    tab = explorer.details
    titles = [explorer.tabs.get_title(i) for i in range(len(explorer.tabs.children))]
    assert explorer.tabs.children[titles.index("Details")] is tab.widget
    tab.season_slider.value = 24
    expected = age_leaves(explorer.model.skeleton.organs, autumn_chain(), steps=24, seed=0)
    fallen = int(expected.fallen.sum())
    assert 0 < fallen < len(expected.leaf_ids)
    assert tab.last_facts == {"step": 24, "leaves": len(expected.leaf_ids), "fallen_leaves": fallen}
    assert f"{fallen} fallen" in tab.facts.value and tab.shown == "season"
    late = _rgb(tab.picture.value)
    tab.season_slider.value = 0
    assert tab.last_facts["fallen_leaves"] == 0
    early = _rgb(tab.picture.value)
    green = autumn_chain().colors[0]
    assert _near(early, green) > _near(late, green)  # every leaf green at step 0, few at the end
    assert tab.season is not None and tab.season.states.shape == (25, len(expected.leaf_ids))
    notes = ROOT.parent / "notes"
    if notes.is_dir():
        tab.season_slider.value = 16
        (notes / "details-jupyter-season.png").write_bytes(tab.picture.value)


def test_wind_makes_more_leaves_fall_by_mid_season(explorer):
    tab = explorer.details
    tab.season_slider.value = 10
    still = tab.last_facts["fallen_leaves"]
    tab.wind.value = 1.5
    assert tab.last_facts["fallen_leaves"] > still


def test_lichen_needs_a_selected_fruit_then_grows_on_it(explorer):
    tab = explorer.details
    before = tab.picture.value
    tab.grow_lichen()
    assert "refused: select a fruit first" in tab.facts.value and tab.picture.value == before
    explorer.select([explorer.model.fruit_ids()[0]])
    tab.grow_lichen()
    assert tab.shown == "lichen" and tab.last_facts["particles"] == 300 and tab.last_facts["clusters"] == 5
    assert _rgb(tab.picture.value).std(axis=(0, 1)).max() > 0.05  # a fruit, not a blank picture
    tab.carve_crack()
    f = tab.last_facts
    assert tab.shown == "crack" and f["watertight"] and f["triangles_result"] > f["triangles_object"]
    notes = ROOT.parent / "notes"
    if notes.is_dir():
        (notes / "details-jupyter-crack.png").write_bytes(tab.picture.value)


def test_where_puts_the_lichen_and_the_crack_at_the_fruit_s_bottom(explorer):
    from ramure.app.details import selected_fruit_surface

    tab = explorer.details
    explorer.select([explorer.model.fruit_ids()[0]])
    tab.where.value = "bottom"
    tab.clusters.value, tab.particles.value, tab.nodes.value = 2, 100, 8
    poly, _ = selected_fruit_surface(explorer.model)
    b = np.reshape(poly.bounds, (3, 2))
    lower_third = b[2, 0] + (b[2, 1] - b[2, 0]) / 3
    tab.grow_lichen()
    assert tab.last_facts["painted"] and tab.last_facts["particles"] == 100 and tab.last_facts["clusters"] == 2
    assert float(np.mean(tab.last_result["discs"].points[:, 2])) < lower_third  # grown at the bottom
    tab.carve_crack()
    assert tab.last_facts["nodes"] == 8 and tab.last_facts["watertight"]
    assert float(tab.last_result["points"][0, 2]) < lower_third  # the crack's root at the bottom
    assert "refused" not in tab.facts.value


def test_lichen_on_the_branches_needs_no_fruit(explorer):
    tab = explorer.details
    tab.clusters.value, tab.particles.value = 4, 250
    tab.grow_lichen_on_bark()
    f = tab.last_facts
    assert tab.shown == "bark" and f["particles"] == 250 and f["clusters"] == 4 and "branches" in tab.facts.value
    rgb = _rgb(tab.picture.value)
    greenish = (rgb[..., 1] > rgb[..., 2] + 0.05) & (rgb[..., 1] > rgb[..., 0])
    assert greenish.mean() > 0.005  # the lichen shows on the bark, close up


def test_the_tab_records_its_details_in_the_session(explorer):
    tab = explorer.details
    session = explorer.model.session
    tab.grow_lichen()  # refused (no fruit selected): nothing recorded
    assert session.details() == []
    explorer.select([explorer.model.fruit_ids()[0]])
    tab.particles.value, tab.clusters.value = 120, 3
    tab.grow_lichen()
    tab.where.value = "bottom"
    tab.carve_crack()
    kinds = [d["kind"] for d in session.details()]
    assert kinds == ["lichen", "crack"] and session.details()[0]["settings"]["particles"] == 120
    assert len(session.details()[1]["settings"]["anchor"]) == 3 and session.can_undo
