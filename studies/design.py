"""What participants see, the same in every front end: texts, questions, order and pages.

A study's design is a :class:`StudyConfig`: the consent (with a contact and how long the data
are kept), the instructions, a practice page, attention checks, demographics questions and the
Likert wording and levels.  Every field has a default; a researcher changes any of them with a
JSON file (:func:`read_config`), checked field by field.  The desktop, the notebook and the web
pages all read their words from here, never from their own copies, and none of the words a
participant reads says "grammar", "variant" or "qualifier".

The order of the picture sets follows a balanced Latin square (:func:`latin_square`), one row
per participant in order of arrival; :class:`ParticipantFlow` says which page comes next, from
what is stored, so a front end only shows pages and passes answers back.

>>> config = config_from_data({"likert": {"levels": ["no", "a little", "rather", "very"]}})
>>> config.levels, config.questions["usefulness"][:28]
(('no', 'a little', 'rather', 'very'), 'How useful is this group for')
>>> latin_square(4)
[[0, 1, 3, 2], [1, 2, 0, 3], [2, 3, 1, 0], [3, 0, 2, 1]]
>>> split_words("dense, taller;  bushy ")
['dense', 'taller', 'bushy']
"""

from __future__ import annotations

import dataclasses
import numbers
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ramure.errors import RamureError
from ramure.io import read_json
from ramure.studies.errors import StudyInputError

if TYPE_CHECKING:
    from ramure.studies.session import TestSession
    from ramure.studies.storage import Study

#: Largest study config file read (bytes).
MAX_CONFIG_BYTES = 1 << 20
#: Words participants never read: they are the researcher's, not theirs.
JARGON = ("grammar", "variant", "qualifier")
#: The front ends that record answers (stored with each answer).
FRONT_ENDS = ("desktop", "notebook", "web", "simulated", "script")
#: How the 27 pictures of a set are framed: ``shared`` (one scale per set, with a scale bar, so
#: size shows) or ``own`` (each plant on its own bounds: size is invisible).
FRAMINGS = ("shared", "own")

DEFAULT_CONSENT = (
    "You will see sets of 27 pictures of plants. For each set, sort the pictures into groups "
    "of pictures that look alike to you, choose one picture that best stands for each group, "
    "answer three short questions per group and give each group one or more words that describe it.\n\n"
    "Your answers are stored under an anonymous code, each as soon as you give it. Taking part "
    "is voluntary: you can stop at any time, and you can withdraw later; your answers are then "
    "deleted."
)
DEFAULT_INSTRUCTIONS = (
    "Drag pictures onto “New group” to start a group, and between groups to move them. "
    "Click a picture to see it larger. There are no right or wrong answers: group the plants "
    "as they look to you."
)
DEFAULT_PRACTICE = (
    "Practice: before the real sets, look at how a group is made. Drag two pictures that look "
    "alike onto “New group”, then a third one onto that group. Nothing you do in the practice "
    "is kept apart from the time it took."
)
DEFAULT_LEVELS = ("poor", "fair", "good", "excellent")
DEFAULT_QUESTIONS = {
    "usefulness": "How useful is this group for telling these plants apart?",
    "difference": "How different are the pictures of this group from those of the other groups?",
    "representative": "How well does the chosen picture stand for its group?",
}
#: What participants read for each step (the same in every front end).
WORDS = {
    "set": "Set",
    "finish": "Finish this set",
    "new_group": "New group",
    "group": "Group",
    "words": "Words for this group",
    "words_hint": "one or more words (e.g. dense, petit), separated by commas; then Enter",
    "representative": "The picture that best stands for this group",
    "sort": "Sort the plants: give each picture a group; plants in a group look alike, groups look different "
    "(a group may hold one picture).",
    "answer": "For each group: choose the picture that best stands for it, answer the questions and describe it in words.",
    "saved": "Your answers are saved.",
}


@dataclass(frozen=True)
class Question:
    """One question on a page: its ``key`` (stored), ``text`` and ``options`` (empty: free text).

    ``answer`` is the expected option of an attention check (None elsewhere).
    """

    key: str
    text: str
    options: tuple[str, ...] = ()
    answer: str | None = None
    required: bool = True


