"""Issue 40 §1, §2, §4: species colours, real sizes, damage marks, round deep pits, UNECE grading."""

import numpy as np
import pytest

from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.organs import defects as D
from ramure.gmap.organs import grading as G
from ramure.gmap.organs import species as SP
from ramure.gmap.organs.defect_specs import apply_defects
from ramure.gmap.organs.fruit import PRESETS, build_fruit
from ramure.gmap.organs.tissue import CODES


def _hue(rgb):
    r, g, b = (np.asarray(rgb, float) / 255.0).T
    mx, mn = np.maximum(np.maximum(r, g), b), np.minimum(np.minimum(r, g), b)
    d = np.where(mx - mn == 0, 1, mx - mn)
    h = np.where(mx == r, ((g - b) / d) % 6, np.where(mx == g, (b - r) / d + 2, (r - g) / d + 4))
    return 60.0 * h


@pytest.mark.parametrize(
    "species, stage, lo, hi",
    [
        ("tomato", "green", 75, 140),
        ("tomato", "turning", 15, 45),
        ("tomato", "red", -1, 12),
        ("banana", "green", 75, 140),
        ("banana", "yellow", 45, 65),
        ("apple", "green", 70, 110),
        ("apple", "yellow", 45, 65),
        ("apple", "red", 340, 361),
        ("pear", "ripe", 40, 65),
        ("plum", "ripe", 260, 300),
    ],
)
def test_skin_hue_by_species_and_stage(species, stage, lo, hi):
    hue = float(_hue([SP.cell_rgb([CODES["exocarp"]], species, stage)[0]])[0])
    hue = hue if not (lo < 0 and hue > 300) else hue - 360
    assert lo <= hue <= hi, (species, stage, hue)


def test_no_tomato_gel_in_pears_bananas_apples_and_a_stone_in_drupes():
    for species in ("pear", "banana", "apple"):
        names = {SP.shown_name(species, t) for t in ("locule", "endocarp", "columella")}
        assert not names & {"locular gel", "locule"}
        flesh, inner = SP.palette(species)["mesocarp"], SP.palette(species)["locule"]
        # pale inside, not red: every channel of the flesh and core above 200
        assert min(SP.hex_rgb(flesh)) > 190 and min(SP.hex_rgb(inner)) > 150
    for species in ("plum", "cherry"):
        assert {SP.shown_name(species, t) for t in SP.STONE_TISSUES} == {"stone"}
        assert SP.shown_name(species, "seed") == "kernel"


def test_every_preset_has_a_species_and_a_real_size():
    assert set(PRESETS) == set(SP.SPECIES_OF) == set(SP.SIZE_MM)
    gm = build_fruit("cherry_tomato")
    assert gm.meta["size_mm"] == 25.0 and gm.meta["species"] == "tomato" and gm.meta["ripeness"] == "red"
    assert build_fruit("banana").meta["size_mm"] == 180.0
    # millimetres follow the preset: the largest extent is the real size
    _, pos = gm.vertex_positions()
    assert np.isclose(float(np.ptp(pos, axis=0).max()) * D.mm_per_unit(gm), 25.0)
    with pytest.raises(ValueRefused, match="choose one of green, yellow, flecked"):
        build_fruit("banana", ripeness="purple")


def test_bicolour_apple_blushes_on_one_side_and_flecks_stay_put():
    tissue = np.full(200, CODES["exocarp"])
    angle = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    centres = np.stack([np.cos(angle), np.sin(angle), np.zeros(200)], axis=1)
    rgb = SP.cell_rgb(tissue, "apple", "bicolour", centres).astype(int)
    sun, shade = rgb[np.cos(angle) > 0.9], rgb[np.cos(angle) < -0.9]
    assert (sun[:, 0] - sun[:, 1]).mean() > (shade[:, 0] - shade[:, 1]).mean() + 60  # redder in the sun
    a = SP.cell_rgb(tissue, "banana", "flecked", centres, seed=3)
    assert np.array_equal(a, SP.cell_rgb(tissue, "banana", "flecked", centres, seed=3))
    dark = (a.astype(int).sum(axis=1) < 300).mean()
    assert 0.04 < dark < 0.2


