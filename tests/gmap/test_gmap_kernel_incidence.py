"""Vertex editing, local cell queries, incidence and adjacency as sparse arrays."""

import numpy as np
import pytest
from scipy import sparse

from ramure.gmap import GMap3, GMapError
from ramure.gmap.kernel import incidence
from ramure.gmap.kernel.topology import assert_solid


def row_of_cubes(k=3):
    gm = GMap3()
    gm.add_prisms(4, k, origins=[[i, 0, 0] for i in range(k)])
    gm.sew3(gm.face_of(np.arange(k - 1), "E"), gm.face_of(np.arange(1, k), "O"))
    gm.embed()
    return gm


def test_adjacency_by_face_and_by_vertex():
    gm = row_of_cubes(3)
    face = incidence.volume_adjacency(gm, "face")
    assert isinstance(face, sparse.csr_array)
    assert face.toarray().tolist() == [[0, 1, 0], [1, 0, 1], [0, 1, 0]]
    vert = incidence.volume_adjacency(gm, "vertex").toarray()
    assert vert.tolist() == face.toarray().tolist()  # stacked cubes touch only by faces
    inc = incidence.vertex_volumes(gm)
    assert inc.shape == (16, 3)
    assert inc.sum() == 8 * 3 and sorted(np.asarray(inc.sum(axis=1)).tolist()) == [1] * 8 + [2] * 8
    with pytest.raises(GMapError):
        incidence.volume_adjacency(gm, "edge")


def test_cubes_on_two_sides_touch_by_vertex_not_by_face():
    from ramure.gmap.kernel.embedding import grow

    gm = GMap3()
    gm.add_prisms(4)
    grow(gm, gm.face_of([0, 0], ["C1", "C2"]), 4, height=1.0)
    assert incidence.volume_adjacency(gm, "face").toarray().tolist() == [[0, 1, 1], [1, 0, 0], [1, 0, 0]]
    assert incidence.volume_adjacency(gm, "vertex").toarray().tolist() == [[0, 1, 1], [1, 0, 1], [1, 1, 0]]
    gm.identify([gm.face_of(1, "C2")], [gm.face_of(2, "C4")])
    assert incidence.volume_adjacency(gm, "face").toarray()[1, 2] == 1


def test_local_queries_match_the_global_cells():
    gm = row_of_cubes(3)
    vid, _ = gm.cells(0)
    for d in (0, 50, 100):
        local = incidence.cell_darts(gm, d, 0)
        assert local.tolist() == np.flatnonzero(vid == vid[d]).tolist()
    members, which = incidence.cells_around(gm, [0, 60], 3)
    assert np.bincount(which).tolist() == [48, 48]
    assert incidence.vertex_volumes_local(gm, gm.face_of(0, "E")).tolist() == [0, 1]


def test_move_vertices_moves_every_dart_of_the_vertex_and_survives_embedding():
    gm = row_of_cubes(2)
    d = gm.face_of(0, "E")
    incidence.move_vertices(gm, [d], [[1.0, 2.0, 3.0]])
    vid, _ = gm.cells(0)
    at = vid == vid[d]
    assert np.allclose(gm.points[at], [1, 2, 3]) and at.sum() == 12
    pos = gm.embed()
    assert np.allclose(pos[vid[d]], [1, 2, 3])
    assert_solid(gm)
    with pytest.raises(GMapError):
        incidence.move_vertices(gm, [d], [[np.nan, 0, 0]])
    with pytest.raises(GMapError):
        incidence.move_vertices(gm, [d, gm.alpha[1][d]], [[0, 0, 0], [1, 1, 1]])
