"""Cracks cut through a 3-G-map's cells along their curve, not along its grid (issue 40, item 2)."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.crackcut import Curve
from ramure.gmap.organs.cracks import random_pattern
from ramure.gmap.organs.fruit import build_fruit
from ramure.gmap.organs.mapcracks import Skin, crack_curves, crack_edges, crack_map, mouth_edges


@pytest.fixture(scope="module")
def fruit():
    return build_fruit("round_tomato", volume_levels=1)  # skin edges about 8 units, 110 across


@pytest.fixture(scope="module")
def skin(fruit):
    return Skin(fruit)


@pytest.fixture(scope="module")
def side(skin):
    return skin.pos[skin.used][np.argmax(skin.pos[skin.used, 0])]


def _to_curves(points, curves):
    """Distance of each point to the nearest of the crack's chains."""
    return np.min([np.linalg.norm(c.nearest(points)[2] - points, axis=1) for c in curves], axis=0)


def _to_segments(points, a, b):
    """Distance of each point to the nearest segment ``a[k] -> b[k]``."""
    ab = b - a
    t = np.clip(np.einsum("pkj,kj->pk", points[:, None, :] - a[None], ab) / np.einsum("kj,kj->k", ab, ab), 0, 1)
    foot = a[None] + t[:, :, None] * ab[None]
    return np.linalg.norm(foot - points[:, None, :], axis=2).min(axis=1)


