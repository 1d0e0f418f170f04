"""New qualifier words from a study: each word people gave a group, with its measured direction.

Participants name their groups freely; the synonym table
(:class:`~ramure.studies.qualifiers.SynonymTable`) maps the texts it knows to
the default vocabulary, and the others are *new words* ("long trunk",
"feathery").  :func:`study_words` gives each new word a metric direction
measured from the pictures it named: on each grammar, the qualifier metrics
(:data:`~ramure.metrics.qualifiers.QUALIFIER_METRICS`) of the 27 picks are
standardised (over the picks), and the word's direction is the mean of the
pictures it named (a picture named by two groups counts twice) minus the
mean of the other pictures; grammars are pooled weighted by the groups that
used the word there, and the sum is scaled to unit length.  A word named by
fewer than ``min_groups`` groups, or whose pictures do not differ from the
rest, is left out, with the reason.

The words are written to a vocabulary file (:func:`ramure.metrics.words.write_words`)
that the front ends load: ``ramure study words study.db -o words.json`` then
``ramure qualify FILE --words words.json --qualifier "long trunk"``.

:func:`pick_metrics` measures the picks of a grammar whose study picks came
from an exploration folder (its ``pca.json`` names the grammar, ``n``, the
seed and the base constants): each pick is derived again with its stored
parameters (27 derivations).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ramure.studies.errors import StudyInputError
from ramure.studies.picks import N_PICKS
from ramure.studies.qualifiers import MAX_PHRASE, SynonymTable, normalise_text

if TYPE_CHECKING:
    from ramure.studies.data import StudyData
    from ramure.studies.storage import Study

#: Weights below this share of the direction's length are dropped (read as "does not move it").
MIN_WEIGHT = 0.05


def new_word_groups(data: StudyData, table: SynonymTable | None = None) -> dict[str, dict]:
    """``{canonical word: {"groups": [group rows], "texts": [as typed]}}`` of the texts that name
    no vocabulary qualifier (at most :data:`~ramure.studies.qualifiers.MAX_PHRASE` words, none
    of them a known one: "pas dense" is a negated vocabulary word, not a new word)."""
    from ramure.metrics.qualifiers import VOCABULARY, canonical_name

    table = table or SynonymTable.load()
    out: dict[str, dict] = {}
    for group, text in zip(data.qualifier_group.tolist(), data.qualifier_text):
        folded = normalise_text(text)
        words = folded.split()
        if not words or len(words) > MAX_PHRASE or table.canonical(text) or any(table.canonical(w) for w in words):
            continue
        key = canonical_name(folded)
        if key in VOCABULARY:
            continue
        entry = out.setdefault(key, {"groups": [], "texts": []})
        if group not in entry["groups"]:
            entry["groups"].append(int(group))
        if text.strip() not in entry["texts"]:
            entry["texts"].append(text.strip())
    return out


def _standardised(metrics: np.ndarray) -> np.ndarray:
    """Each metric (column) of the picks centred and divided by its spread (0 where it is flat)."""
    mean, std = np.nanmean(metrics, axis=0), np.nanstd(metrics, axis=0)
    z = np.divide(metrics - mean, std, out=np.zeros_like(metrics), where=std > 0)
    return np.nan_to_num(z)


def _grammar_direction(z: np.ndarray, named: np.ndarray) -> np.ndarray:
    """Weighted mean of the named picks' ``z`` minus the mean of the others (27 counts ``named``)."""
    rest = named == 0
    if not rest.any():
        return np.zeros(z.shape[1])
    return (named @ z) / named.sum() - z[rest].mean(axis=0)