def test_turning_tomato_colours_from_the_blossom_end():
    tissue = np.full(3, CODES["exocarp"])
    centres = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # blossom end, equator, stem end
    rgb = SP.cell_rgb(tissue, "tomato", "turning", centres)
    hue = _hue(rgb)
    assert tuple(rgb[0]) == SP.hex_rgb(SP.palette("tomato", "turning")["exocarp"])  # coloured first: the stage's own
    assert hue[0] < hue[1] < hue[2] and hue[2] - hue[0] > 12  # shoulders stay yellow-green
    red = SP.cell_rgb(tissue, "tomato", "red", centres)
    assert (red == red[0]).all()  # a ripe tomato is red all over


def test_tomato_and_cherry_stalks_are_green_apple_and_pear_woody():
    for species in ("tomato", "cherry"):
        r, g, b = SP.hex_rgb(SP.stem_colour(species))
        assert g > r > b, species
    for species in ("apple", "pear"):
        r, g, b = SP.hex_rgb(SP.stem_colour(species))
        assert r > g > b, species
    stem = next(m for m in SP.materials("cherry") if m["name"] == "stem")
    assert stem["rgb"][1] > stem["rgb"][0]


@pytest.fixture(scope="module")
def tomato():
    return build_fruit("round_tomato", volume_levels=1)


def test_healed_crack_walls_are_corky_brown_and_fresh_ones_are_not(tomato):
    healed, facts = apply_defects(tomato, ["crack:healed=1"])
    fresh, _ = apply_defects(tomato, ["crack:healed=0"])
    assert healed.is_valid() and fresh.is_valid()
    corky = np.asarray(healed.volume_data["corky"]) > 0
    assert corky.sum() > 0 and np.asarray(fresh.volume_data["wound"]).sum() > 0
    assert not np.any(np.asarray(fresh.volume_data["corky"]))
    rgb_h = SP.cell_rgb(healed.volume_data["tissue"], "tomato", "red", marks={"corky": healed.volume_data["corky"]})
    assert np.all(rgb_h[corky] == SP.hex_rgb(SP.CORK))
    rgb_f = SP.cell_rgb(fresh.volume_data["tissue"], "tomato", "red", marks={"wound": fresh.volume_data["wound"]})
    wound = np.asarray(fresh.volume_data["wound"]) > 0
    assert not np.any(np.all(rgb_f[wound] == SP.hex_rgb(SP.CORK), axis=1))
    assert facts["defects"][0]["volume_lost"] > 0 and facts["volume_lost_mm3"] > 0


def test_growth_cracks_default_to_the_stem_scar(tomato):
    rings = int(tomato.volume_data["ring"].max()) + 1
    _, facts = apply_defects(tomato, ["crack:kind=concentric,healed=1"])
    r0, _ = facts["defects"][0]["rings"]
    assert r0 >= rings - 3  # ring 0 is the blossom end
    _, facts = apply_defects(tomato, ["crack"])
    assert facts["defects"][0]["rings"][1] == rings - 2


def test_hail_pits_are_round_deep_and_bruised(tomato):
    idx_before = tomato.vertex_positions()[1]
    scale = D.mm_per_unit(tomato)
    graph = D._index(tomato).graph
    on_skin = D._index(tomato).on_skin
    for seed in range(4):  # one pit at a time: neighbouring pits would share rim vertices
        out, facts = D.hail(tomato, count=1, depth_mm=(3.0, 4.0), seed=seed, healed=1)
        assert out.is_valid()
        pos = out.vertex_positions()[1]
        c = facts["craters"][0]
        v = c["vertex"]
        assert c["actual_depth_mm"] == pytest.approx(c["depth_mm"])
        rim = graph.indices[graph.indptr[v] : graph.indptr[v + 1]]
        rim = rim[on_skin[rim]]
        sink = np.linalg.norm(pos[rim] - idx_before[rim], axis=1) * scale
        # round: every rim vertex sinks alike (within 25 %), about HAIL_RIM of the depth
        assert sink.std() / sink.mean() < 0.25
        assert sink.mean() == pytest.approx(D.HAIL_RIM * c["depth_mm"], rel=0.3)
        assert c["area_mm2"] == pytest.approx(np.pi * (c["diameter_mm"] / 2) ** 2)
    assert np.asarray(out.volume_data["bruise"]).max() == 1.0
    assert np.asarray(out.volume_data["scar"]).sum() > 0
    with pytest.raises(GMapError, match="healed must be 0"):
        D.hail(tomato, count=1, healed=2)


