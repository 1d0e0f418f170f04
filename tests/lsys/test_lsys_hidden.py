"""Hidden constants (issue 35 section 2): literals and rule probabilities as knobs a combination sets."""

import pytest

from ramure.errors import RamureError
from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session

TEXT = """#define r 0.8
n: 6
w: !(0.06)B(1)
p:
  .4 B(l) -> F(l)[+(30)B(l*r)][-(30)B(l*0.7)]B(l*r)
  .35 B(l) -> F(l)[&(45)B(l*r)]B(l*r)
  .25 B(l) -> F(l)B(l*r)
"""


def _edited(old, new, text=TEXT):
    assert text.count(old) == 1
    return LSystem.from_text(text.replace(old, new))


def test_the_knobs_of_a_grammar_are_its_literals_axiom_numbers_and_probabilities():
    ls = LSystem.from_text(TEXT)
    kinds = {k: h.kind for k, h in ls.hidden.items()}
    assert sorted(k for k, v in kinds.items() if v == "literal") == ["~0.2.0.0", "~0.6.0.0", "~0.7.0.2", "~1.2.0.0"]
    assert sorted(k for k, v in kinds.items() if v == "axiom") == ["~w0.0", "~w1.0"]
    assert sorted(k for k, v in kinds.items() if v == "probability") == ["~p0", "~p1", "~p2"]
    assert ls.hidden["~0.7.0.2"].text(0.75) == "B(l*0.75) in rule 0 (B(l))"
    assert ls.hidden["~w0.0"].written(0.1) == "!(0.1)"


def test_a_literal_override_derives_the_grammar_with_that_literal_written():
    ls = LSystem.from_text(TEXT)
    got = ls.derive(seed=3, params={"rule": 0, "constants": {"~0.7.0.2": 0.55}}).to_string()
    assert got == _edited("B(l*0.7)", "B(l*0.55)").derive(seed=3).to_string()
    assert got != ls.derive(seed=3).to_string()
    # an angle too, and nothing changes without an override
    got = ls.derive(seed=3, params={"rule": 1, "constants": {"~1.2.0.0": 60.0}}).to_string()
    assert got == _edited("&(45)", "&(60)").derive(seed=3).to_string()
    assert ls.derive(seed=3).to_string() == LSystem.from_text(TEXT).derive(seed=3).to_string()


def test_a_probability_override_renormalises_the_group():
    # rule 0 at 1.0 against 0.35 and 0.25: 1/1.6, 0.35/1.6, 0.25/1.6 — the same draws pick the same rules
    ls = LSystem.from_text(TEXT)
    got = ls.derive(seed=5, params={"rule": 0, "constants": {"~p0": 1.0}}).to_string()
    same = TEXT.replace(".4 B", "0.625 B").replace(".35 B", "0.21875 B").replace(".25 B", "0.15625 B")
    assert got == LSystem.from_text(same).derive(seed=5).to_string()
    assert got != ls.derive(seed=5).to_string()


def test_an_axiom_number_changes_when_the_plant_is_derived_again_and_replays_from_a_file(tmp_path):
    session = Session(LSystem.from_text(TEXT))
    session.set_steps(session.n, {"rule": None, "constants": {"~w0.0": 0.2}})
    radii = session.derivation.skeleton().base_radius
    assert radii.max() == pytest.approx(0.1)  # ! sets the diameter: 0.2 -> radius 0.1
    path = session.save(tmp_path / "s.json")
    again = Session.load(path)
    assert again.derivation.to_string() == session.derivation.to_string()


def test_an_unknown_hidden_key_is_refused():
    ls = LSystem.from_text(TEXT)
    with pytest.raises(RamureError, match="unknown constant"):
        ls.derive(params={"rule": 0, "constants": {"~0.9.0.0": 1.0}})
