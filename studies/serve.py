"""Participants anywhere: a study's whole participant flow as web pages (``ramure study serve``).

:class:`StudyServer` is the web-free core: it owns the study database (one connection, used by
one thread only), authenticates participants, turns their requests into
:class:`~ramure.studies.session.TestSession` calls and answers with the page's state.
:func:`make_app` wraps it in a Starlette application (imported lazily: the ``web`` extra), and
:func:`serve` runs that on uvicorn.  The pages (``studies/webpages``) are plain HTML and
JavaScript with no build step.

What a request can and cannot do:

- A participant joins by consenting (``POST /api/join``) and receives a code and a token, an
  HMAC of the code and of their random seed under the study's secret (``STUDY.db.web-secret``
  beside the database, made once, readable by its owner only).  Every later request names the
  code in its path and carries the token: a forged code, another participant's code, or the
  token of a deleted participant whose code was given again, is refused (403).
- Pictures and groups are addressed by the participant's own picture labels (two characters,
  :func:`~ramure.studies.session.picture_labels`), never by pick ids, which encode the PCA
  lattice.
- Each answer carries the ``version`` of the state it was made on (the number of answers the
  participant has given) and the part it answers: a replayed or doubled request is stale and
  refused (409); a body over :data:`MAX_BODY_BYTES` is refused (413).  A refused request
  changes nothing in the database.
- The researcher's page and downloads need the researcher token printed at start.

The participant's pages follow the study design (:class:`~ramure.studies.design.ParticipantFlow`,
the same flow as the desktop and the notebook): consent at join, the instructions, the practice
page and practice set, each picture set in the participant's counterbalanced order, the attention
checks after the first set, the demographics questions, and the completion code (the study's
configured code, else one of the participant's own).  The state names the page (``page``: its
kind, title, text and questions, never an attention check's expected answer) or the set
(``part``: 0 for the practice set, then 1..; ``title`` as participants read it).
"""

from __future__ import annotations

import asyncio
import hashlib
import hmac
import io
import json
import os
import pathlib
import queue
import secrets
import sqlite3
import tempfile
import threading
import zipfile
from collections.abc import Callable
from concurrent.futures import Future
from importlib import resources
from typing import TYPE_CHECKING, Any, TypeVar

from ramure.io import read_regular, write_text
from ramure.studies.errors import StudyInputError
from ramure.studies.session import TestSession, picture_labels

if TYPE_CHECKING:
    from starlette.applications import Starlette

    from ramure.studies.design import ParticipantFlow, Step

    from ramure.studies.picks import Pick
    from ramure.studies.storage import Study

#: The largest request body accepted, in bytes (a whole grouping of 27 pictures is under 1 KiB).
MAX_BODY_BYTES = 16 * 1024
#: The participant's pages that are not picture sets.
PAGES = ("instructions", "practice", "attention", "demographics")
#: Events that are not answers: they do not advance a participant's ``version``.
_NOT_ANSWERS = ("start", "resume", "consent", "external_id")
T = TypeVar("T")


