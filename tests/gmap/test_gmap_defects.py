"""Fruit defects: shrinkage, rot, hail, grade (issue 17)."""

import numpy as np
import pytest

from ramure.gmap import GMap3
from ramure.gmap.kernel import topology
from ramure.gmap.organs import defect_specs as S
from ramure.gmap.organs import defects as D
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.tissue import CODES


@pytest.fixture(scope="module")
def fruit():
    return build_fruit("round_tomato", volume_levels=2, seeds=20, seed=3)


def check_after(before, after):
    """Invariants after every defect."""
    topology.assert_solid(after)
    sign = D.orientation(before)
    vols = D.cell_volumes(after, sign)
    assert vols.min() > 0
    assert vols.sum() <= D.cell_volumes(before, sign).sum() + 1e-9


def unchanged(gm, copy):
    assert np.array_equal(gm.points, copy.points)
    assert np.array_equal(gm.alpha, copy.alpha)
    assert "transpiration" not in gm.volume_data or np.array_equal(
        gm.volume_data["transpiration"], copy.volume_data["transpiration"]
    )


def test_cube_edge_rate_keeps_0729():
    gm = GMap3()
    gm.add_prisms(4, sizes=[[2.0, 3.0, 1.5]])
    assert D.cell_volumes(gm)[0] == pytest.approx(9.0)
    out, facts = D.shrink(gm, 0.1)
    assert facts["volume_kept"] == pytest.approx(0.729, abs=1e-12)
    assert D.cell_volumes(out)[0] == pytest.approx(9.0 * 0.729)
    check_after(gm, out)
    vol, facts = D.shrink(gm, 0.1, rate_kind="volume")
    assert facts["volume_kept"] == pytest.approx(0.9, abs=1e-12)


def test_uniform_shrink_is_homothety(fruit):
    ref = fruit.copy()
    rates = {"seed": 1.0}
    out, facts = D.shrink(fruit, 0.1, steps=2, rates=rates)
    unchanged(fruit, ref)
    assert facts["volume_kept"] == pytest.approx(0.9**6, abs=1e-9)
    _, p0 = fruit.vertex_positions()
    _, p1 = out.vertex_positions()
    c0 = p0.mean(axis=0)
    assert np.abs((p1 - c0) - 0.81 * (p0 - c0)).max() < 1e-7 * np.abs(p0).max()
    check_after(fruit, out)


def test_seeds_with_k0_keep_their_thickness(fruit):
    out, facts = D.shrink(fruit, 0.1, steps=3)
    check_after(fruit, out)
    seeds = np.flatnonzero(fruit.volume_data["tissue"] == CODES["seed"])
    sign = D.orientation(fruit)
    v0, v1 = D.cell_volumes(fruit, sign), D.cell_volumes(out, sign)
    seed_ratio = v1[seeds].sum() / v0[seeds].sum()
    flesh = fruit.volume_data["tissue"] == CODES["mesocarp"]
    flesh_ratio = v1[flesh].sum() / v0[flesh].sum()
    assert flesh_ratio < 0.9**9 * 1.1  # the flesh lost about 1 - 0.9^9
    assert seed_ratio > 0.9  # seeds nearly keep their size
    assert 0.9**9 < facts["volume_kept"] < 1


def test_shrink_refusals(fruit):
    ref = fruit.copy()
    with pytest.raises(GMapError, match="rate x K"):
        D.shrink(fruit, 0.5, rates={"exocarp": 2.0})
    with pytest.raises(GMapError, match="unknown tissue"):
        D.shrink(fruit, 0.1, rates={"peel": 1.0})
    with pytest.raises(GMapError, match="steps"):
        D.shrink(fruit, 0.1, steps=0)
    unchanged(fruit, ref)


