"""Fuzz the readers of sessions, MTG files and the desktop's settings file (issue 37).

Run from the repository root::

    python -m tests.hardening.fuzz_files --inputs 3000            # a campaign
    python -m tests.hardening.fuzz_files --inputs 90 --seed 1     # a slice

Inputs go round three readers.  ``session``: a real session file (regrows, a prune, a
constants edit) with values of other types put at random places of its JSON, keys
deleted, edits repeated or reordered, or its text edited character by character; it is
loaded by :meth:`ramure.app.model.Explorer.load_session` over a plant that must stay as it
was when the file is refused.  ``mtg``: an MTG written by Ramure with random character
edits, read by :func:`ramure.lsys.architecture.mtg.parse_mtg`.  ``settings``: the desktop's settings
file (an INI file QSettings reads) with the recent-files entry given other types (Qt's
``@Variant``, ``@ByteArray``, numbers, NUL bytes, long lists), read by the File menu's
:meth:`~ramure.app.desktop.menus.files.FileActions.recent`.  Outcomes: ``ok``, ``refused`` (a
RamureError), ``crash:<type>`` (a bug), ``changed`` (a refused session changed the plant:
a bug), ``slow`` (over 5 s of CPU).  Goal: no crash, no change, nothing slow.
"""

from __future__ import annotations

import collections
import copy
import functools
import json
import pathlib
import sys
import tempfile
import time
import traceback
import types

import numpy as np

from ramure.errors import RamureError
from tests.hardening.fuzz import edit_text, reader_campaign_main

ROOT = pathlib.Path(__file__).resolve().parents[2]
SLOW_SECONDS = 5.0
READERS = ("session", "mtg", "settings")
VALUES = [None, True, 0, -1, 1, 7, 2**31, 2**63, -(2**63), 10**30, 0.5, -1e308, 1e308, "", "x", "1", [], [0], [-1, 2**40]]
VALUES += [{}, {"a": 1}, [[[[0]]]], "é" * 50, {"op": "regrow"}, [None], "NaN"]


@functools.lru_cache(maxsize=1)
def base_sessions() -> list[dict]:
    """Real sessions to mutate: regrows, a prune and a constants edit on two grammars."""
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.regen import Session

    out = []
    for name, n in (("ternary_branching", 3), ("stochastic_plant", 4)):
        session = Session(LSystem.from_file(name), n=n, seed=2)
        rng = np.random.default_rng(0)
        for step in range(4):
            leaves = session.tree.leaves
            picked = rng.choice(leaves, min(3, len(leaves)), replace=False).tolist()
            if step == 2:
                session.prune(picked[:1], rho=0.5)
            else:
                session.regrow(picked, rho=0.9)
        first = next(iter(session.lsystem.constants), None)
        if first is not None:
            session.set_constants({first: 2.0})
        out.append(session.to_dict())
    return out


@functools.lru_cache(maxsize=1)
def base_mtg() -> str:
    import ramure
    from ramure.lsys.architecture.amap import architecture
    from ramure.lsys.architecture.mtg import mtg_text

    return mtg_text(architecture(ramure.derive("amap/massart", n=3)))


@functools.lru_cache(maxsize=1)
def _explorer():
    from ramure.app.model import Explorer

    return Explorer(ROOT / "grammars" / "ternary_branching.lsys", n=2)


def _paths(value, prefix=()):
    """Every path (tuple of keys and indexes) inside a JSON value."""
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, prefix + (i,))


def _set(data, path, value):
    if not path:
        return value
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return data


def mutate_session(rng) -> str:
    """A session file's text: a real session with 1-3 structural edits, or character edits."""
    data = copy.deepcopy(base_sessions()[int(rng.integers(len(base_sessions())))])
    if rng.random() < 0.2:
        return edit_text(rng, json.dumps(data, indent=1), '{}[]":,0123456789-.e ', ["null", "1e999", "[" * 50, '"x"'])
    for _ in range(int(rng.integers(1, 4))):
        paths = list(_paths(data))
        path = paths[int(rng.integers(1, len(paths)))]
        op = rng.random()
        if op < 0.55:
            data = _set(data, path, copy.deepcopy(VALUES[int(rng.integers(len(VALUES)))]))
        elif op < 0.7 and isinstance(data.get("edits"), list) and data["edits"]:
            edits = data["edits"]
            i = int(rng.integers(len(edits)))
            edits.insert(int(rng.integers(len(edits) + 1)), copy.deepcopy(edits[i]))  # an edit repeated
        elif op < 0.8 and isinstance(data.get("edits"), list):
            rng.shuffle(data["edits"])
        elif op < 0.9 and len(path) >= 1:
            parent = data
            for key in path[:-1]:
                parent = parent[key]
            if isinstance(parent, dict):
                parent.pop(path[-1], None)
            elif isinstance(parent, list) and parent:
                parent.pop()
        elif isinstance(data.get("n"), int):
            data["n"] = int(rng.choice([0, 1, 5, 9, 40, 10**6]))
    return json.dumps(data)


