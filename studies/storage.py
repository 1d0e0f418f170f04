"""A study stored in SQLite: grammars and their 27 picks, participants, tests.

The same code stores a study in PostgreSQL when given a ``postgresql://`` URL instead of a
file (:mod:`ramure.studies.pgsql` is the dialect layer; :func:`check_postgres_study` the
check at each open).  What follows describes the SQLite file.

Every write is one transaction (``with conn:``), foreign keys are on and the
journal is WAL, so a crash loses at most the answer being written.  The schema
is ``studies/schema.sql``.

What makes a file Ramure's, and what is ever written to it:

- A study Ramure creates carries ``PRAGMA application_id`` :data:`APPLICATION_ID`
  ("RAMU") and ``user_version`` :data:`SCHEMA_VERSION`.  A file made before the
  application id holds 0 there; it is recognised by its schema alone.
- Every file is first opened read-only (:func:`open_readonly`: SQLite's
  ``mode=ro``, and ``immutable=1`` when no ``-wal`` file exists, so that SQLite
  creates no ``-wal``/``-shm`` beside a file it only reads) and checked
  (:func:`check_study_file`): a whole SQLite file (``quick_check``), an
  application id of 0 or ours, a version this Ramure reads, every table of that
  version with exactly the columns of ``schema.sql`` (name, type, NOT NULL,
  key), one row in ``study``, then every stored value (:data:`VALUE_RULES`,
  the foreign keys, 27 picks per grammar).  Anything else is refused with
  one line naming the table, row and column, and the file is left byte for byte.
- Only then may :meth:`Study.open` reopen it for writing, switch it to WAL and
  migrate it (stamping the application id).  ``Study.open(path, readonly=True)``,
  used by every read command (``status``, ``analyze``, ``export-csv``, the
  analyst window), never writes: no WAL switch, no migration (a version-1 file
  is read as version 1, with no events).

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
>>> with Study.open(db, readonly=True) as study:
...     study.participants()[0]["code"]
'P101'
"""

from __future__ import annotations

import json
import math
import os
import pathlib
import re
import sqlite3
import time
import zlib
from importlib import resources

from ramure.io import APPLICATION_ID as RAMURE_ID, open_sqlite_readonly
from ramure.studies.errors import StudyInputError
from ramure.studies.pgsql import PgConnection, is_database_url, pg_schema, shown_url, sqlite_path
from ramure.studies.records import log_event, now_iso
from ramure.studies.picks import Pick, check_distinct, inside_folder, load_picks, picks_from_data
from collections.abc import Callable
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    from ramure.studies.design import StudyConfig
    from ramure.studies.session import TestSession

SCHEMA_VERSION = 3
#: The schema version each table appeared in (the others are in version 1).
TABLE_SINCE = {"events": 2, "settings": 3, "enrolments": 3, "page_answers": 3}
#: Columns added to an older table, and the version they appeared in (``ALTER TABLE`` migrates them).
COLUMN_SINCE = {("events", "front_end"): 3}
DEFAULT_BUDGET_MINUTES = 30.0
_CODE = re.compile(r"^[A-Za-z0-9_-]{1,32}$")


def connect(path: str | os.PathLike, durable: bool = True) -> sqlite3.Connection:
    """Open ``path`` with foreign keys on, WAL journal and a busy timeout.

    ``durable=False`` sets ``synchronous=NORMAL``: a committed answer still
    survives a killed process, but not a power cut; simulations use it for speed.
    A PostgreSQL URL opens a :class:`~ramure.studies.pgsql.PgConnection` (used as this
    function's ``sqlite3.Connection``), ``durable=False`` then turning ``synchronous_commit`` off.
    """
    if is_database_url(path):
        return PgConnection(str(path), durable=durable)  # type: ignore[return-value]
    conn = sqlite3.connect(os.fspath(sqlite_path(path)), timeout=10.0)
    conn.execute("PRAGMA foreign_keys = ON")
    conn.execute("PRAGMA journal_mode = WAL")
    conn.execute(f"PRAGMA synchronous = {'FULL' if durable else 'NORMAL'}")
    return conn


def schema_sql() -> str:
    """The text of ``studies/schema.sql``."""
    return resources.files(__package__).joinpath("schema.sql").read_text(encoding="utf-8")


#: SQLite ``PRAGMA application_id`` of a Ramure study (:data:`ramure.io.APPLICATION_ID`, "RAMU");
#: files made before it hold 0.
APPLICATION_ID = RAMURE_ID


def _schema_tables(version: int = SCHEMA_VERSION) -> set:
    names = set(re.findall(r"CREATE TABLE IF NOT EXISTS (\w+)", schema_sql()))
    return {name for name in names if TABLE_SINCE.get(name, 1) <= version}


def _columns(conn: sqlite3.Connection, table: str) -> list[tuple]:
    """(name, declared type, NOT NULL, key position) of each column of ``table``."""
    return [(r[1], r[2].upper(), r[3], r[5]) for r in conn.execute(f"PRAGMA table_info({table})")]


_SIGNATURE: dict[str, list[tuple]] = {}


def _signature(version: int = SCHEMA_VERSION) -> dict[str, list[tuple]]:
    """The columns of every table of ``schema.sql`` in ``version`` (read from an in-memory database, cached)."""
    if not _SIGNATURE:
        mem = sqlite3.connect(":memory:")
        mem.executescript(schema_sql())
        _SIGNATURE.update({name: _columns(mem, name) for name in _schema_tables()})
        mem.close()
    return {
        table: [c for c in columns if COLUMN_SINCE.get((table, c[0]), 1) <= version]
        for table, columns in _SIGNATURE.items()
        if TABLE_SINCE.get(table, 1) <= version
    }


def _added_columns(version: int) -> str:
    """``ALTER TABLE`` statements adding the columns newer than ``version`` (as ``schema.sql`` declares them)."""
    declared = {(t, c[0]): c for t, cols in _signature().items() for c in cols}
    return " ".join(
        f"ALTER TABLE {table} ADD COLUMN {column} {declared[(table, column)][1]};"
        for (table, column), since in COLUMN_SINCE.items()
        if TABLE_SINCE.get(table, 1) <= version < since  # a newer table is created whole by schema.sql
    )


