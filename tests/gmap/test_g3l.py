"""3Gmap L-systems: the .g3l format, the rule-major engine and the shipped grammars."""

import numpy as np
import pytest

from ramure.errors import GrammarError
from ramure.gmap.lsystem.g3l import parse_g3l
from ramure.gmap.lsystem.engine import G3LSystem
from ramure.gmap.kernel.topology import assert_solid


def spiral_darts(n):
    """Table 3.1 under rule-major steps: p1 adds one 16-prism A per step on the newest A's free E
    face; p2 gives 8 cubes to the A whose even sides are still free (one A per step, the axiom at
    step 0); joins add no darts.  darts(n) = 192 (n + 1) + 48 * 8 n."""
    return 192 * (n + 1) + 384 * n


def trunk_counts(n):
    """Table 3.2 under rule-major steps.  Pith prism P_i (A if i even, F if odd) is made at step
    i - 1 (the axiom P_0 before step 0); its 16 radial stacks start at step i and gain one volume per
    step (p2, p5, p6 grow the stack's outer S, R1 or R2 on its free E face).  After n steps a stack
    of P_i has m = n - i volumes: cubes on a node; on an internode two wedges (R2, S(3), 36 darts)
    then cubes.  volumes(n) = (n + 1) + 16 * n (n + 1) / 2;
    darts(n) = 192 (n + 1) + 16 * sum_i d(i, n - i), d = 48 m (node) or 36 min(m, 2) + 48 max(m - 2, 0)."""
    darts = 192 * (n + 1)
    for i in range(n):
        m = n - i
        darts += 16 * (48 * m if i % 2 == 0 else 36 * min(m, 2) + 48 * max(m - 2, 0))
    return darts, (n + 1) + 8 * n * (n + 1)


@pytest.mark.parametrize("n", [0, 1, 2, 4, 6])
def test_spiral_dart_count_follows_the_step_semantics(n):
    d = G3LSystem.from_file("wood/spiral").derive(n, check_every_step=True)
    assert d.gm.n_darts == spiral_darts(n)
    assert d.gm.n_volumes == 1 + n + 8 * n
    assert_solid(d.gm)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_trunk_grammar_counts_closed_form_and_topology_every_step(n):
    d = G3LSystem.from_file("wood/trunk").derive(n, check_every_step=True)
    darts, volumes = trunk_counts(n)
    assert (d.gm.n_darts, d.gm.n_volumes) == (darts, volumes)
    labels = d.gm.volume_data["label"]
    assert (labels == "A").sum() + (labels == "F").sum() == n + 1


def test_trunk_grammar_joins_rings_around_and_along():
    d = G3LSystem.from_file("wood/trunk").derive(3)
    gm = d.gm
    vol = gm.dart_volume
    sewn = gm.alpha[3] != np.arange(gm.n_darts)
    ring = np.isin(gm.volume_data["label"], ["R", "S", "R1", "R2"])
    pairs = {(int(a), int(b)) for a, b in zip(vol[sewn], vol[gm.alpha[3][sewn]]) if ring[a] and ring[b]}
    assert len(pairs) > 16  # rings sewn to rings (p7..p10), not only stacked on each other


def test_skeleton_grammar_is_seeded_and_valid():
    s = G3LSystem.from_file("wood/skeleton")
    a, b = s.derive(5, seed=3, check_every_step=True), s.derive(5, seed=3)
    assert a.gm.volume_data["label"].tolist() == b.gm.volume_data["label"].tolist()
    np.testing.assert_array_equal(a.gm.points, b.gm.points)
    shapes = {tuple(s.derive(5, seed=k).gm.volume_data["label"].tolist()) for k in range(6)}
    assert len(shapes) > 1  # the seed chooses between the paired rules


def test_embedding_every_step_equals_once():
    s = G3LSystem.from_file("wood/trunk")
    every, once = s.derive(4, embed_every_step=True), s.derive(4)
    assert np.max(np.abs(every.gm.points - once.gm.points)) < 1e-12
    before = once.gm.points.copy()
    once.gm.points[:] = 1e3  # embed reads default corners, never old points
    once.embed()
    assert np.max(np.abs(once.gm.points - before)) < 1e-12
    assert np.array_equal(once.gm.corners, every.gm.corners)