def study_words(
    data: StudyData, metrics: Mapping[str, ArrayLike], table: SynonymTable | None = None, min_groups: int = 2
) -> tuple[dict[str, dict], dict[str, str]]:
    """``(words, left_out)``: each new word's vocabulary entry (see the module docstring) and,
    for each word left out, why.

    ``metrics`` maps grammar names to the (27, 15) qualifier metrics of their picks (pick 1
    first); a word used only on grammars without metrics is left out.
    """
    from ramure.metrics.qualifiers import QUALIFIER_METRICS
    from ramure.metrics.words import describe_direction

    if int(min_groups) < 1:
        raise StudyInputError(f"min_groups must be at least 1, not {min_groups}")
    z = {}
    for name, m in metrics.items():
        m = np.asarray(m, float)
        if m.shape != (N_PICKS, len(QUALIFIER_METRICS)):
            raise StudyInputError(f"metrics of grammar {name!r}: expected shape (27, 15), got {m.shape}")
        z[name] = _standardised(m)
    words, left_out = {}, {}
    for word, found in new_word_groups(data, table).items():
        groups = np.array(found["groups"], dtype=np.int64)
        if len(groups) < min_groups:
            left_out[word] = f"named by {len(groups)} group(s); at least {min_groups} needed"
            continue
        total, used = np.zeros(len(QUALIFIER_METRICS)), []
        for g in np.unique(data.group_grammar[groups]).tolist():
            grammar = data.grammars[g]
            mine = groups[data.group_grammar[groups] == g]
            if grammar not in z:
                continue
            named = data.membership[mine].sum(axis=0).astype(float)
            total += len(mine) * _grammar_direction(z[grammar], named)
            used.append(grammar)
        norm = float(np.linalg.norm(total))
        if not used or norm < 1e-9:
            left_out[word] = "its pictures' metrics do not differ from the others'" if used else "no metrics for its grammars"
            continue
        unit = total / norm
        direction = {m: round(float(w), 4) for m, w in zip(QUALIFIER_METRICS, unit) if abs(w) >= MIN_WEIGHT}
        people = sorted({data.participants[p] for p in data.test_participant[data.group_test[groups]].tolist()})
        words[word] = {
            "direction": direction,
            "texts": found["texts"][:10],
            "groups": int(len(groups)),
            "participants": len(people),
            "picks": int(data.membership[groups].any(axis=0).sum()),
            "grammars": used,
            "studies": [data.name],
            "meaning": f"named by {len(groups)} groups in study {data.name!r}: {describe_direction(direction, 4)}",
        }
    return words, left_out


def pick_metrics(study: Study, grammar: str, grammars_dir: str | os.PathLike | None = None) -> np.ndarray:
    """The (27, 15) qualifier metrics of ``grammar``'s picks, each derived again from its
    exploration folder's grammar (``pca.json``: grammar, n, seed, base constants) with the
    parameters the study stored; refused when the study has no folder or grammar file for it."""
    from ramure.io import read_json
    from ramure.lsys import LSystem
    from ramure.metrics.exploration import MAX_PCA_JSON_BYTES, read_exploration_info
    from ramure.metrics.sweep import measure

    folder = study.grammar_source(grammar)
    if folder is None:
        raise StudyInputError(f"grammar {grammar!r} of the study has no exploration folder: its picks cannot be measured")
    info = read_exploration_info(folder, grammars_dir)
    if info.grammar_file is None:
        raise StudyInputError(f"{folder}: no grammar file found for {info.name!r} (give --grammars-dir)")
    doc = read_json(os.path.join(folder, "pca.json"), MAX_PCA_JSON_BYTES, "exploration file")
    base = doc.get("base_constants") if isinstance(doc, dict) else None
    ls = LSystem.from_file(info.grammar_file)
    base = base if isinstance(base, dict) else {}
    constants = {
        **ls.constants,
        **{k: float(v) for k, v in base.items() if k in ls.constants and isinstance(v, (int, float)) and not isinstance(v, bool)},
    }
    rows = [measure(ls, info.n, info.seed, constants, pick.params) for pick in study.picks(grammar)]
    return np.array(rows, float).reshape(N_PICKS, -1)
