"""What the 3D view does for a new plant version besides painting (issue 14: regrow to the frame
<= 100 ms): bounds patched instead of computed by VTK, hairlines written into the memory of the
version dropped, colours computed once.  Each shortcut equals what it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.desktop import state
from ramure.app.desktop.view import plant_actors, scene
from ramure.app.desktop.view.plant_actors import PlantActors
from ramure.app.model import Explorer
from desktop_helpers import HONDA, BarePlotter, show_model_plant


def edit(ex, op, rng, step):
    """One random edit; ``top`` prunes the highest branch tips (a removed tube on the box)."""
    leaves = ex.skeleton.leaf_id
    if op == "top":
        z = np.maximum(np.asarray(ex.skeleton.start)[:, 2], np.asarray(ex.skeleton.end)[:, 2])
        ex.select(np.unique(leaves[np.argsort(z)[-3:]]).tolist())
        ex.prune()
    elif op in ("regrow", "prune"):
        ex.select(rng.choice(leaves, size=min(int(rng.integers(1, 40)), len(leaves) // 2), replace=False).tolist())
        if not ex.preview().changed:  # segments carrying later branches only: add a tip (issue 34)
            tree = ex.derivation.tree
            ex.select([int(leaves[np.argmax(tree.depth[leaves])])], "add")
        ex.regrow(seed=step) if op == "regrow" else ex.prune()
    else:
        getattr(ex, op)()


OPS = ["regrow", "regrow", "top", "regrow", "undo", "redo", "prune", "regrow", "undo", "undo", "regrow", "top", "regrow"]


@pytest.mark.parametrize("grammar, n", [(str(HONDA), 11), ("fruit_tree.lsys", 6)])
def test_patched_bounds_equal_vtk_bounds(grammar, n, monkeypatch):
    patched = []
    real = plant_actors._others
    monkeypatch.setattr(plant_actors, "_others", lambda *a: patched.append(1) or real(*a))
    ex = Explorer(grammar, n=n)
    shown = PlantActors(BarePlotter())
    show_model_plant(shown, ex)
    rng = np.random.default_rng(5)
    for step, op in enumerate(OPS):
        edit(ex, op, rng, step)
        show_model_plant(shown, ex)
        assert shown.sides and shown.bounds == tuple(ex.mesh.GetBounds()), (step, op)
        start, end = np.asarray(ex.skeleton.start, float), np.asarray(ex.skeleton.end, float)
        cells_bounds = [0.0] * 6
        scene.segment_lines(start, end).GetCellsBounds(cells_bounds)
        assert shown.segment_bounds == tuple(cells_bounds), (step, op)  # what the hairline actor reports
    assert len(patched) >= 8  # the regrows and prunes were patched, not computed again


def test_the_shown_props_bounds_and_clipping_range_are_vtks(qtbot):
    """The view frames a new version with the hairlines' bounds it knows: the same clipping
    range as VTK's own pass over every shown prop."""
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.view.plant_view import PlantView

    make_application()
    view = PlantView()
    qtbot.addWidget(view)
    view.resize(400, 300)
    view.show()
    qtbot.waitExposed(view)
    ex = Explorer(str(HONDA), n=11)
    rng = np.random.default_rng(3)
    renderer = view.plotter.renderer
    for step, op in enumerate(["first", *OPS[:7]]):
        if op != "first":
            edit(ex, op, rng, step)
        snap = state.take_snapshot(ex)
        view.show_plant(snap, state.cell_colors(snap.mesh, snap.selection, base=state.base_colors(snap.mesh)), True)
        known = view.shown_bounds()
        assert known is not None and known == tuple(renderer.ComputeVisiblePropBounds()), step
        ours = renderer.GetActiveCamera().GetClippingRange()
        renderer.ResetCameraClippingRange()
        assert renderer.GetActiveCamera().GetClippingRange() == ours, step
        assert view.plant_bounds() == tuple(snap.mesh.GetBounds())
    view.close()


def line_sets(lines):
    """The line sets ``lines`` (a :class:`scene.Hairlines`) holds memory and actors for."""
    return [s for s in (lines.shown, lines.kept, lines._spare) if s is not None]