class RequestRefused(StudyInputError):
    """A web request refused with an HTTP status (4xx); nothing was changed."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


# -- the study design, as the web pages use it -----------------------------------------------------


def grammar_order(study: Study, code: str) -> list[str]:
    """The order in which participant ``code`` sees the study's picture sets: the stored
    counterbalanced order (:meth:`~ramure.studies.storage.Study.grammar_order`)."""
    return study.grammar_order(code)


def consent_text(study: Study) -> str:
    """The consent shown before anything is recorded: the study's configured text with its contact
    and data retention (:meth:`~ramure.studies.design.StudyConfig.consent_text`), and how long it takes."""
    parts = len(grammar_order_of_new(study))
    return (
        study.config().consent_text()
        + f"\n\nThere {'are' if parts != 1 else 'is'} {parts} part{'s' if parts != 1 else ''} of pictures; "
        f"it takes about {study.budget_seconds / 60:g} minutes."
    )


def grammar_order_of_new(study: Study) -> list[str]:
    """The picture sets a new participant will see (the practice set aside)."""
    practice = study.config().practice_set
    return [g for g in study.grammars if g != practice]


def record_external_id(study: Study, code: str, external_id: str) -> None:
    """Keep the id a recruiting platform gave participant ``code`` (e.g. a Prolific PID from the URL)."""
    from ramure.studies.storage import log_event

    pid = study.conn.execute("SELECT id FROM participants WHERE code = ?", (code,)).fetchone()[0]
    with study.conn:
        log_event(study.conn, pid, "external_id", {"external_id": external_id})


def completion_code(study: Study, code: str, secret: bytes) -> str:
    """The code participant ``code`` is shown at the end, to claim completion on a platform: the
    study's configured code when it has one (one code for all, as Prolific gives), else a code of
    this participant's own (an HMAC of their code under the study's secret)."""
    return study.completion_code(code) or _mac(secret, "complete:" + code)[:10].upper()


# -- the server core -------------------------------------------------------------------------------


def _mac(secret: bytes, text: str) -> str:
    return hmac.new(secret, text.encode(), hashlib.sha256).hexdigest()


def secret_path(db: str | os.PathLike) -> pathlib.Path:
    """The file holding the study's web secret: ``STUDY.db.web-secret`` beside the database (for a
    PostgreSQL study, ``db`` is its :attr:`~ramure.studies.storage.Study.path`: the secret lies in
    the study's folder, ``DBNAME.postgresql.web-secret``)."""
    db = pathlib.Path(db)
    return db.with_name(db.name + ".web-secret")


def study_secret(db: str | os.PathLike) -> bytes:
    """The study's web secret (made on first use, owner-readable only): it signs every token."""
    path = secret_path(db)
    if not path.exists():
        old = os.umask(0o077)
        try:
            write_text(path, secrets.token_hex(32) + "\n")
        finally:
            os.umask(old)
    text = read_regular(path, 4096, "the study's web secret").decode("ascii", "replace").strip()
    if len(text) < 32:
        raise StudyInputError(f"{path}: the study's web secret is too short; delete the file to make a new one")
    return text.encode()


QUESTIONS = {
    "usefulness": "How useful would this group of plants be to you?",
    "difference": "How different is this group from the other groups?",
    "representative_quality": "How well does the chosen picture stand for its group?",
}


