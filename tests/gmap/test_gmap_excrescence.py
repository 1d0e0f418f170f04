"""Excrescences by path (issue 17): (3, C1, *) paths, wildcards, carets, volume subdivision keeps them."""

import numpy as np
import pytest

from ramure.errors import GrammarError
from ramure.gmap.organs import defects as D
from ramure.gmap.kernel import subdivide, topology
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.excrescence import branch_stages, excrescence, parse_path, resolve_path
from ramure.gmap.organs.fruit import build_fruit


@pytest.fixture(scope="module")
def fruit():
    return build_fruit("round_tomato", volume_levels=1)


def test_paths_resolve_on_ring_sector_layer(fruit):
    vd = fruit.volume_data
    layers, stage = branch_stages(fruit)
    assert layers == 2
    cells = resolve_path(fruit, "(3, C1, 1)")
    assert len(cells) == 4  # 2 x 2 children of the branch's outer half
    assert set(vd["ring"][cells]) == {3} and set(vd["sector"][cells]) == {0} and set(stage[cells]) == {1}
    assert len(resolve_path(fruit, "(3, C1, *)")) == 8
    assert len(resolve_path(fruit, "(3, C*, 0)")) == 4 * 10
    assert len(resolve_path(fruit, "(*, C2, *)")) == 8 * 10
    trunk = resolve_path(fruit, "(0)")
    assert set(vd["order"][trunk]) == {0} and set(vd["ring"][trunk]) == {0}
    # without subdivision: one cell per branch, stage 0 only
    coarse = build_fruit("round_tomato")
    assert len(resolve_path(coarse, "(3, C1, 0)")) == 1 and len(resolve_path(coarse, "(*, C*, *)")) == 100


def test_syntax_errors_have_a_caret():
    for text, col, msg in (
        ("(3, D1, 1)", 5, "lateral face"),
        ("(3,,1)", 4, "empty"),
        ("(3, C1", 7, "')'"),
        ("(3, x)", 5, "lateral face"),
        ("(3, C1)", 8, "ends with a stage"),
        ("(3, C0, 1)", 5, "from C1"),
    ):
        with pytest.raises(GrammarError) as err:
            parse_path(text)
        assert err.value.column == col, text
        assert msg in str(err.value) and "^" in str(err.value)
        caret_line = str(err.value).splitlines()[-1]
        assert caret_line.index("^") - 2 == col - 1  # under the offending token
    assert repr(parse_path(" ( 3 , C1 , 4 , C5 , 2 ) ")) == "(3, C1, 4, C5, 2)"


def test_out_of_range_paths_are_refused_with_a_caret(fruit):
    for text, col, msg in (
        ("(3, C1, 4, C5, 2)", 9, "stage 4"),
        ("(12)", 2, "ring 12"),
        ("(3, C11, 0)", 5, "C1..C10"),
        ("(3, C1, 9)", 9, "stage 9"),
    ):
        with pytest.raises(GrammarError) as err:
            resolve_path(fruit, text)
        assert err.value.column == col and msg in str(err.value), text


def test_excrescence_grows_a_glued_bump_and_keeps_the_invariants(fruit):
    before = fruit.copy()
    out, facts = excrescence(fruit, "(3, C1, *)", height_mm=5, segments=2)
    np.testing.assert_array_equal(fruit.points, before.points)  # input unchanged
    topology.assert_solid(out)
    assert facts["cells"] == 4 and facts["bumps"] == 1  # the 4 skin faces of that branch
    vd = out.volume_data
    new = np.flatnonzero(vd["excrescence"] > 0)
    assert len(new) == 8 and sorted(set(vd["excrescence"][new])) == [1, 2]
    assert set(vd["ring"][new]) == {3} and set(vd["sector"][new]) == {0}
    vols = D.cell_volumes(out)
    assert vols.min() > 0
    assert facts["volume_added"] == pytest.approx(vols[new].sum(), rel=1e-9)
    # the 4 prisms of a segment are glued into one bump: 4 shared inner faces per segment
    a3 = out.alpha[3]
    vol = out.dart_volume
    mask = np.isin(vol, new) & (a3 != np.arange(out.n_darts))
    inner = np.sum(np.isin(vol[a3[mask]], new) & (vol[a3[mask]] != vol[mask]))
    # 4 lateral glues per segment and 4 segment-on-segment faces, 8 darts a side, seen from both sides
    assert inner == 2 * 8 * (2 * 4 + 4)
    # the bump rises along the outward normal by the height (mm)
    scale = D.mm_per_unit(fruit)
    top = out.points[np.isin(vol, new[vd["excrescence"][new] == 2])]
    base = fruit.points[np.isin(fruit.dart_volume, resolve_path(fruit, "(3, C1, 1)"))]
    centre = fruit.points.mean(axis=0)
    rise = (np.linalg.norm(top - centre, axis=1).max() - np.linalg.norm(base - centre, axis=1).max()) * scale
    assert 3.0 < rise <= 5.0 + 1e-6
    # the path grows with the axis: stage L = the first segment
    assert len(resolve_path(out, "(3, C1, 2)")) == 4 and len(resolve_path(out, "(3, C1, *)")) == 16


def test_volume_subdivision_keeps_the_paths():
    coarse = build_fruit("round_tomato")
    grown, _ = excrescence(coarse, "(4, C3, 0)", height_mm=4)
    named = resolve_path(grown, "(4, C3, *)")
    fine = subdivide.volume(grown, 1)
    topology.assert_solid(fine)
    kids = resolve_path(fine, "(4, C3, *)")
    assert len(kids) == 8 * len(named)  # every named cell's 8 children, nothing else
    vd = fine.volume_data
    assert (vd["excrescence"][kids] > 0).sum() == 8 and (vd["excrescence"] > 0).sum() == 8


def test_excrescence_refusals(fruit):
    copy = fruit.copy()
    for kwargs, msg in (
        ({"path": "(3, C1, 0)"}, "none with a free face"),
        ({"path": "(3, C1, 1)", "height_mm": 0}, "height"),
        ({"path": "(3, C1, 1)", "segments": 0}, "segments"),
        ({"path": "(3, C1, 1)", "taper": 1.0}, "taper"),
    ):
        with pytest.raises(GMapError, match=msg):
            excrescence(fruit, **kwargs)
    np.testing.assert_array_equal(fruit.points, copy.points)
    np.testing.assert_array_equal(fruit.alpha, copy.alpha)


def test_cli_excrescence(capsys):
    import json
    from ramure.app.cli import main

    assert main(["fruit", "--subdivide", "volume:1", "--defect", "excrescence:path=(2, C*, 1),height_mm=3", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["valid"] and rec["defects"]["defects"][0]["cells"] == 40
    assert main(["fruit", "--defect", "excrescence:path=(2, X1, 1)"]) == 2
    err = capsys.readouterr().err
    assert "lateral face" in err and "^" in err and "Traceback" not in err
