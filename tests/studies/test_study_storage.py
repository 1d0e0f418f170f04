"""Study model and storage: creation, participants, sessions, validation, budget."""

from __future__ import annotations

import json
import pathlib
import sqlite3

import pytest
from study_helpers import complete

from ramure.studies.errors import StudyInputError
from ramure.studies.picks import lattice_picks
from ramure.studies.storage import Study


def _pick_dicts(seed=0):
    return [
        dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params, image=f"thumbs/pick_{p.id:02d}.png")
        for p in lattice_picks(seed=seed)
    ]


def test_create_from_exploration_directory(tmp_path):
    explore = tmp_path / "explore" / "honda"
    explore.mkdir(parents=True)
    (explore / "picks.json").write_text(json.dumps(_pick_dicts()))
    with Study.create(tmp_path / "s.db", grammars={"honda": explore}) as study:
        picks = study.picks("honda")
        assert [p.id for p in picks] == list(range(1, 28))
        assert picks[4].image == str((explore / "thumbs/pick_05.png").resolve())
        assert picks[4].params == _pick_dicts()[4]["params"]
        assert study.name == "s" and study.budget_seconds == 1800


def test_create_refuses_bad_picks_and_leaves_no_file(tmp_path):
    items = _pick_dicts()
    items[3]["id"] = 5
    with pytest.raises(StudyInputError, match=r"missing ids \[4\]; repeated ids \[5\]"):
        Study.create(tmp_path / "s.db", grammars={"honda": items})
    assert not (tmp_path / "s.db").exists()
    items = _pick_dicts()
    items[0]["pca"] = [1, 2]
    with pytest.raises(StudyInputError, match=r"honda'\[0\]: pca"):
        Study.create(tmp_path / "s.db", grammars={"honda": items})
    with pytest.raises(StudyInputError, match="no picks.json"):
        Study.create(tmp_path / "s.db", grammars={"honda": tmp_path})


def test_create_refuses_existing_study_and_open_refuses_other_files(tmp_path, study):
    with pytest.raises(StudyInputError, match="already holds a study"):
        Study.create(study.path, grammars={})
    other = tmp_path / "other.db"
    sqlite3.connect(other).execute("CREATE TABLE x (a)").connection.close()
    with pytest.raises(StudyInputError, match="not a Ramure study"):
        Study.open(other)
    with pytest.raises(StudyInputError, match="exists and is not a study"):
        Study.create(other, grammars={})
    (tmp_path / "text.db").write_text("hello, not sqlite at all" * 100)
    with pytest.raises(StudyInputError, match="not a SQLite file"):
        Study.create(tmp_path / "text.db", grammars={})
    with pytest.raises(StudyInputError, match="no such study file"):
        Study.open(tmp_path / "missing.db")


def test_participants_codes_and_consent(study):
    assert study.add_participant() == "P101"
    assert study.add_participant(consent=True) == "P102"
    with pytest.raises(StudyInputError, match="already used"):
        study.add_participant("P101")
    with pytest.raises(StudyInputError, match="anonymous code"):
        study.add_participant("Jean Dupont")
    with pytest.raises(StudyInputError, match="not given consent"):
        study.session("P101", "honda")
    study.record_consent("P101")
    assert study.session("P101", "honda").order()
    assert [p["consent"] for p in study.participants()] == [True, True]
    with pytest.raises(StudyInputError, match="no grammar 'oak'.*honda, tree2"):
        study.session("P101", "oak")


def test_order_is_a_seeded_permutation_stable_across_reopening(study):
    a, b = study.add_participant(consent=True), study.add_participant(consent=True)
    order = study.session(a, "honda").order()
    assert sorted(order) == list(range(1, 28)) and order != list(range(1, 28))
    assert order != study.session(b, "honda").order()
    assert order != study.session(a, "tree2").order()
    path = study.path
    study.close()
    with Study.open(path) as again:
        assert again.session(a, "honda").order() == order


def _snapshot(session):
    return [vars(g) for g in session.groups()]


@pytest.mark.parametrize(
    "groups, message",
    [
        ([[1, 2, 3], [3, 4]], r"image 3 is in two groups \(1 and 2\)"),
        ([[1, 2], []], r"group 2 is empty"),
        ([[1, 28]], r"group 1: 28 is not an image number 1-27"),
        ([[0]], r"group 1: 0 is not an image number"),
        ([[1, True]], r"True is not an image number"),
        ([[1, 1]], r"image 1 is listed twice in group 1"),
        (["12"], r"group 1 must be a list"),
        ("123", r"groups must be a list"),
    ],
)
def test_bad_groupings_refused_and_nothing_lost(study, groups, message):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1, 2, 3], [4, 5]])
    s.rate(1, usefulness="good")
    before = _snapshot(s)
    with pytest.raises(StudyInputError, match=message):
        s.set_groups(groups)
    assert _snapshot(s) == before