def migrate(conn: sqlite3.Connection) -> None:
    """Bring an open study database to :data:`SCHEMA_VERSION`, in one transaction.

    Version 1 lacks the ``events`` table, version 2 the ``settings``, ``enrolments`` and
    ``page_answers`` tables and ``events.front_end``; ``schema.sql`` creates only what is
    missing and ``ALTER TABLE`` adds the columns, so answers already stored are untouched.
    A study made before the application id gets it.  Call it only on a file
    :func:`check_study_file` accepted: it writes.
    Two processes migrating at once are serialised by ``BEGIN IMMEDIATE``.
    """
    version, app_id = (conn.execute(f"PRAGMA {name}").fetchone()[0] for name in ("user_version", "application_id"))
    if version == SCHEMA_VERSION and app_id == APPLICATION_ID:
        return
    try:
        conn.executescript(
            f"BEGIN IMMEDIATE; {schema_sql()} {_added_columns(version)} PRAGMA user_version = {SCHEMA_VERSION}; "
            f"PRAGMA application_id = {APPLICATION_ID}; COMMIT;"
        )
    except sqlite3.Error as exc:
        if conn.in_transaction:
            conn.rollback()
        if "duplicate column" in str(exc) and conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION:
            return  # another process migrated it between our look and our lock
        raise


def open_readonly(path: str | os.PathLike) -> sqlite3.Connection:
    """A read-only connection to study ``path`` that writes nothing (:func:`ramure.io.open_sqlite_readonly`)."""
    return open_sqlite_readonly(path)


def check_study_file(path: str | os.PathLike) -> int:
    """Refuse, with one line, a file that is not a Ramure study database; return its version.

    Read-only (:func:`open_readonly`): another application's database, a
    truncated file or an empty one is never changed and gets no ``-wal``/``-shm``.
    The file is never opened with a plain descriptor: on POSIX,
    closing one drops every lock this process holds on the file, those of its
    open study connections too, and another process would then checkpoint and
    delete the WAL they still write into.  Checked: a whole SQLite file,
    ``application_id`` (:data:`APPLICATION_ID`, or 0 for files made before it),
    ``user_version`` 1 to :data:`SCHEMA_VERSION` (older ones are migrated by
    :meth:`Study.open`), every table of that version with the columns of
    ``schema.sql``, one ``study`` row, and every stored value (:func:`check_values`).
    """
    path = pathlib.Path(path)
    if path.exists() and not path.is_file():  # a folder, a pipe (opening it would block), a device
        raise StudyInputError(f"{path}: not a regular file, so not a Ramure study database")
    if not path.is_file():
        raise StudyInputError(f"{path}: no such study file")
    if path.stat().st_size == 0:
        raise StudyInputError(f"{path}: empty file, not a Ramure study database")
    try:
        conn = open_readonly(path)
    except sqlite3.Error as exc:
        raise StudyInputError(f"{path}: cannot open it read-only ({exc})") from None
    conn.text_factory = strict_text(path)
    try:
        version = _recognise(conn, path)
        check_values(conn, path, version)
    except sqlite3.DatabaseError as exc:
        if getattr(exc, "sqlite_errorcode", None) == sqlite3.SQLITE_NOTADB:
            raise StudyInputError(f"{path}: not a SQLite file, so not a Ramure study database") from None
        raise StudyInputError(f"{path}: not a readable SQLite database ({exc})") from None
    except UnicodeDecodeError:  # SQLite's own message quotes a damaged schema's bytes
        raise StudyInputError(f"{path}: a damaged SQLite database (its schema is not UTF-8); not read") from None
    finally:
        conn.close()
    return version


def strict_text(path: str | os.PathLike) -> Callable[[bytes], str]:
    """A ``text_factory`` for study connections: SQLite stores any bytes as text, so a text that
    is not UTF-8 (a damaged file) is refused with one line instead of an ``OperationalError``."""

    def decode(data: bytes) -> str:
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as exc:
            near = data[max(0, exc.start - 12) : exc.start + 4]
            message = f"a text stored in the study is not UTF-8 (near {near!r}); the file is damaged"
            raise StudyInputError(f"{path}: {message}") from None

    return decode


def _recognise(conn: sqlite3.Connection, path: pathlib.Path) -> int:
    app_id = conn.execute("PRAGMA application_id").fetchone()[0]
    version = conn.execute("PRAGMA user_version").fetchone()[0]
    tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    if app_id not in (0, APPLICATION_ID):
        raise StudyInputError(f"{path}: belongs to another application (application_id {app_id:#x}), not a Ramure study")
    missing = _schema_tables(version if 1 <= version <= SCHEMA_VERSION else 1) - tables
    if missing:
        raise StudyInputError(f"{path}: not a Ramure study database (no table {', '.join(sorted(missing))})")
    if not 1 <= version <= SCHEMA_VERSION:
        raise StudyInputError(f"{path}: study database version {version}; this Ramure reads versions 1 to {SCHEMA_VERSION}")
    for table in sorted(_schema_tables(version)):
        if _columns(conn, table) != _signature(version)[table]:
            raise StudyInputError(f"{path}: not a Ramure study database (table {table} has other columns)")
    problems = [r[0] for r in conn.execute("PRAGMA quick_check(5)")]
    if problems != ["ok"]:
        raise StudyInputError(f"{path}: damaged database ({problems[0]}); not read")
    if conn.execute("SELECT count(*), sum(id = 1) FROM study").fetchone() != (1, 1):
        raise StudyInputError(f"{path}: table study must hold exactly one row, with id 1")
    return version


def _number(column: str, low: str = "-1e300", high: str = "1e300") -> str:
    return f"typeof({column}) IN ('integer', 'real') AND {column} BETWEEN {low} AND {high}"


def _integer(column: str, low: int, high: int) -> str:
    return f"typeof({column}) = 'integer' AND {column} BETWEEN {low} AND {high}"


