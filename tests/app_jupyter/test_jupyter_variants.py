"""Variant exploration in the explorer: sweep with progress and stop, gallery, picks, qualifiers, files."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("metrics")

from ramure.app.jupyter import NotebookExplorer  # noqa: E402
from jupyter_helpers import HONDA  # noqa: E402


@pytest.fixture(scope="module")
def explored():
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(160, 160), cache=False)
    ex.variants.thumb_size = 40  # small thumbnails: faster
    exp = ex.explore_variants(n=4, n_jobs=1)  # the plant's n: qualifiers judge moves on the sweep's scale
    return ex, exp


@pytest.fixture
def ex(explored):
    """A fresh explorer that already holds the shared exploration."""
    source, exp = explored
    fresh = NotebookExplorer(HONDA, n=4, view="static", size=(160, 160), cache=False)
    fresh.variants.exploration, fresh.variants.thumbnails = exp, list(source.variants.thumbnails)
    fresh.variants.refresh()
    fresh.refresh()
    return fresh


def test_exploration_fills_gallery_progress_and_qualifiers(explored):
    ex, exp = explored
    assert exp is not None and exp.sweep.n_variants_ == 486
    assert len(ex.variants.thumbnails) == 27 and all(t[:4] == b"\x89PNG" for t in ex.variants.thumbnails)
    assert ex.variants.bar.value == ex.variants.bar.max == 27
    assert ex.variants.progress_text.value == "thumbnails 27/27"
    assert all(not b.disabled for b in ex.variants.cards)
    # each thumbnail is its button's background: a click on the image applies the pick
    import base64

    css = ex.variants.thumb_css.value
    card = ex.variants.cards[4]
    rule = [c for c in card._dom_classes if c.endswith("-5")][0]
    assert f".{rule}{{background-image:url(data:image/png;base64," + base64.b64encode(ex.variants.thumbnails[4]).decode() in css
    options = ex.edits.qualifier.options  # suggestions for a typed word
    assert {"small", "petit", "dense", "taller", "plus haut", "touffu"} <= set(options) and len(options) > 44
    assert ex.edits.qualifier.value == "" and not ex.edits.qualifier.disabled
    assert "486 variants" in ex.variants.note.value and "486 variants explored" in ex.message.text
    assert ex.variants.scatter.value[:4] == b"\x89PNG"
    assert ex.variants.gallery_html().count("<img") == 27


def test_gallery_button_applies_the_pick(ex):
    before = ex.plant.to_string()
    ex.variants.cards[26].click()  # pick #27
    params = ex.variants.pick_params(27)
    assert ex.history[-1]["params"] == params and ex.plant.to_string() != before
    assert ex.variants.chosen is not None and np.allclose(ex.variants.chosen, ex.variants.pick_point(27))
    assert "applied pick #27" in ex.message.text


def test_qualifier_dropdown_makes_the_selection_thicker(ex):
    """(Issue 35: "dense" adds segments, which no constant of Honda does; "thick" moves its radii.)"""
    from ramure.metrics.apply import active_rules, roots_metrics

    tree = ex.plant.tree
    branch = int(np.flatnonzero((tree.depth == 1) & tree.alive & (tree.child_count > 0))[-1])
    ex.tree.select(branch)  # the derivation tree's Select: every leaf under a main branch
    roots = ex.model.plan().roots
    rules = active_rules(ex.plant.tree, roots)
    before = roots_metrics(ex.session, roots).mean_radius
    ex.edits.qualifier.value = "thick"
    ex.edits.apply_qualifier.click()
    result = ex.model.last_result
    after = roots_metrics(ex.session, result.roots).mean_radius
    assert ex.history[-1]["params"]["rule"] in rules and len(ex.history) == 1  # one undoable edit
    assert result.roots.tolist() == roots.tolist()  # the selection's cut, what the preview shows
    added = np.asarray(result.change.added)
    assert ex.selection == sorted(added[ex.plant.tree.child_count[added] == 0].tolist())  # kept selected
    assert ex.message.kind == "info"
    message = ex.message.text
    assert ex.variants.chosen is not None  # the applied variant is marked in the PCA view
    ex.undo()
    assert ex.history == []
    # the part regrown really got thicker
    part_before = roots_metrics(ex.session, result.roots).mean_radius
    assert part_before == before
    assert after > part_before and message.startswith(f"thicker: mean radius {part_before:.4g} → {after:.4g}")


def test_qualifier_that_cannot_improve_says_so(ex, monkeypatch):
    from ramure.metrics import apply as apply_module

    real = apply_module.apply_qualifier

    def never_better(*args, **kwargs):
        out = real(*args, **kwargs)
        out.improved = False
        return out

    monkeypatch.setattr(apply_module, "apply_qualifier", never_better)
    ex.apply_qualifier("small")
    assert ex.message.kind == "note" and "did not move the selection its way" in ex.message.text
    assert "box volume" in ex.message.text and len(ex.history) == 1


def test_qualifier_sweeps_start_from_the_sessions_constants(ex, monkeypatch):
    monkeypatch.setattr(ex.variants, "_render_thumbnails", lambda exp: [None] * 27)  # not needed here: faster
    ex.set_constant("a2", 45)
    assert ex.variants.stale() and "explores again" in ex.edits.qualifier.tooltip
    assert "other constant values" in ex.variants.note.value
    ex.variants.n.value = 3
    result = ex.apply_qualifier("large")
    sweep = ex.variants.exploration.sweep
    assert result is not None and sweep.base_constants_["a2"] == 45 and not ex.variants.stale()
    assert ex.variants.exploration.name == "honda_sympodial"


def test_new_grammar_text_drops_the_variants(ex):
    ex.set_text(ex.model.text.replace("a2 60 ", "a2 50 "))
    assert ex.variants.exploration is None
    assert ex.variants.thumb_css.value == "" and all(b.disabled for b in ex.variants.cards)


def test_pick_needs_an_exploration_and_a_qualifier_runs_one():
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(120, 120), cache=False)
    ex.apply_pick(3)
    assert "explore the variants first" in ex.error and ex.history == []
    assert all(b.disabled for b in ex.variants.cards)
    ex.apply_qualifier(None)
    assert ex.message.kind == "note"
    assert not ex.edits.qualifier.disabled and "explores the variants" in ex.edits.qualifier.tooltip
    ex.variants.n.value = 3
    ex.apply_qualifier("small")
    assert ex.variants.exploration is not None and ex.history[-1]["params"]["rule"] in (0, 1)
    assert ex.variants.bar.value == 27 and ex.message.text.startswith("smaller: box volume")


def test_stop_button_cancels_a_background_exploration():
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(120, 120), cache=False)
    thread = ex.explore_variants(n=5, n_jobs=1, wait=False)
    assert thread.is_alive() and ex.variants.start.disabled
    ex.variants.stop_button.click()
    ex.variants.wait(60)
    assert not thread.is_alive()
    assert ex.variants.exploration is None and "stopped" in ex.variants.note.value
    assert not ex.variants.start.disabled and ex.variants.stop_button.disabled


def test_kernel_interrupt_stops_a_blocking_exploration(monkeypatch):
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(120, 120), cache=False)

    def interrupted(done, total, what="variants"):
        raise KeyboardInterrupt

    monkeypatch.setattr(ex.variants, "_progress", interrupted)
    assert ex.explore_variants(n=3, n_jobs=1) is None
    assert "stopped" in ex.error and ex.variants.exploration is None


def test_save_writes_what_a_study_reads(ex, tmp_path):
    from ramure.studies import Study

    ex.variants.save(tmp_path / "honda")
    picks = json.loads((tmp_path / "honda" / "picks.json").read_text())
    assert [p["id"] for p in picks] == list(range(1, 28))
    assert all((tmp_path / "honda" / p["image"]).read_bytes()[:4] == b"\x89PNG" for p in picks)
    assert picks[4]["params"] == ex.variants.pick_params(5)
    with Study.create(tmp_path / "s.db", grammars={"honda": tmp_path / "honda"}) as study:
        assert study.picks("honda")[0].image.endswith("thumbs/pick_01.png")


def test_study_regions_come_first_and_are_drawn(ex, tmp_path):
    from ramure.metrics.store import QualifierStore

    exp = ex.variants.exploration
    near = np.argsort(np.linalg.norm(exp.points - exp.picks.points[0], axis=1))[:6]
    with QualifierStore(tmp_path / "q.sqlite") as store:
        store.add(exp.name, "petit", near, exp.points[near], [exp.sweep.combination(int(i)) for i in near], source="study:test")
    ex.load_qualifiers(tmp_path / "q.sqlite")
    assert ex.edits.qualifier.options[0] == "small"  # the study's word first
    assert set(ex.variants.boxes()) == {"small"}
    ex.apply_qualifier("small")
    applied = ex.history[-1]["params"]
    assert applied in [exp.sweep.combination(int(i)) for i in near]  # the region's centre picks among them
    ex.load_qualifiers(tmp_path / "q.sqlite", grammar="other")
    assert "no qualifier points for grammar 'other'" in ex.error
    assert set(ex.variants.boxes()) == {"small"}  # the study's regions stay


@pytest.mark.parametrize(
    "action, expected",
    [
        (lambda ex: ex.apply_pick(28), "pick 28 is not a number 1-27"),
        (lambda ex: ex.apply_pick("x"), "pick 'x' is not a number 1-27"),
        (lambda ex: ex.apply_pick(0), "is not a number 1-27"),
        (lambda ex: ex.apply_qualifier("purple"), "unknown qualifier 'purple'"),
        (lambda ex: ex.load_qualifiers("/nonexistent/q.sqlite"), "no such qualifier store"),
    ],
    ids=["pick 28", "pick x", "pick 0", "unknown qualifier", "missing store"],
)
def test_bad_variant_input_is_refused(ex, action, expected):
    ex.select_where(min_order=2)
    before, selection = ex.plant.to_string(), ex.selection
    action(ex)
    assert ex.message.kind == "error" and expected in ex.message.text
    assert ex.plant.to_string() == before and ex.history == [] and ex.selection == selection


def test_a_file_that_is_not_a_qualifier_store_is_refused(ex, tmp_path):
    (tmp_path / "q.sqlite").write_text("not a database")
    ex.load_qualifiers(tmp_path / "q.sqlite")
    assert "qualifier store" in ex.error and ex.variants.regions is None


def test_hidden_constants_and_wide_steps_are_options_off_by_default(monkeypatch):
    """The tab's boxes reach the sweep as the CLI's --hidden --wide 0.25 (issue 35); off by default."""
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(160, 160), cache=False)
    runs = []
    monkeypatch.setattr(ex.variants, "_run", lambda sweep, lsystem, thumbnails: runs.append(sweep) or sweep)
    default = ex.variants.explore(n=4, n_jobs=1, thumbnails=False)
    assert (default.hidden, default.wide) == (False, None) and not ex.variants.hidden.value
    larger = ex.variants.explore(n=4, n_jobs=1, thumbnails=False, hidden=True, wide=0.25)
    assert (larger.hidden, larger.wide) == (True, 0.25) and ex.variants.hidden.value and ex.variants.wide.value == 0.25
    ls = ex.model.variant_lsystem()  # the larger space has more variants; the default cloud is unchanged
    assert default.fit(ls).n_variants_ == 486 and larger.fit(ls).n_variants_ == 518
    ex.variants.wide.value = 0.0  # 0 in the box: no wide step
    assert ex.variants.explore(wait=True, thumbnails=False).wide is None and len(runs) == 3
