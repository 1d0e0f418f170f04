"""Live and dead knots (issue 39 section 2): a dead branch's knot stops growing and later rings
encase it through its own bark."""

import json

import numpy as np
import pytest

from ramure.app.cli import main
from ramure.gmap.kernel import measure
from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.topology import assert_solid
from ramure.gmap.organs import wood as W

from wood_helpers import contacts

C = W.CODES
LATER = [C["sapwood"], C["heartwood"]]


@pytest.fixture(scope="module")
def mixed():
    # two branches of year 1 facing +x (sectors 0 and 1 of 16): branch 0 lives, branch 1 dies in year 3
    return W.grow_wood("pine", years=7, branches=[(1, 0), (2, 1)], branch_deaths={1: 4}, height=0.12)


def test_a_dead_knots_wood_stops_growing_and_a_live_one_does_not():
    p = W.resolve_params("pine")
    wood = W.Wood(p, 0, [W.Branch(2, 3, 11), W.Branch(2, 9, 12, death=4)], "pine", years=9)
    live, dead = [], []
    for _ in range(18):
        wood.step()
        wood.embed()
        if wood.steps > 8:  # from the death step (spring of year 4, the ninth half-year) on
            vd, vol = wood.gm.volume_data, measure.volumes(wood.gm)
            knot = (vd["wood"] == C["knot"]) & (vd["level"] == 0)
            live.append(vol[knot & (vd["axis"] == 1)].sum())
            dead.append(vol[knot & (vd["axis"] == 2)].sum())
    assert np.ptp(dead) <= 1e-12 * max(dead)  # the same volume for five years
    assert live[-1] > 2 * live[0]  # the live one keeps growing (2.7x on the sourced pine of wood_species)
    assert wood.knot_counts() == {"live": 1, "dead": 1}


def test_rings_laid_after_death_are_trunk_wood_around_the_knot(mixed):
    vd = mixed.gm.volume_data
    death_step = 2 * 4
    mine = (vd["axis"] == 2) & (vd["cell"] > 0)
    later = mine & (vd["born"] > death_step)
    assert later.sum() > 100
    assert not np.any(vd["wood"][later] == C["knot"])  # no knot wood after death
    later_wood = later & np.isin(vd["wood"], LATER)
    assert later_wood.sum() > 50 and vd["year"][later_wood].min() >= 4
    # each such ring cell is sewn to the trunk's cell of the same layer and the same year (on the
    # walls of its node's level: the levels below and above are older or younger, issue 39 (a))
    a, b = contacts(mixed)
    node = mixed.branches[1].level
    pair = later_wood[a] & (vd["axis"][b] == 0) & np.isin(vd["wood"][b], LATER) & (vd["level"][b] == node)
    assert pair.sum() > 0
    assert np.array_equal(vd["year"][a[pair]], vd["year"][b[pair]])
    assert np.array_equal(vd["cell"][a[pair]], vd["cell"][b[pair]])


def test_a_dead_knot_meets_later_wood_only_through_its_bark(mixed):
    """The choice: the boundary is sewn through a bark layer (the knot's bark at death), along the
    stub; over the stub's end (the cap, :meth:`Wood._cap_stub`) the later wood covers its wood."""
    vd = mixed.gm.volume_data
    a, b = contacts(mixed)
    dead_wood = (vd["dead"] == 1) & (vd["wood"] == C["knot"]) & (vd["cell"] > 0)
    later_wood = np.isin(vd["wood"], LATER) & (vd["year"] >= 4)
    cap = (vd["axis"] == 2) & (vd["level"] == mixed.caps[1][0])
    assert not np.any(dead_wood[a] & later_wood[b] & ~cap[b])
    assert np.all(vd["level"][a[dead_wood[a] & cap[b]]] == mixed.caps[1][0] - 1)  # the stub's end only
    # the bark ring: every stack of the dead knot keeps bark cells over its wood, and they meet later wood
    dead_bark = (vd["dead"] == 1) & (vd["wood"] == C["bark"])
    level0 = (vd["axis"] == 2) & (vd["level"] == 0)
    assert len(np.unique(vd["sector"][dead_bark & level0])) == 16
    assert np.any(dead_bark[a] & later_wood[b])
    # a live knot, by contrast, is sewn to later trunk wood (intergrown)
    live_wood = (vd["axis"] == 1) & (vd["wood"] == C["knot"])
    assert np.any(live_wood[a] & later_wood[b])


def test_one_solid_after_every_step_and_after_cuts():
    wood = W.grow_wood("pine", years=6, branches=[(1, 3), (2, 9), (2, 4)], branch_deaths={0: 2, 1: 4}, check_every_step=True)
    assert_solid(wood.gm)
    part = W.plank_map(wood.gm, [1, 0, 0], 0.004, 0.004)
    assert_solid(part)


