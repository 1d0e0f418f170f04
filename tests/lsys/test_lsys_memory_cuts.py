"""Memory of large plants (issue 14): what ``import ramure.lsys`` loads, the dtypes of the turtle's
trace and of the mesh, and the bytes an interpretation allocates per module."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from ramure.lsys import LSystem


def test_importing_lsys_does_not_load_numba_until_a_polygon_is_triangulated():
    # numba costs about 65 MB: a CLI or metrics user who never runs a kernel must not pay it
    code = (
        "import sys; import ramure.lsys, ramure.lsys.interpretation.polygons, ramure.lsys.interpretation.turtle; "
        "import ramure.lsys.interpretation.geometry; "
        "a = 'numba' in sys.modules; "
        "from ramure.lsys.interpretation.polygons import triangulate; "
        "tris, owner = triangulate([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [0, 4]); "
        "print(a, 'numba' in sys.modules, len(tris), owner.tolist())"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "True", "2", "[0,", "0]"], out.stderr


def _traced(fn):
    """(result, bytes still held, peak bytes) of ``fn()`` (numpy's allocations included)."""
    import tracemalloc

    tracemalloc.start()
    try:
        out = fn()
        current, peak = tracemalloc.get_traced_memory()
        return out, current, peak
    finally:
        tracemalloc.stop()


def _trace_bytes(trace):
    return 2 * len(trace.acts) + 4 * (len(trace.segment_at) + len(trace.organ_at) + len(trace.polygon_at))


def test_the_turtle_trace_keeps_int32_positions_and_no_copy_of_the_parameters():
    from ramure.lsys.regeneration.regen import Session
    from ramure.lsys.interpretation.turtle import interpret_string

    from ramure.lsys import load_kernels

    load_kernels()  # the compiled walk, whatever ran before in this process (below 100,000
    # modules a process without numba takes the plain walk)
    ls = LSystem.from_file("honda_sympodial")
    session = Session(ls, n=13)
    tree = session.derivation.tree
    interpret_string(ls, tree, tree.leaves)  # kernels loaded before counting
    sk, held, peak = _traced(lambda: interpret_string(ls, tree, tree.leaves))
    modules, trace = len(tree.leaves), sk.extra["trace"]
    assert modules == 90_101 and len(sk) == 8_191
    assert [a.dtype for a in (trace.segment_at, trace.organ_at, trace.polygon_at)] == [np.int32] * 3
    assert not hasattr(trace, "par") and not hasattr(trace, "match") and trace.balanced
    # action codes (1 byte) and has-parameters flags (1) per module: an edit finds the new
    # string's bracket matches itself
    assert trace.nbytes() == _trace_bytes(trace)
    # skeleton + trace held: 12.6 bytes per module (16.6 with the bracket matches, 29.0 with int64
    # matches and the parameter copy); peak 28.7 (35.9 before)
    assert held < 16 * modules and peak < 32 * modules


def test_an_edit_keeps_the_trace_int32_and_equal_to_a_fresh_interpretation():
    from ramure.lsys.regeneration.regen import Session
    from ramure.lsys.interpretation.turtle import changed_spans, interpret_string, reinterpret

    ls = LSystem.from_file("honda_sympodial")
    session = Session(ls, n=9)
    tree = session.derivation.tree
    old = interpret_string(ls, tree, tree.leaves)
    old_leaves = tree.leaves
    picked = old.leaf_id[len(old) // 3 :: len(old) // 5][:4]
    session.regrow(picked.tolist(), rho=0.5, seed=3)
    spans = changed_spans(old_leaves, tree.leaves, tree.size)
    assert spans is not None
    edited = reinterpret(ls, tree, old, tree.leaves, *spans)
    fresh = interpret_string(ls, tree, tree.leaves)
    assert "reuse" in edited.extra  # re-interpreted in regions, not whole
    a, b = edited.extra["trace"], fresh.extra["trace"]
    for name in ("acts", "nps", "segment_at", "organ_at", "polygon_at"):
        assert getattr(a, name).dtype == getattr(b, name).dtype and np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.balanced and b.balanced and a.nbytes() == _trace_bytes(a)
    assert np.allclose(edited.end, fresh.end, rtol=0, atol=1e-9) and np.array_equal(edited.leaf_id, fresh.leaf_id)


def test_the_explorer_mesh_has_float32_points_and_int32_ids_and_the_library_mesh_float64():
    from ramure.app.model import Explorer, mesh_sides
    from ramure.lsys.interpretation.geometry import skeleton_to_polydata

    ex = Explorer("grammars/fruit_tree.lsys", n=5)
    mesh = ex.mesh
    assert mesh.points.dtype == np.float32 and len(ex.skeleton.organs) > 0  # tubes and organs
    names = ("leaf_id", "segment", "organ", "polygon", "kind", "order", "material")
    dtypes = [np.asarray(mesh.cell_data[k]).dtype for k in names]
    # ids int32; organ, polygon, order and material in a byte each (a few organs, orders, materials)
    assert dtypes == [np.int32] * 2 + [np.int8] * 5
    # 13 bytes per cell instead of 41 with int64 ids and 25 with int32 ones; 12 per point instead of 24
    assert sum(np.asarray(mesh.cell_data[k]).nbytes for k in names) == 13 * mesh.n_cells
    assert np.asarray(mesh.points).nbytes == 12 * mesh.n_points
    full = skeleton_to_polydata(ex.skeleton, mesh_sides(len(ex.skeleton)))
    assert full.points.dtype == np.float64
    np.testing.assert_array_equal(np.asarray(mesh.points), np.asarray(full.points).astype(np.float32))
    for k in names:
        np.testing.assert_array_equal(mesh.cell_data[k], full.cell_data[k], err_msg=k)
    leaf = ex.leaf_of_cell(mesh.n_cells - 1)  # an organ cell still picks its history leaf
    assert isinstance(leaf, int) and leaf in ex.skeleton.organs.leaf_id.tolist()


def test_tube_points_by_blocks_equal_one_block(monkeypatch):
    from ramure.lsys.interpretation import geometry

    sk = LSystem.from_file("honda_sympodial").derive(8).skeleton()
    args = (sk.start, sk.end, sk.normal, sk.base_radius, sk.top_radius, 5)
    whole = geometry.tube_points(*args)
    monkeypatch.setattr(geometry, "TUBE_CHUNK", 7)  # blocks of 7 segments, the last one short
    assert len(sk) % 7 and whole.shape == (len(sk), 10, 3)
    np.testing.assert_array_equal(geometry.tube_points(*args), whole)
    small = geometry.tube_points(*args, dtype=np.float32)
    assert small.dtype == np.float32
    np.testing.assert_array_equal(small, whole.astype(np.float32))
    # each ring lies at its radius around the segment's end
    r = np.linalg.norm(whole[:, :5] - sk.start[:, None], axis=2)
    np.testing.assert_allclose(r, np.repeat(sk.base_radius[:, None], 5, axis=1), rtol=1e-12)


def _spans_reference(old, new):
    """changed_spans by hand: runs of modules not in the other string, keyed by the kept modules
    before them; a string without a run at a key gets the empty span just after that kept module."""
    kept = set(old) & set(new)

    def runs(string):
        out, count, i = {}, 0, 0
        after = {0: 0}  # kept count -> the position just after that many kept modules
        while i < len(string):
            if string[i] in kept:
                count += 1
                after[count] = i + 1
                i += 1
                continue
            j = i
            while j < len(string) and string[j] not in kept:
                j += 1
            out[count] = (i, j - 1)
            i = j
        return out, after

    (ro, ao), (rn, an) = runs(old), runs(new)
    keys = sorted(set(ro) | set(rn))
    return [[list(r.get(k, (a[k], a[k] - 1))) for k in keys] for r, a in ((ro, ao), (rn, an))]


def test_changed_spans_match_a_reference_on_random_edits():
    from ramure.lsys.interpretation.turtle import changed_spans

    rng = np.random.default_rng(3)
    fresh = 1000
    for _ in range(400):
        old = rng.choice(600, size=int(rng.integers(0, 30)), replace=False).tolist()
        new = []
        for v in old:
            new += list(range(fresh, fresh + int(rng.integers(0, 3) if rng.random() < 0.3 else 0)))
            fresh += 3
            if rng.random() < 0.7:
                new.append(v)
        new += list(range(fresh, fresh + int(rng.integers(0, 2))))
        fresh += 2
        spans = changed_spans(old, new, fresh + 1)
        assert spans is not None
        assert [spans[0].tolist(), spans[1].tolist()] == _spans_reference(old, new), (old, new)


def test_changed_spans_of_a_large_plant_allocate_no_int64_copy_of_the_string():
    from ramure.lsys.regeneration.regen import Session
    from ramure.lsys.interpretation.turtle import changed_spans

    session = Session(LSystem.from_file("honda_sympodial"), n=13)
    tree = session.derivation.tree
    before = tree.leaves
    leaves = session.derivation.skeleton().leaf_id
    session.regrow(leaves[len(leaves) // 3 :: len(leaves) // 6][:5].tolist(), rho=0.5, seed=1)
    changed_spans(before, tree.leaves, tree.size)  # kernel loaded before counting
    spans, _, peak = _traced(lambda: changed_spans(before, tree.leaves, tree.size))
    assert spans is not None and 1 <= len(spans[0]) <= 5
    # masks and edges only: 4.2 bytes per module; an int64 cumulative sum of each string took 20
    assert peak < 8 * len(before)
    for (a, b), (c, d) in zip(*spans):  # every span changed something: a removed or an added run
        assert b >= a or d >= c


def test_cell_data_past_a_byte_takes_int16_and_keeps_its_values():
    from ramure.lsys import LSystem
    from ramure.lsys.interpretation.geometry import skeleton_to_polydata, value_dtype

    deep = 200  # branch orders 0 .. 200 and 200 leaves: past int8
    sk = LSystem.from_text("n: 0\n#organ Leaf\nw: " + "F[" * deep + "F" + "Leaf(1)]" * deep + "\n").derive().skeleton()
    mesh = skeleton_to_polydata(sk, sides=3)
    order, organ = np.asarray(mesh.cell_data["order"]), np.asarray(mesh.cell_data["organ"])
    assert order.dtype == np.int16 and organ.dtype == np.int16
    assert np.array_equal(order[: 3 * len(sk)], np.repeat(sk.order, 3)) and order.max() == deep
    assert sorted(set(organ.tolist())) == list(range(-1, deep)) and (order[organ >= 0] == -1).all()
    assert np.asarray(mesh.cell_data["polygon"]).dtype == np.int8  # all -1: no polygons
    assert value_dtype(-(2**15) - 1, 0) is np.int32 and value_dtype(-128, 127) is np.int8
