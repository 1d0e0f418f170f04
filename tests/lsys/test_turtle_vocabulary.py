"""The turtle vocabulary shared with cpfg and L-Py, each against values computed by hand."""

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys import turtle


def colours(axiom):
    return LSystem.from_text(f"n: 0\nw: {axiom}\n").derive().skeleton().color.tolist()


@pytest.mark.parametrize("compiled", [False, True])
def test_semicolon_raises_and_comma_lowers_the_colour_index(monkeypatch, compiled):
    if compiled:  # the compiled loop (numba) must agree with the plain one
        pytest.importorskip("numba")
    monkeypatch.setattr(turtle, "use_kernels", compiled)
    assert colours("F;F;;F,F") == [0, 1, 3, 2]
    assert colours(";(5)F,F,(2)F'F") == [5, 4, 2, 3]
    assert colours("F[;F]F,F") == [0, 1, 0, -1]  # ']' restores the colour


def test_a_cpfg_file_uses_the_same_colour_steps():
    d = LSystem.from_text("derivation length: 1\naxiom: A\nA --> F;F,,F\nendlsystem\n", filename="c.l").derive()
    assert np.array_equal(d.skeleton().color, [0, 1, -1])


def test_check_notes_the_modules_that_nothing_draws(tmp_path, capsys):
    from ramure.app.cli import main
    from ramure.lsys.grammar import parse_grammar
    from ramure.lsys.turtle import undrawn_symbols

    text = "#amap internode F\n#amap uc U\nn: 1\nw: A\np:\n A -> U F[+A]Q~leaf(1)B\ninterpretation:\n B -> F\n"
    assert undrawn_symbols(parse_grammar(text)) == ["Q"]  # A is rewritten, B interpreted, U an #amap mark
    path = tmp_path / "q.lsys"
    path.write_text(text)
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith("note: nothing draws Q ")
    path.write_text(text.replace("Q", ""))
    assert main(["check", str(path)]) == 0
    assert not any(line.startswith("note:") for line in capsys.readouterr().out.splitlines())


def skeleton(axiom):
    return LSystem.from_text(f"n: 0\nw: {axiom}\n").derive().skeleton()


@pytest.mark.parametrize("compiled", [False, True])
def test_hash_and_underscore_set_or_widen_the_width(monkeypatch, compiled):
    if compiled:
        pytest.importorskip("numba")
    monkeypatch.setattr(turtle, "use_kernels", compiled)
    widths = 2 * skeleton("!(0.4)F#F_F!F#(1)F_(2)F").base_radius
    assert np.allclose(widths, [0.4, 0.4 / 0.7, 0.4 / 0.49, 0.4 / 0.7, 1.0, 2.0])


def test_at_v_rolls_to_vertical_like_dollar():
    a, b = skeleton("+(30)&(40)@vF"), skeleton("+(30)&(40)$F")
    assert abs(a.normal[0, 2]) < 1e-12 and np.allclose(a.normal, b.normal)  # L ends horizontal
    # by hand: the horizontal L is z x H normalised, (-H_y, H_x, 0) / |(H_x, H_y)|
    h = a.end[0] - a.start[0]
    h /= np.linalg.norm(h)
    expected = np.array([-h[1], h[0], 0.0]) / np.hypot(h[0], h[1])
    assert np.allclose(a.normal[0], expected)


QUERY = """derivation length: 2
axiom: F(2)+(90)?P(0,0,0)[?H(0,0,0)]A
A --> F(1)?P(0,0,0)?U(0,0,0)
?P(x,y,z) --> ?P(x,y,z)B(x,z)
endlsystem
"""


@pytest.mark.parametrize("compiled", [False, True])
def test_query_modules_receive_the_turtle_state_after_each_step(monkeypatch, compiled):
    if compiled:
        pytest.importorskip("numba")
    monkeypatch.setattr(turtle, "use_kernels", compiled)
    ls = LSystem.from_text(QUERY, filename="query.l")
    modules = {f"{s}{k}": p for k, (s, p) in enumerate(ls.derive(n=1).modules)}
    # by hand: F(2) ends at (0, 0, 2); +(90) turns H = +z toward -L = (-1, 0, 0); A's F(1) then
    # goes from (0, 0, 2) to (-1, 0, 2); U stays +y
    assert np.allclose(modules["?P2"], [0, 0, 2]) and np.allclose(modules["?H5"], [-1, 0, 0])
    assert np.allclose(modules["?P8"], [-1, 0, 2]) and np.allclose(modules["?U9"], [0, 1, 0])
    # the next step's rule reads the answered values
    assert "B(0,2)" in ls.derive(n=2).to_string() and "B(-1,2)" in ls.derive(n=2).to_string()


def test_the_environment_query_is_refused_by_name():
    from ramure.errors import GrammarError

    with pytest.raises(GrammarError, match="environment program"):
        LSystem.from_text(QUERY.replace("?U(0,0,0)", "?E(1)"), filename="query.l")