@dataclass(frozen=True)
class StudyConfig:
    """A study's texts and design, with defaults (see the module docstring)."""

    title: str = "Plants that look alike"
    consent: str = DEFAULT_CONSENT
    contact: str = "the researcher who invited you"
    retention: str = "Your answers are kept for five years, then deleted."
    instructions: str = DEFAULT_INSTRUCTIONS
    practice: str | None = DEFAULT_PRACTICE
    attention_checks: tuple[Question, ...] = (
        Question("attention_1", "To show that you read the questions, choose “fair” here.", DEFAULT_LEVELS, "fair"),
    )
    demographics: tuple[Question, ...] = (
        Question("age", "Your age group", ("under 25", "25-39", "40-59", "60 or over", "I prefer not to say")),
        Question(
            "expertise",
            "How familiar are you with plants (gardening, botany, forestry)?",
            ("not at all", "a little", "quite", "very", "I prefer not to say"),
        ),
    )
    levels: tuple[str, ...] = DEFAULT_LEVELS
    questions: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_QUESTIONS))
    completion_code: str | None = None
    framing: str = "shared"
    #: A grammar of the study sorted first, as practice: never in the Latin square, never analysed.
    practice_set: str | None = None

    def consent_text(self) -> str:
        """The consent as participants read it: the text, then the contact and the data retention."""
        return f"{self.consent}\n\nContact: {self.contact}.\n\n{self.retention}"

    def to_data(self) -> dict[str, Any]:
        """Plain JSON data that :func:`config_from_data` reads back to an equal config."""
        data = dataclasses.asdict(self)
        data["questions"] = dict(self.questions)
        data["likert"] = {"levels": list(data.pop("levels")), **data.pop("questions")}
        for key in ("attention_checks", "demographics"):
            data[key] = [{k: list(v) if k == "options" else v for k, v in q.items() if v is not None} for q in data[key]]
        return data


_TEXT_FIELDS = ("title", "consent", "contact", "retention", "instructions", "completion_code", "practice", "practice_set")
_OPTIONAL = ("completion_code", "practice", "practice_set")
_CODE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


def _text(value: object, where: str, optional: bool = False) -> str | None:
    if value is None and optional:
        return None
    if not isinstance(value, str) or not value.strip():
        raise StudyInputError(f"{where}: expected non-empty text, got {value!r}" + (" (or null)" if optional else ""))
    if len(value) > 20000:
        raise StudyInputError(f"{where}: text longer than 20000 characters")
    return value.strip()


def _questions(items: object, where: str, check: bool) -> tuple[Question, ...]:
    if not isinstance(items, list):
        raise StudyInputError(f"{where}: expected a list of questions")
    out: list[Question] = []
    for i, item in enumerate(items):
        at = f"{where}[{i}]"
        if not isinstance(item, dict):
            raise StudyInputError(f"{at}: expected an object with 'key' and 'text'")
        unknown = set(item) - {"key", "text", "options", "answer", "required"}
        if unknown:
            raise StudyInputError(f"{at}: unknown field {sorted(unknown)[0]!r} (known: key, text, options, answer, required)")
        key = _text(item.get("key"), f"{at}.key")
        assert key is not None  # not optional
        if not re.match(r"^[a-z][a-z0-9_]{0,31}$", key):
            raise StudyInputError(f"{at}.key: {key!r} must be 1-32 lower-case letters, digits or '_', starting with a letter")
        if key in {q.key for q in out}:
            raise StudyInputError(f"{at}.key: {key!r} is used twice")
        options = item.get("options", [])
        if not isinstance(options, list) or not all(isinstance(o, str) and o.strip() for o in options):
            raise StudyInputError(f"{at}.options: expected a list of non-empty texts")
        answer = item.get("answer")
        if check and (answer is None or answer not in options):
            raise StudyInputError(f"{at}.answer: an attention check needs 'answer', one of its options {options}")
        if not check and answer is not None:
            raise StudyInputError(f"{at}.answer: only attention checks have an expected answer")
        required = item.get("required", True)
        if not isinstance(required, bool):
            raise StudyInputError(f"{at}.required: expected true or false")
        out.append(Question(key, str(_text(item.get("text"), f"{at}.text")), tuple(o.strip() for o in options), answer, required))
    return tuple(out)


