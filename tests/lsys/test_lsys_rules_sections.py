"""Interpretation (homomorphism) and decomposition rules (issue 15, part B).

Random grammars are checked against a plain string-rewriting reference written
here from the definitions (L-Py semantics): parallel productions; after each
step, decomposition rules over the whole string, at most ``depth`` rounds;
interpretation rules on the final string only, at most ``depth`` rounds.
"""

import numpy as np
import pytest

from ramure.lsys import GrammarError, LSystem
from ramure.lsys.interpretation.homomorphism import interpreted, interpreted_text
from ramure.lsys.regeneration.regen import Session, regenerate

SYMBOLS = "ABCDF+-"


# -- a reference from the definitions -------------------------------------------------
def rewrite(string, rules):
    """One parallel step with context-free, parameterless rules {symbol: successor}."""
    out = "".join(rules.get(c, c) for c in string)
    return out, any(c in rules for c in string)


def reference(axiom, productions, decomposition=None, depth=1, n=1):
    def decompose(s):
        for _ in range(depth if decomposition else 0):
            s, applied = rewrite(s, decomposition)
            if not applied:
                break
        return s

    s = decompose(axiom)
    for _ in range(n):
        s = decompose(rewrite(s, productions)[0])
    return s


def text(axiom, productions, n, decomposition=None, ddepth=None, interpretation=None, idepth=None):
    lines = [f"n: {n}", f"w: {axiom}", "p:"] + [f"  {k} -> {v}" for k, v in productions.items()]
    for name, rules, depth in (("decomposition", decomposition, ddepth), ("interpretation", interpretation, idepth)):
        if rules:
            lines += [f"{name}:"] + [f"  {k} -> {v}" for k, v in rules.items()]
        if depth:
            lines.append(f"#{name}_depth {depth}")
    return "\n".join(lines) + "\n"


def random_rules(rng, symbols, longest=4):
    keys = rng.choice(list(symbols), size=rng.integers(1, len(symbols)), replace=False)
    return {str(k): "".join(rng.choice(list(SYMBOLS), size=rng.integers(0, longest + 1))) for k in keys}


def check_tree(tree):
    """History invariants: children point back; a child's step is larger; leaves are the leaf nodes."""
    kids = np.flatnonzero(tree.parent >= 0)
    assert (tree.step[tree.parent[kids]] < tree.step[kids]).all()
    for v in np.unique(tree.parent[kids]):
        assert (tree.parent[tree.children(v)] == v).all()
    assert (tree.child_count[tree.leaves] == 0).all()
    first, last = tree.leaf_spans()
    assert (first[tree.leaves] == np.arange(len(tree.leaves))).all()


# -- decomposition ----------------------------------------------------------------------
def test_decomposition_comes_before_the_next_production_step():
    # B decomposes into CC at once, so step 2 already rewrites those C into X.
    g = text("A", {"A": "AB", "C": "X"}, 2, decomposition={"B": "CC"})
    assert LSystem.from_text(g).derive().to_string() == "ACCXX"
    assert reference("A", {"A": "AB", "C": "X"}, {"B": "CC"}, n=2) == "ACCXX"
    # had it run after the last step only, B would be rewritten by no rule: "ABB" -> "ACCCC"
    assert LSystem.from_text(text("A", {"A": "AB", "C": "X"}, 2)).derive().to_string() == "ABB"


def test_the_axiom_is_decomposed_before_the_first_step():
    d = LSystem.from_text(text("B", {"C": "F"}, 1, decomposition={"B": "CC"})).derive()
    assert d.to_string() == "FF"


@pytest.mark.parametrize("depth, expected", [(1, "AC"), (2, "AD"), (3, "AE"), (5, "AF")])
def test_decomposition_depth_limits_the_rounds(depth, expected):
    rules = {"B": "C", "C": "D", "D": "E", "E": "F"}
    got = LSystem.from_text(text("A", {"A": "AB"}, 1, decomposition=rules, ddepth=depth)).derive().to_string()
    assert got == expected == reference("A", {"A": "AB"}, rules, depth, 1)


def test_decomposition_applies_to_the_whole_string_as_in_lpy():
    # K is made once; a non-terminating decomposition K -> KK (depth 1) doubles it every step.
    d = LSystem.from_text(text("AK", {"A": "A"}, 3, decomposition={"K": "KK"})).derive()
    assert d.count("K") == 16  # axiom 2, then 4, 8, 16
    check_tree(d.tree)


