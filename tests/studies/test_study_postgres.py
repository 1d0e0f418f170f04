"""A study on PostgreSQL (issue 38, section 5): the same code from a database URL, the same
answers as on SQLite, and the same guarantees with several processes writing at once.

Every test runs on a throwaway server (the ``pg_cluster`` fixture: Debian's package); they are
skipped only where PostgreSQL's programs are absent.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess

import numpy as np
import pytest
from test_study_processes import READER, WRITER, start

from ramure.app.cli import main
from ramure.studies.data import load_study_data
from ramure.studies.errors import StudyInputError
from ramure.studies.export import export_csv
from ramure.studies.picks import lattice_picks
from ramure.studies.simulate import run_simulation, synthetic_grammars
from ramure.studies.storage import Study


def run(capsys, *argv):
    code = main(["study", *argv])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if out.strip() else None), err


def test_a_simulated_study_stores_the_same_answers_on_postgresql_as_on_sqlite(tmp_path, pg_url):
    grammars = synthetic_grammars(3, seed=5)
    results = {}
    for where in (tmp_path / "study.db", pg_url):
        with Study.create(where, grammars=grammars, name="twin", folder=tmp_path) as study:
            codes = run_simulation(study, participants=6, seed=3)
            data = load_study_data(study)
            files = {p.name: p.read_text() for p in export_csv(study, tmp_path / ("csv-" + type(study.conn).__name__))}
            results[where] = (codes, data, files, study.participants())
    (codes_a, a, files_a, people_a), (codes_b, b, files_b, people_b) = results.values()
    assert codes_a == codes_b == [f"P{101 + i}" for i in range(6)]
    assert a.participants == b.participants and a.n_tests == b.n_tests == 18 and len(a.group_test) > 18
    for name in ("test_grammar", "test_participant", "group_test", "group_label", "membership", "representative"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in ("usefulness", "difference", "representative_quality", "qualifier_group"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_allclose(a.test_seconds, b.test_seconds, rtol=1e-12)  # sums of doubles, in the engines' order
    np.testing.assert_array_equal(a.pca, b.pca)  # double precision, not PostgreSQL's 32-bit REAL
    assert a.qualifier_text == b.qualifier_text and a.params == b.params
    # The CSVs a researcher analyses in R are the same files, but for the times of day.
    for name in ("picks.csv", "groups.csv", "memberships.csv", "qualifiers.csv"):
        assert files_a[name] == files_b[name], name
    assert [(p["code"], p["tests"], p["finished"], round(p["elapsed_seconds"], 6)) for p in people_a] == [
        (p["code"], p["tests"], p["finished"], round(p["elapsed_seconds"], 6)) for p in people_b
    ]


def test_three_writers_a_reader_and_kill_9_lose_no_acknowledged_answer_on_postgresql(pg_url):
    codes = ["P1", "P2", "P3"]
    with Study.create(pg_url, grammars={"honda": lattice_picks(seed=1)}) as study:
        for code in codes:
            study.add_participant(code, consent=True)
    answers = 30
    writers = {code: start(WRITER, pg_url, code, answers) for code in codes}
    reader = start(READER, pg_url, 30)
    acknowledged: dict[str, list[str]] = {code: [] for code in codes}
    try:
        for line in writers["P2"].stdout:
            acknowledged["P2"].append(line.strip())
            if len(acknowledged["P2"]) == answers // 2:
                os.kill(writers["P2"].pid, signal.SIGKILL)
                break
        for code in ("P1", "P3"):
            acknowledged[code] = [line.strip() for line in writers[code].stdout]
        reader.stdout.read()
    finally:
        for proc in [*writers.values(), reader]:
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    assert writers["P2"].returncode == -signal.SIGKILL
    assert writers["P1"].returncode == writers["P3"].returncode == reader.returncode == 0
    assert len(acknowledged["P1"]) == len(acknowledged["P3"]) == answers
    with Study.open(pg_url, readonly=True) as study:
        stored = {text for (text,) in study.conn.execute("SELECT text FROM qualifiers")}
        events = study.events()
    for code in codes:
        missing = [text for text in acknowledged[code] if text not in stored]
        assert not missing, f"{code}: acknowledged but lost: {missing}"
    assert len({t for t in stored if t.startswith("P2-")}) in (answers // 2, answers // 2 + 1)
    # Every stored answer has its event, written in the same transaction.
    assert sum(e["action"] == "add_qualifier" for e in events) == len(stored)


def test_refused_answers_change_nothing_on_postgresql(pg_url, clock):
    with Study.create(pg_url, grammars={"honda": lattice_picks(seed=1)}, clock=clock) as study:
        s = study.session(study.add_participant(consent=True), "honda")
        s.set_groups([range(1, 10), range(10, 28)])
        s.rate(1, usefulness=2)

        def rows():
            tables = ("groups", "group_images", "qualifiers", "events", "tests")
            return {t: study.conn.execute(f"SELECT * FROM {t} ORDER BY 1").fetchall() for t in tables}

        before = rows()
        for bad in (
            lambda: s.set_groups([[1, 2, 2]]),
            lambda: s.set_representative(1, 20),
            lambda: s.rate(1, usefulness=9),
            lambda: s.rate(2, representative="good"),
            lambda: s.add_qualifier(3, "tall"),
            lambda: s.add_qualifier(1, " "),
            lambda: s.finish(),
            lambda: study.add_participant("P101"),
        ):
            clock.advance(5)
            with pytest.raises(StudyInputError):
                bad()
        assert rows() == before
        with pytest.raises(StudyInputError, match="already used"):  # the database's own refusal, translated
            study.add_participant("P101")


def test_the_cli_creates_serves_and_analyses_a_study_from_a_url(tmp_path, pg_url, capsys):
    explore = tmp_path / "explore"
    for name, seed in (("honda", 1), ("tree2", 2)):
        (explore / name).mkdir(parents=True)
        picks = [dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params) for p in lattice_picks(seed)]
        (explore / name / "picks.json").write_text(json.dumps(picks))
    url = pg_url.replace("ramure@", "ramure:secret@")  # trust authentication ignores it; it is never printed
    grammars = ["--grammar", f"honda={explore / 'honda'}", "--grammar", f"tree2={explore / 'tree2'}"]
    code, out, _ = run(capsys, "create", url, *grammars, "--budget-minutes", "20", "--no-render", "--folder", str(tmp_path))
    assert code == 0 and out["grammars"] == ["honda", "tree2"] and out["db"] == url.replace(":secret@", ":***@")
    code, _, err = run(capsys, "create", url, *grammars)
    assert code == 2 and "already holds a study" in err and "secret" not in err
    code, _, err = run(capsys, "create", str(tmp_path / "s.db"), *grammars, "--folder", str(tmp_path))
    assert code == 2 and "--folder is for a study on PostgreSQL" in err and not (tmp_path / "s.db").exists()

    with Study.open(url) as study:
        assert study.grammar_source("honda") == str(explore / "honda")  # stored relative to the folder
        run_simulation(study, participants=4, seed=1)
    code, out, _ = run(capsys, "status", url)
    assert (out["tests"], out["finished"], len(out["participants"])) == (8, 8, 4)
    code, out, _ = run(capsys, "analyze", url, "-o", str(tmp_path / "report"))
    assert code == 0 and (out["tests"], out["participants"]) == (8, 4)
    assert (tmp_path / "report" / "index.html").is_file()
    code, out, _ = run(capsys, "export-csv", url, "-o", str(tmp_path / "csv"))
    assert code == 0 and len(out["files"]) == 8
    memberships = (tmp_path / "csv" / "memberships.csv").read_text().splitlines()
    assert len(memberships) == 1 + 8 * 27  # every picture of every finished test
    # Read commands never write: the server refuses it on their connection.
    with Study.open(url, readonly=True) as study:
        with pytest.raises(Exception, match="read-only"):
            study.conn.execute("DELETE FROM events")


def test_a_database_without_a_study_and_a_server_that_is_not_there_are_refused(pg_url, pg_cluster, capsys):
    code, _, err = run(capsys, "status", pg_url)
    assert code == 2 and "holds no Ramure study" in err and "Traceback" not in err
    code, _, err = run(capsys, "status", f"postgresql://ramure@127.0.0.1:{pg_cluster.port}/nowhere")
    assert code == 2 and "cannot connect" in err and "nowhere" in err
    import psycopg

    with psycopg.connect(pg_url, autocommit=True) as conn:
        conn.execute("CREATE TABLE groups (id int)")
    with pytest.raises(StudyInputError, match="already has tables named groups; choose an empty database"):
        Study.create(pg_url, grammars={"honda": lattice_picks(seed=1)})


ENROL = """
import sys
from ramure.studies.storage import Study
with Study.open(sys.argv[1]) as study:
    for _ in range(int(sys.argv[2])):
        print(study.add_participant(consent=True), flush=True)
