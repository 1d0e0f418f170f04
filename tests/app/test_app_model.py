"""The shared explorer state (app.model.Explorer), without any GUI."""

import json

import numpy as np
import pytest

from ramure.app.model import Explorer, leaves_in_rectangle
from ramure.lsys import RamureError
from ramure.lsys.regeneration.regen import Session

HONDA = "grammars/honda_sympodial.lsys"


@pytest.fixture
def ex():
    return Explorer(HONDA, n=6)


def test_selection_modes(ex):
    f = ex.session.leaves_with_symbol("F")[:4].tolist()
    ex.select(f[:2])
    ex.select(f[2:3], mode="add")
    assert ex.selection == sorted(f[:3])
    ex.select(f[1:2], mode="remove")
    assert ex.selection == sorted([f[0], f[2]])
    ex.select(f[:2], mode="toggle")
    assert ex.selection == sorted([f[1], f[2]])
    ex.clear_selection()
    assert ex.selection == []
    with pytest.raises(RamureError, match="not a leaf"):
        ex.select([0])


def test_rectangle_picks_segments_inside():
    xy = np.array([[0, 0], [5, 5], [10, 10], [5, 5]])
    assert leaves_in_rectangle([7, 8, 9, 8], xy, (11, 11, 4, 4)) == [8, 9]


def _vtk_display_points(plotter, points):
    """Display coordinates of world points by VTK's own renderer (one point at a time)."""
    out = []
    for point in points:
        plotter.renderer.SetWorldPoint(*point, 1.0)
        plotter.renderer.WorldToDisplay()
        out.append(plotter.renderer.GetDisplayPoint()[:2])
    return np.array(out)


def test_a_rubber_band_selects_the_same_leaves_in_both_front_ends():
    """The notebook's rectangle goes through the model's leaves_in_view; the desktop's window
    projects its snapshot's midpoints and organ centres: for the same camera and rectangle they
    select the same leaves, those VTK itself puts inside the rectangle."""
    pv = pytest.importorskip("pyvista")
    from ramure.app.desktop import state
    from ramure.app.render import frame_camera, headless_setup, projection_matrix

    headless_setup()
    ex = Explorer("grammars/fruit_tree.lsys")  # branches, leaves and fruit
    plotter = pv.Plotter(off_screen=True, window_size=[300, 200])
    plotter.add_mesh(ex.mesh)
    frame_camera(plotter, ex.mesh.bounds, "iso")
    plotter.render()
    matrix, size = projection_matrix(plotter.renderer), (300, 200)
    rect = (260, 40, 120, 190)  # the upper right of the crown, corners in any order
    notebook = ex.leaves_in_view(matrix, size, rect)

    snap = state.take_snapshot(ex)  # what the desktop window projects
    xy = state.project_to_display(matrix, np.concatenate([snap.midpoints, snap.organ_points]), size)
    desktop = leaves_in_rectangle(np.concatenate([snap.segment_leaf, snap.organ_leaves]), xy, rect)

    points, leaves = ex.rectangle_points()
    vtk_xy = _vtk_display_points(plotter, points)
    inside = (vtk_xy[:, 0] >= 120) & (vtk_xy[:, 0] <= 260) & (vtk_xy[:, 1] >= 40) & (vtk_xy[:, 1] <= 190)
    plotter.close()
    assert notebook == desktop == sorted(set(leaves[inside].tolist()))
    assert 0 < len(notebook) < len(set(leaves.tolist()))  # some of the plant, not all of it
    assert set(notebook) & set(ex.fruit_ids())  # fruit are selected by their centres
    ex.select(notebook)
    assert ex.selection == notebook


def test_cell_maps_to_leaf(ex):
    mesh = ex.mesh
    cell = int(np.flatnonzero(mesh.cell_data["segment"] == 5)[0])
    assert ex.leaf_of_cell(cell) == int(ex.skeleton.leaf_id[5])
    with pytest.raises(RamureError):
        ex.leaf_of_cell(10**9)


def test_bad_grammar_keeps_plant(ex):
    before = ex.derivation.to_string()
    err = ex.set_text("n: 2\nw: A(\n")
    assert err is not None and err.line == 2
    assert ex.error is err and ex.derivation.to_string() == before
    assert ex.set_text(ex.text.replace("60", "45")) is None and ex.error is None


