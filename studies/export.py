"""Export a study's raw answers to CSV, one file per table, in long format.

Files: ``picks.csv``, ``participants.csv``, ``tests.csv``, ``groups.csv``
(one row per group, images joined by ``;``), ``memberships.csv`` (one row per
image placed), ``qualifiers.csv`` (raw text plus its canonical names), and
``codebook.csv`` (each column's type, levels and meaning, for R) with
``README_R.txt`` (how to read them in R).  Likert
answers are 1-4 (poor, fair, good, excellent); unfinished tests are included
with an empty ``finished_at``.  Answers of participants without recorded
consent are left out (they stay listed in ``participants.csv``).

>>> import tempfile, pathlib
>>> from ramure.studies.simulate import simulate_study
>>> tmp = pathlib.Path(tempfile.mkdtemp())
>>> _ = simulate_study(tmp / "s.db", participants=2, grammars=1)
>>> sorted(p.name for p in export_csv(tmp / "s.db", tmp / "csv"))[:4]
['README_R.txt', 'codebook.csv', 'groups.csv', 'memberships.csv']
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import csv
import os
import pathlib

from ramure.io import open_atomic, write_text
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
        "ORDER BY pick_id) gi ON gi.group_id = g.id WHERE p.consent = 1 GROUP BY g.id, t.id, p.id, gr.id ORDER BY t.id, g.label"
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


_LIKERT = "1 = poor, 2 = fair, 3 = good, 4 = excellent; empty = not answered"
_ISO = "ISO-8601 UTC time"
#: file, column, R type, levels or unit, meaning -- written as ``codebook.csv`` beside the CSVs.
CODEBOOK = [
    ("picks.csv", "grammar", "factor", "", "grammar (stimulus set) name"),
    ("picks.csv", "pick_id", "integer", "1-27", "picture number within the grammar (PCA lattice order)"),
    ("picks.csv", "variant_id", "integer", "", "index of the variant in the exploration's sweep"),
    ("picks.csv", "pc1", "numeric", "PCA units", "first principal component of the variant's metrics"),
    ("picks.csv", "pc2", "numeric", "PCA units", "second principal component"),
    ("picks.csv", "pc3", "numeric", "PCA units", "third principal component"),
    ("picks.csv", "params", "character", "JSON", 'parameter combination, {"rule": int, "constants": {...}}'),
    ("picks.csv", "image", "character", "path", "thumbnail file, empty if none"),
    ("participants.csv", "code", "factor", "", "anonymous participant code"),
    ("participants.csv", "consent", "integer", "0 = no, 1 = yes", "consent recorded; answers without it are not exported"),
    ("participants.csv", "consent_at", "character", _ISO, "when consent was recorded"),
    ("participants.csv", "created_at", "character", _ISO, "when the participant was added"),
    ("tests.csv", "test", "integer", "", "test id: one participant's pass over one grammar"),
    ("tests.csv", "participant", "factor", "", "participant code"),
    ("tests.csv", "grammar", "factor", "", "grammar name"),
    ("tests.csv", "started_at", "character", _ISO, "when the test started"),
    ("tests.csv", "finished_at", "character", _ISO, "when it was finished; empty = unfinished"),
    ("tests.csv", "elapsed_seconds", "numeric", "seconds", "time on task"),
    ("groups.csv", "test", "integer", "", "test id (tests.csv)"),
    ("groups.csv", "participant", "factor", "", "participant code: the unit of analysis"),
    ("groups.csv", "grammar", "factor", "", "grammar name: the within-participant factor"),
    ("groups.csv", "grp", "integer", "1..", "group label within the test, in the participant's order"),
    ("groups.csv", "size", "integer", "1-27", "number of pictures in the group"),
    ("groups.csv", "images", "character", "pick ids joined by ;", "pictures in the group"),
    ("groups.csv", "representative", "integer", "1-27; empty = none", "picture chosen to represent the group"),
    ("groups.csv", "usefulness", "ordered factor", _LIKERT, "how useful the group of variants is"),
    ("groups.csv", "difference", "ordered factor", _LIKERT, "how different the group is from the others"),
    ("groups.csv", "representative_quality", "ordered factor", _LIKERT, "how well the representative represents it"),
    ("memberships.csv", "test", "integer", "", "test id"),
    ("memberships.csv", "participant", "factor", "", "participant code"),
    ("memberships.csv", "grammar", "factor", "", "grammar name"),
    ("memberships.csv", "grp", "integer", "1..", "group label within the test"),
    ("memberships.csv", "pick_id", "integer", "1-27", "a picture placed in that group"),
    ("qualifiers.csv", "test", "integer", "", "test id"),
    ("qualifiers.csv", "participant", "factor", "", "participant code"),
    ("qualifiers.csv", "grammar", "factor", "", "grammar name"),
    ("qualifiers.csv", "grp", "integer", "1..", "group label within the test"),
    ("qualifiers.csv", "text", "character", "", "the words as the participant wrote them"),
    ("qualifiers.csv", "canonical", "character", "names joined by ;", "vocabulary qualifiers coded from the text"),
]

_R_HINT = """# Read in R:
#   g <- read.csv("groups.csv")
#   g$usefulness <- factor(g$usefulness, levels = 1:4, labels = c("poor", "fair", "good", "excellent"), ordered = TRUE)
#   lme4::lmer(as.numeric(usefulness) ~ grammar + (1 | participant) + (1 | test), data = g)
"""


def write_codebook(out_dir: str | os.PathLike) -> pathlib.Path:
    """Write ``codebook.csv`` (file, column, type, levels, meaning) for the exported CSVs."""
    path = pathlib.Path(out_dir) / "codebook.csv"
    with open_atomic(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(["file", "column", "type", "levels", "meaning"])
        writer.writerows(CODEBOOK)
    write_text(pathlib.Path(out_dir) / "README_R.txt", _R_HINT)
    return path


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
        if name == "picks.csv":  # never the researcher's folders: paths as seen from the study
            rows = [(*r[:-1], _shown_path(source, r[-1])) for r in rows]
        if name == "qualifiers.csv":
            header.append("canonical")
            rows = [(*r, ";".join(table.canonical(r[-1][:MAX_QUALIFIER_CHARS]))) for r in rows]
        path = out_dir / name
        with open_atomic(path, "w", newline="", encoding="utf-8") as fh:
            writer = csv.writer(fh)
            writer.writerow(header)
            writer.writerows(rows)
        written.append(path)
    written.append(write_codebook(out_dir))
    written.append(out_dir / "README_R.txt")
    return written


def _shown_path(study: Study, image: str | None) -> str | None:
    """A picture path for ``picks.csv``: relative to the study's folder when inside it (always,
    for studies made now), else the file name alone."""
    from ramure.studies.storage import relative_to

    if not image:
        return image
    shown = relative_to(study.path.parent, study.path.parent / image)
    return shown if shown is not None and not pathlib.PurePath(shown).is_absolute() else pathlib.PurePath(image).name
