"""The study design shared by every front end: config, Latin square, flow, pilots, withdrawal."""

from __future__ import annotations

import collections
import json
import sqlite3

import pytest
from study_helpers import complete

from ramure.studies.data import load_study_data
from ramure.studies.design import (
    DEFAULT_QUESTIONS,
    WORDS,
    ParticipantFlow,
    StudyConfig,
    config_from_data,
    jargon_in,
    latin_square,
    passed_attention,
    read_config,
    split_words,
)
from ramure.studies.errors import StudyInputError
from ramure.studies.picks import lattice_picks
from ramure.studies.storage import SCHEMA_VERSION, Study


def three(tmp_path, clock, **kwargs):
    grammars = {name: lattice_picks(seed=k) for k, name in enumerate(("honda", "tree2", "fern"), start=1)}
    return Study.create(tmp_path / "s.db", grammars=grammars, clock=clock, **kwargs)


# -- config --------------------------------------------------------------------------------
def test_a_config_file_sets_texts_and_likert_and_round_trips(tmp_path):
    path = tmp_path / "config.json"
    path.write_text(
        json.dumps(
            {
                "consent": "Three sets of plants.",
                "contact": "ada@example.org",
                "retention": "Kept two years.",
                "likert": {"levels": ["no", "a little", "rather", "very"], "usefulness": "Useful?"},
                "attention_checks": [{"key": "look", "text": "Choose blue", "options": ["red", "blue"], "answer": "blue"}],
                "demographics": [{"key": "age", "text": "Age", "required": False}],
                "completion_code": "C0DE-42",
            }
        )
    )
    config = read_config(path)
    assert config.levels == ("no", "a little", "rather", "very")
    assert config.questions == {**DEFAULT_QUESTIONS, "usefulness": "Useful?"}
    assert "ada@example.org" in config.consent_text() and "Kept two years." in config.consent_text()
    assert passed_attention(config, {"look": "blue"}) and not passed_attention(config, {"look": "red"})
    assert config_from_data(config.to_data()) == config
    assert config_from_data(StudyConfig().to_data()) == StudyConfig()


@pytest.mark.parametrize(
    "data,match",
    [
        ({"consnt": "x"}, "unknown field 'consnt'"),
        ({"likert": {"levels": ["a", "b", "c"]}}, r"likert.levels: expected the 4 level names"),
        ({"likert": {"levels": ["a", "b", "c", "A"]}}, "must differ"),
        ({"attention_checks": [{"key": "a", "text": "t", "options": ["x"], "answer": "y"}]}, r"attention_checks\[0\].answer"),
        ({"demographics": [{"key": "age"}]}, r"demographics\[0\].text: expected non-empty text"),
        ({"demographics": [{"key": "Age!", "text": "Age"}]}, "lower-case letters"),
        ({"framing": "zoomed"}, "framing: 'zoomed' is not one of shared, own"),
        ([], "expected a JSON object"),
    ],
)
def test_bad_configs_are_refused_naming_the_field(data, match):
    with pytest.raises(StudyInputError, match=match):
        config_from_data(data)


def test_a_config_file_that_is_not_json_is_refused(tmp_path):
    path = tmp_path / "c.json"
    path.write_text("{consent: 1")
    with pytest.raises(StudyInputError, match="not valid JSON"):
        read_config(path)


def test_participant_words_carry_no_jargon():
    config = StudyConfig()
    texts = [config.consent_text(), config.instructions, config.practice or "", *WORDS.values(), *config.questions.values()]
    texts += [q.text for q in config.attention_checks + config.demographics]
    assert [t for t in texts if jargon_in(t)] == []
    assert jargon_in("How useful is this group of variants?") == ["variant"]


def test_words_are_split_the_same_way_everywhere():
    assert split_words("dense, taller") == ["dense", "taller"]
    assert split_words(" petit ;  très  dense,,petit\n") == ["petit", "très dense"]