def session_input(rng, folder: pathlib.Path) -> str:
    path = folder / "s.json"
    path.write_text(mutate_session(rng), encoding="utf-8")
    ex = _explorer()
    before = (ex.text, ex.version, ex.session.derivation.to_string())
    try:
        ex.load_session(path)
    except RamureError:
        if (ex.text, ex.version, ex.session.derivation.to_string()) != before:
            return "changed"
        return "refused"
    _explorer.cache_clear()  # loaded: the next input starts from the plain plant again
    return "ok"


def mtg_input(rng, folder: pathlib.Path) -> str:
    from ramure.lsys.architecture.mtg import parse_mtg

    text = base_mtg()
    if rng.random() < 0.5:
        text = edit_text(rng, text, '^/<+IUSAP1{}[]":,\t\n -0', ["^/I1", "/I1", "# ramure-events: {", "\t" * 40])
    else:
        chars = list(text)
        alphabet = list('^/<+IUSAP1{}[]":,\t\n -0')
        for at in rng.integers(0, len(chars), rng.integers(1, 4)):
            chars[at] = alphabet[rng.integers(len(alphabet))]
        text = "".join(chars)
    parse_mtg(text)
    return "ok"


SETTING_VALUES = [
    "/tmp/a.lsys",
    "@Invalid()",
    "@Variant(\\0\\0\\0\\x7f\\0\\0\\0\\x6QPoint\\0\\0\\0\\0\\x1\\0\\0\\0\\x2)",
    "@Variant(\\0\\0\\0\\x2\\0\\0\\0\\x5)",
    "@ByteArray(\\xff\\xfe)",
    "@Size(3 4)",
    "@Rect(1 2 3 4)",
    "@Point(1 2)",
    "12",
    "a\\0b.lsys",
    "\\0",
    "x" * 5000,
    "/" + "a/" * 2000,
    '"quoted, with comma"',
    "é.lsys",
]


def settings_input(rng, folder: pathlib.Path) -> str:
    from PySide6.QtCore import QSettings

    from ramure.app.desktop.menus.files import FileActions

    values = [SETTING_VALUES[int(i)] for i in rng.integers(0, len(SETTING_VALUES), int(rng.integers(1, 5)))]
    text = "[General]\nrecent=" + ", ".join(values) + "\n"
    if rng.random() < 0.3:
        text = edit_text(rng, text, "[]=,@\\()\n0x", ["@Variant(", "\\0", "[General]"])
    path = folder / "Ramure desktop.conf"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    settings = QSettings(str(path), QSettings.Format.IniFormat)
    recent = FileActions.recent(types.SimpleNamespace(settings=settings))  # the File menu's read
    if not (isinstance(recent, list) and all(isinstance(p, str) for p in recent)):
        raise AssertionError(f"recent files are not a list of paths: {recent!r}")
    return "ok"


INPUTS = {"session": session_input, "mtg": mtg_input, "settings": settings_input}


def run_one(kind: str, rng: np.random.Generator, folder: pathlib.Path) -> str:
    """One input of reader ``kind``; returns its outcome."""
    start = time.process_time()
    try:
        outcome = INPUTS[kind](rng, folder)
    except RamureError:
        outcome = "refused"
    except Exception as exc:  # noqa: BLE001 - what the fuzzer is looking for
        outcome = f"crash:{type(exc).__name__}"
        traceback.print_exc(file=sys.stderr)
    return "slow" if time.process_time() - start > SLOW_SECONDS else outcome


def campaign(inputs: int, seed: int = 0, readers: tuple[str, ...] = READERS) -> collections.Counter:
    """Run ``inputs`` inputs round the ``readers``; counts of ``(reader, outcome)``."""
    rng = np.random.default_rng(seed)
    counts: collections.Counter = collections.Counter()
    with tempfile.TemporaryDirectory(prefix="ramure-fuzz-") as tmp:
        folder = pathlib.Path(tmp)
        for i in range(inputs):
            kind = readers[i % len(readers)]
            counts[kind, run_one(kind, rng, folder)] += 1
    return counts


def main(argv: list[str] | None = None) -> int:
    return reader_campaign_main(campaign, __doc__ or "", argv)


if __name__ == "__main__":
    sys.exit(main())
