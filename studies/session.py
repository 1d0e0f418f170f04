"""One participant's test on one grammar: sort, pick representatives, rate, name.

Every call is checked first and then written in its own transaction, together
with the time spent since the previous answer; a refused call changes nothing.
Front ends (desktop, Jupyter) drive a test only through this object.

>>> import tempfile, pathlib
>>> from ramure.studies.picks import lattice_picks
>>> from ramure.studies.storage import Study
>>> study = Study.create(pathlib.Path(tempfile.mkdtemp()) / "s.db",
...                      grammars={"honda": lattice_picks()})
>>> s = study.session(study.add_participant(consent=True), "honda")
>>> s.set_groups([range(1, 10), range(10, 27), [27]])
>>> s.set_representative(1, 5)
>>> s.rate(1, usefulness="good", difference=3, representative="excellent")
>>> s.add_qualifier(1, "Petit")
>>> s.set_groups([[1, 2, 3, 4, 5, 5]])
Traceback (most recent call last):
...
ramure.studies.errors.StudyInputError: image 5 is listed twice in group 1
>>> s.groups()[0].usefulness, s.missing()[0]
(3, 'group 2: choose a representative')
>>> study.close()
"""

from __future__ import annotations

import contextlib
import numbers
import sqlite3
import zlib
from dataclasses import asdict, dataclass, field

import numpy as np

from ramure.studies.errors import StudyInputError
from ramure.studies.likert import likert_value
from ramure.studies.picks import N_PICKS, PICK_IDS
from ramure.studies.records import MAX_QUALIFIER_CHARS, log_test_event, now_iso
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.studies.picks import Pick
    from ramure.studies.storage import Study


@dataclass
class Group:
    """A group as stored: ``label`` 1.., its images and answers (Likert 1-4 or None)."""

    label: int
    images: list
    representative: int | None = None
    usefulness: int | None = None
    difference: int | None = None
    representative_quality: int | None = None
    qualifiers: list = field(default_factory=list)


def image_order(seed: int, grammar: str) -> list[int]:
    """The seeded random order (a permutation of 1-27) shown to one participant.

    It depends on the participant's seed and on the grammar, never on the clock,
    so a resumed test shows the same order.

    >>> image_order(7, "honda") == image_order(7, "honda") != image_order(8, "honda")
    True
    """
    rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, zlib.crc32(grammar.encode())])
    return (rng.permutation(N_PICKS) + 1).tolist()


#: Letters and digits of the labels participants see (no I, O, 0 or 1, which look alike).
LABEL_LETTERS = "ABCDEFGHJKLMNPQRSTUVWXYZ"
LABEL_DIGITS = "23456789"


