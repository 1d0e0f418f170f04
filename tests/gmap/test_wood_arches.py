"""Flat-sawn figure: each year's rings draw an arch that narrows to its apex up the tree (issue 39).

A flat-sawn board cuts each year's growth sheath, a tapering cone, off its axis: the rings
show as nested "cathedral" arches, U- or V-shaped, their apex where the sheath's radius falls
to the board's distance from the pith (lumber glossaries: "the annular rings running in U
shapes on the board face").  The old model drew each year as straight prisms, so the arches
were rectangles with horizontal ends.
"""

import numpy as np
import pytest

from ramure.gmap.organs import wood as W

#: Heights below an arch's apex, as shares of a year's height, nearest first.
DEPTHS = (0.003, 0.01, 0.02, 0.05, 0.1, 0.4)


@pytest.fixture(scope="module")
def board():
    """A flat-sawn section half-way out of a 10-year pine with no branches, as pictures draw it
    (rings rounded: a 16-gon's facet facing the board would end its arch flat, 9 mm wide)."""
    wood = W.grow_wood("pine", years=10, branches=0, height=0.3)
    offset = 0.5 * wood.trunk_radius()
    section = W.smooth_grid(wood, W.to_grid(wood)).slice(normal=(1, 0, 0), origin=(offset, 0, 0))
    return wood, offset, section


def _arch(section, year):
    """The part of the section inside year ``year``'s outer boundary (wood only)."""
    years = np.asarray(section.cell_data["year"])
    wood = np.asarray(section.cell_data["wood"]) != W.CODES["bark"]
    return section.extract_cells(np.flatnonzero((years >= 0) & (years <= year) & wood))


def _width(part, offset, z):
    line = part.slice(normal=(0, 0, 1), origin=(offset, 0, z))
    return float(np.ptp(np.asarray(line.points)[:, 1])) if line.n_points else 0.0


@pytest.mark.parametrize("year", [5, 6, 7, 8])
def test_a_years_arch_narrows_to_its_apex(board, year):
    wood, offset, section = board
    part = _arch(section, year)
    apex = float(np.asarray(part.points)[:, 2].max())
    widths = [_width(part, offset, apex - d * wood.p["height"]) for d in DEPTHS]
    assert np.all(np.diff(widths) > 0), widths  # wider at every step away from the apex
    assert widths[0] < 0.25 * widths[-1], widths  # pointed or round, not a flat end
    assert widths[-1] > 0.01  # the arms are there, a centimetre apart and more


def test_the_arches_point_up_the_tree_and_nest(board):
    """A later year's sheath reaches higher: its apex is above the year before's."""
    _, _, section = board
    apexes = [float(np.asarray(_arch(section, y).points)[:, 2].max()) for y in range(4, 10)]
    assert np.all(np.diff(apexes) > 0), apexes