def test_rot_multipliers_on_rings(fruit):
    site = equator_site(fruit)
    out, facts = D.rot(fruit, vertex=site)
    k0 = D._transpiration(fruit.copy())
    k1 = out.volume_data["transpiration"]
    rings = D.rot_rings(out, site)
    assert [len(r) for r in rings] == facts["ring_cells"]
    assert len(rings[0]) == 4  # a regular skin vertex touches 4 cells
    inc = set(np.flatnonzero(np.isin(np.arange(fruit.n_volumes), rings[0])).tolist())
    vid, _ = fruit.cells(0)
    assert inc == set(np.unique(fruit.dart_volume[vid == site]).tolist())
    for ring, c in zip(rings, (2.5, 2.0, 1.5)):
        assert np.array_equal(k1[ring], k0[ring] * c)
    rest = np.ones(fruit.n_volumes, bool)
    rest[np.concatenate(rings)] = False
    assert np.array_equal(k1[rest], k0[rest])
    assert len(np.unique(np.concatenate(rings))) == sum(map(len, rings))
    from ramure.gmap.kernel import incidence

    adj = incidence.volume_adjacency(fruit, by="vertex").tocsr()  # the kernel's adjacency agrees
    for inner, outer, before in ((rings[0], rings[1], rings[0]), (rings[1], rings[2], np.r_[rings[0], rings[1]])):
        reach = np.unique(adj[inner].indices)
        assert np.array_equal(np.setdiff1d(reach, before), outer)
    shrunk, _ = D.shrink(out, 0.05)
    check_after(fruit, shrunk)
    with pytest.raises(GMapError, match=">= 0"):
        D.rot(fruit, vertex=site, coefficients=(2.5, -1, 1.5))
    assert "transpiration" not in fruit.volume_data


def equator_site(gm):
    sites = D.hail_sites(gm)
    _, pos = gm.vertex_positions()
    centre = 0.5 * (pos.min(axis=0) + pos.max(axis=0))
    return int(sites[np.argmin(np.abs(pos[sites, 2] - centre[2]))])


def test_targeted_hail_depth_and_stop(fruit):
    ref = fruit.copy()
    site = equator_site(fruit)
    out, facts = D.hail(fruit, vertices=[site], depth_mm=1.0, stop="endocarp")
    unchanged(fruit, ref)
    check_after(fruit, out)
    c = facts["craters"][0]
    assert not c["widened"] and c["actual_depth_mm"] == pytest.approx(1.0)
    _, p0 = fruit.vertex_positions()
    _, p1 = out.vertex_positions()
    moved = np.linalg.norm(p1[site] - p0[site]) * D.mm_per_unit(fruit)
    assert moved == pytest.approx(1.0, rel=0.05)
    # a deep crater stops above the endocarp: no endocarp cell has a moved vertex
    deep, facts = D.hail(fruit, vertices=[site], depth_mm=40.0, stop="endocarp")
    check_after(fruit, deep)
    assert facts["craters"][0]["widened"]
    assert facts["craters"][0]["actual_depth_mm"] < 40.0
    _, p2 = deep.vertex_positions()
    moved = np.flatnonzero(np.linalg.norm(p2 - p0, axis=1) > 1e-9 * np.abs(p0).max())
    vid, _ = fruit.cells(0)
    endo = fruit.volume_data["tissue"][fruit.dart_volume] == CODES["endocarp"]
    assert not np.isin(moved, vid[endo]).any()
    assert facts["volume_lost"] == pytest.approx(sum(x["volume"] for x in facts["craters"]))


def test_random_hail_count_distinct_and_volume(fruit):
    out, facts = D.hail(fruit, count=5, depth_mm=(2.0, 6.0), stop="endocarp", seed=7)
    check_after(fruit, out)
    verts = [c["vertex"] for c in facts["craters"]]
    assert len(verts) == 5 and len(set(verts)) == 5
    assert all(2.0 <= c["depth_mm"] <= 6.0 for c in facts["craters"])
    assert all(c["volume"] > 0 for c in facts["craters"])
    sign = D.orientation(fruit)
    lost = D.cell_volumes(fruit, sign).sum() - D.cell_volumes(out, sign).sum()
    assert facts["volume_lost"] == pytest.approx(lost, rel=1e-9)
    assert facts["volume_lost"] == pytest.approx(sum(c["volume"] for c in facts["craters"]), rel=1e-9)
    again, f2 = D.hail(fruit, count=5, depth_mm=(2.0, 6.0), stop="endocarp", seed=7)
    assert np.array_equal(again.points, out.points) and f2 == facts


