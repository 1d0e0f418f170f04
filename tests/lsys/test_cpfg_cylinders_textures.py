"""cpfg's ``@Gt`` (tangent coefficients of generalised cylinders) and ``@Tx`` (textures), issue 36.

A straight cylinder from 0 to H (chord 1) drawn in 2 pieces: the Hermite midpoint is
0.5 p0 + 0.125 t0 + 0.5 p1 - 0.125 t1 with t0 = c_leave H and t1 = c_arrive H, so it stands at
0.5 + 0.125 (c_leave - c_arrive) along H (worked out by hand)."""

import numpy as np
import pytest

from ramure.lsys import LSystem


def midpoint(axiom):
    sk = LSystem.from_text(f"derivation length: 0\naxiom: {axiom}\n", "g.l").derive().skeleton()
    return sk.end[:, 2].tolist()


def test_default_tangents_put_the_midpoint_half_way():
    assert midpoint("@Gsf(1)@Ge(2)") == pytest.approx([0.5, 1.0])


def test_gt_sets_the_arriving_coefficient_of_the_next_control_point():
    assert midpoint("@Gsf(1)@Gt(4,1)@Ge(2)") == pytest.approx([0.5 + 0.125 * (1.2 - 4), 1.0])  # 0.15


def test_gt_sets_the_leaving_coefficient_of_the_control_points_after_it():
    # first piece: leave 1.2 (from @Gs), arrive 1.2; second: leave 0 (the @Gc's), arrive 1.2
    ends = midpoint("@Gsf(1)@Gt(1.2,0)@Gc(2)f(1)@Ge(2)")
    assert ends == pytest.approx([0.5, 1.0, 1.0 + 0.5 + 0.125 * (0 - 1.2), 2.0])
    # a control point keeps the coefficients it was made with: a later @Gt leaves it alone
    assert midpoint("@Gsf(1)@Gc(2)@Gt(1.2,0)f(1)@Ge(2)")[2] == pytest.approx(1.5)


def test_one_parameter_sets_both_and_a_branch_keeps_its_own():
    assert midpoint("@Gsf(1)@Gt(2)@Ge(2)") == pytest.approx([0.4, 1.0])
    assert midpoint("[@Gt(4)]@Gsf(1)@Ge(2)") == pytest.approx([0.5, 1.0])  # ']' restores 1.2


def test_tx_is_read_not_drawn_and_check_notes_it(tmp_path, capsys):
    from ramure.app.cli import main

    plain = LSystem.from_text("derivation length: 0\naxiom: F(2)+F(1)\n", "a.l").derive().skeleton()
    textured = LSystem.from_text("derivation length: 0\naxiom: @Tx(3)F(2)+@Tx(0)F(1)\n", "b.l").derive().skeleton()
    assert np.allclose(plain.end, textured.end) and len(textured) == 2
    path = tmp_path / "t.l"
    path.write_text("derivation length: 1\naxiom: A\nA --> @Tx(1)F\n")
    assert main(["check", str(path)]) == 0
    assert "note: @Tx is read but not drawn: a texture" in capsys.readouterr().out
