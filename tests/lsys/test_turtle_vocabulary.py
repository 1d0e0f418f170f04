"""The turtle vocabulary shared with cpfg and L-Py, each against values computed by hand."""

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys.interpretation import turtle


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
    from ramure.lsys.language.grammar import parse_grammar
    from ramure.lsys.interpretation.turtle import undrawn_symbols

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


# -- the commands of several parameters (ramure.lsys.interpretation._turtle_rich), values computed by hand --------


def lpy_skeleton(axiom, head=""):
    from ramure.lsys.readers.lpy import LpyLSystem

    return LpyLSystem(f"{head}\nAxiom: {axiom}\nderivation length: 1\nendlsystem\n").derive().skeleton()


def cpfg_skeleton(axiom):
    return LSystem.from_text(f"derivation length: 0\naxiom: {axiom}\nendlsystem\n", filename="c.l").derive().skeleton()


def test_at_m_moves_without_drawing():
    s = skeleton("F@M(1,2,3)F")
    assert s.start.tolist() == [[0, 0, 0], [1, 2, 3]] and s.end.tolist() == [[0, 0, 1], [1, 2, 4]]
    s = lpy_skeleton("F MoveRel(1,0,0) F")
    assert s.start[1].tolist() == [1, 0, 1]


def test_at_r_sets_heading_and_up():
    s = skeleton("@R(1,0,0,0,0,1)F")
    assert s.end.tolist() == [[1, 0, 0]]
    assert np.allclose(s.normal[0], [0, 1, 0])  # L = U x H = z x x = y
    s = skeleton("@R(1,0,0)F")  # the old up (0,1,0) kept: L = y x x = -z
    assert np.allclose(s.normal[0], [0, 0, -1])


def test_line_to_keeps_and_oline_to_turns_the_heading():
    a = lpy_skeleton("LineTo(0,0,2)[LineTo(0,1,3)F]LineTo(0,0,3)")
    assert a.end.tolist() == [[0, 0, 2], [0, 1, 3], [0, 1, 4], [0, 0, 3]]
    b = lpy_skeleton("LineTo(0,0,2)[OLineTo(0,1,3)F]LineTo(0,0,3)")
    r = 1 / np.sqrt(2)
    assert np.allclose(b.end[2], [0, 1 + r, 3 + r])
    c = lpy_skeleton("F LineRel(1,0,0) LineTo(Vector3(1,0,3), 0.5) F")
    assert c.start[1].tolist() == [0, 0, 1] and c.end[1].tolist() == [1, 0, 1]
    assert c.end[2].tolist() == [1, 0, 3]
    assert 2 * c.base_radius[3] == 0.5  # the top diameter given is the width from there on


def test_pinpoint_turns_toward_a_point():
    s = lpy_skeleton("Pinpoint(3,0,0) F")
    assert np.allclose(s.end[0], [1, 0, 0])


def test_at_tp_sets_the_tropism_direction():
    s = skeleton("@Tp(1,0,0)@Ts(0.1)FF")
    # after the first F, H turns toward +x by 0.1 * |H x T| = 0.1 rad
    assert np.allclose(s.end[1], [np.sin(0.1), 0, 1 + np.cos(0.1)])
    s = skeleton("@Ts(0.1)[@Tp(1,0,0)F]FF")  # ']' restores the direction (-z: no bend of an upright F)
    assert np.allclose(s.end[2], [0, 0, 2])


def test_circles_and_discs():
    s = skeleton("F@o(0.5)")
    pts = s.polygons.points
    assert len(s.polygons) == 1 and len(pts) == 16
    assert np.allclose(np.linalg.norm(pts - [0, 0, 1], axis=1), 0.5) and np.allclose(pts[:, 2], 1)  # across H
    c = cpfg_skeleton("F@o(0.5)")  # cpfg: a diameter
    assert np.allclose(np.linalg.norm(c.polygons.points - [0, 0, 1], axis=1), 0.25)
    d = skeleton("!(2)@c")  # the H-L plane (U = y), diameter = the width
    assert np.allclose(np.linalg.norm(d.polygons.points, axis=1), 1) and np.allclose(d.polygons.points[:, 1], 0)


def test_at_b_draws_a_box_and_the_turtle_stays():
    s = skeleton("@B(2,0.5)F")
    assert len(s.polygons) == 6 and s.start.tolist() == [[0, 0, 0]]
    pts = s.polygons.points
    assert pts.min(0).tolist() == [-0.5, -0.5, 0] and pts.max(0).tolist() == [0.5, 0.5, 2]
    tris, _ = s.polygons.triangles()
    assert len(tris) == 12


def test_frame_draws_three_arrows():
    s = lpy_skeleton("F Frame(2)")
    assert len(s.polygons) == 3
    far = s.polygons.points[np.linalg.norm(s.polygons.points - [0, 0, 1], axis=1) > 1.9]
    assert sorted(map(tuple, far.round(9).tolist())) == [(0, 0, 3), (0, 2, 1), (2, 0, 1)]  # H, U, L tips


def test_cpfg_generalised_cylinder_follows_a_hermite_curve():
    s = cpfg_skeleton("@GsF@R(1,0,0)@Gc(2)F@Ge")
    # p0 = 0, t0 = 1.2 z; p1 = z, t1 = 1.2 x; at t = 1/2: 0.125 t0 + 0.5 p1 - 0.125 t1
    assert np.allclose(s.end[0], [-0.15, 0, 0.65]) and np.allclose(s.end[1], [0, 0, 1])
    assert np.allclose(s.end[2], [1, 0, 1]) and len(s) == 3  # the F inside only move
    lpy = lpy_skeleton("@Gc F F @Ge")  # L-Py's StartGC/EndGC: the segments as they are
    assert lpy.end.tolist() == [[0, 0, 1], [0, 0, 2]]


