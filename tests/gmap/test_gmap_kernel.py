"""The 3-G-map kernel: prisms, validity, orbits and cells, operations, embedding, boundary."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ramure.gmap import GMap3, GMapError
from ramure.errors import RamureError, ValueRefused
from ramure.gmap.kernel.topology import assert_solid


def cube_pair(sizes=((1.0, 1.0, 1.0), (1.0, 1.0, 1.0))):
    """Two boxes stacked along x, sewn E of the first to O of the second."""
    gm = GMap3()
    a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]], sizes=sizes)
    gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "O"))
    return gm, a, b


def counts(gm):
    c = gm.counts()
    return c["vertices"], c["edges"], c["faces"], c["volumes"]


@pytest.mark.parametrize("n", [3, 4, 5, 10, 17])
def test_prism_of_order_n_has_12n_darts_and_the_cells_of_a_prism(n):
    gm = GMap3()
    gm.add_prisms(n)
    assert gm.n_darts == 12 * n
    assert counts(gm) == (2 * n, 3 * n, n + 2, 1)
    assert gm.counts()["faces_per_volume"] == n + 2
    assert gm.euler_characteristic() == 1
    assert gm.boundary().euler_characteristic() == 2
    assert gm.is_valid(), gm.validity_problems()


def test_bulk_prisms_equal_prisms_added_one_by_one():
    bulk = GMap3()
    bulk.add_prisms(6, 3, origins=np.arange(9.0).reshape(3, 3))
    single = GMap3()
    for i in range(3):
        single.add_prisms(6, origins=[np.arange(9.0).reshape(3, 3)[i]])
    assert np.array_equal(bulk.alpha, single.alpha)
    assert np.allclose(bulk.points, single.points)
    assert np.array_equal(bulk.dart_volume, single.dart_volume)


@pytest.mark.parametrize("n", [3, 4, 7, 16])
def test_prisms_without_geometry_get_the_unit_corners_bit_for_bit(n):
    """The shortcut (one unit prism's corners for all) equals the batch computation with explicit defaults."""
    plain, explicit = GMap3(), GMap3()
    plain.add_prisms(n, 5)
    explicit.add_prisms(n, 5, origins=np.zeros((5, 3)), frames=np.repeat(np.eye(3)[None], 5, 0), sizes=np.ones((5, 3)))
    for name in ("corner", "point"):
        a, b = plain.dart_data[name], explicit.dart_data[name]
        assert np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))
    assert np.ptp(plain.points[:, 0]) == 1.0  # a unit height, not a degenerate prism


def test_prism_face_labels_and_default_corners():
    gm = GMap3()
    gm.add_prisms(4, sizes=[[2.0, 4.0, 6.0]])
    face = gm.dart_data["face"]
    assert np.bincount(face).tolist() == [8, 8, 8, 8, 8, 8]  # O, E, C1..C4
    pts = gm.points
    assert np.allclose(pts.min(axis=0), [0, -2, -3]) and np.allclose(pts.max(axis=0), [2, 2, 3])
    # C1 faces +L (the x axis of the local L direction is world y here)
    c1 = pts[face == 2]
    assert np.allclose(c1[:, 1], 2.0)
    # the O face lies at H = 0, the E face at H = 2
    assert np.allclose(pts[face == 0][:, 0], 0.0) and np.allclose(pts[face == 1][:, 0], 2.0)


def test_prism_order_below_three_is_refused():
    with pytest.raises(ValueRefused):
        GMap3().add_prisms(2)


def test_validity_detects_each_broken_condition():
    gm = GMap3()
    gm.add_prisms(4)
    assert gm.validity_problems() == []
    broken = gm.copy()
    broken.alpha[0][0] = 0  # fixed point, no longer an involution
    problems = " ".join(broken.validity_problems())
    assert "alpha0 is not an involution" in problems and "alpha0 has" in problems
    broken = gm.copy()
    a2 = broken.alpha[2]
    x, y = 0, int(a2[0])
    u, v = 2, int(a2[2])
    a2[x], a2[u] = u, x  # re-pair alpha2: breaks alpha0 alpha2
    a2[y], a2[v] = v, y
    assert any("alpha0alpha2" in p for p in broken.validity_problems())
    broken = gm.copy()
    broken.alpha[3][0], broken.alpha[3][1] = 1, 0  # alpha3 against alpha0 inside one edge
    problems = broken.validity_problems()
    assert any("alpha0alpha3" in p for p in problems) or any("alpha1alpha3" in p for p in problems)
    with pytest.raises(GMapError):
        broken.check()
    assert issubclass(GMapError, RamureError)