@pytest.mark.parametrize("seed", range(12))
def test_random_grammars_decompose_like_the_reference(seed):
    rng = np.random.default_rng(seed)
    productions = random_rules(rng, "ABCD")
    decomposition = random_rules(rng, "BCDF", longest=3)
    depth = int(rng.integers(1, 4))
    axiom = "".join(rng.choice(list("ABCD"), size=3))
    n = next(k for k in (5, 4, 3, 2, 1) if len(reference(axiom, productions, decomposition, depth, k)) <= 5000)
    d = LSystem.from_text(text(axiom, productions, n, decomposition, depth)).derive()
    assert d.to_string() == reference(axiom, productions, decomposition, depth, n)
    check_tree(d.tree)


def test_decomposed_modules_are_children_of_the_producing_rule():
    g = text("A", {"A": "FAB"}, 2, decomposition={"B": "CD"})
    d = LSystem.from_text(g).derive()
    tree = d.tree
    assert d.to_string() == "FFACDCD"
    a1 = np.flatnonzero((tree.step == 1) & (tree.symbol == d.lsystem.symbols.index("A")))[0]
    kids = tree.children(a1)
    assert "".join(d.lsystem.symbols[s] for s in tree.symbol[kids]) == "FACD"  # A -> FAB, B -> CD in place
    assert set(tree.rule[kids].tolist()) == {0}  # recorded as the production's application
    assert tree.index_in_rule[kids].tolist() == [0, 1, 2, 2]  # C, D came from the successor's B
    assert tree.step[kids].tolist() == [2, 2, 2, 2]


def test_regrow_on_a_grammar_with_decomposition_keeps_ids_and_undoes():
    g = (
        "n: 5\nw: A\np:\n  A -> F[+A]B : 1\n  A -> F[-A]A : 1\n  C(x) -> C(x+1)\n"
        "decomposition:\n  B -> C(0)[-D]\n  D -> FE\n#decomposition_depth 2\n"
    )
    ls = LSystem.from_text(g)
    s = Session(ls, n=5, seed=1)
    before = s.derivation.to_string()
    old_leaves = s.tree.leaves.copy()
    selected = s.leaves_with_symbol("E")[:1]
    result = s.regrow(selected, rho=0.5, seed=7)
    assert result.roots.size
    check_tree(s.tree)
    kept = np.isin(old_leaves, s.tree.leaves)
    assert kept.sum() >= len(old_leaves) - result.removed  # ids outside the regrown part are the same
    assert "B" not in s.derivation.to_string() and "D" not in s.derivation.to_string()
    s.undo()
    assert s.derivation.to_string() == before


@pytest.mark.parametrize("seed", range(4))
def test_regrowing_the_axiom_is_a_fresh_derivation(seed):
    g = (
        "n: 5\nw: A\np:\n  A -> F[+A]B : 1\n  A -> F[-A]A : 1\n  C(x) -> C(x+1)\n"
        "decomposition:\n  B -> C(0)[-D]\n  D -> FE\n#decomposition_depth 2\n"
    )
    ls = LSystem.from_text(g)
    d = ls.derive(seed=seed)
    regenerate(d, np.array([0]), seed=seed + 10)
    assert d.to_string() == ls.derive(seed=seed + 10).to_string()
    check_tree(d.tree)


# -- interpretation ---------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(12))
def test_interpretation_rules_never_change_the_derived_string(seed):
    rng = np.random.default_rng(100 + seed)
    productions = random_rules(rng, "ABCD")
    interpretation = random_rules(rng, "ABCDF", longest=5)
    depth = int(rng.integers(1, 4))
    n = next(k for k in (4, 3, 2, 1) if len(reference("AB", productions, n=k)) <= 3000)
    base = text("AB", productions, n)
    drawn = text("AB", productions, n, interpretation=interpretation, idepth=depth)
    plain, d = LSystem.from_text(base).derive(seed=seed), LSystem.from_text(drawn).derive(seed=seed)
    before = (d.to_string(), d.tree.size, d.tree.leaves.copy())
    skeleton = d.skeleton()
    assert d.to_string() == plain.to_string()
    assert (d.to_string(), d.tree.size) == before[:2] and (d.tree.leaves == before[2]).all()
    expected = reference(plain.to_string(), interpretation, n=0)
    for _ in range(depth):
        expected, applied = rewrite(expected, interpretation)
        if not applied:
            break
    assert interpreted_text(d) == expected
    assert len(skeleton) == expected.count("F")
    assert np.isin(skeleton.leaf_id, d.tree.leaves).all()


def test_interpretation_depth_default_is_one():
    g = "n: 1\nw: A\np:\n  A -> AB\ninterpretation:\n  B -> C\n  C -> F\n"
    d = LSystem.from_text(g).derive()
    assert interpreted_text(d) == "AC" and len(d.skeleton()) == 0
    d2 = LSystem.from_text(g + "#interpretation_depth 2\n").derive()
    assert interpreted_text(d2) == "AF" and len(d2.skeleton()) == 1