def _text(column: str) -> str:
    return f"typeof({column}) = 'text' AND length(trim({column})) > 0"


def _optional(column: str, rule: str) -> str:
    return f"{column} IS NULL OR ({rule})"


_LIKERT = "an integer from 1 to 4, or empty"
_TIME = "non-empty text (a UTC time)"
_ROW_ID = 2**53

#: What every stored value must be, checked at each open: (table, column, SQL condition, wording).
#: SQLite keeps any type in any column and a CHECK can be bypassed, so the schema alone proves nothing.
VALUE_RULES: tuple[tuple[str, str, str, str], ...] = (
    ("study", "name", _text("name"), "non-empty text"),
    ("study", "budget_seconds", _number("budget_seconds", "1e-3", "1e9"), "a number of seconds from 0.001 to 1e9"),
    ("study", "created_at", _text("created_at"), _TIME),
    ("grammars", "id", _integer("id", 1, _ROW_ID), "a positive integer"),
    ("grammars", "name", _text("name"), "non-empty text"),
    ("grammars", "source", _optional("source", "typeof(source) = 'text'"), "text (a folder), or empty"),
    ("picks", "grammar_id", "typeof(grammar_id) = 'integer'", "an integer"),
    ("picks", "pick_id", _integer("pick_id", 1, 27), "an integer from 1 to 27"),
    ("picks", "variant_id", _integer("variant_id", 0, _ROW_ID), "a non-negative integer"),
    *((("picks", pc, _number(pc), "a finite number")) for pc in ("pc1", "pc2", "pc3")),
    ("picks", "params", "typeof(params) = 'text'", "JSON text"),
    ("picks", "image", _optional("image", "typeof(image) = 'text'"), "text (a path), or empty"),
    ("participants", "id", _integer("id", 1, _ROW_ID), "a positive integer"),
    ("participants", "code", "typeof(code) = 'text' AND length(code) BETWEEN 1 AND 32", "text of 1 to 32 characters"),
    ("participants", "seed", _integer("seed", -(2**63), 2**63 - 1), "an integer"),
    ("participants", "consent", _integer("consent", 0, 1), "0 or 1"),
    ("participants", "created_at", _text("created_at"), _TIME),
    ("tests", "id", _integer("id", 1, _ROW_ID), "a positive integer"),
    ("tests", "participant_id", "typeof(participant_id) = 'integer'", "an integer"),
    ("tests", "grammar_id", "typeof(grammar_id) = 'integer'", "an integer"),
    ("tests", "started_at", _text("started_at"), _TIME),
    ("tests", "finished_at", _optional("finished_at", _text("finished_at")), "a UTC time, or empty"),
    ("tests", "elapsed_seconds", _number("elapsed_seconds", "0", "1e9"), "a number of seconds from 0 to 1e9"),
    ("groups", "id", _integer("id", 1, _ROW_ID), "a positive integer"),
    ("groups", "test_id", "typeof(test_id) = 'integer'", "an integer"),
    ("groups", "label", _integer("label", 1, 27), "an integer from 1 to 27"),
    ("groups", "representative", _optional("representative", _integer("representative", 1, 27)), "a pick from 1 to 27, or empty"),
    *(("groups", name, _optional(name, _integer(name, 1, 4)), _LIKERT) for name in ("usefulness", "difference")),
    ("groups", "representative_quality", _optional("representative_quality", _integer("representative_quality", 1, 4)), _LIKERT),
    ("group_images", "group_id", "typeof(group_id) = 'integer'", "an integer"),
    ("group_images", "pick_id", _integer("pick_id", 1, 27), "an integer from 1 to 27"),
    (
        "group_images",
        "test_id",
        "test_id IS (SELECT g.test_id FROM groups g WHERE g.id = group_images.group_id)",
        "the test of its group",
    ),
    ("qualifiers", "group_id", "typeof(group_id) = 'integer'", "an integer"),
    ("qualifiers", "text", _text("text"), "non-empty text"),
    ("events", "participant_id", "typeof(participant_id) = 'integer'", "an integer"),
    ("events", "test_id", _optional("test_id", "typeof(test_id) = 'integer'"), "an integer, or empty"),
    ("events", "at", _text("at"), _TIME),
    ("events", "elapsed_seconds", _optional("elapsed_seconds", _number("elapsed_seconds", "0", "1e9")), "seconds, or empty"),
    ("events", "action", _text("action"), "non-empty text"),
    ("events", "detail", "typeof(detail) = 'text'", "JSON text"),
    ("events", "front_end", _optional("front_end", _text("front_end")), "text (a front end), or empty"),
    ("settings", "key", _text("key"), "non-empty text"),
    ("settings", "value", "typeof(value) = 'text' AND json_valid(value)", "JSON text"),
    ("enrolments", "participant_id", "typeof(participant_id) = 'integer'", "an integer"),
    (
        "enrolments",
        "external_id",
        _optional("external_id", "typeof(external_id) = 'text' AND length(external_id) BETWEEN 1 AND 64"),
        "text of 1 to 64 characters, or empty",
    ),
    ("enrolments", "pilot", _integer("pilot", 0, 1), "0 or 1"),
    (
        "enrolments",
        "grammar_order",
        "typeof(grammar_order) = 'text' AND json_valid(grammar_order) AND json_type(grammar_order) = 'array'",
        "a JSON list of grammar names",
    ),
    ("enrolments", "completion_code", _optional("completion_code", _text("completion_code")), "text, or empty"),
    ("enrolments", "withdrawn_at", _optional("withdrawn_at", _text("withdrawn_at")), "a UTC time, or empty"),
    ("page_answers", "participant_id", "typeof(participant_id) = 'integer'", "an integer"),
    ("page_answers", "page", _text("page"), "non-empty text"),
    (
        "page_answers",
        "answers",
        "typeof(answers) = 'text' AND json_valid(answers) AND json_type(answers) = 'object'",
        "a JSON object",
    ),
    ("page_answers", "at", _text("at"), _TIME),
)


