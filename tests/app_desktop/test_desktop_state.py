"""Qt-free helpers of the desktop window: snapshots, projection, colours, cut layout, variants."""

from __future__ import annotations

import doctest
import json

import numpy as np
import pytest

from ramure.app.desktop import state, variants
from ramure.app.model import Explorer
from desktop_helpers import HONDA, ROOT
from ramure.errors import RamureError


def test_doctests():
    assert doctest.testmod(state).failed == 0


@pytest.fixture(scope="module")
def explorer():
    return Explorer(str(HONDA), n=6)


def test_snapshot_reuses_heavy_parts_for_the_same_version(explorer):
    first = state.take_snapshot(explorer)
    explorer.select(explorer.session.leaves_with_symbol("F")[:2])
    second = state.take_snapshot(explorer, first)
    assert second.mesh is first.mesh and second.selection != first.selection
    assert "2 selected" in second.status
    explorer.clear_selection()


def test_projection_matches_a_hand_made_perspective():
    # a camera at z=+5 looking down -z, 90 degree field of view: x/(5-z) scaled to the viewport
    near, far = 0.1, 100.0
    f = 1.0  # cot(45 degrees)
    proj = np.array(
        [[f, 0, 0, 0], [0, f, 0, 0], [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]]
    )
    view = np.eye(4)
    view[2, 3] = -5.0
    pts = np.array([[1.0, 0.5, 0.0], [0.0, 0.0, 3.0], [0.0, 0.0, 6.0]])
    xy = state.project_to_display(proj @ view, pts, (400, 200))
    assert np.allclose(xy[0], [200 + 200 * 1 / 5, 100 + 100 * 0.5 / 5])
    assert np.allclose(xy[1], [200, 100])
    assert np.isnan(xy[2]).all()  # behind the camera


def test_changed_constants():
    assert state.changed_constants({"a": 1.0, "b": 2.5}, {"a": 1.0, "b": 2.0}) == {"b": 2.5}


def test_kinship_colours_put_the_selection_in_red(explorer):
    leaf = int(explorer.skeleton.leaf_id[-1])
    explorer.select([leaf])
    rgb = state.kinship_cell_colors(explorer, explorer.mesh)
    mine = np.asarray(explorer.mesh.cell_data["leaf_id"]) == leaf
    assert rgb.shape == (explorer.mesh.n_cells, 3) and (rgb[mine] == [255, 0, 0]).all()
    explorer.select([leaf, int(explorer.skeleton.leaf_id[0])])
    assert state.kinship_cell_colors(explorer, explorer.mesh) is None
    explorer.clear_selection()


def test_selection_box_encloses_the_selected_segments(explorer):
    sk = explorer.skeleton
    sel = sk.leaf_id[-8:].tolist()
    lines = state.selection_box_lines(sk, sel)
    assert lines.shape == (12, 2, 3)
    corners = np.unique(lines.reshape(-1, 3), axis=0)
    centre = corners.mean(axis=0)
    axes = np.linalg.svd(corners - centre)[2]
    half = np.abs((corners - centre) @ axes.T).max(axis=0)
    pts = np.r_[sk.start[-8:], sk.end[-8:]]
    assert (np.abs((pts - centre) @ axes.T) <= half + 1e-6).all()
    assert state.selection_box_lines(sk, []) is None


def test_cut_graph_layout_rows_follow_depth(explorer):
    explorer.select(explorer.skeleton.leaf_id[-6:])
    cut = explorer.plan()
    layout = state.cut_graph_layout(cut, explorer.derivation.tree, cut.roots)
    depth = explorer.derivation.tree.depth
    for v, (x, y) in layout.positions.items():
        if isinstance(v, tuple) and v[1] == "in":
            assert layout.positions[(v[0], "out")][1] > y
    ins = [v for v in layout.positions if isinstance(v, tuple) and v[1] == "in"]
    deeper = max(ins, key=lambda v: depth[v[0]])
    assert layout.positions[deeper][1] >= max(layout.positions[v][1] for v in ins)
    assert layout.positions["s"][1] < layout.positions["t"][1]
    cut_edges = [e for e in layout.edges if e[3]]
    assert len(cut_edges) >= 1 and all(u in layout.source_side for u, *_ in cut_edges)
    explorer.clear_selection()


def test_load_exploration(tmp_path):
    picks = [{"id": i, "variant": i, "pca": [i, 0, 0], "params": {"rule": 0, "constants": {"a2": 50 + i}}} for i in range(1, 28)]
    (tmp_path / "picks.json").write_text(json.dumps(picks))
    (tmp_path / "variants.csv").write_text("id,rule,pc1,pc2,pc3,failed\n0,0,1,2,3,0\n1,0,,,,1\n")
    vs = variants.load_exploration(tmp_path)
    assert len(vs.picks) == 27 and vs.points.shape == (2, 3) and np.isnan(vs.points[1]).all()
    assert vs.qualifiers == []  # no sweep: no qualifiers
    with pytest.raises(RamureError, match="no picks.json"):
        variants.load_exploration(tmp_path / "nowhere")
    (tmp_path / "picks.json").write_text("[{")
    with pytest.raises(RamureError, match="not valid JSON"):
        variants.load_exploration(tmp_path)


