"""Properties of selective regeneration, undo/redo and JSON sessions on shipped grammars."""

from __future__ import annotations

import copy
import json
import pathlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ramure.lsys import LSystem, RamureError
from ramure.lsys.regeneration.regen import Session

ROOT = pathlib.Path(__file__).parents[2]
CASES = {
    "honda_sympodial": 6,
    "fruit_tree": 4,
    "context_plant": 12,
    "stochastic_plant": 4,
    "plant_1_24a": 3,
    "branche_stochastic": 4,
}
_SESSIONS = {}


def _fresh(name):
    if name not in _SESSIONS:
        _SESSIONS[name] = Session(LSystem.from_file(ROOT / "grammars" / f"{name}.lsys"), n=CASES[name])
    return Session.from_dict(copy.deepcopy(_SESSIONS[name].to_dict()))


def _snapshot(session):
    tree = session.tree
    leaves = tree.leaves.copy()
    return leaves, tree.symbol[leaves].copy(), tree.params[leaves].copy(), session.derivation.to_string()


def _balanced(session):
    ls = session.lsystem
    syms = session.tree.symbol[session.tree.leaves]
    opens, closes = ls.bracket_ids
    if opens is None:
        return True
    depth = np.cumsum((syms == opens).astype(int) - (syms == closes))
    return depth.size == 0 or (depth.min() >= 0 and depth[-1] == 0)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(sorted(CASES)),
    picks=st.lists(st.integers(0, 10**6), min_size=1, max_size=6),
    rho=st.sampled_from([0.05, 0.3, 0.5, 1.0]),
    min_ascend=st.integers(0, 3),
    prune=st.booleans(),
    seed=st.integers(0, 2**32),
)
def test_regrow_keeps_everything_outside_and_undo_redo_are_exact(name, picks, rho, min_ascend, prune, seed):
    s = _fresh(name)
    leaves0, syms0, params0, text0 = _snapshot(s)
    selection = sorted({int(leaves0[p % len(leaves0)]) for p in picks})
    if prune:
        result = s.prune(selection, rho=rho, min_ascend=min_ascend)
    else:
        result = s.regrow(selection, rho=rho, min_ascend=min_ascend, seed=seed)
    tree = s.tree
    regrown = set(result.change.removed.tolist())  # the old subtrees of the roots
    # every module outside the regrown subtrees keeps its node id, symbol and parameters
    new_leaves = tree.leaves
    kept = [v for v in leaves0.tolist() if v not in regrown]
    assert set(kept) <= set(new_leaves.tolist())
    pos0 = {v: i for i, v in enumerate(leaves0.tolist())}
    for v in kept:
        assert tree.symbol[v] == syms0[pos0[v]]
        np.testing.assert_array_equal(tree.params[v], params0[pos0[v]])
    # kept modules stay in the same order
    order = [v for v in new_leaves.tolist() if v in pos0 and v not in regrown]
    assert order == kept
    assert _balanced(s)
    after = _snapshot(s)
    # the session replays to the identical string
    assert Session.from_dict(json.loads(json.dumps(s.to_dict()))).derivation.to_string() == after[3]
    s.undo()
    assert s.derivation.to_string() == text0
    np.testing.assert_array_equal(s.tree.leaves, leaves0)
    s.redo()
    assert s.derivation.to_string() == after[3]
    np.testing.assert_array_equal(s.tree.leaves, after[0])


def test_failed_regrow_leaves_the_tree_untouched():
    text = "#define k 100\nn: 5\nw: A(0)\np:\n A(x) -> B(x)[+A(x+1)]A(x+1)\n B(x) -> F(1/(x-k))\n"
    s = Session(LSystem.from_text(text))
    tree = s.tree
    before = (tree.size, tree.child_start.copy(), tree.child_count.copy(), s.derivation.to_string())
    spans = [a.copy() for a in tree.leaf_spans()]
    selection = s.leaves_with_symbol("A")[:1]
    with pytest.raises(RamureError, match="division by zero"):
        s.regrow(selection, constants={"k": 3}, min_ascend=3)  # fails a few steps down
    assert tree.size == before[0]
    np.testing.assert_array_equal(tree.child_start, before[1])
    np.testing.assert_array_equal(tree.child_count, before[2])
    assert s.derivation.to_string() == before[3] and not s.edits and not s.can_undo
    for a, b in zip(tree.leaf_spans(), spans):
        np.testing.assert_array_equal(a, b)
    s.regrow(selection, min_ascend=3, seed=4)  # still works, and undoes exactly
    s.undo()
    assert s.derivation.to_string() == before[3]


def test_refused_constants_change_nothing():
    s = Session(LSystem.from_text("#define k 1\nn: 3\nw: A(1)\np:\n A(x) -> F(x)[+A(x/k)]A(x)\n"))
    text = s.derivation.to_string()
    for values in ({"k": 0}, {"k": float("nan")}, {"k": "x"}, {"zz": 1}, {"k": None}):
        with pytest.raises(RamureError):
            s.set_constants(values)
        assert s.constants == {"k": 1.0} and s.derivation.to_string() == text and not s.edits


