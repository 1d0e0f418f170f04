"""A study stored in SQLite: grammars and their 27 picks, participants, tests.

Every write is one transaction (``with conn:``), foreign keys are on and the
journal is WAL, so a crash loses at most the answer being written.  The schema
is ``studies/schema.sql``.

>>> import tempfile, pathlib
>>> from ramure.studies.picks import lattice_picks
>>> db = pathlib.Path(tempfile.mkdtemp()) / "study.db"
>>> study = Study.create(db, grammars={"honda": lattice_picks(seed=1)}, name="demo")
>>> code = study.add_participant(consent=True)
>>> code, study.grammars
('P101', ['honda'])
>>> session = study.session(code, "honda")
>>> sorted(session.order()) == list(range(1, 28))
True
>>> study.close()
"""

from __future__ import annotations

import datetime
import json
import math
import os
import pathlib
import re
import sqlite3
import time
import zlib
from importlib import resources

from ramure.studies.errors import StudyInputError
from ramure.studies.picks import Pick, inside_folder, load_picks, picks_from_data
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.studies.session import TestSession

SCHEMA_VERSION = 2
#: The schema version each table appeared in (the others are in version 1).
TABLE_SINCE = {"events": 2}
DEFAULT_BUDGET_MINUTES = 30.0
_CODE = re.compile(r"^[A-Za-z0-9_-]{1,32}$")


def now_iso() -> str:
    """The current UTC time as ISO-8601 text (seconds precision)."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def connect(path: str | os.PathLike, durable: bool = True) -> sqlite3.Connection:
    """Open ``path`` with foreign keys on, WAL journal and a busy timeout.

    ``durable=False`` sets ``synchronous=NORMAL``: a committed answer still
    survives a killed process, but not a power cut; simulations use it for speed.
    """
    conn = sqlite3.connect(os.fspath(path), timeout=10.0)
    conn.execute("PRAGMA foreign_keys = ON")
    conn.execute("PRAGMA journal_mode = WAL")
    conn.execute(f"PRAGMA synchronous = {'FULL' if durable else 'NORMAL'}")
    return conn


def schema_sql() -> str:
    """The text of ``studies/schema.sql``."""
    return resources.files(__package__).joinpath("schema.sql").read_text(encoding="utf-8")


#: SQLite ``PRAGMA application_id`` of a Ramure study ("RAMU"); files made before it hold 0.
APPLICATION_ID = 0x52414D55


def _schema_tables(version: int = SCHEMA_VERSION) -> set:
    names = set(re.findall(r"CREATE TABLE IF NOT EXISTS (\w+)", schema_sql()))
    return {name for name in names if TABLE_SINCE.get(name, 1) <= version}


def migrate(conn: sqlite3.Connection) -> None:
    """Bring an open study database to :data:`SCHEMA_VERSION`, in one transaction.

    Version 1 lacks the ``events`` table; ``schema.sql`` creates only what is
    missing, so running it migrates, and answers already stored are untouched.
    Two processes migrating at once are serialised by ``BEGIN IMMEDIATE``.
    """
    if conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION:
        return
    try:
        conn.executescript(f"BEGIN IMMEDIATE; {schema_sql()} PRAGMA user_version = {SCHEMA_VERSION}; COMMIT;")
    except sqlite3.Error:
        if conn.in_transaction:
            conn.rollback()
        raise


def event_time() -> str:
    """The current UTC time as ISO-8601 text, to the millisecond (event log)."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="milliseconds")


def log_test_event(conn: sqlite3.Connection, test_id: int, action: str, detail: dict) -> None:
    """Append an action on test ``test_id`` to the ``events`` table, with the test's participant and
    elapsed time read in the same statement (call it inside the change's transaction)."""
    conn.execute(
        "INSERT INTO events (participant_id, test_id, at, elapsed_seconds, action, detail) "
        "SELECT participant_id, id, ?, elapsed_seconds, ?, ? FROM tests WHERE id = ?",
        (event_time(), action, json.dumps(detail, sort_keys=True), test_id),
    )