def test_plank_map_of_a_dead_knot_is_one_solid(mixed):
    part = W.plank_map(mixed.gm, [1, 0, 0], 0.006, 0.004)
    assert_solid(part)


def test_facts_count_live_and_dead_knots(mixed):
    assert mixed.knot_counts() == {"live": 1, "dead": 1}
    grid = W.to_grid(mixed)
    slab = W.plank(grid, [1, 0, 0], 0.006, 0.004)
    facts = W.cut_facts(slab)
    assert (facts["knots"], facts["live_knots"], facts["dead_knots"]) == (2, 1, 1)
    smooth = W.plank(W.smooth_grid(mixed, grid), [1, 0, 0], 0.006, 0.004)  # the pictures' grid too
    assert W.knot_states(smooth) == (1, 1)
    nothing_dead = W.grow_wood("pine", years=7, branches=[(1, 0), (2, 1)], height=0.12)
    assert W.knot_states(W.plank(W.to_grid(nothing_dead), [1, 0, 0], 0.006, 0.004)) == (2, 0)


def test_json_counts_live_and_dead_knots(capsys):
    argv = ["wood", "--years", "6", "--set", "branches=4", "--set", "branch_life=2", "--json"]
    assert main(argv) == 0
    r = json.loads(capsys.readouterr().out)
    # branches born in years 1..4 (placed over 1..5) live 2 years: those born by year 3 are dead at 6
    assert r["branches"]["live"] + r["branches"]["dead"] == 4
    assert r["branches"]["dead"] >= 2 and (r["chi"], r["boundary_chi"]) == (1, 2)
    assert main(["wood", "--years", "4", "--set", "branch_life=-1"]) == 2


def test_branch_life_rule_and_dart_estimate():
    wood = W.grow_wood("pine", years=8, branches=3, branch_life=2)
    for b, br in enumerate(wood.branches):
        assert wood.death_year(b) == br.year + 2
        ax = wood.branch_axis[b]
        # the stub grew no level after death; a dead one has its cap on its end
        assert len(ax.levels) == min(2, 8 - br.year) + (b in wood.caps)
    assert wood.gm.n_darts == W.estimated_darts(wood.p, 8, [br.year for br in wood.branches])
    assert wood.knot_counts()["dead"] == sum(1 for br in wood.branches if br.year + 2 <= 7)
    long_stub = W.grow_wood("pine", years=8, branches=[(1, 2)], branch_levels=0, branch_deaths={0: 4})
    assert len(long_stub.branch_axis[0].levels) == 4  # years 1, 2, 3; none after death in year 4; the cap
    assert long_stub.caps == {0: (3, 3, 4)}  # on level 3, 3 cells a stack at death (its top level's)
    assert long_stub.gm.n_darts == W.estimated_darts(long_stub.p, 8, [1], [4])


def test_regrowing_a_branch_keeps_the_deaths(mixed):
    again = W.regrow_branch(mixed, 0, seed=5)
    assert again.knot_counts() == {"live": 1, "dead": 1} and again.branches[1].death == 4
    assert np.array_equal(again.gm.volume_data["dead"], mixed.gm.volume_data["dead"])


@pytest.mark.parametrize("deaths", [{0: 1}, {0: 0}, {3: 5}])
def test_bad_deaths_are_refused(deaths):
    with pytest.raises(ValueRefused):
        W.grow_wood("pine", years=5, branches=[(1, 2)], branch_deaths=deaths)


def test_no_ring_ends_on_a_level_boundary():
    """Across every level boundary a trunk wood cell is sewn to a cell of its own year.

    Cell ``i`` of level ``t`` is sewn to cell ``i + s`` of level ``t - 1``, ``s`` the levels' age
    difference in half-years (2, or 0 between a node and its internode), a knot's node included
    (:meth:`Wood._bridge`).  The exception is the cone apex: the older level's cells ``1..s``
    (the year before level ``t`` existed) end on level ``t``'s first cell.
    """
    wood = W.grow_wood("pine", years=6, branches=[(2, 3)])
    vd = wood.gm.volume_data
    a, b = contacts(wood)
    trunk_wood = (vd["axis"] == 0) & np.isin(vd["wood"], LATER)
    across = trunk_wood[a] & trunk_wood[b] & (vd["level"][a] != vd["level"][b])
    upper = np.where(vd["level"][a] > vd["level"][b], a, b)
    lower = np.where(vd["level"][a] > vd["level"][b], b, a)
    apex = (vd["cell"][upper] == 1) & (vd["cell"][lower] <= 2) & (vd["year"][lower] == vd["year"][upper] - 1)
    assert across.sum() > 100 and (across & apex).sum() > 0
    rest = across & ~apex
    assert np.array_equal(vd["year"][a[rest]], vd["year"][b[rest]])
    # the node carrying the knot (level 2) is glued by year too: its first cells end the cones below
    node = wood.branches[0].level
    assert np.any(rest & (vd["level"][upper] == node) & (vd["level"][lower] == node - 1))
    assert np.any(across & apex & (vd["level"][upper] == node))


