"""A study as a jsPsych experiment for hosted platforms (JATOS, Pavlovia), and its results imported back.

:func:`export_jspsych` writes a folder that runs as it is: ``index.html``, the task
(``ramure-task.js``, two jsPsych plugins of Ramure's own), its settings (``ramure-config.js``:
title, consent, questions, levels, the stimulus sets) and the pictures (``img/CODE.png``).  Pictures
are named by codes, an HMAC of the grammar and pick under the study's web secret
(:func:`ramure.studies.serve.study_secret`, kept beside the database, never exported), so neither
a file name nor the page gives away a pick number (pick numbers encode the PCA lattice).  jsPsych
itself is loaded from :data:`JSPSYCH_CDN` unless a local copy is given (then it is copied in and
the folder works offline, from ``file://`` too).  Ramure itself never goes on the network.

Each participant (a *run*) does the consent page, then one jsPsych trial per stimulus set, in a
random order: sort the 27 pictures into groups, then for each group choose a representative, answer
the questions and give words.  On JATOS the data is submitted with ``jatos.js``; elsewhere the page
offers it as a download, or calls ``window.ramureSave(jsPsych)`` if a platform's page defines it.

:func:`import_jspsych` reads result files (jsPsych's JSON, JATOS's one array per line, or jsPsych's
CSV), checks all of it (the study it came from, every picture code, a whole partition, every answer,
runs not imported before) and only then stores each run as a new participant through
:class:`~ramure.studies.session.TestSession`, with the page's times; a bad file is refused in one
line and nothing is written.
"""

from __future__ import annotations

import csv
import hashlib
import hmac
import io
import json
import numbers
import os
import pathlib
import re
import sqlite3
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from ramure.errors import RamureError
from ramure.io import read_regular, write_bytes, write_text
from ramure.studies.errors import StudyInputError
from ramure.studies.likert import LEVELS
from ramure.studies.picks import N_PICKS
from ramure.studies.qualifiers import MAX_QUALIFIER_CHARS

#: Where the exported page loads jsPsych from when no local copy is given (the version the task is written for).
JSPSYCH_VERSION = "8.3.0"
JSPSYCH_CDN = f"https://unpkg.com/jspsych@{JSPSYCH_VERSION}"
#: Largest results file read (bytes): a run is about 10 KB, so this holds thousands.
MAX_RESULTS_BYTES = 64 << 20
#: Size the pictures are shown at on the page (CSS pixels).
PICTURE_PIXELS = 120
_RUN = re.compile(r"^[0-9a-f]{8,64}$")
_PNG = b"\x89PNG\r\n\x1a\n"


def _mac(secret: bytes, text: str) -> str:
    return hmac.new(secret, text.encode(), hashlib.sha256).hexdigest()


def study_mark(secret: bytes) -> str:
    """The mark every trial of the study's export carries (results of another study are refused)."""
    return _mac(secret, "jspsych-study")[:16]


def picture_codes(secret: bytes, grammar: str) -> dict[int, str]:
    """Pick id -> the code naming its picture in the export (12 hex digits; no pick number in it)."""
    return {pid: _mac(secret, f"jspsych-picture:{grammar}:{pid}")[:12] for pid in range(1, N_PICKS + 1)}


def jspsych_completion_code(secret: bytes) -> str:
    """The completion code the exported page shows at the end (one per study, as platforms expect)."""
    return _mac(secret, "jspsych-complete")[:10].upper()


def _study_secret(db: str | os.PathLike, create: bool) -> bytes:
    from ramure.studies.serve import secret_path, study_secret

    if not create and not secret_path(db).exists():
        raise StudyInputError(
            f"{db}: no jsPsych export was made from this study (its web secret {secret_path(db).name} is missing), "
            "so these results cannot be from it"
        )
    return study_secret(db)


# -- export --------------------------------------------------------------------------------------------


def _task_file(name: str) -> bytes:
    return resources.files(__package__).joinpath("jspsych", name).read_bytes()


