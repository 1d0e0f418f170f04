"""The explorer's document (issue 34, section 1): ρ in one unit, Save writes n, seed and
constants, typing keeps n, whole-plant picks change the constants, local edits need a session,
the "*" follows the file on disk, Open starts a fresh history."""

from __future__ import annotations

import pathlib
import shutil

import pytest

from ramure.app.cli import main
from ramure.app.model import Explorer
from ramure.errors import RamureError
from ramure.lsys import GrammarError, LSystem
from ramure.lsys.language.grammar import parse_grammar
from ramure.lsys.regeneration.regen import Session

ROOT = pathlib.Path(__file__).resolve().parents[2]
HONDA = ROOT / "grammars" / "honda_sympodial.lsys"
STOCHASTIC = ROOT / "grammars" / "stochastic_plant.lsys"
SMALL = "#define a 30\n#define b a*2\nn: 3\nw: A\np:\n0.5 A -> F[+(a)A]F[-(b)A]\n0.5 A -> F[-(b)A]A\n"


@pytest.fixture
def honda(tmp_path):
    path = tmp_path / "honda.lsys"
    shutil.copy(HONDA, path)
    return path


# -- ρ ----------------------------------------------------------------------------
def test_rho_is_a_fraction_only():
    ex = Explorer(SMALL)
    ex.set_rho(1)
    assert ex.rho == 1.0
    ex.set_rho(0.02)
    assert ex.rho == 0.02
    for bad in (2, 50, 100, 0, -0.5):  # before: 2 and 50 were read as 2 % and 50 %
        with pytest.raises(RamureError, match=r"rho must be in \(0, 1\]"):
            ex.set_rho(bad)
    assert ex.rho == 0.02


# -- #seed --------------------------------------------------------------------------
def test_seed_directive_is_read_and_is_the_default_seed():
    text = "#seed 7\n" + SMALL
    assert parse_grammar(text).seed == 7 and parse_grammar(SMALL).seed is None
    ls = LSystem.from_text(text)
    assert ls.seed == 7 and LSystem.from_text(SMALL).seed == 0
    assert ls.derive().seed == 7 and ls.derive().to_string() == ls.derive(seed=7).to_string()
    assert Session(ls).seed == 7 and Session(ls, seed=3).seed == 3
    assert Explorer(text).session.seed == 7


@pytest.mark.parametrize("line, message", [("#seed -1", "whole number >= 0"), ("#seed 2.5", "whole number"), ("#seed", "needs")])
def test_bad_seed_directive_is_refused_at_its_line(line, message):
    with pytest.raises(GrammarError, match=message) as err:
        parse_grammar("#define a 1\n" + line + "\nn: 1\nw: A\n")
    assert err.value.line == 2


def test_check_reports_the_seed(tmp_path, capsys):
    path = tmp_path / "seeded.lsys"
    path.write_text("#seed 7\n" + SMALL)
    assert main(["check", str(path)]) == 0
    assert "n = 3, seed = 7," in capsys.readouterr().out


# -- Save writes what is on screen -----------------------------------------------------
def test_save_writes_n_seed_and_constants_and_reopens_the_same_plant(honda, tmp_path):
    ex = Explorer(honda)
    assert not ex.dirty
    ex.set_derivation(n=7, seed=5)
    ex.set_constant("a2", 30)
    assert ex.dirty
    out = ex.save_grammar(tmp_path / "mine.lsys")
    assert not ex.dirty
    text = out.read_text()
    assert "\n#seed 5\nn:      7\n" in text and "#define a2 30" in text
    again = Explorer(out)
    assert (again.session.n, again.session.seed) == (7, 5) and again.constants == ex.constants
    assert again.derivation.to_string() == ex.derivation.to_string()


def test_a_constant_read_by_another_is_written_as_its_value(tmp_path):
    ex = Explorer(SMALL, seed=0)
    ex.set_constant("a", 10)  # b (= a*2 in the text) stays 60 in the plant
    out = ex.save_grammar(tmp_path / "small.lsys")
    assert Explorer(out).constants == {"a": 10.0, "b": 60.0}


def test_typing_keeps_n_seed_and_constants_unless_their_line_changed():
    ex = Explorer(HONDA)
    ex.set_derivation(n=7, seed=4)
    ex.set_constant("a2", 30)
    assert ex.set_text(ex.text + "\n// note\n") is None  # before: n went back to the text's 10
    assert (ex.session.n, ex.session.seed, ex.constants["a2"]) == (7, 4, 30)
    assert ex.set_text(ex.text.replace("n:      10", "n:      5")) is None
    assert ex.session.n == 5 and ex.session.seed == 4  # the text's own n: changed: it wins


def test_a_whole_plant_pick_changes_the_constants_and_the_seed(tmp_path):
    ex = Explorer(STOCHASTIC, n=4)
    name = next(iter(ex.constants))
    value = ex.constants[name] * 1.25
    ex.regrow(params={"rule": None, "constants": {name: value}})  # a gallery pick, nothing selected
    assert ex.constants[name] == value  # before: the constants kept their old value
    assert ex.local_edits() == [] and name in ex.document_text()
    shown = ex.derivation.to_string()
    out = ex.save_grammar(tmp_path / "picked.lsys")
    again = Explorer(out)
    assert again.derivation.to_string() == shown and again.session.seed == ex.session.seed != 0
    ex.undo()  # one undo step back to the plant before the pick
    assert ex.constants[name] != value and ex.session.seed == 0


def test_a_pick_for_one_rule_stays_a_local_edit():
    ex = Explorer(STOCHASTIC, n=4)
    name = next(iter(ex.constants))
    ex.regrow(params={"rule": 0, "constants": {name: ex.constants[name] * 1.25}})
    assert [e["op"] for e in ex.local_edits()] == ["regrow"]


def test_local_edits_refuse_a_grammar_save_and_a_session_keeps_them(tmp_path):
    ex = Explorer(HONDA, n=6)
    ex.select(ex.session.leaves_with_symbol("F")[-3:])
    ex.regrow(constants={"a2": 20})
    target = tmp_path / "g.lsys"
    with pytest.raises(RamureError, match="Save session"):
        ex.save_grammar(target)
    assert not target.exists() and ex.dirty
    ex.save_session(tmp_path / "s.json")
    assert not ex.dirty


def test_dirty_follows_the_file_across_undo_and_redo(tmp_path):
    ex = Explorer(HONDA, n=6)
    ex.set_derivation(n=5)
    ex.save_grammar(tmp_path / "g.lsys")
    assert not ex.dirty
    ex.undo()  # back past the save point: the plant is no longer what the file holds
    assert ex.session.n == 6 and ex.dirty
    ex.redo()
    assert ex.session.n == 5 and not ex.dirty
    ex.set_constant("a2", 20)
    assert ex.dirty
    ex.undo()
    assert not ex.dirty


def test_open_starts_a_fresh_history(tmp_path):
    ex = Explorer(HONDA, n=6)
    ex.set_derivation(n=5)
    ex.set_constant("a2", 20)
    ex.open_grammar(ROOT / "grammars" / "algae.lsys")
    assert ex.path.name == "algae.lsys" and not ex.dirty
    assert not ex.can_undo and ex.undo() is None  # before: Undo brought back the plant left
    assert ex.path.name == "algae.lsys" and "a2" not in ex.constants
    with pytest.raises(RamureError, match="cannot read"):
        ex.open_grammar(tmp_path / "missing.lsys")
    assert ex.path.name == "algae.lsys"