def test_set_guide_moves_along_the_rescaled_curve():
    head = "from openalea.plantgl.all import Polyline2D\nC0 = Polyline2D([(0, 0), (2, 0), (2, 2)])\n"
    s = lpy_skeleton("SetGuide(C0, 2) F(0.5)F(0.5)F(0.5)F(0.5)F(1) EndGuide F", head)
    # the curve of length 4 rescaled to 2: up (x = H) by 1, then along y = L (+x) by 1, then straight on
    assert np.allclose(s.end[:5], [[0, 0, 0.5], [0, 0, 1], [0.5, 0, 1], [1, 0, 1], [2, 0, 1]])
    assert np.allclose(s.end[5], [3, 0, 1])


def test_set_contour_and_sweep_draw_the_section():
    head = "from openalea.plantgl.all import Polyline2D\nS = Polyline2D([(1,0),(0,1),(-1,0),(0,-1),(1,0)])\n"
    s = lpy_skeleton("SetContour(S) _(2) F", head)
    assert len(s) == 0 and len(s.polygons) == 4  # four quads, no tube
    pts = s.polygons.points
    assert np.allclose(np.linalg.norm(pts[:, :2], axis=1), 1) and set(pts[:, 2].round(9)) == {0, 1}
    head += "P = Polyline2D([(0,0),(1,0)])\n"
    w = lpy_skeleton("Sweep(P, S, 2, 1, 0.5) F", head)
    assert len(w.polygons) == 8 and np.allclose(np.linalg.norm(w.polygons.points[:, :2], axis=1), 0.5)
    assert w.start.tolist() == [[0, 0, 2]]  # the sweep moved the turtle, then a plain tube


def test_interpolate_colors_blends_two_materials():
    text = "#module InterpolateColors\n#material 1 1 0 0\n#material 2 0 0 1\nn: 0\n"
    s = LSystem.from_text(text + "w: InterpolateColors(1,2,0.25)F InterpolateColors(1,2,0.25)F ;(2)F\n").derive().skeleton()
    assert s.color.tolist() == [3, 3, 2]  # one new material for the blend, after the table's
    assert np.allclose(s.extra["materials"][3], [0.75, 0, 0.25, 1])
    mesh = s.to_polydata()
    assert 3 in set(np.asarray(mesh.cell_data["material"]).tolist())
    # without both in the table: the index nearest the blend
    plain = lpy_skeleton("InterpolateColors(1, 5, 0.25) F InterpolateColors(1, 5, 0.9) F")
    assert plain.color.tolist() == [2, 5]


def test_tilde_l_is_the_predefined_leaf():
    s = skeleton("F~l(2)")
    assert s.organs.kind.tolist() == ["~l"]
    mesh = s.to_polydata()
    assert np.isclose(mesh.bounds[5], 3)  # the leaf's tip: 1 + 2 along H


def test_check_knows_the_new_commands():
    from ramure.lsys.language.grammar import parse_grammar
    from ramure.lsys.interpretation.turtle import undrawn_symbols

    text = "n: 0\nw: @M(1,2,3)@R(1,0,0)@Tp(0,0,1)@o(1)@c(1)@B(1,1)@Gs@Gc@Ge~l(1)\n"
    assert undrawn_symbols(parse_grammar(text)) == []


def test_query_modules_see_the_new_commands():
    d = LSystem.from_text("derivation length: 1\naxiom: A\nA --> @M(1,2,3)F?P(0,0,0)\nendlsystem\n", filename="c.l").derive()
    assert d.to_string() == "@M(1,2,3)F?P(1,2,4)"


def test_cylinder_resolutions_are_read_and_change_nothing_drawn():
    plain = cpfg_skeleton("F@Gs F@Gc(2)")
    hinted = cpfg_skeleton("@#(6)F@!(3)@Gs F@Gc(2)")
    assert np.array_equal(plain.end, hinted.end) and len(plain) == 3


def test_n_f_draws_pieces_on_the_guide_and_branches_inherit_it():
    s = lpy_skeleton("nF(2, 0.5) nF(1, 0.5, 0.25)")
    assert s.end[:, 2].tolist() == [0.5, 1, 1.5, 2, 2.5, 3]
    assert np.allclose(s.base_radius[4:], 0.25)  # the radius given sets the width: 2 * 0.25
    head = "from openalea.plantgl.all import Polyline2D\nC0 = Polyline2D([(0, 0), (2, 0), (2, 2)])\n"
    g = lpy_skeleton("SetGuide(C0, 2) F(0.5) [F(1)] F(1)", head)
    # the branch goes on along its copy of the guide; the parent resumes where it was
    assert np.allclose(g.end, [[0, 0, 0.5], [0.5, 0, 1], [0.5, 0, 1]])


def test_a_guide_or_contour_that_is_not_a_curve_is_refused():
    from ramure.lsys.errors import DerivationError

    with pytest.raises(DerivationError, match=r"SetGuide \(and Sweep\) take a curve.*not SetGuide\(3"):
        lpy_skeleton("SetGuide(3, 2) F")
    with pytest.raises(DerivationError, match="SetContour"):
        lpy_skeleton("SetContour('round') F")


def test_a_3d_guide_goes_along_u_too():
    head = "from openalea.plantgl.all import Polyline\nC = Polyline([(0, 0, 0), (1, 0, 0), (1, 0, 1)])\n"
    s = lpy_skeleton("SetGuide(C, 2) F F", head)
    assert np.allclose(s.end, [[0, 0, 1], [0, 1, 1]])  # z of the curve along U = +y
