"""Regions of one fruit (issue 40 §6): selected by rubber band, brush and label pattern,
regrown alone, the rest byte-identical, undoable."""

import numpy as np
import pytest

from ramure.app import fruit_defects as FD
from ramure.app import fruit_regions as FR
from ramure.app.model import Explorer
from ramure.errors import RamureError
from ramure.gmap.organs.fruit import build_fruit, regrow_region
from ramure.gmap.organs.regions import check_region, region_darts, region_volumes, skin_cells


@pytest.fixture
def ex():
    from ramure import grammars

    ex = Explorer(grammars.path("fruit_tree"), n=5)
    ex.select([ex.fruit_ids()[0]])
    return ex


def _camera_matrix(gm, size=(400, 300)):
    """A perspective camera in front of the fruit (looking along +y at its centre)."""
    import pyvista as pv

    _, pos = gm.vertex_positions()
    centre, extent = pos.mean(axis=0), float(np.ptp(pos, axis=0).max())
    cam = pv.Camera()
    cam.position = tuple(centre - np.array([0.0, 4.0 * extent, 0.0]))
    cam.focal_point = tuple(centre)
    cam.up = (0.0, 0.0, 1.0)
    m = cam.GetCompositeProjectionTransformMatrix(size[0] / size[1], -1, 1)
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)]), centre


def _bytes_outside(gm, mask):
    """Every column of the darts in ``mask`` (positions, involutions, attributes), as bytes."""
    cols = [gm.alpha[:, mask].tobytes()] + [np.asarray(gm.dart_data[k])[mask].tobytes() for k in sorted(gm.dart_data)]
    return b"".join(cols)


def test_rubber_band_selects_the_skin_facing_the_camera(ex):
    leaf = ex.fruit_region is None and ex.selection[0]
    gm = ex.fruit_volume(leaf)
    matrix, centre = _camera_matrix(gm)
    size = (400, 300)
    region = ex.select_fruit_region("rectangle", matrix, size, (180, 130, 220, 170))["region"]
    cells = np.asarray(region["cells"])
    assert 2 <= len(cells) < 40  # a patch, not the whole fruit
    centres, all_cells, outward = skin_cells(gm)
    key = all_cells[:, 0] * 100 + all_cells[:, 1]
    picked = np.isin(key, cells[:, 0] * 100 + cells[:, 1])
    # every picked cell has a skin face towards the camera (-y); the far side is never picked
    facing = {int(k) for k in key[outward[:, 1] < 0]}
    behind = {int(k) for k in key} - facing
    assert {int(k) for k in key[picked]} <= facing and behind and not behind & {int(k) for k in key[picked]}
    # a brush adds the cells near a skin point; remove takes them out again
    grown = ex.select_fruit_region("point", centres[~picked][0], 0.0, mode="add")["region"]
    assert len(grown["cells"]) == len(cells) + 1
    back = ex.select_fruit_region("point", centres[~picked][0], 0.0, mode="remove")["region"]
    assert back["cells"] == region["cells"]


def test_regions_regrow_alone_byte_identical_outside_and_undo(ex):
    leaf = ex.selection[0]
    before, _ = FD.damaged_fruit(ex, leaf)
    chi = before.euler_characteristic()
    gm = ex.fruit_volume(leaf)
    matrix, _ = _camera_matrix(gm)
    band = ex.select_fruit_region("rectangle", matrix, (400, 300), (175, 125, 225, 175))["region"]
    after, _ = ex.regrow_fruit_region(largeur=75.0)
    inside = region_darts(before, band)
    assert 0 < inside.sum() < before.n_darts
    assert _bytes_outside(after, ~inside) == _bytes_outside(before, ~inside)
    moved = np.linalg.norm(after.points - before.points, axis=1)
    assert moved[inside].max() > 0.05 * float(np.ptp(before.points, axis=0).max())  # a visible bulge
    assert after.is_valid() and after.euler_characteristic() == chi
    # then a label pattern, on top of the first region: the first stays, the rest is untouched
    ex.select_fruit_region("pattern", "(8, C*, *)")
    twice, _ = ex.regrow_fruit_region(creux=0.3, nbprotus=5)
    ring8 = region_darts(before, {"path": "(8, C*, *)"})
    assert _bytes_outside(twice, ~ring8) == _bytes_outside(after, ~ring8)
    assert not np.array_equal(twice.points[ring8], after.points[ring8])
    assert twice.is_valid() and twice.euler_characteristic() == chi
    # the plant's coarse fruit shows the regions too; other fruit are untouched
    assert len(FD.fruit_settings(ex, leaf)["regions"]) == 2
    # undo twice: the original bytes
    ex.undo()
    ex.undo()
    restored, _ = FD.damaged_fruit(ex, leaf)
    assert _bytes_outside(restored, np.ones(restored.n_darts, bool)) == _bytes_outside(before, np.ones(before.n_darts, bool))
    ex.redo()
    again, _ = FD.damaged_fruit(ex, leaf)
    np.testing.assert_array_equal(again.points, after.points)


