"""Branches of every order become wood: a branch on a branch is a knot in its host's wood."""

import json

import numpy as np
import pytest

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.topology import assert_solid
from ramure.gmap.organs import wood as W

#: a first-order branch (year 1, sector 0) carrying a second-order one (year 2, its sector 5)
ON_A_BRANCH = [(1, 0), (2, 5, 0)]


def _estimate(w):
    return W.estimated_darts(
        w.p, w.final_years, [b.year for b in w.branches], [b.death for b in w.branches], [b.parent for b in w.branches]
    )


@pytest.fixture(scope="module")
def forked():
    return W.grow_wood("pine", years=5, branches=ON_A_BRANCH, check_every_step=True)


@pytest.fixture(scope="module")
def plant():
    from ramure.lsys import LSystem

    d = LSystem.from_file("abop_tree").derive(n=5)
    sk = d.skeleton()
    return sk, d, W.from_skeleton(sk, 5, leaf_steps=d.tree.step, steps=d.n)


@pytest.mark.parametrize(
    "branches, params",
    [
        (ON_A_BRANCH, {}),
        ([(1, 0), (2, 5, 0), (2, 9, 0)], {}),  # two sub-branches on one node
        ([(1, 0), (1, 8), (2, 5, 0), (2, 0, 1)], {}),  # sub-branches on two hosts of one trunk node
        ([(1, 0), (2, 5, 0), (3, 3, 0), (4, 2, 2)], {"branch_levels": 0}),  # whole branches, third order
    ],
)
def test_branches_on_branches_keep_one_solid_and_the_exact_dart_count(branches, params):
    w = W.grow_wood("pine", years=6, branches=branches, check_every_step=True, **params)
    assert_solid(w.gm)  # valid, chi = 1, boundary chi = 2 (after every step, too)
    assert w.gm.n_darts == _estimate(w)
    orders = W.branch_orders(w.branches)
    assert w.knot_orders() == {str(o): orders.count(o) for o in sorted(set(orders))}


def test_a_sub_branch_is_a_knot_in_its_hosts_node(forked):
    w = forked
    host = w.branch_axis[0]
    # the host grew a node and an internode in the sub-branch's year (2), after its knot (year 1);
    # the stub of branch_levels = 2 years then stops
    assert host.parts == [(1, "whole"), (2, "node"), (2, "internode")]
    assert w.branches[1].level == 1 and not host.alive[1, 5] and host.alive[1].sum() == host.sides - 1
    assert not w.trunk.parts.count((2, "node"))  # the trunk grows no node for a branch's branch
    vd = w.gm.volume_data
    knot = (vd["axis"] == 2) & (vd["level"] == 0) & (vd["cell"] > 0)
    wood = knot & (vd["season"] >= 0)
    assert sorted(set(vd["year"][wood].tolist())) == [2, 3, 4]  # born in year 2 of 5: 3 rings
    # each knot ring cell is sewn to the host's slot walls, never to the trunk
    gm = w.gm
    a3 = gm.alpha[3][: gm.n_darts]
    d = np.flatnonzero(np.isin(gm.dart_volume[: gm.n_darts], np.flatnonzero(knot)))
    across = gm.dart_volume[a3[d]][a3[d] != d]
    others = np.unique(vd["axis"][across])
    assert set(others.tolist()) == {1, 2}  # its own axis and its host's (axis 1), not the trunk (0)
    # the knot starts on the host's pith and runs out past the host's bark
    o, f, h = w.level_frames(host)
    _, pos = gm.vertex_positions()
    base, frame = w.branch_frame(w.branches[1], knot=True)
    assert np.linalg.norm(base - (o[1] + 0.5 * h[1] * f[1, 0])) == pytest.approx(w.pith_apothem(host))
    assert w.knot_length(w.branches[1]) >= w.host_radius(w.branches[1]) - w.pith_apothem(host)


def test_knots_next_to_their_hosts_knot_are_not_torn(forked):
    # the node next to the host's knot cuts the knot's (exclusive) edges; their corners were read
    # from unset rows and pulled the knots' piths 0.1 m long (knots 0.04 m long)
    w = forked
    gm, vd = w.gm, w.gm.volume_data
    vid, pos = gm.vertex_positions()
    dv = gm.dart_volume[: gm.n_darts]
    for b, br in enumerate(w.branches):
        pith = int(np.flatnonzero((vd["axis"] == b + 1) & (vd["level"] == 0) & (vd["cell"] == 0))[0])
        size = np.linalg.norm(np.ptp(pos[vid[np.flatnonzero(dv == pith)]], axis=0))
        assert size < w.knot_length(br) + 10 * w.pith_apothem(w.branch_axis[b])


@pytest.mark.parametrize(
    "branches, params, words",
    [
        ([(1, 0), (3, 5, 0)], {}, "stub of 2 levels"),  # branch_levels = 2: the host stops in year 2
        ([(2, 5, 1), (1, 0)], {}, "listed before"),
        ([(1, 0), (1, 5, 0)], {}, "after its host's year"),
        ([(1, 0), (2, 5, 0)], {"branch_life": 1}, "dies in year 2"),
        ([(1, 0), (2, 16, 0)], {}, "sector in 0..15"),
    ],
)
def test_a_host_that_cannot_carry_the_branch_is_refused(branches, params, words):
    with pytest.raises(ValueRefused, match=words):
        W.grow_wood("pine", years=5, branches=branches, **params)
    assert W.grow_wood("pine", years=5, branches=[(1, 0), (3, 5, 0)], branch_levels=0).gm.is_valid()