def test_hail_refusals(fruit):
    ref = fruit.copy()
    n = len(D.hail_sites(fruit))
    with pytest.raises(GMapError, match="above the"):
        D.hail(fruit, count=n + 1)
    with pytest.raises(GMapError, match="unknown stop tissue"):
        D.hail(fruit, count=1, stop="rind")
    with pytest.raises(GMapError, match="> 0"):
        D.hail(fruit, count=1, depth_mm=0)
    with pytest.raises(GMapError, match="size"):
        D.hail(fruit, count=1, size_mm=float("nan"))
    unchanged(fruit, ref)


def test_grade_rule():
    ok = {"kind": "crack", "length_mm": 30.0, "depth_layers": 1, "healed_layers": 1}
    assert D.grade([ok])["marketable"]
    long = dict(ok, length_mm=31.0)
    g = D.grade([long])
    assert not g["marketable"] and "31.0 mm" in g["reasons"][0]
    g = D.grade([dict(ok, healed_layers=0)])
    assert not g["marketable"] and "healed" in g["reasons"][0]
    g = D.grade([dict(ok, depth_layers=3, healed_layers=3)])
    assert g["reasons"] == ["crack 3 layers deep, not shallow"]
    g = D.grade([{"kind": "hail", "count": 1}])
    assert not g["marketable"] and "hail" in g["reasons"][0]
    assert D.grade([{"kind": "shrink"}])["marketable"]


def test_hail_needs_the_stop_tissue():
    flat = build_fruit("round_tomato")
    with pytest.raises(GMapError, match="no endocarp cells"):
        D.hail(flat, count=1, stop="endocarp")
    with pytest.raises(GMapError, match="no mesocarp cells.*needs --subdivide volume:N"):
        D.hail(flat, count=1)  # default stop: the mesocarp without an endocarp


def test_parse_defect_specs():
    assert S.parse_defect("shrink:rate=0.1,steps=3") == ("shrink", {"rate": 0.1, "steps": 3})
    assert S.parse_defect("rot:coefficients=3/2/1") == ("rot", {"coefficients": (3.0, 2.0, 1.0)})
    with pytest.raises(GMapError, match="unknown defect"):
        S.parse_defect("mould:rate=1")
    with pytest.raises(GMapError, match="not a valid value"):
        S.parse_defect("hail:count=2.5")


def test_cli_defects_json(capsys):
    from ramure.app.cli import main
    import json

    argv = [
        "fruit",
        "--subdivide",
        "volume:2",
        "--set",
        "seeds=5",
        "--defect",
        "hail:count=3,depth_mm=1..2",
        "--defect",
        "shrink:rate=0.1,steps=2,wrinkle=0",  # smooth: the bound below is a homothety's
        "--size-mm",
        "65",
        "--json",
    ]
    assert main(argv) == 0
    rec = json.loads(capsys.readouterr().out)["defects"]
    assert [d["kind"] for d in rec["defects"]] == ["hail", "shrink"]
    assert rec["defects"][0]["count"] == 3
    assert rec["volume_lost"] == pytest.approx(rec["defects"][0]["volume_lost"] + rec["defects"][1]["volume_lost"])
    assert 0.45 < rec["volume_lost_fraction"] < 1 - 0.9**6 + 0.005  # seeds (K = 0) keep theirs
    assert rec["grade"]["marketable"] is False and "hail" in rec["grade"]["reasons"][0]
    for bad, msg in (
        (["--defect", "hail:count=x"], "not a valid value"),
        (["--defect", "shrink", "--size-mm", "-1"], "millimetres > 0"),
        (["--defect", "shrink:rate=1.5"], "[0, 1)"),
    ):
        assert main(["fruit", *bad]) == 2
        err = capsys.readouterr().err
        assert msg in err and "Traceback" not in err


