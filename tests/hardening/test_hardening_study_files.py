"""Study databases from strangers (issue 37, items 3 and 7): refused unchanged, read without a write.

A file that is not Ramure's is refused byte for byte, with no ``-wal``/``-shm`` left beside it;
read commands (``status``, ``analyze``, ``export-csv``) never write, not even to a study; a study
whose values are not what Ramure writes is refused with one line naming table, row and column.
"""

from __future__ import annotations

import hashlib
import shutil
import sqlite3

import pytest

from ramure.app.cli import main
from ramure.errors import RamureError
from ramure.studies.errors import StudyInputError
from ramure.studies.storage import APPLICATION_ID, Study, schema_sql


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def cli(argv, capsys):
    """``ramure ARGV`` in this process: (exit status, stderr)."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    return rc, capsys.readouterr().err.strip()


def refused_in_one_line(rc, err, *words):
    assert rc == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    for word in words:
        assert word in err, err


@pytest.fixture(scope="module")
def real_study(tmp_path_factory):
    """A study with answers, made by the simulator, closed (WAL checkpointed away)."""
    from ramure.studies.simulate import simulate_study

    path = tmp_path_factory.mktemp("real") / "study.db"
    simulate_study(path, participants=3, grammars=2, seed=3)
    return path


@pytest.fixture
def study_copy(real_study, tmp_path):
    (tmp_path / "study").mkdir()
    path = tmp_path / "study" / "study.db"
    shutil.copyfile(real_study, path)
    return path


def foreign_db(path, journal="delete", version=1):
    """Another application's database: our table names, its own columns."""
    conn = sqlite3.connect(path)
    conn.execute(f"PRAGMA journal_mode = {journal}")
    for table in ("study", "grammars", "picks", "participants", "tests", "groups", "group_images", "qualifiers", "events"):
        conn.execute(f"CREATE TABLE {table} (id INTEGER PRIMARY KEY, name TEXT, budget_seconds REAL)")
    conn.execute("INSERT INTO study VALUES (1, 'their data', 60)")
    conn.execute(f"PRAGMA user_version = {version}")
    conn.commit()
    conn.close()
    return path


def only_file(path):
    return sorted(p.name for p in path.parent.iterdir()) == [path.name]


# -- item 3: nothing written to a file that is not Ramure's --------------------------------
@pytest.mark.parametrize("journal", ["delete", "wal"])
@pytest.mark.parametrize("readonly", [False, True])
def test_a_foreign_database_with_our_table_names_is_refused_unchanged(tmp_path, journal, readonly):
    path = foreign_db(tmp_path / "other.db", journal)
    before = digest(path)
    with pytest.raises(StudyInputError, match="has other columns"):
        Study.open(path, readonly=readonly)
    assert digest(path) == before and only_file(path)
    conn = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == journal  # not switched
    conn.close()


def test_a_foreign_database_is_refused_by_status_and_create(tmp_path, capsys):
    path = foreign_db(tmp_path / "other.db")
    before = digest(path)
    refused_in_one_line(*cli(["study", "status", path], capsys), "other columns")
    with pytest.raises(StudyInputError, match="exists and is not a study"):
        Study.create(path, grammars={})
    assert digest(path) == before and only_file(path)


