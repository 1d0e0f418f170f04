"""A study on PostgreSQL: the thin dialect layer under :mod:`ramure.studies.storage`.

When one machine's SQLite file is not enough (several servers, a database the institution
backs up), a study lives in a PostgreSQL database named by a URL
(``postgresql://user:password@host:5432/dbname``).  The study code stays one code path, written
against the subset of :class:`sqlite3.Connection` it uses; :class:`PgConnection` gives that
subset on psycopg 3 (the ``postgres`` extra), translating only what differs:

- placeholders ``?`` become ``%s`` (values are bound client-side, so ``? IS NULL`` needs no
  declared type, as in SQLite), and ``IS [NOT] ?`` becomes ``IS [NOT] DISTINCT FROM``;
- ``group_concat(x, 'sep')`` becomes ``string_agg``, ordered by ``x``;
- an ``INSERT`` into a table keyed by ``id`` returns it, for ``cursor.lastrowid``;
- ``with conn:`` is one transaction, committed or rolled back; it first takes a transaction
  advisory lock, so writers take turns as on SQLite (one writer at a time): a Latin-square row
  counted in a transaction is never given twice by two processes enrolling at once;
- ``PRAGMA synchronous = FULL`` / ``NORMAL`` set ``synchronous_commit`` on / off (the web
  server's group commit: a commit at ``on`` flushes the write-ahead log holding the earlier
  ones); other pragmas are SQLite's own and are refused;
- psycopg's errors are raised as the :mod:`sqlite3` exception of the same DB-API class
  (``IntegrityError``...), so callers catch one family.

The schema is ``schema.sql`` with PostgreSQL's types (:func:`pg_schema`): 64-bit integers,
identity keys, double precision and byte-ordered (``"C"``) text, so rows sort as in SQLite.
"""

from __future__ import annotations

import functools
import os
import re
import sqlite3
import urllib.parse
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

#: Tables whose rows are keyed by an ``id`` the database assigns (``lastrowid``).
ID_TABLES = frozenset({"grammars", "participants", "tests", "groups", "qualifiers", "events"})
#: The key of the advisory lock every write transaction takes ("RAMU").
LOCK_KEY = 0x52414D55
_QUOTED = re.compile(r"('(?:[^']|'')*'|\"[^\"]*\")")
_GROUP_CONCAT = re.compile(r"group_concat\(\s*([\w.]+)\s*,\s*('[^']*')\s*\)", re.IGNORECASE)
_INSERT = re.compile(r"^\s*INSERT\s+INTO\s+(\w+)", re.IGNORECASE)
_PRAGMA = re.compile(r"^\s*PRAGMA\s+(\w+)\s*(?:=\s*(\w+))?\s*;?\s*$", re.IGNORECASE)
_ERRORS = (
    ("IntegrityError", sqlite3.IntegrityError),
    ("DataError", sqlite3.DataError),
    ("OperationalError", sqlite3.OperationalError),
    ("ProgrammingError", sqlite3.ProgrammingError),
    ("InternalError", sqlite3.InternalError),
    ("NotSupportedError", sqlite3.NotSupportedError),
)


def is_database_url(location: object) -> bool:
    """Whether ``location`` names a PostgreSQL database (``postgresql://`` or ``postgres://``).

    >>> is_database_url("postgresql://study@db.lab/plants"), is_database_url("study.db")
    (True, False)
    """
    return isinstance(location, str) and location.split("://", 1)[0].lower() in ("postgresql", "postgres")


def sqlite_path(location: str | os.PathLike) -> str | os.PathLike:
    """A ``sqlite:///path`` URL as its path (SQLAlchemy's spelling: three slashes before a relative
    path, four before an absolute one); anything else unchanged.

    >>> sqlite_path("sqlite:////data/study.db"), sqlite_path("sqlite:///rel.db"), sqlite_path("study.db")
    ('/data/study.db', 'rel.db', 'study.db')
    """
    if isinstance(location, str) and location.lower().startswith("sqlite:///"):
        rest = location[len("sqlite:///") :]
        return "/" + rest[1:] if rest.startswith("/") else rest
    return location


def shown_url(url: str) -> str:
    """``url`` with its password masked, for messages and printed results.

    >>> shown_url("postgresql://ann:s3cret@db.lab:5432/plants")
    'postgresql://ann:***@db.lab:5432/plants'
    """
    parts = urllib.parse.urlsplit(url)
    if parts.password is None:
        return url
    netloc = parts.netloc.rsplit("@", 1)
    return urllib.parse.urlunsplit(parts._replace(netloc=f"{parts.username}:***@{netloc[1]}"))


