"""Levels glued by year (issue 39 (a)): a ring meets its own year across a level boundary, its
growth cone ends at the pith, and a board shows no step in the rings at the level boundaries."""

import numpy as np
import pytest

from ramure.gmap.kernel.topology import assert_solid
from ramure.gmap.organs import wood as W

from wood_helpers import contacts

C = W.CODES
LATER = [C["sapwood"], C["heartwood"]]


@pytest.fixture(scope="module")
def trunk6():
    return W.grow_wood("pine", years=6, branches=0)


def test_each_ring_meets_its_own_year_and_the_older_cones_end_on_the_first_cell(trunk6):
    vd = trunk6.gm.volume_data
    a, b = contacts(trunk6)
    up = (vd["axis"][a] == 0) & (vd["axis"][b] == 0) & (vd["level"][a] == vd["level"][b] + 1)
    up &= (vd["cell"][a] > 0) & (vd["cell"][b] > 0)
    same = vd["year"][a] == vd["year"][b]
    # the cone apex: cell 1 of level t on cells 1 and 2 of level t - 1 (the year before t existed)
    apex = up & ~same
    assert np.array_equal(np.unique(vd["cell"][a[apex]]), [1])
    assert np.array_equal(np.unique(vd["cell"][b[apex]]), [1, 2])
    assert np.all(vd["year"][b[apex]] == vd["year"][a[apex]] - 1)
    pairs = np.unique(np.stack([a[apex], b[apex]]), axis=1)
    assert pairs.shape[1] == 5 * 16 * 2  # five boundaries, 16 sectors, two older cells each
    # every other cell meets the cell two further out below: same year, same season, same tissue role
    rest = up & same
    assert np.array_equal(vd["cell"][b[rest]], vd["cell"][a[rest]] + 2)
    assert np.array_equal(vd["season"][b[rest]], vd["season"][a[rest]])
    assert np.array_equal(vd["wood"][b[rest]] == C["bark"], vd["wood"][a[rest]] == C["bark"])


@pytest.mark.parametrize("years", [1, 2, 4])
def test_the_solid_stays_one_ball_and_the_dart_count_exact(years):
    w = W.grow_wood("pine", years=years, branches=0, check_every_step=True)
    assert_solid(w.gm)
    assert w.gm.n_darts == W.trunk_darts(16, years) == W.estimated_darts(w.p, years)
    # each level glued by year adds 24 darts a sector (its first cells' bottoms cut in three)
    assert W.trunk_darts(16, years) - W.trunk_darts(16, years - 1) == (
        12 * 16 + 48 * 16 * 3 * years + (W.BRIDGE_DARTS * 16 if years > 1 else 0)
    )


def _year_edges(grid, z, angle=0.3, radius=0.1):
    """Outer radius of each wood year met along a radial ray at height z."""
    t = np.linspace(1e-5, radius, 20000)
    pts = np.stack([t * np.cos(angle), t * np.sin(angle), np.full_like(t, z)], axis=1)
    cells = grid.find_containing_cell(pts)
    ok = cells >= 0
    year = np.asarray(grid.cell_data["year"])[cells[ok]]
    wood = np.isin(np.asarray(grid.cell_data["wood"])[cells[ok]], LATER)
    r = t[ok]
    return {int(y): float(r[wood & (year == y)].max()) for y in np.unique(year[wood])}


def test_rings_run_on_across_a_level_boundary_without_a_step(trunk6):
    """On both sides of the boundary between levels 1 and 2 (z = 1 m), each year ends at the same radius.

    Glued cell to cell, year ``y`` below the boundary ended where year ``y - 1`` ended above it:
    a step of a whole ring (about 2 mm here) on every board."""
    grid = W.to_grid(trunk6)
    below, above = _year_edges(grid, 1.0 - 1e-4), _year_edges(grid, 1.0 + 1e-4)
    assert sorted(below) == list(range(1, 6)) and sorted(above) == list(range(2, 6))
    widths = np.diff([below[y] for y in sorted(below)])
    steps = [abs(below[y] - above[y]) for y in above]
    assert max(steps) < 0.05 * widths.min()
    # and the cone of year 1 (below only) closes at the pith there: a sliver, not a whole ring
    assert below[1] - trunk6.p["pith_radius"] < 0.15 * (below[2] - below[1])


def test_rings_run_on_across_a_knots_node_without_a_step():
    """The node carrying a knot is glued by year too: opposite the knot, across the node's bottom
    (z = 1 m, a year younger than the level below), each year of the node ends where it ends below.
    Glued cell to cell it ended where the next older year ended below (4.5 mm off here)."""
    wood = W.grow_wood("pine", years=6, branches=[(2, 3)])
    o, _, _ = wood.level_frames(wood.trunk)
    z = float(o[wood.branches[0].level][2])
    grid = W.to_grid(wood)
    angle = 2 * np.pi * (3 + 8) / 16 + 0.3  # across the trunk from the knot's sector
    below, above = _year_edges(grid, z - 1e-4, angle), _year_edges(grid, z + 1e-4, angle)
    years = [y for y in range(2, 6)]
    assert all(y in below and y in above for y in years)
    widths = np.diff([below[y] for y in years])
    assert max(abs(below[y] - above[y]) for y in years) < 0.05 * widths.min()
