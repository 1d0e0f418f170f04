"""Botanical architecture: the AMAP tables, the Hallé–Oldeman models, MTG and the scheduler."""

from __future__ import annotations

import numpy as np
import pytest

import ramure
from ramure.errors import GrammarError, ValueRefused
from ramure.lsys.architecture.amap import architecture, grown_by
from ramure.lsys.architecture.mtg import MTGError, mtg_text, parse_mtg
from ramure.lsys.architecture.schedule import KINDS, EventScheduler

MODELS = ["attims", "champagnat", "corner", "leeuwenberg", "massart", "rauh", "troll"]


@pytest.fixture(scope="module", params=MODELS)
def model(request):
    derivation = ramure.derive(f"amap/{request.param}")
    return request.param, derivation, architecture(derivation)


def test_every_model_is_shipped_and_grows_a_tree(model):
    name, derivation, arch = model
    assert f"amap/{name}" in ramure.grammars.names()
    skeleton = derivation.skeleton()
    assert len(skeleton) == len(arch.internodes)  # every drawn segment is an internode
    assert np.ptp(skeleton.end[:, 2]) > 1.0  # it stands up


def test_containment_is_a_tree(model):
    _, _, arch = model
    inter, units, shoots = arch.internodes, arch.growth_units, arch.shoots
    assert units.count.sum() == len(inter) and shoots.count.sum() == len(units)
    assert np.array_equal(units.axis[inter.growth_unit], inter.axis)
    assert np.array_equal(units.shoot[inter.growth_unit], inter.shoot)
    assert np.array_equal(shoots.axis[units.shoot], units.axis)
    assert (units.count >= 1).all() and np.array_equal(inter.growth_unit[units.first], np.arange(len(units)))
    for unit in range(len(units)):  # ranks run 0..count-1 in string order inside each unit
        assert inter.rank[inter.growth_unit == unit].tolist() == list(range(units.count[unit]))


def test_bearers_are_internodes_of_the_parent_axis(model):
    _, _, arch = model
    axes, inter = arch.axes, arch.internodes
    assert axes.parent[0] == -1 and axes.bearer[0] == -1 and axes.order[0] == 1
    branches = np.arange(1, len(axes))
    assert (axes.bearer[branches] >= 0).all()
    assert np.array_equal(inter.axis[axes.bearer[branches]], axes.parent[branches])
    assert (axes.parent[branches] < branches).all()  # parents come first: no cycle
    assert np.array_equal(axes.order[branches], axes.order[axes.parent[branches]] + 1)
    # a bearer comes before the first internode of the axis it bears in the string
    node_pos = {int(n): i for i, n in enumerate(inter.node)}
    assert all(node_pos[int(inter.node[axes.bearer[a]])] < node_pos[int(inter.node[axes.first[a]])] for a in branches)


def test_mtg_round_trip_is_exact(model):
    _, _, arch = model
    again = parse_mtg(mtg_text(arch))
    assert again.equals(arch)


def test_pruning_an_axis_removes_exactly_its_subtree(model):
    _, _, arch = model
    if len(arch.axes) < 3:  # Corner's palm is unbranched: only the trunk, which stays
        with pytest.raises(ValueRefused, match="trunk cannot be pruned"):
            arch.prune(0)
        return
    axis = int(np.argmax(np.bincount(arch.axes.parent[1:], minlength=len(arch.axes))))  # a branch with branches
    axis = max(axis, 1)
    pruned = arch.prune(axis)
    gone = set(arch.subtree_nodes(axis).tolist())
    assert set(pruned.internodes.node.tolist()) == set(arch.internodes.node.tolist()) - gone
    assert len(pruned.axes) == len(arch.axes) - len(arch.subtree_axes(axis))
    assert parse_mtg(mtg_text(pruned)).equals(pruned)
    assert parse_mtg(mtg_text(arch)).prune(axis).equals(pruned)


