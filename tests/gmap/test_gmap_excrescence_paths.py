"""Excrescence paths with side axes (issue 17): (3, C1, 4, C5, 2) on the glued fruit."""

import json

import numpy as np
import pytest

from ramure.errors import GrammarError
from ramure.gmap.organs import defects as D
from ramure.gmap.kernel import subdivide, topology
from ramure.gmap.organs.excrescence import SIDE_STEPS, _first_darts, excrescence, resolve_path
from ramure.gmap.organs.fruit import build_fruit


@pytest.fixture(scope="module")
def coarse():
    return build_fruit("round_tomato")  # 10 rings x 10 sectors, one radial layer


def cells_at(gm, path):
    c = resolve_path(gm, path)
    vd = gm.volume_data
    return sorted(zip(vd["ring"][c].tolist(), vd["sector"][c].tolist()))


def test_side_steps_cross_the_named_face_in_the_map(coarse):
    """C1 = ring - 1, C2 = sector + 1, C3 = ring + 1, C4 = sector - 1, read off alpha3 on every branch cell."""
    vd = coarse.volume_data
    branch = np.flatnonzero(vd["order"] == 1)
    first = _first_darts(coarse, branch)
    for k, (dr, ds) in SIDE_STEPS.items():
        d = coarse.prism_face(first, 4, f"C{k}")
        other = coarse.dart_volume[coarse.alpha[3][d]]
        glued = other != branch  # free at the poles only
        assert glued.sum() == (100 if ds else 90)
        np.testing.assert_array_equal(vd["ring"][other[glued]], vd["ring"][branch[glued]] + dr)
        np.testing.assert_array_equal(vd["sector"][other[glued]], (vd["sector"][branch[glued]] + ds) % 10)


def test_two_turn_path_by_hand(coarse):
    # ring 3, branch on C1 (sector 0), stage 0; C2: sectors 1, 2 (side stage 1); C3: rings 4, 5, 6 (stage 2)
    assert cells_at(coarse, "(3, C1, 0, C2, 1, C3, 2)") == [(6, 2)]
    assert cells_at(coarse, "(3, C1, 0, C2, 1, C4, 0)") == [(3, 1)]  # turning back one sector
    # C5 is C1 again on the quad cells (cyclic numbering): 3 cells towards the blossom end, ring 0
    assert cells_at(coarse, "(3, C1, 0, C5, 2)") == cells_at(coarse, "(3, C1, 0, C1, 2)") == [(0, 0)]
    assert cells_at(coarse, "(2, C10, 0, C2, 0)") == [(2, 0)]  # sectors wrap round the fruit
    assert len(resolve_path(coarse, "(3, C1, 0, C2, 1, C3, 2)")) == 1


def test_side_axis_wildcards(coarse):
    assert cells_at(coarse, "(3, C1, 0, C*, 0)") == [(2, 0), (3, 1), (3, 9), (4, 0)]
    assert cells_at(coarse, "(3, C1, 0, C1, *)") == [(0, 0), (1, 0), (2, 0)]  # up to the pole
    assert cells_at(coarse, "(3, C1, 0, C2, *)") == [(3, s) for s in range(1, 10)]  # round, not the start
    assert len(resolve_path(coarse, "(3, C1, 0, C*, *)")) == 3 + 6 + 9
    # * before the turn: every ring's branch on C1, one step towards ring 0 (ring 0 has none)
    assert cells_at(coarse, "(*, C1, 0, C1, 0)") == [(r, 0) for r in range(9)]
    assert len(resolve_path(coarse, "(3, C*, 0, C2, 0)")) == 10


