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
        "import sys; import ramure.lsys, ramure.lsys.polygons, ramure.lsys.turtle, ramure.lsys.geometry; "
        "a = 'numba' in sys.modules; "
        "from ramure.lsys.polygons import triangulate; "
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
    return 6 * len(trace.acts) + 4 * (len(trace.segment_at) + len(trace.organ_at) + len(trace.polygon_at))


def test_the_turtle_trace_keeps_int32_positions_and_no_copy_of_the_parameters():
    from ramure.lsys.regen import Session
    from ramure.lsys.turtle import interpret_string

    ls = LSystem.from_file("honda_sympodial")
    session = Session(ls, n=13)
    tree = session.derivation.tree
    interpret_string(ls, tree, tree.leaves)  # kernels loaded before counting
    sk, held, peak = _traced(lambda: interpret_string(ls, tree, tree.leaves))
    modules, trace = len(tree.leaves), sk.extra["trace"]
    assert modules == 90_101 and len(sk) == 8_191
    assert [a.dtype for a in (trace.segment_at, trace.organ_at, trace.match, trace.polygon_at)] == [np.int32] * 4
    assert not hasattr(trace, "par")
    # action codes (1 byte), has-parameters flags (1) and bracket matches (4) per module
    assert trace.nbytes() == _trace_bytes(trace)
    assert trace.match[trace.match[trace.acts == 11]].tolist() == np.flatnonzero(trace.acts == 11).tolist()
    # skeleton + trace held: 16.6 bytes per module (29.0 with int64 matches and the parameter copy);
    # peak 28.7 (35.9 before)
    assert held < 20 * modules and peak < 32 * modules


def test_an_edit_keeps_the_trace_int32_and_equal_to_a_fresh_interpretation():
    from ramure.lsys.regen import Session
    from ramure.lsys.turtle import changed_spans, interpret_string, reinterpret

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
    for name in ("acts", "nps", "segment_at", "organ_at", "match", "polygon_at"):
        assert getattr(a, name).dtype == getattr(b, name).dtype and np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.match.dtype == np.int32 and a.nbytes() == _trace_bytes(a)
    assert np.allclose(edited.end, fresh.end, rtol=0, atol=1e-9) and np.array_equal(edited.leaf_id, fresh.leaf_id)
