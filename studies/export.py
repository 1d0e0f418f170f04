"""Export a study's raw answers to CSV, one file per table, in long format.

Files: ``picks.csv``, ``participants.csv``, ``tests.csv``, ``groups.csv``
(one row per group, images joined by ``;``), ``memberships.csv`` (one row per
image placed), ``qualifiers.csv`` (raw text plus its canonical names).  Likert
answers are 1-4 (poor, fair, good, excellent); unfinished tests are included
with an empty ``finished_at``.  Answers of participants without recorded
consent are left out (they stay listed in ``participants.csv``).

>>> import tempfile, pathlib
>>> from ramure.studies.simulate import simulate_study
>>> tmp = pathlib.Path(tempfile.mkdtemp())
>>> _ = simulate_study(tmp / "s.db", participants=2, grammars=1)
>>> sorted(p.name for p in export_csv(tmp / "s.db", tmp / "csv"))[:3]
['groups.csv', 'memberships.csv', 'participants.csv']
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import csv
import os
import pathlib

from ramure.io import open_atomic
from ramure.studies.qualifiers import MAX_QUALIFIER_CHARS, SynonymTable

if TYPE_CHECKING:
    from ramure.studies.storage import Study

_QUERIES = {
    "picks.csv": (
        "SELECT g.name AS grammar, p.pick_id, p.variant_id, p.pc1, p.pc2, p.pc3, p.params, p.image "
        "FROM picks p JOIN grammars g ON g.id = p.grammar_id ORDER BY g.id, p.pick_id"
    ),
    "participants.csv": ("SELECT code, consent, consent_at, created_at FROM participants ORDER BY id"),
    "tests.csv": (
        "SELECT t.id AS test, p.code AS participant, g.name AS grammar, t.started_at, t.finished_at, "
        "t.elapsed_seconds FROM tests t JOIN participants p ON p.id = t.participant_id "
        "JOIN grammars g ON g.id = t.grammar_id WHERE p.consent = 1 ORDER BY t.id"
    ),
    "groups.csv": (
        "SELECT t.id AS test, p.code AS participant, gr.name AS grammar, g.label AS grp, "
        "count(gi.pick_id) AS size, group_concat(gi.pick_id, ';') AS images, g.representative, "
        "g.usefulness, g.difference, g.representative_quality "
        "FROM groups g JOIN tests t ON t.id = g.test_id JOIN participants p ON p.id = t.participant_id "
        "JOIN grammars gr ON gr.id = t.grammar_id LEFT JOIN (SELECT * FROM group_images "
        "ORDER BY pick_id) gi ON gi.group_id = g.id WHERE p.consent = 1 GROUP BY g.id ORDER BY t.id, g.label"
    ),
    "memberships.csv": (
        "SELECT t.id AS test, p.code AS participant, gr.name AS grammar, g.label AS grp, gi.pick_id "
        "FROM group_images gi JOIN groups g ON g.id = gi.group_id JOIN tests t ON t.id = g.test_id "
        "JOIN participants p ON p.id = t.participant_id JOIN grammars gr ON gr.id = t.grammar_id "
        "WHERE p.consent = 1 ORDER BY t.id, g.label, gi.pick_id"
    ),
    "qualifiers.csv": (
        "SELECT t.id AS test, p.code AS participant, gr.name AS grammar, g.label AS grp, q.text "
        "FROM qualifiers q JOIN groups g ON g.id = q.group_id JOIN tests t ON t.id = g.test_id "
        "JOIN participants p ON p.id = t.participant_id JOIN grammars gr ON gr.id = t.grammar_id "
        "WHERE p.consent = 1 ORDER BY t.id, g.label, q.id"
    ),
}


def export_csv(
    source: Study | str | os.PathLike, out_dir: str | os.PathLike, synonyms: Sequence[str | os.PathLike] | None = None
) -> list[pathlib.Path]:
    """Write the CSV files of study ``source`` (a Study or a path) into ``out_dir``.

    ``synonyms`` (extra synonym files) only affects the ``canonical`` column of
    ``qualifiers.csv``.  Returns the paths written.
    """
    from ramure.studies.storage import Study

    if isinstance(source, (str, os.PathLike)):
        with Study.open(source, readonly=True) as study:
            return export_csv(study, out_dir, synonyms)
    table = SynonymTable.load(*(synonyms or []))  # a bad synonym file is refused before any folder is made
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, sql in _QUERIES.items():
        cur = source.conn.execute(sql)
        header = [d[0] for d in cur.description]
        rows = cur.fetchall()
        if name == "qualifiers.csv":
            header.append("canonical")
            rows = [(*r, ";".join(table.canonical(r[-1][:MAX_QUALIFIER_CHARS]))) for r in rows]
        path = out_dir / name
        with open_atomic(path, "w", newline="", encoding="utf-8") as fh:
            writer = csv.writer(fh)
            writer.writerow(header)
            writer.writerows(rows)
        written.append(path)
    return written
