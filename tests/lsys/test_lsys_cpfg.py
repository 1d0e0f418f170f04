"""L-studio/cpfg ``.l`` files (issue 15, part B): ABOP figures derive to the shipped grammars'
strings; what is not supported is refused at the ``.l`` file's own line and column."""

import pathlib
import pytest

from ramure.lsys import GrammarError, LSystem
from ramure.lsys.language.cpfg import parse_cpfg, to_lsys, translate
from ramure.lsys.interpretation.homomorphism import interpreted_text

HERE = pathlib.Path(__file__).parent / "cpfg"


@pytest.mark.parametrize(
    "cpfg, shipped",
    [
        ("abop_1_24a.l", "plant_1_24a"),  # bracketed OL-system, fig. 1.24a
        ("abop_1_25.l", "abop/bush_1_25"),  # rolls, colour steps and polygons, fig. 1.25
        ("abop_1_31a.l", "context_plant"),  # context-sensitive with ignore:, fig. 1.31a
    ],
)
def test_abop_figures_derive_to_the_shipped_grammars_strings(cpfg, shipped):
    imported = LSystem.from_file(HERE / cpfg)
    reference = LSystem.from_file(shipped)
    assert imported.grammar.n == reference.grammar.n
    assert imported.derive().to_string() == reference.derive().to_string()


def test_abop_1_26_flowering_plant_matches_the_shipped_grammar_module_for_module():
    text = (HERE / "abop_1_26.l").read_text()
    imported = LSystem.from_text(to_lsys(text, "abop_1_26.l", angle=18)).derive()
    shipped = LSystem.from_file("abop/plant_1_26").derive()
    names = dict(P="plant", I="internode", S="seg", L="leaf", K="flower", D="pedicel", W="wedge")
    assert [names.get(s, s) for s in imported.symbols] == shipped.symbols  # 15,325 modules
    assert len(imported) == 15325
    ours, theirs = imported.skeleton().polygons, shipped.skeleton().polygons
    assert len(ours) == len(theirs) == 327  # leaves and petal wedges
    assert sorted(ours.areas()) == pytest.approx(sorted(theirs.areas()))


def test_homomorphism_and_decomposition_sections_read_as_lsys_sections():
    ls = LSystem.from_file(HERE / "compound_leaf.l")
    g = ls.grammar
    assert (len(g.rules), len(g.interpretation), len(g.decomposition)) == (2, 2, 1)
    assert (g.interpretation_depth, g.decomposition_depth) == (2, 1)
    same = LSystem.from_text(
        "#define R 1.2\n#define D 45\nn: 6\nw: A\np:\n  A -> I(1)[+(D)K][-(D)K]A\n  I(s) -> I(s*R)\n"
        "interpretation:\n  I(s) -> F(s)\n  L -> {-(20)f(1)+(40)f(1)+(140)f(1)}\n#interpretation_depth 2\n"
        "decomposition:\n  K -> [+(20)L][-(20)L]\n"
    )
    d, e = ls.derive(), same.derive()
    assert d.to_string() == e.to_string()
    assert "K" not in d.to_string() and d.count("L") == 4 * 6  # each step's two leaflets, halved
    assert interpreted_text(d) == interpreted_text(e)
    sk = d.skeleton()
    assert len(sk) == 6 and len(sk.polygons) == 4 * 6  # six internodes, 24 half-leaflets
    assert set(d.symbols[p] for p in d.tree.leaf_positions(sk.polygons.leaf_id)) == {"L"}


def test_translation_keeps_every_line_in_place():
    text = (HERE / "compound_leaf.l").read_text()
    assert len(translate(text).split("\n")) == len(text.split("\n"))


def test_cpfg_keywords_and_functions():
    g = parse_cpfg(
        "#define f(x) (x*2)\nLsystem: 1\nseed: 4\nderivation length: 1\nconsider: BA\n"
        "axiom: B(f(3))FA\nB(x) < A --> A(ran(1))\nA(x) --> B(nran(0, 1)) : 2\nA(x) --> B(1) : 1\n"
        "endlsystem\nanything after endlsystem is not read\n"
    )
    assert g.n == 1 and g.axiom[0].args[0].text.strip() == "f(3)"
    derived = LSystem(g).derive().modules
    assert derived[:2] == [("B", (6.0,)), ("F", ())] and derived[2][0] == "A" and 0 <= derived[2][1][0] < 1
    assert g.ignore == frozenset({"F"})  # consider: B A -> every other symbol is ignored
    assert [r.probability for r in g.rules[1:]] == pytest.approx([2 / 3, 1 / 3])


