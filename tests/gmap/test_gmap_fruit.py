"""Fruit shape: acceptance counts, presets, parameters, placement."""

import numpy as np
import pytest

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.fruit import PRESETS, build_fruit, dimple_angles, resolve_params, rib_profile, sample


def test_round_tomato_matches_the_thesis_table():
    gm = build_fruit("round_tomato")
    c = gm.counts()
    assert (c["darts"], c["vertices"], c["faces_per_volume"], c["volumes"]) == (6000, 220, 720, 110)
    assert c["edges"] == 530 and c["faces"] == 421  # 720 - 299 sewn pairs
    assert gm.euler_characteristic() == 1
    assert gm.boundary().euler_characteristic() == 2
    assert gm.is_valid(), gm.validity_problems()
    vd = gm.volume_data
    assert (vd["label"] == "A").sum() == 10 and (vd["label"] == "B").sum() == 100
    assert np.array_equal(np.bincount(vd["parent"][10:]), np.full(10, 10))


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_every_preset_is_a_valid_solid_ball(preset):
    gm = build_fruit(preset)
    p = resolve_params(preset)
    n, ph = p["precision"], p["ph"]
    c = gm.counts()
    assert c["darts"] == n * 12 * ph + n * ph * 48
    assert c["vertices"] == 2 * (n + 1) * ph
    assert c["volumes"] == n * (ph + 1)
    assert gm.is_valid(), gm.validity_problems()
    assert gm.euler_characteristic() == 1
    assert gm.boundary().euler_characteristic() == 2


def skin_points(gm):
    """Vertices of the branches' E faces (the skin), as positions."""
    face, vol = gm.dart_data["face"], gm.dart_volume
    skin = (face == 1) & (gm.volume_data["order"][vol] == 1)
    return gm.points[skin]


def test_round_tomato_size_follows_largeur_and_has_a_stem_dimple():
    gm = build_fruit("round_tomato")
    skin = skin_points(gm)
    radius = np.hypot(skin[:, 0], skin[:, 1])
    assert 50 < radius.max() < 65  # about largeur + trunk radius
    wider = build_fruit("round_tomato", largeur=80.0)
    assert np.hypot(*skin_points(wider)[:, :2].T).max() > radius.max() + 20
    # the stem pole (axis top) sits below the shoulders around it
    top_axis = gm.points[(gm.dart_volume == 9) & (gm.dart_data["face"] == 1)][:, 2].mean()
    assert skin[:, 2].max() > top_axis + 5
    flat = build_fruit("round_tomato", nbvolangle=0)
    top_flat = flat.points[(flat.dart_volume == 9) & (flat.dart_data["face"] == 1)][:, 2].mean()
    assert skin_points(flat)[:, 2].max() < top_flat + 5