def test_bad_values_refused_and_nothing_changes(ex):
    before, version = ex.derivation.to_string(), ex.version
    for call in (
        lambda: ex.set_constant("r1", "abc"),
        lambda: ex.set_constant("nope", 1),
        lambda: ex.set_constant("r1", float("nan")),
        lambda: ex.set_rho(0),
        lambda: ex.set_rho(250),
        lambda: ex.set_derivation(n=-1),
        lambda: ex.prune(),
        lambda: ex.regrow_fruit(),
    ):
        with pytest.raises(RamureError):
            call()
    assert ex.derivation.to_string() == before and ex.version == version


def test_regrow_undo_redo_and_version(ex):
    before = ex.derivation.to_string()
    ex.set_rho(0.8)
    assert ex.rho == 0.8
    ex.select(ex.session.leaves_with_symbol("F")[-6:])
    v = ex.version
    result = ex.regrow(constants={"a2": 20})
    assert ex.version == v + 1 and result.roots.size
    tree = ex.derivation.tree
    added = np.asarray(result.change.added)
    drawn = np.union1d(ex.skeleton.leaf_id, ex.skeleton.organs.leaf_id)
    new = added[tree.child_count[added] == 0]
    assert ex.selection == sorted(new[np.isin(new, drawn)].tolist()) and ex.selection  # its segments stay selected
    assert ex.preview().roots.tolist() == result.roots.tolist()  # so Regrow again regrows the same part
    assert f"regrew {result.removed} of " in ex.status()
    assert ex.undo() is not None and ex.derivation.to_string() == before
    assert ex.redo() is not None and ex.derivation.to_string() != before


def test_kinship_needs_one_leaf(ex):
    assert ex.kinship_hues() is None
    leaf = int(ex.skeleton.leaf_id[3])
    ex.select([leaf])
    rgb = ex.kinship_hues()
    assert rgb.shape == (len(ex.skeleton), 3)
    assert np.allclose(rgb[3], [1, 0, 0])  # the selection itself is red


def test_order_filter(ex):
    picked = ex.leaves_where(min_order=3, min_height=1.0)
    sk = ex.skeleton
    mask = np.isin(sk.leaf_id, picked)
    assert mask.any() and (sk.order[mask] >= 3).all()


def test_exports(ex, tmp_path):
    for suffix in (".vtp", ".obj", ".gltf"):
        path = ex.export(tmp_path / f"plant{suffix}")
        assert path.stat().st_size > 1000
    obj = (tmp_path / "plant.obj").read_text().splitlines()
    assert sum(line.startswith("f ") for line in obj) == 2 * ex.mesh.n_cells  # quads -> 2 triangles
    with pytest.raises(RamureError, match="cannot export"):
        ex.export(tmp_path / "plant.xyz")


def test_session_round_trip(ex, tmp_path):
    ex.select(ex.session.leaves_with_symbol("F")[10:14])
    ex.regrow()
    path = ex.save_session(tmp_path / "s.json")
    other = Explorer(HONDA, n=3)
    other.load_session(path)
    assert other.derivation.to_string() == ex.derivation.to_string()
    (tmp_path / "broken.json").write_text(json.dumps({"format": "ramure-session"})[:-3])
    with pytest.raises(RamureError):
        other.load_session(tmp_path / "broken.json")
    assert other.derivation.to_string() == ex.derivation.to_string()


def test_regrow_one_fruit_changes_only_that_fruit():
    ex = Explorer("grammars/fruit_tree.lsys")
    fruit = ex.fruit_ids()
    base = ex.fruit_volumes()
    ex.select(fruit[:1])
    ex.regrow_fruit(preset="pear")
    assert ex.status().endswith("1 fruit regrown")
    surface = ex.fruit_surface()
    assert set(np.unique(surface.cell_data["leaf_id"]).tolist()) == set(fruit)
    after = ex.fruit_volumes()
    leaf = np.asarray(after.volume_data["leaf_id"])
    old = np.asarray(base.volume_data["leaf_id"])
    assert (leaf == fruit[0]).sum() != (old == fruit[0]).sum()  # the pear has another shape
    for other in fruit[1:]:
        assert (leaf == other).sum() == (old == other).sum()
    # saved and replayed: the override comes back
    s = Session.from_dict(ex.session.to_dict())
    assert (
        s.fruit_overrides()
        == ex.session.fruit_overrides()
        == {fruit[0]: {"preset": "pear", "seed": s.edits[0]["settings"]["seed"]}}
    )
    ex.undo()
    assert ex.session.fruit_overrides() == {}