def test_deterministic_models_grow_one_growth_unit_a_year():
    derivation = ramure.derive("amap/massart")
    arch, steps = architecture(derivation), derivation.tree.step
    first_step = steps[arch.internodes.node[arch.axes.first]]
    units_per_axis = np.bincount(arch.growth_units.axis, minlength=len(arch.axes))
    assert np.array_equal(units_per_axis, derivation.n - first_step + 1)
    assert units_per_axis[0] == derivation.n == 8
    corner = architecture(ramure.derive("amap/corner", n=5))
    assert corner.counts() == {"axes": 1, "annual_shoots": 5, "growth_units": 5, "internodes": 15}


def test_stochastic_internodes_per_growth_unit_follow_the_law():
    """Rauh's units have 2, 3 or 4 internodes with probabilities 1/4, 1/2, 1/4 (mean 3, sd 1/sqrt 2).

    2,500 seeds at n = 3 give over 10,000 units (every unit draws its size independently).
    """
    lsystem = ramure.load("amap/rauh")
    sizes = np.concatenate([architecture(lsystem.derive(n=3, seed=seed)).growth_units.count for seed in range(2_500)])
    assert len(sizes) >= 10_000 and set(np.unique(sizes).tolist()) == {2, 3, 4}
    standard_error = np.sqrt(0.5) / np.sqrt(len(sizes))
    assert abs(sizes.mean() - 3.0) < 3 * standard_error
    assert abs(np.mean(sizes == 3) - 0.5) < 3 * np.sqrt(0.25 / len(sizes))


def test_events_are_counted_from_the_history():
    arch = architecture(ramure.derive("amap/rauh", seed=3))
    tree = ramure.derive("amap/rauh", seed=3).tree
    assert arch.events["internode"] == len(arch.internodes)  # internodes are never rewritten here
    assert arch.events["death"] > 0 and arch.events["growth_unit"] >= len(arch.growth_units)
    assert arch.events == architecture(ramure.derive("amap/rauh", seed=3)).events and len(tree) > 0


def test_models_work_with_regrowth_and_metrics():
    session = ramure.Session(ramure.load("amap/rauh"), n=6)
    before = architecture(session.derivation)
    tips = before.subtree_nodes(len(before.axes) - 1).tolist()
    session.regrow(tips, seed=7)
    after = architecture(session.derivation)
    assert after.counts()["internodes"] > 0
    assert ramure.plant_metrics(session.derivation.skeleton()).branch_count == len(after.internodes)


@pytest.mark.parametrize(
    "line, column, message",
    [
        ("#amap bogus F", 7, "unknown #amap role 'bogus'"),
        ("#amap internode G", 17, "never writes a module 'G'"),
        ("#amap internode", 7, "takes a role and one or more modules"),
    ],
)
def test_bad_annotations_name_line_and_column(line, column, message):
    with pytest.raises(GrammarError) as err:
        ramure.LSystem.from_text(f"{line}\nn: 1\nw: F\n")
    assert err.value.line == 1 and err.value.column == column and message in str(err.value)


def test_a_grammar_without_internodes_is_refused():
    with pytest.raises(ValueRefused, match="names no internode"):
        architecture(ramure.LSystem.from_text("n: 1\nw: F\n").derive())


def test_mtg_with_unknown_scale_or_bearer_cycle_is_refused():
    text = mtg_text(architecture(ramure.derive("amap/massart", n=3)))
    with pytest.raises(MTGError, match="unknown class or scale 'Q'"):
        parse_mtg(text.replace("^/U1", "^/Q1", 1))
    # give a branch's bearer the node id of an internode of the branch itself: a bearer cycle
    lines = text.splitlines()
    plus = next(i for i, line in enumerate(lines) if line.lstrip("\t").startswith("+A"))
    bearer_line = plus - 1
    own = next(line for line in lines[plus + 1 :] if line.lstrip("\t").startswith("^/I1"))
    lines[bearer_line] = lines[bearer_line].rsplit("\t", 1)[0] + "\t" + own.rsplit("\t", 1)[1]
    with pytest.raises(MTGError, match="cycle|node"):
        parse_mtg("\n".join(lines))