def test_ribbed_tomato_has_nbprotus_ribs_around_its_equator():
    gm = build_fruit("ribbed_tomato")
    p = resolve_params("ribbed_tomato")
    vd = gm.volume_data
    branches = np.flatnonzero((vd["order"] == 1) & (vd["ring"] == p["precision"] // 2))
    length = vd["size"][branches, 0]
    sector = vd["sector"][branches]
    profile = length[np.argsort(sector)]
    peaks = (profile > np.roll(profile, 1)) & (profile >= np.roll(profile, -1))
    assert peaks.sum() == p["nbprotus"] == 6
    assert profile.min() == pytest.approx(profile.max() * p["creux"], rel=1e-6)


def test_banana_axis_bends():
    gm = build_fruit("banana")
    frames = gm.volume_data["frame"][:10]
    heading = frames[:, 0]
    angle = np.degrees(np.arccos(np.clip(heading[0] @ heading[-1], -1, 1)))
    assert angle == pytest.approx(9 * 12.0)
    straight = build_fruit("banana", rotz=0.0)
    assert np.allclose(straight.volume_data["frame"][:10, 0], straight.volume_data["frame"][0, 0])


def test_profiles_and_ramps():
    assert sample("sin", 3, 0.1).round(6).tolist() == [0.1, 1.0, 0.1]
    assert np.allclose(sample("constant", 4, 0.1), 1.0)
    assert rib_profile(6, 0, 0.5).tolist() == [1.0] * 6
    fd = rib_profile(24, 6, 0.5)
    assert fd.min() == 0.5 and fd.max() == 1.0 and fd[0] == 0.5
    assert dimple_angles(10, 5, 0.0, -60.0)[-5:].tolist() == [0.0, -15.0, -30.0, -45.0, -60.0]
    assert dimple_angles(10, 1, 0.0, -60.0)[-1] == 0.0
    assert not dimple_angles(10, 0, 0.0, -60.0).any()


def test_parameters_are_converted_and_checked():
    p = resolve_params("round_tomato", precision="12", largeur="40.5", fc="constant")
    assert p["precision"] == 12 and p["largeur"] == 40.5 and p["fc"] == "constant"
    for bad in (
        dict(precision=0),
        dict(ph=2),
        dict(largeur=-1),
        dict(fc="cube"),
        dict(creux=0),
        dict(nbvolangle=11),
        dict(precision="1.5"),
        dict(colour=3),
        dict(carpels=0),
        dict(exocarp=0.5, mesocarp=0.5),
    ):
        with pytest.raises(ValueRefused):
            resolve_params("round_tomato", **bad)
    with pytest.raises(ValueRefused, match="unknown fruit preset"):
        build_fruit("quince")


def test_placement_size_origin_and_frame():
    gm = build_fruit("elongated_tomato", size=10.0, origin=(1, 2, 3))
    _, pos = gm.vertex_positions()
    extent = pos.max(axis=0) - pos.min(axis=0)
    assert extent.max() == pytest.approx(10.0)
    assert np.argmax(extent) == 2  # long along its axis (z)
    assert np.allclose(0.5 * (pos.max(axis=0) + pos.min(axis=0)), [1, 2, 3])
    # turn the axis to +x: H = x, L = y, U = z
    turned = build_fruit("elongated_tomato", size=10.0, frame=[[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    _, pos = turned.vertex_positions()
    assert np.argmax(pos.max(axis=0) - pos.min(axis=0)) == 0
    stem = build_fruit("round_tomato", anchor="stem")
    _, pos = stem.vertex_positions()
    axis_top = stem.points[(stem.dart_volume == 9) & (stem.dart_data["face"] == 1)].mean(axis=0)
    assert np.allclose(axis_top, 0.0, atol=1e-9)
    assert pos[:, 2].min() < -40  # the body hangs below the stem point


def test_builds_are_deterministic_and_store_provenance():
    a = build_fruit("cherry_tomato", seed=3)
    b = build_fruit("cherry_tomato", seed=3)
    assert np.array_equal(a.alpha, b.alpha) and np.allclose(a.points, b.points)
    assert a.meta["preset"] == "cherry_tomato" and a.meta["seed"] == 3
    assert a.meta["params"]["precision"] == 20


def test_seeds_carved_at_once_sit_between_two_gel_slabs():
    """Issue 40 (level-2 profile): the seeds are cut in one batch, as one by one before: each
    is a middle slab of its cell (gel on the columella side, gel outside), so no seed touches
    the columella, and carving keeps the locules' volume."""
    from ramure.gmap.organs.defects import cell_volumes
    from ramure.gmap.organs.fruit import build_fruit
    from ramure.gmap.organs.tissue import CODES

    plain = build_fruit("round_tomato", volume_levels=2, seeds=0, seed=1)
    gm = build_fruit("round_tomato", volume_levels=2, seeds=30, seed_smoothing=0, seed=1)
    assert gm.is_valid()
    tissue, vol, a3 = gm.volume_data["tissue"], gm.dart_volume.astype(np.int64), gm.alpha[3]
    seeds = np.flatnonzero(tissue == CODES["seed"])
    assert len(seeds) == 30 and gm.n_volumes == plain.n_volumes + 60
    for s in seeds:
        darts = np.flatnonzero(vol == s)
        around = tissue[vol[a3[darts[a3[darts] != darts]]]]
        assert CODES["columella"] not in around and (around == CODES["locule"]).sum() >= 8
    gel = (tissue == CODES["locule"]) | (tissue == CODES["seed"])
    before = cell_volumes(plain)[plain.volume_data["tissue"] == CODES["locule"]].sum()
    assert cell_volumes(gm)[gel].sum() == pytest.approx(before, rel=1e-6)
    share = cell_volumes(gm)[seeds].sum() / before
    assert 0.005 < share < 0.2
