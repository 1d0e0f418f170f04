"""What a study records about a test as it runs: event rows, their time stamps, and the
longest qualifier a participant may type.

Kept apart from :mod:`ramure.studies.storage` (which opens, checks and migrates the study
file) so that a running :class:`~ramure.studies.session.TestSession` writes its events
without importing the storage that creates it.
"""

from __future__ import annotations

import datetime
import json
import sqlite3

#: Longest qualifier text (characters) a participant may give; a stored text is cut to it when read,
#: so the analysis of a study is bounded by its number of answers, not by the bytes in its file.
MAX_QUALIFIER_CHARS = 200


def now_iso() -> str:
    """The current UTC time as ISO-8601 text (seconds precision)."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def event_time() -> str:
    """The current UTC time as ISO-8601 text, to the millisecond (event log)."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="milliseconds")


def log_test_event(conn: sqlite3.Connection, test_id: int, action: str, detail: dict, front_end: str | None = None) -> None:
    """Append an action on test ``test_id`` to the ``events`` table, with the test's participant and
    elapsed time read in the same statement and the ``front_end`` that took the answer (call it
    inside the change's transaction)."""
    conn.execute(
        "INSERT INTO events (participant_id, test_id, at, elapsed_seconds, action, detail, front_end) "
        "SELECT participant_id, id, ?, elapsed_seconds, ?, ?, ? FROM tests WHERE id = ?",
        (event_time(), action, json.dumps(detail, sort_keys=True), front_end, test_id),
    )


def log_event(
    conn: sqlite3.Connection,
    participant_id: int,
    action: str,
    detail: dict | None = None,
    test_id: int | None = None,
    elapsed_seconds: float | None = None,
    front_end: str | None = None,
) -> None:
    """Append one participant action to the ``events`` table (call it inside the change's transaction)."""
    conn.execute(
        "INSERT INTO events (participant_id, test_id, at, elapsed_seconds, action, detail, front_end) "
        "VALUES (?, ?, ?, ?, ?, ?, ?)",
        (participant_id, test_id, event_time(), elapsed_seconds, action, json.dumps(detail or {}, sort_keys=True), front_end),
    )
