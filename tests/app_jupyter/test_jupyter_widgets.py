"""The explorer's widgets without a kernel: set values, click, and check the plant and selection."""

from __future__ import annotations

import base64

import numpy as np
import pytest

from ramure.app.jupyter import NotebookExplorer
from ramure.app.ids import parse_ids
from ramure.app.model import Explorer as Model
from ramure.lsys.regeneration.regen import Session
from jupyter_helpers import HONDA, red_pixels


def test_built_from_the_grammar(explorer):
    ex = explorer
    assert set(ex.grammar.sliders) == {"r1", "r2", "a1", "a2", "wr"}
    assert ex.grammar.sliders["a2"].value == 60.0 and ex.grammar.sliders["a2"].max == 120.0
    assert ex.grammar.n.value == 5 and ex.grammar.seed.value == 0
    assert ex.view.backend == "static" and ex.view.image.value[:4] == b"\x89PNG"
    assert ex.plant is ex.model.derivation and ex.session is ex.model.session
    assert ex.selection == [] and ex.history == []
    titles = [ex.tabs.get_title(i) for i in range(len(ex.tabs.children))]
    assert titles == ["Derivation tree", "Architecture", "Variants", "PCA & qualifiers", "Wood", "Details", "Defects"]


def test_grammar_error_is_shown_inline_and_keeps_the_plant(explorer):
    ex = explorer
    before = ex.plant.to_string()
    bad = ex.model.text.replace("w:      A(1,10)", "w:      A(1,10")
    ex.grammar.text.value = bad  # what losing focus after typing does
    assert "line 11, column 10" in ex.grammar.error.value and "^" in ex.grammar.error.value
    assert "no matching" in ex.error and ex.message.kind == "error"
    assert ex.plant.to_string() == before and ex.grammar.text.value == bad
    ex.grammar.text.value = bad.replace("A(1,10", "A(1,10)").replace("a1 10 ", "a1 20 ")
    assert ex.grammar.error.value == "" and ex.error is None
    assert ex.model.constants["a1"] == 20.0 and ex.plant.to_string() != before


def test_bad_grammar_at_start_opens_with_the_error():
    ex = NotebookExplorer("n: 2\nw: A(1\np: A(x) -> F(x)", view="static")
    assert "column 5" in ex.grammar.error.value
    assert ex.grammar.text.value.startswith("n: 2\nw: A(1")
    ex.set_text("n: 2\nw: A(1)\np: A(x) -> F(x)A(x+1)")
    assert ex.error is None and ex.plant.to_string() == "F(1)F(2)A(3)"


def test_missing_file_is_refused():
    from ramure.errors import RamureError

    with pytest.raises(RamureError, match="no such grammar file"):
        NotebookExplorer("grammars/nope.lsys", view="static")


def test_sliders_stage_or_apply_constants(explorer):
    ex = explorer
    before = ex.plant.to_string()
    ex.grammar.sliders["a2"].value = 30.0  # live off: only staged
    assert ex.plant.to_string() == before and ex.grammar.staged() == {"a2": 30.0}
    ex.edits  # noqa: B018
    ex.apply_constants()
    assert ex.model.constants["a2"] == 30.0 and ex.plant.to_string() != before
    assert ex.history[-1] == {"op": "constants", "values": {"a2": 30.0}}
    ex.grammar.live.value = True
    ex.grammar.sliders["r1"].value = 0.8
    assert ex.model.constants["r1"] == 0.8 and len(ex.history) == 2
    ex.edits.undo.click()
    assert ex.model.constants["r1"] == 0.9 and ex.grammar.sliders["r1"].value == 0.9


def test_derivation_count_and_seed(explorer):
    ex = explorer
    n5 = len(ex.skeleton)
    ex.grammar.n.value = 4
    assert ex.model.session.n == 4 and len(ex.skeleton) == (n5 - 1) // 2
    ex.grammar.seed.value = 7
    assert ex.model.session.seed == 7
    ex.set_derivation(n=2.5)
    assert ex.message.kind == "error" and "whole number" in ex.error and ex.model.session.n == 4


