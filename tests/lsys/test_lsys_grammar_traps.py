"""The grammar language has no silent traps (issue 11): every line is a rule, a directive
or an error; comments never eat turtle symbols; ABOP's wildcard context and the cpfg
weight suffix mean what they mean in ABOP and cpfg."""

import pytest

from ramure.lsys import GrammarError, LSystem
from ramure.lsys.language.grammar import parse_grammar, strip_comments

HEAD = "n: 1\nw: A\np:\n"


def derive(text, **kw):
    return LSystem.from_text(text).derive(**kw)


# -- a line that is not a rule is an error, never part of the previous successor --------


@pytest.mark.parametrize(
    "line, column, fragment",
    [
        (" B => A", 4, "'=>' is not a rule arrow"),
        ("endlsystem", 1, "'endlsystem' is a cpfg keyword"),  # homomorphism:/decomposition: open sections
        ("  axiom: B", 3, "'axiom' is a cpfg keyword"),
        (" B", 2, "not a rule (no '->')"),
        ("  F[+F]F", 3, "not a rule (no '->')"),  # what an indented continuation used to be
    ],
)
def test_a_line_that_is_not_a_rule_is_an_error_at_its_column(line, column, fragment):
    with pytest.raises(GrammarError) as info:
        parse_grammar(HEAD + " A -> B\n" + line + "\n")
    err = info.value
    assert (err.line, err.column) == (5, column)
    assert fragment in err.message
    assert str(err).splitlines()[-1] == " " * (column + 1) + "^"  # the caret sits under the column


def test_a_successor_ends_at_the_end_of_its_line():
    g = parse_grammar(HEAD + " A -> B\n B -> C\n")
    assert [[str(m) for m in r.successor] for r in g.rules] == [["B"], ["C"]]


def test_a_line_ending_with_the_continuation_mark_continues_the_successor():
    text = HEAD + " A -> B[+F] ...\n   /* a comment line is skipped */\n\n      C(1) ...\n   D\n B -> E\n"
    g = parse_grammar(text)
    assert [str(m) for m in g.rules[0].successor] == ["B", "[", "+", "F", "]", "C(1)", "D"]
    assert [str(m) for m in g.rules[1].successor] == ["E"]
    assert derive(text).to_string() == "B[+F]C(1)D"


def test_the_axiom_continues_too():
    assert derive("n: 0\nw: A B ...\n  C\n").to_string() == "ABC"


@pytest.mark.parametrize(
    "text, line, fragment",
    [
        (HEAD + " A -> B ...\n", 4, "no line follows"),
        (HEAD + " A -> B ...\n B -> C\n", 5, "line 4 ends with '...'"),
        (HEAD + " A -> B ...\n#define k 1\n", 5, "not the rest of its successor"),
        (HEAD + " A -> B -> C\n", 4, "second '->'"),
    ],
)
def test_a_bad_continuation_is_an_error(text, line, fragment):
    with pytest.raises(GrammarError) as info:
        parse_grammar(text)
    assert info.value.line == line and fragment in info.value.message


def test_shipped_honda_continues_its_first_rule_with_the_mark():
    g = LSystem.from_file("honda_sympodial").grammar
    assert [m.symbol for m in g.rules[0].successor].count("B") == 2  # both branches of A's rule


# -- comments never eat turtle symbols ---------------------------------------------------


def test_bush_rolls_are_modules_not_a_comment():
    # ABOP fig. 1.25, p1: 35 modules at n = 1 ('//' used to start a comment: 7 modules).
    d = derive("#angle 22.5\nn: 1\nw: A\np:\n  A -> [&FL!A]/////'[&FL!A]///////'[&FL!A]\n")
    assert len(d) == 35 and d.count("/") == 12


def test_hilbert_trailing_rolls_are_modules():
    d = derive("n: 1\nw: A\np:\n A -> B-F+CFC+F-D&F^D-F+&&CFC+F+B//\n")
    assert d.to_string().endswith("+B//") and d.count("/") == 2


def test_rolls_written_with_spaces_stay_modules():
    # ABOP typesets p2 of fig. 1.25 as 'F -> S ///// F'.
    d = derive("n: 1\nw: F\np:\n F -> S ///// F\n")
    assert d.to_string() == "S/////F"


@pytest.mark.parametrize(
    "text, expected",
    [
        ("// a whole-line comment\nn: 1\nw: A\np:\n A -> B\n", "B"),
        ("n: 1 // steps\nw: A\np: // rules follow\n A -> B\n", "B"),
        ("#define k 2 // a constant\nn: 1\nw: A(1)\np:\n A(x) -> B(x*k)\n", "B(2)"),
        ("n: 1\nw: A\np:\n A -> B /* a block comment */ C\n", "BC"),
        ("n: 1\nw: A\np:\n A -> B /* a block comment\n  over // two lines */\n B -> C\n", "B"),
        ("n: 1\nw: A /* axiom */\np:\n  // the rules\n A -> B\n", "B"),
    ],
)
def test_comments_that_cannot_collide_with_slash(text, expected):
    assert derive(text).to_string() == expected