def test_orbits_and_cells_of_a_cube():
    gm = GMap3()
    gm.add_prisms(4)
    assert len(gm.orbit(0, "0")) == 2
    assert len(gm.orbit(0, "01")) == 8  # a quad face of one volume
    assert len(gm.orbit(0, "12")) == 6  # 3 faces meet at a corner
    assert len(gm.orbit(0, "02")) == 4  # an edge seen by 2 faces
    ids, count = gm.orbit_ids("01")
    assert count == 6 and np.bincount(ids).tolist() == [8] * 6
    vid, nv = gm.cells(0)
    assert nv == 8 and np.all(np.bincount(vid) == 6)
    with pytest.raises(GMapError):
        gm.cells(4)
    with pytest.raises(GMapError):
        gm.orbit_ids("05")


def test_sewing_two_cubes_shares_a_face():
    gm, a, b = cube_pair()
    assert counts(gm) == (12, 20, 11, 2)
    assert gm.counts()["faces_per_volume"] == 12
    assert gm.euler_characteristic() == 1
    assert gm.boundary().euler_characteristic() == 2
    assert gm.is_valid()
    alpha = gm.alpha
    sewn = np.flatnonzero(alpha[3] != np.arange(gm.n_darts))
    assert len(sewn) == 16
    assert np.array_equal(alpha[0][alpha[3][sewn]], alpha[3][alpha[0][sewn]])
    with pytest.raises(GMapError):  # already sewn
        gm.sew3(gm.prism_face(a, 4, "E"), gm.prism_face(b, 4, "E"))


def test_unsew_restores_two_free_cubes():
    gm, a, b = cube_pair()
    gm.unsew3([gm.prism_face(a, 4, "E")])
    assert counts(gm) == (16, 24, 12, 2)
    assert np.all(gm.alpha[3] == np.arange(gm.n_darts))
    assert gm.is_valid()


def test_sewing_faces_of_different_degrees_splits_the_smaller_face():
    gm = GMap3()
    tri = gm.add_prisms(3)[0]
    quad = gm.add_prisms(4, origins=[[-1, 0, 0]])[0]
    gm.sew3(gm.prism_face(tri, 3, "O"), gm.prism_face(quad, 4, "E"))
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    walk, length = gm.face_walk([gm.prism_face(tri, 3, "O")])
    assert length[0] == 8  # the triangle became a 4-gon
    assert gm.counts()["volumes"] == 2
    # the triangle prism's split edge is split in its lateral face too (a 5-gon now)
    _, lengths = gm.face_walk([gm.prism_face(tri, 3, "C1")])
    assert lengths[0] == 10


def test_split_edge_puts_the_vertex_on_the_segment_in_every_volume_around():
    gm, a, b = cube_pair()
    d = gm.prism_face(a, 4, "E", 0)  # an edge of the shared face
    before = gm.points[[d, gm.alpha[0][d]]].copy()
    (new,) = gm.split_edge([d], t=0.25)
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    assert counts(gm) == (13, 21, 11, 2)
    assert np.allclose(gm.points[new], before[0] + 0.25 * (before[1] - before[0]))
    vid, _ = gm.cells(0)
    at_new = np.flatnonzero(vid == vid[new])
    assert set(gm.dart_volume[at_new].tolist()) == {0, 1}
    with pytest.raises(GMapError):
        gm.split_edge([d, gm.alpha[0][d]])  # two darts of one edge


def test_split_face_splits_both_sides_of_a_sewn_face():
    gm, a, b = cube_pair()
    d1 = gm.prism_face(a, 4, "E", 0)
    walk, _ = gm.face_walk([d1])
    gm.split_face(d1, int(walk[0, 4]))  # the opposite corner
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    assert counts(gm) == (12, 21, 12, 2)
    assert gm.counts()["faces_per_volume"] == 14
    with pytest.raises(GMapError):
        gm.split_face(0, 1)  # same edge: adjacent corners


