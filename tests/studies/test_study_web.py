"""``ramure study serve``: the participant flow over HTTP (Starlette's TestClient), the
researcher's page, and requests that must be refused with a 4xx and change nothing (issue 38 §5)."""

from __future__ import annotations

import csv
import io
import json
import pathlib
import subprocess
import threading
import sys
import warnings
import zipfile

import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx")

with warnings.catch_warnings():  # Starlette 1.x prefers httpx2 for its test client; httpx works the same
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient
from web_helpers import WebParticipant, make_study, snapshot  # noqa: E402

from ramure.studies.serve import MAX_BODY_BYTES, StudyServer, make_app, secret_path  # noqa: E402
from ramure.studies.session import picture_labels  # noqa: E402
from ramure.studies.storage import Study  # noqa: E402


@pytest.fixture(params=["sqlite", "postgresql"])
def served(request, tmp_path):
    """A served study, on a SQLite file and on PostgreSQL (the same tests, the same guarantees)."""
    url = request.getfixturevalue("pg_url") if request.param == "postgresql" else None
    db = make_study(tmp_path, db=url)
    server = StudyServer(db)
    with TestClient(make_app(server)) as client:
        yield db, server, client
    server.close()


def test_a_whole_participant_session_is_stored_and_gives_a_completion_code(served):
    db, server, client = served
    assert "2 parts" in client.get("/api/study").json()["consent"]
    p = WebParticipant(client, external_id="5f1e0c")
    assert (p.state["part"], p.state["parts"], len(p.state["unsorted"])) == (1, 2, 27)
    first = p.answer_part()
    assert (p.state["part"], p.state["complete"]) == (2, False)  # the next part, not the end
    p.get_state()  # a reload in the middle continues the same part
    assert p.state["part"] == 2 and p.state["unsorted"] == p.state["pictures"]
    p.answer_part(sizes=(20, 7))
    assert p.state["complete"] is True and p.pages_seen == ["instructions", "practice", "attention", "demographics"]
    assert p.get_state()["completion_code"] == p.state["completion_code"]  # stable on reload
    server.close()  # the database is written by the server's one connection; read it now
    with Study.open(db, readonly=True) as study:
        assert study.finished(p.code, "g0") and study.finished(p.code, "g1")
        groups = study.conn.execute(
            "SELECT g.label, g.usefulness, g.difference, g.representative_quality FROM groups g "
            "JOIN tests t ON t.id = g.test_id JOIN grammars gr ON gr.id = t.grammar_id WHERE gr.name = 'g0' ORDER BY g.label"
        ).fetchall()
        assert groups == [(1, 2, 3, 3), (2, 3, 2, 3), (3, 4, 1, 3), (4, 1, 4, None)]
        seed = study.conn.execute("SELECT seed FROM participants WHERE code = ?", (p.code,)).fetchone()[0]
        pick_of = {v: k for k, v in picture_labels(seed, "g0").items()}
        stored = study.conn.execute(
            "SELECT gi.pick_id FROM group_images gi JOIN groups g ON g.id = gi.group_id JOIN tests t ON t.id = g.test_id "
            "JOIN grammars gr ON gr.id = t.grammar_id WHERE gr.name = 'g0' AND g.label = 1"
        ).fetchall()
        assert sorted(r[0] for r in stored) == sorted(pick_of[label] for label in first[0])
        external = [e["detail"] for e in study.events(p.code) if e["action"] == "external_id"]
        assert external == [{"external_id": "5f1e0c"}]
        assert p.state["completion_code"] == study.completion_code(p.code)  # the study's code for them
        assert set(study.participant_answers(p.code)) == {"instructions", "practice", "attention", "demographics"}


def test_pages_speak_in_labels_never_pick_ids_or_jargon(served):
    _, server, client = served
    p = WebParticipant(client)
    labels = set(p.state["pictures"])
    assert len(labels) == 27 and all(len(label) == 2 and label[0].isalpha() for label in labels)
    assert not {str(i) for i in range(1, 28)} & labels
    pages = client.get("/").text + client.get("/static/study.js").text
    assert not [word for word in ("grammar", "variant", "qualifier") if word in pages.lower()]
    shown = client.get("/api/study").json()["consent"] + json.dumps(p.state["questions"]) + " ".join(p.state["missing"])
    assert not {"grammar", "variant", "qualifier"} & set(shown.lower().replace(",", " ").replace(".", " ").split())