class StudyServer:
    """The participant flow on one study database, without any web framework.

    Every method that touches the database runs on the one thread that opened it: :meth:`call`
    (and :meth:`acall`, which the web app awaits) queue a function there.  That thread takes
    the calls queued so far as one batch and runs them in order, each answer in its own
    transaction (``synchronous=NORMAL``: no flush yet); then, if any of them wrote, one last
    tiny transaction with ``synchronous=FULL`` flushes the journal holding them all, and only
    then are their results handed back (group commit).  So an answer acknowledged to a
    participant is on disk, and a crowd answering at once shares the flushes.
    """

    #: At most this many queued calls share one flush.
    MAX_BATCH = 64

    def __init__(self, db: str | os.PathLike, secret: bytes | None = None, folder: str | os.PathLike | None = None) -> None:
        from ramure.studies.pgsql import is_database_url, sqlite_path

        self.db: str | pathlib.Path = str(db) if is_database_url(db) else pathlib.Path(sqlite_path(db))
        self.folder = folder  # a PostgreSQL study's folder, when not the one stored at its creation
        self._study: Study | None = None
        self._sessions: dict[tuple[str, str], TestSession] = {}
        self._picks: dict[str, list[Pick]] = {}
        self._versions: dict[str, int] = {}
        self._seeds: dict[str, int] = {}
        self._shown: dict[tuple[int, str], tuple[dict[int, str], dict[int, int]]] = {}
        self._closed = False
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._serve_calls, name="ramure-study-db", daemon=True)
        self._thread.start()
        if secret is None:  # beside the SQLite file; for PostgreSQL, in the study's folder (Study.path)
            secret = study_secret(self.db if isinstance(self.db, pathlib.Path) else self.call(lambda: self.study.path))
        self.secret = secret

    # -- the database thread ---------------------------------------------------------------------
    @property
    def study(self) -> Study:
        """The study, opened for writing on first use (call only on the database thread)."""
        if self._study is None:
            from ramure.studies.storage import Study

            self._study = Study.open(self.db, folder=self.folder)
            self._study.conn.execute("PRAGMA synchronous = NORMAL")  # flushed once per batch (_flush)
        return self._study

    def call(self, fn: Callable[..., T], *args: Any) -> T:
        """Run ``fn(*args)`` on the database thread and return its result once it is on disk (blocking)."""
        return self._submit(fn, *args).result()

    async def acall(self, fn: Callable[..., T], *args: Any) -> T:
        """Await ``fn(*args)`` run on the database thread (its writes on disk)."""
        return await asyncio.wrap_future(self._submit(fn, *args))

    def _submit(self, fn: Callable[..., T], *args: Any) -> Future:
        if self._closed:
            raise RequestRefused(503, "the study server is stopping")
        future: Future = Future()
        self._queue.put((fn, args, future))
        return future

    def _serve_calls(self) -> None:
        while True:
            batch = [self._queue.get()]
            while batch[-1] is not None and len(batch) < self.MAX_BATCH:
                try:
                    batch.append(self._queue.get_nowait())
                except queue.Empty:
                    break
            stop = batch[-1] is None
            self._run_batch([item for item in batch if item is not None])
            if stop:
                return

    def _run_batch(self, batch: list) -> None:
        changes = self._study.conn.total_changes if self._study is not None else 0
        done: list[tuple[Future, Any, BaseException | None]] = []
        for fn, args, future in batch:
            if future.set_running_or_notify_cancel():
                try:
                    done.append((future, fn(*args), None))
                except BaseException as exc:  # handed to the caller, which turns it into a reply
                    done.append((future, None, exc))
        try:
            if self._study is not None and self._study.conn.total_changes != changes:
                self._flush()
        except sqlite3.Error as exc:
            done = [(future, None, exc) for future, _, _ in done]
        if self._study is not None and getattr(self._study.conn, "broken", False):
            self._forget_connection()
        for future, value, error in done:
            future.set_exception(error) if error is not None else future.set_result(value)

    def _forget_connection(self) -> None:
        """The database server went away (a PostgreSQL restart): this batch's requests got a 503;
        the next call opens the study again.  Sessions and answer counts are read afresh from
        it, so an answer the server lost with its connection is asked for again, never assumed."""
        try:
            self._study.close()  # type: ignore[union-attr]
        except Exception:  # noqa: BLE001 - already broken; nothing more to release
            pass
        self._study = None
        self._sessions.clear()
        self._versions.clear()

    def _flush(self) -> None:
        """Put every answer committed since the last flush on disk: one transaction at
        ``synchronous=FULL`` syncs the write-ahead log, which holds them all."""
        conn = self.study.conn
        conn.execute("PRAGMA synchronous = FULL")
        try:
            with conn:
                conn.execute("UPDATE study SET name = name WHERE id = 1")
        finally:
            conn.execute("PRAGMA synchronous = NORMAL")

    def close(self) -> None:
        """Close the database and stop its thread (again: nothing)."""
        if self._closed:
            return

        def shut() -> None:
            if self._study is not None:
                self._flush()
                self._study.close()
                self._study = None

        self.call(shut)
        self._closed = True
        self._queue.put(None)
        self._thread.join()

    # -- tokens ------------------------------------------------------------------------------------
    def participant_token(self, code: str, seed: int) -> str:
        """Participant ``code``'s token: bound to their random seed too, so a code used again
        after a deletion never accepts the deleted participant's token."""
        return _mac(self.secret, f"participant:{code}:{seed}")[:32]

    def researcher_token(self) -> str:
        return _mac(self.secret, "researcher")[:32]

    def check_researcher(self, token: str | None) -> None:
        if not token or not hmac.compare_digest(token, self.researcher_token()):
            raise RequestRefused(403, "the researcher token is missing or wrong")

    # -- participant requests (database thread) ----------------------------------------------------
    def info(self) -> dict:
        """What the consent page shows."""
        study = self.study
        return dict(title=study.name, parts=len(study.grammars), consent=consent_text(study))

    def join(self, body: dict) -> dict:
        """Register a consenting participant; returns their code and token."""
        if body.get("consent") is not True:
            raise RequestRefused(400, "consent must be given (consent: true) before anything is recorded")
        external = body.get("external_id")
        if external is not None and (not isinstance(external, str) or not 0 < len(external) <= 64):
            raise RequestRefused(400, "external_id must be text of 1 to 64 characters")
        seed = secrets.randbits(31)
        code = self.study.add_participant(code=None, consent=True, seed=seed)
        if external:
            record_external_id(self.study, code, external)
        return dict(code=code, token=self.participant_token(code, seed))

    def check_participant(self, code: str, token: str | None) -> int:
        """Refuse (403) a token that is not participant ``code``'s, or a participant who withdrew;
        return their seed.  An unknown code is refused the same way, so codes cannot be probed."""
        row = self.study.conn.execute("SELECT seed, consent FROM participants WHERE code = ?", (code,)).fetchone()
        if row is None or not token or not hmac.compare_digest(token, self.participant_token(code, row[0])):
            raise RequestRefused(403, "this link does not belong to a participant of this study")
        if not row[1]:
            raise RequestRefused(403, f"participant {code!r} has withdrawn consent")
        if self._seeds.setdefault(code, row[0]) != row[0]:  # the code now names someone else: forget the old one
            self._versions.pop(code, None)
            self._sessions = {key: s for key, s in self._sessions.items() if key[0] != code}
            self._seeds[code] = row[0]
        return row[0]

    def version(self, code: str) -> int:
        """How many answers participant ``code`` has given: each answer must name it, so a replay is stale.

        Counted once from the event log, then kept here: this process alone writes answers.
        """
        if code not in self._versions:
            marks = ", ".join("?" * len(_NOT_ANSWERS))
            self._versions[code] = self.study.conn.execute(
                f"SELECT count(*) FROM events e JOIN participants p ON p.id = e.participant_id "
                f"WHERE p.code = ? AND e.action NOT IN ({marks})",
                (code, *_NOT_ANSWERS),
            ).fetchone()[0]
        return self._versions[code]

    def _shown_as(self, session: TestSession) -> tuple[dict[int, str], dict[int, int]]:
        """The participant's labels and display rank of each pick id in ``session`` (cached)."""
        key = (session.seed, session.grammar)
        if key not in self._shown:
            self._shown[key] = (session.labels(), {pid: i for i, pid in enumerate(session.order())})
        return self._shown[key]

    def _current(self, code: str) -> tuple[ParticipantFlow, Step, TestSession | None]:
        """Participant ``code``'s flow (:class:`~ramure.studies.design.ParticipantFlow`, the study's
        config read once), the page they are on and, on a picture set, its session (started or resumed)."""
        from ramure.studies.design import ParticipantFlow

        flow = ParticipantFlow(self.study, code, front_end="web")
        step = flow.step()
        if step.kind != "test":
            return flow, step, None
        assert step.grammar is not None  # a test step names its set
        key = (code, step.grammar)
        if key not in self._sessions:
            self._sessions[key] = self.study.session(code, step.grammar, front_end="web")
        return flow, step, self._sessions[key]

    def state(self, code: str, token: str | None) -> dict:
        """Everything the participant page shows, in the participant's own picture labels."""
        self.check_participant(code, token)
        return self._state(code)

    def _state(self, code: str) -> dict:
        flow, step, session = self._current(code)
        config = flow.config
        out: dict[str, Any] = dict(code=code, version=self.version(code), part=None, parts=step.total or len(flow.grammars))
        out.update(levels=list(config.levels), title=step.title)
        if step.kind == "done":
            out.update(
                complete=True,
                time_up=bool(step.skipped),
                skipped=len(step.skipped),
                completion_code=completion_code(self.study, code, self.secret),
            )
            return out
        if session is None:  # instructions, practice text, attention checks, demographics
            questions = [dict(key=q.key, text=q.text, options=list(q.options), required=q.required) for q in step.questions]
            out.update(complete=False, page=dict(kind=step.kind, title=step.title, text=step.text, questions=questions))
            return out
        labels, rank = self._shown_as(session)
        shown = lambda ids: [labels[i] for i in sorted(ids, key=rank.__getitem__)]  # noqa: E731
        groups = [
            dict(
                label=g.label,
                pictures=shown(g.images),
                representative=labels[g.representative] if g.representative is not None else None,
                usefulness=g.usefulness,
                difference=g.difference,
                representative_quality=g.representative_quality,
                words=g.qualifiers,
            )
            for g in session.groups()
        ]
        out.update(
            complete=False,
            part=step.number,
            practice=step.number == 0,
            pictures=shown(rank),
            unsorted=shown(session.unsorted()),
            groups=groups,
            missing=[_plain(m) for m in session.missing()],
            questions={**QUESTIONS, **{k: v for k, v in config.questions.items() if k in QUESTIONS}},
        )
        if "representative" in config.questions:
            out["questions"]["representative_quality"] = config.questions["representative"]
        return out

    def answer(self, code: str, token: str | None, body: dict) -> dict:
        """Apply one answer (refused whole, or written in one transaction) and return the new state.

        On a page of text (``instructions``, ``practice``) the answer is ``{"page": kind}``; on a
        page of questions (``attention``, ``demographics``) ``{"page": kind, "answers": {key: option}}``;
        on a picture set one of the actions of :func:`apply_answer` with the set's ``part``.
        """
        self.check_participant(code, token)
        if body.get("version") != self.version(code):
            raise RequestRefused(409, "this answer was made on an older page (a repeat, or another tab); reload the page")
        flow, step, session = self._current(code)
        if "page" in body:
            self._answer_page(flow, step, body)
        else:
            if session is None or body.get("part") != step.number:
                raise RequestRefused(409, "this part is already finished; reload the page")
            apply_answer(session, body, {v: k for k, v in self._shown_as(session)[0].items()})
            if session.finished:
                self._sessions.pop((code, session.grammar), None)
        self._versions[code] += 1
        return self._state(code)

    def _answer_page(self, flow: ParticipantFlow, step: Step, body: dict) -> None:
        if body.get("page") != step.kind or step.kind not in PAGES:
            raise RequestRefused(409, "this page is already done; reload the page")
        if step.kind in ("instructions", "practice"):
            flow.acknowledge(step.kind)
            return
        answers = body.get("answers")
        if not isinstance(answers, dict):
            raise RequestRefused(400, "answers must be an object of question key to the chosen option")
        flow.answer(step.kind, answers)

    def picture(self, code: str, token: str | None, part: int, label: str) -> str | None:
        """The file of participant ``code``'s picture ``label`` in ``part`` (0: the practice set), or None."""
        seed = self.check_participant(code, token)
        order = grammar_order(self.study, code)
        practice = self.study.config().practice_set
        if part == 0 and practice is not None:
            grammar = practice
        elif 1 <= part <= len(order):
            grammar = order[part - 1]
        else:
            raise RequestRefused(404, f"no part {part}")
        by_label = {v: k for k, v in picture_labels(seed, grammar).items()}
        if label not in by_label:
            raise RequestRefused(404, f"no picture {label!r}")
        if grammar not in self._picks:
            self._picks[grammar] = self.study.picks(grammar)
        return self._picks[grammar][by_label[label] - 1].image

    # -- researcher requests (database thread) ---------------------------------------------------
    def progress(self) -> dict:
        """Live progress for the researcher's page."""
        study = self.study
        tests = study.tests()
        answers = study.conn.execute(
            f"SELECT count(*) FROM events WHERE action NOT IN ({', '.join('?' * len(_NOT_ANSWERS))})", _NOT_ANSWERS
        ).fetchone()[0]
        return dict(
            title=study.name,
            parts=study.grammars,
            participants=study.participants(),
            tests=len(tests),
            finished=sum(t["finished_at"] is not None for t in tests),
            answers=answers,
        )

    def export_zip(self) -> bytes:
        """The CSV export (:func:`~ramure.studies.export.export_csv`) as one zip file."""
        from ramure.studies.export import export_csv

        buffer = io.BytesIO()
        with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as zf:
            for path in export_csv(self.study, tmp):
                zf.write(path, path.name)
        return buffer.getvalue()