def test_bad_ratings_refused_and_nothing_lost(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1, 2, 3], [4]])
    s.rate(1, usefulness=2, difference="Excellent")
    before = _snapshot(s)
    for bad in (5, 0, -1, 2.5, "great", True, "  "):
        with pytest.raises(StudyInputError, match="scale 1-4"):
            s.rate(1, usefulness=bad)
    with pytest.raises(StudyInputError, match="group 3 does not exist .this test has groups 1-2"):
        s.rate(3, usefulness=2)
    with pytest.raises(StudyInputError, match="choose its representative before"):
        s.rate(1, representative="good")
    with pytest.raises(StudyInputError, match="single image"):
        s.rate(2, representative="good")
    with pytest.raises(StudyInputError, match="image 4 is not in group 1"):
        s.set_representative(1, 4)
    with pytest.raises(StudyInputError, match="non-empty word"):
        s.add_qualifier(1, "   ")
    assert _snapshot(s) == before
    assert before[0]["usefulness"] == 2 and before[0]["difference"] == 4


def test_likert_names_in_both_languages(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1, 2]])
    s.set_representative(1, 2)
    s.rate(1, usefulness="Mauvais", difference="bonne", representative="PASSABLE")
    g = s.groups()[0]
    assert (g.usefulness, g.difference, g.representative_quality) == (1, 3, 2)


def test_regrouping_keeps_the_answers_that_still_apply(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1, 2, 3], [4, 5], [6]])
    s.set_representative(1, 2)
    s.rate(1, usefulness=4, difference=1, representative=2)
    s.add_qualifier(1, "rond")
    s.rate(2, usefulness=1)
    s.set_groups([[6, 7], [3, 2, 1], [4], [5]])  # group 1 moves to label 2, group 2 is split
    g = s.groups()
    assert [x.images for x in g] == [[6, 7], [1, 2, 3], [4], [5]]
    assert (g[1].representative, g[1].usefulness, g[1].representative_quality, g[1].qualifiers) == (2, 4, 2, ["rond"])
    assert g[0].usefulness is None and g[0].representative is None  # 6 was a single: never chosen
    assert g[2].representative == 4 and g[2].usefulness == 1  # the first part of the split continues group 2
    assert g[3].representative == 5 and g[3].usefulness is None
    assert s.unsorted() == list(range(8, 28))


def test_changing_representative_clears_its_rating(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1, 2, 3]])
    s.set_representative(1, 2)
    s.rate(1, representative=4)
    s.set_representative(1, 2)
    assert s.groups()[0].representative_quality == 4
    s.set_representative(1, 3)
    assert s.groups()[0].representative_quality is None