@pytest.mark.parametrize("n", [3, 4, 7])
def test_split_prism_makes_two_stacked_prisms(n):
    gm = GMap3()
    gm.add_prisms(n, sizes=[[2.0, 1.0, 1.0]])
    upper = gm.split_prism(0, t=0.25)
    assert gm.is_valid(), gm.validity_problems()
    assert_solid(gm)
    assert counts(gm) == (3 * n, 5 * n, 2 * n + 3, 2)
    assert upper == 1
    cent = gm.volume_centroids()
    assert np.allclose(cent[:, 0], [0.25, 1.25])  # cut at a quarter of the height
    face = gm.dart_data["face"]
    lower_faces = set(face[gm.dart_volume == 0].tolist())
    assert {0, 1} <= lower_faces  # O kept, new E


def test_split_volume_refuses_an_open_path():
    gm = GMap3()
    gm.add_prisms(4)
    with pytest.raises(GMapError):
        gm.split_volume([gm.prism_face(0, 4, "O", 0)])


def test_remove_volume_frees_the_faces_it_was_sewn_to():
    gm, a, b = cube_pair()
    gm.remove_volumes([1])
    assert_solid(gm)
    assert gm.n_darts == 48 and gm.n_volumes == 1
    assert np.all(gm.alpha[3] == np.arange(48))
    assert gm.is_valid()
    gm2, _, _ = cube_pair()
    gm2.remove_volumes([0])
    assert gm2.n_volumes == 1 and gm2.is_valid()
    assert np.all(gm2.dart_volume == 0)


def test_a_ring_of_sewn_cubes_is_a_solid_torus():
    gm = GMap3()
    first = gm.add_prisms(4, 8, origins=np.arange(24.0).reshape(8, 3))
    gm.sew3(gm.prism_face(first, 4, "E"), gm.prism_face(np.roll(first, -1), 4, "O"))
    assert gm.is_valid()
    assert gm.euler_characteristic() == 0
    assert gm.boundary().euler_characteristic() == 0


def test_embedding_averages_the_corners_of_incident_volumes():
    gm, a, b = cube_pair(sizes=((1.0, 1.0, 1.0), (1.0, 3.0, 3.0)))
    pos = gm.embed()
    vid, _ = gm.cells(0)
    shared = vid[gm.prism_face(a, 4, "E", 0)]
    # corner (1, 0.5, -0.5) of the small box and (1, 1.5, -1.5) of the big one
    assert np.allclose(pos[shared], [1.0, 1.0, -1.0])
    assert np.allclose(gm.embed(), pos)  # idempotent
    assert np.allclose(gm.points, pos[vid])


def test_merge_offsets_darts_and_volumes():
    gm, _, _ = cube_pair()
    merged = GMap3.merge([gm, gm])
    assert merged.n_darts == 2 * gm.n_darts and merged.n_volumes == 4
    assert counts(merged) == (24, 40, 22, 4)
    assert merged.is_valid()
    assert_solid(merged, solids=2)


def test_transform_moves_points_and_frames():
    gm = GMap3()
    gm.add_prisms(4)
    rot = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    gm.transform(rotation=rot, scale=2.0, offset=[1, 2, 3])
    assert np.allclose(gm.volume_data["frame"][0], rot)
    assert np.allclose(gm.volume_data["origin"][0], [1, 2, 3])
    assert np.allclose(gm.points.max(axis=0) - gm.points.min(axis=0), [2, 2, 2])
    assert np.allclose([gm.points[:, 1].min(), gm.points[:, 1].max()], [2, 4])  # H (was x) is now y


@settings(max_examples=25, deadline=None)
@given(n=st.integers(3, 9), picks=st.lists(st.integers(0, 10_000), min_size=1, max_size=6))
def test_random_edge_splits_keep_the_map_valid(n, picks):
    gm = GMap3()
    first = gm.add_prisms(n, 2, origins=[[0, 0, 0], [1, 0, 0]])
    gm.sew3(gm.prism_face(first[0], n, "E"), gm.prism_face(first[1], n, "O"))
    v, e, f, c = counts(gm)
    for k, pick in enumerate(picks):
        gm.split_edge([pick % gm.n_darts], t=0.3)
        assert counts(gm) == (v + k + 1, e + k + 1, f, c)
    assert gm.is_valid(), gm.validity_problems()
    assert gm.euler_characteristic() == 1