def _plain(line: str) -> str:
    """A :meth:`TestSession.missing` line in the participant's words (no jargon)."""
    return (
        line.replace("qualifier", "describing word")
        .replace("its usefulness", "how useful it is")
        .replace("its difference", "how different it is")
    )


def _picture_id(by_label: dict[str, int], label: object) -> int:
    if not isinstance(label, str) or label not in by_label:
        raise RequestRefused(400, f"no picture {label!r} in this part")
    return by_label[label]


def _group_number(body: dict) -> int:
    group = body.get("group")
    if isinstance(group, bool) or not isinstance(group, int):
        raise RequestRefused(400, f"group must be a group number, not {group!r}")
    return group


def apply_answer(session: TestSession, body: dict, by_label: dict[str, int] | None = None) -> None:
    """Apply one answer ``body`` (``action`` and its fields, pictures as labels) to ``session``.

    ``by_label`` maps the participant's labels to pick ids (default: from ``session``)."""
    by_label = by_label if by_label is not None else {v: k for k, v in session.labels().items()}
    action = body.get("action")
    if action == "groups":
        groups = body.get("groups")
        if not isinstance(groups, list) or not all(isinstance(g, list) for g in groups):
            raise RequestRefused(400, "groups must be a list of lists of picture labels")
        session.set_groups([[_picture_id(by_label, label) for label in g] for g in groups])
    elif action == "representative":
        session.set_representative(_group_number(body), _picture_id(by_label, body.get("picture")))
    elif action == "rate":
        scales = {k: body.get(k) for k in QUESTIONS if body.get(k) is not None}
        session.rate(
            _group_number(body), scales.get("usefulness"), scales.get("difference"), scales.get("representative_quality")
        )
    elif action == "add_word":
        session.add_qualifier(_group_number(body), body.get("text"))  # type: ignore[arg-type]  # checked by add_qualifier
    elif action == "remove_word":
        session.remove_qualifier(_group_number(body), body.get("text"))  # type: ignore[arg-type]  # checked there too
    elif action == "finish":
        session.finish()
    else:
        raise RequestRefused(400, f"unknown action {action!r}")