@pytest.mark.parametrize(
    "text, line, column, fragment",
    [
        ('#include "plant.v"\n', 1, 1, "#include"),
        ("#ifdef X\n", 1, 1, "#ifdef"),
        ("axiom: A\nA --> F?E(1)\n", 2, 8, "talks to an environment program"),
        ("axiom: A\nA --> [?(1)]\n", 2, 8, "sub-L-system call"),
        ("axiom: A\nA --> F?(1,2)\n", 2, 8, "sub-L-system"),
        ("axiom: A\nA --> F@Gr(1)\n", 2, 8, "@Gr (generalised cylinders)"),
        ("axiom: A(1)\nA(x) : {y=x;} y>1 {z=1;} {w=2;} --> B\n", 2, 8, "cannot read the blocks"),
        ("start: {n=0;\naxiom: A\n", 1, 1, "'start:' block's '{' is never closed"),
        ("Lsystem: 1\naxiom: A\nendlsystem\nLsystem: 2\n", 4, 1, "sub-L-systems"),
        ("axiom: A\nmaximum depth: 2\n", 2, 1, "belongs after"),
        ("axiom: A\nA -> B\nwhat: is this\n", 3, 1, "not supported"),
        ("axiom: A(1)\nA(x) --> B(x*qq)\n", 2, 14, "unknown name 'qq'"),  # column mapped back
        ("axiom: A(1)\nA(x) --> B(ran(2)*qq)\n", 2, 19, "unknown name 'qq'"),  # after a renamed function
        ("derivation length: -1\naxiom: A\n", 1, 19, "whole number"),
    ],
)
def test_unsupported_constructs_are_errors_at_the_l_files_line_and_column(text, line, column, fragment):
    with pytest.raises(GrammarError) as info:
        parse_cpfg("derivation length: 1\n" * ("derivation" not in text) + text, "plant.l")
    err = info.value
    shift = "derivation" not in text
    assert (err.line, err.column) == (line + shift, column), str(err)
    assert fragment in err.message
    assert err.filename == "plant.l"
    source = str(err).splitlines()
    assert source[-2].strip() == (("derivation length: 1\n" * shift + text).split("\n")[err.line - 1]).strip()
    assert source[-1] == " " * (column + 1) + "^"


def test_from_file_errors_name_the_l_file(tmp_path):
    bad = tmp_path / "bad.l"
    bad.write_text("derivation length: 2\naxiom: A\nA --> F?E\n")
    with pytest.raises(GrammarError) as info:
        LSystem.from_file(bad)
    assert str(bad) in str(info.value) and "line 3, column 8" in str(info.value)


def test_to_lsys_writes_a_grammar_that_derives_the_same(tmp_path):
    source = (HERE / "abop_1_24a.l").read_text()
    lsys = to_lsys(source, "abop_1_24a.l", angle=25.7)
    assert lsys.splitlines()[1] == "#angle 25.7"
    assert LSystem.from_text(lsys).derive().to_string() == LSystem.from_file(HERE / "abop_1_24a.l").derive().to_string()


def test_cli_import_and_check(tmp_path, capsys):
    from ramure.app.cli import main

    out = tmp_path / "leaf.lsys"
    assert main(["import", str(HERE / "compound_leaf.l"), "-o", str(out)]) == 0
    assert "2 production(s), 2 interpretation and 1 decomposition rule(s), n = 6" in capsys.readouterr().out
    assert LSystem.from_file(out).derive().to_string() == LSystem.from_file(HERE / "compound_leaf.l").derive().to_string()
    bad = tmp_path / "bad.l"
    bad.write_text("derivation length: 2\naxiom: A\nA --> F?E(1)\n")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"ramure check: {bad}, line 3, column 8: the communication module ?E talks")
    assert "environment program" in err and "Traceback" not in err
    assert main(["import", str(bad), "-o", str(tmp_path / "bad.lsys")]) == 2
    assert not (tmp_path / "bad.lsys").exists()
    assert main(["import", str(HERE / "compound_leaf.l"), "-o", str(tmp_path / "x.txt")]) == 2
    assert "ending with .lsys" in capsys.readouterr().err