def _same_partition(a, b):
    """Two orbit labellings describe the same partition (labels may differ)."""
    pairs = np.unique(np.stack([a, b]), axis=1)
    return len(np.unique(pairs[0])) == pairs.shape[1] == len(np.unique(pairs[1]))


def _fresh_orbits(gm, key):
    clean = GMap3.from_arrays(gm.alpha, dict(gm.dart_data), dict(gm.volume_data))
    return clean.orbit_ids(key)


def test_orbits_after_growth_are_updated_and_equal_a_fresh_labelling():
    """Labels follow growth (add + sew) incrementally; a split falls back to a full pass; same cells."""
    gm = GMap3()
    gm.add_prisms(4)
    keys = ("123", "023", "013", "012", "0123", "12", "01")
    for key in keys:
        gm.orbit_ids(key)
    top = 0
    for step in range(6):  # a column of cubes, then a ring of cubes on its sides
        (new,) = gm.add_prisms(4, 1, origins=[[step + 1.0, 0, 0]])
        gm.sew3(gm.prism_face(top, 4, "E"), gm.prism_face(new, 4, "O"))
        top = int(new)
        for key in keys:
            ids, count = gm.orbit_ids(key)
            fresh_ids, fresh_count = _fresh_orbits(gm, key)
            assert count == fresh_count and _same_partition(ids, fresh_ids), (step, key)
    assert "_orbit_memo" in gm.__dict__
    gm.split_prism(0, 0.5)  # unsews and re-links: not growth, full pass
    for key in keys:
        ids, count = gm.orbit_ids(key)
        fresh_ids, fresh_count = _fresh_orbits(gm, key)
        assert count == fresh_count and _same_partition(ids, fresh_ids)
    assert_solid(gm)


def test_validity_after_growth_checks_new_darts_and_finds_defects_anywhere():
    gm = GMap3()
    a, b = gm.add_prisms(4, 2, origins=[[0, 0, 0], [1, 0, 0]])
    assert gm.validity_problems() == []  # remembered as valid
    (c,) = gm.add_prisms(4, 1, origins=[[2, 0, 0]])
    gm.sew3(gm.prism_face(b, 4, "E"), gm.prism_face(c, 4, "O"))
    assert gm.validity_problems() == []
    assert gm._changed_since_valid() is not None  # incremental: only darts near the new ones
    gm.add_prisms(4, 1, origins=[[3, 0, 0]])
    gm.alpha[3][0], gm.alpha[3][1] = 1, 0  # a bad link between old darts, by hand
    problems = gm.validity_problems()
    assert any("alpha0alpha3" in p or "alpha1alpha3" in p for p in problems)
    gm.alpha[3][0], gm.alpha[3][1] = 0, 1
    gm.mark_changed()
    assert gm.validity_problems() == []
    gm.dart_data["face"][5] = 3  # an old dart far from any new one relabelled
    assert any("face orbit" in p for p in gm.validity_problems())


def test_cells_of_a_volume_sewn_to_itself_do_not_hang():
    """Two involutions sending a dart to the same dart made scipy's strong components loop forever
    (the 'grow hang' of the random-operations property test); run in a child process with a timeout."""
    import subprocess
    import sys

    code = (
        "from ramure.gmap import GMap3\n"
        "gm = GMap3(); gm.add_prisms(4)\n"
        "d = int(gm.face_of(0, 'C1')); e = int(gm.alpha[2][d])\n"
        "gm.sew3([d], [e])\n"
        "assert gm.is_valid() and int((gm.alpha[2] == gm.alpha[3]).sum()) == 4\n"
        "from ramure.gmap.kernel.topology import orientation_parity\n"
        "orientation_parity(gm)\n"
        "print(gm.cells(0)[1], gm.cells(1)[1], gm.euler_characteristic(), gm.boundary().euler_characteristic())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    v, e, chi, bchi = map(int, out.stdout.split())
    assert (v, e) == (6, 9) and chi == 1  # C1 folded onto C2: 8-2 vertices, 12-3 edges
