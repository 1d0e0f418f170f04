"""#consider and #include (issue 15, parser part)."""

import pytest

from ramure.lsys import GrammarError, LSystem
from ramure.lsys.language.grammar import parse_grammar


# -- #consider: the dual of #ignore ----------------------------------------------------


def test_consider_sees_only_the_listed_symbols():
    text = "#consider: A B\nn: 1\nw: A+F[-F]B\np:\n A < B -> X\n"
    assert LSystem.from_text(text).derive().to_string() == "A+F[-F]X"
    assert LSystem.from_text(text.replace("#consider: A B\n", "")).derive().to_string() == "A+F[-F]B"


def test_consider_equals_the_complementary_ignore():
    body = "n: 3\nw: F1F1F1\np:\n 0 < 1 > 1 -> 1[+F1F1]\n 1 < 1 > 0 -> 0\n 0 < 0 > 1 -> 1F1\n 1 < 0 > 1 -> 0\n"
    considered = LSystem.from_text("#consider: 0, 1\n" + body).derive().to_string()
    ignored = LSystem.from_text("#ignore: + - F\n" + body).derive().to_string()
    assert considered == ignored


def test_consider_keeps_brackets_structural():
    g = parse_grammar("#consider: A\nn: 1\nw: A[B]C\np:\n A < C -> D\n")
    assert "[" not in g.ignore and "]" not in g.ignore and {"B", "C", "D"} <= g.ignore


def test_consider_and_ignore_together_are_refused():
    with pytest.raises(GrammarError) as info:
        parse_grammar("#ignore: F\n#consider: A\nn: 1\nw: A\n")
    assert info.value.line == 2 and "cannot both be used" in info.value.message


# -- #include ------------------------------------------------------------------------


def test_include_is_relative_to_the_including_file(tmp_path, monkeypatch):
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "rules.lsys").write_text('#include "more/consts.lsys"\np:\n A(x) -> A(x*k)B\n')
    (tmp_path / "lib" / "more").mkdir()
    (tmp_path / "lib" / "more" / "consts.lsys").write_text("#define k 3\n")
    (tmp_path / "main.lsys").write_text('#include "lib/rules.lsys"\nn: 2\nw: A(1)\n')
    monkeypatch.chdir(tmp_path / "lib")  # not the including file's folder
    ls = LSystem.from_file(tmp_path / "main.lsys")
    assert ls.constants == {"k": 3.0}
    assert ls.derive().to_string() == "A(9)BB"


def test_include_cycle_names_both_files(tmp_path):
    (tmp_path / "a.lsys").write_text("#include b.lsys\nn: 1\nw: A\n")
    (tmp_path / "b.lsys").write_text("#include a.lsys\n")
    with pytest.raises(GrammarError) as info:
        LSystem.from_file(tmp_path / "a.lsys")
    message = str(info.value)
    assert "cycle" in message and "b.lsys includes a.lsys" in message and info.value.line == 1


def test_self_include_is_a_cycle(tmp_path):
    (tmp_path / "a.lsys").write_text("n: 1\nw: A\n#include 'a.lsys'\n")
    with pytest.raises(GrammarError, match="cycle"):
        LSystem.from_file(tmp_path / "a.lsys")


def test_missing_include_is_an_error_at_its_line(tmp_path):
    (tmp_path / "a.lsys").write_text("n: 1\n#include <gone.lsys>\nw: A\n")
    with pytest.raises(GrammarError) as info:
        LSystem.from_file(tmp_path / "a.lsys")
    assert (info.value.line, info.value.column) == (2, 10) and "cannot #include gone.lsys" in info.value.message


def test_an_error_inside_an_included_file_names_that_file(tmp_path):
    (tmp_path / "bad.lsys").write_text("p:\n A -> B(r)\n")
    (tmp_path / "a.lsys").write_text("n: 1\nw: A\n#include bad.lsys\n")
    with pytest.raises(GrammarError) as info:
        LSystem.from_file(tmp_path / "a.lsys")
    assert info.value.filename.endswith("bad.lsys") and info.value.line == 2
    assert "unknown name 'r'" in info.value.message


# -- #function: pure user functions ----------------------------------------------------

FUNCTIONS = "#define k 2\n#function sq(x) = x*x\n#function g(a, b) = sq(a) + b*k\n#define c sq(3)\n"


def test_user_functions_inline_in_rules_conditions_and_constants():
    ls = LSystem.from_text(FUNCTIONS + "n: 2\nw: A(1)\np:\n A(x) : sq(x) < 5 -> A(x+1)B(g(x, c))\n")
    assert ls.constants == {"k": 2.0, "c": 9.0}
    # step 1: A(2)B(1 + 18); step 2: sq(2) = 4 < 5, A(3)B(4 + 18)
    assert ls.derive().to_string() == "A(3)B(22)B(19)"


def test_a_function_body_constant_is_not_captured_by_a_rule_parameter():
    # the rule's formal is named k too; g's k is still the constant 2
    ls = LSystem.from_text(FUNCTIONS + "n: 1\nw: A(1)\np:\n A(k) -> B(g(k, 1))\n")
    assert ls.derive().to_string() == "B(3)"
    ls.constants["k"] = 5  # constants stay live: no re-parse needed
    assert ls.derive().to_string() == "B(6)"


@pytest.mark.parametrize(
    "lines, line, column, fragment",
    [
        ("#function f(x) = f(x - 1)\n", 1, 18, "calls itself"),
        ("#function f(x) = y\n", 1, 18, "unknown name 'y'"),
        ("#function sin(x) = x\n", 1, 11, "built-in"),
        ("#function f(x) = x\n#define z f(1, 2)\n", 2, 11, "takes 1 argument"),
        ("#function f x = 1\n", 1, 11, "name(x, y) = expression"),
        ("#function f(x, x) = x\n", 1, 13, "distinct names"),
    ],
)
def test_bad_functions_are_grammar_errors(lines, line, column, fragment):
    with pytest.raises(GrammarError) as info:
        parse_grammar(lines + "n: 1\nw: A\n")
    assert (info.value.line, info.value.column) == (line, column) and fragment in info.value.message


def test_exponential_inlining_is_refused():
    lines = "#function f0(x) = x + 1\n" + "".join(f"#function f{i}(x) = f{i - 1}(x) * f{i - 1}(x)\n" for i in range(1, 20))
    with pytest.raises(GrammarError, match="operations"):
        parse_grammar(lines + "n: 1\nw: A\n")