def picture_labels(seed: int, grammar: str) -> dict[int, str]:
    """The label shown under each pick to one participant: pick id -> a letter and a digit.

    Pick ids encode the PCA lattice (1-9 are PC1 low), so participants never see them:
    each sees codes drawn at random from the participant's stored seed and the grammar
    (another stream than :func:`image_order`), so the mapping is the same at each
    resume and can be rebuilt from the database; the answers keep pick ids.

    >>> a, b = picture_labels(7, "honda"), picture_labels(8, "honda")
    >>> a == picture_labels(7, "honda") and a != b and len(set(a.values())) == 27
    True
    """
    rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, zlib.crc32(grammar.encode()), 1])
    codes = rng.choice(len(LABEL_LETTERS) * len(LABEL_DIGITS), size=N_PICKS, replace=False)
    n = len(LABEL_DIGITS)
    return {pid: LABEL_LETTERS[int(c) // n] + LABEL_DIGITS[int(c) % n] for pid, c in zip(PICK_IDS, codes)}


def _check_partition(groups):
    """Validate ``groups`` (iterables of image ids) and return them as lists of ints."""
    if isinstance(groups, (str, bytes)) or not hasattr(groups, "__iter__"):
        raise StudyInputError("groups must be a list of groups, each a list of image numbers 1-27")
    checked: list[list[int]] = []
    owner: dict[int, int] = {}
    for label, group in enumerate(groups, start=1):
        if isinstance(group, (str, bytes)) or not hasattr(group, "__iter__"):
            raise StudyInputError(f"group {label} must be a list of image numbers 1-27, got {group!r}")
        images = list(group)
        if not images:
            raise StudyInputError(f"group {label} is empty; every group needs at least one image")
        seen = set()
        for image in images:
            if isinstance(image, bool) or not isinstance(image, numbers.Integral) or not 1 <= int(image) <= N_PICKS:
                raise StudyInputError(f"group {label}: {image!r} is not an image number 1-27")
            image = int(image)
            if image in seen:
                raise StudyInputError(f"image {image} is listed twice in group {label}")
            if image in owner:
                raise StudyInputError(f"image {image} is in two groups ({owner[image]} and {label})")
            seen.add(image)
            owner[image] = label
        checked.append(sorted(seen))
    return checked


def continued_groups(old: Sequence[Sequence[int]], new: Sequence[Sequence[int]]) -> dict[int, int]:
    """Which old group each new group continues: ``{new index: old index}`` (0-based).

    A new group continues the old group it shares the most images with; each old
    group is continued at most once, the largest overlaps first (ties: the older
    group, then the earlier new one).  So a group that gained or lost a few images
    keeps its answers, and of a split group the larger part does.

    >>> continued_groups([[1, 2, 3], [4, 5]], [[1, 2], [3, 4, 5]])  # image 3 moved
    {0: 0, 1: 1}
    >>> continued_groups([[1, 2, 3, 4]], [[1], [2, 3, 4]])  # split: the larger part continues
    {1: 0}
    """
    olds = [set(images) for images in old]
    pairs = sorted((-len(o & set(n)), i, j) for i, o in enumerate(olds) for j, n in enumerate(new) if o & set(n))
    result: dict[int, int] = {}
    used: set[int] = set()
    for _, i, j in pairs:
        if i not in used and j not in result:
            result[j] = i
            used.add(i)
    return dict(sorted(result.items()))


def _answered(group: Group) -> bool:
    """Whether ``group`` holds any answer beyond its images (a single's own representative aside)."""
    chosen = group.representative is not None and len(group.images) > 1
    ratings = (group.usefulness, group.difference, group.representative_quality)
    return chosen or any(r is not None for r in ratings) or bool(group.qualifiers)


class TestSession:
    """A participant's test on one grammar, backed by the study database.

    Obtain it with :meth:`ramure.studies.storage.Study.session`; the same call resumes
    an unfinished test.  Groups are addressed by their ``label`` (1, 2, ... in
    the order given to :meth:`set_groups`).
    """

    __test__ = False  # not a pytest class

    def __init__(self, study: Study, test_id: int, participant: str, grammar: str, seed: int, front_end: str = "script") -> None:
        self.study = study
        self.front_end = front_end  # stored with each answer
        self.conn = study.conn
        self.test_id = test_id
        self.participant = participant
        self.grammar = grammar
        self.seed = seed
        self._tick = study.clock()

    # -- reading ----------------------------------------------------------------
    def order(self) -> list[int]:
        """The image ids 1-27 in this participant's seeded display order."""
        return image_order(self.seed, self.grammar)

    def labels(self) -> dict[int, str]:
        """What this participant sees under each picture, by pick id (:func:`picture_labels`)."""
        return picture_labels(self.seed, self.grammar)

    def in_order(self, ids: Sequence[int]) -> list[int]:
        """``ids`` in this participant's display order (never by pick id, which encodes the lattice)."""
        rank = {pid: i for i, pid in enumerate(self.order())}
        return sorted(ids, key=lambda pid: rank.get(pid, N_PICKS))

    def picks(self) -> list[Pick]:
        """The 27 :class:`~ramure.studies.picks.Pick` of the grammar (image paths, params)."""
        return self.study.picks(self.grammar)

    @property
    def finished(self) -> bool:
        return self.conn.execute("SELECT finished_at FROM tests WHERE id = ?", (self.test_id,)).fetchone()[0] is not None

    def groups(self) -> list[Group]:
        """The groups as stored, by label, with their answers and qualifiers."""
        rows = self.conn.execute(
            "SELECT id, label, representative, usefulness, difference, representative_quality "
            "FROM groups WHERE test_id = ? ORDER BY label",
            (self.test_id,),
        ).fetchall()
        members: dict[int, list[int]] = {}
        names: dict[int, list[str]] = {}
        for gid, image in self.conn.execute(
            "SELECT group_id, pick_id FROM group_images WHERE test_id = ? ORDER BY pick_id", (self.test_id,)
        ):
            members.setdefault(gid, []).append(image)
        for gid, text in self.conn.execute(
            "SELECT q.group_id, q.text FROM qualifiers q JOIN groups g ON g.id = q.group_id WHERE g.test_id = ? ORDER BY q.id",
            (self.test_id,),
        ):
            names.setdefault(gid, []).append(text)
        return [Group(r[1], members.get(r[0], []), r[2], r[3], r[4], r[5], qualifiers=names.get(r[0], [])) for r in rows]

    def unsorted(self) -> list[int]:
        """Images not yet placed in a group."""
        placed = {r[0] for r in self.conn.execute("SELECT pick_id FROM group_images WHERE test_id = ?", (self.test_id,))}
        return [i for i in PICK_IDS if i not in placed]

    def missing(self) -> list[str]:
        """What is still to answer before :meth:`finish`, one line per item."""
        todo = []
        left = self.unsorted()
        if left:
            labels = self.labels()
            todo.append(f"pictures not in any group: {', '.join(labels[i] for i in self.in_order(left))}")
        for g in self.groups():
            several = len(g.images) > 1
            if several and g.representative is None:
                todo.append(f"group {g.label}: choose a representative")
            for name, value in (("usefulness", g.usefulness), ("difference", g.difference)):
                if value is None:
                    todo.append(f"group {g.label}: rate its {name}")
            if several and g.representative_quality is None:
                todo.append(f"group {g.label}: rate its representative")
            if not g.qualifiers:
                todo.append(f"group {g.label}: describe it in at least one word")
        return todo

    # -- time ---------------------------------------------------------------------
    def elapsed_seconds(self) -> float:
        """Time spent on this test: committed time plus time since the last answer."""
        stored = self.conn.execute("SELECT elapsed_seconds FROM tests WHERE id = ?", (self.test_id,)).fetchone()[0]
        return float(stored) + (0.0 if self.finished else self.study.clock() - self._tick)

    def remaining_seconds(self) -> float:
        """The participant's budget left over all their tests (never below 0).

        The budget is advisory while a test runs: answers are still accepted
        after it is spent, so nothing typed is lost; only new tests are refused.
        """
        pending = 0.0 if self.finished else self.study.clock() - self._tick
        return max(0.0, self.study.remaining_seconds(self.participant) - pending)

    # -- writing ------------------------------------------------------------------
    @contextlib.contextmanager
    def _write(self, action: str, detail: dict):
        """One transaction holding the change, the time spent since the last one and the
        event ``action`` with ``detail`` (which the change may still fill in)."""
        if self.finished:
            raise StudyInputError(
                "this set is finished; its answers can no longer change"  # read by participants: no grammar name
            )
        now = self.study.clock()
        try:
            with self.conn:
                yield self.conn
                self.conn.execute(
                    "UPDATE tests SET elapsed_seconds = elapsed_seconds + ? WHERE id = ?",
                    (max(0.0, now - self._tick), self.test_id),
                )
                log_test_event(self.conn, self.test_id, action, detail, self.front_end)
        except sqlite3.IntegrityError as exc:  # a check the validation above missed
            raise StudyInputError(f"answer refused by the database: {exc}") from None
        self._tick = now

    def _group(self, label):
        if isinstance(label, bool) or not isinstance(label, numbers.Integral):
            raise StudyInputError(f"group {label!r} must be a group number")
        row = self.conn.execute("SELECT id FROM groups WHERE test_id = ? AND label = ?", (self.test_id, int(label))).fetchone()
        if row is None:
            count = self.conn.execute("SELECT count(*) FROM groups WHERE test_id = ?", (self.test_id,)).fetchone()[0]
            have = f"groups 1-{count}" if count else "no groups yet"
            raise StudyInputError(f"group {label} does not exist (this test has {have})")
        images = [
            r[0] for r in self.conn.execute("SELECT pick_id FROM group_images WHERE group_id = ? ORDER BY pick_id", (row[0],))
        ]
        return row[0], images

    def set_groups(self, groups: Sequence[Sequence[int]]) -> None:
        """Replace the grouping with ``groups``: a list of groups of image ids 1-27.

        Images may stay unsorted until :meth:`finish`.  Moving images keeps the
        answers that still apply: each new group continues the old group it
        shares most images with (:func:`continued_groups`) and keeps its ratings
        and qualifiers under its new label; its representative is cleared (with
        its rating) only if it left the group.  Only old groups that no new group
        continues lose their answers; the event log keeps them.  A single-image
        group's representative is its image.
        Refused: an empty group, an image outside 1-27, an image twice.
        """
        checked = _check_partition(groups)
        before = self.groups()
        rows = self.conn.execute("SELECT id, label FROM groups WHERE test_id = ? ORDER BY label", (self.test_id,)).fetchall()
        gid_of = {label: gid for gid, label in rows}
        links = continued_groups([g.images for g in before], checked)
        detail: dict = {"groups": checked, "continued": {}, "dropped": [], "representative_cleared": []}
        with self._write("group", detail) as conn:
            conn.execute("DELETE FROM group_images WHERE test_id = ?", (self.test_id,))
            kept = {before[i].label for i in links.values()}
            dropped = [g for g in before if g.label not in kept]
            conn.executemany("DELETE FROM groups WHERE id = ?", [(gid_of[g.label],) for g in dropped])
            # Kept groups move to new labels: free the old ones first (labels are unique per test).
            conn.execute("UPDATE groups SET label = -label WHERE test_id = ?", (self.test_id,))
            for label, images in enumerate(checked, start=1):
                single = images[0] if len(images) == 1 else None
                if label - 1 not in links:
                    gid = conn.execute(
                        "INSERT INTO groups (test_id, label, representative) VALUES (?, ?, ?)", (self.test_id, label, single)
                    ).lastrowid
                else:
                    old = before[links[label - 1]]
                    gid = gid_of[old.label]
                    detail["continued"][label] = old.label
                    if len(old.images) > 1 and old.representative is not None and old.representative not in images:
                        detail["representative_cleared"].append(label)
                    chosen = old.representative if len(old.images) > 1 and old.representative in images else None
                    representative = single or chosen  # a single's own image was never chosen
                    conn.execute(
                        "UPDATE groups SET label = ?, representative = ?, representative_quality = "
                        "CASE WHEN ? IS NULL AND representative = ? THEN representative_quality END WHERE id = ?",
                        (label, representative, single, representative, gid),
                    )
                conn.executemany(
                    "INSERT INTO group_images (group_id, test_id, pick_id) VALUES (?, ?, ?)",
                    [(gid, self.test_id, image) for image in images],
                )
            detail["dropped"] = [asdict(g) for g in dropped if _answered(g)]

    def set_representative(self, group: int, image: int) -> None:
        """Choose ``image`` (which must be in ``group``) as the group's representative.

        Changing the representative clears its quality rating.
        """
        gid, images = self._group(group)
        if image not in images:
            raise StudyInputError(f"image {image!r} is not in group {group} (it holds {', '.join(map(str, images))})")
        with self._write("representative", {"group": int(group), "image": int(image)}) as conn:
            conn.execute(
                "UPDATE groups SET representative_quality = CASE WHEN representative = ? "
                "THEN representative_quality END, representative = ? WHERE id = ?",
                (int(image), int(image), gid),
            )

    def rate(self, group: int, usefulness: object = None, difference: object = None, representative: object = None) -> None:
        """Rate ``group`` on any of the three scales (1-4 or poor/fair/good/excellent).

        Only the scales given are written.  The representative's quality is
        rated only for groups of two or more images, once it is chosen.
        """
        gid, images = self._group(group)
        answers = {}
        for column, value in (("usefulness", usefulness), ("difference", difference), ("representative_quality", representative)):
            if value is not None:
                answers[column] = likert_value(value, f"group {group} {column.replace('_', ' ')}")
        if not answers:
            raise StudyInputError(f"group {group}: give at least one of usefulness, difference, representative")
        if "representative_quality" in answers:
            if len(images) == 1:
                raise StudyInputError(f"group {group} holds a single image; its representative is not rated")
            chosen = self.conn.execute("SELECT representative FROM groups WHERE id = ?", (gid,)).fetchone()[0]
            if chosen is None:
                raise StudyInputError(f"group {group}: choose its representative before rating it")
        with self._write("rate", {"group": int(group), **answers}) as conn:
            conn.execute(f"UPDATE groups SET {', '.join(f'{c} = ?' for c in answers)} WHERE id = ?", (*answers.values(), gid))

    def add_qualifier(self, group: int, text: str) -> None:
        """Add one free-text qualifier (French or English) to ``group``."""
        gid, _ = self._group(group)
        if not isinstance(text, str) or not text.strip():
            raise StudyInputError(f"group {group}: a description must be a non-empty word, got {text!r}")
        if len(text.strip()) > MAX_QUALIFIER_CHARS:
            raise StudyInputError(
                f"group {group}: a description is a word or a short phrase, at most {MAX_QUALIFIER_CHARS} characters"
            )
        with self._write("add_qualifier", {"group": int(group), "text": text.strip()}) as conn:
            conn.execute("INSERT INTO qualifiers (group_id, text) VALUES (?, ?)", (gid, text.strip()))

    def remove_qualifier(self, group: int, text: str) -> None:
        """Remove the qualifier ``text`` from ``group`` (refused if it is not there)."""
        gid, _ = self._group(group)
        row = self.conn.execute(
            "SELECT id FROM qualifiers WHERE group_id = ? AND text = ? ORDER BY id DESC", (gid, str(text).strip())
        ).fetchone()
        if row is None:
            raise StudyInputError(f"group {group} has no description {text!r}")
        with self._write("remove_qualifier", {"group": int(group), "text": str(text).strip()}) as conn:
            conn.execute("DELETE FROM qualifiers WHERE id = ?", (row[0],))

    def finish(self) -> None:
        """Mark the test finished; refused, listing what is missing, if incomplete."""
        todo = self.missing()
        if todo:
            raise StudyInputError("the test is not complete: " + "; ".join(todo))
        with self._write("finish", {}) as conn:
            conn.execute("UPDATE tests SET finished_at = ? WHERE id = ?", (now_iso(), self.test_id))