"""


def test_stations_enrolling_at_once_draw_distinct_codes_and_balanced_orders_on_postgresql(pg_url):
    """Codes and Latin-square rows are drawn inside the enrolment's transaction, where writers
    take turns: three stations enrolling at once never draw one code or one row twice."""
    with Study.create(pg_url, grammars={"a": lattice_picks(seed=1), "b": lattice_picks(seed=2)}) as study:
        pass
    stations = [start(ENROL, pg_url, 12) for _ in range(3)]
    codes = [line.strip() for station in stations for line in station.stdout]
    assert [station.wait(timeout=120) for station in stations] == [0, 0, 0]
    assert len(codes) == len(set(codes)) == 36
    with Study.open(pg_url, readonly=True) as study:
        assert sorted(p["code"] for p in study.participants()) == sorted(codes)
        orders = [tuple(study.grammar_order(code)) for code in codes]
    assert orders.count(("a", "b")) == orders.count(("b", "a")) == 18  # the square's two rows, evenly


def test_a_sqlite_url_names_the_file(tmp_path, monkeypatch):
    """``sqlite:///`` URLs (SQLAlchemy's spelling) name the same file as its path: three slashes
    before a relative path, four before an absolute one."""
    monkeypatch.chdir(tmp_path)
    Study.create("sqlite:///rel.db", grammars={"honda": lattice_picks(seed=1)}).close()
    with Study.open(f"sqlite:///{tmp_path / 'rel.db'}", readonly=True) as study:
        assert study.path == tmp_path / "rel.db" and study.grammars == ["honda"] and not study.postgres


def test_the_web_server_opens_the_study_again_after_postgresql_drops_its_connection(tmp_path, pg_url):
    """A database restart cuts the server's connection: the request then gets a 503 and stores
    nothing, and the next one is served on a new connection, with the answer counts read again."""
    import warnings

    import psycopg

    pytest.importorskip("starlette")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient
    from web_helpers import WebParticipant, make_study

    from ramure.studies.serve import StudyServer, make_app

    server = StudyServer(make_study(tmp_path, db=pg_url))
    with TestClient(make_app(server)) as client:
        p = WebParticipant(client)
        p.send(action="groups", groups=[p.state["pictures"][:13], p.state["pictures"][13:]])
        with psycopg.connect(pg_url, autocommit=True) as admin:  # what a restart does to the server's connection
            others = "datname = current_database() AND pid <> pg_backend_pid()"
            admin.execute(f"SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE {others}")
        body = {"version": p.state["version"], "part": 1, "action": "rate", "group": 1, "usefulness": 4}
        r = client.post(f"/api/p/{p.code}/answer", json=body, headers=p.headers)
        assert r.status_code == 503 and "try again" in r.json()["error"]
        assert p.get_state()["version"] == body["version"] and p.state["groups"][0]["usefulness"] is None
        p.send(action="rate", group=1, usefulness=4)
        assert p.state["groups"][0]["usefulness"] == 4
    server.close()
    with Study.open(pg_url, readonly=True) as study:
        rows = study.conn.execute("SELECT label, usefulness FROM groups ORDER BY label").fetchall()
        assert rows == [(1, 4), (2, None)]
        actions = [e["action"] for e in study.events(p.code)]
        assert actions[-3:] == ["group", "resume", "rate"]  # the test resumed on the new connection