def test_select_ids_modes_and_errors(explorer):
    ex = explorer
    leaves = ex.model.session.leaves_with_symbol("F").tolist()
    sp = ex.selection_panel
    sp.ids.value = f"{leaves[0]}, {leaves[1]}-{leaves[1]}"
    sp.select_ids()
    assert ex.selection == sorted(leaves[:2])
    sp.mode.value = "add"
    sp.ids.value = str(leaves[2])
    sp.select_ids()
    assert ex.selection == sorted(leaves[:3])
    sp.mode.value = "toggle"
    sp.select_ids()
    assert ex.selection == sorted(leaves[:2])
    sp.ids.value = "12, abc"
    sp.select_ids()
    assert ex.message.kind == "error" and "'abc' is not a leaf id" in ex.error
    assert ex.selection == sorted(leaves[:2])  # a refused input changes nothing
    assert "2 selected" in sp.summary.value


def test_parse_ids():
    assert parse_ids(" 3,7-9  12;4 ") == [3, 7, 8, 9, 12, 4]
    assert parse_ids("") == []
    with pytest.raises(ValueError, match="backwards"):
        parse_ids("9-7")


def test_the_first_selection_warms_up_edits_once_in_the_background(explorer, monkeypatch):
    import threading

    from ramure.app import model

    started = []
    monkeypatch.setattr(model, "_warm_up", [])
    monkeypatch.setattr(model, "warm_up_edits", lambda text, n: started.append((text, n, threading.current_thread().name)))
    ex = explorer
    ex.clear_selection()
    ex.selection_panel.ids.value = "abc"
    ex.selection_panel.select_ids()  # refused: nothing selected, nothing started
    assert started == [] and model._warm_up == []
    leaves = ex.model.session.leaves_with_symbol("F").tolist()
    ex.selection_panel.ids.value = str(leaves[0])
    ex.selection_panel.select_ids()
    model._warm_up[0].join(10)
    assert started == [(ex.model.text, 5, "ramure-warm-up")]
    ex.select(leaves[1:3])
    ex.pick(0)
    assert len(model._warm_up) == 1 and len(started) == 1  # once per process


def test_select_where_matches_order_and_height(explorer):
    ex = explorer
    sp = ex.selection_panel
    sk = ex.skeleton
    z_mid = (sk.start[:, 2] + sk.end[:, 2]) / 2
    h = float(np.median(z_mid))
    sp.min_order.value = 3
    sp.height.value = (h, sp.height.max)
    sp.select_where()
    expect = sorted(set(sk.leaf_id[(sk.order >= 3) & (z_mid >= h - 1e-9)].tolist()))
    assert ex.selection == expect and 0 < len(expect) < len(sk)
    # the full height range means no height filter
    sp.height.value = (sp.height.min, sp.height.max)
    sp.min_order.value = 0
    sp.select_where()
    assert ex.selection == sorted(set(sk.leaf_id.tolist()))


def test_tree_browser_selects_a_leaf_and_a_subtree(explorer):
    ex = explorer
    tb = ex.tree
    assert [v for _, v in tb.rows.options] == [0]  # the axiom A(1,10)
    tb.rows.value = 0
    tb.open_selected()
    labels = dict((v, label) for label, v in tb.rows.options)
    f_leaf = tb.children_with("F")[0]
    assert labels[f_leaf].endswith("F(1) · leaf")
    tb.rows.value = f_leaf
    tb.select_selected()
    assert ex.selection == [f_leaf]
    branch = tb.children_with("B")[0]
    tb.select(branch)
    assert ex.selection == sorted(ex.plant.tree.leaves_under(branch).tolist()) and len(ex.selection) > 100
    tb.open(branch)
    assert "A(1,10) ▸ B(0.9,7.07)" in tb.crumbs.value
    tb.up()
    assert "B(" not in tb.crumbs.value