def test_variant_skeleton_applies_the_combination_to_one_rule():
    from ramure.lsys import LSystem

    ls = LSystem.from_file(ROOT / "grammars" / "honda_sympodial.lsys")
    base = variants.variant_skeleton(ls, 5, 0, None)
    other = variants.variant_skeleton(ls, 5, 0, {"rule": 1, "constants": {"a2": 30.0}})
    direct = ls.derive(n=5, seed=0, params={"rule": 1, "constants": {"a2": 30.0}}).skeleton()
    assert np.allclose(other.end, direct.end) and not np.allclose(other.end, base.end)


def test_set_constant_merging_replaces_only_its_own_last_edit():
    ex = Explorer(str(HONDA), n=4)
    first = state.set_constant_merging(ex, "a2", 50)
    second = state.set_constant_merging(ex, "a2", 40, previous=first)
    assert len(ex.session.edits) == 1 and ex.constants["a2"] == 40
    with pytest.raises(RamureError):
        state.set_constant_merging(ex, "a2", float("nan"), previous=second)
    assert len(ex.session.edits) == 1 and ex.constants["a2"] == 40  # refused: history as it was
    ex.select(ex.session.leaves_with_symbol("F")[-3:])
    ex.regrow(seed=1)  # another edit in between: the drag's next value is a new step
    state.set_constant_merging(ex, "a2", 30, previous=second)
    assert [e["op"] for e in ex.session.edits] == ["constants", "regrow", "constants"]
    ex.undo(), ex.undo(), ex.undo()
    assert ex.constants["a2"] == 60


def test_cut_graph_layout_is_a_tidy_tree():
    ex = Explorer(str(HONDA), n=6)
    ex.select(ex.skeleton.leaf_id[-40:])
    cut = ex.plan()
    tree = ex.derivation.tree
    layout = state.cut_graph_layout(cut, tree, cut.roots, ex.lsystem.symbols)
    nodes = {v[0] for v in layout.positions if isinstance(v, tuple)}
    xs = {v: layout.positions[(v, "in")][0] for v in nodes}
    for v in nodes:
        kids = [k for k in nodes if tree.parent[k] == v]
        if kids:  # a parent sits over its children
            assert min(xs[k] for k in kids) <= xs[v] <= max(xs[k] for k in kids)
    rows = {}
    for v in nodes:
        rows.setdefault(layout.positions[(v, "in")][1], []).append(xs[v])
    assert all(len(set(r)) == len(r) for r in rows.values())  # no two nodes on one spot
    assert set(layout.names) == nodes and all(layout.names.values())


def test_base_colors_are_the_shared_palette_looked_up_by_kind():
    """The desktop's palette lookup gives plant_colors' very bytes (bark, leaf, fruit, materials)."""
    from ramure.app.desktop.state import base_colors
    from ramure.app.model import Explorer
    from ramure.app.render import plant_colors
    import ramure.grammars as grammars

    for name, n in (("fruit_tree", 5), ("apricot_tree", 4), ("honda_sympodial", 8)):
        mesh = Explorer(str(grammars.path(name)), n=n).mesh
        rgb = base_colors(mesh)
        assert rgb.dtype == np.uint8 and rgb.shape == (mesh.n_cells, 3)
        assert np.array_equal(rgb, plant_colors(mesh)), name
    kinds = np.unique(np.asarray(Explorer(str(grammars.path("fruit_tree")), n=5).mesh.cell_data["kind"]))
    assert {0, 1, 2} <= set(kinds.tolist())  # every palette row is checked


@pytest.mark.parametrize("grammar, n", [("honda_sympodial", 12), ("stochastic_plant", 6), ("fruit_tree", 6)])
def test_regrown_leaves_are_the_added_nodes_in_the_string(grammar, n):
    import ramure.grammars as grammars

    ex = Explorer(str(grammars.path(grammar)), n=n)
    for seed in range(3):
        leaves = ex.skeleton.leaf_id
        ex.select(sorted(int(v) for v in np.random.default_rng(seed).choice(leaves[len(leaves) // 3 :], 5, replace=False)))
        result = ex.regrow(seed=seed)
        tree = ex.derivation.tree
        added = np.asarray(result.change.added, np.int64)
        expected = np.sort(added[np.isin(added, tree.leaves)]).tolist()  # the string itself, searched
        got = state.regrown_leaves(ex, result)
        assert got == expected and len(got) > 0
        ex.select(got, "replace")  # every one is a leaf the model accepts (else ValueRefused)
        assert sorted(ex.selection) == got


def test_the_regrow_note_says_why_and_what_next():
    from ramure.app.desktop.state import REGROWN, SAME_PLANT, regrow_note

    assert regrow_note("regrow", "new constants apply from the next step", True, True) == (
        "New constants apply from the next step."
    )  # the model's own words come first
    assert regrow_note("regrow", None, True, True) == SAME_PLANT  # a deterministic grammar
    assert regrow_note("regrow", "", False, True) == REGROWN
    assert regrow_note("regrow", None, False, False) == ""
    assert regrow_note("prune", "a note", True, True) == ""  # only a regrow gets a note
