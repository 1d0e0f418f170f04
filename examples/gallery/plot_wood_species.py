"""
Four woods: pine, larch, elm and oak
====================================

Each species grows 18 years on a 3D generalized map with its own ring width law
(latewood share), heartwood, branch pattern (pine's whorls, larch's scattered
branches, elm's two ranks, oak's clusters) and bark (shed beyond a species
thickness; plates for the conifers, ridges for the broadleaves).  A cross-cut
shows the rings, the sapwood and heartwood, and the bark; a flat-sawn board
shows the arches, and a quarter-sawn board the straight stripes and, in oak, the
rays' silver figure, with each species' texture: oak's band of earlywood pores and
its broad rays, elm's pores and wavy latewood bands, the resin canals of pine
and larch.  Branch wood is darker on its lower side in the conifers
(compression wood) and paler on its upper side in the broadleaves (tension
wood).  Last, each species' knots: a 12-year tree with two branches on one side, the lower
one alive, the upper one dead since year 7, cross-cut through each knot (the live knot's rings run
into the trunk's; the dead one is ringed with its dark bark and encased).  See
:mod:`ramure.gmap.organs.wood_species` for the sources of the numbers.
"""

import numpy as np

from ramure.app.commands.wood import legend_for, render_plank
from ramure.gmap.organs import wood as W

from _show import show

YEARS = 18


def grown(species):
    """The species' wood and its picture grid (rings drawn round)."""
    wood = W.grow_wood(species, years=YEARS, height=0.3)
    return wood, W.smooth_grid(wood, W.to_grid(wood))


def clear_height(wood):
    """Half-way up the lowest year from the third on with no branch in it or the next: a cut
    between knots, low enough for the heartwood."""
    busy = {br.year for br in wood.branches}
    year = next((y for y in range(2, YEARS - 2) if not busy & {y, y + 1}), 2)
    return (year + 0.5) * wood.p["height"]


def cross_cut(species, path):
    wood, grid = grown(species)
    z = clear_height(wood)
    slab = W.plank(grid, (0.0, 0.0, 1.0), z, 0.004)
    title = f"{species}: cross-cut at {z:.2f} m"
    render_plank(slab, path, np.array([0.0, 0.0, 1.0]), title=title, legend=legend_for(species), species=species)


def flat_sawn(species, path):
    wood, grid = grown(species)
    offset = 0.45 * wood.trunk_radius()
    slab = W.plank(grid, (1.0, 0.0, 0.0), offset, 0.004)
    part = W.plank_window(slab, 6 * wood.trunk_radius())[0]
    title = f"{species}: flat-sawn, {100 * offset:.1f} cm from the pith"
    render_plank(part, path, (1, 0, 0), title=title, legend=legend_for(species), species=species)


def clear_normal(wood):
    """The normal of a plane through the pith that runs farthest from every branch (their stubs
    would stick out of the board)."""
    sides = wood.trunk.sides
    branch = np.array([2 * np.pi * br.sector / sides for br in wood.branches])
    candidates = np.linspace(0, np.pi, 64, endpoint=False)
    gap = np.abs((candidates[:, None] - branch[None, :] + np.pi / 2) % np.pi - np.pi / 2).min(axis=1)
    along = candidates[np.argmax(gap)]
    return np.array([-np.sin(along), np.cos(along), 0.0])


def quarter_sawn(species, path):
    wood, grid = grown(species)
    normal = clear_normal(wood)
    slab = W.plank(grid, normal, -0.002, 0.004)
    part = W.plank_window(slab, 6 * wood.trunk_radius())[0]
    title = f"{species}: quarter-sawn, through the pith"
    render_plank(part, path, normal, title=title, legend=legend_for(species), species=species)


#: Where the knot cuts cross the live and the dead knot's pith, as a share of the trunk's radius:
#: half-way out along the live one, four fifths of the way out along the dead one, in its loose
#: (encased) part.  A dead branch's knot is intergrown out to the radius the trunk had when it died
#: (0.26-0.35 R here: the wood grew round it while it lived, a "sound knot") and encased past it
#: (Moberg 2001, *Forest Ecology and Management* 147: sound-knot and loose-knot lengths); a
#: cross-cut through a rising knot runs a long way along it, so a cut half-way out would reach the
#: sound part and show its inner end with no bark round it.
KNOT_CUTS = (0.5, 0.8)


def knot_cuts(species, path):
    """Cross-cuts through a live knot and a dead one, side by side (the dead one on the right)."""
    wood = W.grow_wood(species, years=12, branches=[(3, 0), (4, 1)], branch_deaths={1: 7}, height=0.3)
    grid, radius = W.smooth_grid(wood, W.to_grid(wood)), wood.trunk_radius()
    cuts = []
    for b in (0, 1):
        base, frame = wood.branch_frame(wood.branches[b], knot=True)
        rise = frame[0][2] / max(np.hypot(frame[0][0], frame[0][1]), 1e-9)
        height = float(base[2] + KNOT_CUTS[b] * radius * rise)
        cut = W.plank(grid, (0.0, 0.0, 1.0), height, 0.004)
        cut.translate((-2.4 * radius * b, 0.0, -height), inplace=True)  # +x is drawn on the left
        cuts.append(cut)
    title = f"{species}: live knot (left), dead knot (right)"
    both = cuts[0].merge(cuts[1])
    render_plank(both, path, np.array([0.0, 0.0, 1.0]), title=title, legend=legend_for(species), species=species)


for name in ("pine", "larch", "elm", "oak"):
    show(cross_cut, name)
    show(flat_sawn, name)
    show(quarter_sawn, name)
    show(knot_cuts, name)