def test_rot_marks_fade_from_the_centre(tomato):
    out, facts = apply_defects(tomato, ["rot:at=ring4/sector2"])
    rot = np.asarray(out.volume_data["rot"])
    assert out.is_valid() and rot.max() == pytest.approx(1.0) and rot[rot > 0].min() == pytest.approx(0.15)
    assert (rot > 0).sum() == sum(facts["defects"][0]["ring_cells"])
    rgb = SP.cell_rgb(out.volume_data["tissue"], "tomato", "red", marks={"rot": rot})
    plain = SP.cell_rgb(out.volume_data["tissue"], "tomato", "red")
    assert np.all(np.any(rgb[rot > 0] != plain[rot > 0], axis=1))


# -------------------------------------------------------------------- grading
def test_tomato_table_matches_ffv36_limits():
    rows = {r["measure"]: r for r in G.table_rows("tomato")}
    assert rows["healed_crack_mm"]["class_ii"] == 30.0 and rows["healed_crack_mm"]["class_i"] == 0
    assert rows["crack_count"]["class_i"] == 0 and rows["crack_count"]["class_ii"] is None
    assert rows["rot_cells"]["class_ii"] == 0
    assert "FFV-36" in G.STANDARDS["tomato"]["standard"]


@pytest.mark.parametrize("species, class_i, class_ii", [("apple", 20.0, 40.0), ("pear", 20.0, 40.0)])
def test_pome_tables_match_ffv50_ffv51_limits(species, class_i, class_ii):
    rows = {r["measure"]: r for r in G.table_rows(species)}
    assert (rows["healed_crack_mm"]["class_i"], rows["healed_crack_mm"]["class_ii"]) == (class_i, class_ii)
    assert (rows["hail_area_mm2"]["class_i"], rows["hail_area_mm2"]["class_ii"]) == (100.0, 250.0)


def _crack(length, healed=True):
    return {"kind": "crack", "length_mm": length, "depth_layers": 1, "healed_layers": 1 if healed else 0}


def test_grades_say_which_limit_failed_and_by_how_much():
    assert G.grade_unece([], "tomato")["grade"] == "Extra"
    g = G.grade_unece([_crack(25.0)], "tomato")
    assert g["grade"] == "Class II"
    g = G.grade_unece([_crack(36.0)], "tomato")
    assert g["grade"] == G.OUT
    fail = next(f for f in g["failed"] if f["class"] == "Class II")
    assert fail["measure"] == "healed_crack_mm" and fail["by"] == pytest.approx(6.0) and "3 cm" in fail["clause"]
    assert G.grade_unece([_crack(15.0)], "apple")["grade"] == "Class I"
    assert G.grade_unece([_crack(35.0)], "pear")["grade"] == "Class II"
    assert G.grade_unece([_crack(5.0, healed=False)], "apple")["grade"] == G.OUT
    hail = {"kind": "hail", "healed": 1, "craters": [{"area_mm2": 40.0, "actual_depth_mm": 0.8}]}
    assert G.grade_unece([hail], "tomato")["grade"] == "Class I"  # slight healed hail: Class I (FFV-36)
    assert G.grade_unece([dict(hail, healed=0)], "tomato")["grade"] == G.OUT
    assert G.grade_unece([{"kind": "rot", "ring_cells": [4, 8, 12]}], "apple")["grade"] == G.OUT
    assert G.grade_unece([], "tomato", {"volume_lost_fraction": 0.04})["grade"] == "Class II"  # shrivel is graded
    banana = G.grade_unece([_crack(5.0)], "banana")
    assert banana["grade"] is None and "FFV-35" in banana["standard"]


