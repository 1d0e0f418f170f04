"""cpfg's C conditional ``c ? a : b`` and the ``?E`` environment (issue 36), values by hand."""

import pytest

from ramure.lsys import GrammarError, LSystem


def derive(body, n=1):
    return LSystem.from_text(f"derivation length: {n}\n{body}\nendlsystem\n", filename="q.l").derive()


def test_the_conditional_picks_per_module_and_nests_to_the_right():
    d = derive("axiom: A(-1)A(0)A(2)\nA(x) --> B(x > 0 ? 1/x : x < 0 ? 7 : 8)")
    assert d.to_string() == "B(7)B(8)B(0.5)"  # 1/x is not taken at x = 0: no division error


def test_the_conditional_in_a_define_macro_and_a_block():
    body = "#define MAX(a,b) (((a)>(b))?(a):(b))\naxiom: A(3)A(-2)\nA(x) : {c = (x>0)?3:4;} * --> B(MAX(x, 0), c)"
    assert derive(body).to_string() == "B(3,3)B(0,4)"


def test_a_conditional_without_its_colon_is_refused_at_the_end():
    with pytest.raises(GrammarError, match="':' of 'condition") as info:
        derive("axiom: A(1)\nA(x) --> B(x > 0 ? 1)")
    assert info.value.line == 3


def test_the_taken_branch_must_be_finite():
    with pytest.raises(Exception, match="branch a '\\? :' takes"):
        derive("axiom: A(0)\nA(x) --> B(x < 1 ? 1/x : 0)")
