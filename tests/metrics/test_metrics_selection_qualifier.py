"""A qualifier applied to a selection acts on that selection's cut only (issue 34 section 2, issue 35
item 3).  On 3 tips of a conifer, 7 of the 22 qualifiers once replaced the whole plant (the cut
climbed 7 levels to the axiom, root [0]) and "fir-like" 813 of 1115 modules; the text said nothing."""

import pathlib

import numpy as np
import pytest

from ramure.app.model import Explorer
from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session
from ramure.metrics import VariantSweep
from ramure.metrics.apply import apply_qualifier
from ramure.metrics.qualifiers import VOCABULARY

CONIFER = pathlib.Path(__file__).parents[1] / "data" / "conifer.lsys"


@pytest.fixture(scope="module")
def conifer():
    ls = LSystem.from_file(CONIFER)
    return ls, VariantSweep(n_jobs=1, cache=False).fit(ls)


def _three_tips(session):
    tree = session.tree
    f = session.leaves_with_symbol("F")
    tips = f[tree.step[f] == session.n]
    return tips[len(tips) // 2 : len(tips) // 2 + 3].tolist()


def test_all_22_qualifiers_on_three_tips_stay_in_the_tips_cut(conifer):
    ls, sweep = conifer
    assert len(VOCABULARY) == 22
    said = refused = last = grown = 0
    for q in VOCABULARY:
        session = Session(ls)
        tips = _three_tips(session)
        tree, total = session.tree, len(session.tree.leaves)
        shown = session.plan(tips, 0.5)[1]  # what the preview shows a Regrow would change
        assert len(shown) == 3 and (tree.depth_of(shown) >= 2).all()
        out = apply_qualifier(session, q, sweep, selection=tips, tries=2)
        depth = tree.depth_of(out.roots)
        assert (depth >= 2).all(), (q, out.roots.tolist(), depth.tolist())  # never the axiom or a main branch
        assert set(out.roots.tolist()) <= set(shown.tolist()) and out.climbed == 0, (q, out.roots)
        changed = out.regen.removed if out.regen is not None else 0
        assert changed <= 0.05 * total, (q, changed, total)
        if q == "normal":  # no direction: the closest combination, applied to the same cut
            assert out.regen is not None and out.roots.tolist() == shown.tolist()
        elif not out.improved:
            assert out.reason and out.suggestion and not session.edits
            # the tips' part cannot show new constants, nor gain what the word asks with one
            # more derivation step of its own: the reason says both
            said += "n +1 inside the selection" in out.reason
            last += "last derivation step" in out.reason
            refused += 1
        elif "steps" in out.changed:  # the part grew one step more, the rest of the plant did not
            grown += 1
            assert out.changed["text"].startswith("n 7 -> 8 inside the selection") and session.n == 7
            assert out.roots.tolist() == shown.tolist()
    assert said == refused >= 5 and last >= 5 and grown >= 10, (said, refused, last, grown)


def test_a_qualifier_keeps_the_regrown_part_selected_as_regrow_does(conifer):
    _, sweep = conifer
    ex = Explorer(str(CONIFER))
    tree = ex.derivation.tree
    branch = np.flatnonzero((tree.depth == 2) & tree.alive & (tree.symbol == ex.lsystem.symbols.index("B")))
    ex.select(tree.leaves_under(int(branch[len(branch) // 2])).tolist())
    shown = ex.preview()
    out = ex.apply_qualifier("regular", sweep)
    assert out.improved and out.roots.tolist() == shown.roots.tolist()
    added = np.asarray(out.regen.change.added)
    assert ex.selection == sorted(added[tree.child_count[added] == 0].tolist()) and ex.selection
    assert f"regrew {out.regen.removed} of {shown.total:,} modules" in ex.status()
    ex.select(ex.selection)  # the same part again: a Regrow now previews exactly it
    assert ex.preview().changed == out.regen.added


GRAMMARS = pathlib.Path(__file__).parents[1] / "data" / "grammars"


@pytest.mark.parametrize("name", ["shrub", "vine", "palm", "stochastic_bush"])
def test_three_tips_never_replace_the_whole_plant_on_the_new_grammars(name):
    """Issue 35's figures: on 3 tips, 8 of 22 qualifiers (conifer) and 10 of 22 (shrub) replaced
    the whole plant.  Now none does on any of the grammars written for it: each regrows at most
    the previewed cut of the tips, never an axiom module, or leaves the plant and says why."""
    ls = LSystem.from_file(GRAMMARS / f"{name}.lsys")
    sweep = VariantSweep(n_jobs=1, cache=False, wide=0.25).fit(ls)
    whole, applied = 0, 0
    for q in VOCABULARY:
        session = Session(ls)
        tips = _three_tips(session)
        tree, total = session.tree, len(session.tree.leaves)
        shown = session.plan(tips, 0.5)[1]
        assert len(tips) == 3 and (tree.parent[shown] >= 0).all()
        out = apply_qualifier(session, q, sweep, selection=tips, tries=2)
        whole += bool((tree.parent[out.roots] < 0).any()) or session.n != ls.n
        assert set(out.roots.tolist()) <= set(shown.tolist()) and out.climbed == 0, (q, out.roots)
        if out.regen is not None:
            applied += out.improved
            assert out.regen.removed <= 0.1 * total, (q, out.regen.removed, total)
        else:
            assert out.reason and out.suggestion and not session.edits
    assert whole == 0


def test_dense_and_bushy_grow_a_selected_branch_one_step_more_and_nothing_else():
    """Issue 35 section 3: on Honda, no constant changes the number of segments, so "dense" and
    "bushy" on a selection were refused.  The selection's part now regrows one derivation step
    more (the rest of the plant unchanged, the cut the preview shows, the part kept selected)."""
    sweep = VariantSweep(n=6, n_jobs=1, cache=False, wide=0.25).fit("honda_sympodial")
    ex = Explorer("honda_sympodial", n=6)
    tree = ex.derivation.tree
    f = set(ex.session.leaves_with_symbol("F").tolist())
    branch = np.flatnonzero(tree.alive & (tree.depth == 3) & (tree.child_count > 0))
    leaves = [x for x in tree.leaves_under(int(branch[len(branch) // 2])).tolist() if x in f]
    ex.select(leaves)
    shown = ex.preview()
    old = ex.derivation.to_string()
    first, last = tree.string_spans(shown.roots)
    outside = np.concatenate([tree.leaves[: first.min()], tree.leaves[last.max() + 1 :]])
    out = ex.apply_qualifier("bushy", sweep)
    assert out.improved and out.changed["steps"] == 1 and "n 6 -> 7 inside the selection" in out.changed["text"]
    assert out.roots.tolist() == shown.roots.tolist() and ex.session.n == 6
    assert out.after.branch_count > out.before.branch_count and out.after.crown_width > out.before.crown_width
    assert np.isin(outside, tree.leaves).all()  # every leaf outside the part is still there
    assert (tree.step[tree.leaves] == 7).any()  # the part grew a step past the plant's n
    added = np.asarray(out.regen.change.added)
    # the part grown stays selected: its new leaves that draw (as a Regrow keeps them)
    assert set(ex.selection) <= set(added[tree.child_count[added] == 0].tolist()) and len(ex.selection) > len(leaves)
    assert f"regrew {out.regen.removed} of {shown.total:,} modules" in ex.status()
    ex.session.undo()
    assert ex.derivation.to_string() == old