@functools.lru_cache(maxsize=512)
def translate(sql: str, params: bool = True) -> str:
    """SQLite's spelling of ``sql`` in PostgreSQL's (see the module's list); string literals are kept.

    >>> translate("SELECT id FROM grammars WHERE name IS NOT ? AND note = 'why?'")
    "SELECT id FROM grammars WHERE name IS DISTINCT FROM %s AND note = 'why?'"
    >>> translate("SELECT group_concat(gi.pick_id, ';') FROM t WHERE x = ? AND y LIKE 'a%'", params=True)
    "SELECT string_agg(CAST(gi.pick_id AS TEXT), ';' ORDER BY gi.pick_id) FROM t WHERE x = %s AND y LIKE 'a%%'"
    """
    sql = _GROUP_CONCAT.sub(r"string_agg(CAST(\1 AS TEXT), \2 ORDER BY \1)", sql)
    pieces = _QUOTED.split(sql)
    for i in range(0, len(pieces), 2):  # outside quotes
        text = pieces[i]
        text = re.sub(r"\bIS\s+NOT\s+\?", "IS DISTINCT FROM ?", text, flags=re.IGNORECASE)
        text = re.sub(r"\bIS\s+\?", "IS NOT DISTINCT FROM ?", text, flags=re.IGNORECASE)
        if params:
            text = text.replace("%", "%%").replace("?", "%s")
        pieces[i] = text
    if params:  # a literal's % must be doubled too when psycopg reads placeholders
        for i in range(1, len(pieces), 2):
            pieces[i] = pieces[i].replace("%", "%%")
    return "".join(pieces)


def pg_schema(sql: str) -> list[str]:
    """The statements of ``schema.sql`` with PostgreSQL's types.

    ``INTEGER PRIMARY KEY`` ``id`` columns become identity keys (the rowid SQLite assigns),
    ``INTEGER`` 64-bit (participants' seeds need it), ``REAL`` double precision (PostgreSQL's
    ``REAL`` is 32-bit), and text byte-ordered.
    """
    sql = re.sub(r"--[^\n]*", "", sql)
    sql = re.sub(r"\bid INTEGER PRIMARY KEY\b", "id BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY", sql)
    sql = re.sub(r"\bINTEGER\b", "BIGINT", sql)
    sql = re.sub(r"\bREAL\b", "DOUBLE PRECISION", sql)
    sql = re.sub(r"\bTEXT\b", 'TEXT COLLATE "C"', sql)
    return [s.strip() for s in sql.split(";") if s.strip()]


@functools.lru_cache(maxsize=512)
def _statement(sql: str, params: bool) -> tuple[str, bool, bool]:
    """``sql`` in PostgreSQL's spelling (cached), whether it returns the new row's ``id``, and
    whether it changes rows (counted in ``total_changes``)."""
    table = _INSERT.match(sql)
    returning = bool(table and table.group(1).lower() in ID_TABLES and "RETURNING" not in sql.upper())
    changes = bool(table or re.match(r"^\s*(UPDATE|DELETE)\b", sql, re.IGNORECASE))
    return translate(sql, params=params) + (" RETURNING id" if returning else ""), returning, changes


def _as_sqlite_error(exc: Exception) -> sqlite3.Error:
    """psycopg's error ``exc`` as the :mod:`sqlite3` exception of its DB-API class."""
    message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    for name, kind in _ERRORS:
        if any(base.__name__ == name for base in type(exc).__mro__):
            return kind(message)
    return sqlite3.DatabaseError(message)


class PgCursor:
    """The part of :class:`sqlite3.Cursor` the study code uses: fetches, iteration, ``lastrowid``,
    ``rowcount`` and ``description``."""

    def __init__(self, cursor: Any, lastrowid: int | None = None) -> None:
        self._cursor = cursor  # None: a statement that returns nothing (a pragma, no rows to write)
        self.lastrowid = lastrowid
        self.rowcount = cursor.rowcount if cursor is not None else -1
        self.description = cursor.description if cursor is not None else None

    def fetchone(self) -> tuple | None:
        if self.description is None:
            return None
        return self._cursor.fetchone()

    def fetchall(self) -> list[tuple]:
        if self.description is None:
            return []
        return self._cursor.fetchall()

    def __iter__(self) -> Iterator[tuple]:
        return iter(self.fetchall())


