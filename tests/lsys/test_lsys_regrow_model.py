"""The model's part of an edit (issue 14) gives exactly what a full rebuild gives."""

import numpy as np

from ramure.app.model import Explorer, mesh_sides
from ramure.lsys.interpretation.geometry import skeleton_to_polydata
from ramure.lsys.interpretation.turtle import interpret_string

from test_lsys_turtle_edits import assert_same, assert_same_mesh

#: Polygons are rare: the first plant (seed 0) has none, regrown branches may grow some.
RARE_POLYGONS = "#angle 30\nn: 3\nw: A\np:\n A -> F[+A][-A]FA : 40\n A -> F[&{+f-ff-f+|+f-ff-f}]A : 1\n"


def test_polygons_that_only_regrown_branches_grow_are_drawn_as_a_rebuild_draws_them():
    ex = Explorer(RARE_POLYGONS, n=3, seed=0)
    assert len(ex.skeleton.polygons) == 0
    ex.mesh  # noqa: B018 - patched by the edits below
    rng = np.random.default_rng(1)
    grew = False
    for step in range(40):
        tree = ex.derivation.tree  # every leaf under a random node (the derivation tree's Select)
        inner = np.flatnonzero(tree.alive & (tree.child_count > 0))
        ex.select(tree.leaves_under(int(rng.choice(inner))).tolist())
        ex.regrow(seed=step)
        incremental = ex.skeleton
        assert "reuse" in incremental.extra
        assert incremental.extra["polygon_acts"] == bool(len(incremental.polygons))
        full = interpret_string(ex.lsystem, ex.derivation.tree, ex.derivation.tree.leaves)
        assert_same(incremental, full)
        assert_same_mesh(ex.mesh, skeleton_to_polydata(full, mesh_sides(len(full))))
        if len(incremental.polygons):
            grew = True
            ex.undo()  # back to a plant without polygons, whose flag says so
            assert len(ex.skeleton.polygons) == 0 and ex.skeleton.extra.get("polygon_acts") in (False, None)
    assert grew


def test_undo_and_redo_after_many_regrows_give_the_rebuilt_plant():
    ex = Explorer("honda_sympodial.lsys", n=10)
    rng = np.random.default_rng(5)
    for step in range(6):
        leaves = ex.skeleton.leaf_id
        ex.select(rng.choice(leaves, size=10, replace=False).tolist())
        ex.regrow(seed=step)
    for op in ("undo", "undo", "redo", "undo", "undo", "undo", "redo", "redo"):
        getattr(ex, op)()
        full = interpret_string(ex.lsystem, ex.derivation.tree, ex.derivation.tree.leaves)
        assert_same(ex.skeleton, full)
        assert_same_mesh(ex.mesh, skeleton_to_polydata(full, mesh_sides(len(full))))


def test_a_regrow_that_overflows_names_the_module_a_full_turtle_names():
    from ramure.errors import RamureError

    ex = Explorer("#define L 1\nn: 4\nw: A\np:\n A -> F(L)[+A]F(L)A\n", n=4)
    ex.mesh  # noqa: B018 - the edit below is re-interpreted in part
    leaves, depth = ex.skeleton.leaf_id, ex.derivation.tree.depth
    ex.select(leaves[np.argsort(depth[leaves], kind="stable")[-3:]].tolist())  # the deepest segments: they regrow
    ex.regrow(seed=1, constants={"L": 1e308})
    messages = []
    for draw in (lambda: ex.skeleton, lambda: interpret_string(ex.lsystem, ex.derivation.tree, ex.derivation.tree.leaves)):
        try:
            draw()
        except RamureError as exc:
            messages.append(str(exc))
    assert len(messages) == 2 and messages[0] == messages[1] and "F(1e+308)" in messages[0]


def test_collapse_nested_keeps_the_highest_roots_of_few_or_many():
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.mincut import collapse_nested

    tree = LSystem.from_file("honda_sympodial").derive(n=10).tree
    rng = np.random.default_rng(0)
    alive = np.flatnonzero(tree.alive)
    for size in (0, 1, 2, 10, 200, 256, 257, 600):
        roots = rng.choice(alive, size)
        roots = np.r_[roots, tree.parent[roots[: size // 3]]]
        roots = np.unique(roots[roots >= 0])
        above = [set(tree.ancestors(int(r)).tolist()) for r in roots]
        expected = [int(r) for r, up in zip(roots, above) if not up & set(roots.tolist())]
        assert collapse_nested(tree, roots).tolist() == expected