def config_from_data(data: object, where: str = "study config") -> StudyConfig:
    """Check plain data (a JSON object) into a :class:`StudyConfig`; missing fields keep their defaults.

    Refused with one line naming the field: an unknown field, a wrong type, Likert levels that
    are not four texts, a question without text, an attention check whose answer is not one of
    its options.
    """
    if not isinstance(data, dict):
        raise StudyInputError(f"{where}: expected a JSON object")
    known = {f.name for f in dataclasses.fields(StudyConfig)} - {"levels", "questions"} | {"likert"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise StudyInputError(f"{where}: unknown field {unknown[0]!r} (known: {', '.join(sorted(known))})")
    values: dict[str, Any] = {}
    for key in _TEXT_FIELDS:
        if key in data:
            values[key] = _text(data[key], f"{where}.{key}", optional=key in _OPTIONAL)
    code = values.get("completion_code")
    if code is not None and not _CODE.match(code):
        raise StudyInputError(f"{where}.completion_code: {code!r} must be 1-64 letters, digits, '-' or '_'")
    if "framing" in data and data["framing"] not in FRAMINGS:
        raise StudyInputError(f"{where}.framing: {data['framing']!r} is not one of {', '.join(FRAMINGS)}")
    if "framing" in data:
        values["framing"] = data["framing"]
    if "attention_checks" in data:
        values["attention_checks"] = _questions(data["attention_checks"], f"{where}.attention_checks", check=True)
    if "demographics" in data:
        values["demographics"] = _questions(data["demographics"], f"{where}.demographics", check=False)
    if "likert" in data:
        values.update(_likert(data["likert"], f"{where}.likert"))
    return StudyConfig(**values)


def _likert(data: object, where: str) -> dict[str, Any]:
    if not isinstance(data, dict):
        raise StudyInputError(f"{where}: expected an object with 'levels' and the questions")
    unknown = sorted(set(data) - {"levels", *DEFAULT_QUESTIONS})
    if unknown:
        raise StudyInputError(f"{where}: unknown field {unknown[0]!r} (known: levels, {', '.join(DEFAULT_QUESTIONS)})")
    out: dict[str, Any] = {}
    if "levels" in data:
        levels = data["levels"]
        if not isinstance(levels, list) or len(levels) != 4 or not all(isinstance(x, str) and x.strip() for x in levels):
            raise StudyInputError(f"{where}.levels: expected the 4 level names, lowest first (answers are stored as 1-4)")
        if len({x.strip().casefold() for x in levels}) != 4:
            raise StudyInputError(f"{where}.levels: the 4 level names must differ")
        out["levels"] = tuple(x.strip() for x in levels)
    questions = dict(DEFAULT_QUESTIONS)
    for key in DEFAULT_QUESTIONS:
        if key in data:
            questions[key] = str(_text(data[key], f"{where}.{key}"))
    out["questions"] = questions
    return out


def read_config(path: str | os.PathLike) -> StudyConfig:
    """Read and check a study config JSON file (see :func:`config_from_data`)."""
    try:
        data = read_json(path, MAX_CONFIG_BYTES, "study config")
    except RamureError as exc:
        raise StudyInputError(str(exc)) from None
    return config_from_data(data, where=str(path))


def jargon_in(text: str) -> list[str]:
    """The researcher's words (:data:`JARGON`) found in ``text``, which participants should not read.

    >>> jargon_in("Finish this grammar"), jargon_in("Finish this set")
    (['grammar'], [])
    """
    low = text.casefold()
    return [word for word in JARGON if word in low]


def split_words(text: str) -> list[str]:
    """The words a participant typed for a group: split at commas and semicolons, trimmed, no repeats.

    Every front end stores what this returns, so "dense, taller" is two descriptions everywhere.
    """
    seen: list[str] = []
    for part in re.split(r"[,;\n]", str(text)):
        word = " ".join(part.split())
        if word and word not in seen:
            seen.append(word)
    return seen


def latin_square(n: int) -> list[list[int]]:
    """A balanced Latin square (Williams design) of ``n`` conditions: each row an order of ``0..n-1``.

    Every condition comes in every position equally often and, for even ``n``, follows every
    other condition once; for odd ``n`` the square is followed by its mirror (``2n`` rows), which
    balances the carry-over too.

    >>> latin_square(3)
    [[0, 1, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0], [0, 2, 1], [1, 0, 2]]
    """
    if n < 1:
        return []
    first = [0]
    low, high = 1, n - 1
    while len(first) < n:
        first.append(low)
        low += 1
        if len(first) < n:
            first.append(high)
            high -= 1
    rows = [[(c + r) % n for c in first] for r in range(n)]
    return rows + [row[::-1] for row in rows] if n % 2 else rows


def grammar_order(grammars: Sequence[str], index: int) -> list[str]:
    """The order of ``grammars`` for the participant who arrived ``index``-th (0-based): a row of
    :func:`latin_square`, cycled.

    >>> grammar_order(["a", "b", "c"], 0), grammar_order(["a", "b", "c"], 4)
    (['a', 'b', 'c'], ['a', 'c', 'b'])
    """
    if isinstance(index, bool) or not isinstance(index, numbers.Integral) or index < 0:
        raise StudyInputError(f"participant index {index!r} must be a non-negative integer")
    rows = latin_square(len(grammars))
    return [grammars[i] for i in rows[int(index) % len(rows)]] if rows else []


@dataclass(frozen=True)
class Step:
    """One page of a participant's flow (see :class:`ParticipantFlow`).

    ``kind``: ``consent``, ``instructions``, ``practice``, ``attention``, ``demographics``,
    ``test`` (``grammar`` set, ``number`` of ``total``) or ``done``.
    """

    kind: str
    title: str
    text: str = ""
    questions: tuple[Question, ...] = ()
    grammar: str | None = None
    number: int = 0
    total: int = 0
    skipped: tuple[str, ...] = ()


def set_title(number: int, total: int) -> str:
    """``"Set 1 of 3"``: what participants read for a test (never the grammar's name)."""
    return f"{WORDS['set']} {number} of {total}"


class ParticipantFlow:
    """The pages of one participant, in order, worked out from what the study stores.

    Consent, the instructions, the practice page, then each picture set in the participant's
    order (:meth:`ramure.studies.storage.Study.grammar_order`), the attention checks after the
    first set, the demographics questions, and the last page with the completion code.  Sets the
    time budget no longer allows are skipped and named on the last page, never silently.

    A front end shows :meth:`step` and calls :meth:`consent`, :meth:`acknowledge`, :meth:`answer`
    or drives :meth:`session` for a test, then asks :meth:`step` again.
    """

    def __init__(self, study: Study, code: str, front_end: str = "script") -> None:
        self.study, self.code, self.front_end = study, str(code), front_end
        self.config = study.config()

    @property
    def grammars(self) -> list[str]:
        """The participant's sets, in their order."""
        return self.study.grammar_order(self.code)

    def number(self, grammar: str) -> tuple[int, int]:
        """``(n, m)``: ``grammar`` is set n of the participant's m (n is 0 for the practice set)."""
        order = self.grammars
        return (order.index(grammar) + 1 if grammar in order else 0), len(order)

    def title(self, grammar: str) -> str:
        """What participants read for a set: "Set 2 of 3", or "Practice"."""
        n, m = self.number(grammar)
        return set_title(n, m) if n else "Practice"

    def _done(self, page: str) -> bool:
        return page in self.study.participant_answers(self.code)

    def step(self) -> Step:
        """The page to show now."""
        c = self.config
        if not self.study.has_consent(self.code):
            return Step("consent", c.title, c.consent_text())
        if not self._done("instructions"):
            return Step("instructions", "Instructions", c.instructions)
        if c.practice and not self._done("practice"):
            return Step("practice", "Practice", c.practice)
        practice = c.practice_set
        if practice and practice in self.study.grammars and not self.study.finished(self.code, practice):
            return Step("test", "Practice", c.practice or "", grammar=practice, number=0, total=len(self.grammars))
        order = self.grammars
        finished = [g for g in order if self.study.finished(self.code, g)]
        if c.attention_checks and finished and not self._done("attention"):
            return Step("attention", "A few questions", "", c.attention_checks)
        for grammar in order:
            if self.study.finished(self.code, grammar):
                continue
            if self.study.started(self.code, grammar) or self.study.remaining_seconds(self.code) > 0:
                n, m = self.number(grammar)
                return Step("test", set_title(n, m), c.instructions, grammar=grammar, number=n, total=m)
        if c.attention_checks and not self._done("attention"):
            return Step("attention", "A few questions", "", c.attention_checks)
        if c.demographics and not self._done("demographics"):
            return Step("demographics", "About you", "", c.demographics)
        return self._last_page()

    def _last_page(self) -> Step:
        order = self.grammars
        skipped = tuple(g for g in order if not self.study.finished(self.code, g))
        text = "Thank you! " + WORDS["saved"]
        if skipped:
            shown = ", ".join(set_title(*self.number(g)).lower() for g in skipped)
            text += f" Your time was up, so {shown} {'was' if len(skipped) == 1 else 'were'} not shown."
        code = self.study.completion_code(self.code)
        if code:
            text += f"\n\nYour completion code: {code}"
        return Step("done", "Thank you", text, skipped=skipped)

    def consent(self) -> None:
        """Record consent (the consent page's "I agree")."""
        self.study.record_consent(self.code, True)

    def acknowledge(self, kind: str) -> None:
        """The participant read the ``instructions`` or did the ``practice``."""
        if kind not in ("instructions", "practice"):
            raise StudyInputError(f"{kind!r} is not a page to acknowledge (instructions, practice)")
        self.study.record_answers(self.code, kind, {"read": True})

    def answer(self, kind: str, answers: Mapping[str, str]) -> None:
        """Store the answers of the ``attention`` or ``demographics`` page, checked against its questions."""
        questions = {"attention": self.config.attention_checks, "demographics": self.config.demographics}.get(kind)
        if questions is None:
            raise StudyInputError(f"{kind!r} is not a page of questions (attention, demographics)")
        self.study.record_answers(self.code, kind, check_answers(questions, answers))

    def session(self, grammar: str) -> TestSession:
        """The test of the participant on ``grammar`` (started or resumed), recording this front end."""
        return self.study.session(self.code, grammar, front_end=self.front_end)


def check_answers(questions: Sequence[Question], answers: Mapping[str, str]) -> dict[str, str]:
    """``answers`` checked against ``questions``: each key known, each option one of its options,
    every required question answered; refused with one line naming the question."""
    if not isinstance(answers, Mapping):
        raise StudyInputError("answers must be a mapping of question key to answer")
    keys = {q.key: q for q in questions}
    out: dict[str, str] = {}
    for key, value in answers.items():
        if key not in keys:
            raise StudyInputError(f"no question {key!r} on this page (questions: {', '.join(keys)})")
        q = keys[key]
        if not isinstance(value, str):
            raise StudyInputError(f"{q.text}: expected text, got {value!r}")
        value = value.strip()
        if q.options and value and value not in q.options:
            raise StudyInputError(f"{q.text}: {value!r} is not one of {', '.join(q.options)}")
        if len(value) > 500:
            raise StudyInputError(f"{q.text}: at most 500 characters")
        if value:
            out[key] = value
    missing = [q.text for q in questions if q.required and q.key not in out]
    if missing:
        raise StudyInputError(f"please answer: {missing[0]}")
    return out


def passed_attention(config: StudyConfig, answers: Mapping[str, str]) -> bool:
    """Whether ``answers`` (of the attention page) give every check's expected answer."""
    return all(answers.get(q.key) == q.answer for q in config.attention_checks)