def test_the_ribbon_field_measures_across_and_down():
    """On a straight chain over a flat skin, ``s`` is the offset across the crack and ``depth``
    the distance under the skin, whatever the point's place along the chain."""
    x = np.linspace(0.0, 10.0, 11)
    points = np.c_[x, np.zeros(11), np.zeros(11)]
    normal = np.tile([0.0, 0.0, 1.0], (11, 1))
    side = np.cross(np.tile([1.0, 0.0, 0.0], (11, 1)), normal)  # d x n = (0, -1, 0)
    curve = Curve(points, normal, side, np.full(11, 0.5), np.full(11, 3.0))
    p = np.array([[2.5, 0.7, -1.0], [7.25, -0.3, -2.0], [0.0, 0.0, 0.0], [12.0, 0.0, 0.0]])
    f = curve.field(p)
    np.testing.assert_allclose(f["s"], [-0.7, 0.3, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(f["depth"], [1.0, 2.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(f["along"], [2.5, 7.25, 0.0, 10.0], atol=1e-12)
    assert f["inside"].tolist() == [True, True, False, False]


@pytest.mark.parametrize("seed, nodes, branching", [(0, 12, 0.3), (5, 7, 0.0)])
def test_the_crack_follows_its_curve_not_the_grid(fruit, skin, side, seed, nodes, branching):
    pattern = random_pattern(nodes, seed=seed, length=8.0, width=0.0, depth=8.0, branching=branching)
    out, facts = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
    assert facts["valid"] and (facts["euler_after"], facts["skin_euler_after"]) == (1, 2)
    curves = crack_curves(skin, pattern, side, (0, 0, 1))
    edge = skin.mean_edge
    walls = np.flatnonzero(np.asarray(out.dart_data["crack"]) == 1)
    mouth = mouth_edges(out, walls)  # on the skin, both lips (shut: the crack has no width here)
    _, pos = out.vertex_positions()
    a, b = pos[mouth[:, 0]], pos[mouth[:, 1]]
    # every corner and every edge middle of the crack's mouth lies on its curve ...
    assert _to_curves(np.r_[a, b, (a + b) / 2], curves).max() < 0.05 * edge
    # ... and the mouth runs the curve's whole way (every sample of the curve is next to it)
    samples = np.concatenate([c.points for c in curves])
    assert _to_segments(samples, a, b).max() < 0.25 * edge
    # the old crack, along the skin's edges, was off the same curve by more than half an edge
    old = np.array(list(crack_edges(skin, pattern, side, (0, 0, 1)))).ravel()
    assert _to_curves(skin.pos[old], curves).max() > 0.5 * edge
    # its length is the curve's (both lips counted once), and the pattern's to a few per cent
    curve_length = sum(c.length[-1] for c in curves)
    assert facts["length"] == pytest.approx(0.5 * np.linalg.norm(a - b, axis=1).sum(), rel=1e-9)
    assert facts["length"] == pytest.approx(curve_length, rel=0.03)
    assert facts["length"] == pytest.approx(pattern.total_length(), rel=0.05)
    # the cells along the crack are labelled, and only they (the dataset's per-cell defect mark)
    wounded = np.flatnonzero(np.asarray(out.volume_data["wound"]) == 1)
    assert np.array_equal(wounded, np.unique(out.dart_volume[walls])) and len(wounded) >= facts["cells_split"]
    # cutting alone keeps the fruit's volume: a shut crack loses nothing
    assert abs(facts["volume_lost"]) < 1e-9 * facts["volume_before"]
    assert facts["volume_after"] == pytest.approx(facts["volume_before"], rel=1e-5)


def test_an_open_crack_is_centred_on_its_curve_and_loses_its_gap(fruit, skin, side):
    pattern = random_pattern(7, seed=5, length=8.0, width=1.0, depth=8.0, branching=0.0)
    out, facts = crack_map(fruit, pattern, anchor=side, direction=(0, 0, 1))
    assert facts["valid"] and facts["opening"] > 0 and facts["narrowed"] == 1.0
    curves = crack_curves(skin, pattern, side, (0, 0, 1))
    walls = np.flatnonzero(np.asarray(out.dart_data["crack"]) == 1)
    mouth = mouth_edges(out, walls)
    _, pos = out.vertex_positions()
    lips = np.unique(mouth)
    off = curves[0].field(pos[lips])
    # the lips part to both sides of the curve, no wider than the opening, none on the curve
    # but the tips (which stay shut)
    assert (off["s"] > 0.05).sum() > 5 and (off["s"] < -0.05).sum() > 5
    assert np.abs(off["s"]).max() <= 0.5 * facts["opening"] + 1e-9
    # the volume lost is the gap: positive, and less than the mouth's length x opening x depth
    assert 0 < facts["volume_lost"] < facts["length"] * facts["opening"] * 8.0


def test_a_concentric_crack_follows_the_circle_round_the_stem(fruit, skin):
    from ramure.gmap.organs.crackcut import ring_curve
    from ramure.gmap.organs.mapcracks import crack_along

    top = float(skin.pos[skin.used, 2].max())
    curve = ring_curve(skin.mesh, top - 15.0, arc=120.0, start=-60.0, width=0.0, depth=6.0)
    # the curve is the skin's level section: one height, a circle's arc round the axis
    rho = np.hypot(curve.points[:, 0], curve.points[:, 1])
    theta = np.degrees(np.arctan2(curve.points[:, 1], curve.points[:, 0]))
    assert np.ptp(curve.points[:, 2]) < 1e-9 and np.ptp(rho) < 0.05 * rho.mean()
    assert theta[0] == pytest.approx(-60.0, abs=1.0) and theta[-1] == pytest.approx(60.0, abs=1.0)
    assert curve.length[-1] == pytest.approx(np.radians(120.0) * rho.mean(), rel=0.01)
    out, facts = crack_along(fruit, [curve])
    assert facts["valid"] and (facts["euler_after"], facts["skin_euler_after"]) == (1, 2)
    walls = np.flatnonzero(np.asarray(out.dart_data["crack"]) == 1)
    mouth = mouth_edges(out, walls)
    _, pos = out.vertex_positions()
    a, b = pos[mouth[:, 0]], pos[mouth[:, 1]]
    assert _to_curves(np.r_[a, b, (a + b) / 2], [curve]).max() < 0.05 * skin.mean_edge
    assert np.abs(np.r_[a, b][:, 2] - (top - 15.0)).max() < 0.05 * skin.mean_edge  # level all round
    assert facts["length"] == pytest.approx(curve.length[-1], rel=0.01)
    with pytest.raises(GMapError, match="closed ring"):
        ring_curve(skin.mesh, top - 15.0, arc=360.0)
    with pytest.raises(GMapError, match="misses the skin"):
        ring_curve(skin.mesh, top + 50.0, arc=90.0)


def test_the_command_cracks_a_fruit_round_its_stem(tmp_path, capsys):
    import json

    from ramure.app.cli import main

    assert main(["crack", "--on", "fruit", "--ring", "120", "--json", "-o", str(tmp_path / "ring.vtp")]) == 0
    facts = json.loads(capsys.readouterr().out)
    assert facts["valid"] and facts["ring_degrees"] == 120.0 and facts["euler_after"] == 1
    assert facts["volume_lost_mm3"] > 0 and 20 < facts["length_mm"] < 80  # a third of the way round
    assert main(["crack", "--on", "wood", "--ring", "90"]) == 2
    assert "for --on fruit" in capsys.readouterr().err
    assert main(["crack", "--on", "fruit", "--ring", "400"]) == 2
    err = capsys.readouterr().err
    assert "closed ring" in err and "Traceback" not in err


def test_a_chain_that_would_cut_a_tunnel_stays_shut(fruit, skin):
    """This crack's branches meet again under the fruit: unsewn, one chain would close a loop
    (chi 0, a tunnel). It stays shut; the others open, and the fruit stays a ball."""
    anchor = skin.pos[skin.used][np.argmin(np.linalg.norm(skin.pos[skin.used] - (17.38, 23.93, -42.46), axis=1))]
    pattern = random_pattern(12, seed=7, length=8.0, width=3.0, depth=8.0)
    out, facts = crack_map(fruit, pattern, anchor=anchor, direction=(0.3646, 0.2941, 0.0284))
    assert facts["chains"] > facts["chains_left_shut"] >= 1
    assert facts["valid"] and (facts["euler_after"], facts["skin_euler_after"]) == (1, 2)
    assert out.euler_characteristic() == 1 and facts["length"] > 0 and facts["opened_vertices"] > 0


def test_a_crack_that_can_only_cut_a_piece_off_is_refused():
    """Right across the stem scar, where the cells meet at the axis, this crack's only chain
    would cut pieces off the tomato (three pieces, chi 6): refused in one line, not left shut."""
    fruit = build_fruit("round_tomato", volume_levels=2)
    skin = Skin(fruit)
    scar = skin.pos[skin.used][np.argmin(np.linalg.norm(skin.pos[skin.used] - (-2.57, 0.42, 33.70), axis=1))]
    pattern = random_pattern(6, seed=0, length=8.0, width=3.0, depth=8.0)
    with pytest.raises(GMapError, match="cutting a piece off"):
        crack_map(fruit, pattern, anchor=scar, direction=(0.2987, -0.2741, -0.8906))


def test_thickness_is_the_chord_through_the_model():
    """From a sphere's skin straight in, the other side is a diameter away (2 R); depths are
    capped at half of it, so a crack never cuts through a thin board or a fruit's neck."""
    import pyvista as pv

    from ramure.gmap.organs.crackcut import thickness
    from ramure.gmap.organs.trimesh import from_polydata

    mesh = from_polydata(pv.Sphere(radius=3.0, theta_resolution=48, phi_resolution=48))
    tri = np.arange(0, len(mesh.triangles), 97)
    centres = mesh.points[mesh.triangles[tri]].mean(axis=1)
    normals = mesh.normals[tri] * np.sign(np.einsum("ij,ij->i", mesh.normals[tri], centres))[:, None]  # outward
    t = thickness(mesh, centres, normals)
    np.testing.assert_allclose(t, 6.0, rtol=0.01)
    assert np.isinf(thickness(mesh, centres[:3], -normals[:3])).all()  # pointing out: no other side


def test_the_old_path_along_the_edges_is_kept_by_name(fruit, side):
    pattern = random_pattern(8, seed=2, length=8.0, width=3.0, depth=8.0)
    from ramure.gmap.organs.edgecracks import crack_map_edges

    out, facts = crack_map_edges(fruit, pattern, anchor=side, direction=(0, 0, 1))
    assert facts["valid"] and facts["euler_after"] == 1 and out.n_volumes == fruit.n_volumes  # no cell cut