def strip_expectation(gm, kind, sector, rings, depth):
    """Strip vertices minus its tips (vertices on strip border edges that are not skin), computed apart."""
    layers, layer = D.radial_layers(gm)
    vd = gm.volume_data
    ring, sec = vd["ring"], vd["sector"]
    ph = int(sec.max()) + 1
    shallow = (layer >= 0) & (layer < depth)
    in_rings = (ring >= rings[0]) & (ring <= rings[1])
    if kind == "longitudinal":
        a, b = shallow & (sec == sector) & in_rings, shallow & (sec == (sector + 1) % ph) & in_rings
    else:
        arc = (
            np.ones(len(ring), bool)
            if kind == "concentric"
            else np.isin(sec, [(sector + j) % ph for j in range(rings[1] - rings[0] + 1)])
        )
        a, b = shallow & (ring == rings[0]) & arc, shallow & (ring == rings[0] + 1) & arc
    vol = gm.dart_volume
    a3 = gm.alpha[3]
    d = np.flatnonzero((a3 != np.arange(gm.n_darts)) & a[vol] & b[vol[a3]])
    vid, _ = gm.cells(0)
    eid, _ = gm.cells(1)
    fid, _ = gm.orbit_ids("01")
    free = a3 == np.arange(gm.n_darts)
    skin_edge = np.zeros(eid.max() + 1, bool)
    skin_edge[eid[free]] = True
    pairs = np.unique(np.c_[eid[d], fid[d]], axis=0)
    faces_per_edge = np.bincount(pairs[:, 0], minlength=eid.max() + 1)
    border = (faces_per_edge[eid[d]] == 1) & ~skin_edge[eid[d]]
    tips = set(vid[d[border]].tolist()) | set(vid[gm.alpha[0][d[border]]].tolist())
    return len(set(vid[d].tolist()) - tips), d


@pytest.mark.parametrize("kind", ["longitudinal", "transverse", "concentric"])
def test_crack_duplicates_interior_vertices(fruit, kind):
    ref = fruit.copy()
    out, facts = D.crack(fruit, kind, sector=3, rings=(3, 5), depth=2, width_mm=1.0, healed=1)
    unchanged(fruit, ref)
    check_after(fruit, out)
    expected, strip = strip_expectation(fruit, kind, 3, (3, 5), 2)
    assert facts["duplicated_vertices"] == expected > 0
    assert out.cells(0)[1] - fruit.cells(0)[1] == expected
    assert facts["volume_lost"] > 0
    assert 0 < facts["opening_mm"] <= 1.0 + 1e-9
    # reported length = sum of the strip's skin edge lengths
    vid, _ = fruit.cells(0)
    eid, _ = fruit.cells(1)
    _, pos = fruit.vertex_positions()
    free = fruit.alpha[3] == np.arange(fruit.n_darts)
    skin_edges = np.zeros(eid.max() + 1, bool)
    skin_edges[eid[free]] = True
    on = strip[skin_edges[eid[strip]]]
    _, first = np.unique(eid[on], return_index=True)
    d = on[first]
    length = np.linalg.norm(pos[vid[d]] - pos[vid[fruit.alpha[0][d]]], axis=1).sum() * D.mm_per_unit(fruit)
    assert facts["length_mm"] == pytest.approx(length, rel=1e-12) and length > 0


def test_healed_faces_survive_subdivision(fruit):
    from ramure.gmap.kernel import subdivide

    out, facts = D.crack(fruit, "longitudinal", sector=2, rings=(4, 4), depth=2, width_mm=0.5, healed=1)
    healed = out.dart_data["healed"] == 1
    assert healed.any() and np.all(out.alpha[3][healed] == np.flatnonzero(healed))
    finer = subdivide.surface(out, 1)
    h2 = finer.dart_data["healed"] == 1
    assert h2.sum() == 4 * healed.sum()  # each healed quad face becomes 4
    assert np.all(finer.alpha[3][h2] == np.flatnonzero(h2))
    g = D.grade([facts])
    assert not g["marketable"] and any("healed" in r for r in g["reasons"])