def test_same_tick_lists_ascend_by_order_with_seeded_ties():
    def lists(seed):
        s = EventScheduler(seed=seed)
        rng = np.random.default_rng(0)
        s.add(dates=rng.uniform(0, 3, 400), kinds=rng.integers(0, 4, 400), orders=rng.integers(1, 4, 400), nodes=np.arange(400))
        return [(tick, kind, nodes.copy()) for tick, kind, nodes, _ in s.run()]

    first, again, other = lists(1), lists(1), lists(2)
    rng = np.random.default_rng(0)  # the same draws as in lists(): dates, kinds, then orders
    rng.uniform(0, 3, 400), rng.integers(0, 4, 400)
    orders = rng.integers(1, 4, 400)
    for _tick, _kind, nodes in first:
        assert (np.diff(orders[nodes]) >= 0).all()
    assert all(np.array_equal(a[2], b[2]) for a, b in zip(first, again))
    assert any(not np.array_equal(a[2], b[2]) for a, b in zip(first, other))
    ticks_and_lists = [(t, KINDS.index(k)) for t, k, _ in first]
    assert ticks_and_lists == sorted(ticks_and_lists)


def test_dead_nodes_drop_events_and_paused_nodes_wait():
    s = EventScheduler()
    s.add(dates=[0.1, 0.2, 0.3], kinds="internode", orders=[1, 1, 1], nodes=[0, 1, 2])
    s.set_state([1], "dead")
    s.set_state([2], "paused")
    seen = []
    for tick, _kind, nodes, _ in s.run():
        seen.append((tick, nodes.tolist()))
        if tick == 0:
            s.set_state([2], "active")
    assert seen == [(0, [0]), (1, [2])]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"dates": [-1.0]}, "finite and >= 0"),
        ({"dates": [float("nan")]}, "finite and >= 0"),
        ({"kinds": ["flower"]}, "unknown event kind"),
        ({"orders": [0]}, "orders start at 1"),
    ],
)
def test_bad_events_are_refused(kwargs, message):
    args = {"dates": [1.0], "kinds": ["internode"], "orders": [1], "nodes": [0], **kwargs}
    with pytest.raises(ValueRefused, match=message):
        EventScheduler().add(**args)


def test_command_line_prints_the_tables_and_writes_an_mtg(tmp_path):
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "ramure.app.cli",
            "amap",
            "amap/massart",
            "-n",
            "5",
            "--json",
            "--at",
            "2",
            "--mtg",
            str(tmp_path / "m.mtg"),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["axes_per_order"] == {"1": 1, "2": 12} and facts["growth_units"] == 5 + 3 * (4 + 3 + 2 + 1)
    assert facts["internodes_per_growth_unit"] == {"2": 30, "3": 5}
    assert facts["at"]["internodes"] == 3 + 3 + 3 * 2  # two trunk units and the first tier's first year
    again = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "mtg", str(tmp_path / "m.mtg")], capture_output=True, text=True, cwd=tmp_path
    )
    assert json.loads(again.stdout)["internodes"] == facts["internodes"]
    bad = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "amap", "amap/massart", "--mtg", "x.txt"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert bad.returncode == 2 and "must end with .mtg" in bad.stderr and "Traceback" not in bad.stderr


def test_replaying_the_growth_through_the_scheduler():
    derivation = ramure.derive("amap/rauh", seed=2)
    arch = architecture(derivation)
    steps = derivation.tree.step[arch.internodes.node]
    for year in range(derivation.n + 1):  # after year k, exactly the internodes made by step k
        grown = grown_by(derivation, arch, float(year))
        assert sorted(grown["internodes"].tolist()) == sorted(arch.internodes.node[steps <= year].tolist())
    middle = grown_by(derivation, arch, 3.5, seed=1)
    order_of = dict(zip(arch.internodes.node.tolist(), arch.axes.order[arch.internodes.axis].tolist()))
    tick_three = [n for n in middle["internodes"].tolist() if 3 < derivation.tree.step[n] <= 4]
    assert tick_three and all(order_of[a] <= order_of[b] for a, b in zip(tick_three, tick_three[1:]))
    assert grown_by(derivation, arch, 3.5, seed=1)["internodes"].tolist() == middle["internodes"].tolist()
    with pytest.raises(ValueRefused, match="finite and >= 0"):
        grown_by(derivation, arch, -1.0)