@pytest.mark.parametrize("keep", [0.5, 0.9])
def test_a_truncated_study_is_refused_with_no_debris(study_copy, keep, capsys):
    data = study_copy.read_bytes()
    study_copy.write_bytes(data[: int(len(data) * keep) // 4096 * 4096 or 4096])
    before = digest(study_copy)
    for readonly in (False, True):
        with pytest.raises(StudyInputError):
            Study.open(study_copy, readonly=readonly)
    refused_in_one_line(*cli(["study", "status", study_copy], capsys), str(study_copy))
    assert digest(study_copy) == before and only_file(study_copy)


@pytest.mark.parametrize("kind", ["pipe", "folder", "device"])
def test_a_study_that_is_a_pipe_a_folder_or_a_device_is_refused_at_once(tmp_path, capsys, kind):
    import os

    path = tmp_path / "study.db"
    if kind == "pipe":
        os.mkfifo(path)  # no writer: opening it would block for good
    elif kind == "folder":
        path.mkdir()
    else:
        path = "/dev/zero"
    refused_in_one_line(*cli(["study", "status", path], capsys), "not a regular file")


def to_rollback_journal(path):
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA journal_mode = DELETE").fetchone()[0] == "delete"
    conn.close()


def test_status_on_a_rollback_journal_study_changes_nothing(study_copy, capsys):
    to_rollback_journal(study_copy)
    before = digest(study_copy)
    rc, err = cli(["study", "status", study_copy], capsys)
    assert rc == 0, err
    assert digest(study_copy) == before and only_file(study_copy)
    conn = sqlite3.connect(f"{study_copy.as_uri()}?mode=ro", uri=True)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "delete"
    conn.close()


def test_read_commands_leave_a_version_1_study_as_it_is(study_copy, tmp_path, capsys):
    conn = sqlite3.connect(study_copy)  # what a version-1 Ramure wrote: no events, no application id
    conn.executescript("DROP TABLE events; PRAGMA user_version = 1; PRAGMA application_id = 0; PRAGMA journal_mode = DELETE;")
    conn.close()
    before = digest(study_copy)
    assert cli(["study", "status", study_copy], capsys)[0] == 0
    assert cli(["study", "export-csv", study_copy, "-o", tmp_path / "csv"], capsys)[0] == 0
    assert cli(["study", "analyze", study_copy, "-o", tmp_path / "report", "--no-figures"], capsys)[0] == 0
    with Study.open(study_copy, readonly=True) as study:
        assert study.version == 1 and study.events() == [] and len(study.participants()) == 3
        with pytest.raises(StudyInputError, match="read-only"):
            study.add_participant()
    assert digest(study_copy) == before and only_file(study_copy)
    with Study.open(study_copy) as study:  # a write open recognises it by its schema, then migrates it
        assert study.conn.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
        assert study.version == 3 and study.events() == []


def test_a_read_only_study_refuses_every_change(study_copy):
    with Study.open(study_copy, readonly=True) as study:
        code = study.participants()[0]["code"]
        for change in (
            lambda: study.add_participant(),
            lambda: study.record_consent(code, False),
            lambda: study.delete_participant(code),
            lambda: study.session(code, study.grammars[0]),
            lambda: study.add_grammar("more", None),
        ):
            with pytest.raises(StudyInputError, match="opened read-only"):
                change()


def test_a_study_exactly_like_ours_but_made_before_the_application_id_opens(tmp_path):
    path = tmp_path / "old.db"
    conn = sqlite3.connect(path)
    conn.executescript(schema_sql() + "PRAGMA user_version = 3;")
    conn.execute("INSERT INTO study VALUES (1, 'old', 600, '2025-01-01T00:00:00+00:00')")
    conn.commit()
    conn.close()
    with Study.open(path, readonly=True) as study:
        assert (study.name, study.budget_seconds, study.grammars) == ("old", 600.0, [])


@pytest.mark.parametrize("kind", ["foreign", "text", "foreign_wal"])
def test_export_qualifiers_refuses_a_foreign_store_unchanged(real_study, tmp_path, capsys, kind):
    store = tmp_path / "other.db"
    if kind == "text":
        store.write_text("not sqlite at all " * 50)
    else:
        conn = sqlite3.connect(store)
        conn.execute(f"PRAGMA journal_mode = {'wal' if kind == 'foreign_wal' else 'delete'}")
        conn.execute("CREATE TABLE accounts (id INTEGER PRIMARY KEY, owner TEXT)")
        conn.execute("INSERT INTO accounts (owner) VALUES ('someone')")
        conn.commit()
        conn.close()
    before = digest(store)
    refused_in_one_line(*cli(["study", "export-qualifiers", real_study, "--store", store], capsys), str(store))
    assert digest(store) == before and only_file(store)


def test_export_qualifiers_writes_new_stores_its_own_and_studies(real_study, study_copy, tmp_path, capsys):
    from ramure.metrics.store import QualifierStore

    store = tmp_path / "store" / "q.db"
    for target in (store, store, study_copy):  # new, then its own again, then a study
        rc, err = cli(["study", "export-qualifiers", real_study, "--store", target, "--min-usefulness", "poor"], capsys)
        assert rc == 0, err
    with QualifierStore(store) as opened:
        assert opened.rows() and opened.conn.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
    with QualifierStore(study_copy) as opened:
        assert len(opened.rows()) == len(QualifierStore(store).rows())


def test_a_store_made_before_the_application_id_is_still_ramure_s(tmp_path):
    from ramure.metrics.store import SCHEMA, QualifierStore

    path = tmp_path / "old.db"
    conn = sqlite3.connect(path)
    conn.execute(SCHEMA)
    conn.commit()
    conn.close()
    with QualifierStore(path) as store:
        assert store.add("g", "dense", [1], [[0, 0, 0]], [{"rule": 0, "constants": {}}]) == 1


# -- item 7: right tables, wrong values ------------------------------------------------------
def mutate(path, sql):
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA ignore_check_constraints = 1")
    conn.execute(sql)
    conn.commit()
    conn.close()


WRONG_VALUES = [
    ("UPDATE study SET budget_seconds = 'lots'", "table study, row 1: budget_seconds"),
    ("UPDATE picks SET pick_id = 1000 WHERE rowid = 3", "table picks, row 3: pick_id must be an integer from 1 to 27, not 1000"),
    ("UPDATE picks SET pick_id = 0 WHERE rowid = 27", "table picks, row 27: pick_id must be an integer from 1 to 27, not 0"),
    ("UPDATE study SET name = ''", "table study, row 1: name must be non-empty text"),
    ("UPDATE grammars SET name = x'00ff' WHERE id = 1", "table grammars, row 1: name"),
    ("UPDATE picks SET pc2 = 9e999 WHERE rowid = 5", "table picks, row 5: pc2 must be a finite number"),
    ("UPDATE picks SET params = '{not json' WHERE rowid = 7", "table picks, row 7: params"),
    ("UPDATE participants SET consent = 7 WHERE id = 2", "table participants, row 2: consent"),
    ("UPDATE groups SET usefulness = 9 WHERE id = 4", "table groups, row 4: usefulness"),
    ("UPDATE groups SET representative = 'x' WHERE id = 4", "table groups, row 4: representative"),
    ("UPDATE group_images SET pick_id = -3 WHERE rowid = 2", "table group_images, row 2: pick_id"),
    ("UPDATE tests SET participant_id = 99 WHERE id = 1", "row 1: participant_id names no row of table participants"),
    ("UPDATE qualifiers SET text = x'41' WHERE id = 1", "table qualifiers, row 1: text"),
    ("DELETE FROM picks WHERE rowid = 9", "has 26 picks"),
]


@pytest.mark.parametrize("sql, words", WRONG_VALUES)
def test_wrong_values_are_refused_naming_table_row_and_column(study_copy, sql, words):
    mutate(study_copy, sql)
    before = digest(study_copy)
    for readonly in (True, False):
        with pytest.raises(StudyInputError) as info:
            Study.open(study_copy, readonly=readonly)
        assert words in str(info.value) and "\n" not in str(info.value)
    assert digest(study_copy) == before


@pytest.mark.parametrize("sql, words", WRONG_VALUES[:3])
def test_status_and_analyze_refuse_wrong_values_in_one_line(study_copy, tmp_path, capsys, sql, words):
    mutate(study_copy, sql)
    before = digest(study_copy)
    refused_in_one_line(*cli(["study", "status", study_copy], capsys), words)
    refused_in_one_line(*cli(["study", "analyze", study_copy, "-o", tmp_path / "r", "--no-figures"], capsys), words)
    assert digest(study_copy) == before and not (tmp_path / "r").exists()


def test_a_column_without_its_constraint_is_not_our_schema(tmp_path):
    path = tmp_path / "s.db"
    conn = sqlite3.connect(path)  # grammars.name may be NULL here: not the table Ramure writes
    conn.executescript(schema_sql().replace("name TEXT NOT NULL UNIQUE", "name TEXT") + "PRAGMA user_version = 3;")
    conn.execute("INSERT INTO study VALUES (1, 's', 60, 'now')")
    conn.execute("INSERT INTO grammars (id, name) VALUES (1, NULL)")
    conn.commit()
    conn.close()
    with pytest.raises(StudyInputError, match="table grammars has other columns"):
        Study.open(path, readonly=True)


def test_fuzz_slice_of_the_study_readers_raises_only_ramure_errors():
    """A fixed-seed slice of ``python -m tests.hardening.fuzz_studies``: mutated study databases
    (read commands must not change a byte), synonym files and exploration folders."""
    from tests.hardening.fuzz_studies import campaign

    counts = campaign(120, seed=37)
    bad = {key: n for key, n in counts.items() if key[1] not in ("ok", "refused")}
    assert not bad, counts
    for reader in ("study", "synonyms", "exploration"):  # each reader both accepts and refuses
        assert counts[reader, "ok"] > 3 and counts[reader, "refused"] > 10, counts


# -- item 7: synonym files; item 6: qualifier text bounded -------------------------------------
SYNONYM_FILES = [
    (b'{"qualifiers": {"petit\xff": {"synonyms": []}}}', "not UTF-8 text (byte 22)"),
    (b"[" * 100_000 + b"]" * 100_000, "nested too deeply"),
    (b'{"qualifiers": {"small": {"synonyms": [1, 2]}}}', "synonym 1 must be text"),
    (b'{"qualifiers": {"small": {"synonyms": [["nested"]]}}}', "synonym 1 must be text"),
    (b'{"qualifiers": {"small": {"fr": {"x": 1}}}}', "'fr' must be text"),
    (b'{"qualifiers": {"small": "petit"}}', "must be an object"),
    (b'{"qualifiers": ["small"]}', "expected an object with a 'qualifiers' object"),
    (b"[1, 2, 3]", "expected an object with a 'qualifiers' object"),
    (b'{"qualifiers": {"small": {"synonyms": ["' + b"x" * 300 + b'"]}}}', "at most 200 characters"),
    (b" " * (2 << 20), "more than the limit"),
]


@pytest.mark.parametrize("content, words", SYNONYM_FILES, ids=range(len(SYNONYM_FILES)))
def test_bad_synonym_files_are_refused_in_one_line(real_study, tmp_path, capsys, content, words):
    from ramure.studies.qualifiers import SynonymTable

    path = tmp_path / "syn.json"
    path.write_bytes(content)
    with pytest.raises(RamureError) as info:
        SynonymTable.load(path)
    assert words in str(info.value) and "\n" not in str(info.value)
    refused_in_one_line(*cli(["study", "export-csv", real_study, "-o", tmp_path / "csv", "--synonyms", path], capsys), words)
    assert not (tmp_path / "csv").exists()


@pytest.mark.parametrize("kind", ["pipe", "device"])
def test_a_synonym_file_that_is_a_pipe_or_a_device_is_refused_at_once(tmp_path, capsys, real_study, kind):
    import os

    path = tmp_path / "syn.json"
    if kind == "pipe":
        os.mkfifo(path)  # no writer: a plain open would block for good
    else:
        path = "/dev/zero"
    refused_in_one_line(
        *cli(["study", "analyze", real_study, "-o", tmp_path / "r", "--no-figures", "--synonyms", path], capsys),
        "not a regular file",
    )


def test_qualifier_text_is_bounded_when_written_and_when_read(study_copy):
    from ramure.studies.data import load_study_data
    from ramure.studies.qualifiers import MAX_QUALIFIER_CHARS

    conn = sqlite3.connect(study_copy)  # a megabyte of text in one answer, as a tampered file may hold
    conn.execute("UPDATE qualifiers SET text = ? WHERE id = 1", ("petit " * 200_000,))
    conn.commit()
    conn.close()
    data = load_study_data(study_copy)
    assert max(map(len, data.qualifier_text)) == MAX_QUALIFIER_CHARS == 200
    with Study.open(study_copy) as study:
        code = study.add_participant(consent=True)
        session = study.session(code, study.grammars[0])
        session.set_groups([list(range(1, 28))])
        with pytest.raises(StudyInputError, match="at most 200 characters"):
            session.add_qualifier(1, "x" * 201)
        session.add_qualifier(1, "x" * 200)


def test_text_that_is_not_utf8_is_refused_in_one_line(study_copy, tmp_path):
    conn = sqlite3.connect(study_copy)  # SQLite keeps any bytes as text
    conn.execute("UPDATE qualifiers SET text = CAST(x'636c6169728c' AS TEXT) WHERE id = 2")
    conn.commit()
    conn.close()
    from ramure.studies.data import load_study_data

    with pytest.raises(StudyInputError, match=r"not UTF-8 \(near b'clair\\x8c'\); the file is damaged"):
        load_study_data(study_copy)  # found when read: checking every text at each open would read them twice
    damaged = tmp_path / "damaged.db"  # a table name whose bytes are not UTF-8: SQLite's message quotes them
    conn = sqlite3.connect(damaged)
    conn.execute("CREATE TABLE study (id)")
    conn.commit()
    conn.close()
    data = bytearray(damaged.read_bytes())
    data[data.find(b"study", 100) + 1] = 0x8C
    damaged.write_bytes(bytes(data))
    with pytest.raises(StudyInputError, match="damaged"):
        Study.open(damaged, readonly=True)