def test_pictures_are_served_by_label_and_a_missing_one_is_a_placeholder(tmp_path):
    db = make_study(tmp_path, grammars=1)
    server = StudyServer(db)
    with TestClient(make_app(server)) as client:
        p = WebParticipant(client)
        label = p.state["pictures"][0]
        r = client.get(f"/img/{p.code}/1/{label}?t={p.token}")
        assert r.status_code == 200 and r.content.startswith(b"\x89PNG")
        assert client.get(f"/img/{p.code}/1/{label}").status_code == 403  # no token: no picture, no hint
        assert client.get(f"/img/P999/1/{label}?t={p.token}").status_code == 403
        pick = {
            v: k
            for k, v in picture_labels(
                server.call(
                    lambda: server.study.conn.execute("SELECT seed FROM participants WHERE code = ?", (p.code,)).fetchone()[0]
                ),
                "g0",
            ).items()
        }[label]
        assert r.content == (tmp_path / "set0" / f"pick_{pick:02d}.png").read_bytes()
        assert client.get(f"/img/{p.code}/1/ZZ?t={p.token}").status_code == 404
        assert client.get(f"/img/{p.code}/2/{label}?t={p.token}").status_code == 404
    server.close()
    db2 = make_study(tmp_path / "bare", grammars=1, pictures=False)
    server = StudyServer(db2)
    with TestClient(make_app(server)) as client:
        p = WebParticipant(client)
        r = client.get(f"/img/{p.code}/1/{p.state['pictures'][0]}?t={p.token}")
        assert r.status_code == 200 and r.headers["content-type"].startswith("image/svg+xml")
        assert p.state["pictures"][0].encode() in r.content
    server.close()


def refused(client, db, method, url, status, **kwargs):
    """Send one bad request: it must get ``status`` and leave every row as it was."""
    before = snapshot(db)
    r = getattr(client, method)(url, **kwargs)
    assert r.status_code == status, (url, r.status_code, r.text)
    assert "error" in r.json()
    assert snapshot(db) == before
    return r.json()["error"]