def test_apply_defects_grades_by_the_fruit_species(tomato):
    _, facts = apply_defects(tomato, ["shrink:rate=0.05"])
    assert facts["grade"]["marketable"] and facts["unece"]["grade"] == G.OUT  # OECD check kept, shrivel graded
    pear = build_fruit("pear", volume_levels=1)
    _, facts = apply_defects(pear, ["crack:healed=1"])
    assert facts["unece"]["standard"].startswith("UNECE FFV-51")


def test_shrivel_wrinkles_the_skin_and_is_no_homothety(tomato):
    smooth, _ = apply_defects(tomato, ["shrink:rate=0.06,wrinkle=0"])
    wrinkled, facts = apply_defects(tomato, ["shrink:rate=0.06"])
    assert wrinkled.is_valid() and facts["defects"][0]["wrinkle_mm"] > 0.5
    idx = D._index(tomato)
    skin = idx.on_skin

    def radius_spread(gm):
        pos = gm.vertex_positions()[1]
        r = np.linalg.norm(pos[skin] - pos[skin].mean(axis=0), axis=1)
        fresh = np.linalg.norm(tomato.vertex_positions()[1][skin] - tomato.vertex_positions()[1][skin].mean(axis=0), axis=1)
        return np.std(r / fresh)  # 0 for a homothety

    assert radius_spread(smooth) < 1e-6 < 0.005 < radius_spread(wrinkled)
    assert facts["volume_lost_mm3"] > 0 and facts["unece"]["grade"] == G.OUT
    with pytest.raises(GMapError, match="wrinkle must be >= 0"):
        apply_defects(tomato, ["shrink:rate=0.05,wrinkle=-1"])


def test_shrivel_wavelength_is_chosen_in_mm_and_checked(tomato):
    default, facts = apply_defects(tomato, ["shrink:rate=0.06"])
    fine, fine_facts = apply_defects(tomato, ["shrink:rate=0.06,wave_mm=12"])
    size = facts["size_mm"] * (1 - facts["defects"][0]["edge_rate"])  # the shrunk fruit's size
    assert facts["defects"][0]["wrinkle_wavelength_mm"] == pytest.approx(size * D.WRINKLE_WAVELENGTH, rel=0.02)
    assert fine_facts["defects"][0]["wrinkle_wavelength_mm"] == pytest.approx(12.0)
    assert fine.is_valid() and not np.allclose(fine.points, default.points)  # another crease pattern
    for bad in ("0", "-3", "nan"):
        with pytest.raises(GMapError, match="wave_mm must be > 0"):
            apply_defects(tomato, [f"shrink:rate=0.05,wave_mm={bad}"])


def test_rot_patch_is_round_and_hail_scars_are_separate_from_crack_walls(tomato):
    out, _ = apply_defects(tomato, ["rot:at=ring4/sector2"])
    rot = np.asarray(out.volume_data["rot"])
    assert rot.max() == pytest.approx(1.0) and rot[rot > 0].min() == pytest.approx(0.15)
    healed, _ = D.hail(tomato, count=1, depth_mm=2.0, healed=1, seed=1)
    assert np.asarray(healed.volume_data["scar"]).sum() > 0 and "corky" not in healed.volume_data


@pytest.mark.parametrize(
    "spec",
    [
        "hail:count=3,depth_mm=3..4,healed=1",
        "crack:healed=1",
        "crack:kind=concentric",
        "rot:at=ring4/sector2,rate=0.05",
        "shrink:rate=0.06",
        "excrescence:path=(6,C3,*),height_mm=3",
    ],
)
def test_every_defect_keeps_a_valid_ball(tomato, spec):
    """chi = 1 for the solid and 2 for its skin after each defect (a crack is a notch, not a hole)."""
    out, facts = apply_defects(tomato, [spec])
    assert out.is_valid()
    assert out.euler_characteristic() == tomato.euler_characteristic() == 1
    assert out.boundary().euler_characteristic() == 2
    assert facts["volume_lost_mm3"] >= 0 or spec.startswith("excrescence")  # a bump adds volume