def _refuse_value(path, table, row, column, wording, value) -> StudyInputError:
    shown = value if len(str(value)) <= 40 else f"{str(value)[:37]}..."
    return StudyInputError(f"{path}: table {table}, row {row}: {column} must be {wording}, not {shown}")


def check_values(conn: sqlite3.Connection, path: str | os.PathLike, version: int = SCHEMA_VERSION) -> None:
    """Refuse a study whose stored values are not what Ramure writes, naming table, row and column.

    Checks :data:`VALUE_RULES`, the foreign keys, the 27 picks of each grammar and
    each pick's ``params`` (a JSON object with a ``rule``), in a few queries.
    """
    tables = _schema_tables(version)
    for table, column, rule, wording in VALUE_RULES:
        if table not in tables or COLUMN_SINCE.get((table, column), 1) > version:
            continue
        bad = conn.execute(f"SELECT rowid, quote({column}) FROM {table} WHERE ({rule}) IS NOT 1 LIMIT 1").fetchone()
        if bad is not None:
            raise _refuse_value(path, table, bad[0], column, wording, bad[1])
    for table, row, parent, key in conn.execute("PRAGMA foreign_key_check"):
        if table in tables:
            column = next(r[3] for r in conn.execute(f"PRAGMA foreign_key_list({table})") if r[0] == key)
            raise StudyInputError(f"{path}: table {table}, row {row}: {column} names no row of table {parent}")
    check_picks(conn, path)


def check_picks(conn: sqlite3.Connection, path: str | os.PathLike, row_id: str = "rowid") -> None:
    """Refuse a study whose grammar lacks one of the 27 picks, or whose pick ``params`` is not a
    JSON object with a ``rule`` (SQLite and PostgreSQL alike; ``row_id`` is the SQL naming a row
    in the message: SQLite's ``rowid``, which PostgreSQL lacks)."""
    short = conn.execute(
        "SELECT g.name, count(p.pick_id) FROM grammars g LEFT JOIN picks p ON p.grammar_id = g.id "
        "GROUP BY g.id, g.name HAVING count(DISTINCT p.pick_id) != 27 LIMIT 1"
    ).fetchone()
    if short is not None:
        raise StudyInputError(f"{path}: table picks: grammar {short[0]!r} has {short[1]} picks, not the 27 ids 1-27")
    for row, params in conn.execute(f"SELECT {row_id}, params FROM picks"):
        try:
            decoded = json.loads(params)
        except ValueError:
            decoded = None
        if not isinstance(decoded, dict) or "rule" not in decoded or not isinstance(decoded.get("constants", {}), dict):
            raise _refuse_value(path, "picks", row, "params", "a JSON object with a 'rule'", repr(params))


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


#: The ``settings`` key holding a PostgreSQL study's schema version (SQLite's ``user_version``).
PG_VERSION_KEY = "ramure_schema_version"


def _fill(conn, name: str, budget: float, loaded: dict, folder: pathlib.Path, config: StudyConfig) -> None:
    """The rows of a new study: its name and budget, grammars with picks, and config (in the caller's transaction)."""
    conn.execute("INSERT INTO study (id, name, budget_seconds, created_at) VALUES (1, ?, ?, ?)", (name, 60.0 * budget, now_iso()))
    for gname, (source, picks) in loaded.items():
        _insert_grammar(conn, gname, source, picks, folder)
    conn.execute("INSERT INTO settings (key, value) VALUES ('config', ?)", (json.dumps(config.to_data()),))


def _connect_postgres(url: str, where: str, readonly: bool = False, durable: bool = True) -> PgConnection:
    try:
        return PgConnection(url, readonly=readonly, durable=durable)
    except sqlite3.Error as exc:
        raise StudyInputError(f"{where}: cannot connect to the study's database ({exc})") from None


def _pg_tables(conn: PgConnection) -> set[str]:
    rows = conn.execute("SELECT table_name FROM information_schema.tables WHERE table_schema = current_schema()")
    return {r[0] for r in rows}


def check_postgres_study(conn: PgConnection, where: str) -> int:
    """Refuse, with one line, a PostgreSQL database that does not hold a Ramure study; return its version.

    Checked: every table of ``schema.sql`` with its columns in order, the schema version stored
    in ``settings`` (:data:`PG_VERSION_KEY`; PostgreSQL studies start at version 3), one
    ``study`` row with id 1, and the 27 picks of each grammar (:func:`check_picks`).  The
    column types, ``CHECK`` constraints and foreign keys are PostgreSQL's to enforce: unlike
    SQLite it never stores a value of another type, so the per-value rules are not re-read.
    """
    tables = _pg_tables(conn)
    if "study" not in tables:
        raise StudyInputError(f"{where}: holds no Ramure study (no table study); create one with `ramure study create`")
    missing = _schema_tables() - tables
    if missing:
        raise StudyInputError(f"{where}: not a Ramure study database (no table {', '.join(sorted(missing))})")
    for table, columns in _signature().items():
        names = [
            r[0]
            for r in conn.execute(
                "SELECT column_name FROM information_schema.columns WHERE table_schema = current_schema() "
                "AND table_name = ? ORDER BY ordinal_position",
                (table,),
            )
        ]
        if names != [c[0] for c in columns]:
            raise StudyInputError(f"{where}: not a Ramure study database (table {table} has other columns)")
    row = conn.execute("SELECT value FROM settings WHERE key = ?", (PG_VERSION_KEY,)).fetchone()
    version = json.loads(row[0]) if row else None
    if version != SCHEMA_VERSION:
        raise StudyInputError(
            f"{where}: study database version {version}; this Ramure reads version {SCHEMA_VERSION} on PostgreSQL"
        )
    if conn.execute("SELECT count(*), min(id) FROM study").fetchone() != (1, 1):
        raise StudyInputError(f"{where}: table study must hold exactly one row, with id 1")
    check_picks(cast(sqlite3.Connection, conn), where, row_id="grammar_id * 100 + pick_id")
    return SCHEMA_VERSION