def test_bad_requests_get_a_4xx_and_change_nothing(served):
    db, server, client = served
    alice, bob = WebParticipant(client), WebParticipant(client)
    groups = [alice.state["pictures"][:13], alice.state["pictures"][13:]]
    alice.send(action="groups", groups=groups)
    url = f"/api/p/{alice.code}/answer"
    good = {"version": alice.state["version"], "part": 1, "action": "rate", "group": 1, "usefulness": 4}

    # A forged participant: a made-up token, no token, a code that does not exist.
    assert "does not belong" in refused(client, db, "post", url, 403, json=good, headers={"Authorization": "Bearer " + "0" * 32})
    refused(client, db, "post", url, 403, json=good)
    refused(client, db, "post", "/api/p/P999/answer", 403, json=good, headers=alice.headers)
    # Another participant's answer: Bob's token on Alice's test, and Alice's code read by Bob.
    refused(client, db, "post", url, 403, json=good, headers=bob.headers)
    refused(client, db, "get", f"/api/p/{alice.code}/state", 403, headers=bob.headers)
    # A replay: the grouping request sent again (its version is stale), and an answer to a finished part.
    stale = {"version": alice.state["version"] - 1, "part": 1, "action": "groups", "groups": [alice.state["pictures"]]}
    assert "older page" in refused(client, db, "post", url, 409, json=stale, headers=alice.headers)
    refused(client, db, "post", url, 409, json={**good, "part": 2}, headers=alice.headers)
    # An oversized body, announced or streamed without a length.
    huge = {**good, "text": "x" * MAX_BODY_BYTES}
    refused(client, db, "post", url, 413, json=huge, headers=alice.headers)
    chunks = (b'{"a": "' + b"x" * 4096 for _ in range(MAX_BODY_BYTES // 4096 + 2))
    refused(client, db, "post", url, 413, content=chunks, headers=alice.headers)
    # Malformed answers: not JSON, not an object, unknown action, a picture of nobody, a bad level.
    refused(client, db, "post", url, 400, content=b"{nope", headers=alice.headers)
    refused(client, db, "post", url, 400, json=[1, 2], headers=alice.headers)
    refused(client, db, "post", url, 400, json={**good, "action": "drop_table"}, headers=alice.headers)
    refused(client, db, "post", url, 400, json={**good, "action": "groups", "groups": [["ZZ"]]}, headers=alice.headers)
    refused(client, db, "post", url, 400, json={**good, "usefulness": 7}, headers=alice.headers)
    refused(client, db, "post", url, 400, json={**good, "action": "finish"}, headers=alice.headers)
    refused(client, db, "post", "/api/join", 400, json={"consent": False})
    refused(client, db, "post", "/api/join", 400, json={"consent": True, "external_id": "x" * 65})

    # The good answer still goes through, once: its replay is refused.
    r = client.post(url, json=good, headers=alice.headers)
    assert r.status_code == 200 and r.json()["groups"][0]["usefulness"] == 4
    refused(client, db, "post", url, 409, json=good, headers=alice.headers)


def test_the_researcher_page_needs_its_token_and_shows_progress_and_downloads(served):
    db, server, client = served
    assert client.get("/researcher").status_code == 200  # the page itself holds nothing
    for url in ("/api/researcher/progress", "/api/researcher/export.zip"):
        assert client.get(url).status_code == 403
        assert client.get(url, headers={"Authorization": "Bearer wrong"}).status_code == 403
    done, started = WebParticipant(client), WebParticipant(client)
    done.answer_part()
    done.answer_part()
    started.send(action="groups", groups=[started.state["pictures"]])
    auth = {"Authorization": f"Bearer {server.researcher_token()}"}
    progress = client.get("/api/researcher/progress", headers=auth).json()
    assert (progress["tests"], progress["finished"]) == (3, 2)
    assert [p["code"] for p in progress["participants"]] == [done.code, started.code]
    # per part: the grouping, 3 groups x (representative, its rating, two ratings, a word), a single x 2, finish;
    # the pages: instructions and practice for both, attention and demographics for the one who finished
    assert progress["answers"] == 2 * (1 + 3 * 4 + 2 + 1) + 1 + 2 + 2 + 2
    r = client.get("/api/researcher/export.zip", headers=auth)
    assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
    with zipfile.ZipFile(io.BytesIO(r.content)) as zf:
        assert {"groups.csv", "codebook.csv", "tests.csv"} <= set(zf.namelist())
        rows = list(csv.DictReader(io.TextIOWrapper(zf.open("groups.csv"), encoding="utf-8")))
    assert len(rows) == 4 + 4 + 1 and {r["participant"] for r in rows} == {done.code, started.code}


def test_tokens_survive_a_restart_and_the_secret_is_private(tmp_path):
    db = make_study(tmp_path, grammars=1)
    server = StudyServer(db)
    with TestClient(make_app(server)) as client:
        p = WebParticipant(client)
        p.send(action="groups", groups=[p.state["pictures"][:5]])
    server.close()
    assert secret_path(db).stat().st_mode & 0o077 == 0
    server = StudyServer(db)  # a new process would read the same secret
    with TestClient(make_app(server)) as client:
        r = client.get(f"/api/p/{p.code}/state", headers=p.headers)
        assert r.status_code == 200 and len(r.json()["groups"][0]["pictures"]) == 5
    server.close()


def test_serve_refuses_a_file_that_is_not_a_study_before_listening(tmp_path):
    bad = tmp_path / "notes.db"
    bad.write_text("not a database")
    out = subprocess.run(
        [str(pathlib.Path(sys.executable).with_name("ramure")), "study", "serve", str(bad), "--port", "9"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "not a SQLite file" in out.stderr and "Traceback" not in out.stderr
    assert out.stdout == "" and sorted(tmp_path.iterdir()) == [bad]  # no secret written beside it
    bare = make_study(tmp_path / "bare", grammars=1, pictures=False)
    out = subprocess.run(
        [str(pathlib.Path(sys.executable).with_name("ramure")), "study", "serve", str(bare), "--port", "9"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "pictures missing" in out.stderr and "g0: 27 of 27" in out.stderr
    assert not secret_path(bare).exists()
    good = make_study(tmp_path / "good", grammars=1)
    out = subprocess.run(
        [str(pathlib.Path(sys.executable).with_name("ramure")), "study", "serve", str(good), "--port", "0"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "--port must be from 1 to 65535" in out.stderr and out.stdout == ""


def test_answers_queued_together_share_one_flush_and_are_acknowledged_after_it(tmp_path):
    db = make_study(tmp_path, grammars=1)
    server = StudyServer(db)
    with TestClient(make_app(server)) as client:
        people = [WebParticipant(client) for _ in range(6)]
    flushes, flush = [], server._flush
    gate = threading.Event()

    def counted_flush():
        flushes.append(sum(f.done() for f in futures))  # answers already handed back at this flush
        flush()

    server._flush = counted_flush
    server._submit(gate.wait)  # hold the database thread while the crowd queues its answers
    answers = [{"version": p.state["version"], "part": 1, "action": "groups", "groups": [p.state["pictures"]]} for p in people]
    futures = [server._submit(server.answer, p.code, p.token, body) for p, body in zip(people, answers)]
    gate.set()
    states = [f.result(timeout=30) for f in futures]
    assert flushes == [0]  # one flush for the six answers, before any was acknowledged
    assert [len(s["groups"][0]["pictures"]) for s in states] == [27] * 6
    server.close()
    with Study.open(db, readonly=True) as study:
        assert study.conn.execute("SELECT count(*) FROM groups").fetchone()[0] == 6


def test_a_code_used_again_after_a_deletion_does_not_accept_the_old_token(served):
    db, server, client = served
    gone = WebParticipant(client)
    gone.send(action="groups", groups=[gone.state["pictures"][:3]])
    server.call(server.study.delete_participant, gone.code)  # the researcher erases them
    assert client.get(f"/api/p/{gone.code}/state", headers=gone.headers).status_code == 403
    new = WebParticipant(client)
    assert new.code == gone.code and new.token != gone.token  # the lowest free code again
    assert client.get(f"/api/p/{new.code}/state", headers=gone.headers).status_code == 403
    assert new.state["groups"] == [] and new.state["version"] == len(new.pages_seen)  # nothing of the erased one
    new.send(action="groups", groups=[new.state["pictures"][:2]])
    assert len(new.state["groups"][0]["pictures"]) == 2


def test_a_spent_time_budget_ends_the_study_with_its_code_and_says_so(tmp_path):
    db = make_study(tmp_path, grammars=2, budget_minutes=0.0005)  # 30 ms: spent during the first part
    server = StudyServer(db)
    ticks = iter(range(10**6))  # every reading of the study's clock a second later: a warm process
    server.call(lambda: setattr(server.study, "clock", lambda: float(next(ticks))))  # answers in < 30 ms
    with TestClient(make_app(server)) as client:
        p = WebParticipant(client)
        p.answer_part()
        assert p.state["complete"] is True and p.state["time_up"] is True and p.state["skipped"] == 1
        assert p.pages_seen[-2:] == ["attention", "demographics"]  # the questions still come, the set does not
    server.close()
    with Study.open(db, readonly=True) as study:
        assert study.finished(p.code, "g0") and [t["grammar"] for t in study.tests()] == ["g0"]


# -- the participant flow of the study design, over the web (issue 38 §3 and §5) ---------------------
def test_the_web_walks_the_designed_flow_and_refuses_a_page_out_of_turn(served):
    db, server, client = served
    p = WebParticipant(client, pages=False)
    page = p.state["page"]
    assert (page["kind"], page["questions"]) == ("instructions", []) and "New group" in page["text"]
    url = f"/api/p/{p.code}/answer"
    before = snapshot(db)
    for body in ({"page": "practice"}, {"page": "attention", "answers": {}}, {"action": "groups", "groups": [], "part": 1}):
        r = client.post(url, json={"version": p.state["version"], **body}, headers=p.headers)
        assert r.status_code == 409, body  # not the page the participant is on
    assert snapshot(db) == before
    p.send(page="instructions")
    p.send(page="practice")
    assert p.state["part"] == 1 and p.state["title"] == "Set 1 of 2" and len(p.state["unsorted"]) == 27
    p.pages = False  # answer_part leaves the next page to this test
    p.answer_part()
    page = p.state["page"]
    assert page["kind"] == "attention" and page["questions"][0]["options"] == ["poor", "fair", "good", "excellent"]
    assert "answer" not in page["questions"][0]  # the expected option is never sent
    for answers, status, words in (({}, 400, "please answer"), ({"attention_1": "splendid"}, 400, "is not one of")):
        before = snapshot(db)
        r = client.post(url, json={"version": p.state["version"], "page": "attention", "answers": answers}, headers=p.headers)
        assert r.status_code == status and words in r.json()["error"]
        assert snapshot(db) == before
    p.send(page="attention", answers={"attention_1": "good"})  # the wrong option: stored, flagged in the analysis
    assert p.state["part"] == 2
    p.answer_part()
    assert p.state["page"]["kind"] == "demographics"
    p.send(page="demographics", answers={"age": "25-39", "expertise": "a little"})
    assert p.state["complete"] is True and p.state["skipped"] == 0
    server.close()
    with Study.open(db, readonly=True) as study:
        assert study.participant_answers(p.code)["attention"] == {"attention_1": "good"}
        assert {e["front_end"] for e in study.events(p.code) if e["grammar"]} == {"web"}


def test_a_practice_set_comes_first_over_the_web_and_participants_get_counterbalanced_orders(tmp_path):
    from ramure.studies.design import StudyConfig

    config = StudyConfig(practice_set="g2", levels=("no", "a little", "rather", "very"), attention_checks=())
    db = make_study(tmp_path, grammars=3, config=config)
    server = StudyServer(db)
    with TestClient(make_app(server)) as client:
        first, second = WebParticipant(client), WebParticipant(client)
        for p in (first, second):
            assert (p.state["part"], p.state["practice"], p.state["title"]) == (0, True, "Practice")
            assert p.state["levels"] == ["no", "a little", "rather", "very"]
            label = p.state["pictures"][0]
            assert client.get(f"/img/{p.code}/0/{label}", params={"t": p.token}).status_code == 200
            p.answer_part(sizes=(27,))
            assert (p.state["part"], p.state["practice"], p.state["title"]) == (1, False, "Set 1 of 2")
        orders = [server.call(server.study.grammar_order, p.code) for p in (first, second)]
        assert orders == [["g0", "g1"], ["g1", "g0"]]  # the Williams square's first two rows
    server.close()
