"""Cracks from a skeleton and a profile: patterns, growth in time, a watertight carve."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest
import pyvista as pv

from ramure.gmap.organs.cracks import (
    CrackPattern,
    add_noise,
    carve,
    pattern_from_skeleton,
    project,
    random_pattern,
    smooth,
    symmetric,
)
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.trimesh import from_polydata


@pytest.fixture(scope="module")
def stone():
    return pv.Icosphere(radius=2.0, nsub=4)


@pytest.fixture(scope="module")
def pattern():
    return random_pattern(20, seed=4, length=0.25, width=0.03, depth=0.06)


def _manifold(poly):
    faces = np.asarray(poly.faces).reshape(-1, 4)[:, 1:]
    return manifold3d.Manifold(
        manifold3d.Mesh(vert_properties=np.asarray(poly.points, np.float32), tri_verts=faces.astype(np.uint32))
    )


def test_the_carved_object_is_watertight_and_loses_exactly_the_crack(stone, pattern):
    crack = carve(stone, pattern, anchor=(0, 0, 2.0), direction=(1, 0, 0))
    assert crack.facts()["watertight"] and crack.result.n_cells > stone.n_cells
    solid, volume = _manifold(stone), _manifold(crack.volume)
    inside = (solid ^ volume).volume()
    assert crack.volume_removed == pytest.approx(inside, rel=1e-6, abs=1e-12) and inside > 0
    assert _manifold(crack.result).volume() == pytest.approx(solid.volume() - inside, rel=1e-6)
    assert crack.facts()["nodes"] == 20


def test_the_skeleton_lies_on_the_surface(stone, pattern):
    points, arcs = project(from_polydata(stone), pattern, (0, 0, 2.0), (0, 1, 0))
    assert np.abs(np.linalg.norm(points, axis=1) - 2.0).max() < 0.01  # chord sag of the icosphere
    for _i, j, samples in arcs:  # each arc is as long as its delta, measured along the surface
        walked = sum(np.linalg.norm(b[0] - a[0]) for a, b in zip(samples, samples[1:]))
        assert walked == pytest.approx(pattern.length[j], rel=0.05)


def test_crack_length_grows_with_time_and_ends_as_the_static_crack(stone, pattern):
    pattern.timing(speed=2.0, tau=0.3)
    end = float((pattern.start + pattern.duration).max())
    lengths = [pattern.at(t).total_length() for t in np.linspace(0, end, 25)]
    assert all(b >= a - 1e-12 for a, b in zip(lengths, lengths[1:]))
    assert lengths[0] == 0.0 and lengths[-1] == pytest.approx(pattern.total_length())
    final = pattern.at(end + 1e-9)
    for name in ("parent", "length", "angle", "width", "depth"):
        assert np.allclose(getattr(final, name), getattr(pattern, name))
    static = carve(stone, pattern, (0, 0, 2.0), (1, 0, 0))
    grown = carve(stone, pattern, (0, 0, 2.0), (1, 0, 0), t0=end + 1.0)
    assert grown.volume_removed == pytest.approx(static.volume_removed, rel=1e-9)
    half = carve(stone, pattern, (0, 0, 2.0), (1, 0, 0), t0=end / 2)
    assert 0 < half.length < static.length


def test_a_growing_node_is_scaled_and_an_arc_in_progress_is_cut():
    p = CrackPattern(np.array([-1, 0]), np.array([0.0, 1.0]), np.zeros(2), np.full(2, 0.1), np.full(2, 0.2))
    p.timing(speed=1.0, tau=0.5)  # node 1 starts at t = 1 and grows until 1.5
    assert p.at(0.5).length[1] == pytest.approx(0.5) and p.at(0.5).width[1] == 0.0
    assert p.at(1.25).width[1] == pytest.approx(0.05) and p.at(1.25).length[1] == pytest.approx(1.0)


def test_operators_keep_a_tree(pattern):
    noisy = add_noise(pattern, amount=15, inserts=2, seed=1)
    assert len(noisy) == 1 + 3 * (len(pattern) - 1)
    assert noisy.total_length() == pytest.approx(pattern.total_length())
    calm = smooth(pattern, max_change=5)
    inner = calm.parent > 0
    assert (np.abs(calm.angle[inner] - calm.angle[calm.parent[inner]]) <= 5 + 1e-9).all()
    star = symmetric(pattern, 4)
    assert len(star) == 1 + 4 * (len(pattern) - 1) and (star.parent[1:] < np.arange(1, len(star))).all()


def test_same_seed_same_pattern_and_an_l_system_pattern():
    a, b = random_pattern(30, seed=2), random_pattern(30, seed=2)
    assert np.array_equal(a.parent, b.parent) and np.array_equal(a.angle, b.angle)
    import ramure

    sk = ramure.derive("honda_sympodial", n=4).skeleton()
    tree = pattern_from_skeleton(sk, scale=0.2)
    segment_lengths = np.linalg.norm(sk.end - sk.start, axis=1)
    assert len(tree) == len(sk) + 1 and tree.total_length() == pytest.approx(0.2 * segment_lengths.sum())


def test_cycles_and_wrong_profile_counts_are_refused():
    with pytest.raises(GMapError, match="cycle: 0 -> 1 -> 2 -> 0"):
        CrackPattern.from_arcs([(0, 1), (1, 2), (2, 0)], [1, 1, 1], [0, 0, 0], [[(1, 1)] * 2] * 3)
    with pytest.raises(GMapError, match="node 1 has 1 profile"):
        CrackPattern.from_arcs([(0, 1), (1, 2)], [1, 1], [0, 0], [[(1, 1)] * 2, [(1, 1)], [(1, 1)] * 2])
    ok = CrackPattern.from_arcs(
        [(0, 1), (1, 2), (1, 3)], [1, 1, 1], [0, 20, -20], [[(1, 1)] * 2, [(1, 1)] * 3, [(1, 1)] * 2, [(1, 1)] * 2]
    )
    assert ok.parent.tolist() == [-1, 0, 1, 1]


def test_a_node_listed_before_its_parent_is_refused():
    # the walks fill node positions in list order; a child before its parent had no position
    with pytest.raises(GMapError, match="after its parent"):
        CrackPattern(np.array([-1, 2, 0]), np.array([0.0, 1.0, 1.0]), np.zeros(3), np.ones(3), np.ones(3))
    with pytest.raises(GMapError, match="after its parent"):
        CrackPattern(np.array([0, -1]), np.array([1.0, 0.0]), np.zeros(2), np.ones(2), np.ones(2))
    ok = CrackPattern(np.array([-1, 0, 0]), np.array([0.0, 1.0, 2.0]), np.zeros(3), np.ones(3), np.ones(3))
    assert ok.start.tolist() == [0.0, 1.0, 2.0] and ok.duration.tolist() == [0.5] * 3


def test_bad_placement_is_refused(stone, pattern):
    with pytest.raises(GMapError, match="not on the surface"):
        carve(stone, pattern, anchor=(0, 0, 9.0), direction=(1, 0, 0))
    with pytest.raises(GMapError, match="along the surface normal"):
        carve(stone, pattern, anchor=(0, 0, 2.0), direction=(0, 0, 1))
    with pytest.raises(GMapError, match="close the model first"):
        carve(pv.Plane(), pattern, anchor=(0, 0, 0), direction=(1, 0, 0))


def test_command_line_carves_and_reports(tmp_path):
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "crack", "--nodes", "12", "--json", "-o", str(tmp_path / "c.stl")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["nodes"] == 12 and facts["watertight"] and facts["triangles_result"] > facts["triangles_object"]
    assert pv.read(tmp_path / "c.stl").n_cells == facts["triangles_result"]
    bad = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "crack", "--anchor", "0,0,50"], capture_output=True, text=True, cwd=tmp_path
    )
    assert bad.returncode == 2 and "not on the surface" in bad.stderr and "Traceback" not in bad.stderr