class PgConnection:
    """A psycopg 3 connection behaving as the :class:`sqlite3.Connection` the study code uses.

    Statements outside ``with conn:`` commit on their own (autocommit); ``with conn:`` is one
    transaction (nested blocks join the outer one) that first takes the study's advisory lock.
    ``readonly`` makes every transaction read-only on the server: nothing can be written.
    """

    def __init__(self, url: str, readonly: bool = False, durable: bool = True) -> None:
        try:
            import psycopg
        except ImportError:
            raise sqlite3.OperationalError(
                "a PostgreSQL study needs psycopg 3: pip install 'ramure[postgres]' (or psycopg[binary])"
            ) from None
        self._psycopg = psycopg
        self.url = url
        self.readonly = readonly
        try:
            self.raw = psycopg.connect(url, autocommit=True, cursor_factory=psycopg.ClientCursor, connect_timeout=10)
        except psycopg.Error as exc:
            raise _as_sqlite_error(exc) from None
        self.text_factory: Any = str  # SQLite's; PostgreSQL checks the encoding itself
        self.total_changes = 0
        self._depth = 0
        # Sent ahead of the next statement, in its round trip: a session setting (PRAGMA
        # synchronous), then the BEGIN of a transaction and its lock.  A SET sent this way joins the
        # transaction that follows and is undone if it rolls back: only a rolled-back answer can
        # undo one, leaving commits synchronous (slower, never less durable) until the next flush.
        self._pending = ""
        self._begin = ""
        if readonly:
            self.execute("SET default_transaction_read_only = on")
        self.execute(f"SET synchronous_commit = {'on' if durable else 'off'}")

    @property
    def dbname(self) -> str:
        """The database's name on its server."""
        return str(self.raw.info.dbname)

    @property
    def broken(self) -> bool:
        """Whether the connection to the server is lost (a restart, a network cut): open a new one."""
        return bool(self.raw.broken or self.raw.closed)

    @property
    def in_transaction(self) -> bool:
        return self._depth > 0

    def execute(self, sql: str, params: Sequence = ()) -> PgCursor:
        """Run one statement (SQLite's spelling, ``?`` placeholders); see :func:`translate`."""
        pragma = _PRAGMA.match(sql)
        if pragma:
            return self._pragma(pragma.group(1).lower(), (pragma.group(2) or "").upper())
        text, returning, changes = _statement(sql, bool(params))
        cursor = self._run(text, tuple(params) if params else None)
        lastrowid = None
        if returning:
            row = cursor.fetchone()
            lastrowid = row[0] if row else None
        if changes:
            self.total_changes += max(0, cursor.rowcount)
        return PgCursor(cursor, lastrowid)

    def _run(self, text: str, params: tuple | None) -> Any:
        """Execute ``text`` (PostgreSQL's spelling), with any pending settings in the same round trip
        (the client-side cursor sends several statements at once; the last one's result is read)."""
        ahead = [part for part in (self._pending, self._begin) if part]  # no placeholder or % in them
        if ahead:
            text, self._pending, self._begin = "; ".join([*ahead, text]), "", ""
        try:
            cursor = self.raw.cursor()
            cursor.execute(text, params)
        except self._psycopg.Error as exc:
            raise _as_sqlite_error(exc) from None
        while cursor.nextset():  # the last statement's result
            pass
        return cursor

    def executemany(self, sql: str, rows: Iterable[Sequence]) -> PgCursor:
        """Run one statement for each row of ``rows``."""
        rows = [tuple(r) for r in rows]
        if not rows:
            return PgCursor(None)
        try:
            cursor = self.raw.cursor()
            cursor.executemany(translate(sql), rows)
        except self._psycopg.Error as exc:
            raise _as_sqlite_error(exc) from None
        self.total_changes += max(0, cursor.rowcount)
        return PgCursor(cursor)

    def _pragma(self, name: str, value: str) -> PgCursor:
        if name == "synchronous" and value in ("FULL", "NORMAL", "OFF", "EXTRA"):
            self._pending = f"SET synchronous_commit = {'off' if value in ('NORMAL', 'OFF') else 'on'}"
            return PgCursor(None)
        if name == "foreign_keys":  # always enforced by PostgreSQL
            return PgCursor(None)
        raise sqlite3.OperationalError(f"PRAGMA {name} is SQLite's; this study is on PostgreSQL")

    def __enter__(self) -> PgConnection:
        if self._depth == 0:  # sent with the transaction's first statement
            self._begin = "BEGIN" if self.readonly else f"BEGIN; SELECT pg_advisory_xact_lock({LOCK_KEY})"
        self._depth += 1
        return self

    def __exit__(self, kind: Any, exc: Any, tb: Any) -> None:
        self._depth -= 1
        if self._depth == 0:
            if self._begin:  # no statement ran: there is no transaction to end
                self._begin = ""
                return
            self._finish("COMMIT" if kind is None else "ROLLBACK")

    def _finish(self, command: str) -> None:
        self._depth = 0
        try:
            self._run(command, None)
        except sqlite3.Error:
            if command == "COMMIT":  # the COMMIT itself failed: PostgreSQL has rolled back
                raise

    def commit(self) -> None:
        """Nothing to do: statements outside ``with conn:`` are committed as they run."""

    def rollback(self) -> None:
        """Nothing to do outside ``with conn:`` (autocommit); inside, the block rolls back on error."""

    def close(self) -> None:
        self.raw.close()