def test_finish_lists_what_is_missing_then_locks_the_test(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([list(range(1, 27))])
    with pytest.raises(StudyInputError) as err:
        s.finish()
    text = str(err.value)
    for part in (
        f"pictures not in any group: {s.labels()[27]}",
        "group 1: choose a representative",
        "group 1: rate its usefulness",
        "group 1: describe it in at least one word",
    ):
        assert part in text
    assert not s.finished
    complete(s)
    assert s.finished and s.missing() == []
    with pytest.raises(StudyInputError, match="finished"):
        s.rate(1, usefulness=1)
    assert s.groups()[0].usefulness == 2


def test_remove_qualifier(study):
    s = study.session(study.add_participant(consent=True), "honda")
    s.set_groups([[1]])
    s.add_qualifier(1, "dense")
    s.add_qualifier(1, "small")
    s.remove_qualifier(1, "dense")
    assert s.groups()[0].qualifiers == ["small"]
    with pytest.raises(StudyInputError, match="no description 'dense'"):
        s.remove_qualifier(1, "dense")


def test_time_budget_counts_committed_answers(study, clock):
    code = study.add_participant(consent=True)
    s = study.session(code, "honda")
    clock.advance(100)
    s.set_groups([[1, 2]])
    clock.advance(50)
    assert s.elapsed_seconds() == pytest.approx(150)
    assert s.remaining_seconds() == pytest.approx(1800 - 150)
    assert study.used_seconds(code) == pytest.approx(100)  # only committed time is stored
    clock.advance(2000)
    s.rate(1, usefulness=3)  # answers after the budget are still kept
    assert s.groups()[0].usefulness == 3
    assert s.remaining_seconds() == 0 and study.used_seconds(code) == pytest.approx(2150)
    with pytest.raises(StudyInputError, match="30-minute budget"):
        study.session(code, "tree2")
    assert study.session(code, "honda").groups()[0].images == [1, 2]  # resuming is allowed


def test_budget_is_configurable(tmp_path, clock):
    with Study.create(tmp_path / "s.db", grammars={"g": lattice_picks()}, budget_minutes=1, clock=clock) as study:
        assert study.budget_seconds == 60
        s = study.session(study.add_participant(consent=True), "g")
        clock.advance(20)
        assert s.remaining_seconds() == pytest.approx(40)
    with pytest.raises(StudyInputError, match="positive number of minutes"):
        Study.create(tmp_path / "t.db", budget_minutes=0)


def test_resume_after_reopening(study):
    code = study.add_participant(consent=True)
    s = study.session(code, "honda")
    s.set_groups([[1, 2], [3]])
    s.add_qualifier(2, "grand")
    path = study.path
    study.close()
    with Study.open(path) as again:
        s = again.session(code, "honda")
        assert [g.images for g in s.groups()] == [[1, 2], [3]]
        assert s.groups()[1].qualifiers == ["grand"]
        complete(s)
        assert again.tests()[0]["finished_at"] is not None


def test_foreign_keys_are_enforced(study):
    with pytest.raises(sqlite3.IntegrityError):
        with study.conn:
            study.conn.execute("INSERT INTO tests (participant_id, grammar_id, started_at) VALUES (99, 99, 'x')")


def test_withdrawn_consent_excludes_answers_and_delete_erases_them(study, tmp_path):
    from ramure.studies.data import load_study_data
    from ramure.studies.export import export_csv

    a, b = study.add_participant(consent=True), study.add_participant(consent=True)
    complete(study.session(a, "honda"))
    complete(study.session(b, "honda"))
    assert load_study_data(study).n_tests == 2
    study.record_consent(b, given=False)
    assert load_study_data(study).n_tests == 1
    with pytest.raises(StudyInputError, match="not given consent"):
        study.session(b, "honda")
    export_csv(study, tmp_path / "csv")
    assert (tmp_path / "csv" / "tests.csv").read_text().count("\n") == 2  # header + one test
    study.delete_participant(b)
    assert [p["code"] for p in study.participants()] == [a]
    counts = [
        study.conn.execute(f"SELECT count(*) FROM {t}").fetchone()[0] for t in ("tests", "groups", "group_images", "qualifiers")
    ]
    assert counts == [1, 4, 27, 4]


def test_reserved_grammar_name(tmp_path):
    with pytest.raises(StudyInputError, match="reserved"):
        Study.create(tmp_path / "s.db", grammars={"All": lattice_picks()})


def test_a_study_folder_copied_elsewhere_still_finds_its_pictures(tmp_path):
    """Issue 38, section 3: paths are stored relative to the study's folder, so a copied study
    shows its pictures, and picks.csv names none of the researcher's folders."""
    import csv
    import shutil

    from ramure.studies.export import export_csv

    first = tmp_path / "lab" / "study"
    explore = first / "explore" / "honda"
    (explore / "thumbs").mkdir(parents=True)
    (explore / "picks.json").write_text(json.dumps(_pick_dicts()))
    for p in lattice_picks():
        (explore / "thumbs" / f"pick_{p.id:02d}.png").write_bytes(b"png")
    Study.create(first / "s.db", grammars={"honda": explore}).close()
    raw = sqlite3.connect(first / "s.db")
    stored = raw.execute("SELECT image FROM picks ORDER BY pick_id").fetchall()
    source = raw.execute("SELECT source FROM grammars").fetchone()[0]
    raw.close()
    assert stored[0][0] == "explore/honda/thumbs/pick_01.png" and source == "explore/honda"
    moved = tmp_path / "elsewhere" / "copy"
    shutil.copytree(first, moved)
    shutil.rmtree(tmp_path / "lab")
    with Study.open(moved / "s.db") as study:
        picks = study.picks("honda")
        assert all(p.image and pathlib.Path(p.image).is_file() for p in picks)
        assert study.grammar_source("honda") == str((moved / "explore" / "honda").resolve())
        export_csv(study, tmp_path / "csv")
    with open(tmp_path / "csv" / "picks.csv", newline="") as fh:
        images = [row["image"] for row in csv.DictReader(fh)]
    assert images[0] == "explore/honda/thumbs/pick_01.png"
    assert not any(str(tmp_path) in image for image in images)