def test_regions_survive_subdivision():
    """A region names the same cells at every level: its volumes' (ring, sector) agree."""
    region = {"path": "(7, C2, *)"}
    coarse = build_fruit("round_tomato")
    fine = build_fruit("round_tomato", volume_levels=2)
    key = lambda gm, v: {(int(gm.volume_data["ring"][i]), int(gm.volume_data["sector"][i])) for i in v}  # noqa: E731
    assert key(coarse, region_volumes(coarse, region)) == key(fine, region_volumes(fine, region)) == {(7, 1)}
    assert len(region_volumes(fine, region)) >= 64  # one coarse cell, 8 x 8 children (and seed cells)
    out = regrow_region(fine, region, {"largeur": 70.0}, blend=2)
    inside = region_darts(fine, region)
    np.testing.assert_array_equal(out.points[~inside], fine.points[~inside])
    assert out.is_valid() and out.euler_characteristic() == fine.euler_characteristic()


def test_plant_fruit_keeps_its_place_and_size(ex):
    leaf = ex.selection[0]
    coarse = ex.fruit_volume(leaf)
    block = {"cells": [[4, 2], [4, 3], [5, 2], [5, 3]]}  # one skin vertex of its own, coarse
    centres, cells, _ = skin_cells(coarse)
    mine = centres[np.isin(cells[:, 0] * 100 + cells[:, 1], [402, 403, 502, 503])]
    point = mine.mean(axis=0)  # the block's shared skin vertex, about
    radius = 1.05 * float(np.linalg.norm(mine - point, axis=1).max())
    for cell in block["cells"]:
        ex.select_fruit_region("pattern", f"({cell[0]}, C{cell[1] + 1}, *)", mode="add")
    assert ex.fruit_region["region"] == {"path": "(5, C4, *)"}  # a pattern replaces
    ex.select_fruit_region("point", point, 1e-9)
    ex.select_fruit_region("point", point, radius, mode="add")
    assert ex.fruit_region["region"] == block
    ex.regrow_fruit_region(largeur=90.0)
    grown = ex.fruit_volume(leaf)
    inside = region_darts(coarse, block)
    np.testing.assert_array_equal(grown.points[~inside], coarse.points[~inside])
    assert not np.array_equal(grown.points[inside], coarse.points[inside])
    # a ring of the coarse fruit has no vertex of its own: the plant's fruit stays, the
    # Defects view's subdivided fruit changes
    ex.select_fruit_region("pattern", "(7, C*, *)")
    shown, _ = ex.regrow_fruit_region(largeur=90.0)
    np.testing.assert_array_equal(ex.fruit_volume(leaf).points, grown.points)
    assert shown.is_valid()


def test_refusals_change_nothing(ex):
    edits = len(ex.session.edits)
    with pytest.raises(RamureError, match="select a region"):
        ex.regrow_fruit_region(largeur=70.0)
    with pytest.raises(RamureError, match="stage 9 is past"):
        ex.select_fruit_region("pattern", "(3, C1, 9)")
    ex.select_fruit_region("pattern", "(3, C*, *)")
    with pytest.raises(RamureError, match="times 2, 4 or 8"):  # finer precision: see the next test
        ex.regrow_fruit_region(precision=12)
    with pytest.raises(RamureError, match="cannot be coarser"):
        ex.regrow_fruit_region(precision=5)
    with pytest.raises(RamureError, match="cannot change ph"):
        ex.regrow_fruit_region(ph=12)
    with pytest.raises(RamureError, match="unknown fruit parameter"):
        ex.regrow_fruit_region(bogus=1.0)
    with pytest.raises(RamureError, match="new parameters"):
        ex.regrow_fruit_region()
    with pytest.raises(RamureError, match="either a 'path'"):
        check_region({"path": "(1)", "cells": [[1, 1]]})
    assert len(ex.session.edits) == edits