def enclosed_bark(wood, grid, b, out, step=1 / 80):
    """Area (in R^2) of the bark, other than a dead knot's own, that a flat-sawn section ``out`` R
    from the pith through knot ``b`` shows with no air beside it: bark inside the wood."""
    from scipy import ndimage

    vd, radius = wood.gm.volume_data, wood.trunk_radius()
    base, frame = wood.branch_frame(wood.branches[b], knot=True)
    side = 1.0 if frame[0][0] > 0 else -1.0  # the knot faces +x or -x
    x = side * out * radius
    zc = base[2] + out * radius * frame[0][2] / abs(frame[0][0])
    y = np.arange(-1.2, 1.2, step) * radius
    z = zc + np.arange(-1.5, 1.5, step) * radius
    yy, zz = np.meshgrid(y, z)
    cell = grid.find_containing_cell(np.stack([np.full(yy.size, x), yy.ravel(), zz.ravel()], 1))
    owner = np.asarray(grid.cell_data["volume"])[np.maximum(cell, 0)]
    air = (cell < 0).reshape(yy.shape)
    bark = (~air.ravel() & (vd["wood"][owner] == C["bark"]) & (vd["dead"][owner] == 0)).reshape(yy.shape)
    regions, _ = ndimage.label(ndimage.binary_dilation(bark, iterations=2))  # a thin band sampled in pieces is one
    open_air = np.unique(regions[bark & ndimage.binary_dilation(air, iterations=3)])
    return float((bark & ~np.isin(regions, open_air)).sum() * step * step)


@pytest.mark.parametrize("species", ["pine", "oak"])
def test_no_bark_lies_inside_the_wood_beside_a_knot(species):
    """Flat-sawn boards through a live and a dead knot show bark only at the board's edges or as
    the dead knot's lining: the upper wall's bark does not follow a rising knot into the trunk.

    Before the fix the wall above each knot sagged along the knot's section, and boards 0.6 R
    from the pith showed a wedge of the trunk's bark over the knot (0.06 R^2 in oak's dead knot,
    0.11 R^2 over pine's live knot).
    """
    wood = W.grow_wood(species, years=12, branches=[(3, 0), (2, 8)], branch_deaths={1: 4}, height=0.3)
    grid = W.to_grid(wood)
    areas = {(b, out): enclosed_bark(wood, grid, b, out) for b in (0, 1) for out in (0.45, 0.6, 0.75)}
    assert max(areas.values()) == 0.0, areas
    # the sampling sees bark: the boards' edges and the dead knot's lining are there
    vd = wood.gm.volume_data
    assert np.any((vd["dead"] == 1) & (vd["wood"] == C["bark"]))


@pytest.fixture(scope="module")
def occluded():
    # the brief's case: a pine grown 12 years, its branch born in year 2 dies in year 4
    return W.grow_wood("pine", years=12, branches=[(3, 0), (2, 8)], branch_deaths={1: 4}, height=0.3)


def boundary_volumes(gm):
    """Volumes with a face on the boundary (an alpha3-free dart)."""
    free = np.flatnonzero(gm.alpha[3][: gm.n_darts] == np.arange(gm.n_darts))
    return np.unique(gm.dart_volume[free])