def test_regrow_with_constants_changes_only_the_cut(explorer):
    ex = explorer
    ex.select_where(min_order=3)
    cut = ex.model.plan()
    tree = ex.plant.tree
    first, last = tree.leaf_spans()
    lo = min(int(first[r]) for r in cut.roots)
    before = [ex.model.lsystem.module_text(tree, n) for n in tree.leaves[:lo]]
    ex.grammar.sliders["a2"].value = 25.0
    ex.edits.regrow_constants.click()
    assert ex.history[-1]["op"] == "regrow" and ex.history[-1]["constants"] == {"a2": 25.0}
    added = set(np.asarray(ex.model.last_result.change.added).tolist())
    assert ex.selection and set(ex.selection) <= added  # the regrown part stays selected
    assert ex.model.constants["a2"] == 60.0  # scoped to the cut
    tree = ex.plant.tree
    assert [ex.model.lsystem.module_text(tree, n) for n in tree.leaves[:lo]] == before
    assert f"regrew {ex.model.last_result.removed} of " in ex.status_line.value


def test_regrow_with_constants_needs_a_moved_slider(explorer):
    ex = explorer
    ex.edits.regrow_constants.click()
    assert ex.history == [] and ex.message.kind == "note"


def test_prune_undo_redo_buttons(explorer):
    ex = explorer
    assert ex.edits.undo.disabled and ex.edits.prune.disabled
    ex.edits.prune.click()
    assert ex.message.kind == "error" and "select the branches to prune first" in ex.error
    start = ex.plant.to_string()
    ex.select_where(min_order=3)
    assert not ex.edits.prune.disabled
    ex.edits.prune.click()
    pruned = ex.plant.to_string()
    assert len(pruned) < len(start) and not ex.edits.undo.disabled
    ex.edits.undo.click()
    assert ex.plant.to_string() == start and not ex.edits.redo.disabled
    ex.edits.redo.click()
    assert ex.plant.to_string() == pruned


def test_rho_slider(explorer):
    ex = explorer
    ex.edits.rho.value = 30
    assert ex.model.rho == pytest.approx(0.3)
    ex.set_rho(0)
    assert ex.message.kind == "error" and ex.model.rho == pytest.approx(0.3)


def test_rho_slider_is_a_percent_the_model_a_fraction(explorer):
    ex = explorer
    ex.edits.rho.value = 1  # the slider's minimum: 1 %, not ρ = 1 (issue 34)
    assert ex.model.rho == pytest.approx(0.01)
    ex.edits.rho.value = 100
    assert ex.model.rho == pytest.approx(1.0)


def test_grammar_box_shows_n_and_seed_and_keeps_the_plant_when_sent_back(explorer):
    ex = explorer
    ex.set_derivation(seed=9)
    assert "#seed 9" in ex.grammar.text.value  # what Save writes
    ex.select(ex.model.session.leaves_with_symbol("F")[-2:])
    ex.regrow()
    edits = list(ex.model.session.edits)
    ex.set_text(ex.grammar.text.value)  # the shown text, unchanged: the regrown part stays
    assert ex.model.session.edits == edits and ex.model.session.seed == 9


def test_rho_changes_the_cut():
    # with ρ low the cut climbs above a partly selected parent; with ρ high it stays low
    ex = NotebookExplorer(HONDA, n=5, view="static", size=(120, 120))
    tree = ex.plant.tree
    branch = ex.tree.children()[0]
    leaves = [int(x) for x in ex.model.session.leaves_with_symbol("F") if x in set(tree.leaves_under(branch).tolist())]
    ex.select(leaves[-3:])
    ex.set_rho(5)
    low = ex.model.plan().roots
    ex.set_rho(100)
    high = ex.model.plan().roots
    cover = lambda roots: sum(len(tree.leaves_under(int(r))) for r in roots)  # noqa: E731
    assert cover(low) >= cover(high)


def test_view_shows_the_selection_in_red(explorer):
    ex = explorer
    assert red_pixels(ex.png()) == 0
    ex.select_where(min_order=3)
    assert red_pixels(ex.view.image.value) > 50
    ex.clear_selection()
    assert red_pixels(ex.view.image.value) == 0


def test_pick_selects_the_leaf_of_a_cell(explorer):
    ex = explorer
    mesh = ex.model.mesh
    cell = int(np.flatnonzero(np.asarray(mesh.cell_data["order"]) == 2)[0])
    ex.pick(cell)
    assert ex.selection == [int(mesh.cell_data["leaf_id"][cell])]
    ex.pick(10**7)
    assert "is not part of the plant" in ex.error