def test_a_region_at_a_finer_precision_is_one_undoable_edit(ex, tmp_path):
    leaf = ex.selection[0]
    before, _ = FD.damaged_fruit(ex, leaf)
    everything = np.ones(before.n_darts, bool)
    ex.select_fruit_region("cells", [[4, 2], [4, 3], [5, 2], [5, 3]])
    region = ex.fruit_region["region"]
    finer, _ = ex.regrow_fruit_region(precision=20)
    inside = region_darts(before, region)
    n = before.n_darts
    assert _bytes_outside(finer, np.r_[~inside, np.zeros(finer.n_darts - n, bool)]) == _bytes_outside(before, ~inside)
    assert finer.is_valid() and finer.euler_characteristic() == before.euler_characteristic()
    # 16 cells of the once-subdivided fruit, 8 each, and a pillow per face towards the rest
    assert len(region_volumes(finer, region)) > 8 * len(region_volumes(before, region))
    assert FD.fruit_settings(ex, leaf)["regions"] == [{**region, "params": {"precision": 20}, "blend": 1}]
    assert ex.fruit_volume(leaf).is_valid()  # the plant's coarse fruit is refined there too
    # a shape change on top: the precision region stays, the shape applies under it
    ex.select_fruit_region("pattern", "(8, C*, *)")
    both, _ = ex.regrow_fruit_region(largeur=75.0)
    assert both.is_valid() and both.n_darts == finer.n_darts
    ring8 = region_darts(finer, {"path": "(8, C*, *)"})
    assert not np.array_equal(both.points[ring8], finer.points[ring8])
    ex.undo()
    again, _ = FD.damaged_fruit(ex, leaf)
    assert _bytes_outside(again, np.ones(again.n_darts, bool)) == _bytes_outside(finer, np.ones(finer.n_darts, bool))
    ex.undo()
    restored, _ = FD.damaged_fruit(ex, leaf)
    assert _bytes_outside(restored, np.ones(restored.n_darts, bool)) == _bytes_outside(before, everything)
    ex.redo()
    redone, _ = FD.damaged_fruit(ex, leaf)
    assert _bytes_outside(redone, np.ones(redone.n_darts, bool)) == _bytes_outside(finer, np.ones(finer.n_darts, bool))
    # a hail placed in the refined region lands there, by labels, on the refined cells
    ex.select([leaf])
    ex.select_fruit_region("cells", [[4, 2], [4, 3], [5, 2], [5, 3]])
    hit, facts = ex.place_defect_in_region("hail:depth_mm=2,healed=0")
    assert hit.is_valid() and facts["volume_lost_fraction"] > 0
    moved = np.linalg.norm(hit.points[: finer.n_darts] - finer.points, axis=1) > 1e-9
    assert set(np.unique(hit.volume_data["ring"][hit.dart_volume[: finer.n_darts][moved]]).tolist()) <= {3, 4, 5, 6}
    # a session file keeps the precision region: the same bytes once loaded
    ex.save_session(tmp_path / "finer.json")
    from ramure import grammars

    again = Explorer(grammars.path("fruit_tree"), n=5)
    again.load_session(tmp_path / "finer.json")
    loaded, _ = FD.damaged_fruit(again, leaf)
    assert _bytes_outside(loaded, np.ones(loaded.n_darts, bool)) == _bytes_outside(hit, np.ones(hit.n_darts, bool))


def test_region_is_highlighted(ex):
    ex.select_fruit_region("pattern", "(6, C*, *)")
    gm, skin = FR.shown(ex)
    lit = np.asarray(skin.cell_data["region"], bool)
    assert 0 < lit.sum() < skin.n_cells
    rgb = np.asarray(skin.cell_data["rgb"], float)
    # lit cells lean to the highlight's blue, the others keep the fruit's red
    assert rgb[lit, 2].mean() > rgb[~lit, 2].mean() + 80


