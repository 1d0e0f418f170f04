"""Words beyond the default vocabulary: a vocabulary file of qualifiers with measured directions.

A study's participants name groups of pictures with their own words
(:func:`ramure.studies.words.study_words` measures each new word's metric
direction from the pictures it named).  Those words live in a small JSON
*vocabulary file* that every front end loads next to the default
vocabulary (``ramure qualify --words words.json``, the desktop's
*Variants ▸ Load study words…*, the notebook's ``ex.load_words(path)``)::

    {"format": "ramure-words", "version": 1,
     "words": {"long-trunk": {"direction": {"height": 0.9, "crown_width": -0.4},
                              "texts": ["long trunk"], "groups": 3, "picks": 11,
                              "grammars": ["honda"], "studies": ["pilot"]}}}

Keys are canonical names (:func:`~ramure.metrics.qualifiers.canonical_name`:
folded case and accents, words joined by ``-``); a direction is weights over
:data:`~ramure.metrics.qualifiers.QUALIFIER_METRICS`, as
``QualifierModel(directions=...)`` takes them.  The file is read by the
confined reader (:func:`ramure.io.read_json`) and written atomically.

>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "words.json"
>>> _ = write_words(path, {"Long trunk": {"direction": {"height": 2.0}, "groups": 3}})
>>> read_words(path)
{'long-trunk': {'height': 2.0}}
>>> word_label("long-trunk"), describe_direction({"height": 0.9, "crown_width": -0.4})
('long trunk', '+0.9 height -0.4 crown_width')
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping

from ramure.errors import RamureError

from .qualifiers import QUALIFIER_METRICS, VOCABULARY, accepted_words, canonical_name

FORMAT = "ramure-words"
#: Largest vocabulary file read (bytes): a few hundred words take a few tens of kilobytes.
MAX_WORDS_BYTES = 1 << 20
#: Most words a vocabulary file may hold.
MAX_WORDS = 2000


class WordsFileError(RamureError):
    """A vocabulary file that is not one (says which file and what is wrong)."""


def word_label(name: str) -> str:
    """How a canonical word is shown: ``long-trunk`` -> ``long trunk`` (``fir-like`` stays)."""
    return name if name in VOCABULARY else name.replace("-", " ")


def typed_words(extra: Iterable[str] = ()) -> list[str]:
    """What a qualifier box suggests while typing, in every front end: the accepted words
    (:func:`~ramure.metrics.qualifiers.accepted_words`: English, French, synonyms,
    comparatives) then the ``extra`` canonical words (a study's) as shown.

    >>> words = typed_words(["long-trunk"])
    >>> {"taller", "touffu", "plus haut"} <= set(words), words[-1]
    (True, 'long trunk')
    """
    shown = accepted_words()
    return shown + [w for w in map(word_label, extra) if w not in shown]


def describe_direction(direction: Mapping[str, float], top: int | None = None) -> str:
    """A direction in one line, strongest metric first (the ``top`` strongest): ``+0.9 height -0.4 crown_width``."""
    parts = sorted(direction.items(), key=lambda kv: -abs(kv[1]))[:top]
    return " ".join(f"{'+' if w > 0 else '-'}{abs(w):.2g} {m}" for m, w in parts)


def _weight(m: object, w: object) -> bool:
    return m in QUALIFIER_METRICS and isinstance(w, (int, float)) and not isinstance(w, bool) and math.isfinite(w)


def _direction(value: object, where: str) -> dict[str, float]:
    if not (
        isinstance(value, dict)
        and 0 < len(value) <= len(QUALIFIER_METRICS)
        and all(_weight(m, w) for m, w in value.items())
        and any(w != 0 for w in value.values())
    ):
        raise WordsFileError(
            f"{where}: a direction is {{metric: finite weight}}, not all zero, over {', '.join(QUALIFIER_METRICS)}"
        )
    return {str(m): float(w) for m, w in value.items()}


def words_of(doc: object, where: str = "words") -> dict[str, dict]:
    """The checked ``{canonical word: entry}`` of a vocabulary document (entries keep their
    ``direction`` and what else they say)."""
    words = doc.get("words") if isinstance(doc, dict) else None
    if not isinstance(words, dict) or (isinstance(doc, dict) and doc.get("format", FORMAT) != FORMAT):
        raise WordsFileError(f"{where}: not a Ramure vocabulary file (expected {{'format': '{FORMAT}', 'words': {{...}}}})")
    if len(words) > MAX_WORDS:
        raise WordsFileError(f"{where}: {len(words)} words; a vocabulary file holds at most {MAX_WORDS}")
    out: dict[str, dict] = {}
    for text, entry in words.items():
        key = canonical_name(text) if isinstance(text, str) and len(text) <= 200 else ""
        if not key:
            raise WordsFileError(f"{where}: word {str(text)[:40]!r} is not a word of at most 200 characters")
        if not isinstance(entry, dict):
            raise WordsFileError(f"{where}: word {text!r} must be an object with a 'direction'")
        out[key] = {**entry, "direction": _direction(entry.get("direction"), f"{where}: word {text!r}")}
    return out


def read_words_file(path: str | os.PathLike) -> dict[str, dict]:
    """Every entry of vocabulary file ``path`` (see the module docstring), checked."""
    from ramure.io import read_json

    return words_of(read_json(path, MAX_WORDS_BYTES, "vocabulary file"), str(path))


def read_words(path: str | os.PathLike) -> dict[str, dict[str, float]]:
    """``{word: {metric: weight}}`` of vocabulary file ``path``: ``directions=`` for a qualifier model."""
    return {k: v["direction"] for k, v in read_words_file(path).items()}


def write_words(path: str | os.PathLike, words: Mapping[str, Mapping], merge: bool = False) -> dict[str, dict]:
    """Write ``words`` (``{word: entry with a "direction"}``) as a vocabulary file, atomically;
    with ``merge``, the words already in ``path`` are kept unless ``words`` names them again.
    Returns what was written."""
    import pathlib

    from ramure.io import write_text

    new = words_of({"words": dict(words)}, "new words")
    old = read_words_file(path) if merge and pathlib.Path(path).exists() else {}
    words_out = {**old, **new}
    doc = {"format": FORMAT, "version": 1, "words": words_out}
    write_text(path, json.dumps(doc, indent=1, ensure_ascii=False) + "\n")
    return words_out
