"""Simulated participants, so the whole study pipeline runs without people.

A :class:`SimulatedParticipant` sees each image as its pick's point in PCA
space plus Gaussian "perception" noise, groups the points by Ward clustering
into a number of groups drawn around the thesis mean (5.2), and answers the
questionnaire from the geometry: compact groups are more useful, groups far
from the others more different, the representative is the image nearest the
group's centre.  Qualifiers come from where the group sits in the box (PC1 ->
small/large, PC2 -> sparse/dense, PC3 -> thin/thick, the centre -> normal,
plus round/fir-like/realistic at random), written in French or English with
random case, accents and plurals, so normalisation has work to do.

Everything goes through :class:`~ramure.studies.session.TestSession`, exactly like a
front end, so a simulation exercises storage and validation too.

>>> data = simulate_study(participants=2, grammars=1, seed=3)
>>> data.n_tests, bool(data.membership.sum(axis=0).min() == 2)
(2, True)
"""

from __future__ import annotations

import pathlib
import tempfile
from dataclasses import dataclass

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage

from ramure.studies.picks import synthetic_grammars
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.studies.data import StudyData
    from ramure.studies.session import TestSession
    from ramure.studies.storage import Study

# Surface forms per canonical qualifier: English, French, and misspelt/plural variants.  Each form
# must code back to its own name through the synonym table (a test checks it): "tall" written for
# *large* would be counted as *tall*, and the simulation could not recover its own ground truth.
_FORMS = {
    "small": ["small", "petit", "Petits", "petite", "tiny"],
    "large": ["large", "grand", "Grande", "big", "huge"],
    "sparse": ["sparse", "épars", "epars", "clairsemé", "peu dense"],
    "dense": ["dense", "Dense", "denses", "fourni", "full"],
    "thin": ["thin", "mince", "minces", "slender", "élancé"],
    "thick": ["thick", "gros", "grosse", "épais", "stout"],
    "normal": ["normal", "normale", "ordinaire", "typical"],
    "round": ["round", "rond", "ronde", "arrondi"],
    "fir-like": ["fir-like", "sapin", "Sapin de Noël", "conifer"],
    "symmetric": ["symmetric", "symétrique", "équilibré"],
    "asymmetric": ["asymmetric", "asymétrique", "penché"],
    "realistic": ["realistic", "réaliste", "naturel"],
    "unrealistic": ["unrealistic", "irréaliste", "bizarre"],
}
_FREE_TEXT = ["branches obliques et longues", "angles plus fermés", "comme un buisson", "weird spirals", "long trunk"]
_AXES = (("small", "large"), ("sparse", "dense"), ("thin", "thick"))


def _level(x):
    return int(np.clip(np.rint(x), 1, 4))


@dataclass
class SimulatedParticipant:
    """A participant model: grouping by PCA distance with noise, geometric answers.

    ``noise`` is the standard deviation of the perception noise as a fraction
    of the box's largest extent; ``mean_groups`` the mean number of groups.
    ``leniency_sd`` spreads the participants' own rating bias (in Likert points,
    drawn once per participant into ``leniency``): real raters differ in how
    generous they are, which is why the analysis takes participants as its unit.
    ``said`` records each qualifier written, as (text, intended name) pairs.
    """

    noise: float = 0.15
    mean_groups: float = 5.2
    max_groups: int = 9
    seed: int = 0
    leniency_sd: float = 0.4

    def __post_init__(self):
        self.rng = np.random.default_rng(self.seed)
        # its own stream, so the sorting and answers draw the same numbers as before it existed
        self.leniency = float(np.random.default_rng([self.seed, 1]).normal(0.0, self.leniency_sd))
        self.said: list[tuple[str, str | None]] = []

    def sort(self, points: np.ndarray) -> list:
        """Groups (lists of pick ids 1-27) for the 27 ``points`` (27 x 3)."""
        points = np.asarray(points, dtype=float)
        scale = np.ptp(points, axis=0).max() or 1.0
        seen = points / scale + self.rng.normal(0.0, self.noise, size=points.shape)
        k = int(np.clip(np.rint(self.rng.normal(self.mean_groups, 1.5)), 2, self.max_groups))
        labels = fcluster(linkage(seen, "ward"), k, criterion="maxclust")
        groups = [sorted((np.flatnonzero(labels == lab) + 1).tolist()) for lab in np.unique(labels)]
        self.rng.shuffle(groups)
        return groups

    def answer(self, session: TestSession, points: np.ndarray, shift: float = 0.0) -> None:
        """Do a whole test through ``session`` and finish it.

        ``shift`` (Likert points) is added to every usefulness answer before
        rounding: the simulated effect of this grammar, which an analysis should recover.
        """
        points = np.asarray(points, dtype=float)
        scale = np.ptp(points, axis=0).max() or 1.0
        unit = (points - points.mean(axis=0)) / scale
        box = (points - points.min(axis=0)) / np.where(np.ptp(points, axis=0) > 0, np.ptp(points, axis=0), 1.0) * 2 - 1
        groups = self.sort(points)
        session.set_groups(groups)
        centres = np.array([unit[np.array(g) - 1].mean(axis=0) for g in groups])
        for label, images in enumerate(groups, start=1):
            idx = np.array(images) - 1
            spread = np.linalg.norm(unit[idx] - centres[label - 1], axis=1).mean()
            others = np.delete(centres, label - 1, axis=0)
            gap = np.linalg.norm(others - centres[label - 1], axis=1).min() if len(others) else 1.0
            usefulness = _level(3.9 - 5.0 * spread + shift + self.leniency + self.rng.normal(0, 0.7))
            difference = _level(1.2 + 4.0 * gap + self.leniency + self.rng.normal(0, 0.7))
            if len(images) > 1:
                nearest = images[int(np.argmin(np.linalg.norm(unit[idx] - centres[label - 1], axis=1)))]
                good = self.rng.random() < 0.8
                session.set_representative(label, nearest if good else int(self.rng.choice(images)))
                session.rate(label, representative=_level((3.6 if good else 2.2) + self.rng.normal(0, 0.6)))
            session.rate(label, usefulness=usefulness, difference=difference)
            for text in self.qualifiers(box[idx].mean(axis=0), usefulness):
                session.add_qualifier(label, text)
        session.finish()

    def qualifiers(self, where: np.ndarray, usefulness: int) -> list:
        """1-4 qualifier texts for a group centred at ``where`` (box coords in [-1, 1])."""
        names = []
        order = np.argsort(-np.abs(where))
        for axis in order:
            if abs(where[axis]) > 0.35 and self.rng.random() < 0.85:
                names.append(_AXES[axis][int(where[axis] > 0)])
        if not names:
            names.append("normal")
        for name, chance in (("round", 0.15), ("fir-like", 0.1), ("symmetric", 0.1), ("asymmetric", 0.08)):
            if self.rng.random() < chance:
                names.append(name)
        if self.rng.random() < 0.3:
            names.append("realistic" if usefulness >= 3 else "unrealistic")
        said: list[tuple[str, str | None]] = [(str(self.rng.choice(_FORMS[n])), n) for n in names[:3]]
        if self.rng.random() < 0.1:
            said.append((str(self.rng.choice(_FREE_TEXT)), None))
        self.said += said
        return [text for text, _ in said]