def test_selection_setter_and_history_mix_code_and_clicks(explorer):
    ex = explorer
    leaves = ex.model.session.leaves_with_symbol("F").tolist()[-4:]
    ex.selection = leaves
    assert ex.selection == sorted(leaves)
    ex.regrow(constants={"a1": 15})
    ex.edits.undo.click()
    assert ex.history == [] and ex.session.can_redo


def test_session_save_replays(explorer, tmp_path):
    ex = explorer
    ex.select_where(min_order=3)
    ex.regrow(constants={"a2": 40})
    ex.edits.path.value = str(tmp_path / "s.json")
    ex.edits.widget.children[-1].children[1].click()  # the Save button
    assert Session.load(tmp_path / "s.json").derivation.to_string() == ex.plant.to_string()
    ex.save(tmp_path / "plant.obj")
    assert (tmp_path / "plant.obj").read_text().startswith("# Ramure plant")
    ex.save(tmp_path / "plant.xyz")
    assert ex.message.kind == "error" and ".xyz" in ex.error


def test_mimebundle_has_widget_and_png(explorer):
    bundle = explorer._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert base64.b64decode(bundle["image/png"])[:4] == b"\x89PNG"
    assert bundle["text/plain"].startswith("<Ramure Explorer:")


def test_model_state_is_shared_with_app_model(explorer):
    assert isinstance(explorer.model, Model)
    explorer.model.select(explorer.model.leaves_where(min_order=4))
    explorer.refresh()
    assert f"{len(explorer.selection)} selected" in explorer.selection_panel.summary.value


def test_regrowing_the_whole_plant_with_new_constants_redraws():
    """A whole-plant regrow that keeps no segment of the old mesh (every tube changes) is drawn
    anew (it raised IndexError in the incremental re-mesh, which stopped explore.ipynb)."""
    from ramure.app.jupyter import NotebookExplorer

    ex = NotebookExplorer(HONDA, n=5, view="static", size=(64, 64))
    before = ex.png()
    assert ex.regrow(params={"rule": 1, "constants": {"a2": 66.0}}) is not None, ex.error
    assert ex.error is None and ex.png() != before and ex.model.mesh.n_cells > 0


def test_picture_tabs_show_no_broken_image_before_their_first_action(explorer):
    """An empty ``ipywidgets.Image`` is a broken-image icon in the browser: hidden until filled."""
    ex = explorer
    for tab in (ex.wood, ex.details, ex.defects):
        assert tab.picture.value == b"" and tab.picture.layout.display == "none"
        assert "<small>" in tab.facts.value  # a short text says what to do instead
    ex.defects.apply()  # refused: no fruit selected, still nothing to show
    assert ex.defects.picture.layout.display == "none"
    ex.details.season_slider.value = 2  # Honda's tree has no leaves: refused in words, no picture yet
    assert "no leaves to age" in ex.details.facts.value and ex.details.picture.layout.display == "none"
    ex.wood.years.value = 2
    ex.wood.grow()
    assert ex.wood.picture.value[:4] == b"\x89PNG" and ex.wood.picture.layout.display is None
    assert "live, 0 dead" in ex.wood.facts.value  # the species' branches live (branch_life = 0)
    assert ex.view.image.layout.display is None  # the plant's picture is there from the start


def test_architecture_buttons_need_an_amap_grammar(explorer):
    from jupyter_helpers import ROOT

    arch = explorer.architecture  # Honda's grammar names no architecture
    assert arch.arch is None and "#amap" in arch.crumbs.value
    assert len(arch.buttons) == 4 and all(b.disabled for b in arch.buttons) and arch.rows.disabled
    ex = NotebookExplorer(str(ROOT / "grammars" / "amap" / "massart.lsys"), n=4, view="static", size=(120, 120), cache=False)
    arch = ex.architecture
    assert arch.arch is not None and not any(b.disabled for b in arch.buttons) and not arch.rows.disabled
    ex.set_text("n: 2\nw: A(1)\np: A(x) -> F(x)A(x+1)")  # the #amap lines gone
    assert all(b.disabled for b in arch.buttons) and "#amap" in arch.crumbs.value