def test_provenance_and_regrow_change_only_the_branch_and_its_neighbours():
    s = G3LSystem.from_file("wood/trunk")
    d = s.derive(5)
    vd = d.gm.volume_data
    head = int(np.flatnonzero(vd["label"] == "R")[0])
    assert d.provenance(head)[-1] == ("axiom", 0)
    branch = d.branch(head)
    assert len(branch) >= 2
    new = d.regrow(head, seed=99)
    key_old, key_new = d.gm.volume_data["key"], new.gm.volume_data["key"]
    assert sorted(key_old.tolist()) == sorted(key_new.tolist())
    where = {int(k): i for i, k in enumerate(key_new.tolist())}
    perm = np.array([where[int(k)] for k in key_old.tolist()])
    changed = np.flatnonzero(np.any(np.abs(new.gm.volume_data["size"][perm] - vd["size"]) > 0, axis=1))
    assert changed.size and set(changed.tolist()) <= set(branch.tolist())
    cen_old, cen_new = d.gm.volume_centroids(), new.gm.volume_centroids()[perm]
    moved = set(np.flatnonzero(np.linalg.norm(cen_old - cen_new, axis=1) > 1e-12).tolist())
    gm = d.gm
    in_branch = np.isin(gm.dart_volume, branch)
    vid, _ = gm.cells(0)  # positions average over vertices: vertex neighbours move
    touching = set(gm.dart_volume[np.isin(vid, vid[in_branch])].tolist())
    assert moved <= touching
    assert len(moved) < gm.n_volumes // 2


@pytest.mark.parametrize(
    "text, line, column, words",
    [
        ("axiom: A(4)\n(p1) A -> A[B(4, q)]_E\n", 2, 18, "unknown name 'q'"),
        ("axiom: A(4)\n(p1) A  A[B]_E\n", 2, 6, "needs '->'"),
        ("axiom: A(4)\n(p1) A -> A[B]_Q\n", 2, 15, "unknown face"),
        ("axiom: A(4)\n(p1) A -> A[B(4]_E\n", 2, 12, "not closed"),
        ("#define x 1 +\naxiom: A(4)\n", 1, 14, "cannot read"),  # the caret at the missing operand
        ("(p1) A -> A[B]_E\n", 1, 1, "no 'axiom:'"),
    ],
)
def test_grammar_errors_name_line_column_and_caret(text, line, column, words):
    with pytest.raises(GrammarError) as err:
        parse_g3l(text, "x.g3l")
    assert err.value.line == line and words in str(err.value)
    assert err.value.column is not None and abs(err.value.column - column) <= 3
    assert "^" in str(err.value).splitlines()[-1]


def test_runtime_errors_name_the_rule_and_column():
    s = G3LSystem.from_text("axiom: A(4)\n(p1) A -> A[B]_C7\n", "bad.g3l")
    with pytest.raises(GrammarError, match=r"rule p1: .* has no face C7"):
        s.derive(1)
    s = G3LSystem.from_text("axiom: A(4)\n(p1) A -> A[B(2)]_E\n", "bad.g3l")
    with pytest.raises(GrammarError, match="order must be at least 3"):
        s.derive(1)


def test_conditions_on_season_age_and_order():
    text = """axiom: A(4)
(p1) A : season == spring -> A[B]_E
(p2) B : age >= 1 && order == 1 -> B[C]_C1
"""
    d = G3LSystem.from_text(text).derive(4)
    labels = d.gm.volume_data["label"].tolist()
    assert labels.count("B") == 1  # only the spring step 0 adds on the free E
    assert labels.count("C") == 1  # B is one step old at step 2; its C1 is then sewn
    assert_solid(d.gm)


def test_adding_only_on_free_faces_keeps_rules_self_limiting():
    d = G3LSystem.from_text("axiom: A(4)\n(p1) A -> A[B]_C*\n").derive(3)
    assert d.gm.n_volumes == 5


def test_stochastic_probabilities_must_stay_in_range():
    s = G3LSystem.from_text("axiom: A(4)\n(p1) A -> A[B]_E : 0.7\n(p2) A -> A[C]_E : 0.6\n")
    with pytest.raises(GrammarError, match="add up"):
        for seed in range(20):
            s.derive(1, seed=seed)


def test_split_operator_makes_two_volumes_and_the_new_ones_wait():
    text = "axiom: A(4, 0, 0, 0, 2, 1, 1)\n(p1) A ->^O B C\n(p2) C -> C[D]_E\n"
    one = G3LSystem.from_text(text).derive(1)
    assert one.gm.volume_data["label"].tolist() == ["B", "C"] and one.gm.n_darts == 96
    two = G3LSystem.from_text(text).derive(2)
    assert two.gm.volume_data["label"].tolist() == ["B", "C", "D"]
    assert two.provenance(2) == [("p2", 1), ("p1", 0), ("axiom", 0)]
    assert_solid(two.gm)
    # the halves split the axiom's height 2 along its heading z; D (height 1 by default) sits on C
    np.testing.assert_allclose(two.gm.volume_centroids()[:, 2], [0.5, 1.5, 2.5], atol=1e-12)
