"""The plain-Python turtle walk (short strings, no numba) gives the compiled walk's arrays bit for
bit, and a new process draws a small plant without loading numba (issue 34, a fast first call)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys.interpretation import turtle
from ramure.lsys.interpretation._turtle_kernel import bracket_pairs32
from ramure.lsys.interpretation._turtle_kernel import walk as compiled_walk
from ramure.lsys.interpretation._turtle_walk import FULL, REGION, SEEK, initial_state
from ramure.lsys.interpretation._turtle_walk import walk as plain_walk
from ramure.lsys.interpretation.polygons import _gather

# stochastic, context-sensitive, polygons, tropism and $, organs, surfaces and spheres, colours
GRAMMARS = [
    ("honda_sympodial", 10),
    ("stochastic_plant", None),
    ("context_plant", None),
    ("abop/bush_1_25", None),
    ("abop/plant_1_26", None),
    ("abop/cordate_leaf_5_5", None),
    ("apricot_tree", None),
    ("amap/attims", None),
    ("lily_of_the_valley", None),
    ("fruit_tree", None),
]


def _arrays(skeleton):
    """Every array a skeleton hands out, by name."""
    out = {
        name: getattr(skeleton, name)
        for name in ("start", "end", "base_radius", "top_radius", "order", "leaf_id", "color", "normal", "parent")
    }
    out.update({f"organs.{n}": getattr(skeleton.organs, n) for n in ("position", "frame", "size", "params", "leaf_id", "color")})
    out["organs.kind"] = skeleton.organs.kind.astype(str)
    out.update({f"polygons.{n}": getattr(skeleton.polygons, n) for n in ("leaf_id", "color", "offsets", "points")})
    trace = skeleton.extra["trace"]
    out.update({f"trace.{n}": getattr(trace, n) for n in ("acts", "nps", "segment_at", "organ_at", "polygon_at")})
    out["trace.balanced"] = np.array(trace.balanced)
    return out


def _skeleton(ls, d, compiled, monkeypatch):
    monkeypatch.setattr(turtle, "use_kernels", compiled)
    return turtle.interpret_string(ls, d.tree, d.tree.leaves)


@pytest.mark.parametrize(("name", "n"), GRAMMARS)
def test_the_plain_walk_gives_the_compiled_walks_arrays(name, n, monkeypatch):
    ls = LSystem.from_file(name)
    d = ls.derive(n=n, seed=5)
    plain, compiled = (_arrays(_skeleton(ls, d, c, monkeypatch)) for c in (False, True))
    assert plain.keys() == compiled.keys()
    for key, value in compiled.items():
        assert plain[key].dtype == value.dtype, key
        assert plain[key].shape == value.shape, key
        np.testing.assert_array_equal(plain[key], value, err_msg=key)  # bit for bit, NaN where NaN
    assert len(compiled["start"]) + len(compiled["organs.size"]) + len(compiled["polygons.points"]) > 20


def test_the_shared_cases_are_not_vacuous(monkeypatch):
    found = {}
    for name, n in GRAMMARS:
        ls = LSystem.from_file(name)
        sk = _skeleton(ls, ls.derive(n=n, seed=5), False, monkeypatch)
        found[name] = (len(sk), len(sk.organs), len(sk.polygons))
    assert found["abop/bush_1_25"][2] > 100 and found["amap/attims"][1] > 10 and found["honda_sympodial"][0] == 1023


def _walk_args(name):
    ls = LSystem.from_file(name)
    d = ls.derive(seed=1)
    leaves = turtle.node_ids(d.tree.leaves)
    acts, nps, _ = turtle.module_arrays(ls, d.tree, leaves)
    match = bracket_pairs32(acts, int(turtle.TurtleAction.PUSH), int(turtle.TurtleAction.POP))[0]
    angle, step, trop = turtle._settings(ls)
    return ls, d, leaves, acts, nps, match, angle, step, trop


@pytest.mark.parametrize("name", ["honda_sympodial", "abop/bush_1_25", "apricot_tree"])
def test_seek_and_region_walks_agree(name):
    # what an edit runs: walk to a module jumping over branches, then draw to the end of its branch
    ls, d, leaves, acts, nps, match, angle, step, trop = _walk_args(name)
    par = d.tree.params[:, 0]
    for a in np.linspace(1, len(acts) - 2, 7).astype(int):
        results = []
        for walk in (compiled_walk, plain_walk):
            state = initial_state(ls.grammar.width)
            walk(acts, nps, par, 0, a, match, SEEK, state, angle, step, trop, 0, leaves)
            seek_state = state.copy()
            stop, segs, orgs, poly, err = walk(acts, nps, par, a, len(acts), match, REGION, state, angle, step, trop, 0, leaves)
            results.append((seek_state, stop, segs, orgs, poly, err, state))
        (s1, stop1, *rest1), (s2, stop2, *rest2) = results
        np.testing.assert_array_equal(s1, s2)
        assert stop1 == stop2
        for x, y in zip(_flat(rest1), _flat(rest2)):
            assert x.dtype == y.dtype
            np.testing.assert_array_equal(x, y)


def _flat(parts):
    for part in parts:
        if isinstance(part, tuple):
            yield from _flat(part)
        else:
            yield np.asarray(part)


A = turtle.TurtleAction
# raw strings (action, first parameter or None), past what a grammar lets through
EDGE_CASES = {
    "triangle": [(A.DRAW, None), (A.POLY_START, None), (A.POLY_VERTEX, None), (A.MOVE, None), (A.POLY_VERTEX, None)]
    + [(A.MOVE, 2.0), (A.TURN_LEFT, 120.0), (A.MOVE, 1.0), (A.POLY_END, None)],
    "close without open": [(A.DRAW, None), (A.POLY_END, None), (A.DRAW, None)],
    "vertex outside": [(A.DRAW, None), (A.POLY_VERTEX, None), (A.DRAW, None)],
    "never closed": [(A.POLY_START, None), (A.POLY_VERTEX, None), (A.MOVE, None), (A.POLY_START, None)],
    "closed back at its start": [(A.POLY_START, None), (A.MOVE, 1.0), (A.TURN_LEFT, 90.0), (A.MOVE, 1.0)]
    + [(A.TURN_LEFT, 90.0), (A.MOVE, 1.0), (A.TURN_LEFT, 90.0), (A.MOVE, 1.0), (A.POLY_END, None)],
    "colours": [(A.COLOR_UP, 3.0), (A.DRAW, None), (A.COLOR_DOWN, None), (A.DRAW, None), (A.COLOR_UP, 1e300)]
    + [(A.DRAW, None), (A.COLOR_UP, float("nan")), (A.DRAW, None)],
    "huge colours": [(A.COLOR_UP, 2.0**60), (A.COLOR_UP, None), (A.PUSH, None), (A.DRAW, None), (A.ORGAN, None)]
    + [(A.POP, None), (A.DRAW, None), (A.COLOR_DOWN, -(2.0**62)), (A.DRAW, None)],
    "unbalanced": [(A.DRAW, None), (A.POP, None), (A.DRAW, None), (A.PUSH, None), (A.DRAW, None)],
    "widths and spheres": [(A.WIDTH, 2.0), (A.DRAW, None), (A.SPHERE, 1.0), (A.SPHERE, None), (A.WIDTH, None)]
    + [(A.DRAW, 2.0), (A.ORGAN, None), (A.SURFACE, 3.0)],
    "elasticity and rolls": [(A.ELASTICITY, 0.3), (A.DRAW, None), (A.PUSH, None), (A.PITCH_DOWN, 40.0)]
    + [(A.ELASTICITY, None), (A.DRAW, None), (A.POP, None), (A.ROLL_HORIZONTAL, None), (A.TURN_AROUND, None)]
    + [(A.ROLL_LEFT, 30.0), (A.ROLL_RIGHT, None), (A.PITCH_UP, None), (A.TURN_RIGHT, None), (A.DRAW, None)],
}


@pytest.mark.parametrize("case", sorted(EDGE_CASES))
@pytest.mark.parametrize("trop", [(), (0.0, 0.0, -1.0, 0.2)])
def test_full_walks_agree_on_edge_cases(case, trop):
    acts = np.array([a for a, _ in EDGE_CASES[case]], np.int8)
    nps = np.array([p is not None for _, p in EDGE_CASES[case]])
    par = np.array([np.nan if p is None else p for _, p in EDGE_CASES[case]])
    out = []
    for walk in (compiled_walk, plain_walk):
        state = initial_state(1.5)
        args = (0, len(acts), np.zeros(0, np.int32), FULL, state, 30.0, 1.0, np.array(trop, float), 0)
        out.append((*_flat(walk(acts, nps, par, *args)[1:]), state))
    for x, y in zip(*out):
        assert x.dtype == y.dtype
        np.testing.assert_array_equal(x, y)
    assert any(len(x) for x in out[1][:-1])


def test_the_balance_check_without_numba(monkeypatch):
    push, pop = int(turtle.TurtleAction.PUSH), int(turtle.TurtleAction.POP)
    monkeypatch.setattr(turtle, "use_kernels", False)
    cases = {(): True, (push, pop): True, (pop, push): False, (push,): False, (push, push, pop, 1, pop): True}
    for acts, balanced in cases.items():
        assert turtle._balanced(np.array(acts, np.int8)) is balanced, acts


def test_the_numpy_gather_groups_vertices_by_polygon_in_recording_order():
    vtx = np.arange(18.0).reshape(6, 3)
    offsets, points = _gather(vtx, np.array([1, 0, -1, 1, 0, 1]), 3)
    assert offsets.tolist() == [0, 2, 5, 5]
    assert points[:, 0].tolist() == [3.0, 12.0, 0.0, 9.0, 15.0]


_FRESH = """
import json, sys, time
from ramure.lsys import LSystem
d = LSystem.from_file("honda_sympodial").derive()
sk = d.skeleton()
print(json.dumps({"segments": len(sk), "numba": "numba" in sys.modules}))
"""


def test_a_new_process_draws_a_small_plant_without_loading_numba():
    done = subprocess.run([sys.executable, "-c", _FRESH], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert record == {"segments": 1023, "numba": False}


def test_numpy_bracket_pairs_equal_the_kernels():
    from ramure.lsys.interpretation import _turtle_walk

    rng = np.random.default_rng(4)
    cases = [np.zeros(0, np.int8), np.array([11, 12], np.int8), np.array([12, 11], np.int8)]
    for n in (1, 2, 5, 17, 60, 300):
        for _ in range(40):
            cases.append(rng.choice(np.array([0, 1, 11, 12], np.int8), n, p=[0.3, 0.2, 0.25, 0.25]))
    balanced_seen = set()
    for acts in cases:
        expected, ok = bracket_pairs32(acts, 11, 12)
        got, got_ok = _turtle_walk.bracket_pairs32(acts, 11, 12)
        assert got.dtype == expected.dtype
        np.testing.assert_array_equal(got, expected, err_msg=str(acts.tolist()))
        assert got_ok == bool(ok)
        balanced_seen.add(got_ok)
    assert balanced_seen == {True, False}


def test_numpy_kept_modules_equal_the_kernels():
    from ramure.lsys.interpretation import _turtle_kernel, _turtle_walk

    rng = np.random.default_rng(5)
    for _ in range(200):
        old = rng.permutation(40)[: rng.integers(0, 30)].astype(np.int32)
        new = old.copy()
        if rng.random() < 0.5:  # a splice: drop a run, insert new ids
            a = int(rng.integers(0, len(old) + 1))
            b = int(rng.integers(a, len(old) + 1))
            new = np.concatenate([old[:a], np.arange(40, 40 + int(rng.integers(0, 5)), dtype=np.int32), old[b:]])
        else:
            rng.shuffle(new)
        for x, y in zip(_turtle_walk.kept_modules(old, new, 50), _turtle_kernel.kept_modules(old, new, 50)):
            np.testing.assert_array_equal(x, y)


_EDIT = """
import json, sys
from ramure.app.model import Explorer
ex = Explorer("grammars/honda_sympodial.lsys", n=10)
ex.mesh
ex.select(ex.skeleton.leaf_id[100::97][:8])
ex.regrow(seed=1)
reused = "reuse" in ex.skeleton.extra
ex.mesh
ex.undo()
ex.mesh
print(json.dumps({"numba": "numba" in sys.modules, "networkx": "networkx" in sys.modules, "reused": reused}))
"""


def test_a_new_process_edits_a_small_plant_without_numba_or_networkx():
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-c", _EDIT], capture_output=True, text=True, timeout=300, cwd=root)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == {"numba": False, "networkx": False, "reused": True}


@pytest.mark.parametrize("name", ["honda_sympodial", "apricot_tree", "abop/bush_1_25"])
def test_an_edit_reinterprets_alike_with_either_walk(name, monkeypatch):
    from ramure.lsys.regeneration.regen import Session

    skeletons = []
    for compiled in (True, False):
        monkeypatch.setattr(turtle, "use_kernels", compiled)
        s = Session(LSystem.from_file(name), seed=2)
        old = turtle.interpret_string(s.lsystem, s.tree, s.tree.leaves)
        before = s.tree.leaves.copy()
        s.regrow(before[len(before) // 3 :: 41][:6], rho=0.5, seed=3)
        spans = s.edit_spans(before, s.tree.leaves) or turtle.changed_spans(before, s.tree.leaves, s.tree.size)
        skeletons.append(turtle.reinterpret(s.lsystem, s.tree, old, s.tree.leaves, *spans))
    compiled, plain = (_arrays(sk) for sk in skeletons)
    for key, value in compiled.items():
        assert plain[key].dtype == value.dtype, key
        np.testing.assert_array_equal(plain[key], value, err_msg=key)
    if name != "abop/bush_1_25":  # (its polygons may make an edit draw the whole string)
        assert all("reuse" in sk.extra for sk in skeletons)  # both re-interpreted only the change