def test_one_fruit_built_alone_is_that_fruit_among_all():
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    ex = Explorer("grammars/fruit_tree.lsys")
    fruit = ex.fruit_ids()
    ex.select(fruit[2:3])
    ex.regrow_fruit(preset="pear")  # an override: the pear must come back alone too
    every = to_unstructured_grid(ex.fruit_volumes(volume_levels=1))
    for leaf in (fruit[0], fruit[2]):
        alone = to_unstructured_grid(ex.fruit_volume(leaf, volume_levels=1))
        among = every.extract_cells(np.asarray(every.cell_data["leaf_id"]) == leaf)
        assert alone.n_cells == among.n_cells > 100
        assert set(np.unique(alone.cell_data["leaf_id"]).tolist()) == {leaf}
        assert np.allclose(alone.bounds, among.bounds)
        assert alone.volume == pytest.approx(among.volume)
        assert np.array_equal(np.bincount(alone.cell_data["tissue"]), np.bincount(among.cell_data["tissue"]))
    assert to_unstructured_grid(ex.fruit_volume(fruit[0])).n_cells != to_unstructured_grid(ex.fruit_volume(fruit[2])).n_cells
    with pytest.raises(RamureError, match="not a fruit"):
        ex.fruit_volume(10**9)


def test_apply_qualifier_makes_the_selection_thicker_and_undoes():
    from ramure.metrics import VariantSweep

    ex = Explorer(HONDA, n=5)
    ex.set_constant("a2", 50)  # the sweep must start from the session's constants
    ls = ex.variant_lsystem()
    assert ls.constants["a2"] == 50 and ex.lsystem.constants["a2"] == 60
    sweep = VariantSweep(n=5, n_jobs=1, cache=False).fit(ls)
    before = ex.derivation.to_string()
    tree = ex.derivation.tree
    twig = np.flatnonzero((tree.depth == 2) & tree.alive & (tree.child_count > 0))[-1]
    ex.select(tree.leaves_under(int(twig)).tolist())  # a twig three steps from the tips
    shown = ex.preview()
    # "denser" adds segments (issue 35), which no constant of Honda does: "thicker" here
    out = ex.apply_qualifier("thicker", sweep)
    assert out.improved and out.after.mean_radius > out.before.mean_radius
    assert out.roots.tolist() == shown.roots.tolist() == [twig]  # what the preview showed, nothing more
    added = np.asarray(out.regen.change.added)
    assert ex.selection == sorted(added[tree.child_count[added] == 0].tolist())  # kept selected, as Regrow does
    assert ex.derivation.to_string() != before
    ex.undo()
    assert ex.derivation.to_string() == before


def test_select_refuses_erased_and_dead_modules_like_leaf_positions():
    """The leaf check (childless with a leaf span) agrees with the string's positions: a module an
    empty successor erased, a module a regrow removed and an inner node are all refused."""
    from ramure.app.model import Explorer

    ex = Explorer("n: 3\nw: A\np:\n  A -> F[+A]B\n  B ->\n", n=3)
    tree = ex.derivation.tree
    in_string = tree.leaf_positions(np.arange(tree.size)) >= 0
    erased = np.flatnonzero((tree.child_count == 0) & ~in_string)
    assert erased.size  # the B modules
    for node in range(tree.size):
        if in_string[node]:
            ex.select([node])
        else:
            with pytest.raises(RamureError, match="not a leaf"):
                ex.select([node])
    leaves = ex.derivation.tree.leaves
    ex.select([int(leaves[np.argmax(ex.derivation.tree.depth[leaves])])])  # a tip: it regrows with its siblings
    ex.regrow(seed=1)
    dead = np.flatnonzero(~ex.derivation.tree.alive)
    assert dead.size
    with pytest.raises(RamureError, match="not a leaf"):
        ex.select([int(dead[-1])])


