"""cpfg's C-like statements (Start:/StartEach:/EndEach:/End:/Define: blocks)."""

import re

import pytest

from ramure.errors import DerivationError, GrammarError
from ramure.lsys import LSystem
from ramure.lsys.language.cstatements import MAX_STATEMENTS, Scope, parse_program


def run(text, **variables):
    scope = Scope(dict(variables))
    parse_program(text).run(scope)
    return scope


def test_loops_conditions_and_compound_assignments():
    s = run("{ s = 0; for (i = 1, j = 10; i <= 4; i++, j -= 2) s += i * j; while (s > 50) s /= 2; }")
    # i*j = 10 + 16 + 18 + 16 = 60; 60 > 50 -> 30
    assert s.variables["s"] == 30 and s.variables["i"] == 5 and s.variables["j"] == 2
    s = run("{ n = 0; do n++; while (n < 0); if (n == 1 && !(n > 1)) k = 2^3; else k = -1; }")
    assert s.variables["n"] == 1 and s.variables["k"] == 8


def test_arrays_declarations_and_functions():
    s = run("{ array a[4] = {3, 1}; a[2] = a[0] + a[1]; a[3]++; int m = floor(7.9) + fabs(-2); float z; }")
    assert s.arrays["a"].tolist() == [3, 1, 4, 1] and s.variables["m"] == 9 and s.variables["z"] == 0
    s = run("{ x = exp(0) + log(1) + sin(90) + sqrt(16); }")
    assert s.variables["x"] == 1 + 0 + 1 + 4  # trigonometry in degrees, as everywhere in Ramure


def test_random_draws_follow_srand():
    a = run("{ srand(7); r = ran(10); q = nran(5, 0); }")
    b = run("{ srand(7); r = ran(10); }")
    assert a.variables["r"] == b.variables["r"] and 0 <= a.variables["r"] < 10 and a.variables["q"] == 5


def test_printf_formats_like_c():
    s = run('{ n = 3; printf("step %d of %.2f%%\\n", n, 12.5); }')
    assert s.printed == ["step 3 of 12.50%\n"]


@pytest.mark.parametrize(
    ("text", "column", "message"),
    [
        ("{ x = ; }", 6, "an expression is missing"),
        ("{ x = 1 }", 3, "does not end with ';'"),
        ("{ if x > 1) y = 2; }", 6, "expected '('"),
        ("{ 3 = x; }", 3, "cannot assign to '3'"),
        ('{ fprintf(f, "a"); }', 3, "'fprintf' (files and strings) is not supported"),
        ("{ x = 1 +* 2; }", 10, "found '*'"),
    ],
)
def test_syntax_errors_name_line_and_column(text, column, message):
    with pytest.raises(GrammarError, match=re.escape(message)) as info:
        parse_program(text, line=4, column=1)
    assert info.value.line == 4 and info.value.column == column


def test_runtime_errors_are_derivation_errors():
    with pytest.raises(DerivationError, match="variable 'q' is used before"):
        run("{ x = q + 1; }")
    with pytest.raises(DerivationError, match=r"index 4 is outside array a\[4\]"):
        run("{ array a[4]; a[4] = 1; }")
    with pytest.raises(DerivationError, match=f"more than {MAX_STATEMENTS:,} statements"):
        run("{ while (1) x = 1; }")


BLOCKS = """#define dt 0.5
Lsystem: 0
Define: { array a[3] = {1, 2, 3}; }
Start: {t = 0; count = 0;}
StartEach: { count = count + a[1]; }
EndEach: {t = t+dt;
   printf("t=%.1f\\n", t);
}
End: { done = 1; }
derivation length: 3
axiom: A(0)
A(x) : t < 1 --> F(t) A(count)
A(x) : t >= 1 --> B(x)
endlsystem
"""


def test_cpfg_blocks_run_in_cpfg_order_and_rules_read_the_globals():
    d = LSystem.from_text(BLOCKS, filename="blocks.l").derive()
    # step 1: count 2, t 0 -> F(0)A(2); step 2: count 4, t 0.5 -> F(0.5)A(4); step 3: t 1 -> B(4)
    assert d.to_string() == "F(0)F(0.5)B(4)"
    assert d.printed == ["t=0.5\n", "t=1.0\n", "t=1.5\n"]
    assert d.constants["done"] == 1 and d.constants["count"] == 6
    again = LSystem.from_text(BLOCKS, filename="blocks.l").derive(n=1)
    assert again.to_string() == "F(0)A(2)"  # every derivation starts from Define and Start again


def test_a_block_error_points_at_the_l_file():
    with pytest.raises(GrammarError) as info:
        LSystem.from_text(BLOCKS.replace("t = t+dt;", "t = t+;"), filename="blocks.l")
    assert info.value.line == 6 and info.value.column == 17  # the ";" that ends "t+"
    with pytest.raises(GrammarError, match="never closed"):
        LSystem.from_text(BLOCKS.replace("}\nEnd:", "\nEnd:"), filename="blocks.l")


def test_production_blocks_run_module_by_module_in_string_order():
    text = (
        "Lsystem: 0\nStart: {n = 0;}\nderivation length: 3\naxiom: A(1)B(5)A(2)\n"
        "A(x) : {y = x*2; n = n + 1;} y > 2 {z = n;} --> F(y)A(z)\n"
        "B(x) --> B(x+1)\nendlsystem\n"
    )
    ls = LSystem.from_text(text, filename="blocks.l")
    # step 1: A(1) sets n = 1 and fails; A(2) sets n = 2, passes, z = 2
    assert ls.derive(n=1).to_string() == "A(1)B(6)F(4)A(2)"
    assert ls.derive(n=3).to_string() == "A(1)B(8)F(4)F(4)F(8)A(6)"


def test_a_production_whose_blocks_go_over_several_lines():
    text = (
        "derivation length: 2\naxiom: A(1)\n"
        "A(s) : s < 3 {        // to the first power of two above 10\n"
        "   t = s;\n"
        "   while (t < 10) { t = t * 2; }\n"
        "} --> F(t) A(s+1)\n"
        "   [+B]\n"
        "B : { k = 1; } --> C\nendlsystem\n"
    )
    ls = LSystem.from_text(text, filename="blocks.l")
    assert ls.derive().to_string() == "F(16)F(16)A(3)[+B][+C]"
    with pytest.raises(GrammarError) as info:
        LSystem.from_text(text.replace("t = t * 2;", "t = t * ;"), filename="blocks.l")
    assert info.value.line == 5 and info.value.column == 28  # just after "t *"


def test_decomposition_rules_with_blocks():
    text = (
        "#define PL 1\nderivation length: 1\naxiom: A(3)\ndecomposition\nmaximum depth: 10\n"
        "A(t) : {t=t-PL;} t>0 --> I(t)A(t)\nendlsystem\n"
    )
    # the block lowers the formal before the condition: A(3) -> I(2)A(2) -> I(2)I(1)A(1); then
    # t = 0 fails the condition and A(1) stays as it was
    assert LSystem.from_text(text, filename="d.l").derive(n=0).to_string() == "I(2)I(1)A(1)"


def test_the_command_line_shows_printf_on_stderr(tmp_path, capsys):
    from ramure.app.cli import main

    path = tmp_path / "steps.l"
    path.write_text('Start: {n = 0;}\nEndEach: {n = n + 1; printf("step %d\\n", n);}\nderivation length: 2\naxiom: F\n')
    assert main(["derive", str(path)]) == 0
    out = capsys.readouterr()
    assert out.out.strip() == "F" and out.err == "step 1\nstep 2\n"
