"""A study's answers read once from SQLite into plain numpy arrays for analysis.

Groups are rows of a boolean membership matrix (groups x 27); tests, grammars
and participants are integer indices.  Likert answers are floats 1-4, NaN when
unanswered.  Qualifier texts are cut to
:data:`~ramure.studies.qualifiers.MAX_QUALIFIER_CHARS` characters as they are read
(a participant cannot type more), so the analysis time is bounded by the number
of answers.  By default only finished tests are read: an unfinished test is
work in progress, not an answer.  Tests of participants whose consent is not
recorded (or was withdrawn) are never read.

>>> import tempfile, pathlib
>>> from ramure.studies.picks import lattice_picks
>>> from ramure.studies.storage import Study
>>> study = Study.create(pathlib.Path(tempfile.mkdtemp()) / "s.db", grammars={"g": lattice_picks()})
>>> s = study.session(study.add_participant(consent=True), "g")
>>> s.set_groups([range(1, 28)])
>>> load_study_data(study).n_tests, load_study_data(study, finished_only=False).membership.shape
(0, (1, 27))
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import json
import os
from dataclasses import dataclass, field

import numpy as np

from ramure.studies.picks import N_PICKS
from ramure.studies.qualifiers import MAX_QUALIFIER_CHARS

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ramure.studies.design import Question
    from ramure.studies.storage import Study


@dataclass
class StudyData:
    """Every answer of a study as arrays (see the module docstring)."""

    name: str
    grammars: list  # grammar names; index = grammar number
    participants: list  # participant codes; index = participant number
    pca: np.ndarray  # (n_grammars, 27, 3) PCA coordinates of the picks
    variant: np.ndarray  # (n_grammars, 27) variant index in the sweep
    params: list  # params[g][pick - 1] -> JSON text
    test_grammar: np.ndarray  # (n_tests,)
    test_participant: np.ndarray
    group_test: np.ndarray  # (n_groups,)
    group_label: np.ndarray
    membership: np.ndarray  # (n_groups, 27) bool
    representative: np.ndarray  # (n_groups,) pick id, 0 when none
    usefulness: np.ndarray  # (n_groups,) float 1-4 or NaN
    difference: np.ndarray
    representative_quality: np.ndarray
    qualifier_group: np.ndarray  # (n_qualifiers,) group row of each qualifier
    qualifier_text: list
    test_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n_tests,) time on task
    #: (n_participants,) attention checks answered with another option than the expected one
    #: (0 for a participant who did not reach the page, or a study without checks)
    attention_missed: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_tests(self) -> int:
        return len(self.test_grammar)

    @property
    def group_grammar(self) -> np.ndarray:
        """Grammar number of each group."""
        return self.test_grammar[self.group_test]

    def grammar_index(self, grammar: str) -> int:
        from ramure.studies.errors import StudyInputError

        if grammar not in self.grammars:
            raise StudyInputError(f"no grammar {grammar!r} in study {self.name!r} (known: {', '.join(self.grammars)})")
        return self.grammars.index(grammar)


def load_study_data(source: Study | str | os.PathLike, finished_only: bool = True, include_pilot: bool = False) -> StudyData:
    """Read a :class:`~ramure.studies.storage.Study` (or a path to one) into arrays.

    Pilot participants (trial runs, :meth:`~ramure.studies.storage.Study.add_participant`
    ``pilot=True``) are left out unless ``include_pilot``."""
    from ramure.studies.storage import TABLE_SINCE, Study

    if isinstance(source, (str, os.PathLike)):
        with Study.open(source, readonly=True) as study:
            return load_study_data(study, finished_only, include_pilot)
    conn = source.conn
    config = source.config()
    practice = config.practice_set  # sorted to learn the task: never analysed
    grammars = [r for r in conn.execute("SELECT id, name FROM grammars WHERE name IS NOT ? ORDER BY id", (practice,))]
    gindex = {gid: i for i, (gid, _) in enumerate(grammars)}
    n_g = len(grammars)
    pca = np.zeros((n_g, N_PICKS, 3))
    variant = np.zeros((n_g, N_PICKS), dtype=np.int64)
    params = [[None] * N_PICKS for _ in range(n_g)]
    for gid, pick, var, x, y, z, par in conn.execute("SELECT grammar_id, pick_id, variant_id, pc1, pc2, pc3, params FROM picks"):
        if gid not in gindex:
            continue  # the practice set
        pca[gindex[gid], pick - 1] = (x, y, z)
        variant[gindex[gid], pick - 1] = var
        params[gindex[gid]][pick - 1] = par
    pilots = ""
    if not include_pilot and source.version >= TABLE_SINCE["enrolments"]:
        pilots = " AND p.id NOT IN (SELECT participant_id FROM enrolments WHERE pilot = 1)"
    people = conn.execute(f"SELECT id, code FROM participants p WHERE 1 = 1 {pilots} ORDER BY id").fetchall()
    pindex = {pid: i for i, (pid, _) in enumerate(people)}

    where = (
        "JOIN participants p ON p.id = t.participant_id WHERE p.consent = 1"
        + pilots
        + ("" if practice is None else f" AND t.grammar_id != {int(source.grammar_id(practice))}")
        + (" AND t.finished_at IS NOT NULL" if finished_only else "")
    )
    tests = np.array(
        conn.execute(
            f"SELECT t.id, t.grammar_id, t.participant_id, t.elapsed_seconds FROM tests t {where} ORDER BY t.id"
        ).fetchall(),
        dtype=float,
    ).reshape(-1, 4)
    seconds, tests = tests[:, 3], tests[:, :3].astype(np.int64)
    tindex = {tid: i for i, tid in enumerate(tests[:, 0].tolist())}
    groups = conn.execute(
        f"SELECT g.id, g.test_id, g.label, g.representative, g.usefulness, g.difference, "
        f"g.representative_quality FROM groups g JOIN tests t ON t.id = g.test_id {where} "
        "ORDER BY g.test_id, g.label"
    ).fetchall()
    gid_row = {row[0]: i for i, row in enumerate(groups)}
    cols = list(zip(*groups)) if groups else [()] * 7

    def likert(values):
        return np.array([np.nan if v is None else v for v in values], dtype=float)

    membership = np.zeros((len(groups), N_PICKS), dtype=bool)
    pairs = np.array(
        conn.execute(f"SELECT gi.group_id, gi.pick_id FROM group_images gi JOIN tests t ON t.id = gi.test_id {where}").fetchall(),
        dtype=np.int64,
    ).reshape(-1, 2)
    if len(pairs):
        rows = np.array([gid_row[g] for g in pairs[:, 0].tolist()])
        membership[rows, pairs[:, 1] - 1] = True
    quals = conn.execute(
        f"SELECT q.group_id, substr(q.text, 1, {MAX_QUALIFIER_CHARS}) FROM qualifiers q JOIN groups g ON g.id = q.group_id "
        f"JOIN tests t ON t.id = g.test_id {where} ORDER BY q.id"
    ).fetchall()
    name = conn.execute("SELECT name FROM study").fetchone()[0]
    missed = attention_missed(source, [c for _, c in people], config.attention_checks)
    return StudyData(
        name=name,
        grammars=[n for _, n in grammars],
        participants=[c for _, c in people],
        pca=pca,
        variant=variant,
        params=params,
        test_grammar=np.array([gindex[g] for g in tests[:, 1].tolist()], dtype=np.int64),
        test_participant=np.array([pindex[p] for p in tests[:, 2].tolist()], dtype=np.int64),
        group_test=np.array([tindex[t] for t in cols[1]], dtype=np.int64),
        group_label=np.array(cols[2], dtype=np.int64),
        membership=membership,
        representative=np.array([0 if r is None else r for r in cols[3]], dtype=np.int64),
        usefulness=likert(cols[4]),
        difference=likert(cols[5]),
        representative_quality=likert(cols[6]),
        qualifier_group=np.array([gid_row[g] for g, _ in quals], dtype=np.int64),
        qualifier_text=[t for _, t in quals],
        test_seconds=seconds,
        attention_missed=missed,
    )


def attention_missed(study: Study, codes: list[str], checks: Sequence[Question]) -> np.ndarray:
    """Per participant of ``codes``: how many of the attention ``checks`` (the study config's)
    were answered with another option than the expected one (a check left unanswered on a
    stored page counts)."""
    out = np.zeros(len(codes), np.int64)
    if not checks:
        return out
    for i, code in enumerate(codes):
        page = study.participant_answers(code).get("attention")
        if page is not None:
            out[i] = sum(page.get(q.key) != q.answer for q in checks)
    return out


def params_of(data: StudyData, grammar: int, pick: int) -> dict:
    """The parameter combination (rule and constants) of a pick, as a dict."""
    return json.loads(data.params[grammar][pick - 1])
