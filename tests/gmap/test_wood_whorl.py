"""A whorl does not make a bottle of the log (issue 39): the knots' push bends the trunk's rings
round each knot but keeps every ring, and the bark, on its cylinder, so the stem's outer radius
goes on tapering past the node instead of jumping by a knot's radius all round it."""

import numpy as np
import pytest

from ramure.gmap.kernel.prism import face_label_code
from ramure.gmap.kernel.topology import assert_solid
from ramure.gmap.organs import wood as W

WHORL = [(1, 0), (1, 5), (1, 11)]  # three branches of year 1, as a pine's whorl


@pytest.fixture(scope="module")
def whorl():
    return W.grow_wood("pine", years=10, seed=0, branches=WHORL)


def outer_radii(wood: W.Wood) -> np.ndarray:
    """``(levels, sectors, 2)``: the largest distance from the trunk's axis of the drawn vertices of
    each trunk stack's outermost cell, at the level's bottom and top (NaN in a knot's slot).  The
    vertices a branch's volumes share (the knot's seam and its end) are left out, and the top faces
    of the bark the bottom wall closes under each knot (:func:`under_knots`): the branch leaves the
    trunk there."""
    gm = wood.gm
    vid, pos = gm.vertex_positions()
    on_branch = np.zeros(len(pos), bool)
    on_branch[vid[gm.volume_data["axis"][gm.dart_volume] > 0]] = True
    under = under_knots(wood)  # the trunk's bark closing under each knot's lower bark ring
    on_branch[vid[np.isin(gm.dart_volume, under) & (gm.dart_data["face"] == face_label_code("C3"))]] = True
    order = np.argsort(gm.dart_volume, kind="stable")
    starts = np.searchsorted(gm.dart_volume[order], np.arange(len(gm.volume_data["cell"]) + 1))
    ax = wood.trunk
    o, f, h = wood.level_frames(ax)
    out = np.full((len(ax.levels), ax.sides, 2), np.nan)
    for t in range(len(ax.levels)):
        middle = o[t, 2] + 0.5 * h[t]
        for k in range(ax.sides):
            if not ax.alive[t, k]:
                continue
            vol = gm.dart_volume[ax.cells[t, k, int(ax.count[t, k]) - 1]]
            v = np.unique(vid[order[starts[vol] : starts[vol + 1]]])
            pts = pos[v[~on_branch[v]]]
            r = np.hypot(pts[:, 0], pts[:, 1])
            low, high = pts[:, 2] < middle, pts[:, 2] >= middle
            out[t, k] = (r[low].max() if low.any() else np.nan), (r[high].max() if high.any() else np.nan)
    return out


def under_knots(wood: W.Wood) -> np.ndarray:
    """Volumes of each slot's bottom wall past the knot's last ring (:meth:`Wood._close_under_knots`):
    their top faces lie on the knot's section, under its lower bark ring, which juts out of the trunk
    under a rising knot, so they reach past it (by 1.3 to 2.2 mm past the seam's farthest vertex, on a
    12-year pine's knots and a 10-year whorl's)."""
    ax, gm = wood.trunk, wood.gm
    shift = wood.year_shift(ax)
    out = []
    for b, br in enumerate(wood.branches):
        t, k = br.level - 1, br.sector
        last = int(wood.branch_axis[b].count[0].max()) + int(shift[br.level])
        if br.parent < 0 and ax.alive[t, k] and ax.count[t, k] > last:
            out.extend(gm.dart_volume[ax.cells[t, k, last : ax.count[t, k]]].tolist())
    return np.array(out, np.int64)


def swelling(radii: np.ndarray) -> float:
    """Largest outer radius over the narrowest one below it in the same sector, less 1, over the
    trunk read upwards level by level (bottom, then top)."""
    worst = 0.0
    for k in range(radii.shape[1]):
        along = radii[:, k].reshape(-1)
        along = along[~np.isnan(along)]
        narrowest = np.minimum.accumulate(along)
        worst = max(worst, float(np.max(along[1:] / narrowest[:-1])) - 1)
    return worst


def test_the_log_tapers_past_a_whorl(whorl):
    """Away from the knots (sectors neither holding a knot nor next to one) every sector's outer
    radius is non-increasing upwards within 3 % (it swelled by 40 %, the knots' push moving the bark
    out all round the node), and the stem's mean radius at the node is as without knots.  Next to a
    knot too (it swelled by 44 %, then 6 %: the bottom wall's outer bark, folded under the knot at the
    trunk's apothem pushed round it, see test_wood_under_knot.py; that bark now closes on the knot's
    section, left out with the seam): 2.8 %, as far from it."""
    bent = outer_radii(whorl)
    whorl.bend_rings = False
    whorl.embed()
    straight = outer_radii(whorl)
    whorl.bend_rings = True
    whorl.embed()
    n = whorl.trunk.sides
    near = {(k + d) % n for _, k in WHORL for d in (-1, 0, 1)}
    far = [k for k in range(n) if k not in near]
    assert len(far) == 7
    assert swelling(bent[:, far]) < 0.03
    assert swelling(straight) < 0.03
    assert swelling(bent) < 0.03
    node = WHORL[0][0]  # the node's level: the bottom of its level and the top of the level below
    # over all sectors (0.5 %; with the folded bark's corners beside each slot 3.7 %, 6 % over 9
    # sectors of 16) and away from the knots the level below the node ends as without knots
    assert np.nanmean(bent[node - 1, :, 1]) == pytest.approx(np.nanmean(straight[node - 1, :, 1]), rel=0.01)
    assert np.nanmean(bent[node - 1, far, 1]) == pytest.approx(np.nanmean(straight[node - 1, far, 1]), rel=0.01)
    assert np.nanmean(bent[node, :, 0]) == pytest.approx(np.nanmean(straight[node, :, 0]), rel=0.035)


