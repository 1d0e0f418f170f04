"""The qualifier store: one SQLite file of labelled variant points per grammar.

The studies package writes study results into the same table
(``source = 'study:<name>'``); this module reads them back as
:class:`~ramure.metrics.qualifiers.QualifierRegions`, and can also write the
default vocabulary's top-ranked variants (``source = 'default'``) so a
grammar has regions before any study.  ``grammar`` is a name, by convention
the grammar file's stem (:func:`ramure.metrics.exploration.grammar_name`); ``qualifier``
is the normalised English name.

>>> import tempfile, pathlib
>>> store = QualifierStore(pathlib.Path(tempfile.mkdtemp()) / "q.sqlite")
>>> store.add("honda", "dense", [4, 7], [[0, 0, 0], [1, 1, 1]], [{"rule": 0, "constants": {}}] * 2)
2
>>> store.qualifiers("honda"), store.points("honda")["dense"].shape
(['dense'], (2, 3))
>>> store.close()
"""

from __future__ import annotations

import json
import os
import pathlib
import sqlite3
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Self

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import RamureError
from ramure.io import APPLICATION_ID, open_sqlite_readonly

from .qualifiers import VOCABULARY, QualifierRegions, canonical_name, rank_variants

if TYPE_CHECKING:
    from .exploration import Exploration

SCHEMA = """CREATE TABLE IF NOT EXISTS qualifier_points (
  id INTEGER PRIMARY KEY,
  grammar TEXT NOT NULL,
  qualifier TEXT NOT NULL,       -- normalised English name, e.g. 'dense', 'small', 'round'
  variant_id INTEGER NOT NULL,
  pick_id INTEGER,               -- 1..27
  pc1 REAL NOT NULL, pc2 REAL NOT NULL, pc3 REAL NOT NULL,
  params TEXT NOT NULL,          -- JSON {"rule": int, "constants": {...}}
  source TEXT NOT NULL           -- e.g. 'study:<name>' or 'default'
)"""


_COLUMNS = ["id", "grammar", "qualifier", "variant_id", "pick_id", "pc1", "pc2", "pc3", "params", "source"]


def check_store_file(path: str | os.PathLike, study: bool = False) -> None:
    """Refuse, with one line and the file left byte for byte, a file Ramure did not create.

    Accepted: no file, an empty one, a SQLite file carrying Ramure's application id
    (:data:`ramure.io.APPLICATION_ID`: a study, or a store made by this version) whose
    ``qualifier_points``, if any, has our columns, and a store made before the id
    (application id 0 and no table but a ``qualifier_points`` of our columns).
    ``study=True`` says the caller recognised the file as a Ramure study
    (:func:`ramure.studies.storage.check_study_file`), also one made before the id.
    Read with :func:`ramure.io.open_sqlite_readonly`, which writes nothing.
    """
    path = pathlib.Path(path)
    if not path.exists():
        return
    if not path.is_file():
        raise RamureError(f"{path}: not a regular file; give a new file or a qualifier store")
    if path.stat().st_size == 0:
        return
    try:
        conn = open_sqlite_readonly(path)
        try:
            app_id = conn.execute("PRAGMA application_id").fetchone()[0]
            tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
            columns = [r[1] for r in conn.execute("PRAGMA table_info(qualifier_points)")]
        finally:
            conn.close()
    except sqlite3.DatabaseError as exc:
        if getattr(exc, "sqlite_errorcode", None) == sqlite3.SQLITE_NOTADB:
            raise RamureError(f"{path}: not a SQLite file; give a new file or a qualifier store") from None
        raise RamureError(f"{path}: not a readable SQLite database ({exc})") from None
    except UnicodeDecodeError:  # SQLite's own message quotes a damaged schema's bytes
        raise RamureError(f"{path}: a damaged SQLite database (its schema is not UTF-8)") from None
    if "qualifier_points" in tables and columns != _COLUMNS:
        raise RamureError(
            f"{path}: its qualifier_points table has another schema ({', '.join(columns)}); not a Ramure qualifier store"
        )
    if app_id == APPLICATION_ID or study or tables <= {"qualifier_points"}:
        return
    raise RamureError(
        f"{path}: a database Ramure did not create (application_id {app_id:#x}, tables "
        f"{', '.join(sorted(tables)[:5])}); give a new file, a qualifier store or a Ramure study"
    )


def open_store(path: str | os.PathLike, study: bool = False) -> sqlite3.Connection:
    """A connection to qualifier store ``path``, refused (unchanged) unless Ramure made it
    (:func:`check_store_file`); a new store gets the table and Ramure's application id."""
    path = pathlib.Path(path)
    check_store_file(path, study)  # read-only first: a database of another application is refused
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        conn = sqlite3.connect(os.fspath(path), timeout=10.0)
    except (sqlite3.Error, OSError) as exc:
        raise RamureError(f"{path}: cannot open the qualifier store ({exc})") from None
    try:
        with conn:
            if conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0] == 0:
                conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(SCHEMA)
    except sqlite3.Error as exc:
        conn.close()
        raise RamureError(f"{path}: cannot open the qualifier store ({exc})") from None
    return conn