# -- order -----------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_latin_square_puts_each_grammar_in_each_position_equally_often(n):
    rows = latin_square(n)
    assert all(sorted(r) == list(range(n)) for r in rows)
    for position in range(n):
        counts = collections.Counter(r[position] for r in rows)
        assert set(counts.values()) == {len(rows) // n} and len(counts) == n
    follows = collections.Counter((r[i], r[i + 1]) for r in rows for i in range(n - 1))
    assert len(follows) == n * (n - 1) and len(set(follows.values())) == 1  # carry-over balanced


def test_participants_get_stored_latin_square_orders_and_pilots_count_apart(tmp_path, clock):
    with three(tmp_path, clock) as study:
        real = [study.add_participant() for _ in range(6)]
        pilot = study.add_participant(pilot=True)
        orders = [tuple(study.grammar_order(c)) for c in real]
        assert len(set(orders)) == 6  # 3 grammars: a 6-row Williams square
        assert [o[0] for o in orders].count("honda") == 2
        assert study.grammar_order(pilot) == ["honda", "tree2", "fern"]  # the first row again
        assert study.grammar_order(real[0]) == ["honda", "tree2", "fern"]
    with Study.open(tmp_path / "s.db", readonly=True) as study:  # stored, not recomputed from the clock
        assert [tuple(study.grammar_order(c)) for c in real] == orders


# -- flow ------------------------------------------------------------------------------------
def test_the_flow_walks_consent_instructions_practice_sets_checks_and_the_code(tmp_path, clock):
    with three(tmp_path, clock, config=StudyConfig(completion_code="DONE-7")) as study:
        code = study.add_participant(external_id="5f3a9c1e2b")
        flow = ParticipantFlow(study, code, front_end="desktop")
        kinds = []
        for _ in range(12):
            step = flow.step()
            kinds.append(step.kind if step.kind != "test" else step.title)
            if step.kind == "consent":
                assert "Contact:" in step.text
                flow.consent()
            elif step.kind in ("instructions", "practice"):
                flow.acknowledge(step.kind)
            elif step.kind == "attention":
                with pytest.raises(StudyInputError, match="please answer"):
                    flow.answer("attention", {})
                flow.answer("attention", {"attention_1": "good"})
            elif step.kind == "demographics":
                with pytest.raises(StudyInputError, match="is not one of"):
                    flow.answer("demographics", {"age": "42", "expertise": "quite"})
                flow.answer("demographics", {"age": "40-59", "expertise": "quite"})
            elif step.kind == "test":
                assert step.grammar == flow.grammars[step.number - 1]
                complete(flow.session(step.grammar))
            else:
                break
        assert kinds == [
            "consent", "instructions", "practice", "Set 1 of 3", "attention", "Set 2 of 3", "Set 3 of 3", "demographics", "done",
        ]  # fmt: skip
        assert "DONE-7" in step.text and step.skipped == ()
        assert not passed_attention(study.config(), study.participant_answers(code)["attention"])
        assert study.find_participant("5f3a9c1e2b") == code
        answers = [e for e in study.events(code) if e["grammar"]]
        assert answers and {e["front_end"] for e in answers} == {"desktop"}


def test_a_spent_budget_names_the_sets_it_skipped(tmp_path, clock):
    config = StudyConfig(practice=None, attention_checks=(), demographics=())
    with three(tmp_path, clock, budget_minutes=1, config=config) as study:
        code = study.add_participant(consent=True)
        flow = ParticipantFlow(study, code)
        flow.acknowledge("instructions")
        first = flow.step()
        session = flow.session(first.grammar)
        clock.advance(120)
        complete(session)
        last = flow.step()
        assert last.kind == "done" and len(last.skipped) == 2
        assert "set 2 of 3, set 3 of 3 were not shown" in last.text
        assert "Your completion code: " in last.text


# -- pilots, withdrawal, front ends ----------------------------------------------------------
def test_pilots_are_left_out_of_the_analysis_unless_asked(study):
    complete(study.session(study.add_participant(consent=True), "honda"))
    complete(study.session(study.add_participant(consent=True, pilot=True), "honda"))
    assert len(load_study_data(study).participants) == 1
    assert len(load_study_data(study, include_pilot=True).participants) == 2
    assert [p["pilot"] for p in study.participants()] == [False, True]


def test_withdrawal_leaves_answers_out_and_deletion_erases_them(study):
    a, b, c = (study.add_participant(consent=True) for _ in range(3))
    for code in (a, b, c):
        complete(study.session(code, "honda"))
    study.withdraw(b)
    study.withdraw(c, delete=True)
    assert load_study_data(study).participants == [a, b] and len(load_study_data(study).test_participant) == 1
    rows = {p["code"]: p for p in study.participants()}
    assert rows[b]["withdrawn_at"] and not rows[b]["consent"] and c not in rows
    assert study.conn.execute("SELECT count(*) FROM events e JOIN participants p ON p.id = e.participant_id").fetchone()[0]
    with pytest.raises(StudyInputError, match="no participant"):
        study.withdraw(c)


def test_an_unknown_front_end_or_a_taken_external_id_is_refused(study):
    study.add_participant(external_id="abc")
    with pytest.raises(StudyInputError, match="already enrolled"):
        study.add_participant(external_id="abc")
    with pytest.raises(StudyInputError, match="external id"):
        study.add_participant(external_id="a b")
    with pytest.raises(StudyInputError, match="front end 'phone'"):
        study.session(study.add_participant(consent=True), "honda", front_end="phone")


V2_EVENTS = """
DROP TABLE settings; DROP TABLE enrolments; DROP TABLE page_answers;
CREATE TABLE old_events AS SELECT id, participant_id, test_id, at, elapsed_seconds, action, detail FROM events;
DROP TABLE events;
CREATE TABLE events (
  id INTEGER PRIMARY KEY,
  participant_id INTEGER NOT NULL REFERENCES participants(id) ON DELETE CASCADE,
  test_id INTEGER REFERENCES tests(id) ON DELETE CASCADE,
  at TEXT NOT NULL,
  elapsed_seconds REAL,
  action TEXT NOT NULL,
  detail TEXT NOT NULL DEFAULT '{}'
);
INSERT INTO events SELECT * FROM old_events; DROP TABLE old_events;
PRAGMA user_version = 2;
"""


def test_a_version_2_study_is_migrated_and_its_answers_kept(tmp_path):
    db = tmp_path / "study.db"
    with Study.create(db, grammars={"honda": lattice_picks(seed=1)}) as study:
        complete(study.session(study.add_participant("P1", consent=True), "honda"))
    conn = sqlite3.connect(db)  # what a version-2 Ramure wrote
    conn.executescript(V2_EVENTS)
    conn.close()
    with Study.open(db, readonly=True) as study:  # read as version 2: defaults, the study's order
        assert study.version == 2 and study.grammar_order("P1") == ["honda"] and study.config() == StudyConfig()
        assert len(load_study_data(study).participants) == 1
    with Study.open(db) as study:
        assert study.conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION == 3
        assert study.finished("P1", "honda") and study.completion_code("P1") is None
        assert {e["front_end"] for e in study.events()} == {None}
        code = study.add_participant(consent=True, external_id="x1")
        study.session(code, "honda", front_end="notebook").set_groups([[1, 2]])
        assert study.events(code)[-1]["front_end"] == "notebook" and study.completion_code(code)


def test_a_practice_sort_comes_first_and_is_never_analysed(tmp_path, clock):
    config = StudyConfig(practice_set="fern", attention_checks=(), demographics=())
    with three(tmp_path, clock, config=config) as study:
        code = study.add_participant(consent=True)
        assert study.grammar_order(code) == ["honda", "tree2"] and study.sets() == ["honda", "tree2"]
        flow = ParticipantFlow(study, code)
        flow.acknowledge("instructions")
        flow.acknowledge("practice")
        step = flow.step()
        assert (step.kind, step.title, step.grammar, flow.title("fern")) == ("test", "Practice", "fern", "Practice")
        complete(flow.session("fern"))
        assert flow.step().title == "Set 1 of 2"
        for grammar in ("honda", "tree2"):
            complete(flow.session(grammar))
        data = load_study_data(study)
        assert data.grammars == ["honda", "tree2"] and len(data.test_participant) == 2
    with pytest.raises(StudyInputError, match="practice set 'oak' is not a grammar of the study"):
        Study.create(tmp_path / "t.db", grammars={"honda": lattice_picks(seed=1)}, config=StudyConfig(practice_set="oak"))


def test_the_example_config_is_valid_and_free_of_jargon():
    import pathlib

    config = read_config(pathlib.Path(__file__).resolve().parents[2] / "examples" / "study_config.json")
    assert [q.key for q in config.demographics] == ["age", "expertise", "comments"] and not config.demographics[2].required
    texts = [config.consent_text(), config.instructions, config.practice or "", *config.questions.values()]
    assert [t for t in texts + [q.text for q in config.demographics] if jargon_in(t)] == []


def test_refusals_participants_read_name_no_grammar(study):
    s = study.session(study.add_participant(consent=True), "honda")
    complete(s)
    with pytest.raises(StudyInputError) as refused:
        s.add_qualifier(1, "late")
    assert "honda" not in str(refused.value) and not jargon_in(str(refused.value))
    other = study.session(study.add_participant(consent=True), "honda")
    other.set_groups([[1, 2]])
    todo = other.missing()
    assert len(todo) == 6 and [m for m in todo if jargon_in(m)] == []  # "give at least one qualifier" before