# -- the web application -----------------------------------------------------------------------------


def page(name: str) -> bytes:
    """A file of the participant and researcher pages (``studies/webpages``)."""
    return resources.files(__package__).joinpath("webpages", name).read_bytes()


_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8"}
_HEADERS = {
    "Cache-Control": "no-store",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data:; frame-ancestors 'none'",
}


async def read_body(request: Any, limit: int = MAX_BODY_BYTES) -> dict:
    """The JSON object of ``request``'s body, read at most ``limit`` bytes (413 beyond, 400 if not JSON)."""
    length = request.headers.get("content-length")
    if length is not None and (not length.isdigit() or int(length) > limit):
        raise RequestRefused(413, f"request body over {limit} bytes")
    data = bytearray()
    async for chunk in request.stream():
        data += chunk
        if len(data) > limit:
            raise RequestRefused(413, f"request body over {limit} bytes")
    try:
        body = json.loads(bytes(data))
    except ValueError:
        raise RequestRefused(400, "the request body is not JSON") from None
    if not isinstance(body, dict):
        raise RequestRefused(400, "the request body must be a JSON object")
    return body


def _bearer(request: Any) -> str | None:
    auth = request.headers.get("authorization", "")
    return auth[7:].strip() if auth.lower().startswith("bearer ") else None


