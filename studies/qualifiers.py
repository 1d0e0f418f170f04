"""Free-text qualifiers: normalisation, frequencies, labelled points, export.

Normalisation folds case and accents, turns punctuation into spaces, then maps
phrases to the canonical English names of a synonym table (``synonyms.json``
here, extended by user files of the same shape).  Within a text, the longest
known phrase wins ("peu dense" -> sparse, not dense); a single word is also
tried without a final ``s``/``x`` and ``e`` ("petites" -> "petit"); a term
just after a negation (pas, not, non, peu, moins, less, sans, without, ni, no)
that is not itself a known phrase is dropped.  One text can name several
qualifiers ("petit et dense" -> small, dense); a text naming none is kept as
its folded form under ``unmatched``.

>>> table = SynonymTable.load()
>>> table.canonical("Très ÉPARS!"), table.canonical("petites et denses"), table.canonical("peu dense")
(['sparse'], ['small', 'dense'], ['sparse'])
>>> table.canonical("pas très dense"), table.canonical("sapin de Noël"), table.french("fir-like")
([], ['fir-like'], 'sapin')
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import sqlite3
from collections import Counter
from dataclasses import dataclass
from importlib import resources

import numpy as np

from ramure.studies.errors import StudyInputError
from ramure.studies.likert import fold, likert_value
from ramure.studies.records import MAX_QUALIFIER_CHARS as MAX_QUALIFIER_CHARS  # read by data, export and tests
from typing import TYPE_CHECKING
from typing import Any

if TYPE_CHECKING:
    from ramure.studies.data import StudyData

NEGATIONS = {"pas", "not", "non", "peu", "moins", "less", "sans", "without", "ni", "no"}
MAX_PHRASE = 4
#: Largest synonym file read (bytes); a synonym table is a few kilobytes.
MAX_SYNONYM_BYTES = 1 << 20
#: Longest phrase (characters) in a synonym file.
MAX_SYNONYM_CHARS = 200

QUALIFIER_POINTS_SQL = """CREATE TABLE IF NOT EXISTS qualifier_points (
  id INTEGER PRIMARY KEY,
  grammar TEXT NOT NULL,
  qualifier TEXT NOT NULL,
  variant_id INTEGER NOT NULL,
  pick_id INTEGER,
  pc1 REAL NOT NULL, pc2 REAL NOT NULL, pc3 REAL NOT NULL,
  params TEXT NOT NULL,
  source TEXT NOT NULL
)"""


def normalise_text(text: str) -> str:
    """Fold case and accents, punctuation to spaces: ``"Fir-like!" -> "fir like"``."""
    return " ".join(re.sub(r"[^0-9a-z]+", " ", fold(text)).split())


def read_synonym_file(path: str | os.PathLike) -> dict:
    """The JSON document of synonym file ``path``, refused in one line unless it is a regular
    UTF-8 JSON file of at most :data:`MAX_SYNONYM_BYTES` (devices, pipes and deep nesting too)."""
    from ramure.io import read_regular

    if not pathlib.Path(path).exists():
        raise StudyInputError(f"{path}: no such synonym file")
    data = read_regular(path, MAX_SYNONYM_BYTES, "synonym file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise StudyInputError(f"{path}: not UTF-8 text (byte {exc.start}); save the synonym file as UTF-8") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise StudyInputError(f"{path}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    except RecursionError:
        raise StudyInputError(f"{path}: nested too deeply to be a synonym table") from None


def _check_entry(name: object, entry: object, where: str) -> None:
    """Refuse a ``qualifiers`` entry whose name, French name or synonyms are not short text."""

    def phrase(value: object) -> bool:
        return isinstance(value, str) and len(value) <= MAX_SYNONYM_CHARS

    if not phrase(name):
        raise StudyInputError(f"{where}: qualifier name {str(name)[:40]!r} must be at most {MAX_SYNONYM_CHARS} characters")
    if entry is None:
        return
    synonyms = entry.get("synonyms", []) if isinstance(entry, dict) else None
    if not isinstance(entry, dict) or not isinstance(synonyms, list):
        raise StudyInputError(f"{where}: qualifier {name!r} must be an object with 'fr' and a 'synonyms' list")
    if entry.get("fr") is not None and not phrase(entry["fr"]):
        raise StudyInputError(f"{where}: qualifier {name!r}: 'fr' must be text of at most {MAX_SYNONYM_CHARS} characters")
    for i, value in enumerate(synonyms):
        if not phrase(value):
            raise StudyInputError(
                f"{where}: qualifier {name!r}: synonym {i + 1} must be text of at most {MAX_SYNONYM_CHARS} characters, "
                f"not {type(value).__name__}"
            )


class SynonymTable:
    """Canonical qualifier names with their French names and synonyms."""

    def __init__(self) -> None:
        self.names: dict[str, str] = {}  # canonical -> French display name
        self.lookup: dict[str, str] = {}  # normalised phrase -> canonical

    @classmethod
    def load(cls, *paths: str | os.PathLike | None) -> SynonymTable:
        """The built-in table, extended (and overridden) by each file in ``paths``."""
        table = cls()
        builtin = resources.files(__package__).joinpath("synonyms.json").read_text(encoding="utf-8")
        table.update(json.loads(builtin), "studies/synonyms.json")
        for path in paths:
            if path is None:
                continue
            table.update(read_synonym_file(path), str(path))
        return table

    def update(self, doc: dict, where: str = "synonyms") -> None:
        """Add the ``{"qualifiers": {name: {"fr": ..., "synonyms": [...]}}}`` of ``doc``.

        A phrase listed under two names of the same document is refused; a
        later document may move a phrase to another name.  A French name that
        is another qualifier's English name (``wide``'s ``large``: English
        *large* is *grand*) names the entry but does not map: the English
        name wins, and French "wider" is reached by its synonyms
        ("plus large", "étalé").
        """
        entries = doc.get("qualifiers") if isinstance(doc, dict) else None
        if not isinstance(entries, dict):
            raise StudyInputError(f"{where}: expected an object with a 'qualifiers' object")
        for name, entry in entries.items():
            _check_entry(name, entry, where)
        english = {normalise_text(name) for name in entries} | set(self.names)
        seen: dict[str, str] = {}
        for name, entry in entries.items():
            entry = entry or {}
            canonical = normalise_text(name).replace(" ", "-")
            if not canonical:
                raise StudyInputError(f"{where}: empty qualifier name {name!r}")
            self.names[canonical] = entry.get("fr") or self.names.get(canonical) or canonical
            french = normalise_text(entry.get("fr") or "")
            for phrase in [name, entry.get("fr") or "", *entry.get("synonyms", [])]:
                key = normalise_text(phrase)
                if not key or (key == french and key in english and key != normalise_text(name)):
                    continue
                if seen.get(key, canonical) != canonical:
                    raise StudyInputError(f"{where}: {phrase!r} is listed under both {seen[key]!r} and {canonical!r}")
                seen[key] = canonical
                self.lookup[key] = canonical

    @property
    def vocabulary(self) -> list:
        """Canonical names, in table order."""
        return list(self.names)

    def french(self, name: str) -> str:
        return self.names[name]

    def _word(self, word):
        for form in (word, re.sub(r"[sx]$", "", word), re.sub(r"e?[sx]?$", "", word)):
            if form in self.lookup:
                return self.lookup[form]
        return None

    def canonical(self, text: str) -> list:
        """Canonical qualifiers named in ``text`` (see the module docstring)."""
        key = normalise_text(text)
        if key in self.lookup:
            return [self.lookup[key]]
        words = key.split()
        found, i = [], 0
        while i < len(words):
            for size in range(min(MAX_PHRASE, len(words) - i), 0, -1):
                phrase = " ".join(words[i : i + size])
                name = self.lookup.get(phrase) if size > 1 else self._word(phrase)
                if name:
                    negated = any(w in NEGATIONS for w in words[max(0, i - 2) : i])
                    if not negated and name not in found:
                        found.append(name)
                    i += size
                    break
            else:
                i += 1
        return found


@dataclass
class QualifierObservation:
    """One qualifier text given to one group, with what it normalises to."""

    group: int  # group row in StudyData
    text: str
    folded: str
    names: list  # canonical names, possibly empty


def observations(data: StudyData, table: SynonymTable | None = None) -> list:
    """Every qualifier text of the study, normalised with ``table``."""
    table = table or SynonymTable.load()
    return [
        QualifierObservation(int(g), t, normalise_text(t), table.canonical(t))
        for g, t in zip(data.qualifier_group, data.qualifier_text)
    ]


def _kept_groups(data, min_usefulness):
    if min_usefulness is None:
        return np.ones(len(data.usefulness), dtype=bool)
    level = likert_value(min_usefulness, "minimum usefulness")
    return np.nan_to_num(data.usefulness, nan=0) >= level


def qualifier_frequencies(data: StudyData, table: SynonymTable | None = None, min_usefulness: str | int | None = None) -> dict:
    """Counts of qualifiers, optionally only for groups rated at least ``min_usefulness``.

    Returns ``{"observations", "unique_texts", "per_group", "qualifiers":
    [{name, fr, groups, images, tests, grammars}], "unmatched": [{text, groups}]}``
    sorted by decreasing number of groups.  ``min_usefulness="good"`` keeps
    the groups rated good or excellent, as Clément-Corriveau did.
    """
    table = table or SynonymTable.load()
    kept = _kept_groups(data, min_usefulness)
    obs = [o for o in observations(data, table) if kept[o.group]]
    sizes = data.membership.sum(axis=1)
    per_name: dict[str, set] = {}
    for o in obs:
        for name in o.names:
            per_name.setdefault(name, set()).add(o.group)
    rows: list[dict[str, Any]] = []
    for name, groups in per_name.items():
        g = np.fromiter(groups, dtype=np.int64)
        rows.append(
            dict(
                name=name,
                fr=table.french(name),
                groups=len(g),
                images=int(sizes[g].sum()),
                tests=len(set(data.group_test[g].tolist())),
                grammars=sorted({data.grammars[i] for i in data.group_grammar[g].tolist()}),
            )
        )
    rows.sort(key=lambda r: (-r["groups"], r["name"]))
    unmatched = Counter(o.folded for o in obs if not o.names)
    n_groups = int(kept.sum())
    return dict(
        observations=len(obs),
        unique_texts=len({o.folded for o in obs}),
        per_group=(len(obs) / n_groups) if n_groups else 0.0,
        groups=n_groups,
        qualifiers=rows,
        unmatched=[dict(text=t, groups=c) for t, c in unmatched.most_common()],
    )


def labelled_points(
    data: StudyData, table: SynonymTable | None = None, min_usefulness: str | int = "good", source: str | None = None
) -> list:
    """Rows for ``qualifier_points``: every image of every kept group, per qualifier.

    A qualifier attaches to each image (variant point) of the group it names
    (thesis §5.5).  Only groups rated at least ``min_usefulness`` are kept and
    only vocabulary qualifiers are exported.  The same point named by several
    participants appears once per group, so agreement weighs in the boxes.
    """
    table = table or SynonymTable.load()
    kept = _kept_groups(data, min_usefulness)
    source = source or f"study:{data.name}"
    names_of: dict[int, list[str]] = {}
    for o in observations(data, table):
        if kept[o.group]:
            names = names_of.setdefault(o.group, [])
            names += [n for n in o.names if n not in names]
    rows = []
    for group, names in sorted(names_of.items()):
        g = int(data.group_grammar[group])
        for pick in (np.flatnonzero(data.membership[group]) + 1).tolist():
            pc = data.pca[g, pick - 1]
            for name in names:
                rows.append(
                    dict(
                        grammar=data.grammars[g],
                        qualifier=name,
                        variant_id=int(data.variant[g, pick - 1]),
                        pick_id=pick,
                        pc1=float(pc[0]),
                        pc2=float(pc[1]),
                        pc3=float(pc[2]),
                        params=data.params[g][pick - 1],
                        source=source,
                    )
                )
    return rows


def export_qualifier_points(rows: list[dict], store: str | os.PathLike) -> int:
    """Write ``rows`` into the ``qualifier_points`` table of SQLite file ``store``.

    Rows of the same ``source`` already there are replaced, in one transaction,
    so exporting twice gives the same table.  Returns the number of rows written.
    ``store`` must be new, a qualifier store or a Ramure study: a database of
    another application is refused unchanged
    (:func:`ramure.metrics.store.check_store_file`).
    """
    from ramure.metrics.store import open_store
    from ramure.studies.storage import check_study_file

    store = pathlib.Path(store)
    try:  # a Ramure study, even one made before the application id, may hold the points
        check_study_file(store)
        study = True
    except StudyInputError:
        study = False
    conn = open_store(store, study)
    try:
        with conn:
            conn.execute(QUALIFIER_POINTS_SQL)
            for source in sorted({r["source"] for r in rows}):
                conn.execute("DELETE FROM qualifier_points WHERE source = ?", (source,))
            conn.executemany(
                "INSERT INTO qualifier_points (grammar, qualifier, variant_id, pick_id, pc1, pc2, pc3, "
                "params, source) VALUES (:grammar, :qualifier, :variant_id, :pick_id, :pc1, :pc2, :pc3, "
                ":params, :source)",
                rows,
            )
    except sqlite3.DatabaseError as exc:
        raise StudyInputError(f"{store}: cannot write the qualifier store ({exc})") from None
    finally:
        conn.close()
    return len(rows)
