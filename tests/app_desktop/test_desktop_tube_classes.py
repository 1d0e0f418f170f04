"""After an edit the plant's radius classes are patched from the version it was edited from, and
equal what sorting the new plant from scratch gives (issue 14: edits cost what they touch)."""

from __future__ import annotations

import numpy as np

from ramure.app.desktop.view import plant_actors
from ramure.app.desktop.view.plant_actors import PlantActors
from ramure.app.model import Explorer
from desktop_helpers import BarePlotter, show_model_plant


def groups_of(actors):
    return [(g.count, g.radius, g.corners, None if g.segments is None else g.segments) for g in actors.groups]


def assert_same_groups(a, b):
    assert len(a) == len(b)
    for (ca, ra, ka, sa), (cb, rb, kb, sb) in zip(a, b):
        assert ca == cb and ra == rb
        np.testing.assert_array_equal(ka, kb)
        if sa is None or sb is None:
            assert sa is None and sb is None
        else:
            np.testing.assert_array_equal(sa, sb)


def test_patched_classes_equal_classes_sorted_from_scratch(monkeypatch):
    patched = []
    real = plant_actors._classes_after_edit
    monkeypatch.setattr(plant_actors, "_classes_after_edit", lambda *a: patched.append(1) or real(*a))
    ex = Explorer("honda_sympodial.lsys", n=11)
    shown = PlantActors(BarePlotter())
    show_model_plant(shown, ex)
    rng = np.random.default_rng(2)
    ops = ["regrow", "regrow", "prune", "regrow", "undo", "redo", "regrow", "undo", "undo", "regrow", "regrow"]
    for step, op in enumerate(ops):
        leaves = ex.skeleton.leaf_id
        if op in ("regrow", "prune"):
            ex.select(rng.choice(leaves, size=int(rng.integers(1, 40)), replace=False).tolist())
            ex.regrow(seed=step) if op == "regrow" else ex.prune()
        else:
            getattr(ex, op)()
        show_model_plant(shown, ex)
        fresh = PlantActors(BarePlotter())
        show_model_plant(fresh, ex)
        assert_same_groups(groups_of(shown), groups_of(fresh))
    assert len(patched) >= 4  # the regrows were patched, not sorted again


def test_a_regrow_that_grows_a_thicker_branch_sorts_again():
    ex = Explorer("#define W 0.5\nn: 6\nw: !(1)FA\np:\n A -> !(W)F[+A][-A]A\n", n=6)
    shown = PlantActors(BarePlotter())
    show_model_plant(shown, ex)
    before = shown._classes["top"]
    ex.select(ex.skeleton.leaf_id[-20:].tolist())
    ex.regrow(seed=1, constants={"W": 4})  # the regrown branches are thicker than the trunk
    show_model_plant(shown, ex)
    fresh = PlantActors(BarePlotter())
    show_model_plant(fresh, ex)
    assert_same_groups(groups_of(shown), groups_of(fresh))
    assert shown._classes["top"] > before