def test_later_rings_close_over_a_dead_stubs_end(occluded):
    """Occlusion (issue 39 section 2): the cap's cells of later years cover the stub's end face, so
    no face of the dead knot is on the boundary, and its length stays what it was at death."""
    wood, gm = occluded, occluded.gm
    vd = gm.volume_data
    ax = wood.branch_axis[1]
    cap, c, died = wood.caps[1]
    assert (cap, died) == (2, 4) and len(ax.levels) == 3  # the knot, the stub (year 3), the cap
    assert c == 3  # the stub (born in year 3) held 3 cells a stack at death in year 4
    dead = np.flatnonzero(vd["dead"] == 1)
    assert dead.size and not np.isin(dead, boundary_volumes(gm)).any()
    # the end face: the stub's top pith E face and its cells' C3 faces are all sewn to cap volumes
    on_cap = (vd["axis"] == 2) & (vd["level"] == cap)
    a, b = contacts(wood)
    end = (vd["dead"][a] == 1) & on_cap[b]
    top = (vd["axis"] == 2) & (vd["level"] == cap - 1) & (vd["dead"] == 1)
    assert set(np.unique(a[end])) == set(np.flatnonzero(top))  # every dead cell of the end, and its pith
    # the cap: a pith prism and per stack c cells at death then 3 a year, all later wood or bark
    cells = on_cap & (vd["cell"] > 0)
    assert cells.sum() == 16 * (c + 3 * (12 - died))
    cap_wood = cells & np.isin(vd["wood"], LATER)
    assert np.all(vd["born"][on_cap] >= 2 * died) and np.all(vd["year"][cap_wood] >= died)
    assert np.array_equal(np.unique(vd["year"][cap_wood]), np.arange(died, 12))  # a ring a year since death
    assert not np.any(vd["wood"][on_cap] == C["knot"])
    # rings continue over the end: each cap cell over a ring laid after death (past the dead knot's
    # `held` cells) meets the stub's cell of its layer: same ring, same year
    held = int(wood.dead[1][1][cap - 1])
    pair = cells[b] & (vd["level"][a] == cap - 1) & (vd["axis"][a] == 2) & (vd["dead"][a] == 0)
    assert np.array_equal(vd["cell"][a[pair]], vd["cell"][b[pair]])
    assert np.array_equal(vd["year"][a[pair]], vd["year"][b[pair]])
    assert len(np.unique(b[pair])) == 16 * (c + 3 * (12 - died) - held)
    # the stub's end stays where it was: the stub keeps its level length, the cap lies beyond it
    wood.embed()
    _, pos = gm.vertex_positions()
    o, f, h = wood.level_frames(ax)
    end = int(gm.prism_face(ax.levels[cap - 1], ax.sides, "E"))  # a dart of the stub's end face
    end_s = float((pos[gm.cells(0)[0][end]] - o[cap - 1]) @ f[cap - 1, 0] - h[cap - 1])
    assert abs(end_s) < 1e-9 * h[cap - 1]


def test_the_cap_closes_in_nested_cones(occluded):
    """In a cut along the stub, each later ring turns over the end: its cap cells rise with their
    radius on the stub (an outer ring closes farther out), and every cap cell has positive volume."""
    from ramure.gmap.kernel import measure

    wood, gm = occluded, occluded.gm
    wood.embed()
    vd = gm.volume_data
    cap, c, _ = wood.caps[1]
    vol = measure.volumes(gm)
    on_cap = (vd["axis"] == 2) & (vd["level"] == cap)
    assert vol[on_cap].min() > 0
    ax = wood.branch_axis[1]
    _, pos = gm.vertex_positions()
    vid, _ = gm.cells(0)
    o, f, h = wood.level_frames(ax)
    tip = []
    for i in range(c + 1, int(vd["cell"][on_cap].max()) + 1):
        darts = ax.cells[cap, :, i - 1]
        top = pos[vid[darts + 40]]  # a dart of each cell's C4 face (its side), its height over the end
        tip.append(float(((top - o[cap - 1]) @ f[cap - 1, 0]).max()))
    assert np.all(np.diff(tip) > 0)  # nested: each ring's cone reaches farther over the end


@pytest.mark.parametrize("species", ["pine", "larch", "elm", "oak"])
def test_every_species_has_a_live_intergrown_knot_and_a_dead_encased_one(species):
    """The gallery's knot cuts for each species (``plot_wood_species.knot_cuts``): the lower branch
    lives, its knot wood sewn to the trunk's later wood; the upper one dies in year 7, its knot
    lined with its bark on all 16 sides and meeting later wood only through it (or over its
    stub's end, the cap)."""
    wood = W.grow_wood(species, years=12, branches=[(3, 0), (4, 1)], branch_deaths={1: 7}, height=0.3)
    assert wood.knot_counts() == {"live": 1, "dead": 1}
    vd = wood.gm.volume_data
    a, b = contacts(wood)
    later_wood = np.isin(vd["wood"], LATER) & (vd["year"] >= 7) & (vd["axis"] == 0)
    live_wood = (vd["axis"] == 1) & (vd["wood"] == C["knot"])
    assert np.any(live_wood[a] & later_wood[b])
    dead_wood = (vd["dead"] == 1) & (vd["wood"] == C["knot"]) & (vd["cell"] > 0)
    cap = (vd["axis"] == 2) & (vd["level"] == wood.caps[1][0])
    assert not np.any(dead_wood[a] & later_wood[b] & ~cap[b])
    dead_bark = (vd["dead"] == 1) & (vd["wood"] == C["bark"]) & (vd["axis"] == 2) & (vd["level"] == 0)
    assert len(np.unique(vd["sector"][dead_bark])) == 16
    assert np.any(dead_bark[a] & later_wood[b])
