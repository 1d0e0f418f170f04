"""A new study from the current exploration: the one function the desktop and the notebook call.

:func:`new_study` writes the exploration into the study's folder (``picks.json``, ``pca.json``,
``variants.csv`` and the 27 pictures, rendered once, without captions: what every participant
sees, on every front end), creates the study database beside it and returns where everything
went and the command that serves it (:func:`serve_command`).  Qt-free and ipywidgets-free;
the rendering is off-screen VTK, so call it from the thread that may draw (the GUI thread, the
kernel's main thread).

>>> from ramure.metrics import explore
>>> import tempfile, pathlib
>>> exp = explore("grammars/honda_sympodial.lsys", n=3, n_jobs=1, cache=False)
>>> made = new_study(exp, pathlib.Path(tempfile.mkdtemp()) / "honda-study", size=(48, 48))
>>> made.db.name, made.grammar, (made.exploration / "picks.json").is_file()
('study.db', 'honda_sympodial', True)
>>> made.command.startswith("ramure study serve ")
True
"""

from __future__ import annotations

import os
import pathlib
import re
import shlex
import socket
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ramure.studies.errors import StudyInputError

if TYPE_CHECKING:
    from ramure.metrics.exploration import Exploration

#: The database file a new study gets inside its folder.
STUDY_FILE = "study.db"
#: Size of the pictures participants sort (pixels); the web page and the export scale them.
PICTURE_SIZE = (240, 240)
_FOLDER_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


@dataclass(frozen=True)
class NewStudy:
    """What :func:`new_study` made: the database, the grammar's name and exploration folder,
    and the command that serves the study to participants."""

    db: pathlib.Path
    grammar: str
    exploration: pathlib.Path
    command: str


def serve_command(db: str | os.PathLike, port: int | None = None) -> str:
    """The shell command that serves study ``db`` (``ramure study serve``), quoted for a shell.

    >>> serve_command("/data/my study/study.db", port=8001)
    "ramure study serve '/data/my study/study.db' --port 8001"
    """
    command = f"ramure study serve {shlex.quote(os.fspath(db))}"
    return command if port is None else f"{command} --port {int(port)}"


def serve_argv(db: str | os.PathLike, port: int) -> list[str]:
    """The ``ramure study serve`` command as a program and its arguments, run with this Python
    (for a front end that starts the server itself, on this machine only: 127.0.0.1)."""
    code = "import sys; from ramure.app.cli import main; sys.exit(main())"
    return [sys.executable, "-c", code, "study", "serve", os.fspath(db), "--host", "127.0.0.1", "--port", str(int(port))]


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now (the server may still lose it to another program)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def save_exploration(
    exploration: Exploration, directory: str | os.PathLike, size: tuple[int, int] = PICTURE_SIZE
) -> dict[str, pathlib.Path]:
    """Write ``exploration`` to ``directory`` as ``ramure explore`` does: ``picks.json``,
    ``pca.json``, ``variants.csv`` and ``thumbs/pick_NN.png`` (no captions); returns the paths."""
    from ramure.app.thumbnails import render_picks
    from ramure.metrics.exploration import write_exploration

    images = render_picks(exploration, directory, size=size)
    paths = write_exploration(exploration, directory, images)
    return {**paths, "thumbs": pathlib.Path(directory) / "thumbs"}


def _check_grammar_name(grammar: str) -> str:
    if not isinstance(grammar, str) or not _FOLDER_NAME.match(grammar):
        raise StudyInputError(
            f"grammar name {grammar!r}: use 1-64 letters, digits, '_', '-' or '.' (it names a folder of the study)"
        )
    return grammar


def new_study(
    exploration: Exploration,
    folder: str | os.PathLike,
    name: str | None = None,
    grammar: str | None = None,
    budget_minutes: float = 30.0,
    size: tuple[int, int] = PICTURE_SIZE,
) -> NewStudy:
    """Make study ``folder/study.db`` from ``exploration``, its pictures in ``folder/GRAMMAR``.

    Refused, before anything is written: a folder that already holds a study, a bad grammar
    name, picks that do not show 27 different plants (:func:`ramure.studies.picks.check_distinct`).
    ``name`` is the study's title (default: the folder's name).
    """
    from ramure.studies.picks import check_distinct, picks_from_data
    from ramure.studies.storage import Study

    folder = pathlib.Path(folder)
    grammar = _check_grammar_name(grammar or exploration.name)
    db = folder / STUDY_FILE
    if folder.exists() and not folder.is_dir():
        raise StudyInputError(f"{folder}: exists and is not a folder")
    if db.exists():
        raise StudyInputError(f"{db}: this folder already holds a study; choose a new folder")
    if not 0 < budget_minutes <= 24 * 60:
        raise StudyInputError(f"the time budget must be from 0 to 1440 minutes, not {budget_minutes}")
    check_distinct(picks_from_data(exploration.pick_records(), where=grammar), f"grammar {grammar!r}")
    directory = folder / grammar
    save_exploration(exploration, directory, size)
    with Study.create(db, grammars={grammar: directory}, name=name or folder.resolve().name, budget_minutes=budget_minutes):
        pass
    return NewStudy(db, grammar, directory, serve_command(db))


def add_to_study(
    exploration: Exploration,
    folder: str | os.PathLike,
    grammar: str | None = None,
    size: tuple[int, int] = PICTURE_SIZE,
) -> NewStudy:
    """Add ``exploration`` as one more stimulus set of the study in ``folder`` (made by :func:`new_study`).

    Refused, before anything is written: no study in ``folder``, a study that already has
    participants (its stimuli are fixed once anyone took part), a grammar already in it, a bad
    name or coinciding picks.
    """
    from ramure.studies.picks import check_distinct, picks_from_data
    from ramure.studies.storage import Study

    folder = pathlib.Path(folder)
    grammar = _check_grammar_name(grammar or exploration.name)
    db = folder / STUDY_FILE
    if not db.is_file():
        raise StudyInputError(f"{folder}: holds no study ({STUDY_FILE}); make a new study there instead")
    with Study.open(db, readonly=True) as study:
        if study.participants():
            raise StudyInputError(f"{db}: participants have taken part already; its pictures can no longer change")
        if grammar in study.grammars:
            raise StudyInputError(f"{db}: already holds a stimulus set named {grammar!r}; give this one another name")
    check_distinct(picks_from_data(exploration.pick_records(), where=grammar), f"grammar {grammar!r}")
    directory = folder / grammar
    save_exploration(exploration, directory, size)
    with Study.open(db) as study:
        study.add_grammar(grammar, directory)
    return NewStudy(db, grammar, directory, serve_command(db))
