"""``import ramure`` gives a script what it needs, and a session's constants are respected."""

from __future__ import annotations

import ramure
from ramure.lsys import Session, leaves_where, select_roots


def test_session_constants_carry_into_the_grammar_to_explore():
    session = ramure.Session(ramure.load("honda_sympodial"), n=5)
    session.set_constants({"a2": 30})
    current = session.current_lsystem()
    assert current.constants["a2"] == 30 and session.lsystem.constants["a2"] == 60
    assert current.derive(n=5).to_string() == session.derivation.to_string()


def test_script_path_in_one_namespace():
    session = Session(ramure.load("honda_sympodial"), n=6)
    skeleton = session.derivation.skeleton()
    high = leaves_where(skeleton, min_order=3)
    assert high and set(high) <= set(skeleton.leaf_id.tolist())
    cut = select_roots(session.tree, high)  # every branch of order 3: whole twigs, so they regrow
    assert len(cut.roots) >= 1
    before = ramure.plant_metrics(skeleton).branch_count
    session.prune(high)
    assert ramure.plant_metrics(session.derivation.skeleton()).branch_count < before
    session.undo()
    assert ramure.plant_metrics(session.derivation.skeleton()).branch_count == before
