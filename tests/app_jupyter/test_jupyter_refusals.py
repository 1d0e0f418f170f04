"""Every handler refuses bad input on the message line and changes nothing (no traceback)."""

from __future__ import annotations

import pytest

from ramure.app.jupyter import NotebookExplorer
from jupyter_helpers import HONDA


def _ids(text):
    def act(ex):
        ex.selection_panel.ids.value = text
        ex.selection_panel.select_ids()

    return act


def _tree_select_without_row(ex):
    ex.tree.rows.value = None
    ex.tree.select_selected()


REFUSALS = {
    "ids with an empty token and a word": (_ids("12,,x"), "'x' is not a leaf id"),
    "ids range backwards": (_ids("9-7"), "goes backwards"),
    "id not a leaf": (_ids("999999999"), "is not a leaf of the current plant"),
    "prune with nothing selected": (lambda ex: ex.prune(), "select the branches to prune first"),
    "regrow fruit with nothing selected": (lambda ex: ex.regrow_fruit(), "select one or more fruit first"),
    "regrow fruit on branches": (
        lambda ex: (ex.model.select(ex.model.leaves_where(min_order=2)), ex.regrow_fruit(preset="pear")),
        "select one or more fruit first",
    ),
    "pick without an exploration": (lambda ex: ex.apply_pick(3), "explore the variants first"),
    "qualifier regions without an exploration": (lambda ex: ex.load_qualifiers("missing.sqlite"), "explore the variants first"),
    "constant not a number": (lambda ex: ex.set_constant("a2", "abc"), "'abc' is not a number"),
    "constant not finite": (lambda ex: ex.set_constant("a2", float("nan")), "finite"),
    "unknown constant": (lambda ex: ex.set_constant("zz", 1), "no constant 'zz'"),
    "one bad constant among good ones": (lambda ex: ex.apply_constants({"a2": 30, "r1": "x"}), "'x' is not a number"),
    "regrow with a non-numeric constant": (lambda ex: ex.regrow_with_constants({"a2": "x"}), "not a number"),
    "n out of range": (lambda ex: ex.set_derivation(n=31), "from 0 to 30"),
    "n negative": (lambda ex: ex.set_derivation(n=-1), "from 0 to 30"),
    "n not a number": (lambda ex: ex.set_derivation(n="x"), "'x' is not a number"),
    "seed not a number": (lambda ex: ex.set_derivation(seed="x"), "'x' is not a number"),
    "rho zero": (lambda ex: ex.set_rho(0), "rho must be in"),
    "rho not a number": (lambda ex: ex.set_rho("x"), "not a number"),
    "cell not in the plant": (lambda ex: ex.pick(10**9), "not part of the plant"),
    "unknown camera side": (lambda ex: ex.set_view("bogus"), "view must be one of"),
    "export to an unknown format": (lambda ex: ex.save("plant.foo"), "cannot export to '.foo'"),
    "save into a missing folder": (lambda ex: ex.save("/nonexistent/dir/s.json"), "/nonexistent/dir/s.json"),
    "load a missing session": (lambda ex: ex.load_session("/nonexistent/s.json"), "s.json"),
    "tree select without a row": (_tree_select_without_row, "choose a row"),
}


@pytest.fixture(scope="module")
def shared():
    """One explorer for every case: a refusal changes nothing, which each case checks."""
    return NotebookExplorer(HONDA, n=4, view="static", size=(80, 80), cache=False)


@pytest.mark.parametrize("case", REFUSALS)
def test_bad_input_is_refused_on_the_message_line(case, shared):
    action, expected = REFUSALS[case]
    ex = shared
    leaf = ex.model.session.leaves_with_symbol("F")[-1]
    ex.select([int(leaf)])
    if "select" in expected and "first" in expected:  # the refusals of an empty selection
        ex.clear_selection()
    before = (ex.plant.to_string(), list(ex.history), ex.model.constants, ex.session.n, ex.session.seed, ex.model.rho)
    selected = ex.selection
    action(ex)  # no exception escapes
    assert ex.message.kind in ("error", "note") and expected in ex.message.text
    assert (ex.plant.to_string(), list(ex.history), ex.model.constants, ex.session.n, ex.session.seed, ex.model.rho) == before
    if case != "regrow fruit on branches":  # (that action selects first)
        assert ex.selection == selected


def test_loading_a_session_shows_the_replay_on_the_message_line(tmp_path):
    """Issue 37: a session of many edits replayed with no word; the message line follows it."""
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.regen import Session

    session = Session(LSystem.from_file(HONDA), n=4, seed=1)
    for _ in range(3):
        session.regrow([int(session.tree.leaves[-1])], rho=0.5)
    path = session.save(tmp_path / "s.json")
    ex = NotebookExplorer(HONDA, n=3, view="static", size=(80, 80), cache=False)
    shown = []
    show = ex.message.show
    ex.message.show = lambda text, kind="info": (shown.append(str(text)), show(text, kind))
    ex.load_session(path)
    assert shown[:2] == ["replaying the session: edit 1 of 3", "replaying the session: edit 3 of 3"]
    assert len(ex.model.session.edits) == 3 and ex.message.kind == "info"
