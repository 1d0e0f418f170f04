"""Malformed grammars fail with GrammarError at the right line and column."""

import subprocess
import sys

import pytest

from ramure.lsys import DerivationError, GrammarError, LSystem

BAD = [
    # (text, line, message fragment)
    ("n: 2\nw: A\np:\n A -> B(r)\n", 4, "unknown name 'r'"),
    ("n: 2\nw: A(1)\np:\n A(x) -> A(sin(x, 2))\n", 4, "takes 1 argument"),
    ("n: 2\nw: A\np:\n A -> [B\n", 4, "unbalanced '['"),
    ("n: 2\nw: A]\np:\n A -> B\n", 2, "unbalanced ']'"),
    ("n: 2\nw: A\np:\n .5 A -> B\n .4 A -> C\n", 4, "sum to 0.9"),
    ("#define k 1 +\nn: 1\nw: A\n", 1, "expected a number"),
    ("#angel 30\nn: 1\nw: A\n", 1, "unknown directive"),
    ("n: 2\nw: A(1,2)\np:\n A(x) -> A(x)\n", 2, "written with 2 parameter"),
    ("n: 2\nw: A(1)\np:\n A(x) -> A(x+)\n", 4, "expected a number"),
    ("n: 1\nw: A\np:\n A B\n", 4, "not a rule"),
    ("n: 1.5\nw: A\n", 1, "whole number"),
    ("n: 1\nw: A(1)\np:\n A(1) -> B\n", 4, "must be names"),
]


@pytest.mark.parametrize("text,line,fragment", BAD)
def test_malformed_grammar_names_its_line(text, line, fragment):
    with pytest.raises(GrammarError) as err:
        LSystem.from_text(text)
    assert err.value.line == line
    assert fragment in str(err.value)
    assert "^" in str(err.value)  # the caret under the column


def test_caret_points_at_column():
    with pytest.raises(GrammarError) as err:
        LSystem.from_text("n: 2\nw: A\np:\n  A -> F(l*r9)\n")
    e = err.value
    assert (e.line, e.column) == (4, 10)
    source, caret = str(e).splitlines()[1:3]
    assert source[caret.index("^")] == "l"


def test_missing_axiom():
    with pytest.raises(GrammarError, match="no axiom"):
        LSystem.from_text("n: 1\np:\n A -> B\n")


def test_division_by_zero_names_rule_and_module():
    ls = LSystem.from_text("n: 3\nw: A(2)\np:\n A(x) -> A(1/(x-1))\n")
    with pytest.raises(DerivationError) as err:
        ls.derive()
    msg = str(err.value)
    assert "division by zero" in msg and "A(1)" in msg and "rule 1" in msg
    assert err.value.line == 4


def test_cli_check_prints_error_without_traceback(tmp_path):
    bad = tmp_path / "bad.lsys"
    bad.write_text("n: 2\nw: A\np:\n A -> B(q)\n")
    proc = subprocess.run([sys.executable, "-m", "ramure.app.cli", "check", str(bad)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "line 4" in proc.stderr and "unknown name 'q'" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_unknown_constant_override_refused():
    ls = LSystem.from_file("grammars/honda_sympodial.lsys")
    with pytest.raises(GrammarError, match="unknown constant"):
        ls.derive(constants={"nope": 1})


@pytest.mark.parametrize(
    "argv,fragment",
    [
        (["derive", "grammars/algae.lsys", "--set", "x=1"], "no constant 'x'"),
        (["regen", "grammars/algae.lsys", "--select", "a,b"], "--select: 'a' is not a leaf id"),
        (["derive", "missing.lsys"], "No such file"),
    ],
)
def test_cli_user_errors_exit_2_without_traceback(argv, fragment):
    proc = subprocess.run([sys.executable, "-m", "ramure.app.cli", *argv], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert fragment in proc.stderr and "Traceback" not in proc.stderr
