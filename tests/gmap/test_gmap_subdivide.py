"""Surface and volume subdivision: topology, sub-labels, Catmull-Clark geometry."""

import numpy as np
import pytest

from ramure.gmap import GMap3, sublabel_name
from ramure.gmap.kernel import subdivide
from ramure.gmap.organs.fruit import build_fruit


@pytest.fixture(scope="module")
def tomato():
    return build_fruit("round_tomato")


def cube(size=2.0):
    gm = GMap3()
    gm.add_prisms(4, sizes=[[size, size, size]], origins=[[-size / 2, 0, 0]])
    return gm


def test_surface_subdivision_quadruples_darts_and_keeps_volumes(tomato):
    once = subdivide.surface(tomato, 1)
    twice = subdivide.surface(tomato, 2)
    assert once.n_darts == 24_000 and twice.n_darts == 96_000
    assert twice.counts()["volumes"] == 110
    assert twice.counts()["faces_per_volume"] == 4 * once.counts()["faces_per_volume"]
    assert twice.is_valid(), twice.validity_problems()
    assert twice.euler_characteristic() == 1
    assert twice.boundary().euler_characteristic() == 2


def test_sub_labels_grow_one_letter_per_level_and_keep_the_face_label():
    gm = GMap3()
    gm.add_prisms(4)
    s = subdivide.surface(gm, 2)
    side, count = s.orbit_ids("01")
    _, first = np.unique(side, return_index=True)
    names = [sublabel_name(c) for c in s.dart_data["sublabel"][first]]
    assert count == 96 and all(len(n) == 2 for n in names)
    faces = s.dart_data["face"][first]
    for code in range(6):  # each parent face: 16 distinct sub-labels
        assert sorted(n for n, f in zip(names, faces) if f == code) == sorted(a + b for a in "abcd" for b in "abcd")


def test_quad_sub_label_layout_follows_the_thesis():
    """On a lateral face seen from outside (H up): a top-left, b bottom-left, c bottom-right, d top-right."""
    gm = GMap3()
    gm.add_prisms(4, sizes=[[2.0, 2.0, 2.0]])
    s = subdivide.surface(gm, 1)
    side, _ = s.orbit_ids("01")
    face, sub = s.dart_data["face"], s.dart_data["sublabel"]
    c1 = face == 2  # C1 faces +L (world y); H is world x
    centre = {}
    for letter in "abcd":
        code = ord(letter) - ord("a") + 1
        centre[letter] = s.points[c1 & (sub == code)].mean(axis=0)
    # seen from +y looking at the face, "right" is the tangent t = H x r = x cross y = +z
    up, right = 0, 2
    assert centre["a"][up] > centre["b"][up] and centre["a"][right] < centre["d"][right]
    assert centre["b"][right] < centre["c"][right] and centre["d"][up] > centre["c"][up]


def test_catmull_clark_moves_cube_corners_to_five_ninths():
    s = subdivide.surface(cube(2.0), 1)
    vid, pos = s.vertex_positions()
    corners = pos[np.all(np.isclose(np.abs(pos), 5 / 9), axis=1)]
    assert len(corners) == 8
    assert len(pos) == 26  # 8 corners, 12 edge points, 6 face points
    # face points stay at face centres, edge points at (v1 + v2 + f1 + f2) / 4 = (1, 0.75, 0)
    assert np.sum(np.all(np.isclose(np.sort(np.abs(pos), axis=1), [0, 0, 1]), axis=1)) == 6
    assert np.sum(np.all(np.isclose(np.sort(np.abs(pos), axis=1), [0, 0.75, 0.75]), axis=1)) == 12


def test_volume_subdivision_splits_each_cell_into_one_hexahedron_per_corner(tomato):
    once = subdivide.volume(tomato, 1)
    assert once.n_darts == 48_000
    assert once.counts()["volumes"] == 10 * 20 + 100 * 8
    assert np.all(once.volume_data["degree"] == 4)
    twice = subdivide.volume(tomato, 2)
    assert twice.n_darts == 384_000
    assert twice.is_valid(), twice.validity_problems()
    assert twice.euler_characteristic() == 1
    faces = twice.orbit_ids("01")[1]
    assert faces == 6 * twice.n_volumes  # all hexahedra
    # labels and tissues follow the parent volume
    assert set(twice.volume_data["label"].tolist()) == {"A", "B"}
    assert (twice.volume_data["label"] == "A").sum() == 200 * 8


def test_volume_subdivision_keeps_inner_points_and_smooths_the_surface():
    v = subdivide.volume(cube(2.0), 1)
    vid, pos = v.vertex_positions()
    assert len(pos) == 27
    assert np.sum(np.all(np.isclose(pos, 0.0), axis=1)) == 1  # the cell centre
    s = subdivide.surface(cube(2.0), 1)
    _, spos = s.vertex_positions()
    boundary = np.any(~np.isclose(pos, 0.0), axis=1)
    # the boundary points are the surface subdivision's points
    a = np.round(pos[boundary], 9)
    b = np.round(spos, 9)
    assert sorted(map(tuple, a)) == sorted(map(tuple, b))
    inner = v.dart_data["face"] == -1
    assert inner.sum() == 12 * 2 * 8  # 12 inner quads x 2 sides x 8 darts
    assert v.is_valid()


def test_radial_scalar_is_interpolated_not_smoothed(tomato):
    twice = subdivide.volume(tomato, 2)
    values = np.unique(np.round(twice.dart_data["radial"], 9))
    assert values.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_selected_volume_surface_subdivision_keeps_neighbours_conforming():
    gm = GMap3()
    a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
    gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
    gm.embed()
    s = subdivide.surface(gm, 1, volumes=[1])
    assert s.is_valid(), s.validity_problems()
    side, _ = s.orbit_ids("01")
    per_volume = np.bincount(s.dart_volume[np.unique(side, return_index=True)[1]])
    assert per_volume.tolist() == [9, 24]  # volume 0: 5 faces + its shared face split in 4
    vid, pos = s.vertex_positions()
    # volume 0's far face (x = 0) did not move; the shared face's corners moved with volume 1
    assert np.allclose(np.sort(pos[:, 0])[:4], 0.0)
    assert s.euler_characteristic() == 1


def test_negative_levels_are_refused(tomato):
    from ramure.errors import ValueRefused

    with pytest.raises(ValueRefused):
        subdivide.surface(tomato, -1)
    with pytest.raises(ValueRefused):
        subdivide.volume(tomato, -2)