@pytest.mark.parametrize(
    "kwargs",
    [
        {"seed": -1},
        {"seed": 2**70},
        {"constants": {"r1": float("inf")}},
        {"params": {"rule": 99, "constants": {}}},
        {"params": {"rule": None, "constants": {"r1": float("nan")}}},
    ],
)
def test_bad_regrow_arguments_are_refused(kwargs):
    s = _fresh("honda_sympodial")
    text = s.derivation.to_string()
    with pytest.raises(RamureError):
        s.regrow(s.leaves_with_symbol("F")[-3:], **kwargs)
    assert s.derivation.to_string() == text and not s.edits


def test_ascend_levels_check_the_selection():
    s = _fresh("honda_sympodial")
    for selection in ([-1], [10**7], [0]):
        with pytest.raises(RamureError):
            s.regrow(selection, ascend_levels=2)
    with pytest.raises(RamureError):
        s.regrow(s.leaves_with_symbol("F")[-2:], ascend_levels=-1)


def _corrupt(data, path, value):
    out = copy.deepcopy(data)
    target = out
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return out


CORRUPTIONS = [
    (("n",), -1),
    (("n",), "7"),
    (("n",), True),
    (("n",), 10**9),
    (("seed",), -1),
    (("seed",), "x"),
    (("constants",), None),
    (("constants",), {"r1": float("nan")}),
    (("constants",), {"zz": 1}),
    (("edits",), None),
    (("edits",), [None]),
    (("grammar",), 5),
    (("grammar",), "garbage"),
    (("filename",), 5),
    (("format",), "x"),
    (("version",), 99),
    (("grammar",), KeyError),
    (("edits", 0, "op"), "explode"),
    (("edits", 0, "selection"), [-1]),
    (("edits", 0, "selection"), [0]),
    (("edits", 0, "selection"), [10**8]),
    (("edits", 0, "selection"), None),
    (("edits", 0, "selection"), [1.5]),
    (("edits", 0, "selection"), [True]),
    (("edits", 0, "seed"), -3),
    (("edits", 0, "seed"), 1.5),
    (("edits", 0, "seed"), 2**70),
    (("edits", 0, "rho"), 0),
    (("edits", 0, "rho"), [1]),
    (("edits", 0, "min_ascend"), "x"),
    (("edits", 0, "constants"), {"r1": "x"}),
    (("edits", 0, "constants"), [1]),
    (("edits", 0, "params"), [1]),
    (("edits", 0, "params"), {"rule": 99, "constants": {}}),
    (("edits", 0, "params"), {"rule": "x", "constants": {}}),
    (("edits", 0, "ascend"), -1),
    (("edits", 0, "ascend"), 1.5),
    (("edits", 0, "rho"), KeyError),
    (("edits", 1, "values"), {"r1": None}),
    (("edits", 1, "values"), {"zz": 1}),
    (("edits", 1, "values"), {"r1": "nan"}),
    (("edits", 2, "leaves"), [-5]),
    (("edits", 2, "leaves"), ["a"]),
    (("edits", 2, "settings"), None),
]


def _session_with_three_edits():
    s = Session(LSystem.from_file(ROOT / "grammars" / "fruit_tree.lsys"), n=4)
    s.regrow(s.leaves_with_symbol("F")[-3:], seed=1)
    s.set_constants({next(iter(s.lsystem.constants)): 1.0})
    s.regrow_fruit(s.leaves_with_symbol("Fruit")[:1], seed=2)
    return s


@pytest.fixture(scope="module")
def saved():
    return _session_with_three_edits().to_dict()


@pytest.mark.parametrize("path, value", CORRUPTIONS, ids=[f"{'.'.join(map(str, p))}={v!r}"[:40] for p, v in CORRUPTIONS])
def test_corrupt_session_dicts_are_refused(saved, path, value):
    first = next(iter(saved["constants"]))
    if isinstance(value, dict) and "r1" in value:  # use a constant this grammar defines
        value = {first: value["r1"]}
    data = _corrupt(saved, path, value)
    existing = _session_with_three_edits()
    before = existing.derivation.to_string(), copy.deepcopy(existing.edits)
    with pytest.raises(RamureError):
        Session.from_dict(data)
    assert (existing.derivation.to_string(), existing.edits) == before


def test_saved_session_replays(saved):
    assert Session.from_dict(copy.deepcopy(saved)).derivation.to_string() == _session_with_three_edits().derivation.to_string()


def test_save_to_a_directory_or_missing_folder_is_refused_and_leaves_no_tmp(tmp_path):
    s = _fresh("honda_sympodial")
    (tmp_path / "dir").mkdir()
    for target in (tmp_path / "dir", tmp_path / "missing" / "s.json"):
        with pytest.raises(RamureError, match="cannot save"):
            s.save(target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir"]
    assert list((tmp_path / "dir").iterdir()) == []