def test_a_whorl_stays_a_valid_ball_with_the_estimated_darts(whorl):
    assert_solid(whorl.gm)
    assert whorl.gm.euler_characteristic() == 1
    assert whorl.gm.n_darts == W.estimated_darts(whorl.p, 10, [y for y, _ in WHORL])


def test_the_push_moves_ring_corners_round_the_trunk_not_out(whorl):
    """Away from the knots' sectors the push moves trunk corners by centimetres round and along the
    trunk but at most 2.5 mm out from its axis (it moved them 18 mm out), and none in."""
    vd = whorl.gm.volume_data
    flat, offset = whorl.default_corners()
    whorl.bend_rings = False
    straight, _ = whorl.default_corners()
    whorl.bend_rings = True
    n = whorl.trunk.sides
    near = [(k + d) % n for _, k in WHORL for d in (-1, 0, 1)]
    trunk = (vd["axis"] == 0) & (vd["cell"] > 0) & (np.abs(vd["level"] - 1) <= 1)
    cells = np.flatnonzero(trunk & ~np.isin(vd["sector"], near))
    rows = (offset[cells][:, None] + np.arange(8)[None, :]).reshape(-1)
    moved = np.linalg.norm(flat[rows] - straight[rows], axis=1)
    assert moved.max() > 0.02  # 34 mm
    out = np.hypot(flat[rows, 0], flat[rows, 1]) - np.hypot(straight[rows, 0], straight[rows, 1])
    assert out.max() < 2.5e-3  # 2.2 mm
    assert out.min() > -1e-6


def ring_corner(wood: W.Wood, level: int, sector: int, cell: int, top: bool) -> tuple[float, float]:
    """Mean distance from the axis and mean height of a trunk cell's outer corners, bottom or top."""
    gm, vd = wood.gm, wood.gm.volume_data
    vol = np.flatnonzero((vd["axis"] == 0) & (vd["level"] == level) & (vd["sector"] == sector) & (vd["cell"] == cell))
    darts = np.flatnonzero(np.isin(gm.dart_volume, vol) & np.isin(wood.corner, [6, 7] if top else [4, 5]))
    p = gm.points[darts]
    return float(np.hypot(p[:, 0], p[:, 1]).mean()), float(p[:, 2].mean())


@pytest.mark.parametrize("cell", [2, 4, 6])
def test_a_year_with_knots_narrows_over_its_whole_height_not_in_its_node(cell):
    """A year carrying a knot is a short node and a tall internode, glued cell to cell.  Each ring
    narrows by one year's width from the year below to its own radius; that narrowing is spread over
    the year's height (node and internode), so the node, a tenth of the year's height, takes about a
    tenth of it.  Taken in the node alone (half of it, as before), every ring of a flat-sawn board
    kinks at each whorl.  Measured on the side away from the knot, out of its push."""
    wood = W.grow_wood("pine", years=8, branches=[(3, 0)], height=0.3)
    br = wood.branches[0]
    t, away = br.level, (br.sector + wood.trunk.sides // 2) % wood.trunk.sides
    assert [part for _, part in wood.trunk.parts[t : t + 2]] == ["node", "internode"]
    r0, z0 = ring_corner(wood, t, away, cell, top=False)
    r1, z1 = ring_corner(wood, t, away, cell, top=True)
    r2, z2 = ring_corner(wood, t + 1, away, cell, top=True)
    assert r0 > r1 > r2  # the ring narrows upwards all the way
    height_share = (z1 - z0) / (z2 - z0)
    assert 0.05 < height_share < 0.15
    assert (r0 - r1) / (r0 - r2) == pytest.approx(height_share, abs=0.04)


@pytest.mark.parametrize(("branches", "sector"), [([(3, 0), (5, 6), (7, 11)], 3), ([], 9)])
def test_the_bark_outline_has_no_step_at_a_level_boundary(branches, sector):
    """A stack holds one year's bark cell more than the stack above it; that outermost cell closes
    at the top of its level onto the boundary vertex, which is the average of the cells that meet
    there, not onto its inner neighbour's own radius (which left a flat shoulder of 1.1 to 1.4 mm
    in the bark's outline at every level).  Away from the knots (three sectors or more), the
    outline's radius just under a boundary and just over it differ by under 0.3 mm."""
    wood = W.grow_wood("pine", years=12, branches=branches, height=0.3)
    ax = wood.trunk
    steps = []
    for t in range(len(ax.levels) - 1):
        below, _ = ring_corner(wood, t, sector, int(ax.count[t, sector]), top=True)
        above, _ = ring_corner(wood, t + 1, sector, int(ax.count[t + 1, sector]), top=False)
        steps.append(abs(below - above))
    assert max(steps) < 3e-4
