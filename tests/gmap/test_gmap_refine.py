"""A fruit region at another precision (issue 40 §6): refined alone and pillowed at its rim,
every dart outside byte-identical, the map valid, χ kept, the labels still naming it."""

import numpy as np
import pytest

from ramure.errors import RamureError
from ramure.gmap.kernel.measure import volumes
from ramure.gmap.organs.defects import radial_layers
from ramure.gmap.organs.fruit import build_fruit, regrow_region
from ramure.gmap.organs.refine import refine_volumes
from ramure.gmap.organs.regions import refine_levels, region_volumes


@pytest.fixture(scope="module")
def fruit():
    return build_fruit("round_tomato", volume_levels=1)


def _bytes(gm, darts):
    """Every column of ``darts`` (involutions, positions, attributes), as bytes."""
    return b"".join([gm.alpha[:, darts].tobytes()] + [np.asarray(gm.dart_data[k])[darts].tobytes() for k in sorted(gm.dart_data)])


def _rim_faces(gm, vols):
    """Faces ``<a0,a1>`` of ``vols`` glued to a volume outside, counted independently."""
    inside = np.isin(gm.dart_volume, vols)
    a3 = gm.alpha[3]
    rim = inside & (a3 != np.arange(gm.n_darts)) & ~inside[a3]
    side, _ = gm.orbit_ids("01")
    return len(np.unique(side[rim]))


@pytest.mark.parametrize(
    ("region", "levels"),
    [
        ({"path": "(5, C*, *)"}, 1),
        ({"cells": [[4, 2], [4, 3], [5, 2], [5, 3]]}, 1),
        ({"path": "(3, C2, *)"}, 2),
        ({"path": "(6)"}, 1),
    ],
)
def test_refined_region_leaves_the_rest_byte_identical(fruit, region, levels):
    vols = region_volumes(fruit, region)
    out = refine_volumes(fruit, vols, levels)
    outside = np.flatnonzero(~np.isin(fruit.dart_volume, vols))
    assert _bytes(out, outside) == _bytes(fruit, outside)  # positions, alphas, attributes
    assert out.is_valid() and out.euler_characteristic() == fruit.euler_characteristic() == 1
    # every cell of the region (all hexahedra here) becomes 8**levels, plus one pillow per rim face
    assert np.all(fruit.volume_data["degree"][vols] == 4)
    made = 8**levels * len(vols) + _rim_faces(fruit, vols)
    assert out.n_volumes == fruit.n_volumes - len(vols) + made
    assert out.counts()["volumes"] == out.n_volumes  # every id is a volume: none left empty
    # ids outside never move; the region's ids are reused and the new ones follow
    assert np.array_equal(np.unique(out.dart_volume[outside]), np.setdiff1d(np.arange(fruit.n_volumes), vols))
    # the label pattern names exactly the refined cells and the pillows
    again = region_volumes(out, region)
    assert len(again) == made
    assert np.all(out.volume_data["refined"][again] == levels) and not out.volume_data["refined"][outside_vols(fruit, vols)].any()
    assert sorted(np.unique(out.volume_data["sub"][again]))[0] == 1


def outside_vols(gm, vols):
    return np.setdiff1d(np.arange(gm.n_volumes), vols)


@pytest.mark.parametrize("path", ["(4, C*, 0)", "(0, C*, *)"])
def test_refined_cells_tile_the_region_without_overlap(fruit, path):
    """The refined cells fill exactly the region, skin included (new points are linear, the
    skin stays where it was): the sum of their unsigned volumes is the region's, so none is
    turned inside out or overlaps another (an inner stage, and the blossom end's ring, whose
    curved skin Catmull-Clark would have shrunk by 5 %)."""
    vols = region_volumes(fruit, {"path": path})
    before = volumes(fruit)
    for levels in (1, 2, 3):
        out = refine_volumes(fruit, vols, levels)
        after = volumes(out)
        new = region_volumes(out, {"path": path})
        assert after[new].sum() == pytest.approx(before[vols].sum(), rel=1e-6)
        assert after.sum() == pytest.approx(before.sum(), rel=1e-6)
        assert after[new].min() > 1e-6 * before[vols].mean()  # no flat cell
        assert after[new].max() < before[vols].max()  # every one smaller than a cell it came from


def test_labels_and_radial_stages_survive_refinement(fruit):
    out = regrow_region(fruit, {"path": "(5, C*, *)"}, {"precision": 20})
    # the fruit still has its 2 radial layers (the finer skin cells would count 4)
    assert radial_layers(out)[0] == radial_layers(fruit)[0] == 2
    for path in ("(4, C*, *)", "(6, C3, 1)", "(9, C*, *)"):
        assert np.array_equal(region_volumes(out, {"path": path}), region_volumes(fruit, {"path": path}))
    skin = region_volumes(fruit, {"path": "(5, C3, 1)"})
    finer = region_volumes(out, {"path": "(5, C3, 1)"})
    assert len(finer) > 8 * len(skin)  # its children and its pillows, still at stage 1, sector C3
    assert set(out.volume_data["tissue"][finer]) <= set(fruit.volume_data["tissue"][skin])
    # sub-labels of the skin's faces still narrow the region (Bohl's E(...)); a face of the
    # refined skin gained a letter
    quarter = region_volumes(out, {"path": "(5, C*, *)", "faces": "E(^b[a-z]*$)"})
    assert 0 < len(quarter) < len(region_volumes(out, {"path": "(5, C*, *)", "faces": "E(.*)"}))