def test_drawn_parts_carry_the_leaf_id_of_their_source_module():
    g = "n: 2\nw: A(1)\np:\n  A(x) -> I(x)[+L(x)]A(x+1)\ninterpretation:\n  I(x) -> F(x)F(x)\n  L(x) : x > 1 -> F(x)Leaf(x)\n"
    d = LSystem.from_text(g).derive()
    sk = d.skeleton()
    symbols = np.array(d.symbols)
    # I(1), I(2) draw two segments each; L(2) one and a leaf; L(1) nothing (its condition fails)
    assert "".join(symbols[d.tree.leaf_positions(sk.leaf_id)]) == "IIIIL"
    assert symbols[d.tree.leaf_positions(sk.organs.leaf_id)].tolist() == ["L"]
    assert sk.organs.params[0, 0] == 2.0  # the drawn module's parameters
    assert sk.select([d.tree.leaves[0]]).sum() == 2  # selecting I(1) selects both its segments


def test_regrow_through_interpreted_ids():
    g = "n: 4\nw: A\np:\n  A -> I[+A][-A] : 1\n  A -> I[A] : 1\ninterpretation:\n  I -> FF\n"
    s = Session(LSystem.from_text(g), n=4, seed=2)
    sk = s.derivation.skeleton()
    picked = np.unique(sk.leaf_id)[-2:]  # ids the viewer reports for a click on the drawing
    before = s.derivation.to_string()
    s.regrow(picked, rho=0.5, seed=5)
    after = s.derivation.skeleton()
    assert np.isin(after.leaf_id, s.tree.leaves).all()
    s.undo()
    assert s.derivation.to_string() == before


def test_the_explorer_draws_the_interpreted_string_before_and_after_an_edit():
    from ramure.app.model import Explorer

    ex = Explorer("n: 3\nw: A\np:\n  A -> I[+A][-A]\ninterpretation:\n  I -> F[&F]\n")
    assert len(ex.skeleton) == 2 * ex.derivation.count("I") == 14
    ex.select(ex.skeleton.leaf_id[-1:])  # a click on the last drawn segment
    ex.regrow(seed=3)
    assert len(ex.skeleton) == 2 * ex.derivation.count("I")
    assert np.isin(ex.mesh.cell_data["leaf_id"], ex.derivation.tree.leaves).all()


def test_polygons_drawn_by_interpretation_rules_keep_their_modules_leaf_id():
    d = LSystem.from_text("n: 2\nw: A\np:\n  A -> I[+L]A\ninterpretation:\n  I -> F\n  L -> {.+f.+f.}\n").derive()
    sk = d.skeleton()
    assert len(sk.polygons) == 2 and sk.polygons.areas() == pytest.approx([0.5, 0.5])  # right triangles
    assert [d.symbols[p] for p in d.tree.leaf_positions(sk.polygons.leaf_id)] == ["L", "L"]
    mesh = sk.to_polydata()
    assert np.isin(mesh.cell_data["leaf_id"], d.leaves).all()


def test_an_interpretation_rules_mistake_names_its_line():
    with pytest.raises(GrammarError) as info:
        LSystem.from_text("n: 2\nw: A\np:\n  A -> I[+L]A\ninterpretation:\n  L -> {.+f}\n")
    assert info.value.line == 6 and "fewer than 3 vertices" in info.value.message


# -- errors -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "line, column, fragment",
    [
        ("#interpretation_depth 0", 23, "from 1 to 1000"),
        ("#decomposition_depth 2.5", 22, "whole number"),
        ("maximum depth: 2", 1, "not a rule"),
    ],
)
def test_depth_errors_name_line_and_column(line, column, fragment):
    with pytest.raises(GrammarError) as info:
        LSystem.from_text(f"n: 1\nw: A\np:\n  A -> B\ndecomposition:\n{line}\n")
    assert (info.value.line, info.value.column) == (6, column)
    assert fragment in info.value.message


def test_a_rule_error_in_a_section_names_its_line():
    with pytest.raises(GrammarError) as info:
        LSystem.from_text("n: 1\nw: A\np:\n  A -> B\ninterpretation:\n  B -> F(q)\n")
    assert (info.value.line, info.value.column) == (6, 10) and "q" in info.value.message


def test_interpreted_keeps_the_tree_untouched():
    d = LSystem.from_text("n: 2\nw: A\np:\n  A -> AB\ninterpretation:\n  B -> F\n").derive()
    size, leaves = d.tree.size, d.tree.leaves.copy()
    scratch, string, source = interpreted(d.lsystem, d.tree, d.tree.leaves)
    assert d.tree.size == size and (d.tree.leaves == leaves).all()
    assert (source == d.tree.leaves).all()  # one module drawn per module here