_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<!-- jsPsych {version}: {where}.  ramure-task.js holds the task, ramure-config.js its settings. -->
<link rel="stylesheet" href="{css}">
<style>
.ramure {{ max-width: 1100px; margin: 0 auto; text-align: left; }}
.ramure-pool, .ramure-group {{ display: flex; flex-wrap: wrap; gap: 6px; }}
fieldset.ramure-group {{ margin: 8px 0; }}
.ramure-pic {{ display: inline-flex; flex-direction: column; align-items: center; padding: 2px; border: 3px solid transparent;
  background: #fff; cursor: pointer; }}
.ramure-pic.selected {{ border-color: #1565c0; }}
.ramure-pic img {{ width: {size}px; height: {size}px; object-fit: contain; }}
.ramure-scale {{ margin: 6px 0; }}
</style>
</head>
<body>
<script src="jatos.js"></script>
<script src="{js}"></script>
<script src="ramure-config.js"></script>
<script src="ramure-task.js"></script>
</body>
</html>
"""

_README = """A Ramure study as a jsPsych {version} experiment: {title}

Open index.html in a browser to try it.  Upload this whole folder:
- JATOS: a new study, one component with index.html as its HTML file (jatos.js is served by JATOS;
  the answers are submitted to JATOS at the end).  Export the results as JSON ("Export Results > Data").
- Pavlovia: the folder as the experiment's html/ folder; define window.ramureSave(jsPsych) in
  index.html to save with Pavlovia's jsPsych plugin (otherwise the page offers the answers as a download).
jsPsych is loaded from {where}.
A PROLIFIC_PID (or participant) in the page's URL is kept with the answers.  Completion code: {code}.

Import the results into the study (checked first; a bad file changes nothing):
    ramure study import-jspsych STUDY.db RESULTS.json   (or .csv, or JATOS's results file)
"""


def _local_jspsych(source: pathlib.Path) -> tuple[bytes, bytes]:
    js, css = source / "dist" / "index.browser.min.js", source / "css" / "jspsych.css"
    if not js.is_file() or not css.is_file():
        raise StudyInputError(f"{source}: not a jsPsych package folder (no dist/index.browser.min.js and css/jspsych.css)")
    return js.read_bytes(), css.read_bytes()


def _check_folder(folder: pathlib.Path) -> None:
    if folder.exists() and not folder.is_dir():
        raise StudyInputError(f"{folder}: exists and is not a folder")
    if folder.is_dir() and any(folder.iterdir()) and not (folder / "ramure-config.js").is_file():
        raise StudyInputError(f"{folder}: not empty and not a Ramure jsPsych export; choose a new folder")


def export_jspsych(db: str | os.PathLike, folder: str | os.PathLike, jspsych: str | os.PathLike | None = None) -> dict:
    """Write study ``db`` as a jsPsych experiment into ``folder``; returns what was written.

    ``jspsych``: None (load jsPsych from :data:`JSPSYCH_CDN`), a URL of a jsPsych package, or a local
    jsPsych package folder (``node_modules/jspsych``), copied in so the experiment runs offline.
    Refused before anything is written: a study with a missing or non-PNG picture, a folder that
    is neither empty nor an earlier export, a local jsPsych folder that is not one.
    """
    from ramure.studies.serve import QUESTIONS, check_servable, consent_text
    from ramure.studies.storage import Study

    _sqlite_only(db)

    folder = pathlib.Path(folder)
    _check_folder(folder)
    local = None
    if jspsych is not None and not re.match(r"^https?://", os.fspath(jspsych)):
        local = _local_jspsych(pathlib.Path(jspsych))
    with Study.open(db, readonly=True) as study:
        check_servable(study)
        pictures = {g: study.picks(g) for g in study.grammars}
        title, consent = study.name, consent_text(study)
    for grammar, picks in pictures.items():
        for pick in picks:
            with open(pick.image, "rb") as f:
                if f.read(8) != _PNG:
                    raise StudyInputError(f"{pick.image}: not a PNG picture ({grammar}, pick {pick.id}); explore again")
    secret = _study_secret(db, create=True)
    (folder / "img").mkdir(parents=True, exist_ok=True)
    if local is not None:
        (folder / "jspsych").mkdir(exist_ok=True)
    sets, written = [], []
    for grammar, picks in pictures.items():
        codes = picture_codes(secret, grammar)
        sets.append(dict(grammar=grammar, pictures=[codes[p.id] for p in picks]))
        for pick in picks:
            written.append(write_bytes(folder / "img" / f"{codes[pick.id]}.png", pathlib.Path(pick.image).read_bytes()))
    task = dict(
        title=title,
        consent=consent,
        questions=QUESTIONS,
        levels=list(LEVELS),
        size=PICTURE_PIXELS,
        study=study_mark(secret),
        completion_code=jspsych_completion_code(secret),
        sets=sets,
    )
    written.append(write_text(folder / "ramure-config.js", f"window.RAMURE_TASK = {json.dumps(task, indent=1)};\n"))
    written.append(write_bytes(folder / "ramure-task.js", _task_file("ramure-task.js")))
    if local is not None:
        written.append(write_bytes(folder / "jspsych" / "jspsych.js", local[0]))
        written.append(write_bytes(folder / "jspsych" / "jspsych.css", local[1]))
        js, css, where = "jspsych/jspsych.js", "jspsych/jspsych.css", "the copy in jspsych/ (works offline)"
    else:
        base = (os.fspath(jspsych) if jspsych is not None else JSPSYCH_CDN).rstrip("/")
        js, css, where = f"{base}/dist/index.browser.min.js", f"{base}/css/jspsych.css", f"{base} (needs the network)"
    escape = lambda text: text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")  # noqa: E731
    page = _PAGE.format(
        title=escape(title), version=JSPSYCH_VERSION, where=escape(where), css=escape(css), js=escape(js), size=PICTURE_PIXELS
    )
    written.append(write_text(folder / "index.html", page))
    code = task["completion_code"]
    written.append(
        write_text(folder / "README.txt", _README.format(version=JSPSYCH_VERSION, title=title, where=where, code=code))
    )
    return dict(
        folder=str(folder),
        files=len(written),
        pictures=sum(len(p) for p in pictures.values()),
        completion_code=code,
        jspsych=where,
    )


# -- reading results ---------------------------------------------------------------------------------


def read_results(path: str | os.PathLike) -> list[dict]:
    """The trials of a results file: a JSON array of trials, JATOS's export (one JSON array per
    line, one per result), or jsPsych's CSV (objects in JSON text).  Refused in one line otherwise."""
    path = pathlib.Path(path)
    try:
        data = read_regular(path, MAX_RESULTS_BYTES, "results file")
    except RamureError as exc:
        raise StudyInputError(str(exc)) from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise StudyInputError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    if not text.strip():
        raise StudyInputError(f"{path}: empty results file")
    if text.lstrip()[0] in "[{":
        trials = _json_trials(path, text)
    else:
        trials = _csv_trials(path, text)
    if not all(isinstance(t, dict) for t in trials):
        raise StudyInputError(f"{path}: every trial must be a JSON object")
    return trials


def _json_trials(path: pathlib.Path, text: str) -> list:
    try:
        whole = json.loads(text)
        chunks = [whole]
    except ValueError:
        chunks = []
        for number, line in enumerate(text.splitlines(), start=1):
            if line.strip():
                try:
                    chunks.append(json.loads(line))
                except json.JSONDecodeError as exc:
                    raise StudyInputError(f"{path}: line {number} is not JSON ({exc.msg})") from None
    trials: list = []
    for chunk in chunks:
        if isinstance(chunk, dict) and isinstance(chunk.get("trials"), list):  # jsPsych's values() wrapped
            chunk = chunk["trials"]
        if not isinstance(chunk, list):
            raise StudyInputError(f"{path}: expected jsPsych data (a JSON array of trials)")
        trials += chunk
    return trials


_CSV_JSON = ("shown", "groups", "external_id")
_CSV_NUMBERS = ("part", "parts", "sorted_ms", "rt")


def _csv_trials(path: pathlib.Path, text: str) -> list[dict]:
    rows = list(csv.DictReader(io.StringIO(text, newline="")))
    if not rows or "ramure" not in rows[0]:
        raise StudyInputError(f"{path}: not jsPsych data of a Ramure export (no 'ramure' column)")
    trials = []
    for number, row in enumerate(rows, start=2):
        trial: dict[str, Any] = {k: v for k, v in row.items() if k is not None and v != ""}
        try:
            for key in _CSV_JSON:
                if key in trial:
                    trial[key] = json.loads(trial[key]) if key != "external_id" or trial[key] == "null" else trial[key]
            for key in _CSV_NUMBERS:
                if key in trial:
                    trial[key] = float(trial[key]) if "." in trial[key] else int(trial[key])
        except ValueError:
            raise StudyInputError(f"{path}: line {number}: column {key} is not what jsPsych writes") from None
        if trial.get("consent") in ("true", "false"):
            trial["consent"] = trial["consent"] == "true"
        trials.append(trial)
    return trials


# -- checking results ---------------------------------------------------------------------------------


@dataclass
class ImportedGroup:
    """One group of a part, in pick ids."""

    pictures: list[int]
    representative: int
    usefulness: int
    difference: int
    representative_quality: int | None
    words: list[str]


@dataclass
class ImportedPart:
    grammar: str
    part: int
    groups: list[ImportedGroup]
    shown: list[tuple[int, str]]
    sorted_ms: float
    rt: float


@dataclass
class ImportedRun:
    """One participant's run of the exported page."""

    run: str
    external_id: str | None = None
    consent: bool = False
    parts: list[ImportedPart] = field(default_factory=list)


def _likert(value: object, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not 1 <= int(value) <= len(LEVELS):
        raise StudyInputError(f"{where} is {value!r}, not a level 1 to {len(LEVELS)}")
    return int(value)


def _milliseconds(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 <= float(value) <= 1e9:
        raise StudyInputError(f"{where} is {value!r}, not a time in milliseconds")
    return float(value)


def _words(value: object, where: str) -> list[str]:
    if not isinstance(value, list) or not value:
        raise StudyInputError(f"{where}: words must be a non-empty list")
    words = []
    for word in value:
        if not isinstance(word, str) or not word.strip() or len(word.strip()) > MAX_QUALIFIER_CHARS:
            raise StudyInputError(f"{where}: word {word!r} must be text of 1 to {MAX_QUALIFIER_CHARS} characters")
        words.append(word.strip())
    return words


def _group(raw: object, ids: dict[str, int], where: str) -> ImportedGroup:
    if not isinstance(raw, dict) or not isinstance(raw.get("pictures"), list) or not raw["pictures"]:
        raise StudyInputError(f"{where}: expected an object with a non-empty list of pictures")
    pictures = []
    for code in raw["pictures"]:
        if not isinstance(code, str) or code not in ids:
            raise StudyInputError(f"{where}: picture {code!r} is not one of this stimulus set")
        pictures.append(ids[code])
    several = len(pictures) > 1
    chosen = raw.get("representative")
    if not isinstance(chosen, str) or chosen not in ids or ids[chosen] not in pictures:
        raise StudyInputError(f"{where}: representative {chosen!r} is not a picture of the group")
    quality = raw.get("representative_quality")
    if several or quality is not None:
        quality = _likert(quality, f"{where}: representative_quality")
    return ImportedGroup(
        pictures,
        ids[chosen],
        _likert(raw.get("usefulness"), f"{where}: usefulness"),
        _likert(raw.get("difference"), f"{where}: difference"),
        quality if several else None,
        _words(raw.get("words"), where),
    )


def _part(trial: dict, codes: dict[str, dict[int, str]], where: str) -> ImportedPart:
    grammar = trial.get("grammar")
    if grammar not in codes:
        raise StudyInputError(f"{where}: stimulus set {grammar!r} is not in this study (it has {', '.join(codes)})")
    ids = {code: pid for pid, code in codes[grammar].items()}
    groups_raw = trial.get("groups")
    if not isinstance(groups_raw, list) or not groups_raw:
        raise StudyInputError(f"{where}: groups must be a non-empty list")
    groups = [_group(g, ids, f"{where}, group {k}") for k, g in enumerate(groups_raw, start=1)]
    placed = [p for g in groups for p in g.pictures]
    if sorted(placed) != list(range(1, N_PICKS + 1)):
        held = f"they hold {len(placed)}, {len(set(placed))} different"
        raise StudyInputError(f"{where}: the groups must hold each of the {N_PICKS} pictures once ({held})")
    shown_raw = trial.get("shown")
    if not isinstance(shown_raw, list) or len(shown_raw) != N_PICKS:
        raise StudyInputError(f"{where}: shown must list the {N_PICKS} pictures as they were shown")
    shown = []
    for item in shown_raw:
        if not isinstance(item, dict) or item.get("picture") not in ids or not isinstance(item.get("label"), str):
            raise StudyInputError(f"{where}: shown holds {item!r}, not a picture of this set and its label")
        shown.append((ids[item["picture"]], item["label"][:8]))
    part = trial.get("part")
    if isinstance(part, bool) or not isinstance(part, int) or not 1 <= part <= len(codes):
        raise StudyInputError(f"{where}: part {part!r} is not 1 to {len(codes)}")
    rt = _milliseconds(trial.get("rt"), f"{where}: rt")
    sorted_ms = _milliseconds(trial.get("sorted_ms"), f"{where}: sorted_ms")
    if sorted_ms > rt:
        raise StudyInputError(f"{where}: sorted_ms {sorted_ms:g} comes after the part's end (rt {rt:g})")
    return ImportedPart(grammar, part, groups, shown, sorted_ms, rt)


def check_results(trials: list[dict], mark: str, codes: dict[str, dict[int, str]], source: str = "results") -> list[ImportedRun]:
    """The runs in ``trials`` (jsPsych data of the export marked ``mark``), every answer checked;
    refused with one line naming the trial at the first problem.  Trials of other kinds are ignored."""
    runs: dict[str, ImportedRun] = {}
    for number, trial in enumerate(trials, start=1):
        kind = trial.get("ramure")
        if kind not in ("consent", "part"):
            continue
        where = f"{source}: trial {number}"
        if trial.get("ramure_study") != mark:
            raise StudyInputError(f"{where}: from another study's export (mark {trial.get('ramure_study')!r}); nothing imported")
        run_id = trial.get("ramure_run")
        if not isinstance(run_id, str) or not _RUN.match(run_id):
            raise StudyInputError(f"{where}: ramure_run {run_id!r} is not a run id")
        run = runs.setdefault(run_id, ImportedRun(run_id))
        external = trial.get("external_id")
        if external is not None and (not isinstance(external, str) or not 0 < len(external) <= 64):
            raise StudyInputError(f"{where}: external_id must be text of 1 to 64 characters")
        run.external_id = run.external_id or external
        if kind == "consent":
            run.consent = run.consent or trial.get("consent") is True
            continue
        part = _part(trial, codes, f"{where} (run {run_id})")
        if any(p.grammar == part.grammar for p in run.parts):
            raise StudyInputError(f"{where}: run {run_id} answers stimulus set {part.grammar!r} twice")
        run.parts.append(part)
    for run in runs.values():
        if run.parts and not run.consent:
            raise StudyInputError(f"{source}: run {run.run} has answers but no consent trial; nothing imported")
    found = [run for run in runs.values() if run.parts]
    if not found:
        raise StudyInputError(f"{source}: no answered part of a Ramure export in it")
    return found


# -- storing ------------------------------------------------------------------------------------------


def _sqlite_only(db: str | os.PathLike) -> None:
    """Refuse a PostgreSQL study: the jsPsych export signs its codes with the secret kept beside a
    SQLite file, and the import rehearses on an in-memory copy of one."""
    from ramure.studies.pgsql import is_database_url

    if is_database_url(db):
        raise StudyInputError(
            "the jsPsych export and import work on a SQLite study file; serve a PostgreSQL study with `ramure study serve`"
        )


class _PageClock:
    """The study's clock during an import: the page's time, in seconds, set before each answer."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def imported_runs(conn: sqlite3.Connection) -> set[str]:
    """Run ids imported into the study already (from the event log)."""
    rows = conn.execute("SELECT detail FROM events WHERE action = 'jspsych_run'")
    return {json.loads(r[0]).get("run") for r in rows}


def store_run(study: Any, run: ImportedRun, clock: _PageClock, source: str) -> str:
    """Store one checked run as a new participant through the session API; returns their code."""
    from ramure.studies.serve import record_external_id
    from ramure.studies.storage import log_event

    code = study.add_participant(consent=True)
    if run.external_id:
        record_external_id(study, code, run.external_id)
    pid = study.conn.execute("SELECT id FROM participants WHERE code = ?", (code,)).fetchone()[0]
    clock.now = 0.0
    parts = sorted(run.parts, key=lambda p: p.part)
    sessions = [study.session(code, part.grammar) for part in parts]  # all started at 0: the page kept no budget
    with study.conn:
        detail = dict(
            run=run.run,
            file=source,
            external_id=run.external_id,
            order=[p.grammar for p in parts],
            shown={p.grammar: p.shown for p in parts},
            sorted_ms={p.grammar: p.sorted_ms for p in parts},
            rt={p.grammar: p.rt for p in parts},
        )
        log_event(study.conn, pid, "jspsych_run", detail)
    for part, session in zip(parts, sessions):
        clock.now = part.sorted_ms / 1000
        session.set_groups([g.pictures for g in part.groups])
        clock.now = part.rt / 1000
        for label, group in enumerate(part.groups, start=1):
            if len(group.pictures) > 1:
                session.set_representative(label, group.representative)
            session.rate(label, group.usefulness, group.difference, group.representative_quality)
            for word in group.words:
                session.add_qualifier(label, word)
        session.finish()
    return code


def import_jspsych(db: str | os.PathLike, results: str | os.PathLike) -> dict:
    """Import the result file ``results`` of study ``db``'s jsPsych export; returns a summary.

    Everything is checked first (:func:`check_results`, runs already imported), then played on a
    copy of the database in memory through the session API; only if all of it is accepted is it
    stored, one new participant per run.  A refusal leaves the study unchanged.
    """
    from ramure.studies.storage import Study

    _sqlite_only(db)

    source = pathlib.Path(results).name
    trials = read_results(results)
    secret = _study_secret(db, create=False)
    clock = _PageClock()
    with Study.open(db, clock=clock) as study:
        codes = {g: picture_codes(secret, g) for g in study.grammars}
        runs = check_results(trials, study_mark(secret), codes, source)
        again = sorted(imported_runs(study.conn) & {r.run for r in runs})
        if again:
            raise StudyInputError(f"{source}: run {again[0]} is already imported ({len(again)} in all); nothing imported")
        _rehearse(study, runs, source)
        made: list[str] = []
        try:
            for run in runs:
                made.append(store_run(study, run, clock, source))
        except (RamureError, sqlite3.Error):
            for code in made:  # the rehearsal passed, so only a disk error lands here: undo the runs stored
                study.delete_participant(code)
            raise
        return dict(db=str(study.path), file=source, runs=len(runs), participants=made, tests=sum(len(r.parts) for r in runs))


def _rehearse(study: Any, runs: list[ImportedRun], source: str) -> None:
    """Store ``runs`` in an in-memory copy of ``study``: any refusal of the session API comes here."""
    from ramure.studies.storage import Study

    memory = sqlite3.connect(":memory:")
    try:
        study.conn.backup(memory)
        memory.execute("PRAGMA foreign_keys = ON")
        clock = _PageClock()
        copy = Study(memory, study.path, clock)
        for run in runs:
            try:
                store_run(copy, run, clock, source)
            except StudyInputError as exc:
                raise StudyInputError(f"{source}: run {run.run}: {exc}; nothing imported") from None
    finally:
        memory.close()