def log_event(
    conn: sqlite3.Connection,
    participant_id: int,
    action: str,
    detail: dict | None = None,
    test_id: int | None = None,
    elapsed_seconds: float | None = None,
) -> None:
    """Append one participant action to the ``events`` table (call it inside the change's transaction)."""
    conn.execute(
        "INSERT INTO events (participant_id, test_id, at, elapsed_seconds, action, detail) VALUES (?, ?, ?, ?, ?, ?)",
        (participant_id, test_id, event_time(), elapsed_seconds, action, json.dumps(detail or {}, sort_keys=True)),
    )


def check_study_file(path: str | os.PathLike) -> None:
    """Refuse, with one line, a file that is not a study database of this version.

    Read-only: SQLite is opened with ``mode=ro``, so another application's
    database or an empty file is never changed (no WAL switch, no header
    written).  The file is never opened with a plain descriptor: on POSIX,
    closing one drops every lock this process holds on the file, those of its
    open study connections too, and another process would then checkpoint and
    delete the WAL they still write into.  Checked: a SQLite file,
    ``application_id`` (:data:`APPLICATION_ID`, or 0 for files made before it),
    ``user_version`` 1 to :data:`SCHEMA_VERSION` (older ones are migrated by
    :meth:`Study.open`), and every table of that version.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise StudyInputError(f"{path}: no such study file")
    if path.stat().st_size == 0:
        raise StudyInputError(f"{path}: empty file, not a Ramure study database")
    try:
        conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True, timeout=10.0)
    except sqlite3.Error as exc:
        raise StudyInputError(f"{path}: cannot open it read-only ({exc})") from None
    try:
        app_id = conn.execute("PRAGMA application_id").fetchone()[0]
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    except sqlite3.DatabaseError as exc:
        if getattr(exc, "sqlite_errorcode", None) == sqlite3.SQLITE_NOTADB:
            raise StudyInputError(f"{path}: not a SQLite file, so not a Ramure study database") from None
        raise StudyInputError(f"{path}: not a readable SQLite database ({exc})") from None
    finally:
        conn.close()
    if app_id not in (0, APPLICATION_ID):
        raise StudyInputError(f"{path}: belongs to another application (application_id {app_id:#x}), not a Ramure study")
    missing = _schema_tables(version if 1 <= version <= SCHEMA_VERSION else 1) - tables
    if missing:
        raise StudyInputError(f"{path}: not a Ramure study database (no table {', '.join(sorted(missing))})")
    if not 1 <= version <= SCHEMA_VERSION:
        raise StudyInputError(f"{path}: study database version {version}; this Ramure reads versions 1 to {SCHEMA_VERSION}")


def is_database_file(db: str | os.PathLike, path: str | os.PathLike) -> bool:
    """Whether ``path`` is the database ``db`` or one of its journals (``-wal``, ``-shm``,
    ``-journal``), by name or as the same file (a link): never open those with a plain
    descriptor while a connection is open (its close drops the connection's locks).

    Only ``stat`` is used, which takes no descriptor.
    """
    db = pathlib.Path(db)
    for name in (db, *(db.with_name(db.name + tail) for tail in ("-wal", "-shm", "-journal"))):
        try:
            if os.path.samefile(name, path):
                return True
        except OSError:
            if pathlib.Path(name).resolve() == pathlib.Path(path).resolve():
                return True
    return False


def _has_study(conn) -> bool:
    row = conn.execute("SELECT name FROM sqlite_master WHERE type='table' AND name='study'").fetchone()
    return row is not None and conn.execute("SELECT count(*) FROM study").fetchone()[0] == 1


class Study:
    """A study database: grammars x 27 picks, participants, one test per grammar each.

    Use :meth:`create` for a new file and :meth:`open` for an existing one.
    ``clock`` (seconds, monotonic) times the participants' budget; tests pass a fake.
    """

    def __init__(self, conn: sqlite3.Connection, path: str | os.PathLike, clock: Callable[[], float] = time.monotonic) -> None:
        self.conn = conn
        self.path = pathlib.Path(path)
        self.clock = clock
        row = conn.execute("SELECT name, budget_seconds FROM study WHERE id = 1").fetchone()
        self.name, self.budget_seconds = row[0], float(row[1])

    # -- opening -----------------------------------------------------------
    @classmethod
    def create(
        cls,
        path: str | os.PathLike,
        grammars: dict | None = None,
        name: str | None = None,
        budget_minutes: float = DEFAULT_BUDGET_MINUTES,
        clock: Callable[[], float] = time.monotonic,
        durable: bool = True,
    ) -> Study:
        """Create a study in a new file ``path``.

        ``grammars`` maps a grammar name to an exploration directory (holding
        ``picks.json``) or to plain data: a list of 27 pick dicts or
        :class:`~ramure.studies.picks.Pick`.  ``budget_minutes`` is each participant's
        time budget over all their tests.
        """
        path = pathlib.Path(path)
        try:
            budget = float(budget_minutes)
        except (TypeError, ValueError):
            budget = math.nan
        if not budget > 0:
            raise StudyInputError(f"budget must be a positive number of minutes, got {budget_minutes!r}")
        # Read every grammar before touching the disk, so a bad one leaves no file.
        loaded = {gname: _read_grammar(gname, spec) for gname, spec in (grammars or {}).items()}
        if path.exists() and path.stat().st_size > 0:
            conn = sqlite3.connect(os.fspath(path))
            try:
                exists = _has_study(conn)
            except sqlite3.DatabaseError:
                raise StudyInputError(f"{path}: exists and is not a SQLite file") from None
            finally:
                conn.close()
            if exists:
                raise StudyInputError(f"{path}: already holds a study; open it instead")
            raise StudyInputError(f"{path}: exists and is not a study; choose a new file")
        path.parent.mkdir(parents=True, exist_ok=True)
        conn = connect(path, durable)
        conn.executescript(schema_sql())
        with conn:
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(
                "INSERT INTO study (id, name, budget_seconds, created_at) VALUES (1, ?, ?, ?)",
                (name or path.stem, 60.0 * budget, now_iso()),
            )
            for gname, (source, picks) in loaded.items():
                _insert_grammar(conn, gname, source, picks)
        return cls(conn, path, clock)

    @classmethod
    def open(cls, path: str | os.PathLike, clock: Callable[[], float] = time.monotonic, durable: bool = True) -> Study:
        """Open an existing study file (refused with a clear message otherwise).

        A file of an older schema version is migrated in place (see :func:`migrate`).
        """
        path = pathlib.Path(path)
        check_study_file(path)  # read-only: a file that is not ours is never changed
        conn: sqlite3.Connection | None = None
        try:
            conn = connect(path, durable)
            ok = _has_study(conn)
            if ok:
                migrate(conn)
        except sqlite3.DatabaseError:
            ok = False
        if not ok or conn is None:
            if conn is not None:
                conn.close()
            raise StudyInputError(f"{path}: not a Ramure study database")
        return cls(conn, path, clock)

    def close(self) -> None:
        self.conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- grammars and picks --------------------------------------------------
    @property
    def grammars(self) -> list[str]:
        """Grammar names, in the order they were added."""
        return [r[0] for r in self.conn.execute("SELECT name FROM grammars ORDER BY id")]

    def add_grammar(self, name: str, spec: object) -> None:
        """Add one grammar (exploration directory or plain pick data)."""
        source, picks = _read_grammar(name, spec)
        with self.conn:
            _insert_grammar(self.conn, name, source, picks)

    def grammar_id(self, name: str) -> int:
        row = self.conn.execute("SELECT id FROM grammars WHERE name = ?", (name,)).fetchone()
        if row is None:
            known = ", ".join(self.grammars) or "none"
            raise StudyInputError(f"no grammar {name!r} in this study (known: {known})")
        return row[0]

    def grammar_source(self, name: str) -> str | None:
        """Where grammar ``name``'s picks came from (an exploration directory), or None."""
        row = self.conn.execute("SELECT source FROM grammars WHERE id = ?", (self.grammar_id(name),)).fetchone()
        return row[0] if row and row[0] else None

    def picks(self, grammar: str) -> list[Pick]:
        """The 27 picks of ``grammar``, by id."""
        rows = self.conn.execute(
            "SELECT pick_id, variant_id, pc1, pc2, pc3, params, image FROM picks WHERE grammar_id = ? ORDER BY pick_id",
            (self.grammar_id(grammar),),
        )
        return [Pick(r[0], r[1], (r[2], r[3], r[4]), json.loads(r[5]), self._picture(r[6])) for r in rows]

    def _picture(self, image):
        """A pick's picture path if it lies inside the study's folder, else None (never shown).

        A database can name any file; only pictures under the folder holding the
        database are ever read (symbolic links and ``..`` resolved first), and never
        the database or its journals: reading them would drop this process's locks.
        """
        try:
            picture = inside_folder(self.path.parent, image, str(self.path))
        except StudyInputError:
            return None
        if picture is not None and is_database_file(self.path, picture):
            return None
        return picture

    # -- participants --------------------------------------------------------
    def add_participant(self, code: str | None = None, consent: bool = False, seed: int | None = None) -> str:
        """Register a participant under an anonymous ``code`` (default P101, P102...).

        ``seed`` fixes the image order of their tests (default: from the code).
        """
        if code is None:
            taken = {r[0] for r in self.conn.execute("SELECT code FROM participants")}
            number = 101
            while f"P{number}" in taken:
                number += 1
            code = f"P{number}"
        code = str(code)
        if not _CODE.match(code):
            raise StudyInputError(
                f"participant code {code!r} must be 1-32 letters, digits, '-' or '_' (an anonymous code, not a name)"
            )
        if seed is None:
            seed = zlib.crc32(code.encode())
        stamp = now_iso()
        try:
            with self.conn:
                pid = self.conn.execute(
                    "INSERT INTO participants (code, seed, consent, consent_at, created_at) VALUES (?, ?, ?, ?, ?)",
                    (code, int(seed), int(bool(consent)), stamp if consent else None, stamp),
                ).lastrowid
                if consent and pid is not None:  # pid: set by the INSERT just made
                    log_event(self.conn, pid, "consent", {"given": True})
        except sqlite3.IntegrityError:
            raise StudyInputError(f"participant code {code!r} is already used") from None
        return code

    def record_consent(self, code: str, given: bool = True) -> None:
        """Record that participant ``code`` gave (or withdrew) consent, with the time.

        Without consent a participant cannot start or resume a test, and their
        answers are left out of the analysis and exports (but kept on disk; use
        :meth:`delete_participant` to erase them).
        """
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute(
                "UPDATE participants SET consent = ?, consent_at = ? WHERE code = ?", (int(bool(given)), now_iso(), code)
            )
            log_event(self.conn, pid, "consent", {"given": bool(given)})

    def delete_participant(self, code: str) -> None:
        """Erase participant ``code`` and every answer they gave (one transaction)."""
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute("DELETE FROM participants WHERE id = ?", (pid,))

    def _participant(self, code):
        row = self.conn.execute("SELECT id, seed, consent FROM participants WHERE code = ?", (str(code),)).fetchone()
        if row is None:
            raise StudyInputError(f"no participant {code!r} in this study")
        return row

    def participants(self) -> list[dict]:
        """Each participant's code, consent and number of tests started/finished."""
        rows = self.conn.execute(
            "SELECT p.code, p.consent, p.consent_at, count(t.id), count(t.finished_at), "
            "coalesce(sum(t.elapsed_seconds), 0) FROM participants p "
            "LEFT JOIN tests t ON t.participant_id = p.id GROUP BY p.id ORDER BY p.id"
        )
        return [
            dict(code=r[0], consent=bool(r[1]), consent_at=r[2], tests=r[3], finished=r[4], elapsed_seconds=r[5]) for r in rows
        ]

    def used_seconds(self, code: str) -> float:
        """Seconds participant ``code`` has spent, as committed with their answers."""
        pid = self._participant(code)[0]
        return float(
            self.conn.execute("SELECT coalesce(sum(elapsed_seconds), 0) FROM tests WHERE participant_id = ?", (pid,)).fetchone()[
                0
            ]
        )

    def remaining_seconds(self, code: str) -> float:
        """Budget left for ``code`` (never below 0)."""
        return max(0.0, self.budget_seconds - self.used_seconds(code))

    # -- tests ----------------------------------------------------------------
    def session(self, code: str, grammar: str) -> TestSession:
        """Start, or resume, participant ``code``'s test on ``grammar``.

        Refused without consent, and refused for a *new* test once the
        participant's budget is spent (an unfinished test can always be resumed).
        """
        from ramure.studies.session import TestSession

        pid, seed, consent = self._participant(code)
        gid = self.grammar_id(grammar)
        if not consent:
            raise StudyInputError(f"participant {code!r} has not given consent; record it first")
        row = self.conn.execute(
            "SELECT id, finished_at, elapsed_seconds FROM tests WHERE participant_id = ? AND grammar_id = ?", (pid, gid)
        ).fetchone()
        if row is None:
            if self.remaining_seconds(code) <= 0:
                raise StudyInputError(
                    f"participant {code!r} has used their {self.budget_seconds / 60:g}-minute budget; no new test"
                )
            with self.conn:
                cur = self.conn.execute(
                    "INSERT INTO tests (participant_id, grammar_id, started_at) VALUES (?, ?, ?)", (pid, gid, now_iso())
                )
                test_id = cur.lastrowid
                assert test_id is not None  # set by the INSERT just made
                log_event(self.conn, pid, "start", {"grammar": grammar}, test_id, 0.0)
        else:
            test_id = row[0]
            if row[1] is None:
                with self.conn:
                    log_event(self.conn, pid, "resume", {"grammar": grammar}, test_id, row[2])
        return TestSession(self, test_id, str(code), grammar, seed)

    def finished(self, code: str, grammar: str) -> bool:
        """Whether participant ``code`` has finished their test on ``grammar``."""
        row = self.conn.execute(
            "SELECT t.finished_at FROM tests t JOIN participants p ON p.id = t.participant_id "
            "JOIN grammars g ON g.id = t.grammar_id WHERE p.code = ? AND g.name = ?",
            (str(code), grammar),
        ).fetchone()
        return row is not None and row[0] is not None

    def events(self, code: str | None = None) -> list[dict]:
        """The event log, oldest first: every accepted action of participant ``code`` (or of all).

        Each event: participant, grammar (None for consent), ``at`` (UTC, ms), the
        test's ``elapsed_seconds`` then, ``action`` and its ``detail`` (a dict).
        """
        where, args = ("WHERE p.code = ?", (str(code),)) if code is not None else ("", ())
        rows = self.conn.execute(
            "SELECT p.code, g.name, e.at, e.elapsed_seconds, e.action, e.detail FROM events e "
            "JOIN participants p ON p.id = e.participant_id LEFT JOIN tests t ON t.id = e.test_id "
            f"LEFT JOIN grammars g ON g.id = t.grammar_id {where} ORDER BY e.id",
            args,
        )
        keys = ("participant", "grammar", "at", "elapsed_seconds", "action")
        return [dict(zip(keys, r[:5]), detail=json.loads(r[5])) for r in rows]

    def tests(self) -> list[dict]:
        """Every test: participant, grammar, finished or not, elapsed seconds."""
        rows = self.conn.execute(
            "SELECT t.id, p.code, g.name, t.started_at, t.finished_at, t.elapsed_seconds "
            "FROM tests t JOIN participants p ON p.id = t.participant_id "
            "JOIN grammars g ON g.id = t.grammar_id ORDER BY t.id"
        )
        return [
            dict(test=r[0], participant=r[1], grammar=r[2], started_at=r[3], finished_at=r[4], elapsed_seconds=r[5]) for r in rows
        ]


def _read_grammar(name, spec):
    if not isinstance(name, str) or not name.strip():
        raise StudyInputError(f"grammar name {name!r} must be non-empty text")
    if name.strip().casefold() == "all":
        raise StudyInputError("grammar name 'all' is reserved for the pooled statistics")
    if isinstance(spec, (str, os.PathLike)):
        return str(pathlib.Path(spec).resolve()), load_picks(spec)
    return None, picks_from_data(spec, where=f"grammar {name!r}")


def _insert_grammar(conn, name, source, picks):
    try:
        gid = conn.execute("INSERT INTO grammars (name, source) VALUES (?, ?)", (name, source)).lastrowid
    except sqlite3.IntegrityError:
        raise StudyInputError(f"grammar {name!r} is already in this study") from None
    conn.executemany(
        "INSERT INTO picks (grammar_id, pick_id, variant_id, pc1, pc2, pc3, params, image) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
        [(gid, p.id, p.variant, *p.pca, json.dumps(p.params, sort_keys=True), p.image) for p in picks],
    )