def make_app(server: StudyServer) -> Starlette:
    """The Starlette application serving ``server``'s participant and researcher pages."""
    from starlette.applications import Starlette
    from starlette.responses import FileResponse, JSONResponse, Response
    from starlette.routing import Route

    def static(name: str) -> Callable:
        body, kind = page(name), _TYPES[pathlib.Path(name).suffix]

        async def endpoint(request):
            return Response(body, media_type=kind, headers=_HEADERS)

        return endpoint

    def reply(obj: object) -> Response:
        return JSONResponse(obj, headers=_HEADERS)

    async def info(request):
        return reply(await server.acall(server.info))

    async def join(request):
        return reply(await server.acall(server.join, await read_body(request)))

    async def state(request):
        return reply(await server.acall(server.state, request.path_params["code"], _bearer(request)))

    async def answer(request):
        body = await read_body(request)
        return reply(await server.acall(server.answer, request.path_params["code"], _bearer(request), body))

    async def picture(request):
        params = request.path_params
        token = request.query_params.get("t")  # an <img> sends no header
        path = await server.acall(server.picture, params["code"], token, params["part"], params["label"])
        if path is None or not os.path.isfile(path):
            return Response(_placeholder(params["label"]), media_type="image/svg+xml", headers=_HEADERS)
        return FileResponse(path, headers={"Cache-Control": "private, max-age=3600"})

    async def progress(request):
        server.check_researcher(_bearer(request))
        return reply(await server.acall(server.progress))

    async def export(request):
        server.check_researcher(_bearer(request))
        data = await server.acall(server.export_zip)
        headers = {**_HEADERS, "Content-Disposition": 'attachment; filename="study-csv.zip"'}
        return Response(data, media_type="application/zip", headers=headers)

    async def refused(request, exc):
        status = exc.status if isinstance(exc, RequestRefused) else 400
        return JSONResponse({"error": str(exc)}, status_code=status, headers=_HEADERS)

    async def broken(request, exc):  # a database error: say so, keep serving
        return JSONResponse({"error": f"the study could not store this ({exc}); try again"}, status_code=503)

    routes = [
        Route("/", static("participant.html")),
        Route("/researcher", static("researcher.html")),
        *(Route(f"/static/{name}", static(name)) for name in ("study.js", "researcher.js", "study.css")),
        Route("/api/study", info),
        Route("/api/join", join, methods=["POST"]),
        Route("/api/p/{code}/state", state),
        Route("/api/p/{code}/answer", answer, methods=["POST"]),
        Route("/img/{code}/{part:int}/{label}", picture),
        Route("/api/researcher/progress", progress),
        Route("/api/researcher/export.zip", export),
    ]
    handlers: dict[Any, Callable] = {StudyInputError: refused, sqlite3.Error: broken}
    return Starlette(routes=routes, exception_handlers=handlers)


