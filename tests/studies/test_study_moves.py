"""Moving pictures keeps the answers that still apply, and every action is logged (issue 38)."""

from __future__ import annotations

import datetime
import sqlite3

from study_helpers import complete

from ramure.studies.picks import lattice_picks
from ramure.studies.storage import SCHEMA_VERSION, Study

A, B = list(range(1, 10)), list(range(10, 19))


def answered(session):
    """Two groups, each fully answered: representatives 5 and 14."""
    session.set_groups([A, B])
    for label, rep, word in ((1, 5, "petit"), (2, 14, "grand")):
        session.set_representative(label, rep)
        session.rate(label, usefulness=label + 1, difference=4 - label, representative=3)
        session.add_qualifier(label, word)


def answers(group):
    return group.representative, group.usefulness, group.difference, group.representative_quality, group.qualifiers


def test_moving_a_picture_between_answered_groups_keeps_both(study):
    s = study.session(study.add_participant(consent=True), "honda")
    answered(s)
    s.set_groups([[i for i in A if i != 3], [3, *B]])  # picture 3 moves from group 1 to group 2
    g = s.groups()
    assert [len(x.images) for x in g] == [8, 10]
    assert answers(g[0]) == (5, 2, 3, 3, ["petit"])
    assert answers(g[1]) == (14, 3, 2, 3, ["grand"])
    labels = s.labels()
    assert s.missing() == ["pictures not in any group: " + ", ".join(labels[i] for i in s.in_order(range(19, 28)))]


def test_a_representative_that_left_is_cleared_and_only_it(study):
    s = study.session(study.add_participant(consent=True), "honda")
    answered(s)
    s.set_groups([[i for i in A if i != 5], [5, *B]])  # group 1's representative moves out
    g = s.groups()
    assert answers(g[0]) == (None, 2, 3, None, ["petit"])
    assert answers(g[1]) == (14, 3, 2, 3, ["grand"])
    assert "group 1: choose a representative" in s.missing()
    event = study.events()[-1]
    assert event["action"] == "group"
    assert event["detail"]["representative_cleared"] == [1]
    assert event["detail"]["continued"] == {"1": 1, "2": 2}
    assert event["detail"]["dropped"] == []


def test_a_merge_keeps_the_larger_group_and_logs_what_the_other_said(study):
    s = study.session(study.add_participant(consent=True), "honda")
    answered(s)
    s.set_groups([[1, 2], [i for i in A if i > 2] + B])  # 7 of group 1 join group 2's 9
    g = s.groups()
    assert answers(g[1]) == (14, 3, 2, 3, ["grand"])  # continues group 2 (9 shared)
    assert answers(g[0]) == (None, 2, 3, None, ["petit"])  # what is left of group 1 continues it
    s.set_groups([A + B])  # now a true merge: one group continues, the other's answers are logged
    (merged,) = s.groups()
    assert answers(merged) == (14, 3, 2, 3, ["grand"])  # group 2 (16 images) continues
    (dropped,) = study.events()[-1]["detail"]["dropped"]
    assert (dropped["label"], dropped["usefulness"], dropped["qualifiers"]) == (1, 2, ["petit"])


def test_every_action_is_logged_in_order_with_times(study, clock):
    code = study.add_participant(consent=True)
    s = study.session(code, "honda")
    clock.advance(7)
    answered(s)
    clock.advance(3)
    s.remove_qualifier(1, "petit")
    s.set_groups([[i for i in A if i != 3], [3, *B]])
    events = study.events(code)
    actions = [e["action"] for e in events]
    assert actions == ["consent", "start", "group"] + ["representative", "rate", "add_qualifier"] * 2 + [
        "remove_qualifier",
        "group",
    ]
    assert events[3]["detail"] == {"group": 1, "image": 5}
    assert events[4]["detail"] == {"group": 1, "usefulness": 2, "difference": 3, "representative_quality": 3}
    assert events[5]["detail"] == {"group": 1, "text": "petit"}
    assert [e["elapsed_seconds"] for e in events[1:4]] == [0.0, 7.0, 7.0]
    assert events[-2]["elapsed_seconds"] == 10.0
    times = [datetime.datetime.fromisoformat(e["at"]) for e in events]
    assert times == sorted(times) and all(t.tzinfo is not None for t in times)
    assert {e["grammar"] for e in events[1:]} == {"honda"}
    # A refused action changes nothing, so it logs nothing either.
    before = len(study.events())
    try:
        s.set_representative(1, 27)
    except Exception:  # noqa: BLE001 - refused: 27 is not in group 1
        pass
    assert len(study.events()) == before


def test_deleting_a_participant_deletes_their_events(study):
    keep, gone = study.add_participant(consent=True), study.add_participant(consent=True)
    answered(study.session(gone, "honda"))
    study.session(keep, "honda").set_groups([A])
    study.delete_participant(gone)
    assert {e["participant"] for e in study.events()} == {keep}


def test_a_version_1_study_is_migrated_with_its_answers(tmp_path):
    db = tmp_path / "study.db"
    with Study.create(db, grammars={"honda": lattice_picks(seed=1)}) as study:
        answered(study.session(study.add_participant("P1", consent=True), "honda"))
    conn = sqlite3.connect(db)  # what a version-1 Ramure wrote: no events table
    conn.executescript("DROP TABLE events; PRAGMA user_version = 1;")
    conn.close()
    with Study.open(db) as study:
        assert study.conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION == 3
        assert study.conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        assert study.events() == []
        s = study.session("P1", "honda")
        assert [answers(g) for g in s.groups()] == [(5, 2, 3, 3, ["petit"]), (14, 3, 2, 3, ["grand"])]
        s.add_qualifier(1, "rond")
        assert [e["action"] for e in study.events()] == ["resume", "add_qualifier"]
    with Study.open(db) as study:  # a second open finds it migrated already
        assert study.session("P1", "honda").groups()[0].qualifiers == ["petit", "rond"]


def test_finished_is_per_participant_and_grammar(study):

    a, b = study.add_participant(consent=True), study.add_participant(consent=True)
    complete(study.session(a, "honda"))
    study.session(b, "honda")
    assert [study.finished(a, "honda"), study.finished(a, "tree2"), study.finished(b, "honda")] == [True, False, False]