class SimulatedClock:
    """A clock that stands still until moved: simulated time on task, not the machine's."""

    def __init__(self, start: float = 0.0) -> None:
        self.now = float(start)

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += float(seconds)


def run_simulation(
    study: Study,
    participants: int = 20,
    tests_per_participant: int | None = None,
    noise: float = 0.15,
    seed: int = 0,
    effects: Mapping[str, float] | None = None,
    test_minutes: float = 4.0,
) -> list:
    """Add ``participants`` simulated participants to ``study``, each doing tests.

    Each does ``tests_per_participant`` grammars drawn at random (default:
    every grammar), in random order.  ``effects`` maps grammar names to a shift
    of the usefulness answers (Likert points; others 0).  Each test takes a
    log-normal time with median ``test_minutes`` on a simulated clock (shortened so
    that every test fits the study's time budget), so time on task is recorded as
    people would spend it.  Returns the new participant codes.
    """
    rng = np.random.default_rng(seed)
    grammars = study.grammars
    effects = dict(effects or {})
    unknown = sorted(set(effects) - set(grammars))
    if unknown:
        from ramure.studies.errors import StudyInputError

        raise StudyInputError(f"effects name grammars not in the study: {', '.join(unknown)} (known: {', '.join(grammars)})")
    points = {g: np.array([p.pca for p in study.picks(g)]) for g in grammars}
    count = len(grammars) if tests_per_participant is None else min(int(tests_per_participant), len(grammars))
    codes = []
    # Time on task within the participant's budget, as the front ends keep it.
    longest = 0.95 * study.budget_seconds / max(count, 1)
    median = min(60.0 * test_minutes, 0.6 * longest)
    machine_clock, clock = study.clock, SimulatedClock(study.clock())
    study.clock = clock
    try:
        for n in range(int(participants)):
            code = study.add_participant(consent=True)
            person = SimulatedParticipant(noise=noise, seed=int(rng.integers(2**31)))
            for grammar in rng.permutation(grammars)[:count].tolist():
                session = study.session(code, grammar, front_end="simulated")
                clock.advance(min(median * float(np.exp(rng.normal(0.0, 0.35))), longest))
                person.answer(session, points[grammar], effects.get(grammar, 0.0))
            codes.append(code)
    finally:
        study.clock = machine_clock
    return codes


def simulate_study(
    db: str | os.PathLike | None = None,
    participants: int = 20,
    grammars: int | dict = 3,
    tests_per_participant: int | None = None,
    noise: float = 0.15,
    seed: int = 0,
    name: str = "simulated",
    effects: Mapping[str, float] | None = None,
) -> StudyData:
    """Create a study, run simulated participants, and return its :class:`StudyData`.

    ``grammars`` is a number of synthetic grammars or a mapping accepted by
    :meth:`~ramure.studies.storage.Study.create`; ``effects`` as in :func:`run_simulation`.  Without ``db`` a temporary file is
    used and removed.  Writes use ``synchronous=NORMAL`` for speed.
    """
    from ramure.studies.data import load_study_data
    from ramure.studies.storage import Study

    if isinstance(grammars, int):
        grammars = synthetic_grammars(grammars, seed=seed)
    tmp = None
    if db is None:
        tmp = tempfile.TemporaryDirectory()
        db = pathlib.Path(tmp.name) / "simulated.db"
    try:
        with Study.create(db, grammars=grammars, name=name, durable=False) as study:
            run_simulation(study, participants, tests_per_participant, noise, seed, effects)
            return load_study_data(study)
    finally:
        if tmp is not None:
            tmp.cleanup()