_WARM_UP = """
import json, sys, time
from ramure.app.model import Explorer, warm_up_edits
ex = Explorer("grammars/honda_sympodial.lsys", n=12)
ex.mesh
ex.select(ex.skeleton.leaf_id[len(ex.skeleton.leaf_id) // 3 :: 500][:10])
before = "networkx" in sys.modules
numba_before = "numba" in sys.modules
warmed = {warm} and warm_up_edits(ex.text, ex.session.n)
from numba.core import dispatcher
loads = []
original = dispatcher.Dispatcher._compile_for_args
def counted(self, *args, **kwargs):
    loads.append(self.py_func.__name__)
    return original(self, *args, **kwargs)
dispatcher.Dispatcher._compile_for_args = counted
ex.regrow(seed=1)
ex.mesh
print(json.dumps({{"before": before, "numba_before": numba_before, "warmed": warmed, "loads": loads}}))
"""


@pytest.mark.parametrize("warm", [False, True])
def test_after_the_warm_up_the_first_regrow_imports_and_loads_nothing(warm):
    import pathlib
    import subprocess
    import sys

    code = _WARM_UP.format(warm=warm)
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=pathlib.Path(__file__).resolve().parents[2]
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["before"] is False  # a plant drawn and a selection made: networkx not needed yet
    assert out["numba_before"] is False  # nor numba, for 45,045 modules (issue 34: a fast first call)
    if warm:
        assert out["warmed"] is True and out["loads"] == []
    else:  # without it, the first regrow loads the edit kernels (and imports networkx)
        assert {"leaf_sums", "walk"} <= set(out["loads"])


def test_a_warm_up_on_text_that_gives_no_plant_says_so_and_raises_nothing():
    from ramure.app.model import warm_up_edits

    assert warm_up_edits("n: 2\nw: A\np: A -> ((", 2) is False
    assert warm_up_edits("n: 1\nw: A\np: A -> A\n", 1) is False  # no segment to select
    jump = "n: 2\nw: A\np:\n  A -> " + "B" * 400 + "\n  B -> " + "F" * 400 + "\n"  # 401 nodes, then 160,401
    assert warm_up_edits(jump, 2) is False  # as costly as an edit: not warmed up
    assert warm_up_edits(jump.replace("F" * 400, "F" * 20), 2) is True  # 8,401 nodes


def test_a_constant_after_pruning_a_regrown_branch_forgets_the_old_cut():
    """Issue 34 §3: regrow a quarter, prune one regrown branch, set a2 = 45.  The constant
    re-derives the plant into a new tree (as large as the first); the prune's cut names nodes of
    the regrown tree, past its end.  The constant edit is the last edit now: the snapshot the
    desktop takes after it drew the stale cut's graph and raised IndexError."""
    from ramure.app.desktop import state

    ex = Explorer(HONDA, n=9)
    first_size = ex.derivation.tree.size
    leaves = ex.skeleton.leaf_id
    ex.select(leaves[: len(leaves) // 4])
    result = ex.regrow(seed=1)
    ex.select(state.regrown_leaves(ex, result))
    regrown = np.asarray(ex.selection)
    drawn = np.intersect1d(regrown, ex.skeleton.leaf_id)
    ex.select([int(drawn[len(drawn) // 2])])  # one regrown branch: a node past the first tree's end
    assert ex.selection[0] >= first_size
    pruned = ex.prune()
    assert pruned.op == "prune" and pruned.cut is not None
    pruned_modules = len(ex.derivation)
    ex.set_constant("a2", 45)
    assert ex.derivation.tree.size == first_size  # the new tree ends before the pruned leaf's id
    assert ex.last_result.op == "constants" and ex.last_result.cut is None
    assert "constants changed" in ex.status()
    snap = state.take_snapshot(ex)
    assert snap.cut_layout is None and snap.n_modules == len(ex.derivation)
    assert "constants changed, whole plant re-derived" in snap.status
    ex.undo()  # back to the pruned plant: no edit result shown, as after any undo
    assert ex.last_result is None and state.take_snapshot(ex).n_modules == pruned_modules
