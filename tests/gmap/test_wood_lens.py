"""Pictures of the rings round a knot (issue 39): smooth curves in a board, no hole, no overlap."""

import numpy as np
import pytest

from ramure.gmap.organs import wood as W
from wood_helpers import triangle_hits


@pytest.fixture(scope="module")
def whorls():
    """Three knots born in years 3, 5 and 7, one facing +x (branch 0), on a 12-year pine."""
    wood = W.grow_wood("pine", years=12, branches=[(3, 0), (5, 6), (7, 11)], height=0.3)
    raw = W.to_grid(wood)
    return wood, raw, W.smooth_grid(wood, raw)


def _polygons(section):
    """The polygons of a slice (lists of point ids) and the merged id of each point (by position)."""
    _, pid = np.unique(np.round(np.asarray(section.points) * 1e9).astype(np.int64), axis=0, return_inverse=True)
    faces, out, i = np.asarray(section.faces), [], 0
    while i < len(faces):
        out.append(faces[i + 1 : i + 1 + faces[i]])
        i += faces[i] + 1
    return out, pid.reshape(-1)


def _ring_lines(section):
    """The edges (merged point-id pairs) between trunk cells of two rings in a slice, and the points."""
    polys, pid = _polygons(section)
    pts = np.zeros((int(pid.max()) + 1, 3))
    pts[pid] = section.points
    ring = np.asarray(section.cell_data["year"]) * 2 + np.asarray(section.cell_data["season"])
    trunk = (np.asarray(section.cell_data["axis"]) == 0) & (np.asarray(section.cell_data["season"]) >= 0)
    rows = [(min(a, b), max(a, b), c) for c, ids in enumerate(polys) for a, b in zip(pid[ids], np.roll(pid[ids], -1)) if a != b]
    e = np.array(rows)
    e = e[np.lexsort((e[:, 1], e[:, 0]))]
    twice = np.flatnonzero((e[1:, 0] == e[:-1, 0]) & (e[1:, 1] == e[:-1, 1]))
    c0, c1 = e[twice, 2], e[twice + 1, 2]
    keep = trunk[c0] & trunk[c1] & (ring[c0] != ring[c1])
    return e[twice[keep], :2], pts


def _paths(edges):
    """The ring lines as ordered point-id paths (split where three lines meet)."""
    nb = {}
    for a, b in edges:
        nb.setdefault(a, []).append(b)
        nb.setdefault(b, []).append(a)
    seen, paths = set(), []
    for start in [v for v in nb if len(nb[v]) != 2] + list(nb):
        for first in nb[start]:
            if (start, first) in seen:
                continue
            path, prev, cur = [start], start, first
            while True:
                seen.update({(prev, cur), (cur, prev)})
                path.append(cur)
                ahead = [w for w in nb[cur] if w != prev]
                if len(nb[cur]) != 2 or (cur, ahead[0]) in seen:
                    break
                prev, cur = cur, ahead[0]
            paths.append(path)
    return paths


def _passing_turns(section, centre, radius, step=1e-3):
    """The direction change (degrees) of the ring lines passing a knot (``centre``, ``radius``) over
    chords of ``step`` either side of each of their vertices within two radii of it, along the trunk
    and across it in the board (y, z)."""
    edges, pts = _ring_lines(section)
    turns = []
    for path in _paths(edges):
        p = pts[path][:, 1:]
        if p[:, 1].min() > centre[2] - 2 * radius or p[:, 1].max() < centre[2] + 2 * radius:
            continue  # a ring that ends at the knot, or a piece of one
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        for i in range(1, len(path) - 1):
            if np.linalg.norm(pts[path[i]] - centre) > 2 * radius or not step <= s[i] <= s[-1] - step:
                continue
            back = np.array([np.interp(s[i] - step, s, p[:, k]) for k in range(2)])
            ahead = np.array([np.interp(s[i] + step, s, p[:, k]) for k in range(2)])
            d0, d1 = p[i] - back, ahead - p[i]
            turns.append(np.degrees(np.arccos(np.clip(d0 @ d1 / np.linalg.norm(d0) / np.linalg.norm(d1), -1, 1))))
    return np.array(turns)


def _board(grid, wood, offset):
    section = grid.slice(normal=(1, 0, 0), origin=(offset * wood.trunk_radius(), 0, 0))
    knot = section.extract_cells(np.flatnonzero(np.asarray(section.cell_data["axis"]) >= 1)).connectivity("largest")
    kp = np.asarray(knot.points)
    return section, kp.mean(axis=0), 0.5 * np.ptp(kp[:, 2])


