"""Per-dart attributes and their propagation rules; default corners and weighted embedding."""

import numpy as np
import pytest

from ramure.gmap import GMap3, GMapError
from ramure.gmap.kernel import subdivide
from ramure.gmap.kernel.topology import assert_solid


def cube_pair():
    gm = GMap3()
    gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
    gm.sew3(gm.face_of(0, "E"), gm.face_of(1, "O"))
    return gm


def with_attributes(gm):
    gm.add_dart_data("uvw", float, (3,), rule="interpolate")
    gm.add_dart_data("crack", np.int8, rule="copy")
    gm.add_dart_data("seen", np.int8, fill=0, rule="reset")
    gm.dart_data["uvw"][:] = gm.dart_data["corner"]
    darts, _ = gm.face_darts([0], "C1")
    gm.dart_data["crack"][darts] = 1
    gm.dart_data["seen"][:] = 7
    return gm


def test_rules_are_checked():
    gm = GMap3()
    gm.add_prisms(4)
    with pytest.raises(GMapError):
        gm.add_dart_data("x", float, rule="smooth")
    with pytest.raises(GMapError):
        gm.add_dart_data("x", np.int8, rule="interpolate")
    gm.add_dart_data("x", float)
    with pytest.raises(GMapError):
        gm.add_dart_data("x", float)
    assert gm.dart_rules()["x"] == "copy"


def test_edge_face_volume_splits_and_sew_carry_the_attributes():
    gm = with_attributes(cube_pair())
    n0 = gm.n_darts
    gm.split_edge([gm.face_of(0, "C1")], 0.3)
    gm.split_prism(1, 0.25)
    walk, _ = gm.face_walk([gm.face_of(0, "O")])
    gm.split_face(int(walk[0, 0]), int(walk[0, 4]))
    assert_solid(gm)
    data = gm.dart_data
    # interpolate: a linear function of the default corners stays equal to them
    assert np.abs(data["uvw"] - data["corner"]).max() < 1e-12
    # copy: the cracked face C1 of volume 0 stays cracked on every dart of it, none elsewhere on C1 of 1
    c1, _ = gm.face_darts([0, 1], "C1")
    owner = gm.dart_volume[c1]
    assert np.all(data["crack"][c1[owner == 0]] == 1) and np.all(data["crack"][c1[owner != 0]] == 0)
    # reset: old darts keep 7, every new dart 0
    assert np.all(data["seen"][:n0] == 7) and np.all(data["seen"][n0:] == 0)
    assert gm.n_darts > n0


def test_subdivisions_carry_the_attributes():
    gm = with_attributes(cube_pair())
    gm.embed()
    s = subdivide.surface(gm, 1)
    assert s.dart_rules()["uvw"] == "interpolate"
    u = s.dart_data["uvw"][:, 0]
    face = s.dart_data["face"]
    assert np.allclose(u[(face == 0) & (s.dart_volume == 0)], 0.0)  # O face of the first cube
    assert np.allclose(u[(face == 1) & (s.dart_volume == 1)], 2.0)  # E face of the second
    assert set(np.round(u, 9).tolist()) == {0.0, 0.5, 1.0, 1.5, 2.0}
    c1 = (face == 2) & (s.dart_volume == 0)
    assert np.all(s.dart_data["crack"][c1] == 1) and s.dart_data["crack"].sum() == c1.sum()
    assert (s.dart_data["seen"] == 7).sum() == gm.n_darts  # one continuing dart each
    v = subdivide.volume(gm, 1)
    uv = v.dart_data["uvw"][:, 0]
    assert set(np.round(uv, 9).tolist()) == {0.0, 0.5, 1.0, 1.5, 2.0}
    assert v.n_darts == 8 * gm.n_darts and (v.dart_data["seen"] == 7).sum() == gm.n_darts


def test_corners_are_kept_so_embedding_now_or_later_agrees():
    every = GMap3()
    once = GMap3()
    for gm, embed_each in ((every, True), (once, False)):
        gm.add_prisms(4, 3, origins=[[0, 0, 0], [1, 0, 0], [2, 0, 0]], sizes=[[1, 1, 1], [1, 2, 2], [1, 3, 1]])
        for a, b in ((0, 1), (1, 2)):
            gm.sew3(gm.face_of(a, "E"), gm.face_of(b, "O"))
            if embed_each:
                gm.embed()
        gm.split_prism(1, 0.5)
        if embed_each:
            gm.embed()
        gm.embed()
    assert np.abs(every.points - once.points).max() < 1e-12
    assert np.abs(once.dart_data["corner"] - GMap3.copy(once).dart_data["corner"]).max() == 0


def test_exclusive_volumes_alone_place_their_vertices():
    gm = GMap3()
    gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]], sizes=[[1, 1, 1], [1, 3, 3]])
    gm.sew3(gm.face_of(0, "E"), gm.face_of(1, "O"))
    shared = gm.face_of(0, "E")
    pos = gm.embed()
    vid, _ = gm.cells(0)
    assert np.allclose(pos[vid[shared]], [1.0, 1.0, -1.0])  # plain mean
    gm.volume_data["exclusive"][1] = True  # the branch base
    pos = gm.embed()
    assert np.allclose(pos[vid[shared]], [1.0, 1.5, -1.5])  # the big box alone
    gm.volume_data["exclusive"][1] = False
    gm.volume_data["weight"][:] = [3.0, 1.0]
    pos = gm.embed()
    assert np.allclose(pos[vid[shared]], [1.0, 0.75, -0.75])