def test_wood_of_a_plant_has_knots_of_every_order_with_their_birth_years(plant):
    sk, d, w = plant
    assert_solid(w.gm)
    assert w.knot_orders() == {"1": 3, "2": 2, "3": 1}
    assert w.gm.n_darts == _estimate(w)
    parent, order = np.asarray(sk.parent), np.asarray(sk.order)
    steps = np.asarray(d.tree.step)[np.asarray(sk.leaf_id)]
    segments = w.gm.meta["branch_segments"]
    vd = w.gm.volume_data
    for b, br in enumerate(w.branches):
        seg = segments[b]
        # closed check from the skeleton: born in the year of the step that made the segment it grows from
        assert br.year == min(4, steps[parent[seg]] * 5 // d.n)
        assert order[seg] == W.branch_orders(w.branches)[b]
        if br.parent >= 0:  # it grows on its host's axis: the segment it starts from continues the host's
            s = int(parent[seg])
            while s != segments[br.parent] and order[parent[s]] == order[s]:
                s = int(parent[s])
            assert s == segments[br.parent]
            assert w.branches[br.parent].year < br.year
        knot = (vd["axis"] == b + 1) & (vd["level"] == 0) & (vd["season"] >= 0)
        assert len(np.unique(vd["year"][knot])) == 5 - br.year  # its age from the derivation
    leaves = [x for own in w.gm.meta["branch_leaves"] for x in own]
    assert len(leaves) == len(set(leaves)) > 0  # each plant leaf picks one knot: the deepest branch's it grows on
    # a sub-branch born after its host's stub ended is left out and counted, with what grows on it
    left = w.gm.meta["left_out"]
    assert left["beyond_stub"] == 1 and left["on_left_out"] == 1
    whole = W.from_skeleton(sk, 5, leaf_steps=d.tree.step, steps=d.n, branch_levels=0)
    # whole branches (branch_levels = 0) carry it; the one on it is born in the last year, without rings
    assert whole.knot_orders() == {"1": 3, "2": 3, "3": 1}
    assert whole.gm.meta["left_out"] == {**left, "beyond_stub": 0, "on_left_out": 0, "last_year": left["last_year"] + 1}


def test_a_cut_through_a_first_order_branch_shows_its_second_order_knot(plant):
    _, _, w = plant
    b = next(i for i, br in enumerate(w.branches) if br.parent >= 0)
    host = w.branches[w.branches[b].parent]
    (_, f_host), (o_sub, f_sub) = w.branch_frame(host), w.branch_frame(w.branches[b])
    normal = np.cross(f_host[0], f_sub[0])  # the plane of both axes
    normal /= np.linalg.norm(normal)
    grid = W.to_grid(w)
    slab = W.plank(grid, normal, float(normal @ o_sub) - 0.002, 0.004)
    axis = np.asarray(slab.cell_data["axis"])
    level = np.asarray(slab.cell_data["level"])
    tissue = np.asarray(slab.cell_data["wood"])
    sub_knot = (axis == b + 1) & (level == 0)
    assert np.count_nonzero(sub_knot & (tissue == W.CODES["knot"])) > 20  # the knot's wood, in rings
    ring, year = np.asarray(slab.cell_data["ring"]), np.asarray(slab.cell_data["year"])
    age = 5 - w.branches[b].year  # every ring of the knot, each laid in its year, shows in the board
    assert set(ring[sub_knot & (ring > 0)].tolist()) == set(range(1, age + 1))
    assert set(year[sub_knot & (ring > 0)].tolist()) == set(range(w.branches[b].year, 5))
    host_cells = axis == w.branches[b].parent + 1
    assert np.count_nonzero(host_cells & (level >= 1)) > 20  # cut along its host past the trunk's bark


def test_cli_counts_knots_by_order_and_refuses_over_the_dart_limit(capsys, monkeypatch):
    from ramure.app.cli import main

    assert main(["wood", "--from-plant", "abop_tree", "-n", "5", "--years", "5", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["knots_by_order"] == {"1": 3, "2": 2, "3": 1} and record["branches"]["live"] == 6
    assert record["left_out"]["beyond_stub"] == 1 and record["valid"] and record["chi"] == 1
    assert main(["wood", "--from-plant", "abop_tree", "-n", "5", "--years", "5"]) == 0
    assert "(by order 1: 3, 2: 2, 3: 1)" in capsys.readouterr().out
    monkeypatch.setattr(W, "MAX_DARTS", 100_000)
    assert main(["wood", "--from-plant", "abop_tree", "-n", "5", "--years", "5"]) == 2
    err = capsys.readouterr().err
    assert "more than the limit of 100,000" in err and "3 of order 1, 2 of order 2, 1 of order 3" in err


def test_without_derivation_steps_a_branch_is_born_by_its_place_on_its_host(plant):
    sk, _, _ = plant
    w = W.from_skeleton(sk, 6, branch_levels=0)  # years from heights on the trunk, places along hosts
    assert_solid(w.gm)
    orders = W.branch_orders(w.branches)
    assert w.knot_orders() == {"1": 3, "2": 6, "3": 4, "4": 1} and w.gm.n_darts == _estimate(w)
    assert orders == sorted(orders)  # order by order: a host is listed before its branches
    for br in w.branches:
        if br.parent >= 0:  # on the year's shoot of its host, after the host's birth, before the last year
            assert w.branches[br.parent].year < br.year < 5