def test_rings_pass_a_knot_in_a_flat_sawn_board_without_corners(whorls):
    """A flat-sawn board facing the knot (half the trunk's radius from the pith): the rings that pass
    it (in the picture) turn by at most 32 degrees over 1 mm either side of any vertex within two
    knot radii.  The slot walls, drawn as tetrahedra, made them turn by 45 degrees at a corner."""
    wood, _, smooth = whorls
    section, centre, radius = _board(smooth, wood, 0.5)
    turns = _passing_turns(section, centre, radius)
    assert len(turns) > 10
    assert turns.max() < 32.0


def test_a_knot_board_and_a_node_cross_cut_have_no_hole_and_no_overlap(whorls):
    """Boards through the knot (0.3 and 0.5 of the trunk's radius from the pith) are covered once
    everywhere inside the wood (the walls' tetrahedra overlapped their neighbours or left holes
    there), and cross-cuts through each knot's node, near the knot (three sectors either side),
    no worse than the kernel's own cells (a few points in a thousand next to a slot): the seated
    cells' pieces meet the knot, the next rings and the level's other cells at the same points."""
    wood, raw, smooth = whorls
    radius = wood.trunk_radius()
    rng = np.random.default_rng(0)
    n = 6000
    for offset in (0.3, 0.5):
        section = smooth.slice(normal=(1, 0, 0), origin=(offset * radius, 0, 0)).triangulate()
        tri = section.points[np.asarray(section.faces).reshape(-1, 4)[:, 1:]][:, :, 1:]
        q = np.stack([rng.uniform(-0.6, 0.6, n) * radius, rng.uniform(0.85, 1.05, n)], axis=1)
        assert np.count_nonzero(triangle_hits(tri, q) != 1) == 0
    o, _, h = wood.level_frames(wood.trunk)
    for br in wood.branches[:2]:
        phi = W.Wood.sector_centre(wood.trunk, br.sector)
        r = np.sqrt(rng.uniform(0.15**2, 0.6**2, n)) * radius
        a = phi + rng.uniform(-3.5, 3.5, n) * 2 * np.pi / wood.trunk.sides
        q = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
        for share in (0.3, 0.5, 0.7):
            bad = []
            for grid in (raw, smooth):
                section = grid.slice(normal=(0, 0, 1), origin=(0, 0, float(o[br.level, 2] + share * h[br.level])))
                section = section.triangulate()
                tri = section.points[np.asarray(section.faces).reshape(-1, 4)[:, 1:]][:, :, :2]
                bad.append(np.count_nonzero(triangle_hits(tri, q) != 1))
            assert bad[1] <= bad[0] + 0.001 * n


def test_seated_cells_are_hexahedra_and_the_rest_is_unchanged(whorls, monkeypatch):
    """Each ring cell seated on a knot (its walls, the cells over and under it) is drawn as four
    hexahedra across its seated edges, each cut in four round the trunk (but the bark cell under
    a knot, seated on one edge only, left in tetrahedra); a wall's pieces, stacked along the knot,
    are first cut in four along it too (on the knot's arcs: 64 pieces); every other cell keeps its four pieces,
    and three levels or more from the knots' nodes they keep their very points (nearer, an arc
    that met a seated cell's tetrahedra was left a chord)."""
    wood, raw, smooth = whorls
    vd = wood.gm.volume_data
    owner = np.asarray(smooth.cell_data["volume"])
    nodes = np.array([br.level for br in wood.branches])
    seated = np.abs(vd["level"] - nodes[:, None]).min(axis=0) <= 1
    seated &= (vd["axis"] == 0) & (vd["cell"] > 0)
    ring_cells = np.flatnonzero((vd["axis"] == 0) & (vd["cell"] > 0))
    pieces = np.bincount(owner, minlength=len(vd["cell"]))[ring_cells]
    whole = np.bincount(owner[smooth.celltypes != 12], minlength=len(vd["cell"]))[ring_cells] > 0
    assert np.count_nonzero(whole) <= len(wood.branches)  # the bark under a knot, seated on one edge
    assert set(np.unique(pieces[~whole])) == {4, 16, 64}
    assert np.count_nonzero(pieces == 16) > 100 and np.count_nonzero(pieces == 64) > 100
    assert np.all(seated[ring_cells[pieces >= 16]])
    walls = ring_cells[pieces == 64]
    assert np.all(np.isin(vd["level"][walls], nodes))  # the slot walls, in the knots' nodes
    monkeypatch.setattr(W, "seated_as_hexahedra", lambda wood, grid: grid)
    before = W.smooth_grid(wood, raw)
    far = ring_cells[np.abs(vd["level"][ring_cells] - nodes[:, None]).min(axis=0) >= 3]

    def points(grid):
        rows = np.isin(np.asarray(grid.cell_data["volume"]), far)
        cells = grid.extract_cells(rows)
        return np.unique(np.round(np.asarray(cells.points) * 1e9).astype(np.int64), axis=0)

    assert np.array_equal(points(before), points(smooth))