class Study:
    """A study database: grammars x 27 picks, participants, one test per grammar each.

    Use :meth:`create` for a new file and :meth:`open` for an existing one.
    ``clock`` (seconds, monotonic) times the participants' budget; tests pass a fake.

    The location is a SQLite file (a path, or ``sqlite:///path``) or a PostgreSQL database
    (``postgresql://user:password@host/dbname``, the ``postgres`` extra; see
    :mod:`ramure.studies.pgsql`).  A study's pictures live in its *folder*: the SQLite file's
    folder, or for PostgreSQL the ``folder`` given at creation (default: the current directory),
    stored in the study and overridable at :meth:`open` (a server on another machine).
    ``path`` is then ``FOLDER/DBNAME.postgresql``, a name no file has: it places the study's
    web secret beside its pictures.  ``where`` names the study in messages (the URL's
    password masked).
    """

    def __init__(
        self,
        conn: sqlite3.Connection,
        path: str | os.PathLike,
        clock: Callable[[], float] = time.monotonic,
        readonly: bool = False,
        version: int = SCHEMA_VERSION,
        where: str | None = None,
    ) -> None:
        self.conn = conn
        self.path = pathlib.Path(path)
        self.where = where or str(self.path)
        self.postgres = isinstance(conn, PgConnection)
        self.clock = clock
        conn.text_factory = strict_text(self.path)
        self.readonly = readonly  # opened by a read command: every change is refused
        self.version = version  # a version-1 file read read-only stays version 1 (no events)
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
        config: StudyConfig | None = None,
        folder: str | os.PathLike | None = None,
    ) -> Study:
        """Create a study in a new file ``path``.

        ``grammars`` maps a grammar name to an exploration directory (holding
        ``picks.json``) or to plain data: a list of 27 pick dicts or
        :class:`~ramure.studies.picks.Pick`.  ``budget_minutes`` is each participant's
        time budget over all their tests.  ``config`` holds what participants read
        (:class:`~ramure.studies.design.StudyConfig`, default texts when None).
        ``path`` may be a PostgreSQL URL: the database must exist and hold no study tables;
        ``folder`` is then the study's folder (pictures; default: the current directory).
        """
        from ramure.studies.design import StudyConfig

        config = config if config is not None else StudyConfig()
        if config.practice_set is not None and config.practice_set not in (grammars or {}):
            known = ", ".join(grammars or {}) or "none"
            raise StudyInputError(f"the practice set {config.practice_set!r} is not a grammar of the study (grammars: {known})")
        try:
            budget = float(budget_minutes)
        except (TypeError, ValueError):
            budget = math.nan
        if not budget > 0:
            raise StudyInputError(f"budget must be a positive number of minutes, got {budget_minutes!r}")
        # Read every grammar before touching the disk, so a bad one leaves no file.
        loaded = {gname: _read_grammar(gname, spec) for gname, spec in (grammars or {}).items()}
        if is_database_url(path):
            return cls._create_postgres(str(path), loaded, name, budget, clock, durable, config, folder)
        path = pathlib.Path(sqlite_path(path))
        if path.exists() and path.stat().st_size > 0:
            try:
                check_study_file(path)
            except StudyInputError as exc:
                kind = "is not a SQLite file" if "not a SQLite file" in str(exc) else "is not a study"
                raise StudyInputError(f"{path}: exists and {kind}; choose a new file") from None
            raise StudyInputError(f"{path}: already holds a study; open it instead")
        path.parent.mkdir(parents=True, exist_ok=True)
        conn = connect(path, durable)
        conn.executescript(schema_sql())
        with conn:
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            _fill(conn, name or path.stem, budget, loaded, path.parent, config)
        return cls(conn, path, clock)

    @classmethod
    def _create_postgres(cls, url, loaded, name, budget, clock, durable, config, folder) -> Study:
        """:meth:`create` in the PostgreSQL database ``url``: schema and rows in one transaction."""
        where = shown_url(url)
        conn = _connect_postgres(url, where, durable=durable)
        folder = pathlib.Path(folder if folder is not None else os.getcwd()).resolve()
        try:
            with conn:
                tables = _pg_tables(conn)
                if "study" in tables:
                    raise StudyInputError(f"{where}: already holds a study; open it instead")
                if tables & _schema_tables():
                    taken = ", ".join(sorted(tables & _schema_tables()))
                    raise StudyInputError(f"{where}: already has tables named {taken}; choose an empty database")
                for statement in pg_schema(schema_sql()):
                    conn.execute(statement)
                conn.execute("INSERT INTO settings (key, value) VALUES (?, ?)", (PG_VERSION_KEY, json.dumps(SCHEMA_VERSION)))
                conn.execute("INSERT INTO settings (key, value) VALUES ('folder', ?)", (json.dumps(str(folder)),))
                _fill(conn, name or conn.dbname, budget, loaded, folder, config)
        except sqlite3.Error as exc:
            conn.close()
            raise StudyInputError(f"{where}: cannot create the study ({exc})") from None
        except BaseException:
            conn.close()
            raise
        return cls(cast(sqlite3.Connection, conn), folder / f"{conn.dbname}.postgresql", clock, where=where)

    @classmethod
    def open(
        cls,
        path: str | os.PathLike,
        clock: Callable[[], float] = time.monotonic,
        durable: bool = True,
        readonly: bool = False,
        folder: str | os.PathLike | None = None,
    ) -> Study:
        """Open an existing study file (refused with a clear message otherwise).

        The file is checked read-only first (:func:`check_study_file`): a file that
        is not a Ramure study is refused unchanged.  ``readonly=True`` (read
        commands) keeps that read-only connection: nothing is ever written.
        Otherwise the file is reopened for writing, in WAL mode, and a file of an
        older schema version is migrated in place (see :func:`migrate`).
        A PostgreSQL URL is checked by :func:`check_postgres_study` (``readonly`` then makes
        the server refuse any write); ``folder`` overrides the study folder stored at creation.
        """
        if is_database_url(path):
            return cls._open_postgres(str(path), clock, durable, readonly, folder)
        path = pathlib.Path(sqlite_path(path))
        version = check_study_file(path)  # read-only: a file that is not ours is never changed
        try:
            if readonly:
                return cls(open_readonly(path), path, clock, readonly=True, version=version)
            conn = connect(path, durable)
        except sqlite3.Error as exc:
            raise StudyInputError(f"{path}: cannot open the study ({exc})") from None
        try:
            migrate(conn)
            return cls(conn, path, clock)
        except sqlite3.Error as exc:
            conn.close()
            raise StudyInputError(f"{path}: cannot open the study for writing ({exc})") from None

    @classmethod
    def _open_postgres(cls, url, clock, durable, readonly, folder) -> Study:
        where = shown_url(url)
        conn = _connect_postgres(url, where, readonly=readonly, durable=durable)
        try:
            version = check_postgres_study(conn, where)
            stored = conn.execute("SELECT value FROM settings WHERE key = 'folder'").fetchone()
        except BaseException:
            conn.close()
            raise
        if folder is None:
            folder = json.loads(stored[0]) if stored else os.getcwd()
        path = pathlib.Path(folder).resolve() / f"{conn.dbname}.postgresql"
        return cls(cast(sqlite3.Connection, conn), path, clock, readonly=readonly, version=version, where=where)

    def _writable(self) -> None:
        if self.readonly:
            raise StudyInputError(f"{self.where}: opened read-only; open it again for writing to change it")

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
        self._writable()
        source, picks = _read_grammar(name, spec)
        with self.conn:
            _insert_grammar(self.conn, name, source, picks, self.path.parent)

    def grammar_id(self, name: str) -> int:
        row = self.conn.execute("SELECT id FROM grammars WHERE name = ?", (name,)).fetchone()
        if row is None:
            known = ", ".join(self.grammars) or "none"
            raise StudyInputError(f"no grammar {name!r} in this study (known: {known})")
        return row[0]

    def grammar_source(self, name: str) -> str | None:
        """Where grammar ``name``'s picks came from (an exploration directory), or None."""
        row = self.conn.execute("SELECT source FROM grammars WHERE id = ?", (self.grammar_id(name),)).fetchone()
        if not row or not row[0]:
            return None
        return str((self.path.parent / row[0]).resolve())  # stored relative to the study's folder

    def picks(self, grammar: str) -> list[Pick]:
        """The 27 picks of ``grammar``, by id."""
        rows = self.conn.execute(
            "SELECT pick_id, variant_id, pc1, pc2, pc3, params, image FROM picks WHERE grammar_id = ? ORDER BY pick_id",
            (self.grammar_id(grammar),),
        )
        return [Pick(r[0], r[1], (r[2], r[3], r[4]), json.loads(r[5]), self._picture(r[6])) for r in rows]

    def set_pictures(self, grammar: str, images: dict[int, str | os.PathLike]) -> None:
        """Store the picture of each pick of ``grammar`` (``{pick id: file}``), relative to the study's
        folder; each file must lie inside it (one transaction)."""
        self._writable()
        gid = self.grammar_id(grammar)
        rows = []
        for pid, image in sorted(images.items()):
            inside_folder(self.path.parent, image, f"picture of pick {pid}")  # refused if outside
            rows.append((relative_to(self.path.parent, image), gid, int(pid)))
        with self.conn:
            self.conn.executemany("UPDATE picks SET image = ? WHERE grammar_id = ? AND pick_id = ?", rows)

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

    # -- settings --------------------------------------------------------------
    def setting(self, key: str) -> object:
        """The stored setting ``key`` (decoded JSON), or None (and None for a study before version 3)."""
        if self.version < TABLE_SINCE["settings"]:
            return None
        row = self.conn.execute("SELECT value FROM settings WHERE key = ?", (key,)).fetchone()
        return json.loads(row[0]) if row else None

    def set_setting(self, key: str, value: object) -> None:
        """Store setting ``key`` as JSON (replacing any earlier value)."""
        self._writable()
        with self.conn:
            self.conn.execute(
                "INSERT INTO settings (key, value) VALUES (?, ?) ON CONFLICT (key) DO UPDATE SET value = excluded.value",
                (key, json.dumps(value, sort_keys=True)),
            )

    def config(self) -> StudyConfig:
        """What participants read (:class:`~ramure.studies.design.StudyConfig`); the defaults for a
        study stored without one."""
        from ramure.studies.design import StudyConfig, config_from_data

        data = self.setting("config")
        return StudyConfig() if data is None else config_from_data(data, where=f"{self.where}: settings config")

    # -- participants --------------------------------------------------------
    def add_participant(
        self,
        code: str | None = None,
        consent: bool = False,
        seed: int | None = None,
        external_id: str | None = None,
        pilot: bool = False,
    ) -> str:
        """Register a participant under an anonymous ``code`` (default P101, P102...).

        ``seed`` fixes the image order of their tests (default: from the code).
        ``external_id`` is a recruiting platform's id (a Prolific PID); ``pilot`` marks a
        trial run, left out of the analysis.  The participant's order of the grammars is
        the next row of a balanced Latin square (pilots and real participants count apart),
        and a completion code is drawn; both are stored.
        """
        self._writable()
        external_id = _external_id(external_id)
        if code is not None and not _CODE.match(str(code)):
            raise StudyInputError(
                f"participant code {str(code)!r} must be 1-32 letters, digits, '-' or '_' (an anonymous code, not a name)"
            )
        stamp = now_iso()
        try:
            with self.conn:  # on PostgreSQL writers take turns here, so two stations never draw one code
                code = self._next_code() if code is None else str(code)
                seed = zlib.crc32(code.encode()) if seed is None else seed
                pid = self.conn.execute(
                    "INSERT INTO participants (code, seed, consent, consent_at, created_at) VALUES (?, ?, ?, ?, ?)",
                    (code, int(seed), int(bool(consent)), stamp if consent else None, stamp),
                ).lastrowid
                if consent and pid is not None:  # pid: set by the INSERT just made
                    log_event(self.conn, pid, "consent", {"given": True})
                self._enrol(pid, external_id, bool(pilot))
        except sqlite3.IntegrityError as exc:
            if external_id is not None and "external_id" in str(exc):
                raise StudyInputError(f"external id {external_id!r} is already enrolled in this study") from None
            raise StudyInputError(f"participant code {code!r} is already used") from None
        return code

    def _next_code(self) -> str:
        """The first free code P101, P102, ..."""
        taken = {r[0] for r in self.conn.execute("SELECT code FROM participants")}
        number = 101
        while f"P{number}" in taken:
            number += 1
        return f"P{number}"

    def _enrol(self, pid: int | None, external_id: str | None, pilot: bool) -> None:
        import secrets

        from ramure.studies.design import grammar_order

        index = self.conn.execute("SELECT count(*) FROM enrolments WHERE pilot = ?", (int(pilot),)).fetchone()[0]
        order = grammar_order(self.sets(), index)
        fixed = self.config().completion_code
        code = fixed or "".join(secrets.choice("ABCDEFGHJKLMNPQRSTUVWXYZ23456789") for _ in range(8))
        self.conn.execute(
            "INSERT INTO enrolments (participant_id, external_id, pilot, grammar_order, completion_code) VALUES (?, ?, ?, ?, ?)",
            (pid, external_id, int(pilot), json.dumps(order), code),
        )

    def _enrolment(self, code: str) -> tuple | None:
        """(external_id, pilot, grammar order, completion code, withdrawn_at) of ``code``, or None."""
        pid = self._participant(code)[0]
        if self.version < TABLE_SINCE["enrolments"]:
            return None
        return self.conn.execute(
            "SELECT external_id, pilot, grammar_order, completion_code, withdrawn_at FROM enrolments WHERE participant_id = ?",
            (pid,),
        ).fetchone()

    def grammar_order(self, code: str) -> list[str]:
        """Participant ``code``'s order of the grammars (their Latin-square row; the study's order for
        a participant enrolled before version 3).  Grammars added after they enrolled come last."""
        row = self._enrolment(code)
        sets = self.sets()
        order = [g for g in json.loads(row[2]) if g in sets] if row else []
        return order + [g for g in sets if g not in order]

    def sets(self) -> list[str]:
        """The grammars participants sort for real: all but the config's practice set."""
        practice = self.config().practice_set
        return [g for g in self.grammars if g != practice]

    def completion_code(self, code: str) -> str | None:
        """The code participant ``code`` gives their recruiting platform at the end (None before version 3)."""
        row = self._enrolment(code)
        return row[3] if row else None

    def is_pilot(self, code: str) -> bool:
        row = self._enrolment(code)
        return bool(row and row[1])

    def find_participant(self, name: str) -> str:
        """The code of the participant whose code, or external id, is ``name``."""
        row = self.conn.execute("SELECT code FROM participants WHERE code = ?", (str(name),)).fetchone()
        if row is None and self.version >= TABLE_SINCE["enrolments"]:
            row = self.conn.execute(
                "SELECT p.code FROM participants p JOIN enrolments e ON e.participant_id = p.id WHERE e.external_id = ?",
                (str(name),),
            ).fetchone()
        if row is None:
            raise StudyInputError(f"no participant {name!r} in this study (neither a code nor an external id)")
        return row[0]

    def has_consent(self, code: str) -> bool:
        return bool(self._participant(code)[2])

    def withdraw(self, code: str, delete: bool = False) -> None:
        """Participant ``code`` withdraws: their consent is withdrawn and the time recorded, so their
        answers are left out of every analysis and export; ``delete=True`` erases them too."""
        self._writable()
        if delete:
            self.delete_participant(code)
            return
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute("UPDATE participants SET consent = 0, consent_at = ? WHERE id = ?", (now_iso(), pid))
            self.conn.execute("UPDATE enrolments SET withdrawn_at = ? WHERE participant_id = ?", (now_iso(), pid))
            log_event(self.conn, pid, "withdraw", {})

    def record_answers(self, code: str, page: str, answers: dict) -> None:
        """Store participant ``code``'s ``answers`` (a JSON object) on ``page`` (instructions,
        practice, attention, demographics), with the time, replacing earlier ones."""
        self._writable()
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute(
                "INSERT INTO page_answers (participant_id, page, answers, at) VALUES (?, ?, ?, ?) "
                "ON CONFLICT (participant_id, page) DO UPDATE SET answers = excluded.answers, at = excluded.at",
                (pid, page, json.dumps(answers, sort_keys=True), now_iso()),
            )
            log_event(self.conn, pid, "page", {"page": page, "answers": answers})

    def participant_answers(self, code: str) -> dict[str, dict]:
        """Participant ``code``'s answers by page (see :meth:`record_answers`)."""
        pid = self._participant(code)[0]
        if self.version < TABLE_SINCE["page_answers"]:
            return {}
        rows = self.conn.execute("SELECT page, answers FROM page_answers WHERE participant_id = ?", (pid,))
        return {page: json.loads(text) for page, text in rows}

    def started(self, code: str, grammar: str) -> bool:
        """Whether participant ``code`` has started (or finished) their test on ``grammar``."""
        row = self.conn.execute(
            "SELECT 1 FROM tests t JOIN participants p ON p.id = t.participant_id "
            "JOIN grammars g ON g.id = t.grammar_id WHERE p.code = ? AND g.name = ?",
            (str(code), grammar),
        ).fetchone()
        return row is not None

    def record_consent(self, code: str, given: bool = True) -> None:
        """Record that participant ``code`` gave (or withdrew) consent, with the time.

        Without consent a participant cannot start or resume a test, and their
        answers are left out of the analysis and exports (but kept on disk; use
        :meth:`delete_participant` to erase them).
        """
        self._writable()
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute(
                "UPDATE participants SET consent = ?, consent_at = ? WHERE code = ?", (int(bool(given)), now_iso(), code)
            )
            log_event(self.conn, pid, "consent", {"given": bool(given)})

    def delete_participant(self, code: str) -> None:
        """Erase participant ``code`` and every answer they gave (one transaction)."""
        self._writable()
        pid = self._participant(code)[0]
        with self.conn:
            self.conn.execute("DELETE FROM participants WHERE id = ?", (pid,))

    def _participant(self, code):
        row = self.conn.execute("SELECT id, seed, consent FROM participants WHERE code = ?", (str(code),)).fetchone()
        if row is None:
            raise StudyInputError(f"no participant {code!r} in this study")
        return row

    def participants(self) -> list[dict]:
        """Each participant's code, consent, number of tests started/finished, external id, pilot flag
        and withdrawal time."""
        enrolled = self.version >= TABLE_SINCE["enrolments"]
        extra = "e.external_id, coalesce(e.pilot, 0), e.withdrawn_at" if enrolled else "NULL, 0, NULL"
        join = "LEFT JOIN enrolments e ON e.participant_id = p.id" if enrolled else ""
        by = "p.id, e.participant_id" if enrolled else "p.id"  # PostgreSQL: e's columns depend on its key
        rows = self.conn.execute(
            f"SELECT p.code, p.consent, p.consent_at, count(t.id), count(t.finished_at), "
            f"coalesce(sum(t.elapsed_seconds), 0), {extra} FROM participants p {join} "
            f"LEFT JOIN tests t ON t.participant_id = p.id GROUP BY {by} ORDER BY p.id"
        )
        return [
            dict(
                code=r[0],
                consent=bool(r[1]),
                consent_at=r[2],
                tests=r[3],
                finished=r[4],
                elapsed_seconds=r[5],
                external_id=r[6],
                pilot=bool(r[7]),
                withdrawn_at=r[8],
            )
            for r in rows
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
    def session(self, code: str, grammar: str, front_end: str = "script") -> TestSession:
        """Start, or resume, participant ``code``'s test on ``grammar``.

        Refused without consent, and refused for a *new* test once the
        participant's budget is spent (an unfinished test can always be resumed).
        ``front_end`` (desktop, notebook, web, simulated, script) is stored with every answer.
        """
        from ramure.studies.design import FRONT_ENDS

        if front_end not in FRONT_ENDS:
            raise StudyInputError(f"front end {front_end!r} is not one of {', '.join(FRONT_ENDS)}")
        from ramure.studies.session import TestSession

        self._writable()
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
                log_event(self.conn, pid, "start", {"grammar": grammar}, test_id, 0.0, front_end)
        else:
            test_id = row[0]
            if row[1] is None:
                with self.conn:
                    log_event(self.conn, pid, "resume", {"grammar": grammar}, test_id, row[2], front_end)
        return TestSession(self, test_id, str(code), grammar, seed, front_end)

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
        if self.version < TABLE_SINCE["events"]:
            return []  # a version-1 study read read-only: it logged no events
        where, args = ("WHERE p.code = ?", (str(code),)) if code is not None else ("", ())
        rows = self.conn.execute(
            "SELECT p.code, g.name, e.at, e.elapsed_seconds, e.action, e.detail, e.id FROM events e "
            "JOIN participants p ON p.id = e.participant_id LEFT JOIN tests t ON t.id = e.test_id "
            f"LEFT JOIN grammars g ON g.id = t.grammar_id {where} ORDER BY e.id",
            args,
        )
        keys = ("participant", "grammar", "at", "elapsed_seconds", "action")
        front = {}
        if self.version >= COLUMN_SINCE[("events", "front_end")]:
            front = dict(self.conn.execute("SELECT id, front_end FROM events"))
        return [dict(zip(keys, r[:5]), detail=self._detail(r[6], r[5]), front_end=front.get(r[6])) for r in rows]

    def _detail(self, row: int, text: str) -> dict:
        try:
            detail = json.loads(text)
        except ValueError:
            detail = None
        if not isinstance(detail, dict):
            raise _refuse_value(self.where, "events", row, "detail", "a JSON object", repr(text))
        return detail

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


def _external_id(value: object) -> str | None:
    """A recruiting platform's participant id, checked (None stays None)."""
    if value is None:
        return None
    if not isinstance(value, str) or not re.match(r"^[A-Za-z0-9_.:-]{1,64}$", value):
        raise StudyInputError(f"external id {value!r} must be 1-64 letters, digits, '.', ':', '-' or '_' (e.g. a Prolific PID)")
    return value


def _read_grammar(name, spec):
    if not isinstance(name, str) or not name.strip():
        raise StudyInputError(f"grammar name {name!r} must be non-empty text")
    if name.strip().casefold() == "all":
        raise StudyInputError("grammar name 'all' is reserved for the pooled statistics")
    if isinstance(spec, (str, os.PathLike)):
        source, picks = str(pathlib.Path(spec).resolve()), load_picks(spec)
    else:
        source, picks = None, picks_from_data(spec, where=f"grammar {name!r}")
    check_distinct(picks, f"grammar {name!r}")
    return source, picks


def _insert_grammar(conn, name, source, picks, folder):
    """Store a grammar's picks; paths inside the study's ``folder`` are stored relative to it, so
    a study folder copied elsewhere still finds its pictures and names no researcher's folders."""
    try:
        gid = conn.execute("INSERT INTO grammars (name, source) VALUES (?, ?)", (name, relative_to(folder, source))).lastrowid
    except sqlite3.IntegrityError:
        raise StudyInputError(f"grammar {name!r} is already in this study") from None
    conn.executemany(
        "INSERT INTO picks (grammar_id, pick_id, variant_id, pc1, pc2, pc3, params, image) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
        [(gid, p.id, p.variant, *p.pca, json.dumps(p.params, sort_keys=True), relative_to(folder, p.image)) for p in picks],
    )


def relative_to(folder: str | os.PathLike, path: str | os.PathLike | None) -> str | None:
    """``path`` relative to ``folder`` (POSIX separators) when it lies inside it, else as given.

    >>> relative_to("/data/study", "/data/study/explore/pick_01.png"), relative_to("/data/study", "/elsewhere/a.png")
    ('explore/pick_01.png', '/elsewhere/a.png')
    """
    if not path:
        return None
    root, full = pathlib.Path(folder).resolve(), pathlib.Path(path).resolve()
    return full.relative_to(root).as_posix() if full.is_relative_to(root) else str(path)
