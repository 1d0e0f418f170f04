"""cpfg's several-module strict predecessors (issue 36): cpfg reads one module per character,
so ``XF(x) --> ...`` and ``spikef --> ...`` rewrite a run of modules.  Every expected string
below is worked out by hand from cpfg's rule: left to right, the first matching rule takes its
modules, and the scan goes on after them."""

import numpy as np
import pytest

from ramure.lsys import GrammarError, LSystem
from ramure.lsys.interpretation.homomorphism import interpreted_text


def derive(body, n=1):
    return LSystem.from_text(f"derivation length: {n}\n{body}\nendlsystem\n", filename="p.l").derive()


def test_a_two_module_predecessor_rewrites_each_run_it_matches():
    d = derive("axiom: AXF(2)BXF(3)XF(1)X\nXF(x) --> F(x/2)[+F(x)]")
    assert d.to_string() == "AF(1)[+F(2)]BF(1.5)[+F(3)]F(0.5)[+F(1)]X"  # the last X has no F after it


def test_matches_never_overlap_and_the_scan_goes_left_to_right():
    assert derive("axiom: AAAAA\nAA --> B").to_string() == "BBA"
    assert derive("axiom: ABAB\nAB --> C\nBA --> D").to_string() == "CC"  # BA at position 1 overlaps


def test_names_are_one_module_per_letter_as_cpfg_reads_them():
    d = derive("axiom: Fspikef\nspikef --> X(1)")
    assert d.to_string() == "FX(1)"
    tree = d.tree  # the first module gets the successor, the other five end (no children)
    assert [int(tree.child_count[v]) for v in range(7)] == [0, 1, 0, 0, 0, 0, 0]
    assert tree.symbol[int(tree.child_start[1])] == d.lsystem.symbols.index("X")


def test_parameters_contexts_and_conditions_of_every_module():
    body = "axiom: C A(1)B(2)D A(3)B(1)D A(2)B(5)E\nC < A(x)B(y) > D : x < y --> Z(x+y)"
    # only the first A B follows a C: "C < A(x)B(y)" reads the left context before the run's first module
    assert derive(body).to_string() == "CZ(3)DA(3)B(1)DA(2)B(5)E"
    body = "axiom: A(1)B(2)D A(3)B(1)D A(2)B(5)E\nA(x)B(y) > D : x < y --> Z(x*y)"
    assert derive(body).to_string() == "Z(2)DA(3)B(1)DA(2)B(5)E"  # 3 < 1 fails; the third has no D after it


def test_a_several_module_rule_takes_its_run_before_one_module_rules():
    assert derive("axiom: AB B\nA --> X\nB --> Y\nAB --> Z").to_string() == "ZY"


def test_cpfg_matches_a_rule_to_modules_of_its_own_arity_only():
    assert derive("axiom: GG(1)\nG(x) --> G(x+1)", n=2).to_string() == "GG(3)"  # G alone is not rewritten


def test_homomorphism_and_decomposition_take_runs_too():
    d = derive("axiom: SlA\nA --> SrA\nhomomorphism\nSl --> F\nSr --> +F")
    assert d.to_string() == "SlSrA" and interpreted_text(d) == "F+FA"
    d = derive("axiom: A\nA --> Bb\ndecomposition\nBb --> CC")
    assert d.to_string() == "CC"


def test_lsys_text_needs_the_cpfg_dialect_for_several_modules():
    with pytest.raises(GrammarError, match="only with '#dialect cpfg'") as info:
        LSystem.from_text("n: 1\nw: AB\np:\n AB -> C\n")
    assert (info.value.line, info.value.column) == (4, 2)
    assert LSystem.from_text("#dialect cpfg\nn: 1\nw: ABAB\np:\n AB -> C\n").derive().to_string() == "CC"


def test_a_stochastic_several_module_rule_is_refused_at_its_line():
    with pytest.raises(GrammarError, match="cannot be stochastic") as info:
        LSystem.from_text("derivation length: 1\naxiom: AB\nAB --> C : 0.5\nAB --> D : 0.5\n", filename="s.l")
    assert (info.value.line, info.value.column) == (3, 1)


def test_the_imported_lsys_keeps_the_dialect():
    from ramure.lsys.language.cpfg import to_lsys

    text = "derivation length: 2\naxiom: XF(4)\nXF(x) --> XF(x/2)F(x/2)\n"
    lsys = to_lsys(text, "x.l")
    assert "#dialect cpfg" in lsys.splitlines()
    assert LSystem.from_text(lsys).derive().to_string() == "XF(1)F(1)F(2)"
    assert np.isclose(LSystem.from_text(lsys).derive().skeleton().length.sum(), 4.0)


def test_statement_blocks_run_for_the_runs_in_string_order():
    d = derive("Start: {k=0;}\naxiom: A(1)BA(2)BA(3)B\nA(x)B : {y=x*2; k=k+1;} y>2 --> C(y,k)")
    assert d.to_string() == "A(1)BC(4,2)C(6,3)"  # the block ran for all three runs, the condition kept two