def test_defects_placed_and_moved_in_a_region(ex):
    leaf = ex.selection[0]
    ex.select_fruit_region("pattern", "(3, C2, *)")
    gm, facts = ex.place_defect_in_region("hail:depth_mm=2,healed=0")
    assert FD.fruit_settings(ex, leaf)["defects"] == ["hail:depth_mm=2,healed=0,at=ring3/sector1"]
    before, _ = FD.damaged_fruit(ex, leaf, specs=[])
    moved = np.linalg.norm(gm.points - before.points, axis=1) > 1e-9
    vd = gm.volume_data
    sectors = np.unique(vd["sector"][gm.dart_volume[moved]])
    rings = np.unique(vd["ring"][gm.dart_volume[moved]])
    assert set(sectors.tolist()) <= {0, 1, 2} and set(rings.tolist()) <= {2, 3, 4}  # the crater is there
    # move it to another region, and add a crack along a rubber-band-like set of cells
    ex.select_fruit_region("pattern", "(6, C7, *)")
    ex.place_defect_in_region("", replace=0)
    ex.select_fruit_region("cells", [[4, 5], [5, 5], [6, 5]])
    ex.place_defect_in_region("crack:kind=longitudinal,depth=1,width_mm=1")
    assert FD.fruit_settings(ex, leaf)["defects"] == [
        "hail:depth_mm=2,healed=0,at=ring6/sector6",
        "crack:kind=longitudinal,depth=1,width_mm=1,sector=5,rings=4-6",
    ]
    with pytest.raises(RamureError, match="whole fruit"):
        ex.place_defect_in_region("shrink:rate=0.1")
    ex.undo()
    ex.undo()
    ex.undo()
    assert FD.fruit_settings(ex, leaf)["defects"] == []


def test_a_session_file_keeps_the_regions(ex, tmp_path):
    leaf = ex.selection[0]
    ex.select_fruit_region("cells", [[4, 2], [4, 3], [5, 2], [5, 3]])
    grown, _ = ex.regrow_fruit_region(largeur="80")
    ex.save_session(tmp_path / "regions.json")
    from ramure import grammars

    again = Explorer(grammars.path("fruit_tree"), n=5)
    again.load_session(tmp_path / "regions.json")
    assert FD.fruit_settings(again, leaf)["regions"] == FD.fruit_settings(ex, leaf)["regions"]
    np.testing.assert_array_equal(FD.damaged_fruit(again, leaf)[0].points, grown.points)


def test_sub_label_patterns_narrow_a_region_and_survive_subdivision():
    """Bohl's E(^b[a-z]*$): the bottom-left quarter of each skin face, at every level."""
    once = build_fruit("round_tomato", volume_levels=1)
    twice = build_fruit("round_tomato", volume_levels=2)
    ring = {"path": "(5, C*, *)"}
    quarter = {**ring, "faces": "E(^b[a-z]*$)"}
    all_once, q_once = region_volumes(once, ring), region_volumes(once, quarter)
    # one skin cell in four of ring 5 (each coarse branch has 2 x 2 skin children)
    skin_once = region_volumes(once, {**ring, "faces": "E(.*)"})
    assert len(q_once) * 4 == len(skin_once) and set(q_once) < set(skin_once) < set(all_once)
    q_twice = region_volumes(twice, quarter)
    assert len(q_twice) == 4 * len(q_once)  # the same quarters, subdivided once more
    # the quarters' skin centres are the same part of the fruit: near the once-level ones
    c1 = once.volume_centroids()[q_once].mean(axis=0)
    c2 = twice.volume_centroids()[q_twice].mean(axis=0)
    assert np.linalg.norm(c1 - c2) < 0.05 * float(np.ptp(once.points, axis=0).max())
    out = regrow_region(twice, quarter, {"largeur": 70.0})
    inside = region_darts(twice, quarter)
    np.testing.assert_array_equal(out.points[~inside], twice.points[~inside])
    assert out.is_valid() and not np.array_equal(out.points[inside], twice.points[inside])
    with pytest.raises(RamureError, match="sub-label pattern"):
        check_region({"path": "(1)", "faces": "E^b"})


def test_a_typed_pattern_with_sub_labels(ex):
    found = ex.select_fruit_region("pattern", "(5, C*, *) E(^[ab])")["region"]
    assert found == {"path": "(5, C*, *)", "faces": "E(^[ab])"}
    before, _ = FD.damaged_fruit(ex, ex.selection[0], regions=[])
    inside = region_darts(before, found)
    assert 0 < inside.sum() < region_darts(before, {"path": "(5, C*, *)"}).sum()
    # on the once-subdivided fruit these are strips one cell wide: nothing of their own to move
    edits = len(ex.session.edits)
    with pytest.raises(RamureError, match="no vertex of its own"):
        ex.regrow_fruit_region(largeur=72.0)
    assert len(ex.session.edits) == edits
    # a hail placed there lands in the strip's middle cell, by labels
    ex.place_defect_in_region("hail:depth_mm=2")
    assert FD.fruit_settings(ex, ex.selection[0])["defects"][0].startswith("hail:depth_mm=2,at=ring5/sector")