class QualifierStore:
    """Read and write ``qualifier_points`` in one SQLite file (created if missing; an existing
    file only if Ramure made it, see :func:`check_store_file`)."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = pathlib.Path(path)
        self.conn = open_store(self.path)

    def close(self) -> None:
        self.conn.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- writing -----------------------------------------------------------
    def add(
        self,
        grammar: str,
        qualifier: str,
        variant_ids: Iterable[int],
        points: ArrayLike,
        params: Iterable[Mapping[str, float]],
        pick_ids: Iterable[int | None] | None = None,
        source: str = "default",
    ) -> int:
        """Insert labelled points: one row per variant (``points`` (k,3), ``params`` k dicts)."""
        points = np.asarray(points, float).reshape(-1, 3)
        variant_ids = [int(v) for v in variant_ids]
        params = list(params)
        pick_ids = [None] * len(variant_ids) if pick_ids is None else [None if p is None else int(p) for p in pick_ids]
        if not (len(points) == len(variant_ids) == len(params) == len(pick_ids)):
            raise RamureError("variant_ids, points, params and pick_ids must have the same length")
        if not np.isfinite(points).all():
            raise RamureError("qualifier points must be finite")
        name = canonical_name(qualifier)
        rows = [
            (str(grammar), name, v, p, *map(float, pt), json.dumps(pr), str(source))
            for v, p, pt, pr in zip(variant_ids, pick_ids, points, params)
        ]
        with self.conn:
            self.conn.executemany(
                "INSERT INTO qualifier_points (grammar, qualifier, variant_id, pick_id, pc1, pc2, pc3, "
                "params, source) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                rows,
            )
        return len(rows)

    def remove(self, grammar: str | None = None, source: str | None = None) -> int:
        """Delete rows of a grammar and/or a source; returns how many."""
        where, args = self._where(grammar, None, source)
        with self.conn:
            return self.conn.execute(f"DELETE FROM qualifier_points{where}", args).rowcount

    def write_default(self, exploration: Exploration, per_qualifier: int = 10) -> int:
        """Store, for every vocabulary qualifier, its ``per_qualifier`` best-ranked variants.

        Rows use ``source='default'`` and replace that grammar's previous
        default rows, so the call is idempotent.
        """
        sweep, cloud, grammar = exploration.sweep, exploration.points, exploration.name
        self.remove(grammar, "default")
        total = 0
        for name in VOCABULARY:
            top = rank_variants(name, sweep)[:per_qualifier]
            top = top[np.all(np.isfinite(cloud[top]), axis=1)]
            total += self.add(grammar, name, top, cloud[top], [sweep.combination(i) for i in top])
        return total

    # -- reading -----------------------------------------------------------
    @staticmethod
    def _where(grammar, qualifier, source):
        clauses, args = [], []
        if grammar is not None:
            clauses.append("grammar = ?")
            args.append(str(grammar))
        if qualifier is not None:
            clauses.append("qualifier = ?")
            args.append(canonical_name(qualifier))
        if source is not None:
            if str(source).endswith("%"):
                clauses.append("source LIKE ?")
            else:
                clauses.append("source = ?")
            args.append(str(source))
        return (" WHERE " + " AND ".join(clauses)) if clauses else "", args

    def rows(self, grammar: str | None = None, qualifier: str | None = None, source: str | None = None) -> list[dict]:
        """Rows as dicts (``params`` decoded); ``source`` may end with ``%`` (e.g. ``'study:%'``)."""
        where, args = self._where(grammar, qualifier, source)
        cur = self.conn.execute(
            "SELECT id, grammar, qualifier, variant_id, pick_id, pc1, pc2, pc3, params, "
            f"source FROM qualifier_points{where} ORDER BY id",
            args,
        )
        keys = [c[0] for c in cur.description]
        out = []
        for values in cur.fetchall():
            row = dict(zip(keys, values))
            try:
                row["params"] = json.loads(row["params"])
            except json.JSONDecodeError:
                raise RamureError(f"{self.path}: row {row['id']} has invalid params JSON") from None
            out.append(row)
        return out

    def grammars(self) -> list[str]:
        return [r[0] for r in self.conn.execute("SELECT DISTINCT grammar FROM qualifier_points ORDER BY grammar")]

    def qualifiers(self, grammar: str, source: str | None = None) -> list[str]:
        where, args = self._where(grammar, None, source)
        return [
            r[0] for r in self.conn.execute(f"SELECT DISTINCT qualifier FROM qualifier_points{where} ORDER BY qualifier", args)
        ]

    def points(self, grammar: str, source: str | None = None) -> dict[str, np.ndarray]:
        """``{qualifier: (k,3) PCA points}`` of a grammar."""
        out: dict[str, list[tuple[float, float, float]]] = {}
        for r in self.rows(grammar, source=source):
            out.setdefault(r["qualifier"], []).append((r["pc1"], r["pc2"], r["pc3"]))
        return {k: np.array(v, float) for k, v in out.items()}

    def regions(self, grammar: str, source: str | None = None, trim: float = 0.07) -> QualifierRegions | None:
        """Fitted :class:`QualifierRegions` of a grammar, or None if it has no points."""
        points = self.points(grammar, source)
        return QualifierRegions(trim=trim).fit(points) if points else None