def test_missing_keywords_are_named_in_cpfg_words():
    with pytest.raises(GrammarError, match="add a line 'derivation length: ...'"):
        parse_cpfg("Lsystem: 1\naxiom: A\nendlsystem\n")
    with pytest.raises(GrammarError, match="add a line 'axiom: ...'"):
        parse_cpfg("derivation length: 3\nA --> B\n")


def test_polygons_spheres_and_cut_read_from_a_cpfg_file():
    g = parse_cpfg("derivation length: 2\naxiom: A\nA --> F[+L]@O(0.1)A\nhomomorphism\nL --> {.-f.+f.+f.}\nendlsystem\n")
    d = LSystem(g).derive()
    sk = d.skeleton()
    assert len(sk.polygons) == 2 and len(sk) == 2
    assert [d.symbols[p] for p in d.tree.leaf_positions(sk.polygons.leaf_id)] == ["L", "L"]
    assert (sk.organs.kind == "@O").sum() == 2


def test_a_session_on_a_cpfg_file_saves_and_loads(tmp_path):
    from ramure.lsys.regeneration.regen import Session

    s = Session(LSystem.from_file(HERE / "compound_leaf.l"), n=4, seed=3)
    s.regrow(s.leaves_with_symbol("L")[:1], rho=0.5, seed=2)
    s.save(tmp_path / "session.json")
    again = Session.load(tmp_path / "session.json")
    assert again.derivation.to_string() == s.derivation.to_string()


def test_keywords_may_come_between_productions():
    g = parse_cpfg("derivation length: 2\nA --> AB\naxiom: A\nB --> C\nignore: F\nC --> D\n")
    assert [str(r.pred) for r in g.rules] == ["A", "B", "C"] and g.ignore == frozenset({"F"})


def test_derivation_errors_point_at_the_l_files_rule():
    from ramure.lsys import DerivationError

    with pytest.raises(DerivationError) as info:
        LSystem.from_text("derivation length: 1\naxiom: A(0)\nA(x) --> B(1/x)\n", "plant.l").derive()
    err = info.value
    assert (err.line, err.column) == (3, 1) and "rule 1 (A(x) --> B(1/x))" in err.message
    assert str(err).splitlines()[-2].strip() == "A(x) --> B(1/x)"


def test_comments_continuations_and_successors_over_several_lines():
    text = (
        "derivation length: 1\n"
        "#define W(x) \\\n"
        "   (x*2)\n"
        "axiom: A(1) // the apex\n"
        "A(x) --> F(W(x)) // a comment, not rolls\n"
        "   [+F(x)]\n"
        "   F(3)\n"
        "F(x) --> F(x) \\\n"
        "   G/////G\n"
        "endlsystem\n"
    )
    ls = LSystem.from_text(text, filename="multi.l")
    assert [str(r) for r in ls.grammar.rules][0].startswith("A(x) -->")
    assert ls.derive().to_string() == "F(2)[+F(1)]F(3)"
    assert ls.derive(n=2).to_string() == "F(2)G/////G[+F(1)G/////G]F(3)G/////G"


def test_a_condition_over_several_lines_and_cpfg_functions_in_defines():
    text = (
        "#define ANGLE nran(80, 0)\nderivation length: 1\naxiom: A(1)A(-1)\n"
        "A(x) : fabs(x) < 2\n"
        "   && x > 0\n"
        "   --> F(ANGLE)\n"
        "endlsystem\n"
    )
    assert LSystem.from_text(text, filename="heads.l").derive().to_string() == "F(80)A(-1)"


def test_a_deep_maximum_depth_is_a_cap():
    """cpfg files write ``maximum depth: 500``: rounds stop once no rule applies."""
    text = "derivation length: 1\naxiom: A\nA --> B\ndecomposition\nmaximum depth: 500\nB --> C\nC --> F\nendlsystem\n"
    d = LSystem.from_text(text, filename="deep.l").derive()
    assert d.to_string() == "F"


def test_homomorphism_no_warnings_after_the_productions_opens_the_section():
    text = "derivation length: 1\naxiom: A\nA --> AB\nhomomorphism: no warnings\nB --> [F]\nendlsystem\n"
    d = LSystem.from_text(text, "h.l").derive()
    assert d.to_string() == "AB" and interpreted_text(d) == "A[F]"