def test_crack_refusals(fruit):
    ref = fruit.copy()
    for kwargs, msg in (
        (dict(depth=0), "depth"),
        (dict(depth=4), "depth"),
        (dict(width_mm=0), "width"),
        (dict(healed=3, depth=2), "healed"),
        (dict(rings=(6, 3)), "rings"),
        (dict(sector=99), "sector"),
        (dict(kind="spiral"), "kind"),
    ):
        with pytest.raises(GMapError, match=msg):
            D.crack(fruit, **kwargs)
    unchanged(fruit, ref)
    with pytest.raises(GMapError, match="subdivide volume"):
        D.crack(build_fruit("round_tomato"))


def test_crack_spec_and_grade_through_apply(fruit):
    spec = "crack:kind=longitudinal,sector=3,rings=4-4,depth=1,width_mm=0.5,healed=1"
    assert S.parse_defect(spec)[1]["rings"] == (4, 4)
    out, facts = S.apply_defects(fruit, [spec], size_mm=65)
    check_after(fruit, out)
    c = facts["defects"][0]
    assert c["length_mm"] < 30 and facts["grade"]["marketable"], facts["grade"]
    big, facts = S.apply_defects(fruit, [spec], size_mm=650)  # ten times the fruit: a long crack
    assert facts["defects"][0]["length_mm"] == pytest.approx(10 * c["length_mm"])
    assert not facts["grade"]["marketable"] and "mm long" in facts["grade"]["reasons"][0]


def test_rot_at_ring_and_sector_names_a_skin_vertex_of_that_branch(fruit):
    v = D.skin_vertex_at(fruit, 4, 2)
    out, facts = S.apply_defects(fruit, ["rot:at=ring4/sector2"])
    assert facts["defects"][0]["vertex"] == v
    vd = fruit.volume_data
    ring1 = D.rot_rings(fruit, v)[0]
    assert set(vd["ring"][ring1].tolist()) >= {4} and 2 in set(vd["sector"][ring1].tolist())
    with pytest.raises(GMapError, match="rings 0..9"):
        S.apply_defects(fruit, ["rot:at=ring12/sector2"])
    with pytest.raises(GMapError, match="ringR/sectorS"):
        S.parse_defect("rot:at=r4s2")


def test_hail_goes_into_the_flesh_without_an_endocarp():
    """Issue 40: at one subdivision, stopping at the mesocarp capped craters at a fraction of the
    thin skin (median 0.67 mm for 3.37 mm asked); the default stop is now the core."""
    one = build_fruit("round_tomato", volume_levels=1)
    out, facts = D.hail(one, count=6, depth_mm=(3.0, 4.0), seed=2)
    assert facts["stop"] == "columella" and facts["count"] == 6
    asked = np.array([c["depth_mm"] for c in facts["craters"]])
    got = np.array([c["actual_depth_mm"] for c in facts["craters"]])
    assert np.allclose(got, asked) and np.median(got) > 3.0
    check_after(one, out)
    with pytest.raises(GMapError, match="needs --subdivide volume:N"):
        D.hail(build_fruit("round_tomato"), count=1)


def test_index_reuse_matches_a_fresh_map(fruit):
    """Defects reuse a topology index cached per map; a copy made by pickling has none."""
    import pickle

    fresh = pickle.loads(pickle.dumps(fruit))
    a, fa = D.shrink(fruit, 0.05, steps=2)
    b, fb = D.shrink(fresh, 0.05, steps=2)
    np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-9)
    assert fa["volume_lost"] == pytest.approx(fb["volume_lost"], rel=1e-9)
    np.testing.assert_allclose(D.cell_volumes(a), D.cell_volumes(a, D.orientation(fruit)), rtol=1e-9)


def test_millimetres_stay_those_of_the_fruit_as_given_after_a_shrink(fruit):
    site = int(D.hail_sites(fruit)[5])
    out, facts = S.apply_defects(fruit, ["shrink:rate=0.1", f"hail:vertex={site},depth_mm=1,stop=endocarp"], size_mm=65.0)
    shrunk, _ = D.shrink(fruit, 0.1)
    _, p0 = shrunk.vertex_positions()
    _, p1 = out.vertex_positions()
    moved_mm = np.linalg.norm(p1[site] - p0[site]) * D.mm_per_unit(fruit, 65.0)  # the given fruit's mm
    assert moved_mm == pytest.approx(1.0, rel=0.05)
