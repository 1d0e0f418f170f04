"""Faces by label, identify (glue by the shared edge), and refused operations that change nothing."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ramure.gmap import GMap3, GMapError
from ramure.gmap.kernel.identify import boundary_neighbour
from ramure.gmap.kernel.topology import assert_solid


def crown(n=6):
    """A prism of order n with a cube sewn on each side face (cube j on C(j+1))."""
    gm = GMap3()
    gm.add_prisms(n, sizes=[[1.0, 2.0, 2.0]])
    gm.add_prisms(4, n)
    cubes = np.arange(1, n + 1)
    gm.sew3(gm.face_of(np.zeros(n, int), [f"C{j + 1}" for j in range(n)]), gm.face_of(cubes, "O"))
    return gm, cubes


def arrays(gm):
    out = {"alpha": gm.alpha.copy()}
    out.update({f"d.{k}": v.copy() for k, v in gm.dart_data.items()})
    out.update({f"v.{k}": v.copy() for k, v in gm.volume_data.items()})
    return out


def assert_same(before, gm):
    after = arrays(gm)
    assert before.keys() == after.keys()
    for k in before:
        assert np.array_equal(before[k], after[k]), k


def test_face_of_equals_the_template_offsets_on_fresh_prisms():
    gm = GMap3()
    first = gm.add_prisms(5, 3)
    for label in ["O", "E", "C1", "C3", "C5"]:
        assert np.array_equal(gm.face_of([0, 1, 2], label), gm.prism_face(first, 5, label))
    darts, which = gm.face_darts([0, 2], "C2")
    assert len(darts) == 16 and np.bincount(which).tolist() == [8, 8]
    assert set(gm.dart_data["face"][darts].tolist()) == {3}
    with pytest.raises(GMapError, match="volume 0 .*has no face C6"):
        gm.face_of([0, 1], "C6")
    with pytest.raises(GMapError):
        gm.face_of([0], "Q")


def test_face_of_survives_a_knot_that_turns_a_quad_into_a_7_gon():
    gm = GMap3()
    gm.add_prisms(4, 2, origins=[[0, 0, 0], [0, 1, 0]])
    gm.add_prisms(7, origins=[[0, -1, 0]])  # the knot
    gm.sew3([gm.face_of(0, "C2")], [gm.face_of(1, "C4")])
    anchor = gm.face_of(0, "C4")
    gm.sew3([anchor], [gm.face_of(2, "O")])
    _, length = gm.face_walk([gm.face_of(0, "C4")])
    assert length[0] == 14  # a 7-gon now
    assert gm.face_of(0, "C4") == anchor  # same anchor dart
    assert {int(gm.face_of(0, lab)) for lab in ["O", "E", "C1", "C2", "C3"]} == {
        int(gm.prism_face(0, 4, lab)) for lab in ["O", "E", "C1", "C2", "C3"]
    }
    assert_solid(gm)


def test_boundary_neighbour_finds_the_ring_join_faces():
    gm, cubes = crown(6)
    nb = boundary_neighbour(gm, gm.face_of(cubes, "C2"))
    assert gm.dart_volume[nb].tolist() == np.roll(cubes, -1).tolist()
    assert set(gm.dart_data["face"][nb].tolist()) == {5}  # C4


@pytest.mark.parametrize("n", [3, 6, 16])
def test_identify_closes_a_crown_of_cubes_into_one_solid(n):
    gm, cubes = crown(n)
    v0, e0 = gm.counts()["vertices"], gm.counts()["edges"]
    gm.identify(gm.face_of(cubes, "C2"), gm.face_of(np.roll(cubes, -1), "C4"))
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    c = gm.counts()
    # each join merges 2 outer vertex pairs and 3 edge pairs (2 radial, 1 outer); the shared edge stays
    assert c["vertices"] == v0 - 2 * n and c["edges"] == e0 - 3 * n
    assert c["faces"] == (n + 2) + 5 * n - n
    # alpha3 pairs the shared edge's darts, never by coordinates
    a = gm.face_of(cubes, "C2")
    assert np.all(gm.alpha[3][a] != a)


def test_identify_splits_the_run_that_has_fewer_edges():
    gm, cubes = crown(6)
    far = gm.face_of(1, "C2")
    walk, _ = gm.face_walk([far])
    gm.split_edge([int(walk[0, 4])], 0.25)  # the edge opposite the shared one, in C2 of cube 1
    _, before = gm.face_walk([gm.face_of(2, "C4")])
    assert before[0] == 8
    gm.identify(gm.face_of(cubes, "C2"), gm.face_of(np.roll(cubes, -1), "C4"))
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    _, after = gm.face_walk([gm.face_of(2, "C4")])
    assert after[0] == 10  # split too, at the partner's position
    split = gm.dart_data["fcorner"] == -1
    assert split.sum() > 0


def test_identify_refusals_name_both_faces_and_change_nothing():
    gm, cubes = crown(6)
    before = arrays(gm)
    with pytest.raises(GMapError, match="face C2 of volume 1 .* and face C4 of volume 4 .* share no edge"):
        gm.identify([gm.face_of(1, "C2")], [gm.face_of(4, "C4")])
    assert_same(before, gm)
    with pytest.raises(GMapError, match="not alpha3-free"):
        gm.identify([gm.face_of(1, "O")], [gm.face_of(2, "C4")])
    assert_same(before, gm)
    with pytest.raises(GMapError, match="to itself or use a face twice"):
        gm.identify([gm.face_of(1, "C2")], [gm.face_of(1, "C2")])
    assert_same(before, gm)
    with pytest.raises(GMapError, match="to itself or use a face twice"):  # one face in two pairs
        gm.identify([gm.face_of(1, "C2"), gm.face_of(3, "C2")], [gm.face_of(2, "C4"), gm.face_of(1, "C2")])
    assert_same(before, gm)


def test_sew3_on_a_prisms_own_faces_of_other_degree_is_refused_cleanly():
    gm = GMap3()
    gm.add_prisms(3)
    before = arrays(gm)
    with pytest.raises(GMapError):
        gm.sew3(gm.face_of(0, "O"), gm.face_of(0, "C1"))
    assert_same(before, gm)
    assert gm.is_valid()


def _random_operation(gm, kind, x, y, t):
    n = gm.n_darts
    if kind == 0:
        gm.sew3([x % n], [y % n])
    elif kind == 1:
        gm.split_prism(x % gm.n_volumes, t, face=y % n)
    elif kind == 2:
        gm.identify([x % n], [y % n])
    elif kind == 3:
        gm.split_face(x % n, y % n)
    elif kind == 4:
        gm.split_volume([x % n, y % n])
    elif kind == 5:
        gm.split_prisms(np.unique([x % gm.n_volumes, y % gm.n_volumes]), t)
    else:
        from ramure.gmap.kernel.embedding import grow

        grow(gm, [x % n], 3 + y % 4, height=t)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    ops=st.lists(
        st.tuples(st.integers(0, 6), st.integers(0, 10_000), st.integers(0, 10_000), st.floats(-0.5, 1.5)), min_size=1, max_size=6
    )
)
def test_a_refused_operation_leaves_the_map_exactly_as_it_was(ops):
    gm, _ = crown(4)
    for kind, x, y, t in ops:
        before = arrays(gm)
        try:
            _random_operation(gm, kind, x, y, t)
        except GMapError:
            assert_same(before, gm)
        assert gm.is_valid(), gm.validity_problems()


def test_batch_split_of_joined_ring_cubes_splits_shared_edges_once():
    from ramure.gmap.kernel.embedding import grow
    from ramure.gmap.kernel.measure import total_volume

    gm = GMap3()
    gm.add_prisms(6, sizes=[[2.0, 2.0, 2.0]])
    cubes = grow(gm, gm.face_of(np.zeros(6, int), [f"C{j + 1}" for j in range(6)]), 4, height=0.5)
    gm.identify(gm.face_of(cubes, "C2"), gm.face_of(np.roll(cubes, -1), "C4"))
    gm.embed()
    v0, vol0 = gm.counts()["vertices"], total_volume(gm)
    new = gm.split_prisms(cubes, 0.25)
    assert_solid(gm)
    # 6 cubes x 4 lateral edges, each shared by two neighbours: 12 new vertices, not 24
    assert gm.counts()["vertices"] == v0 + 12
    assert len(new) == 6 and gm.n_volumes == 13
    assert set(gm.volume_data["parent"][new].tolist()) == {0}  # attributes copied
    gm.embed()
    assert abs(total_volume(gm) - vol0) < 1e-9
    before = arrays(gm)
    with pytest.raises(GMapError):
        gm.split_prisms([1, 1], 0.5)
    with pytest.raises(GMapError):
        gm.split_prisms([1], 1.5)
    assert_same(before, gm)