def test_strip_comments_keeps_columns_and_lines():
    text = "#angle 30 // deg\nw: F//F /* c */\n  // note\n"
    out = strip_comments(text)
    assert len(out) == len(text) and out.count("\n") == text.count("\n")
    assert out.splitlines() == ["#angle 30       ", "w: F//F        ", "         "]


def test_text_after_a_multi_line_comment_is_its_own_line():
    # A block comment does not join lines: the rule still ends at the end of its line.
    with pytest.raises(GrammarError) as info:
        parse_grammar(HEAD + " A -> B /* one\n two */ C\n")
    assert (info.value.line, info.value.column) == (5, 9) and "not a rule" in info.value.message


def test_rule_error_columns_survive_comments():
    with pytest.raises(GrammarError) as info:
        parse_grammar("n: 1\nw: A\np:\n /* x */ A -> B(r)\n")
    assert (info.value.line, info.value.column) == (4, 17)


# -- ABOP's wildcard context and ',' --------------------------------------------------


def test_wildcard_context_matches_any_neighbour_or_none():
    # ABOP fig. 1.31: * < + > * -> -  (today's bug: it never matched)
    text = "n: 1\nw: +F+[+F]F+\np:\n * < + > * -> -\n"
    assert derive(text).to_string() == "-F-[-F]F-"


def test_wildcard_on_one_side_keeps_the_other_context():
    # B between A and C takes the first context rule (file order); B after A, before B, the
    # second; the last B (left B, no right) neither.
    text = "n: 1\nw: ABC AB B\np:\n * < B > C -> X\n A < B > * -> Y\n"
    assert derive(text).to_string() == "AXCAYB"


def test_wildcard_cannot_be_mixed_into_a_context():
    with pytest.raises(GrammarError) as info:
        parse_grammar(HEAD + " A * < B -> C\n")
    assert "'*' stands for a whole context" in info.value.message and info.value.column == 4


def test_comma_between_modules_is_the_colour_down_module():
    rule = parse_grammar(HEAD + " A -> B,C\n").rules[0]
    assert [m.symbol for m in rule.successor] == ["B", ",", "C"]  # cpfg's and L-Py's ','


def test_commas_separate_ignored_symbols():
    a = parse_grammar("#ignore: +, -, F\n" + HEAD + " A -> B\n")
    b = parse_grammar("#ignore: + - F\n" + HEAD + " A -> B\n")
    assert a.ignore == b.ignore == frozenset("+-F")


# -- cpfg / L-studio weight suffix ----------------------------------------------------


def test_weight_suffix_is_a_stochastic_weight():
    text = "#define wb 3\nn: 1\nw: " + "A" * 4000 + "\np:\n A -> B : wb\n A -> C : 1\n"
    g = parse_grammar(text)
    assert [r.probability for r in g.rules] == [0.75, 0.25]
    assert [str(m) for m in g.rules[0].successor] == ["B"]
    d = derive(text, seed=3)
    share = d.count("B") / len(d)
    assert abs(share - 0.75) < 0.03 and d.count("B") + d.count("C") == 4000


def test_weight_suffix_equals_the_same_probability_prefix():
    suffix = LSystem.from_text("n: 3\nw: A\np:\n A -> AB : 0.5\n A -> BA : 0.5\n").derive(seed=7)
    prefix = LSystem.from_text("n: 3\nw: A\np:\n .5 A -> AB\n .5 A -> BA\n").derive(seed=7)
    assert suffix.to_string() == prefix.to_string()


def test_weight_suffix_on_a_continued_line_and_with_a_condition():
    g = parse_grammar("n: 1\nw: A(1)\np:\n A(x) : x > 0 -> B ...\n   C : 2\n A(x) : x > 0 -> D : 2\n")
    assert [str(m) for m in g.rules[0].successor] == ["B", "C"]
    assert [r.probability for r in g.rules] == [0.5, 0.5]


@pytest.mark.parametrize(
    "rules, fragment",
    [
        (" A -> B : 0\n", "weight must be a number > 0"),
        (" A -> B : -1\n", "weight must be a number > 0"),
        (" A -> B :\n", "starts a weight"),
        (" A -> B : 0.5\n A -> C\n", "mix weights and none"),
        (" A -> B : 0.5\n .5 A -> C\n", "mix probability prefixes"),
        (" .5 A -> B : 0.5\n", "not both"),
    ],
)
def test_bad_weights_are_refused(rules, fragment):
    with pytest.raises(GrammarError) as info:
        parse_grammar(HEAD + rules)
    assert fragment in info.value.message and info.value.line is not None
