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


def model(tmp_path, program="honda81 -e plant.e d.spec", spec="radius: 1\n3d case: on\n"):
    (tmp_path / "plant.e").write_text(f"executable: {program}\ncommunication type: files\n")
    (tmp_path / "d.spec").write_text(spec)
    path = tmp_path / "plant.l"
    path.write_text("derivation length: 1\naxiom: [A?E(1)][f(0.5)A?E(2)][f(3)A?E(1)]\nA > ?E(x) : x == 1 --> F\nendlsystem\n")
    return path


def test_honda81_answers_whether_a_stronger_query_is_near(tmp_path):
    # the first query (vigor 1) has the second (vigor 2) 0.5 away, within the radius 1: it may
    # not grow (0); the second has no query as strong near it (1); the third is 2.5 away (1)
    d = LSystem.from_file(model(tmp_path)).derive()
    assert d.to_string() == "[A?E(0)][f(0.5)F?E(1)][f(3)F?E(1)]"


def test_honda81_with_a_larger_radius_stops_the_third_too(tmp_path):
    d = LSystem.from_file(model(tmp_path, spec="radius: 3\n3d case: on\n")).derive()
    assert d.to_string() == "[A?E(0)][f(0.5)F?E(1)][f(3)A?E(0)]"


def test_another_environment_program_is_refused_by_name(tmp_path):
    with pytest.raises(GrammarError, match="environment program chiba") as info:
        LSystem.from_file(model(tmp_path, program="chiba -e plant.e light.spec"))
    assert (info.value.line, info.value.column) == (2, 10)


def test_without_an_e_file_the_refusal_says_so(tmp_path):
    path = tmp_path / "plant.l"
    path.write_text("derivation length: 1\naxiom: A?E(1)\n")
    with pytest.raises(GrammarError, match="here none beside the .l file"):
        LSystem.from_file(path)


@pytest.mark.parametrize("three_d", [True, False])
def test_honda81_agrees_with_its_double_loop(three_d):
    import numpy as np

    from ramure.lsys.interpretation.environment import honda81

    rng = np.random.default_rng(3)
    points, vigor, index = rng.random((300, 3)), rng.integers(0, 3, 300).astype(float), rng.integers(0, 2, 300)
    flat = points[:, [0, 1, 2] if three_d else [0, 2]]
    gap = ((flat[:, None] - flat[None]) ** 2).sum(-1)
    blocked = (gap <= 0.1**2) & (vigor[:, None] <= vigor[None]) & (index[:, None] == index[None])
    np.fill_diagonal(blocked, False)
    assert np.array_equal(honda81(points, vigor, index, 0.1, three_d), np.where(blocked.any(1), 0.0, 1.0))
