"""No trunk cell of a pine or a larch turned inside out under its lowest whorl (issue 39).

The volumes are the kernel's own signed ones: each face walked from a dart
of orientation class 0, fanned from its vertex centroid, summed over the
volume (divergence theorem), and turned so the wood's total is positive.
The class is per volume (:func:`orientation_parity`), so the test checks
that it flips across every face two volumes share: then the walks orient
the whole solid one way, by topology alone, and a cell with a volume <= 0
is inside out.
(VTK's ``compute_cell_sizes`` is not the measure here: it measures a
hexahedron as :func:`ramure.gmap.kernel.pyvista.to_unstructured_grid` orders
its corners, which turned long thin valid cells over until the converter
oriented each bottom face by Newell's normal; the last test checks it
agrees now.)  On the code before the fix the
woods below had 9, 2 and 9 trunk cells inside out, all shed bark slivers
(50 um) next to the lowest whorl's knots.
"""

from __future__ import annotations

import numpy as np
import pytest

from ramure.gmap.kernel.topology import orientation_parity
from ramure.gmap.organs import wood as W


def signed_volumes(gm) -> np.ndarray:
    """Signed volume of every volume, positive for a wood whose cells are all the right way out."""
    vid, pos = gm.vertex_positions()
    side, n_sides = gm.orbit_ids("01")
    parity = orientation_parity(gm)
    sewn = np.flatnonzero(gm.alpha[3] != np.arange(gm.n_darts))
    assert np.all(parity[sewn] != parity[gm.alpha[3][sewn]]), "volumes oriented apart: the sign means nothing"
    even = np.flatnonzero(parity == 0)
    first = np.full(n_sides, -1, np.int64)
    first[side[even][::-1]] = even[::-1]
    first = first[first >= 0]
    walk, length = gm.face_walk(first)
    corners = walk[:, 0::2]
    ok = corners >= 0
    degree = length // 2
    p = np.where(ok[:, :, None], pos[vid[np.maximum(corners, 0)]], 0.0)
    centre = p.sum(axis=1) / degree[:, None]
    nxt = (np.arange(corners.shape[1])[None, :] + 1) % degree[:, None]
    q = np.take_along_axis(p, nxt[:, :, None], axis=1)
    ref = pos.mean(axis=0)
    tet = np.einsum("fki,fki->fk", np.cross(p - ref, q - ref), (centre - ref)[:, None, :]) / 6.0
    signed = np.bincount(gm.dart_volume[first], np.where(ok, tet, 0.0).sum(axis=1), minlength=gm.n_volumes)
    return signed * np.sign(signed.sum())


@pytest.mark.parametrize(
    "species, params",
    [
        ("pine", dict(years=20)),
        ("pine", dict(years=16, branch_life=4)),
        ("larch", dict(years=16, branch_life=6)),
    ],
)
def test_no_trunk_cell_inside_out_under_the_lowest_whorl(species, params):
    wood = W.grow_wood(species, height=0.3, **params)
    vd = wood.gm.volume_data
    vol = signed_volumes(wood.gm)
    trunk = (vd["axis"] == 0) & (vd["cell"] > 0)
    bad = np.flatnonzero(trunk & (vol <= 0))
    where = sorted({(int(vd["level"][v]), int(vd["sector"][v]), int(vd["cell"][v])) for v in bad})
    assert not bad.size, f"{bad.size} trunk cells inside out (level, sector, cell): {where[:10]}"


def test_the_pull_moves_only_folded_vertices():
    """The vertices :meth:`Wood._keep_rings_apart` moves are few and move by a fraction of a millimetre."""
    wood = W.grow_wood("pine", years=20, height=0.3, branches=3)
    raw = wood.gm.embed()
    pos = raw.copy()
    wood._keep_rings_apart(pos)
    assert np.allclose(wood.gm.vertex_positions()[1], pos, rtol=0, atol=1e-12)
    moved = np.linalg.norm(pos - raw, axis=1)
    assert 0 < np.count_nonzero(moved > 1e-9) < 100
    assert moved.max() < 5e-4
    wood.check_topology()


def test_vtk_measures_every_hexahedron_the_way_out_the_kernel_does():
    """The converter writes a hexahedron bottom face first, turned towards its top: the 20-year
    pine's long thin cone cells in level 2 (cells 2-13, closing in to the pith) came out inside
    out by a test at one corner, 82 of them measured negative by VTK."""
    wood = W.grow_wood("pine", height=0.3, years=20)
    grid = W.to_grid(wood)
    hexa = np.flatnonzero(grid.celltypes == 12)
    vtk = np.asarray(grid.compute_cell_sizes(length=False, area=False).cell_data["Volume"])[hexa]
    kernel = signed_volumes(wood.gm)[np.asarray(grid.cell_data["volume"])[hexa]]
    assert np.all(kernel > 0)
    assert np.all(vtk > 0)
    assert np.allclose(vtk, kernel, rtol=0.05)


@pytest.fixture(scope="module")
def pine30():
    """The issue's benchmark tree: a 30-year pine, default branches."""
    return W.grow_wood("pine", years=30, height=0.3)


def test_no_knot_ring_inside_out_where_its_seat_slides_along_it(pine30):
    """The seat of the lowest whorl's knot's last ring slid along the knot past the face inside it
    (:meth:`Wood._clear_of_tops`): 5 of its cells (branch 1, level 0, sectors 7-11, cell 58) were inside out."""
    vd = pine30.gm.volume_data
    vol = signed_volumes(pine30.gm)
    bad = np.flatnonzero((vd["axis"] > 0) & (vd["cell"] > 0) & (vol <= 0))
    where = [(int(vd["axis"][v]), int(vd["level"][v]), int(vd["sector"][v]), int(vd["cell"][v])) for v in bad]
    assert not bad.size, f"{bad.size} knot cells inside out (axis, level, sector, cell): {where[:10]}"


def test_no_shed_sliver_inside_out_where_a_knot_tilts_it(pine30):
    """A shed bark sliver tilted along the trunk by a knot's push (level 2, sector 13, cell 87)
    was inside out with its layers in order across the axis (:meth:`Wood._square_turned_cells`)."""
    vd = pine30.gm.volume_data
    vol = signed_volumes(pine30.gm)
    bad = np.flatnonzero((vd["axis"] == 0) & (vd["cell"] > 0) & (vol <= 0))
    where = [(int(vd["level"][v]), int(vd["sector"][v]), int(vd["cell"][v])) for v in bad]
    assert not bad.size, f"{bad.size} trunk cells inside out (level, sector, cell): {where[:10]}"
    pine30.check_topology()
    brs = pine30.branches
    est = W.estimated_darts(pine30.p, 30, [b.year for b in brs], [b.death for b in brs], [b.parent for b in brs])
    assert pine30.gm.n_darts == est


def test_hex_volumes_are_positive_the_right_way_out():
    """The 8-corner measure :meth:`Wood._square_turned_cells` tests: a unit cube in the cube order is +1."""
    cube = np.array([[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1], [1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]], float)
    assert np.isclose(W.Wood.hex_volumes(cube[None])[0], 1.0)
    assert np.isclose(W.Wood.hex_volumes(cube[None, [4, 5, 6, 7, 0, 1, 2, 3]])[0], -1.0)