def test_hairlines_written_in_place_equal_lines_built_afresh(qtbot):
    """After random regrows, undos and redos the shown hairlines (points, cells, colours) equal
    a line set built from scratch; a new version reuses the memory of the one dropped, never
    that of the version kept for an undo."""
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True)
    lines = scene.Hairlines(plotter)
    ex = Explorer(str(HONDA), n=10)
    rng = np.random.default_rng(7)
    reused = 0
    for step, op in enumerate(["first", "regrow", "regrow", "undo", "regrow", "regrow", "undo", "redo", "prune", "regrow"]):
        if op != "first":
            edit(ex, op, rng, step)
        mesh, sk = ex.mesh, ex.skeleton
        rgb = np.random.default_rng(step).integers(0, 256, (mesh.n_cells, 3)).astype(np.uint8)
        kept = lines.kept
        kept_points = None if kept is None else np.array(kept.lines.points)
        before = {id(s.buffers.conn) for s in line_sets(lines)}
        lines.show(sk, mesh, rgb, key=mesh, sides=plant_actors.tube_layout(mesh, len(sk)))
        fresh = scene.segment_lines(sk.start, sk.end)
        shown = lines.lines
        assert shown is not None and lines.visible() and all(a.GetVisibility() for a in lines.actors)
        np.testing.assert_array_equal(shown.points, fresh.points)
        assert np.shares_memory(shown.points, sk.start) and np.shares_memory(shown.points, sk.end)  # no copy
        np.testing.assert_array_equal(shown.lines, fresh.lines)
        np.testing.assert_array_equal(lines.line_colors(), scene.segment_colors(mesh, rgb, len(sk)))
        rgba = np.asarray(shown.point_data["rgb"])
        np.testing.assert_array_equal(rgba[:, :3], np.concatenate([lines.line_colors()] * 2))
        assert (rgba[:, 3] == 255).all()
        if kept is not None and lines.kept is not None and lines.kept.key is kept.key:
            np.testing.assert_array_equal(lines.kept.lines.points, kept_points)  # the kept version untouched
        if kept is not None and op != "undo":
            reused += id(lines.shown.buffers.conn) in before
            assert lines.kept is not None and not np.shares_memory(shown.points, lines.kept.lines.points)
            assert not np.shares_memory(lines.shown.buffers.conn, lines.kept.buffers.conn)
        assert len(line_sets(lines)) <= 2
        assert not any(a.GetVisibility() for a in lines.kept.chunks.actors) if lines.kept is not None else True
    assert reused >= 3  # new versions were written into memory already used
    plotter.close()


def test_base_colors_are_kept_per_mesh_and_read_only():
    ex = Explorer("fruit_tree.lsys", n=6)
    first = state.base_colors(ex.mesh)
    assert state.base_colors(ex.mesh) is first and not first.flags.writeable
    assert np.array_equal(first, state.base_colors(ex.mesh.copy(deep=True)))  # computed again: the same
    ex.mesh.cell_data["kind"] = np.zeros(ex.mesh.n_cells, np.int8)  # another kind array: not the kept colours
    assert state.base_colors(ex.mesh) is not first and (state.base_colors(ex.mesh) == first[0]).all()


def test_selection_colours_and_leaf_masks_equal_their_definition():
    ex = Explorer("fruit_tree.lsys", n=6)
    mesh = ex.mesh
    leaf, kind = np.asarray(mesh.cell_data["leaf_id"]), np.asarray(mesh.cell_data["kind"])
    fruit_leaves = np.unique(leaf[kind == state.KIND_FRUIT])
    rng = np.random.default_rng(11)
    for size in (1, 5, 60):
        sel = np.r_[rng.choice(np.unique(leaf), size, replace=False), rng.choice(fruit_leaves, 2)].tolist()
        expected = state.base_colors(mesh).copy()
        chosen = np.isin(leaf, sel)
        expected[chosen & (kind != state.KIND_FRUIT)] = (255, 0, 0)
        expected[chosen & (kind == state.KIND_FRUIT)] = state.FRUIT_SELECTED
        got = state.cell_colors(mesh, sel, base=state.base_colors(mesh))
        assert got.flags.writeable and np.array_equal(got, expected)
        with_unknown = np.where(rng.random(len(leaf)) < 0.1, -1, leaf)  # cells of no leaf
        assert np.array_equal(state.leaf_mask(with_unknown, [*sel, -1]), np.isin(with_unknown, sel))