def test_precision_steps_and_refusals(fruit):
    assert [refine_levels(10, p) for p in (10, 20, 40, 80)] == [0, 1, 2, 3]
    region = {"path": "(5, C3, *)"}
    with pytest.raises(RamureError, match="cannot be coarser"):
        regrow_region(fruit, region, {"precision": 5})
    with pytest.raises(RamureError, match="times 2, 4 or 8"):
        regrow_region(fruit, region, {"precision": 30})
    with pytest.raises(RamureError, match="whole number"):
        regrow_region(fruit, region, {"precision": "fine"})
    with pytest.raises(RamureError, match="cannot change ph"):
        regrow_region(fruit, region, {"ph": 12})
    with pytest.raises(RamureError, match="1 to 3 times"):
        refine_volumes(fruit, region_volumes(fruit, region), 4)
    with pytest.raises(RamureError, match="more than the limit"):  # the whole fruit x8: 24 million darts
        regrow_region(fruit, {"path": "(*, C*, *)"}, {"precision": 80})
    same = regrow_region(fruit, region, {"precision": 10})  # the fruit's own: nothing to do
    assert same.n_darts == fruit.n_darts


def test_shape_and_precision_together(fruit):
    """A region with a shape change and a finer precision: shaped first, then refined."""
    region = {"cells": [[4, 2], [4, 3], [5, 2], [5, 3]]}
    out = regrow_region(fruit, region, {"largeur": 75.0, "precision": 20})
    shaped = regrow_region(fruit, region, {"largeur": 75.0})
    vols = region_volumes(fruit, region)
    outside = np.flatnonzero(~np.isin(fruit.dart_volume, vols))
    assert _bytes(out, outside) == _bytes(fruit, outside)
    assert out.is_valid() and out.euler_characteristic() == 1
    # the refined skin lies on the shaped region: its bulge is kept
    _, pos = out.vertex_positions()
    _, shaped_pos = shaped.vertex_positions()
    _, old_pos = fruit.vertex_positions()
    centre = old_pos.mean(axis=0)
    reach = lambda p: float(np.linalg.norm(p[:, :2] - centre[:2], axis=1).max())  # noqa: E731
    assert reach(pos) > reach(old_pos) + 0.5 * (reach(shaped_pos) - reach(old_pos))


def test_build_fruit_applies_a_precision_region():
    region = {"path": "(5, C*, *)", "params": {"precision": 20}}
    plain = build_fruit("round_tomato")  # the plant's coarse fruit (no volume subdivision)
    built = build_fruit("round_tomato", regions=[region])
    vols = region_volumes(plain, region)
    outside = np.flatnonzero(~np.isin(plain.dart_volume, vols))
    assert _bytes(built, outside) == _bytes(plain, outside)
    assert built.is_valid() and built.euler_characteristic() == plain.euler_characteristic()
    assert len(region_volumes(built, region)) > 8 * len(vols)
    assert built.meta["regions"] == [region]


def test_overlapping_regions_refine_twice_and_defects_still_apply():
    """A region refined inside a refined one is refined again (pillows are cells as any
    other); hail, cracks and rot still apply to the refined fruit, which stays valid."""
    from ramure.gmap.organs.defect_specs import apply_defects

    ring = {"path": "(5, C*, *)", "params": {"precision": 20}}
    patch = {"cells": [[5, 2], [6, 2]], "params": {"precision": 20}}
    once = build_fruit("round_tomato", volume_levels=1, regions=[ring])
    twice = build_fruit("round_tomato", volume_levels=1, regions=[ring, patch])
    assert twice.is_valid() and twice.euler_characteristic() == 1
    outside = np.flatnonzero(~np.isin(once.dart_volume, region_volumes(once, patch)))
    assert _bytes(twice, outside) == _bytes(once, outside)
    assert np.any(twice.volume_data["refined"] == 2)  # the cells of (5, C3) refined twice
    for spec in ("hail:depth_mm=2,at=ring5/sector2", "crack:kind=longitudinal,depth=1,width_mm=1,sector=5,rings=4-6"):
        damaged, facts = apply_defects(once, [spec], seed=0)
        assert damaged.is_valid() and facts["volume_lost_fraction"] > 0


def test_a_sub_label_region_is_skipped_where_faces_have_no_sub_labels():
    """The plant's coarse fruit has no sub-labels yet: a region narrowed by one names no cell
    there and is left out (the Defects view's subdivided fruit is refined)."""
    region = {"path": "(5, C*, *)", "faces": "E(^b[a-z]*$)", "params": {"precision": 20}}
    coarse = build_fruit("round_tomato", regions=[region])
    assert coarse.n_darts == build_fruit("round_tomato").n_darts
    with pytest.raises(RamureError, match="names no cell"):
        regrow_region(build_fruit("round_tomato"), region, {"precision": 20})
    fine = build_fruit("round_tomato", volume_levels=1, regions=[region])
    assert fine.is_valid() and fine.n_darts > 48000


def test_a_trunk_prism_of_the_coarse_fruit():
    """The coarse fruit's trunk stage is one 10-sided prism: refined once it becomes one
    hexahedron per corner (20) and a pillow on each of its 12 faces, all shared."""
    coarse = build_fruit("round_tomato")
    vols = region_volumes(coarse, {"path": "(5)"})
    assert len(vols) == 1 and coarse.volume_data["degree"][vols[0]] == 10
    out = refine_volumes(coarse, vols)
    assert out.n_volumes == coarse.n_volumes - 1 + 20 + 12
    assert out.is_valid() and out.euler_characteristic() == coarse.euler_characteristic()
    outside = np.flatnonzero(coarse.dart_volume != vols[0])
    assert _bytes(out, outside) == _bytes(coarse, outside)
    assert volumes(out)[region_volumes(out, {"path": "(5)"})].sum() == pytest.approx(volumes(coarse)[vols[0]], rel=1e-9)