def test_volume_subdivision_keeps_side_axis_paths(coarse):
    fine = subdivide.volume(coarse, 1)
    vd = fine.volume_data
    for path in ("(3, C1, *, C2, 1, C3, 2)", "(3, C1, *, C*, *)", "(*, C4, *, C1, 0)"):
        before = resolve_path(coarse, path)
        after = resolve_path(fine, path)
        assert len(after) == 8 * len(before), path
        named = set(zip(coarse.volume_data["ring"][before].tolist(), coarse.volume_data["sector"][before].tolist()))
        kids = set(zip(vd["ring"][after].tolist(), vd["sector"][after].tolist()))
        assert kids == named, path


def test_a_path_leaving_the_fruit_has_a_caret_under_the_step(coarse):
    for text, col in (
        ("(3, C1, 0, C1, 3)", 16),  # rings 2, 1, 0, then past the pole: the 3
        ("(0, C1, 0, C1, 0)", 12),  # ring 0 has nothing below it: the C1
        ("(9, C1, 0, C3, 0)", 12),
        ("(3, C1, 0, C2, 1, C1, 2, C3, 9)", 30),
    ):
        with pytest.raises(GrammarError) as err:
            resolve_path(coarse, text)
        assert err.value.column == col and "leaves the fruit" in str(err.value), text
        caret_line = str(err.value).splitlines()[-1]
        assert caret_line.index("^") - 2 == col - 1


def test_issue_example_path_grows_a_valid_excrescence():
    fruit = build_fruit("round_tomato", volume_levels=1)  # branch stages 0, 1
    with pytest.raises(GrammarError, match="stage 4"):
        resolve_path(fruit, "(3, C1, 4, C5, 2)")
    # a ridge of 3-segment excrescences along sector 0 makes branch stages 2, 3, 4 there
    ridge, _ = excrescence(fruit, "(*, C1, 1)", height_mm=6, segments=3)
    named = resolve_path(ridge, "(3, C1, 4, C5, 2)")
    vd = ridge.volume_data
    assert set(vd["ring"][named]) == {0} and set(vd["sector"][named]) == {0}
    assert set(vd["excrescence"][named]) == {3}
    out, facts = excrescence(ridge, "(3, C1, 4, C5, 2)", height_mm=3)
    topology.assert_solid(out)  # valid, chi 1, boundary chi 2
    assert facts["cells"] == len(named) and facts["bumps"] == 1  # on top faces only
    assert D.cell_volumes(out).min() > 0 and facts["volume_added"] > 0
    # leaving the ridge sideways: sector 1 has no stage 4
    with pytest.raises(GrammarError, match="leaves the fruit") as err:
        resolve_path(ridge, "(3, C1, 4, C2, 0)")
    assert err.value.column == 12
    # turning from a stage the ridge did not grow on that branch: caret under the stage
    with pytest.raises(GrammarError, match="no cell at this stage") as err:
        resolve_path(ridge, "(4, C2, 2, C1, 0)")
    assert err.value.column == 9


def test_cli_side_axis_excrescence(capsys):
    from ramure.app.cli import main

    assert main(["fruit", "--subdivide", "volume:1", "--defect", "excrescence:path=(3,C1,1,C5,1),height_mm=3", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["valid"] and rec["defects"]["defects"][0]["cells"] == 4  # ring 1's 4 skin faces
    # the issue's path, once a ridge of excrescences makes stage 4 on sector 0
    assert (
        main(
            [
                "fruit",
                "--subdivide",
                "volume:1",
                "--defect",
                "excrescence:path=(*,C1,1),height_mm=6,segments=3",
                "--defect",
                "excrescence:path=(3,C1,4,C5,2),height_mm=3",
                "--json",
            ]
        )
        == 0
    )
    rec = json.loads(capsys.readouterr().out)
    assert rec["valid"] and rec["defects"]["defects"][1]["path"] == "(3, C1, 4, C5, 2)"
    assert main(["fruit", "--defect", "excrescence:path=(3,C1,0,C1,5),height_mm=3"]) == 2
    err = capsys.readouterr().err
    assert "leaves the fruit" in err and "^" in err and "Traceback" not in err