def _placeholder(label: str) -> bytes:
    text = "".join(c for c in label if c.isalnum())[:4]
    return (
        '<svg xmlns="http://www.w3.org/2000/svg" width="160" height="160" viewBox="0 0 160 160">'
        '<rect width="160" height="160" fill="#e8eee4"/><text x="80" y="92" font-size="40" text-anchor="middle" '
        f'fill="#4a5a40" font-family="sans-serif">{text}</text></svg>'
    ).encode()


def missing_pictures(study: Study) -> dict[str, list[int]]:
    """Pick ids whose picture file is absent (or outside the study's folder), by stimulus set."""
    missing = {g: [p.id for p in study.picks(g) if p.image is None or not os.path.isfile(p.image)] for g in study.grammars}
    return {g: ids for g, ids in missing.items() if ids}


def check_servable(study: Study) -> None:
    """Refuse to serve a study that participants could not see: every pick needs its picture."""
    missing = missing_pictures(study)
    if missing:
        which = "; ".join(f"{g}: {len(ids)} of 27 (e.g. pick {ids[0]})" for g, ids in missing.items())
        raise StudyInputError(
            f"{study.where}: pictures missing or outside the study's folder ({which}); explore with thumbnails "
            "into the study's folder (ramure explore GRAMMAR -o STUDY_FOLDER/NAME) and create the study from there"
        )


def serve(
    db: str | os.PathLike,
    host: str = "127.0.0.1",
    port: int = 8000,
    announce: Callable[[dict], None] = print,
    folder: str | os.PathLike | None = None,
) -> None:
    """Serve study ``db`` (a SQLite file or a PostgreSQL URL) on ``host:port`` until interrupted
    (needs the ``web`` extra).  ``folder`` overrides a PostgreSQL study's folder of pictures.

    The file is checked first (a study, every picture present) and nothing is written beside a
    file that is refused.  ``announce`` receives the participant and researcher addresses
    before the server starts listening.
    """
    from ramure.studies.storage import Study

    try:
        import uvicorn
    except ImportError:
        raise StudyInputError("serving a study needs the web extra: pip install 'ramure[web]'") from None
    with Study.open(db, readonly=True, folder=folder) as study:
        check_servable(study)
        where = study.where
    server = StudyServer(db, folder=folder)
    try:
        server.call(lambda: server.study)  # opened for writing before listening: refused here, not per request
        base = f"http://{host if ':' not in host else f'[{host}]'}:{port}"
        token = server.researcher_token()
        addresses = dict(participants=f"{base}/", researcher=f"{base}/researcher#{token}", researcher_token=token)
        announce(dict(db=where, **addresses))
        uvicorn.run(make_app(server), host=host, port=port, log_level="warning", access_log=False)
    finally:
        server.close()
