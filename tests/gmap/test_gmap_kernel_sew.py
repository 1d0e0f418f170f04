"""CGAL's vocabulary on the kernel: sew(i, a, b) and unsew(i, a) for every i, is_sewable, is_orientable."""

import numpy as np
import pytest

from ramure.gmap import GMap3, GMapError


def cube():
    gm = GMap3()
    gm.add_prisms(4)
    return gm


def ring(twisted):
    """Eight cubes in a ring; the last gluing reflected when ``twisted`` (a solid Klein bottle)."""
    gm = GMap3()
    first = gm.add_prisms(4, 8, origins=np.arange(24.0).reshape(8, 3))
    gm.sew(3, gm.prism_face(first[:-1], 4, "E"), gm.prism_face(first[1:], 4, "O"))
    gm.sew(3, [gm.prism_face(first[-1], 4, "E")], [gm.prism_face(first[0], 4, "O", 1 if twisted else 0)])
    return gm


def cells(gm):
    c = gm.counts()
    return c["vertices"], c["edges"], c["faces"], c["volumes"]


# unsewing one dart of a cube: the orbit unsewn, the cells it splits, chi = V - E + F - C
@pytest.mark.parametrize(
    "i,orbit,expected",
    [
        (0, 4, (8, 13, 6, 1)),  # an edge opens at one end: its <a2,a3> orbit of 2 darts (a3 free) and their partners
        (1, 2, (8, 12, 6, 1)),  # two edges of a face come apart at a corner: no cell count changes
        (2, 4, (8, 13, 6, 1)),  # two faces come apart along an edge: one edge more
    ],
)
def test_unsew_then_sew_each_dimension_round_trips(i, orbit, expected):
    gm, before = cube(), cube()
    partner = int(gm.alpha[i][0])
    gm.unsew(i, 0)
    assert int(np.count_nonzero(gm.alpha[i] == np.arange(gm.n_darts))) == orbit
    assert cells(gm) == expected
    assert gm.euler_characteristic() == expected[0] - expected[1] + expected[2] - expected[3]
    assert gm.validity_problems() == [f"alpha{i} has {orbit} fixed points"]  # the kernel wants closed volumes
    assert gm.is_sewable(i, 0, partner) is True
    gm.sew(i, 0, partner)
    assert np.array_equal(gm.alpha, before.alpha)
    assert gm.is_valid() and gm.euler_characteristic() == 1


def test_sew_3_and_unsew_3_are_sew3_and_unsew3():
    gm = GMap3()
    a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
    e, o = gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O")
    assert gm.is_sewable(3, e, o) is True
    gm.sew(3, e, o)
    assert cells(gm) == (12, 20, 11, 2) and gm.euler_characteristic() == 1
    assert gm.is_sewable(3, e, o) is False  # sewn already
    gm.unsew(3, e)
    assert cells(gm) == (16, 24, 12, 2) and np.all(gm.alpha[3] == np.arange(gm.n_darts))


def test_is_sewable_is_a_bool_and_a_refused_sew_changes_nothing():
    gm = cube()
    before = gm.alpha.copy()
    assert gm.is_sewable(2, 0, int(gm.alpha[2][0])) is False  # both 2-sewn
    assert gm.is_sewable(5, 0, 1) is False and gm.is_sewable(3, 0, 10**6) is False
    with pytest.raises(GMapError, match="2-free"):
        gm.sew(2, 0, int(gm.alpha[2][0]))
    with pytest.raises(GMapError, match="0, 1, 2 or 3"):
        gm.sew(4, 0, 1)
    with pytest.raises(GMapError, match="free already"):
        gm.unsew(3, 0)
    assert np.array_equal(gm.alpha, before)


def test_sew_refuses_orbits_of_different_shapes():
    gm = GMap3()
    a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
    gm.sew(3, gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
    sewn, free = int(gm.prism_face(a, 4, "E")), int(gm.prism_face(a, 4, "O"))  # alpha3-sewn, alpha3-free
    sewn_partner, free_partner = int(gm.alpha[1][sewn]), int(gm.alpha[1][free])
    gm.unsew(1, [sewn, free])
    assert int(np.count_nonzero(gm.alpha[1] == np.arange(gm.n_darts))) == 2 * 2 + 2  # <a3> orbits of 2 and of 1
    assert gm.is_sewable(1, sewn, free_partner) is False  # an orbit of 2 darts against one of 1
    assert gm.is_sewable(1, sewn, sewn) is False  # an orbit sewn to itself
    assert gm.is_sewable(1, [sewn, free], [sewn_partner, free_partner]) is True
    gm.sew(1, [sewn, free], [sewn_partner, free_partner])
    assert gm.is_valid() and gm.euler_characteristic() == 1


def test_a_twisted_ring_is_a_solid_klein_bottle_not_a_torus():
    torus, klein = ring(False), ring(True)
    for gm in (torus, klein):  # chi cannot tell them apart ...
        assert gm.is_valid() and gm.euler_characteristic() == 0 and gm.boundary().euler_characteristic() == 0
    assert torus.is_orientable() is True  # ... orientability does
    assert klein.is_orientable() is False
    assert cube().is_orientable() is True and GMap3().is_orientable() is True


def test_attributes_are_written_and_read_under_one_name_with_one_signature():
    gm = cube()
    gm.add_volume_data("colour", np.float64, (3,), 0.5)  # name, dtype, shape, fill: the same order for darts
    gm.add_dart_data("uvw", np.float64, (3,), 0.25, rule="interpolate")
    assert gm.volume_data["colour"].shape == (1, 3) and gm.volume_data["colour"].tolist() == [[0.5, 0.5, 0.5]]
    assert gm.dart_data["uvw"].shape == (48, 3) and float(gm.dart_data["uvw"].sum()) == 48 * 3 * 0.25
    assert gm.dart_rules()["uvw"] == "interpolate"


def test_is_sewable_says_what_sew3_does_with_faces_of_different_degrees():
    gm = GMap3()
    tri = gm.add_prisms(3)[0]
    quad = gm.add_prisms(4, origins=[[-1, 0, 0]])[0]
    before = gm.alpha.copy()
    assert gm.is_sewable(3, gm.prism_face(tri, 3, "O"), gm.prism_face(quad, 4, "E")) is True  # the triangle is split
    # a triangle and a quad of one prism share an edge: splitting one splits the other, sew3 refuses
    assert gm.is_sewable(3, gm.prism_face(tri, 3, "O"), gm.prism_face(tri, 3, "C1")) is False
    with pytest.raises(GMapError, match="share an edge"):
        gm.sew(3, gm.prism_face(tri, 3, "O"), gm.prism_face(tri, 3, "C1"))
    assert gm.n_darts == 36 + 48 and np.array_equal(gm.alpha, before)  # neither the question nor the refusal changed it
